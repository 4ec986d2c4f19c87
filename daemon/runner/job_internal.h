/* job_internal.h: what the job runner's files share (job.h is the public
 * side). job_run.c orchestrates a job (job.h, fm_job_run); each concern has
 * a file of its own:
 *   job_tools.c    the tool table built into cutters (custom HyperFun ones too)
 *   job_program.c  program dispatch (G-code, trajectory) and the stop-at rule
 *   job_cut.c      the cut loop: the survey pass, batching, cuts, progress
 *   job_check.c    the collision check's set-up beside the cut
 *   job_live.c     live jobs: motions from a controller through the same cut
 *   job_motions.c  the program's motions kept: interpreted once per job
 *   job_follow.c   the cut along the planner's blend arcs (machine dynamics)
 *   job_design.c   the design comparison's design and the blame of gouges
 *   job_resources.c  clocks and the process's memory and CPU time */
#ifndef FM_JOB_INTERNAL_H
#define FM_JOB_INTERNAL_H

#include <stdio.h>

#include "cycle_times.h"
#include "frep/frep.h"
#include "job.h"

/* The most motions cut together (one swept-volume field). */
#define JOB_MAX_BATCH 256

/* ---------------------------------------------------------- tools -- */

/* A built tool, with the HyperFun model behind a custom cutter. */
typedef struct job_tool {
    fm_tool tool;
    fm_graph *graph;
    fm_tape *tape;
} job_tool;

typedef struct job_tools {
    fm_tool_table table; /* when loaded here */
    const fm_tool_table *use;
    job_tool *built;
    size_t count;
} job_tools;

/* The spec's table (or its file) built into tools; free with
 * job_tools_free, also on error. */
fm_status job_tools_load(const fm_job_spec *spec, job_tools *t, fm_error *err);
void job_tools_free(job_tools *t);
/* The tool that cuts for a motion: the spindle's, or the table's only tool
 * when the program never loaded one (T0: many single-tool programs have no
 * M6). NULL: nothing cuts. */
const fm_tool *job_tool_for(const job_tools *t, int number);

/* -------------------------------------------------------- program -- */

typedef fm_status (*job_probe_fn)(void *user, const fm_motion *move, int toward, int *tripped,
                                  double *fraction, int *at_start, fm_error *err);

fm_program_kind job_program_kind(const fm_job_spec *spec);
/* Interpret the spec's program into sink (probe: G38 moves, NULL: none
 * trips). */
fm_status job_run_program(const fm_job_spec *spec, const fm_tool_table *tools,
                          fm_motion_sink sink, void *user, job_probe_fn probe, fm_error *err);

/* spec.stop_at_line: has the program gone past LINE with this motion? */
typedef struct job_stop_rule {
    int line;  /* 0: never stop */
    int seen;  /* a motion of LINE went by */
} job_stop_rule;

int job_stop_before(job_stop_rule *r, const fm_motion *m);

/* -------------------------------------------------------- motions -- */

/* How much of a log stays in memory before it spills to a temporary file. */
#define JOB_MOTIONS_MEMORY ((size_t)64 << 20)

/* A log in memory (memory_bytes, then spilled to file, or to a temporary
 * file when file is NULL), or in the job's own file (spec.motion_log). */
fm_job_motions *job_motions_new(size_t memory_bytes, FILE *file);
fm_job_motions *job_motions_open_log(const char *path, fm_error *err);
/* The job's own log complete (keep: the survey succeeded): in place at
 * path when usable, else no file there. */
fm_status job_motions_keep(fm_job_motions *log, const char *path, int keep);
void job_motions_add(fm_job_motions *log, const fm_motion *m);
/* Some motions cannot reach the log (the planner in front of it failed):
 * the cut interprets the program again. */
void job_motions_spoil(fm_job_motions *log);
/* Every motion the program made is in it (none was a PARAM motion, no
 * write failed). */
int job_motions_usable(const fm_job_motions *log);

/* ------------------------------------------------------------ cut -- */

/* The first pass: the whole program is checked before anything is cut,
 * and its length gives the progress its denominator. */
typedef struct job_survey {
    long motions;
    double time_total;
    int max_line;
    int any_tip;
    double tip_lo[3], tip_hi[3]; /* box of the tool tip over the program */
    job_stop_rule stop;
    int stopped;
    fm_job_motions *log; /* the motions kept for the cut and the blame */
    int probing;         /* a G38 move: the cut's motions depend on the stock */
    /* With the machine's dynamics every motion goes through the planner on
     * its way into the log, which so holds the planned times the cut, the
     * progress and the toolpath then use (without: feed-only times). */
    fm_planner *planner;
    int plan_failed;     /* the planner refused a motion: the cycle time stays feed-only */
    fm_plan_totals plan;
    long stop_index;     /* the first motion past the stop (LONG_MAX: none) */
    double plan_end;     /* the planned end of the last motion before it */
    fm_cycle_times times; /* the planned time per tool, operation and block */
} job_survey;

int job_survey_sink(void *user, const fm_motion *m);
/* The survey planner's sink (user: the survey): into the log and the
 * breakdown. */
int job_survey_planned(void *user, const fm_plan_motion *pm);
/* The survey's G38: noted (the cut then interprets the program again, its
 * probe reading the stock), tripped at the end as with no probe. */
fm_status job_survey_probe(void *user, const fm_motion *move, int toward, int *tripped,
                           double *fraction, int *at_start, fm_error *err);

typedef struct job_cutter {
    const fm_job_spec *spec;
    const fm_job_hooks *hooks;
    job_tools *tools;
    fm_stock *stock;
    fm_error *err;
    fm_status status;
    int stopped;

    fm_motion batch[JOB_MAX_BATCH];
    size_t batch_count;
    double batch_length;
    const fm_tool *batch_tool;

    fm_job_progress progress;
    double started;
    job_stop_rule stop;
    int stopped_at_line;
    unsigned char *lines_cut; /* bitmap of source lines that cut */
    size_t lines_cap;
    long blocks;
    fm_stock_cut_stats stats; /* summed over cuts */
    long cuts;

    /* the collision check and its grid (c->stock itself, or a grid of its
     * own cut alongside) */
    fm_check *check;
    fm_stock *check_grid;
    int check_twin;
    size_t findings_seen;
    double check_time;
    /* the no-tool warning (fm_job_result.no_tool_line) */
    int no_tool_line;
    long no_tool_motions;

    /* cutting along the blend arcs (job_follow.c): the piece being cut is
     * a blend arc (not a motion of its own), or its motion's arc is still
     * to come (continues); the batch's last piece's continues */
    int piece_blend, piece_continues;
    int batch_last_continues;

    double trimmed_at; /* when the cut loop last gave free pages back */
} job_cutter;

/* Give the heap's free pages back to the system (glibc's malloc_trim;
 * elsewhere nothing). Each cut frees the leaves that tiles replace and
 * makes new ones elsewhere, in the malloc arena of whichever thread ran
 * the leaf's job; glibc keeps the pages it freed resident in the middle of
 * its heaps, a free space that grows over the job (3D_Chips at 0.1 mm:
 * 20-24 MB of a 260 MB peak). A call costs about a millisecond, so the cut
 * loop makes one at most every JOB_TRIM_INTERVAL_S of cutting. */
void job_release_free_memory(void);
#define JOB_TRIM_INTERVAL_S 0.25

/* The motion sink of the cutting pass (user: the cutter) and its G38
 * probe. */
int job_cut_sink(void *user, const fm_motion *m);
fm_status job_cut_probe(void *user, const fm_motion *move, int toward, int *tripped,
                        double *fraction, int *at_start, fm_error *err);
/* Cut what the batch holds, then report progress. */
fm_status job_flush_batch(job_cutter *c);
/* Tell the progress hook where the job is after motion last (nothing is
 * pending in the batch). */
void job_report(job_cutter *c, const fm_motion *last);

/* --------------------------------------------------------- follow -- */

/* Does the cut follow the blend arcs: the machine's dynamics given (and
 * not "follow_blends": false), the program planned, its motions kept and
 * no probe reading the stock. */
int job_follow_wanted(const fm_job_spec *spec, const job_survey *sv);
/* The kept motions through the planner and its blended path into the cut
 * sink. */
fm_status job_follow_replay(job_cutter *c, fm_job_motions *log, fm_error *err);

/* ---------------------------------------------------------- check -- */

fm_status job_check_setup(job_cutter *c, const job_survey *sv, fm_error *err);
void job_check_free(job_cutter *c);

/* ----------------------------------------------------------- live -- */

fm_status job_run_live(job_cutter *c);

/* --------------------------------------------------------- design -- */

fm_design *job_make_design(const fm_job_spec *spec, const fm_stock *stock, fm_error *err);
fm_status job_blame_gouges(const fm_job_spec *spec, const job_tools *tools, double voxel,
                           fm_job_motions *log, fm_job_result *result, fm_error *err);

#endif
