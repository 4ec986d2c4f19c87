/* test_thin_wall.c: the thin-wall warning (issue 19). Two slots of a 6 mm
 * flat end mill, 5 mm deep across a 40 x 20 block at 0.2 mm voxels, leave a
 * wall between them. A wall of half a voxel placed between two columns of
 * voxel centres holds no centre: the mesh cannot show it, and the job must
 * report one region there, spanning the wall; the removed volume still
 * counts the wall (the slots' closed form, 2 x 6 x 20 x 5 mm3). A wall of
 * one and a half voxels always holds a column of centres: no warning. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

#define VOXEL 0.2
#define STOCK "box:0,0,-10,40,20,0"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

static fm_tool_table tools;

/* Run the two slots leaving a wall [x0, x0 + w]. */
static int run(double x0, double w, fm_job_result *result)
{
    char program[512];
    snprintf(program, sizeof program,
             "G21 G90 G94\nT1 M6\nS1000 M3\n"
             "G0 X%.6f Y-5 Z5\nG1 Z-5 F600\nG1 Y25\nG0 Z5\n"
             "G0 X%.6f Y-5\nG1 Z-5\nG1 Y25\nG0 Z5\nM2\n",
             x0 - 3, x0 + w + 3);
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "wall.ngc";
    spec.stock_spec = STOCK;
    spec.tools = &tools;
    spec.stock.voxel_mm = VOXEL;
    fm_error err;
    if (fm_job_run(&spec, NULL, result, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 0;
    }
    return 1;
}

int main(void)
{
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        fprintf(stderr, "tools: %s\n", err.message);
        return 1;
    }
    /* where the voxel centres are: the same stock the job will make */
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = VOXEL;
    fm_stock *probe = fm_job_make_stock(STOCK, &so, &err);
    if (!probe) {
        fprintf(stderr, "stock: %s\n", err.message);
        return 1;
    }
    const double zero[3] = {0, 0, 0};
    double o[3];
    fm_stock_index_to_world(probe, zero, o);
    fm_stock_free(probe);
    /* a centre column near x = 20 */
    const double xc = o[0] + VOXEL * floor((20 - o[0]) / VOXEL);
    const double slots = 2 * 6 * 20 * 5.0;

    fm_job_result thin;
    CHECK(run(xc + 0.25 * VOXEL, 0.5 * VOXEL, &thin));
    if (thin.stock) {
        fprintf(stderr, "half-voxel wall: %zu voxels in %zu regions; removed %.3f mm3 (slots %.3f)\n",
                thin.thin.voxels, thin.thin.regions, thin.removed_volume_mm3, slots);
        CHECK(thin.has_thin);
        CHECK(thin.thin.regions == 1 && thin.thin.count == 1 && thin.thin.walls == 1);
        CHECK(thin.thin.region[0].wall);
        /* the wall: 20 mm long, 5 mm high, seen from both sides: at least
         * (20 / 0.2) * (5 / 0.2) voxel centres beside it */
        CHECK(thin.thin.voxels >= 100 * 25);
        const fm_stock_thin_region *g = &thin.thin.region[0];
        fprintf(stderr, "  at (%.3f, %.3f, %.3f), x %.3f..%.3f y %.3f..%.3f z %.3f..%.3f\n", g->position[0],
                g->position[1], g->position[2], g->lo[0], g->hi[0], g->lo[1], g->hi[1], g->lo[2], g->hi[2]);
        /* beside the wall: the centre columns xc and xc + voxel */
        CHECK(g->lo[0] >= xc - 1e-6 && g->hi[0] <= xc + VOXEL + 1e-6);
        CHECK(g->position[0] >= xc - 1e-6 && g->position[0] <= xc + VOXEL + 1e-6);
        /* along the whole wall, within a voxel of its ends */
        CHECK(g->lo[1] <= VOXEL && g->hi[1] >= 20 - VOXEL);
        CHECK(g->lo[2] <= -5 + 2 * VOXEL + 1e-6 && g->hi[2] >= -VOXEL && g->hi[2] <= 0.5 * VOXEL + 1e-6);
        CHECK(g->position[1] > 5 && g->position[1] < 15 && g->position[2] > -4 && g->position[2] < -1);
        /* the volume counts the wall */
        CHECK_NEAR(thin.removed_volume_mm3, slots, 0.001 * slots);
    }
    fm_job_result_release(&thin);

    fm_job_result thick;
    CHECK(run(xc + 0.25 * VOXEL, 1.5 * VOXEL, &thick));
    if (thick.stock) {
        fprintf(stderr, "voxel-and-a-half wall: %zu voxels; removed %.3f mm3\n", thick.thin.voxels,
                thick.removed_volume_mm3);
        CHECK(thick.has_thin && thick.thin.voxels == 0 && thick.thin.regions == 0 && thick.thin.walls == 0);
        CHECK_NEAR(thick.removed_volume_mm3, slots, 0.001 * slots);
    }
    fm_job_result_release(&thick);
    fm_tool_table_free(&tools);
    fprintf(stderr, "%d checks, %d failed\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
