/* ops.c: the builders of every F-rep operation of frep.h: set operations by
 * R-functions, blends, offsets, coordinate mappings (with the memoized
 * substitution fm_remap underneath them) and the dimension operations
 * (product, time segment, metamorphosis, projection, normalization). Each
 * formula and its source is in docs/frep.md. Builders only build nodes: bad
 * arguments become a graph error and FM_NONE. */
#include "frep/ops_internal.h"

#include <stdlib.h>
#include <string.h>

/* ----------------------------------------------------------- helpers -- */

/* A builder given FM_NONE returns FM_NONE; when no earlier failure explains
 * the missing argument, say which builder got it. */
static int missing(fm_graph *g, fm_node f, const char *who)
{
    if (!g) return 1;
    if (g->failed) return 1;
    if (f == FM_NONE || f >= g->count) {
        fm_graph_fail(g, FM_ERR_INPUT, "%s: an argument is missing (FM_NONE or not a node)", who);
        return 1;
    }
    return 0;
}

static fm_node k(fm_graph *g, double v) { return fm_const(g, v); }

/* c * a, folding c = 0 (graph.c folds only 1 and -1) so that sparse
 * matrices do not leave x * 0 nodes behind. */
static fm_node scale(fm_graph *g, double c, fm_node a)
{
    if (c == 0.0) return k(g, 0.0);
    return fm_mul(g, k(g, c), a);
}

/* a * b with a constant 0 on either side folded to 0 (used where entries of
 * symbolic matrices are often constant zeros). */
static fm_node mul0(fm_graph *g, fm_node a, fm_node b)
{
    if (fm_node_is_const(g, a, NULL) && g->nodes[a].value == 0.0) return a;
    if (fm_node_is_const(g, b, NULL) && g->nodes[b].value == 0.0) return b;
    return fm_mul(g, a, b);
}

static fm_node pow_c(fm_graph *g, fm_node a, double p)
{
    return fm_binary(g, FM_OP_POW, a, k(g, p));
}

static int finite(double v) { return isfinite(v); }

/* -------------------------------------------------- R-function systems -- */

/* sqrt(f1^2 + f2^2 - 2 alpha f1 f2) written as a sum of non-negative terms,
 * so that rounding can never make the radicand negative (which would give
 * NaN) and interval evaluation sees a non-negative radicand:
 *   alpha in [0, 1):  (1 - alpha)(f1^2 + f2^2) + alpha (f1 - f2)^2
 *   alpha in (-1, 0): (1 + alpha)(f1^2 + f2^2) - alpha (f1 + f2)^2 */
static fm_node r_alpha_root(fm_graph *g, fm_node f1, fm_node f2, double alpha)
{
    fm_node sum2 = fm_add(g, fm_square(g, f1), fm_square(g, f2));
    if (alpha == 0.0) return fm_sqrt(g, sum2);
    fm_node rad;
    if (alpha > 0.0)
        rad = fm_add(g, scale(g, 1.0 - alpha, sum2), scale(g, alpha, fm_square(g, fm_sub(g, f1, f2))));
    else
        rad = fm_add(g, scale(g, 1.0 + alpha, sum2), scale(g, -alpha, fm_square(g, fm_add(g, f1, f2))));
    return fm_sqrt(g, rad);
}

static fm_node r_alpha(fm_graph *g, fm_node f1, fm_node f2, double alpha, int sign, const char *who)
{
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (!(alpha > -1.0 && alpha <= 1.0))
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: alpha = %g is outside (-1, 1]", who, alpha);
    if (alpha == 1.0) return sign > 0 ? fm_max(g, f1, f2) : fm_min(g, f1, f2);
    fm_node root = r_alpha_root(g, f1, f2, alpha);
    fm_node s = fm_add(g, f1, f2);
    fm_node v = sign > 0 ? fm_add(g, s, root) : fm_sub(g, s, root);
    return scale(g, 1.0 / (1.0 + alpha), v);
}

fm_node fm_r_union(fm_graph *g, fm_node f1, fm_node f2, double alpha)
{
    return r_alpha(g, f1, f2, alpha, +1, "R_alpha union");
}

fm_node fm_r_inter(fm_graph *g, fm_node f1, fm_node f2, double alpha)
{
    return r_alpha(g, f1, f2, alpha, -1, "R_alpha intersection");
}

static fm_node r_m(fm_graph *g, fm_node f1, fm_node f2, int m, int sign, const char *who)
{
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (m < 0) return fm_graph_fail(g, FM_ERR_INPUT, "%s: m = %d must be >= 0", who, m);
    fm_node r0 = r_alpha(g, f1, f2, 0.0, sign, who);
    if (m == 0) return r0;
    fm_node sum2 = fm_add(g, fm_square(g, f1), fm_square(g, f2));
    return fm_mul(g, r0, pow_c(g, sum2, 0.5 * m));
}

fm_node fm_r_union_m(fm_graph *g, fm_node f1, fm_node f2, int m)
{
    return r_m(g, f1, f2, m, +1, "R_0^m union");
}

fm_node fm_r_inter_m(fm_graph *g, fm_node f1, fm_node f2, int m)
{
    return r_m(g, f1, f2, m, -1, "R_0^m intersection");
}

/* |f|^p; for even integer p the absolute value is not needed (and p = 2
 * becomes a SQUARE node, so that R_2 shares its nodes with R_0). */
static fm_node abs_pow(fm_graph *g, fm_node f, double p)
{
    if (p == floor(p) && fmod(p, 2.0) == 0.0) return pow_c(g, f, p);
    return pow_c(g, fm_abs(g, f), p);
}

static int check_p(fm_graph *g, double p, const char *who)
{
    /* p = 1 would make the union f1 + f2 + |f1| + |f2| >= 0 everywhere: the
     * whole space; only p > 1 keeps the R-function sign rule. */
    if (!(p > 1.0) || !finite(p)) {
        fm_graph_fail(g, FM_ERR_INPUT,
                      "%s: p = %g must be a finite number > 1 (p = 1 loses the sign rule)", who, p);
        return 0;
    }
    return 1;
}

static fm_node r_p(fm_graph *g, fm_node f1, fm_node f2, double p, int sign, const char *who)
{
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (!check_p(g, p, who)) return FM_NONE;
    fm_node norm = pow_c(g, fm_add(g, abs_pow(g, f1, p), abs_pow(g, f2, p)), 1.0 / p);
    fm_node s = fm_add(g, f1, f2);
    return sign > 0 ? fm_add(g, s, norm) : fm_sub(g, s, norm);
}

fm_node fm_rp_union(fm_graph *g, fm_node f1, fm_node f2, double p)
{
    return r_p(g, f1, f2, p, +1, "R_p union");
}

fm_node fm_rp_inter(fm_graph *g, fm_node f1, fm_node f2, double p)
{
    return r_p(g, f1, f2, p, -1, "R_p intersection");
}

fm_node fm_complement(fm_graph *g, fm_node f)
{
    if (missing(g, f, "complement")) return FM_NONE;
    return fm_neg(g, f);
}

fm_node fm_r_subtract(fm_graph *g, fm_node f1, fm_node f2, double alpha)
{
    if (missing(g, f1, "R_alpha subtraction") || missing(g, f2, "R_alpha subtraction"))
        return FM_NONE;
    return r_alpha(g, f1, fm_neg(g, f2), alpha, -1, "R_alpha subtraction");
}

/* ------------------------------------------------------------ blends -- */

/* a / c for a constant c as a multiplication by 1 / c (as the double-valued
 * builders always did), else a division node. */
static fm_node div_by(fm_graph *g, fm_node a, fm_node c)
{
    double v;
    if (fm_node_is_const(g, c, &v)) return scale(g, 1.0 / v, a);
    return fm_div(g, a, c);
}

static fm_node displacement_blend(fm_graph *g, fm_node f1, fm_node f2, fm_node a0, fm_node a1,
                                  fm_node a2, int sign, const char *who)
{
    if (missing(g, f1, who) || missing(g, f2, who) || missing(g, a0, who) || missing(g, a1, who) ||
        missing(g, a2, who))
        return FM_NONE;
    const fm_node a[3] = {a0, a1, a2};
    for (int i = 0; i < 3; i++) {
        double v;
        if (fm_node_is_const(g, a[i], &v) && (!finite(v) || (i > 0 && v == 0.0)))
            return fm_graph_fail(g, FM_ERR_INPUT, "%s: a%d = %g must be finite%s", who, i, v,
                                 i > 0 ? " and non-zero" : "");
    }
    fm_node r0 = r_alpha(g, f1, f2, 0.0, sign, who);
    fm_node den = fm_add(g, k(g, 1.0),
                         fm_add(g, fm_square(g, div_by(g, f1, a1)), fm_square(g, div_by(g, f2, a2))));
    return fm_add(g, r0, fm_div(g, a0, den));
}

fm_node fm_blend_union(fm_graph *g, fm_node f1, fm_node f2, double a0, double a1, double a2)
{
    return displacement_blend(g, f1, f2, k(g, a0), k(g, a1), k(g, a2), +1, "blend union");
}

fm_node fm_blend_inter(fm_graph *g, fm_node f1, fm_node f2, double a0, double a1, double a2)
{
    return displacement_blend(g, f1, f2, k(g, a0), k(g, a1), k(g, a2), -1, "blend intersection");
}

fm_node fm_blend_union_expr(fm_graph *g, fm_node f1, fm_node f2, fm_node a0, fm_node a1, fm_node a2)
{
    return displacement_blend(g, f1, f2, a0, a1, a2, +1, "blend union");
}

fm_node fm_blend_inter_expr(fm_graph *g, fm_node f1, fm_node f2, fm_node a0, fm_node a1, fm_node a2)
{
    return displacement_blend(g, f1, f2, a0, a1, a2, -1, "blend intersection");
}

static fm_node rho_blend(fm_graph *g, fm_node f1, fm_node f2, double rho, int sign, const char *who)
{
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (!(rho > 0.0) || !finite(rho))
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: rho = %g must be a finite number > 0", who, rho);
    fm_node sum2 = fm_add(g, fm_square(g, f1), fm_square(g, f2));
    fm_node s_rho = fm_sub(g, sum2, k(g, rho * rho));
    /* s_rho (s_rho - |s_rho|) is 2 s_rho^2 inside the disc and exactly 0
     * outside, so the radicand stays >= sum2 >= 0. */
    fm_node corr = fm_mul(g, s_rho, fm_sub(g, s_rho, fm_abs(g, s_rho)));
    fm_node root = fm_sqrt(g, fm_add(g, sum2, scale(g, 1.0 / (8.0 * rho * rho), corr)));
    fm_node s = fm_add(g, f1, f2);
    return sign > 0 ? fm_add(g, s, root) : fm_sub(g, s, root);
}

fm_node fm_rho_blend_union(fm_graph *g, fm_node f1, fm_node f2, double rho)
{
    return rho_blend(g, f1, f2, rho, +1, "rho-blend union");
}

fm_node fm_rho_blend_inter(fm_graph *g, fm_node f1, fm_node f2, double rho)
{
    return rho_blend(g, f1, f2, rho, -1, "rho-blend intersection");
}

fm_node fm_hyperbolic_blend_union(fm_graph *g, fm_node f1, fm_node f2, double a)
{
    const char *who = "hyperbolic blend union";
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (!finite(a)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: a = %g must be finite", who, a);
    fm_node hyper = fm_sub(g, k(g, a * a), fm_mul(g, f1, f2));
    return fm_max(g, fm_max(g, f1, f2), hyper);
}

fm_node fm_hyperbolic_blend_inter(fm_graph *g, fm_node f1, fm_node f2, double a)
{
    const char *who = "hyperbolic blend intersection";
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (!finite(a)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: a = %g must be finite", who, a);
    fm_node hyper = fm_sub(g, fm_mul(g, f1, f2), k(g, a * a));
    return fm_min(g, fm_min(g, f1, f2), hyper);
}

/* R_p over f[lo, hi) folded as a balanced tree, so that depth is log2 n. */
static fm_node lp_tree(fm_graph *g, const fm_node *f, size_t lo, size_t hi, double p, int sign,
                       const char *who)
{
    if (hi - lo == 1) return f[lo];
    size_t mid = lo + (hi - lo) / 2;
    fm_node left = lp_tree(g, f, lo, mid, p, sign, who);
    fm_node right = lp_tree(g, f, mid, hi, p, sign, who);
    return r_p(g, left, right, p, sign, who);
}

static fm_node lp(fm_graph *g, const fm_node *f, size_t n, double p, int sign, const char *who)
{
    if (!g || g->failed) return FM_NONE;
    if (!f || n == 0) return fm_graph_fail(g, FM_ERR_INPUT, "%s: needs at least one function", who);
    if (!check_p(g, p, who)) return FM_NONE;
    for (size_t i = 0; i < n; i++)
        if (missing(g, f[i], who)) return FM_NONE;
    return lp_tree(g, f, 0, n, p, sign, who);
}

fm_node fm_lp_union(fm_graph *g, const fm_node *f, size_t n, double p)
{
    return lp(g, f, n, p, +1, "L_p union");
}

fm_node fm_lp_inter(fm_graph *g, const fm_node *f, size_t n, double p)
{
    return lp(g, f, n, p, -1, "L_p intersection");
}

/* ----------------------------------------------------------- offsets -- */

fm_node fm_offset_iso(fm_graph *g, fm_node f, double c)
{
    if (missing(g, f, "iso offset")) return FM_NONE;
    if (!finite(c)) return fm_graph_fail(g, FM_ERR_INPUT, "iso offset: c = %g must be finite", c);
    return fm_add(g, f, k(g, c));
}

static fm_node special1(fm_graph *g, fm_op op, fm_node f, double d, const char *who)
{
    if (missing(g, f, who)) return FM_NONE;
    if (!finite(d)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: distance %g must be finite", who, d);
    if (d == 0.0 && op != FM_OP_NORMALIZE) return f;
    fm_node_rec r = {0};
    r.op = (uint8_t)op;
    r.a = f;
    r.value = d;
    return fm_graph_intern(g, &r);
}

fm_node fm_offset_normal(fm_graph *g, fm_node f, double d)
{
    return special1(g, FM_OP_NORMAL_OFFSET, f, d, "normal offset");
}

fm_node fm_offset_radius(fm_graph *g, fm_node f, double d)
{
    return special1(g, FM_OP_BALL_MAX, f, d, "constant-radius offset");
}

fm_node fm_normalize(fm_graph *g, fm_node f)
{
    return special1(g, FM_OP_NORMALIZE, f, 0.0, "normalize");
}

/* ------------------------------------------------------------- remap -- */

/* Memo of the substitution: old node -> new node, an open-addressing hash
 * map so that the cost is proportional to the part of the DAG visited, not
 * to the size of the graph. */
typedef struct memo {
    fm_node *keys, *vals;
    size_t size, used;
} memo;

static size_t memo_slot(const memo *m, fm_node key)
{
    size_t h = (size_t)key * 2654435761u;
    size_t slot = h & (m->size - 1);
    while (m->keys[slot] && m->keys[slot] != key) slot = (slot + 1) & (m->size - 1);
    return slot;
}

static fm_node memo_get(const memo *m, fm_node key)
{
    if (m->size == 0) return FM_NONE;
    size_t slot = memo_slot(m, key);
    return m->keys[slot] ? m->vals[slot] : FM_NONE;
}

static int memo_put(memo *m, fm_node key, fm_node val)
{
    if ((m->used + 1) * 2 > m->size) {
        memo bigger = {0};
        bigger.size = m->size ? m->size * 2 : 64;
        bigger.keys = calloc(bigger.size, sizeof *bigger.keys);
        bigger.vals = calloc(bigger.size, sizeof *bigger.vals);
        if (!bigger.keys || !bigger.vals) {
            free(bigger.keys);
            free(bigger.vals);
            return 0;
        }
        for (size_t i = 0; i < m->size; i++)
            if (m->keys[i]) {
                size_t s = memo_slot(&bigger, m->keys[i]);
                bigger.keys[s] = m->keys[i];
                bigger.vals[s] = m->vals[i];
            }
        bigger.used = m->used;
        free(m->keys);
        free(m->vals);
        *m = bigger;
    }
    size_t slot = memo_slot(m, key);
    if (!m->keys[slot]) m->used++;
    m->keys[slot] = key;
    m->vals[slot] = val;
    return 1;
}

static void memo_free(memo *m)
{
    free(m->keys);
    free(m->vals);
}

static const char *const axis_name[FM_AXES] = {"x", "y", "z", "t"};

typedef struct remap_job {
    fm_graph *g;
    fm_node map[FM_AXES];
    unsigned mask;   /* axes that are substituted */
    int rigid;       /* the map is a rigid motion of x, y, z (see docs/frep.md) */
    memo done;
} remap_job;

static fm_node remap_run(fm_graph *g, fm_node root, const fm_node map[FM_AXES], int rigid);

static int touched(const remap_job *job, fm_node n)
{
    return (job->g->nodes[n].deps & job->mask) != 0;
}

/* The new node for n, or FM_NONE if not computed yet. */
static fm_node mapped(const remap_job *job, fm_node n)
{
    if (n == FM_NONE || !touched(job, n)) return n;
    return memo_get(&job->done, n);
}

static fm_node rebuild(remap_job *job, fm_node n)
{
    fm_graph *g = job->g;
    fm_node_rec r = g->nodes[n];
    fm_op op = (fm_op)r.op;
    switch (op) {
    case FM_OP_VAR: return job->map[r.aux] ? job->map[r.aux] : n;
    case FM_OP_CONST:
    case FM_OP_PARAM: return n;
    default: break;
    }
    int arity = fm_op_arity(op);
    if (arity == 1) return fm_unary(g, op, mapped(job, r.a));
    if (arity == 2) return fm_binary(g, op, mapped(job, r.a), mapped(job, r.b));
    if (arity == 3) return fm_select(g, mapped(job, r.a), mapped(job, r.b), mapped(job, r.c));
    if (op == FM_OP_PROJECT) {
        /* The projection binds its axis: inside, that coordinate is the
         * search variable, not the outer one. */
        fm_node inner[FM_AXES];
        memcpy(inner, job->map, sizeof inner);
        inner[r.aux] = FM_NONE;
        for (int j = 0; j < FM_AXES; j++)
            if (inner[j] && fm_node_depends_on(g, r.a, j) && fm_node_depends_on(g, inner[j], (int)r.aux))
                return fm_graph_fail(g, FM_ERR_INPUT,
                                     "remap: the map for %s depends on %s, which a projection over %s "
                                     "binds inside; the substitution would capture it",
                                     axis_name[j], axis_name[r.aux], axis_name[r.aux]);
        r.a = remap_run(g, r.a, inner, job->rigid);
        if (!r.a) return FM_NONE;
        return fm_graph_intern(g, &r);
    }
    if (op == FM_OP_VOXELS) {
        if (!FM_VOXELS_SAMPLE_CHILDREN)
            return fm_graph_fail(g, FM_ERR_INPUT,
                                 "remap: a voxel grid cannot be moved or deformed yet (the evaluators "
                                 "sample it at the unmapped point)");
        r.a = mapped(job, r.a);
        r.b = mapped(job, r.b);
        r.c = mapped(job, r.c);
        for (int i = 0; i < 3; i++) {
            fm_node c = i == 0 ? r.a : i == 1 ? r.b : r.c;
            if (!c) return FM_NONE;
            /* graph.c gives VOXELS the dependencies x, y, z whatever its
             * children are, so a time- or parameter-dependent placement
             * would be reported as constant in t: refuse it. */
            if (g->nodes[c].deps & ((1u << FM_T) | FM_DEP_PARAM))
                return fm_graph_fail(g, FM_ERR_INPUT,
                                     "remap: a voxel grid can only be placed by a map of x, y, z "
                                     "that depends on neither t nor parameters");
        }
        return fm_graph_intern(g, &r);
    }
    /* BALL_MAX, NORMAL_OFFSET, NORMALIZE look at the child around the
     * point (a sphere, the gradient): substituting inside equals
     * substituting outside only when the map is a rigid motion. */
    if (!job->rigid)
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "remap: cannot map the coordinates of a %s (offset or normalization): "
                             "only rigid motions (translate, rotate, orthonormal affine) commute with it",
                             op == FM_OP_BALL_MAX ? "constant-radius offset"
                             : op == FM_OP_NORMAL_OFFSET ? "normal offset"
                                                         : "normalization");
    r.a = mapped(job, r.a);
    if (!r.a) return FM_NONE;
    return fm_graph_intern(g, &r);
}

/* Children of n that the substitution must visit (not those of PROJECT:
 * remap_run recurses into them with the bound axis removed). */
static int remap_children(const fm_graph *g, fm_node n, fm_node out[3])
{
    const fm_node_rec *r = &g->nodes[n];
    if (r->op == FM_OP_PROJECT || r->op == FM_OP_VAR || r->op == FM_OP_CONST ||
        r->op == FM_OP_PARAM)
        return 0;
    out[0] = r->a;
    out[1] = r->b;
    out[2] = r->c;
    return 3;
}

static fm_node remap_run(fm_graph *g, fm_node root, const fm_node map[FM_AXES], int rigid)
{
    if (!g || g->failed) return FM_NONE;
    remap_job job = {0};
    job.g = g;
    job.rigid = rigid;
    for (int i = 0; i < FM_AXES; i++) {
        fm_node m = map[i];
        /* x -> x is no substitution. */
        if (m && g->nodes[m].op == FM_OP_VAR && g->nodes[m].aux == (uint32_t)i) m = FM_NONE;
        job.map[i] = m;
        if (m) job.mask |= 1u << i;
    }
    if (!touched(&job, root)) return root;
    /* A map of t alone that does not mix in x, y, z leaves space as it is,
     * so it commutes with the spatial searches of the special ops. */
    if (!(job.mask & 0x7u) && !(g->nodes[job.map[FM_T]].deps & 0x7u)) job.rigid = 1;

    /* Iterative post-order walk: the DAG can be deeper than the C stack. */
    size_t cap = 64, top = 0;
    fm_node *stack = malloc(cap * sizeof *stack);
    fm_node result = FM_NONE;
    if (!stack) return fm_graph_fail(g, FM_ERR_LIMIT, "out of memory in remap");
    stack[top++] = root;
    while (top > 0 && !g->failed) {
        fm_node n = stack[top - 1];
        if (memo_get(&job.done, n)) {
            top--;
            continue;
        }
        fm_node kids[3];
        int nk = remap_children(g, n, kids), pushed = 0;
        for (int i = 0; i < nk; i++) {
            fm_node c = kids[i];
            if (c && touched(&job, c) && !memo_get(&job.done, c)) {
                if (top == cap) {
                    fm_node *bigger = realloc(stack, 2 * cap * sizeof *stack);
                    if (!bigger) {
                        fm_graph_fail(g, FM_ERR_LIMIT, "out of memory in remap");
                        break;
                    }
                    stack = bigger;
                    cap *= 2;
                }
                stack[top++] = c;
                pushed = 1;
            }
        }
        if (pushed || g->failed) continue;
        fm_node v = rebuild(&job, n);
        if (!v) break;
        if (!memo_put(&job.done, n, v)) {
            fm_graph_fail(g, FM_ERR_LIMIT, "out of memory in remap");
            break;
        }
        top--;
    }
    if (!g->failed) result = memo_get(&job.done, root);
    free(stack);
    memo_free(&job.done);
    return g->failed ? FM_NONE : result;
}

static int check_map(fm_graph *g, const fm_node map[FM_AXES], const char *who)
{
    if (!map) {
        fm_graph_fail(g, FM_ERR_INPUT, "%s: no map given", who);
        return 0;
    }
    for (int i = 0; i < FM_AXES; i++)
        if (map[i] >= g->count) {
            fm_graph_fail(g, FM_ERR_INPUT, "%s: the map for %s is not a node", who, axis_name[i]);
            return 0;
        }
    return 1;
}

fm_node fm_remap(fm_graph *g, fm_node f, const fm_node map[FM_AXES])
{
    if (missing(g, f, "remap") || !check_map(g, map, "remap")) return FM_NONE;
    return remap_run(g, f, map, 0);
}

/* Rigid motions: translate, rotate and orthonormal affine maps. */
static fm_node remap_rigid(fm_graph *g, fm_node f, const fm_node map[FM_AXES])
{
    return remap_run(g, f, map, 1);
}

/* ---------------------------------------------------------- mappings -- */

static int check_axis3(fm_graph *g, int axis, const char *who, const char *what)
{
    if (axis < 0 || axis > 2) {
        fm_graph_fail(g, FM_ERR_INPUT, "%s: %s axis %d is not 0 (x), 1 (y) or 2 (z)", who, what, axis);
        return 0;
    }
    return 1;
}

/* Invert a 4x4 row-major matrix by Gauss-Jordan elimination with partial
 * pivoting. Returns 0 if a pivot is negligible against the matrix's
 * largest entry (singular to working precision). */
static int invert4(const double m[16], double inv[16])
{
    double a[4][8];
    double big = 0.0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            a[i][j] = m[4 * i + j];
            a[i][4 + j] = i == j ? 1.0 : 0.0;
            if (fabs(a[i][j]) > big) big = fabs(a[i][j]);
        }
    if (!(big > 0.0) || !isfinite(big)) return 0;
    for (int col = 0; col < 4; col++) {
        int piv = col;
        for (int i = col + 1; i < 4; i++)
            if (fabs(a[i][col]) > fabs(a[piv][col])) piv = i;
        if (!(fabs(a[piv][col]) > 1e-12 * big)) return 0;
        if (piv != col)
            for (int j = 0; j < 8; j++) {
                double tmp = a[col][j];
                a[col][j] = a[piv][j];
                a[piv][j] = tmp;
            }
        double p = a[col][col];
        for (int j = 0; j < 8; j++) a[col][j] /= p;
        for (int i = 0; i < 4; i++) {
            if (i == col || a[i][col] == 0.0) continue;
            double factor = a[i][col];
            for (int j = 0; j < 8; j++) a[i][j] -= factor * a[col][j];
        }
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) inv[4 * i + j] = a[i][4 + j];
    return 1;
}

fm_node fm_affine(fm_graph *g, fm_node f, const double m[16])
{
    const char *who = "affine map";
    if (missing(g, f, who)) return FM_NONE;
    if (!m) return fm_graph_fail(g, FM_ERR_INPUT, "%s: no matrix given", who);
    for (int i = 0; i < 16; i++)
        if (!finite(m[i]))
            return fm_graph_fail(g, FM_ERR_INPUT, "%s: matrix entry %d is not finite", who, i);
    if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0)
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "%s: the last row must be 0 0 0 1 (a projective map is not affine)", who);
    double inv[16];
    if (!invert4(m, inv))
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: the matrix is singular (no inverse map)", who);
    fm_node map[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, FM_NONE};
    for (int i = 0; i < 3; i++) {
        fm_node e = k(g, inv[4 * i + 3]);
        for (int j = 0; j < 3; j++) e = fm_add(g, e, scale(g, inv[4 * i + j], fm_var(g, j)));
        map[i] = e;
    }
    /* Orthonormal A (A^T A = I) is a rigid motion. */
    int rigid = 1;
    for (int i = 0; i < 3 && rigid; i++)
        for (int j = 0; j < 3; j++) {
            double dot = 0.0;
            for (int r = 0; r < 3; r++) dot += m[4 * r + i] * m[4 * r + j];
            if (fabs(dot - (i == j ? 1.0 : 0.0)) > 1e-12) {
                rigid = 0;
                break;
            }
        }
    return remap_run(g, f, map, rigid);
}

int fm_affine_t_coords(fm_graph *g, fm_node p[3], const fm_node m[12])
{
    const char *who = "time-dependent affine map";
    if (!g || g->failed) return 0;
    if (!p || !m) {
        fm_graph_fail(g, FM_ERR_INPUT, "%s: no %s given", who, p ? "matrix" : "point");
        return 0;
    }
    for (int i = 0; i < 3; i++)
        if (missing(g, p[i], who)) return 0;
    for (int i = 0; i < 12; i++)
        if (missing(g, m[i], who)) return 0;
    /* A = m[4 r + c] for r, c < 3; translation m[4 r + 3]. Inverse by
     * cofactors: (A^-1)_{ij} = C_{ji} / det A. */
#define A(r, c) m[4 * (r) + (c)]
    fm_node cof[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            /* Cyclic indices give the signed cofactor directly. */
            cof[r][c] = fm_sub(g, mul0(g, A(r1, c1), A(r2, c2)), mul0(g, A(r1, c2), A(r2, c1)));
        }
    fm_node det = fm_add(g, fm_add(g, mul0(g, A(0, 0), cof[0][0]), mul0(g, A(0, 1), cof[0][1])),
                         mul0(g, A(0, 2), cof[0][2]));
    double det_value;
    if (fm_node_is_const(g, det, &det_value) && (det_value == 0.0 || !isfinite(det_value))) {
        fm_graph_fail(g, FM_ERR_INPUT, "%s: the matrix is singular (determinant %g)", who, det_value);
        return 0;
    }
    fm_node d[3], out[3];
    for (int r = 0; r < 3; r++) d[r] = fm_sub(g, p[r], A(r, 3));
    for (int i = 0; i < 3; i++) {
        fm_node e = k(g, 0.0);
        for (int j = 0; j < 3; j++) e = fm_add(g, e, mul0(g, cof[j][i], d[j]));
        out[i] = fm_div(g, e, det);
    }
#undef A
    if (g->failed) return 0;
    for (int i = 0; i < 3; i++) p[i] = out[i];
    return 1;
}

fm_node fm_affine_t(fm_graph *g, fm_node f, const fm_node m[12])
{
    const char *who = "time-dependent affine map";
    if (missing(g, f, who)) return FM_NONE;
    if (!m) return fm_graph_fail(g, FM_ERR_INPUT, "%s: no matrix given", who);
    fm_node p[3] = {fm_var(g, FM_X), fm_var(g, FM_Y), fm_var(g, FM_Z)};
    if (!fm_affine_t_coords(g, p, m)) return FM_NONE;
    fm_node map[FM_AXES] = {p[0], p[1], p[2], FM_NONE};
    /* Rigidity of a symbolic matrix cannot be checked; a constant one can. */
    int rigid = 1;
    double a[9];
    for (int r = 0; r < 3 && rigid; r++)
        for (int c = 0; c < 3; c++)
            if (!fm_node_is_const(g, m[4 * r + c], &a[3 * r + c])) {
                rigid = 0;
                break;
            }
    for (int i = 0; i < 3 && rigid; i++)
        for (int j = 0; j < 3; j++) {
            double dot = a[i] * a[j] + a[3 + i] * a[3 + j] + a[6 + i] * a[6 + j];
            if (fabs(dot - (i == j ? 1.0 : 0.0)) > 1e-12) {
                rigid = 0;
                break;
            }
        }
    return remap_run(g, f, map, rigid);
}

fm_node fm_translate(fm_graph *g, fm_node f, double dx, double dy, double dz)
{
    const char *who = "translate";
    if (missing(g, f, who)) return FM_NONE;
    if (!finite(dx) || !finite(dy) || !finite(dz))
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: offset (%g, %g, %g) is not finite", who, dx, dy, dz);
    double d[3] = {dx, dy, dz};
    fm_node map[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, FM_NONE};
    for (int i = 0; i < 3; i++)
        if (d[i] != 0.0) map[i] = fm_sub(g, fm_var(g, i), k(g, d[i]));
    return remap_rigid(g, f, map);
}

/* The inverse of a rotation about `axis` by the angle whose cosine and sine
 * are the nodes c and s, applied to the point p: coordinates i and j (the
 * next two in cyclic order) of the original point. */
static void inverse_rotation(fm_graph *g, fm_node p[3], int axis, fm_node c, fm_node s)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    fm_node xi = p[i], xj = p[j];
    p[i] = fm_add(g, mul0(g, c, xi), mul0(g, s, xj));
    p[j] = fm_sub(g, mul0(g, c, xj), mul0(g, s, xi));
}

int fm_rotate_coords(fm_graph *g, fm_node p[3], int axis, fm_node theta)
{
    const char *who = "rotate coordinates";
    if (!g || g->failed) return 0;
    if (!p) {
        fm_graph_fail(g, FM_ERR_INPUT, "%s: no point given", who);
        return 0;
    }
    if (!check_axis3(g, axis, who, "rotation") || missing(g, theta, who)) return 0;
    for (int i = 0; i < 3; i++)
        if (missing(g, p[i], who)) return 0;
    inverse_rotation(g, p, axis, fm_unary(g, FM_OP_COS, theta), fm_unary(g, FM_OP_SIN, theta));
    return !g->failed;
}

/* The x, y, z coordinates, for the builders that map an object. */
static void identity_coords(fm_graph *g, fm_node p[3])
{
    for (int i = 0; i < 3; i++) p[i] = fm_var(g, i);
}

fm_node fm_rotate(fm_graph *g, fm_node f, int axis, double angle)
{
    const char *who = "rotate";
    if (missing(g, f, who) || !check_axis3(g, axis, who, "rotation")) return FM_NONE;
    if (!finite(angle)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: angle %g is not finite", who, angle);
    if (angle == 0.0) return f;
    fm_node p[3];
    identity_coords(g, p);
    inverse_rotation(g, p, axis, k(g, cos(angle)), k(g, sin(angle)));
    fm_node map[FM_AXES] = {p[0], p[1], p[2], FM_NONE};
    return remap_rigid(g, f, map);
}

fm_node fm_twist(fm_graph *g, fm_node f, int axis, double rate)
{
    const char *who = "twist";
    if (missing(g, f, who) || !check_axis3(g, axis, who, "twist")) return FM_NONE;
    if (!finite(rate)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: rate %g is not finite", who, rate);
    if (rate == 0.0) return f;
    fm_node p[3];
    identity_coords(g, p);
    if (!fm_rotate_coords(g, p, axis, scale(g, rate, p[axis]))) return FM_NONE;
    fm_node map[FM_AXES] = {p[0], p[1], p[2], FM_NONE};
    return fm_remap(g, f, map);
}

fm_node fm_taper(fm_graph *g, fm_node f, int axis, double rate)
{
    const char *who = "taper";
    if (missing(g, f, who) || !check_axis3(g, axis, who, "taper")) return FM_NONE;
    if (!finite(rate)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: rate %g is not finite", who, rate);
    if (rate == 0.0) return f;
    fm_node s = fm_add(g, k(g, 1.0), scale(g, rate, fm_var(g, axis)));
    fm_node map[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, FM_NONE};
    for (int i = 0; i < 3; i++)
        if (i != axis) map[i] = fm_div(g, fm_var(g, i), s);
    return fm_remap(g, f, map);
}

fm_node fm_bend(fm_graph *g, fm_node f, int along, int about, double kappa)
{
    const char *who = "bend";
    if (missing(g, f, who) || !check_axis3(g, along, who, "along") ||
        !check_axis3(g, about, who, "about"))
        return FM_NONE;
    if (along == about)
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: the along and about axes must differ (both %d)",
                             who, along);
    if (!finite(kappa)) return fm_graph_fail(g, FM_ERR_INPUT, "%s: curvature %g is not finite", who, kappa);
    if (kappa == 0.0) return f;
    int radial = 3 - along - about;
    double radius = 1.0 / kappa, sigma = kappa > 0.0 ? 1.0 : -1.0;
    /* Forward: theta = k u, u' = sin(theta) (R - v), v' = R - cos(theta) (R - v)
     * with u = along, v = radial, R = 1/k. Inverse about the centre (0, R):
     * v = R - sigma |(u', v' - R)|, u = atan2(sigma u', sigma (R - v')) / k. */
    fm_node du = fm_var(g, along);
    fm_node dv = fm_sub(g, fm_var(g, radial), k(g, radius));
    fm_node rho = fm_sqrt(g, fm_add(g, fm_square(g, du), fm_square(g, dv)));
    fm_node map[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, FM_NONE};
    map[radial] = fm_sub(g, k(g, radius), scale(g, sigma, rho));
    map[along] = scale(g, 1.0 / kappa,
                       fm_binary(g, FM_OP_ATAN2, scale(g, sigma, du), scale(g, -sigma, dv)));
    return fm_remap(g, f, map);
}

/* ------------------------------------------------ dimension operations -- */

fm_node fm_product(fm_graph *g, fm_node f1, int n1, fm_node f2, double alpha)
{
    const char *who = "Cartesian product";
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (n1 < 1 || n1 > 3)
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: n1 = %d must be 1, 2 or 3", who, n1);
    for (int i = n1; i < FM_AXES; i++)
        if (fm_node_depends_on(g, f1, i))
            return fm_graph_fail(g, FM_ERR_INPUT,
                                 "%s: the first object depends on %s but owns only the first %d "
                                 "coordinates", who, axis_name[i], n1);
    for (int i = FM_AXES - n1; i < FM_AXES; i++)
        if (fm_node_depends_on(g, f2, i))
            return fm_graph_fail(g, FM_ERR_INPUT,
                                 "%s: the second object depends on its coordinate %d, which would "
                                 "land beyond t", who, i);
    fm_node map[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, FM_NONE};
    for (int i = 0; i + n1 < FM_AXES; i++) map[i] = fm_var(g, n1 + i);
    fm_node moved = remap_run(g, f2, map, 0);
    return r_alpha(g, f1, moved, alpha, -1, who);
}

fm_node fm_time_segment(fm_graph *g, double t0, double t1)
{
    if (!g || g->failed) return FM_NONE;
    if (!finite(t0) || !finite(t1) || t0 > t1)
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "time segment: [%g, %g] must be finite with t0 <= t1", t0, t1);
    fm_node t = fm_var(g, FM_T);
    return fm_min(g, fm_sub(g, t, k(g, t0)), fm_sub(g, k(g, t1), t));
}

fm_node fm_metamorph(fm_graph *g, fm_node f1, fm_node f2, double t0, double t1)
{
    const char *who = "metamorphosis";
    if (missing(g, f1, who) || missing(g, f2, who)) return FM_NONE;
    if (!finite(t0) || !finite(t1) || !(t0 < t1))
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: [%g, %g] must be finite with t0 < t1", who, t0, t1);
    fm_node ramp = scale(g, 1.0 / (t1 - t0), fm_sub(g, fm_var(g, FM_T), k(g, t0)));
    fm_node s = fm_min(g, fm_max(g, ramp, k(g, 0.0)), k(g, 1.0));
    return fm_add(g, fm_mul(g, f1, fm_sub(g, k(g, 1.0), s)), fm_mul(g, f2, s));
}

fm_node fm_project(fm_graph *g, fm_node f, int axis, double lo, double hi)
{
    const char *who = "projection";
    if (missing(g, f, who)) return FM_NONE;
    if (axis < 0 || axis >= FM_AXES)
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: axis %d is not 0..3 (x, y, z, t)", who, axis);
    if (!finite(lo) || !finite(hi) || lo > hi)
        return fm_graph_fail(g, FM_ERR_INPUT, "%s: interval [%g, %g] must be finite with lo <= hi",
                             who, lo, hi);
    if (!fm_node_depends_on(g, f, axis)) return f;
    if (lo == hi) {
        fm_node map[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, FM_NONE};
        map[axis] = k(g, lo);
        return remap_run(g, f, map, 0);
    }
    fm_node_rec r = {0};
    r.op = FM_OP_PROJECT;
    r.a = f;
    r.aux = (uint32_t)axis;
    r.value = lo;
    r.value2 = hi;
    return fm_graph_intern(g, &r);
}
