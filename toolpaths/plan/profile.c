/* profile.c: trapezoidal velocity profiles over one segment in closed form:
 * accelerate from the entry velocity, cruise at the target, decelerate to
 * the final velocity (LinuxCNC's tpCalculateTrapezoidalAccel in
 * continuous time), and the time at a distance along it. */
#include <math.h>

#include "toolpaths/plan/plan_internal.h"

/* An acceleration of 0 means none is given: a large finite one keeps the
 * formulas free of special cases (a ramp of 10^-9 s). */
#define PLAN_UNLIMITED_ACCEL 1e12

void plan_profile_make(double L, double v0, double vt, double vf, double a, plan_profile *out)
{
    plan_profile p = {0};
    if (!(a > 0.0)) a = PLAN_UNLIMITED_ACCEL;
    if (L < 0.0) L = 0.0;
    if (vt < 0.0) vt = 0.0;
    if (vf > vt) vf = vt;
    if (vf < 0.0) vf = 0.0;
    if (v0 < 0.0) v0 = 0.0;
    p.a = a;
    /* The end velocity: no faster than accelerating all the way allows; no
     * slower than decelerating all the way from v0 allows (the look-ahead
     * keeps v0 low enough that this does not happen). */
    double v_acc = sqrt(v0 * v0 + 2.0 * a * L);
    double v1 = fmin(vf, v_acc);
    double v_dec2 = v0 * v0 - 2.0 * a * L;
    if (v_dec2 > v1 * v1) v1 = sqrt(v_dec2);
    double vp = sqrt((2.0 * a * L + v0 * v0 + v1 * v1) / 2.0);
    if (vp > vt) vp = vt;
    if (vp < v0) vp = v0;
    if (vp < v1) vp = v1;
    p.v0 = v0;
    p.vp = vp;
    p.v1 = v1;
    p.s1 = (vp * vp - v0 * v0) / (2.0 * a);
    p.s3 = (vp * vp - v1 * v1) / (2.0 * a);
    p.s2 = L - p.s1 - p.s3;
    if (p.s2 < 0.0 && p.s2 > -1e-9 * (1.0 + L)) p.s2 = 0.0; /* a triangle, up to rounding */
    if (p.s2 < 0.0) {
        /* entering above what the length allows (v0 > vt after a clamp):
         * decelerate all the way */
        p.s2 = 0.0;
        p.s1 = 0.0;
        p.s3 = L;
        p.vp = v0;
    }
    p.t1 = (p.vp - v0) / a;
    p.t2 = p.vp > 0.0 ? p.s2 / p.vp : 0.0;
    p.t3 = (p.vp - v1) / a;
    *out = p;
}

double plan_profile_time(const plan_profile *p) { return p->t1 + p->t2 + p->t3; }

double plan_profile_time_at(const plan_profile *p, double s)
{
    if (s <= 0.0) return 0.0;
    if (s < p->s1) return (sqrt(p->v0 * p->v0 + 2.0 * p->a * s) - p->v0) / p->a;
    s -= p->s1;
    if (s < p->s2) return p->t1 + s / p->vp;
    s -= p->s2;
    /* decelerating: measured back from the end, where rounding would
     * otherwise leave sqrt of a tiny difference */
    double rem = p->s3 - s;
    if (rem <= 0.0) return plan_profile_time(p);
    return plan_profile_time(p) - (sqrt(p->v1 * p->v1 + 2.0 * p->a * rem) - p->v1) / p->a;
}
