/* bench_simulate.c: whole programs through the job runner (daemon/runner/job.h) at
 * 0.1 mm: LinuxCNC's 3D_Chips.ngc (10 mm ball end mill, skipped when absent)
 * and a generated 50,000-motion pocket (6 mm flat end mill, zigzag clearing
 * of a 84 x 44 mm area in 12 depths of 1 mm, 0.3 mm segments). Prints
 * motions per second, band voxels per second (voxels the cuts evaluated the
 * swept field at), CPU and wall time, peak RSS, and the ratio of the job's
 * cutting time to the floor.
 *
 * The floor: the same motions, batched as the job batches them, each
 * batch's swept field rasterized alone into an empty grid
 * (fm_stock_new_from_field: interval pass and every voxel of its boundary
 * leaves), clipped to the stock's box. It is the cost of the swept volumes
 * without any stock work; the job can go below it because it skips voxels
 * the stock settles. Usage: bench_simulate [chips|pocket|all] [--no-floor]. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "gcode/gcode.h"
#include "job.h"
#include "mesh/mesh.h"
#include "stock/stock.h"
#include "sweep/sweep.h"

#define CHIPS_PATH "/usr/share/linuxcnc/ncfiles/3D_Chips.ngc"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double cpu_now(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_utime.tv_sec + 1e-6 * ru.ru_utime.tv_usec + ru.ru_stime.tv_sec + 1e-6 * ru.ru_stime.tv_usec;
}

/* ------------------------------------------------- generated pocket -- */

typedef struct text {
    char *p;
    size_t len, cap;
} text;

static void put(text *t, const char *fmt, double a, double b)
{
    char line[128];
    int n = snprintf(line, sizeof line, fmt, a, b);
    if (t->len + (size_t)n + 1 > t->cap) {
        t->cap = t->cap ? 2 * t->cap : 1 << 20;
        t->p = realloc(t->p, t->cap);
        if (!t->p) {
            fprintf(stderr, "bench_simulate: out of memory\n");
            exit(1);
        }
    }
    memcpy(t->p + t->len, line, (size_t)n + 1);
    t->len += (size_t)n;
}

/* Zigzag rows 3 mm apart (half the diameter), each row in segs segments. */
static char *pocket_program(size_t *len)
{
    const double x0 = 8, x1 = 92, y0 = 8, y1 = 52, step = 3;
    const int levels = 12, segs = 277;
    text t = {0};
    put(&t, "(bench_simulate: zigzag pocket, 6 mm flat)\nG21 G90 G17 G94\nT1 M6\nS10000 M3\n", 0, 0);
    put(&t, "G0 Z5\nG0 X%.4f Y%.4f\n", x0, y0);
    for (int l = 1; l <= levels; l++) {
        put(&t, "G1 Z%.4f F300\n", -1.0 * l, 0);
        int row = 0;
        for (double y = y0; y <= y1 + 1e-9; y += step, row++) {
            if (row > 0) put(&t, "G1 Y%.4f F1500\n", y, 0);
            for (int k = 1; k <= segs; k++) {
                double u = (double)k / segs;
                double x = row % 2 ? x1 - u * (x1 - x0) : x0 + u * (x1 - x0);
                put(&t, "G1 X%.4f F1500\n", x, 0);
            }
        }
        put(&t, "G0 Z5\nG0 X%.4f Y%.4f\n", x0, y0);
    }
    put(&t, "M5\nM2\n", 0, 0);
    *len = t.len;
    return t.p;
}

/* ------------------------------------------------------------ floor -- */

typedef struct collect {
    fm_motion *m;
    size_t n, cap;
} collect;

static int collect_sink(void *user, const fm_motion *m)
{
    collect *c = user;
    if (c->n == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 4096;
        fm_motion *p = realloc(c->m, c->cap * sizeof *p);
        if (!p) return 1;
        c->m = p;
    }
    c->m[c->n++] = *m;
    return 0;
}

/* Rasterize one batch's field alone, clipped to the stock box. */
static int floor_batch(const fm_motion *m, size_t n, const fm_tool_part *part, const double slo[3],
                       const double shi[3])
{
    fm_field f;
    fm_error err;
    if (fm_sweep_field_many(&f, m, n, part, &err) != FM_OK) {
        fprintf(stderr, "bench_simulate: %s\n", err.message);
        return -1;
    }
    int empty = 0;
    for (int a = 0; a < 3; a++) {
        f.lo[a] = fmax(f.lo[a], slo[a] - 0.5);
        f.hi[a] = fmin(f.hi[a], shi[a] + 0.5);
        if (f.lo[a] > f.hi[a]) empty = 1;
    }
    if (!empty) {
        fm_stock *g = fm_stock_new_from_field(&f, NULL, &err);
        fm_stock_free(g); /* NULL when the clipped band is empty */
    }
    f.release(f.ctx);
    return 0;
}

static double run_floor(const char *path, const char *textp, size_t len, const fm_tool_table *tools,
                        const fm_tool *tool, const double slo[3], const double shi[3])
{
    fm_gcode_options opt;
    fm_gcode_options_default(&opt);
    opt.tools = tools;
    collect c = {0};
    fm_error err;
    fm_status st = path ? fm_gcode_run_file(path, &opt, collect_sink, &c, NULL, &err)
                        : fm_gcode_run_string(textp, len, "pocket", &opt, collect_sink, &c, NULL, &err);
    if (st != FM_OK) {
        fprintf(stderr, "bench_simulate: %s\n", err.message);
        free(c.m);
        return -1;
    }
    /* The job's batching: consecutive motions while their path length stays
     * under one tool diameter, at most 256, dwells not cut. */
    double t0 = now();
    size_t first = 0, count = 0;
    double length = 0, limit = tool->spec.diameter;
    for (size_t i = 0; i <= c.n; i++) {
        int flush = i == c.n;
        double l = 0;
        if (!flush) {
            if (c.m[i].kind == FM_MOTION_DWELL) continue;
            l = fm_job_motion_length(&c.m[i]);
            flush = count > 0 && (length + l > limit || count >= 256);
        }
        if (flush && count > 0) {
            if (floor_batch(&c.m[first], count, &tool->flutes, slo, shi) != 0) break;
            count = 0;
            length = 0;
        }
        if (i == c.n) break;
        if (count == 0) first = i;
        count++;
        length += l;
    }
    double t = now() - t0;
    free(c.m);
    return t;
}

/* -------------------------------------------------------------- run -- */

/* The final stock as binary STL and as Draco with the default settings
 * (issue 7: Draco at least 15 times smaller with a position error under
 * 5 um). The error is Draco's quantization bound over the mesh's bounding
 * cube, which no decoded vertex exceeds; the decoded volume is printed as
 * a check that the file holds the same solid. */
static void mesh_figures(const char *name, fm_stock *stock)
{
    fm_error err;
    double t0 = now();
    fm_mesh *mesh = fm_mesh_from_stock(stock, NULL, &err);
    if (!mesh) {
        fprintf(stderr, "bench_simulate %s: meshing: %s\n", name, err.message);
        return;
    }
    double t_mesh = now() - t0;
    uint8_t *stl = NULL, *drc = NULL;
    size_t stl_size = 0, drc_size = 0;
    fm_mesh_draco_options opt;
    fm_mesh_draco_default(&opt);
    t0 = now();
    fm_status st = fm_mesh_encode_stl(mesh, &stl, &stl_size, &err);
    double t_stl = now() - t0;
    t0 = now();
    if (st == FM_OK) st = fm_mesh_encode_draco(mesh, &opt, &drc, &drc_size, &err);
    double t_drc = now() - t0;
    fm_mesh *back = st == FM_OK ? fm_mesh_decode_draco(drc, drc_size, NULL, &err) : NULL;
    if (!back) {
        fprintf(stderr, "bench_simulate %s: encoding: %s\n", name, err.message);
    } else {
        float lo[3], hi[3];
        fm_mesh_bounds(mesh, lo, hi);
        double bound = fm_mesh_draco_error_bound(lo, hi, opt.position_bits);
        printf("  mesh: %zu triangles (%.2f s); binary STL %.1f MB (%.2f s), Draco %.2f MB (%.2f s, %d bits, "
               "speed %d): %.1fx smaller; position error bound %.2f um; volume %.1f mm3, decoded %.1f mm3\n",
               mesh->triangle_count, t_mesh, stl_size / 1e6, t_stl, drc_size / 1e6, t_drc, opt.position_bits,
               opt.speed, (double)stl_size / (double)drc_size, bound * 1000, fm_mesh_volume(mesh),
               fm_mesh_volume(back));
    }
    fm_mesh_free(back);
    free(stl);
    free(drc);
    fm_mesh_free(mesh);
}

static void run_case(const char *name, const char *path, const char *textp, size_t len, const fm_tool_spec *ts,
                     const char *stock_spec, const double slo[3], const double shi[3], int with_floor,
                     int want_mesh)
{
    fm_tool_table table = {1, (fm_tool_spec *)ts};
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = path;
    spec.program_text = textp;
    spec.program_length = len;
    spec.program_name = name;
    spec.program_kind = FM_PROGRAM_GCODE;
    spec.stock_spec = stock_spec;
    spec.tools = &table;
    spec.stock.voxel_mm = 0.1;
    fm_job_result r;
    fm_error err;
    double c0 = cpu_now(), w0 = now();
    fm_status st = fm_job_run(&spec, NULL, &r, &err);
    double cpu = cpu_now() - c0, wall = now() - w0;
    if (st != FM_OK) {
        fprintf(stderr, "bench_simulate %s: %s\n", name, err.message);
        return;
    }
    printf("%s: %ld motions in %ld cuts, removed %.1f mm3, %.2f s wall, %.2f s CPU (user+sys), peak RSS %.0f MB\n",
           name, r.motions, r.cuts, r.removed_volume_mm3, wall, cpu, r.peak_memory_bytes / 1048576.0);
    printf("  %.0f motions/s, %.3g band voxels/s (%zu voxels evaluated in %zu leaves, %zu interval boxes)\n",
           r.motions / wall, r.cut_stats.voxels_evaluated / wall, r.cut_stats.voxels_evaluated,
           r.cut_stats.leaves_evaluated, r.cut_stats.intervals);
    if (want_mesh) mesh_figures(name, r.stock);
    fm_stock_free(r.stock);
    if (!with_floor) return;
    fm_tool tool;
    if (fm_tool_build(ts, &tool, &err) != FM_OK) {
        fprintf(stderr, "bench_simulate: %s\n", err.message);
        return;
    }
    double f = run_floor(path, textp, len, &table, &tool, slo, shi);
    if (f > 0)
        printf("  floor (each batch's swept volume rasterized alone in the stock's box, empty grid): %.2f s;"
               " ratio total / floor = %.2f\n", f, wall / f);
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0); /* figures appear as each run ends */
    const char *which = argc > 1 ? argv[1] : "all";
    int with_floor = !(argc > 2 && strcmp(argv[2], "--no-floor") == 0);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    double load = -1;
    FILE *lf = fopen("/proc/loadavg", "r");
    if (lf) {
        if (fscanf(lf, "%lf", &load) != 1) load = -1;
        fclose(lf);
    }
    printf("bench_simulate: %ld cores, load average %.2f at start, voxel 0.1 mm\n", cores, load);
    if (strcmp(which, "all") == 0 || strcmp(which, "chips") == 0) {
        if (access(CHIPS_PATH, R_OK) != 0) {
            printf("3D_Chips.ngc: skipped (%s not found; install linuxcnc-uspace's examples)\n", CHIPS_PATH);
        } else {
            fm_tool_spec ball;
            memset(&ball, 0, sizeof ball);
            ball.number = 1;
            ball.shape = FM_TOOL_BALL;
            ball.diameter = 10;
            ball.flute_length = 35;
            ball.length = 60;
            ball.holder_count = 1;
            ball.holder[0].diameter = ball.holder[0].diameter_top = 30;
            ball.holder[0].length = 40;
            ball.center_cutting = 1;
            double lo[3] = {-50, -50, -50}, hi[3] = {50, 50, 0};
            run_case("3D_Chips.ngc", CHIPS_PATH, NULL, 0, &ball, "box:-50,-50,-50,50,50,0", lo, hi, with_floor,
                     1);
        }
    }
    if (strcmp(which, "all") == 0 || strcmp(which, "pocket") == 0) {
        size_t len;
        char *prog = pocket_program(&len);
        fm_tool_spec flat;
        memset(&flat, 0, sizeof flat);
        flat.number = 1;
        flat.shape = FM_TOOL_FLAT;
        flat.diameter = 6;
        flat.flute_length = 20;
        flat.length = 40;
        flat.center_cutting = 1;
        double lo[3] = {0, 0, -30}, hi[3] = {100, 60, 0};
        run_case("pocket-50k", NULL, prog, len, &flat, "box:0,0,-30,100,60,0", lo, hi, with_floor, 0);
        free(prog);
    }
    return 0;
}
