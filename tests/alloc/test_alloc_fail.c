/* test_alloc_fail.c: every parser and the stock builder when memory runs
 * out, in the manner of SQLite's malloc tests (tests/support/alloc_fail.h):
 * for each case, the Nth allocation fails for N = 1, 2, ... until a run
 * needs no more than N - 1. Each failed call must return a clean error (a
 * status and a message; or, if it tolerates the failure, the same result),
 * leave no block allocated, and the next call must work and give the same
 * result as the first. Cases: G-code, HyperFun (compiled and evaluated),
 * trajectories, JSON and .tbl tool tables, the job JSON, a multipart
 * upload into a job, the daemon's config file, STL, stocks from a box, a
 * cylinder, a HyperFun model and a snapshot, and
 * whole jobs: one cut with the collision check (sweep, cut, check), one
 * compared with a design. Each case must have had allocations failed, and
 * some of them must have ended in an error (else the injection did not
 * happen, and the case tested nothing: so the check's machine file is not
 * a case, since its reader allocates nothing but in jansson's file reader,
 * which is not failed). The harness and what it does
 * not fail (third-party code that cannot survive a failure) are described
 * in tests/support/alloc_fail.c and tests/README.md. Usage: test_alloc_fail [CASE]
 * (run from tests/). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check/check.h"
#include "frep/frep.h"
#include "hf/hf.h"
#include "protocols/http/http_server.h"
#include "job.h"
#include "runner/job_doc.h"
#include "server/config.h"
#include "runner/findings_json.h"
#include "stock/stock.h"
#include "support/alloc_fail.h"
#include "test.h"
#include "toolpaths/gcode/gcode.h"
#include "toolpaths/tooltable/tooltable.h"
#include "toolpaths/traj/traj.h"

/* One call of the code under test. Returns 0 with *summary (a number that
 * changes with the result) on success, non-zero with msg filled on error;
 * either way it frees what it allocated. */
typedef int (*case_fn)(double *summary, char *msg, size_t msg_size);

typedef struct alloc_case {
    const char *name;
    case_fn run;
    /* 0: every allocation fails in turn. Else at most about this many
     * runs: every k-th allocation fails, k = the run's allocations / runs
     * (a whole job makes tens of thousands, and each failed run costs a
     * whole run). */
    long max_runs;
} alloc_case;

static char *slurp(const char *path, size_t *len)
{
    char *text;
    fm_error err;
    if (fm_file_read(path, NULL, (size_t)64 << 20, &text, len, &err) != FM_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    return text;
}

static int fail_with(const fm_error *err, char *msg, size_t msg_size)
{
    fm_error_format(err, msg, msg_size);
    return 1;
}

/* ------------------------------------------------------------ programs -- */

/* G-code: programs that between them use o-word subroutines and loops,
 * expressions and parameters, canned cycles, arcs in every plane, offsets
 * and tool length compensation. */
static const char *const gcode_files[] = {"gcode/programs/oword.ngc", "gcode/programs/expr.ngc",
                                          "gcode/programs/cycles_abs.ngc", "gcode/programs/arcs_planes.ngc",
                                          "gcode/programs/offsets.ngc", "gcode/programs/tlo.ngc"};
#define GCODE_FILES (sizeof gcode_files / sizeof gcode_files[0])
static char *gcode_text[GCODE_FILES], *traj_text;
static size_t gcode_len[GCODE_FILES], traj_len;

static int motion_sum(void *user, const fm_motion *m)
{
    double *sum = user;
    *sum += 1 + m->end[0] + 3 * m->end[1] + 7 * m->end[2] + 11 * m->t1;
    if (m->kind == FM_MOTION_PARAM) {
        /* The trajectory's path evaluates lazily: make it allocate. */
        double pos[3], axis[3];
        m->path->pose(m->path->ctx, 0.5 * (m->t0 + m->t1), pos, axis);
        *sum += pos[0] + axis[0];
    }
    return 0;
}

static int run_gcode(double *summary, char *msg, size_t msg_size)
{
    fm_error err;
    *summary = 0;
    for (size_t i = 0; i < GCODE_FILES; i++)
        if (fm_gcode_run_string(gcode_text[i], gcode_len[i], gcode_files[i], NULL, motion_sum, summary, NULL, &err))
            return fail_with(&err, msg, msg_size);
    return 0;
}

static int run_traj(double *summary, char *msg, size_t msg_size)
{
    fm_error err;
    *summary = 0;
    if (fm_traj_run_string(traj_text, traj_len, "helix_tilt.json", NULL, motion_sum, summary, NULL, &err))
        return fail_with(&err, msg, msg_size);
    return 0;
}

static char *hf_text;
static size_t hf_len;

static int run_hf(double *summary, char *msg, size_t msg_size)
{
    fm_error err;
    fm_graph *g = fm_graph_new(0);
    if (!g) {
        snprintf(msg, msg_size, "fm_graph_new: out of memory");
        return 1;
    }
    fm_hf_model model;
    fm_tape *tape = NULL;
    fm_evaluator *ev = NULL;
    int rc = 0;
    if (fm_hf_compile_string(g, hf_text, hf_len, "cast_stock.hf", NULL, NULL, &model, &err) ||
        !(tape = fm_tape_compile(g, model.root, &err)) || !(ev = fm_evaluator_new(tape, &err))) {
        rc = fail_with(&err, msg, msg_size);
    } else {
        const double p[4] = {10, 20, 5, 0};
        *summary = fm_eval_point(ev, p);
    }
    fm_evaluator_free(ev);
    fm_tape_free(tape);
    fm_graph_free(g);
    return rc;
}

/* ---------------------------------------------------------- tool tables -- */

static char *json_tools, *tbl_tools;
static size_t json_tools_len, tbl_tools_len;

static double table_sum(const fm_tool_table *t)
{
    double s = (double)t->count;
    for (size_t i = 0; i < t->count; i++) s += t->tools[i].number * 13 + t->tools[i].diameter;
    return s;
}

static int run_tools_json(double *summary, char *msg, size_t msg_size)
{
    fm_tool_table t;
    fm_error err;
    if (fm_tooltable_parse_json(json_tools, json_tools_len, "tools.json", &t, &err))
        return fail_with(&err, msg, msg_size);
    *summary = table_sum(&t);
    fm_tool_table_free(&t);
    return 0;
}

static int run_tools_tbl(double *summary, char *msg, size_t msg_size)
{
    fm_tool_table t;
    fm_error err;
    if (fm_tooltable_parse_tbl(tbl_tools, tbl_tools_len, "tools.tbl", &t, &err))
        return fail_with(&err, msg, msg_size);
    *summary = table_sum(&t);
    fm_tool_table_free(&t);
    return 0;
}

/* ----------------------------------------------------- job JSON, config -- */

static char *job_text;

static int run_job_json(double *summary, char *msg, size_t msg_size)
{
    fm_error err;
    fm_job_doc_rules rules;
    memset(&rules, 0, sizeof rules);
    fm_job_doc *doc = NULL;
    if (fm_job_doc_parse(job_text, strlen(job_text), &rules, &doc, &err) != FM_OK)
        return fail_with(&err, msg, msg_size);
    /* The canonical form's size (json_dumpb allocates: not part of the
     * call, so measured with the failures paused). */
    alloc_fail_pause();
    *summary = (double)json_dumpb(doc->json, NULL, 0, JSON_COMPACT | JSON_SORT_KEYS) +
               1000.0 * json_object_size(doc->json) + (double)doc->program_length;
    alloc_fail_resume();
    fm_job_doc_free(doc);
    return 0;
}

static int run_config(double *summary, char *msg, size_t msg_size)
{
    fm_daemon_config cfg;
    fm_daemon_config_default(&cfg);
    if (fm_daemon_config_load(&cfg, "../deploy/frepmilld.conf", msg, msg_size) != 0) return 1;
    *summary = cfg.workers + 7.0 * cfg.max_jobs + cfg.snapshot_interval_s + (double)strlen(cfg.state_dir);
    return 0;
}

/* A multipart upload (the daemon's POST /v1/jobs with files) into the job
 * document: the parts split, the job assembled from them, then validated. */
static char *multipart_body;
static size_t multipart_len;
static const char multipart_type[] = "multipart/form-data; boundary=alloc-fail-boundary";

static int run_multipart(double *summary, char *msg, size_t msg_size)
{
    fm_http_part parts[FM_HTTP_MAX_PARTS];
    fm_http_error herr;
    int n = fm_http_multipart_parse(multipart_type, multipart_body, multipart_len, parts, FM_HTTP_MAX_PARTS,
                                    &herr);
    json_t *job = n < 0 ? NULL : fm_http_job_from_multipart(parts, n, &herr);
    if (!job) {
        snprintf(msg, msg_size, "%d %s: %s", herr.status, herr.code, herr.message);
        return 1;
    }
    fm_error err;
    fm_job_doc *doc = NULL;
    fm_status st = fm_job_doc_from_json(job, NULL, &doc, &err);
    json_decref(job);
    if (st != FM_OK) return fail_with(&err, msg, msg_size);
    alloc_fail_pause();
    *summary = (double)json_dumpb(doc->json, NULL, 0, JSON_COMPACT | JSON_SORT_KEYS) +
               1000.0 * json_object_size(doc->json) + (double)doc->program_length + 1e6 * n;
    alloc_fail_resume();
    fm_job_doc_free(doc);
    return 0;
}

/* ---------------------------------------------------------------- stocks -- */

static char stl_path[256], vdb_path[256];

static fm_stock_options stock_options(void)
{
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = 0.5;
    o.threads = 1; /* the allocations of one thread, in a repeatable order */
    return o;
}

static int stock_result(fm_stock *s, const fm_error *err, double *summary, char *msg, size_t msg_size)
{
    if (!s) return fail_with(err, msg, msg_size);
    /* The volume is the measure of the result, not part of the call: it
     * has no error return (fm_stock_volume gives 0 when it cannot
     * allocate), so it is taken with the failures paused. */
    alloc_fail_pause();
    *summary = fm_stock_volume(s);
    alloc_fail_resume();
    fm_stock_free(s);
    return 0;
}

static int run_box(double *summary, char *msg, size_t msg_size)
{
    fm_stock_options o = stock_options();
    const double lo[3] = {0, 0, -6}, hi[3] = {10, 8, 0};
    fm_error err;
    return stock_result(fm_stock_new_box(lo, hi, &o, &err), &err, summary, msg, msg_size);
}

static int run_cylinder(double *summary, char *msg, size_t msg_size)
{
    fm_stock_options o = stock_options();
    fm_error err;
    return stock_result(fm_stock_new_cylinder(0, 0, -5, 0, 4, &o, &err), &err, summary, msg, msg_size);
}

static char hf_stock_path[256];

static int run_hf_stock(double *summary, char *msg, size_t msg_size)
{
    fm_stock_options o = stock_options();
    fm_error err;
    return stock_result(fm_job_make_stock(hf_stock_path, &o, &err), &err, summary, msg, msg_size);
}

static int run_stl(double *summary, char *msg, size_t msg_size)
{
    fm_stock_options o = stock_options();
    fm_error err;
    return stock_result(fm_stock_new_from_stl(stl_path, &o, &err), &err, summary, msg, msg_size);
}

static int run_vdb(double *summary, char *msg, size_t msg_size)
{
    fm_stock_options o = stock_options();
    fm_error err;
    return stock_result(fm_stock_load_vdb(vdb_path, &o, &err), &err, summary, msg, msg_size);
}

/* ------------------------------------------- jobs: check, cut, design -- */

/* A 6 mm flat end mill, a holder above its 10 mm of shank. */
static fm_tool_spec job_tool;
static fm_tool_table job_tools = {1, &job_tool};
static char fixture_path[256];

/* A whole job through the runner, single-threaded: the program's motions
 * swept and cut (lib/sweep, lib/stock), and with check the collision check
 * in the same pass (lib/check: a HyperFun clamp in the tool's way), with
 * design the comparison with the octahedron (building the design, the
 * deviation regions, the blame of each gouge). */
static int run_job(const char *program, const char *stock, int check, int design, double *summary, char *msg,
                   size_t msg_size)
{
    fm_job_check chk;
    fm_job_check_default(&chk);
    chk.fixtures[0] = fixture_path;
    chk.fixture_count = 1;
    chk.voxel_mm = 0.5;
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "alloc.ngc";
    spec.stock_spec = stock;
    spec.tools = &job_tools;
    spec.stock = stock_options();
    if (check) {
        spec.check = &chk;
        spec.stock.band_voxels = fm_check_band_voxels(&chk.options, spec.stock.voxel_mm);
    }
    if (design) spec.design_path = stl_path;
    fm_job_result res;
    fm_error err;
    if (fm_job_run(&spec, NULL, &res, &err) != FM_OK) return fail_with(&err, msg, msg_size);
    *summary = res.removed_volume_mm3 + 3.0 * res.motions;
    if (res.check) {
        for (size_t i = 0; i < fm_check_count(res.check); i++) {
            const fm_check_finding *f = fm_check_get(res.check, i);
            *summary += 1000.0 * (1 + f->kind) + 10 * f->line + f->penetration_mm;
        }
    }
    if (res.has_deviation) {
        *summary += 1e5 + res.deviation.max_gouge_mm + 7 * res.deviation.max_excess_mm +
                    res.deviation.gouge_volume_mm3 + 5.0 * res.deviation.gouge_total + 11.0 * res.deviation.excess_total;
        for (size_t i = 0; i < res.deviation.gouge_count; i++) *summary += 13.0 * res.gouge_blame[i].line;
    }
    fm_job_result_release(&res);
    return 0;
}

/* A slot through a 20 x 20 x 5 block past a 3 mm ball clamped on it. */
static const char check_program[] = "G21 G90 G17\nT1 M6\nG0 X-5 Y10 Z2\nG1 Z-1 F600\nG1 X25\nG0 Z10\nM30\n";

static int run_job_check(double *summary, char *msg, size_t msg_size)
{
    return run_job(check_program, "box:0,0,-5,20,20,0", 1, 0, summary, msg, msg_size);
}

/* A slot across the top of a block that holds the octahedron design. */
static const char design_program[] = "G21 G90 G17\nT1 M6\nG0 X-9 Y0 Z4\nG1 Z1 F600\nG1 X9\nG0 Z10\nM30\n";

static int run_job_design(double *summary, char *msg, size_t msg_size)
{
    return run_job(design_program, "box:-3.5,-3.5,-3.5,3.5,3.5,3.5", 0, 1, summary, msg, msg_size);
}

/* An octahedron |x| + |y| + |z| <= 3 as a binary STL (outward normals). */
static void write_octahedron(const char *path)
{
    FILE *f = fopen(path, "wb");
    char header[80] = "alloc_fail octahedron";
    fwrite(header, 1, 80, f);
    uint32_t n = 8;
    fwrite(&n, 4, 1, f);
    for (int k = 0; k < 8; k++) {
        float sx = k & 1 ? -1 : 1, sy = k & 2 ? -1 : 1, sz = k & 4 ? -1 : 1;
        float a[3] = {3 * sx, 0, 0}, b[3] = {0, 3 * sy, 0}, c[3] = {0, 0, 3 * sz};
        /* Counter-clockwise seen from outside: swap when the octant flips
         * an odd number of axes. */
        if (sx * sy * sz < 0) {
            float t[3];
            memcpy(t, b, sizeof t);
            memcpy(b, c, sizeof t);
            memcpy(c, t, sizeof t);
        }
        float normal[3] = {sx, sy, sz};
        uint16_t attr = 0;
        fwrite(normal, 4, 3, f);
        fwrite(a, 4, 3, f);
        fwrite(b, 4, 3, f);
        fwrite(c, 4, 3, f);
        fwrite(&attr, 2, 1, f);
    }
    fclose(f);
}

/* ------------------------------------------------------------ the loop -- */

static void exercise(const alloc_case *c)
{
    char msg[1024];
    double want = 0, got = 0;
    /* Twice unarmed: the second run shows that the code keeps nothing
     * between calls, and first-use caches (OpenVDB's type registry, TBB's
     * arena) exist before the counting starts. */
    for (int warm = 0; warm < 2; warm++) {
        msg[0] = 0;
        if (c->run(&want, msg, sizeof msg) != 0) {
            fprintf(stderr, "%s: fails without any injected failure: %s\n", c->name, msg);
            CHECK(0);
            return;
        }
    }
    long stride = 1, total = 0;
    if (c->max_runs) {
        alloc_fail_arm(0);
        c->run(&got, msg, sizeof msg);
        total = alloc_fail_disarm();
        stride = total / c->max_runs > 1 ? total / c->max_runs : 1;
    }
    long n = 1, failed = 0, errors = 0, tolerated = 0, leaks = 0;
    for (;; n += stride) {
        long before = alloc_fail_live();
        msg[0] = 0;
        alloc_fail_arm(n);
        int rc = c->run(&got, msg, sizeof msg);
        alloc_fail_disarm();
        int hit = alloc_fail_hit();
        long after = alloc_fail_live();
        if (!hit) {
            /* This run needed fewer than n allocations: every one has
             * failed in turn. (A whole job's count on this thread varies
             * a little from run to run, as its worker threads share the
             * work out: it goes on to the count it had unarmed.) */
            CHECK(rc == 0 && got == want);
            CHECK(after == before);
            if (stride == 1 || n > total) break;
            continue;
        }
        failed++;
        /* Allocations the harness does not fail were skipped: go on after
         * the one that failed. */
        long at = alloc_fail_failed_at();
        if (at > n) n = at;
        if (rc == 0) {
            /* The failure was tolerated (a cache, a smaller buffer): the
             * result must be the same. */
            tolerated++;
            if (got != want) fprintf(stderr, "%s: allocation %ld failed, result %.17g instead of %.17g\n",
                                     c->name, n, got, want);
            CHECK(got == want);
        } else {
            errors++;
            if (getenv("ALLOC_FAIL_VERBOSE")) printf("  allocation %ld: %s\n", n, msg);
            if (!msg[0]) fprintf(stderr, "%s: allocation %ld failed, an error without a message\n", c->name, n);
            CHECK(msg[0] != 0);
        }
        if (after != before) {
            if (leaks++ < 5) {
                fprintf(stderr, "%s: allocation %ld failed (%s): %ld blocks left allocated\n", c->name, n,
                        rc ? msg : "tolerated", after - before);
                alloc_fail_report_leaks(stderr);
            }
            CHECK(after == before);
        }
        /* The next call works. */
        msg[0] = 0;
        rc = c->run(&got, msg, sizeof msg);
        if (rc) fprintf(stderr, "%s: after allocation %ld failed, the next call failed: %s\n", c->name, n, msg);
        CHECK(rc == 0 && got == want);
        CHECK(alloc_fail_live() == before);
    }
    printf("%-12s %6ld allocations, %6ld failed %s: %ld clean errors, %ld tolerated, %ld leaked\n", c->name,
           stride > 1 ? total : n - 1, failed, stride > 1 ? "(every k-th)" : "in turn", errors, tolerated, leaks);
    /* A case in which no allocation failed tested nothing: the allocator
     * was not replaced, or the code under test did not run. */
    if (failed == 0) fprintf(stderr, "%s: no allocation was failed (none injected)\n", c->name);
    CHECK(failed > 0);
    /* and one in which every failure was tolerated never reached an error path */
    if (errors == 0) fprintf(stderr, "%s: no injected failure gave an error\n", c->name);
    CHECK(errors > 0);
}

int main(int argc, char **argv)
{
    /* stdout's buffer is allocated at its first use: before any count. */
    printf("allocation failures, each allocation in turn\n");
    fflush(stdout);
    for (size_t i = 0; i < GCODE_FILES; i++) gcode_text[i] = slurp(gcode_files[i], &gcode_len[i]);
    traj_text = slurp("../examples/helix_tilt.json", &traj_len);
    hf_text = slurp("../examples/cast_stock.hf", &hf_len);
    json_tools = slurp("../deploy/demo/tools.json", &json_tools_len);
    tbl_tools = slurp("gcode/programs/tools.tbl", &tbl_tools_len);
    size_t n;
    char *demo = slurp("../deploy/demo/pocket.ngc", &n);
    json_t *job = json_pack("{s:s, s:f, s:o, s:{s:s}, s:{s:s, s:b}}", "stock", "box:0,0,-30,100,60,0",
                            "voxel", 0.25, "tools", json_loadb(json_tools, json_tools_len, 0, NULL),
                            "program", "gcode", demo, "options", "name", "alloc", "check", 1);
    job_text = json_dumps(job, JSON_INDENT(1));
    json_decref(job);
    free(demo);

    char dir[] = "/tmp/fm_alloc_fail_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    snprintf(stl_path, sizeof stl_path, "%s/octahedron.stl", dir);
    snprintf(vdb_path, sizeof vdb_path, "%s/box.vdb", dir);
    snprintf(hf_stock_path, sizeof hf_stock_path, "%s/ball.hf", dir);
    write_octahedron(stl_path);
    {
        /* A HyperFun stock small enough to be built a thousand times. */
        FILE *f = fopen(hf_stock_path, "w");
        fputs("ball(x[3], a[1]) { ball = 3 - sqrt(x[1]^2 + x[2]^2 + x[3]^2); }\n", f);
        fclose(f);
    }
    snprintf(fixture_path, sizeof fixture_path, "%s/clamp.hf", dir);
    {
        /* A ball of radius 3 at (12, 10, 1): in the slot's way. */
        FILE *f = fopen(fixture_path, "w");
        fputs("clamp(x[3], a[1]) { clamp = 9 - (x[1] - 12)^2 - (x[2] - 10)^2 - (x[3] - 1)^2; }\n", f);
        fclose(f);
    }
    memset(&job_tool, 0, sizeof job_tool);
    job_tool.number = 1;
    job_tool.shape = FM_TOOL_FLAT;
    job_tool.diameter = 6;
    job_tool.shank_diameter = 6;
    job_tool.flute_length = 15;
    job_tool.length = 25;
    job_tool.holder_count = 1;
    job_tool.holder[0] = (fm_holder_segment){20, 20, 30};
    {
        /* The job, its G-code and its tool table as three parts. */
        const char *job_part = "{\"stock\": \"box:0,0,-30,100,60,0\", \"voxel\": 0.25, \"options\": {\"check\": true}}";
        size_t prog_len;
        char *prog = slurp("gcode/programs/offsets.ngc", &prog_len);
        size_t cap = json_tools_len + prog_len + 4096;
        multipart_body = malloc(cap);
        int len = snprintf(multipart_body, cap,
                           "--alloc-fail-boundary\r\nContent-Disposition: form-data; name=\"job\"\r\n"
                           "Content-Type: application/json\r\n\r\n%s\r\n"
                           "--alloc-fail-boundary\r\nContent-Disposition: form-data; name=\"program\"; "
                           "filename=\"offsets.ngc\"\r\n\r\n%.*s\r\n"
                           "--alloc-fail-boundary\r\nContent-Disposition: form-data; name=\"tools\"; "
                           "filename=\"tools.json\"\r\nContent-Type: application/json\r\n\r\n%.*s\r\n"
                           "--alloc-fail-boundary--\r\n",
                           job_part, (int)prog_len, prog, (int)json_tools_len, json_tools);
        CHECK(len > 0 && (size_t)len < cap);
        multipart_len = (size_t)len;
        free(prog);
    }
    {
        fm_stock_options o = stock_options();
        const double lo[3] = {0, 0, -4}, hi[3] = {6, 5, 0};
        fm_error err;
        fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
        CHECK(s && fm_stock_save(s, vdb_path, "alloc", &err) == FM_OK);
        fm_stock_free(s);
    }

    static const alloc_case cases[] = {
        {"gcode", run_gcode, 0},
        {"hyperfun", run_hf, 0},
        {"traj", run_traj, 0},
        {"tools.json", run_tools_json, 0},
        {"tools.tbl", run_tools_tbl, 0},
        {"job.json", run_job_json, 0},
        {"multipart", run_multipart, 0},
        {"config", run_config, 0},
        {"stl", run_stl, 0},
        {"box", run_box, 0},
        {"cylinder", run_cylinder, 0},
        {"hf-stock", run_hf_stock, 0},
        {"vdb", run_vdb, 0},
        {"job-check", run_job_check, 150},
        {"job-design", run_job_design, 0},
    };
    int ran = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        if (argc > 1 && strcmp(argv[1], cases[i].name) != 0) continue;
        exercise(&cases[i]);
        fflush(stdout);
        ran++;
    }
    CHECK(ran > 0);

    unlink(stl_path);
    unlink(vdb_path);
    unlink(hf_stock_path);
    unlink(fixture_path);
    rmdir(dir);
    free(multipart_body);
    for (size_t i = 0; i < GCODE_FILES; i++) free(gcode_text[i]);
    free(traj_text);
    free(hf_text);
    free(json_tools);
    free(tbl_tools);
    free(job_text);
    return test_summary("alloc_fail");
}
