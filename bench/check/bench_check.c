/* bench_check.c: how long `frepmill check` takes on LinuxCNC's 3D_Chips.ngc
 * (0.5 mm voxels, every motion related to the stock) next to the full
 * simulation at the preview's 0.1 mm (`frepmill simulate`), both through
 * the job runner. Usage: bench_check [PROGRAM [TOOLS [STOCK]]]; run from
 * the source tree's root or give the paths. Exit 77 if the program is
 * absent. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "check/check.h"
#include "job.h"

typedef struct run {
    fm_check *check;
    fm_status status;
    fm_error err;
} run;

static int before_motion(void *user, const fm_motion *m, const fm_tool *tool, fm_stock *stock)
{
    run *r = user;
    r->status = fm_check_motion(r->check, m, tool, stock, &r->err);
    return r->status != FM_OK;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double cpu_s(void)
{
    return (double)clock() / CLOCKS_PER_SEC;
}

int main(int argc, char **argv)
{
    const char *program = argc > 1 ? argv[1] : "/usr/share/linuxcnc/ncfiles/3D_Chips.ngc";
    const char *tools = argc > 2 ? argv[2] : "tests/check/chips_tools.json";
    const char *stock = argc > 3 ? argv[3] : "box:-50,-50,-50,50,50,0";
    FILE *f = fopen(program, "r");
    if (!f) {
        fprintf(stderr, "bench_check: %s is absent\n", program);
        return 77;
    }
    fclose(f);

    fm_error err;
    fm_error_clear(&err);
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = program;
    spec.tools_path = tools;
    spec.stock_spec = stock;

    /* the check, as frepmill check runs it */
    run r = {0};
    r.check = fm_check_new(NULL, &err);
    if (!r.check) return 2;
    double lo[3], hi[3];
    if (sscanf(stock, "box:%lf,%lf,%lf,%lf,%lf,%lf", &lo[0], &lo[1], &lo[2], &hi[0], &hi[1],
               &hi[2]) == 6)
        fm_check_set_initial_box(r.check, lo, hi);
    spec.stock.voxel_mm = 0.5;
    spec.stock.band_voxels = 4;
    fm_job_hooks hooks = {.user = &r, .before_motion = before_motion};
    fm_job_result res;
    double w0 = now_s(), c0 = cpu_s();
    fm_status st = fm_job_run(&spec, &hooks, &res, &err);
    double check_wall = now_s() - w0, check_cpu = cpu_s() - c0;
    if (st != FM_OK || r.status != FM_OK) {
        fprintf(stderr, "bench_check: %s\n", st != FM_OK ? err.message : r.err.message);
        fm_check_free(r.check);
        return 2;
    }
    fm_check_finish(r.check);
    fm_check_stats stats;
    fm_check_get_stats(r.check, &stats);
    long motions = res.motions;
    fm_stock_free(res.stock);

    /* the full simulation at the preview's resolution */
    fm_job_spec_default(&spec);
    spec.program_path = program;
    spec.tools_path = tools;
    spec.stock_spec = stock;
    spec.stock.voxel_mm = 0.1;
    w0 = now_s();
    c0 = cpu_s();
    st = fm_job_run(&spec, NULL, &res, &err);
    double sim_wall = now_s() - w0, sim_cpu = cpu_s() - c0;
    if (st != FM_OK) {
        fprintf(stderr, "bench_check: %s\n", err.message);
        fm_check_free(r.check);
        return 2;
    }
    fm_stock_free(res.stock);

    printf("program            %s (%ld motions)\n", program, motions);
    printf("check  (0.5 mm)    wall %8.2f s  cpu %8.2f s  findings %zu  relations %ld "
           "(skipped %ld)  boxes %ld\n",
           check_wall, check_cpu, fm_check_count(r.check), stats.relations, stats.skipped,
           stats.boxes);
    printf("simulate (0.1 mm)  wall %8.2f s  cpu %8.2f s\n", sim_wall, sim_cpu);
    fm_check_free(r.check);
    return 0;
}
