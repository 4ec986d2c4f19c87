/* blend.c: the blend arc of a G64 corner (LinuxCNC's blendmath.c: the
 * corner's tolerance, how much of each segment it may take, the plane's
 * acceleration and velocity limits, the arc's radius and planned speed). */
#include <math.h>

#include "toolpaths/plan/plan_internal.h"

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static int unit3(const double a[3], double out[3])
{
    double n = sqrt(dot3(a, a));
    if (!(n > 1e-12)) return -1;
    for (int i = 0; i < 3; i++) out[i] = a[i] / n;
    return 0;
}

/* The tolerance of a corner: each segment's G64 P, or a quarter of its
 * length without one, and never more than a quarter of either length
 * (LinuxCNC's tcFindBlendTolerance). */
static double corner_tolerance(const plan_seg *prev, const plan_seg *next)
{
    double T1 = prev->tolerance > 0.0 ? prev->tolerance : prev->nominal_length * PLAN_TOLERANCE_RATIO;
    double T2 = next->tolerance > 0.0 ? next->tolerance : next->nominal_length * PLAN_TOLERANCE_RATIO;
    double T = fmin(T1, T2);
    T = fmin(T, prev->nominal_length * PLAN_TOLERANCE_RATIO);
    return fmin(T, next->nominal_length * PLAN_TOLERANCE_RATIO);
}

/* An arc's side of a corner (LinuxCNC's blendInit3From*Arc*): convex when
 * the arc bends on with the corner (arcConvexTest), then the blend may
 * reach a quarter of the corner's angle along it and is planned on the
 * secant's direction; concave, up to a quarter turn. Returns the reach
 * (L), tightens *theta for a convex arc. before: the arc ends at P. */
static double arc_side(const plan_seg *arc, int before, const double P[3], const double u_other[3],
                       double theta_tan, double *theta)
{
    double diff[3] = {P[0] - arc->center[0], P[1] - arc->center[1], P[2] - arc->center[2]};
    double d = dot3(diff, u_other);
    int convex = before ? d < 0.0 : !(d < 0.0);
    double share = before ? 2.0 / 3.0 : 1.0 / 3.0;
    double phi_max = fmin(arc->angle * share, convex ? theta_tan : PLAN_PI / 2.0);
    if (!convex) return phi_max * arc->radius;
    *theta = fmin(*theta, theta_tan - phi_max / 4.0);
    return sin(phi_max / 4.0) * arc->radius;
}

int plan_blend_compute(const fm_plan_machine *m, const plan_seg *prev, const plan_seg *next,
                       plan_blend_params *o)
{
    plan_blend_params p = {0};
    const double *u1 = prev->u_end, *u2 = next->u_start;
    double d = fmax(-1.0, fmin(1.0, dot3(u1, u2)));
    p.theta = acos(-d) / 2.0;
    if (PLAN_PI / 2.0 - p.theta < 1e-6 || p.theta < 1e-6) return -1;
    double cross[3] = {u1[1] * u2[2] - u1[2] * u2[1], u1[2] * u2[0] - u1[0] * u2[2],
                       u1[0] * u2[1] - u1[1] * u2[0]};
    double binormal[3];
    if (unit3(cross, binormal)) return -1;
    p.phi = PLAN_PI - 2.0 * p.theta;
    p.tolerance = corner_tolerance(prev, next);

    /* Arcs: only in the plane of the corner, and no helix (LinuxCNC
     * refuses the blend arc otherwise). */
    double theta_tan = p.theta;
    const plan_seg *arcs[2] = {prev, next};
    for (int k = 0; k < 2; k++)
        if (arcs[k]->kind == SEG_ARC &&
            (fabs(arcs[k]->helix) > 1e-12 || fabs(fabs(dot3(arcs[k]->normal, binormal)) - 1.0) > 1e-6))
            return -1;
    p.L1 = prev->kind == SEG_ARC
               ? fmin(arc_side(prev, 1, prev->p_end, u2, theta_tan, &p.theta), prev->length)
               : fmin(prev->length, prev->nominal_length * PLAN_BLEND_DIST_FRACTION);
    p.L2 = next->kind == SEG_ARC ? arc_side(next, 0, prev->p_end, u1, theta_tan, &p.theta)
                                 : next->length * PLAN_BLEND_DIST_FRACTION;
    if (prev->kind == SEG_ARC || next->kind == SEG_ARC) {
        /* LinuxCNC's minimum corner for an arc blend */
        if (p.theta < (prev->kind == SEG_ARC && next->kind == SEG_ARC ? PLAN_PI / 12.0 : 0.0)) return -1;
        p.phi = PLAN_PI - 2.0 * p.theta;
    }

    double acc_bounds[3], vel_bounds[3];
    for (int i = 0; i < 3; i++) {
        acc_bounds[i] = m->linear[i].max_acceleration;
        vel_bounds[i] = m->linear[i].max_velocity;
    }
    p.a_max = plan_plane_limit(binormal, acc_bounds);
    if (m->traj_max_acceleration > 0.0)
        p.a_max = p.a_max > 0.0 ? fmin(p.a_max, m->traj_max_acceleration) : m->traj_max_acceleration;
    if (!(p.a_max > 0.0)) return -1; /* no acceleration limit: corners cost nothing */
    p.a_n_max = p.a_max * PLAN_ACC_RATIO_NORMAL;

    double mfo = m->max_feed_override > 0.0 ? m->max_feed_override : 1.0;
    p.v_req = fmax(fmin(prev->reqvel, prev->maxvel), fmin(next->reqvel, next->maxvel));
    p.v_goal = fmax(fmin(prev->reqvel * mfo, prev->maxvel), fmin(next->reqvel * mfo, next->maxvel));
    double v_planar = plan_plane_limit(binormal, vel_bounds);
    if (!(v_planar > 0.0)) v_planar = INFINITY;
    double v_alt = 0.0;
    if (prev->kind != SEG_ARC && next->kind != SEG_ARC) {
        /* The corner's velocity triangle: the altitude of the triangle of
         * both segments' velocity limits (LinuxCNC's v_max_alt). */
        double phi_eff = fmin(p.phi, PLAN_PI * 0.49);
        double v1 = fmin(prev->maxvel, next->maxvel / cos(phi_eff));
        double v2 = fmin(next->maxvel, prev->maxvel / cos(phi_eff));
        double area = v1 * v2 / 2.0 * sin(p.phi);
        double diff[3];
        for (int i = 0; i < 3; i++) diff[i] = u2[i] * v2 - u1[i] * v1;
        double base = sqrt(dot3(diff, diff));
        if (base > 0.0 && isfinite(area)) v_alt = 2.0 * area / base;
    }
    p.v_goal = fmin(p.v_goal, fmax(v_alt, v_planar));

    /* The radius: the tolerance and the lengths bound the distance from
     * the corner; the speed the normal acceleration allows there; a
     * parabolic blend's duration sizes the arc on long segments. */
    double h_tol = p.tolerance / (1.0 - sin(p.theta));
    double d_tol = cos(p.theta) * h_tol;
    double d_geom = fmin(fmin(p.L1, p.L2), d_tol);
    double R_geom = tan(p.theta) * d_geom;
    double v_normal = sqrt(p.a_n_max * R_geom);
    p.v_plan = fmin(v_normal, p.v_goal);
    double a_parabolic = p.a_max * 0.5;
    double v_triangle = sqrt(2.0 * a_parabolic * d_geom);
    double t_blend = fmin(v_triangle, p.v_plan) / a_parabolic;
    double s_blend = t_blend * p.v_plan;
    double R_blend = fmin(s_blend / p.phi, R_geom);
    p.R_plan = fmax(p.v_plan * p.v_plan / p.a_n_max, R_blend);
    p.d_plan = p.R_plan / tan(p.theta);
    p.s_arc = p.R_plan * p.phi;
    p.v_actual = fmin(p.v_plan, p.v_req);
    if (p.R_plan < 1e-9 || p.s_arc < 1e-9 || !isfinite(p.R_plan)) return -1;
    *o = p;
    return 0;
}
