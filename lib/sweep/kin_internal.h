/* kin_internal.h: a motion's kinematic chain, prepared once (kinematics.c)
 * and evaluated many times by the sweep: the tool's pose in the workpiece
 * frame at a motion parameter u, its derivatives, and sound boxes of it
 * over [ua, ub]. Private to lib/sweep. */
#ifndef FM_KIN_INTERNAL_H
#define FM_KIN_INTERNAL_H

#include "sweep/sweep.h"

/* One rotation of the chain: about the fixed line (b, omega) by the angle
 * th0 + u * dth (radians). */
typedef struct kin_step {
    double omega[3], b[3];
    double th0, dth;
    int point; /* turns points about the line; 0: vectors only (TCP's orientation) */
} kin_step;

/* every axis, and with TCP the table axes once more for a frame_up */
#define KIN_MAX_STEPS (2 * FM_MACHINE_MAX_ROTARY)

typedef struct fm_kin {
    int tcp;
    /* The programmed point P(u): a line p0 + u dp, or an arc. */
    int is_arc;
    double p0[3], dp[3];
    fm_motion_arc arc;
    double off[3]; /* tip_offset */
    /* Steps in the order they apply to a point of the tool: head steps
     * (nearest the spindle first), then, past `translate`, the translation
     * by P(u) (without TCP), then the table steps with negated angles (base
     * axis first): the workpiece frame's view of the tool. With TCP those
     * steps turn vectors only and P(u) is added after them; then, for a
     * frame nearer the base (fm_machine.frame_up), the inner table steps
     * with their own angles turn the point into that frame. */
    kin_step step[KIN_MAX_STEPS];
    int nsteps, translate;
    /* Sound constants over the whole motion: |dtip/du|, |daxis/du| (and
     * the tool frame's angular speed), |d2tip/du2|, |d(omega)/du|. */
    double speed, turn, accel, domega;
} fm_kin;

/* Box of an arc's points over [ua, ub] (geometry.c). */
void fm_arc_box(const fm_motion_arc *arc, double ua, double ub, double lo[3], double hi[3]);

/* Prepare the chain of a motion whose machine has rotary axes (0 and an
 * error on bad input). */
int fm_kin_init(fm_kin *k, const fm_motion *m, fm_error *err);
/* Pose at u: tip c and unit axis a; dc, da (d/du) may be NULL. */
void fm_kin_pose(const fm_kin *k, double u, double c[3], double a[3], double dc[3], double da[3]);
/* A bound of |q''| over a piece of the motion where the point p stays
 * within vmax of the tip, q = R^T (p - c) the point in the tool's frame:
 * F'' <= |q''| for a convex part (docs/sweep.md), the sweep's
 * second-order bound. */
double fm_kin_second(const fm_kin *k, double vmax);
/* Boxes holding the tip and the axis for every u in [ua, ub]. */
void fm_kin_pose_box(const fm_kin *k, double ua, double ub, double clo[3], double chi[3], double alo[3],
                     double ahi[3]);
/* The pose as frep nodes of the motion parameter node u (for the 4D DAG). */
void fm_kin_build_pose(fm_graph *g, const fm_kin *k, fm_node u, fm_node c[3], fm_node a[3]);
/* The constant pose of a motion whose joints do not move, as a plain
 * 3-axis motion in the workpiece frame (tip_offset folded into start and
 * end). 0 when the joints move or an arc's plane does not map onto a
 * coordinate plane. */
int fm_kin_fold(const fm_motion *m, fm_motion *out);

#endif
