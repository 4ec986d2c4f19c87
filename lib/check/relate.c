/* relate.c: one relation of a tool part swept over a motion to a grid (the
 * stock or a fixture), evaluated at the grid's voxel centres, where the
 * grid holds the exact distance of what it stores (clamped to its band).
 * The grid is walked in the blocks the part can reach (lib/stock's
 * fm_stock_visit, blocks pruned by the part's interval); leaves are taken
 * deepest first, so that once a contact is proven the rest is dropped by
 * its value alone; voxels are evaluated cheapest bound first (the grid
 * value, then the part, then the flutes leading it). Depths beyond the band
 * are searched in the grid afterwards. check_internal.h states what Q is;
 * docs/check.md argues what is never reported and what is never missed. */
#include "check/check_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Entry times are bisected to this fraction of the motion (and at most
 * this many steps); non-concave motions are scanned first. */
#define REL_BISECT 48
#define REL_SCAN 32
/* Depths beyond the band are searched this far at most (mm), at most this
 * many times per relation. */
#define REL_DEPTH_MAX_MM 200.0
#define REL_DEPTH_SEARCHES 128
/* Contact voxels clamped at the band kept for the depth search. */
#define REL_DEEP_MAX 65536

static double dist3(const double a[3], const double b[3])
{
    double d2 = 0;
    for (int k = 0; k < 3; k++) d2 += (a[k] - b[k]) * (a[k] - b[k]);
    return sqrt(d2);
}

/* ------------------------------------------------------------- scratch -- */

static int grow(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return 1;
    size_t n = *cap ? 2 * *cap : 64;
    while (n < need) n *= 2;
    void *q = realloc(*p, n * size);
    if (!q) return 0;
    *p = q;
    *cap = n;
    return 1;
}

/* ------------------------------------------------------- the walk -- */

static void block_box(const check_rel *r, const int32_t lo[3], const int32_t hi[3],
                      fm_interval box[3])
{
    for (int k = 0; k < 3; k++) {
        box[k].lo = r->origin[k] + r->voxel * lo[k];
        box[k].hi = r->origin[k] + r->voxel * hi[k];
    }
}

/* A block none of whose voxel centres comes within reach of the part. */
static int part_misses(check_rel *r, const int32_t lo[3], const int32_t hi[3])
{
    fm_interval box[3];
    block_box(r, lo, hi, box);
    fm_interval iv = fm_sweep_interval(r->sweep, r->worker, box);
    return iv.hi < (r->custom ? 0.0 : -r->reach);
}

static int prune_block(void *user, const int32_t lo[3], const int32_t hi[3])
{
    return part_misses(user, lo, hi);
}

static int collect(void *user, const fm_stock_region *reg)
{
    check_rel *r = user;
    fm_check *c = r->check;
    c->stats.regions++;
    if (!reg->values) {
        if (reg->value <= 0) return 0; /* outside by more than the band */
        if (!grow((void **)&c->tiles, &c->tile_cap, c->tile_count + 1, sizeof *c->tiles)) {
            c->scratch_status = FM_ERR_LIMIT;
            return 1;
        }
        check_box *b = &c->tiles[c->tile_count++];
        memcpy(b->lo, reg->lo, sizeof b->lo);
        memcpy(b->hi, reg->hi, sizeof b->hi);
        return 0;
    }
    float mx = -FLT_MAX;
    for (int i = 0; i < 512; i++)
        if (reg->values[i] > mx) mx = reg->values[i];
    /* Q <= G: a leaf no deeper than the threshold holds no contact */
    if (mx <= r->threshold) return 0;
    if (!grow((void **)&c->leaves, &c->leaf_cap, c->leaf_count + 1, sizeof *c->leaves)) {
        c->scratch_status = FM_ERR_LIMIT;
        return 1;
    }
    check_leaf *l = &c->leaves[c->leaf_count++];
    memcpy(l->lo, reg->lo, sizeof l->lo);
    l->max = mx;
    memcpy(l->values, reg->values, sizeof l->values);
    return 0;
}

static int deeper_first(const void *a, const void *b)
{
    float x = ((const check_leaf *)a)->max, y = ((const check_leaf *)b)->max;
    return (x < y) - (x > y);
}

/* ------------------------------------------------------- one voxel -- */

/* What Q must exceed for a voxel to matter now: the threshold until a
 * contact is proven, then whatever depth is already known (the finding's
 * first contact needs every contact). */
static double cut_level(const check_rel *r)
{
    if (r->need_first || !r->found) return r->threshold;
    return fmax(r->threshold, fmax(r->depth, r->known));
}

/* A motion along which a part's value at a fixed point rises then falls
 * (a convex part on a line with a fixed axis): its entry can be bisected. */
static int unimodal(const fm_sweep *s)
{
    fm_sweep_method m = fm_sweep_method_of(s);
    return m == FM_SWEEP_PLANAR_LINE || m == FM_SWEEP_CAPSULE || m == FM_SWEEP_CONCAVE ||
           m == FM_SWEEP_STATIC;
}

/* The tip's path length over the motion (an upper bound for arcs whose
 * radius changes); 0 when it is not known (parametric paths, rotary
 * axes). */
static double path_length(const fm_motion *m)
{
    double d2 = 0;
    for (int k = 0; k < 3; k++) d2 += (m->end[k] - m->start[k]) * (m->end[k] - m->start[k]);
    if (m->kind == FM_MOTION_ARC) {
        double r0, a0;
        int ccw;
        double ang = check_arc_angle(m, &r0, &a0, &ccw);
        int p = m->plane_axis, i = (p + 1) % 3, j = (p + 2) % 3;
        double r1 = hypot(m->end[i] - m->center[i], m->end[j] - m->center[j]);
        return fmax(r0, r1) * ang + fabs(r1 - r0) + fabs(m->end[p] - m->start[p]);
    }
    if (m->kind == FM_MOTION_PARAM || fm_motion_has_rotary(m)) return 0;
    return sqrt(d2);
}

/* The first parameter u in [0, u_max] where the part's value at p reaches
 * level, given that it does at u_max: bisected from the last scanned u
 * where it does not.
 * Where the motion is not unimodal a scan finds the first piece that holds
 * p; an earlier piece between two scanned points may be missed, which only
 * makes the time later, and a later time never adds a contact (the flutes'
 * sweep only grows). */
static double entry_u(const check_rel *r, const double p[3], double u_max, double level)
{
    const fm_sweep *s = r->sweep;
    if (fm_sweep_tool_at_u(s, r->worker, p, 0) >= level) return 0;
    double lo = 0, hi = u_max;
    if (!unimodal(s)) {
        for (int k = 1; k <= REL_SCAN; k++) {
            double u = u_max * k / REL_SCAN;
            if (fm_sweep_tool_at_u(s, r->worker, p, u) >= level) {
                hi = u;
                break;
            }
            lo = u;
        }
    }
    /* to a tenth of the tolerance in path length: the tip moves no farther
     * in the time left, so the flutes' sweep and the first contact are off
     * by no more (a parametric path's length is not known: to the end of
     * the bisection) */
    double len = path_length(r->motion);
    double want = len > 0 ? 0.1 * r->check->opt.tolerance_mm / len : 0;
    for (int i = 0; i < REL_BISECT && hi - lo > want; i++) {
        double mid = 0.5 * (lo + hi);
        if (fm_sweep_tool_at_u(s, r->worker, p, mid) >= level) hi = mid;
        else lo = mid;
    }
    return hi;
}

static double u_of_t(const check_rel *r, double t)
{
    const fm_motion *m = r->motion;
    if (!(m->t1 > m->t0)) return 1; /* no duration: the whole sweep at once */
    double u = (t - m->t0) / (m->t1 - m->t0);
    return u < 0 ? 0 : u > 1 ? 1 : u;
}

static double t_of_u(const check_rel *r, double u)
{
    const fm_motion *m = r->motion;
    return m->t0 + u * (m->t1 - m->t0);
}

/* An upper bound of the flutes' sweep over [t0, t(u)] at p. */
static fm_status flutes_until(check_rel *r, const double p[3], double u, fm_sweep_value *out,
                              fm_error *err)
{
    fm_motion sub;
    check_motion_prefix(r->motion, u, &sub);
    fm_sweep *s = NULL;
    fm_status st = fm_sweep_new(&sub, r->flutes_shape, check_sweep_options(r->check), &s, err);
    if (st != FM_OK) return st;
    fm_sweep_eval_ex(s, r->flutes_worker, p, out);
    fm_sweep_free(s);
    return FM_OK;
}

static void record_uncertain(check_rel *r, const double p[3], double t)
{
    if (r->uncertain++ == 0) {
        memcpy(r->uncertain_at, p, sizeof r->uncertain_at);
        r->uncertain_t = t;
    }
}

static fm_status eval_voxel(check_rel *r, const double p[3], double g, int deep, fm_error *err)
{
    fm_check *c = r->check;
    double cut = cut_level(r);
    /* the grid less the flutes not yet cut: [gb_lo, gb_hi] holds it */
    double gb_lo = g, gb_hi = deep ? INFINITY : g, cap_lo = INFINITY;
    int exhausted = 0;
    if (r->is_stock) {
        if (c->have_box && deep) {
            double f = INFINITY;
            for (int k = 0; k < 3; k++)
                f = fmin(f, fmin(p[k] - c->box_lo[k], c->box_hi[k] - p[k]));
            gb_hi = fmin(gb_hi, f);
        }
        for (size_t j = 0; j < c->pending_count; j++) {
            const check_pending *pd = &c->pending[j];
            /* outside its box by d, -S >= d: no tighter than what is known */
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                double e = fmax(pd->lo[k] - p[k], p[k] - pd->hi[k]);
                if (e > 0) d2 += e * e;
            }
            if (d2 > 0 && sqrt(d2) >= gb_hi) continue;
            fm_sweep_value v;
            fm_sweep_eval_ex(pd->sweep, pd->worker, p, &v);
            exhausted |= v.exhausted;
            gb_hi = fmin(gb_hi, -v.value);
            gb_lo = fmin(gb_lo, -v.upper);
            cap_lo = fmin(cap_lo, -v.upper);
        }
    }
    if (gb_hi <= cut) return FM_OK;
    fm_sweep_value s;
    fm_sweep_eval_ex(r->sweep, r->worker, p, &s);
    exhausted |= s.exhausted;
    double q_hi, q_lo, part_lo, t_at = s.t;
    if (r->custom) {
        q_hi = s.upper >= 0 ? gb_hi : -INFINITY;
        part_lo = s.value >= 0 ? 0 : -INFINITY;
    } else {
        q_hi = gb_hi + fmin(0, s.upper);
        part_lo = fmin(0, s.value);
    }
    if (q_hi <= cut) return FM_OK;
    c->stats.voxels++;
    int inside = s.value >= 0;
    double u_at = u_of_t(r, s.t);
    if (r->flutes) {
        fm_sweep_value f;
        fm_sweep_eval_ex(r->flutes, r->flutes_worker, p, &f);
        exhausted |= f.exhausted;
        /* The flutes of this motion come no nearer than -f.upper: where that
         * is beyond the stock's own depth, time order changes nothing. */
        if (-f.upper < gb_hi) {
            c->stats.ordered++;
            if (inside) {
                u_at = entry_u(r, p, u_at, 0);
            }
            t_at = t_of_u(r, u_at);
            fm_sweep_value m;
            fm_status st = flutes_until(r, p, u_at, &m, err);
            if (st != FM_OK) return st;
            exhausted |= m.exhausted;
            gb_lo = fmin(gb_lo, -m.upper);
            cap_lo = fmin(cap_lo, -m.upper);
        }
    }
    q_lo = gb_lo + part_lo;
    if (!(q_lo > r->threshold)) {
        if (exhausted && q_hi > r->threshold) record_uncertain(r, p, t_at);
        return FM_OK;
    }
    /* a contact (or a near miss within the clearance) */
    r->found = 1;
    if (q_lo > r->depth) {
        r->depth = q_lo;
        memcpy(r->depth_at, p, sizeof r->depth_at);
        r->depth_t = t_at;
    }
    if (r->need_first) {
        /* The first time the same proof holds: the part's value reaching
         * threshold - the stock's term (that term only grows earlier, as
         * the flutes' sweep shrinks). */
        double level = r->custom ? 0 : r->threshold - gb_lo;
        double tc = t_of_u(r, entry_u(r, p, u_at, level));
        if (tc < r->first_t) {
            r->first_t = tc;
            memcpy(r->first_at, p, sizeof r->first_at);
        }
    }
    /* clamped by the band (and not by an exact term): deeper than it says */
    if (deep && gb_lo >= g && c->deep_count < REL_DEEP_MAX) {
        if (!grow((void **)&c->deep, &c->deep_cap, c->deep_count + 1, sizeof *c->deep))
            return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        check_deep *d = &c->deep[c->deep_count++];
        memcpy(d->p, p, sizeof d->p);
        d->cap = cap_lo;
        d->part = part_lo;
        d->t = t_at;
    }
    return FM_OK;
}

/* ----------------------------------------------------------- blocks -- */

/* Voxels of an 8^3 leaf (values given) or of a block inside a tile
 * (values NULL: every voxel at the band), clipped to [clo, chi], by 4^3
 * octants the part can reach. */
static fm_status eval_block(check_rel *r, const int32_t lo[3], const float *values,
                            const int32_t clo[3], const int32_t chi[3], fm_error *err)
{
    for (int oct = 0; oct < 8; oct++) {
        int32_t olo[3] = {lo[0] + ((oct & 4) ? 4 : 0), lo[1] + ((oct & 2) ? 4 : 0),
                          lo[2] + ((oct & 1) ? 4 : 0)};
        int32_t ohi[3];
        int empty = 0;
        for (int k = 0; k < 3; k++) {
            ohi[k] = olo[k] + 3;
            if (ohi[k] < clo[k] || olo[k] > chi[k]) empty = 1;
        }
        if (empty) continue;
        if (values) {
            float mx = -FLT_MAX;
            for (int k = 0; k < 64; k++) {
                int x = olo[0] - lo[0] + (k >> 4), y = olo[1] - lo[1] + ((k >> 2) & 3),
                    z = olo[2] - lo[2] + (k & 3);
                float v = values[64 * x + 8 * y + z];
                if (v > mx) mx = v;
            }
            if (mx <= cut_level(r)) continue;
        }
        if (part_misses(r, olo, ohi)) continue;
        for (int k = 0; k < 64; k++) {
            int32_t ijk[3] = {olo[0] + (k >> 4), olo[1] + ((k >> 2) & 3), olo[2] + (k & 3)};
            if (ijk[0] < clo[0] || ijk[0] > chi[0] || ijk[1] < clo[1] || ijk[1] > chi[1] ||
                ijk[2] < clo[2] || ijk[2] > chi[2])
                continue;
            double g = values ? values[64 * (ijk[0] - lo[0]) + 8 * (ijk[1] - lo[1]) +
                                       (ijk[2] - lo[2])]
                              : r->band;
            if (g <= cut_level(r)) continue;
            double p[3];
            for (int a = 0; a < 3; a++) p[a] = r->origin[a] + r->voxel * ijk[a];
            fm_status st = eval_voxel(r, p, g, g >= r->band * (1 - 1e-6), err);
            if (st != FM_OK) return st;
        }
    }
    return FM_OK;
}

/* An inside tile, clipped to the relation's box, in 8^3 blocks. */
static fm_status eval_tile(check_rel *r, const check_box *t, const int32_t clo[3],
                           const int32_t chi[3], fm_error *err)
{
    int32_t lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = t->lo[k] > clo[k] ? t->lo[k] : clo[k];
        hi[k] = t->hi[k] < chi[k] ? t->hi[k] : chi[k];
        if (lo[k] > hi[k]) return FM_OK;
        lo[k] &= ~7;
    }
    for (int32_t x = lo[0]; x <= hi[0]; x += 8)
        for (int32_t y = lo[1]; y <= hi[1]; y += 8)
            for (int32_t z = lo[2]; z <= hi[2]; z += 8) {
                int32_t blo[3] = {x, y, z}, bhi[3] = {x + 7, y + 7, z + 7};
                if (part_misses(r, blo, bhi)) continue;
                int32_t c2lo[3], c2hi[3];
                for (int k = 0; k < 3; k++) {
                    c2lo[k] = clo[k] > t->lo[k] ? clo[k] : t->lo[k];
                    c2hi[k] = chi[k] < t->hi[k] ? chi[k] : t->hi[k];
                }
                fm_status st = eval_block(r, blo, NULL, c2lo, c2hi, err);
                if (st != FM_OK) return st;
            }
    return FM_OK;
}

/* ------------------------------------------------------- depth search -- */

/* Contacts clamped at the band: how deep they really are. The depth of a
 * voxel is at most min(search, exact terms) + its part term, and the
 * search's answer is 1-Lipschitz, so points near one already searched are
 * bounded by it without a search of their own; a motion needs no depth it
 * cannot raise above what is known (by half the tolerance). When the
 * searches run out, the depth is still known within a voxel if no point
 * left can exceed it by more; otherwise the point counts as uncertain. */
static int higher_bound_first(const void *a, const void *b)
{
    const check_deep *x = a, *y = b;
    double u = x->cap + x->part, v = y->cap + y->part;
    return (u < v) - (u > v);
}

static fm_status depth_search(check_rel *r, fm_error *err)
{
    fm_check *c = r->check;
    double kp[REL_DEPTH_SEARCHES][3], kv[REL_DEPTH_SEARCHES];
    int nk = 0;
    /* the initial box bounds the depth from above */
    for (size_t i = 0; i < c->deep_count; i++) {
        check_deep *d = &c->deep[i];
        if (r->is_stock && c->have_box)
            for (int k = 0; k < 3; k++)
                d->cap = fmin(d->cap, fmin(d->p[k] - c->box_lo[k], c->box_hi[k] - d->p[k]));
    }
    qsort(c->deep, c->deep_count, sizeof *c->deep, higher_bound_first);
    for (size_t i = 0; i < c->deep_count; i++) {
        const check_deep *d = &c->deep[i];
        double enough = fmax(r->depth, r->known) + 0.5 * c->opt.tolerance_mm;
        if (d->cap + d->part <= enough) break; /* sorted: none later can either */
        double ub = d->cap;
        for (int k = 0; k < nk; k++) ub = fmin(ub, kv[k] + dist3(kp[k], d->p));
        if (ub + d->part <= enough) continue;
        if (nk == REL_DEPTH_SEARCHES) {
            if (ub + d->part > fmax(r->depth, r->known) + r->voxel) {
                /* the depth may be larger than reported by more than a voxel */
                record_uncertain(r, d->p, d->t);
                break;
            }
            continue;
        }
        /* a small ball first: most depths are a few bands */
        double limit = fmin(ub, 4 * r->band), g;
        for (;;) {
            g = check_grid_depth(c, r->grid, d->p, limit, err);
            if (g != g) return err ? err->code : FM_ERR_INTERNAL;
            c->stats.depth_searches++;
            if (g < limit || limit >= fmin(ub, REL_DEPTH_MAX_MM)) break;
            limit = fmin(fmin(ub, REL_DEPTH_MAX_MM), 4 * limit);
        }
        if (g >= REL_DEPTH_MAX_MM) record_uncertain(r, d->p, d->t);
        memcpy(kp[nk], d->p, sizeof kp[nk]);
        kv[nk++] = g;
        double q = fmin(g, d->cap) + d->part;
        if (q > r->depth) {
            r->depth = q;
            memcpy(r->depth_at, d->p, sizeof r->depth_at);
            r->depth_t = d->t;
        }
    }
    return FM_OK;
}

typedef struct depth_ctx {
    const double *p;
    double best, voxel, band, origin[3];
} depth_ctx;

static double box_distance(const depth_ctx *d, const int32_t lo[3], const int32_t hi[3])
{
    double e2 = 0;
    for (int k = 0; k < 3; k++) {
        double a = d->origin[k] + d->voxel * lo[k], b = d->origin[k] + d->voxel * hi[k];
        double e = fmax(a - d->p[k], d->p[k] - b);
        if (e > 0) e2 += e * e;
    }
    return sqrt(e2);
}

static int depth_prune(void *user, const int32_t lo[3], const int32_t hi[3])
{
    depth_ctx *d = user;
    return box_distance(d, lo, hi) - d->band >= d->best;
}

static int depth_visit(void *user, const fm_stock_region *reg)
{
    depth_ctx *d = user;
    if (!reg->values) {
        /* an outside tile: G <= -band at every voxel centre of it */
        if (reg->value < 0) d->best = fmin(d->best, box_distance(d, reg->lo, reg->hi) - d->band);
        return 0;
    }
    const float limit = (float)(d->band * (1 - 1e-6));
    for (int i = 0; i < 512; i++) {
        float g = reg->values[i];
        /* a clamped inside value only says "at least the band" */
        if (g >= limit) continue;
        double u[3] = {d->origin[0] + d->voxel * (reg->lo[0] + (i >> 6)),
                       d->origin[1] + d->voxel * (reg->lo[1] + ((i >> 3) & 7)),
                       d->origin[2] + d->voxel * (reg->lo[2] + (i & 7))};
        double e = dist3(u, d->p) + g;
        if (e < d->best) d->best = e;
    }
    return 0;
}

double check_grid_depth(fm_check *c, const fm_stock *grid, const double p[3], double limit,
                        fm_error *err)
{
    (void)c;
    depth_ctx d;
    d.p = p;
    d.best = limit;
    d.voxel = fm_stock_voxel_size(grid);
    d.band = fm_stock_band_voxels(grid) * d.voxel;
    const double zero[3] = {0, 0, 0};
    fm_stock_index_to_world(grid, zero, d.origin);
    int32_t lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        double a = floor((p[k] - limit - d.band - d.origin[k]) / d.voxel);
        double b = ceil((p[k] + limit + d.band - d.origin[k]) / d.voxel);
        lo[k] = (int32_t)fmax(a, -(double)(1 << 28));
        hi[k] = (int32_t)fmin(b, (double)(1 << 28));
    }
    if (fm_stock_visit(grid, lo, hi, depth_prune, depth_visit, &d, err) != FM_OK) return NAN;
    return d.best;
}

/* ------------------------------------------------------------ relate -- */

/* The voxel that proved the first contact may lie inside the stock, off
 * the part: the contact is the part's point nearest to it then, a step of
 * -P along the part's gradient (central differences; the part is a
 * distance, so the step lands on its surface). */
static void first_contact_point(check_rel *r)
{
    double u = u_of_t(r, r->first_t), *p = r->first_at;
    double v = fm_sweep_tool_at_u(r->sweep, r->worker, p, u);
    if (!(v < 0)) return;
    double g[3], n2 = 0, e = 1e-4 * fmax(r->voxel, 1e-3);
    for (int k = 0; k < 3; k++) {
        double a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
        a[k] += e;
        b[k] -= e;
        g[k] = (fm_sweep_tool_at_u(r->sweep, r->worker, a, u) -
                fm_sweep_tool_at_u(r->sweep, r->worker, b, u)) / (2 * e);
        n2 += g[k] * g[k];
    }
    if (!(n2 > 0)) return;
    double step = -v / sqrt(n2);
    for (int k = 0; k < 3; k++) p[k] += step * g[k] / sqrt(n2);
}

fm_status check_relate(check_rel *r, fm_error *err)
{
    fm_check *c = r->check;
    c->stats.relations++;
    r->found = 0;
    r->depth = -INFINITY;
    r->first_t = INFINITY;
    r->uncertain = 0;
    r->voxel = fm_stock_voxel_size(r->grid);
    r->band = fm_stock_band_voxels(r->grid) * r->voxel;
    const double zero[3] = {0, 0, 0};
    fm_stock_index_to_world(r->grid, zero, r->origin);
    double lo[3], hi[3];
    fm_sweep_bounds(r->sweep, lo, hi);
    int32_t ilo[3], ihi[3];
    for (int k = 0; k < 3; k++) {
        double a = floor((lo[k] - r->reach - r->origin[k]) / r->voxel);
        double b = ceil((hi[k] + r->reach - r->origin[k]) / r->voxel);
        if (!(a <= b)) {
            c->stats.skipped++;
            return FM_OK;
        }
        ilo[k] = (int32_t)fmax(a, -(double)(1 << 28));
        ihi[k] = (int32_t)fmin(b, (double)(1 << 28));
    }
    c->leaf_count = c->tile_count = c->deep_count = 0;
    c->scratch_status = FM_OK;
    fm_status st = fm_stock_visit(r->grid, ilo, ihi, prune_block, collect, r, err);
    if (st != FM_OK) return st;
    if (c->scratch_status != FM_OK) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    if (c->leaf_count == 0 && c->tile_count == 0) {
        c->stats.skipped++;
        return FM_OK;
    }
    /* Inside tiles hold the deepest voxels; then leaves, deepest first. */
    for (size_t i = 0; i < c->tile_count; i++) {
        st = eval_tile(r, &c->tiles[i], ilo, ihi, err);
        if (st != FM_OK) return st;
    }
    qsort(c->leaves, c->leaf_count, sizeof *c->leaves, deeper_first);
    for (size_t i = 0; i < c->leaf_count; i++) {
        const check_leaf *l = &c->leaves[i];
        if (l->max <= cut_level(r)) break;
        st = eval_block(r, l->lo, l->values, ilo, ihi, err);
        if (st != FM_OK) return st;
    }
    if (r->need_first && r->found && !r->custom) first_contact_point(r);
    if (r->found && c->deep_count) return depth_search(r, err);
    return FM_OK;
}
