/* eval.c: the evaluator object (per-thread scratch registers for one tape
 * and the tapes shortened from it) and the point and batch evaluators. The
 * batch evaluator runs one instruction at a time over a chunk of FM_CHUNK
 * points held as structure of arrays, in loops GCC vectorizes at -O3. */
#include "frep/tape_internal.h"

#include <stdlib.h>
#include <string.h>

static int alloc_regs(fm_evaluator *ev, uint32_t cap, size_t choices)
{
    size_t bytes;
    if (!fm_size_mul(cap, (size_t)FM_CHUNK * sizeof(double), &bytes)) return 0;
    double *reg = malloc(cap * sizeof *reg);
    double *batch = malloc(bytes);
    fm_interval *ivl = malloc(cap * sizeof *ivl);
    uint8_t *ivl_nan = malloc(cap);
    double *grad = malloc(cap * 5 * sizeof *grad);
    uint8_t *choice = malloc(choices ? choices : 1);
    if (!reg || !batch || !ivl || !ivl_nan || !grad || !choice) {
        free(ivl_nan);
        free(reg);
        free(batch);
        free(ivl);
        free(grad);
        free(choice);
        return 0;
    }
    free(ev->reg);
    free(ev->batch);
    free(ev->ivl);
    free(ev->ivl_nan);
    free(ev->grad);
    free(ev->choice);
    ev->ivl_nan = ivl_nan;
    ev->reg = reg;
    ev->batch = batch;
    ev->ivl = ivl;
    ev->grad = grad;
    ev->choice = choice;
    ev->cap = cap;
    ev->choice_cap = choices ? choices : 1;
    return 1;
}

fm_evaluator *fm_evaluator_new(const fm_tape *tape, fm_error *err)
{
    if (!tape) {
        fm_error_set(err, FM_ERR_INPUT, "no tape to evaluate");
        return NULL;
    }
    fm_evaluator *ev = calloc(1, sizeof *ev);
    if (!ev) goto oom;
    ev->root = ev->tape = tape;
    if (!alloc_regs(ev, tape->reg_capacity, tape->root_ninsns)) goto oom;
    const fm_tape_shared *s = tape->shared;
    if (s->nspecials) {
        ev->sub = calloc(s->nspecials, sizeof *ev->sub);
        if (!ev->sub) goto oom;
        ev->nsub = s->nspecials;
        for (size_t i = 0; i < s->nspecials; i++) {
            if (!s->specials[i].child) continue;
            ev->sub[i] = fm_evaluator_new(s->specials[i].child, err);
            if (!ev->sub[i]) {
                fm_evaluator_free(ev);
                return NULL;
            }
        }
    }
    return ev;
oom:
    fm_evaluator_free(ev);
    fm_error_set(err, FM_ERR_LIMIT, "out of memory making an evaluator");
    return NULL;
}

void fm_evaluator_free(fm_evaluator *ev)
{
    if (!ev) return;
    for (size_t i = 0; i < ev->nsub; i++) fm_evaluator_free(ev->sub[i]);
    free(ev->sub);
    free(ev->reg);
    free(ev->batch);
    free(ev->ivl);
    free(ev->ivl_nan);
    free(ev->grad);
    free(ev->choice);
    free(ev->sh_map);
    free(ev->sh_live);
    free(ev->sh_code);
    free(ev);
}

void fm_evaluator_use(fm_evaluator *ev, const fm_tape *tape)
{
    if (!ev) return;
    if (!tape) tape = ev->root;
    /* Only tapes of the same family (same special ops, same parameters). */
    if (tape->shared != ev->root->shared) return;
    if (tape->nregs > ev->cap || tape->ninsns > ev->choice_cap) {
        uint32_t cap = tape->nregs > ev->cap ? tape->nregs : ev->cap;
        size_t ch = tape->ninsns > ev->choice_cap ? tape->ninsns : ev->choice_cap;
        if (!alloc_regs(ev, cap, ch)) return; /* keep the current tape */
    }
    ev->tape = tape;
}

/* ------------------------------------------------------------ point -- */

double fm_eval_point(fm_evaluator *ev, const double p[4])
{
    const fm_tape *t = ev->tape;
    double *r = ev->reg;
    r[0] = p[0];
    r[1] = p[1];
    r[2] = p[2];
    r[3] = p[3];
    for (uint32_t i = FM_AXES; i < t->nleaf; i++) r[i] = t->param_values[i - FM_AXES];
    /* A tape of a bare coordinate has no instructions and a NULL array:
     * no arithmetic on it (NULL + 0 is undefined). */
    const fm_insn *in = t->insns, *end = t->ninsns ? t->insns + t->ninsns : t->insns;
    for (; in < end; in++) {
        fm_op op = (fm_op)in->op;
        double v;
        switch (fm_op_arity(op)) {
        case 0: v = in->imm; break; /* CONST */
        case 1: v = fm_apply_unary(op, r[in->a]); break;
        case 2:
            v = fm_apply_binary(op, fm_insn_operand(r, in, 0), fm_insn_operand(r, in, 1));
            break;
        case 3: v = r[in->a] != 0.0 ? r[in->b] : r[in->c]; break;
        default:
            v = op == FM_OP_VOXELS
                    ? fm_voxel_sample(&t->shared->specials[in->aux].grid, r[in->a], r[in->b], r[in->c])
                    : fm_special_point(ev, in, p);
            break;
        }
        r[in->out] = v;
    }
    return r[t->result];
}

/* ------------------------------------------------------------ batch -- */

/* Three loops per binary op (register-register, immediate first, immediate
 * second) so that each is a plain elementwise loop. */
#define BINARY_LOOPS(EXPR)                                                        \
    do {                                                                          \
        if (!in->imm_mask) {                                                      \
            const double *restrict A = R(in->a), *restrict B = R(in->b);          \
            for (size_t i = 0; i < m; i++) {                                      \
                double a = A[i], b = B[i];                                        \
                O[i] = (EXPR);                                                    \
            }                                                                     \
        } else if (in->imm_mask & FM_IMM_A) {                                     \
            const double a = in->imm, *restrict B = R(in->b);                     \
            for (size_t i = 0; i < m; i++) {                                      \
                double b = B[i];                                                  \
                O[i] = (EXPR);                                                    \
            }                                                                     \
        } else {                                                                  \
            const double *restrict A = R(in->a), b = in->imm;                     \
            for (size_t i = 0; i < m; i++) {                                      \
                double a = A[i];                                                  \
                O[i] = (EXPR);                                                    \
            }                                                                     \
        }                                                                         \
    } while (0)

#define UNARY_LOOP(EXPR)                                                          \
    do {                                                                          \
        const double *restrict A = R(in->a);                                      \
        for (size_t i = 0; i < m; i++) {                                          \
            double a = A[i];                                                      \
            O[i] = (EXPR);                                                        \
        }                                                                         \
    } while (0)

/* sqrt sets no errno here (the result is NaN either way), which lets GCC
 * vectorize the sqrt loop; IEEE semantics are otherwise unchanged. The
 * loops are also compiled for AVX2 (4 doubles a step instead of SSE2's 2),
 * picked at load time where the CPU has it: AVX2 without FMA rounds every
 * operation as SSE2 does, so the values are the same bits (lib/sweep/batch.c
 * does the same). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-math-errno"), target_clones("avx2", "default")))
#elif defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-math-errno")))
#endif
static void run_chunk(fm_evaluator *ev, size_t m)
{
    const fm_tape *t = ev->tape;
    double *regs = ev->batch;
#define R(slot) (regs + (size_t)(slot) * FM_CHUNK)
    /* A tape of a bare coordinate has no instructions and a NULL array:
     * no arithmetic on it (NULL + 0 is undefined). */
    const fm_insn *in = t->insns, *end = t->ninsns ? t->insns + t->ninsns : t->insns;
    for (; in < end; in++) {
        double *restrict O = R(in->out);
        fm_op op = (fm_op)in->op;
        switch (op) {
        case FM_OP_CONST: {
            const double c = in->imm;
            for (size_t i = 0; i < m; i++) O[i] = c;
            break;
        }
        case FM_OP_NEG: UNARY_LOOP(-a); break;
        case FM_OP_ABS: UNARY_LOOP(fabs(a)); break;
        case FM_OP_SQRT: UNARY_LOOP(sqrt(a)); break;
        case FM_OP_SQUARE: UNARY_LOOP(a * a); break;
        case FM_OP_ADD: BINARY_LOOPS(a + b); break;
        case FM_OP_SUB: BINARY_LOOPS(a - b); break;
        case FM_OP_MUL: BINARY_LOOPS(a * b); break;
        case FM_OP_DIV: BINARY_LOOPS(a / b); break;
        case FM_OP_MIN: BINARY_LOOPS(a < b ? a : b); break;
        case FM_OP_MAX: BINARY_LOOPS(a > b ? a : b); break;
        case FM_OP_LT: BINARY_LOOPS(a < b ? 1.0 : 0.0); break;
        case FM_OP_LE: BINARY_LOOPS(a <= b ? 1.0 : 0.0); break;
        case FM_OP_SELECT: {
            const double *restrict C = R(in->a), *restrict B = R(in->b), *restrict E = R(in->c);
            for (size_t i = 0; i < m; i++) O[i] = C[i] != 0.0 ? B[i] : E[i];
            break;
        }
        default:
            switch (fm_op_arity(op)) {
            case 1: {
                const double *A = R(in->a);
                for (size_t i = 0; i < m; i++) O[i] = fm_apply_unary(op, A[i]);
                break;
            }
            case 2: {
                if (!in->imm_mask) {
                    const double *A = R(in->a), *B = R(in->b);
                    for (size_t i = 0; i < m; i++) O[i] = fm_apply_binary(op, A[i], B[i]);
                } else if (in->imm_mask & FM_IMM_A) {
                    const double *B = R(in->b);
                    for (size_t i = 0; i < m; i++) O[i] = fm_apply_binary(op, in->imm, B[i]);
                } else {
                    const double *A = R(in->a);
                    for (size_t i = 0; i < m; i++) O[i] = fm_apply_binary(op, A[i], in->imm);
                }
                break;
            }
            default: {
                if (op == FM_OP_VOXELS) {
                    const fm_voxel_grid *grid = &t->shared->specials[in->aux].grid;
                    const double *A = R(in->a), *B = R(in->b), *C = R(in->c);
                    for (size_t i = 0; i < m; i++) O[i] = fm_voxel_sample(grid, A[i], B[i], C[i]);
                    break;
                }
                /* Special ops: one search per point. */
                const double *X = R(FM_X), *Y = R(FM_Y), *Z = R(FM_Z), *T = R(FM_T);
                for (size_t i = 0; i < m; i++) {
                    double p[4] = {X[i], Y[i], Z[i], T[i]};
                    O[i] = fm_special_point(ev, in, p);
                }
                break;
            }
            }
            break;
        }
    }
#undef R
}

void fm_eval_batch(fm_evaluator *ev, size_t n, const double *x, const double *y,
                   const double *z, const double *t, double *out)
{
    const fm_tape *tp = ev->tape;
    double *regs = ev->batch;
    for (uint32_t k = FM_AXES; k < tp->nleaf; k++) {
        double v = tp->param_values[k - FM_AXES];
        double *P = regs + (size_t)k * FM_CHUNK;
        for (size_t i = 0; i < FM_CHUNK; i++) P[i] = v;
    }
    const double *src[4] = {x, y, z, t};
    for (size_t start = 0; start < n; start += FM_CHUNK) {
        size_t m = n - start < FM_CHUNK ? n - start : FM_CHUNK;
        for (int a = 0; a < FM_AXES; a++) {
            double *D = regs + (size_t)a * FM_CHUNK;
            if (src[a]) memcpy(D, src[a] + start, m * sizeof *D);
            else memset(D, 0, m * sizeof *D);
        }
        run_chunk(ev, m);
        memcpy(out + start, regs + (size_t)tp->result * FM_CHUNK, m * sizeof *out);
    }
}
