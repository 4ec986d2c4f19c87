/* test_alloc_fail.c: every parser and the stock builder when memory runs
 * out, in the manner of SQLite's malloc tests (tests/support/alloc_fail.h):
 * for each case, the Nth allocation fails for N = 1, 2, ... until a run
 * needs no more than N - 1. Each failed call must return a clean error (a
 * status and a message; or, if it tolerates the failure, the same result),
 * leave no block allocated, and the next call must work and give the same
 * result as the first. Cases: G-code, HyperFun (compiled and evaluated),
 * trajectories, JSON and .tbl tool tables, the job JSON, the daemon's
 * config file, the check's machine file, STL, and stocks from a box, a
 * cylinder, a HyperFun model and a snapshot. The harness and what it does
 * not fail (third-party code that cannot survive a failure) are described
 * in tests/support/alloc_fail.c and tests/README.md. Usage: test_alloc_fail [CASE]
 * (run from tests/). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frep/frep.h"
#include "hf/hf.h"
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

/* ---------------------------------------------- job JSON, config, machine -- */

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

static int run_machine(double *summary, char *msg, size_t msg_size)
{
    fm_check_machine m;
    fm_error err;
    if (fm_check_machine_load("check/machine.json", &m, &err)) return fail_with(&err, msg, msg_size);
    *summary = m.rapid_rate;
    for (int a = 0; a < 3; a++) *summary += m.limit_lo[a] + 3 * m.limit_hi[a] + 5 * m.start[a];
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
    long n = 1, failed = 0, errors = 0, tolerated = 0, leaks = 0;
    for (;; n++) {
        long before = alloc_fail_live();
        msg[0] = 0;
        alloc_fail_arm(n);
        int rc = c->run(&got, msg, sizeof msg);
        alloc_fail_disarm();
        int hit = alloc_fail_hit();
        long after = alloc_fail_live();
        if (!hit) {
            /* This run needed fewer than n allocations: every one has
             * failed in turn. */
            CHECK(rc == 0 && got == want);
            CHECK(after == before);
            break;
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
    printf("%-12s %6ld allocations, %6ld failed in turn: %ld clean errors, %ld tolerated, %ld leaked\n",
           c->name, n - 1, failed, errors, tolerated, leaks);
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
    {
        fm_stock_options o = stock_options();
        const double lo[3] = {0, 0, -4}, hi[3] = {6, 5, 0};
        fm_error err;
        fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
        CHECK(s && fm_stock_save(s, vdb_path, "alloc", &err) == FM_OK);
        fm_stock_free(s);
    }

    static const alloc_case cases[] = {
        {"gcode", run_gcode},         {"hyperfun", run_hf},       {"traj", run_traj},
        {"tools.json", run_tools_json}, {"tools.tbl", run_tools_tbl}, {"job.json", run_job_json},
        {"config", run_config},       {"machine", run_machine},   {"stl", run_stl},
        {"box", run_box},             {"cylinder", run_cylinder}, {"hf-stock", run_hf_stock},
        {"vdb", run_vdb},
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
    rmdir(dir);
    for (size_t i = 0; i < GCODE_FILES; i++) free(gcode_text[i]);
    free(traj_text);
    free(hf_text);
    free(json_tools);
    free(tbl_tools);
    free(job_text);
    return test_summary("alloc_fail");
}
