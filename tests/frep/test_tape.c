/* test_tape.c: the tape compiler and the point and batch evaluators against
 * the reference evaluator (fm_graph_eval_reference) on random DAGs over
 * every non-special op, the min/max rewrite rules, parameters, and limits. */
#include "frep/frep_internal.h" /* fm_graph_eval_reference */
#include "test.h"
#include "frep_random.h"

#include <stdlib.h>

static void check_random_dags(int minmax_heavy)
{
    int mismatches = 0, compared = 0;
    for (int trial = 0; trial < 300; trial++) {
        fm_graph *g = fm_graph_new(0);
        fm_node root = random_dag(g, 10 + (size_t)(test_rand01() * 60), minmax_heavy);
        fm_error err;
        fm_error_clear(&err);
        fm_tape *tape = fm_tape_compile(g, root, &err);
        CHECK(tape != NULL);
        if (!tape) {
            fm_graph_free(g);
            continue;
        }
        fm_evaluator *ev = fm_evaluator_new(tape, &err);
        CHECK(ev != NULL);
        enum { NPTS = 300 };
        double xs[NPTS], ys[NPTS], zs[NPTS], ts[NPTS], out[NPTS];
        for (int i = 0; i < NPTS; i++) {
            double p[4];
            random_point(p);
            xs[i] = p[0];
            ys[i] = p[1];
            zs[i] = p[2];
            ts[i] = p[3];
            double ref = fm_graph_eval_reference(g, root, p);
            double got = fm_eval_point(ev, p);
            compared++;
            if (!same(ref, got)) {
                if (mismatches++ < 5)
                    fprintf(stderr, "trial %d point %d: reference %.17g, tape %.17g\n", trial, i,
                            ref, got);
            }
        }
        fm_eval_batch(ev, NPTS, xs, ys, zs, ts, out);
        for (int i = 0; i < NPTS; i++) {
            double p[4] = {xs[i], ys[i], zs[i], ts[i]};
            double pt = fm_eval_point(ev, p);
            if (!same(pt, out[i])) {
                if (mismatches++ < 5)
                    fprintf(stderr, "trial %d point %d: point %.17g, batch %.17g\n", trial, i, pt,
                            out[i]);
            }
        }
        fm_evaluator_free(ev);
        fm_tape_free(tape);
        fm_graph_free(g);
    }
    CHECK(compared > 0);
    CHECK(mismatches == 0);
}

static size_t length_of(fm_graph *g, fm_node root)
{
    fm_error err;
    fm_tape *t = fm_tape_compile(g, root, &err);
    size_t n = t ? fm_tape_length(t) : (size_t)-1;
    fm_tape_free(t);
    return n;
}

static double value_at(fm_graph *g, fm_node root, const double p[4])
{
    fm_error err;
    fm_tape *t = fm_tape_compile(g, root, &err);
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    double v = ev ? fm_eval_point(ev, p) : NAN;
    fm_evaluator_free(ev);
    fm_tape_free(t);
    return v;
}

static void check_rewrites(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z);
    fm_node a = fm_sub(g, x, fm_const(g, 1.0)); /* 1 instruction */
    fm_node b = fm_add(g, y, fm_const(g, 2.0)); /* 1 instruction */
    fm_node c = fm_mul(g, z, fm_const(g, 3.0)); /* 1 instruction */
    /* max(-a, -b) = -min(a, b): neg, neg, max (3) becomes min, neg (2). */
    fm_node mm = fm_max(g, fm_neg(g, a), fm_neg(g, b));
    CHECK(length_of(g, mm) == 2 + 2);
    /* min(a, min(a, b)) = min(a, b). */
    fm_node m1 = fm_min(g, a, fm_min(g, a, b));
    CHECK(length_of(g, m1) == 2 + 1);
    /* Absorption: min(a, max(a, b)) = a. */
    fm_node ab = fm_min(g, a, fm_max(g, a, b));
    CHECK(length_of(g, ab) == 1);
    /* Nested chains flatten: min(min(a, 1), min(b, min(c, 0.5))) keeps one constant. */
    fm_node ch = fm_min(g, fm_min(g, a, fm_const(g, 1.0)),
                        fm_min(g, b, fm_min(g, c, fm_const(g, 0.5))));
    CHECK(length_of(g, ch) == 3 + 3);
    /* max(a, b) with b containing a NaN source (log) is left alone. */
    fm_node l = fm_max(g, a, fm_max(g, a, fm_unary(g, FM_OP_LOG, b)));
    CHECK(length_of(g, l) == 2 + 1 + 2);
    for (int i = 0; i < 200; i++) {
        double p[4];
        random_point(p);
        double ai = p[0] - 1, bi = p[1] + 2, ci = p[2] * 3;
        CHECK(value_at(g, mm, p) == fmax(-ai, -bi));
        CHECK(value_at(g, m1, p) == fmin(ai, bi));
        CHECK(value_at(g, ab, p) == ai);
        CHECK(value_at(g, ch, p) == fmin(fmin(ai, 1.0), fmin(bi, fmin(ci, 0.5))));
        CHECK(same(value_at(g, l, p), fm_graph_eval_reference(g, l, p)));
    }
    fm_graph_free(g);
}

static void check_leaves_and_params(void)
{
    fm_graph *g = fm_graph_new(0);
    double p[4] = {1.5, -2.0, 0.25, 7.0};
    /* A bare coordinate and a constant compile and evaluate. */
    CHECK(value_at(g, fm_var(g, FM_T), p) == 7.0);
    CHECK(value_at(g, fm_const(g, -3.5), p) == -3.5);
    fm_node r = fm_param(g, "r", 2.0);
    fm_node f = fm_sub(g, r, fm_sqrt(g, fm_add(g, fm_square(g, fm_var(g, FM_X)),
                                               fm_square(g, fm_var(g, FM_Y)))));
    fm_error err;
    fm_tape *t = fm_tape_compile(g, f, &err);
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    double d = sqrt(1.5 * 1.5 + 4.0);
    CHECK(fm_eval_point(ev, p) == 2.0 - d);
    CHECK(fm_tape_set_param(t, "r", 3.0) == FM_OK);
    CHECK(fm_eval_point(ev, p) == 3.0 - d);
    double xs[3] = {0, 3, 1}, ys[3] = {0, 4, 1}, out[3];
    fm_eval_batch(ev, 3, xs, ys, NULL, NULL, out);
    CHECK(out[0] == 3.0 && out[1] == -2.0 && out[2] == 3.0 - sqrt(2.0));
    CHECK(fm_tape_set_param(t, "nope", 1.0) == FM_ERR_INPUT);
    fm_evaluator_free(ev);
    fm_tape_free(t);
    /* Errors: FM_NONE and a failed graph. */
    CHECK(fm_tape_compile(g, FM_NONE, &err) == NULL && err.code == FM_ERR_INPUT);
    fm_graph_free(g);
}

/* A long chain (deeper than any C stack would allow recursively) compiles
 * and evaluates; the register count stays small. */
static void check_deep_chain(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node f = fm_var(g, FM_X);
    for (int i = 0; i < 200000; i++) f = fm_add(g, fm_mul(g, f, fm_const(g, 0.5)), fm_var(g, FM_Y));
    fm_error err;
    fm_tape *t = fm_tape_compile(g, f, &err);
    CHECK(t != NULL);
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    double p[4] = {1.0, 1.0, 0, 0};
    /* Fixed point of f = f / 2 + 1 is 2; starting at 1 it stays below 2. */
    double v = fm_eval_point(ev, p);
    CHECK_NEAR(v, 2.0, 1e-12);
    fm_evaluator_free(ev);
    fm_tape_free(t);
    fm_graph_free(g);
}

int main(void)
{
    check_random_dags(0);
    check_random_dags(1);
    check_rewrites();
    check_leaves_and_params();
    check_deep_chain();
    return test_summary("test_tape");
}
