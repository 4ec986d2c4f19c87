/* test_budget.c: the budget warning (issue 19). A flat tool's helix has
 * no closed form, so every voxel's value comes from the branch-and-bound
 * search; with a search budget forced down to a few evaluations per point
 * the search stops before its proof at many voxels, and the job must count
 * them (result, progress hook, report JSON) and name the helix's line;
 * with the default budget it must count none. The under-cut is one-sided:
 * a stopped search keeps a lower value, so the small budget can only
 * remove less. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "job.h"
#include "report_json.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

/* line 4 is the helix, line 5 a full circle at the bottom */
static const char *helix = "G21 G90 T1 M6 S10000 M3\nG0 X52.5 Y30 Z5\nG1 Z0 F300\n"
                           "G3 X52.5 Y30 Z-10 I-2.5 J0 P4 F600\nG3 X52.5 Y30 I-2.5 J0\nG0 Z5\nM2\n";

typedef struct seen {
    size_t last_uncertain;
    int last_line;
    int decreased;
} seen;

static int on_progress(void *user, const fm_job_progress *p)
{
    seen *s = user;
    if (p->voxels_uncertain < s->last_uncertain) s->decreased = 1;
    s->last_uncertain = p->voxels_uncertain;
    s->last_line = p->uncertain_line;
    return 0;
}

static void run(size_t evaluations, fm_job_result *result, seen *s, const fm_tool_table *tools)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = helix;
    spec.program_length = strlen(helix);
    spec.program_name = "helix.ngc";
    spec.stock_spec = "box:40,20,-14,60,40,0";
    spec.tools = tools;
    spec.stock.voxel_mm = 0.1;
    spec.batch_diameters = -1; /* one cut per motion: the first line is the helix's */
    spec.sweep_evaluations = evaluations;
    fm_job_hooks hooks = {.user = s, .progress = on_progress};
    memset(s, 0, sizeof *s);
    fm_error err;
    fm_status st = fm_job_run(&spec, &hooks, result, &err);
    if (st != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
    }
    CHECK(st == FM_OK);
}

int main(void)
{
    fm_tool_table tools;
    fm_error err;
    CHECK(fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) ==
          FM_OK);

    fm_job_result exact, starved;
    seen s_exact, s_starved;
    run(0, &exact, &s_exact, &tools);
    run(8, &starved, &s_starved, &tools);
    printf("default budget: %zu uncertain voxels, removed %.3f mm3\n", exact.voxels_uncertain,
           exact.removed_volume_mm3);
    printf("budget 8: %zu uncertain voxels (up to %.4f mm, first at line %d), removed %.3f mm3\n",
           starved.voxels_uncertain, starved.uncertain_max_mm, starved.uncertain_line,
           starved.removed_volume_mm3);

    CHECK(exact.voxels_uncertain == 0);
    CHECK(exact.uncertain_line == 0);
    CHECK(s_exact.last_uncertain == 0);

    CHECK(starved.voxels_uncertain > 0);
    CHECK(starved.uncertain_max_mm > 0);
    CHECK(starved.uncertain_line == 4);
    /* the progress hook saw the count grow to the result's */
    CHECK(!s_starved.decreased);
    CHECK(s_starved.last_uncertain == starved.voxels_uncertain);
    CHECK(s_starved.last_line == 4);
    /* a stopped search keeps a lower value: it can only cut less */
    CHECK(starved.removed_volume_mm3 <= exact.removed_volume_mm3 + 1e-9);

    /* the report says the same */
    json_t *rep = fm_job_report_json(&starved);
    CHECK(rep != NULL);
    CHECK((size_t)json_integer_value(json_object_get(rep, "voxels_uncertain")) ==
          starved.voxels_uncertain);
    CHECK(json_integer_value(json_object_get(rep, "uncertain_line")) == 4);
    CHECK(json_real_value(json_object_get(rep, "uncertain_max_mm")) == starved.uncertain_max_mm);
    json_decref(rep);
    rep = fm_job_report_json(&exact);
    CHECK(json_integer_value(json_object_get(rep, "voxels_uncertain")) == 0);
    CHECK(json_is_null(json_object_get(rep, "uncertain_line")));
    json_decref(rep);

    fm_job_result_release(&exact);
    fm_job_result_release(&starved);
    fm_tool_table_free(&tools);
    return test_summary("budget warning");
}
