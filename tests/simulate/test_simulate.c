/* test_simulate.c: the whole pipeline (G-code -> motions -> sweeps ->
 * stock) against volumes computed by hand: a flat slot with plunge, a ball
 * slot, a full-circle ring, a helical bore, a G81 drill pattern, a V-bit
 * line and a bull-nose slot. Removed volume must be within 0.5% of the
 * analytic value at 0.1 mm voxels and within 0.1% at 0.05 mm. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40},"
    "{\"number\": 2, \"shape\": \"ball\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40},"
    "{\"number\": 3, \"shape\": \"drill\", \"diameter\": 5, \"point_angle\": 118, \"flute_length\": 30,"
    " \"length\": 45},"
    "{\"number\": 4, \"shape\": \"vbit\", \"diameter\": 6, \"angle\": 90, \"flute_length\": 10,"
    " \"length\": 30},"
    "{\"number\": 5, \"shape\": \"bull\", \"diameter\": 10, \"corner_radius\": 2, \"flute_length\": 20,"
    " \"length\": 40}]}";

/* The README's claim for these seven cuts, at 0.1 mm and at 0.05 mm: at
 * most 0.022% off the closed form (issue 19: the tests assert the claim). */
#define README_TOL 0.00022

static fm_tool_table tools;

/* Removed volume of program on stock at voxel size, or NAN on error. */
static double removed(const char *program, const char *stock, double voxel)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "test.ngc";
    spec.stock_spec = stock;
    spec.tools = &tools;
    spec.stock.voxel_mm = voxel;
    fm_job_result result;
    fm_error err;
    if (fm_job_run(&spec, NULL, &result, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        return NAN;
    }
    /* The running sum of removals and the difference of whole-grid volumes
     * are computed differently; they must agree. */
    double by_difference = result.initial_volume_mm3 - result.final_volume_mm3;
    CHECK_NEAR(result.removed_volume_mm3, by_difference, 1e-6 * result.initial_volume_mm3 + 0.05);
    fm_stock_free(result.stock);
    return result.removed_volume_mm3;
}

static void check_case(const char *name, const char *program, const char *stock, double exact,
                       double voxel, double rel_tol)
{
    double v = removed(program, stock, voxel);
    double rel = fabs(v - exact) / exact;
    printf("%-22s voxel %.2f: removed %10.3f mm3, analytic %10.3f mm3, error %.3f%%\n", name, voxel,
           v, exact, 100 * rel);
    CHECK(rel <= rel_tol);
}

/* Volume of revolution of r(h) for h in [0, H] by composite Simpson. */
static double revolution_volume(double (*r)(double), double H)
{
    const int n = 20000;
    double h = H / n, sum = 0;
    for (int i = 0; i <= n; i++) {
        double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        double ri = r(i * h);
        sum += w * FM_PI * ri * ri;
    }
    return sum * h / 3;
}

/* Cross-section width of the bull nose (D 10, corner radius 2) at height h. */
static double bull_radius(double h)
{
    if (h >= 2) return 5;
    double dz = 2 - h;
    return 3 + sqrt(4 - dz * dz);
}

static double bull_area(double H)
{
    const int n = 20000;
    double h = H / n, sum = 0;
    for (int i = 0; i <= n; i++) {
        double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        sum += w * 2 * bull_radius(i * h);
    }
    return sum * h / 3;
}

int main(int argc, char **argv)
{
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "tool table: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 1;
    }
    int fine = argc > 1 && !strcmp(argv[1], "--fine");

    /* Flat slot with plunge: 60 mm long, 6 wide, 3 deep with round ends. */
    const char *flat_slot = "G21 G90 T1 M6 S10000 M3\nG0 X20 Y30 Z5\nG1 Z-3 F300\nG1 X80 F800\nG0 Z5\nM2\n";
    double flat_slot_v = (60 * 6 + FM_PI * 9) * 3;

    /* Ball slot, ball centre on the stock top: half a capsule. */
    const char *ball_slot = "G21 G90 T2 M6 S10000 M3\nG0 X20 Y30 Z5\nG1 Z-3 F300\nG1 X80 F800\nG0 Z5\nM2\n";
    double ball_slot_v = (FM_PI * 9 * 60 + 4.0 / 3 * FM_PI * 27) / 2;

    /* Full circle of radius 20 at depth 2: an annulus 17..23. */
    const char *ring = "G21 G90 T1 M6 S10000 M3\nG0 X70 Y30 Z5\nG1 Z-2 F300\nG2 X70 Y30 I-20 J0 F800\n"
                       "G0 Z5\nM2\n";
    double ring_v = FM_PI * (23 * 23 - 17 * 17) * 2;

    /* Helical bore: helix of radius 2.5 down 10 mm in 4 turns, then a full
     * circle at the bottom: a cylinder of radius 5.5, depth 10. */
    const char *helix = "G21 G90 T1 M6 S10000 M3\nG0 X52.5 Y30 Z5\nG1 Z0 F300\n"
                        "G3 X52.5 Y30 Z-10 I-2.5 J0 P4 F600\nG3 X52.5 Y30 I-2.5 J0\nG0 Z5\nM2\n";
    double helix_v = FM_PI * 5.5 * 5.5 * 10;

    /* G81 pattern: four 5 mm holes, tip at Z-10, 118 degree point. */
    const char *drill = "G21 G90 T3 M6 S3000 M3\nG0 Z5\nG98 G81 X20 Y20 Z-10 R2 F200\nX40\nY40\nX20\n"
                        "G80\nG0 Z5\nM2\n";
    double cone_h = 2.5 / tan(59.0 * FM_PI / 180);
    double drill_v = 4 * (FM_PI * 6.25 * (10 - cone_h) + FM_PI * 6.25 * cone_h / 3);

    /* V-bit (90 degrees, sharp) line 2 mm deep: a triangular groove of half
     * width 2 plus a cone at the ends (two halves). */
    const char *vline = "G21 G90 T4 M6 S15000 M3\nG0 X20 Y30 Z5\nG1 Z-2 F300\nG1 X80 F800\nG0 Z5\nM2\n";
    double vline_v = 60 * 2 * 2 + FM_PI * 4 * 2 / 3;

    /* Bull nose slot 3 mm deep, 50 mm long: the profile's cross-section
     * along the slot plus one whole tool bottom for the two ends. */
    const char *bull = "G21 G90 T5 M6 S10000 M3\nG0 X25 Y30 Z5\nG1 Z-3 F300\nG1 X75 F800\nG0 Z5\nM2\n";
    double bull_v = 50 * bull_area(3) + revolution_volume(bull_radius, 3);

    const char *block = "box:0,0,-20,100,60,0";
    if (!fine) {
        check_case("flat slot + plunge", flat_slot, block, flat_slot_v, 0.1, README_TOL);
        check_case("ball slot", ball_slot, block, ball_slot_v, 0.1, README_TOL);
        check_case("full-circle ring", ring, block, ring_v, 0.1, README_TOL);
        check_case("helical bore", helix, block, helix_v, 0.1, README_TOL);
        check_case("G81 drill pattern", drill, block, drill_v, 0.1, README_TOL);
        check_case("V-bit line", vline, block, vline_v, 0.1, README_TOL);
        check_case("bull-nose slot", bull, block, bull_v, 0.1, README_TOL);
    } else {
        /* Smaller stocks around each cut keep the fine grids small. */
        check_case("flat slot + plunge", flat_slot, "box:14,24,-8,86,36,0", flat_slot_v, 0.05, README_TOL);
        check_case("ball slot", ball_slot, "box:14,24,-8,86,36,0", ball_slot_v, 0.05, README_TOL);
        check_case("full-circle ring", ring, "box:25,5,-5,75,55,0", ring_v, 0.05, README_TOL);
        check_case("helical bore", helix, "box:40,20,-14,60,40,0", helix_v, 0.05, README_TOL);
        check_case("G81 drill pattern", drill, "box:14,14,-14,46,46,0", drill_v, 0.05, README_TOL);
        check_case("V-bit line", vline, "box:14,25,-5,86,35,0", vline_v, 0.05, README_TOL);
        check_case("bull-nose slot", bull, "box:15,20,-6,85,40,0", bull_v, 0.05, README_TOL);
    }
    fm_tool_table_free(&tools);
    return test_summary(fine ? "simulate (0.05 mm)" : "simulate (0.1 mm)");
}
