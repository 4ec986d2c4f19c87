/* limits.c: a machine's dynamics and what they allow a segment: the
 * defaults, the straight and arc limits (LinuxCNC canon's per-axis scaling
 * and the tp's normal-acceleration limit of arcs), the limit in a corner's
 * plane. */
#include <math.h>

#include "toolpaths/plan/plan_internal.h"

void fm_plan_machine_default(fm_plan_machine *m)
{
    *m = (fm_plan_machine){0};
    m->servo_period_s = 0.001;
    m->max_feed_override = 1.0;
    m->lookahead = 50;
    m->blend_gap_cycles = 4;
    m->kink_ratio = 0.1;
    m->rapid_rate = 5000.0;
}

/* The time the slowest axis needs per unit of its own limit: max |d_i| / lim_i
 * over the limited axes that move. 0 when no limited axis moves. */
static double slowest_axis(const double d[3], const double r[3], const double lin[3],
                           const double rot[3])
{
    double t = 0.0;
    for (int i = 0; i < 3; i++) {
        if (lin[i] > 0.0 && fabs(d[i]) > 0.0) t = fmax(t, fabs(d[i]) / lin[i]);
        if (rot[i] > 0.0 && fabs(r[i]) > 0.0) t = fmax(t, fabs(r[i]) / rot[i]);
    }
    return t;
}

void plan_line_limits(const fm_plan_machine *m, const double d[3], const double r[3], int rapid,
                      double *length, double *maxvel, double *maxaccel)
{
    double lin_v[3], rot_v[3], lin_a[3], rot_a[3];
    for (int i = 0; i < 3; i++) {
        lin_v[i] = m->linear[i].max_velocity;
        if (rapid && m->rapid_velocity[i] > 0.0) lin_v[i] = m->rapid_velocity[i];
        rot_v[i] = m->rotary[i].max_velocity;
        lin_a[i] = m->linear[i].max_acceleration;
        rot_a[i] = m->rotary[i].max_acceleration;
    }
    double xyz = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double abc = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    double L = xyz > 1e-9 ? xyz : abc;
    double tv = slowest_axis(d, r, lin_v, rot_v);
    double ta = slowest_axis(d, r, lin_a, rot_a);
    double v = tv > 0.0 ? L / tv : INFINITY;
    double a = ta > 0.0 ? L / ta : INFINITY;
    if (xyz > 1e-9) {
        if (m->traj_max_velocity > 0.0) v = fmin(v, m->traj_max_velocity);
        if (m->traj_max_acceleration > 0.0) a = fmin(a, m->traj_max_acceleration);
    }
    *length = L;
    *maxvel = v;
    *maxaccel = a;
}

void plan_curvature_limits(double radius, double maxvel, double maxaccel, double *vmax,
                           double *acc_ratio_tan)
{
    /* The normal acceleration v^2/R may take at most 0.866 of the
     * acceleration, leaving half of it for speeding up and slowing down;
     * below that speed the tangential share is what the normal one leaves. */
    double a_n_cutoff = PLAN_ACC_RATIO_NORMAL * maxaccel;
    double v = maxvel;
    double ratio = PLAN_ACC_RATIO_TANGENTIAL;
    if (!(radius > 0.0) || !isfinite(maxaccel)) {
        *vmax = v;
        *acc_ratio_tan = isfinite(maxaccel) ? ratio : 1.0;
        return;
    }
    double a_n_vmax = maxvel * maxvel / radius;
    if (a_n_vmax > a_n_cutoff)
        v = sqrt(a_n_cutoff * radius);
    else
        ratio = sqrt(1.0 - (a_n_vmax / maxaccel) * (a_n_vmax / maxaccel));
    *vmax = v;
    *acc_ratio_tan = ratio;
}

void plan_arc_limits(const fm_plan_machine *m, const plan_seg *arc, double *maxvel,
                     double *maxaccel, double *acc_ratio_tan)
{
    /* The plane axes are the two the normal does not point along; the
     * helix axis moves helix*angle over the arc's length. */
    int k = 0;
    double an = 0.0;
    for (int i = 0; i < 3; i++)
        if (fabs(arc->normal[i]) > an) {
            an = fabs(arc->normal[i]);
            k = i;
        }
    double v = INFINITY, a = INFINITY;
    for (int i = 0; i < 3; i++) {
        if (i == k) continue;
        if (m->linear[i].max_velocity > 0.0) v = fmin(v, m->linear[i].max_velocity);
        if (m->linear[i].max_acceleration > 0.0) a = fmin(a, m->linear[i].max_acceleration);
    }
    double h = fabs(arc->helix * arc->angle);
    if (h > 1e-9 && arc->length > 0.0) {
        double share = h / arc->length;
        if (m->linear[k].max_velocity > 0.0) v = fmin(v, m->linear[k].max_velocity / share);
        if (m->linear[k].max_acceleration > 0.0)
            a = fmin(a, m->linear[k].max_acceleration / share);
    }
    if (m->traj_max_velocity > 0.0) v = fmin(v, m->traj_max_velocity);
    if (m->traj_max_acceleration > 0.0) a = fmin(a, m->traj_max_acceleration);
    /* The radius of curvature of a helix: R + c^2/R, c its rise per radian. */
    double r_eff = arc->radius + arc->helix * arc->helix / arc->radius;
    plan_curvature_limits(r_eff, v, a, maxvel, acc_ratio_tan);
    *maxaccel = a;
}

double plan_plane_limit(const double n[3], const double bounds[3])
{
    double best = INFINITY;
    for (int i = 0; i < 3; i++) {
        if (!(bounds[i] > 0.0)) continue;
        /* the length of axis i's unit vector projected into the plane */
        double scale = sqrt(fmax(0.0, 1.0 - n[i] * n[i]));
        if (scale > 1e-12) best = fmin(best, bounds[i] / scale);
    }
    return isfinite(best) ? best : 0.0;
}
