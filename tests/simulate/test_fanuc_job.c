/* test_fanuc_job.c: a realistic Haas-style program (O number, comments, N
 * numbers, tool changes with G43 H and tool lengths in the table, G54, a
 * pocket cut by an M98 subprogram with L repeats, a slot by an M97 local
 * call, G81 and G83 drilling, G91 G28 Z0. to the reference point, M30)
 * through the job runner in the Fanuc dialect. The removed volume must equal
 * the closed form computed here from the geometry (within 0.5% at 0.1 mm
 * voxels, the tolerance test_simulate uses). A forgotten tool length offset
 * would put the tips 75 or 90 mm lower, so the volume also proves G43 H.
 * Two more programs: a Fusion-style contour with G41/G42 and Haas' G12/G13
 * circular pockets (G154, G95, G51.1 on the way), each against its closed
 * form. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 10, \"flute_length\": 25, \"length\": 75,"
    " \"length_offset\": 75},"
    "{\"number\": 2, \"shape\": \"drill\", \"diameter\": 6, \"point_angle\": 118,"
    " \"flute_length\": 30, \"length\": 90, \"length_offset\": 90}]}";

/* The pocket (O2000, three 2 mm layers) traces the rectangle (15,15)-(35,25)
 * with a 10 mm tool; the slot (N1000) runs from (55,15) to (85,15), 3 deep. */
static const char *program =
    "%\n"
    "O01234 (FANUC DIALECT JOB TEST)\n"
    "(T1 10MM FLAT, T2 6MM DRILL)\n"
    "N10 G21 G17 G40 G49 G80 G90\n"
    "N20 T1 M06 (10MM FLAT END MILL)\n"
    "N30 G00 G90 G54 X15. Y15. S8000 M03\n"
    "N40 G43 H01 Z25. M08\n"
    "N50 G01 Z0. F300.\n"
    "N60 M98 P2000 L3 (POCKET, 3 X 2MM)\n"
    "N70 G00 Z25.\n"
    "N80 M97 P1000 (SLOT)\n"
    "N90 G00 Z100. M09\n"
    "N100 G91 G28 Z0.\n"
    "N110 M05\n"
    "N120 T2 M06 (6MM DRILL)\n"
    "N130 G00 G90 G54 X20. Y45. S3000 M03\n"
    "N140 G43 H02 Z25. M08\n"
    "N150 G98 G81 Z-10. R2. F150.\n"
    "N160 X35.\n"
    "N170 G83 X60. Z-15. R2. Q4. F120.\n"
    "N180 X80.\n"
    "N190 G80 G00 Z100. M09\n"
    "N200 G91 G28 Z0.\n"
    "N210 G90 M05\n"
    "N220 M30\n"
    "N1000 G00 X55. Y15.\n"
    "N1010 G01 Z-3. F300.\n"
    "N1020 X85. F600.\n"
    "N1030 G00 Z25.\n"
    "N1040 M99\n"
    "O02000 (POCKET LAYER)\n"
    "G91 G01 Z-2. F200.\n"
    "G90 G01 X35. F600.\n"
    "Y25.\n"
    "X15.\n"
    "Y15.\n"
    "M99\n"
    "%\n";

/* A program in the shape Fusion 360's Haas post writes (header comments,
 * G90 G94 G17, G21, G53 G0 Z0., T1 M6, S M3, G154 P1, G43 Z H1, G187 P3, M8,
 * a contour with a G41 D1 start-up line and tangent lead-in arc, a G40
 * lead-out, G53 G0 Z0., M1, M30) around a 40 x 20 boss, 5 deep, in a block
 * 8 mm wider on every side. The first line sets P1's offset as an operator
 * sets it at the control (the part's top at machine Z-200). The compensated path (r 5) runs 5 mm
 * outside the boss with square corners at (-5,-5), (-5,25), (45,25),
 * (45,-5) (Fanuc's intersection for alpha = 90): the tool clears every
 * point within 10 mm outside the boss's sides, and the block's corners
 * (8, 8 from the boss's: 4.24 mm from the corner points) too, while the
 * lead-in and lead-out arcs (R 10 about (-10,10), the tool inside them on
 * R 5) stay off the boss. So the cut removes the block outside the boss to
 * 5 mm: (56 x 36 - 40 x 20) x 5 = 6080 mm3. Without compensation the tool
 * centre would follow the boss's outline and cut 5 mm into it. */
static const char *fusion_program =
    "%\n"
    "O01001 (BOSS)\n"
    "(Machine)\n"
    "(  vendor: Haas Automation)\n"
    "(  description: VF-2)\n"
    "(T1 D=10. CR=0. - ZMIN=-5. - FLAT END MILL)\n"
    "G10 L20 P1 X0. Y0. Z-200.\n"
    "N10 G90 G94 G17\n"
    "N15 G21\n"
    "N20 G53 G0 Z0.\n"
    "(2D CONTOUR1)\n"
    "N25 T1 M6\n"
    "N30 S8000 M3\n"
    "N35 G154 P1\n"
    "N40 G0 X-10. Y-25.\n"
    "N45 G43 Z15. H1\n"
    "N50 G187 P3\n"
    "N55 M8\n"
    "N60 G0 Z5.\n"
    "N65 G1 Z-5. F1000.\n"
    "N70 G41 D1 Y0. F1500.\n"
    "N75 G3 X0. Y10. I0. J10.\n"
    "N80 G1 Y20.\n"
    "N85 X40.\n"
    "N90 Y0.\n"
    "N95 X0.\n"
    "N100 Y10.\n"
    "N105 G3 X-10. Y20. I-10. J0.\n"
    "N110 G40 G1 Y35.\n"
    "N115 G0 Z15.\n"
    "N120 M9\n"
    "N125 G53 G0 Z0.\n"
    "N130 M1\n"
    "N135 M30\n"
    "%\n";

static void test_fusion_haas(const fm_tool_table *tools)
{
    double exact = (56.0 * 36.0 - 40.0 * 20.0) * 5.0;
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = fusion_program;
    spec.program_length = strlen(fusion_program);
    spec.program_name = "O01001.nc";
    /* the block where G154 P1 puts the part: its top at machine Z-200 */
    spec.stock_spec = "box:-8,-8,-230,48,28,-200";
    spec.tools = tools;
    spec.stock.voxel_mm = 0.1;
    spec.dialect = "fanuc";
    fm_job_result result;
    fm_error err;
    char buf[700];
    fm_status st = fm_job_run(&spec, NULL, &result, &err);
    CHECK(st == FM_OK);
    if (st) {
        fprintf(stderr, "Fusion-style job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        return;
    }
    double v = result.removed_volume_mm3;
    double rel = fabs(v - exact) / exact;
    printf("Fusion 360 Haas-post program (G41 D1 lead-in, G40 lead-out), voxel 0.10: "
           "removed %.3f mm3, closed form %.3f mm3, error %.3f%%\n", v, exact, 100 * rel);
    CHECK(rel <= 0.005);
    fm_stock_free(result.stock);
}

/* Haas' own codes as a shop writes them (tool comment header, G154 P1 set
 * by G10 L20, G187, G95 feed per revolution, G12/G13 circular pockets with
 * I K Q D L in G91, G51.1 mirror image): two pockets of radius K = 20 and
 * 3 x 2 mm deep, the first at G154 P1's (15, 25) = machine (25, 30), the
 * second programmed at the same place mirrored about X40: work (65, 25) =
 * machine (75, 30). The tool centre runs circles of radius 1, 6, 11 and 15
 * (I6, 11, 16, K20 less the tool's 5), each within a tool diameter of the
 * last, so each pocket is the whole cylinder: pi 20^2 6. */
static const char *haas_program =
    "%\n"
    "O01235 (HAAS POCKETS)\n"
    "(T1 D=10. CR=0. - ZMIN=-6. - FLAT END MILL)\n"
    "N10 G90 G94 G17\n"
    "N15 G21\n"
    "N20 G10 L20 P1 X10. Y5. Z0\n"
    "N25 T1 M06\n"
    "N30 S5000 M03\n"
    "N35 G154 P1\n"
    "N40 G00 X15. Y25.\n"
    "N45 G43 H01 Z5.\n"
    "N50 G187 P3\n"
    "N55 G01 Z0 F300.\n"
    "N60 G95 G13 G91 Z-2. I6. K20. Q5. D1 L3 F0.08\n"
    "N65 G90 G94 G00 Z5.\n"
    "N70 G51.1 X40.\n"
    "N75 G00 X15. Y25.\n"
    "N80 G01 Z0 F300.\n"
    "N85 G12 G91 Z-2. I6. K20. Q5. D1 L3 F400.\n"
    "N90 G90 G00 Z5.\n"
    "N95 G50.1 X0\n"
    "N100 G00 Z50. M05\n"
    "N105 M30\n"
    "%\n";

static void test_haas_pockets(const fm_tool_table *tools)
{
    double exact = 2 * FM_PI * 20 * 20 * 6;
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = haas_program;
    spec.program_length = strlen(haas_program);
    spec.program_name = "O01235.nc";
    spec.stock_spec = "box:0,0,-30,100,60,0";
    spec.tools = tools;
    spec.stock.voxel_mm = 0.1;
    spec.dialect = "fanuc";
    spec.reference_points[0][2] = 200; /* the tool starts 200 mm above Z0 */
    fm_job_result result;
    fm_error err;
    char buf[700];
    fm_status st = fm_job_run(&spec, NULL, &result, &err);
    CHECK(st == FM_OK);
    if (st) {
        fprintf(stderr, "Haas pockets: %s\n", fm_error_format(&err, buf, sizeof buf));
        return;
    }
    double v = result.removed_volume_mm3;
    double rel = fabs(v - exact) / exact;
    printf("Haas G154 G95 G12/G13 G51.1 pockets, voxel 0.10: removed %.3f mm3, closed form "
           "%.3f mm3, error %.3f%%, %ld motions\n", v, exact, 100 * rel, result.motions);
    CHECK(rel <= 0.005);
    fm_stock_free(result.stock);
}

int main(void)
{
    fm_tool_table tools;
    fm_error err;
    char buf[700];
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err)) {
        fprintf(stderr, "tool table: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 1;
    }
    /* Pocket: the points within 5 mm of a 20 x 10 rectangle's outline: the
     * whole rectangle (no point inside is farther than 5 from a long side)
     * plus the outer band with round corners: a b + 2 r (a + b) + pi r^2. */
    double a = 20, b = 10, r = 5;
    double pocket = (a * b + 2 * r * (a + b) + FM_PI * r * r) * 6;
    /* Slot: 30 mm long, 10 wide, round ends, 3 deep. */
    double slot = (30 * 10 + FM_PI * r * r) * 3;
    /* Drills: radius 3, point 118 degrees: a cone of height 3 / tan 59
     * under a cylinder, to tip depths 10 (two G81 holes) and 15 (two G83). */
    double rd = 3, cone = rd / tan(59 * FM_PI / 180);
    double hole10 = FM_PI * rd * rd * (10 - cone) + FM_PI * rd * rd * cone / 3;
    double hole15 = FM_PI * rd * rd * (15 - cone) + FM_PI * rd * rd * cone / 3;
    double exact = pocket + slot + 2 * hole10 + 2 * hole15;

    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "O01234.nc";
    spec.stock_spec = "box:0,0,-30,100,60,0";
    spec.tools = &tools;
    spec.stock.voxel_mm = 0.1;
    spec.dialect = "fanuc";
    /* the machine's reference point: the gauge line 200 mm above Z0 */
    spec.reference_points[0][2] = 200;
    fm_job_result result;
    fm_status st = fm_job_run(&spec, NULL, &result, &err);
    CHECK(st == FM_OK);
    if (st) {
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        fm_tool_table_free(&tools);
        return test_summary("test_fanuc_job");
    }
    double v = result.removed_volume_mm3;
    double rel = fabs(v - exact) / exact;
    printf("Haas-style program, fanuc dialect, voxel 0.10: removed %.3f mm3, closed form %.3f "
           "mm3, error %.3f%%, %ld motions\n", v, exact, 100 * rel, result.motions);
    CHECK(rel <= 0.005);
    fm_stock_free(result.stock);

    /* The same text in the LinuxCNC dialect is not the same program: the
     * O number line is an O-word error there. */
    spec.dialect = NULL;
    CHECK(fm_job_run(&spec, NULL, &result, &err) != FM_OK);
    spec.dialect = "haas";
    CHECK(fm_job_run(&spec, NULL, &result, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "expected linuxcnc or fanuc");
    test_fusion_haas(&tools);
    test_haas_pockets(&tools);
    fm_tool_table_free(&tools);
    return test_summary("test_fanuc_job");
}
