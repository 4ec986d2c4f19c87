/* bench_cam_stats.c: where one program's simulation spends its work, for a program file (bench/cam's CAM output;
 * bench_simulate's breakdown is for its built-in cases only). Runs the program through the job runner
 * (daemon/runner/job.h, as frepmill simulate does) and prints the cut statistics per motion and per cut: voxels
 * the swept field was evaluated at against voxels the cut changed, leaves, interval boxes, the voxel pass's share
 * in the swept field, and the ratio of the job's CPU to its floor (bench_simulate's: voxels changed x OpenVDB's
 * bare update, timed on the final stock). Never a test.
 *
 * Usage: bench_cam_stats PROGRAM STOCK TOOLS [--voxel MM] [--initial-tool N] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "stock/stock.h"
#include "bench_clock.h"

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: bench_cam_stats PROGRAM STOCK TOOLS [--voxel MM] [--initial-tool N]\n");
        return 2;
    }
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = argv[1];
    spec.program_kind = FM_PROGRAM_GCODE;
    spec.stock_spec = argv[2];
    spec.tools_path = argv[3];
    spec.stock.voxel_mm = 0.2;
    for (int i = 4; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--voxel") == 0) {
            spec.stock.voxel_mm = atof(argv[i + 1]);
        } else if (strcmp(argv[i], "--initial-tool") == 0) {
            spec.initial_tool = atoi(argv[i + 1]);
        } else {
            fprintf(stderr, "bench_cam_stats: unknown option %s\n", argv[i]);
            return 2;
        }
    }
    fm_job_result r;
    fm_error err;
    double c0 = bench_cpu_s(), w0 = bench_wall_s();
    if (fm_job_run(&spec, NULL, &r, &err) != FM_OK) {
        fprintf(stderr, "bench_cam_stats: %s\n", err.message);
        return 1;
    }
    double cpu = bench_cpu_s() - c0, wall = bench_wall_s() - w0;
    const fm_stock_cut_stats *cs = &r.cut_stats;
    double motions = r.motions > 0 ? (double)r.motions : 1, cuts = r.cuts > 0 ? (double)r.cuts : 1;
    printf("%s at %g mm: %ld motions in %ld cuts, removed %.1f mm3; %.2f s wall, %.2f s CPU, peak %.0f MB\n",
           argv[1], spec.stock.voxel_mm, r.motions, r.cuts, r.removed_volume_mm3, wall, cpu,
           r.peak_memory_bytes / 1048576.0);
    printf("  voxels evaluated %zu (%.0f per motion, %.0f per cut) in %zu leaves (%.1f per cut); voxels changed %zu "
           "(%.0f per motion, %.0f per cut) in %zu leaves: %.1f evaluated per changed\n",
           cs->voxels_evaluated, cs->voxels_evaluated / motions, cs->voxels_evaluated / cuts, cs->leaves_evaluated,
           cs->leaves_evaluated / cuts, cs->voxels_changed, cs->voxels_changed / motions, cs->voxels_changed / cuts,
           cs->leaves_changed, cs->voxels_changed ? (double)cs->voxels_evaluated / (double)cs->voxels_changed : 0);
    printf("  %zu interval boxes (%.0f per cut), %zu interior boxes; voxels uncertain %zu\n", cs->intervals,
           cs->intervals / cuts, cs->interior_boxes, r.voxels_uncertain);
    double share = cs->time_leaves_cpu_s > 0 ? cs->time_field_cpu_s / cs->time_leaves_cpu_s : 0;
    printf("  cuts: interval pass (serial) %.2f s + voxel pass (parallel) %.2f s + topology and bookkeeping (serial) "
           "%.2f s of %.2f s wall; voxel pass %.0f%% in the swept field (%.2f thread-s in all)\n",
           cs->time_classify_s, cs->time_voxels_s, cs->time_apply_s, wall, 100 * share, cs->time_leaves_cpu_s);
    size_t timed = 0;
    double per = fm_stock_time_bare_update(r.stock, &timed);
    double floor_s = per * (double)cs->voxels_changed;
    if (floor_s > 0)
        printf("  floor: %zu voxels changed x %.2f ns = %.3f thread-s; CPU / floor = %.1f\n", cs->voxels_changed,
               per * 1e9, floor_s, cpu / floor_s);
    fm_job_result_release(&r);
    return 0;
}
