/* bench_plan.c: the planner's speed on a generated 1,000,000-segment
 * finishing program (rows of 0.25 mm chords over a wavy surface, G64 P0.01:
 * every corner a blend arc candidate, naive-CAM merging on): segments per
 * second planned from motions in memory (the goal, >= 1 M/s on one core),
 * then `frepmill time`'s whole path, interpreting and planning, beside its
 * floor, interpreting without planning (with the breakdown per tool,
 * operation and block that `frepmill time` and the report make). Wall and
 * CPU time are printed; on a shared machine the CPU figure is the
 * comparable one.
 * usage: bench_plan [SEGMENTS] [--program FILE]: FILE gets the generated
 * G-code, for `frepmill time` and `frepmill simulate` (docs/plan.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "toolpaths/gcode/gcode.h"
#include "runner/cycle_times.h"
#include "toolpaths/plan/plan.h"
#include "bench_clock.h"

#define ROW 400 /* chords per row: 100 mm */

/* The i-th point of the path: rows along X, 0.5 mm apart, Z a gentle wave. */
static void point(long i, double p[3])
{
    long row = i / (ROW + 1), k = i % (ROW + 1);
    double x = (row % 2 ? ROW - k : k) * 0.25;
    double y = (double)row * 0.5;
    p[0] = x;
    p[1] = y;
    p[2] = 0.5 * sin(x * 0.2) * cos(y * 0.1);
}

static int count(void *user, const fm_motion *m)
{
    (void)m;
    (*(long *)user)++;
    return 0;
}

static int count_planned(void *user, const fm_plan_motion *m)
{
    (void)m;
    (*(long *)user)++;
    return 0;
}

static fm_plan_machine machine(void)
{
    fm_plan_machine m;
    fm_plan_machine_default(&m);
    m.given = 1;
    for (int i = 0; i < 3; i++) {
        m.linear[i].max_velocity = 100.0;
        m.linear[i].max_acceleration = 2000.0;
    }
    m.max_feed_override = 1.2;
    return m;
}

int main(int argc, char **argv)
{
    long n = 1000000;
    const char *program = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--program") && i + 1 < argc) program = argv[++i];
        else if ((n = atol(argv[i])) <= 0) {
            fprintf(stderr, "usage: bench_plan [SEGMENTS] [--program FILE]\n");
            return 2;
        }
    }
    fm_plan_machine m = machine();
    fm_error err;

    /* 1. the planner alone: motions made in memory, pushed one by one;
     * with G64 P0.01 Q0.01 (naive-CAM merging on) and with Q0 (every chord
     * its own segment, every corner a blend: the most work per motion) */
    fm_plan_totals tot;
    for (int pass = 0; pass < 2; pass++) {
        long planned = 0;
        fm_planner *p = fm_planner_new(&m, count_planned, &planned, &err);
        if (!p) return 3;
        double w0 = bench_wall_s(), c0 = bench_cpu_s();
        fm_motion mo = {0};
        mo.kind = FM_MOTION_LINE;
        mo.feed = 3000.0;
        mo.path_tolerance = 0.01;
        mo.naive_tolerance = pass == 0 ? 0.01 : 0.0;
        mo.axis_start[2] = mo.axis_end[2] = 1.0;
        point(0, mo.end);
        for (long i = 1; i <= n; i++) {
            mo.start[0] = mo.end[0];
            mo.start[1] = mo.end[1];
            mo.start[2] = mo.end[2];
            point(i, mo.end);
            mo.index = i - 1;
            mo.line = (int)i;
            mo.t0 = mo.t1;
            mo.t1 += sqrt((mo.end[0] - mo.start[0]) * (mo.end[0] - mo.start[0]) +
                          (mo.end[1] - mo.start[1]) * (mo.end[1] - mo.start[1]) +
                          (mo.end[2] - mo.start[2]) * (mo.end[2] - mo.start[2])) /
                     (mo.feed / 60.0);
            if (fm_planner_push(p, &mo, &err)) return 2;
        }
        if (fm_planner_finish(p, &tot, &err)) return 2;
        double pw = bench_wall_s() - w0, pc = bench_cpu_s() - c0;
        fm_planner_free(p);
        printf("planner, %s: %ld segments in %.3f s wall, %.3f s CPU: %.0f segments/s wall, %.0f per "
               "CPU second (goal >= 1000000: %.2fx)\n",
               pass == 0 ? "G64 P0.01 Q0.01" : "G64 P0.01 Q0", n, pw, pc, n / pw, n / pc, n / pc / 1e6);
        printf("  cycle time %.1f s, feed-only %.1f s; %ld planned segments, %ld blend arcs\n",
               tot.cycle_time_s, tot.feed_only_s, tot.segments, tot.blends);
    }

    /* 2. the same path as G-code: interpreting only (the floor), then
     * interpreting and planning (what `frepmill time` does) */
    size_t cap = (size_t)n * 40 + 64, len = 0;
    char *text = malloc(cap);
    if (!text) return 3;
    double q[3];
    point(0, q);
    len += (size_t)snprintf(text + len, cap - len, "G21 G90 G64 P0.01 F3000\nG1 X%.4f Y%.4f Z%.4f\n",
                            q[0], q[1], q[2]);
    for (long i = 1; i <= n && len + 48 < cap; i++) {
        point(i, q);
        len += (size_t)snprintf(text + len, cap - len, "X%.4f Y%.4f Z%.4f\n", q[0], q[1], q[2]);
    }
    len += (size_t)snprintf(text + len, cap - len, "M2\n");
    if (program) {
        FILE *f = fopen(program, "w");
        if (!f || fwrite(text, 1, len, f) != len || fclose(f)) {
            fprintf(stderr, "bench_plan: cannot write %s\n", program);
            return 4;
        }
    }
    long motions = 0;
    double w0 = bench_wall_s(), c0 = bench_cpu_s();
    if (fm_gcode_run_string(text, len, "bench", NULL, count, &motions, NULL, &err)) return 2;
    double iw = bench_wall_s() - w0, ic = bench_cpu_s() - c0;
    printf("floor, interpreting only: %ld motions in %.3f s wall, %.3f s CPU: %.0f per CPU second\n",
           motions, iw, ic, motions / ic);
    fm_cycle_times ct;
    fm_cycle_times_init(&ct, 10);
    fm_planner *p = fm_planner_new(&m, fm_cycle_times_sink, &ct, &err);
    if (!p) return 3;
    w0 = bench_wall_s();
    c0 = bench_cpu_s();
    if (fm_gcode_run_string(text, len, "bench", NULL, fm_planner_motion_sink, p, NULL, &err)) return 2;
    if (fm_planner_finish(p, &tot, &err)) return 2;
    fm_cycle_times_finish(&ct);
    double tw = bench_wall_s() - w0, tc = bench_cpu_s() - c0;
    fm_planner_free(p);
    printf("interpreting and planning (frepmill time's path, with the breakdown): %ld motions in "
           "%.3f s wall, %.3f s CPU: %.0f per CPU second (%.2fx the floor's time); cycle time %.1f "
           "s, feed-only %.1f s\n",
           ct.motions, tw, tc, ct.motions / tc, tc / ic, tot.cycle_time_s, tot.feed_only_s);
    fm_cycle_times_free(&ct);
    free(text);
    return 0;
}
