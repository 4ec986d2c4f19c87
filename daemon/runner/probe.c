/* probe.c: simulated probing (probe.h). The tool is sampled on the surface
 * of its cutting part and shank (solids of revolution, lib/tools), keeping
 * only the points whose outward normal does not face away from the motion
 * (a first contact can only happen there). Along the move the search steps
 * by the signed distance at those points of the stock and the fixtures
 * together (their maximum: a distance, so no sample can cross a surface
 * within one step), then bisects between the last free and the first
 * touching position. */
#include "probe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PROBE_MAX_SAMPLES 4000000 /* about 100 MB of doubles: refuse beyond */
#define PROBE_MAX_STEPS 1000000
#define PROBE_RESOLUTION 1e-6     /* mm: the bisection stops here */

typedef struct probe_samples {
    double *p; /* xyz offsets from the tip */
    size_t n, cap;
} probe_samples;

static int add_sample(probe_samples *s, double x, double y, double z)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? s->cap * 2 : 1024;
        double *p = realloc(s->p, cap * 3 * sizeof *p);
        if (!p) return 0;
        s->p = p;
        s->cap = cap;
    }
    s->p[3 * s->n] = x;
    s->p[3 * s->n + 1] = y;
    s->p[3 * s->n + 2] = z;
    s->n++;
    return 1;
}

/* A point of a profile element at parameter f (0..1), with its outward
 * normal in the (r, z) half-plane. */
static void elem_point(const fm_profile_elem *e, double f, double rz[2], double n[2])
{
    if (e->kind == FM_PROFILE_ARC) {
        double a0 = atan2(e->a[1] - e->c[1], e->a[0] - e->c[0]);
        double a1 = atan2(e->b[1] - e->c[1], e->b[0] - e->c[0]);
        double d = a1 - a0;
        if (e->ccw && d < 0) d += 2 * FM_PI;
        if (!e->ccw && d > 0) d -= 2 * FM_PI;
        double a = a0 + f * d;
        rz[0] = e->c[0] + e->radius * cos(a);
        rz[1] = e->c[1] + e->radius * sin(a);
        /* the profile bounds {r <= R(z)} walking from the bottom axis point
         * to the top one: the outside is on the right of the walk */
        double tx = -sin(a) * (d > 0 ? 1 : -1), tz = cos(a) * (d > 0 ? 1 : -1);
        n[0] = tz;
        n[1] = -tx;
        return;
    }
    rz[0] = e->a[0] + f * (e->b[0] - e->a[0]);
    rz[1] = e->a[1] + f * (e->b[1] - e->a[1]);
    double tx = e->b[0] - e->a[0], tz = e->b[1] - e->a[1];
    double l = hypot(tx, tz);
    n[0] = l > 0 ? tz / l : 0;
    n[1] = l > 0 ? -tx / l : 0;
}

static double elem_length(const fm_profile_elem *e)
{
    if (e->kind == FM_PROFILE_ARC) {
        double a0 = atan2(e->a[1] - e->c[1], e->a[0] - e->c[0]);
        double a1 = atan2(e->b[1] - e->c[1], e->b[0] - e->c[0]);
        double d = fabs(a1 - a0);
        if (d > FM_PI) d = 2 * FM_PI - d;
        return e->radius * d;
    }
    return hypot(e->b[0] - e->a[0], e->b[1] - e->a[1]);
}

static fm_status sample_part(const fm_tool_part *part, double h, const double dir[3],
                             probe_samples *s, fm_error *err)
{
    if (part->kind != FM_TOOL_PART_PROFILE) {
        /* a custom cutter: its bounding cylinder's surface stands in */
        fm_profile_elem box[3];
        memset(box, 0, sizeof box);
        double r = part->r_max, z0 = part->z_lo, z1 = part->z_hi;
        box[0].a[0] = 0, box[0].a[1] = z0, box[0].b[0] = r, box[0].b[1] = z0;
        box[1].a[0] = r, box[1].a[1] = z0, box[1].b[0] = r, box[1].b[1] = z1;
        box[2].a[0] = r, box[2].a[1] = z1, box[2].b[0] = 0, box[2].b[1] = z1;
        fm_tool_part p;
        memset(&p, 0, sizeof p);
        p.kind = FM_TOOL_PART_PROFILE;
        p.count = 3;
        memcpy(p.elem, box, sizeof box);
        return sample_part(&p, h, dir, s, err);
    }
    for (size_t k = 0; k < part->count; k++) {
        const fm_profile_elem *e = &part->elem[k];
        double len = elem_length(e);
        size_t nf = (size_t)ceil(len / h);
        if (nf < 1) nf = 1;
        for (size_t i = 0; i <= nf; i++) {
            double rz[2], n[2];
            elem_point(e, (double)i / (double)nf, rz, n);
            size_t nt = rz[0] <= 1e-12 ? 1 : (size_t)ceil(2 * FM_PI * rz[0] / h);
            if (nt < 8 && rz[0] > 1e-12) nt = 8;
            if (s->n + nt > PROBE_MAX_SAMPLES)
                return fm_error_set(err, FM_ERR_LIMIT,
                                    "probing: the tool's surface needs more than %d samples at "
                                    "this voxel size", PROBE_MAX_SAMPLES);
            for (size_t j = 0; j < nt; j++) {
                double th = 2 * FM_PI * (double)j / (double)nt;
                double c = cos(th), sn = sin(th);
                double nx = n[0] * c, ny = n[0] * sn, nz = n[1];
                /* a first contact cannot happen where the surface faces away
                 * from the motion (edges keep both neighbours' points) */
                if (nx * dir[0] + ny * dir[1] + nz * dir[2] < -1e-9 && i > 0 && i < nf) continue;
                if (!add_sample(s, rz[0] * c, rz[0] * sn, rz[1]))
                    return fm_error_set(err, FM_ERR_LIMIT, "out of memory (probe samples)");
            }
        }
    }
    return FM_OK;
}

/* The largest distance (positive inside) of the stock or a fixture over
 * the samples with the tip at c: >= 0 when the tool touches either. */
static double deepest(const fm_stock *stock, const fm_check *fixtures, const probe_samples *s,
                      const double c[3])
{
    double best = -INFINITY;
    for (size_t i = 0; i < s->n; i++) {
        double p[3] = {c[0] + s->p[3 * i], c[1] + s->p[3 * i + 1], c[2] + s->p[3 * i + 2]};
        double v = fm_stock_sample(stock, p);
        if (fixtures) v = fmax(v, fm_check_fixture_distance(fixtures, p));
        if (v > best) best = v;
    }
    return best;
}

fm_status fm_runner_probe(const fm_stock *stock, const fm_check *fixtures, const fm_tool *tool,
                          const double tip_start[3], const double tip_end[3], int toward,
                          int *tripped, double *fraction, int *at_start, fm_error *err)
{
    *tripped = 0;
    *fraction = 1;
    *at_start = 0;
    double d[3] = {tip_end[0] - tip_start[0], tip_end[1] - tip_start[1], tip_end[2] - tip_start[2]};
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double dir[3] = {0, 0, 0};
    if (len > 0)
        for (int k = 0; k < 3; k++) dir[k] = d[k] / len;
    /* for loss of contact the trailing side matters: the point that leaves
     * last faces against the motion */
    double face[3] = {toward ? dir[0] : -dir[0], toward ? dir[1] : -dir[1], toward ? dir[2] : -dir[2]};
    probe_samples s = {NULL, 0, 0};
    double h = 0.5 * fm_stock_voxel_size(stock);
    fm_status st = FM_OK;
    if (tool) {
        st = sample_part(&tool->flutes, h, face, &s, err);
        if (!st && tool->has_shank) st = sample_part(&tool->shank, h, face, &s, err);
    } else if (!add_sample(&s, 0, 0, 0)) {
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory (probe samples)");
    }
    if (st) {
        free(s.p);
        return st;
    }
    /* state(f) is 1 when the probe is tripped at fraction f */
    double c[3];
    double v = deepest(stock, fixtures, &s, tip_start);
    int touching = v >= 0;
    if (touching == (toward != 0)) {
        *at_start = 1;
        free(s.p);
        return FM_OK;
    }
    double f = 0, step_min = h * 0.25 / (len > 0 ? len : 1);
    long steps = 0;
    while (f < 1 && len > 0) {
        /* v < 0 (toward) or v >= 0 (away): |v| is how far every sample is
         * from changing side */
        double step = fabs(v) / len;
        if (step < step_min) step = step_min;
        double nf = f + step;
        if (nf > 1) nf = 1;
        for (int k = 0; k < 3; k++) c[k] = tip_start[k] + nf * d[k];
        double nv = deepest(stock, fixtures, &s, c);
        int now = nv >= 0;
        if (now == (toward != 0)) {
            /* changed between f and nf: bisect */
            double lo = f, hi = nf;
            while ((hi - lo) * len > PROBE_RESOLUTION) {
                double mid = 0.5 * (lo + hi);
                for (int k = 0; k < 3; k++) c[k] = tip_start[k] + mid * d[k];
                int m = deepest(stock, fixtures, &s, c) >= 0;
                if (m == (toward != 0)) hi = mid;
                else lo = mid;
            }
            *tripped = 1;
            *fraction = hi;
            break;
        }
        f = nf;
        v = nv;
        if (++steps > PROBE_MAX_STEPS) {
            st = fm_error_set(err, FM_ERR_LIMIT, "probing: more than %d steps along one move",
                              PROBE_MAX_STEPS);
            break;
        }
    }
    free(s.p);
    return st;
}
