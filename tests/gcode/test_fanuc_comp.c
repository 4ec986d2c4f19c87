/* test_fanuc_comp.c: cutter radius compensation (G40/G41/G42 with D) in the
 * Fanuc dialect, end to end through the front end: every expected tool
 * centre point is worked out by hand from Fanuc's type C rules (docs/gcode.md,
 * "Cutter radius compensation (Fanuc)"): the start-up block ends at its
 * programmed end plus the radius perpendicular to the next block; corners
 * with alpha >= 90 degrees on the workpiece side meet where the offset
 * paths cross; the block before G40 ends perpendicular to its own end and the
 * cancel block runs from there to its programmed end; D n is tool n's
 * radius. Positions are machine mm (G54 at 0, no tool length). The
 * engine's corner rules one by one are tests/gcode/test_comp_intersect.c. */
#include <math.h>
#include <string.h>

#include "test.h"
#include "toolpaths/gcode/gcode.h"

#define MAXM 64

static fm_motion got[MAXM];
static int ngot;

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    return 0;
}

/* Tool 1: 10 mm (r = 5); tool 2: 6 mm (r = 3); tool 3: 10 mm with a wear of
 * -0.02 (r = 4.98); tool 4: 6 mm, named by D register 14 (a Fusion library's
 * diameter-offset); tool 5: 10 mm with a radius offset of 4.5 (r = 4.5). */
static fm_tool_spec tool_specs[5];
static fm_tool_table tools = {5, tool_specs};

static fm_gcode_options options(fm_gcode_dialect dialect)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.dialect = dialect;
    o.tools = &tools;
    return o;
}

static fm_status run(const char *text, fm_gcode_dialect dialect, fm_error *err)
{
    fm_gcode_options o = options(dialect);
    ngot = 0;
    return fm_gcode_run_string(text, strlen(text), "comp.nc", &o, collect, NULL, NULL, err);
}

/* Expected: kind (R rapid, L line, A arc), end, and for arcs the centre and
 * turns. */
typedef struct em {
    char kind;
    double x, y, z;
    double cx, cy;
    int turns;
} em;

static void expect(const char *what, const char *text, const em *e, int n)
{
    fm_error err;
    fm_status st = run(text, FM_GCODE_FANUC, &err);
    CHECK(st == FM_OK);
    if (st) {
        char buf[700];
        fprintf(stderr, "  %s: %s\n", what, fm_error_format(&err, buf, sizeof buf));
        return;
    }
    CHECK(ngot == n);
    if (ngot != n) fprintf(stderr, "  %s: %d motions, expected %d\n", what, ngot, n);
    for (int i = 0; i < n && i < ngot; i++) {
        const fm_motion *m = &got[i];
        char k = m->kind == FM_MOTION_RAPID ? 'R' : m->kind == FM_MOTION_LINE ? 'L'
                 : m->kind == FM_MOTION_ARC ? 'A' : 'D';
        int ok = k == e[i].kind && fabs(m->end[0] - e[i].x) < 1e-9 &&
                 fabs(m->end[1] - e[i].y) < 1e-9 && fabs(m->end[2] - e[i].z) < 1e-9;
        if (k == 'A')
            ok = ok && m->turns == e[i].turns && fabs(m->center[0] - e[i].cx) < 1e-9 &&
                 fabs(m->center[1] - e[i].cy) < 1e-9;
        if (i > 0) /* a continuous path */
            ok = ok && fabs(m->start[0] - got[i - 1].end[0]) < 1e-12 &&
                 fabs(m->start[1] - got[i - 1].end[1]) < 1e-12;
        CHECK(ok);
        if (!ok)
            fprintf(stderr, "  %s: motion %d (line %d) is %c %.6f %.6f %.6f c %.6f %.6f t %d, "
                    "expected %c %.6f %.6f %.6f c %.6f %.6f t %d\n", what, i, m->line, k,
                    m->end[0], m->end[1], m->end[2], m->center[0], m->center[1], m->turns,
                    e[i].kind, e[i].x, e[i].y, e[i].z, e[i].cx, e[i].cy, e[i].turns);
    }
}

static void expect_error(const char *text, int line, int column, const char *fragment)
{
    fm_error err;
    fm_status st = run(text, FM_GCODE_FANUC, &err);
    CHECK(st == FM_ERR_INPUT);
    CHECK(err.line == line);
    CHECK(err.column == column);
    CHECK_STR_CONTAINS(err.message, fragment);
    if (err.line != line || err.column != column)
        fprintf(stderr, "  for '%s': got %d:%d %s\n", fragment, err.line, err.column, err.message);
}

/* A 40 x 20 boss (0..40, 0..20), r = 5. G41 clockwise (the tool on the
 * left is outside): the start-up block (-20,0) -> (0,0) ends at (0,0) plus 5
 * to the left of the next block's direction +Y: (-5, 0). Each corner of the
 * boss has alpha = 90 on the workpiece side: the offset lines x = -5, y = 25,
 * x = 45, y = -5 meet at (-5,25), (45,25), (45,-5). The last block (40,0) ->
 * (0,0) runs -X: before G40 it ends 5 to its left, (0,-5); the cancel block
 * goes to (-20,-10). G42 counter-clockwise is the mirror: start-up 5 to the
 * right of +X, (0,-5); corners (45,-5), (45,25), (-5,25); the last block runs
 * -Y and ends 5 to its right, (-5,0). */
static void test_boss(void)
{
    const em left[] = {{'R', -20, 0, 0, 0, 0, 0}, {'L', -20, 0, -5, 0, 0, 0},
                       {'L', -5, 0, -5, 0, 0, 0}, {'L', -5, 25, -5, 0, 0, 0},
                       {'L', 45, 25, -5, 0, 0, 0}, {'L', 45, -5, -5, 0, 0, 0},
                       {'L', 0, -5, -5, 0, 0, 0}, {'L', -20, -10, -5, 0, 0, 0},
                       {'R', -20, -10, 20, 0, 0, 0}};
    expect("G41 boss", "%\nO1000\nG21 G17 G90 G94 G40 G49 G80\nT1 M06\nG00 X-20. Y0 S1000 M03\n"
                       "G01 Z-5. F300.\nG41 D1 X0 Y0\nY20.\nX40.\nY0\nX0\nG40 X-20. Y-10.\n"
                       "G00 Z20.\nM30\n%\n",
           left, 9);
    const em right[] = {{'R', -20, 0, 0, 0, 0, 0}, {'L', -20, 0, -5, 0, 0, 0},
                        {'L', 0, -5, -5, 0, 0, 0}, {'L', 45, -5, -5, 0, 0, 0},
                        {'L', 45, 25, -5, 0, 0, 0}, {'L', -5, 25, -5, 0, 0, 0},
                        {'L', -5, 0, -5, 0, 0, 0}, {'L', -20, -10, -5, 0, 0, 0},
                        {'R', -20, -10, 20, 0, 0, 0}};
    expect("G42 boss", "G21 G17 G90 G94\nT1 M06\nG00 X-20. Y0 S1000 M03\nG01 Z-5. F300.\n"
                       "G42 D1 X0 Y0\nX40.\nY20.\nX0\nY0\nG40 X-20. Y-10.\nG00 Z20.\nM30\n",
           right, 9);
}

/* A 40 x 30 pocket (0..40, 0..30), G41 counter-clockwise (the tool on the
 * left is inside), r = 5. Start-up (20,15) -> (20,0) ends 5 left of the next
 * block's +X: (20,5). Every corner is an inner one (alpha 270): the offset
 * lines y = 5, x = 35, y = 25, x = 5 meet at (35,5), (35,25), (5,25), (5,5).
 * The last block, (0,0) -> (20,0) along +X, ends 5 to its left, (20,5); the
 * cancel block goes back to the centre. */
static void test_pocket(void)
{
    const em e[] = {{'R', 20, 15, 0, 0, 0, 0}, {'L', 20, 15, -5, 0, 0, 0},
                    {'L', 20, 5, -5, 0, 0, 0},  {'L', 35, 5, -5, 0, 0, 0},
                    {'L', 35, 25, -5, 0, 0, 0}, {'L', 5, 25, -5, 0, 0, 0},
                    {'L', 5, 5, -5, 0, 0, 0},   {'L', 20, 5, -5, 0, 0, 0},
                    {'L', 20, 15, -5, 0, 0, 0}};
    expect("G41 pocket", "G21 G17 G90\nT1 M06\nG00 X20. Y15. S1000 M03\nG01 Z-5. F300.\n"
                         "G41 D1 X20. Y0\nX40.\nY30.\nX0\nY0\nX20.\nG40 X20. Y15.\nM30\n",
           e, 9);
}

/* A round boss R 20 about the origin, climb milled clockwise with G41 (the
 * tool outside, on R 25), with a lead-in and a lead-out arc of R 10 about
 * (-30, 0) as Fusion 360's Haas post writes them (counter-clockwise, tangent
 * to the circle at (-20, 0) where both run +Y; the tool is inside them, on R
 * 5). The start-up line (-30,-25) -> (-30,-10) ends perpendicular to the
 * lead-in arc's start, along its radius toward the tool's side: (-30,-5). The
 * lead-in ends at (-25,0), where the circle's offset starts (a tangent
 * junction: nothing added); the full circle about (0,0) on R 25 comes back
 * there; the lead-out arc ends at its offset end (-30,5), which is also the
 * vector perpendicular to its end; the cancel block runs to (-30,25). */
static void test_arcs_lead_in_out(void)
{
    const em e[] = {{'R', -30, -25, 0, 0, 0, 0},   {'L', -30, -25, -5, 0, 0, 0},
                    {'L', -30, -5, -5, 0, 0, 0},   {'A', -25, 0, -5, -30, 0, 1},
                    {'A', -25, 0, -5, 0, 0, -1},   {'A', -30, 5, -5, -30, 0, 1},
                    {'L', -30, 25, -5, 0, 0, 0},   {'R', -30, 25, 20, 0, 0, 0}};
    expect("lead-in, circle, lead-out",
           "G21 G17 G90 G94\nT1 M06\nG00 X-30. Y-25. S2000 M03\nG01 Z-5. F500.\n"
           "G41 D1 G01 X-30. Y-10.\nG03 X-20. Y0 I0 J10.\nG02 X-20. Y0 I20. J0\n"
           "G03 X-30. Y10. I-10. J0\nG40 G01 X-30. Y25.\nG00 Z20.\nM30\n",
           e, 8);
}

/* The control's interference check (Fanuc alarm 041): in a pocket 8 mm wide
 * a tool of radius 5 cannot follow the bottom: from the start-up's end (4,5)
 * the bottom's offset would have to run to the corner point (3,5), against
 * its programmed +X direction. The error names the bottom's block. */
static void test_interference(void)
{
    expect_error("G21 G17 G90\nT1 M06\nG00 X4. Y10.\nG01 Z-1. F100.\nG41 D1 X4. Y0\nX8.\nY20.\n"
                 "X0\nY0\nX4.\nG40 X4. Y10.\nM30\n",
                 6, 1, "reverse");
    /* the start-up block cannot be an arc (Fanuc alarm 034) */
    expect_error("G21 G17 G90\nT1 M06\nG00 X0 Y0\nG41 D1\nG02 X10. Y0 R5. F100.\nM30\n", 5, 1,
                 "cannot start compensation");
    /* what a control refuses while compensating */
    expect_error("G21 G90\nT1 M06\nG41 D1 G01 X10. Y0 F100.\nX20.\nG81 X30. Z-5. R1.\n", 5, 1,
                 "canned cycle with cutter radius compensation on");
    expect_error("G21 G90\nT1 M06\nG41 D1 G01 X10. Y0 F100.\nG28 X0 Y0\n", 4, 1,
                 "reference point return with cutter radius compensation on");
    expect_error("G21 G90\nT1 M06\nG41 D1 G01 X10. Y0 F100.\nT2 M06\n", 4, 4,
                 "tool change (M06) with cutter radius compensation on");
    expect_error("G21 G90\nT1 M06\nG41 D7 G01 X10. Y0 F100.\n", 3, 5,
                 "tool 7 is not in the tool table");
}

/* Compensation started again after G40 with another offset (D2, r = 3): the
 * same boss side twice. */
static void test_second_start(void)
{
    const em e[] = {{'R', -20, 0, 0, 0, 0, 0},  {'L', -20, 0, -5, 0, 0, 0},
                    {'L', -5, 0, -5, 0, 0, 0},  {'L', -5, 20, -5, 0, 0, 0},
                    {'L', -20, 30, -5, 0, 0, 0}, {'L', -20, 0, -5, 0, 0, 0},
                    {'L', -3, 0, -5, 0, 0, 0},  {'L', -3, 20, -5, 0, 0, 0},
                    {'L', -20, 30, -5, 0, 0, 0}};
    /* each pass: start-up (-20,0) -> (0,0) ends r left of +Y, (-r, 0); the
     * side x = 0 up to (0,20) ends r left of its end before G40, (-r, 20) */
    expect("two compensated passes",
           "G21 G17 G90\nT1 M06\nG00 X-20. Y0\nG01 Z-5. F300.\nG41 D1 X0 Y0\nY20.\n"
           "G40 X-20. Y30.\nX-20. Y0\nG41 D2 X0 Y0\nY20.\nG40 X-20. Y30.\nM30\n",
           e, 9);
}

/* The same pocket means the same in both dialects: with its corners all
 * inner ones and a start-up along the first side, LinuxCNC's compensation
 * (rs274's geometry) and Fanuc's type C agree point for point. */
static void test_same_in_both(void)
{
    const char *text = "G21 G17 G90 G94\nT2 M06\nG00 X10. Y0 S1000 M03\nG01 Z-2. F200.\n"
                       "G41 D2 G01 X20. Y0\nX40.\nY30.\nX0\nY0\nX20.\nG40 G01 X20. Y10.\n"
                       "G00 Z20.\nM30\n";
    static fm_motion lin[MAXM];
    fm_error err;
    CHECK(run(text, FM_GCODE_LINUXCNC, &err) == FM_OK);
    int nl = ngot;
    memcpy(lin, got, sizeof lin);
    CHECK(run(text, FM_GCODE_FANUC, &err) == FM_OK);
    CHECK(nl == ngot && nl == 10);
    int bad = 0;
    for (int i = 0; i < nl && i < ngot; i++)
        for (int k = 0; k < 3; k++)
            if (lin[i].kind != got[i].kind || fabs(lin[i].end[k] - got[i].end[k]) > 1e-9 ||
                fabs(lin[i].t1 - got[i].t1) > 1e-9)
                bad++;
    CHECK(bad == 0);
    /* and both are the hand-worked path: the tool (r 3) inside the pocket */
    CHECK_NEAR(got[2].end[0], 20, 1e-9); /* start-up: 3 left of +X */
    CHECK_NEAR(got[2].end[1], 3, 1e-9);
    CHECK_NEAR(got[3].end[0], 37, 1e-9); /* inner corners */
    CHECK_NEAR(got[3].end[1], 3, 1e-9);
    CHECK_NEAR(got[4].end[0], 37, 1e-9);
    CHECK_NEAR(got[4].end[1], 27, 1e-9);
    CHECK_NEAR(got[5].end[0], 3, 1e-9);
    CHECK_NEAR(got[6].end[1], 3, 1e-9);
    CHECK_NEAR(got[7].end[0], 20, 1e-9); /* before G40: 3 left of its end */
    CHECK_NEAR(got[7].end[1], 3, 1e-9);
}

/* A compensated block keeps the feed it was programmed with while it waits
 * for the next block: the start-up and the side after it are programmed in
 * G95 (F0.5 mm/rev at S1000: 500 mm/min) and leave the queue after the next
 * block has switched to G94 F300. Start-up (-20,0) -> (-5,0): 15 mm, 1.8 s;
 * the side (-5,0) -> (-5,25): 25 mm, 3 s; the top (-5,25) -> (45,25) at
 * 300 mm/min: 50 mm, 10 s. */
static void test_feed_modes(void)
{
    fm_error err;
    fm_status st = run("G21 G17 G90\nT1 M06\nS1000 M03\nG00 X-20. Y0\nG01 Z-5. F300.\n"
                       "G95 G41 D1 X0 Y0 F0.5\nY20.\nG94 X40. F300.\nY0\nG40 X60. Y0\nM30\n",
                       FM_GCODE_FANUC, &err);
    CHECK(st == FM_OK && ngot >= 5);
    if (st || ngot < 5) return;
    CHECK_NEAR(got[2].t1 - got[2].t0, 15.0 / 500.0 * 60.0, 1e-9);
    CHECK_NEAR(got[3].t1 - got[3].t0, 25.0 / 500.0 * 60.0, 1e-9);
    CHECK_NEAR(got[4].t1 - got[4].t0, 50.0 / 300.0 * 60.0, 1e-9);
    CHECK_NEAR(got[3].feed, 500, 1e-9);
}

/* D takes the table's compensation registers: the G41 boss of test_boss
 * with r = 4.98 (D3: radius 5 and wear -0.02), r = 3 (D14: the tool whose
 * diameter register is 14) and r = 4.5 (D5: its radius offset): start-up
 * (-r, 0), corners (-r, 20 + r), (40 + r, 20 + r), (40 + r, -r), the last
 * side's end (0, -r). */
static void test_registers(void)
{
    const struct {
        int d;
        double r;
    } cases[] = {{3, 4.98}, {14, 3}, {5, 4.5}};
    for (int k = 0; k < 3; k++) {
        double r = cases[k].r;
        char text[400];
        snprintf(text, sizeof text,
                 "G21 G17 G90 G94\nG00 X-20. Y0 S1000 M03\nG01 Z-5. F300.\nG41 D%d X0 Y0\nY20.\n"
                 "X40.\nY0\nX0\nG40 X-20. Y-10.\nG00 Z20.\nM30\n", cases[k].d);
        const em e[] = {{'R', -20, 0, 0, 0, 0, 0},        {'L', -20, 0, -5, 0, 0, 0},
                        {'L', -r, 0, -5, 0, 0, 0},        {'L', -r, 20 + r, -5, 0, 0, 0},
                        {'L', 40 + r, 20 + r, -5, 0, 0, 0}, {'L', 40 + r, -r, -5, 0, 0, 0},
                        {'L', 0, -r, -5, 0, 0, 0},        {'L', -20, -10, -5, 0, 0, 0},
                        {'R', -20, -10, 20, 0, 0, 0}};
        expect("G41 with the table's registers", text, e, 9);
    }
}

int main(void)
{
    tool_specs[0].number = 1;
    tool_specs[0].diameter = 10;
    tool_specs[1].number = 2;
    tool_specs[1].diameter = 6;
    tool_specs[2].number = 3;
    tool_specs[2].diameter = 10;
    tool_specs[2].radius_wear = -0.02;
    tool_specs[3].number = 4;
    tool_specs[3].diameter = 6;
    tool_specs[3].diameter_register = 14;
    tool_specs[4].number = 5;
    tool_specs[4].diameter = 10;
    tool_specs[4].radius_offset = 4.5;
    test_boss();
    test_pocket();
    test_arcs_lead_in_out();
    test_interference();
    test_second_start();
    test_same_in_both();
    test_feed_modes();
    test_registers();
    return test_summary("gcode_fanuc_comp");
}
