/* motion.h: one segment of tool movement, as the toolpath front ends
 * (toolpaths/gcode, toolpaths/traj) produce it and lib/sweep consumes it.
 * Part of the sweep module's public interface (included by sweep.h). */
#ifndef FM_MOTION_H
#define FM_MOTION_H

#include <stddef.h>

typedef enum fm_motion_kind {
    FM_MOTION_RAPID = 0, /* G0: straight line at the rapid rate */
    FM_MOTION_LINE,      /* G1 and canned-cycle feeds */
    FM_MOTION_ARC,       /* G2/G3: arc or helix */
    FM_MOTION_PARAM,     /* parametric trajectory segment */
    FM_MOTION_DWELL      /* G4: no movement, time passes */
} fm_motion_kind;

/* A parametric tool pose: tip position and unit tool axis at program time t
 * (t in the motion's [t0, t1]). pose_bounds gives sound bounds of both over
 * [ta, tb] (interval evaluation of the trajectory's expressions). */
typedef struct fm_path {
    void *ctx;
    void (*pose)(void *ctx, double t, double pos[3], double axis[3]);
    void (*pose_bounds)(void *ctx, double ta, double tb, double pos_lo[3], double pos_hi[3],
                        double axis_lo[3], double axis_hi[3]);
} fm_path;

/* A machine's rotary axes (ARCHITECTURE.md, "Rotary axes", docs/sweep.md "Machine
 * kinematics"). Each axis turns the link it carries about a line: positive
 * joint values turn that link right-handed about `around` (as LinuxCNC).
 * Table axes turn the workpiece (stock, fixtures, design); head axes turn
 * the spindle. Axes are listed in chain order from the base: a table axis
 * rides on the table axes before it, a head axis on the head axes before
 * it. Every line is given with all joints at 0, where the workpiece frame
 * is the machine frame. */
#define FM_MACHINE_MAX_ROTARY 3

typedef enum fm_rotary_link { FM_ROTARY_TABLE = 0, FM_ROTARY_HEAD } fm_rotary_link;

typedef struct fm_rotary_axis {
    int letter;             /* 0 = A, 1 = B, 2 = C: the G-code word that drives it */
    fm_rotary_link carries;
    double around[3];       /* unit direction of the line */
    /* Table: a point of the line in machine coordinates. Head: the line's
     * offset from the pivot point, which lies on the spindle axis
     * pivot_length above the gauge line (all joints at 0). */
    double through[3];
    double pivot_length;    /* head axes: pivot point to spindle gauge line, mm */
    int has_limits;         /* travel limits of the joint, degrees */
    double limit_lo, limit_hi;
    int wrapped;            /* rolls over: absolute targets modulo 360, sign = direction */
} fm_rotary_axis;

typedef struct fm_machine {
    int rotary_count;                              /* 0: a 3-axis machine */
    fm_rotary_axis rotary[FM_MACHINE_MAX_ROTARY];  /* chain order from the base */
    int tcp;  /* tool centre point control: active from the start (G43.4 on, G49 off) */
    /* The frame the tool's pose is given in: 0, the workpiece's (every
     * table axis inverted); k > 0, the link k table axes nearer the base
     * (the innermost k table axes are not inverted): 1 is the cradle under
     * an AC trunnion's C table, the number of table axes the machine table.
     * The check sweeps the tool there against machine components on that
     * link (lib/check). */
    int frame_up;
} fm_machine;

/* How the controller joins a motion to the next (docs/plan.md, "Path
 * modes"); the zero value is LinuxCNC's start-up mode, G64 without P. */
typedef enum fm_path_mode {
    FM_PATH_BLEND = 0,   /* G64 (Fanuc G64, Haas G187): blend within path_tolerance */
    FM_PATH_EXACT_PATH,  /* LinuxCNC G61: stop at corners, flow through tangent joints */
    FM_PATH_EXACT_STOP   /* LinuxCNC G61.1, Fanuc G61 and G09: stop at the end of the motion */
} fm_path_mode;

/* Positions are millimetres in machine coordinates: the programmed point plus
 * the active G5x and G92 offsets. The tool tip is start/end + tip_offset
 * (tip_offset is zero when the active tool length offset matches the tool).
 * Arcs: center is the arc centre with center[plane_axis] = start[plane_axis];
 * the helix moves linearly along plane_axis from start to end; turns > 0 is
 * counter-clockwise seen from +plane_axis, |turns| - 1 extra full circles
 * (LinuxCNC ARC_FEED's rotation). */
typedef struct fm_motion {
    fm_motion_kind kind;
    double start[3];
    double end[3];
    double axis_start[3];  /* unit tool axis, (0,0,1) for 3-axis programs */
    double axis_end[3];
    double center[3];      /* arcs */
    int plane_axis;        /* arcs: 0 = X (G19), 1 = Y (G18), 2 = Z (G17) */
    int turns;             /* arcs */
    double tip_offset[3];  /* tool tip minus programmed point */
    double feed;           /* mm/min; 0 for rapids and dwells */
    double spindle_rpm;    /* 0 when stopped */
    int spindle_dir;       /* 1 clockwise (M3), -1 counter-clockwise (M4), 0 stopped */
    int coolant;           /* bit 0 mist (M7), bit 1 flood (M8) */
    int tool;              /* tool number in the spindle */
    double t0, t1;         /* program time interval, seconds */
    int line;              /* 1-based source line */
    long block;            /* N number if given, else -1 */
    long index;            /* 0-based position in the motion stream */
    const fm_path *path;   /* FM_MOTION_PARAM only; valid while the producer lives */
    /* Rotary axes. machine NULL or without rotary axes: a 3-axis motion as
     * above. Otherwise rotary_start/rotary_end are the joint values in
     * degrees (index 0 = A, 1 = B, 2 = C) and the tool's pose comes from
     * the machine's chain (docs/sweep.md): with tcp, start/end (+
     * tip_offset turned with the tool) are the tool tip in the workpiece
     * frame, moving on the line or arc; without, start/end are the linear
     * joints and every joint moves linearly in time. axis_start/axis_end
     * then hold the tool axis in the workpiece frame at the ends (for
     * reports; the sweep recomputes it). machine must outlive the motion's
     * consumers (the producer's options own it). */
    const fm_machine *machine;
    double rotary_start[3], rotary_end[3];
    int tcp;
    double tool_length;    /* gauge line to tip (the tool's G43 length); head axes without TCP */
    /* Path control in force for this motion (toolpaths/plan). Tolerances in
     * mm; 0: none given (LinuxCNC: as fast as possible, no merging). */
    fm_path_mode path_mode;
    double path_tolerance;   /* G64 P, Haas G187's tolerance */
    double naive_tolerance;  /* G64 Q: collinear feed lines within it are merged */
} fm_motion;

/* Receives motions in program order; return non-zero to stop the producer. */
typedef int (*fm_motion_sink)(void *user, const fm_motion *motion);

#endif
