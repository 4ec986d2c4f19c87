/* test_gcode_curves.c: G-code constructs whose geometry is checked by
 * volume through the whole pipeline (issue 15):
 *  - splines: a program of G5, G5.1 and G5.2/G5.3 curves removes the same
 *    volume, within 0.1% at 0.1 mm voxels, as a dense G1 polyline built here
 *    from the curve definitions in docs/gcode.md (Bezier curves and LinuxCNC's
 *    clamped uniform NURBS, evaluated by the Cox-de Boor recursion, not by
 *    the interpreter's Bezier decomposition);
 *  - probing: a program that finds the stock top with G38.2 and faces 1 mm
 *    below the height it found removes the closed-form volume. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 4, \"flute_length\": 20, \"length\": 40},"
    "{\"number\": 2, \"shape\": \"ball\", \"diameter\": 3, \"flute_length\": 20, \"length\": 40},"
    "{\"number\": 3, \"shape\": \"flat\", \"diameter\": 10, \"flute_length\": 20, \"length\": 40}]}";

static fm_tool_table tools;

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
    fm_stock_free(result.stock);
    return result.removed_volume_mm3;
}

/* ------------------------------------------------------------ splines -- */

/* Cox-de Boor basis N_{i,k}(u) on knots U (half-open spans; the last span
 * closed so that u = U[m] is the last control point). */
static double basis(int i, int k, double u, const double *U, int m)
{
    if (k == 1) {
        if (U[i] <= u && u < U[i + 1]) return 1;
        if (u == U[m] && U[i] < u && u <= U[i + 1]) return 1;
        return 0;
    }
    double a = 0, b = 0;
    if (U[i + k - 1] > U[i]) a = (u - U[i]) / (U[i + k - 1] - U[i]) * basis(i, k - 1, u, U, m);
    if (U[i + k] > U[i + 1]) b = (U[i + k] - u) / (U[i + k] - U[i + 1]) * basis(i + 1, k - 1, u, U, m);
    return a + b;
}

/* Append to buf "G1 X.. Y.." lines along the NURBS of order k through n
 * control points P (x, y, w), LinuxCNC's knots: k zeros, 1..n-k, then n-k+1
 * k times. */
static void nurbs_polyline(char *buf, size_t cap, const double *P, int n, int k, int pieces)
{
    double U[64];
    int m = n + k - 1;
    for (int i = 0; i <= m; i++) U[i] = i < k ? 0 : i <= n - 1 ? i - k + 1 : n - k + 1;
    for (int j = 1; j <= pieces; j++) {
        double u = U[m] * j / pieces, x = 0, y = 0, w = 0;
        for (int i = 0; i < n; i++) {
            double b = basis(i, k, u, U, m) * P[3 * i + 2];
            x += b * P[3 * i];
            y += b * P[3 * i + 1];
            w += b;
        }
        size_t len = strlen(buf);
        snprintf(buf + len, cap - len, "G1 X%.9f Y%.9f\n", x / w, y / w);
    }
}

static void test_splines(void)
{
    /* the curves of the program below, as control points (docs/gcode.md:
     * G5's second control point is the start + (I, J), its third the end +
     * (P, Q)): G5 from (0,0) with I0 J10 P0 Q-10 to (20,0): (0,0) (0,10)
     * (20,-10) (20,0); G5 with I J omitted (the previous end tangent
     * continues: I = -P = 0, J = -Q = 10) P0 Q-10 to (40,0); G5.1 I-5 J8 to
     * (30,12); G5.2 through (20,12) w1, (20,4) w2, (10,4) w0.5, (10,12) w1,
     * order 3 */
    const char *head = "G21 G90 G17 F1000 S10000 M3\nT2 M6\nG0 X0 Y0 Z1\nG1 Z-1\n";
    char *spline = malloc(4096), *poly = malloc(1 << 20);
    snprintf(spline, 4096,
             "%sG5 I0 J10 P0 Q-10 X20 Y0\nG5 P0 Q-10 X40 Y0\nG5.1 I-5 J8 X30 Y12\n"
             "G1 X20\nG5.2 X20 Y4 P2 L3\nX10 Y4 P0.5\nX10 Y12 P1\nG5.3\nG0 Z5\nM2\n", head);
    snprintf(poly, 1 << 20, "%s", head);
    double c1[] = {0, 0, 1, 0, 10, 1, 20, -10, 1, 20, 0, 1};
    double c2[] = {20, 0, 1, 20, 10, 1, 40, -10, 1, 40, 0, 1};
    double c3[] = {40, 0, 1, 35, 8, 1, 30, 12, 1};
    double c4[] = {20, 12, 1, 20, 4, 2, 10, 4, 0.5, 10, 12, 1};
    nurbs_polyline(poly, 1 << 20, c1, 4, 4, 2000);
    nurbs_polyline(poly, 1 << 20, c2, 4, 4, 2000);
    nurbs_polyline(poly, 1 << 20, c3, 3, 3, 2000);
    strcat(poly, "G1 X20 Y12\n");
    nurbs_polyline(poly, 1 << 20, c4, 4, 3, 4000);
    strcat(poly, "G0 Z5\nM2\n");
    const char *stock = "box:-5,-15,-3,45,20,0";
    double vs = removed(spline, stock, 0.1);
    double vp = removed(poly, stock, 0.1);
    double rel = fabs(vs - vp) / vp;
    printf("splines: removed %.3f mm3, dense polyline %.3f mm3, difference %.4f%%\n", vs, vp,
           100 * rel);
    CHECK(vp > 100);
    CHECK(rel <= 0.001);
    free(spline);
    free(poly);
}

/* ------------------------------------------------------------ probing -- */

static void test_probe_then_face(void)
{
    /* Stock top at Z = 7.3 (unknown to the program), footprint 24 x 16 at
     * X 10..34, Y 10..26. The 10 mm flat end mill probes down from Z 20,
     * then faces 1 mm below the found height in passes 6 mm apart, starting
     * and ending outside the stock in X, so the removed volume is the whole
     * 1 mm layer of the stock's footprint. */
    const char *program =
        "G21 G90 G17 F600 S8000 M3\nT3 M6\n"
        "G0 Z20\nG0 X22 Y18\n"
        "G38.2 Z0 F200\n"
        "#<top> = #5063\n"
        "(debug, found the top at #<top>, ok #5070)\n"
        "G0 Z[#<top> + 2]\n"
        "G0 X0 Y6\n"
        "G1 Z[#<top> - 1] F600\n"
        "#<y> = 6\n"
        "o1 while [#<y> LE 30]\n"
        "  G1 Y#<y>\n"
        "  G1 X44\n"
        "  #<y> = [#<y> + 6]\n"
        "  G1 Y#<y>\n"
        "  G1 X0\n"
        "  #<y> = [#<y> + 6]\n"
        "o1 endwhile\n"
        "G0 Z30\nM2\n";
    double v = removed(program, "box:10,10,0,34,26,7.3", 0.1);
    double exact = 24.0 * 16.0 * 1.0;
    double rel = fabs(v - exact) / exact;
    printf("probe then face: removed %.3f mm3, closed form %.3f mm3, error %.3f%%\n", v, exact,
           100 * rel);
    CHECK(rel <= 0.005);
}

int main(void)
{
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "%s\n", fm_error_format(&err, buf, sizeof buf));
        return 1;
    }
    test_splines();
    test_probe_then_face();
    fm_tool_table_free(&tools);
    return test_summary("gcode curves and probing");
}
