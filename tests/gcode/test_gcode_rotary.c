/* test_gcode_rotary.c: the rotary axes A, B, C in the G-code front end
 * (toolpaths/gcode/gcode_rotary.c): times of rotary moves (F in degrees per
 * minute when only rotary axes move, the XYZ length otherwise, G93 inverse
 * time, coordinated rapids), LinuxCNC's wrapped rotary axes, TCP on and
 * off (G43.4, G49), and the joint values, machine and tool axis each
 * motion carries. (A B C end values against rs274 are in rs274_diff.py.) */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test.h"
#include "sweep/sweep.h"
#include "toolpaths/gcode/gcode.h"

#define MAXM 200

static fm_motion got[MAXM];
static int ngot;

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    return 0;
}

static fm_status run_machine(const char *text, const fm_machine *mc, fm_error *err)
{
    fm_gcode_options opt;
    fm_gcode_options_default(&opt);
    opt.machine = mc;
    ngot = 0;
    return fm_gcode_run_string(text, strlen(text), "r.ngc", &opt, collect, NULL, NULL, err);
}

static fm_machine trunnion(int tcp)
{
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 2;
    mc.rotary[0].letter = 0;
    mc.rotary[0].carries = FM_ROTARY_TABLE;
    mc.rotary[0].around[0] = 1;
    mc.rotary[1].letter = 2;
    mc.rotary[1].carries = FM_ROTARY_TABLE;
    mc.rotary[1].around[2] = 1;
    mc.rotary[1].wrapped = 1;
    mc.tcp = tcp;
    return mc;
}

static void test_times(void)
{
    fm_machine mc = trunnion(0);
    fm_error err;
    CHECK(run_machine("G21 G90 G94\nG1 A90 F360\nG1 X30 A0 F600\nG0 A-60\nG0 X10 A-55\n"
                      "G93 G1 X0 C45 F4\nG1 C90 F0.5\nM2\n",
                      &mc, &err) == FM_OK);
    CHECK(ngot == 6);
    /* only A: 90 degrees at 360 degrees per minute */
    CHECK_NEAR(got[0].t1 - got[0].t0, 15, 1e-12);
    CHECK_NEAR(got[0].rotary_start[0], 0, 0);
    CHECK_NEAR(got[0].rotary_end[0], 90, 0);
    CHECK(got[0].machine == &mc && got[0].tcp == 0);
    /* X with A: the feed is along XYZ, 30 mm at 600 mm/min */
    CHECK_NEAR(got[1].t1 - got[1].t0, 3, 1e-12);
    /* rapids: the longer of the XYZ length and the turn, at 5000 per minute */
    CHECK_NEAR(got[2].t1 - got[2].t0, 60.0 / 5000 * 60, 1e-12);
    CHECK_NEAR(got[3].t1 - got[3].t0, 20.0 / 5000 * 60, 1e-12);
    /* G93: 1/F minutes whatever moves */
    CHECK_NEAR(got[4].t1 - got[4].t0, 15, 1e-12);
    CHECK_NEAR(got[5].t1 - got[5].t0, 120, 1e-12);
    /* the tool axis in the workpiece frame at A = 90 (table about +X): the
     * machine's +Z is the workpiece's Rx(-90) (0, 0, 1) = (0, 1, 0) */
    CHECK_NEAR(got[0].axis_end[0], 0, 1e-15);
    CHECK_NEAR(got[0].axis_end[1], 1, 1e-15);
    CHECK_NEAR(got[0].axis_end[2], 0, 1e-15);
    /* without a machine the words are followed but carry no machine */
    CHECK(run_machine("G1 A90 F360\nM2\n", NULL, &err) == FM_OK);
    CHECK(ngot == 1 && got[0].machine == NULL && got[0].rotary_end[0] == 90);
    CHECK_NEAR(got[0].axis_end[2], 1, 0);
}

/* LinuxCNC's wrapped rotary: |C| modulo 360 is the target, its sign the
 * direction of travel. */
static void test_wrapped(void)
{
    fm_machine mc = trunnion(0);
    fm_error err;
    CHECK(run_machine("G0 C350\nG0 C10\nG0 C-350\nG0 C-0\nG0 A370\nM2\n", &mc, &err) == FM_OK);
    CHECK(ngot == 5);
    CHECK_NEAR(got[0].rotary_end[2], 350, 0);
    CHECK_NEAR(got[1].rotary_end[2], 370, 0);   /* forwards from 350 to 10 */
    CHECK_NEAR(got[2].rotary_end[2], 350, 0);   /* backwards from 370 (10) to 350 */
    CHECK_NEAR(got[3].rotary_end[2], 0, 0);     /* backwards from 350 to 0 */
    CHECK_NEAR(got[4].rotary_end[0], 370, 0);   /* A is not wrapped */
    fm_status st = run_machine("G0 C400\n", &mc, &err);
    CHECK(st == FM_ERR_INPUT && err.line == 1 && err.column == 4);
    CHECK_STR_CONTAINS(err.message, "between -360 and 360");
    /* incremental moves are not unwrapped */
    CHECK(run_machine("G91 G0 C400\nM2\n", &mc, &err) == FM_OK);
    CHECK_NEAR(got[0].rotary_end[2], 400, 0);
}

static void test_tcp(void)
{
    fm_machine plain = trunnion(0), tcp = trunnion(1);
    fm_error err;
    fm_status st = run_machine("G21\nG43.4 H0\n", &plain, &err);
    CHECK(st == FM_ERR_INPUT && err.line == 2);
    CHECK_STR_CONTAINS(err.message, "tcp");
    st = run_machine("G43.4\n", NULL, &err);
    CHECK(st == FM_ERR_INPUT);
    /* on from the start with a TCP machine, off after G49, on after G43.4 */
    CHECK(run_machine("G0 X1 A10\nG49\nG0 X2\nG43.4\nG0 X3 A20\nM2\n", &tcp, &err) == FM_OK);
    CHECK(ngot == 3);
    CHECK(got[0].tcp == 1 && got[1].tcp == 0 && got[2].tcp == 1);
    /* with TCP the tip is the programmed point in the workpiece frame */
    double tip[3], ax[3];
    fm_motion_pose_at(&got[2], 0.5, tip, ax);
    CHECK_NEAR(tip[0], 2.5, 1e-12);
    CHECK_NEAR(tip[1], 0, 1e-12);
    CHECK_NEAR(tip[2], 0, 1e-12);
    /* a rotary-only move with TCP: the tip stays, the axis turns */
    CHECK(run_machine("G1 X5 Y0 Z10 F100\nG1 A30\nM2\n", &tcp, &err) == FM_OK);
    fm_motion_pose_at(&got[1], 0.5, tip, ax);
    CHECK_NEAR(tip[0], 5, 1e-12);
    CHECK_NEAR(tip[2], 10, 1e-12);
    CHECK_NEAR(ax[1], sin(15 * FM_PI / 180), 1e-12);
}

int main(void)
{
    test_times();
    test_wrapped();
    test_tcp();
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
