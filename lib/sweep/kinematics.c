/* kinematics.c: machine kinematics. A machine's rotary axes (motion.h)
 * turn joint values into the tool's pose in the workpiece frame, where the
 * stock does not move (ARCHITECTURE.md, "Rotary axes"): the chain from the tool
 * through the head axes, the linear axes and the table axes (inverted).
 * With TCP the programmed point is the tip in the workpiece frame and only
 * the orientation comes from the joints; without it every joint moves
 * linearly in time and the tip's path curves. Also sound boxes of the pose
 * over a piece of the motion (interval rotation of boxes), the constants
 * the sweep's branch-and-bound needs, the 3-axis equivalent of a motion
 * whose joints stand still, and the machine's own checks and transforms.
 * docs/sweep.md "Machine kinematics" has the conventions and proofs. */
#include "sweep/kin_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }
static void cross3(const double a[3], const double b[3], double out[3])
{
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    out[0] = x, out[1] = y, out[2] = z;
}
static int finite3(const double v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

/* Rodrigues: R = c I + s [w]x + (1 - c) w w^T, row-major. */
static void rotation(const double w[3], double th, double R[9])
{
    double c = cos(th), s = sin(th), t = 1 - c;
    R[0] = c + t * w[0] * w[0], R[1] = t * w[0] * w[1] - s * w[2], R[2] = t * w[0] * w[2] + s * w[1];
    R[3] = t * w[1] * w[0] + s * w[2], R[4] = c + t * w[1] * w[1], R[5] = t * w[1] * w[2] - s * w[0];
    R[6] = t * w[2] * w[0] - s * w[1], R[7] = t * w[2] * w[1] + s * w[0], R[8] = c + t * w[2] * w[2];
}

static void mat_vec(const double R[9], const double v[3], double out[3])
{
    double x = R[0] * v[0] + R[1] * v[1] + R[2] * v[2];
    double y = R[3] * v[0] + R[4] * v[1] + R[5] * v[2];
    double z = R[6] * v[0] + R[7] * v[1] + R[8] * v[2];
    out[0] = x, out[1] = y, out[2] = z;
}

/* ------------------------------------------------------------ machine -- */

int fm_machine_axis_of(const fm_machine *mc, int letter)
{
    if (!mc) return -1;
    for (int i = 0; i < mc->rotary_count && i < FM_MACHINE_MAX_ROTARY; i++)
        if (mc->rotary[i].letter == letter) return i;
    return -1;
}

int fm_machine_table_axes(const fm_machine *mc)
{
    int n = 0;
    for (int i = 0; mc && i < mc->rotary_count && i < FM_MACHINE_MAX_ROTARY; i++)
        n += mc->rotary[i].carries == FM_ROTARY_TABLE;
    return n;
}

fm_status fm_machine_validate(fm_machine *mc, fm_error *err)
{
    if (mc->rotary_count < 0 || mc->rotary_count > FM_MACHINE_MAX_ROTARY)
        return fm_error_set(err, FM_ERR_INPUT, "a machine has at most %d rotary axes (A, B, C), not %d",
                            FM_MACHINE_MAX_ROTARY, mc->rotary_count);
    for (int i = 0; i < mc->rotary_count; i++) {
        fm_rotary_axis *ax = &mc->rotary[i];
        char name = (char)('A' + (ax->letter >= 0 && ax->letter <= 2 ? ax->letter : 0));
        if (ax->letter < 0 || ax->letter > 2)
            return fm_error_set(err, FM_ERR_INPUT, "rotary axis %d: the axis is a, b or c", i);
        for (int j = 0; j < i; j++)
            if (mc->rotary[j].letter == ax->letter)
                return fm_error_set(err, FM_ERR_INPUT, "rotary axis %c is given twice", name);
        if (ax->carries != FM_ROTARY_TABLE && ax->carries != FM_ROTARY_HEAD)
            return fm_error_set(err, FM_ERR_INPUT, "rotary axis %c: carries \"table\" or \"head\"", name);
        double n = norm3(ax->around);
        if (!finite3(ax->around) || !(n > 1e-9))
            return fm_error_set(err, FM_ERR_INPUT, "rotary axis %c: \"around\" must be a non-zero direction",
                                name);
        for (int k = 0; k < 3; k++) ax->around[k] /= n;
        if (!finite3(ax->through) || !isfinite(ax->pivot_length))
            return fm_error_set(err, FM_ERR_INPUT, "rotary axis %c: a number is not finite", name);
        if (ax->has_limits && !(isfinite(ax->limit_lo) && isfinite(ax->limit_hi) && ax->limit_lo <= ax->limit_hi))
            return fm_error_set(err, FM_ERR_INPUT, "rotary axis %c: limits are [lo, hi] in degrees with lo <= hi",
                                name);
    }
    int ntable = fm_machine_table_axes(mc);
    if (mc->frame_up < 0 || mc->frame_up > ntable)
        return fm_error_set(err, FM_ERR_INPUT, "the frame is %d links below the workpiece's, of %d table axes",
                            mc->frame_up, ntable);
    return FM_OK;
}

void fm_machine_table_transform(const fm_machine *mc, const double rotary[3], int upto, double rot[9],
                                double trans[3])
{
    static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(rot, I, sizeof I);
    trans[0] = trans[1] = trans[2] = 0;
    if (!mc) return;
    /* x_machine = R_1 R_2 ... R_n x_workpiece (each about its line with
     * every joint at 0: the product of exponentials); build it from the
     * innermost link outward. */
    int idx[FM_MACHINE_MAX_ROTARY], n = 0;
    for (int i = 0; i < mc->rotary_count; i++)
        if (mc->rotary[i].carries == FM_ROTARY_TABLE) idx[n++] = i;
    if (upto >= 0 && upto < n) n = upto;
    for (int j = n - 1; j >= 0; j--) {
        const fm_rotary_axis *ax = &mc->rotary[idx[j]];
        double R[9], r2[9], t2[3], Rb[3];
        rotation(ax->around, rotary[ax->letter] * FM_DEG, R);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) r2[3 * r + c] = R[3 * r] * rot[c] + R[3 * r + 1] * rot[3 + c] + R[3 * r + 2] * rot[6 + c];
        mat_vec(R, trans, t2);
        mat_vec(R, ax->through, Rb);
        for (int k = 0; k < 3; k++) trans[k] = t2[k] + ax->through[k] - Rb[k];
        memcpy(rot, r2, sizeof r2);
    }
}

void fm_motion_joints_at(const fm_motion *m, double t, double joints[3])
{
    joints[0] = joints[1] = joints[2] = 0;
    if (!m || !m->machine) return;
    double u = m->t1 > m->t0 ? (t - m->t0) / (m->t1 - m->t0) : 1.0;
    if (!(u > 0)) u = 0; /* NaN too */
    if (u > 1) u = 1;
    for (int l = 0; l < 3; l++) joints[l] = m->rotary_start[l] + u * (m->rotary_end[l] - m->rotary_start[l]);
}

/* -------------------------------------------------------------- chain -- */

/* The farthest the tool's point gets from each step's line over [ua, ub]
 * (raises reach[i]); defined with the boxes below. */
static void kin_reach(const fm_kin *k, double ua, double ub, double reach[]);

int fm_motion_has_rotary(const fm_motion *m)
{
    return m && m->machine && m->machine->rotary_count > 0 && m->kind != FM_MOTION_PARAM;
}

int fm_kin_init(fm_kin *k, const fm_motion *m, fm_error *err)
{
    memset(k, 0, sizeof *k);
    const fm_machine *mc = m->machine;
    k->tcp = m->tcp != 0;
    memcpy(k->off, m->tip_offset, sizeof k->off);
    if (m->kind == FM_MOTION_ARC) {
        if (!fm_motion_arc_of(m, &k->arc)) {
            fm_error_at(err, FM_ERR_INPUT, "", m->line, 0,
                        "motion %ld: arc with turns = 0, no centre, zero radius or a bad plane", m->index);
            return 0;
        }
        k->is_arc = 1;
    } else {
        memcpy(k->p0, m->start, sizeof k->p0);
        if (m->kind != FM_MOTION_DWELL)
            for (int i = 0; i < 3; i++) k->dp[i] = m->end[i] - m->start[i];
    }
    if (!finite3(m->rotary_start) || !finite3(m->rotary_end) || !isfinite(m->tool_length)) {
        fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: a rotary joint value is not finite", m->index);
        return 0;
    }
    int ntable = fm_machine_table_axes(mc);
    if (mc->frame_up < 0 || mc->frame_up > ntable) {
        fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: the machine's frame_up %d is not in 0..%d",
                    m->index, mc->frame_up, ntable);
        return 0;
    }
    /* Without TCP the inner frame_up table axes are left out (the pose in
     * the frame they ride on); with TCP every axis gives the orientation
     * and the inner table axes turn the tip into that frame afterwards. */
    int inverted = k->tcp ? ntable : ntable - mc->frame_up;
    /* Head axes, nearest the spindle first. */
    for (int i = mc->rotary_count - 1; i >= 0; i--) {
        const fm_rotary_axis *ax = &mc->rotary[i];
        if (ax->carries != FM_ROTARY_HEAD) continue;
        kin_step *s = &k->step[k->nsteps++];
        memcpy(s->omega, ax->around, sizeof s->omega);
        s->point = !k->tcp;
        /* The pivot with the programmed point at 0: the tip is at
         * tip_offset, the gauge line tool_length above it. */
        if (s->point) {
            for (int j = 0; j < 3; j++) s->b[j] = m->tip_offset[j] + ax->through[j];
            s->b[2] += m->tool_length + ax->pivot_length;
        }
        s->th0 = m->rotary_start[ax->letter] * FM_DEG;
        s->dth = (m->rotary_end[ax->letter] - m->rotary_start[ax->letter]) * FM_DEG;
    }
    if (!k->tcp) k->translate = k->nsteps;
    /* Table axes inverted, the base axis first. */
    for (int i = 0, t = 0; i < mc->rotary_count && t < inverted; i++) {
        const fm_rotary_axis *ax = &mc->rotary[i];
        if (ax->carries != FM_ROTARY_TABLE) continue;
        t++;
        kin_step *s = &k->step[k->nsteps++];
        memcpy(s->omega, ax->around, sizeof s->omega);
        s->point = !k->tcp;
        if (s->point) memcpy(s->b, ax->through, sizeof s->b);
        s->th0 = -m->rotary_start[ax->letter] * FM_DEG;
        s->dth = -(m->rotary_end[ax->letter] - m->rotary_start[ax->letter]) * FM_DEG;
    }
    if (k->tcp) {
        k->translate = k->nsteps;
        /* x_frame = R_{j+1} ... R_n x_workpiece: the innermost axis first. */
        for (int i = mc->rotary_count - 1, t = 0; i >= 0 && t < mc->frame_up; i--) {
            const fm_rotary_axis *ax = &mc->rotary[i];
            if (ax->carries != FM_ROTARY_TABLE) continue;
            t++;
            kin_step *s = &k->step[k->nsteps++];
            memcpy(s->omega, ax->around, sizeof s->omega);
            memcpy(s->b, ax->through, sizeof s->b);
            s->point = 1;
            s->th0 = m->rotary_start[ax->letter] * FM_DEG;
            s->dth = (m->rotary_end[ax->letter] - m->rotary_start[ax->letter]) * FM_DEG;
        }
    }

    /* Constants: |daxis/du| <= the sum of the joint rates (angular
     * velocities of a serial chain add); |dtip/du| <= |P'| plus each
     * joint's rate times the farthest the tip gets from its line, from the
     * boxes of 32 pieces. */
    double pspeed;
    if (k->is_arc) {
        double rmax = fmax(fabs(k->arc.r0), fabs(k->arc.r0 + k->arc.dr));
        pspeed = sqrt(rmax * k->arc.dth * rmax * k->arc.dth + k->arc.dh * k->arc.dh) + fabs(k->arc.dr);
    } else {
        pspeed = norm3(k->dp);
    }
    k->turn = 0;
    for (int i = 0; i < k->nsteps; i++) k->turn += fabs(k->step[i].dth);
    /* |P''|: an arc's centripetal and spiral terms. */
    double paccel = 0;
    if (k->is_arc) {
        double rmax = fmax(fabs(k->arc.r0), fabs(k->arc.r0 + k->arc.dr));
        paccel = rmax * k->arc.dth * k->arc.dth + 2 * fabs(k->arc.dr * k->arc.dth);
    }
    /* Step by step, a point turned about a fixed line by th(u):
     * p+' = R p' + th' w x (p+ - b), p+'' = R p'' + th' w x (R p' + p+'),
     * so |p+'| <= |p'| + |th'| d and |p+''| <= |p''| + |th'| (|p'| + |p+'|)
     * with d the farthest the point gets from the line (with TCP the
     * offset vector, |d| <= |o|). */
    double reach[KIN_MAX_STEPS] = {0};
    int turns_points = 0;
    for (int i = 0; i < k->nsteps; i++) turns_points |= k->step[i].point;
    if (turns_points)
        for (int piece = 0; piece < 32; piece++) kin_reach(k, piece / 32.0, (piece + 1) / 32.0, reach);
    for (int i = 0; i < k->nsteps; i++)
        if (!k->step[i].point) reach[i] = norm3(k->off);
    double sp = 0, ac = 0;
    for (int i = 0; i <= k->nsteps; i++) {
        if (i == k->translate) sp += pspeed, ac += paccel;
        if (i == k->nsteps) break;
        double w = fabs(k->step[i].dth), sp2 = sp + w * reach[i];
        ac += w * (sp + sp2);
        sp = sp2;
    }
    k->speed = sp;
    k->accel = ac;
    /* The tool frame turns at sum_j th_j' w_j(u), each w_j turned by the
     * later steps: |omega'| <= sum over i < j of |th_i'| |th_j'|. */
    k->domega = 0;
    for (int i = 0; i < k->nsteps; i++)
        for (int j = i + 1; j < k->nsteps; j++) k->domega += fabs(k->step[i].dth) * fabs(k->step[j].dth);
    k->speed *= 1 + 1e-12;
    k->turn *= 1 + 1e-12;
    k->accel *= 1 + 1e-12;
    k->domega *= 1 + 1e-12;
    return 1;
}

double fm_kin_second(const fm_kin *k, double vmax)
{
    /* q = R^T v, v = p - c: q'' = R^T (-c'' - omega' x v + 2 omega x c'
     * + omega x (omega x v)) (docs/sweep.md). */
    return (k->accel + k->domega * vmax + 2 * k->turn * k->speed + k->turn * k->turn * vmax) * (1 + 1e-12);
}

static void program_point(const fm_kin *k, double u, double p[3], double dp[3])
{
    if (k->is_arc) {
        fm_motion_arc_point(&k->arc, u, p, dp);
        return;
    }
    for (int i = 0; i < 3; i++) {
        p[i] = k->p0[i] + u * k->dp[i];
        if (dp) dp[i] = k->dp[i];
    }
}

void fm_kin_pose(const fm_kin *k, double u, double c[3], double a[3], double dc[3], double da[3])
{
    double p[3], v[3] = {0, 0, 1}, dp[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
    double P[3], dP[3];
    memcpy(p, k->off, sizeof p);
    program_point(k, u, P, dP);
    for (int i = 0; i <= k->nsteps; i++) {
        if (i == k->translate)
            for (int j = 0; j < 3; j++) p[j] += P[j], dp[j] += dP[j];
        if (i == k->nsteps) break;
        const kin_step *s = &k->step[i];
        double R[9], q[3], wq[3];
        rotation(s->omega, s->th0 + u * s->dth, R);
        for (int j = 0; j < 3; j++) q[j] = p[j] - s->b[j];
        mat_vec(R, q, q);
        for (int j = 0; j < 3; j++) p[j] = s->b[j] + q[j];
        mat_vec(R, v, v);
        if (dc) {
            /* d/du (R q) = R q' + dth (omega x R q) */
            mat_vec(R, dp, dp);
            cross3(s->omega, q, wq);
            for (int j = 0; j < 3; j++) dp[j] += s->dth * wq[j];
        }
        if (da) {
            mat_vec(R, dv, dv);
            cross3(s->omega, v, wq);
            for (int j = 0; j < 3; j++) dv[j] += s->dth * wq[j];
        }
    }
    memcpy(c, p, sizeof p);
    memcpy(a, v, sizeof v);
    if (dc) memcpy(dc, dp, sizeof dp);
    if (da) memcpy(da, dv, sizeof dv);
}

/* ------------------------------------------------------------- boxes -- */

/* A box as centre m and half-widths h. */
typedef struct kbox {
    double m[3], h[3];
} kbox;

/* The programmed point's box over [ua, ub]. */
static void program_box(const fm_kin *k, double ua, double ub, kbox *b)
{
    double lo[3], hi[3];
    if (k->is_arc) {
        fm_arc_box(&k->arc, ua, ub, lo, hi);
    } else {
        double pa[3], pb[3];
        program_point(k, ua, pa, NULL);
        program_point(k, ub, pb, NULL);
        for (int i = 0; i < 3; i++) {
            lo[i] = fmin(pa[i], pb[i]);
            hi[i] = fmax(pa[i], pb[i]);
        }
    }
    for (int i = 0; i < 3; i++) {
        b->m[i] = 0.5 * (lo[i] + hi[i]);
        b->h[i] = 0.5 * (hi[i] - lo[i]);
    }
}

/* Turn a box about the line (b, omega) by any angle within delta of th:
 * the box turned by th, then grown by the chord 2 sin(delta / 2) times the
 * farthest distance of the box from the line. Returns that distance. */
static double rotate_box(const kin_step *s, double th, double delta, int point, kbox *x)
{
    double R[9], q[3];
    rotation(s->omega, th, R);
    for (int j = 0; j < 3; j++) q[j] = x->m[j] - (point ? s->b[j] : 0);
    double along = dot3(q, s->omega), perp[3];
    for (int j = 0; j < 3; j++) perp[j] = q[j] - along * s->omega[j];
    double dist = norm3(perp) + norm3(x->h);
    double chord = 2 * sin(0.5 * fmin(delta, FM_PI)) * dist;
    double qm[3], h2[3];
    mat_vec(R, q, qm);
    for (int r = 0; r < 3; r++) {
        h2[r] = fabs(R[3 * r]) * x->h[0] + fabs(R[3 * r + 1]) * x->h[1] + fabs(R[3 * r + 2]) * x->h[2] + chord;
        /* rounding: a few ulps of the magnitudes involved */
        h2[r] += 1e-13 * (fabs(qm[r]) + dist + 1);
    }
    for (int j = 0; j < 3; j++) {
        x->m[j] = qm[j] + (point ? s->b[j] : 0);
        x->h[j] = h2[j];
    }
    return dist;
}

static void pose_boxes(const fm_kin *k, double ua, double ub, kbox *pb, kbox *vb, double reach[])
{
    double um = 0.5 * (ua + ub), w = 0.5 * (ub - ua);
    kbox P;
    program_box(k, ua, ub, &P);
    memset(pb, 0, sizeof *pb);
    memset(vb, 0, sizeof *vb);
    memcpy(pb->m, k->off, sizeof pb->m);
    vb->m[2] = 1;
    for (int i = 0; i <= k->nsteps; i++) {
        if (i == k->translate)
            for (int j = 0; j < 3; j++) pb->m[j] += P.m[j], pb->h[j] += P.h[j];
        if (i == k->nsteps) break;
        const kin_step *s = &k->step[i];
        double th = s->th0 + um * s->dth, delta = fabs(s->dth) * w;
        double d = rotate_box(s, th, delta, s->point, pb);
        if (reach && d > reach[i]) reach[i] = d;
        rotate_box(s, th, delta, 0, vb);
    }
    /* rounding of the additions (a frame with no step after the
     * translation gets no padding from rotate_box) */
    for (int j = 0; j < 3; j++) pb->h[j] += 1e-13 * (fabs(pb->m[j]) + pb->h[j] + 1);
}

static void kin_reach(const fm_kin *k, double ua, double ub, double reach[])
{
    kbox pb, vb;
    pose_boxes(k, ua, ub, &pb, &vb, reach);
}

void fm_kin_pose_box(const fm_kin *k, double ua, double ub, double clo[3], double chi[3], double alo[3],
                     double ahi[3])
{
    kbox pb, vb;
    pose_boxes(k, ua, ub, &pb, &vb, NULL);
    for (int j = 0; j < 3; j++) {
        clo[j] = pb.m[j] - pb.h[j];
        chi[j] = pb.m[j] + pb.h[j];
        /* The axis is a unit vector (its computed components may pass 1
         * by a rounding). */
        alo[j] = fmax(-1 - 1e-12, vb.m[j] - vb.h[j]);
        ahi[j] = fmin(1 + 1e-12, vb.m[j] + vb.h[j]);
    }
}

/* ------------------------------------------------------------ folding -- */

int fm_kin_fold(const fm_motion *m, fm_motion *out)
{
    if (!fm_motion_has_rotary(m)) return 0;
    const fm_machine *mc = m->machine;
    for (int i = 0; i < mc->rotary_count; i++) {
        int l = mc->rotary[i].letter;
        if (m->rotary_start[l] != m->rotary_end[l]) return 0;
    }
    fm_kin k;
    if (!fm_kin_init(&k, m, NULL)) return 0;
    /* tip(u) = M P(u) + t: M the rotation of the steps after the
     * translation (without TCP the table's inverse; with it the turn into a
     * frame nearer the base, or the identity). */
    double M[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3], axis[3];
    for (int i = k.translate; i < k.nsteps; i++) {
        double R[9], r2[9];
        rotation(k.step[i].omega, k.step[i].th0, R);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                r2[3 * r + c] = R[3 * r] * M[c] + R[3 * r + 1] * M[3 + c] + R[3 * r + 2] * M[6 + c];
        memcpy(M, r2, sizeof M);
    }
    /* t: the tip with the programmed point at 0. */
    fm_kin k0 = k;
    k0.is_arc = 0;
    memset(k0.p0, 0, sizeof k0.p0);
    memset(k0.dp, 0, sizeof k0.dp);
    fm_kin_pose(&k0, 0, t, axis, NULL, NULL);
    *out = *m;
    out->machine = NULL;
    memset(out->tip_offset, 0, sizeof out->tip_offset);
    memcpy(out->axis_start, axis, sizeof axis);
    memcpy(out->axis_end, axis, sizeof axis);
    double ctr[3];
    if (m->kind == FM_MOTION_ARC) {
        /* The arc's plane must land on a coordinate plane. */
        int kk = k.arc.plane_axis, k2 = -1;
        double sgn = 0;
        for (int j = 0; j < 3; j++)
            if (fabs(fabs(M[3 * j + kk]) - 1) <= 1e-9) k2 = j, sgn = M[3 * j + kk] > 0 ? 1 : -1;
        if (k2 < 0) return 0;
        memcpy(ctr, k.arc.center, sizeof ctr);
        mat_vec(M, ctr, out->center);
        for (int j = 0; j < 3; j++) out->center[j] += t[j];
        out->plane_axis = k2;
        out->turns = sgn > 0 ? m->turns : -m->turns;
    }
    mat_vec(M, m->start, out->start);
    mat_vec(M, m->end, out->end);
    for (int j = 0; j < 3; j++) {
        out->start[j] += t[j];
        out->end[j] += t[j];
    }
    if (m->kind == FM_MOTION_ARC) {
        /* Snap the rotated arc exactly into its plane (rounding of cos 90). */
        out->center[out->plane_axis] = out->start[out->plane_axis];
    }
    return 1;
}

/* --------------------------------------------------------------- DAG -- */

/* A point (or vector) turned about the line (b, omega) by the angle node
 * th: Rodrigues, q' = q cos + (omega x q) sin + omega (omega . q)(1 - cos). */
static void build_rotate(fm_graph *g, const kin_step *s, fm_node th, int point, fm_node p[3])
{
    fm_node co = fm_unary(g, FM_OP_COS, th), si = fm_unary(g, FM_OP_SIN, th);
    fm_node omc = fm_sub(g, fm_const(g, 1), co);
    fm_node q[3], wq = fm_const(g, 0);
    for (int j = 0; j < 3; j++) {
        q[j] = point ? fm_sub(g, p[j], fm_const(g, s->b[j])) : p[j];
        wq = fm_add(g, wq, fm_mul(g, fm_const(g, s->omega[j]), q[j]));
    }
    const double *w = s->omega;
    fm_node cx[3];
    for (int j = 0; j < 3; j++) {
        int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
        cx[j] = fm_sub(g, fm_mul(g, fm_const(g, w[j1]), q[j2]), fm_mul(g, fm_const(g, w[j2]), q[j1]));
    }
    for (int j = 0; j < 3; j++) {
        fm_node r = fm_add(g, fm_add(g, fm_mul(g, q[j], co), fm_mul(g, cx[j], si)),
                           fm_mul(g, fm_const(g, w[j]), fm_mul(g, wq, omc)));
        p[j] = point ? fm_add(g, r, fm_const(g, s->b[j])) : r;
    }
}

void fm_kin_build_pose(fm_graph *g, const fm_kin *k, fm_node u, fm_node c[3], fm_node a[3])
{
    fm_node P[3];
    if (k->is_arc) {
        const fm_motion_arc *ar = &k->arc;
        fm_node th = fm_add(g, fm_const(g, ar->th0), fm_mul(g, u, fm_const(g, ar->dth)));
        fm_node rr = fm_add(g, fm_const(g, ar->r0), fm_mul(g, u, fm_const(g, ar->dr)));
        P[ar->ai] = fm_add(g, fm_const(g, ar->center[ar->ai]), fm_mul(g, rr, fm_unary(g, FM_OP_COS, th)));
        P[ar->aj] = fm_add(g, fm_const(g, ar->center[ar->aj]), fm_mul(g, rr, fm_unary(g, FM_OP_SIN, th)));
        P[ar->plane_axis] = fm_add(g, fm_const(g, ar->center[ar->plane_axis]), fm_mul(g, u, fm_const(g, ar->dh)));
    } else {
        for (int j = 0; j < 3; j++) P[j] = fm_add(g, fm_const(g, k->p0[j]), fm_mul(g, u, fm_const(g, k->dp[j])));
    }
    fm_node p[3], v[3];
    for (int j = 0; j < 3; j++) {
        p[j] = fm_const(g, k->off[j]);
        v[j] = fm_const(g, j == 2 ? 1 : 0);
    }
    for (int i = 0; i <= k->nsteps; i++) {
        if (i == k->translate)
            for (int j = 0; j < 3; j++) p[j] = fm_add(g, p[j], P[j]);
        if (i == k->nsteps) break;
        const kin_step *s = &k->step[i];
        fm_node th = fm_add(g, fm_const(g, s->th0), fm_mul(g, u, fm_const(g, s->dth)));
        build_rotate(g, s, th, s->point, p);
        build_rotate(g, s, th, 0, v);
    }
    for (int j = 0; j < 3; j++) {
        c[j] = p[j];
        a[j] = v[j];
    }
}
