/* test_stocks.c: the stocks a user names besides a box, through the job
 * runner as `frepmill simulate --stock` takes them (the same spec string):
 * a cylinder, an STL mesh and a .vdb snapshot written by a previous job
 * (which carries that job's initial and removed volumes).
 * Initial and removed volumes against closed forms, at the README's 0.022%
 * where the cut is a slot like test_simulate's (issue 22). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "job.h"
#include "test.h"
#include "test_stl.h"
#include "toolpaths/tooltable/tooltable.h"

/* The README's "at most 0.022% off at 0.1 mm". */
#define CLAIMED 0.00022

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

static fm_tool_table tools;

/* Run program on stock; the caller frees out->stock. */
static int run(const char *program, const char *stock, fm_job_result *out)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "test.ngc";
    spec.stock_spec = stock;
    spec.tools = &tools;
    spec.stock.voxel_mm = 0.1;
    fm_error err;
    if (fm_job_run(&spec, NULL, out, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "%s: job failed: %s\n", stock, fm_error_format(&err, buf, sizeof buf));
        return -1;
    }
    double by_difference = out->initial_volume_mm3 - out->final_volume_mm3;
    CHECK_NEAR(out->removed_volume_mm3, by_difference, 1e-6 * out->initial_volume_mm3 + 0.05);
    return 0;
}

static void check_rel(const char *what, double v, double exact, double tol)
{
    double rel = fabs(v - exact) / exact;
    printf("%-34s %12.3f mm3, closed form %12.3f mm3, error %.4f%%\n", what, v, exact, 100 * rel);
    CHECK(rel <= tol);
}

/* Area of the strip |y| <= w of a disc of radius r (w < r). */
static double disc_strip(double r, double w)
{
    return 2 * (w * sqrt(r * r - w * w) + r * r * asin(w / r));
}

int main(void)
{
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "tool table: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 1;
    }
    fm_job_result r;

    /* Cylinder r 20 about (0, 0), z -10..0. A 3 mm deep slot right across it
     * (the 6 mm tool from X-30 to X30 at Y0: its round ends lie outside)
     * removes the strip |y| <= 3 of the disc, 3 deep. */
    if (run("G21 G90 T1 M6 S10000 M3\nG0 X-30 Y0 Z5\nG1 Z-3 F300\nG1 X30 F800\nG0 Z5\nM2\n",
            "cylinder:0,0,-10,0,20", &r) == 0) {
        check_rel("cylinder: initial volume", r.initial_volume_mm3, FM_PI * 400 * 10, CLAIMED);
        check_rel("cylinder: slot across", r.removed_volume_mm3, disc_strip(20, 3) * 3, CLAIMED);
        fm_stock_free(r.stock);
    }

    /* An STL box 0..40 x 0..30 x -10..0 (12 facets): a slot inside it,
     * 20 long, 6 wide, 3 deep with round ends, plunged at its start. */
    char dir[] = "/tmp/fm-test-stocks.XXXXXX";
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    char stl[64], vdb[64];
    snprintf(stl, sizeof stl, "%s/box.stl", dir);
    snprintf(vdb, sizeof vdb, "%s/after.vdb", dir);
    const double lo[3] = {0, 0, -10}, hi[3] = {40, 30, 0};
    CHECK(fm_test_write_box_stl(stl, lo, hi, FM_TEST_BOX_NO_FACE) == 0);
    const double slot = (20 * 6 + FM_PI * 9) * 3;
    if (run("G21 G90 T1 M6 S10000 M3\nG0 X10 Y10 Z5\nG1 Z-3 F300\nG1 X30 F800\nG0 Z5\nM2\n", stl, &r) == 0) {
        check_rel("stl box: initial volume", r.initial_volume_mm3, 40 * 30 * 10, CLAIMED);
        check_rel("stl box: slot", r.removed_volume_mm3, slot, CLAIMED);
        /* The snapshot of what is left, as --out after.vdb writes it. */
        CHECK(fm_stock_save(r.stock, vdb, "", &err) == FM_OK);
        fm_stock_free(r.stock);
    }

    /* The snapshot as the next job's stock: a second, parallel slot at Y20
     * (6 mm clear of the first). The snapshot carries its history (its
     * metadata holds the initial volume and the removed total, so that a
     * resumed job reports the whole job: docs/stock.md), so the report
     * counts from the STL box: both slots removed, the box less both left. */
    if (run("G21 G90 T1 M6 S10000 M3\nG0 X10 Y20 Z5\nG1 Z-3 F300\nG1 X30 F800\nG0 Z5\nM2\n", vdb, &r) == 0) {
        check_rel("vdb snapshot: initial volume", r.initial_volume_mm3, 40 * 30 * 10, CLAIMED);
        check_rel("vdb snapshot: both slots removed", r.removed_volume_mm3, 2 * slot, CLAIMED);
        check_rel("vdb snapshot: final volume", r.final_volume_mm3, 40 * 30 * 10 - 2 * slot, CLAIMED);
        fm_stock_free(r.stock);
    }
    unlink(stl);
    unlink(vdb);
    rmdir(dir);
    fm_tool_table_free(&tools);
    return test_summary("simulate_stocks");
}
