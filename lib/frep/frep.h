/* frep.h: the F-rep kernel. An object is f(x, y, z, t) >= 0, positive
 * inside (Pasko et al. 1995, eq. 1). Functions are built as a DAG of nodes
 * in an fm_graph (an arena: nodes live until the graph is freed, identical
 * subexpressions are stored once), compiled to a flat tape, and evaluated on
 * points, batches of points, boxes (interval arithmetic) and with gradients.
 *
 * Building never fails loudly: a builder given FM_NONE, or one that hits an
 * error (node budget, bad argument), returns FM_NONE and records the first
 * error in the graph (fm_graph_error). So a whole expression can be built
 * and checked once at the end.
 *
 * Thread safety: a graph is built by one thread. A compiled tape is
 * immutable and may be shared; each thread evaluates it through its own
 * fm_evaluator (the scratch registers). */
#ifndef FM_FREP_H
#define FM_FREP_H

#include <stddef.h>
#include <stdint.h>

#include "core/core.h"

/* ---------------------------------------------------------------- graph -- */

typedef struct fm_graph fm_graph;
typedef uint32_t fm_node;
#define FM_NONE ((fm_node)0)

enum { FM_X = 0, FM_Y = 1, FM_Z = 2, FM_T = 3, FM_AXES = 4 };

typedef enum fm_op {
    /* leaves */
    FM_OP_CONST,
    FM_OP_VAR,   /* coordinate x, y, z or t */
    FM_OP_PARAM, /* named scalar, changeable on a compiled tape */
    /* unary */
    FM_OP_NEG, FM_OP_ABS, FM_OP_SQRT, FM_OP_SQUARE, FM_OP_EXP, FM_OP_LOG,
    FM_OP_SIN, FM_OP_COS, FM_OP_TAN, FM_OP_ASIN, FM_OP_ACOS, FM_OP_ATAN,
    FM_OP_SINH, FM_OP_COSH, FM_OP_TANH, FM_OP_FLOOR, FM_OP_CEIL, FM_OP_TRUNC,
    FM_OP_SIGN,
    FM_OP_NOT, /* 1 if a == 0 else 0 */
    /* binary */
    FM_OP_ADD, FM_OP_SUB, FM_OP_MUL, FM_OP_DIV, FM_OP_MIN, FM_OP_MAX,
    FM_OP_POW,   /* a^b; for non-integer b defined for a >= 0 only (NaN otherwise) */
    FM_OP_ATAN2, /* atan2(a, b) = angle of (b, a) */
    FM_OP_MOD,   /* fmod(a, b) */
    FM_OP_LT, FM_OP_LE, FM_OP_EQ, FM_OP_NE, /* 1 or 0 */
    FM_OP_AND, FM_OP_OR,                    /* logical, on 0 / non-0 */
    /* ternary */
    FM_OP_SELECT, /* a != 0 ? b : c (HyperFun if-then-else on a point) */
    /* operations that need a search or data at evaluation time */
    FM_OP_PROJECT,       /* max of child over one coordinate in [lo, hi] (eq. 12) */
    FM_OP_BALL_MAX,      /* constant-radius offset: max (D > 0) or min (D < 0) of child over the sphere |X'-X| = |D| */
    FM_OP_NORMAL_OFFSET, /* f(X + D grad f / |grad f|) */
    FM_OP_NORMALIZE,     /* f / sqrt(f^2 + |grad f|^2)  (Shapiro eq. 4.9) */
    FM_OP_VOXELS,        /* trilinear interpolation of a voxel grid */
    FM_OP_COUNT
} fm_op;

/* A graph that holds at most max_nodes nodes (0: a default of 1,000,000). */
fm_graph *fm_graph_new(size_t max_nodes);
void fm_graph_free(fm_graph *g);
/* The first error met while building, or NULL. */
const fm_error *fm_graph_error(const fm_graph *g);
size_t fm_graph_node_count(const fm_graph *g);

/* Inspection, for compilers and printers. */
fm_op fm_node_op(const fm_graph *g, fm_node n);
/* Children (FM_NONE where absent). */
fm_node fm_node_child(const fm_graph *g, fm_node n, int i);
/* Constant value; coordinate index for VAR; current value for PARAM. */
double fm_node_value(const fm_graph *g, fm_node n);
int fm_node_is_const(const fm_graph *g, fm_node n, double *value);
/* Does n depend on coordinate axis (FM_X..FM_T)? */
int fm_node_depends_on(const fm_graph *g, fm_node n, int axis);

/* ----------------------------------------------------- basic building -- */

fm_node fm_const(fm_graph *g, double value);
fm_node fm_var(fm_graph *g, int axis); /* FM_X .. FM_T */
/* A named parameter: the same name gives the same node; value is its
 * initial value (the last one given wins). */
fm_node fm_param(fm_graph *g, const char *name, double value);
fm_status fm_graph_set_param(fm_graph *g, const char *name, double value);

/* Generic builders (constant folding happens here: an op on constants is a
 * constant; x + 0, x * 1, x * -1, --x, min(a, a), max(a, a) simplify; x * 0
 * is kept, since x may be infinite or NaN at some points). */
fm_node fm_unary(fm_graph *g, fm_op op, fm_node a);
fm_node fm_binary(fm_graph *g, fm_op op, fm_node a, fm_node b);
fm_node fm_select(fm_graph *g, fm_node cond, fm_node if_true, fm_node if_false);

/* Shorthands. */
fm_node fm_add(fm_graph *g, fm_node a, fm_node b);
fm_node fm_sub(fm_graph *g, fm_node a, fm_node b);
fm_node fm_mul(fm_graph *g, fm_node a, fm_node b);
fm_node fm_div(fm_graph *g, fm_node a, fm_node b);
fm_node fm_neg(fm_graph *g, fm_node a);
fm_node fm_min(fm_graph *g, fm_node a, fm_node b);
fm_node fm_max(fm_graph *g, fm_node a, fm_node b);
fm_node fm_sqrt(fm_graph *g, fm_node a);
fm_node fm_square(fm_graph *g, fm_node a);
fm_node fm_abs(fm_graph *g, fm_node a);

/* --------------------------------------------- set operations (sec. 2.2) -- */

/* R_alpha system (Pasko eq. 2): (f1 + f2 +- sqrt(f1^2 + f2^2 - 2 alpha f1 f2)) / (1 + alpha),
 * -1 < alpha <= 1. alpha = 1 gives max / min exactly (built as MAX / MIN
 * nodes), alpha = 0 gives R_0 (eq. 4). */
fm_node fm_r_union(fm_graph *g, fm_node f1, fm_node f2, double alpha);
fm_node fm_r_inter(fm_graph *g, fm_node f1, fm_node f2, double alpha);
/* R_0^m (eq. 5): (f1 + f2 +- sqrt(f1^2 + f2^2)) (f1^2 + f2^2)^(m/2), m >= 0. */
fm_node fm_r_union_m(fm_graph *g, fm_node f1, fm_node f2, int m);
fm_node fm_r_inter_m(fm_graph *g, fm_node f1, fm_node f2, int m);
/* R_p (Shapiro eq. 3.6): f1 + f2 +- (|f1|^p + |f2|^p)^(1/p), p > 1
 * (p = 2 equals R_0; p = 1 would make the union all of space). */
fm_node fm_rp_union(fm_graph *g, fm_node f1, fm_node f2, double p);
fm_node fm_rp_inter(fm_graph *g, fm_node f1, fm_node f2, double p);
fm_node fm_complement(fm_graph *g, fm_node f);
/* f1 \ f2 = f1 & -f2 with the R_alpha system. */
fm_node fm_r_subtract(fm_graph *g, fm_node f1, fm_node f2, double alpha);

/* ---------------------------------------------------------- blends -- */

/* Displacement blends (Pasko eq. 6-8): R_0(f1, f2) + a0 / (1 + (f1/a1)^2 + (f2/a2)^2).
 * a0 > 0 adds material, a0 < 0 removes it. */
fm_node fm_blend_union(fm_graph *g, fm_node f1, fm_node f2, double a0, double a1, double a2);
fm_node fm_blend_inter(fm_graph *g, fm_node f1, fm_node f2, double a0, double a1, double a2);
/* The same with a0, a1, a2 given as expressions (parameters, or values a
 * language computes); a constant a1 or a2 of 0, or a non-finite constant,
 * is refused. */
fm_node fm_blend_union_expr(fm_graph *g, fm_node f1, fm_node f2, fm_node a0, fm_node a1, fm_node a2);
fm_node fm_blend_inter_expr(fm_graph *g, fm_node f1, fm_node f2, fm_node a0, fm_node a1, fm_node a2);
/* rho-blending (Shapiro eq. 6.2): x1 + x2 + s sqrt(x1^2 + x2^2 + s_rho (s_rho - |s_rho|) / (8 rho^2)),
 * s_rho = x1^2 + x2^2 - rho^2; s = +1 union, -1 intersection. */
fm_node fm_rho_blend_union(fm_graph *g, fm_node f1, fm_node f2, double rho);
fm_node fm_rho_blend_inter(fm_graph *g, fm_node f1, fm_node f2, double rho);
/* Hyperbolic blending (Hasan sec. 5.2): union max(f, g, a^2 - f g),
 * intersection min(f, g, f g - a^2). */
fm_node fm_hyperbolic_blend_union(fm_graph *g, fm_node f1, fm_node f2, double a);
fm_node fm_hyperbolic_blend_inter(fm_graph *g, fm_node f1, fm_node f2, double a);
/* L_p approximate union / intersection of n functions (Akleman sec. 3):
 * union (sum f_i^-p)^(-1/p) and intersection (sum f_i^p)^(1/p) as the paper
 * writes them for positive f_i; here extended to signed f by the R_p forms so
 * that the zero set is kept: see docs/frep.md. n >= 1, p > 1. */
fm_node fm_lp_union(fm_graph *g, const fm_node *f, size_t n, double p);
fm_node fm_lp_inter(fm_graph *g, const fm_node *f, size_t n, double p);

/* --------------------------------------------------------- offsets -- */

fm_node fm_offset_iso(fm_graph *g, fm_node f, double c);          /* f + c */
fm_node fm_offset_normal(fm_graph *g, fm_node f, double d);       /* f(X + d N) */
fm_node fm_offset_radius(fm_graph *g, fm_node f, double d);       /* BALL_MAX */

/* -------------------------------------------------------- mappings -- */

/* f with coordinate i replaced by map[i] (FM_NONE keeps it): the bijective
 * mapping of eq. 9 when map is the inverse map. */
fm_node fm_remap(fm_graph *g, fm_node f, const fm_node map[FM_AXES]);
/* Affine map of a 3D object: m is the 4x4 row-major matrix that moves the
 * object (X' = M X); f is evaluated at M^-1 X'. Singular M is an error. */
fm_node fm_affine(fm_graph *g, fm_node f, const double m[16]);
/* Time-dependent affine map: m[12] is the 3x4 row-major matrix [A | c] whose
 * entries are expressions (usually of t); the object is moved by X' = A X + c
 * and f is evaluated at A^-1 (X' - c), inverted symbolically. */
fm_node fm_affine_t(fm_graph *g, fm_node f, const fm_node m[12]);
/* The inverse maps behind fm_affine_t and fm_rotate / fm_twist applied to
 * coordinate expressions instead of an object, for languages that transform
 * the point before they build the object (lib/hf): p[0..2] are the x, y, z
 * expressions of the point and are replaced by those of the point the
 * motion brings there. fm_affine_t_coords: p = A^-1 (p - c), m as for
 * fm_affine_t. fm_rotate_coords: the inverse rotation about `axis` by the
 * angle expression theta, which may depend on p[axis] (a twist). Return 1,
 * or 0 with a graph error (p is then unchanged). */
int fm_affine_t_coords(fm_graph *g, fm_node p[3], const fm_node m[12]);
int fm_rotate_coords(fm_graph *g, fm_node p[3], int axis, fm_node theta);
fm_node fm_translate(fm_graph *g, fm_node f, double dx, double dy, double dz);
/* Rotation about a coordinate axis by angle (radians), right-handed. */
fm_node fm_rotate(fm_graph *g, fm_node f, int axis, double angle);
/* Twist about axis: rotation by rate * (coordinate along axis)
 * (fm_rotate_coords with theta = rate * p[axis]). */
fm_node fm_twist(fm_graph *g, fm_node f, int axis, double rate);
/* Taper along axis: scale of the other two coordinates by
 * 1 + rate * (coordinate along axis), evaluated by its inverse. */
fm_node fm_taper(fm_graph *g, fm_node f, int axis, double rate);
/* Bend of the axis-aligned object about `about` (bends coordinate `along`
 * into arcs of curvature k, Barr's bend with no limits). */
fm_node fm_bend(fm_graph *g, fm_node f, int along, int about, double k);

/* ----------------------------------------- dimension operations (sec. 2.2) -- */

/* Cartesian product (eq. 13): f1 over coordinates 0..n1-1 and f2 over the
 * following ones (f2's coordinate i becomes coordinate n1 + i), joined with
 * R_alpha intersection. */
fm_node fm_product(fm_graph *g, fm_node f1, int n1, fm_node f2, double alpha);
/* Time segment (eq. 14): (t - t0) & (t1 - t) with min (R_1). */
fm_node fm_time_segment(fm_graph *g, double t0, double t1);
/* Metamorphosis (eq. 15): f1 (1 - s(t)) + f2 s(t), s(t) = clamp((t - t0) / (t1 - t0), 0, 1). */
fm_node fm_metamorph(fm_graph *g, fm_node f1, fm_node f2, double t0, double t1);
/* Projection (eq. 12): max over coordinate `axis` in [lo, hi] of f. The
 * result does not depend on that coordinate. Computed exactly to the
 * tolerance FM_PROJECT_TOL by interval branch-and-bound plus local search. */
fm_node fm_project(fm_graph *g, fm_node f, int axis, double lo, double hi);
#define FM_PROJECT_TOL 1e-9
/* Normalization to first order (Shapiro eq. 4.9). */
fm_node fm_normalize(fm_graph *g, fm_node f);

/* ------------------------------------------------------ primitives -- */
/* Each is positive inside and at least first-order normalized (exact
 * Euclidean distance where a closed form exists, as documented). */

/* Half-space n . X <= d (n need not be unit; it is normalized): d - n.X. */
fm_node fm_halfspace(fm_graph *g, const double n[3], double d);
fm_node fm_sphere(fm_graph *g, const double c[3], double r);                   /* exact */
fm_node fm_ellipsoid(fm_graph *g, const double c[3], const double radii[3]);   /* first order */
fm_node fm_block(fm_graph *g, const double lo[3], const double hi[3]);         /* exact */
/* Finite cylinder: base centre, axis direction (normalized here), radius,
 * height along the axis. Exact. */
fm_node fm_cylinder(fm_graph *g, const double base[3], const double axis[3], double r, double h);
/* Truncated cone: radius r0 at the base, r1 at base + h * axis. Exact. */
fm_node fm_cone(fm_graph *g, const double base[3], const double axis[3], double r0, double r1,
                double h);
/* Torus about axis through c: major radius R, minor r. Exact. */
fm_node fm_torus(fm_graph *g, const double c[3], const double axis[3], double R, double r);
/* The same torus about the line through c parallel to coordinate `axis`
 * (0..2), at the point whose coordinates are the expressions p, with the
 * centre and radii given as expressions (not checked: expressions may have
 * any value; the formula is r - sqrt((sqrt(l1^2 + l2^2) - R)^2 + l0^2) with
 * l = p - c, l0 along the axis). */
fm_node fm_torus_expr(fm_graph *g, const fm_node p[3], const fm_node c[3], int axis, fm_node R,
                      fm_node r);
/* Superellipsoid ((|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1) <= 1),
 * normalized to first order. */
fm_node fm_superellipsoid(fm_graph *g, const double c[3], const double radii[3], double e1,
                          double e2);
/* Blinn blobby: sum_i b_i exp(-a_i r_i^2) - threshold, normalized (eq. 4.9). */
fm_node fm_blobby(fm_graph *g, size_t n, const double *centers /* 3n */, const double *a,
                  const double *b, double threshold);
/* Wyvill soft objects: sum_i C(r_i / R_i) - threshold with
 * C(s) = 1 - 4/9 s^6 + 17/9 s^4 - 22/9 s^2 for s < 1, else 0; normalized. */
fm_node fm_soft(fm_graph *g, size_t n, const double *centers, const double *radii,
                double threshold);
/* Voxel grid over [lo, hi] with nx*ny*nz samples (x fastest), trilinear
 * interpolation; outside the grid, the nearest face value minus the
 * distance to the grid box (so the field stays first-order). values are
 * copied into the graph. */
fm_node fm_voxels(fm_graph *g, const double lo[3], const double hi[3], size_t nx, size_t ny,
                  size_t nz, const float *values);

/* ------------------------------------------------------------ tape -- */

typedef struct fm_tape fm_tape;

/* Compile the function rooted at root. Applies constant folding and the
 * function-invariant min/max rewrite rules of Hasan sec. 4.2.1. */
fm_tape *fm_tape_compile(const fm_graph *g, fm_node root, fm_error *err);
void fm_tape_free(fm_tape *tape);
/* Number of instructions. */
size_t fm_tape_length(const fm_tape *tape);
/* Change a parameter's value on a compiled tape (and its shortened tapes
 * made afterwards). FM_ERR_INPUT if the tape has no such parameter. */
fm_status fm_tape_set_param(fm_tape *tape, const char *name, double value);

/* -------------------------------------------------------- evaluators -- */

typedef struct fm_interval {
    double lo, hi;
} fm_interval;

/* Per-thread scratch for evaluating one tape (and tapes shortened from it). */
typedef struct fm_evaluator fm_evaluator;
fm_evaluator *fm_evaluator_new(const fm_tape *tape, fm_error *err);
void fm_evaluator_free(fm_evaluator *ev);
/* Switch to a tape shortened from the evaluator's tape (or back to it). */
void fm_evaluator_use(fm_evaluator *ev, const fm_tape *tape);

double fm_eval_point(fm_evaluator *ev, const double p[4]);
/* Structure-of-arrays batch: out[i] = f(x[i], y[i], z[i], t[i]); t may be
 * NULL (t = 0), likewise z (z = 0). */
void fm_eval_batch(fm_evaluator *ev, size_t n, const double *x, const double *y,
                   const double *z, const double *t, double *out);
/* A sound enclosure of f over the box: every f(p), p in the box, lies in
 * the result. */
fm_interval fm_eval_interval(fm_evaluator *ev, const fm_interval box[4]);
/* As fm_eval_interval, and also a new tape, valid inside the box only,
 * with the min/max branches that cannot win there removed. Free it with
 * fm_tape_free. NULL if nothing could be removed (use the current tape). */
fm_tape *fm_eval_interval_shorten(fm_evaluator *ev, const fm_interval box[4],
                                  fm_interval *result);
/* fm_eval_interval_shorten into a tape the caller keeps in *slot (NULL at
 * first; free it with fm_tape_free when done): the tape there is rewritten
 * in place when it has room, so that shortening once per leaf of a grid
 * allocates nothing after the first leaves. Returns *slot, or NULL when
 * nothing could be removed (*slot is kept). The evaluator must not be using
 * *slot (it is then left alone and NULL returned). */
fm_tape *fm_eval_interval_shorten_in(fm_evaluator *ev, const fm_interval box[4],
                                     fm_interval *result, fm_tape **slot);
/* Value and gradient (df/dx, df/dy, df/dz, df/dt) by forward-mode
 * automatic differentiation. */
double fm_eval_grad(fm_evaluator *ev, const double p[4], double grad[4]);

/* ------------------------------------------------------- relations -- */

typedef enum fm_membership { FM_OUTSIDE = -1, FM_ON_BOUNDARY = 0, FM_INSIDE = 1 } fm_membership;

/* 3-valued point membership (Pasko eq. 16 with a tolerance band). */
fm_membership fm_classify_point(fm_evaluator *ev, const double p[4], double tol);

typedef struct fm_max_result {
    double value;    /* best value found (a lower bound of the maximum) */
    double upper;    /* a sound upper bound of the maximum */
    double at[4];    /* where value was found */
    size_t evaluations;
} fm_max_result;

/* Maximum of the tape's function over a box (coordinates not in the box's
 * dims are fixed at box[i].lo when lo == hi) by interval branch-and-bound:
 * stops when upper - value <= tol or after max_evaluations point
 * evaluations (then upper is still sound). */
fm_status fm_maximize(const fm_tape *tape, const fm_interval box[4], double tol,
                      size_t max_evaluations, fm_max_result *out, fm_error *err);
/* Intersection relation (Pasko eq. 18; Shapiro sec. 6.5): 1 if the
 * objects f1 and f2 (in one graph) meet inside the box (max of min(f1, f2)
 * >= 0), 0 if they provably do not, -1 if undecided within the budget. */
int fm_intersects(const fm_graph *g, fm_node f1, fm_node f2, const fm_interval box[4],
                  double tol, fm_error *err);
/* Inclusion: 1 if f1 is inside f2 within the box (max of min(f1, -f2) < 0),
 * 0 if not, -1 if undecided. */
int fm_includes(const fm_graph *g, fm_node inner, fm_node outer, const fm_interval box[4],
                double tol, fm_error *err);

/* Bounds of where an object may be inside (f >= 0) within box at t = 0,
 * by interval subdivision: boxes provably outside are dropped, boxes
 * provably inside or of edge min_size or less are kept (a NaN bound counts
 * as undecided). found = 0: outside everywhere in the box. FM_ERR_LIMIT
 * (err untouched: the caller names the model) after max_boxes interval
 * evaluations. */
typedef struct fm_inside_bounds {
    double lo[3], hi[3];
    int found;
    size_t boxes; /* interval evaluations made */
} fm_inside_bounds;
fm_status fm_find_inside_bounds(fm_evaluator *ev, const fm_interval box[3], double min_size,
                                size_t max_boxes, fm_inside_bounds *out);

/* ---------------------------------------------------------- fields -- */

/* A 3D scalar field as lib/stock consumes it: positive inside, first-order
 * distance near the surface, and negative outside [lo, hi] by at least the
 * distance to that box. Callbacks may run on several threads at once, each
 * thread with its own worker state made by worker_new. A field without
 * per-thread state leaves worker_new (and worker_free) NULL and its
 * callbacks get a NULL worker; worker_new returning NULL means it could not
 * allocate, and the consumer fails with out of memory. */
typedef struct fm_field {
    void *ctx;
    double lo[3], hi[3];
    void *(*worker_new)(void *ctx);
    void (*worker_free)(void *ctx, void *worker);
    void (*batch)(void *ctx, void *worker, size_t n, const double *x, const double *y,
                  const double *z, double *out);
    fm_interval (*interval)(void *ctx, void *worker, const fm_interval box[3]);
    void (*release)(void *ctx); /* frees ctx; may be NULL */
    /* Optional (NULL: every value is proven): batch, and per point how much
     * the true value may exceed out[i] where an evaluation stopped at its
     * budget before its proof closed (0 where it is proven). lib/stock
     * counts the voxels where that could matter (fm_stock_cut_stats). */
    void (*batch_shortfall)(void *ctx, void *worker, size_t n, const double *x, const double *y,
                            const double *z, double *out, double *shortfall);
    /* Nonzero: inside [lo, hi] too the value is at most the distance to the
     * box's nearest face (a 1-Lipschitz field, nonpositive outside, has it
     * when the box holds its inside). Consumers may then bound a point's
     * value by its signed distance to the box without evaluating it: where
     * a previous cut already left the stock at that bound (a pocket's floor
     * or wall retraced), lib/stock skips the point. */
    int within_box;
} fm_field;

/* A field over a compiled tape at fixed time t; the tape must outlive the
 * field. Release it with fm_field_release. */
fm_status fm_field_from_tape(fm_field *field, const fm_tape *tape, const double lo[3],
                             const double hi[3], double t, fm_error *err);
void fm_field_release(fm_field *field);

#endif
