/* test_gcode_linuxcnc.c: unit tests of the LinuxCNC constructs of issue 15
 * that the rs274 differential test cannot see: every new error with its
 * message and line:column, probing through a probe callback, messages,
 * subroutine files, spline motions (pose and sound boxes), G33 times, and the
 * two places where frepmill follows LinuxCNC's documentation rather than
 * rs274 2.9.0~pre1 (a do-while after another loop, break inside repeat). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test.h"
#include "toolpaths/gcode/gcode.h"

#define MAXM 4000

static fm_motion got[MAXM];
static int ngot;
static char messages[64][256];
static int nmessages;

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    return 0;
}

static void on_message(void *user, int line, const char *text)
{
    (void)user;
    (void)line;
    if (nmessages < 64) snprintf(messages[nmessages++], sizeof messages[0], "%s", text);
}

static fm_status run_opt(const char *text, fm_gcode_options *opt, fm_error *err)
{
    ngot = 0;
    nmessages = 0;
    opt->message = on_message;
    return fm_gcode_run_string(text, strlen(text), "t.ngc", opt, collect, NULL, NULL, err);
}

static fm_status run(const char *text, fm_error *err)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    return run_opt(text, &o, err);
}

static void expect_error_opt(const char *text, fm_gcode_options *o, int line, int column,
                             const char *fragment)
{
    fm_error err;
    fm_status st = run_opt(text, o, &err);
    CHECK(st != FM_OK);
    CHECK(err.line == line);
    CHECK(err.column == column);
    CHECK_STR_CONTAINS(err.message, fragment);
    if (st == FM_OK || err.line != line || err.column != column || !strstr(err.message, fragment))
        fprintf(stderr, "  for '%s': got %d:%d %s\n", fragment, err.line, err.column,
                err.message);
}

static void expect_error(const char *text, int line, int column, const char *fragment)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    expect_error_opt(text, &o, line, column, fragment);
}

/* ------------------------------------------------------------- errors -- */

static void test_comp_errors(void)
{
    /* a tool table: tool 1 of 6 mm */
    fm_tool_spec t[1];
    memset(t, 0, sizeof t);
    t[0].number = 1;
    t[0].diameter = 6;
    fm_tool_table table = {1, t};
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.tools = &table;
    const char *h = "G21 G17 F100\nT1 M6\nG0 X0 Y0\n";
    char prog[1024];
#define COMP(body) (snprintf(prog, sizeof prog, "%s%s", h, body), prog)
    expect_error_opt(COMP("G41\nG1 X2\n"), &o, 5, 1, "entry move of length 2.0000 is shorter than the tool radius 3.0000");
    expect_error_opt(COMP("G19\nG41\n"), &o, 5, 1, "compensates in G17 or G18 only");
    expect_error_opt(COMP("G41\nG42\n"), &o, 5, 1, "already on");
    expect_error_opt(COMP("G41.1\n"), &o, 4, 1, "G41.1: D word missing");
    expect_error_opt(COMP("G41.1 D4 L3\n"), &o, 4, 10, "needs the G18 plane");
    expect_error_opt(COMP("G41 D1.5\n"), &o, 4, 5, "expected a whole tool number");
    expect_error_opt(COMP("G41 D7\n"), &o, 4, 5, "tool 7 is not in the tool table");
    /* a tool number beyond int (found by fuzz_gcode: the conversion was
     * undefined, clang's UBSan stopped there) */
    expect_error_opt(COMP("G41 D111111111111111111111\n"), &o, 4, 5, "expected a tool number up to 1000000000");
    /* a concave corner the tool cannot reach: the 2 mm step back is shorter
     * than the radius */
    expect_error_opt(COMP("G41 G1 X10 Y0\nG1 X20\nG1 Y2\nG1 X10\n"), &o, 7, 1,
                     "the feed of line 6 in this concave corner cannot be reached by the tool "
                     "without gouging");
    /* an inside arc smaller than the tool */
    expect_error_opt(COMP("G41 G1 X10\nG3 X12 Y2 R2\n"), &o, 5, 1,
                     "larger than the radius 2.0000 of this inside arc");
    expect_error_opt(COMP("G41 G1 X10\nG40\nG2 X20 R5\n"), &o, 6, 1, "just after G40");
    expect_error_opt(COMP("G0 X-10\nG41 G3 X0 Y0 R2\n"), &o, 5, 5,
                     "larger than the radius 2.0000 of this inside arc");
    expect_error_opt(COMP("G0 X-2\nG41 G2 X0 Y0 R1\n"), &o, 5, 5,
                     "entry arc: its end is nearer than the tool radius");
    expect_error_opt(COMP("G41 G1 X10 Y0\nG3 X20 Y0 R5\nG2 X10 Y0 R5\n"), &o, 6, 1,
                     "this arc and the arc of line 5 have the same centre");
    expect_error_opt(COMP("G42 G1 X10 Y0\nG2 X20 Y0 R5\nG1 X15 Y4\n"), &o, 6, 1,
                     "the corner from the arc of line 5 to this line is too tight");
    expect_error_opt(COMP("G41 G1 X10 Y0\nG1 X20 Y0\nG3 X18 Y4 R3.1\n"), &o, 6, 1,
                     "this arc in a concave corner cannot be reached by the tool without gouging");
    expect_error_opt(COMP("G42 G1 X10 Y0\nG2 X20 Y0 R5\nG3 X19 Y1 R4\n"), &o, 6, 1,
                     "the corner from the arc of line 5 to this arc is too tight");
    expect_error_opt(COMP("G41 G1 X10\nT1 M6\n"), &o, 5, 4, "M6 (tool change) with cutter radius compensation on");
    expect_error_opt(COMP("G41 G1 X10\nG55\n"), &o, 5, 1, "coordinate system change with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG43 H1\n"), &o, 5, 1, "tool length offset change with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG92 X0\n"), &o, 5, 1, "G92 with cutter radius");
    expect_error_opt(COMP("G41 G1 X10\nG52 X0\n"), &o, 5, 1, "G52 with cutter radius");
    expect_error_opt(COMP("G41 G1 X10\nG18\n"), &o, 5, 1, "plane change with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG28\n"), &o, 5, 1, "G28 with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG53 G0 X0\n"), &o, 5, 5, "G53 with cutter radius");
    expect_error_opt(COMP("G41 G1 X10\nG81 X1 Y1 Z-1 R1\n"), &o, 5, 1, "canned cycle with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG5.1 X20 I1 J1\n"), &o, 5, 1, "spline (G5.x) with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG38.2 Z-5\n"), &o, 5, 1, "probing (G38.x) with cutter");
    expect_error_opt(COMP("G41 G1 X10\nS100 M3 G33 Z-1 K1\n"), &o, 5, 9, "G33 with cutter");
    expect_error_opt(COMP("G41 G1 X10\nG10 L2 P0 X1\n"), &o, 5, 1, "active coordinate system with cutter");
#undef COMP
    /* the same programs are fine without compensation errors where LinuxCNC
     * allows them: G20 inside compensation, G10 L2 of another system */
    fm_error err;
    CHECK(run_opt("G21 G17 F100\nT1 M6\nG0 X0 Y0\nG41 G1 X10\nG20\nG1 Y1\nG10 L2 P2 X1\nG40\nG1 X0\n",
                  &o, &err) == FM_OK);
}

static void test_other_errors(void)
{
    /* polar coordinates */
    expect_error("G18 G0 @1 ^2\n", 1, 8, "polar coordinates in the G18 plane");
    expect_error("G91 G0 @1\n", 1, 8, "at the origin is indeterminate");
    expect_error("G0 @1\n", 1, 4, "@ without ^ at the origin");
    expect_error("G53 G0 @1 ^2\n", 1, 8, "polar coordinates with G53");
    expect_error("G92 @1\n", 1, 5, "not a motion");
    expect_error("G0 @1 @2\n", 1, 7, "second '@' word");
    /* G10 */
    expect_error("G10 L1 Z1\n", 1, 1, "G10 L1: P word missing");
    expect_error("G10 L5 P1\n", 1, 5, "expected L1, L2, L10, L11 or L20");
    expect_error("G10 L10 P0 Z1\n", 1, 9, "expected a tool number > 0");
    /* M70-M73 */
    expect_error("M72\n", 1, 1, "no modal state saved at this call level");
    expect_error("M70\nM71\nM72\n", 3, 1, "no modal state saved");
    /* returns and subroutine files */
    expect_error("o<nothere> call\n", 1, 1, "no subroutine onothere in this program or on the subroutine path");
    expect_error("#<_x> = 3\n", 1, 1, "#<_x> is a read-only parameter");
    expect_error("G0 X1\n#<_value> = 3\n", 2, 1, "read-only");
    /* splines */
    expect_error("G21 F100\nG5 X10 Y0 I1 P1 Q1\n", 2, 1, "G5: J word missing");
    expect_error("G21 F100\nG5 X10 Y0 I1 J1 P1\n", 2, 1, "G5: Q word missing");
    expect_error("G21 F100\nG5.1 X10 Y0 I1\n", 2, 1, "G5.1: J word missing");
    expect_error("G21 F100\nG18 G5.1 X10 I1 J1\n", 2, 5, "G5.1 in the G18 plane");
    expect_error("G21 F100\nG5.1 X10 Y0 Z1 I1 J1\n", 2, 13, "with a Z word");
    expect_error("G21 F100\nG5.3\n", 2, 1, "G5.3 without G5.2 first");
    expect_error("G21 F100\nG5.2 X1 Y1 P1 L4\nX2 Y2 P1\nG5.3\n", 4, 1, "3 control points for a NURBS of order L4");
    expect_error("G21 F100\nG5.2 X1 P1\n", 2, 6, "only X; expected both X and Y");
    expect_error("G21 F100\nG5.2 X1 Y1\n", 2, 1, "without P");
    expect_error("G21 F100\nG5.2 X1 Y1 P-1\n", 2, 12, "expected a weight P > 0");
    expect_error("G21 F100\nG5.2 X1 Y1 P1\nG5.2 P2\n", 3, 6, "a weight alone is only for the first");
    expect_error("G21 F0\nG5 X1 Y1 I1 J1 P1 Q1\n", 2, 1, "feed rate is zero");
    /* G33 */
    expect_error("G21 S100 M3\nG33 Z-5\n", 2, 1, "G33: K word missing");
    expect_error("G21 S100\nG33.1 Z-5 K1\n", 2, 1, "spindle not turning");
    expect_error("G21 S100 M3\nG33 Z-5 K0\n", 2, 9, "expected a pitch K > 0");
    /* lathe codes */
    expect_error("G7\n", 1, 1, "for lathes");
    expect_error("G8\n", 1, 1, "for lathes");
    expect_error("G70 P1 Q2\n", 1, 1, "for lathes");
    expect_error("G71.1 P1 Q2\n", 1, 1, "for lathes");
    expect_error("G72 P1 Q2\n", 1, 1, "for lathes");
    expect_error("G76 P1 Z-1 I1 J1 K2\n", 1, 1, "threading cycle is for lathes");
    /* an arc with neither centre nor radius */
    expect_error("G21 F100\nG2 X1\n", 2, 1, "no centre and no radius");
    /* rotation and the G18 plane */
    expect_error("G21 F100\nG10 L2 P1 R30\nG18 G2 X1 Z1 I1\n", 3, 5, "rotated coordinate system");
}

/* ------------------------------------------------------------ probing -- */

typedef struct fake_probe {
    double fraction;
    int tripped, at_start, calls, toward;
    fm_motion last;
} fake_probe;

static fm_status probe(void *user, const fm_motion *move, int toward, int *tripped,
                       double *fraction, int *at_start, fm_error *err)
{
    (void)err;
    fake_probe *p = user;
    p->calls++;
    p->last = *move;
    p->toward = toward;
    *tripped = p->tripped;
    *fraction = p->fraction;
    *at_start = p->at_start;
    return FM_OK;
}

static void test_probe(void)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    fake_probe fp = {0.25, 1, 0, 0, 0, {0}};
    o.probe = probe;
    o.probe_user = &fp;
    fm_error err;
    /* G92 shifts the program coordinates; the probe results are in them */
    CHECK(run_opt("G21 F100\nG0 X1 Y2 Z10\nG92 Z5\nG38.2 Z-3\n"
                  "(debug, #5061 #5062 #5063 #5070)\nG1 Z[#5063 + 1]\n", &o, &err) == FM_OK);
    CHECK(fp.calls == 1 && fp.toward == 1);
    CHECK_NEAR(fp.last.start[2], 10, 1e-12);
    CHECK_NEAR(fp.last.end[2], 2, 1e-12); /* machine: Z-3 + G92 offset 5 */
    CHECK(ngot == 3);
    CHECK(got[1].kind == FM_MOTION_LINE);
    CHECK_NEAR(got[1].end[2], 8, 1e-12); /* a quarter of the way down from machine 10 to 2 */
    CHECK(nmessages == 1);
    CHECK(!strcmp(messages[0], " 1.000000 2.000000 3.000000 1.000000"));
    CHECK_NEAR(got[2].end[2], 9, 1e-12);
    /* G38.3 that does not trip goes to the target and says so in #5070 */
    fp.tripped = 0;
    CHECK(run_opt("G21 F100\nG0 Z10\nG38.3 Z0\n(debug, #5063 #5070)\n", &o, &err) == FM_OK);
    CHECK(!strcmp(messages[0], " 0.000000 0.000000"));
    /* G38.2 and G38.4 must trip */
    expect_error_opt("G21 F100\nG0 Z10\nG38.2 Z0\n", &o, 3, 1, "finished without making contact");
    expect_error_opt("G21 F100\nG0 Z10\nG38.4 Z20\n", &o, 3, 1, "finished without losing contact");
    CHECK(fp.toward == 0);
    fp.tripped = 1;
    fp.at_start = 1;
    expect_error_opt("G21 F100\nG0 Z10\nG38.2 Z0\n", &o, 3, 1, "already touches the stock");
    expect_error_opt("G21 F100\nG0 Z10\nG38.5 Z20\n", &o, 3, 1, "does not touch the stock at the start");
    fp.at_start = 0;
    expect_error_opt("G21 F100\nG38.2 Z0\n", &o, 2, 1, "the probe target is the current point");
    expect_error_opt("G21\nG38.2 Z-1\n", &o, 2, 1, "zero feed rate");
    expect_error_opt("G21 G93 F1\nG38.2 Z-1\n", &o, 2, 1, "inverse time");
    /* without a callback the probe trips at the target */
    CHECK(run("G21 F100\nG0 Z10\nG38.2 Z1\n(debug, #5063 #5070)\n", &err) == FM_OK);
    CHECK(!strcmp(messages[0], " 1.000000 1.000000"));
}

/* ------------------------------------------------ messages and files -- */

static void test_messages(void)
{
    fm_error err;
    CHECK(run("#1=2.5\n#<a>=3\n(debug, a=#<a> one=#1 n=#<nope> ##1 #[1] # end)\n"
              "(DEBUG,upper #<A>)\n(msg, raw #<a>)\n(print, not a message)\nG0 X1 (debug,on a block)\n"
              "o1 if [1]\n(debug,)\no1 endif\n",
              &err) == FM_OK);
    CHECK(nmessages == 5);
    CHECK(!strcmp(messages[0], " a=3.000000 one=2.500000 n=###### #2.500000 #[1] # end"));
    CHECK(!strcmp(messages[1], "upper 3.000000"));
    CHECK(!strcmp(messages[2], " raw #<a>"));
    CHECK(!strcmp(messages[3], "on a block"));
    CHECK(!strcmp(messages[4], ""));
}

static void test_subroutine_files(void)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.subroutine_path = "gcode/no-such-folder:gcode/programs/subs";
    fm_error err;
    CHECK(run_opt("G21 F100\nG0 X0 Y0\no<offset_square> call [1] [2] [3]\nG1 Z#<_value>\n", &o,
                  &err) == FM_OK);
    CHECK(ngot == 6);
    CHECK(got[1].line == 3); /* the file's own line numbers */
    CHECK_NEAR(got[5].end[2], 12, 0);
    /* a second call finds the loaded file again */
    CHECK(run_opt("G21 F100\no<offset_square> call [1] [2] [3]\no<offset_square> call [5] [5] [1]\n",
                  &o, &err) == FM_OK);
    CHECK(ngot == 8);
    /* an error inside the file names the file and its line */
    CHECK(run_opt("G21 F0\no<offset_square> call [1] [2] [3]\n", &o, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.file, "programs/subs/offset_square.ngc");
    CHECK(err.line == 3);
    /* numbered subroutines are never looked up in files; nor are paths */
    o.subroutine_path = "gcode/programs/subs";
    expect_error_opt("o100 call\n", &o, 1, 1, "no subroutine o100 in this program;");
    /* without the path the file is not found */
    expect_error("o<offset_square> call\n", 1, 1, "on the subroutine path");
}

/* ------------------------------------------------------------- curves -- */

static void test_spline_motion(void)
{
    fm_error err;
    for (int c = 0; c < 3; c++) {
        const char *prog[3] = {
            "G21 F600\nG0 X1 Y2 Z-1\nG5 I0 J10 P0 Q-10 X20 Y0\n",
            "G21 F600\nG0 X1 Y2 Z-1\nG5.1 I5 J8 X20 Y0\n",
            "G21 F600\nG0 X1 Y2 Z-1\nG5.2 X5 Y10 P2 L4\nX10 Y-5 P0.5\nX15 Y10 P1\nX20 Y0 P3\nX25 Y2 P1\nG5.3\n"};
        ngot = 0;
        fm_gcode_options o;
        fm_gcode_options_default(&o);
        /* the path is valid while the sink runs: check it there */
        fm_status st = fm_gcode_run_string(prog[c], strlen(prog[c]), "t.ngc", &o, collect, NULL,
                                           NULL, &err);
        CHECK(st == FM_OK);
        CHECK(ngot == 2 && got[1].kind == FM_MOTION_PARAM);
        CHECK_NEAR(got[1].start[0], 1, 1e-12);
        CHECK_NEAR(got[1].end[0], c == 2 ? 25 : 20, 1e-12);
    }
}

/* A sink that checks a parametric motion while it is valid: the pose at t0
 * and t1 is the start and end, and boxes over random intervals hold the
 * poses sampled in them. */
static int spline_checks, spline_failures;
static int check_param(void *user, const fm_motion *m)
{
    (void)user;
    if (m->kind != FM_MOTION_PARAM) return 0;
    double p[3], a[3];
    m->path->pose(m->path->ctx, m->t0, p, a);
    for (int k = 0; k < 3; k++) spline_failures += fabs(p[k] - m->start[k]) > 1e-9;
    m->path->pose(m->path->ctx, m->t1, p, a);
    for (int k = 0; k < 3; k++) spline_failures += fabs(p[k] - m->end[k]) > 1e-9;
    spline_failures += a[0] != 0 || a[1] != 0 || a[2] != 1;
    for (int i = 0; i < 200; i++) {
        double ta = test_uniform(m->t0, m->t1), tb = test_uniform(ta, m->t1);
        double lo[3], hi[3], alo[3], ahi[3];
        m->path->pose_bounds(m->path->ctx, ta, tb, lo, hi, alo, ahi);
        for (int j = 0; j <= 20; j++) {
            m->path->pose(m->path->ctx, ta + (tb - ta) * j / 20.0, p, a);
            for (int k = 0; k < 3; k++) spline_failures += p[k] < lo[k] || p[k] > hi[k];
            spline_checks++;
        }
        /* boxes shrink with the interval: a tiny interval's box is tiny */
        m->path->pose_bounds(m->path->ctx, ta, ta + 1e-9 * (m->t1 - m->t0), lo, hi, alo, ahi);
        spline_failures += hi[0] - lo[0] > 1e-6 || hi[1] - lo[1] > 1e-6;
    }
    return 0;
}

static void test_spline_paths(void)
{
    const char *prog = "G21 G90 F600\nG10 L2 P1 X3 Y-2 R25\nG0 X1 Y2 Z-1\n"
                       "G5 I0 J10 P0 Q-10 X20 Y0\nG5 P3 Q-4 X30 Y10\nG5.1 I5 J8 X40 Y0\n"
                       "G5.2 X45 Y10 P2 L5\nX50 Y-5 P0.5\nX55 Y10 P1\nX60 Y0 P3\nX65 Y2 P1\n"
                       "X70 Y8 P0.2\nG5.3\n";
    fm_error err;
    CHECK(fm_gcode_run_string(prog, strlen(prog), "t.ngc", NULL, check_param, NULL, NULL, &err) ==
          FM_OK);
    printf("spline paths: %d sampled poses, %d outside their boxes or off their ends\n",
           spline_checks, spline_failures);
    CHECK(spline_checks > 1000);
    CHECK(spline_failures == 0);
}

static void test_sync(void)
{
    fm_error err;
    /* G33: |dz| / (K S) minutes; G33.1: in and out again */
    CHECK(run("G21 G90 S500 M3\nG0 X0 Y0 Z5\nG33 Z-10 K1.5\nG33.1 X1 Z-20 K2\n(debug, #5422)\n", &err) ==
          FM_OK);
    CHECK(ngot == 4);
    CHECK_NEAR(got[1].t1 - got[1].t0, 15.0 / (1.5 * 500) * 60, 1e-9);
    CHECK_NEAR(got[1].feed, 1.5 * 500, 1e-9);
    CHECK_NEAR(got[2].t1 - got[2].t0, 10.0 / (2 * 500) * 60, 1e-9);
    CHECK_NEAR(got[3].end[2], -10, 0);
    CHECK(got[3].spindle_dir == -1);
    CHECK(!strcmp(messages[0], " -10.000000"));
}

/* --------------------------------------------- rs274's documented gaps -- */

static void test_loop_differences(void)
{
    fm_error err;
    /* a do-while after another loop runs until its condition fails (rs274
     * 2.9.0~pre1 runs it once) */
    CHECK(run("#1=0\no1 while [#1 LT 2]\n#1=[#1+1]\no1 endwhile\n#2=0\no2 do\n#2=[#2+1]\n"
              "G0 X#2\no2 while [#2 LT 3]\n", &err) == FM_OK);
    CHECK(ngot == 3);
    CHECK_NEAR(got[2].end[0], 3, 0);
    /* break inside repeat leaves the loop (rs274 refuses it) */
    CHECK(run("#1=0\no1 repeat [10]\n#1=[#1+1]\no2 if [#1 EQ 4]\no1 break\no2 endif\nG0 X#1\n"
              "o1 endrepeat\nG0 Y1\n", &err) == FM_OK);
    CHECK(ngot == 4);
    CHECK_NEAR(got[2].end[0], 3, 0);
    CHECK_NEAR(got[3].end[1], 1, 0);
}

/* Path control (docs/plan.md "Path modes"): LinuxCNC starts in G64 with
 * no tolerance; G61 is exact path, G61.1 exact stop; G64 P sets the
 * tolerance and Q the naive-CAM tolerance (Q defaults to P), in program
 * units; a canned cycle runs in exact path and the mode comes back after
 * it (rs274's convert_cycle). */
static void test_path_modes(void)
{
    fm_error err = {0};
    CHECK(run("G21 G90 G17\nG1 X1 F100\nG61 X2\nG61.1 X3\nG64 P0.05 X4\nG64 P0.1 Q0.02 X5\n"
              "G20 G64 P0.001 X0.25\nG21 G64 X6\nG0 Z5\nG81 X7 Z-1 R1\nG80 G0 X8\nM2\n",
              &err) == FM_OK);
    CHECK(ngot >= 11);
    if (ngot < 11) return;
    CHECK(got[0].path_mode == FM_PATH_BLEND && got[0].path_tolerance == 0 && got[0].naive_tolerance == 0);
    CHECK(got[1].path_mode == FM_PATH_EXACT_PATH);
    CHECK(got[2].path_mode == FM_PATH_EXACT_STOP);
    CHECK(got[3].path_mode == FM_PATH_BLEND);
    CHECK_NEAR(got[3].path_tolerance, 0.05, 1e-12);
    CHECK_NEAR(got[3].naive_tolerance, 0.05, 1e-12);
    CHECK_NEAR(got[4].path_tolerance, 0.1, 1e-12);
    CHECK_NEAR(got[4].naive_tolerance, 0.02, 1e-12);
    CHECK_NEAR(got[5].path_tolerance, 0.0254, 1e-12);
    CHECK(got[6].path_tolerance == 0 && got[6].naive_tolerance == 0);
    /* G0 Z5, then the cycle's moves in exact path, then G64 again */
    CHECK(got[7].path_mode == FM_PATH_BLEND);
    for (int i = 8; i < ngot - 1; i++) CHECK(got[i].path_mode == FM_PATH_EXACT_PATH);
    CHECK(got[ngot - 1].path_mode == FM_PATH_BLEND);
}

int main(void)
{
    test_path_modes();
    test_comp_errors();
    test_other_errors();
    test_probe();
    test_messages();
    test_subroutine_files();
    test_spline_motion();
    test_spline_paths();
    test_sync();
    test_loop_differences();
    return test_summary("gcode_linuxcnc");
}
