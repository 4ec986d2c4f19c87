/* test_helix_tilt.c: the 5-axis trajectory example examples/helix_tilt.json
 * simulated through the job runner (as `frepmill simulate` runs it) against a
 * closed form (issue 22: the example was only parsed).
 *
 * The stock is a block x 0..30, y 20..35, z -10..0 that only the swarf pass
 * reaches: the helical ramp stays within 10 + r of the Z axis (r = 3, so
 * y <= 13), the tilt happens at y = 0 (|y| <= r), the retract and the rapid
 * at y = 40 (y >= 37). The swarf pass moves a flat end mill whose axis lies in
 * the XZ plane, 15 degrees from Z, along Y from y = 0 to 40. Seen along Y a
 * cylinder whose axis is perpendicular to Y is a rectangle (2r wide, along
 * the axis), and every plane y = c with 0 <= c <= 40 cuts the swept volume
 * in that whole rectangle (the tool's axis plane passes through it). So the
 * removed volume is the rectangle's part below the stock's top times the
 * block's length in Y. At width offset w (-r..r) across the axis the end
 * face sits at depth h + w sin(t) below the top (h = 3: the tip at z = -3),
 * a length (h + w sin(t)) / cos(t) along the axis; integrated over w:
 * 2 r h / cos(t). The flutes (20 mm) are far longer than the 3.9 mm the
 * cut needs along the axis, and the block's sides x 0..30 are clear of it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

/* The README's "at most 0.022% off at 0.1 mm". */
#define CLAIMED 0.00022

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

int main(void)
{
    fm_error err;
    fm_tool_table tools;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        fprintf(stderr, "tools: %s\n", err.message);
        return 1;
    }
    size_t len = 0;
    char *program = NULL;
    CHECK(fm_file_read("../examples/helix_tilt.json", NULL, 1 << 16, &program, &len, &err) ==
          FM_OK);
    CHECK(program != NULL && len > 100);
    if (!program) return 1;

    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = len;
    spec.program_name = "helix_tilt.json";
    spec.stock_spec = "box:0,20,-10,30,35,0";
    spec.tools = &tools;
    spec.stock.voxel_mm = 0.1;
    fm_job_result r;
    if (fm_job_run(&spec, NULL, &r, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        free(program);
        return 1;
    }
    const double radius = 3, depth = 3, tilt = 15 * FM_PI / 180, length_y = 35 - 20;
    const double exact = 2 * radius * depth / cos(tilt) * length_y;
    double rel = fabs(r.removed_volume_mm3 - exact) / exact;
    printf("helix_tilt.json on box 0,20,-10,30,35,0 at 0.1 mm: removed %.3f mm3, closed form %.3f mm3, "
           "error %.4f%%\n",
           r.removed_volume_mm3, exact, 100 * rel);
    CHECK_NEAR(r.initial_volume_mm3, 30 * 15 * 10, CLAIMED * 30 * 15 * 10);
    CHECK(rel <= CLAIMED);
    CHECK_NEAR(r.removed_volume_mm3, r.initial_volume_mm3 - r.final_volume_mm3,
               1e-6 * r.initial_volume_mm3 + 0.05);
    fm_job_result_release(&r);
    free(program);
    fm_tool_table_free(&tools);
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
