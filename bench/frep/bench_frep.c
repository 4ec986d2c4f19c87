/* bench_frep.c: point evaluations per second of the batch evaluator on a
 * ~100-node CSG model (a plate of blocks and cylinders minus a grid of
 * holes, plus spheres, all from basic nodes), against a floor (the same
 * model as a hand-written C function over the same points), and the time
 * with tapes shortened per box (16^3 boxes over the bounds, libfive style)
 * against the full tape over the same points. Prints figures; not a test. */
#include "frep/frep.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_clock.h"

/* The model, once as a DAG and once as plain C. Half-width box:
 * min over axes of (h - |p - c|). */
static fm_node g_block(fm_graph *g, double cx, double cy, double cz, double hx, double hy, double hz)
{
    double c[3] = {cx, cy, cz}, h[3] = {hx, hy, hz};
    fm_node r = FM_NONE;
    for (int i = 0; i < 3; i++) {
        fm_node d = fm_sub(g, fm_const(g, h[i]), fm_abs(g, fm_sub(g, fm_var(g, i), fm_const(g, c[i]))));
        r = r ? fm_min(g, r, d) : d;
    }
    return r;
}

static double c_block(const double p[3], double cx, double cy, double cz, double hx, double hy, double hz)
{
    double a = hx - fabs(p[0] - cx), b = hy - fabs(p[1] - cy), c = hz - fabs(p[2] - cz);
    double m = a < b ? a : b;
    return m < c ? m : c;
}

/* Vertical cylinder (along z) of radius r between z0 and z1. */
static fm_node g_cyl(fm_graph *g, double cx, double cy, double r, double z0, double z1)
{
    fm_node dx = fm_sub(g, fm_var(g, FM_X), fm_const(g, cx)), dy = fm_sub(g, fm_var(g, FM_Y), fm_const(g, cy));
    fm_node radial = fm_sub(g, fm_const(g, r), fm_sqrt(g, fm_add(g, fm_square(g, dx), fm_square(g, dy))));
    fm_node zc = fm_sub(g, fm_const(g, 0.5 * (z1 - z0)),
                        fm_abs(g, fm_sub(g, fm_var(g, FM_Z), fm_const(g, 0.5 * (z0 + z1)))));
    return fm_min(g, radial, zc);
}

static double c_cyl(const double p[3], double cx, double cy, double r, double z0, double z1)
{
    double dx = p[0] - cx, dy = p[1] - cy;
    double radial = r - sqrt(dx * dx + dy * dy), zc = 0.5 * (z1 - z0) - fabs(p[2] - 0.5 * (z0 + z1));
    return radial < zc ? radial : zc;
}

static fm_node g_sphere(fm_graph *g, double cx, double cy, double cz, double r)
{
    fm_node dx = fm_sub(g, fm_var(g, FM_X), fm_const(g, cx)), dy = fm_sub(g, fm_var(g, FM_Y), fm_const(g, cy)),
            dz = fm_sub(g, fm_var(g, FM_Z), fm_const(g, cz));
    return fm_sub(g, fm_const(g, r),
                  fm_sqrt(g, fm_add(g, fm_add(g, fm_square(g, dx), fm_square(g, dy)), fm_square(g, dz))));
}

static double c_sphere(const double p[3], double cx, double cy, double cz, double r)
{
    double dx = p[0] - cx, dy = p[1] - cy, dz = p[2] - cz;
    return r - sqrt(dx * dx + dy * dy + dz * dz);
}

#define HOLES 3
static const double hole_x[HOLES] = {-6, 0, 6}, hole_y[HOLES] = {-6, 0, 6};

static fm_node build_model(fm_graph *g)
{
    fm_node plate = g_block(g, 0, 0, 0, 10, 10, 1.5);
    fm_node boss = g_cyl(g, 0, 0, 3, 0, 5);
    fm_node rib = g_block(g, 0, -8, 2, 9, 1, 1);
    fm_node ball = g_sphere(g, 7, 7, 2, 2.5);
    fm_node u = fm_max(g, fm_max(g, plate, boss), fm_max(g, rib, ball));
    for (int i = 0; i < HOLES; i++)
        for (int j = 0; j < HOLES; j++) {
            if (i == 1 && j == 1) continue;
            fm_node hole = g_cyl(g, hole_x[i], hole_y[j], 1.0, -3, 3);
            u = fm_min(g, u, fm_neg(g, hole));
        }
    return u;
}

static double c_model(const double p[3])
{
    double plate = c_block(p, 0, 0, 0, 10, 10, 1.5), boss = c_cyl(p, 0, 0, 3, 0, 5);
    double rib = c_block(p, 0, -8, 2, 9, 1, 1), ball = c_sphere(p, 7, 7, 2, 2.5);
    double a = plate > boss ? plate : boss, b = rib > ball ? rib : ball, u = a > b ? a : b;
    for (int i = 0; i < HOLES; i++)
        for (int j = 0; j < HOLES; j++) {
            if (i == 1 && j == 1) continue;
            double h = -c_cyl(p, hole_x[i], hole_y[j], 1.0, -3, 3);
            u = u < h ? u : h;
        }
    return u;
}

static void c_batch(size_t n, const double *x, const double *y, const double *z, double *out)
{
    for (size_t i = 0; i < n; i++) {
        double p[3] = {x[i], y[i], z[i]};
        out[i] = c_model(p);
    }
}

int main(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node model = build_model(g);
    fm_error err;
    fm_tape *tape = fm_tape_compile(g, model, &err);
    if (!tape) {
        fprintf(stderr, "compile failed: %s\n", err.message);
        return 1;
    }
    fm_evaluator *ev = fm_evaluator_new(tape, &err);
    printf("model: %zu DAG nodes, %zu tape instructions\n", fm_graph_node_count(g), fm_tape_length(tape));

    /* Grid over the bounds: B boxes per axis, P points per box axis. */
    enum { B = 16, P = 8 };
    const double lo[3] = {-11, -11, -2.5}, hi[3] = {11, 11, 5.5};
    size_t n = (size_t)B * B * B * P * P * P;
    double *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y), *z = malloc(n * sizeof *z);
    double *out = malloc(n * sizeof *out), *ref = malloc(n * sizeof *ref);
    if (!x || !y || !z || !out || !ref) return 1;
    /* Points stored box by box, so that each box's points are contiguous. */
    size_t k = 0;
    double w[3];
    for (int i = 0; i < 3; i++) w[i] = (hi[i] - lo[i]) / B;
    for (int bz = 0; bz < B; bz++)
        for (int by = 0; by < B; by++)
            for (int bx = 0; bx < B; bx++)
                for (int pz = 0; pz < P; pz++)
                    for (int py = 0; py < P; py++)
                        for (int px = 0; px < P; px++, k++) {
                            x[k] = lo[0] + w[0] * (bx + (px + 0.5) / P);
                            y[k] = lo[1] + w[1] * (by + (py + 0.5) / P);
                            z[k] = lo[2] + w[2] * (bz + (pz + 0.5) / P);
                        }

    const int reps = 5;
    double t0 = bench_wall_s();
    for (int r = 0; r < reps; r++) fm_eval_batch(ev, n, x, y, z, NULL, out);
    double t_full = (bench_wall_s() - t0) / reps;
    t0 = bench_wall_s();
    for (int r = 0; r < reps; r++) c_batch(n, x, y, z, ref);
    double t_c = (bench_wall_s() - t0) / reps;
    double maxdiff = 0;
    for (size_t i = 0; i < n; i++) maxdiff = fmax(maxdiff, fabs(out[i] - ref[i]));

    /* Shortened: per box, interval + shorten, then the box's points. */
    size_t per_box = (size_t)P * P * P, total_len = 0, shortened = 0;
    double t_short = 0;
    for (int r = 0; r < reps; r++) {
        t0 = bench_wall_s();
        size_t b = 0;
        for (int bz = 0; bz < B; bz++)
            for (int by = 0; by < B; by++)
                for (int bx = 0; bx < B; bx++, b++) {
                    fm_interval box[4] = {{lo[0] + w[0] * bx, lo[0] + w[0] * (bx + 1)},
                                          {lo[1] + w[1] * by, lo[1] + w[1] * (by + 1)},
                                          {lo[2] + w[2] * bz, lo[2] + w[2] * (bz + 1)},
                                          {0, 0}};
                    fm_interval iv;
                    fm_tape *s = fm_eval_interval_shorten(ev, box, &iv);
                    if (s) fm_evaluator_use(ev, s);
                    size_t off = b * per_box;
                    fm_eval_batch(ev, per_box, x + off, y + off, z + off, NULL, out + off);
                    if (r == 0) {
                        total_len += s ? fm_tape_length(s) : fm_tape_length(tape);
                        shortened += s != NULL;
                    }
                    if (s) {
                        fm_evaluator_use(ev, NULL);
                        fm_tape_free(s);
                    }
                }
        t_short += bench_wall_s() - t0;
    }
    t_short /= reps;
    double maxdiff_short = 0;
    for (size_t i = 0; i < n; i++) maxdiff_short = fmax(maxdiff_short, fabs(out[i] - ref[i]));

    printf("points: %zu (%d^3 boxes x %d^3 points)\n", n, B, P);
    printf("full tape batch:      %.3g points/s (%.2f ns/point)\n", n / t_full, 1e9 * t_full / n);
    printf("hand-written C floor: %.3g points/s (%.2f ns/point)\n", n / t_c, 1e9 * t_c / n);
    printf("tape / floor time ratio: %.2f  (max |difference| %.3g)\n", t_full / t_c, maxdiff);
    printf("shortened per box:    %.3g points/s, time ratio shortened / full = %.2f\n", n / t_short,
           t_short / t_full);
    printf("  boxes shortened %zu of %d, mean tape length %.1f of %zu (max |diff| %.3g)\n", shortened,
           B * B * B, (double)total_len / (B * B * B), fm_tape_length(tape), maxdiff_short);

    /* Point evaluator for comparison. */
    t0 = bench_wall_s();
    double sink = 0;
    for (size_t i = 0; i < n; i++) {
        double p[4] = {x[i], y[i], z[i], 0};
        sink += fm_eval_point(ev, p);
    }
    double t_point = bench_wall_s() - t0;
    printf("point evaluator:      %.3g points/s (checksum %.6g)\n", n / t_point, sink);

    free(x);
    free(y);
    free(z);
    free(out);
    free(ref);
    fm_evaluator_free(ev);
    fm_tape_free(tape);
    fm_graph_free(g);
    return 0;
}
