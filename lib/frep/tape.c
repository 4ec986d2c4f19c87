/* tape.c: the compiler from an fm_graph DAG to a flat tape. The reachable
 * part of the DAG is copied into a local arena where constant folding and
 * the function-invariant min/max rewrite rules (Hasan sec. 4.2.1) apply,
 * then emitted in topological order as instructions over value numbers,
 * then given register slots that are reused after a value's last use.
 * Special ops (projection, offsets, normalization, voxels) compile their
 * child to a sub-tape held in the tape's special table. */
#include "frep/tape_internal.h"

#include <stdlib.h>
#include <string.h>

/* --------------------------------------------------- local arena -- */

/* A node of the compiler's arena. `safe`: cannot be NaN when the
 * coordinates are finite and below ~1e150 in magnitude (so that sums and
 * products of them stay finite); only then may min/max operands be
 * reordered, because fm_apply_binary's min/max are not commutative on NaN.
 * `nonneg`: safe and >= 0. `uses`: parents in the graph (1 for nodes the
 * rewrites make), so that flattening never copies a shared subtree. */
typedef struct cnode {
    uint8_t op, safe, nonneg;
    uint32_t aux;
    uint32_t a, b, c;
    double value;
    uint32_t uses;
} cnode;

typedef struct compiler {
    const fm_graph *g;
    fm_error *err;
    int failed;
    int depth;
    cnode *cn;
    size_t ncn, capcn;
    uint32_t *table;
    size_t table_size;
    uint32_t *param_map; /* graph param index -> tape param index */
    size_t nparams;
    fm_tape_shared *shared;
} compiler;

static uint32_t fail(compiler *cc, fm_status code, const char *msg)
{
    if (!cc->failed) {
        cc->failed = 1;
        fm_error_set(cc->err, code, "%s", msg);
    }
    return 0;
}

static uint64_t hash_cn(const cnode *r)
{
    uint64_t h = 1469598103934665603ULL;
    uint64_t w[4];
    w[0] = (uint64_t)r->op | ((uint64_t)r->aux << 8);
    w[1] = ((uint64_t)r->a << 32) | r->b;
    w[2] = r->c;
    memcpy(&w[3], &r->value, 8);
    for (int i = 0; i < 4; i++) {
        h ^= w[i];
        h *= 1099511628211ULL;
        h ^= h >> 29;
    }
    return h;
}

static int same_cn(const cnode *x, const cnode *y)
{
    return x->op == y->op && x->aux == y->aux && x->a == y->a && x->b == y->b && x->c == y->c &&
           memcmp(&x->value, &y->value, sizeof x->value) == 0;
}

static int grow_cn_table(compiler *cc)
{
    size_t size = cc->table_size ? cc->table_size * 2 : 256;
    uint32_t *table = calloc(size, sizeof *table);
    if (!table) return 0;
    for (size_t i = 1; i < cc->ncn; i++) {
        size_t slot = hash_cn(&cc->cn[i]) & (size - 1);
        while (table[slot]) slot = (slot + 1) & (size - 1);
        table[slot] = (uint32_t)i;
    }
    free(cc->table);
    cc->table = table;
    cc->table_size = size;
    return 1;
}

static void set_flags(compiler *cc, cnode *r)
{
    const cnode *A = r->a ? &cc->cn[r->a] : NULL, *B = r->b ? &cc->cn[r->b] : NULL,
                *C = r->c ? &cc->cn[r->c] : NULL;
    int sa = A && A->safe, sb = B && B->safe, sc = C && C->safe;
    int na = A && A->nonneg, nb = B && B->nonneg;
    r->safe = r->nonneg = 0;
    switch ((fm_op)r->op) {
    case FM_OP_CONST:
        r->safe = isfinite(r->value);
        r->nonneg = r->safe && r->value >= 0;
        break;
    case FM_OP_VAR: r->safe = 1; break;
    case FM_OP_NEG:
    case FM_OP_SIN:
    case FM_OP_COS:
    case FM_OP_ATAN:
    case FM_OP_TANH:
    case FM_OP_FLOOR:
    case FM_OP_CEIL:
    case FM_OP_TRUNC: r->safe = sa; break;
    case FM_OP_ABS:
    case FM_OP_SQUARE: r->safe = r->nonneg = sa; break;
    case FM_OP_SQRT: r->safe = r->nonneg = na; break;
    case FM_OP_SIGN:
    case FM_OP_NOT:
    case FM_OP_LT:
    case FM_OP_LE:
    case FM_OP_EQ:
    case FM_OP_NE:
    case FM_OP_AND:
    case FM_OP_OR: r->safe = r->nonneg = 1; break; /* never NaN, even of NaN */
    case FM_OP_ADD:
    case FM_OP_MUL:
        r->safe = sa && sb;
        r->nonneg = na && nb;
        break;
    case FM_OP_SUB:
    case FM_OP_ATAN2: r->safe = sa && sb; break;
    case FM_OP_MIN:
    case FM_OP_MAX:
        r->safe = sa && sb;
        r->nonneg = na && nb;
        break;
    case FM_OP_SELECT:
        r->safe = sb && sc;
        r->nonneg = C && B && B->nonneg && C->nonneg;
        break;
    default: break; /* PARAM, specials, DIV, LOG, POW, ...: may be NaN */
    }
}

static uint32_t mk_raw(compiler *cc, fm_op op, uint32_t aux, uint32_t a, uint32_t b, uint32_t c,
                       double value)
{
    if (cc->failed) return 0;
    cnode r = {0};
    r.op = (uint8_t)op;
    r.aux = aux;
    r.a = a;
    r.b = b;
    r.c = c;
    r.value = value;
    r.uses = 1;
    if (!cc->table_size && !grow_cn_table(cc))
        return fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape");
    size_t mask = cc->table_size - 1, slot = hash_cn(&r) & mask;
    while (cc->table[slot]) {
        if (same_cn(&cc->cn[cc->table[slot]], &r)) return cc->table[slot];
        slot = (slot + 1) & mask;
    }
    if (cc->ncn >= FM_TAPE_MAX_INSNS)
        return fail(cc, FM_ERR_LIMIT, "the tape would exceed its instruction budget");
    if (cc->ncn == cc->capcn) {
        size_t cap = cc->capcn ? cc->capcn * 2 : 256;
        cnode *n = realloc(cc->cn, cap * sizeof *n);
        if (!n) return fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape");
        cc->cn = n;
        cc->capcn = cap;
        if (cc->ncn == 0) cc->ncn = 1; /* id 0 means none */
    }
    uint32_t id = (uint32_t)cc->ncn++;
    set_flags(cc, &r);
    cc->cn[id] = r;
    cc->table[slot] = id;
    if (cc->ncn * 2 > cc->table_size && !grow_cn_table(cc))
        return fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape");
    return id;
}

static uint32_t mk_const(compiler *cc, double v)
{
    return mk_raw(cc, FM_OP_CONST, 0, 0, 0, 0, v == 0.0 ? 0.0 : v);
}

static int cn_is_const(const compiler *cc, uint32_t n, double v)
{
    return cc->cn[n].op == FM_OP_CONST && cc->cn[n].value == v;
}

/* Operands of a min (or max) chain, for flattening. */
#define FLAT_MAX 64

static uint32_t build_balanced(compiler *cc, fm_op op, const uint32_t *list, size_t n)
{
    if (n == 1) return list[0];
    size_t h = n / 2;
    uint32_t l = build_balanced(cc, op, list, h);
    uint32_t r = build_balanced(cc, op, list + h, n - h);
    return mk_raw(cc, op, 0, l, r, 0, 0.0);
}

/* min(a, b) / max(a, b) of NaN-free operands: flatten nested chains of the
 * same op, drop duplicates (min(a, min(a, b)) = min(a, b)), keep one
 * constant, apply absorption (min(a, max(a, b)) = a), and rebuild as a
 * balanced tree (its subtrees are pruned whole by interval shortening).
 *
 * Bit exactness: on non-NaN values, any tree of m(a, b) = a < b ? a : b
 * over leaves in a fixed order returns the LAST leaf (in order) among those
 * of minimal value, whatever its shape. So the leaf order is kept, of equal
 * leaves the last one stays, of the constants only the one that would win
 * among them. Absorption drops max(a, b) from a min list holding a: its
 * value is never below a's, and when equal it differs at most in the sign
 * of a zero (max(+0, -0)), the one place where the tape may differ from the
 * DAG's literal order (documented in docs/frep.md). */
static uint32_t flatten_minmax(compiler *cc, fm_op op, uint32_t a, uint32_t b)
{
    uint32_t list[FLAT_MAX], keep[FLAT_MAX], stack[FLAT_MAX];
    size_t n = 0, m = 0, sp = 0;
    /* In-order leaves, opening single-use links of the same op only (a
     * shared subexpression is still computed once); FLAT_MAX bounds the
     * work per node. */
    stack[sp++] = b;
    stack[sp++] = a;
    while (sp) {
        uint32_t x = stack[--sp];
        const cnode *r = &cc->cn[x];
        if (r->op == op && r->uses == 1 && n + sp + 2 <= FLAT_MAX) {
            stack[sp++] = r->b;
            stack[sp++] = r->a;
        } else {
            list[n++] = x;
        }
    }
    long winner = -1; /* the constant that wins among the constants */
    for (size_t i = 0; i < n; i++) {
        const cnode *r = &cc->cn[list[i]];
        if (r->op != FM_OP_CONST) continue;
        double w = winner < 0 ? 0.0 : cc->cn[list[winner]].value;
        /* A later constant wins unless strictly beaten (ties go to it). */
        if (winner < 0 || !(op == FM_OP_MIN ? w < r->value : w > r->value)) winner = (long)i;
    }
    fm_op dual = op == FM_OP_MIN ? FM_OP_MAX : FM_OP_MIN;
    for (size_t i = 0; i < n; i++) {
        const cnode *r = &cc->cn[list[i]];
        if (r->op == FM_OP_CONST && (long)i != winner) continue;
        int later_copy = 0, absorbed = 0;
        for (size_t j = i + 1; j < n; j++) {
            if (list[j] == list[i]) later_copy = 1;
        }
        for (size_t j = 0; j < n && r->op == dual; j++)
            if (j != i && (list[j] == r->a || list[j] == r->b)) absorbed = 1;
        if (!later_copy && !absorbed) keep[m++] = list[i];
    }
    return build_balanced(cc, op, keep, m);
}

/* Build a node with folding and the rewrite rules. */
static uint32_t mk(compiler *cc, fm_op op, uint32_t a, uint32_t b, uint32_t c, uint32_t uses)
{
    if (cc->failed) return 0;
    int arity = fm_op_arity(op);
    const cnode *A = a ? &cc->cn[a] : NULL, *B = b ? &cc->cn[b] : NULL;
    uint32_t id;
    if (arity == 1) {
        if (A->op == FM_OP_CONST) return mk_const(cc, fm_apply_unary(op, A->value));
        if (op == FM_OP_NEG && A->op == FM_OP_NEG) return A->a;
        if (op == FM_OP_ABS && (A->op == FM_OP_ABS || A->op == FM_OP_SQUARE)) return a;
        id = mk_raw(cc, op, 0, a, 0, 0, 0.0);
    } else if (arity == 2) {
        if (A->op == FM_OP_CONST && B->op == FM_OP_CONST)
            return mk_const(cc, fm_apply_binary(op, A->value, B->value));
        switch (op) {
        case FM_OP_ADD:
            if (cn_is_const(cc, a, 0.0)) return b;
            if (cn_is_const(cc, b, 0.0)) return a;
            break;
        case FM_OP_SUB:
            if (cn_is_const(cc, b, 0.0)) return a;
            break;
        case FM_OP_MUL:
            if (cn_is_const(cc, a, 1.0)) return b;
            if (cn_is_const(cc, b, 1.0)) return a;
            break;
        case FM_OP_DIV:
        case FM_OP_POW:
            if (cn_is_const(cc, b, 1.0)) return a;
            break;
        case FM_OP_MIN:
        case FM_OP_MAX:
            if (a == b) return a;
            /* max(-p, -q) = -min(p, q), bit for bit (also on NaN): one
             * instruction fewer when the negations are used only here. */
            if (A->op == FM_OP_NEG && B->op == FM_OP_NEG && A->uses == 1 && B->uses == 1) {
                fm_op dual = op == FM_OP_MIN ? FM_OP_MAX : FM_OP_MIN;
                uint32_t inner = mk(cc, dual, A->a, B->a, 0, 1);
                return mk(cc, FM_OP_NEG, inner, 0, 0, 1);
            }
            if (A->safe && B->safe) {
                id = flatten_minmax(cc, op, a, b);
                if (!cc->failed && uses > 1 && cc->cn[id].uses < uses) cc->cn[id].uses = uses;
                return id;
            }
            break;
        default: break;
        }
        id = mk_raw(cc, op, 0, a, b, 0, 0.0);
    } else if (arity == 3) {
        if (A->op == FM_OP_CONST) return A->value != 0.0 ? b : c;
        if (b == c) return b;
        id = mk_raw(cc, op, 0, a, b, c, 0.0);
    } else {
        return fail(cc, FM_ERR_INTERNAL, "bad op in the tape compiler");
    }
    if (!cc->failed && uses > cc->cn[id].uses) cc->cn[id].uses = uses;
    return id;
}

/* ------------------------------------------------ graph -> arena -- */

static fm_tape *compile_at_depth(const fm_graph *g, fm_node root, int depth, fm_error *err);

static uint32_t add_special(compiler *cc, const fm_node_rec *r, const uint32_t ch[3])
{
    fm_tape_shared *s = cc->shared;
    fm_special *sp = realloc(s->specials, (s->nspecials + 1) * sizeof *sp);
    if (!sp) return fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape");
    s->specials = sp;
    fm_special *x = &sp[s->nspecials];
    memset(x, 0, sizeof *x);
    x->op = r->op;
    x->axis = r->aux;
    x->value = r->value;
    x->value2 = r->value2;
    if (r->op == FM_OP_VOXELS) {
        if (r->aux >= cc->g->grid_count)
            return fail(cc, FM_ERR_INTERNAL, "voxel node refers to a missing grid");
        const fm_voxel_grid *src = &cc->g->grids[r->aux];
        size_t cells;
        if (!fm_size_mul(src->n[0], src->n[1], &cells) || !fm_size_mul(cells, src->n[2], &cells) ||
            !fm_size_mul(cells, sizeof(float), &cells))
            return fail(cc, FM_ERR_LIMIT, "voxel grid too large");
        x->grid = *src;
        x->grid.values = malloc(cells ? cells : 1);
        if (!x->grid.values) return fail(cc, FM_ERR_LIMIT, "out of memory copying a voxel grid");
        memcpy(x->grid.values, src->values, cells);
        s->nspecials++;
    } else {
        if (r->op == FM_OP_PROJECT && r->aux >= FM_AXES)
            return fail(cc, FM_ERR_INPUT, "projection axis out of range");
        fm_error sub_err;
        fm_error_clear(&sub_err);
        x->child = compile_at_depth(cc->g, r->a, cc->depth + 1, &sub_err);
        if (!x->child) {
            if (!cc->failed) {
                cc->failed = 1;
                if (cc->err) *cc->err = sub_err;
            }
            return 0;
        }
        s->nspecials++;
    }
    /* VOXELS samples at its three children (the possibly remapped x, y, z:
     * see ops_internal.h); the other special ops own their child. */
    if (r->op == FM_OP_VOXELS)
        return mk_raw(cc, FM_OP_VOXELS, (uint32_t)(s->nspecials - 1), ch[0], ch[1], ch[2], 0.0);
    return mk_raw(cc, (fm_op)r->op, (uint32_t)(s->nspecials - 1), 0, 0, 0, 0.0);
}

static uint32_t param_index(compiler *cc, uint32_t graph_index)
{
    if (cc->param_map[graph_index] != UINT32_MAX) return cc->param_map[graph_index];
    fm_tape_shared *s = cc->shared;
    const char *name = cc->g->param_names[graph_index];
    char **names = realloc(s->param_names, (s->nparams + 1) * sizeof *names);
    if (!names) return fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape"), UINT32_MAX;
    s->param_names = names;
    char *copy = malloc(strlen(name) + 1);
    if (!copy) return fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape"), UINT32_MAX;
    strcpy(copy, name);
    names[s->nparams] = copy;
    cc->param_map[graph_index] = (uint32_t)s->nparams;
    return (uint32_t)s->nparams++;
}

/* Children of a graph node that belong to this tape (special ops own their
 * child through a sub-tape). */
static int graph_children(const fm_node_rec *r, fm_node out[3])
{
    int ar = r->op == FM_OP_VOXELS ? 3 : fm_op_arity((fm_op)r->op);
    if (ar < 0) return 0;
    out[0] = r->a;
    out[1] = r->b;
    out[2] = r->c;
    return ar;
}

/* Post-order walk of the reachable graph: map each node into the arena.
 * Iterative, so that a deep expression cannot overflow the C stack. */
static uint32_t import_graph(compiler *cc, fm_node root)
{
    const fm_graph *g = cc->g;
    size_t count = g->count;
    uint32_t *map = calloc(count, sizeof *map);
    uint32_t *uses = calloc(count, sizeof *uses);
    uint8_t *state = calloc(count, 1);
    /* A node may sit on the stack once per parent edge before it is
     * expanded, and each node is expanded once: at most 3 pushes each. */
    fm_node *stack = malloc((3 * count + 1) * sizeof *stack);
    uint32_t result = 0;
    if (!map || !uses || !state || !stack) {
        fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape");
        goto done;
    }
    /* Pass 1: parents of each reachable node. */
    size_t sp = 0;
    stack[sp++] = root;
    state[root] = 1;
    while (sp) {
        fm_node n = stack[--sp];
        fm_node ch[3];
        int k = graph_children(&g->nodes[n], ch);
        for (int i = 0; i < k; i++) {
            if (!ch[i] || ch[i] >= count) continue;
            uses[ch[i]]++;
            if (!state[ch[i]]) {
                state[ch[i]] = 1;
                stack[sp++] = ch[i];
            }
        }
    }
    memset(state, 0, count);
    /* Pass 2: post-order. state 1: children pushed; 2: done. */
    sp = 0;
    stack[sp++] = root;
    while (sp && !cc->failed) {
        fm_node n = stack[sp - 1];
        const fm_node_rec *r = &g->nodes[n];
        if (state[n] == 2) {
            sp--;
            continue;
        }
        fm_node ch[3];
        int k = graph_children(r, ch);
        if (state[n] == 0) {
            state[n] = 1;
            for (int i = k - 1; i >= 0; i--) {
                if (!ch[i] || ch[i] >= count) {
                    fail(cc, FM_ERR_INTERNAL, "a node has a missing child");
                    break;
                }
                if (!state[ch[i]]) stack[sp++] = ch[i];
                else if (state[ch[i]] == 1) {
                    fail(cc, FM_ERR_INTERNAL, "the graph has a cycle");
                    break;
                }
            }
            continue;
        }
        sp--;
        state[n] = 2;
        uint32_t id;
        switch ((fm_op)r->op) {
        case FM_OP_CONST: id = mk_const(cc, r->value); break;
        case FM_OP_VAR: id = mk_raw(cc, FM_OP_VAR, r->aux, 0, 0, 0, 0.0); break;
        case FM_OP_PARAM: {
            if (r->aux >= g->param_count) {
                id = fail(cc, FM_ERR_INTERNAL, "parameter node out of range");
                break;
            }
            uint32_t pi = param_index(cc, r->aux);
            id = cc->failed ? 0 : mk_raw(cc, FM_OP_PARAM, pi, 0, 0, 0, 0.0);
            break;
        }
        default:
            if (r->op == FM_OP_VOXELS) {
                uint32_t vch[3] = {map[ch[0]], map[ch[1]], map[ch[2]]};
                id = add_special(cc, r, vch);
            } else if (k > 0) id = mk(cc, (fm_op)r->op, map[ch[0]], k > 1 ? map[ch[1]] : 0,
                               k > 2 ? map[ch[2]] : 0, uses[n]);
            else if (r->op < FM_OP_COUNT) id = add_special(cc, r, NULL);
            else id = fail(cc, FM_ERR_INTERNAL, "unknown op in the graph");
            break;
        }
        map[n] = id;
        if (!cc->failed && uses[n] > cc->cn[id].uses) cc->cn[id].uses = uses[n];
    }
    if (!cc->failed) result = map[root];
done:
    free(map);
    free(uses);
    free(state);
    free(stack);
    return result;
}

/* -------------------------------------------------- arena -> tape -- */

typedef struct emitter {
    compiler *cc;
    uint32_t *vn;     /* arena id -> value number (UINT32_MAX: not yet) */
    fm_insn *insns;
    size_t n, cap;
    uint32_t nleaf;
} emitter;

static uint32_t emit(emitter *e, fm_insn in)
{
    if (e->n >= FM_TAPE_MAX_INSNS)
        return fail(e->cc, FM_ERR_LIMIT, "the tape would exceed its instruction budget"),
               FM_NO_OPERAND;
    if (e->n == e->cap) {
        size_t cap = e->cap ? e->cap * 2 : 64;
        fm_insn *p = realloc(e->insns, cap * sizeof *p);
        if (!p) return fail(e->cc, FM_ERR_LIMIT, "out of memory compiling the tape"), FM_NO_OPERAND;
        e->insns = p;
        e->cap = cap;
    }
    e->insns[e->n] = in;
    return e->nleaf + (uint32_t)e->n++;
}

static fm_insn blank_insn(fm_op op)
{
    fm_insn in;
    memset(&in, 0, sizeof in);
    in.op = (uint8_t)op;
    in.sa = in.sb = in.sc = FM_NO_OPERAND;
    in.a = in.b = in.c = 0;
    return in;
}

/* Value number of an arena node whose operands are already numbered;
 * constants become CONST instructions on first use as a register. */
static uint32_t value_of(emitter *e, uint32_t id)
{
    if (e->vn[id] != UINT32_MAX) return e->vn[id];
    const cnode *r = &e->cc->cn[id];
    uint32_t v;
    if (r->op == FM_OP_CONST) {
        fm_insn in = blank_insn(FM_OP_CONST);
        in.imm = r->value;
        v = emit(e, in);
    } else if (r->op == FM_OP_VAR) {
        v = r->aux;
    } else if (r->op == FM_OP_PARAM) {
        v = FM_AXES + r->aux;
    } else {
        fm_insn in = blank_insn((fm_op)r->op);
        int ar = fm_op_arity((fm_op)r->op);
        if (ar < 0) {
            in.aux = r->aux;
            if (r->op == FM_OP_VOXELS) {
                in.sa = value_of(e, r->a);
                in.sb = value_of(e, r->b);
                in.sc = value_of(e, r->c);
            }
        } else if (ar == 2 && (e->cc->cn[r->a].op == FM_OP_CONST) !=
                                  (e->cc->cn[r->b].op == FM_OP_CONST)) {
            /* One constant operand: an immediate, so that batch loops read
             * no array for it. */
            if (e->cc->cn[r->a].op == FM_OP_CONST) {
                in.imm_mask = FM_IMM_A;
                in.imm = e->cc->cn[r->a].value;
                in.sb = value_of(e, r->b);
            } else {
                in.imm_mask = FM_IMM_B;
                in.imm = e->cc->cn[r->b].value;
                in.sa = value_of(e, r->a);
            }
        } else {
            if (ar >= 1) in.sa = value_of(e, r->a);
            if (ar >= 2) in.sb = value_of(e, r->b);
            if (ar >= 3) in.sc = value_of(e, r->c);
        }
        v = e->cc->failed ? FM_NO_OPERAND : emit(e, in);
    }
    e->vn[id] = v;
    return v;
}

/* Emit in post-order without recursion: children are numbered before the
 * node, so value_of above never recurses more than one level. */
static uint32_t emit_all(emitter *e, uint32_t root)
{
    compiler *cc = e->cc;
    uint32_t *stack = malloc((3 * cc->ncn + 1) * sizeof *stack); /* 3 pushes per node at most */
    uint8_t *state = calloc(cc->ncn, 1);
    uint32_t result = FM_NO_OPERAND;
    if (!stack || !state) {
        fail(cc, FM_ERR_LIMIT, "out of memory compiling the tape");
        goto done;
    }
    size_t sp = 0;
    stack[sp++] = root;
    while (sp && !cc->failed) {
        uint32_t n = stack[sp - 1];
        const cnode *r = &cc->cn[n];
        if (state[n] == 2) {
            sp--;
            continue;
        }
        uint32_t ch[3] = {r->a, r->b, r->c};
        if (state[n] == 0) {
            state[n] = 1;
            for (int i = 2; i >= 0; i--)
                if (ch[i] && !state[ch[i]]) stack[sp++] = ch[i];
            continue;
        }
        sp--;
        state[n] = 2;
        /* Constants are numbered lazily (they may end up as immediates). */
        if (r->op != FM_OP_CONST || n == root) value_of(e, n);
    }
    if (!cc->failed) result = value_of(e, root);
done:
    free(stack);
    free(state);
    return result;
}

/* ------------------------------------------- register allocation -- */

void fm_tape_shared_release(fm_tape_shared *s)
{
    if (!s) return;
    if (atomic_fetch_sub(&s->refs, 1) != 1) return;
    for (size_t i = 0; i < s->nparams; i++) free(s->param_names[i]);
    free(s->param_names);
    for (size_t i = 0; i < s->nspecials; i++) {
        fm_tape_free(s->specials[i].child);
        free(s->specials[i].grid.values);
    }
    free(s->specials);
    free(s);
}

uint32_t fm_tape_assign_slots(fm_insn *insns, size_t ninsns, uint32_t nleaf, uint32_t result_ssa,
                              uint32_t *scratch, uint32_t *result)
{
    size_t nvn = nleaf + ninsns;
    uint32_t *last = scratch, *reg = scratch + nvn, *free_list = scratch + 2 * nvn;
    for (size_t i = 0; i < nvn; i++) last[i] = 0;
    for (size_t i = 0; i < ninsns; i++) {
        const fm_insn *in = &insns[i];
        if (in->sa != FM_NO_OPERAND) last[in->sa] = (uint32_t)i;
        if (in->sb != FM_NO_OPERAND) last[in->sb] = (uint32_t)i;
        if (in->sc != FM_NO_OPERAND) last[in->sc] = (uint32_t)i;
    }
    last[result_ssa] = UINT32_MAX;
    for (uint32_t i = 0; i < nleaf; i++) reg[i] = i;
    uint32_t nregs = nleaf;
    size_t nfree = 0;
    for (size_t i = 0; i < ninsns; i++) {
        fm_insn *in = &insns[i];
        in->a = in->sa != FM_NO_OPERAND ? reg[in->sa] : 0;
        in->b = in->sb != FM_NO_OPERAND ? reg[in->sb] : 0;
        in->c = in->sc != FM_NO_OPERAND ? reg[in->sc] : 0;
        /* The output is taken before the operands are released, so it never
         * aliases an operand and the batch loops can use restrict. */
        uint32_t out = nfree ? free_list[--nfree] : nregs++;
        in->out = out;
        reg[nleaf + i] = out;
        uint32_t ops[3] = {in->sa, in->sb, in->sc};
        for (int k = 0; k < 3; k++) {
            uint32_t v = ops[k];
            if (v == FM_NO_OPERAND || v < nleaf || last[v] != i) continue;
            if ((k >= 1 && ops[0] == v) || (k == 2 && ops[1] == v)) continue;
            free_list[nfree++] = reg[v];
        }
        /* A value nobody reads frees its slot at once. */
        if (last[nleaf + i] == 0 && nleaf + i != result_ssa) free_list[nfree++] = out;
    }
    *result = reg[result_ssa];
    return nregs;
}

fm_tape *fm_tape_from_ssa(fm_tape_shared *shared, const double *param_values, fm_insn *insns,
                          size_t ninsns, uint32_t result_ssa, size_t root_ninsns)
{
    uint32_t nleaf = (uint32_t)(FM_AXES + shared->nparams);
    size_t nvn = nleaf + ninsns;
    fm_tape *t = calloc(1, sizeof *t);
    uint32_t *scratch = NULL;
    size_t scratch_n;
    if (fm_size_mul(nvn ? nvn : 1, 3 * sizeof *scratch, &scratch_n)) scratch = malloc(scratch_n);
    double *pv = malloc((shared->nparams ? shared->nparams : 1) * sizeof *pv);
    if (!t || !scratch || !pv || ninsns > FM_TAPE_MAX_INSNS) {
        free(t);
        free(scratch);
        free(pv);
        free(insns);
        return NULL;
    }
    if (shared->nparams) memcpy(pv, param_values, shared->nparams * sizeof *pv);
    t->nregs = fm_tape_assign_slots(insns, ninsns, nleaf, result_ssa, scratch, &t->result);
    free(scratch);
    t->shared = shared;
    atomic_fetch_add(&shared->refs, 1);
    t->param_values = pv;
    t->nleaf = nleaf;
    t->reg_capacity = t->nregs;
    t->ninsns = ninsns;
    t->insns_cap = ninsns;
    t->insns = insns;
    t->result_ssa = result_ssa;
    t->root_ninsns = root_ninsns > ninsns ? root_ninsns : ninsns;
    return t;
}

/* ------------------------------------------------------ public API -- */

static fm_tape *compile_at_depth(const fm_graph *g, fm_node root, int depth, fm_error *err)
{
    if (!g || root == FM_NONE || root >= g->count) {
        fm_error_set(err, FM_ERR_INPUT, "no function to compile (FM_NONE or a foreign node)");
        return NULL;
    }
    if (g->failed) {
        if (err) *err = g->error;
        return NULL;
    }
    if (depth >= FM_TAPE_MAX_DEPTH) {
        fm_error_set(err, FM_ERR_LIMIT, "special operations nested more than %d deep",
                     FM_TAPE_MAX_DEPTH);
        return NULL;
    }
    compiler cc;
    memset(&cc, 0, sizeof cc);
    cc.g = g;
    cc.err = err;
    cc.depth = depth;
    cc.shared = calloc(1, sizeof *cc.shared);
    cc.param_map = malloc((g->param_count ? g->param_count : 1) * sizeof *cc.param_map);
    fm_tape *tape = NULL;
    emitter e;
    memset(&e, 0, sizeof e);
    if (!cc.shared || !cc.param_map) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory compiling the tape");
        free(cc.shared);
        free(cc.param_map);
        return NULL;
    }
    atomic_init(&cc.shared->refs, 1);
    cc.shared->depth = depth;
    for (size_t i = 0; i < g->param_count; i++) cc.param_map[i] = UINT32_MAX;

    uint32_t root_cn = import_graph(&cc, root);
    if (cc.failed) goto done;
    e.cc = &cc;
    e.nleaf = (uint32_t)(FM_AXES + cc.shared->nparams);
    e.vn = malloc(cc.ncn * sizeof *e.vn);
    if (!e.vn) {
        fail(&cc, FM_ERR_LIMIT, "out of memory compiling the tape");
        goto done;
    }
    for (size_t i = 0; i < cc.ncn; i++) e.vn[i] = UINT32_MAX;
    uint32_t result = emit_all(&e, root_cn);
    if (cc.failed) goto done;
    double *pv = malloc((cc.shared->nparams ? cc.shared->nparams : 1) * sizeof *pv);
    if (!pv) {
        fail(&cc, FM_ERR_LIMIT, "out of memory compiling the tape");
        goto done;
    }
    for (uint32_t graph_i = 0; graph_i < g->param_count; graph_i++)
        if (cc.param_map[graph_i] != UINT32_MAX) pv[cc.param_map[graph_i]] = g->param_values[graph_i];
    tape = fm_tape_from_ssa(cc.shared, pv, e.insns, e.n, result, e.n);
    e.insns = NULL;
    free(pv);
    if (!tape) fail(&cc, FM_ERR_LIMIT, "out of memory compiling the tape");
done:
    free(e.insns);
    free(e.vn);
    free(cc.cn);
    free(cc.table);
    free(cc.param_map);
    fm_tape_shared_release(cc.shared); /* the tape holds its own reference */
    return tape;
}

fm_tape *fm_tape_compile(const fm_graph *g, fm_node root, fm_error *err)
{
    return compile_at_depth(g, root, 0, err);
}

void fm_tape_free(fm_tape *tape)
{
    if (!tape) return;
    fm_tape_shared_release(tape->shared);
    free(tape->param_values);
    free(tape->insns);
    free(tape);
}

size_t fm_tape_length(const fm_tape *tape)
{
    return tape ? tape->ninsns : 0;
}

fm_status fm_tape_set_param(fm_tape *tape, const char *name, double value)
{
    if (!tape || !name) return FM_ERR_INPUT;
    fm_status st = FM_ERR_INPUT;
    const fm_tape_shared *s = tape->shared;
    for (size_t i = 0; i < s->nparams; i++)
        if (!strcmp(s->param_names[i], name)) {
            tape->param_values[i] = value;
            st = FM_OK;
        }
    /* Sub-tapes of special ops read their own copies. */
    for (size_t i = 0; i < s->nspecials; i++)
        if (s->specials[i].child && fm_tape_set_param(s->specials[i].child, name, value) == FM_OK)
            st = FM_OK;
    return st;
}
