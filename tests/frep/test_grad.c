/* test_grad.c: forward-mode gradients against central finite differences,
 * on smooth expressions over many ops and on random CSG-like DAGs (points
 * near a kink, where two step sizes disagree, are skipped and counted). */
#include "frep/tape_internal.h"
#include "test.h"
#include "frep_random.h"

static int checked, skipped;

static void check_grad_at(fm_evaluator *ev, const double p[4])
{
    double grad[4];
    double v = fm_eval_grad(ev, p, grad);
    double pv = fm_eval_point(ev, p);
    CHECK(same(v, pv));
    if (!isfinite(v)) return;
    for (int i = 0; i < 4; i++) {
        double fd[2];
        for (int s = 0; s < 2; s++) {
            double h = (s ? 2e-6 : 1e-6) * (1 + fabs(p[i])), a[4], b[4];
            for (int j = 0; j < 4; j++) a[j] = b[j] = p[j];
            a[i] += h;
            b[i] -= h;
            fd[s] = (fm_eval_point(ev, a) - fm_eval_point(ev, b)) / (2 * h);
        }
        double scale = 1 + fabs(fd[0]);
        /* Two step sizes that disagree mean a kink or a step within 2h. */
        if (!isfinite(fd[0]) || fabs(fd[0] - fd[1]) > 1e-6 * scale) {
            skipped++;
            continue;
        }
        checked++;
        CHECK_NEAR(grad[i], fd[0], 1e-5 * scale);
    }
}

static void check_smooth_ops(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z), t = fm_var(g, FM_T);
    fm_node one = fm_const(g, 1.0), k4 = fm_const(g, 4.0);
    fm_node r2 = fm_add(g, fm_add(g, fm_square(g, x), fm_square(g, y)), one);
    fm_node exprs[] = {
        fm_mul(g, fm_unary(g, FM_OP_SIN, fm_mul(g, x, y)), fm_unary(g, FM_OP_COS, z)),
        fm_div(g, fm_unary(g, FM_OP_EXP, fm_mul(g, x, fm_const(g, 0.3))), r2),
        fm_binary(g, FM_OP_ATAN2, y, fm_add(g, x, fm_const(g, 5.0))),
        fm_binary(g, FM_OP_POW, r2, fm_const(g, 1.5)),
        fm_binary(g, FM_OP_POW, r2, fm_mul(g, fm_const(g, 0.2), z)),
        fm_unary(g, FM_OP_LOG, r2),
        fm_unary(g, FM_OP_TANH, fm_sub(g, x, t)),
        fm_add(g, fm_unary(g, FM_OP_SINH, fm_mul(g, y, fm_const(g, 0.5))),
               fm_unary(g, FM_OP_COSH, fm_mul(g, z, fm_const(g, 0.5)))),
        fm_unary(g, FM_OP_ASIN, fm_div(g, x, k4)),
        fm_unary(g, FM_OP_ACOS, fm_div(g, y, k4)),
        fm_unary(g, FM_OP_ATAN, fm_mul(g, x, z)),
        fm_unary(g, FM_OP_TAN, fm_mul(g, x, fm_const(g, 0.3))),
        fm_sqrt(g, r2),
        fm_neg(g, fm_abs(g, fm_add(g, x, fm_const(g, 10.0)))),
        fm_binary(g, FM_OP_MOD, fm_add(g, x, fm_const(g, 3.5)), fm_const(g, 7.0)),
        fm_select(g, fm_binary(g, FM_OP_LT, x, y), fm_mul(g, x, t), fm_mul(g, y, z)),
        fm_max(g, fm_min(g, x, fm_sub(g, y, one)), fm_neg(g, z)),
    };
    for (size_t e = 0; e < sizeof exprs / sizeof exprs[0]; e++) {
        fm_error err;
        fm_tape *tp = fm_tape_compile(g, exprs[e], &err);
        fm_evaluator *ev = fm_evaluator_new(tp, &err);
        for (int k = 0; k < 100; k++) {
            double p[4] = {test_uniform(-2.5, 2.5), test_uniform(-2.5, 2.5), test_uniform(-2.5, 2.5),
                           test_uniform(-2.5, 2.5)};
            check_grad_at(ev, p);
        }
        fm_evaluator_free(ev);
        fm_tape_free(tp);
    }
    fm_graph_free(g);
}

/* sqrt at 0 has an infinite slope; where its operand does not depend on a
 * coordinate (max(x, 0) for x < 0 is the constant 0) that partial is 0, not
 * inf * 0 = NaN. Found by clang's build, whose random DAGs reached it. */
static void check_infinite_slope_constant_operand(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
    fm_node root = fm_add(g, fm_sqrt(g, fm_max(g, x, fm_const(g, 0.0))), y);
    fm_error err;
    fm_tape *tp = fm_tape_compile(g, root, &err);
    fm_evaluator *ev = fm_evaluator_new(tp, &err);
    double p[4] = {-1.5, 0.25, 0.0, 0.0}, grad[4];
    CHECK_NEAR(fm_eval_grad(ev, p, grad), 0.25, 0.0);
    CHECK_NEAR(grad[0], 0.0, 0.0);
    CHECK_NEAR(grad[1], 1.0, 0.0);
    check_grad_at(ev, p);
    fm_evaluator_free(ev);
    fm_tape_free(tp);
    fm_graph_free(g);
}

static void check_random_csg(void)
{
    for (int trial = 0; trial < 100; trial++) {
        fm_graph *g = fm_graph_new(0);
        fm_node root = random_dag(g, 10 + (size_t)(test_rand01() * 30), 1);
        fm_error err;
        fm_tape *tp = fm_tape_compile(g, root, &err);
        fm_evaluator *ev = fm_evaluator_new(tp, &err);
        for (int k = 0; k < 20; k++) {
            double p[4] = {test_uniform(-3, 3), test_uniform(-3, 3), test_uniform(-3, 3),
                           test_uniform(-3, 3)};
            check_grad_at(ev, p);
        }
        fm_evaluator_free(ev);
        fm_tape_free(tp);
        fm_graph_free(g);
    }
}

int main(void)
{
    check_smooth_ops();
    check_infinite_slope_constant_operand();
    check_random_csg();
    printf("gradient components checked %d, skipped near kinks %d\n", checked, skipped);
    CHECK(checked > 10 * skipped);
    return test_summary("test_grad");
}
