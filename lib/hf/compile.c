/* compile.c: symbolic execution of a parsed HyperFun program into an frep
 * DAG (Hasan sec. 4.1). Variables hold nodes; loops whose condition is a
 * compile-time constant are unrolled; an `if` whose condition depends on
 * the point (or a parameter) runs both branches and joins every variable
 * they assign differently with a select node, which evaluates per point
 * exactly as HyperFun's interpreter does. Calls of other objects are
 * inlined. Every run is bounded by the step, iteration, call-depth and
 * node budgets, and every error carries file:line:column. */
#include "hf/hf_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define HF_EPS 1e-6 /* HyperFun's EPS for = and /= */

enum { VAR_UNSET = 0, VAR_SCALAR = 1, VAR_ARRAY = 2 };
enum { EL_UNSET = 0, EL_SET = 1, EL_PARTIAL = 2 };

typedef struct hf_var {
    uint8_t kind;
    uint8_t partial; /* a scalar assigned on one branch of a point-dependent if only */
    fm_node v;
    fm_node *elems;
    uint8_t *state; /* per element: EL_* */
    size_t n;
    int if_line, if_col; /* where it became partial */
} hf_var;

typedef struct hf_frame {
    hf_var *vars; /* indexed by name id */
    size_t count;
    const hf_object *obj;
    double alpha;
} hf_frame;

typedef struct hf_exec {
    hf_program *p;
    fm_graph *g;
    const fm_hf_options *opt;
    fm_error *err;
    int failed;
    size_t steps, iterations, call_depth;
    uint8_t *active; /* per object: being executed (recursion check) */
    uint32_t *spine; /* explicit stack for left-deep operator chains */
    size_t spine_count, spine_cap;
    uint32_t alpha_name;
} hf_exec;

/* ------------------------------------------------------------- errors -- */

static int xfail(hf_exec *ex, const hf_ast *at, fm_status code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static int xfail(hf_exec *ex, const hf_ast *at, fm_status code, const char *fmt, ...)
{
    if (ex->failed) return 0;
    ex->failed = 1;
    char msg[sizeof ex->err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    fm_error_at(ex->err, code, ex->p->source_name, at ? at->line : 0, at ? at->col : 0, "%s",
                msg);
    return 0;
}

/* A node budget overflow or other build failure recorded in the graph. */
static int check_graph(hf_exec *ex, const hf_ast *at)
{
    const fm_error *ge = fm_graph_error(ex->g);
    if (!ge) return 1;
    return xfail(ex, at, ge->code, "%s", ge->message);
}

static int step(hf_exec *ex, const hf_ast *at)
{
    if (++ex->steps <= ex->opt->max_steps) return 1;
    return xfail(ex, at, FM_ERR_LIMIT,
                 "the program needs more than %zu steps to unroll (the step budget)",
                 ex->opt->max_steps);
}

static const char *nm(hf_exec *ex, uint32_t name) { return ex->p->spellings[name]; }

/* ------------------------------------------------------------ names -- */

typedef enum { BI_UNARY, BI_BINARY, BI_LOGD, BI_MOD, BI_INT, BI_FRAC } bi_kind;
static const struct {
    const char *name;
    bi_kind kind;
    fm_op op;
} builtins[] = {
    {"sqrt", BI_UNARY, FM_OP_SQRT},   {"exp", BI_UNARY, FM_OP_EXP},
    {"log", BI_UNARY, FM_OP_LOG},     {"logd", BI_LOGD, FM_OP_LOG},
    {"sin", BI_UNARY, FM_OP_SIN},     {"cos", BI_UNARY, FM_OP_COS},
    {"tan", BI_UNARY, FM_OP_TAN},     {"asin", BI_UNARY, FM_OP_ASIN},
    {"acos", BI_UNARY, FM_OP_ACOS},   {"atan", BI_UNARY, FM_OP_ATAN},
    {"atan2", BI_BINARY, FM_OP_ATAN2}, {"abs", BI_UNARY, FM_OP_ABS},
    {"sinh", BI_UNARY, FM_OP_SINH},   {"cosh", BI_UNARY, FM_OP_COSH},
    {"tanh", BI_UNARY, FM_OP_TANH},   {"sign", BI_UNARY, FM_OP_SIGN},
    {"mod", BI_MOD, FM_OP_MOD},       {"max", BI_BINARY, FM_OP_MAX},
    {"min", BI_BINARY, FM_OP_MIN},    {"ceil", BI_UNARY, FM_OP_CEIL},
    {"floor", BI_UNARY, FM_OP_FLOOR}, {"int", BI_INT, FM_OP_TRUNC},
    {"frac", BI_FRAC, FM_OP_TRUNC},
};
#define N_BUILTINS (sizeof builtins / sizeof builtins[0])

/* The frepmill extension (docs/hf.md). */
typedef enum {
    EXT_PROJECT, EXT_METAMORPH, EXT_OFFSET, EXT_OFFSET_NORMAL, EXT_OFFSET_RADIUS, EXT_NORMALIZE,
    EXT_TIME_SEGMENT, EXT_AFFINE_T
} ext_kind;
static const struct {
    const char *name;
    ext_kind kind;
    int arity;
} extensions[] = {
    {"fmProject", EXT_PROJECT, 3},       {"fmMetamorph", EXT_METAMORPH, 4},
    {"fmOffset", EXT_OFFSET, 2},         {"fmOffsetNormal", EXT_OFFSET_NORMAL, 2},
    {"fmOffsetRadius", EXT_OFFSET_RADIUS, 2}, {"fmNormalize", EXT_NORMALIZE, 1},
    {"fmTimeSegment", EXT_TIME_SEGMENT, 2}, {"fmAffineT", EXT_AFFINE_T, 13},
};
#define N_EXTENSIONS (sizeof extensions / sizeof extensions[0])

static int same_ci(const char *spelled, const char *lower)
{
    while (*spelled && *lower && (*spelled | 0x20) == *lower) {
        spelled++;
        lower++;
    }
    return !*spelled && !*lower;
}

/* Closest candidate within a small edit distance, or NULL. */
typedef struct best_match {
    const char *name;
    size_t dist;
} best_match;

static void consider(best_match *b, const char *candidate, const char *wanted)
{
    size_t d = fm_hf_edit_distance(candidate, wanted);
    size_t len = strlen(wanted);
    size_t limit = len <= 3 ? 1 : len <= 6 ? 2 : 3;
    if (d <= limit && d < b->dist) {
        b->dist = d;
        b->name = candidate;
    }
}

static const char *suggest_function(hf_exec *ex, const char *wanted)
{
    best_match b = {NULL, (size_t)-1};
    for (size_t i = 0; i < N_BUILTINS; i++) consider(&b, builtins[i].name, wanted);
    for (size_t i = 0; i < N_EXTENSIONS; i++) consider(&b, extensions[i].name, wanted);
    for (size_t i = 0; fm_hf_library_at(i); i++) consider(&b, fm_hf_library_at(i)->name, wanted);
    for (size_t i = 0; i < ex->p->object_count; i++)
        consider(&b, ex->p->spellings[ex->p->objects[i].name], wanted);
    return b.name;
}

static const char *suggest_variable(hf_exec *ex, hf_frame *fr, const char *wanted)
{
    best_match b = {NULL, (size_t)-1};
    for (size_t i = 1; i < fr->count; i++)
        if (fr->vars[i].kind != VAR_UNSET) consider(&b, ex->p->spellings[i], wanted);
    return b.name;
}

/* -------------------------------------------------------------- frames -- */

static int frame_init(hf_exec *ex, hf_frame *fr, const hf_object *obj, const hf_ast *at)
{
    memset(fr, 0, sizeof *fr);
    fr->count = ex->p->name_count;
    fr->vars = calloc(fr->count ? fr->count : 1, sizeof *fr->vars);
    fr->obj = obj;
    fr->alpha = ex->opt->alpha;
    if (!fr->vars) return xfail(ex, at, FM_ERR_LIMIT, "out of memory compiling");
    return 1;
}

static void var_clear(hf_var *v)
{
    free(v->elems);
    free(v->state);
    memset(v, 0, sizeof *v);
}

static void frame_free(hf_frame *fr)
{
    if (!fr->vars) return;
    for (size_t i = 0; i < fr->count; i++) var_clear(&fr->vars[i]);
    free(fr->vars);
    fr->vars = NULL;
}

static int make_array(hf_exec *ex, hf_var *v, size_t n, const hf_ast *at)
{
    var_clear(v);
    if (n == 0 || n > ex->opt->max_array)
        return xfail(ex, at, FM_ERR_LIMIT, "array of %zu items is larger than %zu (the array budget)",
                     n, ex->opt->max_array);
    v->elems = calloc(n, sizeof *v->elems);
    v->state = calloc(n, 1);
    if (!v->elems || !v->state) {
        var_clear(v);
        return xfail(ex, at, FM_ERR_LIMIT, "out of memory compiling");
    }
    v->kind = VAR_ARRAY;
    v->n = n;
    /* copying and merging arrays is work too */
    ex->steps += n / 8;
    return step(ex, at);
}

static int frame_copy(hf_exec *ex, hf_frame *dst, const hf_frame *src, const hf_ast *at)
{
    if (!frame_init(ex, dst, src->obj, at)) return 0;
    dst->alpha = src->alpha;
    ex->steps += src->count / 8;
    for (size_t i = 0; i < src->count; i++) {
        const hf_var *s = &src->vars[i];
        hf_var *d = &dst->vars[i];
        if (s->kind == VAR_ARRAY) {
            if (!make_array(ex, d, s->n, at)) return 0;
            memcpy(d->elems, s->elems, s->n * sizeof *s->elems);
            memcpy(d->state, s->state, s->n);
        } else {
            *d = *s;
        }
    }
    return step(ex, at);
}

/* Join the frames of the two branches of a point-dependent if into out
 * (which holds the then-branch): a value assigned differently becomes
 * select(cond, then, else); assigned on one side only, it is "partial"
 * and may not be read later. */
static int frame_merge(hf_exec *ex, hf_frame *then_fr, hf_frame *else_fr, fm_node cond,
                       const hf_ast *at)
{
    for (size_t i = 0; i < then_fr->count; i++) {
        hf_var *t = &then_fr->vars[i], *e = &else_fr->vars[i];
        if (t->kind == VAR_UNSET && e->kind == VAR_UNSET) continue;
        if (t->kind != e->kind && t->kind != VAR_UNSET && e->kind != VAR_UNSET)
            return xfail(ex, at, FM_ERR_INPUT,
                         "'%s' is an array in one branch of this 'if' and a number in the other",
                         nm(ex, (uint32_t)i));
        if (t->kind == VAR_UNSET || e->kind == VAR_UNSET) {
            if (t->kind == VAR_UNSET) {
                *t = *e; /* take the else value; e is cleared so it is not freed twice */
                memset(e, 0, sizeof *e);
            }
            if (t->kind == VAR_SCALAR) t->partial = 1;
            else
                for (size_t k = 0; k < t->n; k++)
                    if (t->state[k] != EL_UNSET) t->state[k] = EL_PARTIAL;
            t->if_line = at->line;
            t->if_col = at->col;
            continue;
        }
        if (t->kind == VAR_SCALAR) {
            if (t->v != e->v || t->partial != e->partial) {
                t->v = fm_select(ex->g, cond, t->v, e->v);
                if (e->partial) {
                    t->if_line = e->if_line;
                    t->if_col = e->if_col;
                }
                t->partial |= e->partial;
            }
            continue;
        }
        if (t->n != e->n)
            return xfail(ex, at, FM_ERR_INPUT,
                         "array '%s' has %zu items in one branch of this 'if' and %zu in the other",
                         nm(ex, (uint32_t)i), t->n, e->n);
        for (size_t k = 0; k < t->n; k++) {
            uint8_t ts = t->state[k], es = e->state[k];
            if (ts == EL_UNSET && es == EL_UNSET) continue;
            if (ts == EL_UNSET || es == EL_UNSET) {
                if (ts == EL_UNSET) t->elems[k] = e->elems[k];
                t->state[k] = EL_PARTIAL;
                t->if_line = at->line;
                t->if_col = at->col;
                continue;
            }
            if (t->elems[k] != e->elems[k]) t->elems[k] = fm_select(ex->g, cond, t->elems[k], e->elems[k]);
            if (es == EL_PARTIAL) t->state[k] = EL_PARTIAL;
        }
        ex->steps += t->n / 8;
    }
    return check_graph(ex, at) && step(ex, at);
}

/* --------------------------------------------------------- expressions -- */

static int eval(hf_exec *ex, hf_frame *fr, uint32_t e, fm_node *out);
static int exec_block(hf_exec *ex, hf_frame *fr, uint32_t first);

/* The value of a constant expression (array sizes, indexes, loop bounds). */
static int eval_const(hf_exec *ex, hf_frame *fr, uint32_t e, double *value, const char *what)
{
    fm_node n;
    if (!eval(ex, fr, e, &n)) return 0;
    if (!fm_node_is_const(ex->g, n, value))
        return xfail(ex, &ex->p->nodes[e], FM_ERR_INPUT,
                     "%s must be known at compile time, but it depends on %s", what,
                     fm_node_depends_on(ex->g, n, FM_X) || fm_node_depends_on(ex->g, n, FM_Y) ||
                             fm_node_depends_on(ex->g, n, FM_Z) || fm_node_depends_on(ex->g, n, FM_T)
                         ? "the point coordinates (x)"
                         : "a parameter (a)");
    return 1;
}

/* HyperFun rounds an index to the nearest integer and checks its range. */
static int eval_index(hf_exec *ex, hf_frame *fr, uint32_t e, const hf_var *arr, uint32_t name,
                      size_t *index)
{
    double v;
    if (!eval_const(ex, fr, e, &v, "an array index")) return 0;
    double r = floor(v + 0.5);
    if (!(r >= 1 && r <= (double)arr->n))
        return xfail(ex, &ex->p->nodes[e], FM_ERR_INPUT,
                     "index %g is out of range for array '%s' of %zu items (indexes start at 1)",
                     v, nm(ex, name), arr->n);
    *index = (size_t)r - 1;
    return 1;
}

static int read_var(hf_exec *ex, hf_frame *fr, const hf_ast *at, fm_node *out)
{
    hf_var *v = &fr->vars[at->name];
    const char *name = nm(ex, at->name);
    if (v->kind == VAR_SCALAR) {
        if (v->partial)
            return xfail(ex, at, FM_ERR_INPUT,
                         "'%s' may have no value here: it is assigned in only one branch of the "
                         "'if' at line %d:%d, whose condition depends on the point",
                         name, v->if_line, v->if_col);
        *out = v->v;
        return 1;
    }
    if (v->kind == VAR_ARRAY)
        return xfail(ex, at, FM_ERR_INPUT, "'%s' is an array; use an item such as %s[1]", name,
                     name);
    const char *s = suggest_variable(ex, fr, ex->p->names[at->name]);
    if (fm_hf_library_find(ex->p->names[at->name]))
        return xfail(ex, at, FM_ERR_INPUT, "'%s' is a function; call it with arguments, as %s(...)",
                     name, name);
    if (s)
        return xfail(ex, at, FM_ERR_INPUT,
                     "unknown name '%s' (no value is assigned to it before this use); did you "
                     "mean '%s'?",
                     name, s);
    return xfail(ex, at, FM_ERR_INPUT,
                 "unknown name '%s' (no value is assigned to it before this use)", name);
}

static fm_node rel_eq(fm_graph *g, fm_node a, fm_node b)
{
    return fm_binary(g, FM_OP_LT, fm_abs(g, fm_sub(g, a, b)), fm_const(g, HF_EPS));
}

static fm_node apply_binary(hf_exec *ex, hf_frame *fr, hf_tok op, fm_node a, fm_node b)
{
    fm_graph *g = ex->g;
    switch (op) {
    case HF_TK_PLUS: return fm_add(g, a, b);
    case HF_TK_MINUS: return fm_sub(g, a, b);
    case HF_TK_STAR: return fm_mul(g, a, b);
    case HF_TK_SLASH: return fm_div(g, a, b);
    case HF_TK_CARET: return fm_binary(g, FM_OP_POW, a, b);
    /* HyperFun's | & \ are Pasko's R_alpha (eq. 2) with the current r_alpha */
    case HF_TK_BAR: return fm_r_union(g, a, b, fr->alpha);
    case HF_TK_AMP:
    case HF_TK_AT: /* operands name their own coordinates, so eq. 13 is an intersection */
        return fm_r_inter(g, a, b, fr->alpha);
    case HF_TK_BACKSLASH: return fm_r_subtract(g, a, b, fr->alpha);
    case HF_TK_LT: return fm_binary(g, FM_OP_LT, a, b);
    case HF_TK_GT: return fm_binary(g, FM_OP_LT, b, a);
    case HF_TK_LE: return fm_binary(g, FM_OP_LE, a, b);
    case HF_TK_GE: return fm_binary(g, FM_OP_LE, b, a);
    case HF_TK_EQ: return rel_eq(g, a, b);
    case HF_TK_NE: return fm_binary(g, FM_OP_LE, fm_const(g, HF_EPS), fm_abs(g, fm_sub(g, a, b)));
    case HF_TK_AND: return fm_binary(g, FM_OP_AND, a, b);
    case HF_TK_OR: return fm_binary(g, FM_OP_OR, a, b);
    default: return FM_NONE;
    }
}

/* An argument passed as an array: the named array variable (aliased, so
 * transforms change it) or an array literal (a temporary). */
static int eval_array_arg(hf_exec *ex, hf_frame *fr, uint32_t e, hf_value *out, fm_node **temp,
                          int in_place, const char *fname, int argno)
{
    const hf_ast *at = &ex->p->nodes[e];
    if (at->kind == HF_E_NAME && fr->vars[at->name].kind == VAR_ARRAY) {
        hf_var *v = &fr->vars[at->name];
        for (size_t k = 0; k < v->n; k++)
            if (v->state[k] != EL_SET)
                return xfail(ex, at, FM_ERR_INPUT, "%s[%zu] %s, so '%s' cannot be passed to %s",
                             nm(ex, at->name), k + 1,
                             v->state[k] == EL_UNSET ? "has no value"
                                                     : "may have no value (assigned in one "
                                                       "branch of a point-dependent 'if')",
                             nm(ex, at->name), fname);
        out->is_array = 1;
        out->elems = v->elems;
        out->n = v->n;
        return 1;
    }
    if (at->kind == HF_E_ARRAY && !in_place) {
        size_t n = (size_t)at->num;
        *temp = calloc(n, sizeof **temp);
        if (!*temp) return xfail(ex, at, FM_ERR_LIMIT, "out of memory compiling");
        size_t k = 0;
        for (uint32_t item = at->a; item; item = ex->p->nodes[item].next)
            if (!eval(ex, fr, item, &(*temp)[k++])) return 0;
        out->is_array = 1;
        out->elems = *temp;
        out->n = n;
        return 1;
    }
    return xfail(ex, at, FM_ERR_INPUT, "%s: argument %d must be %s", fname, argno,
                 in_place ? "the name of an array variable (the function changes it in place)"
                          : "an array (the name of an array variable or a list [a, b, c])");
}

static int count_args(const hf_program *p, uint32_t first)
{
    int n = 0;
    for (uint32_t a = first; a; a = p->nodes[a].next) n++;
    return n;
}

static int call_library(hf_exec *ex, hf_frame *fr, const hf_ast *at, const hf_lib_fn *fn,
                        fm_node *out)
{
    int want = (int)strlen(fn->sig), got = count_args(ex->p, at->a);
    if (want != got)
        return xfail(ex, at, FM_ERR_INPUT, "%s takes %d arguments, found %d", fn->name, want, got);
    hf_value args[16];
    fm_node *temps[16];
    memset(args, 0, sizeof args);
    memset(temps, 0, sizeof temps);
    int ok = 1, i = 0;
    for (uint32_t e = at->a; e && ok; e = ex->p->nodes[e].next, i++) {
        char kind = fn->sig[i];
        if (kind == 'r') {
            ok = eval(ex, fr, e, &args[i].scalar);
            continue;
        }
        ok = eval_array_arg(ex, fr, e, &args[i], &temps[i], kind == 'x', fn->name, i + 1);
        size_t need = kind == 'a' ? 1 : 3;
        if (ok && args[i].n < need)
            ok = xfail(ex, &ex->p->nodes[e], FM_ERR_INPUT,
                       "%s: argument %d must have at least %zu items, found %zu", fn->name, i + 1,
                       need, args[i].n);
    }
    if (ok) {
        hf_lib_ctx ctx;
        memset(&ctx, 0, sizeof ctx);
        ctx.g = ex->g;
        ctx.alpha = fr->alpha;
        ctx.fname = fn->name;
        *out = fn->fn(&ctx, args);
        if (!*out) {
            if (!check_graph(ex, at)) ok = 0;
            else ok = xfail(ex, at, FM_ERR_INPUT, "%s", ctx.message[0] ? ctx.message : "bad arguments");
        }
    }
    for (int k = 0; k < 16; k++) free(temps[k]);
    return ok;
}

static int const_arg(hf_exec *ex, hf_frame *fr, uint32_t e, double *v, const char *fname,
                     const char *what)
{
    char buf[96];
    snprintf(buf, sizeof buf, "%s: %s", fname, what);
    return eval_const(ex, fr, e, v, buf);
}

/* fmAffineT(x, a11, a12, a13, c1, a21, a22, a23, c2, a31, a32, a33, c3):
 * the object moves by X' = A X + c (entries may depend on t = x[4]); the
 * coordinate array becomes A^-1 (x - c), inverted symbolically with the
 * adjugate (Pasko eq. 11). */
static int ext_affine_t(hf_exec *ex, hf_frame *fr, const hf_ast *at, fm_node *out)
{
    uint32_t e = at->a;
    hf_value xs;
    fm_node *temp = NULL;
    if (!eval_array_arg(ex, fr, e, &xs, &temp, 1, "fmAffineT", 1)) return 0;
    if (xs.n < 3)
        return xfail(ex, at, FM_ERR_INPUT, "fmAffineT: argument 1 must have at least 3 items");
    fm_node m[12];
    int i = 0;
    for (e = ex->p->nodes[e].next; e; e = ex->p->nodes[e].next)
        if (!eval(ex, fr, e, &m[i++])) return 0;
    fm_affine_t_coords(ex->g, xs.elems, m); /* a singular A is a graph error */
    *out = fm_const(ex->g, 1.0);
    return check_graph(ex, at);
}

static int call_extension(hf_exec *ex, hf_frame *fr, const hf_ast *at, size_t which,
                          fm_node *out)
{
    const char *fname = extensions[which].name;
    int got = count_args(ex->p, at->a);
    if (got != extensions[which].arity)
        return xfail(ex, at, FM_ERR_INPUT, "%s takes %d arguments, found %d", fname,
                     extensions[which].arity, got);
    if (extensions[which].kind == EXT_AFFINE_T) return ext_affine_t(ex, fr, at, out);
    uint32_t e[4] = {0};
    int i = 0;
    for (uint32_t a = at->a; a && i < 4; a = ex->p->nodes[a].next) e[i++] = a;
    fm_graph *g = ex->g;
    fm_node f = FM_NONE, f2 = FM_NONE;
    double v0 = 0, v1 = 0;
    switch (extensions[which].kind) {
    case EXT_PROJECT:
        if (!eval(ex, fr, e[0], &f) || !const_arg(ex, fr, e[1], &v0, fname, "t0") ||
            !const_arg(ex, fr, e[2], &v1, fname, "t1"))
            return 0;
        if (!(v0 <= v1))
            return xfail(ex, at, FM_ERR_INPUT, "%s: t0 = %g must not exceed t1 = %g", fname, v0, v1);
        *out = fm_project(g, f, FM_T, v0, v1);
        break;
    case EXT_METAMORPH:
        if (!eval(ex, fr, e[0], &f) || !eval(ex, fr, e[1], &f2) ||
            !const_arg(ex, fr, e[2], &v0, fname, "t0") || !const_arg(ex, fr, e[3], &v1, fname, "t1"))
            return 0;
        if (!(v0 < v1))
            return xfail(ex, at, FM_ERR_INPUT, "%s: t0 = %g must be less than t1 = %g", fname, v0, v1);
        *out = fm_metamorph(g, f, f2, v0, v1);
        break;
    case EXT_OFFSET:
        if (!eval(ex, fr, e[0], &f) || !eval(ex, fr, e[1], &f2)) return 0;
        *out = fm_add(g, f, f2);
        break;
    case EXT_OFFSET_NORMAL:
    case EXT_OFFSET_RADIUS:
        if (!eval(ex, fr, e[0], &f) || !const_arg(ex, fr, e[1], &v0, fname, "the distance"))
            return 0;
        *out = extensions[which].kind == EXT_OFFSET_NORMAL ? fm_offset_normal(g, f, v0)
                                                           : fm_offset_radius(g, f, v0);
        break;
    case EXT_NORMALIZE:
        if (!eval(ex, fr, e[0], &f)) return 0;
        *out = fm_normalize(g, f);
        break;
    case EXT_TIME_SEGMENT:
        if (!const_arg(ex, fr, e[0], &v0, fname, "t0") || !const_arg(ex, fr, e[1], &v1, fname, "t1"))
            return 0;
        if (!(v0 <= v1))
            return xfail(ex, at, FM_ERR_INPUT, "%s: t0 = %g must not exceed t1 = %g", fname, v0, v1);
        *out = fm_time_segment(g, v0, v1);
        break;
    case EXT_AFFINE_T: break;
    }
    if (!check_graph(ex, at)) return 0;
    if (!*out) return xfail(ex, at, FM_ERR_INTERNAL, "%s: the frep builder failed", fname);
    return 1;
}

static int call_builtin(hf_exec *ex, hf_frame *fr, const hf_ast *at, size_t which, fm_node *out)
{
    int binary = builtins[which].kind == BI_BINARY || builtins[which].kind == BI_MOD;
    int got = count_args(ex->p, at->a);
    if (got != (binary ? 2 : 1))
        return xfail(ex, at, FM_ERR_INPUT, "%s takes %d argument%s, found %d",
                     builtins[which].name, binary ? 2 : 1, binary ? "s" : "", got);
    fm_node a, b = FM_NONE;
    if (!eval(ex, fr, at->a, &a)) return 0;
    if (binary && !eval(ex, fr, ex->p->nodes[at->a].next, &b)) return 0;
    fm_graph *g = ex->g;
    switch (builtins[which].kind) {
    case BI_UNARY: *out = fm_unary(g, builtins[which].op, a); break;
    case BI_BINARY: *out = fm_binary(g, builtins[which].op, a, b); break;
    case BI_LOGD: *out = fm_mul(g, fm_unary(g, FM_OP_LOG, a), fm_const(g, 1.0 / log(10.0))); break;
    case BI_MOD: { /* HyperFun: fmod(round(a), round(b)) */
        fm_node half = fm_const(g, 0.5);
        *out = fm_binary(g, FM_OP_MOD, fm_unary(g, FM_OP_FLOOR, fm_add(g, a, half)),
                         fm_unary(g, FM_OP_FLOOR, fm_add(g, b, half)));
        break;
    }
    case BI_INT: *out = fm_unary(g, FM_OP_TRUNC, a); break;
    case BI_FRAC: *out = fm_sub(g, a, fm_unary(g, FM_OP_TRUNC, a)); break;
    }
    return check_graph(ex, at);
}

static int call_object(hf_exec *ex, hf_frame *fr, const hf_ast *at, size_t which, fm_node *out);

static int eval_call(hf_exec *ex, hf_frame *fr, const hf_ast *at, fm_node *out)
{
    const char *lower = ex->p->names[at->name];
    if (fr->vars[at->name].kind != VAR_UNSET)
        return xfail(ex, at, FM_ERR_INPUT, "'%s' is a variable, not a function",
                     nm(ex, at->name));
    for (size_t i = 0; i < N_BUILTINS; i++)
        if (!strcmp(builtins[i].name, lower)) return call_builtin(ex, fr, at, i, out);
    const hf_lib_fn *fn = fm_hf_library_find(lower);
    if (fn) return call_library(ex, fr, at, fn, out);
    for (size_t i = 0; i < N_EXTENSIONS; i++)
        if (same_ci(extensions[i].name, lower)) return call_extension(ex, fr, at, i, out);
    for (size_t i = 0; i < ex->p->object_count; i++)
        if (ex->p->objects[i].name == at->name) return call_object(ex, fr, at, i, out);
    const char *s = suggest_function(ex, lower);
    if (s)
        return xfail(ex, at, FM_ERR_INPUT, "unknown function '%s'; did you mean '%s'?",
                     nm(ex, at->name), s);
    return xfail(ex, at, FM_ERR_INPUT, "unknown function '%s'", nm(ex, at->name));
}

static int eval_leaf(hf_exec *ex, hf_frame *fr, uint32_t e, fm_node *out)
{
    const hf_ast *at = &ex->p->nodes[e];
    if (!step(ex, at)) return 0;
    switch (at->kind) {
    case HF_E_NUM: *out = fm_const(ex->g, at->num); break;
    case HF_E_NAME:
        if (!read_var(ex, fr, at, out)) return 0;
        break;
    case HF_E_INDEX: {
        hf_var *v = &fr->vars[at->name];
        if (v->kind != VAR_ARRAY) {
            if (v->kind == VAR_SCALAR)
                return xfail(ex, at, FM_ERR_INPUT, "'%s' is a number, not an array",
                             nm(ex, at->name));
            return xfail(ex, at, FM_ERR_INPUT,
                         "unknown array '%s' (declare it with 'array %s[N];')", nm(ex, at->name),
                         nm(ex, at->name));
        }
        size_t k;
        if (!eval_index(ex, fr, at->a, v, at->name, &k)) return 0;
        v = &fr->vars[at->name]; /* the index expression cannot move it, but be safe */
        if (v->state[k] == EL_UNSET)
            return xfail(ex, at, FM_ERR_INPUT, "%s[%zu] is used before it is assigned",
                         nm(ex, at->name), k + 1);
        if (v->state[k] == EL_PARTIAL)
            return xfail(ex, at, FM_ERR_INPUT,
                         "%s[%zu] may have no value here: it is assigned in only one branch of the "
                         "'if' at line %d:%d, whose condition depends on the point",
                         nm(ex, at->name), k + 1, v->if_line, v->if_col);
        *out = v->elems[k];
        break;
    }
    case HF_E_CALL:
        if (!eval_call(ex, fr, at, out)) return 0;
        break;
    case HF_E_UNARY: {
        fm_node a;
        if (!eval(ex, fr, at->a, &a)) return 0;
        if (at->op == HF_TK_NOT) *out = fm_unary(ex->g, FM_OP_NOT, a);
        else if (at->op == HF_TK_PLUS) *out = a;
        else *out = fm_neg(ex->g, a); /* - and ~ (complement) */
        break;
    }
    case HF_E_ARRAY:
        return xfail(ex, at, FM_ERR_INPUT,
                     "an array list [...] can only be assigned to an array or passed to a "
                     "function that takes an array");
    default: return xfail(ex, at, FM_ERR_INTERNAL, "unexpected syntax node %d", at->kind);
    }
    return check_graph(ex, at);
}

/* Binary operators: the left spine of a chain a + b + c + ... is walked
 * with an explicit stack, so a long chain cannot overflow the C stack. */
static int eval(hf_exec *ex, hf_frame *fr, uint32_t e, fm_node *out)
{
    if (ex->failed) return 0;
    if (ex->p->nodes[e].kind != HF_E_BINARY) return eval_leaf(ex, fr, e, out);
    size_t base = ex->spine_count;
    uint32_t cur = e;
    while (ex->p->nodes[cur].kind == HF_E_BINARY) {
        if (ex->spine_count == ex->spine_cap) {
            size_t cap = ex->spine_cap ? ex->spine_cap * 2 : 64;
            uint32_t *s = realloc(ex->spine, cap * sizeof *s);
            if (!s) return xfail(ex, &ex->p->nodes[cur], FM_ERR_LIMIT, "out of memory compiling");
            ex->spine = s;
            ex->spine_cap = cap;
        }
        ex->spine[ex->spine_count++] = cur;
        cur = ex->p->nodes[cur].a;
    }
    fm_node acc;
    int ok = eval_leaf(ex, fr, cur, &acc);
    while (ok && ex->spine_count > base) {
        const hf_ast *at = &ex->p->nodes[ex->spine[--ex->spine_count]];
        fm_node b;
        ok = step(ex, at) && eval(ex, fr, at->b, &b);
        if (ok) {
            acc = apply_binary(ex, fr, (hf_tok)at->op, acc, b);
            ok = check_graph(ex, at);
        }
    }
    ex->spine_count = base;
    if (ok) *out = acc;
    return ok;
}

/* ---------------------------------------------------------- statements -- */

static int exec_assign(hf_exec *ex, hf_frame *fr, const hf_ast *at)
{
    hf_var *v = &fr->vars[at->name];
    const hf_ast *rhs = &ex->p->nodes[at->a];
    const hf_object *o = fr->obj;
    if (o && at->name == o->x_name)
        return xfail(ex, at, FM_ERR_INPUT,
                     "'%s' is the coordinate array of '%s'; assign its items (%s[1] = ...)",
                     nm(ex, at->name), nm(ex, o->name), nm(ex, at->name));
    if (rhs->kind == HF_E_ARRAY) {
        size_t n = (size_t)rhs->num;
        if (v->kind == VAR_ARRAY && v->n != n)
            return xfail(ex, rhs, FM_ERR_INPUT,
                         "array '%s' has %zu items, but the list has %zu", nm(ex, at->name), v->n,
                         n);
        fm_node *vals = calloc(n, sizeof *vals);
        if (!vals) return xfail(ex, at, FM_ERR_LIMIT, "out of memory compiling");
        size_t k = 0;
        int ok = 1;
        for (uint32_t item = rhs->a; item && ok; item = ex->p->nodes[item].next)
            ok = eval(ex, fr, item, &vals[k++]);
        v = &fr->vars[at->name];
        if (ok && v->kind != VAR_ARRAY) ok = make_array(ex, v, n, at);
        if (ok) {
            memcpy(v->elems, vals, n * sizeof *vals);
            memset(v->state, EL_SET, n);
        }
        free(vals);
        return ok;
    }
    if (rhs->kind == HF_E_NAME && fr->vars[rhs->name].kind == VAR_ARRAY &&
        !(o && at->name == o->name)) {
        /* a = b copies an array (an extension: HyperFun copies item by item) */
        if (rhs->name == at->name) return 1;
        hf_var *src = &fr->vars[rhs->name];
        if (v->kind == VAR_ARRAY && v->n != src->n)
            return xfail(ex, rhs, FM_ERR_INPUT, "array '%s' has %zu items, but '%s' has %zu",
                         nm(ex, at->name), v->n, nm(ex, rhs->name), src->n);
        if (v->kind != VAR_ARRAY && !make_array(ex, v, src->n, at)) return 0;
        memcpy(v->elems, src->elems, src->n * sizeof *src->elems);
        memcpy(v->state, src->state, src->n);
        return 1;
    }
    if (v->kind == VAR_ARRAY)
        return xfail(ex, at, FM_ERR_INPUT,
                     "'%s' is an array; assign an item (%s[1] = ...) or a list ([1, 2, 3])",
                     nm(ex, at->name), nm(ex, at->name));
    fm_node value;
    if (!eval(ex, fr, at->a, &value)) return 0;
    if (at->name == ex->alpha_name) { /* r_alpha = c; sets the R-functions' alpha */
        double a;
        if (!fm_node_is_const(ex->g, value, &a))
            return xfail(ex, rhs, FM_ERR_INPUT, "r_alpha must be a constant known at compile time");
        if (!(a >= 0.0 && a <= 1.0))
            return xfail(ex, rhs, FM_ERR_INPUT, "r_alpha must be in [0, 1] (as HyperFun's ALPHA), found %g", a);
        fr->alpha = a;
    }
    v = &fr->vars[at->name];
    v->kind = VAR_SCALAR;
    v->partial = 0;
    v->v = value;
    return 1;
}

static int exec_assign_elem(hf_exec *ex, hf_frame *fr, const hf_ast *at)
{
    hf_var *v = &fr->vars[at->name];
    if (v->kind != VAR_ARRAY) {
        if (v->kind == VAR_SCALAR)
            return xfail(ex, at, FM_ERR_INPUT, "'%s' is a number, not an array", nm(ex, at->name));
        return xfail(ex, at, FM_ERR_INPUT, "unknown array '%s' (declare it with 'array %s[N];')",
                     nm(ex, at->name), nm(ex, at->name));
    }
    size_t k;
    fm_node value;
    if (!eval_index(ex, fr, at->a, v, at->name, &k) || !eval(ex, fr, at->b, &value)) return 0;
    v = &fr->vars[at->name];
    v->elems[k] = value;
    v->state[k] = EL_SET;
    return 1;
}

static int exec_decl(hf_exec *ex, hf_frame *fr, const hf_ast *at)
{
    for (uint32_t d = at->a; d; d = ex->p->nodes[d].next) {
        const hf_ast *item = &ex->p->nodes[d];
        const hf_object *o = fr->obj;
        if (o && (item->name == o->x_name || item->name == o->a_name || item->name == o->s_name))
            return xfail(ex, item, FM_ERR_INPUT,
                         "'%s' is a parameter of '%s' and cannot be declared again",
                         nm(ex, item->name), nm(ex, o->name));
        double size;
        if (!eval_const(ex, fr, item->a, &size, "an array size")) return 0;
        if (!(size >= 1 && size == floor(size)))
            return xfail(ex, &ex->p->nodes[item->a], FM_ERR_INPUT,
                         "array size must be a positive integer, found %g", size);
        if (size > (double)ex->opt->max_array)
            return xfail(ex, &ex->p->nodes[item->a], FM_ERR_LIMIT,
                         "array '%s' of %g items is larger than %zu (the array budget)",
                         nm(ex, item->name), size, ex->opt->max_array);
        if (!make_array(ex, &fr->vars[item->name], (size_t)size, item)) return 0;
    }
    return 1;
}

static int exec_if(hf_exec *ex, hf_frame *fr, const hf_ast *at)
{
    fm_node cond;
    if (!eval(ex, fr, at->a, &cond)) return 0;
    double c;
    if (fm_node_is_const(ex->g, cond, &c)) return exec_block(ex, fr, c != 0.0 ? at->b : at->c);
    /* The condition depends on the point or a parameter: run both branches
     * on copies and join them with selects. */
    hf_frame else_fr;
    if (!frame_copy(ex, &else_fr, fr, at)) {
        frame_free(&else_fr);
        return 0;
    }
    int ok = exec_block(ex, fr, at->b) && exec_block(ex, &else_fr, at->c);
    if (ok) {
        if (else_fr.alpha != fr->alpha)
            ok = xfail(ex, at, FM_ERR_INPUT,
                       "r_alpha is set differently in the two branches of this point-dependent 'if'");
        else
            ok = frame_merge(ex, fr, &else_fr, cond, at);
    }
    frame_free(&else_fr);
    return ok;
}

static int exec_while(hf_exec *ex, hf_frame *fr, const hf_ast *at)
{
    size_t count = 0;
    for (;;) {
        fm_node cond;
        if (!eval(ex, fr, at->a, &cond)) return 0;
        double c;
        if (!fm_node_is_const(ex->g, cond, &c)) {
            int on_x = 0;
            for (int axis = 0; axis < FM_AXES; axis++) on_x |= fm_node_depends_on(ex->g, cond, axis);
            return xfail(ex, at, FM_ERR_INPUT,
                         "the condition of this 'while' depends on %s; only loops whose "
                         "condition is known at compile time can be unrolled",
                         on_x ? "the point coordinates (x)" : "a parameter (a)");
        }
        if (c == 0.0) return 1;
        if (++ex->iterations > ex->opt->max_iterations)
            return xfail(ex, at, FM_ERR_LIMIT,
                         "this 'while' loop has not ended after %zu iterations (%zu for all "
                         "loops is the iteration budget); does its condition ever become false?",
                         count, ex->opt->max_iterations);
        count++;
        if (!exec_block(ex, fr, at->b)) return 0;
    }
}

static int exec_block(hf_exec *ex, hf_frame *fr, uint32_t first)
{
    for (uint32_t s = first; s; s = ex->p->nodes[s].next) {
        const hf_ast *at = &ex->p->nodes[s];
        if (ex->failed || !step(ex, at)) return 0;
        int ok;
        switch (at->kind) {
        case HF_S_ASSIGN: ok = exec_assign(ex, fr, at); break;
        case HF_S_ASSIGN_ELEM: ok = exec_assign_elem(ex, fr, at); break;
        case HF_S_ARRAY_DECL: ok = exec_decl(ex, fr, at); break;
        case HF_S_IF: ok = exec_if(ex, fr, at); break;
        case HF_S_WHILE: ok = exec_while(ex, fr, at); break;
        default: ok = xfail(ex, at, FM_ERR_INTERNAL, "unexpected statement node %d", at->kind);
        }
        if (!ok) return 0;
    }
    return 1;
}

/* ------------------------------------------------------------ objects -- */

/* Run an object's body in a fresh frame whose x (and a, s) arrays are
 * given; the result is the value assigned to the object's name. */
static int run_object(hf_exec *ex, size_t which, const fm_node *x, size_t nx, const fm_node *a,
                      size_t na, const hf_ast *call_site, fm_node *out)
{
    const hf_object *o = &ex->p->objects[which];
    const hf_ast *at = call_site;
    hf_ast head;
    memset(&head, 0, sizeof head);
    head.line = o->line;
    head.col = o->col;
    if (!at) at = &head;
    if (ex->active[which]) {
        return xfail(ex, at, FM_ERR_INPUT,
                     "recursive call of object '%s' (it calls itself, directly or through other "
                     "objects); HyperFun objects cannot recurse",
                     nm(ex, o->name));
    }
    if (ex->call_depth >= ex->opt->max_call_depth)
        return xfail(ex, at, FM_ERR_LIMIT, "objects call each other more than %zu deep (the call budget)",
                     ex->opt->max_call_depth);
    hf_frame fr;
    if (!frame_init(ex, &fr, o, at)) return 0;
    int ok = make_array(ex, &fr.vars[o->x_name], (size_t)o->x_dim, at);
    if (ok) {
        memcpy(fr.vars[o->x_name].elems, x, (size_t)o->x_dim * sizeof *x);
        memset(fr.vars[o->x_name].state, EL_SET, (size_t)o->x_dim);
    }
    (void)nx;
    if (ok && o->a_name) {
        ok = make_array(ex, &fr.vars[o->a_name], (size_t)o->a_dim, at);
        if (ok) {
            memcpy(fr.vars[o->a_name].elems, a, (size_t)o->a_dim * sizeof *a);
            memset(fr.vars[o->a_name].state, EL_SET, (size_t)o->a_dim);
        }
    }
    (void)na;
    if (ok && o->s_name) { /* attributes do not shape the geometry: all 0 */
        ok = make_array(ex, &fr.vars[o->s_name], (size_t)o->s_dim, at);
        for (int k = 0; ok && k < o->s_dim; k++) {
            fr.vars[o->s_name].elems[k] = fm_const(ex->g, 0.0);
            fr.vars[o->s_name].state[k] = EL_SET;
        }
    }
    ex->active[which] = 1;
    ex->call_depth++;
    ok = ok && exec_block(ex, &fr, o->body);
    ex->call_depth--;
    ex->active[which] = 0;
    if (ok) {
        hf_var *r = &fr.vars[o->name];
        if (r->kind == VAR_SCALAR && !r->partial) {
            *out = r->v;
        } else {
            hf_ast end = head;
            ok = xfail(ex, &end, FM_ERR_INPUT,
                       r->kind == VAR_SCALAR
                           ? "object '%s' assigns its result in only one branch of a point-"
                             "dependent 'if'; assign '%s = ...;' on every path"
                           : "object '%s' never assigns its result; end it with '%s = ...;'",
                       nm(ex, o->name), nm(ex, o->name));
        }
    }
    frame_free(&fr);
    return ok;
}

static int call_object(hf_exec *ex, hf_frame *fr, const hf_ast *at, size_t which, fm_node *out)
{
    const hf_object *o = &ex->p->objects[which];
    /* HyperFun calls pass (x, a); an object without a parameter array
     * ignores a second argument. */
    int want = o->a_name ? 2 : 1, got = count_args(ex->p, at->a);
    if (got != want && !(!o->a_name && got == 2))
        return xfail(ex, at, FM_ERR_INPUT, "object '%s' takes %d argument%s (%s), found %d",
                     nm(ex, o->name), want, want > 1 ? "s" : "",
                     o->a_name ? "a coordinate array and a parameter array" : "a coordinate array",
                     got);
    hf_value xs, as;
    fm_node *tx = NULL, *ta = NULL;
    memset(&as, 0, sizeof as);
    uint32_t second = ex->p->nodes[at->a].next;
    int ok = eval_array_arg(ex, fr, at->a, &xs, &tx, 0, nm(ex, o->name), 1);
    if (ok && (size_t)o->x_dim > xs.n)
        ok = xfail(ex, at, FM_ERR_INPUT, "object '%s' needs a coordinate array of %d items, found %zu",
                   nm(ex, o->name), o->x_dim, xs.n);
    if (ok && o->a_name) {
        ok = eval_array_arg(ex, fr, second, &as, &ta, 0, nm(ex, o->name), 2);
        if (ok && (size_t)o->a_dim > as.n)
            ok = xfail(ex, at, FM_ERR_INPUT, "object '%s' needs a parameter array of %d items, found %zu",
                       nm(ex, o->name), o->a_dim, as.n);
    }
    /* Copies: the callee cannot change the caller's arrays (as HyperFun). */
    fm_node xcopy[4], *acopy = NULL;
    if (ok) memcpy(xcopy, xs.elems, (size_t)o->x_dim * sizeof *xcopy);
    if (ok && o->a_name) {
        acopy = malloc((size_t)o->a_dim * sizeof *acopy);
        if (!acopy) ok = xfail(ex, at, FM_ERR_LIMIT, "out of memory compiling");
        else memcpy(acopy, as.elems, (size_t)o->a_dim * sizeof *acopy);
    }
    if (ok) ok = run_object(ex, which, xcopy, (size_t)o->x_dim, acopy, (size_t)o->a_dim, at, out);
    free(acopy);
    free(tx);
    free(ta);
    return ok;
}

/* ------------------------------------------------------------- entries -- */

static void fill_options(fm_hf_options *o, const fm_hf_options *in)
{
    memset(o, 0, sizeof *o);
    if (in) *o = *in;
    if (!o->max_source) o->max_source = FM_HF_MAX_SOURCE;
    if (!o->max_tokens) o->max_tokens = FM_HF_MAX_TOKENS;
    if (!o->max_depth) o->max_depth = FM_HF_MAX_DEPTH;
    if (!o->max_iterations) o->max_iterations = FM_HF_MAX_ITERATIONS;
    if (!o->max_steps) o->max_steps = FM_HF_MAX_STEPS;
    if (!o->max_array) o->max_array = FM_HF_MAX_ARRAY;
    if (!o->max_call_depth) o->max_call_depth = FM_HF_MAX_CALL_DEPTH;
}

static int exec_init(hf_exec *ex, hf_program *p, fm_graph *g, const fm_hf_options *opt,
                     fm_error *err)
{
    memset(ex, 0, sizeof *ex);
    ex->p = p;
    ex->g = g;
    ex->opt = opt;
    ex->err = err;
    ex->alpha_name = fm_hf_intern(p, "r_alpha", 7);
    ex->active = calloc(p->object_count ? p->object_count : 1, 1);
    if (!ex->active || !ex->alpha_name)
        return xfail(ex, NULL, FM_ERR_LIMIT, "out of memory compiling");
    return 1;
}

static void exec_free(hf_exec *ex)
{
    free(ex->active);
    free(ex->spine);
}

fm_status fm_hf_compile_string(fm_graph *g, const char *source, size_t length,
                               const char *source_name, const char *model_name,
                               const fm_hf_options *options, fm_hf_model *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    if (out) memset(out, 0, sizeof *out);
    if (!g || !source || !out)
        return fm_error_set(err, FM_ERR_INTERNAL, "fm_hf_compile_string: missing argument");
    if (!source_name) source_name = "<string>";
    fm_hf_options opt;
    fill_options(&opt, options);
    if (!(opt.alpha >= 0.0 && opt.alpha <= 1.0))
        return fm_error_set(err, FM_ERR_INPUT, "alpha must be in [0, 1], found %g", opt.alpha);
    hf_program p;
    memset(&p, 0, sizeof p);
    p.source_name = source_name;
    p.opt = &opt;
    fm_status st = fm_hf_parse(&p, source, length, 0, NULL, err);
    if (st != FM_OK) {
        fm_hf_program_free(&p);
        return st;
    }
    size_t which = p.object_count - 1;
    if (model_name) {
        size_t i = 0;
        for (; i < p.object_count; i++)
            if (fm_hf_edit_distance(p.names[p.objects[i].name], model_name) == 0) break;
        if (i == p.object_count) {
            best_match b = {NULL, (size_t)-1};
            for (size_t k = 0; k < p.object_count; k++) consider(&b, p.spellings[p.objects[k].name], model_name);
            if (b.name)
                st = fm_error_at(err, FM_ERR_INPUT, source_name, 0, 0,
                                 "no object named '%s' in the source; did you mean '%s'?",
                                 model_name, b.name);
            else
                st = fm_error_at(err, FM_ERR_INPUT, source_name, 0, 0,
                                 "no object named '%s' in the source", model_name);
            fm_hf_program_free(&p);
            return st;
        }
        which = i;
    }
    const hf_object *o = &p.objects[which];
    hf_exec ex;
    fm_node root = FM_NONE;
    int ok = exec_init(&ex, &p, g, &opt, err);
    if (ok) {
        fm_node x[4], a[FM_HF_MAX_PARAMS];
        for (int i = 0; i < o->x_dim; i++) x[i] = fm_var(g, i);
        for (int i = 0; i < o->a_dim; i++) {
            char name[FM_HF_NAME_MAX + 8];
            snprintf(name, sizeof name, "%s%d", p.names[o->a_name], i + 1);
            a[i] = fm_param(g, name, 0.0);
            snprintf(out->param_names[i], sizeof out->param_names[i], "%s", name);
        }
        out->param_count = (size_t)o->a_dim;
        ok = check_graph(&ex, NULL) &&
             run_object(&ex, which, x, (size_t)o->x_dim, a, (size_t)o->a_dim, NULL, &root);
    }
    exec_free(&ex);
    if (ok) {
        out->root = root;
        out->dimension = o->x_dim;
        snprintf(out->name, sizeof out->name, "%s", p.names[o->name]);
    } else {
        memset(out, 0, sizeof *out);
    }
    fm_hf_program_free(&p);
    return ok ? FM_OK : (err->code ? err->code : FM_ERR_INTERNAL);
}

fm_status fm_hf_compile_file(fm_graph *g, const char *path, const char *model_name,
                             fm_hf_model *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    if (out) memset(out, 0, sizeof *out);
    if (!path) return fm_error_set(err, FM_ERR_INTERNAL, "fm_hf_compile_file: no path");
    char *buf;
    size_t len;
    fm_status st = fm_file_read(path, NULL, FM_HF_MAX_SOURCE, &buf, &len, err);
    if (st != FM_OK) {
        snprintf(err->file, sizeof err->file, "%s", path);
        return st;
    }
    st = fm_hf_compile_string(g, buf, len, path, model_name, NULL, out, err);
    free(buf);
    return st;
}

fm_node fm_hf_parse_expression(fm_graph *g, const char *text, const char *const *var_names,
                               const fm_node *var_nodes, size_t n_vars,
                               const char *source_name, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    if (!g || !text || (n_vars && (!var_names || !var_nodes))) {
        fm_error_set(err, FM_ERR_INTERNAL, "fm_hf_parse_expression: missing argument");
        return FM_NONE;
    }
    fm_hf_options opt;
    fill_options(&opt, NULL);
    hf_program p;
    memset(&p, 0, sizeof p);
    p.source_name = source_name ? source_name : "";
    p.opt = &opt;
    uint32_t root = 0;
    fm_node result = FM_NONE;
    /* Intern the variable names first so that the frame has their slots. */
    for (size_t i = 0; i < n_vars; i++) {
        size_t len = var_names[i] ? strlen(var_names[i]) : 0;
        if (len == 0 || len >= FM_HF_NAME_MAX) {
            fm_error_set(err, FM_ERR_INPUT, "bad variable name #%zu for the expression", i + 1);
            fm_hf_program_free(&p);
            return FM_NONE;
        }
        if (!fm_hf_intern(&p, var_names[i], len)) {
            fm_error_set(err, FM_ERR_LIMIT, "out of memory for the expression's variable names");
            fm_hf_program_free(&p);
            return FM_NONE;
        }
    }
    if (fm_hf_parse(&p, text, strlen(text), 1, &root, err) == FM_OK) {
        hf_exec ex;
        hf_frame fr;
        int ok = exec_init(&ex, &p, g, &opt, err) && frame_init(&ex, &fr, NULL, NULL);
        if (ok) {
            for (size_t i = 0; i < n_vars; i++) {
                uint32_t id = fm_hf_intern(&p, var_names[i], strlen(var_names[i]));
                fr.vars[id].kind = VAR_SCALAR;
                fr.vars[id].v = var_nodes[i];
            }
            ok = eval(&ex, &fr, root, &result);
            frame_free(&fr);
        }
        exec_free(&ex);
        if (!ok) result = FM_NONE;
    }
    fm_hf_program_free(&p);
    return result;
}
