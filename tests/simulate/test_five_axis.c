/* test_five_axis.c: the same 5-axis motion as G-code on an AC trunnion
 * (A tilting the table about X, C turning it about Z, both lines through
 * the origin) and as a parametric trajectory whose tip and axis are the
 * trunnion's kinematics written out as expressions, through the whole job
 * runner at 0.2 mm (0.4 mm under the sanitizers, where the 0.2 mm run takes
 * about ten CPU minutes): they must remove the same volume (within 0.1%). With TCP the tip runs
 * the programmed line and the axis is Rz(-c) Rx(-a) (0, 0, 1) =
 * (sin a sin c, sin a cos c, cos a); without TCP the joints move linearly
 * and the tip is Rz(-c) Rx(-a) X(u). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"ball\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

static fm_tool_table tools;

static double removed(const char *program, const char *name, const fm_machine *machine)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = name;
    spec.stock_spec = "box:-10,-10,-12,40,30,-1";
    spec.tools = &tools;
    spec.stock.voxel_mm = test_coarse() ? 0.4 : 0.2;
    spec.machine = machine;
    fm_job_result result;
    fm_error err;
    if (fm_job_run(&spec, NULL, &result, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        return NAN;
    }
    fm_stock_free(result.stock);
    return result.removed_volume_mm3;
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
    mc.tcp = tcp;
    return mc;
}

/* G-code: down to (0, 0, 2) in the air, then X12 Y6 Z-4 with A 0 -> 30 and
 * C 0 -> 45 degrees. */
static const char *gcode = "G21 G90 G94\nT1 M6\nG0 X0 Y0 Z10\nG1 Z2 F600\nG1 X12 Y6 Z-4 A30 C45 F300\nM2\n";

/* a = 30 u, c = 45 u degrees in radians */
#define A_RAD "(0.5235987755982988*u)"
#define C_RAD "(0.7853981633974483*u)"

static const char *traj_tcp =
    "{\"units\": \"mm\", \"tool\": 1, \"segments\": ["
    "{\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": \"10 - 8*u\"},"
    "{\"t\": [1, 2], \"x\": \"12*u\", \"y\": \"6*u\", \"z\": \"2 - 6*u\","
    " \"axis\": [\"sin(" A_RAD ")*sin(" C_RAD ")\", \"sin(" A_RAD ")*cos(" C_RAD ")\", \"cos(" A_RAD ")\"]}]}";

/* Without TCP: X(u) = (12u, 6u, 2 - 6u) on the machine, q = Rx(-a) X =
 * (X0, X1 cos a + X2 sin a, -X1 sin a + X2 cos a), tip = Rz(-c) q =
 * (q0 cos c + q1 sin c, -q0 sin c + q1 cos c, q2). */
#define X0 "(12*u)"
#define X1 "(6*u)"
#define X2 "(2 - 6*u)"
#define Q1 "(" X1 "*cos(" A_RAD ") + " X2 "*sin(" A_RAD "))"
#define Q2 "(-" X1 "*sin(" A_RAD ") + " X2 "*cos(" A_RAD "))"
static const char *traj_joint =
    "{\"units\": \"mm\", \"tool\": 1, \"segments\": ["
    "{\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": \"10 - 8*u\"},"
    "{\"t\": [1, 2], \"x\": \"" X0 "*cos(" C_RAD ") + " Q1 "*sin(" C_RAD ")\","
    " \"y\": \"-" X0 "*sin(" C_RAD ") + " Q1 "*cos(" C_RAD ")\", \"z\": \"" Q2 "\","
    " \"axis\": [\"sin(" A_RAD ")*sin(" C_RAD ")\", \"sin(" A_RAD ")*cos(" C_RAD ")\", \"cos(" A_RAD ")\"]}]}";

int main(void)
{
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        fprintf(stderr, "tools: %s\n", err.message);
        return 1;
    }
    double by_gcode[2] = {0, 0};
    for (int tcp = 1; tcp >= 0; tcp--) {
        fm_machine mc = trunnion(tcp);
        double g = by_gcode[tcp] = removed(gcode, "five.ngc", &mc);
        const double c0 = fm_clock_cpu_s();
        double t = removed(tcp ? traj_tcp : traj_joint, "five.json", NULL);
        double rel = fabs(g - t) / t;
        printf("5-axis move %s: G-code removes %.3f mm^3, the trajectory %.3f mm^3 (%.4f%%; the trajectory "
               "took %.1f s of CPU)\n",
               tcp ? "with TCP" : "without TCP", g, t, 100 * rel, fm_clock_cpu_s() - c0);
        CHECK(g > 50);
        CHECK(rel <= 1e-3);
    }
    /* The two kinds of motion differ: the curve without TCP is not the line. */
    CHECK(fabs(by_gcode[1] - by_gcode[0]) > 0.01 * by_gcode[1]);
    fm_tool_table_free(&tools);
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
