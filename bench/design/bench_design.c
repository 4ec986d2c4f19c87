/* bench_design.c: what the design comparison (`frepmill simulate --design`)
 * costs beside the simulation it follows, through the job runner at 0.1 mm:
 *  - the demo pocket (deploy/demo/pocket.ngc) against its design model
 *    deploy/demo/part.hf (a HyperFun field);
 *  - LinuxCNC's 3D_Chips.ngc against the .vdb snapshot of its own result
 *    (the design read onto the stock's grid as it is: the comparison's own
 *    cost, with no design to build);
 *  - with --stl, both against the STL of their own result (OpenVDB's
 *    mesh-to-volume of a mesh with voxel-sized triangles: the worst case
 *    of an STL design, minutes of CPU).
 * Each program is simulated once without a design (the simulation's cost;
 * that run also writes the snapshot or STL), then with its design. Issue
 * 16's goal: the comparison (design build + compare + blame) under 20% of
 * the simulation. Prints wall and CPU times of each step, the ratios (CPU is
 * the figure to trust on a loaded machine), the floor under building the
 * design (taking its grid's memory fresh) and the load.
 *
 * Usage: bench_design [--stl] [OUT_DIR [CHIPS_PROGRAM]]; run from the
 * source tree's root. OUT_DIR (default /tmp) gets the snapshots and STL
 * files. 3D_Chips is skipped with a message when LinuxCNC's ncfiles are
 * absent. */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS */
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <time.h>

#include "job.h"
#include "outputs.h"
#include "bench_clock.h"

#define GOAL 0.20

static double load1(void)
{
    double l = -1;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1) l = -1;
        fclose(f);
    }
    return l;
}

typedef struct job_case {
    const char *name, *program, *tools, *stock;
} job_case;

/* The simulation alone; writes the final stock to out (.vdb or .stl) unless
 * out is NULL. */
static int run_plain(const job_case *jc, const char *out, double *wall, double *cpu)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = jc->program;
    spec.tools_path = jc->tools;
    spec.stock_spec = jc->stock;
    spec.stock.voxel_mm = 0.1;
    fm_error err;
    fm_error_clear(&err);
    fm_job_result res;
    const double w0 = bench_wall_s(), c0 = bench_cpu_s();
    fm_status st = fm_job_run(&spec, NULL, &res, &err);
    *wall = bench_wall_s() - w0;
    *cpu = bench_cpu_s() - c0;
    if (st != FM_OK) {
        fprintf(stderr, "bench_design: %s: %s\n", jc->name, err.message);
        return 0;
    }
    printf("%-10s simulate          wall %7.2f s  cpu %7.2f s  (%d motions, removed %.1f mm3)\n",
           jc->name, *wall, *cpu, (int)res.motions, res.removed_volume_mm3);
    if (!out) {
        fm_job_result_release(&res);
        return 1;
    }
    fm_output_options oo;
    fm_output_options_default(&oo);
    oo.coloring = FM_MESH_COLOR_NONE;
    const char *paths[1] = {out};
    st = fm_outputs_write(paths, 1, res.stock, &oo, &err);
    fm_job_result_release(&res);
    if (st != FM_OK) {
        fprintf(stderr, "bench_design: %s: %s\n", out, err.message);
        return 0;
    }
    return 1;
}

/* The floor under building a design grid of the given size: taking that
 * much fresh memory (an anonymous map, one write per 4 kB page), which the
 * grid's leaves cannot avoid. On the 2-core VM this costs about 17 us a
 * page (typically well under 1 us on bare hardware; not measured here).
 * CPU seconds, or -1. */
static double fresh_memory_cpu_s(size_t bytes)
{
    if (bytes == 0) return 0;
    char *p = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return -1;
    const double c0 = bench_cpu_s();
    for (size_t i = 0; i < bytes; i += 4096) ((volatile char *)p)[i] = 1;
    const double cpu = bench_cpu_s() - c0;
    munmap(p, bytes);
    return cpu;
}

static int run_design(const job_case *jc, const char *design, const char *label, double sim_wall,
                      double sim_cpu, int *met)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = jc->program;
    spec.tools_path = jc->tools;
    spec.stock_spec = jc->stock;
    spec.stock.voxel_mm = 0.1;
    spec.design_path = design;
    fm_error err;
    fm_error_clear(&err);
    fm_job_result r;
    const double w0 = bench_wall_s(), c0 = bench_cpu_s();
    fm_status st = fm_job_run(&spec, NULL, &r, &err);
    const double wall = bench_wall_s() - w0, cpu = bench_cpu_s() - c0;
    if (st != FM_OK) {
        fprintf(stderr, "bench_design: %s with %s: %s\n", jc->name, design, err.message);
        return 0;
    }
    const double ratio_cpu = r.design_cpu_s / sim_cpu, ratio_wall = r.design_wall_s / sim_wall;
    const int ok = ratio_cpu <= GOAL;
    *met &= ok;
    printf("%-10s + design %-8s job wall %7.2f s  cpu %7.2f s\n", jc->name, label, wall, cpu);
    printf("    comparison          wall %7.2f s  cpu %7.2f s  ratio to simulate wall %.3f cpu %.3f "
           "(goal <= %.2f: %s)\n",
           r.design_wall_s, r.design_cpu_s, ratio_wall, ratio_cpu, GOAL, ok ? "met" : "NOT met");
    printf("      build design      wall %7.2f s  cpu %7.2f s\n", r.design_build_wall_s,
           r.design_build_cpu_s);
    printf("      compare           wall %7.2f s  cpu %7.2f s\n", r.design_compare_wall_s,
           r.design_compare_cpu_s);
    printf("      blame             wall %7.2f s  cpu %7.2f s\n", r.design_blame_wall_s,
           r.design_blame_cpu_s);
    const size_t grid = r.design ? fm_design_memory_bytes(r.design) : 0;
    const double floor_cpu = fresh_memory_cpu_s(grid);
    printf("      floor: fresh memory for the design's %.1f MB grid  cpu %7.2f s  (%.1f us a 4 kB "
           "page; %.2f of the comparison's cpu)\n",
           grid / 1048576.0, floor_cpu, grid ? floor_cpu * 1e6 / ((double)grid / 4096) : 0,
           r.design_cpu_s > 0 ? floor_cpu / r.design_cpu_s : 0);
    const fm_deviation *d = &r.deviation;
    printf("    deviation: max gouge %.3f mm (%zu regions), max excess %.3f mm (%zu regions), "
           "tolerance %.3f mm\n",
           d->max_gouge_mm, d->gouge_count, d->max_excess_mm, d->excess_count, d->tolerance_mm);
    fm_job_result_release(&r);
    return 1;
}

int main(int argc, char **argv)
{
    int stl = 0;
    if (argc > 1 && !strcmp(argv[1], "--stl")) {
        stl = 1;
        argc--;
        argv++;
    }
    const char *out = argc > 1 ? argv[1] : "/tmp";
    const char *chips = argc > 2 ? argv[2] : "/usr/share/linuxcnc/ncfiles/3D_Chips.ngc";
    const job_case demo = {"demo", "deploy/demo/pocket.ngc", "deploy/demo/tools.json",
                           "box:0,0,-30,100,60,0"};
    const job_case chip = {"3D_Chips", chips, "tests/check/chips_tools.json",
                           "box:-50,-50,-50,50,50,0"};
    setvbuf(stdout, NULL, _IOLBF, 0);
    printf("voxel 0.1 mm; load before %.2f\n", load1());
    int met = 1;
    char path[4096];
    double wall, cpu;

    snprintf(path, sizeof path, "%s/bench_design_demo.stl", out);
    if (!run_plain(&demo, stl ? path : NULL, &wall, &cpu)) return 2;
    if (!run_design(&demo, "deploy/demo/part.hf", "part.hf", wall, cpu, &met)) return 2;
    if (stl && !run_design(&demo, path, "own STL", wall, cpu, &met)) return 2;

    FILE *f = fopen(chips, "r");
    if (!f) {
        printf("3D_Chips: %s is absent (LinuxCNC's ncfiles): skipped\n", chips);
    } else {
        fclose(f);
        snprintf(path, sizeof path, "%s/bench_design_chips.vdb", out);
        if (!run_plain(&chip, path, &wall, &cpu)) return 2;
        if (!run_design(&chip, path, "own vdb", wall, cpu, &met)) return 2;
        if (stl) {
            char mesh[4096];
            snprintf(mesh, sizeof mesh, "%s/bench_design_chips.stl", out);
            double w2, c2;
            if (!run_plain(&chip, mesh, &w2, &c2)) return 2;
            if (!run_design(&chip, mesh, "own STL", wall, cpu, &met)) return 2;
        }
    }
    printf("load after %.2f (figures taken under load are noisy: compare CPU)\n", load1());
    return met ? 0 : 1;
}
