/* frep_random.h: random DAGs over every non-special op and random points,
 * shared by the tape, interval and gradient tests. Include after test.h. */
#ifndef FM_TEST_FREP_RANDOM_H
#define FM_TEST_FREP_RANDOM_H

#include <stdlib.h>

#include "frep/frep_internal.h"

static const fm_op unary_ops[] = {FM_OP_NEG,   FM_OP_ABS,  FM_OP_SQRT,  FM_OP_SQUARE, FM_OP_EXP,
                                  FM_OP_LOG,   FM_OP_SIN,  FM_OP_COS,   FM_OP_TAN,    FM_OP_ASIN,
                                  FM_OP_ACOS,  FM_OP_ATAN, FM_OP_SINH,  FM_OP_COSH,   FM_OP_TANH,
                                  FM_OP_FLOOR, FM_OP_CEIL, FM_OP_TRUNC, FM_OP_SIGN,   FM_OP_NOT};
static const fm_op binary_ops[] = {FM_OP_ADD, FM_OP_SUB,   FM_OP_MUL, FM_OP_DIV, FM_OP_MIN,
                                   FM_OP_MAX, FM_OP_POW,   FM_OP_ATAN2, FM_OP_MOD, FM_OP_LT,
                                   FM_OP_LE,  FM_OP_EQ,    FM_OP_NE,  FM_OP_AND, FM_OP_OR};
#define NUNARY (sizeof unary_ops / sizeof unary_ops[0])
#define NBINARY (sizeof binary_ops / sizeof binary_ops[0])

/* Same value: equal (with +0 == -0, see the absorption note in tape.c) or
 * both NaN. */
static inline int same(double a, double b)
{
    return (isnan(a) && isnan(b)) || a == b;
}

static inline fm_node pick(const fm_node *pool, size_t n)
{
    /* Half the time one of the newest nodes, so that expressions get deep. */
    if (n > 8 && test_rand01() < 0.5) return pool[n - 1 - (size_t)(test_rand01() * 8)];
    return pool[(size_t)(test_rand01() * (double)n)];
}

/* A random DAG over every non-special op; returns its root. */
static inline fm_node random_dag(fm_graph *g, size_t steps, int minmax_heavy)
{
    fm_node *pool = malloc((steps + 16) * sizeof *pool);
    size_t n = 0;
    for (int a = 0; a < FM_AXES; a++) pool[n++] = fm_var(g, a);
    const double consts[] = {0.0, 1.0, -1.0, 0.5, 2.0, 3.0, -2.5, 1e-3};
    for (size_t i = 0; i < sizeof consts / sizeof consts[0]; i++) pool[n++] = fm_const(g, consts[i]);
    pool[n++] = fm_param(g, "p0", 0.75);
    pool[n++] = fm_param(g, "p1", -1.25);
    fm_node last = pool[0];
    for (size_t s = 0; s < steps; s++) {
        /* Every draw in its own statement: the order in which a call's
         * arguments are evaluated is unspecified in C (GCC and clang
         * differ), and draws inside one call made the DAGs compiler-
         * dependent (clang's hit sqrt(0) with a constant operand, GCC's
         * did not). */
        double u = test_rand01();
        double pick_op = test_rand01();
        fm_node a = pick(pool, n);
        fm_node b = pick(pool, n);
        fm_node c = pick(pool, n);
        fm_node k = fm_const(g, test_uniform(-2, 2));
        fm_node r;
        if (minmax_heavy) {
            /* CSG-like: min/max/neg of linear and distance-like terms. */
            if (u < 0.3) r = fm_min(g, a, b);
            else if (u < 0.6) r = fm_max(g, a, b);
            else if (u < 0.7) r = fm_neg(g, a);
            else if (u < 0.8) r = fm_sub(g, a, k);
            else if (u < 0.9) r = fm_sqrt(g, fm_add(g, fm_square(g, a), fm_square(g, b)));
            else r = fm_mul(g, a, k);
        } else if (u < 0.4) {
            r = fm_unary(g, unary_ops[(size_t)(pick_op * NUNARY)], a);
        } else if (u < 0.93) {
            r = fm_binary(g, binary_ops[(size_t)(pick_op * NBINARY)], a, b);
        } else {
            r = fm_select(g, a, b, c);
        }
        if (r != FM_NONE) {
            pool[n++] = r;
            last = r;
        }
    }
    free(pool);
    return last;
}

static inline void random_point(double p[4])
{
    /* A third of the points on a coarse lattice, so that zeros, ties and
     * integer arguments (floor, mod, pow with negative bases) occur. */
    for (int i = 0; i < 4; i++)
        p[i] = test_rand01() < 0.33 ? 0.5 * (double)(int)test_uniform(-6, 7) : test_uniform(-3, 3);
}

#endif
