/* graph.c: the node arena of lib/frep. Nodes are interned in a hash table so
 * that building the same subexpression twice yields the same node, constant
 * subexpressions are folded as they are built, and the first error met is
 * kept in the graph (builders then return FM_NONE). Also the slow reference
 * evaluator that tests compare the tape evaluators with. */
#include "frep/frep_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FM_DEFAULT_MAX_NODES 1000000u

fm_graph *fm_graph_new(size_t max_nodes)
{
    fm_graph *g = calloc(1, sizeof *g);
    if (!g) return NULL;
    g->max_nodes = max_nodes ? max_nodes : FM_DEFAULT_MAX_NODES;
    if (g->max_nodes > UINT32_MAX / 4) g->max_nodes = UINT32_MAX / 4;
    g->capacity = 64;
    g->nodes = calloc(g->capacity, sizeof *g->nodes);
    g->table_size = 128;
    g->table = calloc(g->table_size, sizeof *g->table);
    if (!g->nodes || !g->table) {
        fm_graph_free(g);
        return NULL;
    }
    g->count = 1; /* FM_NONE */
    return g;
}

void fm_graph_free(fm_graph *g)
{
    if (!g) return;
    for (size_t i = 0; i < g->param_count; i++) free(g->param_names[i]);
    free(g->param_names);
    free(g->param_values);
    for (size_t i = 0; i < g->grid_count; i++) free(g->grids[i].values);
    free(g->grids);
    free(g->nodes);
    free(g->table);
    free(g);
}

const fm_error *fm_graph_error(const fm_graph *g)
{
    return g && g->failed ? &g->error : NULL;
}

size_t fm_graph_node_count(const fm_graph *g)
{
    return g ? g->count - 1 : 0;
}

fm_node fm_graph_fail(fm_graph *g, fm_status code, const char *fmt, ...)
{
    if (g && !g->failed) {
        va_list ap;
        va_start(ap, fmt);
        g->failed = 1;
        g->error.code = code;
        vsnprintf(g->error.message, sizeof g->error.message, fmt, ap);
        va_end(ap);
    }
    return FM_NONE;
}

static uint64_t hash_rec(const fm_node_rec *r)
{
    uint64_t h = 1469598103934665603ULL;
    uint64_t words[6];
    words[0] = (uint64_t)r->op | ((uint64_t)r->aux << 8);
    words[1] = r->a;
    words[2] = ((uint64_t)r->b << 32) | r->c;
    memcpy(&words[3], &r->value, 8);
    memcpy(&words[4], &r->value2, 8);
    words[5] = 0;
    for (int i = 0; i < 5; i++) {
        h ^= words[i];
        h *= 1099511628211ULL;
        h ^= h >> 29;
    }
    return h;
}

static int same_rec(const fm_node_rec *x, const fm_node_rec *y)
{
    /* Values are compared bitwise so that -0.0 and 0.0, or two NaNs, are
     * told apart exactly as the hash does. */
    return x->op == y->op && x->aux == y->aux && x->a == y->a && x->b == y->b &&
           x->c == y->c && memcmp(&x->value, &y->value, sizeof x->value) == 0 &&
           memcmp(&x->value2, &y->value2, sizeof x->value2) == 0;
}

static int grow_table(fm_graph *g)
{
    size_t size = g->table_size * 2;
    uint32_t *table = calloc(size, sizeof *table);
    if (!table) return 0;
    for (size_t i = 1; i < g->count; i++) {
        size_t slot = hash_rec(&g->nodes[i]) & (size - 1);
        while (table[slot]) slot = (slot + 1) & (size - 1);
        table[slot] = (uint32_t)i;
    }
    free(g->table);
    g->table = table;
    g->table_size = size;
    return 1;
}

static uint8_t deps_of(const fm_graph *g, const fm_node_rec *r)
{
    uint8_t d = 0;
    if (r->op == FM_OP_VAR) return (uint8_t)(1u << r->aux);
    if (r->op == FM_OP_PARAM) return FM_DEP_PARAM;
    /* A voxel grid samples at its children (the x, y, z expressions, so
     * that a grid can be moved); a bare grid samples at x, y, z. */
    if (r->op == FM_OP_VOXELS && !r->a) return 0x7;
    if (r->a) d |= g->nodes[r->a].deps;
    if (r->b) d |= g->nodes[r->b].deps;
    if (r->c) d |= g->nodes[r->c].deps;
    if (r->op == FM_OP_PROJECT) d &= (uint8_t)~(1u << r->aux);
    return d;
}

fm_node fm_graph_intern(fm_graph *g, const fm_node_rec *rec)
{
    if (!g || g->failed) return FM_NONE;
    size_t mask = g->table_size - 1;
    size_t slot = hash_rec(rec) & mask;
    while (g->table[slot]) {
        if (same_rec(&g->nodes[g->table[slot]], rec)) return g->table[slot];
        slot = (slot + 1) & mask;
    }
    if (g->count - 1 >= g->max_nodes)
        return fm_graph_fail(g, FM_ERR_LIMIT,
                             "the model needs more than %zu nodes (the node budget)",
                             g->max_nodes);
    if (g->count == g->capacity) {
        size_t cap = g->capacity * 2;
        fm_node_rec *nodes = realloc(g->nodes, cap * sizeof *nodes);
        if (!nodes) return fm_graph_fail(g, FM_ERR_LIMIT, "out of memory building the model");
        g->nodes = nodes;
        g->capacity = cap;
    }
    fm_node id = (fm_node)g->count++;
    g->nodes[id] = *rec;
    g->nodes[id].deps = deps_of(g, rec);
    g->table[slot] = id;
    if (g->count * 2 > g->table_size && !grow_table(g))
        return fm_graph_fail(g, FM_ERR_LIMIT, "out of memory building the model");
    return id;
}

/* ------------------------------------------------------------ leaves -- */

fm_node fm_const(fm_graph *g, double value)
{
    fm_node_rec r = {0};
    r.op = FM_OP_CONST;
    r.value = value == 0.0 ? 0.0 : value; /* one zero */
    return fm_graph_intern(g, &r);
}

fm_node fm_var(fm_graph *g, int axis)
{
    if (axis < 0 || axis >= FM_AXES)
        return fm_graph_fail(g, FM_ERR_INPUT, "coordinate index %d is not 0..3", axis);
    fm_node_rec r = {0};
    r.op = FM_OP_VAR;
    r.aux = (uint32_t)axis;
    return fm_graph_intern(g, &r);
}

static long find_param(const fm_graph *g, const char *name)
{
    for (size_t i = 0; i < g->param_count; i++)
        if (!strcmp(g->param_names[i], name)) return (long)i;
    return -1;
}

fm_node fm_param(fm_graph *g, const char *name, double value)
{
    if (!g || g->failed) return FM_NONE;
    if (!name || !*name) return fm_graph_fail(g, FM_ERR_INPUT, "a parameter needs a name");
    long i = find_param(g, name);
    if (i < 0) {
        size_t n = g->param_count + 1;
        char **names = realloc(g->param_names, n * sizeof *names);
        if (!names) return fm_graph_fail(g, FM_ERR_LIMIT, "out of memory");
        g->param_names = names;
        double *values = realloc(g->param_values, n * sizeof *values);
        if (!values) return fm_graph_fail(g, FM_ERR_LIMIT, "out of memory");
        g->param_values = values;
        char *copy = malloc(strlen(name) + 1);
        if (!copy) return fm_graph_fail(g, FM_ERR_LIMIT, "out of memory");
        strcpy(copy, name);
        i = (long)g->param_count;
        g->param_names[i] = copy;
        g->param_count = n;
    }
    g->param_values[i] = value;
    fm_node_rec r = {0};
    r.op = FM_OP_PARAM;
    r.aux = (uint32_t)i;
    return fm_graph_intern(g, &r);
}

fm_status fm_graph_set_param(fm_graph *g, const char *name, double value)
{
    long i = g && name ? find_param(g, name) : -1;
    if (i < 0) return FM_ERR_INPUT;
    g->param_values[i] = value;
    return FM_OK;
}

/* ---------------------------------------------------------- inspection -- */

static int valid(const fm_graph *g, fm_node n)
{
    return g && n != FM_NONE && n < g->count;
}

fm_op fm_node_op(const fm_graph *g, fm_node n)
{
    return valid(g, n) ? (fm_op)g->nodes[n].op : FM_OP_COUNT;
}

fm_node fm_node_child(const fm_graph *g, fm_node n, int i)
{
    if (!valid(g, n)) return FM_NONE;
    const fm_node_rec *r = &g->nodes[n];
    return i == 0 ? r->a : i == 1 ? r->b : i == 2 ? r->c : FM_NONE;
}

double fm_node_value(const fm_graph *g, fm_node n)
{
    if (!valid(g, n)) return NAN;
    const fm_node_rec *r = &g->nodes[n];
    if (r->op == FM_OP_VAR) return r->aux;
    if (r->op == FM_OP_PARAM) return g->param_values[r->aux];
    return r->value;
}

int fm_node_is_const(const fm_graph *g, fm_node n, double *value)
{
    if (!valid(g, n) || g->nodes[n].op != FM_OP_CONST) return 0;
    if (value) *value = g->nodes[n].value;
    return 1;
}

int fm_node_depends_on(const fm_graph *g, fm_node n, int axis)
{
    if (!valid(g, n) || axis < 0 || axis >= FM_AXES) return 0;
    return (g->nodes[n].deps >> axis) & 1u;
}

/* ------------------------------------------------------ arithmetic -- */

static int is_const(const fm_graph *g, fm_node n, double v)
{
    return g->nodes[n].op == FM_OP_CONST && g->nodes[n].value == v;
}

fm_node fm_unary(fm_graph *g, fm_op op, fm_node a)
{
    if (!g || g->failed || a == FM_NONE) return FM_NONE;
    if (fm_op_arity(op) != 1) return fm_graph_fail(g, FM_ERR_INTERNAL, "op %d is not unary", op);
    const fm_node_rec *ra = &g->nodes[a];
    if (ra->op == FM_OP_CONST) return fm_const(g, fm_apply_unary(op, ra->value));
    if (op == FM_OP_NEG && ra->op == FM_OP_NEG) return ra->a;
    if (op == FM_OP_ABS && (ra->op == FM_OP_ABS || ra->op == FM_OP_SQUARE)) return a;
    fm_node_rec r = {0};
    r.op = (uint8_t)op;
    r.a = a;
    return fm_graph_intern(g, &r);
}

fm_node fm_binary(fm_graph *g, fm_op op, fm_node a, fm_node b)
{
    if (!g || g->failed || a == FM_NONE || b == FM_NONE) return FM_NONE;
    if (fm_op_arity(op) != 2)
        return fm_graph_fail(g, FM_ERR_INTERNAL, "op %d is not binary", op);
    const fm_node_rec *ra = &g->nodes[a], *rb = &g->nodes[b];
    if (ra->op == FM_OP_CONST && rb->op == FM_OP_CONST)
        return fm_const(g, fm_apply_binary(op, ra->value, rb->value));
    switch (op) {
    case FM_OP_ADD:
        if (is_const(g, a, 0.0)) return b;
        if (is_const(g, b, 0.0)) return a;
        if (rb->op == FM_OP_NEG) return fm_binary(g, FM_OP_SUB, a, rb->a);
        break;
    case FM_OP_SUB:
        if (is_const(g, b, 0.0)) return a;
        if (is_const(g, a, 0.0)) return fm_unary(g, FM_OP_NEG, b);
        break;
    case FM_OP_MUL:
        if (is_const(g, a, 1.0)) return b;
        if (is_const(g, b, 1.0)) return a;
        if (is_const(g, a, -1.0)) return fm_unary(g, FM_OP_NEG, b);
        if (is_const(g, b, -1.0)) return fm_unary(g, FM_OP_NEG, a);
        if (a == b) return fm_unary(g, FM_OP_SQUARE, a);
        break;
    case FM_OP_DIV:
        if (is_const(g, b, 1.0)) return a;
        break;
    case FM_OP_MIN:
    case FM_OP_MAX:
        if (a == b) return a;
        break;
    case FM_OP_POW:
        if (is_const(g, b, 1.0)) return a;
        if (is_const(g, b, 2.0)) return fm_unary(g, FM_OP_SQUARE, a);
        if (is_const(g, b, 0.5)) return fm_unary(g, FM_OP_SQRT, a);
        break;
    default:
        break;
    }
    if (fm_op_commutative(op) && a > b) {
        fm_node tmp = a;
        a = b;
        b = tmp;
    }
    fm_node_rec r = {0};
    r.op = (uint8_t)op;
    r.a = a;
    r.b = b;
    return fm_graph_intern(g, &r);
}

fm_node fm_select(fm_graph *g, fm_node cond, fm_node if_true, fm_node if_false)
{
    if (!g || g->failed || !cond || !if_true || !if_false) return FM_NONE;
    double c;
    if (fm_node_is_const(g, cond, &c)) return c != 0.0 ? if_true : if_false;
    if (if_true == if_false) return if_true;
    fm_node_rec r = {0};
    r.op = FM_OP_SELECT;
    r.a = cond;
    r.b = if_true;
    r.c = if_false;
    return fm_graph_intern(g, &r);
}

fm_node fm_add(fm_graph *g, fm_node a, fm_node b) { return fm_binary(g, FM_OP_ADD, a, b); }
fm_node fm_sub(fm_graph *g, fm_node a, fm_node b) { return fm_binary(g, FM_OP_SUB, a, b); }
fm_node fm_mul(fm_graph *g, fm_node a, fm_node b) { return fm_binary(g, FM_OP_MUL, a, b); }
fm_node fm_div(fm_graph *g, fm_node a, fm_node b) { return fm_binary(g, FM_OP_DIV, a, b); }
fm_node fm_min(fm_graph *g, fm_node a, fm_node b) { return fm_binary(g, FM_OP_MIN, a, b); }
fm_node fm_max(fm_graph *g, fm_node a, fm_node b) { return fm_binary(g, FM_OP_MAX, a, b); }
fm_node fm_neg(fm_graph *g, fm_node a) { return fm_unary(g, FM_OP_NEG, a); }
fm_node fm_sqrt(fm_graph *g, fm_node a) { return fm_unary(g, FM_OP_SQRT, a); }
fm_node fm_square(fm_graph *g, fm_node a) { return fm_unary(g, FM_OP_SQUARE, a); }
fm_node fm_abs(fm_graph *g, fm_node a) { return fm_unary(g, FM_OP_ABS, a); }

/* ---------------------------------------------- reference evaluator -- */

typedef struct ref_state {
    const fm_graph *g;
    double *value;
    unsigned char *done;
    double p[4];
} ref_state;

double fm_reference_special(const fm_graph *g, fm_node n, const double p[4]);

static double ref_eval(ref_state *s, fm_node n)
{
    if (s->done[n]) return s->value[n];
    const fm_node_rec *r = &s->g->nodes[n];
    double v;
    switch (fm_op_arity((fm_op)r->op)) {
    case 0:
        v = r->op == FM_OP_CONST ? r->value
            : r->op == FM_OP_VAR ? s->p[r->aux]
                                 : s->g->param_values[r->aux];
        break;
    case 1: v = fm_apply_unary((fm_op)r->op, ref_eval(s, r->a)); break;
    case 2: v = fm_apply_binary((fm_op)r->op, ref_eval(s, r->a), ref_eval(s, r->b)); break;
    case 3: v = ref_eval(s, r->a) != 0.0 ? ref_eval(s, r->b) : ref_eval(s, r->c); break;
    default: v = fm_reference_special(s->g, n, s->p); break;
    }
    s->value[n] = v;
    s->done[n] = 1;
    return v;
}

double fm_graph_eval_reference(const fm_graph *g, fm_node root, const double p[4])
{
    if (!valid(g, root)) return NAN;
    ref_state s;
    s.g = g;
    s.value = malloc(g->count * sizeof *s.value);
    s.done = calloc(g->count, 1);
    if (!s.value || !s.done) {
        free(s.value);
        free(s.done);
        return NAN;
    }
    memcpy(s.p, p, sizeof s.p);
    double v = ref_eval(&s, root);
    free(s.value);
    free(s.done);
    return v;
}
