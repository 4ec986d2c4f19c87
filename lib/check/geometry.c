/* geometry.c: what the check needs to know of a motion's path, on top of
 * lib/sweep's motion geometry (fm_motion_arc_of): its descent along the
 * tool axis, the box of its programmed point, and the motion up to a
 * parameter u (the flutes' sweep up to a time). */
#include "check/check_internal.h"

#include <math.h>
#include <string.h>

/* Swept angle of an arc in radians (positive), its radius at the start,
 * its start angle and direction (lib/sweep's reading of the arc). */
double check_arc_angle(const fm_motion *m, double *radius, double *a0, int *ccw)
{
    fm_motion_arc arc;
    fm_motion_arc_of(m, &arc);
    *radius = arc.r0;
    *a0 = arc.th0;
    *ccw = arc.dth >= 0;
    return fabs(arc.dth);
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
    return atan2(down, lateral) * 180.0 / FM_PI;
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
        for (int k = -8; k <= 8 + 4 * (int)(ang / (2 * FM_PI)); k++) {
            double q = k * 0.5 * FM_PI;
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
    memcpy(out->rotary_end, m->rotary_start, sizeof out->rotary_end);
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
    /* rotary joints move linearly in u (docs/sweep.md) */
    for (int k = 0; k < 3; k++) out->rotary_end[k] = m->rotary_start[k] + u * (m->rotary_end[k] - m->rotary_start[k]);
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
        fm_motion_arc arc;
        if (!fm_motion_arc_of(m, &arc)) {
            still_at_start(m, out);
            return;
        }
        double ang = fabs(arc.dth), part = u * ang;
        if (part < 1e-9) {
            still_at_start(m, out);
            return;
        }
        /* Whole turns in the prefix: LinuxCNC counts |turns| - 1 extra
         * circles beyond the angle from start to end. An end angle within a
         * hair of a whole turn is moved a hair on, so that the count is
         * never read a turn short; a slightly longer prefix only makes the
         * flutes' sweep larger, which never adds a contact. */
        double two_pi = 2 * FM_PI;
        double whole = floor(part / two_pi);
        if (part - whole * two_pi < 1e-7) part = whole * two_pi + 1e-7;
        if (part > ang) part = ang;
        int turns = (int)floor(part / two_pi) + 1;
        double up = part / ang;
        fm_motion_arc_point(&arc, up, out->end, NULL);
        out->turns = arc.dth > 0 ? turns : -turns;
        out->t1 = m->t0 + up * (m->t1 - m->t0);
        for (int k = 0; k < 3; k++)
            out->rotary_end[k] = m->rotary_start[k] + up * (m->rotary_end[k] - m->rotary_start[k]);
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
