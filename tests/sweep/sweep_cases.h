/* sweep_cases.h: the cutters, motions and brute-force reference shared by
 * the sweep tests and the sweep benchmark. */
#ifndef TEST_SWEEP_CASES_H
#define TEST_SWEEP_CASES_H

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sweep/sweep.h"

static inline fm_tool_spec sc_spec(fm_tool_shape shape)
{
    fm_tool_spec s;
    memset(&s, 0, sizeof s);
    s.number = 1;
    s.shape = shape;
    s.diameter = 6;
    s.flute_length = 10;
    s.length = 25;
    switch (shape) {
    case FM_TOOL_BULL: s.corner_radius = 1; break;
    case FM_TOOL_VBIT: s.angle = 60; s.tip_diameter = 0.5; break;
    case FM_TOOL_DRILL: s.point_angle = 118; break;
    case FM_TOOL_TAPERED: s.taper_angle = 8; break;
    case FM_TOOL_DOVETAIL: s.diameter = 10; s.angle = 35; s.neck_diameter = 4; break;
    case FM_TOOL_LOLLIPOP: s.diameter = 6; s.neck_diameter = 2.5; break;
    default: break;
    }
    return s;
}

typedef struct sc_cutter {
    const char *name;
    fm_tool_spec spec;
} sc_cutter;

static inline int sc_cutters(sc_cutter out[9])
{
    fm_tool_shape shapes[] = {FM_TOOL_FLAT, FM_TOOL_BALL, FM_TOOL_BULL, FM_TOOL_VBIT, FM_TOOL_DRILL,
                              FM_TOOL_TAPERED, FM_TOOL_TAPERED, FM_TOOL_DOVETAIL, FM_TOOL_LOLLIPOP};
    const char *names[] = {"flat", "ball", "bull", "vbit", "drill", "tapered", "tapered-ball", "dovetail",
                           "lollipop"};
    for (int i = 0; i < 9; i++) {
        out[i].name = names[i];
        out[i].spec = sc_spec(shapes[i]);
    }
    out[6].spec.diameter = 0;
    out[6].spec.tip_radius = 1.5;
    return 9;
}

static inline fm_motion sc_base(fm_motion_kind kind)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    m.axis_start[2] = m.axis_end[2] = 1;
    m.t0 = 1;
    m.t1 = 3;
    m.block = -1;
    return m;
}

static inline fm_motion sc_line(double x0, double y0, double z0, double x1, double y1, double z1)
{
    fm_motion m = sc_base(FM_MOTION_LINE);
    m.start[0] = x0, m.start[1] = y0, m.start[2] = z0;
    m.end[0] = x1, m.end[1] = y1, m.end[2] = z1;
    return m;
}

/* An arc about plane axis k, centre c, from start at angle a0 through
 * sweep (turns sign gives the direction), rising by h along the axis. */
static inline fm_motion sc_arc(int k, const double c[3], double radius, double a0, double a1, int turns, double h)
{
    fm_motion m = sc_base(FM_MOTION_ARC);
    int i = (k + 1) % 3, j = (k + 2) % 3;
    memcpy(m.center, c, sizeof m.center);
    m.start[k] = c[k];
    m.start[i] = c[i] + radius * cos(a0);
    m.start[j] = c[j] + radius * sin(a0);
    m.end[k] = c[k] + h;
    m.end[i] = c[i] + radius * cos(a1);
    m.end[j] = c[j] + radius * sin(a1);
    m.plane_axis = k;
    m.turns = turns;
    return m;
}

/* Parametric paths: a curve with a fixed axis, and one whose axis tilts.
 * pose_bounds from Lipschitz constants of each component (sound). */
static inline void sc_curve_pose(void *ctx, double t, double pos[3], double axis[3])
{
    int tilt = ctx != NULL;
    pos[0] = 8 * sin(t);
    pos[1] = 4 * sin(2 * t);
    pos[2] = 1.5 * t;
    double l[3] = {tilt ? 0.3 * sin(t) : 0, tilt ? 0.2 * t : 0, 1};
    double n = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    for (int i = 0; i < 3; i++) axis[i] = l[i] / n;
}

static inline void sc_curve_bounds(void *ctx, double ta, double tb, double plo[3], double phi[3], double alo[3],
                            double ahi[3])
{
    double pm[3], am[3], w = 0.5 * (tb - ta);
    sc_curve_pose(ctx, 0.5 * (ta + tb), pm, am);
    double Lp[3] = {8, 8, 1.5};
    /* |d(l/|l|)/dt| <= |dl/dt| / |l| with |l| >= 1. */
    double La = ctx ? sqrt(0.09 + 0.04) : 0;
    for (int i = 0; i < 3; i++) {
        plo[i] = pm[i] - Lp[i] * w;
        phi[i] = pm[i] + Lp[i] * w;
        alo[i] = am[i] - La * w;
        ahi[i] = am[i] + La * w;
    }
}

__attribute__((unused)) static int sc_tilt_flag;
__attribute__((unused)) static const fm_path sc_curve_path = {NULL, sc_curve_pose, sc_curve_bounds};
__attribute__((unused)) static const fm_path sc_tilt_path = {&sc_tilt_flag, sc_curve_pose, sc_curve_bounds};

static inline fm_motion sc_param(int tilted)
{
    fm_motion m = sc_base(FM_MOTION_PARAM);
    m.t0 = 0.2;
    m.t1 = 1.4;
    m.path = tilted ? &sc_tilt_path : &sc_curve_path;
    return m;
}

enum { SC_LINE, SC_PLUNGE, SC_RAMP, SC_ARC_G17, SC_ARC_G18, SC_ARC_G19, SC_HELIX, SC_PARAM, SC_PARAM_TILT,
       SC_KINDS };
__attribute__((unused)) static const char *const sc_kind_names[SC_KINDS] = {"line", "plunge", "ramp", "arc-G17", "arc-G18", "arc-G19",
                                              "helix", "param", "param-tilt"};

static inline fm_motion sc_motion(int kind)
{
    double c[3] = {1, -2, 0.5};
    switch (kind) {
    case SC_LINE: return sc_line(0, 0, 0, 12, 5, 0);
    case SC_PLUNGE: return sc_line(2, 1, 3, 2, 1, -4);
    case SC_RAMP: return sc_line(0, 0, 2, 10, -4, -1.5);
    case SC_ARC_G17: return sc_arc(2, c, 7, 0.3, 2.5, 1, 0);
    case SC_ARC_G18: return sc_arc(1, c, 6, -0.4, 1.9, -1, 0);
    case SC_ARC_G19: return sc_arc(0, c, 5, 0.5, 2.2, 1, 0);
    case SC_HELIX: return sc_arc(2, c, 4, 0, 0, 2, -6); /* two full turns, down 6 mm */
    case SC_PARAM: return sc_param(0);
    case SC_PARAM_TILT: return sc_param(1);
    }
    return sc_line(0, 0, 0, 1, 0, 0);
}

/* Brute-force S: n + 1 samples of u, then golden-section refinement
 * around every sampled local maximum within `margin` of the best. With
 * a Lipschitz constant L of u -> F(u) the best sample is within L / (2 n)
 * of the true maximum, and so is the sample nearest the maximum: a margin
 * of that (twice it here) refines the sampled maximum next to it; that
 * golden section then finds it assumes F has one maximum between the two
 * samples either side, at both densities. */
static inline double sc_golden(const fm_sweep *s, fm_sweep_worker *w, const double p[3], double a, double b)
{
    const double g = 0.6180339887498949;
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = fm_sweep_tool_at_u(s, w, p, x1), f2 = fm_sweep_tool_at_u(s, w, p, x2);
    for (int it = 0; it < 80 && b - a > 1e-14; it++) {
        if (f1 < f2) {
            a = x1, x1 = x2, f1 = f2;
            x2 = a + g * (b - a);
            f2 = fm_sweep_tool_at_u(s, w, p, x2);
        } else {
            b = x2, x2 = x1, f2 = f1;
            x1 = b - g * (b - a);
            f1 = fm_sweep_tool_at_u(s, w, p, x1);
        }
    }
    double fa = fm_sweep_tool_at_u(s, w, p, a), fb = fm_sweep_tool_at_u(s, w, p, b);
    return fmax(fmax(f1, f2), fmax(fa, fb));
}

#define SC_SAMPLES 100000
__attribute__((unused)) static double sc_vals[SC_SAMPLES + 1];

static inline double sc_brute_n(const fm_sweep *s, fm_sweep_worker *w, const double p[3], int n, double margin)
{
    double best = -DBL_MAX;
    for (int k = 0; k <= n; k++) {
        sc_vals[k] = fm_sweep_tool_at_u(s, w, p, (double)k / n);
        if (sc_vals[k] > best) best = sc_vals[k];
    }
    double out = best;
    for (int k = 0; k <= n; k++) {
        if (sc_vals[k] < best - margin) continue;
        if ((k > 0 && sc_vals[k - 1] > sc_vals[k]) || (k < n && sc_vals[k + 1] > sc_vals[k])) continue;
        double a = k > 0 ? (double)(k - 1) / n : 0, b = k < n ? (double)(k + 1) / n : 1;
        double v = sc_golden(s, w, p, a, b);
        if (v > out) out = v;
    }
    return out;
}

/* The dense reference: 100,000 samples (spacing error L / 2e5 below 1e-3
 * for every motion here), margin 1e-2. */
static inline double sc_brute(const fm_sweep *s, fm_sweep_worker *w, const double p[3])
{
    return sc_brute_n(s, w, p, SC_SAMPLES, 1e-2);
}

/* How fast a motion moves, for the sparse brute force: the largest tip
 * speed |c'(u)| and axis speed |a'(u)| over u (differences of 20,000
 * poses, times 1.25 for what lies between them) and the box of the tip's
 * path. F(u) = part(R(u)^T (p - c(u))) with a 1-Lipschitz part has
 * |F'| <= |c'| + |a'| |p - c|. */
typedef struct sc_speed {
    double tip, axis, lo[3], hi[3];
} sc_speed;

static inline sc_speed sc_motion_speed(const fm_motion *m)
{
    enum { N = 20000 };
    sc_speed v = {0, 0, {DBL_MAX, DBL_MAX, DBL_MAX}, {-DBL_MAX, -DBL_MAX, -DBL_MAX}};
    double c0[3], a0[3];
    fm_motion_pose_at(m, 0, c0, a0);
    for (int k = 0; k <= N; k++) {
        double c[3], a[3], dc = 0, da = 0;
        fm_motion_pose_at(m, (double)k / N, c, a);
        for (int i = 0; i < 3; i++) {
            dc += (c[i] - c0[i]) * (c[i] - c0[i]);
            da += (a[i] - a0[i]) * (a[i] - a0[i]);
            v.lo[i] = fmin(v.lo[i], c[i]);
            v.hi[i] = fmax(v.hi[i], c[i]);
        }
        v.tip = fmax(v.tip, 1.25 * sqrt(dc) * N);
        v.axis = fmax(v.axis, 1.25 * sqrt(da) * N);
        memcpy(c0, c, sizeof c0);
        memcpy(a0, a, sizeof a0);
    }
    for (int i = 0; i < 3; i++) {
        v.lo[i] -= v.tip / N;
        v.hi[i] += v.tip / N;
    }
    return v;
}

/* The sparse brute force: as many samples as make the spacing error
 * L / (2 n) at most SC_SPARSE_SPACING (0.05 mm), refined as above round
 * every sampled local maximum within twice that of the best; its answers
 * are held to the dense one's on a few points of every case
 * (tests/sweep/test_sweep.c). */
#define SC_SPARSE_SPACING 0.05
static inline double sc_brute_sparse(const fm_sweep *s, fm_sweep_worker *w, const sc_speed *v, const double p[3])
{
    double far2 = 0;
    for (int i = 0; i < 3; i++) {
        double d = fmax(fabs(p[i] - v->lo[i]), fabs(p[i] - v->hi[i]));
        far2 += d * d;
    }
    double L = v->tip + v->axis * sqrt(far2);
    double n = ceil(L / (2 * SC_SPARSE_SPACING));
    n = n < 64 ? 64 : n > SC_SAMPLES ? SC_SAMPLES : n;
    return sc_brute_n(s, w, p, (int)n, 2 * SC_SPARSE_SPACING);
}

/* The sparse brute force's answer at p held to the dense one's (1e-9);
 * prints where they differ (what, the case's name) and returns 0 then. */
static inline int sc_sparse_equals_dense(const char *what, const fm_sweep *s, fm_sweep_worker *w, const double p[3],
                                         double sparse)
{
    double dense = sc_brute(s, w, p);
    if (fabs(sparse - dense) <= 1e-9) return 1;
    fprintf(stderr, "%s at (%.6g, %.6g, %.6g): sparse brute force %.12g, dense %.12g\n", what, p[0], p[1], p[2], sparse,
            dense);
    return 0;
}

#endif
