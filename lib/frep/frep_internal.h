/* frep_internal.h: the node record, the graph arena and the scalar
 * semantics of every op, shared by the builders, the tape compiler and the
 * evaluators of lib/frep. Not part of the public API. */
#ifndef FM_FREP_INTERNAL_H
#define FM_FREP_INTERNAL_H

#include <math.h>

#include "frep/frep.h"

/* Dependency bits of a node: bit i set if it depends on coordinate i;
 * FM_DEP_PARAM if it depends on a parameter (so it cannot be folded). */
#define FM_DEP_PARAM 0x10u

typedef struct fm_node_rec {
    uint8_t op;
    uint8_t deps;
    uint32_t aux;   /* VAR: axis; PARAM: parameter index; PROJECT: axis; VOXELS: grid index */
    fm_node a, b, c;
    double value;   /* CONST: value; PROJECT: lo; BALL_MAX, NORMAL_OFFSET: distance d */
    double value2;  /* PROJECT: hi */
} fm_node_rec;

typedef struct fm_voxel_grid {
    double lo[3], hi[3];
    size_t n[3];
    float *values; /* n[0] * n[1] * n[2], x fastest */
} fm_voxel_grid;

struct fm_graph {
    fm_node_rec *nodes; /* nodes[0] is the unused FM_NONE record */
    size_t count, capacity, max_nodes;
    uint32_t *table; /* open-addressing hash of node ids for deduplication */
    size_t table_size;
    int failed;
    fm_error error;
    char **param_names;
    double *param_values;
    size_t param_count;
    fm_voxel_grid *grids;
    size_t grid_count;
};

/* Record the first error; later ones are dropped. Returns FM_NONE. */
fm_node fm_graph_fail(fm_graph *g, fm_status code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Find or add a node (deduplicated); no folding. */
fm_node fm_graph_intern(fm_graph *g, const fm_node_rec *rec);

static inline const fm_node_rec *fm_rec(const fm_graph *g, fm_node n)
{
    return &g->nodes[n];
}

static inline int fm_op_arity(fm_op op)
{
    if (op <= FM_OP_PARAM) return 0;
    if (op <= FM_OP_NOT) return 1;
    if (op <= FM_OP_OR) return 2;
    if (op == FM_OP_SELECT) return 3;
    return -1; /* special */
}

static inline int fm_op_commutative(fm_op op)
{
    return op == FM_OP_ADD || op == FM_OP_MUL || op == FM_OP_MIN || op == FM_OP_MAX ||
           op == FM_OP_EQ || op == FM_OP_NE || op == FM_OP_AND || op == FM_OP_OR;
}

/* The scalar meaning of each op, used by constant folding and by every point
 * evaluator so that they agree bit for bit. */
static inline double fm_apply_unary(fm_op op, double a)
{
    switch (op) {
    case FM_OP_NEG: return -a;
    case FM_OP_ABS: return fabs(a);
    case FM_OP_SQRT: return sqrt(a);
    case FM_OP_SQUARE: return a * a;
    case FM_OP_EXP: return exp(a);
    case FM_OP_LOG: return log(a);
    case FM_OP_SIN: return sin(a);
    case FM_OP_COS: return cos(a);
    case FM_OP_TAN: return tan(a);
    case FM_OP_ASIN: return asin(a);
    case FM_OP_ACOS: return acos(a);
    case FM_OP_ATAN: return atan(a);
    case FM_OP_SINH: return sinh(a);
    case FM_OP_COSH: return cosh(a);
    case FM_OP_TANH: return tanh(a);
    case FM_OP_FLOOR: return floor(a);
    case FM_OP_CEIL: return ceil(a);
    case FM_OP_TRUNC: return trunc(a);
    case FM_OP_SIGN: return (a > 0) - (a < 0);
    case FM_OP_NOT: return a == 0.0 ? 1.0 : 0.0;
    default: return NAN;
    }
}

static inline double fm_apply_binary(fm_op op, double a, double b)
{
    switch (op) {
    case FM_OP_ADD: return a + b;
    case FM_OP_SUB: return a - b;
    case FM_OP_MUL: return a * b;
    case FM_OP_DIV: return a / b;
    case FM_OP_MIN: return a < b ? a : b;
    case FM_OP_MAX: return a > b ? a : b;
    case FM_OP_POW: return pow(a, b);
    case FM_OP_ATAN2: return atan2(a, b);
    case FM_OP_MOD: return fmod(a, b);
    case FM_OP_LT: return a < b ? 1.0 : 0.0;
    case FM_OP_LE: return a <= b ? 1.0 : 0.0;
    case FM_OP_EQ: return a == b ? 1.0 : 0.0;
    case FM_OP_NE: return a != b ? 1.0 : 0.0;
    case FM_OP_AND: return (a != 0.0 && b != 0.0) ? 1.0 : 0.0;
    case FM_OP_OR: return (a != 0.0 || b != 0.0) ? 1.0 : 0.0;
    default: return NAN;
    }
}

/* Reference evaluator: a direct recursive walk of the DAG with
 * memoization, slow and simple, used by tests to check the tape evaluators
 * and by builders that need a value at build time. Special ops are
 * evaluated by fm_reference_special (defined with the evaluators). */
double fm_graph_eval_reference(const fm_graph *g, fm_node root, const double p[4]);

/* Trilinear sample of a voxel grid (with the outside rule of fm_voxels). */
double fm_voxel_sample(const fm_voxel_grid *grid, double x, double y, double z);

#endif
