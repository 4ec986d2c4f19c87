/* plan.h: the trajectory planner: motions (lib/sweep/motion.h) and a
 * machine's dynamics -> timed motions, as LinuxCNC 2.9's trajectory planner
 * times them (trapezoidal velocity profiles, look-ahead over a bounded
 * queue, G64 P/Q blend arcs with their reduced accelerations, exact stops,
 * arcs limited by their normal acceleration, per-axis limits of rapids).
 * docs/plan.md has the model, what is approximated and the LinuxCNC
 * reference it is measured against.
 *
 * Streaming: push motions in program order; each comes back to the sink,
 * with its planned times, once the look-ahead has passed it (at most
 * lookahead + a few motions later), so a program of any length never has
 * all its motions in memory. A planner is used by one thread at a time. */
#ifndef FM_PLAN_H
#define FM_PLAN_H

#include "core/core.h"
#include "sweep/motion.h"

/* One axis' limits: mm/s and mm/s^2 (rotary axes: deg/s, deg/s^2).
 * 0 means not limited. */
typedef struct fm_plan_axis {
    double max_velocity;
    double max_acceleration;
} fm_plan_axis;

/* A machine's dynamics, as LinuxCNC's INI gives them ([AXIS_n], [TRAJ]). */
typedef struct fm_plan_machine {
    /* 0: the machine gives no dynamics: every motion takes its length over
     * its feed (rapids at rapid_rate), today's feed-only figure. */
    int given;
    fm_plan_axis linear[3];       /* X Y Z */
    fm_plan_axis rotary[3];       /* A B C */
    double traj_max_velocity;     /* [TRAJ] MAX_LINEAR_VELOCITY, mm/s (0: none) */
    double traj_max_acceleration; /* [TRAJ] MAX_LINEAR_ACCELERATION, mm/s^2 (0: none) */
    double rapid_velocity[3];     /* G0 per linear axis, mm/s (0: that axis' max_velocity) */
    double tool_change_s;         /* added at each change of tool (default 0) */
    double servo_period_s;        /* [EMCMOT] SERVO_PERIOD (default 0.001 s) */
    /* [DISPLAY] MAX_FEED_OVERRIDE (default 1.0): LinuxCNC sizes blend arcs
     * for the highest feed override, so it changes the path and the time
     * even at 100%. */
    double max_feed_override;
    int lookahead;                /* [TRAJ] ARC_BLEND_OPTIMIZATION_DEPTH (default 50) */
    int blend_gap_cycles;         /* [TRAJ] ARC_BLEND_GAP_CYCLES (default 4) */
    double kink_ratio;            /* [TRAJ] ARC_BLEND_TANGENT_KINK_RATIO (default 0.1) */
    double rapid_rate;            /* mm/min, rapids when !given (default 5000) */
    /* Not the planner's: 1 makes the job runner cut along the programmed
     * corners rather than the blend arcs (the machine file's dynamics
     * "follow_blends": false; docs/plan.md "Where the tool goes"). */
    int programmed_path;
} fm_plan_machine;

/* Defaults above; given = 0. */
void fm_plan_machine_default(fm_plan_machine *m);

/* The arc a blended corner takes instead of the programmed corner
 * (LinuxCNC's blend arc): from start to end about center, in the plane of
 * the two segments. */
typedef struct fm_plan_blend {
    double start[3], end[3], center[3];
    double radius;  /* mm */
    double angle;   /* radians turned */
    double t0, t1;  /* when the tool is on it, seconds */
    double speed;   /* the planned speed on it, mm/s */
} fm_plan_blend;

/* A motion with its planned times. motion.t0/t1 are the planned start and
 * end (a blended corner's time is split at the middle of its arc); feed_t0
 * and feed_t1 are the times the motion came with (feed-only). blend_out,
 * when has_blend, is the corner between this motion and the next. */
typedef struct fm_plan_motion {
    fm_motion motion;
    double feed_t0, feed_t1;
    double v_start, v_end;  /* mm/s where the motion's own segment starts and ends */
    int has_blend;
    fm_plan_blend blend_out;
} fm_plan_motion;

/* Receives planned motions in program order; non-zero stops the planner
 * (the push that delivered it returns FM_ERR_LIMIT with reason "stopped"). */
typedef int (*fm_plan_sink)(void *user, const fm_plan_motion *motion);

typedef struct fm_plan_totals {
    double cycle_time_s;  /* the planned end of the last motion */
    double feed_only_s;   /* the end of the last motion as pushed */
    long motions;         /* pushed */
    long segments;        /* planned segments after naive-CAM merging, blend arcs included */
    long blends;          /* corners blended with an arc */
    long stops;           /* segments that end at rest */
    long tool_changes;
} fm_plan_totals;

typedef struct fm_planner fm_planner;

/* A planner over machine m (copied) delivering to sink. NULL on error. */
fm_planner *fm_planner_new(const fm_plan_machine *m, fm_plan_sink sink, void *user,
                           fm_error *err);
/* The next motion in program order (its t0/t1 as the producer timed it). */
fm_status fm_planner_push(fm_planner *p, const fm_motion *motion, fm_error *err);
/* The program ended: plan and deliver what is queued; *totals if non-NULL. */
fm_status fm_planner_finish(fm_planner *p, fm_plan_totals *totals, fm_error *err);
void fm_planner_free(fm_planner *p);

/* fm_motion_sink over a planner (user = the fm_planner): for producers that
 * stream into a sink (fm_gcode_run_file). A failed push stops the producer;
 * fm_planner_error then says why. */
int fm_planner_motion_sink(void *planner, const fm_motion *motion);
const fm_error *fm_planner_error(const fm_planner *p);

/* ---- where the tool really goes (docs/plan.md, "Where the tool goes") ----
 * The planned motions (the planner's sink) -> the path the machine takes,
 * as motions: a straight move ending in a blended corner is cut short at
 * its blend arc's start, the arc follows (FM_MOTION_ARC when the corner
 * lies in the XY, XZ or YZ plane; chords within chord_tolerance of it out
 * of those planes, and for rapids, which stay rapids), and the next move
 * starts at the arc's end. Corners next to arcs, in a naive-CAM chain or
 * between moves that change tool, tool axis or kind keep the programmed
 * corner. */
typedef struct fm_plan_path_options {
    double chord_tolerance; /* mm, the chords' largest distance from the arc (default 0.001) */
    /* 1: the pieces carry the planned times (a piece of a motion its share,
     * an arc its blend_out.t0..t1); 0: the motions' own times as pushed
     * (feed_t0..feed_t1, split by length; an arc from its start on the
     * motion before to its end on the motion after). */
    int planned_times;
} fm_plan_path_options;

void fm_plan_path_options_default(fm_plan_path_options *o);

/* Receives the path in order: motion is a programmed motion (or the piece
 * of it the blends leave) when blend is 0, a blend arc (or one of its
 * chords) when 1; a blend arc keeps the fields of the motion before the
 * corner (index, line, tool, feed). continues: the next piece belongs to
 * the same motion (its blend arc follows). Non-zero stops. */
typedef int (*fm_plan_path_sink)(void *user, const fm_motion *motion, int blend, int continues);

typedef struct fm_plan_path fm_plan_path;

/* opt NULL: the defaults. NULL on error. */
fm_plan_path *fm_plan_path_new(const fm_plan_path_options *opt, fm_plan_path_sink sink, void *user,
                               fm_error *err);
/* An fm_plan_sink (user = the fm_plan_path): each planned motion in program
 * order. Returns non-zero when the path's sink stopped. */
int fm_plan_path_push(void *path, const fm_plan_motion *motion);
/* The program ended: the last motion goes out. Non-zero: the sink stopped. */
int fm_plan_path_finish(fm_plan_path *p);
/* Blend arcs followed so far. */
long fm_plan_path_blends(const fm_plan_path *p);
void fm_plan_path_free(fm_plan_path *p);

#endif
