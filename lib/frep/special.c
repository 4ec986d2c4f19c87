/* special.c: evaluation of the ops that need a search or data (projection,
 * constant-radius offset, normal offset, normalization, voxel grids) in
 * every evaluator mode, and fm_reference_special, an independent and simple
 * implementation (dense sampling + refinement on the reference evaluator)
 * that the reference evaluator uses and the tests compare with. */
#include "frep/tape_internal.h"

#include <string.h>

/* ------------------------------------------------------- projection -- */

/* Interval branch-and-bound on the projected coordinate (the other
 * coordinates fixed): split the segment with the highest upper bound until
 * no segment can beat the best sampled value by more than FM_PROJECT_TOL or
 * the budget is spent; then golden-section refinement around the best point
 * and in the most promising segments left. */
#define PROJECT_BUDGET 256
#define PROJECT_SAMPLES 16
#define GOLDEN_ITERS 90

typedef struct seg {
    double lo, hi, ub;
} seg;

typedef struct searcher {
    fm_evaluator *sub;
    double q[4];
    int axis;
    double best, best_s;
    size_t evals;
} searcher;

static double probe(searcher *s, double x)
{
    s->q[s->axis] = x;
    double v = fm_eval_point(s->sub, s->q);
    s->evals++;
    if (v > s->best || (isnan(s->best) && !isnan(v))) {
        s->best = v;
        s->best_s = x;
    }
    return v;
}

/* Golden-section search for a maximum of the probe on [a, b]; every probe
 * updates the best value, so the result is never worse than before. */
static void golden(searcher *s, double a, double b)
{
    const double r = 0.6180339887498949;
    double c = b - r * (b - a), d = a + r * (b - a);
    double fc = probe(s, c), fd = probe(s, d);
    for (int i = 0; i < GOLDEN_ITERS && b - a > 1e-13 * (1.0 + fabs(a) + fabs(b)); i++) {
        if (fc >= fd || isnan(fd)) {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = probe(s, c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = probe(s, d);
        }
    }
}

static void heap_push(seg *h, size_t *n, seg x)
{
    size_t i = (*n)++;
    while (i > 0) {
        size_t parent = (i - 1) / 2;
        if (h[parent].ub >= x.ub) break;
        h[i] = h[parent];
        i = parent;
    }
    h[i] = x;
}

static seg heap_pop(seg *h, size_t *n)
{
    seg top = h[0], last = h[--(*n)];
    size_t i = 0;
    for (;;) {
        size_t l = 2 * i + 1, r = l + 1, m = i;
        double mv = last.ub;
        if (l < *n && h[l].ub > mv) {
            m = l;
            mv = h[l].ub;
        }
        if (r < *n && h[r].ub > mv) m = r;
        if (m == i) break;
        h[i] = h[m];
        i = m;
    }
    if (*n > 0) h[i] = last;
    return top;
}

static double segment_upper(searcher *s, double lo, double hi)
{
    fm_interval box[4];
    for (int i = 0; i < 4; i++) box[i].lo = box[i].hi = s->q[i];
    box[s->axis].lo = lo;
    box[s->axis].hi = hi;
    int nan = 0;
    fm_interval r = fm_eval_interval_nan(s->sub, box, &nan);
    return isnan(r.hi) ? -INFINITY : r.hi; /* only NaN there: nothing to find */
}

static double project_search(fm_evaluator *sub, const double p[4], int axis, double lo, double hi,
                             double *arg)
{
    searcher s;
    s.sub = sub;
    memcpy(s.q, p, sizeof s.q);
    s.axis = axis;
    s.best = NAN;
    s.best_s = lo;
    s.evals = 0;
    double step = (hi - lo) / PROJECT_SAMPLES;
    for (int i = 0; i <= PROJECT_SAMPLES; i++) probe(&s, i == PROJECT_SAMPLES ? hi : lo + step * i);
    double best_width = step;
    seg heap[2 * PROJECT_BUDGET + 2];
    size_t n = 0;
    if (hi > lo) heap_push(heap, &n, (seg){lo, hi, segment_upper(&s, lo, hi)});
    for (int it = 0; it < PROJECT_BUDGET && n > 0; it++) {
        seg top = heap_pop(heap, &n);
        /* The largest upper bound left cannot beat the best: converged. */
        if (!(top.ub > s.best + FM_PROJECT_TOL) && !isnan(s.best)) {
            n = 0;
            break;
        }
        double mid = 0.5 * (top.lo + top.hi);
        if (!(mid > top.lo && mid < top.hi)) continue; /* no room left to split */
        double before = s.best_s;
        probe(&s, mid);
        if (s.best_s != before) best_width = top.hi - top.lo;
        seg halves[2] = {{top.lo, mid, 0}, {mid, top.hi, 0}};
        for (int k = 0; k < 2; k++) {
            halves[k].ub = segment_upper(&s, halves[k].lo, halves[k].hi);
            if (halves[k].ub > s.best + FM_PROJECT_TOL || isnan(s.best)) heap_push(heap, &n, halves[k]);
        }
    }
    /* Local refinement around the best point, then in the best few
     * segments the budget left open. */
    double a = s.best_s - best_width, b = s.best_s + best_width;
    golden(&s, a < lo ? lo : a, b > hi ? hi : b);
    for (int k = 0; k < 3 && n > 0; k++) {
        seg top = heap_pop(heap, &n);
        if (!(top.ub > s.best + FM_PROJECT_TOL)) break;
        golden(&s, top.lo, top.hi);
    }
    if (arg) *arg = s.best_s;
    return s.best;
}

/* ------------------------------------------------------ sphere search -- */

/* Max of sign * f over the sphere |X' - X| = r (x, y, z; t unchanged):
 * a Fibonacci lattice of directions, then a pattern search on the sphere
 * from the best two directions. */
#define BALL_SAMPLES 128

typedef double (*point_fn)(void *ctx, const double q[4]);

static double sphere_value(point_fn f, void *ctx, const double p[4], double r, const double u[3],
                           double sign)
{
    double q[4] = {p[0] + r * u[0], p[1] + r * u[1], p[2] + r * u[2], p[3]};
    double v = sign * f(ctx, q);
    return isnan(v) ? -INFINITY : v;
}

static void tangent_basis(const double u[3], double e1[3], double e2[3])
{
    double a[3] = {1, 0, 0};
    if (fabs(u[0]) > 0.6) a[0] = 0, a[1] = 1;
    double d = a[0] * u[0] + a[1] * u[1] + a[2] * u[2];
    for (int i = 0; i < 3; i++) e1[i] = a[i] - d * u[i];
    double n = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int i = 0; i < 3; i++) e1[i] /= n;
    e2[0] = u[1] * e1[2] - u[2] * e1[1];
    e2[1] = u[2] * e1[0] - u[0] * e1[2];
    e2[2] = u[0] * e1[1] - u[1] * e1[0];
}

static double sphere_search(point_fn f, void *ctx, const double p[4], double d, int samples,
                            double best_q[4])
{
    double r = fabs(d), sign = d > 0 ? 1.0 : -1.0;
    double dirs[2][3] = {{0, 0, 1}, {0, 0, -1}}, vals[2] = {-INFINITY, -INFINITY};
    const double golden_angle = 2.399963229728653;
    for (int i = 0; i < samples; i++) {
        double z = 1.0 - 2.0 * (i + 0.5) / samples, rad = sqrt(1.0 - z * z);
        double u[3] = {rad * cos(golden_angle * i), rad * sin(golden_angle * i), z};
        double v = sphere_value(f, ctx, p, r, u, sign);
        if (v > vals[0]) {
            vals[1] = vals[0];
            memcpy(dirs[1], dirs[0], sizeof dirs[0]);
            vals[0] = v;
            memcpy(dirs[0], u, sizeof u);
        } else if (v > vals[1]) {
            vals[1] = v;
            memcpy(dirs[1], u, sizeof u);
        }
    }
    double best = -INFINITY, best_u[3] = {0, 0, 1};
    for (int start = 0; start < 2; start++) {
        double u[3], v = vals[start];
        memcpy(u, dirs[start], sizeof u);
        double h = 2.0 * sqrt(4.0 * FM_PI / samples);
        while (h > 1e-9) {
            double e1[3], e2[3];
            tangent_basis(u, e1, e2);
            int moved = 0;
            for (int k = 0; k < 4 && !moved; k++) {
                const double *e = k < 2 ? e1 : e2;
                double s = (k & 1) ? -sin(h) : sin(h), c = cos(h), w[3];
                for (int i = 0; i < 3; i++) w[i] = c * u[i] + s * e[i];
                double n = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
                for (int i = 0; i < 3; i++) w[i] /= n;
                double vw = sphere_value(f, ctx, p, r, w, sign);
                if (vw > v) {
                    v = vw;
                    memcpy(u, w, sizeof u);
                    moved = 1;
                }
            }
            if (!moved) h *= 0.5;
        }
        if (v > best) {
            best = v;
            memcpy(best_u, u, sizeof u);
        }
    }
    for (int i = 0; i < 3; i++) best_q[i] = p[i] + r * best_u[i];
    best_q[3] = p[3];
    return sign * best;
}

static double tape_point(void *ctx, const double q[4])
{
    return fm_eval_point((fm_evaluator *)ctx, q);
}

/* --------------------------------------------------- gradient users -- */

/* Lengths by hypot, which scales before squaring: the sum of squares
 * overflows above 1.3e154 (a gradient of 1e200 had no direction; a value of
 * 1e200 normalized to 0 instead of 1) and vanishes below 1e-154. */
static double norm3(double a, double b, double c)
{
    return hypot(hypot(a, b), c);
}

static double normalize_value(double v, const double g[3])
{
    return v / hypot(hypot(v, g[0]), hypot(g[1], g[2]));
}

static double normal_offset_point(fm_evaluator *sub, const double p[4], double d)
{
    double g[4];
    double v = fm_eval_grad(sub, p, g);
    double n = norm3(g[0], g[1], g[2]);
    if (!(n > 0) || !isfinite(n)) return v; /* no direction: the value in place */
    double q[4] = {p[0] + d * g[0] / n, p[1] + d * g[1] / n, p[2] + d * g[2] / n, p[3]};
    return fm_eval_point(sub, q);
}

static double normalize_point(fm_evaluator *sub, const double p[4])
{
    double g[4];
    double v = fm_eval_grad(sub, p, g);
    return normalize_value(v, g);
}

/* --------------------------------------------------------- dispatch -- */

double fm_special_point(fm_evaluator *ev, const fm_insn *in, const double p[4])
{
    const fm_special *sp = &ev->tape->shared->specials[in->aux];
    fm_evaluator *sub = ev->sub[in->aux];
    switch ((fm_op)sp->op) {
    case FM_OP_PROJECT: return project_search(sub, p, (int)sp->axis, sp->value, sp->value2, NULL);
    case FM_OP_BALL_MAX: {
        double q[4];
        return sphere_search(tape_point, sub, p, sp->value, BALL_SAMPLES, q);
    }
    case FM_OP_NORMAL_OFFSET: return normal_offset_point(sub, p, sp->value);
    case FM_OP_NORMALIZE: return normalize_point(sub, p);
    default: return NAN;
    }
}

fm_interval fm_special_interval(fm_evaluator *ev, const fm_insn *in, const fm_interval box[4],
                                int *maybe_nan)
{
    const fm_special *sp = &ev->tape->shared->specials[in->aux];
    fm_evaluator *sub = ev->sub[in->aux];
    fm_interval b[4], r = {-INFINITY, INFINITY};
    memcpy(b, box, sizeof b);
    *maybe_nan = 1;
    switch ((fm_op)sp->op) {
    case FM_OP_PROJECT:
        /* max over s of f lies between f's bounds over the box x [lo, hi]. */
        b[sp->axis].lo = sp->value;
        b[sp->axis].hi = sp->value2;
        return fm_eval_interval_nan(sub, b, maybe_nan);
    case FM_OP_BALL_MAX:
    case FM_OP_NORMAL_OFFSET: {
        /* Every point looked at is within |d| of the box. */
        double d = fabs(sp->value);
        for (int i = 0; i < 3; i++) {
            b[i].lo = nextafter(b[i].lo - d, -INFINITY);
            b[i].hi = nextafter(b[i].hi + d, INFINITY);
        }
        return fm_eval_interval_nan(sub, b, maybe_nan);
    }
    case FM_OP_NORMALIZE: {
        /* f / sqrt(f^2 + |grad f|^2) has the sign of f and modulus <= 1.
         * NaN stays possible (a gradient can be NaN where f is not). */
        int nan = 0;
        fm_interval f = fm_eval_interval_nan(sub, box, &nan);
        r.lo = f.lo > 0 ? 0.0 : -1.0;
        r.hi = f.hi < 0 ? 0.0 : 1.0;
        if (isnan(f.lo)) r.lo = -1.0, r.hi = 1.0;
        return r;
    }
    default: return r;
    }
}

/* Central differences of the special's value: the exact derivative of a
 * normal offset or a normalization needs second derivatives of the child. */
static double special_fd_grad(fm_evaluator *ev, const fm_insn *in, const double p[4], double g[4])
{
    double v = fm_special_point(ev, in, p);
    for (int i = 0; i < 4; i++) {
        double h = 1e-6 * (1.0 + fabs(p[i])), q[4];
        memcpy(q, p, sizeof q);
        q[i] = p[i] + h;
        double fp = fm_special_point(ev, in, q);
        q[i] = p[i] - h;
        double fm = fm_special_point(ev, in, q);
        g[i] = (fp - fm) / (2 * h);
    }
    return v;
}

double fm_special_grad(fm_evaluator *ev, const fm_insn *in, const double p[4], double grad[4])
{
    const fm_special *sp = &ev->tape->shared->specials[in->aux];
    fm_evaluator *sub = ev->sub[in->aux];
    switch ((fm_op)sp->op) {
    case FM_OP_PROJECT: {
        /* Envelope theorem: the gradient of the maximum is the child's
         * gradient at the maximizer, with no component along the axis. */
        double s, q[4];
        double v = project_search(sub, p, (int)sp->axis, sp->value, sp->value2, &s);
        memcpy(q, p, sizeof q);
        q[sp->axis] = s;
        fm_eval_grad(sub, q, grad);
        grad[sp->axis] = 0.0;
        return v;
    }
    case FM_OP_BALL_MAX: {
        double q[4];
        double v = sphere_search(tape_point, sub, p, sp->value, BALL_SAMPLES, q);
        fm_eval_grad(sub, q, grad);
        return v;
    }
    default: return special_fd_grad(ev, in, p, grad);
    }
}

/* ------------------------------------------------------------ voxels -- */

double fm_voxels_grad(const fm_voxel_grid *grid, double x, double y, double z, double d[3])
{
    double p[3] = {x, y, z};
    for (int i = 0; i < 3; i++) {
        double cell = (grid->hi[i] - grid->lo[i]) / (double)(grid->n[i] > 1 ? grid->n[i] - 1 : 1);
        double h = 1e-6 * cell, a[3], b[3];
        memcpy(a, p, sizeof a);
        memcpy(b, p, sizeof b);
        a[i] += h;
        b[i] -= h;
        d[i] = (fm_voxel_sample(grid, a[0], a[1], a[2]) - fm_voxel_sample(grid, b[0], b[1], b[2])) /
               (2 * h);
    }
    return fm_voxel_sample(grid, x, y, z);
}

/* Trilinear values are convex combinations of the sample values of the
 * cells the (clamped) box touches; outside the grid the distance to the
 * grid box is subtracted, which lies between its least and greatest value
 * over the box. */
fm_interval fm_voxels_interval(const fm_voxel_grid *grid, const fm_interval xyz[3])
{
    size_t first[3], last[3];
    double dmin2 = 0, dmax2 = 0;
    for (int i = 0; i < 3; i++) {
        double glo = grid->lo[i], ghi = grid->hi[i], lo = xyz[i].lo, hi = xyz[i].hi;
        double far = fmax(fmax(glo - lo, hi - ghi), 0.0), near = fmax(fmax(glo - hi, lo - ghi), 0.0);
        dmax2 += far * far;
        dmin2 += near * near;
        double cl = lo < glo ? glo : lo > ghi ? ghi : lo, ch = hi < glo ? glo : hi > ghi ? ghi : hi;
        double cells = (double)(grid->n[i] - 1);
        double sl = (cl - glo) / (ghi - glo) * cells, sh = (ch - glo) / (ghi - glo) * cells;
        /* One cell of slack each way covers the rounding of the index. */
        double fl = floor(sl) - 1, fh = floor(sh) + 2;
        first[i] = fl < 0 ? 0 : (size_t)fl;
        last[i] = fh > cells ? grid->n[i] - 1 : (size_t)fh;
    }
    double vmin = INFINITY, vmax = -INFINITY;
    size_t nx = grid->n[0], nxy = grid->n[0] * grid->n[1];
    for (size_t k = first[2]; k <= last[2]; k++)
        for (size_t j = first[1]; j <= last[1]; j++)
            for (size_t i = first[0]; i <= last[0]; i++) {
                double v = grid->values[i + nx * j + nxy * k];
                if (v < vmin) vmin = v;
                if (v > vmax) vmax = v;
            }
    double slack = 1e-12 * (fabs(vmin) + fabs(vmax) + sqrt(dmax2) + 1.0);
    fm_interval r = {vmin - sqrt(dmax2) - slack, vmax - sqrt(dmin2) + slack};
    return r;
}

/* -------------------------------------------------- reference forms -- */

typedef struct ref_ctx {
    const fm_graph *g;
    fm_node child;
} ref_ctx;

static double ref_point(void *ctx, const double q[4])
{
    const ref_ctx *c = ctx;
    return fm_graph_eval_reference(c->g, c->child, q);
}

static void ref_grad(const ref_ctx *c, const double p[4], double g[3])
{
    for (int i = 0; i < 3; i++) {
        double h = 1e-6 * (1.0 + fabs(p[i])), q[4];
        memcpy(q, p, sizeof q);
        q[i] = p[i] + h;
        double fp = ref_point((void *)c, q);
        q[i] = p[i] - h;
        g[i] = (fp - ref_point((void *)c, q)) / (2 * h);
    }
}

double fm_reference_special(const fm_graph *g, fm_node n, const double p[4])
{
    const fm_node_rec *r = fm_rec(g, n);
    ref_ctx c = {g, r->a};
    switch ((fm_op)r->op) {
    case FM_OP_PROJECT: {
        /* Dense samples, then golden-section refinement around the best. */
        enum { N = 2000 };
        double q[4], lo = r->value, hi = r->value2, best = -INFINITY, best_s = lo;
        memcpy(q, p, sizeof q);
        for (int i = 0; i <= N; i++) {
            q[r->aux] = lo + (hi - lo) * i / N;
            double v = ref_point(&c, q);
            if (v > best) best = v, best_s = q[r->aux];
        }
        double a = fmax(lo, best_s - (hi - lo) / N), b = fmin(hi, best_s + (hi - lo) / N);
        const double k = 0.6180339887498949;
        for (int i = 0; i < 100; i++) {
            double x1 = b - k * (b - a), x2 = a + k * (b - a);
            q[r->aux] = x1;
            double f1 = ref_point(&c, q);
            q[r->aux] = x2;
            double f2 = ref_point(&c, q);
            if (f1 > best) best = f1;
            if (f2 > best) best = f2;
            if (f1 >= f2) b = x2;
            else a = x1;
        }
        return best;
    }
    case FM_OP_BALL_MAX: {
        double q[4];
        return sphere_search(ref_point, &c, p, r->value, 2000, q);
    }
    case FM_OP_NORMAL_OFFSET: {
        double gr[3], v = ref_point(&c, p);
        ref_grad(&c, p, gr);
        double len = norm3(gr[0], gr[1], gr[2]);
        if (!(len > 0) || !isfinite(len)) return v;
        double q[4] = {p[0] + r->value * gr[0] / len, p[1] + r->value * gr[1] / len,
                       p[2] + r->value * gr[2] / len, p[3]};
        return ref_point(&c, q);
    }
    case FM_OP_NORMALIZE: {
        double gr[3], v = ref_point(&c, p);
        ref_grad(&c, p, gr);
        return normalize_value(v, gr);
    }
    case FM_OP_VOXELS: {
        if (r->aux >= g->grid_count) return NAN;
        double x = fm_graph_eval_reference(g, r->a, p), y = fm_graph_eval_reference(g, r->b, p),
               z = fm_graph_eval_reference(g, r->c, p);
        return fm_voxel_sample(&g->grids[r->aux], x, y, z);
    }
    default: return NAN;
    }
}
