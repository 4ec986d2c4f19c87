/* bench_gcode.c: lines interpreted per second on a generated 1,000,000-line
 * program (lines, arcs, a canned cycle, comments, expressions), and the ratio
 * to a floor: splitting the same text into lines and reading every number
 * with strtod, the least any interpreter has to do. Wall and CPU time are
 * both printed: on a shared machine the CPU figure is the comparable one.
 * The goal (430,000 lines/s) is the LinuxCNC dialect's; the Fanuc dialect's
 * figure on the same text follows. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "toolpaths/gcode/gcode.h"
#include "bench_clock.h"

static int count(void *user, const fm_motion *m)
{
    long *n = user;
    (*n)++;
    (void)m;
    return 0;
}

int main(int argc, char **argv)
{
    long lines = argc > 1 ? atol(argv[1]) : 1000000;
    size_t cap = (size_t)lines * 48 + 64, len = 0;
    char *text = malloc(cap);
    if (!text) return 3;
    len += (size_t)snprintf(text + len, cap - len, "G21 G90 G17 F1200 S10000 M3\n");
    for (long i = 1; len + 64 < cap && i < lines - 1; i++) {
        long grp = i / 8; /* one little pocket pass per group of 8 lines */
        double x = (double)(grp % 1000) * 0.1, y = (double)((grp / 1000) % 1000) * 0.1;
        switch (i % 8) {
        case 0: len += (size_t)snprintf(text + len, cap - len, "G0 X%.3f Y%.3f Z1\n", x, y); break;
        case 1: len += (size_t)snprintf(text + len, cap - len, "G1 Z-0.5 (plunge)\n"); break;
        case 2: len += (size_t)snprintf(text + len, cap - len, "N%ld G1 X%.3f Y%.3f\n", i, x + 1, y); break;
        case 3: len += (size_t)snprintf(text + len, cap - len, "G2 X%.3f Y%.3f I0.5 J0\n", x + 2, y); break;
        case 4: len += (size_t)snprintf(text + len, cap - len, "G3 X%.3f Y%.3f R0.5\n", x + 1, y); break;
        case 5: len += (size_t)snprintf(text + len, cap - len, "G1 X[%.3f + 0.25] Y%.3f\n", x, y); break;
        case 6: len += (size_t)snprintf(text + len, cap - len, "G1 X%.3f Y%.3f Z0.2 F900\n", x, y); break;
        default: len += (size_t)snprintf(text + len, cap - len, "G0 Z2\n"); break;
        }
    }
    len += (size_t)snprintf(text + len, cap - len, "M2\n");

    /* floor: split into lines and strtod every number */
    double t0 = bench_wall_s(), sink = 0;
    long nlines = 0;
    for (size_t i = 0; i < len;) {
        size_t e = i;
        while (e < len && text[e] != '\n') e++;
        for (size_t k = i; k < e; k++) {
            char c = text[k];
            if ((c >= '0' && c <= '9') || c == '-' || c == '.') {
                char *end;
                sink += strtod(text + k, &end);
                k = (size_t)(end - text);
            }
        }
        nlines++;
        i = e + 1;
    }
    double floor_s = bench_wall_s() - t0;

    long motions = 0;
    fm_error err;
    fm_gcode_summary sum;
    t0 = bench_wall_s();
    double c0 = bench_cpu_s();
    fm_status st = fm_gcode_run_string(text, len, "bench", NULL, count, &motions, &sum, &err);
    double run_s = bench_wall_s() - t0, run_cpu = bench_cpu_s() - c0;
    if (st) {
        char buf[600];
        fprintf(stderr, "%s\n", fm_error_format(&err, buf, sizeof buf));
        return 2;
    }
    printf("program: %ld lines, %.1f MB, %ld motions (checksum %.0f)\n", nlines, len / 1e6,
           motions, sink);
    printf("interpreter: %.3f s wall, %.0f lines/s; %.3f s CPU (user+sys), %.0f lines per CPU "
           "second\n", run_s, sum.lines / run_s, run_cpu, sum.lines / run_cpu);
    printf("goal >= 430000 lines/s: wall %.2fx, CPU %.2fx the goal (wall counts time other "
           "processes took; compare uptime's load)\n", sum.lines / run_s / 430000.0,
           sum.lines / run_cpu / 430000.0);
    printf("floor (split lines + strtod): %.3f s, %.0f lines/s\n", floor_s, nlines / floor_s);
    /* the same text in the Fanuc dialect (its integers mean the least input
     * increment there, so the geometry differs; the work per line is what
     * is measured) */
    fm_gcode_options fopt;
    fm_gcode_options_default(&fopt);
    fopt.dialect = FM_GCODE_FANUC;
    long fmotions = 0;
    fm_gcode_summary fsum;
    t0 = bench_wall_s();
    c0 = bench_cpu_s();
    st = fm_gcode_run_string(text, len, "bench", &fopt, count, &fmotions, &fsum, &err);
    double fan_s = bench_wall_s() - t0, fan_cpu = bench_cpu_s() - c0;
    if (st) {
        char buf[600];
        fprintf(stderr, "fanuc: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 2;
    }
    printf("fanuc dialect: %.3f s wall, %.0f lines/s; %.3f s CPU, %.0f lines per CPU second "
           "(%ld motions)\n", fan_s, fsum.lines / fan_s, fan_cpu, fsum.lines / fan_cpu, fmotions);
    printf("ratio interpreter/floor time: %.1f\n", run_s / floor_s);
    free(text);
    return 0;
}
