/* bb.c: the relation between a swept tool part and a target as a
 * branch-and-bound over boxes. The objective is min(S + clear, F), the
 * R-conjunction of the part's swept volume (offset by the clearance) and
 * an upper bound F of the target's distance; a box's upper bound comes from
 * the 1-Lipschitz property of every distance involved (value at the centre
 * plus the half-diagonal), or from interval evaluation where a function is
 * not a distance (custom cutters, HyperFun fixtures). */
#include "check/check_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Boxes per relation before giving up and reporting (the safe side). */
#define CHECK_MAX_BOXES 20000000L
/* Float rounding of the grid's stored values (mm, relative and absolute). */
#define CHECK_FLOAT_REL 1e-6
#define CHECK_FLOAT_ABS 1e-6

int check_grid_init(check_grid *g, const fm_stock *stock)
{
    memset(g, 0, sizeof *g);
    g->stock = stock;
    g->voxel = fm_stock_voxel_size(stock);
    g->band = fm_stock_band_voxels(stock) * g->voxel;
    const double zero[3] = {0, 0, 0};
    fm_stock_index_to_world(stock, zero, g->origin);
    int32_t ilo[3], ihi[3];
    fm_error err;
    if (fm_stock_active_bounds(stock, ilo, ihi, &err) != FM_OK) return 0;
    double dlo[3] = {ilo[0], ilo[1], ilo[2]}, dhi[3] = {ihi[0], ihi[1], ihi[2]};
    fm_stock_index_to_world(stock, dlo, g->lo);
    fm_stock_index_to_world(stock, dhi, g->hi);
    for (int a = 0; a < 3; a++) {
        g->lo[a] -= g->voxel;
        g->hi[a] += g->voxel;
    }
    return 1;
}

/* Upper bound of the grid's distance G at p: the trilinear value plus the
 * interpolation error bound h * sqrt(sum u(1-u)) (<= sqrt(3)/2 h), valid
 * while it stays inside the band; beyond it nothing is known. */
static double grid_upper(const check_grid *g, const double p[3])
{
    double s = fm_stock_sample(g->stock, p);
    double e2 = 0;
    for (int a = 0; a < 3; a++) {
        double q = (p[a] - g->origin[a]) / g->voxel;
        double u = q - floor(q);
        e2 += u * (1 - u);
    }
    double e = g->voxel * sqrt(e2) + CHECK_FLOAT_REL * g->band + CHECK_FLOAT_ABS;
    if (s + e >= g->band * (1 - CHECK_FLOAT_REL) - CHECK_FLOAT_ABS) return INFINITY;
    return s + e;
}

static double box_field(const double lo[3], const double hi[3], const double p[3])
{
    double f = INFINITY;
    for (int a = 0; a < 3; a++) f = fmin(f, fmin(p[a] - lo[a], hi[a] - p[a]));
    return f;
}

typedef struct bound {
    double upper;  /* of the objective over the box */
    double centre; /* objective at the box's centre (an upper-bound function's value) */
} bound;

/* Bound min(S + clear, F) over the box. When the upper bound falls to
 * `floor` or below the rest is skipped (centre then undefined). */
static bound evaluate(check_bb *bb, const check_box *b, double floor_)
{
    bound out = {INFINITY, INFINITY};
    check_target *tg = bb->target;
    double c[3], r2 = 0;
    fm_interval ib[3];
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5 * (b->lo[a] + b->hi[a]);
        double h = 0.5 * (b->hi[a] - b->lo[a]);
        r2 += h * h;
        ib[a] = (fm_interval){b->lo[a], b->hi[a]};
    }
    double r = sqrt(r2);

    /* the part */
    double s_up, s_c;
    if (bb->custom) {
        fm_interval iv = fm_sweep_interval(bb->sweep, bb->worker, ib);
        s_up = iv.hi + bb->clear;
        if (s_up <= floor_) return (bound){s_up, s_up};
        s_c = fm_sweep_eval(bb->sweep, bb->worker, c) + bb->clear;
    } else {
        fm_sweep_value v;
        fm_sweep_eval_ex(bb->sweep, bb->worker, c, &v);
        s_up = v.upper + bb->clear + r;
        if (s_up <= floor_) return (bound){s_up, s_up};
        s_c = v.upper + bb->clear;
    }
    /* the target: every term is an upper bound of its distance */
    double f_lip = INFINITY; /* min of the Lipschitz terms at the centre */
    double f_up = INFINITY, f_c = INFINITY;
    if (tg->fixture && tg->fixture->ev) {
        fm_interval b4[4] = {ib[0], ib[1], ib[2], {0, 0}};
        fm_interval iv = fm_eval_interval(tg->fixture->ev, b4);
        /* NaN bounds mean nothing is known */
        f_up = iv.hi == iv.hi ? iv.hi : INFINITY;
        if (fmin(s_up, f_up) <= floor_) return (bound){fmin(s_up, f_up), 0};
        const double p4[4] = {c[0], c[1], c[2], 0};
        double v = fm_eval_point(tg->fixture->ev, p4);
        f_c = v == v ? v : INFINITY;
    }
    if (tg->have_box) {
        f_lip = fmin(f_lip, box_field(tg->box_lo, tg->box_hi, c));
        if (fmin(s_up, fmin(f_up, f_lip + r)) <= floor_) return (bound){fmin(s_up, f_lip + r), 0};
    }
    if (tg->has_grid) {
        f_lip = fmin(f_lip, grid_upper(&tg->grid, c));
        if (fmin(s_up, fmin(f_up, f_lip + r)) <= floor_) return (bound){fmin(s_up, f_lip + r), 0};
    }
    for (size_t i = 0; i < tg->pick_count; i++) {
        const check_history *h = &tg->history[tg->pick[i]];
        int meets = 1;
        for (int a = 0; a < 3; a++)
            if (h->hi[a] < b->lo[a] || h->lo[a] > b->hi[a]) meets = 0;
        if (!meets) continue; /* -S > 0 there: it cannot tighten much */
        fm_sweep_value v;
        fm_sweep_eval_ex(h->sweep, h->worker, c, &v);
        /* v.value is attained, so -v.value >= -S */
        f_lip = fmin(f_lip, -v.value);
        if (fmin(s_up, fmin(f_up, f_lip + r)) <= floor_) return (bound){fmin(s_up, f_lip + r), 0};
    }
    out.upper = fmin(s_up, fmin(f_up, f_lip + r));
    out.centre = fmin(s_c, fmin(f_c, f_lip));
    return out;
}

static int push(fm_check *c, size_t *n, const check_box *b)
{
    if (*n == c->stack_cap) {
        size_t cap = c->stack_cap ? 2 * c->stack_cap : 256;
        check_box *s = realloc(c->stack, cap * sizeof *s);
        if (!s) return 0;
        c->stack = s;
        c->stack_cap = cap;
    }
    c->stack[(*n)++] = *b;
    return 1;
}

static double half_diagonal(const check_box *b)
{
    double r2 = 0;
    for (int a = 0; a < 3; a++) {
        double h = 0.5 * (b->hi[a] - b->lo[a]);
        r2 += h * h;
    }
    return sqrt(r2);
}

static void split(const check_box *b, check_box *l, check_box *h)
{
    int axis = 0;
    for (int a = 1; a < 3; a++)
        if (b->hi[a] - b->lo[a] > b->hi[axis] - b->lo[axis]) axis = a;
    *l = *b;
    *h = *b;
    double mid = 0.5 * (b->lo[axis] + b->hi[axis]);
    l->hi[axis] = mid;
    h->lo[axis] = mid;
}

static void centre_of(const check_box *b, double at[3])
{
    for (int a = 0; a < 3; a++) at[a] = 0.5 * (b->lo[a] + b->hi[a]);
}

/* maximize = 0: stop at the first box whose centre is above 3/4 tol
 * (found), or prove that none is. maximize = 1: the largest centre value,
 * boxes pruned within a quarter of the tolerance of the best. Leaves have a
 * half-diagonal of at most tol/5: a leaf whose upper bound is still above
 * the tolerance is reported, so a maximum above the tolerance is always
 * found (docs/check.md). */
static fm_status run(check_bb *bb, const double lo[3], const double hi[3], int maximize,
                     check_bb_result *out, fm_error *err)
{
    fm_check *c = bb->check;
    memset(out, 0, sizeof *out);
    out->value = -INFINITY;
    const double theta = 0.75 * bb->tol, leaf = 0.2 * bb->tol, slack = 0.25 * bb->tol;
    check_box root;
    for (int a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) return FM_OK;
        root.lo[a] = lo[a];
        root.hi[a] = hi[a];
    }
    size_t n = 0;
    if (!push(c, &n, &root)) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    long boxes = 0;
    while (n > 0) {
        check_box b = c->stack[--n];
        boxes++;
        double floor_ = maximize && out->found ? fmax(theta, out->value + slack) : theta;
        bound v = evaluate(bb, &b, floor_);
        if (v.upper <= floor_) continue;
        if (v.centre > (out->found ? out->value : theta)) {
            out->found = 1;
            out->value = v.centre;
            centre_of(&b, out->at);
            if (!maximize) break;
        }
        if (half_diagonal(&b) <= leaf || boxes >= CHECK_MAX_BOXES) {
            /* cannot be refined (or the budget is spent): an upper bound
             * still above the tolerance is reported, on the safe side */
            if (v.upper > bb->tol && (!out->found || v.upper > out->value)) {
                out->found = 1;
                out->value = v.upper;
                centre_of(&b, out->at);
                if (!maximize) break;
            }
            if (boxes >= CHECK_MAX_BOXES) {
                if (!out->found) {
                    out->found = 1;
                    out->value = fmax(v.upper, bb->tol);
                    centre_of(&b, out->at);
                }
                break;
            }
            continue;
        }
        check_box l, h;
        split(&b, &l, &h);
        if (!push(c, &n, &l) || !push(c, &n, &h))
            return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    c->stats.boxes += boxes;
    return FM_OK;
}

fm_status check_bb_detect(check_bb *bb, const double lo[3], const double hi[3],
                          check_bb_result *out, fm_error *err)
{
    return run(bb, lo, hi, 0, out, err);
}

fm_status check_bb_maximize(check_bb *bb, const double lo[3], const double hi[3],
                            check_bb_result *out, fm_error *err)
{
    return run(bb, lo, hi, 1, out, err);
}

fm_status check_static_detect(check_bb *bb, const fm_motion *m, const fm_tool_part *part, double u,
                              check_bb_result *out, int *found, fm_error *err)
{
    *found = 0;
    double t = m->t0 + u * (m->t1 - m->t0);
    double tip[3], axis[3];
    fm_sweep_pose(bb->sweep, t, tip, axis);
    fm_motion sm;
    memset(&sm, 0, sizeof sm);
    sm.kind = FM_MOTION_RAPID;
    for (int a = 0; a < 3; a++) {
        sm.start[a] = sm.end[a] = tip[a];
        sm.axis_start[a] = sm.axis_end[a] = axis[a];
    }
    sm.t0 = sm.t1 = t;
    sm.line = m->line;
    sm.block = m->block;
    sm.tool = m->tool;
    fm_sweep *s = NULL;
    fm_status st = fm_sweep_new(&sm, part, NULL, &s, err);
    if (st != FM_OK) return st;
    double lo[3], hi[3];
    fm_sweep_bounds(s, lo, hi);
    for (int a = 0; a < 3; a++) {
        lo[a] = fmax(lo[a] - bb->clear, bb->target->lo[a]);
        hi[a] = fmin(hi[a] + bb->clear, bb->target->hi[a]);
    }
    check_bb sb = *bb;
    sb.sweep = s;
    st = run(&sb, lo, hi, 0, out, err);
    fm_sweep_free(s);
    if (st == FM_OK) *found = out->found;
    return st;
}
