/* bench_simulate.c: whole programs through the job runner (daemon/runner/job.h):
 * LinuxCNC's 3D_Chips.ngc (10 mm ball end mill, skipped when absent), the
 * demo pocket of deploy/demo (flat, drill and V-bit; helical entries, full
 * circles, G81) and a generated 50,000-motion pocket (6 mm flat end mill,
 * zigzag clearing of a 84 x 44 mm area in 12 depths of 1 mm, 0.3 mm
 * segments). Prints, per case: wall and CPU time (user + sys), the load
 * average before and after (the machine is shared: CPU time and
 * instructions are the comparable figures), instructions when the kernel
 * exposes hardware counters, peak RSS, motions and voxels per second, where
 * the time goes, and the ratio of the job to its floor.
 *
 * The floor is the work no method can avoid: every voxel whose value the
 * cuts changed must at least be read, compared and written. Its per-voxel
 * cost is measured here, on the final stock, by OpenVDB's bare update
 * (value accessor read, max, setValueOnly) of the voxels the tool marks
 * record, i.e. the leaves and voxels the cuts set that are still in the
 * band; floor = voxels changed (summed over all cuts) x that cost, in
 * thread-seconds. total / floor = job CPU seconds / floor.
 *
 * Memory: the peak resident set, and the stock's breakdown at the peak
 * (fm_stock_memory_usage): active voxels, leaves, bytes per active voxel,
 * the band (leaves x leaf bytes + internal nodes; OpenVDB's memUsage), the
 * tool marks, the meshes (a simulate job keeps none) and the rest of the
 * process. --memory-trace N prints the breakdown every N cuts.
 *
 * goals runs issue 37's rows (3D_Chips at 0.1 and 0.05 mm with a 10 mm
 * ball of 40 mm flutes, the demo at 0.1 mm); every run ends with a summary
 * table of its cases against those goals. Each case runs in a process of
 * its own, so that its peak resident set is its own.
 *
 * Usage: bench_simulate [chips|demo|pocket|all|goals] [--voxel MM]
 *                       [--no-floor] [--no-mesh] [--memory-trace CUTS] */
#define _GNU_SOURCE /* syscall() for perf_event_open */
#include <errno.h>
#include <float.h>
#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>
#include <linux/perf_event.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>

#include "gcode/gcode.h"
#include "job.h"
#include "mesh/mesh.h"
#include "stock/stock.h"
#include "sweep/sweep.h"
#include "bench_clock.h"

#define CHIPS_PATH "/usr/share/linuxcnc/ncfiles/3D_Chips.ngc"
#ifndef FM_SOURCE_DIR
#define FM_SOURCE_DIR "."
#endif
#define DEMO_PATH FM_SOURCE_DIR "/deploy/demo/pocket.ngc"
#define DEMO_TOOLS FM_SOURCE_DIR "/deploy/demo/tools.json"

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

/* ------------------------------------------- counters and load -- */

static void load_average(double l[3])
{
    l[0] = l[1] = l[2] = -1;
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f) return;
    if (fscanf(f, "%lf %lf %lf", &l[0], &l[1], &l[2]) != 3) l[0] = l[1] = l[2] = -1;
    fclose(f);
}

/* Instructions retired by this process and the threads it starts later
 * (inherit), or -1 with the reason when the kernel gives no hardware
 * counter (common under virtual machines). */
static int instr_fd = -1;
static char instr_why[128] = "";

static void instructions_open(void)
{
    struct perf_event_attr pe;
    memset(&pe, 0, sizeof pe);
    pe.type = PERF_TYPE_HARDWARE;
    pe.size = sizeof pe;
    pe.config = PERF_COUNT_HW_INSTRUCTIONS;
    pe.disabled = 0;
    pe.inherit = 1;
    pe.exclude_kernel = 1;
    pe.exclude_hv = 1;
    instr_fd = (int)syscall(SYS_perf_event_open, &pe, 0, -1, -1, 0);
    if (instr_fd < 0)
        snprintf(instr_why, sizeof instr_why, "no hardware counter (perf_event_open: %s)", strerror(errno));
}

static double instructions_now(void)
{
    uint64_t v;
    if (instr_fd < 0 || read(instr_fd, &v, sizeof v) != (ssize_t)sizeof v) return -1;
    return (double)v;
}

static int count_sink(void *user, const fm_motion *m)
{
    (void)m;
    (*(long *)user)++;
    return 0;
}

/* ----------------------------------------------------------- memory -- */

/* The process's resident set now (bytes; 0 when /proc is not there). */
static double rss_now(void)
{
    long pages = 0, resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f) return 0;
    if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    fclose(f);
    return (double)resident * (double)sysconf(_SC_PAGESIZE);
}

/* The resident set over the job: read after every cut (/proc/self/statm);
 * whenever it passes by 1 MB the largest at which the stock's breakdown
 * was taken, the breakdown is taken again (a walk over the grid's
 * nodes), so that the breakdown shown is the one at the peak. The time the hook takes is left out of the
 * job's wall and CPU figures. With trace, the breakdown is printed every
 * trace cuts. */
typedef struct mem_watch {
    double start_rss, stock_rss; /* before the job; when the stock is made */
    double max_rss;              /* over the cuts */
    long max_cut, cuts;
    fm_stock_memory at_max;      /* the stock's breakdown near max_rss */
    double at_max_rss;           /* the resident set when it was taken */
    double hook_wall, hook_cpu;  /* seconds spent here */
    long trace;
} mem_watch;

#define MB(x) ((double)(x) / 1048576.0)

static void print_breakdown(const char *indent, const fm_stock_memory *m)
{
    printf("%sgrid: %zu leaves x %zu bytes = %.1f MB, %zu internal nodes %.1f MB (OpenVDB memUsage %.1f MB); "
           "tool marks %.1f MB (%zu leaf records); tables %.1f MB; %zu active voxels\n",
           indent, m->leaves, m->leaf_bytes, MB(m->leaves * m->leaf_bytes), m->internal_nodes, MB(m->internal_bytes),
           MB(m->band_bytes), MB(m->marks_bytes), m->marks_leaves, MB(m->tables_bytes), m->active_voxels);
}

static void watch_stock(void *user, fm_stock *stock)
{
    mem_watch *w = user;
    double w0 = bench_wall_s(), c0 = bench_cpu_s();
    w->stock_rss = rss_now();
    fm_stock_memory_usage(stock, &w->at_max);
    w->max_rss = w->at_max_rss = w->stock_rss;
    w->hook_wall += bench_wall_s() - w0;
    w->hook_cpu += bench_cpu_s() - c0;
}

static int watch_progress(void *user, const fm_job_progress *p)
{
    mem_watch *w = user;
    double w0 = bench_wall_s(), c0 = bench_cpu_s();
    w->cuts++;
    double rss = rss_now();
    if (rss > w->max_rss) {
        if (rss > w->at_max_rss + 1048576.0 || w->max_cut == 0) {
            fm_stock_memory_usage(p->stock, &w->at_max);
            w->at_max_rss = rss;
        }
        w->max_rss = rss;
        w->max_cut = w->cuts;
    }
    if (w->trace > 0 && w->cuts % w->trace == 0) {
        fm_stock_memory m;
        fm_stock_memory_usage(p->stock, &m);
        char indent[64];
        snprintf(indent, sizeof indent, "  [cut %ld, RSS %.1f MB] ", w->cuts, MB(rss));
        print_breakdown(indent, &m);
#ifdef __GLIBC__
        struct mallinfo2 mi = mallinfo2();
        printf("    malloc: arenas %.1f MB (in use %.1f, free %.1f), mmap %.1f MB\n", MB(mi.arena), MB(mi.uordblks),
               MB(mi.fordblks), MB(mi.hblkhd));
#endif
    }
    w->hook_wall += bench_wall_s() - w0;
    w->hook_cpu += bench_cpu_s() - c0;
    return 0;
}

/* Where the peak goes: the band (the grid), the tool marks, the meshes
 * (a simulate job keeps none: meshes are made from the final stock, after
 * the job), and the rest of the process (its libraries and the heap's
 * free space and allocator overheads). */
static void print_memory(const mem_watch *w, double peak, const fm_stock_memory *final)
{
    const fm_stock_memory *m = &w->at_max;
    const double band = (double)(m->leaves * m->leaf_bytes + m->internal_bytes);
    const double marks = (double)m->marks_bytes, meshes = 0, tables = (double)m->tables_bytes;
    const double rest = w->max_rss - band - marks - meshes - tables;
    printf("  memory: peak RSS %.1f MB (%.1f MB over the cuts, largest after cut %ld of %ld; %.1f MB before the job, "
           "%.1f MB with the stock made)\n",
           MB(peak), MB(w->max_rss), w->max_cut, w->cuts, MB(w->start_rss), MB(w->stock_rss));
    printf("  at the peak: %zu active voxels in %zu leaves (%.0f per leaf): %.1f bytes of RSS per active voxel, %.1f "
           "of band\n",
           m->active_voxels, m->leaves, m->leaves ? (double)m->active_voxels / (double)m->leaves : 0,
           m->active_voxels ? w->max_rss / (double)m->active_voxels : 0,
           m->active_voxels ? band / (double)m->active_voxels : 0);
    printf("    band %.1f MB (%zu leaves x %zu bytes = %.1f MB + %zu internal nodes and the root %.1f MB; OpenVDB's "
           "memUsage %.1f MB)\n",
           MB(band), m->leaves, m->leaf_bytes, MB(m->leaves * m->leaf_bytes), m->internal_nodes,
           MB(m->internal_bytes), MB(m->band_bytes));
    printf("    tool marks %.1f MB (%zu leaf records); meshes %.1f MB (the job keeps none); stock tables %.1f MB; "
           "the rest %.1f MB (%.1f MB of it before the job: libraries, libopenvdb's symbol tables)\n",
           MB(marks), m->marks_leaves, MB(meshes), MB(tables), MB(rest), MB(w->start_rss));
    print_breakdown("  final stock: ", final);
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
    double t0 = bench_wall_s();
    fm_mesh *mesh = fm_mesh_from_stock(stock, NULL, &err);
    if (!mesh) {
        fprintf(stderr, "bench_simulate %s: meshing: %s\n", name, err.message);
        return;
    }
    double t_mesh = bench_wall_s() - t0;
    uint8_t *stl = NULL, *drc = NULL;
    size_t stl_size = 0, drc_size = 0;
    fm_mesh_draco_options opt;
    fm_mesh_draco_default(&opt);
    t0 = bench_wall_s();
    fm_status st = fm_mesh_encode_stl(mesh, &stl, &stl_size, &err);
    double t_stl = bench_wall_s() - t0;
    t0 = bench_wall_s();
    if (st == FM_OK) st = fm_mesh_encode_draco(mesh, &opt, &drc, &drc_size, &err);
    double t_drc = bench_wall_s() - t0;
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

typedef struct bench_case {
    const char *name;
    const char *path;       /* program file, or */
    const char *text;       /* program text */
    size_t len;
    const fm_tool_spec *tool; /* one-tool table, or */
    const char *tools_path; /* a tool table file */
    const char *stock_spec;
    const char *id; /* chips, demo, pocket: the goals' key */
} bench_case;

/* issue 37's goals for a case at a voxel size (0: none): wall seconds,
 * peak RSS MB, and job CPU / floor (at most 4). */
typedef struct bench_goal {
    const char *id;
    double voxel, wall_s, peak_mb, floor_ratio;
} bench_goal;

static const bench_goal goals[] = {
    {"chips", 0.1, 5.0, 200, 4},
    {"chips", 0.05, 15.0, 600, 0},
    {"demo", 0.1, 1.5, 0, 4},
};

/* What a run measured, for the summary. */
typedef struct case_figures {
    const char *name, *id;
    double voxel, wall, cpu, peak_mb, floor_ratio, load0, load1;
    int ran;
} case_figures;

typedef struct bench_opts {
    double voxel;
    int floor, mesh;
    long trace; /* print the memory breakdown every this many cuts (0: never) */
    int report_fd; /* >= 0: the case's figures go there (run_case_alone's child) */
} bench_opts;

static case_figures run_case(const bench_case *bc, const bench_opts *o)
{
    case_figures out = {bc->name, bc->id, o->voxel, 0, 0, 0, 0, 0, 0, 0};
    fm_tool_table table = {1, (fm_tool_spec *)bc->tool};
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = bc->path;
    spec.program_text = bc->text;
    spec.program_length = bc->len;
    spec.program_name = bc->name;
    spec.program_kind = FM_PROGRAM_GCODE;
    spec.stock_spec = bc->stock_spec;
    spec.tools = bc->tool ? &table : NULL;
    spec.tools_path = bc->tools_path;
    spec.stock.voxel_mm = o->voxel;
    fm_job_result r;
    fm_error err;
    double load0[3], load1[3];
    load_average(load0);
    double i0 = instructions_now(), c0 = bench_cpu_s(), w0 = bench_wall_s();
    mem_watch watch;
    memset(&watch, 0, sizeof watch);
    watch.start_rss = rss_now();
    watch.trace = o->trace;
    fm_job_hooks hooks = {.user = &watch, .progress = watch_progress, .on_stock = watch_stock};
    fm_status st = fm_job_run(&spec, &hooks, &r, &err);
    double cpu = bench_cpu_s() - c0 - watch.hook_cpu, wall = bench_wall_s() - w0 - watch.hook_wall,
           instr = instructions_now() - i0;
    load_average(load1);
    if (st != FM_OK) {
        fprintf(stderr, "bench_simulate %s: %s\n", bc->name, err.message);
        return out;
    }
    out.ran = 1;
    out.wall = wall;
    out.cpu = cpu;
    out.peak_mb = MB(r.peak_memory_bytes);
    out.load0 = load0[0];
    out.load1 = load1[0];
    const fm_stock_cut_stats *cs = &r.cut_stats;
    printf("%s at %g mm: %ld motions in %ld cuts, removed %.1f mm3\n", bc->name, o->voxel, r.motions, r.cuts,
           r.removed_volume_mm3);
    printf("  %.2f s wall, %.2f s CPU (user+sys), peak RSS %.0f MB; load average %.2f before, %.2f after (the "
           "memory sampling's %.2f s left out)\n",
           wall, cpu, r.peak_memory_bytes / 1048576.0, load0[0], load1[0], watch.hook_wall);
    if (instr == 0 && instr_fd >= 0)
        snprintf(instr_why, sizeof instr_why, "the hardware counter counted nothing (a virtual machine without PMU)");
    if (instr > 0)
        printf("  %.3g instructions (user space, all threads)\n", instr);
    else
        printf("  instructions: %s; use valgrind --tool=callgrind on a reduced run\n", instr_why);
    printf("  %.0f motions/s, %.3g voxels evaluated/s; %zu voxels evaluated in %zu leaves, %zu voxels changed, "
           "%zu interval boxes, %zu interior boxes\n",
           r.motions / wall, cs->voxels_evaluated / wall, cs->voxels_evaluated, cs->leaves_evaluated,
           cs->voxels_changed, cs->intervals, cs->interior_boxes);
    /* the budget warning: must be 0 (issue 19) */
    printf("  budget warning: %zu voxels uncertain (up to %.4f mm, first at line %d)%s\n", r.voxels_uncertain,
           r.uncertain_max_mm, r.uncertain_line, r.voxels_uncertain ? "  <-- NOT ZERO" : "");

    {
        fm_stock_memory final;
        fm_stock_memory_usage(r.stock, &final);
        print_memory(&watch, (double)r.peak_memory_bytes, &final);
    }

    /* Where the time goes: the parts the job's statistics time, and the
     * set-up and final measures timed here again on their own. */
    double t = bench_wall_s();
    long nmot = 0;
    fm_gcode_options gopt;
    fm_gcode_options_default(&gopt);
    fm_status gst = bc->path ? fm_gcode_run_file(bc->path, &gopt, count_sink, &nmot, NULL, &err)
                             : fm_gcode_run_string(bc->text, bc->len, bc->name, &gopt, count_sink, &nmot, NULL, &err);
    double t_gcode = gst == FM_OK ? bench_wall_s() - t : -1;
    t = bench_wall_s();
    fm_stock *fresh = fm_job_make_stock(bc->stock_spec, &spec.stock, &err);
    double t_stock = bench_wall_s() - t;
    fm_stock_free(fresh);
    t = bench_wall_s();
    double area = 0;
    (void)fm_stock_volume(r.stock);
    (void)fm_stock_surface_area(r.stock, &area, &err);
    double t_measure = bench_wall_s() - t;
    double t_cut = cs->time_classify_s + cs->time_voxels_s + cs->time_apply_s;
    printf("  where the wall time goes: interpreting the program %.2f s (x2: survey and cut), making the stock "
           "%.2f s, final volume and area %.2f s; cuts %.2f s = interval pass (serial) %.2f s + voxel pass "
           "(parallel) %.2f s + topology and bookkeeping (serial) %.2f s; the rest (sweep set-up, batching, "
           "report) %.2f s\n",
           t_gcode, t_stock, t_measure, t_cut, cs->time_classify_s, cs->time_voxels_s, cs->time_apply_s,
           wall - 2 * (t_gcode > 0 ? t_gcode : 0) - t_stock - t_measure - t_cut);
    double share = cs->time_leaves_cpu_s > 0 ? cs->time_field_cpu_s / cs->time_leaves_cpu_s : 0;
    printf("  voxel pass: %.0f%% in the swept field (interval bounds and values), %.0f%% in the grid work around it "
           "(timed on one leaf job in 8; %.2f thread-s in all, inflated by preemption when the machine is loaded)\n",
           100 * share, 100 * (1 - share), cs->time_leaves_cpu_s);
    if (o->floor) {
        size_t timed = 0;
        double per = fm_stock_time_bare_update(r.stock, &timed);
        double fl = per * (double)cs->voxels_changed;
        if (fl > 0) out.floor_ratio = cpu / fl;
        if (fl > 0)
            printf("  floor: %zu voxels changed x %.2f ns (OpenVDB accessor read, max, write; timed on %zu marked "
                   "voxels of the final stock) = %.3f thread-s; ratio total / floor = %.1f (CPU) and %.1f (wall x "
                   "2 cores)\n",
                   cs->voxels_changed, per * 1e9, timed, fl, cpu / fl, 2 * wall / fl);
    }
    if (o->mesh) mesh_figures(bc->name, r.stock);
    fm_stock_free(r.stock);
    return out;
}

/* The figures a case run by --report-fd hands back: one line of numbers. */
static void report_figures(int fd, const case_figures *f)
{
    char line[256];
    int n = snprintf(line, sizeof line, "%d %.17g %.17g %.17g %.17g %.17g %.17g\n", f->ran, f->wall, f->cpu,
                     f->peak_mb, f->floor_ratio, f->load0, f->load1);
    if (n > 0 && write(fd, line, (size_t)n) != n) fprintf(stderr, "bench_simulate: cannot hand the figures back\n");
}

/* A case in a fresh process of its own (this program again, with the
 * case's name and voxel size): its peak resident set is then its own (the
 * kernel's peak only grows over a process's life) and counts what a
 * `frepmill simulate` of it counts, the libraries' pages the loader
 * touched included (a forked child would not). */
static case_figures run_case_alone(const bench_case *bc, const bench_opts *o)
{
    case_figures f = {bc->name, bc->id, o->voxel, 0, 0, 0, 0, 0, 0, 0};
    int fd[2];
    if (pipe(fd) != 0) return f;
    char fdarg[16], voxel[32], trace[32];
    snprintf(fdarg, sizeof fdarg, "%d", fd[1]);
    snprintf(voxel, sizeof voxel, "%.17g", o->voxel);
    snprintf(trace, sizeof trace, "%ld", o->trace);
    const char *argv[16];
    int n = 0;
    argv[n++] = "bench_simulate";
    argv[n++] = bc->id;
    argv[n++] = "--voxel";
    argv[n++] = voxel;
    argv[n++] = "--report-fd";
    argv[n++] = fdarg;
    argv[n++] = "--memory-trace";
    argv[n++] = trace;
    if (!o->floor) argv[n++] = "--no-floor";
    if (!o->mesh) argv[n++] = "--no-mesh";
    argv[n] = NULL;
    fflush(stdout);
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        execv("/proc/self/exe", (char *const *)argv);
        _exit(127);
    }
    close(fd[1]);
    if (pid > 0) {
        char line[256] = "";
        ssize_t got = read(fd[0], line, sizeof line - 1);
        if (got > 0) {
            line[got] = 0;
            if (sscanf(line, "%d %lf %lf %lf %lf %lf %lf", &f.ran, &f.wall, &f.cpu, &f.peak_mb, &f.floor_ratio,
                       &f.load0, &f.load1) != 7)
                f.ran = 0;
        }
        int status = 0;
        waitpid(pid, &status, 0);
    }
    close(fd[0]);
    return f;
}

static case_figures run_one(const bench_case *bc, const bench_opts *o, int alone)
{
    return alone ? run_case_alone(bc, o) : run_case(bc, o);
}

/* A figure against its goal: "8.31 s (goal 5, x1.66)", "-" without one. */
static const char *against(char *buf, size_t size, double v, double goal, const char *unit, int digits)
{
    if (v <= 0) {
        snprintf(buf, size, "-");
    } else if (goal > 0) {
        snprintf(buf, size, "%.*f%s (goal %g, x%.2f%s)", digits, v, unit, goal, v / goal, v <= goal ? " met" : "");
    } else {
        snprintf(buf, size, "%.*f%s", digits, v, unit);
    }
    return buf;
}

/* issue 37's rows: each case run with its figures beside the goals, and
 * the ratio figure / goal (at most 1 meets it). */
static void print_summary(const case_figures *f, size_t n)
{
    printf("\nsummary against issue 37's goals (the ratio is figure / goal: at most 1 meets it):\n");
    printf("| case | voxel | wall | CPU | peak RSS | total / floor (CPU) | load before / after |\n");
    printf("|---|---|---|---|---|---|---|\n");
    for (size_t i = 0; i < n; i++) {
        if (!f[i].ran) continue;
        const bench_goal *g = NULL;
        for (size_t k = 0; k < sizeof goals / sizeof goals[0]; k++)
            if (strcmp(goals[k].id, f[i].id) == 0 && fabs(goals[k].voxel - f[i].voxel) < 1e-9) g = &goals[k];
        char w[64], m[64], r[64];
        printf("| %s | %g mm | %s | %.2f s | %s | %s | %.2f / %.2f |\n", f[i].name, f[i].voxel,
               against(w, sizeof w, f[i].wall, g ? g->wall_s : 0, " s", 2), f[i].cpu,
               against(m, sizeof m, f[i].peak_mb, g ? g->peak_mb : 0, " MB", 0),
               against(r, sizeof r, f[i].floor_ratio, g ? g->floor_ratio : 0, "", 1), f[i].load0, f[i].load1);
    }
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0); /* figures appear as each run ends */
    const char *which = "all";
    bench_opts o = {0.1, 1, 1, 0, -1};
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--no-floor") == 0) {
            o.floor = 0;
        } else if (strcmp(argv[i], "--no-mesh") == 0) {
            o.mesh = 0;
        } else if (strcmp(argv[i], "--report-fd") == 0 && i + 1 < argc) {
            o.report_fd = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--memory-trace") == 0 && i + 1 < argc) {
            o.trace = atol(argv[++i]);
        } else if (strcmp(argv[i], "--voxel") == 0 && i + 1 < argc) {
            o.voxel = atof(argv[++i]);
        } else if (argv[i][0] != '-') {
            which = argv[i];
        } else {
            fprintf(stderr, "usage: bench_simulate [chips|demo|pocket|all|goals] [--voxel MM] [--no-floor] [--no-mesh] "
                            "[--memory-trace CUTS]\n");
            return 2;
        }
    }
    if (!(o.voxel > 0)) {
        fprintf(stderr, "bench_simulate: --voxel needs a positive size in mm\n");
        return 2;
    }
    instructions_open();
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    double load[3];
    load_average(&load[0]);
    if (o.report_fd < 0)
        printf("bench_simulate: %ld cores, load average %.2f %.2f %.2f at start, voxel %g mm\n", cores, load[0], load[1],
           load[2], o.voxel);
    /* goals: issue 37's rows, 3D_Chips at 0.1 and 0.05 mm and the demo at
     * 0.1 mm, whatever --voxel says */
    int goals_run = strcmp(which, "goals") == 0;
    int all = strcmp(which, "all") == 0;
    int several = goals_run || all; /* then each case in a process of its own */
    case_figures figs[8];
    size_t nfigs = 0;
    if (all || goals_run || strcmp(which, "chips") == 0) {
        if (access(CHIPS_PATH, R_OK) != 0) {
            printf("3D_Chips.ngc: skipped (%s not found; install linuxcnc-uspace's examples)\n", CHIPS_PATH);
        } else {
            /* issue 37's tool: a 10 mm ball with 40 mm of flutes */
            fm_tool_spec ball;
            memset(&ball, 0, sizeof ball);
            ball.number = 1;
            ball.shape = FM_TOOL_BALL;
            ball.diameter = 10;
            ball.flute_length = 40;
            ball.length = 60;
            ball.holder_count = 1;
            ball.holder[0].diameter = ball.holder[0].diameter_top = 30;
            ball.holder[0].length = 40;
            ball.center_cutting = 1;
            bench_case bc = {"3D_Chips.ngc", CHIPS_PATH, NULL, 0, &ball, NULL, "box:-50,-50,-50,50,50,0", "chips"};
            if (goals_run) {
                bench_opts d = o;
                d.mesh = 0;
                d.voxel = 0.1;
                figs[nfigs++] = run_one(&bc, &d, several);
                d.voxel = 0.05;
                figs[nfigs++] = run_one(&bc, &d, several);
            } else {
                figs[nfigs++] = run_one(&bc, &o, several);
            }
        }
    }
    if (all || goals_run || strcmp(which, "demo") == 0) {
        bench_case bc = {"demo pocket.ngc", DEMO_PATH, NULL, 0, NULL, DEMO_TOOLS, "box:0,0,-30,100,60,0", "demo"};
        bench_opts d = o;
        d.mesh = 0;
        if (goals_run) d.voxel = 0.1;
        figs[nfigs++] = run_one(&bc, &d, several);
    }
    if (all || strcmp(which, "pocket") == 0) {
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
        bench_case bc = {"pocket-50k", NULL, prog, len, &flat, NULL, "box:0,0,-30,100,60,0", "pocket"};
        bench_opts d = o;
        d.mesh = 0;
        figs[nfigs++] = run_one(&bc, &d, several);
        free(prog);
    }
    if (o.report_fd < 0)
        print_summary(figs, nfigs);
    else if (nfigs > 0)
        report_figures(o.report_fd, &figs[0]);
    return 0;
}
