/* test_interpret_once.c: a job interprets its program once (issue 33): the
 * survey's motions are replayed for the cut and for the design's blame, and
 * kept in the job's motion log file when the spec names one, where they are
 * the motions fm_job_interpret makes. The program is interpreted again only
 * where the motions cannot be kept or depend on the stock: a trajectory's
 * parametric paths (no log file is left) and G38 probing. Figures against
 * closed forms: a 6 mm flat end mill slots 20 mm 2 mm deep, removing
 * 2 (2 r L + pi r^2); the design, the block 1 mm below its top, is gouged
 * 1 mm deep, blamed on the slot's line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

#define SLOT_LINE 5

static const char *TOOLS = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", "
                           "\"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";
static const char *SLOT = "G21 G90 G17\nT1 M6\nS10000 M3\nG0 X10 Y20 Z5\nG1 Z-2 F300 X10\n"
                          "G1 X30 F1000\nG0 Z5\nM30\n";

static fm_tool_table tools;
static char dir[64];

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

static void spec_for(fm_job_spec *spec, const char *program, const char *name)
{
    fm_job_spec_default(spec);
    spec->program_text = program;
    spec->program_length = strlen(program);
    spec->program_name = name;
    spec->program_kind = FM_PROGRAM_AUTO;
    spec->stock_spec = "box:0,0,-10,40,40,0";
    spec->tools = &tools;
    spec->stock.voxel_mm = 0.1;
}

typedef struct motion_list {
    fm_motion m[64];
    int n;
} motion_list;

static int collect(void *user, const fm_motion *m)
{
    motion_list *l = user;
    if (l->n < 64) l->m[l->n] = *m;
    l->n++;
    return 0;
}

/* One interpretation for the survey, the cut and the blame; the log file
 * holds the motions fm_job_interpret makes. */
static void test_slot_with_design(void)
{
    char design[128], log[128];
    snprintf(design, sizeof design, "%s/design.hf", dir);
    snprintf(log, sizeof log, "%s/motions.log", dir);
    write_file(design, "block(x[3], a[1])\n{\n  r_alpha = 1;\n  block = x[1] & (40 - x[1]) & x[2] "
                       "& (40 - x[2]) & (x[3] + 10) & (-1 - x[3]);\n}\n");
    fm_job_spec spec;
    spec_for(&spec, SLOT, "slot.ngc");
    spec.design_path = design;
    spec.motion_log = log;
    fm_job_result r;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_job_run(&spec, NULL, &r, &err) == FM_OK);
    CHECK(r.interpretations == 1);
    const double want = 2 * (2 * 3 * 20 + FM_PI * 9);
    CHECK_NEAR(r.removed_volume_mm3, want, 2e-3 * want);
    CHECK(r.has_deviation && r.deviation.gouge_count >= 1);
    if (r.has_deviation && r.deviation.gouge_count >= 1) {
        CHECK_NEAR(r.deviation.gouges[0].depth_mm, 1.0, 0.05);
        CHECK(r.gouge_blame[0].line == SLOT_LINE || r.gouge_blame[0].line == SLOT_LINE + 1);
    }
    fm_job_result_release(&r);
    motion_list direct = {0}, kept = {0};
    CHECK(fm_job_interpret(&spec, collect, &direct, &err) == FM_OK);
    CHECK(fm_job_motions_replay_file(log, NULL, collect, &kept, &err) == FM_OK);
    CHECK(direct.n > 0 && kept.n == direct.n);
    for (int i = 0; i < direct.n && i < kept.n && i < 64; i++) {
        const fm_motion *a = &direct.m[i], *b = &kept.m[i];
        CHECK(a->line == b->line && a->index == b->index && a->kind == b->kind &&
              a->tool == b->tool && !memcmp(a->start, b->start, sizeof a->start) &&
              !memcmp(a->end, b->end, sizeof a->end) && a->t0 == b->t0 && a->t1 == b->t1);
    }
    unlink(log);
    unlink(design);
}

/* G38.2: the cut's probe reads the stock, so the cut interprets again. */
static void test_probe(void)
{
    const char *program = "G21 G90\nT1 M6\nG0 X20 Y20 Z5\nG38.2 Z-5 F200\nG0 Z5\nM30\n";
    fm_job_spec spec;
    spec_for(&spec, program, "probe.ngc");
    fm_job_result r;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_job_run(&spec, NULL, &r, &err) == FM_OK);
    CHECK(r.interpretations == 2);
    fm_job_result_release(&r);
}

/* A trajectory's parametric motions cannot be kept: interpreted for the
 * cut again, and no log file is left for the toolpath. */
static void test_trajectory(void)
{
    char log[128];
    snprintf(log, sizeof log, "%s/traj.log", dir);
    const char *traj = "{\"units\": \"mm\", \"tool\": 1, \"segments\": [{\"t\": [0, 2], "
                       "\"x\": \"10 + 10*u\", \"y\": 20, \"z\": -1, \"feed\": 600}]}";
    fm_job_spec spec;
    spec_for(&spec, traj, "path.json");
    spec.motion_log = log;
    fm_job_result r;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_job_run(&spec, NULL, &r, &err) == FM_OK);
    CHECK(r.interpretations == 2);
    CHECK(access(log, F_OK) != 0);
    fm_job_result_release(&r);
}

int main(void)
{
    fm_error err;
    CHECK(fm_tooltable_parse_json(TOOLS, strlen(TOOLS), "tools", &tools, &err) == FM_OK);
    snprintf(dir, sizeof dir, "/tmp/fm-once-XXXXXX");
    CHECK(mkdtemp(dir) != NULL);
    test_slot_with_design();
    test_probe();
    test_trajectory();
    rmdir(dir);
    fm_tool_table_free(&tools);
    return test_summary("test_interpret_once");
}
