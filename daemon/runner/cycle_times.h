/* cycle_times.h: a program's planned time broken down, as `frepmill time`
 * prints it and the report's "cycle_times" holds it (docs/plan.md): per
 * tool, per operation (the motions between two tool changes) and the N
 * blocks (consecutive motions of one source line) that take longest, each
 * with its feed-only figure beside. Fed the planner's motions
 * (toolpaths/plan, fm_plan_sink) in program order. */
#ifndef FM_RUNNER_CYCLE_TIMES_H
#define FM_RUNNER_CYCLE_TIMES_H

#include <jansson.h>

#include "toolpaths/plan/plan.h"

typedef struct fm_cycle_tool {
    int tool;
    double time_s, feed_only_s;
} fm_cycle_tool;

/* An operation: the motions from one change of tool to the next. */
typedef struct fm_cycle_operation {
    int tool;
    int first_line, last_line;
    double t0, t1; /* planned start and end, s */
    double time_s, feed_only_s;
} fm_cycle_operation;

typedef struct fm_cycle_block {
    int line;
    long block; /* N number, -1 if none */
    double time_s, feed_only_s;
} fm_cycle_block;

/* The operations a breakdown lists at most (operation_total counts them all). */
#define FM_CYCLE_MAX_OPERATIONS 1000

typedef struct fm_cycle_times {
    double time_s, feed_only_s; /* sums over every motion added */
    long motions;
    fm_cycle_tool *tools; /* in order of first use */
    int tool_count, tool_cap;
    fm_cycle_operation *operations;
    int operation_count, operation_cap;
    long operation_total;
    int operation_tool; /* the current operation's */
    fm_cycle_block *top; /* the slowest blocks, slowest first */
    int top_count, top_max;
    fm_cycle_block current; /* the block being summed */
    int have_current;
    int failed; /* out of memory: the breakdown is incomplete */
} fm_cycle_times;

/* An empty breakdown that keeps the top_blocks slowest blocks; 0 with
 * failed set when out of memory. fm_cycle_times_free also then. */
void fm_cycle_times_init(fm_cycle_times *ct, int top_blocks);
/* One planned motion (motion.t0/t1 planned, feed_t0/t1 feed-only). */
void fm_cycle_times_add(fm_cycle_times *ct, const fm_plan_motion *pm);
/* The program ended: the last block is ranked. */
void fm_cycle_times_finish(fm_cycle_times *ct);
void fm_cycle_times_free(fm_cycle_times *ct);
/* An fm_plan_sink over a breakdown (user: the fm_cycle_times). */
int fm_cycle_times_sink(void *user, const fm_plan_motion *pm);

/* A breakdown kept by value (the job result's: no allocation to free): the
 * first FM_CYCLE_SUMMARY_TOOLS tools and FM_CYCLE_SUMMARY_OPERATIONS
 * operations, the slowest FM_CYCLE_SUMMARY_BLOCKS blocks. */
#define FM_CYCLE_SUMMARY_TOOLS 64
#define FM_CYCLE_SUMMARY_OPERATIONS 64
#define FM_CYCLE_SUMMARY_BLOCKS 10
typedef struct fm_cycle_summary {
    fm_cycle_tool tools[FM_CYCLE_SUMMARY_TOOLS];
    int tool_count;
    fm_cycle_operation operations[FM_CYCLE_SUMMARY_OPERATIONS];
    int operation_count;
    long operation_total;
    fm_cycle_block blocks[FM_CYCLE_SUMMARY_BLOCKS];
    int block_count;
} fm_cycle_summary;

void fm_cycle_times_summarize(const fm_cycle_times *ct, fm_cycle_summary *out);
/* *view reads the summary's arrays (valid while it lives; not to be freed
 * or added to): for fm_cycle_times_json. */
void fm_cycle_summary_view(const fm_cycle_summary *s, fm_cycle_times *view);

/* {"tools": [{"tool", "time_s", "feed_only_s"}], "operations": [{"tool",
 * "first_line", "last_line", "t0", "t1", "time_s", "feed_only_s"}],
 * "operation_count": all of them, "blocks": [{"line", "block"?, "time_s",
 * "feed_only_s"}]}: a new
 * reference, NULL when out of memory. */
json_t *fm_cycle_times_json(const fm_cycle_times *ct);

#endif
