/* test_check.c: lib/check on programs built for the purpose, run through
 * the job runner as `frepmill check` runs them (the check in the cutting
 * pass, 0.5 mm voxels). Every expected value is worked out by hand from the
 * geometry in the comments, never taken from the check's own output.
 *
 * Depth precision (docs/check.md, "How exact the depths are"): the grids
 * hold exact distances at voxel centres, so every expected depth below is
 * the largest Q over the voxel centres, worked out by hand from where the
 * centres lie, and asserted to 1e-4 mm (float rounding of the grid), with
 * the true depth D beside it in the comment. A part's face parallel to a
 * face of what it entered is measured exactly (the voxel centres just
 * outside the part see it); a ridge across one grid axis is sampled at
 * most h/2 low (the centres' planes are h apart); a round side pressed
 * into a face is seen from the centre just outside it, at most e^2 / 2r
 * low (e <= h/2 the centre's offset along the face, r the radius). The
 * box stocks below start at a whole millimetre, so their voxel centres sit
 * at a quarter millimetre off whole ones (x = 0.25 + 0.5 k); fixtures and
 * machine components (a model's zero set) have theirs at whole multiples
 * of 0.5 mm (x = 0.5 k). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check/check.h"
#include "job.h"
#include "test.h"
#include "test_stl.h"

/* A 6 mm flat end mill: flutes 0..flute, shank up to length (6 mm
 * diameter, as the cutter), a 20 mm holder 30 mm long above it. */
static fm_tool_spec flat_tool(double flute, double length, int center_cutting)
{
    fm_tool_spec t;
    memset(&t, 0, sizeof t);
    t.number = 1;
    t.shape = FM_TOOL_FLAT;
    t.diameter = 6;
    t.shank_diameter = 6;
    t.flute_length = flute;
    t.length = length;
    t.holder_count = 1;
    t.holder[0] = (fm_holder_segment){20, 20, 30};
    t.center_cutting = center_cutting;
    return t;
}

/* Run program against a box stock with the check in the pass; returns the
 * check (caller frees). fixture: a model file or NULL. */
static fm_check *check_program(const char *program, const double lo[3], const double hi[3],
                               fm_tool_spec tool, const fm_check_options *opt,
                               const char *fixture)
{
    fm_tool_table table = {1, &tool};
    fm_error err;
    fm_error_clear(&err);
    fm_job_check check;
    fm_job_check_default(&check);
    if (opt) check.options = *opt;
    if (fixture) {
        check.fixtures[0] = fixture;
        check.fixture_count = 1;
    }
    char spec_text[256];
    snprintf(spec_text, sizeof spec_text, "box:%g,%g,%g,%g,%g,%g", lo[0], lo[1], lo[2], hi[0],
             hi[1], hi[2]);
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "test.ngc";
    spec.stock_spec = spec_text;
    spec.tools = &table;
    spec.stock.voxel_mm = 0.5;
    spec.stock.band_voxels = fm_check_band_voxels(&check.options, 0.5);
    spec.check = &check;
    /* as frepmill check does: A B C words turn the machine's rotary axes */
    if (check.options.machine.chain.rotary_count) spec.machine = &check.options.machine.chain;
    fm_job_result res;
    fm_status st = fm_job_run(&spec, NULL, &res, &err);
    if (st != FM_OK) fprintf(stderr, "job: %s\n", err.message);
    CHECK(st == FM_OK);
    if (st != FM_OK) return NULL;
    fm_stock_free(res.stock);
    CHECK(res.check != NULL);
    return res.check;
}

static void dump(const fm_check *c)
{
    for (size_t i = 0; i < fm_check_count(c); i++) {
        const fm_check_finding *f = fm_check_get(c, i);
        fprintf(stderr,
                "  finding: %s %s %s line %d-%d pen %.4f pos (%.3f %.3f %.3f) contact (%.3f %.3f "
                "%.3f)\n",
                fm_check_kind_name(f->kind), fm_check_severity_name(f->severity),
                fm_check_part_name(f->part), f->line, f->last_line, f->penetration_mm,
                f->position[0], f->position[1], f->position[2], f->contact[0], f->contact[1],
                f->contact[2]);
    }
}

static const fm_check_finding *find_kind(const fm_check *c, fm_check_kind kind)
{
    for (size_t i = 0; i < fm_check_count(c); i++)
        if (fm_check_get(c, i)->kind == kind) return fm_check_get(c, i);
    return NULL;
}

static const double box_lo[3] = {0, 0, -20}, box_hi[3] = {50, 50, 0};
static const double voxel = 0.5;
/* A depth that is the exact distance at a voxel centre: float rounding. */
static const double grid_exact = 1e-4;

/* A rapid at Z-5 through a 50 mm block along y = 25. The deepest points of
 * the flutes are their bottom face, 5 mm below the top (15 above the
 * bottom, 25 from the sides): 5 mm, a face parallel to the top's. The tool
 * (radius 3) first touches the face x = 0 with its tip at x = -3, and
 * passes half the tolerance (0.005 mm) at -2.995. The voxel centres
 * nearest the tool's axis are 0.25 mm off it (y = 24.75, 25.25), where the
 * cylinder's side is sqrt(9 - 0.0625) = 2.9896 mm ahead of the axis, not
 * 3: the first contact is seen at most 0.0104 + 0.005 after -3. */
static void test_rapid_through(void)
{
    const char *prog = "G21 G90\nG0 Z10\nG0 X-10 Y25\nG0 Z-5\nG0 X60\nG0 Z10\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 1);
    const fm_check_finding *f = fm_check_get(c, 0);
    if (f) {
        CHECK(f->kind == FM_CHECK_RAPID_INTO_STOCK);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK(f->part == FM_CHECK_PART_FLUTES);
        CHECK(f->line == 5);
        CHECK_NEAR(f->penetration_mm, 5.0, grid_exact);
        CHECK(f->position[0] >= -3.0 && f->position[0] <= -3.0 + 0.0104 + 0.005);
        CHECK_NEAR(f->position[2], -5.0, 1e-9);
        /* on the face x = 0, at the tool's side, within the flutes' height */
        CHECK_NEAR(f->contact[0], 0.0, 0.01);
        CHECK_NEAR(f->contact[1], 25.0, 3.0);
        CHECK(f->contact[2] >= -5.0 && f->contact[2] <= 0.0);
    }
    fm_check_free(c);
}

/* The same rapid half a millimetre over the top: nothing (the tool's
 * bottom stays 0.5 mm above z = 0), and so is the retract. */
static void test_rapid_over(void)
{
    const char *prog = "G21 G90\nG0 Z10\nG0 X-10 Y25\nG0 Z0.5\nG0 X60\nG0 Z10\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 0);
    fm_check_free(c);
}

/* Issue 14: a 6 mm flat end mill with 8 mm of flute and a 6 mm shank
 * plunges 11.5 mm deep (line 5). The flutes cut the hole the shank follows
 * into: no finding there. Then a feed along X (line 6) drags the shank
 * through the 3.5 mm layer of stock between the slot its flutes cut (whose
 * ceiling is z = tip + 8 = -3.5) and the top: the shank's points at depth
 * 1.75 are 1.75 mm from both, the deepest (a voxel centre: z = -1.75). It
 * starts at once, as the shank's side leaves the plunged hole. The rapid
 * retract (line 7) drags the shank on up through that layer (the finding
 * goes on) and the flutes with it: a rapid into the stock, whose deepest
 * point in the layer is again 1.75 from both faces. The holder (clearance
 * 1 mm) stays 28.5 mm above the top. */
static void test_plunge_then_shank(void)
{
    const char *prog = "G21 G90\nS1000 M3\nG0 Z5\nG0 X25 Y25\nG1 Z-11.5 F100\nG1 X40\nG0 Z30\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(8, 40, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 2);
    const fm_check_finding *f = find_kind(c, FM_CHECK_SHANK_CONTACT);
    CHECK(f != NULL);
    if (f) {
        CHECK(f->part == FM_CHECK_PART_SHANK);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK(f->line == 6);
        CHECK(f->last_line == 7);
        CHECK(f->motions == 2);
        CHECK_NEAR(f->penetration_mm, 1.75, grid_exact);
        CHECK_NEAR(f->position[0], 25.0, 0.01);
        CHECK_NEAR(f->position[2], -11.5, 1e-9);
    }
    f = find_kind(c, FM_CHECK_RAPID_INTO_STOCK);
    CHECK(f != NULL);
    if (f) {
        CHECK(f->line == 7);
        CHECK_NEAR(f->penetration_mm, 1.75, grid_exact);
    }
    fm_check_free(c);
}

/* The same with the plunge to Z-12: the layer is 4 mm, its middle z = -2
 * (D = 2.0) lies between voxel centres (-1.75, -2.25), where the depth is
 * 1.75: a ridge across z sampled h/2 = 0.25 low, the most it can be.
 * (And the rapid retract as above.) */
static void test_plunge_then_shank_between(void)
{
    const char *prog = "G21 G90\nS1000 M3\nG0 Z5\nG0 X25 Y25\nG1 Z-12 F100\nG1 X40\nG0 Z30\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(8, 40, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 2);
    const fm_check_finding *f = find_kind(c, FM_CHECK_SHANK_CONTACT);
    CHECK(f != NULL);
    if (f) {
        CHECK(f->line == 6);
        CHECK_NEAR(f->penetration_mm, 1.75, grid_exact);
    }
    fm_check_free(c);
}

/* A holder face 2 mm below the top: 10 mm of flute and no shank, the
 * holder (radius 10) from tip + 10; plunged to Z-12, the face is at z = -2.
 * Its ring 5..10 mm from the axis is 2 mm below the top and at least 2 mm
 * from the hole the flutes cut (radius 3): 2.0, a face parallel to the
 * top. With the holder's 1 mm clearance the finding opens when the face
 * comes within 1 mm of the top, with the tip at -9. */
static void test_holder_face(void)
{
    const char *prog = "G21 G90\nS1000 M3\nG0 Z5\nG0 X25 Y25\nG1 Z-12 F100\nG0 Z30\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(10, 10, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    const fm_check_finding *f = find_kind(c, FM_CHECK_HOLDER_CONTACT);
    CHECK(f != NULL);
    CHECK(fm_check_count(c) == 1);
    if (f) {
        CHECK(f->part == FM_CHECK_PART_HOLDER);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK(f->line == 5);
        CHECK_NEAR(f->penetration_mm, 2.0, grid_exact);
        CHECK_NEAR(f->position[2], -9.0, 0.01);
    }
    fm_check_free(c);

    /* without the clearance: the first contact is the face at the top */
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.clearance_mm[FM_CHECK_PART_HOLDER] = 0;
    c = check_program(prog, box_lo, box_hi, flat_tool(10, 10, 1), &opt, NULL);
    if (!c) return;
    dump(c);
    f = find_kind(c, FM_CHECK_HOLDER_CONTACT);
    CHECK(f != NULL);
    if (f) {
        CHECK_NEAR(f->penetration_mm, 2.0, grid_exact);
        CHECK_NEAR(f->position[2], -10.0, 0.01);
    }
    fm_check_free(c);
}

/* A fixture whose function is a tenth of the distance (tests/check/
 * jaw_scaled.hf: a block x 60..80, y 0..50, z -20..10, every plane times
 * 0.1). A rapid at Z7 along y = 25 drags the flutes' bottom 3 mm below the
 * jaw's top, 10 mm from its ends and 20 from its sides: 3.0 mm, not the
 * model's 0.3. The tool's edge first meets the face x = 60 with the tip at
 * x = 57. */
static void test_fixture_scaled(void)
{
    const char *prog = "G21 G90\nG0 Z20\nG0 X0 Y25\nG0 Z7\nG0 X100\nG0 Z20\n";
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 20;
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), &opt,
                                "check/jaw_scaled.hf");
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 1);
    const fm_check_finding *f = fm_check_get(c, 0);
    if (f) {
        CHECK(f->kind == FM_CHECK_FIXTURE_CONTACT);
        CHECK(f->part == FM_CHECK_PART_FLUTES);
        CHECK(f->fixture == 0);
        CHECK(f->line == 5);
        CHECK_NEAR(f->penetration_mm, 3.0, grid_exact);
        CHECK_NEAR(f->position[0], 57.0, 0.01);
    }
    fm_check_free(c);
}


/* The one finding of a rapid through fixture 0: the flutes on the given
 * line, D deep (the exact depth; the grid reads it at most half a voxel's
 * diagonal and a voxel short, never over, but for float rounding). */
static const fm_check_finding *one_fixture_contact(const fm_check *c, int line, double D)
{
    dump(c);
    CHECK(fm_check_count(c) == 1);
    const fm_check_finding *f = fm_check_get(c, 0);
    if (!f) return NULL;
    CHECK(f->kind == FM_CHECK_FIXTURE_CONTACT);
    CHECK(f->part == FM_CHECK_PART_FLUTES);
    CHECK(f->severity == FM_CHECK_ERROR);
    CHECK(f->line == line);
    CHECK(f->fixture == 0);
    CHECK(f->penetration_mm >= D - voxel * sqrt(3) / 2 - voxel);
    CHECK(f->penetration_mm <= D + grid_exact);
    return f;
}

/* examples/clamp.hf: a rapid at Z35 along y = 30 crosses the strap (z
 * 30..40, x -35..10), the bolt (radius 5 about (-12, 30), up to z 52) and
 * the nut (radius 9, z 40..48). The deepest point of the flutes (radius 3,
 * z 35..55) is on the bolt's axis, where the clamp's surface is nearest at
 * the nut's top edge (r = 5, z = 48: distance sqrt(25 + (48 - z)^2)) or at
 * the corner of the nut's bottom and the strap's side (y = 38, z = 40:
 * sqrt(64 + (z - 40)^2)); the two are equal at z = 665 / 16 = 41.5625,
 * sqrt(25 + 6.4375^2) = 8.151 mm = D. The deepest point is a ridge of
 * the depth, sampled at the fixture's voxel centres (h sqrt(3) / 2 =
 * 0.433 low at most), and the depth search may stop a voxel short once
 * its 128 searches run out (docs/check.md): the depth lies in
 * [D - h sqrt(3) / 2 - h, D]. (Sampling an exact distance alone would give
 * 8.139, at the centre (-12, 30, 41.5); the fixture's grid is not exact
 * there: printed below, docs/check.md.) The tool's edge meets the strap's
 * far end x = -35 first, with the tip at -38. */
static void test_fixture_clamp(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {100, 60, 30};
    const char *prog = "G21 G90\nG0 Z60\nG0 X-60 Y30\nG0 Z35\nG0 X50\nG0 Z60\n";
    FILE *probe = fopen("../examples/clamp.hf", "r");
    CHECK(probe != NULL);
    if (!probe) return;
    fclose(probe);
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 60;
    fm_check *c = check_program(prog, lo, hi, flat_tool(20, 40, 1), &opt, "../examples/clamp.hf");
    if (!c) return;
    const fm_check_finding *f = one_fixture_contact(c, 5, 8.151);
    if (f) CHECK_NEAR(f->position[0], -38.0, 0.01);
    /* for the record: the fixture's grid against the exact distance */
    for (double z = 40.5; z <= 43.01; z += 0.5) {
        const double q[3] = {-12, 30, z};
        double exact = fmin(sqrt(25 + (48 - z) * (48 - z)), sqrt(64 + (z - 40) * (z - 40)));
        printf("clamp fixture on the bolt's axis at z = %.2f: grid %.4f, exact %.4f\n", z,
               fm_check_fixture_distance(c, q), exact);
    }
    fm_check_free(c);
}

/* A clamp block given as an STL mesh: [-20, -10] x [20, 40] x [0, 20] beside
 * a 100 x 60 x 30 block. The tool comes down at x = -30 (its side at -27,
 * clear) to Z15 and rapids to x = -5 (its side at -8 and -2, between the
 * clamp and the stock) through the clamp: line 5. The deepest point of the
 * tool in the clamp is its tip face over the clamp's middle (x = -15, y =
 * 30), 5 mm from the clamp's top and from its ends (D = 5). The same block
 * without its top face is no solid: before the closedness check it became
 * its band's shell and the rapid met only that; now the fixture is refused
 * where its open edges are. */
static void test_fixture_stl(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {100, 60, 30};
    const double clo[3] = {-20, 20, 0}, chi[3] = {-10, 40, 20};
    const char *prog = "G21 G90\nG0 Z60\nG0 X-30 Y30\nG0 Z15\nG0 X-5\nG0 Z60\n";
    char path[64];
    snprintf(path, sizeof path, "/tmp/fm-check-clamp-%d.stl", (int)getpid());
    CHECK(fm_test_write_box_stl(path, clo, chi, FM_TEST_BOX_NO_FACE) == 0);
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 60;
    fm_check *c = check_program(prog, lo, hi, flat_tool(20, 40, 1), &opt, path);
    if (c) {
        one_fixture_contact(c, 5, 5);
        fm_check_free(c);
    }
    CHECK(fm_test_write_box_stl(path, clo, chi, FM_TEST_BOX_TOP) == 0);
    fm_check_options_default(&opt);
    fm_error err;
    fm_error_clear(&err);
    c = fm_check_new(&opt, &err);
    CHECK(c != NULL);
    if (c) {
        CHECK(fm_check_add_fixture_stl(c, path, voxel, &err) == FM_ERR_INPUT);
        CHECK_STR_CONTAINS(err.message, "the STL fixture");
        CHECK_STR_CONTAINS(err.message, "is not a closed surface: 4 of its edges");
        /* the first open edge is in the y = lo face's second triangle, the
         * fourth written, whose facet starts on line 2 + 7 * 3 */
        CHECK(err.line == 23);
        printf("refusal: %s\n", err.message);
        CHECK(fm_check_fixture_count(c) == 0);
        fm_check_free(c);
    }
    remove(path);
}

/* Start inside the stock: the default start is the machine origin, here
 * the middle of a 20 mm block. The flutes' tip is 10 mm from every face
 * there (D = 10); the voxel centres of the flutes nearest it (+-0.25 in x
 * and y, z = 0.25) lie 9.75 from the faces, those below the tip (z =
 * -0.25) 9.75 deep but 0.25 from the part (Q = 9.5): the depth is
 * searched beyond the band, exact for faces along grid planes, 9.75. */
static void test_start_in_stock(void)
{
    const double lo[3] = {-10, -10, -10}, hi[3] = {10, 10, 10};
    const char *prog = "G21 G90\nG0 Z30\n";
    fm_check *c = check_program(prog, lo, hi, flat_tool(20, 40, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) >= 1);
    const fm_check_finding *f = fm_check_get(c, 0);
    if (f) {
        CHECK(f->kind == FM_CHECK_START_IN_STOCK);
        CHECK(f->line == 0);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK_NEAR(f->penetration_mm, 9.75, grid_exact);
    }
    fm_check_free(c);
}

/* A feed into the stock with the spindle stopped, a plunge with a tool
 * that cannot cut at its centre, and a move beyond the Z travel. The
 * plunge goes 3 mm into the top: the flutes' bottom face, 3.0. */
static void test_spindle_plunge_travel(void)
{
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.has_limit[2] = 1;
    opt.machine.limit_lo[2] = -50;
    opt.machine.limit_hi[2] = 40;
    opt.machine.start[2] = 10;
    const char *prog = "G21 G90\nG0 Z10\nG0 X25 Y25\nG1 Z-3 F100\nG0 Z50\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 0), &opt, NULL);
    if (!c) return;
    dump(c);
    int spindle = 0, plunge = 0, travel = 0;
    for (size_t i = 0; i < fm_check_count(c); i++) {
        const fm_check_finding *f = fm_check_get(c, i);
        if (f->kind == FM_CHECK_SPINDLE_OFF_CUT && f->line == 4) {
            spindle++;
            CHECK_NEAR(f->penetration_mm, 3.0, grid_exact);
        }
        if (f->kind == FM_CHECK_NON_CENTER_PLUNGE && f->line == 4) {
            plunge++;
            CHECK_NEAR(f->penetration_mm, 3.0, grid_exact);
            CHECK_NEAR(f->position[2], 0.0, 0.01);
        }
        if (f->kind == FM_CHECK_TRAVEL_LIMIT && f->line == 5) {
            travel++;
            CHECK_NEAR(f->penetration_mm, 10.0, 1e-9);
        }
    }
    CHECK(spindle == 1);
    CHECK(plunge == 1);
    CHECK(travel == 1);
    CHECK(fm_check_count(c) == 3);
    fm_check_free(c);
}

/* Rotary travel (issue 17): A carries the table about X, limits [-30, 90]
 * degrees. Line 3 turns A to 60 (inside), line 4 from 60 to 120 (30 over),
 * line 5 from 120 to -45 (30 over at its start, 15 at its end): one
 * finding from line 4 to line 5, 30 degrees over. The tool stays at Z100,
 * beyond the block's reach from X (sqrt(50^2 + 20^2) = 53.9 mm). A second
 * run with the axis wrapped: no travel to leave, no finding. */
static void test_rotary_travel(void)
{
    for (int wrapped = 0; wrapped <= 1; wrapped++) {
        fm_check_options opt;
        fm_check_options_default(&opt);
        opt.machine.start[2] = 100;
        fm_rotary_axis *a = &opt.machine.chain.rotary[0];
        opt.machine.chain.rotary_count = 1;
        a->letter = 0;
        a->carries = FM_ROTARY_TABLE;
        a->around[0] = 1;
        a->has_limits = 1;
        a->limit_lo = -30;
        a->limit_hi = 90;
        a->wrapped = wrapped;
        const char *prog = "G21 G90\nG0 Z100\nG0 A60\nG0 A120\nG0 A-45\n";
        fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), &opt, NULL);
        if (!c) return;
        dump(c);
        if (wrapped) {
            CHECK(fm_check_count(c) == 0);
        } else {
            CHECK(fm_check_count(c) == 1);
            const fm_check_finding *f = fm_check_count(c) ? fm_check_get(c, 0) : NULL;
            if (f) {
                CHECK(f->kind == FM_CHECK_TRAVEL_LIMIT);
                CHECK(f->line == 4);
                CHECK(f->last_line == 5);
                CHECK(f->motions == 2);
                CHECK_NEAR(f->penetration_mm, 30.0, 1e-9);
            }
        }
        fm_check_free(c);
    }
}

/* A table axis driven by letter (0 = A) about the coordinate axis dir
 * through the origin, appended to the chain. */
static void add_table_axis(fm_machine *m, int letter, int dir)
{
    fm_rotary_axis *ax = &m->rotary[m->rotary_count++];
    ax->letter = letter;
    ax->carries = FM_ROTARY_TABLE;
    ax->around[dir] = 1;
}

/* The machine's only component: a model under tests/ on a link frame_up
 * table axes below the workpiece's. */
static void one_component(fm_check_options *opt, const char *path, int frame_up)
{
    opt->machine.component_count = 1;
    snprintf(opt->machine.component_path[0], sizeof opt->machine.component_path[0], "%s", path);
    opt->machine.component_frame_up[0] = frame_up;
}

/* Machine contact on an AC trunnion (issue 17): A carries the table about
 * X, C the platter about Z (both through the origin), TCP on. The platter
 * (check/platter.hf, a machine component on C's link) is a disc of radius
 * 80, z -30..-10; the 40 x 40 x 20 block sits on it (z -10..10). The tool:
 * flutes 0..20, shank to 40 (radius 3), a 40 mm holder 30 mm long above.
 * Line 3 turns A to 90 with the tip held at (0, 0, 150): the table turns
 * +90 degrees about X, so in the workpiece frame the tool axis is
 * R_x(-90) z = +Y. Line 4 moves the tip to Y25 (5 mm off the block's
 * face y = 20, the tool pointing away from it), line 5 lowers it to Z2:
 * the holder (x -20..20, y 65..95, z 2 +- 20) then goes 8 mm below the
 * platter's top at its deepest (z = -18: 8 to the top, 12 to the bottom,
 * at least 15 to the rim where y <= 65); the flutes and shank stay 9 mm
 * above it (lowest z = 2 - 3) and 5 mm off the block. One finding:
 * machine_contact of the holder at line 5, 8 mm deep: the holder's lowest
 * line (x = 0, z = -18) is a row of the platter's voxel centres (x = 0.5
 * i, z = 0.5 k), so the depth is exact. */
static void test_machine_contact(void)
{
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 150;
    fm_machine *m = &opt.machine.chain;
    m->tcp = 1;
    add_table_axis(m, 0, 0);
    add_table_axis(m, 2, 2);
    one_component(&opt, "check/platter.hf", 0);
    fm_tool_spec tool = flat_tool(20, 40, 1);
    tool.holder[0] = (fm_holder_segment){40, 40, 30};
    const double lo[3] = {-20, -20, -10}, hi[3] = {20, 20, 10};
    const char *prog = "G21 G90\nG0 Z150\nG0 A90\nG0 Y25\nG0 Z2\n";
    fm_check *c = check_program(prog, lo, hi, tool, &opt, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 1);
    const fm_check_finding *f = fm_check_count(c) ? fm_check_get(c, 0) : NULL;
    if (f) {
        CHECK(f->kind == FM_CHECK_MACHINE_CONTACT);
        CHECK(f->part == FM_CHECK_PART_HOLDER);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK(f->line == 5);
        CHECK(f->fixture == 0);
        CHECK_NEAR(f->penetration_mm, 8.0, grid_exact);
    }
    fm_check_free(c);
}

/* Machine components on links that move against the workpiece (issue
 * 17), each with a second move where the component, wrongly placed in the
 * workpiece frame, would be met and is not.
 *  - A 4-axis indexer: A turns the workpiece about X (through the origin);
 *    the headstock housing (check/headstock.hf: x -30..-5, y -8..8,
 *    z -60..15) stands on the machine table. No TCP: X Y Z are the
 *    machine's. With A at 90, line 5 lowers the tip at X-15 Y0 to Z12: the
 *    flutes' bottom goes 3 mm into the housing's top (10 mm from its x
 *    faces, 5 from its y faces for the flutes' rim): machine_contact of
 *    the flutes at line 5, 3 mm deep (the flutes' bottom face z = 12 is a
 *    plane of the housing's voxel centres: exact). In the workpiece frame the tool
 *    then points along R_x(-90) z = +Y from (-15, 12, 0) (x_w = (x, z,
 *    -y)), first touching at (-15, 15, 0) from (x, 15, -y) of a point of
 *    the housing's top. Line 8 lowers the tip at Y30 to Z0: 19 mm off the
 *    housing's y face, clear; in the workpiece frame the housing would
 *    hold the tool (from (-15, 0, -30) along +Y).
 *  - An AC trunnion with TCP: C turns the platter (and the workpiece)
 *    about Z on A's cradle, whose side wall (check/cradle_wall.hf:
 *    x 80..100) turns with A only. The tip stands at (0, 85, 5) in the
 *    workpiece frame; line 4 turns C to -75, which carries that point to
 *    R_z(C) (0, 85) = (85 sin|C|, 85 cos|C|) in the cradle's frame (A at
 *    0): the flutes (radius 3) reach the wall's face x = 80 when
 *    85 sin|C| + 3 = 80, at the point (80, 85 cos|C|) of the cradle's
 *    frame, R_z(|C|) of it in the workpiece frame, and end
 *    85 sin 75 + 3 - 80 = 5.1037 mm deep, as does the shank above them
 *    (z 25..45; the wall's top is at z 40). The deepest points are the
 *    round side's line x = 85 sin 75 + 3, y = 85 cos 75 = 21.9996: the
 *    wall's voxel centre just beyond it (x = 85.5, y = 22) is Q = 5.5 -
 *    (hypot(3.3963, 0.0004) - 3) deep, the depth to 1e-7, and e <= h/2
 *    would bound it by e^2 / 2r = 0.0104 below. */
static void test_machine_moving_link(void)
{
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 100;
    fm_machine *m = &opt.machine.chain;
    add_table_axis(m, 0, 0);
    one_component(&opt, "check/headstock.hf", 1);
    const double lo[3] = {0, -10, -10}, hi[3] = {40, 10, 10};
    const char *prog = "G21 G90\nG0 Z100\nG0 A90\nG0 X-15 Y0\nG0 Z12\nG0 Z100\nG0 Y30\nG0 Z0\nG0 Z100\n";
    fm_check *c = check_program(prog, lo, hi, flat_tool(20, 40, 1), &opt, NULL);
    if (c) {
        dump(c);
        CHECK(fm_check_count(c) == 1);
        const fm_check_finding *f = fm_check_count(c) ? fm_check_get(c, 0) : NULL;
        if (f) {
            CHECK(f->kind == FM_CHECK_MACHINE_CONTACT);
            CHECK(f->part == FM_CHECK_PART_FLUTES);
            /* the flutes leave the housing during line 6 */
            CHECK(f->line == 5 && f->last_line == 6);
            CHECK(f->fixture == 0);
            CHECK_NEAR(f->penetration_mm, 3.0, grid_exact);
            /* where the tip first touches, in the workpiece frame */
            CHECK_NEAR(f->position[0], -15, 1e-9);
            CHECK_NEAR(f->position[1], 15, voxel);
            CHECK_NEAR(f->position[2], 0, 1e-9);
            CHECK_NEAR(f->contact[1], 15, voxel);
            CHECK(f->contact[0] >= -18 - voxel && f->contact[0] <= -12 + voxel);
            CHECK(fabs(f->contact[2]) <= 3 + voxel);
        }
        fm_check_free(c);
    }

    fm_check_options_default(&opt);
    opt.machine.start[2] = 150;
    m->tcp = 1;
    add_table_axis(m, 0, 0);
    add_table_axis(m, 2, 2);
    one_component(&opt, "check/cradle_wall.hf", 1);
    const double blo[3] = {-20, -20, -10}, bhi[3] = {20, 20, 10};
    const char *prog2 = "G21 G90\nG0 Z150\nG0 X0 Y85 Z5\nG0 C-75\nG0 Z150\n";
    const double deep = 85 * sin(75 * FM_PI / 180) + 3 - 80;
    c = check_program(prog2, blo, bhi, flat_tool(20, 40, 1), &opt, NULL);
    if (c) {
        dump(c);
        /* the flutes and the shank above them, each 5.10 mm deep, until
         * line 5 lifts them out */
        CHECK(fm_check_count(c) == 2);
        const fm_check_finding *sh = fm_check_count(c) == 2 ? fm_check_get(c, 1) : NULL;
        if (sh) {
            CHECK(sh->kind == FM_CHECK_MACHINE_CONTACT && sh->part == FM_CHECK_PART_SHANK);
            CHECK(sh->line == 4 && sh->last_line == 5);
            CHECK_NEAR(sh->penetration_mm, deep, grid_exact);
        }
        const fm_check_finding *f = fm_check_count(c) ? fm_check_get(c, 0) : NULL;
        if (f) {
            CHECK(f->kind == FM_CHECK_MACHINE_CONTACT);
            CHECK(f->part == FM_CHECK_PART_FLUTES);
            CHECK(f->line == 4 && f->last_line == 5);
            CHECK_NEAR(f->penetration_mm, deep, grid_exact);
            CHECK_NEAR(f->position[0], 0, 1e-9);
            CHECK_NEAR(f->position[1], 85, 1e-9);
            CHECK_NEAR(f->position[2], 5, 1e-9);
            double th = asin(77.0 / 85.0), px = 80, py = 85 * cos(th);
            double want[2] = {px * cos(th) - py * sin(th), px * sin(th) + py * cos(th)};
            printf("trunnion cradle: first contact (%.3f, %.3f), written out (%.3f, %.3f)\n", f->contact[0],
                   f->contact[1], want[0], want[1]);
            CHECK_NEAR(f->contact[0], want[0], 2 * voxel);
            CHECK_NEAR(f->contact[1], want[1], 2 * voxel);
            CHECK(f->contact[2] >= 5 - voxel && f->contact[2] <= 25 + voxel);
        }
        fm_check_free(c);
    }
    /* The same wall on the platter's link (it would turn with the
     * workpiece): never met. */
    opt.machine.component_frame_up[0] = 0;
    c = check_program(prog2, blo, bhi, flat_tool(20, 40, 1), &opt, NULL);
    if (c) {
        dump(c);
        CHECK(fm_check_count(c) == 0);
        fm_check_free(c);
    }
}

/* The machine's head (its round parts above the holder: a spindle nose
 * 100 mm across, 50 mm tall, stacked on the holder's top 70 mm above the
 * tip) meets the 50 x 50 x 20 block as the tool goes down beside it: the
 * tool at X-15 Y25 (flutes and shank x -18..-12, holder -25..-5: clear of
 * the block's face x = 0) down to Z-80. The head reaches the block's top
 * when the tip is at Z-70 and ends with its bottom face at z = -10, where
 * the points over x 10..35 lie 10 mm below the top and 10 above the bottom
 * (D = 10, a ridge across z midway between the centres z = -9.75 and
 * -10.25: 9.75 inside the head, 9.75 - 0.25 below it): one
 * machine_contact of the head at line 3, 9.75 mm deep, first where it
 * comes within its clearance (1 mm: the tip at Z-69, the block's top 1 mm
 * below the head). Without the head, nothing. */
static void test_machine_head(void)
{
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 20;
    opt.machine.head_count = 1;
    opt.machine.head[0] = (fm_holder_segment){100, 0, 50};
    const char *prog = "G21 G90\nG0 X-15 Y25 Z10\nG0 Z-80\nG0 Z10\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), &opt, NULL);
    if (c) {
        dump(c);
        CHECK(fm_check_count(c) == 1);
        const fm_check_finding *f = fm_check_count(c) ? fm_check_get(c, 0) : NULL;
        if (f) {
            CHECK(f->kind == FM_CHECK_MACHINE_CONTACT);
            CHECK(f->part == FM_CHECK_PART_HEAD);
            CHECK(f->fixture == -1);
            CHECK(f->line == 3 && f->last_line == 4);
            CHECK(f->severity == FM_CHECK_ERROR);
            CHECK_NEAR(f->penetration_mm, 9.75, grid_exact);
            CHECK_NEAR(f->position[0], -15, 1e-9);
            double clear = opt.clearance_mm[FM_CHECK_PART_HEAD];
            CHECK_NEAR(f->position[2], -70 + clear, voxel);
            CHECK_NEAR(f->contact[2], clear, voxel);
        }
        fm_check_free(c);
    }
    opt.machine.head_count = 0;
    c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), &opt, NULL);
    if (c) {
        CHECK(fm_check_count(c) == 0);
        fm_check_free(c);
    }
}

/* A rapid diving across the block (a line neither level nor along the
 * axis: lib/sweep's concave search) with the sweeps' searches allowed one
 * evaluation per point: they stop before their proofs close, and the
 * points where that leaves the answer open are counted in an uncertain
 * warning at that line, not passed over in silence (nor reported as
 * contacts). With lib/sweep's own budget there is none. (Two evaluations
 * were enough to starve it until a flat end mill's ramp got its guessed
 * maximum, which two evaluations prove: docs/sweep.md, CONCAVE.) */
static void test_uncertain(void)
{
    const char *prog = "G21 G90\nG0 Z10\nG0 X-10 Y25\nG0 X40 Z-5\nG0 Z10\n";
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.sweep_evaluations = 1;
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), &opt, NULL);
    if (!c) return;
    dump(c);
    const fm_check_finding *f = find_kind(c, FM_CHECK_UNCERTAIN);
    CHECK(f != NULL);
    if (f) {
        CHECK(f->severity == FM_CHECK_WARNING);
        CHECK(f->line == 4);
        CHECK(f->points > 0);
        CHECK(f->penetration_mm == 0);
    }
    fm_check_free(c);
    c = check_program(prog, box_lo, box_hi, flat_tool(20, 40, 1), NULL, NULL);
    if (!c) return;
    CHECK(find_kind(c, FM_CHECK_UNCERTAIN) == NULL);
    CHECK(find_kind(c, FM_CHECK_RAPID_INTO_STOCK) != NULL);
    fm_check_free(c);
}

/* G38.x stops at a fixture as it does at the stock (daemon/runner/
 * probe.c with fm_check_fixture_distance). tests/check/jaw_scaled.hf is a
 * block x 60..80, y 0..50, z -20..10 whose function is a tenth of the
 * distance; the stock is x 0..50, z -20..0. The jaw's faces are planes,
 * which its grid holds exactly (a linear field's zero set, distances to a
 * plane interpolated), so the probe's 1e-6 mm bisection leaves the
 * expected values to well within 0.01 mm. Results are read back from the
 * last rapid's end, whose coordinates the program sets from #5061-#5070.
 *  - Down: G38.2 from Z20 at X70 Y25; the 6 mm flat end mill's bottom
 *    (x 67..73, inside the jaw's top face) meets the top at Z10. Without
 *    the fixture nothing is under the tool: a G38.2 error.
 *  - Sideways: G38.3 at Z5 (5 above the stock, inside the jaw's height)
 *    from X40 toward X100 along Y25; the tool's side (radius 3) meets the
 *    face x = 60 with the tip at X57, #5070 = 1. Without the fixture the
 *    probe reaches X100 and #5070 = 0 (G38.3: no error). */
static void record_motion(void *user, const fm_motion *m) { *(fm_motion *)user = *m; }

static fm_status probe_run(const char *prog, int with_fixture, fm_motion *last, fm_check **out,
                           fm_error *err)
{
    fm_tool_spec tool = flat_tool(20, 40, 1);
    fm_tool_table table = {1, &tool};
    fm_job_check check;
    fm_job_check_default(&check);
    check.options.machine.start[2] = 20;
    if (with_fixture) {
        check.fixtures[0] = "check/jaw_scaled.hf";
        check.fixture_count = 1;
    }
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = prog;
    spec.program_length = strlen(prog);
    spec.program_name = "probe.ngc";
    spec.stock_spec = "box:0,0,-20,50,50,0";
    spec.tools = &table;
    spec.stock.voxel_mm = 0.5;
    spec.stock.band_voxels = fm_check_band_voxels(&check.options, 0.5);
    spec.check = &check;
    memset(last, 0, sizeof *last);
    fm_job_hooks hooks = {.user = last, .on_motion = record_motion};
    fm_job_result res;
    fm_error_clear(err);
    *out = NULL;
    fm_status st = fm_job_run(&spec, &hooks, &res, err);
    if (st != FM_OK) return st;
    fm_stock_free(res.stock);
    *out = res.check;
    return FM_OK;
}

static void test_probe_fixture(void)
{
    const char *down = "G21 G90\nG0 Z20\nG0 X70 Y25\nG38.2 Z-15 F100\nG0 Z20\nG0 X[#5063]\nM2\n";
    const char *side = "G21 G90\nG0 Z20\nG0 X40 Y25\nG0 Z5\nG38.3 X100 F100\nG0 Z20\n"
                       "G0 X[#5061] Y[#5070 * 10]\nM2\n";
    fm_motion last;
    fm_check *c = NULL;
    fm_error err;
    fm_status st = probe_run(down, 1, &last, &c, &err);
    if (st != FM_OK) fprintf(stderr, "job: %s\n", err.message);
    CHECK(st == FM_OK);
    if (st == FM_OK) {
        fprintf(stderr, "  probing down found Z %.6f\n", last.end[0]);
        CHECK_NEAR(last.end[0], 10.0, 0.01);
        dump(c);
        /* stopped at the surface: not into the jaw */
        CHECK(fm_check_count_severity(c, FM_CHECK_ERROR) == 0);
        fm_check_free(c);
    }
    st = probe_run(down, 0, &last, &c, &err);
    fprintf(stderr, "  without the fixture: %s\n", st == FM_OK ? "ok" : err.message);
    CHECK(st != FM_OK);
    fm_check_free(c);

    st = probe_run(side, 1, &last, &c, &err);
    if (st != FM_OK) fprintf(stderr, "job: %s\n", err.message);
    CHECK(st == FM_OK);
    if (st == FM_OK) {
        fprintf(stderr, "  probing sideways found X %.6f (#5070 %g)\n", last.end[0],
                last.end[1] / 10);
        CHECK_NEAR(last.end[0], 57.0, 0.01);
        CHECK_NEAR(last.end[1], 10.0, 1e-9);
        CHECK(fm_check_count_severity(c, FM_CHECK_ERROR) == 0);
        fm_check_free(c);
    }
    st = probe_run(side, 0, &last, &c, &err);
    CHECK(st == FM_OK);
    if (st == FM_OK) {
        fprintf(stderr, "  without the fixture: X %.6f (#5070 %g)\n", last.end[0],
                last.end[1] / 10);
        CHECK_NEAR(last.end[0], 100.0, 1e-9);
        CHECK_NEAR(last.end[1], 0.0, 1e-9);
        fm_check_free(c);
    }
}

/* Arguments name the cases to run (all by default): valgrind runs the
 * quick ones. */
static int wanted(int argc, char **argv, const char *name)
{
    if (argc < 2) return 1;
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], name)) return 1;
    return 0;
}

/* No tool in the spindle (issue 34): a table of two tools and no M6, so no
 * tool cuts. Line 5 plunges from Z5 to Z-2 at (10, 20), line 6 goes on at
 * Z-2, line 7 climbs out: one no_tool error over lines 5-7, 3 motions,
 * whose tip enters the top at (10, 20, 0) (the first sample inside lies
 * within the samples' spacing, a quarter of the 0.5 mm voxel, below it),
 * read as the band's depth (1.5 mm: the tip goes 2 mm deep, beyond the
 * band of 3 voxels); the job's no-tool warning: line 5, 3 motions. Line 8
 * feeds in the air: nothing. With tool 1 in the spindle at the start (the
 * spec's initial_tool) the same program is clean. */
static void test_no_tool(void)
{
    fm_tool_spec two[2] = {flat_tool(20, 40, 1), flat_tool(20, 40, 1)};
    two[1].number = 2;
    fm_tool_table table = {2, two};
    const char *prog =
        "G21 G90\nM3 S1000\nG0 Z5\nG0 X10 Y20\nG1 Z-2 F300\nG1 X30\nG1 Z5\nG1 X40\n";
    fm_job_check check;
    fm_job_check_default(&check);
    for (int with_tool = 0; with_tool < 2; with_tool++) {
        fm_job_spec spec;
        fm_job_spec_default(&spec);
        spec.program_text = prog;
        spec.program_length = strlen(prog);
        spec.program_name = "no_tool.ngc";
        spec.stock_spec = "box:0,0,-20,50,50,0";
        spec.tools = &table;
        spec.stock.voxel_mm = 0.5;
        spec.stock.band_voxels = fm_check_band_voxels(&check.options, 0.5);
        spec.check = &check;
        spec.initial_tool = with_tool;
        fm_job_result res;
        fm_error err;
        fm_status st = fm_job_run(&spec, NULL, &res, &err);
        CHECK(st == FM_OK);
        if (st != FM_OK) continue;
        dump(res.check);
        if (with_tool) {
            CHECK(fm_check_count(res.check) == 0);
            CHECK(res.no_tool_motions == 0);
            CHECK(res.removed_volume_mm3 > 0);
        } else {
            CHECK(fm_check_count(res.check) == 1);
            const fm_check_finding *f = fm_check_get(res.check, 0);
            if (f) {
                CHECK(f->kind == FM_CHECK_NO_TOOL);
                CHECK(!strcmp(fm_check_kind_name(f->kind), "no_tool"));
                CHECK(f->severity == FM_CHECK_ERROR);
                CHECK(f->part == FM_CHECK_PART_HEAD);
                CHECK(f->line == 5 && f->last_line == 7 && f->motions == 3);
                CHECK_NEAR(f->position[0], 10, 1e-9);
                CHECK_NEAR(f->position[1], 20, 1e-9);
                CHECK(f->position[2] <= 0 && f->position[2] >= -0.25);
                CHECK_NEAR(f->penetration_mm, 1.5, 1e-6);
            }
            CHECK(res.no_tool_line == 5 && res.no_tool_motions == 3);
            CHECK(res.removed_volume_mm3 == 0);
        }
        fm_stock_free(res.stock);
        fm_check_free(res.check);
    }
}

int main(int argc, char **argv)
{
    if (wanted(argc, argv, "rapid_through")) test_rapid_through();
    if (wanted(argc, argv, "rapid_over")) test_rapid_over();
    if (wanted(argc, argv, "plunge_shank")) test_plunge_then_shank();
    if (wanted(argc, argv, "plunge_shank_between")) test_plunge_then_shank_between();
    if (wanted(argc, argv, "holder_face")) test_holder_face();
    if (wanted(argc, argv, "fixture_scaled")) test_fixture_scaled();
    if (wanted(argc, argv, "fixture")) test_fixture_clamp();
    if (wanted(argc, argv, "fixture_stl")) test_fixture_stl();
    if (wanted(argc, argv, "start")) test_start_in_stock();
    if (wanted(argc, argv, "spindle_plunge_travel")) test_spindle_plunge_travel();
    if (wanted(argc, argv, "rotary_travel")) test_rotary_travel();
    if (wanted(argc, argv, "machine_contact")) test_machine_contact();
    if (wanted(argc, argv, "machine_moving_link")) test_machine_moving_link();
    if (wanted(argc, argv, "machine_head")) test_machine_head();
    if (wanted(argc, argv, "uncertain")) test_uncertain();
    if (wanted(argc, argv, "probe_fixture")) test_probe_fixture();
    if (wanted(argc, argv, "no_tool")) test_no_tool();
    fprintf(stderr, "%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures != 0;
}
