/* test_check.c: lib/check on programs built for the purpose, run through
 * the job runner as `frepmill check` runs them (0.5 mm voxels, the check's
 * default). Every expected value is worked out by hand from the geometry
 * in the comments, never taken from the check's own output. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "job.h"
#include "test.h"

typedef struct run {
    fm_check *check;
    fm_status status;
    fm_error err;
} run;

static int before_motion(void *user, const fm_motion *m, const fm_tool *tool, fm_stock *stock)
{
    run *r = user;
    r->status = fm_check_motion(r->check, m, tool, stock, &r->err);
    return r->status != FM_OK;
}

/* A 6 mm flat end mill: flutes 0..flute, shank up to length, a 20 mm
 * holder 30 mm long above it. */
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

/* Run program against a box stock; returns the check (caller frees). */
static fm_check *check_program(const char *program, const double lo[3], const double hi[3],
                               fm_tool_spec tool, const fm_check_options *opt,
                               const char *fixture)
{
    fm_tool_table table = {1, &tool};
    fm_error err;
    fm_error_clear(&err);
    run r = {0};
    r.check = fm_check_new(opt, &err);
    CHECK(r.check != NULL);
    if (!r.check) return NULL;
    fm_check_set_initial_box(r.check, lo, hi);
    if (fixture) CHECK(fm_check_add_fixture_hf(r.check, fixture, NULL, &err) == FM_OK);
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
    spec.stock.band_voxels = 4;
    fm_job_hooks hooks = {.user = &r, .before_motion = before_motion};
    fm_job_result res;
    fm_status st = fm_job_run(&spec, &hooks, &res, &err);
    if (st != FM_OK) fprintf(stderr, "job: %s\n", err.message);
    CHECK(st == FM_OK);
    CHECK(r.status == FM_OK);
    if (st == FM_OK) fm_stock_free(res.stock);
    fm_check_finish(r.check);
    return r.check;
}

static void dump(const fm_check *c)
{
    for (size_t i = 0; i < fm_check_count(c); i++) {
        const fm_check_finding *f = fm_check_get(c, i);
        fprintf(stderr, "  finding: %s %s %s line %d pen %.4f pos (%.3f %.3f %.3f) contact (%.3f %.3f %.3f)\n",
                fm_check_kind_name(f->kind), fm_check_severity_name(f->severity),
                fm_check_part_name(f->part), f->line, f->penetration_mm, f->position[0],
                f->position[1], f->position[2], f->contact[0], f->contact[1], f->contact[2]);
    }
}

static const double box_lo[3] = {0, 0, -20}, box_hi[3] = {50, 50, 0};

/* A rapid at Z-5 through a 50 mm block along y = 25. The deepest point of
 * min(S, F): S = min(z + 5, 3 - |y - 25|) near the tool's bottom, F =
 * -z near the top: at y = 25, min(z + 5, -z) is largest at z = -2.5:
 * 2.5 mm. The tool (radius 3) first touches the face x = 0 with its tip at
 * x = -3. */
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
        CHECK_NEAR(f->penetration_mm, 2.5, 0.5);
        CHECK_NEAR(f->position[0], -3.0, 0.3);
        CHECK_NEAR(f->position[2], -5.0, 1e-9);
        CHECK_NEAR(f->contact[0], 0.0, 0.3);
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

/* Plunge a tool with 10 mm flutes to Z-14 in the middle of the block. The
 * shank (z from tip + 10 to tip + 15, radius 3) sweeps z in [-4, 20]; its
 * depth on the axis is z + 4, the stock's is -z: the maximum of min is at
 * z = -2, 2 mm. It first touches the top face when the tip is at -10
 * (line 5). */
static void test_deep_pocket_shank(void)
{
    const char *prog = "G21 G90\nS1000 M3\nG0 Z5\nG0 X25 Y25\nG1 Z-14 F100\nG0 Z30\n";
    fm_check *c = check_program(prog, box_lo, box_hi, flat_tool(10, 15, 1), NULL, NULL);
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) >= 1);
    const fm_check_finding *f = fm_check_get(c, 0);
    if (f) {
        CHECK(f->kind == FM_CHECK_SHANK_CONTACT);
        CHECK(f->part == FM_CHECK_PART_SHANK);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK(f->line == 5);
        CHECK_NEAR(f->penetration_mm, 2.0, 0.5);
        CHECK_NEAR(f->position[2], -10.0, 0.1);
        CHECK_NEAR(f->contact[2], 0.0, 0.1);
    }
    fm_check_free(c);
}

/* examples/clamp.hf holds the 100 x 60 x 30 cast stock; a rapid at Z35
 * along y = 30 crosses the strap (z 30..40), the bolt (radius 5 to z 52)
 * and the nut (radius 9, z 40..48) at x = -12. The flutes (radius 3, z 35
 * to 55) reach 3 mm deep at most (their own half width), and the clamp is
 * at least 3 mm deep all along the bolt's axis for z in [38, 49]: 3 mm. */
static void test_fixture_clamp(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {100, 60, 30};
    const char *prog = "G21 G90\nG0 Z60\nG0 X-60 Y30\nG0 Z35\nG0 X50\nG0 Z60\n";
    FILE *probe = fopen("../examples/clamp.hf", "r");
    if (!probe) {
        fprintf(stderr, "examples/clamp.hf is absent: fixture test skipped\n");
        return;
    }
    fclose(probe);
    /* the machine origin is the stock's corner: start above it */
    fm_check_options opt;
    fm_check_options_default(&opt);
    opt.machine.start[2] = 60;
    fm_check *c = check_program(prog, lo, hi, flat_tool(20, 40, 1), &opt, "../examples/clamp.hf");
    if (!c) return;
    dump(c);
    CHECK(fm_check_count(c) == 1);
    const fm_check_finding *f = fm_check_get(c, 0);
    if (f) {
        CHECK(f->kind == FM_CHECK_FIXTURE_CONTACT);
        CHECK(f->part == FM_CHECK_PART_FLUTES);
        CHECK(f->severity == FM_CHECK_ERROR);
        CHECK(f->line == 5);
        CHECK(f->fixture == 0);
        CHECK_NEAR(f->penetration_mm, 3.0, 0.5);
        /* the strap's far end is x = -35: the tool's edge gets there first */
        CHECK_NEAR(f->position[0], -38.0, 0.3);
    }
    fm_check_free(c);
}

/* Start inside the stock: the default start is the machine origin, here
 * the middle of a block. */
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
        /* the flat tool at the origin: depth z (from its bottom), radius 3,
         * the block's top is 10 above: max of min(z, 3 - r, 10 - z) = 3 */
        CHECK_NEAR(f->penetration_mm, 3.0, 0.5);
    }
    fm_check_free(c);
}

/* A feed into the stock with the spindle stopped, a plunge with a tool
 * that cannot cut at its centre, and a move beyond the Z travel. */
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
        if (f->kind == FM_CHECK_SPINDLE_OFF_CUT && f->line == 4) spindle++;
        if (f->kind == FM_CHECK_NON_CENTER_PLUNGE && f->line == 4) {
            plunge++;
            /* plunged 3 mm into the top: max of min(z + 3, 3 - r, -z) = 1.5 */
            CHECK_NEAR(f->penetration_mm, 1.5, 0.5);
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

/* Arguments name the cases to run (all by default): valgrind runs the
 * quick ones. */
static int wanted(int argc, char **argv, const char *name)
{
    if (argc < 2) return 1;
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], name)) return 1;
    return 0;
}

int main(int argc, char **argv)
{
    if (wanted(argc, argv, "rapid_through")) test_rapid_through();
    if (wanted(argc, argv, "rapid_over")) test_rapid_over();
    if (wanted(argc, argv, "deep_pocket")) test_deep_pocket_shank();
    if (wanted(argc, argv, "fixture")) test_fixture_clamp();
    if (wanted(argc, argv, "start")) test_start_in_stock();
    if (wanted(argc, argv, "spindle_plunge_travel")) test_spindle_plunge_travel();
    fprintf(stderr, "%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures != 0;
}
