/* test_stock_query.c: lib/stock's read-only queries. fm_stock_visit must
 * report every voxel of the asked box exactly once (leaves with the values
 * a box stock stores: its exact signed distance, computed here from the
 * box's formula, clamped to the band; tiles on the right side of the
 * surface), skip what its prune callback rejects and stop when asked.
 * fm_stock_new_from_zero_set must store true distances for a field whose
 * gradient is 0.1 (a sphere scaled down tenfold): the stored values are
 * compared with the sphere's distance. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stock/stock.h"
#include "test.h"

static const double box_lo[3] = {0, 0, 0}, box_hi[3] = {10, 6, 4};

static double box_distance(const double p[3])
{
    double out2 = 0, in = -INFINITY;
    for (int k = 0; k < 3; k++) {
        double c = 0.5 * (box_lo[k] + box_hi[k]), h = 0.5 * (box_hi[k] - box_lo[k]);
        double d = fabs(p[k] - c) - h;
        if (d > 0) out2 += d * d;
        if (d > in) in = d;
    }
    return -(sqrt(out2) + fmin(in, 0));
}

typedef struct walk {
    const fm_stock *stock;
    double band;
    int32_t lo[3], hi[3];
    unsigned char *seen; /* voxels of [lo, hi] met so far */
    long leaves, tiles, twice, wrong_value, wrong_tile, outside_asked;
    double worst;
    int stop_after;   /* > 0: stop after that many regions */
    long regions;
    int32_t prune_x;  /* blocks wholly beyond this x index are pruned */
    long pruned_met;
} walk;

static long cell(const walk *w, const int32_t ijk[3])
{
    long n = 0, stride = 1;
    for (int k = 0; k < 3; k++) {
        if (ijk[k] < w->lo[k] || ijk[k] > w->hi[k]) return -1;
        n += (ijk[k] - w->lo[k]) * stride;
        stride *= w->hi[k] - w->lo[k] + 1;
    }
    return n;
}

static int prune_beyond(void *user, const int32_t lo[3], const int32_t hi[3])
{
    (void)hi;
    walk *w = user;
    return lo[0] > w->prune_x;
}

static int on_region(void *user, const fm_stock_region *r)
{
    walk *w = user;
    w->regions++;
    if (r->values && r->lo[0] > w->prune_x) w->pruned_met++;
    if (r->values) w->leaves++;
    else w->tiles++;
    int met = 0;
    int32_t lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = r->lo[k] > w->lo[k] ? r->lo[k] : w->lo[k];
        hi[k] = r->hi[k] < w->hi[k] ? r->hi[k] : w->hi[k];
    }
    for (int32_t x = lo[0]; x <= hi[0]; x++)
        for (int32_t y = lo[1]; y <= hi[1]; y++)
            for (int32_t z = lo[2]; z <= hi[2]; z++) {
                const int32_t ijk[3] = {x, y, z};
                long c = cell(w, ijk);
                if (c < 0) continue;
                met = 1;
                if (w->seen[c]) w->twice++;
                w->seen[c] = 1;
                double idx[3] = {x, y, z}, p[3];
                fm_stock_index_to_world(w->stock, idx, p);
                double d = box_distance(p);
                if (r->values) {
                    int i = 64 * (x - r->lo[0]) + 8 * (y - r->lo[1]) + (z - r->lo[2]);
                    double want = fmax(-w->band, fmin(w->band, d));
                    double e = fabs(r->values[i] - want);
                    if (e > w->worst) w->worst = e;
                    if (e > 1e-5) w->wrong_value++;
                } else if ((r->value > 0) != (d > 0) || fabs(d) < w->band - 1e-6) {
                    /* a tile lies beyond the band, on its own side */
                    w->wrong_tile++;
                }
            }
    if (!met) w->outside_asked++;
    return w->stop_after > 0 && w->regions >= w->stop_after;
}

static void test_visit(void)
{
    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = 0.5;
    opt.band_voxels = 3;
    fm_error err;
    fm_stock *s = fm_stock_new_box(box_lo, box_hi, &opt, &err);
    CHECK(s != NULL);
    if (!s) return;
    walk w;
    memset(&w, 0, sizeof w);
    w.stock = s;
    w.band = 3 * 0.5;
    /* the box and 4 mm around it, from an index box not aligned to leaves */
    const double wlo[3] = {-4, -4, -4}, whi[3] = {14, 10, 8};
    double zero[3] = {0, 0, 0}, origin[3];
    fm_stock_index_to_world(s, zero, origin);
    for (int k = 0; k < 3; k++) {
        w.lo[k] = (int32_t)floor((wlo[k] - origin[k]) / 0.5);
        w.hi[k] = (int32_t)ceil((whi[k] - origin[k]) / 0.5);
    }
    long n = 1;
    for (int k = 0; k < 3; k++) n *= w.hi[k] - w.lo[k] + 1;
    w.seen = calloc((size_t)n, 1);
    w.prune_x = INT32_MAX;
    CHECK(fm_stock_visit(s, w.lo, w.hi, NULL, on_region, &w, &err) == FM_OK);
    long missing = 0;
    for (long i = 0; i < n; i++) missing += !w.seen[i];
    fprintf(stderr, "visit: %ld leaves, %ld tiles, worst value error %.3g\n", w.leaves, w.tiles,
            w.worst);
    CHECK(missing == 0);
    CHECK(w.twice == 0);
    CHECK(w.wrong_value == 0);
    CHECK(w.wrong_tile == 0);
    CHECK(w.outside_asked == 0);
    CHECK(w.leaves > 0 && w.tiles > 0);

    /* pruning: no leaf wholly beyond x index prune_x is reported (tiles
     * come whole, unasked) */
    memset(w.seen, 0, (size_t)n);
    w.prune_x = w.lo[0] + (w.hi[0] - w.lo[0]) / 2;
    long all = w.regions;
    w.regions = 0;
    CHECK(fm_stock_visit(s, w.lo, w.hi, prune_beyond, on_region, &w, &err) == FM_OK);
    CHECK(w.pruned_met == 0);
    CHECK(w.regions < all);

    /* stopping */
    w.regions = 0;
    w.stop_after = 3;
    w.prune_x = INT32_MAX;
    memset(w.seen, 0, (size_t)n);
    CHECK(fm_stock_visit(s, w.lo, w.hi, NULL, on_region, &w, &err) == FM_OK);
    CHECK(w.regions == 3);

    /* an empty box is no region */
    int32_t elo[3] = {5, 5, 5}, ehi[3] = {4, 5, 5};
    w.regions = 0;
    w.stop_after = 0;
    CHECK(fm_stock_visit(s, elo, ehi, NULL, on_region, &w, &err) == FM_OK);
    CHECK(w.regions == 0);
    free(w.seen);
    fm_stock_free(s);
}

/* A sphere of radius 5 about (1, 2, 3) as a field whose values are a tenth
 * of the distance. */
static const double sc[3] = {1, 2, 3}, sr = 5;

static double scaled_sphere(double x, double y, double z)
{
    return 0.1 * (sr - sqrt((x - sc[0]) * (x - sc[0]) + (y - sc[1]) * (y - sc[1]) +
                            (z - sc[2]) * (z - sc[2])));
}

static void sphere_batch(void *ctx, void *worker, size_t n, const double *x, const double *y,
                         const double *z, double *out)
{
    (void)ctx;
    (void)worker;
    for (size_t i = 0; i < n; i++) out[i] = scaled_sphere(x[i], y[i], z[i]);
}

/* 0.1-Lipschitz: the centre value +- a tenth of the half diagonal. */
static fm_interval sphere_interval(void *ctx, void *worker, const fm_interval box[3])
{
    (void)ctx;
    (void)worker;
    double c[3], r2 = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (box[k].lo + box[k].hi);
        double h = 0.5 * (box[k].hi - box[k].lo);
        r2 += h * h;
    }
    double v = scaled_sphere(c[0], c[1], c[2]), r = 0.1 * sqrt(r2);
    fm_interval out = {v - r, v + r};
    return out;
}

typedef struct sphere_walk {
    const fm_stock *stock;
    double band, worst;
    long checked;
} sphere_walk;

static int on_sphere_region(void *user, const fm_stock_region *r)
{
    sphere_walk *w = user;
    if (!r->values) return 0;
    for (int i = 0; i < 512; i++) {
        double idx[3] = {r->lo[0] + (i >> 6), r->lo[1] + ((i >> 3) & 7), r->lo[2] + (i & 7)}, p[3];
        fm_stock_index_to_world(w->stock, idx, p);
        double d = 10 * scaled_sphere(p[0], p[1], p[2]);
        if (fabs(d) > w->band - 0.25) continue; /* clamped there */
        double e = fabs(r->values[i] - d);
        if (e > w->worst) w->worst = e;
        w->checked++;
    }
    return 0;
}

static void test_zero_set(void)
{
    fm_field f;
    memset(&f, 0, sizeof f);
    for (int k = 0; k < 3; k++) {
        f.lo[k] = sc[k] - sr - 1;
        f.hi[k] = sc[k] + sr + 1;
    }
    f.batch = sphere_batch;
    f.interval = sphere_interval;
    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = 0.25;
    opt.band_voxels = 4;
    fm_error err;
    fm_stock *s = fm_stock_new_from_zero_set(&f, &opt, &err);
    if (!s) fprintf(stderr, "zero set: %s\n", err.message);
    CHECK(s != NULL);
    if (!s) return;
    sphere_walk w = {s, 4 * 0.25, 0, 0};
    int32_t lo[3] = {-100, -100, -100}, hi[3] = {100, 100, 100};
    CHECK(fm_stock_visit(s, lo, hi, NULL, on_sphere_region, &w, &err) == FM_OK);
    fprintf(stderr, "zero set: %ld voxels in the band, worst distance error %.4f mm\n", w.checked,
            w.worst);
    CHECK(w.checked > 1000);
    /* The rebuilt band holds the distance to the meshed zero set: the mesh
     * lies within a chord's sagitta of the sphere (voxel^2 / (8 r) =
     * 0.0016 mm for the marching-cubes edges' chords) plus the linear
     * interpolation of a curved field along an edge. A tenth of a voxel
     * bounds both; the raw field would be off by 90%. */
    CHECK(w.worst < 0.025);
    /* the volume is the sphere's */
    CHECK_NEAR(fm_stock_volume(s), 4.0 / 3.0 * FM_PI * sr * sr * sr, 0.005 * 523.6);
    fm_stock_free(s);

    /* a field with no zero set is an input error, not a crash */
    fm_field empty = f;
    for (int k = 0; k < 3; k++) {
        empty.lo[k] = 100;
        empty.hi[k] = 101;
    }
    fm_stock *none = fm_stock_new_from_zero_set(&empty, &opt, &err);
    CHECK(none == NULL);
    fm_stock_free(none);
}

int main(void)
{
    test_visit();
    test_zero_set();
    fprintf(stderr, "%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures != 0;
}
