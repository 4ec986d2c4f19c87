/* test_regress.c: one case per bug found in lib/frep, so that none comes
 * back. */
#include "frep/frep.h"
#include "test.h"

/* A tape whose root is a bare coordinate has no instructions; evaluating
 * it did arithmetic on a NULL instruction array (UBSan, found by the
 * trajectory fuzzer with the expression "t"). */
static void bare_coordinate_tape(void)
{
    for (int axis = 0; axis < FM_AXES; axis++) {
        fm_graph *g = fm_graph_new(0);
        fm_tape *tape = fm_tape_compile(g, fm_var(g, axis), NULL);
        CHECK(tape != NULL);
        fm_evaluator *ev = fm_evaluator_new(tape, NULL);
        CHECK(ev != NULL);
        double p[4] = {1.5, -2.5, 3.25, 7.0};
        CHECK(fm_eval_point(ev, p) == p[axis]);
        double xs[3] = {1, 2, 3}, ys[3] = {4, 5, 6}, zs[3] = {7, 8, 9}, ts[3] = {10, 11, 12}, out[3];
        const double *cols[4] = {xs, ys, zs, ts};
        fm_eval_batch(ev, 3, xs, ys, zs, ts, out);
        for (int i = 0; i < 3; i++) CHECK(out[i] == cols[axis][i]);
        fm_interval box[4] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}};
        fm_interval v = fm_eval_interval(ev, box);
        CHECK(v.lo <= box[axis].lo && v.hi >= box[axis].hi);
        double grad[4];
        CHECK(fm_eval_grad(ev, p, grad) == p[axis]);
        for (int i = 0; i < 4; i++) CHECK(grad[i] == (i == axis ? 1.0 : 0.0));
        fm_evaluator_free(ev);
        fm_tape_free(tape);
        fm_graph_free(g);
    }
}

int main(void)
{
    bare_coordinate_tape();
    return test_summary("frep regressions");
}
