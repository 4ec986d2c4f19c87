/* geometry.c: the geometry of a motion in one place: LinuxCNC's arc
 * semantics, the programmed point and the tool's pose at a motion
 * parameter u, sound boxes of the pose over a piece of the motion, and
 * how finely to draw it. The sweep (setup.c), the check, the pictures'
 * toolpath and the viewer's toolpath all use these, so that they agree. */
#include "sweep/kin_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

static int finite3(const double v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

int fm_motion_arc_of(const fm_motion *m, fm_motion_arc *a)
{
    memset(a, 0, sizeof *a);
    int ok = 1, k = m->plane_axis;
    if (k < 0 || k > 2) {
        k = 2;
        ok = 0;
    }
    a->plane_axis = k;
    a->ai = (k + 1) % 3; /* (X, Y) about Z, (Z, X) about Y, (Y, Z) about X: right-handed */
    a->aj = (k + 2) % 3;
    memcpy(a->center, m->center, sizeof a->center);
    a->center[k] = m->start[k];
    if (!finite3(m->center) || !finite3(m->start) || !finite3(m->end) || m->turns == 0) ok = 0;
    double si = m->start[a->ai] - m->center[a->ai], sj = m->start[a->aj] - m->center[a->aj];
    double ei = m->end[a->ai] - m->center[a->ai], ej = m->end[a->aj] - m->center[a->aj];
    a->r0 = sqrt(si * si + sj * sj);
    a->dr = sqrt(ei * ei + ej * ej) - a->r0;
    if (!(a->r0 > 1e-9)) ok = 0;
    a->dh = m->end[k] - m->start[k];
    if (!ok) {
        a->dr = 0;
        a->r0 = isfinite(a->r0) ? a->r0 : 0;
        a->dh = isfinite(a->dh) ? a->dh : 0;
        return 0;
    }
    a->th0 = atan2(sj, si);
    double th1 = atan2(ej, ei);
    double delta = m->turns > 0 ? th1 - a->th0 : a->th0 - th1;
    delta = fmod(delta, 2 * FM_PI);
    if (delta < 0) delta += 2 * FM_PI;
    if (delta < 1e-12) delta = 2 * FM_PI; /* same start and end angle: a full circle */
    delta += 2 * FM_PI * (fabs((double)m->turns) - 1);
    a->dth = m->turns > 0 ? delta : -delta;
    return 1;
}

void fm_motion_arc_point(const fm_motion_arc *a, double u, double p[3], double dp[3])
{
    double th = a->th0 + u * a->dth, r = a->r0 + u * a->dr;
    double co = cos(th), si = sin(th);
    memcpy(p, a->center, 3 * sizeof *p);
    p[a->ai] += r * co;
    p[a->aj] += r * si;
    p[a->plane_axis] += u * a->dh;
    if (dp) {
        dp[a->ai] = a->dr * co - r * a->dth * si;
        dp[a->aj] = a->dr * si + r * a->dth * co;
        dp[a->plane_axis] = a->dh;
    }
}

/* Box of the arc's points over [ua, ub]: with a constant radius the ends
 * and the quadrant points passed (exact); a spiral's points lie within
 * speed * (ub - ua) / 2 of the nearer end and within its larger circle. */
void fm_arc_box(const fm_motion_arc *a, double ua, double ub, double lo[3], double hi[3])
{
    double pa[3], pb[3];
    fm_motion_arc_point(a, ua, pa, NULL);
    fm_motion_arc_point(a, ub, pb, NULL);
    for (int i = 0; i < 3; i++) {
        lo[i] = fmin(pa[i], pb[i]);
        hi[i] = fmax(pa[i], pb[i]);
    }
    double rmax = fmax(fabs(a->r0 + ua * a->dr), fabs(a->r0 + ub * a->dr));
    int ai = a->ai, aj = a->aj;
    if (fabs(a->dr) <= 1e-12 * (1 + a->r0)) {
        double t0 = a->th0 + ua * a->dth, t1 = a->th0 + ub * a->dth;
        double tl = fmin(t0, t1), th = fmax(t0, t1);
        if (th - tl >= 2 * FM_PI) {
            tl = 0;
            th = 2 * FM_PI;
        }
        for (double q = ceil(tl / (FM_PI / 2)); q <= floor(th / (FM_PI / 2)); q++) {
            double ci = a->center[ai] + rmax * cos(q * FM_PI / 2), cj = a->center[aj] + rmax * sin(q * FM_PI / 2);
            lo[ai] = fmin(lo[ai], ci), hi[ai] = fmax(hi[ai], ci);
            lo[aj] = fmin(lo[aj], cj), hi[aj] = fmax(hi[aj], cj);
        }
        /* rounding of cos and sin */
        for (int i = 0; i < 3; i++) {
            double e = 1e-13 * (fabs(lo[i]) + fabs(hi[i]) + rmax + 1);
            lo[i] -= e;
            hi[i] += e;
        }
        return;
    }
    double sp = sqrt(rmax * a->dth * rmax * a->dth + a->dh * a->dh) + fabs(a->dr);
    double grow = sp * (ub - ua) * 0.5;
    int ax[2] = {ai, aj};
    for (int q = 0; q < 2; q++) {
        int i = ax[q];
        lo[i] = fmax(lo[i] - grow, a->center[i] - rmax);
        hi[i] = fmin(hi[i] + grow, a->center[i] + rmax);
    }
}

void fm_motion_point_at(const fm_motion *m, double u, double p[3])
{
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    if (m->kind == FM_MOTION_ARC) {
        fm_motion_arc a;
        if (fm_motion_arc_of(m, &a)) {
            fm_motion_arc_point(&a, u, p, NULL);
            return;
        }
    }
    if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose) {
        double axis[3];
        m->path->pose(m->path->ctx, m->t0 + u * (m->t1 - m->t0), p, axis);
        for (int i = 0; i < 3; i++) p[i] -= m->tip_offset[i];
        return;
    }
    if (m->kind == FM_MOTION_DWELL) u = 0;
    for (int i = 0; i < 3; i++) p[i] = m->start[i] + u * (m->end[i] - m->start[i]);
}

static void unit_or_z(double a[3])
{
    double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(n > 1e-12) || !isfinite(n)) {
        a[0] = a[1] = 0;
        a[2] = 1;
        return;
    }
    for (int i = 0; i < 3; i++) a[i] /= n;
}

void fm_motion_pose_at(const fm_motion *m, double u, double tip[3], double axis[3])
{
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    if (fm_motion_has_rotary(m)) {
        fm_kin k;
        if (fm_kin_init(&k, m, NULL)) {
            fm_kin_pose(&k, u, tip, axis, NULL, NULL);
            return;
        }
    }
    if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose) {
        m->path->pose(m->path->ctx, m->t0 + u * (m->t1 - m->t0), tip, axis);
        for (int i = 0; i < 3; i++) tip[i] += m->tip_offset[i];
        unit_or_z(axis);
        return;
    }
    fm_motion_point_at(m, u, tip);
    for (int i = 0; i < 3; i++) tip[i] += m->tip_offset[i];
    if (m->kind == FM_MOTION_LINE || m->kind == FM_MOTION_RAPID) {
        double a0[3], a1[3];
        memcpy(a0, m->axis_start, sizeof a0);
        memcpy(a1, m->axis_end, sizeof a1);
        unit_or_z(a0);
        unit_or_z(a1);
        for (int i = 0; i < 3; i++) axis[i] = (1 - u) * a0[i] + u * a1[i];
        unit_or_z(axis);
        return;
    }
    memcpy(axis, m->axis_start, 3 * sizeof *axis);
    unit_or_z(axis);
}

void fm_motion_pose_bounds(const fm_motion *m, double ua, double ub, double clo[3], double chi[3],
                           double alo[3], double ahi[3])
{
    ua = ua < 0 ? 0 : ua > 1 ? 1 : ua;
    ub = ub < ua ? ua : ub > 1 ? 1 : ub;
    if (fm_motion_has_rotary(m)) {
        fm_kin k;
        if (fm_kin_init(&k, m, NULL)) {
            fm_kin_pose_box(&k, ua, ub, clo, chi, alo, ahi);
            return;
        }
    }
    if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose_bounds) {
        m->path->pose_bounds(m->path->ctx, m->t0 + ua * (m->t1 - m->t0), m->t0 + ub * (m->t1 - m->t0), clo, chi,
                             alo, ahi);
        for (int i = 0; i < 3; i++) {
            clo[i] += m->tip_offset[i];
            chi[i] += m->tip_offset[i];
            alo[i] = fmax(alo[i], -1);
            ahi[i] = fmin(ahi[i], 1);
        }
        return;
    }
    fm_motion_arc a;
    if (m->kind == FM_MOTION_ARC && fm_motion_arc_of(m, &a)) {
        fm_arc_box(&a, ua, ub, clo, chi);
    } else {
        double pa[3], pb[3];
        fm_motion_point_at(m, ua, pa);
        fm_motion_point_at(m, ub, pb);
        for (int i = 0; i < 3; i++) {
            clo[i] = fmin(pa[i], pb[i]);
            chi[i] = fmax(pa[i], pb[i]);
        }
    }
    for (int i = 0; i < 3; i++) {
        clo[i] += m->tip_offset[i];
        chi[i] += m->tip_offset[i];
    }
    double a0[3], a1[3];
    memcpy(a0, m->axis_start, sizeof a0);
    memcpy(a1, m->axis_end, sizeof a1);
    unit_or_z(a0);
    unit_or_z(a1);
    if (m->kind != FM_MOTION_LINE && m->kind != FM_MOTION_RAPID) memcpy(a1, a0, sizeof a0);
    /* nlerp: l(u) linear, |l| >= lmin (half the length of a0 + a1) */
    double h[3] = {a0[0] + a1[0], a0[1] + a1[1], a0[2] + a1[2]};
    double lmin = 0.5 * sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int i = 0; i < 3; i++) {
        double l0 = (1 - ua) * a0[i] + ua * a1[i], l1 = (1 - ub) * a0[i] + ub * a1[i];
        double llo = fmin(l0, l1), lhi = fmax(l0, l1);
        if (lmin > 1e-9) {
            alo[i] = llo >= 0 ? llo : llo / lmin;
            ahi[i] = lhi <= 0 ? lhi : lhi / lmin;
        } else {
            alo[i] = -1, ahi[i] = 1;
        }
        alo[i] = fmax(alo[i] - 1e-15, -1);
        ahi[i] = fmin(ahi[i] + 1e-15, 1);
    }
}

int fm_motion_pieces(const fm_motion *m, double max_angle, int param_pieces, int max_pieces)
{
    if (max_pieces < 1) max_pieces = 1;
    if (!(max_angle > 0)) max_angle = FM_PI / 36;
    double n = 1;
    if (m->kind == FM_MOTION_PARAM) n = param_pieces;
    fm_motion_arc a;
    if (m->kind == FM_MOTION_ARC && fm_motion_arc_of(m, &a)) n = fmax(n, ceil(fabs(a.dth) / max_angle));
    if (fm_motion_has_rotary(m))
        for (int i = 0; i < m->machine->rotary_count; i++) {
            int l = m->machine->rotary[i].letter;
            double d = fabs(m->rotary_end[l] - m->rotary_start[l]) * FM_PI / 180;
            if (isfinite(d)) n = fmax(n, ceil(d / max_angle));
        }
    if (!(n >= 1)) n = 1;
    return n > max_pieces ? max_pieces : (int)n;
}
