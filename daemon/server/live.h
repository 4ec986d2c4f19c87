/* live.h: Modbus live mode's parts below the job table (live.c): a live
 * job's positions, journal and motion source, the live session (the one
 * job that takes positions now) and the live job's document. The table
 * (jobs.c) starts and stops live mode with these. */
#ifndef FM_DAEMON_LIVE_H
#define FM_DAEMON_LIVE_H

#include "job_record.h"
#include "runner/job.h"

/* The live job's motion source for the runner; reads the journal back
 * first after a restart, and opens it for the positions to come. */
fm_status fm_live_prepare(job *j, fm_job_motion_source *src, fm_error *err);

/* The live session: at most one job taking positions, held by reference.
 * Its lock is taken before the table's and any job's. */
typedef struct fm_live_session {
    pthread_mutex_t lock;
    job *job;
    /* The live machine's latest position (guarded by lock), and who is told
     * of each (the MTConnect agent): the hook is called after the position
     * is queued, under hook_lock, never under lock. */
    int has_last;
    fm_live_pose last;
    pthread_mutex_t hook_lock;
    void (*on_position)(void *user);
    void *on_position_user;
} fm_live_session;
void fm_live_session_init(fm_live_session *s);
void fm_live_session_destroy(fm_live_session *s);
/* Make j the live job (its live state made first: a position written right
 * after "live on" is queued, not refused) / stop that if it is. */
fm_status fm_live_attach(fm_live_session *s, job *j, fm_error *err);
void fm_live_detach(fm_live_session *s, job *j);
int fm_live_active(fm_live_session *s);
/* Queue a position for the live job and journal it; refusals: live mode
 * off or the job ended (FM_ERR_INPUT), reason "busy" (the queue is full). */
fm_status fm_live_position(fm_live_session *s, const fm_live_pose *pose, fm_error *err);
/* Live mode off: the session lets its job go, which cuts what is queued
 * and ends on its own thread. */
void fm_live_stop(fm_live_session *s);
/* The live machine's latest position: 1, or 0 when live mode is off or no
 * position came yet. */
int fm_live_machine(fm_live_session *s, fm_live_pose *out);
/* Call fn(user) after each position queued (NULL: nobody); returns once a
 * call in progress has ended. */
void fm_live_on_position(fm_live_session *s, void (*fn)(void *user), void *user);
/* The source's state into the live job's live_note (nothing without one). */
void fm_live_note(fm_live_session *s, const char *note);

/* The live job's document: the configured stock (a SPEC string) and tool
 * table file, or where NULL or "" those of src (a job, or NULL); voxel and
 * feed (<= 0: 0.25 mm and 1000 mm/min). Parsed by the one parser of job
 * documents with rules. */
typedef struct fm_live_config {
    const char *stock;
    const char *tools;
    const char *machine; /* a machine file (docs/check.md), or NULL / "": none */
    double voxel;
    double feed;
} fm_live_config;
fm_status fm_live_document(const fm_live_config *cfg, const job *src, const fm_job_doc_rules *rules,
                           fm_job_doc **out, fm_error *err);

#endif
