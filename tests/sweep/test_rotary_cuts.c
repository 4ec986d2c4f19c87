/* test_rotary_cuts.c: 4-axis cuts in a level-set stock at 0.1 mm voxels
 * against volumes computed here another way. A round bar along X; A
 * carries the table about X (positive right-handed about +X).
 *  - a flat end mill plunged to radius r, then one full turn of A: the ring
 *    groove pi (R^2 - r^2) w;
 *  - on an eccentric bar, a flat pass at A = 0, A turned to 90, a second
 *    flat pass: the bar's cross-section minus two half-planes, integrated
 *    on a fine 2D grid here (the direction of A decides which side goes);
 *  - X and A together: a helical groove whose cross-section area is
 *    integrated here from the tool's slices (see helix_volume).
 * All within 0.5%. */
#include "test.h"
#include "stock/stock.h"
#include "sweep/sweep.h"

#include <stdlib.h>
#include <time.h>

#define BAR_HALF 20.0

/* A round bar along X: radius R about (y, z) = (yc, 0), |x| <= 20; exact
 * signed distance, positive inside. */
typedef struct bar {
    double R, yc;
} bar;

static double bar_eval(const bar *b, double x, double y, double z)
{
    double dr = hypot(y - b->yc, z) - b->R, dx = fabs(x) - BAR_HALF;
    double ox = fmax(dr, 0), oz = fmax(dx, 0);
    return -(sqrt(ox * ox + oz * oz) + fmin(fmax(dr, dx), 0));
}

static void bar_batch(void *ctx, void *worker, size_t n, const double *x, const double *y, const double *z,
                      double *out)
{
    (void)worker;
    for (size_t i = 0; i < n; i++) out[i] = bar_eval(ctx, x[i], y[i], z[i]);
}

static fm_interval bar_interval(void *ctx, void *worker, const fm_interval box[3])
{
    (void)worker;
    double c[3], r2 = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (box[k].lo + box[k].hi);
        r2 += 0.25 * (box[k].hi - box[k].lo) * (box[k].hi - box[k].lo);
    }
    double v = bar_eval(ctx, c[0], c[1], c[2]), r = sqrt(r2);
    return (fm_interval){v - r, v + r};
}

static fm_stock *bar_stock(bar *b)
{
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = b;
    f.batch = bar_batch;
    f.interval = bar_interval;
    f.lo[0] = -BAR_HALF, f.hi[0] = BAR_HALF;
    f.lo[1] = b->yc - b->R, f.hi[1] = b->yc + b->R;
    f.lo[2] = -b->R, f.hi[2] = b->R;
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = 0.1;
    fm_error err;
    fm_stock *s = fm_stock_new_from_field(&f, &o, &err);
    if (!s) fprintf(stderr, "stock: %s\n", err.message);
    return s;
}

static fm_machine indexer(void)
{
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 1;
    mc.rotary[0].letter = 0;
    mc.rotary[0].carries = FM_ROTARY_TABLE;
    mc.rotary[0].around[0] = 1;
    return mc;
}

static fm_motion move(const fm_machine *mc, const double from[3], const double to[3], double a0, double a1,
                      double t0)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_LINE;
    memcpy(m.start, from, sizeof m.start);
    memcpy(m.end, to, sizeof m.end);
    m.axis_start[2] = m.axis_end[2] = 1;
    m.machine = mc;
    m.rotary_start[0] = a0;
    m.rotary_end[0] = a1;
    m.t0 = t0;
    m.t1 = t0 + 1;
    m.block = -1;
    return m;
}

static int cut(fm_stock *s, const fm_motion *m, const fm_tool *t)
{
    fm_field f;
    fm_error err;
    if (fm_sweep_field(&f, m, &t->flutes, &err) != FM_OK) {
        fprintf(stderr, "sweep: %s\n", err.message);
        return 0;
    }
    fm_status st = fm_stock_subtract(s, &f, NULL, NULL, &err);
    fm_field_release(&f);
    if (st != FM_OK) fprintf(stderr, "cut: %s\n", err.message);
    return st == FM_OK;
}

static fm_tool flat(double diameter, double flutes)
{
    fm_tool_spec spec;
    memset(&spec, 0, sizeof spec);
    spec.number = 1;
    spec.shape = FM_TOOL_FLAT;
    spec.diameter = diameter;
    spec.flute_length = flutes;
    spec.length = flutes + 10;
    fm_tool t;
    fm_error err;
    if (fm_tool_build(&spec, &t, &err) != FM_OK) fprintf(stderr, "tool: %s\n", err.message);
    return t;
}

static double started;

static void report(const char *name, double got, double want)
{
    double rel = (got - want) / want;
    printf("%-16s removed %10.3f mm^3, expected %10.3f: %+.3f%% (%.1f s of CPU)\n", name, got, want, 100 * rel,
           fm_clock_cpu_s() - started);
    started = fm_clock_cpu_s();
    CHECK(fabs(rel) <= 0.005);
}

/* Plunge to radius r, then one turn of A under the still tool. */
static void check_ring_groove(void)
{
    bar b = {10, 0};
    double r = 6, w = 6;
    fm_stock *s = bar_stock(&b);
    CHECK(s != NULL);
    if (!s) return;
    fm_machine mc = indexer();
    fm_tool t = flat(w, 12);
    double above[3] = {0, 0, 15}, down[3] = {0, 0, r};
    fm_motion plunge = move(&mc, above, down, 0, 0, 0);
    fm_motion turn = move(&mc, down, down, 0, 360, 1);
    CHECK(cut(s, &plunge, &t));
    CHECK(cut(s, &turn, &t));
    report("ring groove", fm_stock_removed_volume(s), FM_PI * (b.R * b.R - r * r) * w);
    fm_stock_free(s);
}

/* Two flat passes of a 30 mm end mill over the whole bar: at A = 0 at
 * z = 7 (the workpiece loses z >= 7), A turned to 90, at z = 5. A point
 * p of the workpiece is at Rx(90) p on the machine, whose z is p's y: the
 * second pass takes y >= 5. On the bar centred at y = 2 the other sense
 * (y <= -5) would take a much smaller segment. */
static void check_indexed(void)
{
    bar b = {10, 2};
    fm_stock *s = bar_stock(&b);
    CHECK(s != NULL);
    if (!s) return;
    fm_machine mc = indexer();
    fm_tool t = flat(30, 30);
    double p0[3] = {-40, 0, 30}, p1[3] = {-40, 0, 7}, p2[3] = {40, 0, 7}, p3[3] = {40, 0, 30};
    double q1[3] = {40, 0, 5}, q2[3] = {-40, 0, 5}, q3[3] = {-40, 0, 30};
    fm_motion ms[] = {move(&mc, p0, p1, 0, 0, 0),  move(&mc, p1, p2, 0, 0, 1),   move(&mc, p2, p3, 0, 0, 2),
                      move(&mc, p3, p3, 0, 90, 3), move(&mc, p3, q1, 90, 90, 4), move(&mc, q1, q2, 90, 90, 5),
                      move(&mc, q2, q3, 90, 90, 6)};
    for (size_t i = 0; i < sizeof ms / sizeof ms[0]; i++) CHECK(cut(s, &ms[i], &t));
    /* The cross-section removed: disk (centre (2, 0), radius 10) with z >= 7
     * or y >= 5, midpoint rule on a 4000 x 4000 grid. */
    int n = 4000;
    double h = 2 * b.R / n, area = 0;
    for (int i = 0; i < n; i++) {
        double y = b.yc - b.R + (i + 0.5) * h;
        for (int j = 0; j < n; j++) {
            double z = -b.R + (j + 0.5) * h;
            if ((y - b.yc) * (y - b.yc) + z * z <= b.R * b.R && (z >= 7 || y >= 5)) area += h * h;
        }
    }
    report("indexed flats", fm_stock_removed_volume(s), area * 2 * BAR_HALF);
    fm_stock_free(s);
}

/* The helical groove: a flat end mill (radius a) with its tip at radius r
 * above the axis while X goes from x0 to x1 and A from 0 to Theta. At time
 * u the tool (machine frame) is |x - X(u)|^2 + y^2 <= a^2, z >= r; a
 * workpiece point at (x, rho, phi) (phi from +y towards +z) is on the
 * machine at angle phi + theta(u), so it is cut when for some u, with
 * s = x - X(u) and psi = phi + theta(u): rho sin psi >= r and
 * rho |cos psi| <= sqrt(a^2 - s^2), i.e. psi within alpha(rho, s) =
 * min(acos(r / rho), asin(sqrt(a^2 - s^2) / rho)) of pi/2. For fixed x and
 * rho the covered phi form one interval (a continuous family of intervals
 * over the u with |s| <= a): from min over u of (pi/2 - alpha - theta) to
 * max of (pi/2 + alpha - theta), capped at 2 pi. The volume integrates that
 * over rho dr and x (midpoint rules; u sampled finely). */
static double helix_volume(double R, double r, double a, double x0, double x1, double Theta)
{
    int nx = 800, nr = 300, nu = 600;
    double vol = 0, hx = (x1 - x0 + 2 * a) / nx, hr = (R - r) / nr;
    for (int ix = 0; ix < nx; ix++) {
        double x = x0 - a + (ix + 0.5) * hx;
        /* u where |x - X(u)| <= a */
        double ua = (x - a - x0) / (x1 - x0), ub = (x + a - x0) / (x1 - x0);
        ua = fmax(ua, 0), ub = fmin(ub, 1);
        if (ub <= ua) continue;
        double area = 0;
        for (int ir = 0; ir < nr; ir++) {
            double rho = r + (ir + 0.5) * hr;
            double lo = INFINITY, hi = -INFINITY;
            for (int k = 0; k <= nu; k++) {
                double u = ua + (ub - ua) * k / nu, s = x - (x0 + u * (x1 - x0)), th = u * Theta;
                double c2 = a * a - s * s;
                if (c2 < 0) c2 = 0;
                double alpha = fmin(acos(r / rho), asin(fmin(1, sqrt(c2) / rho)));
                lo = fmin(lo, FM_PI / 2 - alpha - th);
                hi = fmax(hi, FM_PI / 2 + alpha - th);
            }
            area += fmin(2 * FM_PI, hi - lo) * rho * hr;
        }
        vol += area * hx;
    }
    return vol;
}

static void check_helix(void)
{
    bar b = {10, 0};
    double r = 7, w = 4, x0 = -10, x1 = 10, Theta = 720;
    fm_stock *s = bar_stock(&b);
    CHECK(s != NULL);
    if (!s) return;
    fm_machine mc = indexer();
    fm_tool t = flat(w, 12);
    double above[3] = {x0, 0, 15}, down[3] = {x0, 0, r}, end[3] = {x1, 0, r};
    fm_motion plunge = move(&mc, above, down, 0, 0, 0);
    fm_motion helix = move(&mc, down, end, 0, Theta, 1);
    CHECK(cut(s, &plunge, &t));
    CHECK(cut(s, &helix, &t));
    report("helical groove", fm_stock_removed_volume(s), helix_volume(b.R, r, w / 2, x0, x1, Theta * FM_PI / 180));
    fm_stock_free(s);
}

int main(void)
{
    started = fm_clock_cpu_s();
    check_ring_groove();
    check_indexed();
    check_helix();
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
