/* bench_mesh.c: figures for lib/mesh on a machined-stock mesh (not a test).
 * Cuts a 60 x 45 x 25 mm block at 0.1 mm voxels with flat-end plunges and
 * ball-end grooves, meshes it, then prints: binary STL size against Draco
 * sizes over a grid of quantization bits and speeds, with the largest
 * position error measured vertex by vertex after decoding; and the time to
 * remesh and encode the dirty chunks of one more motion next to a whole-grid
 * remesh. Usage: bench_mesh [voxel_mm] [out_dir] (out_dir gets .drc, .stl,
 * .png of the part). */
#include "frep/frep.h"
#include "mesh/mesh.h"
#include "stock/stock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_clock.h"

/* ---- cutters: exact signed distances, positive inside ---- */

typedef struct cut {
    int ball;           /* 1: ball-end groove (capsule), 0: flat-end plunge (cylinder) */
    double a[3], b[3];  /* capsule segment / cylinder axis bottom (a) and top z in b[2] */
    double r;
} cut;

static double cut_f(const cut *c, double x, double y, double z)
{
    if (c->ball) {
        double d[3] = {c->b[0] - c->a[0], c->b[1] - c->a[1], c->b[2] - c->a[2]};
        double q[3] = {x - c->a[0], y - c->a[1], z - c->a[2]};
        double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double t = dd > 0 ? (q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) / dd : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double e[3] = {q[0] - t * d[0], q[1] - t * d[1], q[2] - t * d[2]};
        return c->r - sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    }
    double dr = hypot(x - c->a[0], y - c->a[1]) - c->r;
    double dz = fmax(c->a[2] - z, z - c->b[2]);
    return -(hypot(fmax(dr, 0), fmax(dz, 0)) + fmin(fmax(dr, dz), 0));
}

static void cut_batch(void *ctx, void *w, size_t n, const double *x, const double *y,
                      const double *z, double *out)
{
    (void)w;
    for (size_t i = 0; i < n; i++)
        out[i] = cut_f(ctx, x[i], y[i], z[i]);
}
static fm_interval cut_interval(void *ctx, void *w, const fm_interval box[3])
{
    (void)w;
    double h = 0;
    for (int k = 0; k < 3; k++)
        h += pow(0.5 * (box[k].hi - box[k].lo), 2);
    double v = cut_f(ctx, 0.5 * (box[0].lo + box[0].hi), 0.5 * (box[1].lo + box[1].hi),
                     0.5 * (box[2].lo + box[2].hi));
    fm_interval r = {v - sqrt(h), v + sqrt(h)};
    return r;
}

static fm_field cut_field(cut *c)
{
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = c;
    for (int k = 0; k < 3; k++) {
        double lo = fmin(c->a[k], c->b[k]), hi = fmax(c->a[k], c->b[k]);
        f.lo[k] = c->ball || k == 2 ? lo - (c->ball ? c->r : 0) : c->a[k] - c->r;
        f.hi[k] = c->ball || k == 2 ? hi + (c->ball ? c->r : 0) : c->a[k] + c->r;
    }
    f.worker_new = NULL; /* no per-thread state (frep.h) */
    f.worker_free = NULL;
    f.batch = cut_batch;
    f.interval = cut_interval;
    return f;
}

/* ---- largest distance between decoded and original vertices ---- */

typedef struct grid_index {
    double cell, lo[3];
    int n[3];
    size_t *start;
    uint32_t *ids;
} grid_index;

static size_t cell_at(const grid_index *g, const float *p, int off[3])
{
    int c[3];
    for (int k = 0; k < 3; k++) {
        c[k] = (int)floor((p[k] - g->lo[k]) / g->cell) + (off ? off[k] : 0);
        if (c[k] < 0 || c[k] >= g->n[k])
            return (size_t)-1;
    }
    return ((size_t)c[2] * g->n[1] + c[1]) * g->n[0] + c[0];
}

static void index_build(grid_index *g, const fm_mesh *m, double cell)
{
    float lo[3], hi[3];
    fm_mesh_bounds(m, lo, hi);
    g->cell = cell;
    for (int k = 0; k < 3; k++) {
        g->lo[k] = lo[k] - cell;
        g->n[k] = (int)ceil((hi[k] - lo[k]) / cell) + 3;
    }
    size_t cells = (size_t)g->n[0] * g->n[1] * g->n[2];
    g->start = calloc(cells + 2, sizeof(size_t));
    g->ids = malloc(m->vertex_count * sizeof(uint32_t));
    for (size_t i = 0; i < m->vertex_count; i++)
        g->start[cell_at(g, m->positions + 3 * i, NULL) + 2]++;
    for (size_t c = 0; c < cells; c++)
        g->start[c + 2] += g->start[c + 1];
    for (size_t i = 0; i < m->vertex_count; i++)
        g->ids[g->start[cell_at(g, m->positions + 3 * i, NULL) + 1]++] = (uint32_t)i;
}

static double nearest(const grid_index *g, const fm_mesh *m, const float *p)
{
    double best = INFINITY;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int off[3] = {dx, dy, dz};
                size_t c = cell_at(g, p, off);
                if (c == (size_t)-1)
                    continue;
                for (size_t i = g->start[c]; i < g->start[c + 1]; i++) {
                    const float *q = m->positions + 3 * (size_t)g->ids[i];
                    double d = pow((double)q[0] - p[0], 2) + pow((double)q[1] - p[1], 2) +
                               pow((double)q[2] - p[2], 2);
                    if (d < best)
                        best = d;
                }
            }
    return sqrt(best);
}

static double max_error(const grid_index *g, const fm_mesh *orig, const fm_mesh *dec)
{
    double worst = 0;
    for (size_t i = 0; i < dec->vertex_count; i++)
        worst = fmax(worst, nearest(g, orig, dec->positions + 3 * i));
    return worst;
}

int main(int argc, char **argv)
{
    double voxel = argc > 1 ? atof(argv[1]) : 0.1;
    const char *out_dir = argc > 2 ? argv[2] : NULL;
    const double lo[3] = {0, 0, 0}, hi[3] = {60, 45, 25};
    fm_error err;
    fm_error_clear(&err);
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = voxel;
    double t0 = bench_wall_s();
    fm_stock *s = fm_stock_new_box(lo, hi, &so, &err);
    if (!s) {
        fprintf(stderr, "stock: %s\n", err.message);
        return 1;
    }
    /* A machined part: a grid of flat-end plunges of several depths, ball-end
     * grooves along, across and diagonally, and a wide shallow facing pocket. */
    cut cuts[64];
    int nc = 0;
    cuts[nc++] = (cut){0, {30, 22.5, 21}, {0, 0, 40}, 14};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 2; j++)
            cuts[nc++] = (cut){0, {8 + 14.5 * i, 7 + 31 * j, 25 - 3 - 2.5 * i - j}, {0, 0, 40},
                               2 + 0.5 * j};
    for (int i = 0; i < 3; i++)
        cuts[nc++] = (cut){1, {4, 14 + 8 * i, 22 - i}, {56, 14 + 8 * i + 3, 22 - i}, 1.5};
    cuts[nc++] = (cut){1, {5, 40, 24}, {55, 5, 24}, 2.0};
    cuts[nc++] = (cut){1, {45, 3, 20}, {45, 42, 17}, 3.0};
    for (int i = 0; i < nc; i++) {
        fm_field f = cut_field(&cuts[i]);
        /* the plunges as tool 1, the grooves as tool 2 (for tool colours) */
        const fm_stock_cut tc = {cuts[i].ball ? 2 : 1, i, 0, 0};
        if (fm_stock_subtract(s, &f, &tc, NULL, &err) != FM_OK) {
            fprintf(stderr, "cut %d: %s\n", i, err.message);
            return 1;
        }
    }
    printf("stock: %.0f x %.0f x %.0f mm, voxel %.3f mm, %d cuts, built in %.2f s\n", hi[0],
           hi[1], hi[2], voxel, nc, bench_wall_s() - t0);

    fm_mesh_extract_options eo;
    fm_mesh_extract_default(&eo);
    eo.normals = 0;
    t0 = bench_wall_s();
    fm_mesh *m = fm_mesh_from_stock(s, &eo, &err);
    double t_whole = bench_wall_s() - t0;
    if (!m) {
        fprintf(stderr, "mesh: %s\n", err.message);
        return 1;
    }
    fm_mesh_topology topo;
    fm_mesh_topology_check(m, &topo, NULL);
    printf("mesh: %zu vertices, %zu triangles, %zu boundary / %zu misoriented edges, "
           "whole-grid remesh %.3f s\n",
           m->vertex_count, m->triangle_count, topo.boundary_edges, topo.misoriented_edges,
           t_whole);

    uint8_t *stl = NULL;
    size_t stl_size = 0;
    fm_mesh_encode_stl(m, &stl, &stl_size, NULL);
    free(stl);
    printf("binary STL: %zu bytes\n\n", stl_size);

    grid_index gi;
    index_build(&gi, m, voxel);
    float blo[3], bhi[3];
    fm_mesh_bounds(m, blo, bhi);
    printf("%4s %5s %12s %7s %12s %12s %9s %9s\n", "bits", "speed", "draco bytes", "STL/drc",
           "max err um", "bound um", "enc s", "dec s");
    const int bits_list[] = {11, 12, 14, 16, 18};
    const int speeds[] = {0, 5, 7, 10};
    for (size_t bi = 0; bi < sizeof bits_list / sizeof *bits_list; bi++)
        for (size_t si = 0; si < sizeof speeds / sizeof *speeds; si++) {
            fm_mesh_draco_options o;
            fm_mesh_draco_default(&o);
            o.position_bits = bits_list[bi];
            o.speed = speeds[si];
            uint8_t *d = NULL;
            size_t dsize = 0;
            double te = bench_wall_s();
            if (fm_mesh_encode_draco(m, &o, &d, &dsize, &err) != FM_OK) {
                fprintf(stderr, "draco: %s\n", err.message);
                return 1;
            }
            te = bench_wall_s() - te;
            double td = bench_wall_s();
            fm_mesh *back = fm_mesh_decode_draco(d, dsize, NULL, &err);
            td = bench_wall_s() - td;
            double e = back ? max_error(&gi, m, back) : NAN;
            printf("%4d %5d %12zu %7.1f %12.3f %12.3f %9.3f %9.3f\n", o.position_bits, o.speed,
                   dsize, (double)stl_size / dsize, 1000 * e,
                   1000 * fm_mesh_draco_error_bound(blo, bhi, o.position_bits), te, td);
            fm_mesh_free(back);
            free(d);
        }

    /* Normals and depth colours as the viewer gets them, at the defaults. */
    fm_mesh_extract_options ec = eo;
    ec.normals = 1;
    ec.coloring = FM_MESH_COLOR_DEPTH;
    ec.top_z = hi[2];
    ec.depth_range = 10;
    fm_mesh *mc = fm_mesh_from_stock(s, &ec, &err);
    if (mc) {
        uint8_t *d = NULL;
        size_t dsize = 0;
        fm_mesh_encode_draco(mc, NULL, &d, &dsize, NULL);
        printf("\ndefaults with normals and depth colours: %zu bytes (STL %.1fx larger)\n", dsize,
               (double)stl_size / dsize);
        free(d);
    }
    /* Tool colours as the daemon sends them: what the tool-mark lookup
     * costs next to the same mesh with normals only. */
    fm_mesh_extract_options en = ec, et = ec;
    en.coloring = FM_MESH_COLOR_NONE;
    et.coloring = FM_MESH_COLOR_TOOL;
    t0 = bench_wall_s();
    fm_mesh *mn = fm_mesh_from_stock(s, &en, &err);
    const double t_plain = bench_wall_s() - t0;
    t0 = bench_wall_s();
    fm_mesh *mt = fm_mesh_from_stock(s, &et, &err);
    const double t_tool = bench_wall_s() - t0;
    if (mn && mt) {
        uint8_t *d = NULL;
        size_t dsize = 0;
        fm_mesh_encode_draco(mt, NULL, &d, &dsize, NULL);
        printf("tool colours: remesh %.3f s vs %.3f s without colours (%zu vertices); Draco %zu "
               "bytes (STL %.1fx larger)\n",
               t_tool, t_plain, mt->vertex_count, dsize, (double)stl_size / dsize);
        free(d);
    }
    fm_mesh_free(mn);
    fm_mesh_free(mt);

    /* One more motion: a short ball-end groove, then only its dirty chunks. */
    uint64_t v = fm_stock_version(s);
    cut extra = {1, {20, 30, 21}, {32, 33, 21}, 2.0};
    fm_field f = cut_field(&extra);
    fm_stock_subtract(s, &f, NULL, NULL, &err);
    fm_stock_chunk chunks[512];
    t0 = bench_wall_s();
    size_t n = fm_stock_changed_chunks(s, v, chunks, 512);
    size_t bytes = 0, tris = 0;
    for (size_t i = 0; i < n && i < 512; i++) {
        fm_mesh *cm = fm_mesh_from_stock_chunk(s, chunks[i].index, &ec, &err);
        if (!cm) {
            fprintf(stderr, "chunk: %s\n", err.message);
            return 1;
        }
        uint8_t *d = NULL;
        size_t dsize = 0;
        fm_mesh_encode_draco(cm, NULL, &d, &dsize, NULL);
        bytes += dsize;
        tris += cm->triangle_count;
        free(d);
        fm_mesh_free(cm);
    }
    double t_chunks = bench_wall_s() - t0;
    size_t all = fm_stock_changed_chunks(s, 0, chunks, 0);
    t0 = bench_wall_s();
    fm_mesh *m2 = fm_mesh_from_stock(s, &ec, &err);
    double t_whole2 = bench_wall_s() - t0;
    t0 = bench_wall_s();
    uint8_t *d2 = NULL;
    size_t d2size = 0;
    fm_mesh_encode_draco(m2, NULL, &d2, &d2size, NULL);
    double t_enc2 = bench_wall_s() - t0;
    printf("\none motion: %zu of %zu chunks dirty, remesh + Draco of them %.3f s (%zu triangles, "
           "%zu bytes)\n",
           n, all, t_chunks, tris, bytes);
    printf("whole grid: remesh %.3f s + Draco %.3f s = %.3f s (%zu triangles, %zu bytes)\n",
           t_whole2, t_enc2, t_whole2 + t_enc2, m2->triangle_count, d2size);

    if (out_dir) {
        char path[512];
        fm_mesh_draco_options od;
        fm_mesh_draco_default(&od);
        snprintf(path, sizeof path, "%s/bench_part.drc", out_dir);
        fm_mesh_write_draco(m2, &od, path, NULL);
        snprintf(path, sizeof path, "%s/bench_part.stl", out_dir);
        fm_mesh_write_stl(m2, path, NULL);
        snprintf(path, sizeof path, "%s/bench_part.png", out_dir);
        fm_render_options ro;
        fm_render_default(&ro);
        double path_pts[6] = {20, 30, 21, 32, 33, 21};
        double rapid_pts[9] = {32, 33, 21, 32, 33, 30, 5, 5, 30};
        fm_render_polyline pl[2] = {{path_pts, 2, 0}, {rapid_pts, 3, 1}};
        ro.paths = pl;
        ro.path_count = 2;
        t0 = bench_wall_s();
        fm_render_png(m2, &ro, path, NULL);
        printf("render %dx%d (antialias %d): %.3f s -> %s\n", ro.width, ro.height, ro.antialias,
               bench_wall_s() - t0, path);
    }
    free(d2);
    fm_mesh_free(m2);
    fm_mesh_free(mc);
    free(gi.start);
    free(gi.ids);
    fm_mesh_free(m);
    fm_stock_free(s);
    return 0;
}
