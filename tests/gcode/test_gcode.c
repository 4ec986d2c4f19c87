/* test_gcode.c: unit tests of the G-code interpreter: motion times and
 * lengths against closed forms, units, offsets, tool tips, resume, and every
 * error kind with its line:column and message. (Positions against LinuxCNC
 * itself are checked by rs274_diff.py.) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test.h"
#include "toolpaths/gcode/gcode.h"

#define MAXM 2000

static fm_motion got[MAXM];
static int ngot;

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    return 0;
}

static fm_status run_opt(const char *text, const fm_gcode_options *opt, fm_error *err)
{
    ngot = 0;
    return fm_gcode_run_string(text, strlen(text), "t.ngc", opt, collect, NULL, NULL, err);
}

static fm_status run(const char *text, fm_error *err) { return run_opt(text, NULL, err); }

/* The program must fail with this line, column and message fragment. */
static void expect_error(const char *text, int line, int column, const char *fragment)
{
    fm_error err;
    fm_status st = run(text, &err);
    CHECK(st != FM_OK);
    CHECK(err.line == line);
    CHECK(err.column == column);
    CHECK_STR_CONTAINS(err.message, fragment);
    if (err.line != line || err.column != column)
        fprintf(stderr, "  for %s: got %d:%d %s\n", fragment, err.line, err.column, err.message);
}

static void test_times(void)
{
    fm_error err;
    CHECK(run("G21 G0 X50\nG1 X60 F600\nG4 P1.5\nM2\n", &err) == FM_OK);
    CHECK(ngot == 3);
    CHECK(got[0].kind == FM_MOTION_RAPID);
    CHECK_NEAR(got[0].t1 - got[0].t0, 50.0 / 5000.0 * 60.0, 1e-12);
    CHECK(got[1].kind == FM_MOTION_LINE);
    CHECK_NEAR(got[1].t1 - got[1].t0, 1.0, 1e-12);
    CHECK_NEAR(got[1].feed, 600, 1e-12);
    CHECK(got[2].kind == FM_MOTION_DWELL);
    CHECK_NEAR(got[2].t1 - got[2].t0, 1.5, 1e-12);
    CHECK_NEAR(got[2].t0, got[1].t1, 0);
    /* full circle of radius 5 at 60 mm/min: 2*pi*5 s */
    CHECK(run("G0 X0 Y0\nG2 X0 Y0 I5 J0 F60\n", &err) == FM_OK);
    CHECK(ngot == 2 && got[1].kind == FM_MOTION_ARC && got[1].turns == -1);
    CHECK_NEAR(got[1].t1 - got[1].t0, 2 * FM_PI * 5, 1e-9);
    CHECK_NEAR(got[1].center[0], 5, 1e-12);
    CHECK(got[1].plane_axis == 2);
    /* helix: two turns of radius 3 and 4 mm down: length hypot(2*2*pi*3, 4) */
    CHECK(run("G0 X0 Y0 Z0\nG3 X0 Y0 Z-4 I3 J0 P2 F60\n", &err) == FM_OK);
    CHECK(got[1].turns == 2);
    CHECK_NEAR(got[1].t1 - got[1].t0, hypot(4 * FM_PI * 3, 4), 1e-9);
    /* quarter arc with R: centre at (0,10) for G3 from (10,0)... closed form */
    CHECK(run("G0 X10 Y0\nG3 X0 Y10 R10 F60\n", &err) == FM_OK);
    CHECK_NEAR(got[1].center[0], 0, 1e-9);
    CHECK_NEAR(got[1].center[1], 0, 1e-9);
    CHECK_NEAR(got[1].t1 - got[1].t0, FM_PI * 10 / 2, 1e-9);
    /* negative R: the long way round, centre mirrored */
    CHECK(run("G0 X10 Y0\nG3 X0 Y10 R-10 F60\n", &err) == FM_OK);
    CHECK_NEAR(got[1].center[0], 10, 1e-9);
    CHECK_NEAR(got[1].center[1], 10, 1e-9);
    CHECK_NEAR(got[1].t1 - got[1].t0, 3 * FM_PI * 10 / 2, 1e-9);
    /* inverse time: F2 means half a minute whatever the length */
    CHECK(run("G93 G1 X100 F2\n", &err) == FM_OK);
    CHECK_NEAR(got[0].t1 - got[0].t0, 30, 1e-12);
    CHECK_NEAR(got[0].feed, 200, 1e-9);
    /* configured rapid rate */
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.rapid_rate = 1000;
    CHECK(run_opt("G0 X10\n", &o, &err) == FM_OK);
    CHECK_NEAR(got[0].t1, 0.6, 1e-12);
}

static void test_units_offsets(void)
{
    fm_error err;
    CHECK(run("G20 G0 X1 Y2 Z-0.5\nG1 X2 F10\nG21 G1 X0\n", &err) == FM_OK);
    CHECK_NEAR(got[0].end[0], 25.4, 1e-12);
    CHECK_NEAR(got[0].end[2], -12.7, 1e-12);
    CHECK_NEAR(got[1].t1 - got[1].t0, 25.4 / 254.0 * 60, 1e-9); /* 10 in/min */
    CHECK_NEAR(got[2].end[0], 0, 1e-12);
    /* G10 L2 + G55 + G92: machine = program + G5x + G92 */
    CHECK(run("G10 L2 P2 X10 Y20 Z5\nG55 G0 X1 Y1 Z1\nG92 X0 Y0 Z0\nG0 X2\n", &err) == FM_OK);
    CHECK_NEAR(got[0].end[0], 11, 1e-12);
    CHECK_NEAR(got[0].end[1], 21, 1e-12);
    CHECK_NEAR(got[1].end[0], 13, 1e-12);
    CHECK_NEAR(got[1].end[2], 6, 1e-12);
    /* G53 moves in machine coordinates */
    CHECK(run("G10 L2 P1 X10\nG0 X0\nG53 G0 X3\n", &err) == FM_OK);
    CHECK_NEAR(got[1].end[0], 3, 1e-12);
    /* G28 goes to the position stored by G28.1 */
    CHECK(run("G0 X4 Y5 Z6\nG28.1\nG0 X0 Y0 Z0\nG28\n", &err) == FM_OK);
    CHECK(ngot == 4);
    CHECK_NEAR(got[3].end[0], 4, 1e-12);
    CHECK_NEAR(got[3].end[2], 6, 1e-12);
}

static void test_tool_tip(void)
{
    fm_tool_spec tools[2];
    memset(tools, 0, sizeof tools);
    tools[0].number = 1;
    tools[0].length_offset = 10;
    tools[1].number = 2;
    tools[1].length_offset = 0;
    fm_tool_table table = {2, tools};
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.tools = &table;
    fm_error err;
    /* no G43: the tip is 10 mm below the programmed point; with G43 H1 it is on it */
    CHECK(run_opt("T1 M6\nG0 X0 Y0 Z20\nG43 H1\nG0 Z5\nG49\nG0 Z5\n", &o, &err) == FM_OK);
    CHECK(ngot == 3);
    CHECK(got[0].tool == 1);
    CHECK_NEAR(got[0].tip_offset[2], -10, 1e-12);
    CHECK_NEAR(got[0].end[2] + got[0].tip_offset[2], 10, 1e-12);
    CHECK_NEAR(got[1].tip_offset[2], 0, 1e-12);
    /* G43 does not move the machine: the programmed Z shifts by the offset */
    CHECK_NEAR(got[1].start[2] + got[1].tip_offset[2], 10, 1e-12);
    CHECK_NEAR(got[1].end[2], 5, 1e-12);
    CHECK_NEAR(got[2].end[2] + got[2].tip_offset[2], -5, 1e-12);
    /* unknown tool with a table */
    CHECK(run_opt("T7 M6\n", &o, &err) == FM_ERR_INPUT);
    CHECK(err.line == 1 && err.column == 1);
    CHECK_STR_CONTAINS(err.message, "tool 7 is not in the tool table");
    /* H names the tool whose library register it is (Fusion's post-process
     * length-offset): T5 with register 15 and length 30 under G43 H15 has its
     * tip on the programmed point (30 - 30); with no such register H15 is
     * tool 15, which the table does not have */
    fm_tool_spec reg[2];
    memset(reg, 0, sizeof reg);
    reg[0].number = 5;
    reg[0].length_offset = 30;
    reg[0].length_register = 15;
    reg[1].number = 15;
    reg[1].length_offset = 7;
    fm_tool_table regs = {2, reg};
    o.tools = &regs;
    CHECK(run_opt("T5 M6\nG43 H15\nG0 Z5\n", &o, &err) == FM_OK);
    CHECK(ngot == 1 && got[0].tool == 5);
    CHECK_NEAR(got[0].tip_offset[2], 0, 1e-12);
    fm_gcode_options fo = o;
    fo.dialect = FM_GCODE_FANUC;
    CHECK(run_opt("T5 M06\nG43 H15 Z5.\n#1 = #2015\nG00 X#1\n", &fo, &err) == FM_OK);
    CHECK(ngot == 2);
    CHECK_NEAR(got[0].tip_offset[2], 0, 1e-12);
    CHECK_NEAR(got[1].end[0], 30, 1e-12); /* #2015: register 15's length */
    reg[0].length_register = 0;
    CHECK(run_opt("T5 M6\nG43 H15\nG0 Z5\n", &o, &err) == FM_OK);
    CHECK_NEAR(got[0].tip_offset[2], 7 - 30, 1e-12);
    o.tools = &table;
    /* without a table any tool is fine and offsets are zero */
    CHECK(run("T7 M6 G43\nG0 Z1\n", &err) == FM_OK);
    CHECK_NEAR(got[0].tip_offset[2], 0, 0);
}

/* The state at the start: the tip at start (5, 6, 50) with tool 1 (length
 * 10) in the spindle, so the spindle's point at Z60; T2 alone only selects,
 * M6 loads it (tip offset 0 from then on). In both dialects the start wins
 * over the power-on place (Fanuc's first reference point). */
static void test_start_state(void)
{
    fm_tool_spec tools[2];
    memset(tools, 0, sizeof tools);
    tools[0].number = 1;
    tools[0].length_offset = 10;
    tools[1].number = 2;
    fm_tool_table table = {2, tools};
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.tools = &table;
    o.initial_tool = 1;
    o.has_start = 1;
    o.start[0] = 5;
    o.start[1] = 6;
    o.start[2] = 50;
    fm_error err;
    const char *prog = "T2\nG0 X10.\nG1 Z-1. F100.\nM6\nG0 Z60.\nG91 G0 X1.\n";
    for (int d = 0; d < 2; d++) {
        o.dialect = d ? FM_GCODE_FANUC : FM_GCODE_LINUXCNC;
        o.reference_points[0][0] = 100; /* Fanuc's power-on place, which the start overrides */
        CHECK(run_opt(prog, &o, &err) == FM_OK);
        CHECK(ngot == 4);
        if (ngot != 4) continue;
        CHECK(got[0].tool == 1 && got[1].tool == 1 && got[2].tool == 2 && got[3].tool == 2);
        CHECK_NEAR(got[0].start[0], 5, 1e-12);
        CHECK_NEAR(got[0].start[1], 6, 1e-12);
        CHECK_NEAR(got[0].start[2], 60, 1e-12);
        CHECK_NEAR(got[0].start[2] + got[0].tip_offset[2], 50, 1e-12);
        CHECK_NEAR(got[0].end[0], 10, 1e-12);
        CHECK_NEAR(got[0].end[1], 6, 1e-12); /* an axis left out keeps the start's value */
        CHECK_NEAR(got[0].end[2], 60, 1e-12);
        CHECK_NEAR(got[1].end[2] + got[1].tip_offset[2], -11, 1e-12);
        CHECK_NEAR(got[2].tip_offset[2], 0, 1e-12);
        CHECK_NEAR(got[3].end[0], 11, 1e-12);
    }
    o.dialect = FM_GCODE_LINUXCNC;
    /* no start: the origin; no tool given: none (tool 0) */
    fm_gcode_options none = o;
    none.has_start = 0;
    none.initial_tool = 0;
    CHECK(run_opt("T1\nG0 X1\n", &none, &err) == FM_OK);
    CHECK(ngot == 1 && got[0].tool == 0);
    CHECK_NEAR(got[0].start[2], 0, 0);
    o.initial_tool = 7;
    CHECK(run_opt("G0 X1\n", &o, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "the initial tool 7 is not in the tool table");
}

static void test_skip_and_stop(void)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.skip_motions = 2;
    fm_error err;
    CHECK(run_opt("G0 X1\nG0 X2\nG0 X3\nG0 X4\n", &o, &err) == FM_OK);
    CHECK(ngot == 2);
    CHECK(got[0].index == 2);
    CHECK_NEAR(got[0].start[0], 2, 0);
    CHECK_NEAR(got[0].t0, 2.0 / 5000 * 60, 1e-12);
    /* M2 and a closing % end the program */
    CHECK(run("G0 X1\nM2\nG0 X2\n", &err) == FM_OK && ngot == 1);
    CHECK(run("%\nG0 X1\n%\nG0 X2\n", &err) == FM_OK && ngot == 1);
    /* block delete is off by default (as in rs274), on with the option */
    CHECK(run("/G0 X1\n", &err) == FM_OK && ngot == 1);
    o.skip_motions = 0;
    o.block_delete = 1;
    CHECK(run_opt("/G0 X1\nG0 X2\n", &o, &err) == FM_OK && ngot == 1);
    CHECK(got[0].line == 2);
    /* N numbers become the block number */
    CHECK(run("N120 G0 X1\nG0 X2\n", &err) == FM_OK);
    CHECK(got[0].block == 120 && got[1].block == -1);
}

static void test_words(void)
{
    fm_error err;
    /* case, spaces and comments as LinuxCNC */
    CHECK(run("g 0 x 1 . 5 (c) y#<_q>\n", &err) == FM_ERR_INPUT); /* #<_q> undefined */
    CHECK(run("#<_q>=2\ng 0 x 1 . 5 (c) y#<_q> ; z9\n", &err) == FM_OK);
    CHECK_NEAR(got[0].end[0], 1.5, 0);
    CHECK_NEAR(got[0].end[1], 2, 0);
    CHECK_NEAR(got[0].end[2], 0, 0);
    /* assignments on a line take effect after it is read */
    CHECK(run("#1=1\n#1=2 #2=#1\nG0 X#2\n", &err) == FM_OK);
    CHECK_NEAR(got[0].end[0], 1, 0);
    /* spindle and coolant state travel with the motions */
    CHECK(run("S1000 M3 M8\nG0 X1\nM4 M7\nG0 X2\nM5 M9\nG0 X3\n", &err) == FM_OK);
    CHECK(got[0].spindle_dir == 1 && got[0].coolant == 2);
    CHECK_NEAR(got[0].spindle_rpm, 1000, 0);
    CHECK(got[1].spindle_dir == -1 && got[1].coolant == 3);
    CHECK(got[2].spindle_dir == 0 && got[2].coolant == 0);
    /* planes: G18 arc axis is Y, G19 arc axis is X */
    CHECK(run("G18 G2 X10 Z0 I5 K0 F100\nG19 G2 Y10 Z0 J5 K0\n", &err) == FM_OK);
    CHECK(got[0].plane_axis == 1 && got[1].plane_axis == 0);
    /* canned cycle G81 from Z10: rapid over, rapid to R, feed, retract */
    CHECK(run("G0 Z10\nG98 G81 X1 Y1 Z-2 R1 F100\n", &err) == FM_OK);
    CHECK(ngot == 5);
    CHECK(got[3].kind == FM_MOTION_LINE);
    CHECK_NEAR(got[3].end[2], -2, 0);
    CHECK_NEAR(got[4].end[2], 10, 0);
    /* repeat and a subroutine with a return value */
    CHECK(run("o1 sub\no1 return [#1*2]\no1 endsub\no1 call [21]\n"
              "o2 repeat [3]\nG91 G0 X#<_value>\no2 endrepeat\n", &err) == FM_OK);
    CHECK(ngot == 3);
    CHECK_NEAR(got[2].end[0], 126, 0);
}

static void test_errors(void)
{
    expect_error("G1 X1 F0\n", 1, 1, "feed rate is zero");
    expect_error("G0 X1 (open\n", 1, 7, "unclosed comment");
    expect_error("G0 X[1/0]\n", 1, 7, "division by zero");
    expect_error("G0 X#<nope>\n", 1, 5, "#<nope> is not defined");
    expect_error("G0 X[1+2\n", 1, 5, "'[' without ']'");
    expect_error("\nG0 X1 X2\n", 2, 7, "second X word");
    expect_error("G0 G1 X1\n", 1, 4, "same modal group as G0");
    expect_error("G95 G1 X1\n", 1, 1, "G95");
    expect_error("G7.5\n", 1, 1, "unknown G code");
    expect_error("M123456\n", 1, 1, "not an M code");
    expect_error("M99\n", 1, 1, "unknown M code");
    expect_error("G0 X1 N10\n", 1, 7, "N word after other words");
    expect_error("G0 X1e5\n", 1, 6, "unexpected 'e'; expected a word letter");
    expect_error("G0 X1\nG2 X10 Y0 R2 F100\n", 2, 11, "radius too small");
    expect_error("G2 X10 Y0 I2 J0 F100\n", 1, 1, "differs from the radius");
    expect_error("o1 if [0]\nG0 X1\n", 1, 1, "without a matching o1 endif");
    expect_error("o<nope> call\n", 1, 1, "no subroutine onope");
    expect_error("o1 sub\no1 call\no1 endsub\no1 call\n", 2, 1, "nested deeper than 64");
    expect_error("G0 X[SQRT[-1]]\n", 1, 6, "SQRT[-1]");
    expect_error("G0 X#0\n", 1, 5, "out of range");
    expect_error("G91 G53 G0 X1\n", 1, 5, "G53 in incremental");
    expect_error("G81 X1 Y1 Z-1 F10\n", 1, 1, "R clearance plane unspecified");
    expect_error("G83 X1 Y1 Z-1 R1 F10\n", 1, 1, "peck depth Q missing");
    expect_error("X1\n", 1, 1, "axis words without a motion mode");
    expect_error("o1 return\n", 1, 1, "outside a subroutine");
    expect_error("G0 X1 @2\n", 1, 4, "X word with polar coordinates");
    /* the program size limit */
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.max_program_bytes = 4;
    fm_error err;
    CHECK(run_opt("G0 X1\n", &o, &err) == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "larger than the limit");
    /* an endless loop stops at the iteration budget */
    fm_gcode_options_default(&o);
    o.max_iterations = 1000;
    CHECK(run_opt("o1 while [1]\no1 endwhile\n", &o, &err) == FM_ERR_LIMIT);
    CHECK(err.line == 2 && err.column == 1);
    CHECK_STR_CONTAINS(err.message, "loop iterations");
    /* the formatted error says file:line:column */
    char buf[600];
    run("\n\nG0 X[1/0]\n", &err);
    CHECK_STR_CONTAINS(fm_error_format(&err, buf, sizeof buf), "t.ngc:3:7: '/': division by zero");
    /* motions before an error were delivered */
    CHECK(run("G0 X1\nG0 X1 X2\n", &err) == FM_ERR_INPUT && ngot == 1);
}

/* Arc angles in inverse time under compensation (issue 32): the queued feed
 * of a compensated block is F x its programmed length, so an arc whose sweep
 * is read wrongly takes the wrong time. tests/gcode/programs/g93_comp_arcs.ngc
 * (also compared with rs274 for its geometry): arc A, R 10 about the origin,
 * counter-clockwise from 150 to 210 degrees (crossing +-180: 60 degrees), the
 * tool inside it (left of a G3) on R 8; arc B, R 10, clockwise for 270
 * degrees, the tool outside it on R 12. Every block takes 1/F = 1 s as
 * programmed; a compensated arc takes (its length) / (F x the programmed
 * length) = R_comp / R of it whatever its sweep: 0.8 s and 1.2 s. */
static void test_arc_angles_inverse_time_comp(void)
{
    char *text;
    size_t n;
    fm_error err;
    const char *path = "gcode/programs/g93_comp_arcs.ngc";
    CHECK(fm_file_read(path, NULL, 1 << 16, &text, &n, &err) == FM_OK);
    if (!text) return;
    CHECK(run(text, &err) == FM_OK);
    free(text);
    CHECK(ngot == 5);
    if (ngot != 5) return;
    double s3 = 5 * sqrt(3.0);
    /* the entry line ends on arc A's compensated circle (R 8) at 150 degrees */
    CHECK(got[1].kind == FM_MOTION_LINE);
    CHECK_NEAR(got[1].end[0], -0.8 * s3, 1e-6);
    CHECK_NEAR(got[1].end[1], 4, 1e-6);
    /* its time: the compensated length over F x the programmed length 20 */
    CHECK_NEAR(got[1].t1 - got[1].t0,
               hypot(1.3397459622 + 0.8 * s3, 22.3205080757 - 4) / 20.0, 1e-6);
    const fm_motion *a = &got[2], *b = &got[3];
    CHECK(a->kind == FM_MOTION_ARC && a->turns == 1);
    CHECK_NEAR(a->center[0], 0, 1e-6);
    CHECK_NEAR(a->center[1], 0, 1e-6);
    CHECK_NEAR(a->end[0], -0.8 * s3, 1e-6); /* 8 (cos 210, sin 210) */
    CHECK_NEAR(a->end[1], -4, 1e-6);
    CHECK_NEAR(a->t1 - a->t0, 0.8, 1e-6);
    CHECK(b->kind == FM_MOTION_ARC && b->turns == -1);
    CHECK_NEAR(b->center[0], -2 * s3, 1e-6);
    CHECK_NEAR(b->center[1], -10, 1e-6);
    CHECK_NEAR(b->end[0], -2 * s3 - 6, 1e-6); /* centre + 12 (cos 120, sin 120) */
    CHECK_NEAR(b->end[1], -10 + 6 * sqrt(3.0), 1e-6);
    CHECK_NEAR(b->t1 - b->t0, 1.2, 1e-6);
}

static void put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

/* A program file and the subroutine (LinuxCNC) and subprogram (Fanuc) files
 * it loads are read within max_program_bytes, which counts what the program
 * has loaded already: a budget of exactly both files runs, one byte less
 * refuses the second file and names it; a program file over the budget and
 * a missing one are refused with the file named. */
static void test_program_files(void)
{
    char dir[] = "/tmp/fm_gcode_files_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char prog[256], sub[256], fprog[256], fsub[256], missing[256], want[512];
    snprintf(prog, sizeof prog, "%s/main.ngc", dir);
    snprintf(sub, sizeof sub, "%s/twice.ngc", dir);
    snprintf(fprog, sizeof fprog, "%s/main.nc", dir);
    snprintf(fsub, sizeof fsub, "%s/O4000.nc", dir);
    snprintf(missing, sizeof missing, "%s/missing.ngc", dir);
    const char *prog_text = "o<twice> call\nM2\n";
    const char *sub_text = "o<twice> sub\nG0 X1\no<twice> endsub\n";
    const char *fprog_text = "O0001\nM98 P4000\nM30\n";
    const char *fsub_text = "O4000\nG00 X2.\nM99\n";
    put_file(prog, prog_text);
    put_file(sub, sub_text);
    put_file(fprog, fprog_text);
    put_file(fsub, fsub_text);
    fm_gcode_options o;
    fm_error err;

    fm_gcode_options_default(&o);
    o.subroutine_path = dir;
    o.max_program_bytes = strlen(prog_text) + strlen(sub_text);
    ngot = 0;
    CHECK(fm_gcode_run_file(prog, &o, collect, NULL, NULL, &err) == FM_OK);
    CHECK(ngot == 1 && got[0].end[0] == 1);
    o.max_program_bytes--;
    CHECK(fm_gcode_run_file(prog, &o, collect, NULL, NULL, &err) == FM_ERR_LIMIT);
    snprintf(want, sizeof want, "subroutine file %s makes the program larger than %zu bytes", sub,
             o.max_program_bytes);
    CHECK_STR_CONTAINS(err.message, want);
    CHECK(strcmp(err.file, prog) == 0 && err.line == 1);

    o.max_program_bytes = strlen(prog_text) - 1;
    CHECK(fm_gcode_run_file(prog, &o, collect, NULL, NULL, &err) == FM_ERR_LIMIT);
    snprintf(want, sizeof want, "larger than the limit of %zu bytes (max_program_bytes)",
             strlen(prog_text) - 1);
    CHECK_STR_CONTAINS(err.message, want);
    CHECK(strcmp(err.file, prog) == 0);

    fm_gcode_options_default(&o);
    CHECK(fm_gcode_run_file(missing, &o, collect, NULL, NULL, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "cannot open");
    CHECK_STR_CONTAINS(err.message, missing);

    fm_gcode_options_default(&o);
    o.dialect = FM_GCODE_FANUC;
    o.max_program_bytes = strlen(fprog_text) + strlen(fsub_text);
    ngot = 0;
    CHECK(fm_gcode_run_file(fprog, &o, collect, NULL, NULL, &err) == FM_OK);
    CHECK(ngot == 1 && got[0].end[0] == 2);
    o.max_program_bytes--;
    CHECK(fm_gcode_run_file(fprog, &o, collect, NULL, NULL, &err) == FM_ERR_LIMIT);
    snprintf(want, sizeof want, "subprogram file %s makes the program larger than %zu bytes",
             fsub, o.max_program_bytes);
    CHECK_STR_CONTAINS(err.message, want);
    CHECK(strcmp(err.file, fprog) == 0 && err.line == 2);

    remove(prog);
    remove(sub);
    remove(fprog);
    remove(fsub);
    rmdir(dir);
}

int main(void)
{
    test_arc_angles_inverse_time_comp();
    test_times();
    test_units_offsets();
    test_tool_tip();
    test_start_state();
    test_skip_and_stop();
    test_words();
    test_errors();
    test_program_files();
    return test_summary("gcode_unit");
}
