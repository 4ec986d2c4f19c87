/* cmd_motions.c: `frepmill motions PROGRAM`: interpret a G-code program and
 * print its motions, one JSON object per line, or its first error as
 * file:line:column: message on stderr. */
#include "commands.h"

#include <limits.h>
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
            "usage: frepmill motions PROGRAM [--tools TOOLS] [--format jsonl]\n"
            "                        [--rapid-rate MM_PER_MIN] [--skip N] [--inch]\n"
            "                        [--block-delete] [--subroutine-path DIRS] [--messages]\n"
            "                        [--dialect linuxcnc|fanuc] [--calculator-input]\n"
            "                        [--machine FILE.json] [--initial-tool N]\n\n"
            "Interpret a G-code program (LinuxCNC dialect, or Fanuc/Haas with --dialect\n"
            "fanuc; docs/gcode.md), or a parametric trajectory\n"
            "(PROGRAM.json, docs/trajectory.md), and print one motion per line:\n"
            "  {\"line\":12,\"block\":12,\"kind\":\"arc\",\"start\":[x,y,z],\"end\":[x,y,z],\n"
            "   \"center\":[x,y,z],\"axis\":\"z\",\"turns\":-1,\"feed\":500,\"tool\":1,\n"
            "   \"tip_offset\":[0,0,0],\"t\":[t0,t1],\"cycle_t\":[t0,t1]}\n"
            "Positions are machine millimetres (program point + G5x + G92 offsets).\n"
            "t is the feed-only time (each move's length over its feed); cycle_t the\n"
            "controller's, planned with the machine file's \"dynamics\" (docs/plan.md;\n"
            "the same as t without them).\n"
            "TOOLS is a JSON tool table or a LinuxCNC .tbl file. --skip N interprets\n"
            "everything but prints motions from index N on. --subroutine-path lists the\n"
            "folders (':'-separated) holding NAME.ngc files for o<NAME> call (Fanuc:\n"
            "O1234.nc for M98 P1234). --calculator-input reads Fanuc numbers without a\n"
            "decimal point as whole mm (X5 = 5 mm, not 0.005).\n"
            "A B C words (degrees) give \"rotary\":[a,b,c] at the end of the motion; with\n"
            "--machine (docs/check.md) they turn its rotary axes and each motion also has\n"
            "\"tcp\" and \"tool_axis\" (workpiece frame, both ends).\n"
            "With --machine the tool tip starts at its \"start\" (else the dialect's\n"
            "power-on place: the origin, Fanuc the first reference point).\n"
            "--initial-tool N: the tool in the spindle before the first M6 (default the\n"
            "machine's \"initial_tool\", else none).\n"
            "--messages also prints (debug,...) and (msg,...) texts in order as\n"
            "  {\"kind\":\"message\",\"line\":12,\"text\":\"...\"}\n"
            "Exit status: 0 ok, 2 bad input, 3 limit exceeded, 4 I/O error.\n");
}

static const char *kind_name(fm_motion_kind k)
{
    switch (k) {
    case FM_MOTION_RAPID: return "rapid";
    case FM_MOTION_LINE: return "line";
    case FM_MOTION_ARC: return "arc";
    case FM_MOTION_DWELL: return "dwell";
    default: return "param";
    }
}

/* One motion; t: the times it came with (feed-only), cycle_t: the
 * planned ones (the same without dynamics). */
static int print_motion_timed(FILE *out, const fm_motion *m, double t0, double t1, double c0,
                              double c1)
{
    fprintf(out, "{\"index\":%ld,\"line\":%d,", m->index, m->line);
    if (m->block >= 0) fprintf(out, "\"block\":%ld,", m->block);
    fprintf(out, "\"kind\":\"%s\",\"start\":[%.6f,%.6f,%.6f],\"end\":[%.6f,%.6f,%.6f],",
            kind_name(m->kind), m->start[0], m->start[1], m->start[2], m->end[0], m->end[1],
            m->end[2]);
    if (m->kind == FM_MOTION_ARC)
        fprintf(out, "\"center\":[%.6f,%.6f,%.6f],\"axis\":\"%c\",\"turns\":%d,", m->center[0],
                m->center[1], m->center[2], "xyz"[m->plane_axis], m->turns);
    /* Rotary axes: the end values (degrees, with their offsets) when the
     * program moved any or the machine has them; the tool axis in the
     * workpiece frame at both ends with a machine. */
    const double *r0 = m->rotary_start, *r1 = m->rotary_end;
    if (m->machine || r0[0] || r0[1] || r0[2] || r1[0] || r1[1] || r1[2])
        fprintf(out, "\"rotary\":[%.6f,%.6f,%.6f],", r1[0], r1[1], r1[2]);
    if (m->machine)
        fprintf(out, "\"tcp\":%d,\"tool_axis\":[[%.6f,%.6f,%.6f],[%.6f,%.6f,%.6f]],", m->tcp,
                m->axis_start[0], m->axis_start[1], m->axis_start[2], m->axis_end[0], m->axis_end[1],
                m->axis_end[2]);
    fprintf(out,
            "\"feed\":%.6f,\"tool\":%d,\"spindle\":%.6f,\"tip_offset\":[%.6f,%.6f,%.6f],"
            "\"t\":[%.6f,%.6f],\"cycle_t\":[%.6f,%.6f]}\n",
            m->feed, m->tool, m->spindle_rpm * m->spindle_dir, m->tip_offset[0],
            m->tip_offset[1], m->tip_offset[2], t0, t1, c0, c1);
    return ferror(out) ? 1 : 0;
}

/* Without dynamics: the motion as the program made it. */
static int print_motion(void *user, const fm_motion *m)
{
    return print_motion_timed(user, m, m->t0, m->t1, m->t0, m->t1);
}

/* With dynamics the motions come out of the planner a look-ahead later
 * than the program makes them: messages wait for the motions before them. */
typedef struct held_message {
    long before; /* motions the program had made when it printed this */
    int line;
    char *text;
} held_message;

typedef struct planned_out {
    FILE *out;
    long skip;      /* print motions from this index on */
    long pushed;    /* motions given to the planner */
    long delivered; /* motions it gave back */
    held_message *held;
    size_t held_count, held_cap, held_first;
    int failed;
} planned_out;

static void print_message(void *user, int line, const char *text);

static void release_messages(planned_out *po, long upto)
{
    while (po->held_first < po->held_count && po->held[po->held_first].before <= upto) {
        held_message *h = &po->held[po->held_first++];
        print_message(po->out, h->line, h->text);
        free(h->text);
        h->text = NULL;
    }
}

static void hold_message(void *user, int line, const char *text)
{
    planned_out *po = user;
    if (po->held_count == po->held_cap) {
        size_t cap = po->held_cap ? 2 * po->held_cap : 16;
        held_message *n = realloc(po->held, cap * sizeof *n);
        if (!n) {
            po->failed = 1;
            return;
        }
        po->held = n;
        po->held_cap = cap;
    }
    char *copy = strdup(text);
    if (!copy) {
        po->failed = 1;
        return;
    }
    po->held[po->held_count++] = (held_message){po->pushed, line, copy};
}

static int print_planned(void *user, const fm_plan_motion *pm)
{
    planned_out *po = user;
    release_messages(po, po->delivered);
    po->delivered++;
    if (pm->motion.index < po->skip) return 0;
    return print_motion_timed(po->out, &pm->motion, pm->feed_t0, pm->feed_t1, pm->motion.t0,
                              pm->motion.t1);
}

/* The program's motions into the planner (user: the planned_out; the
 * planner is its second member). */
typedef struct planned_push {
    planned_out *po;
    fm_planner *planner;
} planned_push;

static int push_planned(void *user, const fm_motion *m)
{
    planned_push *pp = user;
    pp->po->pushed++;
    return fm_planner_motion_sink(pp->planner, m);
}

/* A message as a JSON string (quotes, backslashes and control characters
 * escaped). */
static void print_message(void *user, int line, const char *text)
{
    FILE *out = user;
    fprintf(out, "{\"kind\":\"message\",\"line\":%d,\"text\":\"", line);
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p == '"' || *p == '\\') fprintf(out, "\\%c", *p);
        else if (*p < 0x20) fprintf(out, "\\u%04x", *p);
        else fputc(*p, out);
    }
    fprintf(out, "\"}\n");
}

int fm_cmd_motions(int argc, char **argv)
{
    const char *tools_path = NULL, *machine_path = NULL;
    fm_check_machine machine;
    /* the program as a job's (the runner's one dispatch), and what only
     * this command asks of the interpreters */
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.rapid_rate = 0; /* the interpreters' own unless given */
    long skip = 0;
    int initial_tool = 0;
    int start_inch = 0, block_delete = 0, messages = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--tools") && i + 1 < argc) {
            tools_path = argv[++i];
        } else if (!strcmp(a, "--format") && i + 1 < argc) {
            if (strcmp(argv[++i], "jsonl")) {
                fprintf(stderr, "frepmill motions: unknown format '%s'; expected jsonl\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--rapid-rate") && i + 1 < argc) {
            char *end;
            spec.rapid_rate = strtod(argv[++i], &end);
            if (*end || !(spec.rapid_rate > 0)) {
                fprintf(stderr, "frepmill motions: --rapid-rate '%s'; expected mm/min > 0\n",
                        argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--skip") && i + 1 < argc) {
            char *end;
            skip = strtol(argv[++i], &end, 10);
            if (*end || skip < 0) {
                fprintf(stderr, "frepmill motions: --skip '%s'; expected a count >= 0\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--machine") && i + 1 < argc) {
            machine_path = argv[++i];
        } else if (!strcmp(a, "--initial-tool") && i + 1 < argc) {
            char *end;
            long t = strtol(argv[++i], &end, 10);
            if (*end || t < 0 || t > 99999999) {
                fprintf(stderr, "frepmill motions: --initial-tool '%s'; expected a tool number >= 0\n",
                        argv[i]);
                return 2;
            }
            initial_tool = (int)t;
        } else if (!strcmp(a, "--inch")) {
            start_inch = 1;
        } else if (!strcmp(a, "--block-delete")) {
            block_delete = 1;
        } else if (!strcmp(a, "--subroutine-path") && i + 1 < argc) {
            spec.subroutine_path = argv[++i];
        } else if (!strcmp(a, "--messages")) {
            messages = 1;
        } else if (!strcmp(a, "--dialect") && i + 1 < argc) {
            fm_gcode_dialect dialect;
            if (!fm_gcode_dialect_parse(argv[++i], &dialect)) {
                fprintf(stderr, "frepmill motions: --dialect '%s'; expected linuxcnc or fanuc\n",
                        argv[i]);
                return 2;
            }
            spec.dialect = argv[i];
        } else if (!strcmp(a, "--calculator-input")) {
            spec.calculator_input = 1;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "frepmill motions: unknown or incomplete option '%s'\n", a);
            usage(stderr);
            return 2;
        } else if (!spec.program_path) {
            spec.program_path = a;
        } else {
            fprintf(stderr, "frepmill motions: more than one PROGRAM ('%s')\n", a);
            return 2;
        }
    }
    if (!spec.program_path) {
        usage(stderr);
        return 2;
    }
    fm_error err;
    char msg[1024];
    fm_tool_table table = {0, NULL};
    fm_plan_machine dyn;
    fm_plan_machine_default(&dyn);
    if (tools_path) {
        if (fm_tooltable_load(tools_path, &table, &err)) {
            fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
            return (int)err.code;
        }
    }
    if (machine_path) {
        if (fm_check_machine_load(machine_path, &machine, &err) ||
            fm_plan_machine_load(machine_path, &dyn, &err)) {
            fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
            fm_tool_table_free(&table);
            return (int)err.code;
        }
        spec.machine = &machine.chain;
        memcpy(spec.reference_points, machine.reference_points, sizeof spec.reference_points);
        if (machine.rapid_rate > 0 && !(spec.rapid_rate > 0)) spec.rapid_rate = machine.rapid_rate;
    }
    fm_job_spec_start_state(&spec, machine_path ? &machine : NULL, initial_tool);
    fm_gcode_options opt;
    fm_traj_options topt;
    fm_status st = fm_job_program_options(&spec, tools_path ? &table : NULL, &opt, &topt, &err);
    /* a trajectory's units come from its document: --inch and
     * --block-delete are G-code's */
    /* with dynamics every motion is planned, so none is skipped before it
     * is; the printing skips them */
    planned_out po = {stdout, skip, 0, 0, NULL, 0, 0, 0, 0};
    opt.skip_motions = topt.skip_motions = dyn.given ? 0 : skip;
    opt.start_inch = start_inch;
    opt.block_delete = block_delete;
    if (messages) {
        opt.message = dyn.given ? hold_message : print_message;
        opt.message_user = dyn.given ? (void *)&po : (void *)stdout;
    }
    static char outbuf[1 << 16];
    setvbuf(stdout, outbuf, _IOFBF, sizeof outbuf);
    if (st == FM_OK && dyn.given) {
        planned_push pp = {&po, fm_planner_new(&dyn, print_planned, &po, &err)};
        st = pp.planner ? FM_OK : err.code;
        if (st == FM_OK) {
            st = fm_job_program_run(&spec, &opt, &topt, push_planned, &pp, &err);
            if (st && fm_planner_error(pp.planner)->code) err = *fm_planner_error(pp.planner);
            /* the motions before an error are printed, as without dynamics */
            fm_error ferr;
            fm_status fst = fm_planner_finish(pp.planner, NULL, &ferr);
            if (st == FM_OK && fst != FM_OK) {
                st = fst;
                err = ferr;
            }
        }
        fm_planner_free(pp.planner);
        release_messages(&po, LONG_MAX);
        for (size_t i = po.held_first; i < po.held_count; i++) free(po.held[i].text);
        free(po.held);
        if (st == FM_OK && po.failed) st = fm_error_set(&err, FM_ERR_LIMIT, "out of memory");
    } else if (st == FM_OK) {
        st = fm_job_program_run(&spec, &opt, &topt, print_motion, stdout, &err);
    }
    fflush(stdout);
    fm_tool_table_free(&table);
    if (st) {
        fprintf(stderr, "%s\n", fm_error_format(&err, msg, sizeof msg));
        return (int)st;
    }
    if (ferror(stdout)) {
        fprintf(stderr, "frepmill motions: error writing the output\n");
        return 4;
    }
    return 0;
}
