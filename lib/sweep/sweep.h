/* sweep.h: the moving tool. For one motion (fm_motion) and one tool part
 * (fm_tool_part, lib/tools), the 4D object
 *     T(p, t) = part(R(t)^T (p - c(t))) & (t - t0) & (t1 - t)
 * as an frep DAG, and its projection, the swept volume
 *     S(p) = max over t in [t0, t1] of part(R(t)^T (p - c(t)))
 * (Pasko 1995 eq. 12; Shapiro 2007 sec. 6.3) as a native evaluator with
 * point, batch and interval forms, and as an fm_field for lib/stock.
 *
 * c(t) is the tool tip (programmed point + tip_offset), R(t) maps the tool
 * frame (tip at the origin, axis +Z) to the machine. Because every part is a
 * solid of revolution only the axis direction matters.
 *
 * Accuracy (docs/sweep.md): S is max over t of the part's exact signed
 * distance, so outside the swept volume -S is the true distance to it, and
 * inside it is the depth below the nearest moving copy of the tool. The
 * value returned is attained (a lower bound of the true maximum); `upper`
 * (fm_sweep_eval_ex) is a proven upper bound. For profile parts on lines,
 * arcs and helices upper - value <= tol (FM_SWEEP_TOL unless given); for
 * parametric paths, changing axes and custom parts the proof stops at
 * FM_SWEEP_COARSE_TOL and a local search polishes every candidate left.
 *
 * Thread safety: an fm_sweep is immutable once made and may be shared;
 * each thread evaluates through its own fm_sweep_worker. A worker made for
 * one sweep serves every sweep of the same tool part. */
#ifndef FM_SWEEP_H
#define FM_SWEEP_H

#include "sweep/motion.h"
#include "tools/tools.h"

#define FM_SWEEP_TOL 1e-7
#define FM_SWEEP_COARSE_TOL 1e-3
/* An arc whose radius changes by at most this (mm) is swept as the circle
 * of its mean radius when fast paths are on: CAM posts round ends and
 * centres to 3 decimals, which makes the circle they meant a spiral by up
 * to about a micrometre, and a spiral has no closed form. The path moves by
 * at most half of it: 1 um, a hundredth of a 0.1 mm voxel. */
#define FM_SWEEP_NEAR_CIRCLE 2e-3

typedef struct fm_sweep fm_sweep;
typedef struct fm_sweep_worker fm_sweep_worker;

/* How S is computed for a sweep (reported for tests and benchmarks). */
typedef enum fm_sweep_method {
    FM_SWEEP_STATIC = 0,  /* no movement (dwell, zero-length move): S = the part at the start pose */
    FM_SWEEP_PLANAR_LINE, /* line perpendicular to a fixed axis: closed form (stadium extrusion) */
    FM_SWEEP_PLANAR_ARC,  /* arc in the plane perpendicular to a fixed axis: closed form (ring) */
    FM_SWEEP_CAPSULE,     /* ball-tipped part on any line: closed form (the ball swept up its axis) wherever
                             the part's top does not decide, else CONCAVE */
    FM_SWEEP_CONCAVE,     /* convex part on a line, fixed axis: t -> T is concave; certified bracketing */
    FM_SWEEP_SEARCH,      /* everything else: branch-and-bound on t, then local search */
    FM_SWEEP_HELIX        /* convex part on a helix (arc with a rise) about its own axis: the
                             branch-and-bound seeded with the pieces where the distance to the axis
                             is monotone, bounded exactly there (docs/sweep.md) */
} fm_sweep_method;

typedef struct fm_sweep_options {
    double tol;          /* certified tolerance in mm; 0 = FM_SWEEP_TOL */
    int no_fast_paths;   /* 1: skip the closed forms (tests compare them with the general path) */
    size_t max_evaluations; /* per point; 0 = 20000. When hit, upper stays sound but loose. */
} fm_sweep_options;

/* Make the sweep of part along motion (options may be NULL). The part is
 * copied; a PARAM motion's path must outlive the sweep. */
fm_status fm_sweep_new(const fm_motion *motion, const fm_tool_part *part,
                       const fm_sweep_options *options, fm_sweep **out, fm_error *err);
void fm_sweep_free(fm_sweep *sweep);
fm_sweep_method fm_sweep_method_of(const fm_sweep *sweep);

/* NULL when out of memory. */
fm_sweep_worker *fm_sweep_worker_new(const fm_sweep *sweep);
void fm_sweep_worker_free(fm_sweep_worker *worker);

typedef struct fm_sweep_value {
    double value;  /* S(p), attained at time t */
    double upper;  /* proven upper bound of S(p) */
    double t;
    size_t evaluations; /* evaluations of the part */
    /* 1: the search stopped at its evaluation budget (or out of memory)
     * before proving value within its tolerance of the maximum; upper is
     * still sound, but value may be low by up to upper - value. */
    int exhausted;
} fm_sweep_value;

double fm_sweep_eval(const fm_sweep *sweep, fm_sweep_worker *worker, const double p[3]);
void fm_sweep_eval_ex(const fm_sweep *sweep, fm_sweep_worker *worker, const double p[3],
                      fm_sweep_value *out);
void fm_sweep_eval_batch(const fm_sweep *sweep, fm_sweep_worker *worker, size_t n, const double *x,
                         const double *y, const double *z, double *out);
/* Sound enclosure of S over the box (for inside / outside / boundary). */
fm_interval fm_sweep_interval(const fm_sweep *sweep, fm_sweep_worker *worker,
                              const fm_interval box[3]);
/* A box that holds the whole swept volume (tight: the envelope touches it
 * for lines and arcs). */
void fm_sweep_bounds(const fm_sweep *sweep, double lo[3], double hi[3]);

/* The pose at program time t (clamped to [t0, t1]): tip position and unit axis. */
void fm_sweep_pose(const fm_sweep *sweep, double t, double tip[3], double axis[3]);
/* The moving part at (p, t) without the time segment: part(R(t)^T (p - c(t))). */
double fm_sweep_tool_at(const fm_sweep *sweep, fm_sweep_worker *worker, const double p[3], double t);

/* The same at a geometric parameter u in [0, 1] (u = (t - t0) / (t1 - t0)),
 * which keeps its resolution for motions of zero duration. */
double fm_sweep_tool_at_u(const fm_sweep *sweep, fm_sweep_worker *worker, const double p[3],
                          double u);

/* ------------------------------------------------ motion geometry -- */

/* One place for the geometry of a motion, used by the sweep, the check,
 * pictures and the viewer (docs/sweep.md "Motions"). */

/* An arc as LinuxCNC's ARC_FEED runs it, for the programmed point (no tip
 * offset): P(u) = center + r(u) (cos th(u) e_ai + sin th(u) e_aj) + u dh
 * e_k with th(u) = th0 + u dth, r(u) = r0 + u dr. */
typedef struct fm_motion_arc {
    int plane_axis, ai, aj; /* k; the in-plane axes (k+1, k+2) mod 3, right-handed */
    double center[3];       /* center[k] = start[k] */
    double r0, dr;
    double th0, dth;        /* radians; dth > 0 counter-clockwise seen from +k */
    double dh;
} fm_motion_arc;

/* The arc of an FM_MOTION_ARC motion: turns > 0 counter-clockwise, |turns|
 * - 1 extra full circles, the same start and end angle a full circle.
 * Returns 0 (and describes a straight line's worth of nothing: dth = 0)
 * when the arc is degenerate: plane axis not 0..2, turns 0, zero start
 * radius or a coordinate not finite. */
int fm_motion_arc_of(const fm_motion *m, fm_motion_arc *arc);
/* The point at u and its derivative d/du (dp may be NULL). */
void fm_motion_arc_point(const fm_motion_arc *arc, double u, double p[3], double dp[3]);

/* The programmed point at u in [0, 1] (start/end, the arc, or a
 * parametric path minus tip_offset; dwells stay at start). */
void fm_motion_point_at(const fm_motion *m, double u, double p[3]);
/* The tool tip and unit axis in the workpiece frame at u in [0, 1]: every
 * kind, rotary axes included (what the sweep cuts with). */
void fm_motion_pose_at(const fm_motion *m, double u, double tip[3], double axis[3]);
/* Boxes that hold the tip and the axis for every u in [ua, ub] (sound:
 * interval arithmetic on the chain; tests/sweep/test_kinematics.c). */
void fm_motion_pose_bounds(const fm_motion *m, double ua, double ub, double tip_lo[3], double tip_hi[3],
                           double axis_lo[3], double axis_hi[3]);
/* Does the motion's pose come from a machine's rotary axes? */
int fm_motion_has_rotary(const fm_motion *m);
/* Into how many equal pieces of u to cut a motion for drawing: arcs by
 * max_angle of turn (radians) per piece, rotary motions by max_angle of
 * any joint, parametric paths into param_pieces; lines 1. At most
 * max_pieces. */
int fm_motion_pieces(const fm_motion *m, double max_angle, int param_pieces, int max_pieces);

/* --------------------------------------------------------- machine -- */

/* Is the machine well formed (unit axes once normalized, distinct letters,
 * limits lo <= hi, finite numbers)? Normalizes `around` in place. */
fm_status fm_machine_validate(fm_machine *machine, fm_error *err);
/* The index in machine->rotary of the axis driven by letter (0 = A), or -1. */
int fm_machine_axis_of(const fm_machine *machine, int letter);
/* How many of the machine's rotary axes carry the table (0 without one). */
int fm_machine_table_axes(const fm_machine *machine);
/* Where the table's link `upto` (the number of table axes counted from
 * the base that move it; -1: all) puts the workpiece at the joint values
 * (degrees, A B C): x_machine = rot x_workpiece + trans (rot row-major).
 * For pictures of the workpiece in its machine position. */
void fm_machine_table_transform(const fm_machine *machine, const double rotary[3], int upto, double rot[9],
                                double trans[3]);
/* A motion's joint values (degrees, A B C) at program time t, t clamped to
 * [t0, t1]: every joint moves linearly in time (motion.h). A motion
 * without a machine has all joints at 0. */
void fm_motion_joints_at(const fm_motion *m, double t, double joints[3]);

/* ------------------------------------------------------ frep DAGs -- */

/* T(p, t) of motion and part in g. For FM_MOTION_PARAM give pose[0..2]
 * (tip position) and pose[3..5] (unit axis) as nodes depending on t; other
 * kinds take pose = NULL. FM_NONE on error (see fm_graph_error), and for
 * custom parts. */
fm_node fm_sweep_build_4d(fm_graph *g, const fm_motion *motion, const fm_tool_part *part,
                          const fm_node *pose);
/* The projection of T on t in [t0, t1] (fm_project): S as a DAG. */
fm_node fm_sweep_build_projection(fm_graph *g, const fm_motion *motion, const fm_tool_part *part,
                                  const fm_node *pose);

/* --------------------------------------------------------- fields -- */

/* S of one motion as an fm_field (frep.h) over its bounding box. Release
 * with fm_field_release or field->release(field->ctx). */
fm_status fm_sweep_field(fm_field *field, const fm_motion *motion, const fm_tool_part *part,
                         fm_error *err);
/* max of S over n consecutive motions with the same part (n >= 1), one
 * field for lib/stock to rasterize in one pass. Dwells are skipped. */
fm_status fm_sweep_field_many(fm_field *field, const fm_motion *motions, size_t n,
                              const fm_tool_part *part, fm_error *err);
/* The same with sweep options for every motion (NULL: the defaults): a
 * job's forced evaluation budget (fm_job_spec.sweep_evaluations). */
fm_status fm_sweep_field_many_ex(fm_field *field, const fm_motion *motions, size_t n,
                                 const fm_tool_part *part, const fm_sweep_options *options,
                                 fm_error *err);

#endif
