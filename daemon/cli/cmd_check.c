/* cmd_check.c: `frepmill check`: simulate a program at the check's coarse
 * voxel size with the job runner and relate every motion to the stock, the
 * fixtures and the machine (lib/check) before the real machine cuts.
 * Findings go to standard output (or --report) as JSON, a summary to
 * standard error; the exit status says clean (0), findings (1), bad input
 * (2), resource limit (3), I/O (4). */
#include <ctype.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "runner/check_pass.h"
#include "commands.h"
#include "toolpaths/gcode/gcode.h"
#include "runner/findings_json.h"
#include "runner/job.h"

#define CHECK_MAX_FIXTURES 32
#define CHECK_DEFAULT_VOXEL FM_CHECK_PASS_VOXEL

static void usage(FILE *out)
{
    fprintf(out,
            "usage: frepmill check PROGRAM --stock SPEC --tools TOOLS [--fixture FILE]...\n"
            "                      [--machine FILE.json] [--clearance MM] [--report FILE]\n"
            "                      [--voxel MM] [--tolerance MM] [--rapid-clearance MM]\n"
            "                      [--max-ramp DEG] [--rapid-rate MM_PER_MIN]\n"
            "                      [--dialect linuxcnc|fanuc] [--subroutine-path DIRS]\n"
            "                      [--calculator-input]\n"
            "\n"
            "PROGRAM      G-code, or a parametric trajectory (.json)\n"
            "SPEC         box:X0,Y0,Z0,X1,Y1,Z1 | cylinder:X,Y,Z0,Z1,R | FILE.hf | FILE.stl | FILE.vdb\n"
            "TOOLS        JSON tool table or LinuxCNC .tbl file\n"
            "--fixture    clamp, vise or table: HyperFun model (.hf) or closed STL mesh (.stl)\n"
            "--machine    travel limits, rapid rate, start position, rotary axes, head and\n"
            "             components (docs/check.md)\n"
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

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE && isfinite(*out);
}

typedef struct check_run {
    fm_check *check;
} check_run;

static int exit_status(fm_status st)
{
    switch (st) {
    case FM_OK: return 0;
    case FM_ERR_LIMIT: return 3;
    case FM_ERR_IO: return 4;
    case FM_ERR_INPUT: return 2;
    default: return 5;
    }
}

static void summary(const fm_check *check, const fm_job_result *res)
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
    }
}

int fm_cmd_check(int argc, char **argv)
{
    fm_check_pass_input in;
    fm_check_pass_input_default(&in);
    fm_job_spec spec = in.spec;
    spec.stock.voxel_mm = CHECK_DEFAULT_VOXEL;
    fm_check_options opt = in.check.options;
    const char *fixtures[CHECK_MAX_FIXTURES];
    int fixture_count = 0;
    const char *report_path = NULL, *machine_path = NULL;
    double rapid_rate = 0;

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (a[0] != '-' || !a[1]) {
            if (spec.program_path) {
                fprintf(stderr, "frepmill check: more than one program given ('%s' and '%s')\n",
                        spec.program_path, a);
                return 2;
            }
            spec.program_path = a;
            continue;
        } else if (!strcmp(a, "--calculator-input")) {
            spec.calculator_input = 1;
            continue;
        }
        if (!v) {
            fprintf(stderr, "frepmill check: %s needs a value\n", a);
            return 2;
        }
        i++;
        if (!strcmp(a, "--stock")) {
            spec.stock_spec = v;
        } else if (!strcmp(a, "--tools")) {
            spec.tools_path = v;
        } else if (!strcmp(a, "--fixture")) {
            if (fixture_count == CHECK_MAX_FIXTURES) {
                fprintf(stderr, "frepmill check: at most %d fixtures\n", CHECK_MAX_FIXTURES);
                return 2;
            }
            if (!fm_path_has_extension(v, ".hf") && !fm_path_has_extension(v, ".stl")) {
                fprintf(stderr, "frepmill check: --fixture %s: give a .hf model or an .stl mesh\n", v);
                return 2;
            }
            fixtures[fixture_count++] = v;
        } else if (!strcmp(a, "--machine")) {
            machine_path = v;
        } else if (!strcmp(a, "--report")) {
            report_path = v;
        } else if (!strcmp(a, "--dialect")) {
            fm_gcode_dialect dialect;
            if (!fm_gcode_dialect_parse(v, &dialect)) {
                fprintf(stderr, "frepmill check: --dialect %s: expected linuxcnc or fanuc\n", v);
                return 2;
            }
            spec.dialect = v;
        } else if (!strcmp(a, "--subroutine-path")) {
            spec.subroutine_path = v;
        } else if (!strcmp(a, "--clearance") && parse_double(v, &d) && d >= 0) {
            opt.clearance_mm[FM_CHECK_PART_SHANK] = d;
            opt.clearance_mm[FM_CHECK_PART_HOLDER] = d;
            opt.clearance_mm[FM_CHECK_PART_HEAD] = d;
        } else if (!strcmp(a, "--rapid-clearance") && parse_double(v, &d) && d >= 0) {
            opt.clearance_mm[FM_CHECK_PART_FLUTES] = d;
        } else if (!strcmp(a, "--tolerance") && parse_double(v, &d) && d > 0) {
            opt.tolerance_mm = d;
        } else if (!strcmp(a, "--max-ramp") && parse_double(v, &d) && d >= 0 && d <= 90) {
            opt.max_ramp_deg = d;
        } else if (!strcmp(a, "--voxel") && parse_double(v, &d) && d > 0) {
            spec.stock.voxel_mm = d;
        } else if (!strcmp(a, "--rapid-rate") && parse_double(v, &d) && d > 0) {
            rapid_rate = d;
        } else if (!strcmp(a, "--clearance") || !strcmp(a, "--rapid-clearance") ||
                   !strcmp(a, "--tolerance") || !strcmp(a, "--max-ramp") ||
                   !strcmp(a, "--voxel") || !strcmp(a, "--rapid-rate")) {
            fprintf(stderr, "frepmill check: %s %s: not a valid value\n", a, v);
            return 2;
        } else {
            fprintf(stderr, "frepmill check: unknown option %s\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!spec.program_path || !spec.stock_spec || !spec.tools_path) {
        fprintf(stderr, "frepmill check: %s\n",
                !spec.program_path ? "no PROGRAM given"
                : !spec.stock_spec ? "no --stock given"
                                   : "no --tools given");
        usage(stderr);
        return 2;
    }

    fm_error err;
    fm_error_clear(&err);
    char buf[1024];
    if (machine_path) {
        if (fm_check_machine_load(machine_path, &opt.machine, &err) != FM_OK) {
            fprintf(stderr, "frepmill check: %s\n", fm_error_format(&err, buf, sizeof buf));
            return 2;
        }
        if (opt.machine.rapid_rate > 0) spec.rapid_rate = opt.machine.rapid_rate;
        memcpy(spec.reference_points, opt.machine.reference_points, sizeof spec.reference_points);
        spec.machine = &opt.machine.chain; /* A B C words turn its rotary axes */
    }
    if (rapid_rate > 0) spec.rapid_rate = rapid_rate;

    in.spec = spec;
    in.check.voxel_mm = spec.stock.voxel_mm;
    in.check.options = opt;
    for (int i = 0; i < fixture_count; i++) in.check.fixtures[i] = fixtures[i];
    in.check.fixture_count = fixture_count;
    check_run run = {0};
    fm_job_result result;
    fm_status st = fm_check_pass_run(&in, &run.check, &result, &err);
    if (st != FM_OK) {
        fprintf(stderr, "frepmill check: %s\n", fm_error_format(&err, buf, sizeof buf));
        return exit_status(st);
    }
    summary(run.check, &result);

    int status = fm_check_count(run.check) ? 1 : 0;
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
    return status;
}
