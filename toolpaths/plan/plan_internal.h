/* plan_internal.h: the planner's segments, velocity profiles and blend
 * arithmetic, shared by toolpaths/plan's files and tests/plan. The names
 * and formulas follow LinuxCNC 2.9's tp (tc.c, tp.c, blendmath.c) so that
 * docs/plan.md can say which of its rules each one is. */
#ifndef FM_PLAN_INTERNAL_H
#define FM_PLAN_INTERNAL_H

#include "toolpaths/plan/plan.h"

/* LinuxCNC's blendmath.h constants: the share of a segment's acceleration
 * left for the tangential direction on an arc, and its normal share. */
#define PLAN_ACC_RATIO_TANGENTIAL 0.5
#define PLAN_ACC_RATIO_NORMAL 0.86602540378443864676 /* sqrt(1 - 0.5^2) */
#define PLAN_TOLERANCE_RATIO 0.25   /* G64 without P: a quarter of the shorter segment */
#define PLAN_BLEND_DIST_FRACTION 0.5 /* a blend takes at most half of a segment */
#define PLAN_OPTIMIZATION_CUTOFF 4  /* the look-ahead stops after this many peaks */
#define PLAN_NAIVE_MAX_POINTS 100   /* LinuxCNC merges at most this many lines */
#define PLAN_PI 3.14159265358979323846

typedef enum plan_seg_kind { SEG_LINE = 0, SEG_ARC, SEG_BLEND, SEG_DWELL } plan_seg_kind;

/* How a segment ends (LinuxCNC's TC_TERM_COND_*). */
typedef enum plan_term {
    TERM_STOP = 0, /* at rest (G61.1, exact stop, sharp reversal, a dwell or tool change next) */
    TERM_EXACT,    /* G61: at rest unless the next segment is tangent */
    TERM_BLEND,    /* G64: a blend arc is tried with the next segment */
    TERM_TANGENT   /* flows into the next segment at its final velocity */
} plan_term;

typedef struct plan_seg {
    plan_seg_kind kind;
    double length;          /* remaining after blend trims, mm (dwell: 0) */
    double nominal_length;  /* as programmed (merged) */
    double reqvel;          /* the feed, mm/s */
    double maxvel;          /* the machine's limit along the path, mm/s */
    double maxaccel;        /* the machine's limit along the path, mm/s^2 */
    double acc_ratio_tan;   /* arcs and blends: tangential share of maxaccel */
    double kink_vel;        /* < 0: none */
    double kink_reduce, kink_reduce_prev;
    plan_term term;
    double tolerance;       /* G64 P, mm (0: none) */
    double finalvel;        /* the look-ahead's final velocity */
    int at_max;             /* the look-ahead found its peak here */
    int finalized;          /* its length will not change any more */
    int pure_rotary;
    int rotary;             /* moves a rotary axis: no blends (LinuxCNC) */
    int rapid;              /* G0: LinuxCNC never joins a rapid to a feed without a stop */
    double p_start[3], p_end[3];
    double u_start[3], u_end[3]; /* unit tangents at the ends */
    /* Arcs (SEG_ARC) */
    double center[3], normal[3], radius, angle, helix; /* helix: mm along normal per radian */
    double dwell_s;         /* SEG_DWELL */
    fm_plan_blend blend;    /* SEG_BLEND: its geometry (times filled when run) */
    double trim_start;      /* mm cut from the start by the blend before */
    long first_motion;      /* the motions whose path it carries: [first, last] (serial numbers) */
    long last_motion;
} plan_seg;

/* A trapezoidal (or triangular) velocity profile over one segment, the
 * continuous-time form of LinuxCNC's per-cycle update. */
typedef struct plan_profile {
    double v0, vp, v1;  /* start, peak (cruise) and end velocity, mm/s */
    double a;           /* tangential acceleration, mm/s^2 */
    double s1, s2, s3;  /* distance accelerating, cruising, decelerating */
    double t1, t2, t3;  /* their times */
} plan_profile;

/* The profile over length L from v0, ending at no more than vf, not
 * exceeding vt, with acceleration a (a <= 0: unlimited). */
void plan_profile_make(double L, double v0, double vt, double vf, double a, plan_profile *out);
double plan_profile_time(const plan_profile *p);
/* The time at distance s from the start (0 <= s <= L). */
double plan_profile_time_at(const plan_profile *p, double s);

/* The limits of a straight segment of the machine (LinuxCNC canon's
 * getStraightVelocity / getStraightAcceleration): d the XYZ displacement,
 * r the rotary displacement (degrees), rapid selects the G0 rates.
 * *length is the XYZ length, or the rotary one for a pure rotary move. */
void plan_line_limits(const fm_plan_machine *m, const double d[3], const double r[3], int rapid,
                      double *length, double *maxvel, double *maxaccel);
/* An arc's: the plane axes' (and the helix axis' share of) limits, then its
 * normal acceleration: maxvel <= sqrt(0.866 a R_eff) and the tangential
 * share acc_ratio_tan (LinuxCNC's arc limits). */
void plan_arc_limits(const fm_plan_machine *m, const plan_seg *arc, double *maxvel,
                     double *maxaccel, double *acc_ratio_tan);
/* An arc's (or blend arc's) velocity limit and tangential share for its
 * curvature radius, given its machine maxvel and maxaccel. */
void plan_curvature_limits(double radius, double maxvel, double maxaccel, double *vmax,
                           double *acc_ratio_tan);

/* The largest extent of an axis-aligned box of half-sizes bounds (0:
 * unlimited) seen in the plane of unit normal n: LinuxCNC's
 * calculateInscribedDiameter, the acceleration (or velocity) limit of a
 * corner's plane. 0 when every bound is unlimited. */
double plan_plane_limit(const double n[3], const double bounds[3]);

/* A blend arc between prev (ending at P with direction u1) and next
 * (starting at P with u2): LinuxCNC's blendComputeParameters. */
typedef struct plan_blend_params {
    double theta;      /* half the angle between -u1 and u2 */
    double phi;        /* the angle the path turns, pi - 2 theta */
    double tolerance;  /* the corner's tolerance */
    double L1, L2;     /* how much of each segment it may take */
    double a_max, a_n_max;
    double v_goal, v_req, v_plan, v_actual;
    double R_plan, d_plan, s_arc;
} plan_blend_params;

/* 0 when a blend arc fits (params filled), -1 when it does not. */
int plan_blend_compute(const fm_plan_machine *m, const plan_seg *prev, const plan_seg *next,
                       plan_blend_params *out);

#endif
