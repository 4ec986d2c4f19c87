/* grad.c: value and gradient (d/dx, d/dy, d/dz, d/dt) by forward-mode
 * automatic differentiation: each register holds a value and its four
 * partial derivatives. Values are computed with fm_apply_unary/binary, so
 * they equal the point evaluator's bit for bit. At kinks (abs, min, max)
 * the derivative of the branch the value comes from is taken; at steps
 * (floor, comparisons, ...) it is 0. */
#include "frep/tape_internal.h"

#include <string.h>

enum { W = 5 }; /* value + 4 partials */

static void operand(const double *g, const fm_insn *in, int which, double out[W])
{
    if ((which == 0 && (in->imm_mask & FM_IMM_A)) || (which == 1 && (in->imm_mask & FM_IMM_B))) {
        out[0] = in->imm;
        out[1] = out[2] = out[3] = out[4] = 0.0;
        return;
    }
    uint32_t slot = which == 0 ? in->a : which == 1 ? in->b : in->c;
    memcpy(out, g + (size_t)slot * W, W * sizeof *out);
}

/* d(op(a))/da at a, with v = op(a). */
static double unary_slope(fm_op op, double a, double v)
{
    switch (op) {
    case FM_OP_NEG: return -1.0;
    case FM_OP_ABS: return a < 0 ? -1.0 : 1.0;
    case FM_OP_SQRT: return 0.5 / v;
    case FM_OP_SQUARE: return 2.0 * a;
    case FM_OP_EXP: return v;
    case FM_OP_LOG: return 1.0 / a;
    case FM_OP_SIN: return cos(a);
    case FM_OP_COS: return -sin(a);
    case FM_OP_TAN: return 1.0 + v * v;
    case FM_OP_ASIN: return 1.0 / sqrt(1.0 - a * a);
    case FM_OP_ACOS: return -1.0 / sqrt(1.0 - a * a);
    case FM_OP_ATAN: return 1.0 / (1.0 + a * a);
    case FM_OP_SINH: return cosh(a);
    case FM_OP_COSH: return sinh(a);
    case FM_OP_TANH: return 1.0 - v * v;
    default: return 0.0; /* floor, ceil, trunc, sign, not: piecewise constant */
    }
}

double fm_eval_grad(fm_evaluator *ev, const double p[4], double grad[4])
{
    const fm_tape *t = ev->tape;
    double *g = ev->grad;
    for (int i = 0; i < FM_AXES; i++) {
        double *r = g + (size_t)i * W;
        memset(r, 0, W * sizeof *r);
        r[0] = p[i];
        r[1 + i] = 1.0;
    }
    for (uint32_t i = FM_AXES; i < t->nleaf; i++) {
        double *r = g + (size_t)i * W;
        memset(r, 0, W * sizeof *r);
        r[0] = t->param_values[i - FM_AXES];
    }
    for (size_t k = 0; k < t->ninsns; k++) {
        const fm_insn *in = &t->insns[k];
        fm_op op = (fm_op)in->op;
        double o[W] = {0, 0, 0, 0, 0}, a[W], b[W], c[W];
        switch (fm_op_arity(op)) {
        case 0: o[0] = in->imm; break;
        case 1: {
            operand(g, in, 0, a);
            o[0] = fm_apply_unary(op, a[0]);
            double s = unary_slope(op, a[0], o[0]);
            /* A partial the operand does not depend on stays 0 even where
             * the slope is infinite (sqrt at 0): inf * 0 would be NaN. */
            if (s != 0.0)
                for (int j = 1; j < W; j++) o[j] = a[j] != 0.0 ? s * a[j] : 0.0;
            break;
        }
        case 2:
            operand(g, in, 0, a);
            operand(g, in, 1, b);
            o[0] = fm_apply_binary(op, a[0], b[0]);
            for (int j = 1; j < W; j++) {
                switch (op) {
                case FM_OP_ADD: o[j] = a[j] + b[j]; break;
                case FM_OP_SUB: o[j] = a[j] - b[j]; break;
                case FM_OP_MUL: o[j] = a[j] * b[0] + a[0] * b[j]; break;
                case FM_OP_DIV: o[j] = (a[j] * b[0] - a[0] * b[j]) / (b[0] * b[0]); break;
                case FM_OP_MIN: o[j] = a[0] < b[0] ? a[j] : b[j]; break;
                case FM_OP_MAX: o[j] = a[0] > b[0] ? a[j] : b[j]; break;
                case FM_OP_POW: {
                    /* d a^b = b a^(b-1) da + a^b ln(a) db; the second term
                     * only where b varies (ln of a negative base is NaN). */
                    double d = a[j] != 0.0 ? b[0] * pow(a[0], b[0] - 1.0) * a[j] : 0.0;
                    if (b[j] != 0.0) d += o[0] * log(a[0]) * b[j];
                    o[j] = d;
                    break;
                }
                case FM_OP_ATAN2: {
                    double r2 = a[0] * a[0] + b[0] * b[0];
                    o[j] = (b[0] * a[j] - a[0] * b[j]) / r2;
                    break;
                }
                case FM_OP_MOD: o[j] = a[j] - trunc(a[0] / b[0]) * b[j]; break;
                default: o[j] = 0.0; break; /* comparisons and logic */
                }
            }
            break;
        case 3:
            operand(g, in, 0, a);
            operand(g, in, 1, b);
            operand(g, in, 2, c);
            memcpy(o, a[0] != 0.0 ? b : c, sizeof o);
            break;
        default:
            if (op == FM_OP_VOXELS) {
                operand(g, in, 0, a);
                operand(g, in, 1, b);
                operand(g, in, 2, c);
                double dv[3];
                o[0] = fm_voxels_grad(&t->shared->specials[in->aux].grid, a[0], b[0], c[0], dv);
                for (int j = 1; j < W; j++) o[j] = dv[0] * a[j] + dv[1] * b[j] + dv[2] * c[j];
            } else {
                double gr[4];
                o[0] = fm_special_grad(ev, in, p, gr);
                for (int j = 1; j < W; j++) o[j] = gr[j - 1];
            }
            break;
        }
        memcpy(g + (size_t)in->out * W, o, sizeof o);
    }
    const double *r = g + (size_t)t->result * W;
    if (grad)
        for (int j = 0; j < 4; j++) grad[j] = r[1 + j];
    return r[0];
}
