/* bench_check.c: how long `frepmill check` takes on LinuxCNC's 3D_Chips.ngc
 * next to the full simulation at the preview's 0.1 mm (`frepmill
 * simulate`), both through the job runner, for the 10 mm ball with 25 mm
 * flutes (shorter than the 30 mm relief: the shank goes into the stock,
 * findings all along) and with 35 mm flutes (nothing to find). Issue 14's
 * goals: the check within a quarter of the simulation's wall time with the
 * 25 mm flutes, a tenth with the 35 mm ones. Prints wall and CPU times, the
 * ratios, the check's own share of the pass and its work counts.
 *
 * Usage: bench_check [PROGRAM [TOOLS_25 TOOLS_35 [STOCK]]]; run from the
 * source tree's root or give the paths. Exit 77 if the program is absent. */
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "check/check.h"
#include "check_pass.h"
#include "job.h"
#include "bench_clock.h"

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

typedef struct timing {
    double wall, cpu, check_s;
    size_t findings, errors;
    fm_check_stats stats;
} timing;

static int run_check(const char *program, const char *tools, const char *stock, timing *t)
{
    fm_check_pass_input in;
    fm_check_pass_input_default(&in);
    in.spec.program_path = program;
    in.spec.tools_path = tools;
    in.spec.stock_spec = stock;
    fm_error err;
    fm_error_clear(&err);
    fm_check *check = NULL;
    fm_job_result res;
    double w0 = bench_wall_s(), c0 = bench_cpu_s();
    fm_status st = fm_check_pass_run(&in, &check, &res, &err);
    t->wall = bench_wall_s() - w0;
    t->cpu = bench_cpu_s() - c0;
    if (st != FM_OK) {
        fprintf(stderr, "bench_check: check: %s\n", err.message);
        return 0;
    }
    t->check_s = res.check_time_s;
    t->findings = fm_check_count(check);
    t->errors = fm_check_count_severity(check, FM_CHECK_ERROR);
    fm_check_get_stats(check, &t->stats);
    fm_check_free(check);
    return 1;
}

static int run_simulation(const char *program, const char *tools, const char *stock, timing *t)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = program;
    spec.tools_path = tools;
    spec.stock_spec = stock;
    spec.stock.voxel_mm = 0.1;
    fm_error err;
    fm_error_clear(&err);
    fm_job_result res;
    double w0 = bench_wall_s(), c0 = bench_cpu_s();
    fm_status st = fm_job_run(&spec, NULL, &res, &err);
    t->wall = bench_wall_s() - w0;
    t->cpu = bench_cpu_s() - c0;
    if (st != FM_OK) {
        fprintf(stderr, "bench_check: simulation: %s\n", err.message);
        return 0;
    }
    fm_stock_free(res.stock);
    return 1;
}

int main(int argc, char **argv)
{
    const char *program = argc > 1 ? argv[1] : "/usr/share/linuxcnc/ncfiles/3D_Chips.ngc";
    const char *tools25 = argc > 2 ? argv[2] : "tests/check/chips_tools_25.json";
    const char *tools35 = argc > 3 ? argv[3] : "tests/check/chips_tools.json";
    const char *stock = argc > 4 ? argv[4] : "box:-50,-50,-50,50,50,0";
    FILE *f = fopen(program, "r");
    if (!f) {
        fprintf(stderr, "bench_check: %s is absent\n", program);
        return 77;
    }
    fclose(f);

    printf("program  %s, stock %s; load before %.2f\n", program, stock, load1());
    const char *tools[2] = {tools25, tools35};
    const char *name[2] = {"25 mm flutes", "35 mm flutes"};
    const double goal[2] = {0.25, 0.10};
    int ok = 1;
    /* one simulation serves both: the flutes' length does not change the cut */
    timing sim;
    if (!run_simulation(program, tools35, stock, &sim)) return 2;
    printf("simulate (0.1 mm)            wall %7.2f s  cpu %7.2f s\n", sim.wall, sim.cpu);
    for (int i = 0; i < 2; i++) {
        timing ck;
        memset(&ck, 0, sizeof ck);
        if (!run_check(program, tools[i], stock, &ck)) return 2;
        double ratio = ck.wall / sim.wall, cpu_ratio = ck.cpu / sim.cpu;
        int met = ratio <= goal[i];
        ok &= met;
        printf("check %s (0.5 mm) wall %7.2f s  cpu %7.2f s  ratio to simulate wall %.3f cpu "
               "%.3f (goal <= %.2f: %s)\n",
               name[i], ck.wall, ck.cpu, ratio, cpu_ratio, goal[i], met ? "met" : "NOT met");
        printf("    relations %.2f s of it; %zu findings (%zu errors); %ld relations, %ld skipped, "
               "%ld regions, %ld voxels, %ld time-ordered, %ld depth searches, %ld uncertain\n",
               ck.check_s, ck.findings, ck.errors, ck.stats.relations, ck.stats.skipped,
               ck.stats.regions, ck.stats.voxels, ck.stats.ordered, ck.stats.depth_searches,
               ck.stats.uncertain);
    }
    printf("load after %.2f (figures taken under load are noisy: compare CPU)\n", load1());
    return ok ? 0 : 1;
}
