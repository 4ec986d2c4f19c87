/* bench_remesh.c: where a live move's publication time goes, in process
 * (not a test). The scene of bench_live (a 100 x 60 x 10 mm block at
 * 0.1 mm voxels, a 6 mm flat end mill plunged 1 mm deep, then moves of 1 mm
 * along X), cut with an exact analytic swept volume; after each move the
 * changed chunks are remeshed and Draco-encoded as the daemon publishes them
 * (normals, tool colours). Prints per move: the cut, the chunks' meshing
 * (whole extraction, then the share of normals and colours), Draco at
 * speed 5 and at --speed, and the CPU time of it all; then the daemon's
 * way (fm_mesh_chunk_cache, one per chunk: leaves remeshed, CPU of mesh +
 * Draco speed 7 against whole chunks, Draco speed 7 against --speed on the
 * cached meshes, how many chunks came out as their previous version).
 *   bench_remesh [--moves N] [--voxel MM] [--speed S]
 */
#include "frep/frep.h"
#include "mesh/mesh.h"
#include "stock/stock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_clock.h"

/* A flat end mill of radius r, bottom at z0, moved from a to b in XY: the
 * slab z0..z1 over the points within r of the segment. Exact signed
 * distance, positive inside. */
typedef struct slot {
    double a[2], b[2], r, z0, z1;
} slot;

static double slot_f(const slot *s, double x, double y, double z)
{
    const double dx = s->b[0] - s->a[0], dy = s->b[1] - s->a[1];
    const double qx = x - s->a[0], qy = y - s->a[1];
    const double dd = dx * dx + dy * dy;
    double t = dd > 0 ? (qx * dx + qy * dy) / dd : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    const double dr = hypot(qx - t * dx, qy - t * dy) - s->r;
    const double dz = fmax(s->z0 - z, z - s->z1);
    return -(hypot(fmax(dr, 0), fmax(dz, 0)) + fmin(fmax(dr, dz), 0));
}

static void slot_batch(void *ctx, void *w, size_t n, const double *x, const double *y,
                       const double *z, double *out)
{
    (void)w;
    for (size_t i = 0; i < n; i++) out[i] = slot_f(ctx, x[i], y[i], z[i]);
}

/* 1-Lipschitz: the value at the centre plus or minus the half diagonal */
static fm_interval slot_interval(void *ctx, void *w, const fm_interval box[3])
{
    (void)w;
    double h = 0;
    for (int k = 0; k < 3; k++) h += pow(0.5 * (box[k].hi - box[k].lo), 2);
    const double v = slot_f(ctx, 0.5 * (box[0].lo + box[0].hi), 0.5 * (box[1].lo + box[1].hi),
                            0.5 * (box[2].lo + box[2].hi));
    return (fm_interval){v - sqrt(h), v + sqrt(h)};
}

static fm_field slot_field(slot *s)
{
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = s;
    for (int k = 0; k < 2; k++) {
        f.lo[k] = fmin(s->a[k], s->b[k]) - s->r;
        f.hi[k] = fmax(s->a[k], s->b[k]) + s->r;
    }
    f.lo[2] = s->z0;
    f.hi[2] = s->z1;
    f.batch = slot_batch;
    f.interval = slot_interval;
    return f;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n ? v[n / 2] : 0;
}

int main(int argc, char **argv)
{
    int moves = 40, speed = 10;
    double voxel = 0.1;
    for (int i = 1; i < argc; i++) {
        const char *v = i + 1 < argc ? argv[i + 1] : "0";
        if (!strcmp(argv[i], "--moves")) moves = atoi(v), i++;
        else if (!strcmp(argv[i], "--voxel")) voxel = atof(v), i++;
        else if (!strcmp(argv[i], "--speed")) speed = atoi(v), i++;
        else {
            fprintf(stderr, "usage: bench_remesh [--moves N] [--voxel MM] [--speed 0..10]\n");
            return 2;
        }
    }
    if (moves < 1 || moves > 80 || !(voxel > 0)) {
        fprintf(stderr, "bench_remesh: --moves 1..80, --voxel > 0\n");
        return 2;
    }
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = voxel;
    fm_error err;
    const double lo[3] = {0, 0, -10}, hi[3] = {100, 60, 0};
    fm_stock *s = fm_stock_new_box(lo, hi, &so, &err);
    if (!s) {
        fprintf(stderr, "bench_remesh: %s\n", err.message);
        return 1;
    }
    /* plunge at x 10, y 30, as bench_live places the tool */
    slot plunge = {{10, 30}, {10, 30}, 3, -1, 20};
    fm_field pf = slot_field(&plunge);
    fm_stock_cut cut = {1, -1, 0, 0};
    if (fm_stock_subtract(s, &pf, &cut, NULL, &err) != FM_OK) {
        fprintf(stderr, "bench_remesh: %s\n", err.message);
        return 1;
    }

    fm_mesh_extract_options eo;
    fm_mesh_extract_default(&eo);
    eo.coloring = FM_MESH_COLOR_TOOL;
    fm_mesh_extract_options bare = eo;
    bare.normals = 0;
    bare.coloring = FM_MESH_COLOR_NONE;
    fm_mesh_extract_options normals_only = bare;
    normals_only.normals = 1;
    fm_mesh_draco_options d5, dfast;
    fm_mesh_draco_default(&d5);
    fm_mesh_draco_options d7 = d5;
    d7.speed = 7; /* the daemon's live chunks (publish.c) */
    dfast = d5;
    dfast.speed = speed;

    double *t_cut = calloc((size_t)moves, sizeof(double));
    double *t_mesh = calloc((size_t)moves, sizeof(double));
    double *t_bare = calloc((size_t)moves, sizeof(double));
    double *t_norm = calloc((size_t)moves, sizeof(double));
    double *t_enc5 = calloc((size_t)moves, sizeof(double));
    double *t_encf = calloc((size_t)moves, sizeof(double));
    double *c_all = calloc((size_t)moves, sizeof(double));
    double *t_cached = calloc((size_t)moves, sizeof(double));
    double *c_whole = calloc((size_t)moves, sizeof(double));
    double *c_cached = calloc((size_t)moves, sizeof(double));
    double *c_enc7 = calloc((size_t)moves, sizeof(double));
    double *c_encf = calloc((size_t)moves, sizeof(double));
    size_t bytes7 = 0, bytesf_cached = 0;
    /* one cache per chunk, as the daemon keeps them (filled by a first
     * meshing of every chunk with surface) */
    enum { MAX_CACHES = 1024 };
    int32_t cache_index[MAX_CACHES][3];
    fm_mesh_chunk_cache *caches[MAX_CACHES];
    fm_mesh *previous[MAX_CACHES] = {0};
    size_t unchanged = 0;
    size_t ncaches = 0, leaves_total = 0, cached_differ = 0;
    if (!t_cut || !t_mesh || !t_bare || !t_enc5 || !t_encf || !c_all || !t_cached || !c_whole ||
        !c_cached || !c_enc7 || !c_encf)
        return 1;
    {
        fm_stock_chunk *all = malloc(4096 * sizeof *all);
        size_t n = all ? fm_stock_changed_chunks(s, 0, all, 4096) : 0;
        for (size_t i = 0; i < n && i < 4096 && ncaches < MAX_CACHES; i++) {
            memcpy(cache_index[ncaches], all[i].index, sizeof all[i].index);
            caches[ncaches] = fm_mesh_chunk_cache_new();
            fm_mesh_free(fm_mesh_from_stock_chunk_cached(s, all[i].index, &eo, caches[ncaches], &err));
            ncaches++;
        }
        free(all);
    }
    size_t chunks_total = 0, tris_total = 0, bytes5 = 0, bytesf = 0;
    fm_stock_chunk changed[64];
    for (int m = 0; m < moves; m++) {
        uint64_t since = fm_stock_version(s);
        slot mv = {{10 + m, 30}, {11 + m, 30}, 3, -1, 20};
        fm_field f = slot_field(&mv);
        const double c0 = bench_cpu_s();
        double t0 = bench_wall_s();
        if (fm_stock_subtract(s, &f, &cut, NULL, &err) != FM_OK) {
            fprintf(stderr, "bench_remesh: %s\n", err.message);
            return 1;
        }
        t_cut[m] = bench_wall_s() - t0;
        size_t n = fm_stock_changed_chunks(s, since, changed, 64);
        if (n > 64) n = 64;
        chunks_total += n;
        for (size_t i = 0; i < n; i++) {
            t0 = bench_wall_s();
            fm_mesh *cm = fm_mesh_from_stock_chunk(s, changed[i].index, &eo, &err);
            t_mesh[m] += bench_wall_s() - t0;
            t0 = bench_wall_s();
            fm_mesh *bm = fm_mesh_from_stock_chunk(s, changed[i].index, &bare, &err);
            t_bare[m] += bench_wall_s() - t0;
            t0 = bench_wall_s();
            fm_mesh *nm = fm_mesh_from_stock_chunk(s, changed[i].index, &normals_only, &err);
            t_norm[m] += bench_wall_s() - t0;
            fm_mesh_free(nm);
            if (!cm || !bm) {
                fprintf(stderr, "bench_remesh: %s\n", err.message);
                return 1;
            }
            tris_total += cm->triangle_count;
            /* the publication as the daemon makes it: whole, then with the cache */
            size_t k = 0;
            while (k < ncaches && memcmp(cache_index[k], changed[i].index, sizeof cache_index[k]))
                k++;
            if (k == ncaches && ncaches < MAX_CACHES) {
                memcpy(cache_index[k], changed[i].index, sizeof cache_index[k]);
                caches[ncaches++] = fm_mesh_chunk_cache_new();
            }
            fm_mesh_chunk_cache *cache = k < ncaches ? caches[k] : NULL;
            uint8_t *dd = NULL;
            size_t dds = 0;
            double cw = bench_cpu_s();
            fm_mesh *wm = fm_mesh_from_stock_chunk(s, changed[i].index, &eo, &err);
            if (wm && wm->triangle_count) fm_mesh_encode_draco(wm, &d7, &dd, &dds, &err);
            c_whole[m] += bench_cpu_s() - cw;
            free(dd);
            dd = NULL;
            cw = bench_cpu_s();
            t0 = bench_wall_s();
            fm_mesh *km = fm_mesh_from_stock_chunk_cached(s, changed[i].index, &eo, cache, &err);
            t_cached[m] += bench_wall_s() - t0;
            const double ce = bench_cpu_s();
            if (km && km->triangle_count && fm_mesh_encode_draco(km, &d7, &dd, &dds, &err) == FM_OK)
                bytes7 += dds;
            c_cached[m] += bench_cpu_s() - cw;
            c_enc7[m] += bench_cpu_s() - ce;
            free(dd);
            dd = NULL;
            cw = bench_cpu_s();
            if (km && km->triangle_count && fm_mesh_encode_draco(km, &dfast, &dd, &dds, &err) == FM_OK)
                bytesf_cached += dds;
            c_encf[m] += bench_cpu_s() - cw;
            free(dd);
            leaves_total += fm_mesh_chunk_cache_last_leaves(cache);
            if (!km || !wm || km->triangle_count != wm->triangle_count) cached_differ++;
            if (k < ncaches) {
                fm_mesh *p = previous[k];
                if (p && km && p->vertex_count == km->vertex_count &&
                    p->triangle_count == km->triangle_count &&
                    !memcmp(p->positions, km->positions, 12 * km->vertex_count) &&
                    !memcmp(p->normals, km->normals, 12 * km->vertex_count) &&
                    !memcmp(p->colors, km->colors, 3 * km->vertex_count) &&
                    !memcmp(p->triangles, km->triangles, 12 * km->triangle_count))
                    unchanged++;
                fm_mesh_free(p);
                previous[k] = km;
                km = NULL;
            }
            fm_mesh_free(km);
            fm_mesh_free(wm);
            if (getenv("BENCH_REMESH_LIST"))
                printf("move %d chunk %d %d %d: %zu triangles\n", m, changed[i].index[0],
                       changed[i].index[1], changed[i].index[2], cm->triangle_count);
            uint8_t *d = NULL;
            size_t ds = 0;
            t0 = bench_wall_s();
            if (cm->triangle_count && fm_mesh_encode_draco(cm, &d5, &d, &ds, &err) == FM_OK)
                bytes5 += ds;
            t_enc5[m] += bench_wall_s() - t0;
            free(d);
            d = NULL;
            t0 = bench_wall_s();
            if (cm->triangle_count && fm_mesh_encode_draco(cm, &dfast, &d, &ds, &err) == FM_OK)
                bytesf += ds;
            t_encf[m] += bench_wall_s() - t0;
            free(d);
            fm_mesh_free(cm);
            fm_mesh_free(bm);
        }
        c_all[m] = bench_cpu_s() - c0;
    }
    printf("bench_remesh: %d moves of 1 mm at 1 mm deep, voxel %g mm, 6 mm flat; %.2f chunks and "
           "%.0f triangles per move\n",
           moves, voxel, (double)chunks_total / moves, (double)tris_total / moves);
    printf("  per move, median wall ms: cut %.2f; mesh (normals, tool colours) %.2f, of which "
           "bare extraction %.2f, with normals %.2f; Draco speed 5 %.2f (%.0f B), speed %d %.2f (%.0f B)\n",
           1e3 * median(t_cut, moves), 1e3 * median(t_mesh, moves), 1e3 * median(t_bare, moves),
           1e3 * median(t_norm, moves),
           1e3 * median(t_enc5, moves), (double)bytes5 / moves, speed,
           1e3 * median(t_encf, moves), (double)bytesf / moves);
    printf("  CPU per move (all of the above, extraction twice, both encodings): median %.2f ms\n",
           1e3 * median(c_all, moves));
    printf("  with fm_mesh_chunk_cache: %.0f of 512 leaves remeshed per chunk, cached meshing %.2f "
           "ms wall per move (median), %zu chunk meshes with another triangle count than the "
           "whole chunk's\n",
           chunks_total ? (double)leaves_total / chunks_total : 0, 1e3 * median(t_cached, moves),
           cached_differ);
    const double cw = median(c_whole, moves), cc = median(c_cached, moves);
    printf("  publication CPU per move (mesh + Draco speed 7), median: whole chunks %.2f ms, "
           "cached %.2f ms (ratio %.2f)\n",
           1e3 * cw, 1e3 * cc, cw > 0 ? cc / cw : 0);
    printf("  Draco CPU per move (median) of the cached meshes: speed 7 %.2f ms (%.0f B), speed %d "
           "%.2f ms (%.0f B)\n",
           1e3 * median(c_enc7, moves), (double)bytes7 / moves, speed, 1e3 * median(c_encf, moves),
           (double)bytesf_cached / moves);
    printf("  %zu of %zu changed chunks' meshes identical to their previous version\n", unchanged,
           chunks_total);
    for (size_t k = 0; k < ncaches; k++) {
        fm_mesh_chunk_cache_free(caches[k]);
        fm_mesh_free(previous[k]);
    }
    fm_stock_free(s);
    return 0;
}
