/* field.c: sweeps as fm_field (frep.h) for lib/stock: one motion, or the
 * max of S over a run of consecutive motions, with per-motion box culling
 * (S_i <= -distance to its box, so a motion whose box is farther than the
 * best value so far cannot win). */
#include "sweep/sweep_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct many_ctx {
    size_t n;
    fm_sweep **sweeps;
} many_ctx;

static void *many_worker_new(void *ctx)
{
    many_ctx *c = ctx;
    return fm_sweep_worker_new(c->sweeps[0]);
}

static void many_worker_free(void *ctx, void *worker)
{
    (void)ctx;
    fm_sweep_worker_free(worker);
}

/* Distance from p to the box [lo, hi] (0 inside). */
static double box_dist(const double p[3], const double lo[3], const double hi[3])
{
    double d2 = 0;
    for (int i = 0; i < 3; i++) {
        double e = p[i] < lo[i] ? lo[i] - p[i] : p[i] > hi[i] ? p[i] - hi[i] : 0;
        d2 += e * e;
    }
    return sqrt(d2);
}

/* Below this many sweeps the per-call ordering costs more than it saves. */
#define MANY_ORDER_MIN 3

typedef struct many_rank {
    double up; /* proven upper bound of S_i at the centre of the points' box */
    size_t i;
} many_rank;

static int rank_by_up_desc(const void *a, const void *b)
{
    double x = ((const many_rank *)a)->up, y = ((const many_rank *)b)->up;
    return x > y ? -1 : x < y ? 1 : 0;
}

/* Points per many_eval block: the scratch arrays stay on the stack. */
#define MANY_BLOCK 256

/* Scratch for one block of points. */
typedef struct many_scratch {
    double px[MANY_BLOCK], py[MANY_BLOCK], pz[MANY_BLOCK], vals[MANY_BLOCK], sf[MANY_BLOCK];
} many_scratch;

/* Fold sweep s's values at the points idx[0..m) (m <= MANY_BLOCK) into
 * best, and where its search stopped short, value + shortfall into top. */
static void fold(const fm_sweep *s, void *worker, size_t m, const size_t *idx, const double *x, const double *y,
                 const double *z, double *best, double *top, int want_shortfall, int *any_short, many_scratch *t)
{
    for (size_t q = 0; q < m; q++) {
        t->px[q] = x[idx[q]];
        t->py[q] = y[idx[q]];
        t->pz[q] = z[idx[q]];
    }
    fm_sweep_batch_ex(s, worker, m, t->px, t->py, t->pz, t->vals, want_shortfall ? t->sf : NULL);
    for (size_t q = 0; q < m; q++) {
        const size_t k = idx[q];
        if (t->vals[q] > best[k]) best[k] = t->vals[q];
        if (want_shortfall && t->sf[q] > 0) {
            *any_short = 1;
            if (t->vals[q] + t->sf[q] > top[k]) top[k] = t->vals[q] + t->sf[q];
        }
    }
}

/* max over sweeps of S_i at n points; shortfall (may be NULL) as in
 * fm_sweep_batch_ex: how much the maximum may exceed out[k] because a
 * sweep's search stopped at its budget there. */
static void many_eval(void *ctx, void *worker, size_t n, const double *x, const double *y, const double *z,
                      double *out, double *shortfall)
{
    many_ctx *c = ctx;
    if (n == 0) return;
    if (c->n == 1) {
        fm_sweep_batch_ex(c->sweeps[0], worker, n, x, y, z, out, shortfall);
        return;
    }
    /* Points in blocks: the scratch arrays stay on the stack. */
    enum { BLOCK = MANY_BLOCK };
    if (n > BLOCK) {
        for (size_t b = 0; b < n; b += BLOCK)
            many_eval(ctx, worker, n - b < BLOCK ? n - b : BLOCK, x + b, y + b, z ? z + b : NULL, out + b,
                      shortfall ? shortfall + b : NULL);
        return;
    }
    double zeros[BLOCK];
    if (!z) {
        memset(zeros, 0, sizeof zeros);
        z = zeros;
    }
    double best[BLOCK], top[BLOCK];
    many_scratch scratch;
    int any_short = 0;
    for (size_t k = 0; k < n; k++) best[k] = top[k] = -DBL_MAX;
    size_t idx[BLOCK];
    for (size_t k = 0; k < n; k++) idx[k] = k;
    if (c->n < MANY_ORDER_MIN) {
        for (size_t i = 0; i < c->n; i++) fold(c->sweeps[i], worker, n, idx, x, y, z, best, top, shortfall != NULL, &any_short, &scratch);
    } else {
        /* Each S_i is 1-Lipschitz (max of exact distances; for custom
         * parts the interval of the points' box stands in), so with q the
         * centre of the points' box, S_i(p) <= U_i + |p - q| where U_i
         * bounds S_i(q), and S(p) >= L = max_i of the lower ends over the
         * box. Sweeps whose bound stays below L anywhere in the box never
         * win; the rest, tried in decreasing U_i, stop at a point as soon
         * as U_i + |p - q| cannot beat the best value found there. The
         * result is the same max. */
        double lo[3] = {x[0], y[0], z[0]}, hi[3] = {x[0], y[0], z[0]};
        for (size_t k = 1; k < n; k++) {
            const double p[3] = {x[k], y[k], z[k]};
            for (int a = 0; a < 3; a++) {
                if (p[a] < lo[a]) lo[a] = p[a];
                if (p[a] > hi[a]) hi[a] = p[a];
            }
        }
        fm_interval box[3];
        double q[3], hd2 = 0;
        for (int a = 0; a < 3; a++) {
            box[a].lo = lo[a];
            box[a].hi = hi[a];
            q[a] = 0.5 * (lo[a] + hi[a]);
            hd2 += 0.25 * (hi[a] - lo[a]) * (hi[a] - lo[a]);
        }
        double hd = sqrt(hd2);
        int lipschitz = c->sweeps[0]->part.kind == FM_TOOL_PART_PROFILE;
        many_rank stack_rank[64];
        many_rank *rank = c->n <= 64 ? stack_rank : malloc(c->n * sizeof *rank);
        if (!rank) {
            /* No memory for the ordering: every sweep at every point. */
            for (size_t i = 0; i < c->n; i++) fold(c->sweeps[i], worker, n, idx, x, y, z, best, top, shortfall != NULL, &any_short, &scratch);
        } else {
            double L = -DBL_MAX;
            size_t m = 0;
            for (size_t i = 0; i < c->n; i++) {
                const fm_sweep *s = c->sweeps[i];
                double up, low;
                if (lipschitz) {
                    /* S_i <= -dist(p, box_i): far from its box, the box
                     * alone bounds it and it needs no evaluation. */
                    double bd = box_dist(q, s->lo, s->hi);
                    if (bd > hd && -(bd - hd) < L) continue;
                    fm_sweep_value v;
                    fm_sweep_eval_ex(s, worker, q, &v);
                    up = v.upper;
                    if (bd > 0 && -bd < up) up = -bd;
                    low = v.value - hd;
                } else {
                    fm_interval iv = fm_sweep_interval(s, worker, box);
                    up = iv.hi;
                    low = iv.lo;
                }
                if (low > L) L = low;
                rank[m].up = up;
                rank[m].i = i;
                m++;
            }
            qsort(rank, m, sizeof *rank, rank_by_up_desc);
            double reach[BLOCK];
            for (size_t k = 0; k < n; k++) {
                const double e[3] = {x[k] - q[0], y[k] - q[1], z[k] - q[2]};
                reach[k] = lipschitz ? sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) : 0;
            }
            size_t na = n;
            for (size_t j = 0; j < m && na > 0; j++) {
                /* the points where sweep j may still win; a point dropped
                 * here is dropped for every later (lower) sweep too */
                size_t keep = 0;
                for (size_t t = 0; t < na; t++) {
                    const size_t k = idx[t];
                    const double reachable = rank[j].up + reach[k];
                    if (!(reachable < L) && reachable > best[k]) idx[keep++] = k;
                }
                na = keep;
                if (na) fold(c->sweeps[rank[j].i], worker, na, idx, x, y, z, best, top, shortfall != NULL, &any_short, &scratch);
            }
            if (rank != stack_rank) free(rank);
        }
    }
    for (size_t k = 0; k < n; k++) out[k] = best[k];
    if (shortfall)
        for (size_t k = 0; k < n; k++) shortfall[k] = any_short && top[k] > best[k] ? top[k] - best[k] : 0;
}

static void many_batch(void *ctx, void *worker, size_t n, const double *x, const double *y, const double *z,
                       double *out)
{
    many_eval(ctx, worker, n, x, y, z, out, NULL);
}

static void many_batch_shortfall(void *ctx, void *worker, size_t n, const double *x, const double *y,
                                 const double *z, double *out, double *shortfall)
{
    many_eval(ctx, worker, n, x, y, z, out, shortfall);
}

static fm_interval many_interval(void *ctx, void *worker, const fm_interval box[3])
{
    many_ctx *c = ctx;
    fm_interval out = {-DBL_MAX, -DBL_MAX};
    for (size_t i = 0; i < c->n; i++) {
        const fm_sweep *s = c->sweeps[i];
        /* Distance between the query box and the sweep's box bounds S_i
         * from above over the whole query box. */
        double d2 = 0;
        for (int a = 0; a < 3; a++) {
            double e = box[a].hi < s->lo[a] ? s->lo[a] - box[a].hi : box[a].lo > s->hi[a] ? box[a].lo - s->hi[a] : 0;
            d2 += e * e;
        }
        double cap = d2 > 0 ? -sqrt(d2) : DBL_MAX;
        /* S_i <= cap over the query box: when that is below the current
         * upper end, S_i cannot move either end (its lower bound is below
         * cap too). */
        if (cap <= out.hi && out.hi > -DBL_MAX) continue;
        fm_interval v = fm_sweep_interval(s, worker, box);
        if (v.hi > cap) v.hi = cap;
        if (v.lo > v.hi) v.lo = v.hi;
        if (v.lo > out.lo) out.lo = v.lo;
        if (v.hi > out.hi) out.hi = v.hi;
    }
    if (out.hi < out.lo) out.hi = out.lo;
    return out;
}

static void many_release(void *ctx)
{
    many_ctx *c = ctx;
    if (!c) return;
    for (size_t i = 0; i < c->n; i++) fm_sweep_free(c->sweeps[i]);
    free(c->sweeps);
    free(c);
}

fm_status fm_sweep_field_many_ex(fm_field *field, const fm_motion *motions, size_t n, const fm_tool_part *part,
                                 const fm_sweep_options *options, fm_error *err)
{
    memset(field, 0, sizeof *field);
    if (n == 0) return fm_error_set(err, FM_ERR_INTERNAL, "sweep field: no motions");
    many_ctx *c = calloc(1, sizeof *c);
    size_t bytes;
    if (!c || !fm_size_mul(n, sizeof *c->sweeps, &bytes) || !(c->sweeps = calloc(n, sizeof *c->sweeps))) {
        free(c);
        return fm_error_set(err, FM_ERR_LIMIT, "sweep field: out of memory for %zu motions", n);
    }
    for (size_t i = 0; i < n; i++) {
        if (motions[i].kind == FM_MOTION_DWELL && n > 1) continue;
        fm_status st = fm_sweep_new(&motions[i], part, options, &c->sweeps[c->n], err);
        if (st != FM_OK) {
            many_release(c);
            return st;
        }
        c->n++;
    }
    if (c->n == 0) { /* only dwells: the tool at rest still occupies its place */
        fm_status st = fm_sweep_new(&motions[0], part, options, &c->sweeps[0], err);
        if (st != FM_OK) {
            many_release(c);
            return st;
        }
        c->n = 1;
    }
    for (int a = 0; a < 3; a++) {
        field->lo[a] = DBL_MAX;
        field->hi[a] = -DBL_MAX;
    }
    for (size_t i = 0; i < c->n; i++)
        for (int a = 0; a < 3; a++) {
            field->lo[a] = fmin(field->lo[a], c->sweeps[i]->lo[a]);
            field->hi[a] = fmax(field->hi[a], c->sweeps[i]->hi[a]);
        }
    /* Each profile sweep is a max of the part's exact signed distances,
     * so at most the distance to the union's boundary, which lies inside
     * the union of the motions' boxes. Custom parts are not distances. */
    field->within_box = c->sweeps[0]->part.kind == FM_TOOL_PART_PROFILE;
    field->ctx = c;
    field->worker_new = many_worker_new;
    field->worker_free = many_worker_free;
    field->batch = many_batch;
    field->batch_shortfall = many_batch_shortfall;
    field->interval = many_interval;
    field->release = many_release;
    return FM_OK;
}

fm_status fm_sweep_field_many(fm_field *field, const fm_motion *motions, size_t n, const fm_tool_part *part,
                              fm_error *err)
{
    return fm_sweep_field_many_ex(field, motions, n, part, NULL, err);
}

fm_status fm_sweep_field(fm_field *field, const fm_motion *motion, const fm_tool_part *part, fm_error *err)
{
    return fm_sweep_field_many(field, motion, 1, part, err);
}
