/* cmd_time.c: `frepmill time PROGRAM --machine M`: the program's cycle time
 * as the controller runs it (toolpaths/plan: LinuxCNC's planner with the
 * machine file's dynamics, docs/plan.md), beside the feed-only time, per
 * tool and for the slowest blocks; nothing is cut, so it is fast. */
#include "commands.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runner/dynamics.h"
#include "runner/job.h"
#include "runner/machine.h"
#include "toolpaths/gcode/gcode.h"
#include "toolpaths/plan/plan.h"
#include "toolpaths/tooltable/tooltable.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: frepmill time PROGRAM [--machine FILE.json] [--dialect linuxcnc|fanuc]\n"
            "                     [--tools TOOLS] [--blocks N] [--json] [--initial-tool N]\n\n"
            "Plan a G-code program (or a parametric trajectory, PROGRAM.json, whose\n"
            "segments keep their own timing) as the controller runs it and print its cycle time\n"
            "beside the feed-only time (each move's length over its feed): LinuxCNC's\n"
            "trajectory planner (acceleration, look-ahead, G64 P/Q blends, G61 stops,\n"
            "arcs at their normal-acceleration limit) with the machine file's\n"
            "\"dynamics\" (docs/plan.md). Without dynamics the time is feed-only and\n"
            "says so. Also per tool, and the N blocks (source lines) that take longest\n"
            "(default 10). The first move starts at the machine's \"start\" with the tool\n"
            "it holds (--initial-tool, else its \"initial_tool\"; docs/simulate.md).\n"
            "--json prints one object:\n"
            "  {\"cycle_time_s\":..,\"feed_only_s\":..,\"planned\":true,\"motions\":..,\n"
            "   \"segments\":..,\"blends\":..,\"stops\":..,\"tool_changes\":..,\n"
            "   \"tools\":[{\"tool\":1,\"time_s\":..,\"feed_only_s\":..}],\n"
            "   \"blocks\":[{\"line\":12,\"block\":120,\"time_s\":..,\"feed_only_s\":..}],\n"
            "   \"plan_seconds\":..}\n"
            "Exit status: 0 ok, 2 bad input, 3 limit exceeded, 4 I/O error.\n");
}

typedef struct tool_sum {
    int tool;
    double time, feed;
} tool_sum;

typedef struct block_sum {
    int line;
    long block;
    double time, feed;
} block_sum;

typedef struct timing {
    tool_sum *tools;
    int ntools, captools;
    block_sum *top; /* the slowest blocks, slowest first */
    int ntop, maxtop;
    block_sum cur;  /* the block being summed (consecutive motions of a line) */
    int have_cur;
    int failed;
} timing;

static void offer_block(timing *tm, const block_sum *b)
{
    int i;
    if (tm->ntop < tm->maxtop) i = tm->ntop++;
    else if (tm->maxtop == 0 || tm->top[tm->maxtop - 1].time >= b->time) return;
    else i = tm->maxtop - 1;
    tm->top[i] = *b;
    for (; i > 0 && tm->top[i - 1].time < tm->top[i].time; i--) {
        block_sum t = tm->top[i - 1];
        tm->top[i - 1] = tm->top[i];
        tm->top[i] = t;
    }
}

static int on_planned(void *user, const fm_plan_motion *pm)
{
    timing *tm = user;
    const fm_motion *m = &pm->motion;
    double dt = m->t1 - m->t0, df = pm->feed_t1 - pm->feed_t0;
    int k = 0;
    while (k < tm->ntools && tm->tools[k].tool != m->tool) k++;
    if (k == tm->ntools) {
        if (tm->ntools == tm->captools) {
            int cap = tm->captools ? 2 * tm->captools : 8;
            tool_sum *n = realloc(tm->tools, (size_t)cap * sizeof *n);
            if (!n) {
                tm->failed = 1;
                return 1;
            }
            tm->tools = n;
            tm->captools = cap;
        }
        tm->tools[tm->ntools++] = (tool_sum){m->tool, 0, 0};
    }
    tm->tools[k].time += dt;
    tm->tools[k].feed += df;
    if (tm->have_cur && tm->cur.line != m->line) {
        offer_block(tm, &tm->cur);
        tm->have_cur = 0;
    }
    if (!tm->have_cur) {
        tm->cur = (block_sum){m->line, m->block, 0, 0};
        tm->have_cur = 1;
    }
    tm->cur.time += dt;
    tm->cur.feed += df;
    return 0;
}

/* A JSON string: quotes, backslashes and control characters escaped. */
static void print_json_string(const char *text)
{
    putchar('"');
    for (const unsigned char *c = (const unsigned char *)text; *c; c++) {
        if (*c == '"' || *c == '\\') printf("\\%c", *c);
        else if (*c < 0x20) printf("\\u%04x", *c);
        else putchar(*c);
    }
    putchar('"');
}

int fm_cmd_time(int argc, char **argv)
{
    const char *tools_path = NULL, *machine_path = NULL;
    int json = 0, nblocks = 10, initial_tool = 0;
    /* the program as a job's (the runner's one dispatch: G-code or a
     * trajectory) */
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.rapid_rate = 0; /* the interpreters' own unless the machine gives one */
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--tools") && i + 1 < argc) {
            tools_path = argv[++i];
        } else if (!strcmp(a, "--machine") && i + 1 < argc) {
            machine_path = argv[++i];
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--initial-tool") && i + 1 < argc) {
            char *end;
            long t = strtol(argv[++i], &end, 10);
            if (*end || t < 0 || t > 99999999) {
                fprintf(stderr, "frepmill time: --initial-tool '%s'; expected a tool number >= 0\n", argv[i]);
                return 2;
            }
            initial_tool = (int)t;
        } else if (!strcmp(a, "--blocks") && i + 1 < argc) {
            char *end;
            long n = strtol(argv[++i], &end, 10);
            if (*end || n < 0 || n > 100000) {
                fprintf(stderr, "frepmill time: --blocks '%s'; expected a count 0 to 100000\n", argv[i]);
                return 2;
            }
            nblocks = (int)n;
        } else if (!strcmp(a, "--dialect") && i + 1 < argc) {
            fm_gcode_dialect dialect;
            if (!fm_gcode_dialect_parse(argv[++i], &dialect)) {
                fprintf(stderr, "frepmill time: --dialect '%s'; expected linuxcnc or fanuc\n", argv[i]);
                return 2;
            }
            spec.dialect = argv[i];
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "frepmill time: unknown or incomplete option '%s'\n", a);
            usage(stderr);
            return 2;
        } else if (!spec.program_path) {
            spec.program_path = a;
        } else {
            fprintf(stderr, "frepmill time: more than one program ('%s')\n", a);
            return 2;
        }
    }
    if (!spec.program_path) {
        usage(stderr);
        return 2;
    }
    const char *program = spec.program_path;
    fm_error err = {0};
    char msg[1024];
    fm_plan_machine dyn;
    fm_plan_machine_default(&dyn);
    fm_check_machine machine;
    fm_tool_table table = {0, NULL};
    if (machine_path) {
        if (fm_check_machine_load(machine_path, &machine, &err) ||
            fm_plan_machine_load(machine_path, &dyn, &err)) {
            fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
            return (int)err.code;
        }
        spec.machine = &machine.chain;
        memcpy(spec.reference_points, machine.reference_points, sizeof spec.reference_points);
        if (machine.rapid_rate > 0) spec.rapid_rate = machine.rapid_rate;
    }
    if (tools_path) {
        if (fm_tooltable_load(tools_path, &table, &err)) {
            fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
            return (int)err.code;
        }
    }
    /* the first move from where the machine stands, with the tool it holds */
    fm_job_spec_start_state(&spec, machine_path ? &machine : NULL, initial_tool);
    /* feed-only rapids at the rate the motions were timed with */
    if (spec.rapid_rate > 0) dyn.rapid_rate = spec.rapid_rate;
    timing tm = {0};
    tm.maxtop = nblocks;
    tm.top = nblocks ? calloc((size_t)nblocks, sizeof *tm.top) : NULL;
    fm_planner *p = fm_planner_new(&dyn, on_planned, &tm, &err);
    fm_status st = p ? FM_OK : err.code;
    double c0 = fm_clock_monotonic_s();
    fm_plan_totals tot = {0};
    fm_gcode_options opt;
    fm_traj_options topt;
    if (!st) st = fm_job_program_options(&spec, tools_path ? &table : NULL, &opt, &topt, &err);
    if (!st) {
        st = fm_job_program_run(&spec, &opt, &topt, fm_planner_motion_sink, p, &err);
        if (st && fm_planner_error(p)->code) err = *fm_planner_error(p);
        if (!st) st = fm_planner_finish(p, &tot, &err);
    }
    double secs = fm_clock_monotonic_s() - c0;
    fm_planner_free(p);
    fm_tool_table_free(&table);
    if (!st && tm.failed) st = fm_error_set(&err, FM_ERR_LIMIT, "frepmill time: out of memory");
    if (st) {
        fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
        free(tm.tools);
        free(tm.top);
        return (int)st;
    }
    if (tm.have_cur) offer_block(&tm, &tm.cur);
    if (json) {
        printf("{\"program\":");
        print_json_string(program);
        printf(",\"cycle_time_s\":%.6f,\"feed_only_s\":%.6f,\"planned\":%s,"
               "\"motions\":%ld,\"segments\":%ld,\"blends\":%ld,\"stops\":%ld,\"tool_changes\":%ld,"
               "\"tools\":[",
               tot.cycle_time_s, tot.feed_only_s, dyn.given ? "true" : "false", tot.motions,
               tot.segments, tot.blends, tot.stops, tot.tool_changes);
        for (int k = 0; k < tm.ntools; k++)
            printf("%s{\"tool\":%d,\"time_s\":%.6f,\"feed_only_s\":%.6f}", k ? "," : "",
                   tm.tools[k].tool, tm.tools[k].time, tm.tools[k].feed);
        printf("],\"blocks\":[");
        for (int k = 0; k < tm.ntop; k++) {
            printf("%s{\"line\":%d,", k ? "," : "", tm.top[k].line);
            if (tm.top[k].block >= 0) printf("\"block\":%ld,", tm.top[k].block);
            printf("\"time_s\":%.6f,\"feed_only_s\":%.6f}", tm.top[k].time, tm.top[k].feed);
        }
        printf("],\"plan_seconds\":%.6f}\n", secs);
    } else {
        printf("%s: cycle time %.3f s, feed-only %.3f s%s\n", program, tot.cycle_time_s, tot.feed_only_s,
               dyn.given ? "" : " (no dynamics in the machine file: the time is feed-only; docs/plan.md)");
        if (dyn.given)
            printf("  %ld motions, %ld segments (%ld blend arcs, %ld stops), %ld tool changes\n",
                   tot.motions, tot.segments, tot.blends, tot.stops, tot.tool_changes);
        printf("  planned in %.3f s (%.0f motions/s)\n", secs, secs > 0 ? (double)tot.motions / secs : 0.0);
        for (int k = 0; k < tm.ntools; k++)
            printf("  tool %d: %.3f s, feed-only %.3f s\n", tm.tools[k].tool, tm.tools[k].time,
                   tm.tools[k].feed);
        if (tm.ntop) printf("  the %d longest blocks:\n", tm.ntop);
        for (int k = 0; k < tm.ntop; k++) {
            printf("    line %d", tm.top[k].line);
            if (tm.top[k].block >= 0) printf(" (N%ld)", tm.top[k].block);
            printf(": %.3f s, feed-only %.3f s\n", tm.top[k].time, tm.top[k].feed);
        }
    }
    free(tm.tools);
    free(tm.top);
    if (fflush(stdout) || ferror(stdout)) {
        fprintf(stderr, "frepmill time: error writing the output\n");
        return 4;
    }
    return 0;
}
