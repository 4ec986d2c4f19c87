/* planner.c: the streaming planner. Motions become segments (LinuxCNC's
 * tc queue): naive-CAM merging of collinear feed lines (G64 Q), a blend arc
 * or a tangent joint at each G64 corner, stops where the path mode or the
 * machine's state asks for them; a backward look-ahead pass over the last
 * `lookahead` segments after each one (tpRunOptimization); the segments
 * that left the look-ahead window are run in closed form (profile.c) and
 * their motions delivered with planned times. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "toolpaths/plan/plan_internal.h"

typedef struct pending_motion {
    fm_plan_motion out;
    double along; /* where it ends: distance from its segment's start */
} pending_motion;

struct fm_planner {
    fm_plan_machine m;
    fm_plan_sink sink;
    void *user;
    fm_error err;
    int stopped;
    /* segments: a ring of cap, serials seg_head (oldest) .. seg_tail */
    plan_seg *seg;
    long seg_cap, seg_head, seg_tail;
    /* motions waiting for their times: serials mot_head .. mot_tail */
    pending_motion *mot;
    long mot_cap, mot_head, mot_tail;
    /* the naive-CAM chain: motions chain_first .. mot_tail - 1 not yet in a segment */
    long chain_first;
    int chain_len;
    double chain_start[3];
    /* the last motion pushed (state changes between motions) */
    int have_last;
    fm_motion last;
    /* the run */
    double time, vel;
    double feed_end;
    fm_plan_totals totals;
};

#define SEG(p, k) (&(p)->seg[(k) % (p)->seg_cap])
#define MOT(p, k) (&(p)->mot[(k) % (p)->mot_cap])

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void unit_or_zero(const double a[3], double out[3])
{
    double n = sqrt(dot3(a, a));
    for (int i = 0; i < 3; i++) out[i] = n > 1e-12 ? a[i] / n : 0.0;
}

fm_planner *fm_planner_new(const fm_plan_machine *m, fm_plan_sink sink, void *user, fm_error *err)
{
    fm_planner *p = calloc(1, sizeof *p);
    if (!p) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory for the planner");
        return NULL;
    }
    p->m = *m;
    if (p->m.lookahead < 2) p->m.lookahead = 2;
    if (p->m.lookahead > 10000) p->m.lookahead = 10000;
    if (!(p->m.servo_period_s > 0.0)) p->m.servo_period_s = 0.001;
    if (!(p->m.max_feed_override > 0.0)) p->m.max_feed_override = 1.0;
    if (!(p->m.rapid_rate > 0.0)) p->m.rapid_rate = 5000.0;
    p->sink = sink;
    p->user = user;
    p->seg_cap = p->m.lookahead + 16;
    p->seg = calloc((size_t)p->seg_cap, sizeof *p->seg);
    p->mot_cap = 256;
    p->mot = calloc((size_t)p->mot_cap, sizeof *p->mot);
    if (!p->seg || !p->mot) {
        fm_planner_free(p);
        fm_error_set(err, FM_ERR_LIMIT, "out of memory for the planner");
        return NULL;
    }
    return p;
}

void fm_planner_free(fm_planner *p)
{
    if (!p) return;
    free(p->seg);
    free(p->mot);
    free(p);
}

const fm_error *fm_planner_error(const fm_planner *p) { return &p->err; }

/* ---- delivering motions ---- */

static fm_status deliver(fm_planner *p, pending_motion *pm, double t1, fm_error *err)
{
    pm->out.motion.t0 = p->totals.cycle_time_s;
    pm->out.motion.t1 = fmax(t1, pm->out.motion.t0);
    p->totals.cycle_time_s = pm->out.motion.t1;
    if (p->sink && p->sink(p->user, &pm->out)) {
        p->stopped = 1;
        return fm_error_set_reason(err, FM_ERR_LIMIT, "stopped", "the planner's sink stopped it");
    }
    return FM_OK;
}

/* Deliver the motions up to serial `last` that end at time t (the oldest
 * pending ones). */
static fm_status deliver_through(fm_planner *p, long last, double t, fm_error *err)
{
    while (p->mot_head <= last) {
        fm_status st = deliver(p, MOT(p, p->mot_head), t, err);
        p->mot_head++;
        if (st) return st;
    }
    return FM_OK;
}

static fm_status grow_motions(fm_planner *p, fm_error *err)
{
    if (p->mot_tail - p->mot_head < p->mot_cap) return FM_OK;
    long cap = p->mot_cap * 2;
    pending_motion *n = malloc((size_t)cap * sizeof *n);
    if (!n) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for the planner's motions");
    for (long k = p->mot_head; k < p->mot_tail; k++) n[k % cap] = *MOT(p, k);
    free(p->mot);
    p->mot = n;
    p->mot_cap = cap;
    return FM_OK;
}

/* ---- running segments ---- */

static double seg_target_vel(const plan_seg *s)
{
    return fmin(s->reqvel, s->maxvel);
}

static double seg_tangential_accel(const plan_seg *s)
{
    double a = s->maxaccel * (1.0 - fmax(s->kink_reduce, s->kink_reduce_prev));
    if (s->kind == SEG_ARC || s->kind == SEG_BLEND) a *= s->acc_ratio_tan;
    return a;
}

/* Run the oldest segment: its profile from the current velocity, the
 * times of the motions that end in it. */
static fm_status run_oldest(fm_planner *p, fm_error *err)
{
    plan_seg *s = SEG(p, p->seg_head);
    plan_seg *next = p->seg_head + 1 < p->seg_tail ? SEG(p, p->seg_head + 1) : NULL;
    double t0 = p->time;
    plan_profile prof = {0};
    double duration;
    if (s->kind == SEG_DWELL) {
        duration = s->dwell_s;
        p->vel = 0.0;
    } else {
        double vt = seg_target_vel(s);
        double vf = 0.0;
        if (s->term == TERM_TANGENT && next && next->kind != SEG_DWELL)
            vf = fmin(fmin(s->finalvel, vt), seg_target_vel(next));
        plan_profile_make(s->length, p->vel, vt, vf, seg_tangential_accel(s), &prof);
        duration = plan_profile_time(&prof);
        p->vel = prof.v1;
        if (prof.v1 <= 0.0) p->totals.stops++;
    }
    p->time = t0 + duration;
    if (s->kind == SEG_BLEND) {
        s->blend.t0 = t0 + plan_profile_time_at(&prof, s->length - s->blend.radius * s->blend.angle);
        s->blend.t1 = p->time;
        s->blend.speed = prof.vp;
        if (s->last_motion >= 0) {
            pending_motion *pm = MOT(p, s->last_motion);
            pm->out.has_blend = 1;
            pm->out.blend_out = s->blend;
        }
    }
    p->seg_head++;
    for (long k = s->first_motion; k <= s->last_motion && k >= 0; k++) {
        pending_motion *pm = MOT(p, k);
        double along = fmax(0.0, fmin(s->length, pm->along - s->trim_start));
        /* a motion ending at the segment's end ends when it does (the
         * profile's time at its full length, without rounding) */
        double t = s->kind == SEG_DWELL || along >= s->length - 1e-9 * (1.0 + s->length)
                       ? p->time
                       : t0 + plan_profile_time_at(&prof, along);
        if (k == s->first_motion) pm->out.v_start = prof.v0;
        if (k == s->last_motion) pm->out.v_end = prof.v1;
        fm_status st = deliver_through(p, k, t, err);
        if (st) return st;
    }
    return FM_OK;
}

/* ---- the look-ahead (LinuxCNC's tpRunOptimization) ---- */

static void optimize(fm_planner *p)
{
    long len = p->seg_tail - p->seg_head;
    int hit_peaks = 0, hit_non_tangent = 0;
    for (long x = 1; x < p->m.lookahead + 2; x++) {
        long ind = p->seg_tail - x;
        if (ind - 1 < p->seg_head || x > len) return;
        plan_seg *tc = SEG(p, ind), *prev = SEG(p, ind - 1);
        if (prev->term != TERM_TANGENT) {
            if (hit_non_tangent) return;
            hit_non_tangent = 1;
            continue;
        }
        if (!tc->finalized) {
            /* the last segment's length may still change: assume it stops,
             * and may be half taken by a blend (tpCalculateOptimizationInitialVel) */
            double a = seg_tangential_accel(tc);
            double v = fmin(sqrt(a * tc->length), seg_target_vel(tc));
            prev->finalvel = fmin(prev->maxvel, v);
            if (prev->kink_vel >= 0.0) prev->finalvel = fmin(prev->finalvel, prev->kink_vel);
            tc->finalvel = 0.0;
        } else {
            double a = seg_tangential_accel(tc);
            double vs_back = sqrt(tc->finalvel * tc->finalvel + 2.0 * a * tc->length);
            double vf_limit_prev = prev->maxvel;
            if (prev->kink_vel >= 0.0) vf_limit_prev = fmin(vf_limit_prev, prev->kink_vel);
            double vf_limit = fmin(tc->maxvel, vf_limit_prev);
            if (vs_back >= vf_limit) {
                vs_back = vf_limit;
                prev->at_max = 1;
            }
            prev->finalvel = vs_back;
        }
        if (tc->at_max && ++hit_peaks > PLAN_OPTIMIZATION_CUTOFF) return;
    }
}

/* ---- building segments ---- */

static void finalize(fm_planner *p, plan_seg *s)
{
    if (s->finalized) return;
    s->finalized = 1;
    if (s->kind != SEG_DWELL && s->length > 0.0)
        s->maxvel = fmin(s->maxvel, s->length / p->m.servo_period_s);
}

/* The joint between prev and tc: a stop, a tangent joint (with LinuxCNC's
 * kink limits) or a blend arc inserted between them. Returns 1 when a
 * blend segment was made in *blend. */
static int join(fm_planner *p, plan_seg *prev, plan_seg *tc, plan_seg *blend)
{
    if (prev->term == TERM_STOP) return 0;
    if (prev->kind == SEG_DWELL || tc->kind == SEG_DWELL || prev->rotary || tc->rotary ||
        prev->rapid != tc->rapid) {
        prev->term = TERM_STOP;
        return 0;
    }
    double d = dot3(prev->u_end, tc->u_start);
    /* a reversal within 2 degrees is a sharp corner: a stop */
    if (d < -cos(PLAN_PI * 2.0 / 180.0)) {
        prev->term = TERM_STOP;
        return 0;
    }
    /* The acceleration the direction change needs in one servo period at
     * the joint's speed, against each axis' limit (tpSetupTangent). */
    double mfo = p->m.max_feed_override;
    double v_max = fmin(fmin(prev->maxvel, prev->reqvel * mfo), fmin(tc->maxvel, tc->reqvel * mfo));
    double a_inst = v_max / p->m.servo_period_s + tc->maxaccel;
    double scale = 0.0;
    for (int i = 0; i < 3; i++) {
        double diff = a_inst * (tc->u_start[i] - prev->u_end[i]);
        double bound = p->m.linear[i].max_acceleration;
        if (bound > 0.0) scale = fmax(scale, fabs(diff) / bound);
    }
    if (prev->kind == SEG_ARC || tc->kind == SEG_ARC) scale /= PLAN_ACC_RATIO_TANGENTIAL;
    double kr = p->m.kink_ratio;
    if (!isfinite(scale) || !isfinite(v_max)) scale = 0.0; /* no limits: every joint flows */
    if (scale < kr) {
        prev->term = TERM_TANGENT;
        prev->kink_vel = v_max;
        prev->kink_reduce = fmax(prev->kink_reduce, scale);
        tc->kink_reduce_prev = fmax(tc->kink_reduce_prev, scale);
        return 0;
    }
    double kink_vel = v_max * kr / scale;
    if (prev->term != TERM_BLEND) {
        /* G61 stops at the corner; LinuxCNC has already set the kink's
         * acceleration reduction on both feed moves and keeps it
         * (measured: 5 ms more per corner than G61.1, docs/plan.md) */
        if (!prev->rapid) {
            prev->kink_reduce = fmax(prev->kink_reduce, kr);
            tc->kink_reduce_prev = fmax(tc->kink_reduce_prev, kr);
        }
        return 0;
    }
    plan_blend_params bp;
    if (plan_blend_compute(&p->m, prev, tc, &bp) == 0 && bp.v_plan >= kink_vel) {
        plan_seg b = {0};
        b.kind = SEG_BLEND;
        b.rapid = prev->rapid;
        b.term = TERM_TANGENT;
        b.kink_vel = -1.0;
        b.tolerance = prev->tolerance;
        b.reqvel = bp.v_actual;
        b.maxaccel = bp.a_max;
        plan_curvature_limits(bp.R_plan, bp.v_plan, bp.a_max, &b.maxvel, &b.acc_ratio_tan);
        double n[3], diff[3];
        for (int i = 0; i < 3; i++) diff[i] = tc->u_start[i] - prev->u_end[i];
        unit_or_zero(diff, n);
        const double *P = prev->p_end;
        double cd = bp.R_plan / sin(bp.theta);
        for (int i = 0; i < 3; i++) {
            b.blend.start[i] = P[i] - prev->u_end[i] * bp.d_plan;
            b.blend.end[i] = P[i] + tc->u_start[i] * bp.d_plan;
            b.blend.center[i] = P[i] + n[i] * cd;
        }
        b.blend.radius = bp.R_plan;
        b.blend.angle = bp.phi;
        memcpy(b.p_start, b.blend.start, sizeof b.p_start);
        memcpy(b.p_end, b.blend.end, sizeof b.p_end);
        memcpy(b.u_start, prev->u_end, sizeof b.u_start);
        memcpy(b.u_end, tc->u_start, sizeof b.u_end);
        b.length = bp.s_arc;
        b.nominal_length = bp.s_arc;
        b.first_motion = b.last_motion = -1;
        /* trim both neighbours */
        prev->length = fmax(0.0, prev->length - bp.d_plan);
        prev->term = TERM_TANGENT;
        prev->kink_vel = -1.0;
        tc->length = fmax(0.0, tc->length - bp.d_plan);
        tc->trim_start += bp.d_plan;
        for (int i = 0; i < 3; i++) tc->p_start[i] = b.blend.end[i];
        *blend = b;
        p->totals.blends++;
        return 1;
    }
    /* no arc fits: flow through at the kink velocity (LinuxCNC's tangent
     * blend; its parabolic blend is not modelled) */
    prev->term = TERM_TANGENT;
    prev->kink_vel = kink_vel;
    prev->kink_reduce = fmax(prev->kink_reduce, kr);
    tc->kink_reduce_prev = fmax(tc->kink_reduce_prev, kr);
    return 0;
}

static fm_status grow_segments_check(fm_planner *p, fm_error *err)
{
    if (p->seg_tail - p->seg_head + 2 > p->seg_cap)
        return fm_error_set(err, FM_ERR_INTERNAL, "planner queue overflow");
    return FM_OK;
}

/* Move the motions of prev that end within its last `trim` mm into the
 * blend that follows it (they end at the corner, the middle of the arc);
 * a consumed prev gives the blend all of its motions. */
static void hand_motions_to_blend(fm_planner *p, plan_seg *prev, plan_seg *b, int consume,
                                  double line_length)
{
    long first = prev->first_motion, last = prev->last_motion;
    b->first_motion = b->last_motion = -1;
    if (first < 0) return;
    long k = last;
    while (k >= first && (consume || MOT(p, k)->along - prev->trim_start > prev->length - 1e-12)) k--;
    if (k == last) return;
    b->first_motion = k + 1;
    b->last_motion = last;
    double corner = line_length + b->blend.radius * b->blend.angle / 2.0;
    for (long j = k + 1; j <= last; j++) {
        pending_motion *pm = MOT(p, j);
        double a = pm->along - prev->trim_start;
        pm->along = consume && a < line_length - 1e-12 ? fmax(0.0, a) : corner;
    }
    prev->last_motion = k;
    if (k < first) prev->first_motion = prev->last_motion = -1;
}

static fm_status run_ready(fm_planner *p, long keep, fm_error *err)
{
    while (p->seg_tail - p->seg_head > keep) {
        fm_status st = run_oldest(p, err);
        if (st) return st;
    }
    return FM_OK;
}

static fm_status append_segment(fm_planner *p, plan_seg *tc, fm_error *err)
{
    fm_status st = grow_segments_check(p, err);
    if (st) return st;
    p->totals.segments++;
    if (p->seg_tail > p->seg_head) {
        plan_seg *prev = SEG(p, p->seg_tail - 1);
        plan_seg blend;
        if (join(p, prev, tc, &blend)) {
            /* a short rest of prev (less than gap_cycles at the blend's
             * speed) is consumed: the blend carries it (blendCheckConsume) */
            int consume = prev->kind == SEG_LINE &&
                          prev->length / fmax(blend.maxvel, 1e-9) <
                              p->m.blend_gap_cycles * p->m.servo_period_s &&
                          p->seg_tail - 1 > p->seg_head;
            double line_length = consume ? prev->length : 0.0;
            hand_motions_to_blend(p, prev, &blend, consume, line_length);
            if (consume) {
                blend.length += line_length;
                blend.nominal_length = blend.length;
                memcpy(blend.p_start, prev->p_start, sizeof blend.p_start);
                p->seg_tail--;
                p->totals.segments--;
                /* the segment before the consumed line flows into the blend */
            } else {
                finalize(p, prev);
            }
            blend.finalized = 0;
            *SEG(p, p->seg_tail) = blend;
            p->seg_tail++;
            p->totals.segments++;
            finalize(p, SEG(p, p->seg_tail - 1));
        } else {
            finalize(p, prev);
        }
    }
    *SEG(p, p->seg_tail) = *tc;
    p->seg_tail++;
    optimize(p);
    return run_ready(p, p->m.lookahead + 4, err);
}

/* A segment of the motion's kind from its geometry and the machine. */
static void segment_of_motion(const fm_planner *p, const fm_motion *mo, plan_seg *s)
{
    *s = (plan_seg){0};
    s->kink_vel = -1.0;
    s->acc_ratio_tan = 1.0;
    s->tolerance = mo->path_tolerance;
    s->term = mo->path_mode == FM_PATH_EXACT_STOP   ? TERM_STOP
              : mo->path_mode == FM_PATH_EXACT_PATH ? TERM_EXACT
                                                    : TERM_BLEND;
    memcpy(s->p_start, mo->start, sizeof s->p_start);
    memcpy(s->p_end, mo->end, sizeof s->p_end);
    double r[3] = {0, 0, 0};
    if (mo->machine && mo->machine->rotary_count > 0)
        for (int i = 0; i < 3; i++) r[i] = mo->rotary_end[i] - mo->rotary_start[i];
    s->rotary = fabs(r[0]) + fabs(r[1]) + fabs(r[2]) > 1e-9;
    if (mo->kind == FM_MOTION_ARC) {
        s->kind = SEG_ARC;
        int k = mo->plane_axis;
        double n[3] = {0, 0, 0};
        n[k] = mo->turns > 0 ? 1.0 : -1.0;
        memcpy(s->normal, n, sizeof n);
        memcpy(s->center, mo->center, sizeof s->center);
        double rs[3], re[3];
        for (int i = 0; i < 3; i++) {
            rs[i] = i == k ? 0.0 : mo->start[i] - mo->center[i];
            re[i] = i == k ? 0.0 : mo->end[i] - mo->center[i];
        }
        double r0 = sqrt(dot3(rs, rs)), r1 = sqrt(dot3(re, re));
        s->radius = 0.5 * (r0 + r1);
        /* the angle turned about n: from rs to re, positive, plus full turns */
        double c[3] = {rs[1] * re[2] - rs[2] * re[1], rs[2] * re[0] - rs[0] * re[2],
                       rs[0] * re[1] - rs[1] * re[0]};
        double ang = atan2(dot3(c, n), dot3(rs, re));
        if (ang <= 1e-12) ang += 2.0 * PLAN_PI;
        int extra = abs(mo->turns) - 1;
        if (extra > 0) ang += 2.0 * PLAN_PI * extra;
        s->angle = ang;
        double dz = mo->end[k] - mo->start[k];
        s->helix = ang > 0.0 ? dz / ang : 0.0;
        double planar = s->radius * ang;
        s->length = sqrt(planar * planar + dz * dz);
        /* tangents: n x r, plus the helix rise */
        double ts[3] = {n[1] * rs[2] - n[2] * rs[1], n[2] * rs[0] - n[0] * rs[2],
                        n[0] * rs[1] - n[1] * rs[0]};
        double te[3] = {n[1] * re[2] - n[2] * re[1], n[2] * re[0] - n[0] * re[2],
                        n[0] * re[1] - n[1] * re[0]};
        ts[k] += s->helix;
        te[k] += s->helix;
        unit_or_zero(ts, s->u_start);
        unit_or_zero(te, s->u_end);
        double a;
        plan_arc_limits(&p->m, s, &s->maxvel, &a, &s->acc_ratio_tan);
        s->maxaccel = a;
        s->reqvel = mo->feed / 60.0;
    } else {
        s->kind = SEG_LINE;
        s->rapid = mo->kind == FM_MOTION_RAPID;
        double d[3] = {mo->end[0] - mo->start[0], mo->end[1] - mo->start[1], mo->end[2] - mo->start[2]};
        plan_line_limits(&p->m, d, r, mo->kind == FM_MOTION_RAPID, &s->length, &s->maxvel,
                         &s->maxaccel);
        unit_or_zero(d, s->u_start);
        memcpy(s->u_end, s->u_start, sizeof s->u_end);
        double xyz = sqrt(dot3(d, d));
        s->pure_rotary = xyz <= 1e-9;
        s->reqvel = mo->kind == FM_MOTION_RAPID ? s->maxvel : mo->feed / 60.0;
        if (mo->kind != FM_MOTION_RAPID && !(s->reqvel > 0.0)) s->reqvel = s->maxvel;
        if (!isfinite(s->reqvel)) {
            /* a rapid on a machine without velocity limits: the rapid rate */
            s->reqvel = p->m.rapid_rate / 60.0;
        }
    }
    s->nominal_length = s->length;
    if (!isfinite(s->maxvel)) s->maxvel = s->reqvel;
    s->first_motion = s->last_motion = -1;
}

/* A motion with no length ends where the queue's last motion ends. */
static fm_status zero_length(fm_planner *p, long serial, fm_error *err)
{
    if (p->seg_tail > p->seg_head) {
        plan_seg *last = SEG(p, p->seg_tail - 1);
        if (last->first_motion < 0) last->first_motion = serial;
        last->last_motion = serial;
        MOT(p, serial)->along = last->trim_start + last->length;
        return FM_OK;
    }
    return deliver_through(p, serial, p->time, err);
}

/* ---- naive CAM (G64 Q): merging nearly collinear feed lines ---- */

static int chainable(const fm_motion *mo)
{
    return mo->kind == FM_MOTION_LINE && mo->path_mode == FM_PATH_BLEND && mo->naive_tolerance > 0.0 &&
           !(mo->machine && mo->machine->rotary_count > 0);
}

/* Can the chain take a line to `end`: every point of the chain within the
 * tolerance of the straight line from the chain's start to end. */
static int chain_fits(const fm_planner *p, const fm_motion *mo)
{
    if (p->chain_len >= PLAN_NAIVE_MAX_POINTS) return 0;
    const fm_motion *first = &MOT(p, p->chain_first)->out.motion;
    if (first->feed != mo->feed || first->naive_tolerance != mo->naive_tolerance ||
        first->path_tolerance != mo->path_tolerance)
        return 0;
    double ab[3], u[3];
    for (int i = 0; i < 3; i++) ab[i] = mo->end[i] - p->chain_start[i];
    double len = sqrt(dot3(ab, ab));
    if (len < 1e-12) return 0;
    unit_or_zero(ab, u);
    for (long k = p->chain_first; k < p->mot_tail; k++) {
        const double *q = MOT(p, k)->out.motion.end;
        double w[3] = {q[0] - p->chain_start[0], q[1] - p->chain_start[1], q[2] - p->chain_start[2]};
        double t = fmax(0.0, fmin(len, dot3(w, u)));
        double e[3] = {w[0] - u[0] * t, w[1] - u[1] * t, w[2] - u[2] * t};
        if (sqrt(dot3(e, e)) > mo->naive_tolerance) return 0;
    }
    return 1;
}

/* The chain becomes one line segment carrying its motions. */
static fm_status flush_chain(fm_planner *p, fm_error *err)
{
    if (p->chain_len == 0) return FM_OK;
    long first = p->chain_first, last = p->chain_first + p->chain_len - 1;
    fm_motion line = MOT(p, first)->out.motion;
    memcpy(line.start, p->chain_start, sizeof line.start);
    memcpy(line.end, MOT(p, last)->out.motion.end, sizeof line.end);
    plan_seg s;
    segment_of_motion(p, &line, &s);
    s.first_motion = first;
    s.last_motion = last;
    for (long k = first; k <= last; k++) {
        const double *q = MOT(p, k)->out.motion.end;
        double w[3] = {q[0] - s.p_start[0], q[1] - s.p_start[1], q[2] - s.p_start[2]};
        MOT(p, k)->along = fmax(0.0, fmin(s.length, dot3(w, s.u_start)));
    }
    MOT(p, last)->along = s.length;
    p->chain_len = 0;
    if (s.length <= 1e-9) {
        for (long k = first; k <= last; k++) {
            fm_status st = zero_length(p, k, err);
            if (st) return st;
        }
        return FM_OK;
    }
    return append_segment(p, &s, err);
}

/* ---- pushing motions ---- */

static int state_changes(const fm_motion *a, const fm_motion *b)
{
    return a->spindle_rpm != b->spindle_rpm || a->spindle_dir != b->spindle_dir ||
           a->coolant != b->coolant;
}

/* Force the queue's last segment to end at rest. */
static void stop_last(fm_planner *p)
{
    if (p->seg_tail > p->seg_head) SEG(p, p->seg_tail - 1)->term = TERM_STOP;
}

static fm_status push_planned(fm_planner *p, const fm_motion *mo, fm_error *err)
{
    fm_status st = grow_motions(p, err);
    if (st) return st;
    long serial = p->mot_tail;
    pending_motion *pm = MOT(p, serial);
    memset(pm, 0, sizeof *pm);
    pm->out.motion = *mo;
    pm->out.feed_t0 = mo->t0;
    pm->out.feed_t1 = mo->t1;

    int tool_change = p->have_last && mo->tool != p->last.tool;
    int stop_before = p->have_last && (tool_change || state_changes(&p->last, mo));
    if (chainable(mo) && p->chain_len > 0 && !stop_before && chain_fits(p, mo)) {
        p->mot_tail++;
        p->chain_len++;
        p->last = *mo;
        return FM_OK;
    }
    st = flush_chain(p, err);
    if (st) return st;
    /* the flushed chain may have delivered motions: our slot is still mot_tail */
    if (stop_before) stop_last(p);
    if (tool_change && p->m.tool_change_s > 0.0) {
        plan_seg d = {0};
        d.kind = SEG_DWELL;
        d.term = TERM_STOP;
        d.dwell_s = p->m.tool_change_s;
        d.kink_vel = -1.0;
        d.first_motion = d.last_motion = -1;
        p->totals.tool_changes++;
        st = append_segment(p, &d, err);
        if (st) return st;
    }
    p->mot_tail++;
    p->have_last = 1;
    p->last = *mo;
    if (mo->kind == FM_MOTION_PARAM) {
        /* parametric segments keep the producer's timing: a stop before,
         * their own duration */
        plan_seg d = {0};
        d.kind = SEG_DWELL;
        d.term = TERM_STOP;
        d.dwell_s = fmax(0.0, mo->t1 - mo->t0);
        d.kink_vel = -1.0;
        d.first_motion = d.last_motion = serial;
        stop_last(p);
        return append_segment(p, &d, err);
    }
    if (mo->kind == FM_MOTION_DWELL) {
        plan_seg d = {0};
        d.kind = SEG_DWELL;
        d.term = TERM_STOP;
        d.dwell_s = fmax(0.0, mo->t1 - mo->t0);
        d.kink_vel = -1.0;
        d.first_motion = d.last_motion = serial;
        stop_last(p);
        return append_segment(p, &d, err);
    }
    if (chainable(mo)) {
        memcpy(p->chain_start, mo->start, sizeof p->chain_start);
        p->chain_first = serial;
        p->chain_len = 1;
        return FM_OK;
    }
    plan_seg s;
    segment_of_motion(p, mo, &s);
    if (s.length <= 1e-9) return zero_length(p, serial, err);
    s.first_motion = s.last_motion = serial;
    pm->along = s.length;
    return append_segment(p, &s, err);
}

fm_status fm_planner_push(fm_planner *p, const fm_motion *motion, fm_error *err)
{
    if (p->stopped)
        return fm_error_set_reason(err, FM_ERR_LIMIT, "stopped", "the planner's sink stopped it");
    p->totals.motions++;
    p->feed_end = motion->t1;
    if (!p->m.given) {
        pending_motion pm = {0};
        pm.out.motion = *motion;
        pm.out.feed_t0 = motion->t0;
        pm.out.feed_t1 = motion->t1;
        p->totals.cycle_time_s = motion->t0;
        return deliver(p, &pm, motion->t1, err);
    }
    return push_planned(p, motion, err);
}

fm_status fm_planner_finish(fm_planner *p, fm_plan_totals *totals, fm_error *err)
{
    fm_status st = FM_OK;
    if (!p->stopped && p->m.given) {
        st = flush_chain(p, err);
        /* a chain too short to make a segment: its motions end here */
        if (!st && p->chain_len == 0 && p->mot_head < p->mot_tail && p->seg_tail == p->seg_head)
            st = deliver_through(p, p->mot_tail - 1, p->time, err);
        if (!st) {
            stop_last(p);
            if (p->seg_tail > p->seg_head) finalize(p, SEG(p, p->seg_tail - 1));
            optimize(p);
            st = run_ready(p, 0, err);
        }
        if (!st && p->mot_head < p->mot_tail) st = deliver_through(p, p->mot_tail - 1, p->time, err);
    }
    p->totals.feed_only_s = p->feed_end;
    if (totals) *totals = p->totals;
    return st;
}

int fm_planner_motion_sink(void *planner, const fm_motion *motion)
{
    fm_planner *p = planner;
    if (fm_planner_push(p, motion, &p->err)) return 1;
    return 0;
}
