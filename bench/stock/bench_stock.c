/* bench_stock.c: fm_stock_subtract throughput at 0.1 mm voxels.
 * 1. Cut size: a 6 mm flat end mill on straight lines of 1 to 40 mm, 1 mm
 *    deep into the top of a 100 x 100 x 50 mm box, each on fresh material:
 *    time per cut, voxels evaluated, voxels and mm of path per second.
 * 2. Stock size: the same 10 mm cut in boxes from 10 to 200 mm wide: the
 *    time and the leaves evaluated per cut must not grow with the stock
 *    (ARCHITECTURE.md, "Quality bars": work per move follows the swept surface).
 * Usage: bench_stock [repeats]. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "stock/stock.h"
#include "sweep/sweep.h"
#include "bench_clock.h"

static fm_motion line(double x0, double y0, double z, double x1, double y1)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_LINE;
    m.start[0] = x0, m.start[1] = y0, m.start[2] = z;
    m.end[0] = x1, m.end[1] = y1, m.end[2] = z;
    m.axis_start[2] = m.axis_end[2] = 1;
    m.t1 = 1;
    m.block = -1;
    return m;
}

/* Cut repeats parallel lines of length len at y = y0, y0 + 8, ...; returns
 * seconds per cut and fills the summed stats. */
static double cut_lines(fm_stock *s, const fm_tool_part *part, double x0, double y0, double len, int repeats,
                        fm_stock_cut_stats *sum)
{
    memset(sum, 0, sizeof *sum);
    double t = 0;
    for (int k = 0; k < repeats; k++) {
        fm_motion m = line(x0, y0 + 8 * k, -1, x0 + len, y0 + 8 * k);
        fm_field f;
        fm_error err;
        if (fm_sweep_field(&f, &m, part, &err) != FM_OK) {
            fprintf(stderr, "bench_stock: %s\n", err.message);
            exit(1);
        }
        fm_stock_cut_stats st;
        double t0 = bench_wall_s();
        if (fm_stock_subtract(s, &f, NULL, &st, &err) != FM_OK) {
            fprintf(stderr, "bench_stock: %s\n", err.message);
            exit(1);
        }
        t += bench_wall_s() - t0;
        f.release(f.ctx);
        sum->voxels_evaluated += st.voxels_evaluated;
        sum->leaves_evaluated += st.leaves_evaluated;
        sum->intervals += st.intervals;
        sum->removed_mm3 += st.removed_mm3;
    }
    return t / repeats;
}

int main(int argc, char **argv)
{
    int repeats = argc > 1 ? atoi(argv[1]) : 8;
    if (repeats < 1 || repeats > 10) repeats = 8;
    fm_tool_spec spec;
    memset(&spec, 0, sizeof spec);
    spec.number = 1;
    spec.shape = FM_TOOL_FLAT;
    spec.diameter = 6;
    spec.flute_length = 20;
    spec.length = 40;
    spec.center_cutting = 1;
    fm_tool tool;
    fm_error err;
    if (fm_tool_build(&spec, &tool, &err) != FM_OK) {
        fprintf(stderr, "bench_stock: %s\n", err.message);
        return 1;
    }
    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = 0.1;

    printf("bench_stock: 0.1 mm voxels, 6 mm flat end mill 1 mm deep, %d cuts each, on fresh material\n", repeats);
    printf("1. cut size (stock 100 x 100 x 50 mm)\n");
    printf("%8s %12s %14s %12s %14s %12s\n", "line mm", "ms/cut", "voxels/cut", "leaves/cut", "voxels/s", "mm3/cut");
    double lo[3] = {0, 0, -50}, hi[3] = {100, 100, 0};
    double lens[] = {1, 2, 5, 10, 20, 40};
    fm_stock *s;
    for (size_t i = 0; i < sizeof lens / sizeof lens[0]; i++) {
        /* A fresh stock per length: cuts at y = 5, 13, ... never overlap. */
        s = fm_stock_new_box(lo, hi, &opt, &err);
        if (!s) {
            fprintf(stderr, "bench_stock: %s\n", err.message);
            return 1;
        }
        fm_stock_cut_stats st;
        double t = cut_lines(s, &tool.flutes, 5, 5, lens[i], repeats, &st);
        printf("%8.0f %12.3f %14.0f %12.0f %14.3g %12.1f\n", lens[i], 1e3 * t,
               (double)st.voxels_evaluated / repeats, (double)st.leaves_evaluated / repeats,
               st.voxels_evaluated / (t * repeats), st.removed_mm3 / repeats);
        fm_stock_free(s);
    }

    printf("2. stock size (10 mm line)\n");
    printf("%10s %12s %12s %14s %12s\n", "box mm", "grid MB", "ms/cut", "leaves/cut", "intervals");
    double sizes[] = {12, 25, 50, 100, 200};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        double L = sizes[i];
        double blo[3] = {0, 0, -L / 2}, bhi[3] = {L, L, 0};
        s = fm_stock_new_box(blo, bhi, &opt, &err);
        if (!s) {
            printf("%10.0f: %s\n", L, err.message);
            continue;
        }
        fm_stock_cut_stats st;
        int n = L >= 12 + 8 * repeats ? repeats : 1;
        double t = cut_lines(s, &tool.flutes, 1, 3, 10, n, &st);
        printf("%10.0f %12.1f %12.3f %14.0f %12.0f\n", L, fm_stock_memory_bytes(s) / 1048576.0, 1e3 * t,
               (double)st.leaves_evaluated / n, (double)st.intervals / n);
        fm_stock_free(s);
    }
    return 0;
}
