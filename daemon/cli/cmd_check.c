/* cmd_check.c: `frepmill check`: simulate a program at the check's coarse
 * voxel size with the job runner and relate every motion to the stock, the
 * fixtures and the machine (lib/check) before the real machine cuts.
 * Findings go to standard output (or --report) as JSON, a summary to
 * standard error; the exit status says clean (0), findings (1), bad input
 * (2), resource limit (3), I/O (4). */
#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "runner/check_pass.h"
#include "commands.h"
#include "runner/findings_json.h"
#include "job_flags.h"
#include "runner/job.h"

#define CHECK_DEFAULT_VOXEL FM_CHECK_PASS_VOXEL

static void usage(FILE *out)
{
    fprintf(out,
            "usage: frepmill check PROGRAM --stock SPEC --tools TOOLS|--tools-from-program\n"
            "                      [--fixture FILE]...\n"
            "                      [--machine FILE.json] [--clearance MM] [--report FILE]\n"
            "                      [--voxel MM] [--tolerance MM] [--rapid-clearance MM]\n"
            "                      [--max-ramp DEG] [--rapid-rate MM_PER_MIN]\n"
            "                      [--dialect linuxcnc|fanuc] [--subroutine-path DIRS]\n"
            "                      [--calculator-input] [--initial-tool N]\n"
            "\n"
            "PROGRAM      G-code, or a parametric trajectory (.json)\n"
            "SPEC         box:X0,Y0,Z0,X1,Y1,Z1 | cylinder:X,Y,Z0,Z1,R | FILE.hf | FILE.stl | FILE.vdb\n"
            "TOOLS        tool table: frepmill JSON, LinuxCNC .tbl, Fusion 360 .json or .tools,\n"
            "             FreeCAD .fctl or .fctb, CAMotics project or tool table (docs/tooltable.md)\n"
            "--tools-from-program  no table: the tools the program's comments name, as CAM\n"
            "             posts write them ((T1 D=6. CR=0. - FLAT END MILL)); guesses are warned\n"
            "--fixture    clamp, vise or table: HyperFun model (.hf) or closed STL mesh (.stl)\n"
            "--machine    travel limits, rapid rate, start position and tool, rotary axes,\n"
            "             head and components (docs/check.md)\n"
            "--initial-tool  the tool in the spindle before the first M6 (default: the\n"
            "             machine's initial_tool, else none; a one-tool table's tool cuts);\n"
            "             a feed into the stock with no tool is a no_tool finding\n"
            "--clearance  shank, holder and head near misses closer than this are warnings\n"
            "             (default: shank 0, holder and the machine's head 1 mm)\n"
            "--rapid-clearance  the same for the flutes in rapids and at fixtures (default 0)\n"
            "--tolerance  contact deeper than this is an error (default 0.01 mm)\n"
            "--max-ramp   steepest descent for tools that cannot cut at the centre (default 3 deg)\n"
            "--voxel      the check's voxel edge (default %.1f mm)\n"
            "--report     findings JSON to this file instead of standard output\n"
            "--dialect    the G-code's dialect (default linuxcnc; docs/gcode.md)\n"
            "--subroutine-path  ':'-separated folders of subroutine files (NAME.ngc, Fanuc O1234.nc)\n"
            "--calculator-input Fanuc: X5 is 5 mm, not 0.005 (DPI / Haas setting 162)\n"
            "Exit status: 0 clean, 1 findings, 2 bad input, 3 resource limit, 4 I/O error.\n",
            CHECK_DEFAULT_VOXEL);
}

typedef struct check_run {
    fm_check *check;
} check_run;

static void summary(const fm_check *check, const fm_job_result *res, const char *program)
{
    size_t n = fm_check_count(check);
    fprintf(stderr, "frepmill check: %ld motions, %.1f s of program time, checked in %.2f s: ",
            res->motions, res->program_time_s, res->wall_time_s);
    if (n == 0) {
        fprintf(stderr, "no findings\n");
        return;
    }
    fprintf(stderr, "%zu errors, %zu warnings\n", fm_check_count_severity(check, FM_CHECK_ERROR),
            fm_check_count_severity(check, FM_CHECK_WARNING));
    for (size_t i = 0; i < n; i++) {
        const fm_check_finding *f = fm_check_get(check, i);
        fprintf(stderr, "  line %d", f->line);
        if (f->last_line != f->line) fprintf(stderr, "-%d", f->last_line);
        fprintf(stderr, ": %s %s (%s), %.3f mm deep at (%.3f, %.3f, %.3f), t = %.2f s\n",
                fm_check_severity_name(f->severity), fm_check_kind_name(f->kind),
                fm_check_part_name(f->part), f->penetration_mm, f->contact[0], f->contact[1],
                f->contact[2], f->time_s);
        if (f->kind == FM_CHECK_NO_TOOL)
            fprintf(stderr,
                    "  %s:%d: no tool in the spindle (T selects a tool, M6 loads it): the "
                    "spindle's nose goes where the tip is programmed; give the tool in the spindle "
                    "at the start with --initial-tool N (or the machine file's initial_tool) or load "
                    "it with M6\n",
                    program, f->line);
    }
}

/* The job's flags and the document keys they set (job_flags.h): the
 * check's options are the document's options.check. */
static const fm_job_flag CHECK_FLAGS[] = {
    {"PROGRAM", "program.file", FM_JOB_FLAG_TEXT},
    {"--stock", "stock", FM_JOB_FLAG_TEXT},
    {"--tools", "tools", FM_JOB_FLAG_TEXT},
    {"--tools-from-program", "options.tools_from_program", FM_JOB_FLAG_SWITCH},
    {"--fixture", "fixtures", FM_JOB_FLAG_FIXTURE},
    {"--machine", "machine", FM_JOB_FLAG_TEXT},
    {"--clearance", "options.check.clearance", FM_JOB_FLAG_NUMBER},
    {"--rapid-clearance", "options.check.rapid_clearance", FM_JOB_FLAG_NUMBER},
    {"--tolerance", "options.check.tolerance", FM_JOB_FLAG_NUMBER},
    {"--max-ramp", "options.check.max_ramp", FM_JOB_FLAG_NUMBER},
    {"--voxel", "options.check.voxel", FM_JOB_FLAG_NUMBER},
    {"--rapid-rate", "options.rapid_rate", FM_JOB_FLAG_NUMBER},
    {"--dialect", "options.dialect", FM_JOB_FLAG_TEXT},
    {"--subroutine-path", "options.subroutine_path", FM_JOB_FLAG_TEXT},
    {"--calculator-input", "options.calculator_input", FM_JOB_FLAG_SWITCH},
    {"--initial-tool", "options.initial_tool", FM_JOB_FLAG_INTEGER},
    {NULL, NULL, 0}};

int fm_cmd_check(int argc, char **argv)
{
    const char *report_path = NULL;
    fm_job_flags flags = {.command = "frepmill check", .table = CHECK_FLAGS};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        }
        int taken = fm_job_flags_take(&flags, argc, argv, &i);
        if (taken < 0) return 2;
        if (taken) continue;
        if (!strcmp(a, "--report") && i + 1 < argc) {
            report_path = argv[++i];
        } else if (!strcmp(a, "--report")) {
            fprintf(stderr, "frepmill check: %s needs a value\n", a);
            return 2;
        } else {
            fprintf(stderr, "frepmill check: unknown option %s\n", a);
            usage(stderr);
            return 2;
        }
    }
    const char *missing = !fm_job_flags_value(&flags, "PROGRAM") ? "no PROGRAM given"
                          : !fm_job_flags_value(&flags, "--stock") ? "no --stock given"
                          : !fm_job_flags_value(&flags, "--tools") &&
                                      !fm_job_flags_value(&flags, "--tools-from-program")
                                  ? "no --tools (nor --tools-from-program) given"
                                                                   : NULL;
    if (missing) {
        fprintf(stderr, "frepmill check: %s\n", missing);
        usage(stderr);
        return 2;
    }

    /* flags -> job document (the check on) -> the check's pass, as the
     * daemon's POST /v1/check runs it */
    fm_job_doc *doc = NULL;
    int status = fm_job_flags_document(&flags, json_pack("{s:{s:{}}}", "options", "check"), &doc);
    if (status) return status;
    fm_check_pass_input in;
    fm_check_pass_input_default(&in);
    in.spec = doc->spec;
    in.spec.check = NULL;
    in.check = doc->check;
    fm_error err;
    fm_error_clear(&err);
    char buf[1024];
    check_run run = {0};
    fm_job_result result;
    fm_status st = fm_check_pass_run(&in, &run.check, &result, &err);
    if (st != FM_OK) {
        fprintf(stderr, "frepmill check: %s\n", fm_error_format(&err, buf, sizeof buf));
        fm_job_doc_free(doc);
        return fm_job_flags_exit_status(st);
    }
    summary(run.check, &result, fm_job_flags_value(&flags, "PROGRAM"));

    status = fm_check_count(run.check) ? 1 : 0;
    json_t *report = fm_findings_json(run.check);
    int rc;
    if (report_path && strcmp(report_path, "-")) {
        rc = json_dump_file(report, report_path, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    } else {
        rc = json_dumpf(report, stdout, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
        fputc('\n', stdout);
    }
    json_decref(report);
    if (rc != 0) {
        fprintf(stderr, "frepmill check: cannot write the report %s: %s\n",
                report_path ? report_path : "(stdout)", strerror(errno));
        status = 4;
    }
    fm_check_free(run.check);
    fm_job_doc_free(doc);
    return status;
}
