/* geometry.c: what the check needs to know of a motion's path: its swept
 * arc angle (LinuxCNC's ARC_FEED semantics, as lib/sweep reads it), its
 * descent along the tool axis, the box of its programmed point, and the
 * motion up to a parameter u (the flutes' sweep up to a time). */
#include "check/check_internal.h"

#include <math.h>
#include <string.h>

#define CHECK_PI 3.14159265358979323846

/* Swept angle of an arc in radians (positive), its radius at the start,
 * its start angle and direction. */
double check_arc_angle(const fm_motion *m, double *radius, double *a0, int *ccw)
{
    int p = m->plane_axis, u = (p + 1) % 3, v = (p + 2) % 3;
    double su = m->start[u] - m->center[u], sv = m->start[v] - m->center[v];
    double eu = m->end[u] - m->center[u], ev = m->end[v] - m->center[v];
    double s = atan2(sv, su), e = atan2(ev, eu);
    *radius = sqrt(su * su + sv * sv);
    *a0 = s;
    *ccw = m->turns >= 0;
    int turns = m->turns < 0 ? -m->turns : m->turns;
    double sweep = *ccw ? e - s : s - e;
    sweep = fmod(sweep, 2 * CHECK_PI);
    if (sweep < 0) sweep += 2 * CHECK_PI;
    if (sweep < 1e-12) sweep = 2 * CHECK_PI; /* same start and end angle: a full circle */
    if (turns > 1) sweep += 2 * CHECK_PI * (turns - 1);
    return sweep;
}

double check_descent_deg(const fm_motion *m)
{
    const double *ax = m->axis_start;
    double d[3], along = 0;
    for (int a = 0; a < 3; a++) {
        d[a] = m->end[a] - m->start[a];
        along += d[a] * ax[a];
    }
    double down = -along;
    if (down <= 1e-12) return 0;
    double lateral;
    if (m->kind == FM_MOTION_ARC) {
        double r, a0;
        int ccw;
        /* the helix descends along its plane axis while it turns */
        double ang = check_arc_angle(m, &r, &a0, &ccw);
        lateral = r * ang;
    } else {
        double l2 = 0;
        for (int a = 0; a < 3; a++) {
            double q = d[a] - along * ax[a];
            l2 += q * q;
        }
        lateral = sqrt(l2);
    }
    return atan2(down, lateral) * 180.0 / CHECK_PI;
}

void check_motion_point_bounds(const fm_motion *m, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = fmin(m->start[a], m->end[a]);
        hi[a] = fmax(m->start[a], m->end[a]);
    }
    if (m->kind == FM_MOTION_ARC) {
        double r, a0;
        int ccw;
        double ang = check_arc_angle(m, &r, &a0, &ccw);
        int p = m->plane_axis, u = (p + 1) % 3, v = (p + 2) % 3;
        /* the circle's extreme points that the arc passes */
        for (int k = -8; k <= 8 + 4 * (int)(ang / (2 * CHECK_PI)); k++) {
            double q = k * 0.5 * CHECK_PI;
            double rel = ccw ? q - a0 : a0 - q;
            if (rel < 0 || rel > ang) continue;
            double pu = m->center[u] + r * cos(q), pv = m->center[v] + r * sin(q);
            lo[u] = fmin(lo[u], pu);
            hi[u] = fmax(hi[u], pu);
            lo[v] = fmin(lo[v], pv);
            hi[v] = fmax(hi[v], pv);
        }
    } else if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose_bounds) {
        double plo[3], phi[3], alo[3], ahi[3];
        m->path->pose_bounds(m->path->ctx, m->t0, m->t1, plo, phi, alo, ahi);
        /* the path gives the tip; the programmed point is the tip minus the offset */
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], plo[a] - m->tip_offset[a]);
            hi[a] = fmax(hi[a], phi[a] - m->tip_offset[a]);
        }
    }
}

/* A motion standing still at the start of m. */
static void still_at_start(const fm_motion *m, fm_motion *out)
{
    *out = *m;
    out->kind = FM_MOTION_RAPID;
    memcpy(out->end, m->start, sizeof out->end);
    memcpy(out->axis_end, m->axis_start, sizeof out->axis_end);
    out->t1 = m->t0;
    if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose) {
        double c[3], a[3];
        m->path->pose(m->path->ctx, m->t0, c, a);
        for (int k = 0; k < 3; k++) {
            out->start[k] = out->end[k] = c[k] - m->tip_offset[k];
            out->axis_start[k] = out->axis_end[k] = a[k];
        }
    }
    out->path = NULL;
}

void check_motion_prefix(const fm_motion *m, double u, fm_motion *out)
{
    *out = *m;
    if (u >= 1) return;
    if (!(u > 0)) {
        still_at_start(m, out);
        return;
    }
    out->t1 = m->t0 + u * (m->t1 - m->t0);
    switch (m->kind) {
    case FM_MOTION_RAPID:
    case FM_MOTION_LINE: {
        double l[3], n = 0;
        for (int k = 0; k < 3; k++) {
            out->end[k] = m->start[k] + u * (m->end[k] - m->start[k]);
            l[k] = (1 - u) * m->axis_start[k] + u * m->axis_end[k];
            n += l[k] * l[k];
        }
        /* the axis as lib/sweep interpolates it (normalized linear) */
        n = sqrt(n);
        if (n > 0)
            for (int k = 0; k < 3; k++) out->axis_end[k] = l[k] / n;
        return;
    }
    case FM_MOTION_ARC: {
        double r0, a0;
        int ccw;
        double ang = check_arc_angle(m, &r0, &a0, &ccw);
        int p = m->plane_axis, i = (p + 1) % 3, j = (p + 2) % 3;
        double r1 = hypot(m->end[i] - m->center[i], m->end[j] - m->center[j]);
        double part = u * ang;
        if (part < 1e-9) {
            still_at_start(m, out);
            return;
        }
        /* Whole turns in the prefix: LinuxCNC counts |turns| - 1 extra
         * circles beyond the angle from start to end. An end angle within a
         * hair of a whole turn is moved a hair on, so that the count is
         * never read a turn short; a slightly longer prefix only makes the
         * flutes' sweep larger, which never adds a contact. */
        double two_pi = 2 * CHECK_PI;
        double whole = floor(part / two_pi);
        if (part - whole * two_pi < 1e-7) part = whole * two_pi + 1e-7;
        if (part > ang) part = ang;
        int turns = (int)floor(part / two_pi) + 1;
        double th = ccw ? a0 + part : a0 - part;
        double rr = r0 + (part / ang) * (r1 - r0);
        out->end[i] = m->center[i] + rr * cos(th);
        out->end[j] = m->center[j] + rr * sin(th);
        out->end[p] = m->start[p] + (part / ang) * (m->end[p] - m->start[p]);
        out->turns = ccw ? turns : -turns;
        out->t1 = m->t0 + (part / ang) * (m->t1 - m->t0);
        return;
    }
    case FM_MOTION_PARAM:
        /* the path is read by time: t1 is the prefix */
        return;
    case FM_MOTION_DWELL:
    default:
        still_at_start(m, out);
        return;
    }
}
