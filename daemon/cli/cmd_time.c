/* cmd_time.c: `frepmill time PROGRAM --machine M`: the program's cycle time
 * as the controller runs it (toolpaths/plan: LinuxCNC's planner with the
 * machine file's dynamics, docs/plan.md), beside the feed-only time, per
 * tool and for the slowest blocks; nothing is cut, so it is fast. */
#include "commands.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runner/cycle_times.h"
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
            "says so. Also per tool, per operation (the motions from one tool change to\n"
            "the next) and the N blocks (source lines) that take longest (default 10).\n"
            "The first move starts at the machine's \"start\" with the tool it holds\n"
            "(--initial-tool, else its \"initial_tool\"; docs/simulate.md).\n"
            "--json prints one object:\n"
            "  {\"cycle_time_s\":..,\"feed_only_s\":..,\"planned\":true,\"motions\":..,\n"
            "   \"segments\":..,\"blends\":..,\"stops\":..,\"tool_changes\":..,\n"
            "   \"tools\":[{\"tool\":1,\"time_s\":..,\"feed_only_s\":..}],\n"
            "   \"operations\":[{\"tool\":1,\"first_line\":7,\"last_line\":275,\"t0\":..,\"t1\":..,\n"
            "                   \"time_s\":..,\"feed_only_s\":..}],\"operation_count\":1,\n"
            "   \"blocks\":[{\"line\":12,\"block\":120,\"time_s\":..,\"feed_only_s\":..}],\n"
            "   \"plan_seconds\":..}\n"
            "Exit status: 0 ok, 2 bad input, 3 limit exceeded, 4 I/O error.\n");
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
    fm_cycle_times tm;
    fm_cycle_times_init(&tm, nblocks);
    fm_planner *p = fm_planner_new(&dyn, fm_cycle_times_sink, &tm, &err);
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
    fm_cycle_times_finish(&tm);
    json_t *doc = NULL;
    if (!st && json) {
        json_t *parts = fm_cycle_times_json(&tm);
        doc = json_pack("{s:s, s:f, s:f, s:b, s:I, s:I, s:I, s:I, s:I}", "program", program,
                        "cycle_time_s", tot.cycle_time_s, "feed_only_s", tot.feed_only_s, "planned",
                        dyn.given, "motions", (json_int_t)tot.motions, "segments",
                        (json_int_t)tot.segments, "blends", (json_int_t)tot.blends, "stops",
                        (json_int_t)tot.stops, "tool_changes", (json_int_t)tot.tool_changes);
        if (!parts || !doc || json_object_update(doc, parts) ||
            json_object_set_new(doc, "plan_seconds", json_real(secs)))
            st = fm_error_set(&err, FM_ERR_LIMIT, "frepmill time: out of memory");
        json_decref(parts);
    }
    if (st) {
        fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
        json_decref(doc);
        fm_cycle_times_free(&tm);
        return (int)st;
    }
    if (json) {
        json_dumpf(doc, stdout, JSON_COMPACT | JSON_REAL_PRECISION(10));
        putchar('\n');
        json_decref(doc);
    } else {
        printf("%s: cycle time %.3f s, feed-only %.3f s%s\n", program, tot.cycle_time_s, tot.feed_only_s,
               dyn.given ? "" : " (no dynamics in the machine file: the time is feed-only; docs/plan.md)");
        if (dyn.given)
            printf("  %ld motions, %ld segments (%ld blend arcs, %ld stops), %ld tool changes\n",
                   tot.motions, tot.segments, tot.blends, tot.stops, tot.tool_changes);
        printf("  planned in %.3f s (%.0f motions/s)\n", secs, secs > 0 ? (double)tot.motions / secs : 0.0);
        for (int k = 0; k < tm.tool_count; k++)
            printf("  tool %d: %.3f s, feed-only %.3f s\n", tm.tools[k].tool, tm.tools[k].time_s,
                   tm.tools[k].feed_only_s);
        if (tm.operation_total > 1)
            for (int k = 0; k < tm.operation_count; k++)
                printf("  operation %d (tool %d, lines %d-%d): %.3f s, feed-only %.3f s\n", k + 1,
                       tm.operations[k].tool, tm.operations[k].first_line, tm.operations[k].last_line,
                       tm.operations[k].time_s, tm.operations[k].feed_only_s);
        if (tm.top_count) printf("  the %d longest blocks:\n", tm.top_count);
        for (int k = 0; k < tm.top_count; k++) {
            printf("    line %d", tm.top[k].line);
            if (tm.top[k].block >= 0) printf(" (N%ld)", tm.top[k].block);
            printf(": %.3f s, feed-only %.3f s\n", tm.top[k].time_s, tm.top[k].feed_only_s);
        }
    }
    fm_cycle_times_free(&tm);
    if (fflush(stdout) || ferror(stdout)) {
        fprintf(stderr, "frepmill time: error writing the output\n");
        return 4;
    }
    return 0;
}
