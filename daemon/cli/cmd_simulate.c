/* cmd_simulate.c: `frepmill simulate`: run a program against a stock with
 * the job runner (job.c), write the final stock and a JSON report, and
 * show a progress bar on a terminal. The job comes from flags, or from a
 * job document (--job FILE, daemon/runner/job_doc.h: what POST /v1/jobs
 * takes, read by the same parser). */
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"
#include "runner/job.h"
#include "job_flags.h"
#include "runner/job_doc.h"
#include "runner/report_json.h"
#include "runner/outputs.h"
#include "runner/check_pass.h"
#include "runner/findings_json.h"

#define SIMULATE_MAX_OUTPUTS 8

static void usage(FILE *out)
{
    fprintf(out,
            "usage: frepmill simulate PROGRAM --stock SPEC --tools TOOLS|--tools-from-program\n"
            "                         [--voxel MM]\n"
            "       frepmill simulate --job FILE.json\n"
            "                         [--out FILE]... [--report FILE.json] [--progress]\n"
            "                         [--band VOXELS] [--memory-budget MB] [--threads N]\n"
            "                         [--rapid-rate MM_PER_MIN] [--batch DIAMETERS]\n"
            "                         [--machine FILE.json [--pose-at SECONDS|end]]\n"
            "                         [--check [--fixture FILE]...]\n"
            "                         [--png FILE] [--png-size WxH]\n"
            "                         [--color depth|tool|deviation|none]\n"
            "                         [--design PART [--tolerance MM]] [--stop-at LINE]\n"
            "                         [--dialect linuxcnc|fanuc] [--subroutine-path DIRS]\n"
            "                         [--calculator-input] [--initial-tool N]\n"
            "\n"
            "PROGRAM   G-code, or a parametric trajectory (.json)\n"
            "--job     the job as a job document (docs/api.md, POST /v1/jobs; model files\n"
            "          relative to the working folder): stock, tools, program, fixtures,\n"
            "          machine, design and options, the check included unless options.check\n"
            "          is false; only output flags (--out, --png, --report, --color, --pose-at,\n"
            "          --progress) and --sweep-evaluations go with it\n"
            "SPEC      box:X0,Y0,Z0,X1,Y1,Z1 | cylinder:X,Y,Z0,Z1,R | FILE.hf | FILE.stl | FILE.vdb\n"
            "TOOLS     tool table: frepmill JSON, LinuxCNC .tbl, Fusion 360 .json or .tools,\n"
            "          FreeCAD .fctl or .fctb, CAMotics project or tool table (docs/tooltable.md)\n"
            "--tools-from-program  no table: the tools the program's comments name, as CAM\n"
            "          posts write them ((T1 D=6. CR=0. - FLAT END MILL)); guesses are warned\n"
            "--voxel   voxel edge in mm (default 0.1)\n"
            "--out     final stock; format by extension: %s (may be given several times)\n"
            "--report  JSON report (default: none; `-` for standard output)\n"
            "--machine the machine (docs/check.md): rotary axes that A B C words turn, TCP,\n"
            "          rapid rate (times the whole job), Fanuc reference points, limits for --check\n"
            "--pose-at the picture shows the workpiece in its machine position (the rotary\n"
            "          table axes turned) at this program time, or at the end; the report\n"
            "          gets its \"machine_pose\"\n"
            "--check   also run the collision check in the same pass (at the check's own\n"
            "          0.5 mm voxel, as `frepmill check`); the report gets its \"findings\"\n"
            "--png     a shaded isometric picture with the toolpath (same as --out FILE.png)\n"
            "--color   mesh and picture colours: depth below the stock top (default), the tool\n"
            "          that cut last, the deviation from the design (green within the tolerance,\n"
            "          red gouge, blue excess; the default with --design), or none\n"
            "--design  compare the result with the intended part (.stl, .hf or .vdb); the report\n"
            "          gets its \"design\": gouges (with the line that cut them) and excess\n"
            "--tolerance  deviations up to this many mm count as on the design (default half\n"
            "          a voxel)\n"
            "--stop-at  stop after the motions of source line LINE (an in-process stock)\n"
            "--dialect the G-code's dialect (default linuxcnc; docs/gcode.md)\n"
            "--subroutine-path  ':'-separated folders of subroutine files (NAME.ngc, Fanuc O1234.nc)\n"
            "--calculator-input Fanuc: X5 is 5 mm, not 0.005 (DPI / Haas setting 162)\n"
            "--initial-tool  the tool in the spindle before the first M6 (default: the\n"
            "          machine's initial_tool, else none; a one-tool table's tool cuts)\n"
            "--sweep-evaluations  the swept volumes' search budget per point (default 20000);\n"
            "          a smaller one provokes the budget warning (for tests)\n"

            "Warnings (feed motions into the stock with no tool in the spindle, the budget,\n"
            "thin walls) are printed and in the report; they leave the exit status 0\n"
            "(`frepmill check` is the gate: it exits 1 on findings).\n"
            "Exit status: 0 success, 2 bad input, 3 resource limit, 4 I/O error.\n",
            fm_output_formats());
}

typedef struct progress_bar {
    fm_toolpath *toolpath;
    fm_machine_pose *pose; /* --pose-at: tracked from the motions; else NULL */
    int enabled;
    int is_tty;
    double last_shown;
    int last_permille;
} progress_bar;

static int show_progress(void *user, const fm_job_progress *p)
{
    progress_bar *bar = user;
    if (!bar->enabled) return 0;
    double fraction = p->program_time_total > 0 ? p->program_time / p->program_time_total
                      : p->motions_total > 0   ? (double)p->motions_done / (double)p->motions_total
                                               : 1.0;
    if (fraction > 1) fraction = 1;
    int permille = (int)(fraction * 1000);
    /* Repaint at most ten times a second on a terminal, and on each whole
     * percent in a log. */
    if (bar->is_tty ? p->elapsed_s - bar->last_shown < 0.1 && permille < 1000
                    : permille / 10 == bar->last_permille / 10)
        return 0;
    bar->last_shown = p->elapsed_s;
    bar->last_permille = permille;
    double rate = p->elapsed_s > 0 ? (double)p->motions_done / p->elapsed_s : 0;
    /* the fraction is of program time: the controller's when the
     * machine's dynamics planned it, else feed-only (labelled) */
    double eta = fraction > 0.001 ? p->elapsed_s * (1 - fraction) / fraction : 0;
    const char *clock = p->time_planned ? "planned" : "feed-only";
    if (bar->is_tty) {
        char cells[31];
        int filled = (int)(fraction * 30);
        for (int i = 0; i < 30; i++) cells[i] = i < filled ? '#' : '.';
        cells[30] = '\0';
        fprintf(stderr, "\r[%s] %5.1f%%  line %d  %.0f motions/s  ETA %.0f s  %.1f/%.1f s %s ", cells,
                fraction * 100, p->line, rate, eta, p->program_time, p->program_time_total, clock);
    } else {
        fprintf(stderr, "progress %5.1f%%  line %d  %.0f motions/s  ETA %.0f s  %.1f/%.1f s %s\n",
                fraction * 100, p->line, rate, eta, p->program_time, p->program_time_total, clock);
    }
    fflush(stderr);
    return 0;
}

static void collect_motion(void *user, const fm_motion *motion)
{
    progress_bar *bar = user;
    if (bar->toolpath) fm_toolpath_add(bar->toolpath, motion);
    if (bar->pose) fm_machine_pose_track(bar->pose, motion);
}

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE && isfinite(*out);
}

/* "machine_pose": where the rotary table axes put the workpiece at the
 * chosen time (x_machine = rotation x_workpiece + translation). */
static json_t *pose_json(const fm_machine_pose *pose, const double rot[9], const double trans[3],
                         const fm_job_result *result)
{
    json_t *o = json_object();
    double end = result->times_planned ? result->cycle_time_s : result->program_time_s;
    double t = pose->time_s < end ? pose->time_s : end;
    json_object_set_new(o, "time_s", json_real(t));
    json_t *joints = json_object();
    for (int i = 0; pose->machine && i < pose->machine->rotary_count; i++) {
        int l = pose->machine->rotary[i].letter;
        char name[2] = {(char)('a' + l), '\0'};
        json_object_set_new(joints, name, json_real(pose->joints[l]));
    }
    json_object_set_new(o, "joints_deg", joints);
    json_t *r = json_array(), *tr = json_array();
    for (int i = 0; i < 9; i++) json_array_append_new(r, json_real(rot[i]));
    for (int i = 0; i < 3; i++) json_array_append_new(tr, json_real(trans[i]));
    json_object_set_new(o, "rotation", r);
    json_object_set_new(o, "translation", tr);
    return o;
}

/* --job: the document and the private folder its inline models are
 * written to (lib/stock and lib/check read models from files). */
typedef struct job_file {
    fm_job_doc *doc;
    char dir[PATH_MAX];
} job_file;

static fm_status load_job(const char *path, job_file *jf, fm_error *err)
{
    char *text;
    size_t len;
    fm_status st = fm_file_read(path, NULL, 2 * FM_JOB_DOC_MAX_TEXT, &text, &len, err);
    /* The CLI's documents may name files on this machine; live programs
     * are the daemon's. */
    const fm_job_doc_rules rules = {.allow_files = 1};
    if (st == FM_OK) st = fm_job_doc_parse(text, len, &rules, &jf->doc, err);
    free(text);
    if (st != FM_OK) {
        if (err && !err->file[0]) snprintf(err->file, sizeof err->file, "%s", path);
        return st;
    }
    return FM_OK;
}

/* The document's inline models into a private folder (none: no folder). */
static fm_status materialize(job_file *jf, fm_error *err)
{
    fm_job_doc *doc = jf->doc;
    int fixtures = 0;
    for (int i = 0; i < doc->check.fixture_count; i++) fixtures += doc->fixtures[i].size > 0;
    if (!doc->stock_model.size && !doc->design_model.size && !fixtures) return FM_OK;
    const char *tmp = getenv("TMPDIR");
    snprintf(jf->dir, sizeof jf->dir, "%.3000s/frepmill-job-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(jf->dir)) {
        jf->dir[0] = '\0';
        return fm_error_set(err, FM_ERR_IO, "cannot create a temporary folder: %s",
                            strerror(errno));
    }
    return fm_job_doc_materialize(doc, jf->dir, NULL, err);
}

static void job_file_free(job_file *jf)
{
    if (jf->dir[0]) {
        /* the models fm_job_doc_materialize wrote, then the folder */
        fm_job_doc *doc = jf->doc;
        const char *paths[FM_JOB_MAX_FIXTURES + 2] = {doc->stock_model.size ? doc->stock_text : NULL,
                                                      doc->design_model.size ? doc->design_text
                                                                             : NULL};
        for (int i = 0; i < doc->check.fixture_count; i++)
            if (doc->fixtures[i].size) paths[2 + i] = doc->fixture_paths[i]; /* not a user's file */
        for (int i = 0; i < FM_JOB_MAX_FIXTURES + 2; i++)
            if (paths[i]) unlink(paths[i]);
        rmdir(jf->dir);
    }
    fm_job_doc_free(jf->doc);
}

static int simulate(int argc, char **argv, job_file *jf);

int fm_cmd_simulate(int argc, char **argv)
{
    job_file *jf = calloc(1, sizeof *jf);
    if (!jf) {
        fprintf(stderr, "frepmill simulate: out of memory\n");
        return 3;
    }
    int status = simulate(argc, argv, jf);
    job_file_free(jf);
    free(jf);
    return status;
}

/* The job's flags and the document keys they set (job_flags.h): the
 * document's parser holds their ranges and defaults. */
static const fm_job_flag SIMULATE_FLAGS[] = {
    {"PROGRAM", "program.file", FM_JOB_FLAG_TEXT},
    {"--stock", "stock", FM_JOB_FLAG_TEXT},
    {"--tools", "tools", FM_JOB_FLAG_TEXT},
    {"--tools-from-program", "options.tools_from_program", FM_JOB_FLAG_SWITCH},
    {"--voxel", "voxel", FM_JOB_FLAG_NUMBER},
    {"--band", "options.band", FM_JOB_FLAG_INTEGER},
    {"--memory-budget", "options.memory_budget_mb", FM_JOB_FLAG_NUMBER},
    {"--threads", "options.threads", FM_JOB_FLAG_INTEGER},
    {"--rapid-rate", "options.rapid_rate", FM_JOB_FLAG_NUMBER},
    {"--batch", "options.batch", FM_JOB_FLAG_NUMBER},
    {"--machine", "machine", FM_JOB_FLAG_TEXT},
    {"--check", "options.check", FM_JOB_FLAG_SWITCH},
    {"--fixture", "fixtures", FM_JOB_FLAG_FIXTURE},
    {"--design", "design", FM_JOB_FLAG_TEXT},
    {"--tolerance", "options.tolerance", FM_JOB_FLAG_NUMBER},
    {"--stop-at", "options.stop_at", FM_JOB_FLAG_INTEGER},
    {"--dialect", "options.dialect", FM_JOB_FLAG_TEXT},
    {"--subroutine-path", "options.subroutine_path", FM_JOB_FLAG_TEXT},
    {"--calculator-input", "options.calculator_input", FM_JOB_FLAG_SWITCH},
    {"--initial-tool", "options.initial_tool", FM_JOB_FLAG_INTEGER},
    /* the one job flag that goes with --job too (a test's knob) */
    {"--sweep-evaluations", "options.sweep_evaluations", FM_JOB_FLAG_INTEGER},
    {NULL, NULL, 0}};

static int simulate(int argc, char **argv, job_file *jf)
{
    const char *outputs[SIMULATE_MAX_OUTPUTS];
    int output_count = 0;
    const char *report_path = NULL;
    int force_progress = 0;
    fm_output_options out_opt;
    fm_output_options_default(&out_opt);
    int want_png = 0;
    int color_given = 0;
    double pose_time = NAN; /* --pose-at; NAN: none */
    const char *job_path = NULL;
    fm_job_flags flags = {.command = "frepmill simulate", .table = SIMULATE_FLAGS};

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        double d;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--progress")) {
            force_progress = 1;
            continue;
        }
        int taken = fm_job_flags_take(&flags, argc, argv, &i);
        if (taken < 0) return 2;
        if (taken) continue;
        /* the output flags: what is written, not what is run */
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v) {
            fprintf(stderr, "frepmill simulate: %s needs a value\n", a);
            return 2;
        }
        i++;
        int is_png = !strcmp(a, "--png");
        if (is_png || !strcmp(a, "--out")) {
            if (output_count == SIMULATE_MAX_OUTPUTS) {
                fprintf(stderr, "frepmill simulate: at most %d output files\n", SIMULATE_MAX_OUTPUTS);
                return 2;
            }
            size_t n = strlen(v);
            if (is_png ? n < 5 || strcmp(v + n - 4, ".png") : !fm_output_format_known(v)) {
                fprintf(stderr, "frepmill simulate: %s %s: unknown format (use %s)\n", a, v,
                        is_png ? ".png" : fm_output_formats());
                return 2;
            }
            if (n >= 4 && !strcmp(v + n - 4, ".png")) want_png = 1;
            outputs[output_count++] = v;
        } else if (!strcmp(a, "--png-size")) {
            int w, h;
            char tail;
            if (sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 ||
                h > 8192) {
                fprintf(stderr, "frepmill simulate: --png-size %s: expected WxH, 16..8192\n", v);
                return 2;
            }
            out_opt.png_width = w;
            out_opt.png_height = h;
        } else if (!strcmp(a, "--color")) {
            color_given = 1;
            if (!strcmp(v, "depth")) out_opt.coloring = FM_MESH_COLOR_DEPTH;
            else if (!strcmp(v, "tool")) out_opt.coloring = FM_MESH_COLOR_TOOL;
            else if (!strcmp(v, "deviation")) out_opt.coloring = FM_MESH_COLOR_DEVIATION;
            else if (!strcmp(v, "none")) out_opt.coloring = FM_MESH_COLOR_NONE;
            else {
                fprintf(stderr,
                        "frepmill simulate: --color %s: expected depth, tool, deviation or none\n",
                        v);
                return 2;
            }
        } else if (!strcmp(a, "--job")) {
            job_path = v;
        } else if (!strcmp(a, "--report")) {
            report_path = v;
        } else if (!strcmp(a, "--pose-at")) {
            if (!strcmp(v, "end")) pose_time = INFINITY;
            else if (parse_double(v, &d) && d >= 0) pose_time = d;
            else {
                fprintf(stderr, "frepmill simulate: --pose-at %s: expected seconds of program time "
                                "(>= 0) or end\n", v);
                return 2;
            }
        } else {
            fprintf(stderr, "frepmill simulate: unknown option %s\n", a);
            usage(stderr);
            return 2;
        }
    }

    /* The job document: the job file's, or the flags' (the check off unless
     * --check), through the one parser of job documents. */
    json_t *base;
    if (job_path) {
        for (int i = flags.count - 1; i >= 0; i--)
            if (strcmp(flags.given[i]->flag, "--sweep-evaluations")) {
                fprintf(stderr, "frepmill simulate: %s: the job file gives it (with --job only "
                                "output flags and --sweep-evaluations)\n", flags.given[i]->flag);
                return 2;
            }
        fm_error jerr;
        fm_error_clear(&jerr);
        fm_status st = load_job(job_path, jf, &jerr);
        if (st != FM_OK) {
            char buf[1024];
            fprintf(stderr, "frepmill simulate: %s\n", fm_error_format(&jerr, buf, sizeof buf));
            return fm_job_flags_exit_status(st);
        }
        base = json_incref(jf->doc->json);
    } else {
        const char *missing = !fm_job_flags_value(&flags, "PROGRAM") ? "no PROGRAM given"
                              : !fm_job_flags_value(&flags, "--stock") ? "no --stock given"
                              : !fm_job_flags_value(&flags, "--tools") &&
                                      !fm_job_flags_value(&flags, "--tools-from-program")
                                  ? "no --tools (nor --tools-from-program) given"
                                                                       : NULL;
        if (missing) {
            fprintf(stderr, "frepmill simulate: %s\n", missing);
            usage(stderr);
            return 2;
        }
        base = json_pack("{s:{s:b}}", "options", "check", 0);
    }
    if (fm_job_flags_value(&flags, "--tolerance") && !fm_job_flags_value(&flags, "--design")) {
        fprintf(stderr, "frepmill simulate: --tolerance needs --design\n");
        json_decref(base);
        return 2;
    }
    if (fm_job_flags_value(&flags, "--fixture") && !fm_job_flags_value(&flags, "--check")) {
        fprintf(stderr, "frepmill simulate: --fixture needs --check\n");
        json_decref(base);
        return 2;
    }
    if (!job_path || flags.count) {
        /* the flags on the document (with --job: --sweep-evaluations on the
         * file's), read again by the same parser */
        fm_job_doc *doc = NULL;
        int status = fm_job_flags_document(&flags, base, &doc);
        if (status) return status;
        fm_job_doc_free(jf->doc);
        jf->doc = doc;
    } else {
        json_decref(base);
    }
    fm_error merr;
    fm_error_clear(&merr);
    if (materialize(jf, &merr) != FM_OK) {
        char buf[1024];
        fprintf(stderr, "frepmill simulate: %s\n", fm_error_format(&merr, buf, sizeof buf));
        return fm_job_flags_exit_status(merr.code);
    }
    fm_job_spec spec = jf->doc->spec;
    if (jf->doc->memory_budget_mb > 0)
        spec.stock.memory_budget = (size_t)(jf->doc->memory_budget_mb * 1048576.0);

    if (out_opt.coloring == FM_MESH_COLOR_DEVIATION && !spec.design_path) {
        fprintf(stderr, "frepmill simulate: --color deviation needs --design\n");
        return 2;
    }
    /* with a design the pictures show the deviation unless told otherwise */
    if (spec.design_path && !color_given) out_opt.coloring = FM_MESH_COLOR_DEVIATION;
    if (!isnan(pose_time) && !jf->doc->has_machine) {
        fprintf(stderr, "frepmill simulate: --pose-at needs --machine (the rotary axes that turn "
                        "the workpiece)\n");
        return 2;
    }

    progress_bar bar = {0};
    bar.is_tty = isatty(STDERR_FILENO);
    bar.enabled = bar.is_tty || force_progress;
    bar.last_permille = -10;
    if (want_png && !(bar.toolpath = fm_toolpath_new(0))) {
        fprintf(stderr, "frepmill simulate: out of memory\n");
        return 3;
    }
    fm_machine_pose pose = {.machine = spec.machine, .time_s = pose_time};
    if (!isnan(pose_time)) bar.pose = &pose;
    fm_job_hooks hooks = {.user = &bar, .progress = show_progress};
    if (bar.toolpath || bar.pose) hooks.on_motion = collect_motion;

    fm_job_result result;
    fm_error err;
    fm_error_clear(&err);
    fm_status st = fm_job_run(&spec, &hooks, &result, &err);
    if (bar.enabled && bar.is_tty) fputc('\n', stderr);
    if (st != FM_OK) {
        char buf[1024];
        fprintf(stderr, "frepmill simulate: %s\n", fm_error_format(&err, buf, sizeof buf));
        fm_toolpath_free(bar.toolpath);
        return fm_job_flags_exit_status(st);
    }

    int status = 0;
    out_opt.top_z = result.initial_hi[2];
    out_opt.toolpath = bar.toolpath;
    out_opt.design = result.design;
    double pose_rot[9], pose_trans[3];
    if (bar.pose) {
        fm_machine_pose_transform(bar.pose, pose_rot, pose_trans);
        out_opt.rotation = pose_rot;
    }
    st = fm_outputs_write(outputs, (size_t)output_count, result.stock, &out_opt, &err);
    if (st != FM_OK) {
        char buf[1024];
        fprintf(stderr, "frepmill simulate: %s\n", fm_error_format(&err, buf, sizeof buf));
        status = fm_job_flags_exit_status(st);
    }
    if (fm_toolpath_truncated(bar.toolpath))
        fprintf(stderr, "frepmill simulate: the picture shows only the start of the toolpath "
                        "(too many points)\n");

    char times[128];
    if (result.cycle_time_planned)
        snprintf(times, sizeof times, "%.1f s of program time as planned (feed-only %.1f s)",
                 result.cycle_time_s, result.program_time_s);
    else
        snprintf(times, sizeof times, "%.1f s of program time (feed-only)", result.program_time_s);
    fprintf(stderr,
            "frepmill simulate: %ld motions, %s; removed %.1f mm3 of %.1f mm3 "
            "in %.2f s, peak memory %.0f MB\n",
            result.motions, times, result.removed_volume_mm3,
            result.initial_volume_mm3, result.wall_time_s,
            (double)result.peak_memory_bytes / (1024.0 * 1024.0));
    if (result.check)
        fprintf(stderr, "frepmill simulate: check: %zu errors, %zu warnings (%.2f s)\n",
                fm_check_count_severity(result.check, FM_CHECK_ERROR),
                fm_check_count_severity(result.check, FM_CHECK_WARNING), result.check_time_s);
    if (result.voxels_uncertain > 0) {
        char where[32] = "";
        if (result.uncertain_line > 0)
            snprintf(where, sizeof where, " (first at line %d)", result.uncertain_line);
        fprintf(stderr,
                "frepmill simulate: warning: %zu voxels may be under-cut by up to %.4f mm%s: the "
                "swept volume's search ran out of its budget there\n",
                result.voxels_uncertain, result.uncertain_max_mm, where);
    }
    if (result.no_tool_motions > 0) {
        const char *name = spec.program_path ? spec.program_path
                           : spec.program_name ? spec.program_name
                                               : "program";
        fprintf(stderr,
                "frepmill simulate: warning: %s:%d: a feed motion with no tool in the spindle goes "
                "into the stock (%ld such motions): nothing is cut there, where the machine would "
                "drive its spindle's nose (T selects a tool, M6 loads it); give the tool in the "
                "spindle at the start with --initial-tool N (the job's options.initial_tool, the "
                "machine file's initial_tool) or load it with M6\n",
                name, result.no_tool_line, result.no_tool_motions);
    }
    if (result.stopped_at_line)
        fprintf(stderr, "frepmill simulate: stopped after line %d\n", result.stopped_at_line);
    if (result.has_thin && result.thin.walls) {
        const fm_stock_thin_region *g = &result.thin.region[0]; /* walls come first */
        fprintf(stderr,
                "frepmill simulate: warning: %zu%s wall%s thinner than a voxel, the largest at "
                "(%.2f, %.2f, %.2f) (%zu voxels beside it): the volume counts %s, the mesh and "
                "pictures do not show %s; a smaller --voxel would\n",
                result.thin.walls, result.thin.truncated ? "+" : "", result.thin.walls == 1 ? "" : "s",
                g->position[0], g->position[1], g->position[2], g->voxels,
                result.thin.walls == 1 ? "it" : "them", result.thin.walls == 1 ? "it" : "them");
    }
    if (result.has_deviation) {
        const fm_deviation *dv = &result.deviation;
        fprintf(stderr,
                "frepmill simulate: design: %zu gouges (deepest %.3f mm, %.2f mm3), %zu excess "
                "regions (thickest %.3f mm, %.2f mm3) beyond %.3f mm; compared in %.2f s\n",
                dv->gouge_total, dv->max_gouge_mm, dv->gouge_volume_mm3, dv->excess_total,
                dv->max_excess_mm, dv->excess_volume_mm3, dv->tolerance_mm, result.design_wall_s);
        for (size_t i = 0; i < dv->gouge_count && i < 5; i++) {
            const fm_deviation_region *g = &dv->gouges[i];
            if (result.gouge_blame[i].line > 0)
                fprintf(stderr, "  gouge %.3f mm at (%.2f, %.2f, %.2f): line %d, tool %d\n",
                        g->depth_mm, g->position[0], g->position[1], g->position[2],
                        result.gouge_blame[i].line, result.gouge_blame[i].tool);
            else
                fprintf(stderr, "  gouge %.3f mm at (%.2f, %.2f, %.2f): no motion of this "
                                "program reaches it\n",
                        g->depth_mm, g->position[0], g->position[1], g->position[2]);
        }
    }

    if (report_path && status == 0) {
        json_t *report = fm_job_report_json(&result);
        if (bar.pose) json_object_set_new(report, "machine_pose", pose_json(bar.pose, pose_rot, pose_trans, &result));
        int rc = !strcmp(report_path, "-")
                     ? json_dumpf(report, stdout, JSON_INDENT(2) | JSON_REAL_PRECISION(10))
                     : json_dump_file(report, report_path, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
        if (!strcmp(report_path, "-")) fputc('\n', stdout);
        json_decref(report);
        if (rc != 0) {
            fprintf(stderr, "frepmill simulate: cannot write the report %s: %s\n", report_path,
                    strerror(errno));
            status = 4;
        }
    }
    fm_job_result_release(&result);
    fm_toolpath_free(bar.toolpath);
    return status;
}
