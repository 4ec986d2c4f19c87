/* job_view.h: the state of a job and the plain copy of its published
 * status (what Modbus and listings read), shared by the job record
 * (job_record.h) and the job manager's public header (jobs.h). */
#ifndef FM_DAEMON_JOB_VIEW_H
#define FM_DAEMON_JOB_VIEW_H

#include <math.h>
#include <stddef.h>

typedef enum fm_job_state {
    FM_JOB_QUEUED = 0,
    FM_JOB_RUNNING,
    FM_JOB_DONE,
    FM_JOB_FAILED,
    FM_JOB_CANCELLED
} fm_job_state;

/* "queued", "running", ... (defined in job_record.c) */
const char *fm_job_state_name(fm_job_state state);

/* A plain copy of a job's published status. */
typedef struct fm_job_view {
    char id[32];
    fm_job_state state;
    int paused;
    double progress;
    int line;
    long block;
    int tool;
    double position[3];
    /* The rotary joints A, B, C of the motion last cut (degrees), those
     * whose bit (1 << letter) is in rotary_known (the axes of the job's
     * machine), and its spindle speed (rev/min) when has_spindle (not for a
     * live job). Zero: nothing known, as for a job not started. */
    double rotary[3];
    int rotary_known;
    double spindle_rpm;
    int has_spindle;
    double program_time_s;
    /* the whole program's time, the controller's when time_planned (the
     * machine's dynamics planned it), and its feed-only figure */
    double program_time_total_s;
    int time_planned;
    double feed_only_total_s;
    double removed_mm3;
    double stock_mm3;
    double removal_rate_mm3_s;
    int finding_count;
    int error_finding_count; /* findings of severity "error": the collision alarm */
    int first_finding_line;
    int error_code; /* fm_status of a failed job, 0 if none */
    /* The budget warning (fm_job_progress.voxels_uncertain, uncertain_line):
     * counted since the job last started (a resumed job counts anew). */
    size_t voxels_uncertain;
    int uncertain_line;
} fm_job_view;

/* A live machine's position (live mode, daemon/server/live.c): the tool
 * tip's X, Y, Z (mm) or, with a machine's rotary axes, its linear joints;
 * the rotary joints A, B, C (degrees; NAN: not given, taken as 0); the tool;
 * the program line (0: not given, the move's number stands for it); the
 * spindle speed (rev/min; NAN: not given; published only, the cut takes
 * a live move as cutting). */
typedef struct fm_live_pose {
    double xyz[3];
    double abc[3];
    int tool;
    int line;
    double spindle_rpm;
} fm_live_pose;

/* A pose with nothing given but X/Y/Z and the tool. */
static inline void fm_live_pose_init(fm_live_pose *p, const double xyz[3], int tool)
{
    for (int a = 0; a < 3; a++) {
        p->xyz[a] = xyz[a];
        p->abc[a] = NAN;
    }
    p->tool = tool;
    p->line = 0;
    p->spindle_rpm = NAN;
}

#endif
