/* traj_path.c: a compiled trajectory segment as an fm_path: pose(t) by
 * point evaluation of the segment's tapes, pose_bounds by their interval
 * evaluation (sound, since lib/frep's intervals are), and the validation of
 * the expressions over the segment's interval (samples plus interval
 * bisection). */
#include "toolpaths/traj/traj_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double dn(double x)
{
    return nextafter(x, -INFINITY);
}

static double up(double x)
{
    return nextafter(x, INFINITY);
}

static int slot_ready(traj_seg *s, traj_slot *sl)
{
    for (int i = 0; i < TRAJ_COMPONENTS; i++)
        if (s->tape[i] && !sl->ev[i] && !(sl->ev[i] = fm_evaluator_new(s->tape[i], NULL))) return 0;
    return 1;
}

static void slot_clear(traj_slot *sl)
{
    for (int i = 0; i < TRAJ_COMPONENTS; i++) {
        fm_evaluator_free(sl->ev[i]);
        sl->ev[i] = NULL;
    }
}

/* Take a free pooled slot, or fill *spare with fresh evaluators when all
 * are taken (more threads than TRAJ_POOL). NULL only when out of memory. */
static traj_slot *slot_acquire(traj_seg *s, traj_slot *spare)
{
    for (int k = 0; k < TRAJ_POOL; k++) {
        int expected = 0;
        if (atomic_compare_exchange_strong(&s->slot[k].busy, &expected, 1)) {
            if (slot_ready(s, &s->slot[k])) return &s->slot[k];
            atomic_store(&s->slot[k].busy, 0);
            return NULL;
        }
    }
    memset(spare->ev, 0, sizeof spare->ev);
    if (slot_ready(s, spare)) return spare;
    slot_clear(spare);
    return NULL;
}

static void slot_release(traj_slot *sl, traj_slot *spare)
{
    if (sl == spare)
        slot_clear(spare);
    else if (sl)
        atomic_store(&sl->busy, 0);
}

static void eval_raw(const traj_seg *s, traj_slot *sl, double t, double v[TRAJ_COMPONENTS])
{
    double p[4] = {0, 0, 0, t};
    for (int i = 0; i < TRAJ_COMPONENTS; i++)
        v[i] = s->is_t[i] ? t : s->tape[i] ? (sl ? fm_eval_point(sl->ev[i], p) : NAN) : s->cval[i];
}

static void eval_box(const traj_seg *s, traj_slot *sl, double ta, double tb,
                     fm_interval r[TRAJ_COMPONENTS])
{
    fm_interval box[4] = {{0, 0}, {0, 0}, {0, 0}, {ta, tb}};
    for (int i = 0; i < TRAJ_COMPONENTS; i++) {
        if (s->is_t[i]) {
            r[i] = box[3];
        } else if (!s->tape[i]) {
            r[i].lo = r[i].hi = s->cval[i];
        } else if (sl) {
            r[i] = fm_eval_interval(sl->ev[i], box);
        } else {
            r[i].lo = -INFINITY;
            r[i].hi = INFINITY;
        }
    }
}

static double clamp(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* The axis is normalized with hypot, which scales before squaring: the
 * squares of components above about 1.3e154 overflow to infinity (and below
 * 1e-154 vanish), which made the axis 0 where its direction is plain. */
static double norm3(double x, double y, double z)
{
    return hypot(hypot(x, y), z);
}

static void finish_pose(const traj_seg *s, const double v[TRAJ_COMPONENTS], double pos[3],
                        double axis[3])
{
    for (int i = 0; i < 3; i++) pos[i] = v[i] * s->scale;
    double n = norm3(v[3], v[4], v[5]);
    for (int i = 0; i < 3; i++) axis[i] = clamp(v[3 + i] / n, -1, 1);
}

void traj_seg_pose_doc(traj_seg *s, double t, double pos[3], double axis[3])
{
    traj_slot spare, *sl = slot_acquire(s, &spare);
    double v[TRAJ_COMPONENTS];
    eval_raw(s, sl, clamp(t, s->t0, s->t1), v);
    slot_release(sl, &spare);
    finish_pose(s, v, pos, axis);
}

static void path_pose(void *ctx, double t, double pos[3], double axis[3])
{
    traj_seg *s = ctx;
    traj_seg_pose_doc(s, t - s->shift, pos, axis);
}

/* Bounds of a / hypot(a, r) with a in [alo, ahi], r in [rlo, rhi] (r >= 0,
 * the length of the other two components): it grows with a, and for a >= 0
 * (a < 0) shrinks (grows) with r. hypot, not the square root of squares,
 * whose overflow above 1.3e154 once gave an upper end of 0 below the lower
 * (tests/traj/corpus/regress_axis_overflow.json). 0/0 and inf/inf only arise
 * when the box reaches the origin or infinity; then the whole [-1, 1] is the
 * honest answer. */
static void unit_bounds(double alo, double ahi, double rlo, double rhi, double *lo, double *hi)
{
    double l = alo / hypot(alo, alo >= 0 ? rhi : rlo);
    double h = ahi / hypot(ahi, ahi >= 0 ? rlo : rhi);
    /* A few ulps of rounding in here and in finish_pose's division. */
    *lo = isnan(l) ? -1 : clamp(l - 1e-14, -1, 1);
    *hi = isnan(h) ? 1 : clamp(h + 1e-14, -1, 1);
}

static void path_pose_bounds(void *ctx, double ta, double tb, double pos_lo[3], double pos_hi[3],
                             double axis_lo[3], double axis_hi[3])
{
    traj_seg *s = ctx;
    /* Outward, so that the rounding of the shift cannot lose a time. */
    double da = clamp(dn(ta - s->shift), s->t0, s->t1), db = clamp(up(tb - s->shift), s->t0, s->t1);
    if (da > db) da = db;
    traj_slot spare, *sl = slot_acquire(s, &spare);
    fm_interval r[TRAJ_COMPONENTS];
    eval_box(s, sl, da, db, r);
    slot_release(sl, &spare);
    for (int i = 0; i < 3; i++) {
        double lo = r[i].lo * s->scale, hi = r[i].hi * s->scale;
        pos_lo[i] = isnan(lo) ? -INFINITY : s->scale == 1 ? lo : dn(lo);
        pos_hi[i] = isnan(hi) ? INFINITY : s->scale == 1 ? hi : up(hi);
    }
    /* The range of each component's magnitude. */
    double mlo[3], mhi[3];
    for (int i = 0; i < 3; i++) {
        double lo = r[3 + i].lo, hi = r[3 + i].hi;
        if (isnan(lo) || isnan(hi)) {
            lo = -INFINITY;
            hi = INFINITY;
            r[3 + i].lo = lo;
            r[3 + i].hi = hi;
        }
        mhi[i] = fmax(fabs(lo), fabs(hi));
        mlo[i] = lo <= 0 && hi >= 0 ? 0 : fmin(fabs(lo), fabs(hi));
    }
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        /* Rounding the lengths down and up keeps the r range outward. */
        double rlo = hypot(mlo[j], mlo[k]);
        unit_bounds(r[3 + i].lo, r[3 + i].hi, rlo > 0 ? dn(rlo) : 0, up(hypot(mhi[j], mhi[k])),
                    &axis_lo[i], &axis_hi[i]);
        if (axis_lo[i] > 0 && rlo == 0) axis_lo[i] = dn(axis_lo[i]);
    }
}

void traj_seg_init_path(traj_seg *s)
{
    s->path.ctx = s;
    s->path.pose = path_pose;
    s->path.pose_bounds = path_pose_bounds;
    for (int k = 0; k < TRAJ_POOL; k++) atomic_init(&s->slot[k].busy, 0);
}

void traj_seg_free(traj_seg *s)
{
    for (int k = 0; k < TRAJ_POOL; k++) slot_clear(&s->slot[k]);
    for (int i = 0; i < TRAJ_COMPONENTS; i++) {
        fm_tape_free(s->tape[i]);
        s->tape[i] = NULL;
    }
}

/* Does the interval box of one piece prove every component finite and the
 * axis away from zero? Returns 0, or the failing component (6: axis). */
static int piece_fails(const fm_interval r[TRAJ_COMPONENTS])
{
    for (int i = 0; i < TRAJ_COMPONENTS; i++)
        if (!isfinite(r[i].lo) || !isfinite(r[i].hi)) return i + 1;
    double g[3];
    for (int i = 3; i < 6; i++) g[i - 3] = r[i].lo > 0 ? r[i].lo : r[i].hi < 0 ? -r[i].hi : 0;
    return norm3(g[0], g[1], g[2]) >= TRAJ_MIN_AXIS ? 0 : 7;
}

/* Interval bisection: pieces narrower than this that still fail are real
 * faults (poles, zero axes); within it intervals of smooth expressions
 * tighten to their point values. */
#define CHECK_DEPTH 44

int traj_seg_check(traj_seg *s, int samples, double *t_bad, double *value, int *how)
{
    *how = TRAJ_CHECK_SAMPLE;
    *value = NAN;
    traj_slot spare, *sl = slot_acquire(s, &spare);
    *t_bad = s->t0;
    if (!sl) return -2;
    int bad = 0;
    double v[TRAJ_COMPONENTS];
    for (int k = 0; k <= samples && !bad; k++) {
        double t = k == samples ? s->t1 : s->t0 + (s->t1 - s->t0) * ((double)k / samples);
        eval_raw(s, sl, t, v);
        for (int i = 0; i < TRAJ_COMPONENTS && !bad; i++) {
            if (!isfinite(v[i])) {
                bad = i + 1;
                *t_bad = t;
                *value = v[i];
            }
        }
        if (!bad && norm3(v[3], v[4], v[5]) < TRAJ_MIN_AXIS) {
            bad = 7;
            *t_bad = t;
            *value = norm3(v[3], v[4], v[5]);
        }
    }
    /* Depth-first bisection with an explicit stack (depth <= CHECK_DEPTH). */
    struct {
        double a, b;
        int depth;
    } stack[CHECK_DEPTH + 2];
    int top = 0, work = 0;
    if (!bad) {
        stack[top].a = s->t0;
        stack[top].b = s->t1;
        stack[top++].depth = 0;
    }
    while (top > 0 && !bad) {
        top--;
        double a = stack[top].a, b = stack[top].b;
        int depth = stack[top].depth;
        fm_interval r[TRAJ_COMPONENTS];
        eval_box(s, sl, a, b, r);
        int f = piece_fails(r);
        if (!f) continue;
        double m = a + (b - a) / 2;
        if (depth >= CHECK_DEPTH || !(m > a && m < b)) {
            bad = f;
            *t_bad = m;
            *how = TRAJ_CHECK_INTERVAL;
            break;
        }
        if (++work > TRAJ_CHECK_MAX) {
            bad = f;
            *t_bad = m;
            *how = TRAJ_CHECK_BUDGET;
            break;
        }
        stack[top].a = m;
        stack[top].b = b;
        stack[top++].depth = depth + 1;
        stack[top].a = a;
        stack[top].b = m;
        stack[top++].depth = depth + 1;
    }
    slot_release(sl, &spare);
    return bad ? bad - 1 : -1;
}
