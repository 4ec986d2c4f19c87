/* field.c: an fm_field (the 3D scalar field lib/stock rasterizes) over a
 * compiled tape at a fixed time. Each worker thread owns an fm_evaluator.
 * The field is the tape's function intersected (min) with the exact signed
 * distance of the bounds box, so that it is negative outside [lo, hi] by at
 * least the distance to the box, as fm_field promises. */
#include "frep/tape_internal.h"

#include <stdlib.h>

typedef struct field_ctx {
    const fm_tape *tape;
    double t;
    double lo[3], hi[3];
} field_ctx;

typedef struct field_worker {
    fm_evaluator *ev;
    double tbuf[FM_CHUNK];
} field_worker;

/* Exact signed distance to the box, positive inside. */
static double box_distance(const field_ctx *c, double x, double y, double z)
{
    double p[3] = {x, y, z}, out2 = 0, in = INFINITY;
    for (int i = 0; i < 3; i++) {
        double below = c->lo[i] - p[i], above = p[i] - c->hi[i];
        double d = below > above ? below : above; /* > 0 outside this slab */
        if (d > 0) out2 += d * d;
        if (-d < in) in = -d;
    }
    return out2 > 0 ? -sqrt(out2) : in;
}

static void *worker_new(void *ctx)
{
    field_ctx *c = ctx;
    field_worker *w = malloc(sizeof *w);
    if (!w) return NULL;
    w->ev = fm_evaluator_new(c->tape, NULL);
    if (!w->ev) {
        free(w);
        return NULL;
    }
    for (size_t i = 0; i < FM_CHUNK; i++) w->tbuf[i] = c->t;
    return w;
}

static void worker_free(void *ctx, void *worker)
{
    (void)ctx;
    field_worker *w = worker;
    if (!w) return;
    fm_evaluator_free(w->ev);
    free(w);
}

static void batch(void *ctx, void *worker, size_t n, const double *x, const double *y,
                  const double *z, double *out)
{
    field_ctx *c = ctx;
    field_worker *w = worker;
    for (size_t start = 0; start < n; start += FM_CHUNK) {
        size_t m = n - start < FM_CHUNK ? n - start : FM_CHUNK;
        fm_eval_batch(w->ev, m, x + start, y + start, z + start, w->tbuf, out + start);
        for (size_t i = start; i < start + m; i++) {
            double b = box_distance(c, x[i], y[i], z[i]);
            if (!(out[i] < b)) out[i] = b; /* NaN becomes the box distance */
        }
    }
}

static fm_interval interval(void *ctx, void *worker, const fm_interval box[3])
{
    field_ctx *c = ctx;
    field_worker *w = worker;
    fm_interval b4[4] = {box[0], box[1], box[2], {c->t, c->t}};
    int maybe_nan = 0;
    fm_interval f = fm_eval_interval_nan(w->ev, b4, &maybe_nan);
    /* The box distance over the query box: bounds from its corners' slab
     * distances (1-Lipschitz, so the enclosure below is sound). */
    double clo = INFINITY, chi = -INFINITY;
    for (int k = 0; k < 8; k++) {
        double v = box_distance(c, (k & 1) ? box[0].hi : box[0].lo, (k & 2) ? box[1].hi : box[1].lo,
                                (k & 4) ? box[2].hi : box[2].lo);
        if (v < clo) clo = v;
        if (v > chi) chi = v;
    }
    double half = 0;
    for (int i = 0; i < 3; i++) half += (box[i].hi - box[i].lo) * (box[i].hi - box[i].lo);
    half = 0.5 * sqrt(half);
    double cx = 0.5 * (box[0].lo + box[0].hi), cy = 0.5 * (box[1].lo + box[1].hi),
           cz = 0.5 * (box[2].lo + box[2].hi);
    double mid = box_distance(c, cx, cy, cz);
    /* Lipschitz bound around the centre covers the interior extremes. */
    if (mid - half < clo) clo = mid - half;
    if (mid + half > chi) chi = mid + half;
    fm_interval r;
    if (isnan(f.lo) || maybe_nan) {
        /* NaN points take the box distance: widen to cover both. */
        r.lo = isnan(f.lo) ? clo : fmin(f.lo, clo);
        r.hi = chi;
    } else {
        r.lo = fmin(f.lo, clo);
        r.hi = fmin(f.hi, chi);
    }
    return r;
}

static void release(void *ctx)
{
    free(ctx);
}

fm_status fm_field_from_tape(fm_field *field, const fm_tape *tape, const double lo[3],
                             const double hi[3], double t, fm_error *err)
{
    if (!field || !tape || !lo || !hi)
        return fm_error_set(err, FM_ERR_INPUT, "fm_field_from_tape: missing argument");
    for (int i = 0; i < 3; i++)
        if (!(lo[i] <= hi[i]))
            return fm_error_set(err, FM_ERR_INPUT, "field bounds: lo > hi on axis %d", i);
    field_ctx *c = malloc(sizeof *c);
    if (!c) return fm_error_set(err, FM_ERR_LIMIT, "out of memory making a field");
    c->tape = tape;
    c->t = t;
    for (int i = 0; i < 3; i++) {
        c->lo[i] = lo[i];
        c->hi[i] = hi[i];
        field->lo[i] = lo[i];
        field->hi[i] = hi[i];
    }
    field->ctx = c;
    field->worker_new = worker_new;
    field->worker_free = worker_free;
    field->batch = batch;
    field->interval = interval;
    field->release = release;
    field->batch_shortfall = NULL;
    return FM_OK;
}

void fm_field_release(fm_field *field)
{
    if (!field) return;
    if (field->release) field->release(field->ctx);
    field->ctx = NULL;
    field->release = NULL;
}
