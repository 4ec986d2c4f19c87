/* job_view.h: the state of a job and the plain copy of its published
 * status (what Modbus and listings read), shared by the job record
 * (job_record.h) and the job manager's public header (jobs.h). */
#ifndef FM_DAEMON_JOB_VIEW_H
#define FM_DAEMON_JOB_VIEW_H

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
    double program_time_s;
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

#endif
