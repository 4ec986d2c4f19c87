/* test_special.c: the special ops (projection, constant-radius offset,
 * normal offset, normalization, voxels) against brute-force sampling and
 * closed forms, in point, batch, interval and gradient modes, and against
 * the reference evaluator. */
#include "frep/tape_internal.h"
#include "test.h"
#include "frep_shapes.h"

static fm_node special(fm_graph *g, fm_op op, fm_node child, uint32_t aux, double v, double v2)
{
    fm_node_rec r = {0};
    r.op = (uint8_t)op;
    r.a = child;
    r.aux = aux;
    r.value = v;
    r.value2 = v2;
    return fm_graph_intern(g, &r);
}

static void sample_box(const fm_interval box[4], double p[4])
{
    for (int i = 0; i < 4; i++) p[i] = test_uniform(box[i].lo, box[i].hi);
}

/* Sampled values inside the interval over random boxes. */
static void check_interval_sound(fm_evaluator *ev, double half, int boxes, int samples)
{
    for (int b = 0; b < boxes; b++) {
        fm_interval box[4];
        for (int i = 0; i < 4; i++) {
            double c = test_uniform(-2, 2), w = test_uniform(0, half);
            box[i].lo = c - w;
            box[i].hi = c + w;
        }
        fm_interval r = fm_eval_interval(ev, box);
        for (int k = 0; k < samples; k++) {
            double p[4];
            sample_box(box, p);
            double v = fm_eval_point(ev, p);
            CHECK(isnan(v) || (r.lo <= v && v <= r.hi));
        }
    }
}

/* A child with several local maxima in t: projection vs 100,000 samples. */
static void check_project_nonconcave(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), t = fm_var(g, FM_T);
    fm_node f = fm_add(g, fm_mul(g, fm_unary(g, FM_OP_SIN, fm_mul(g, fm_const(g, 3.0), t)),
                                 fm_unary(g, FM_OP_COS, x)),
                       fm_mul(g, fm_const(g, 0.3),
                              fm_unary(g, FM_OP_SIN, fm_add(g, fm_mul(g, fm_const(g, 7.0), t), y))));
    f = fm_sub(g, f, fm_mul(g, fm_const(g, 0.1), fm_square(g, fm_sub(g, t, fm_const(g, 0.5)))));
    fm_node pr = special(g, FM_OP_PROJECT, f, FM_T, 0.0, 2.0);
    fm_error err;
    fm_tape *tp = fm_tape_compile(g, pr, &err), *tf = fm_tape_compile(g, f, &err);
    fm_evaluator *ev = fm_evaluator_new(tp, &err), *ef = fm_evaluator_new(tf, &err);
    for (int k = 0; k < 12; k++) {
        double p[4] = {test_uniform(-2, 2), test_uniform(-2, 2), 0, test_uniform(-5, 5)};
        double brute = -INFINITY;
        for (int i = 0; i <= 100000; i++) {
            double q[4] = {p[0], p[1], p[2], 2.0 * i / 100000.0};
            double v = fm_eval_point(ef, q);
            if (v > brute) brute = v;
        }
        double got = fm_eval_point(ev, p);
        CHECK_NEAR(got, brute, 1e-6);
        CHECK(got >= brute - 1e-12); /* a maximum is never below a sample */
        CHECK_NEAR(fm_graph_eval_reference(g, pr, p), brute, 1e-6);
    }
    check_interval_sound(ev, 0.5, 10, 20);
    fm_evaluator_free(ev);
    fm_evaluator_free(ef);
    fm_tape_free(tp);
    fm_tape_free(tf);
    fm_graph_free(g);
}

/* A ball of radius r moving along x from 0 to L over t in [0, 1]: the
 * projection is the capsule r - dist(p, segment). */
static void check_project_capsule(void)
{
    const double r = 0.5, L = 3.0;
    fm_graph *g = fm_graph_new(0);
    fm_node moving = fm_sub(g, fm_var(g, FM_X), fm_mul(g, fm_const(g, L), fm_var(g, FM_T)));
    fm_node d = fm_sqrt(g, fm_add(g, fm_add(g, fm_square(g, moving), fm_square(g, fm_var(g, FM_Y))),
                                  fm_square(g, fm_var(g, FM_Z))));
    fm_node ball = fm_sub(g, fm_const(g, r), d);
    fm_node cap = special(g, FM_OP_PROJECT, ball, FM_T, 0.0, 1.0);
    fm_error err;
    fm_tape *tp = fm_tape_compile(g, cap, &err);
    fm_evaluator *ev = fm_evaluator_new(tp, &err);
    double xs[64], ys[64], zs[64], out[64];
    for (int k = 0; k < 64; k++) {
        double p[4] = {test_uniform(-1, 4), test_uniform(-1, 1), test_uniform(-1, 1), 0};
        double sx = p[0] < 0 ? 0 : p[0] > L ? L : p[0];
        double exact = r - sqrt((p[0] - sx) * (p[0] - sx) + p[1] * p[1] + p[2] * p[2]);
        CHECK_NEAR(fm_eval_point(ev, p), exact, 1e-7);
        double grad[4];
        double v = fm_eval_grad(ev, p, grad);
        CHECK_NEAR(v, exact, 1e-7);
        double dist = r - exact;
        CHECK_NEAR(grad[0], -(p[0] - sx) / dist, 1e-5);
        CHECK_NEAR(grad[1], -p[1] / dist, 1e-5);
        CHECK_NEAR(grad[3], 0.0, 0.0);
        xs[k] = p[0];
        ys[k] = p[1];
        zs[k] = p[2];
    }
    fm_eval_batch(ev, 64, xs, ys, zs, NULL, out);
    for (int k = 0; k < 64; k++) {
        double p[4] = {xs[k], ys[k], zs[k], 0};
        CHECK(out[k] == fm_eval_point(ev, p));
    }
    check_interval_sound(ev, 0.7, 20, 20);
    fm_evaluator_free(ev);
    fm_tape_free(tp);
    fm_graph_free(g);
}

/* Offsets of a sphere have closed forms: both the ball max (d > 0 grows, d
 * < 0 shrinks) and the normal offset give r + d - |p|. */
static void check_offsets_and_normalize(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node s = shape_sphere(g, 0.2, -0.1, 0.3, 1.0);
    fm_node grow = special(g, FM_OP_BALL_MAX, s, 0, 0.5, 0);
    fm_node shrink = special(g, FM_OP_BALL_MAX, s, 0, -0.25, 0);
    fm_node noff = special(g, FM_OP_NORMAL_OFFSET, s, 0, 0.4, 0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z);
    fm_node q = fm_sub(g, fm_const(g, 4.0),
                       fm_add(g, fm_add(g, fm_square(g, x), fm_square(g, y)), fm_square(g, z)));
    fm_node nq = special(g, FM_OP_NORMALIZE, q, 0, 0, 0);
    fm_node nodes[4] = {grow, shrink, noff, nq};
    for (int n = 0; n < 4; n++) {
        fm_error err;
        fm_tape *tp = fm_tape_compile(g, nodes[n], &err);
        fm_evaluator *ev = fm_evaluator_new(tp, &err);
        for (int k = 0; k < 40; k++) {
            double p[4] = {test_uniform(-3, 3), test_uniform(-3, 3), test_uniform(-3, 3), 0};
            double base = sphere_value(0.2, -0.1, 0.3, 1.0, p);
            double exact;
            if (n == 0) exact = base + 0.5;
            else if (n == 1) exact = base - 0.25;
            else if (n == 2) exact = base + 0.4;
            else {
                double f = 4 - p[0] * p[0] - p[1] * p[1] - p[2] * p[2];
                exact = f / sqrt(f * f + 4 * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
            }
            /* The sphere offsets need |p - c| > |d| (the offset of the
             * centre region is not a sphere function any more). */
            if (n < 3 && 1.0 - base < 0.6) continue;
            double v = fm_eval_point(ev, p);
            CHECK_NEAR(v, exact, 1e-9);
            CHECK_NEAR(fm_graph_eval_reference(g, nodes[n], p), exact, 1e-6);
            double grad[4], h = 1e-5;
            CHECK_NEAR(fm_eval_grad(ev, p, grad), v, 1e-12);
            for (int i = 0; i < 3; i++) {
                double a[4] = {p[0], p[1], p[2], p[3]}, b[4] = {p[0], p[1], p[2], p[3]};
                a[i] += h;
                b[i] -= h;
                double fd = (fm_eval_point(ev, a) - fm_eval_point(ev, b)) / (2 * h);
                CHECK_NEAR(grad[i], fd, 1e-5);
            }
        }
        check_interval_sound(ev, 0.8, 20, 20);
        fm_evaluator_free(ev);
        fm_tape_free(tp);
    }
    fm_graph_free(g);
}

/* Values and gradients beyond 1e154, whose squares overflow: f = 1e200 (x +
 * 2) normalizes to (x + 2) / sqrt((x + 2)^2 + 1) as if the factor were 1
 * (not to 0), its normal offset moves along x, and half-spaces with normals of length 1e200 or 1e-200 are the
 * half-space x <= 1 (issue 22: lengths by hypot). */
static void check_huge_normalize(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node f = fm_mul(g, fm_const(g, 1e200), fm_add(g, fm_var(g, FM_X), fm_const(g, 2.0)));
    fm_node nodes[2] = {fm_normalize(g, f), special(g, FM_OP_NORMAL_OFFSET, f, 0, 0.5, 0)};
    for (int n = 0; n < 2; n++) {
        fm_error err;
        fm_tape *tp = fm_tape_compile(g, nodes[n], &err);
        fm_evaluator *ev = fm_evaluator_new(tp, &err);
        for (int k = 0; k < 20; k++) {
            double p[4] = {test_uniform(-1, 3), test_uniform(-3, 3), test_uniform(-3, 3), 0};
            /* normal offset: f at x + 0.5 (the gradient points along +x) */
            double exact = n == 0 ? (p[0] + 2) / sqrt((p[0] + 2) * (p[0] + 2) + 1) : 1e200 * (p[0] + 2.5);
            CHECK_NEAR(fm_eval_point(ev, p), exact, 1e-12 * fabs(exact));
            CHECK_NEAR(fm_graph_eval_reference(g, nodes[n], p), exact, 1e-6 * fabs(exact));
        }
        fm_evaluator_free(ev);
        fm_tape_free(tp);
    }
    for (int k = 0; k < 2; k++) {
        double len = k ? 1e-200 : 1e200, nrm[3] = {len, 0, 0};
        fm_node h = fm_halfspace(g, nrm, len);
        CHECK(h != FM_NONE);
        if (h == FM_NONE) continue;
        double p[4] = {0.25, 7, -3, 0};
        CHECK_NEAR(fm_graph_eval_reference(g, h, p), 0.75, 1e-15);
    }
    fm_graph_free(g);
}

/* A grid sampled from a linear function is reproduced exactly by trilinear
 * interpolation inside; outside, the rule of fm_voxels applies. The tape
 * agrees with the reference, and intervals are sound across the edges. */
static void check_voxels(void)
{
    fm_graph *g = fm_graph_new(0);
    enum { NX = 9, NY = 7, NZ = 5 };
    static float v[NX * NY * NZ];
    double lo[3] = {-1, -1, -1}, hi[3] = {1, 2, 0.5};
    for (int k = 0; k < NZ; k++)
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++) {
                double x = lo[0] + (hi[0] - lo[0]) * i / (NX - 1);
                double y = lo[1] + (hi[1] - lo[1]) * j / (NY - 1);
                double z = lo[2] + (hi[2] - lo[2]) * k / (NZ - 1);
                v[i + NX * (j + NY * k)] = (float)(0.5 * x - 0.25 * y + 0.125 * z);
            }
    fm_node vox = fm_voxels(g, lo, hi, NX, NY, NZ, v);
    CHECK(vox != FM_NONE);
    fm_node both[1] = {vox};
    for (int n = 0; n < 1; n++) {
        fm_error err;
        fm_tape *tp = fm_tape_compile(g, both[n], &err);
        CHECK(tp != NULL);
        if (!tp) {
            fprintf(stderr, "voxels: %s\n", err.message);
            continue;
        }
        fm_evaluator *ev = fm_evaluator_new(tp, &err);
        for (int k = 0; k < 200; k++) {
            double p[4] = {test_uniform(-2, 2), test_uniform(-2, 3), test_uniform(-2, 2), 0};
            double got = fm_eval_point(ev, p);
            CHECK(got == fm_graph_eval_reference(g, both[n], p));
            double x = p[0] - (n ? 0.5 : 0.0);
            if (x > lo[0] && x < hi[0] && p[1] > lo[1] && p[1] < hi[1] && p[2] > lo[2] &&
                p[2] < hi[2])
                CHECK_NEAR(got, 0.5 * x - 0.25 * p[1] + 0.125 * p[2], 1e-6);
            double grad[4];
            CHECK(fm_eval_grad(ev, p, grad) == got);
        }
        check_interval_sound(ev, 0.6, 60, 30);
        fm_evaluator_free(ev);
        fm_tape_free(tp);
    }
    fm_graph_free(g);
}

/* Nesting depth is bounded: a tower of projections deeper than the limit
 * is refused with an error, not a crash. */
static void check_depth_limit(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node f = shape_sphere(g, 0, 0, 0, 1);
    for (int i = 0; i < FM_TAPE_MAX_DEPTH + 2; i++) f = special(g, FM_OP_NORMALIZE, f, 0, 0, 0);
    fm_error err;
    fm_error_clear(&err);
    fm_tape *t = fm_tape_compile(g, f, &err);
    CHECK(t == NULL);
    CHECK(err.code == FM_ERR_LIMIT);
    fm_graph_free(g);
}

int main(void)
{
    check_project_nonconcave();
    check_project_capsule();
    check_offsets_and_normalize();
    check_huge_normalize();
    check_voxels();
    check_depth_limit();
    return test_summary("test_special");
}
