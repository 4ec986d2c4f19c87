/* test_cycle_times: the breakdown of a cycle time (daemon/runner/
 * cycle_times.c) against sums kept here independently: 3,000 motions of
 * random durations over 80 tools, changing tool often enough that the
 * operations overflow the list (FM_CYCLE_MAX_OPERATIONS) and the tools
 * the job result's summary (64): per tool and per listed operation the
 * sums are the test's own, the operations counted all the same, the
 * slowest blocks the test's sort of them, and the summary a prefix; and
 * the summary of no motion at all. */
#include <stdlib.h>

#include "runner/cycle_times.h"
#include "test.h"

#define N 3000
#define TOOLS 80

static int by_time_desc(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x < y) - (x > y);
}

int main(void)
{
    fm_cycle_times ct;
    fm_cycle_times_init(&ct, 10);
    static double tool_t[TOOLS], tool_f[TOOLS], block_t[N];
    static int first_use[TOOLS];
    int order[TOOLS], used = 0;
    double t = 0, f = 0, total = 0, ftotal = 0;
    int tool = -1, line = 0, blocks = 0, prev_tool = -1, prev_line = -1;
    long switches = 0;
    double first_op = 0;
    for (int i = 0; i < N; i++) {
        fm_plan_motion pm = {0};
        /* a new tool every few motions, a new line every one or two */
        if (i == 0 || test_rand01() < 0.4) {
            int next = (int)(test_rand01() * TOOLS) % TOOLS;
            if (i == 0 || next != tool) switches++;
            tool = next;
        }
        if (i == 0 || test_rand01() < 0.7 || tool != prev_tool) line++;
        double dt = test_uniform(0.01, 2.0), df = test_uniform(0.01, 2.0);
        pm.motion.tool = tool;
        pm.motion.line = line;
        pm.motion.block = -1;
        pm.motion.t0 = t;
        pm.motion.t1 = t + dt;
        pm.feed_t0 = f;
        pm.feed_t1 = f + df;
        t += dt;
        f += df;
        total += dt;
        ftotal += df;
        if (!first_use[tool]) {
            first_use[tool] = 1;
            order[used++] = tool;
        }
        tool_t[tool] += dt;
        tool_f[tool] += df;
        if (switches == 1) first_op += dt;
        /* blocks: consecutive motions of one line */
        if (line != prev_line) blocks++;
        block_t[blocks - 1] += dt;
        prev_line = line;
        prev_tool = tool;
        fm_cycle_times_add(&ct, &pm);
    }
    fm_cycle_times_finish(&ct);
    CHECK(!ct.failed);
    CHECK_NEAR(ct.time_s, total, 1e-9);
    CHECK_NEAR(ct.feed_only_s, ftotal, 1e-9);
    CHECK(ct.tool_count == used);
    double sum = 0;
    for (int k = 0; k < ct.tool_count && k < used; k++) {
        CHECK(ct.tools[k].tool == order[k]);
        CHECK_NEAR(ct.tools[k].time_s, tool_t[order[k]], 1e-9);
        CHECK_NEAR(ct.tools[k].feed_only_s, tool_f[order[k]], 1e-9);
        sum += ct.tools[k].time_s;
    }
    CHECK_NEAR(sum, total, 1e-9);
    CHECK(ct.operation_total == switches);
    CHECK(switches > FM_CYCLE_MAX_OPERATIONS);
    CHECK(ct.operation_count == FM_CYCLE_MAX_OPERATIONS);
    CHECK_NEAR(ct.operations[0].time_s, first_op, 1e-9);
    CHECK_NEAR(ct.operations[0].t0, 0.0, 0.0);
    for (int k = 1; k < ct.operation_count; k++) {
        CHECK(ct.operations[k].tool != ct.operations[k - 1].tool);
        CHECK_NEAR(ct.operations[k].t0, ct.operations[k - 1].t1, 1e-9);
    }
    /* the ten slowest blocks, by the test's own sort */
    qsort(block_t, (size_t)blocks, sizeof *block_t, by_time_desc);
    CHECK(ct.top_count == 10);
    for (int k = 0; k < ct.top_count; k++) CHECK_NEAR(ct.top[k].time_s, block_t[k], 1e-9);
    /* the job result's summary: a prefix of each list */
    static fm_cycle_summary s;
    fm_cycle_times_summarize(&ct, &s);
    CHECK(s.tool_count == FM_CYCLE_SUMMARY_TOOLS && s.operation_count == FM_CYCLE_SUMMARY_OPERATIONS);
    CHECK(s.operation_total == switches && s.block_count == 10);
    CHECK(s.tools[63].tool == ct.tools[63].tool && s.operations[63].t1 == ct.operations[63].t1);
    fm_cycle_times view;
    fm_cycle_summary_view(&s, &view);
    json_t *j = fm_cycle_times_json(&view);
    CHECK(j && json_array_size(json_object_get(j, "tools")) == 64 &&
          json_integer_value(json_object_get(j, "operation_count")) == switches &&
          json_array_size(json_object_get(j, "blocks")) == 10);
    json_decref(j);
    fm_cycle_times_free(&ct);

    /* No motion at all (a program that only sets modes): empty lists, no
     * NULL handed to memcpy (UBSan found it in simulate_examples). */
    fm_cycle_times none;
    fm_cycle_times_init(&none, 10);
    fm_cycle_times_finish(&none);
    fm_cycle_times_summarize(&none, &s);
    CHECK(s.tool_count == 0 && s.operation_count == 0 && s.operation_total == 0 && s.block_count == 0);
    fm_cycle_times_free(&none);
    return test_summary("cycle_times");
}
