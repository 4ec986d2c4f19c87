/* dag_eval.h: a small recursive interpreter of frep DAGs through the
 * public inspection API (fm_node_op / child / value), so that the tool and
 * sweep tests check the DAG builders independently of the tape compiler. */
#ifndef TEST_DAG_EVAL_H
#define TEST_DAG_EVAL_H

#include <math.h>

#include "frep/frep.h"

static double test_dag_eval(const fm_graph *g, fm_node n, const double p[4])
{
    fm_op op = fm_node_op(g, n);
    fm_node a = fm_node_child(g, n, 0), b = fm_node_child(g, n, 1), c = fm_node_child(g, n, 2);
    switch (op) {
    case FM_OP_CONST: return fm_node_value(g, n);
    case FM_OP_VAR: return p[(int)fm_node_value(g, n)];
    case FM_OP_NEG: return -test_dag_eval(g, a, p);
    case FM_OP_ABS: return fabs(test_dag_eval(g, a, p));
    case FM_OP_SQRT: return sqrt(test_dag_eval(g, a, p));
    case FM_OP_SQUARE: { double v = test_dag_eval(g, a, p); return v * v; }
    case FM_OP_SIN: return sin(test_dag_eval(g, a, p));
    case FM_OP_COS: return cos(test_dag_eval(g, a, p));
    case FM_OP_ADD: return test_dag_eval(g, a, p) + test_dag_eval(g, b, p);
    case FM_OP_SUB: return test_dag_eval(g, a, p) - test_dag_eval(g, b, p);
    case FM_OP_MUL: return test_dag_eval(g, a, p) * test_dag_eval(g, b, p);
    case FM_OP_DIV: return test_dag_eval(g, a, p) / test_dag_eval(g, b, p);
    case FM_OP_MIN: return fmin(test_dag_eval(g, a, p), test_dag_eval(g, b, p));
    case FM_OP_MAX: return fmax(test_dag_eval(g, a, p), test_dag_eval(g, b, p));
    case FM_OP_LT: return test_dag_eval(g, a, p) < test_dag_eval(g, b, p);
    case FM_OP_LE: return test_dag_eval(g, a, p) <= test_dag_eval(g, b, p);
    case FM_OP_AND: return test_dag_eval(g, a, p) != 0 && test_dag_eval(g, b, p) != 0;
    case FM_OP_OR: return test_dag_eval(g, a, p) != 0 || test_dag_eval(g, b, p) != 0;
    case FM_OP_SELECT: return test_dag_eval(g, a, p) != 0 ? test_dag_eval(g, b, p) : test_dag_eval(g, c, p);
    default: return NAN; /* an op the builders are not expected to emit */
    }
}

#endif
