/* test_stock_memory_usage.c: fm_stock_memory_usage, the breakdown that
 * bench_simulate prints (issue 37). For a box stock the active voxels and
 * the leaves are counted here from the box's exact distance: a voxel is in
 * the band when its centre lies within band x voxel of the surface, and a
 * leaf exists where an aligned 8^3 block holds one such voxel (the box's
 * faces sit at half-voxel positions, so no centre lies at exactly the
 * band's distance). After a ball slot the counts are taken again by
 * walking the grid's leaves (fm_stock_visit), and the tool marks hold
 * records for no more leaves than the grid has. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fields.h"
#include "test.h"

static const double box_lo[3] = {0, 0, 0}, box_hi[3] = {12, 7, 5};

/* the box's exact signed distance (fields.h), positive inside */
static double box_distance(const double p[3])
{
    const shape b = {.kind = SHAPE_BOX, .a = {box_lo[0], box_lo[1], box_lo[2]}, .b = {box_hi[0], box_hi[1], box_hi[2]}};
    return shape_eval(&b, p[0], p[1], p[2]);
}

static int32_t floor_div8(int32_t i) { return i >= 0 ? i / 8 : -((-i + 7) / 8); }

typedef struct counts {
    double band;
    size_t leaves, active;
} counts;

static int count_leaf(void *user, const fm_stock_region *r)
{
    counts *c = user;
    if (!r->values) return 0;
    c->leaves++;
    for (int i = 0; i < 512; i++) c->active += fabsf(r->values[i]) < c->band;
    return 0;
}

int main(void)
{
    fm_error err;
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = 0.25;
    const double h = o.voxel_mm, band = o.band_voxels * h;
    fm_stock *s = fm_stock_new_box(box_lo, box_hi, &o, &err);
    CHECK(s != NULL);
    if (!s) return test_summary("stock_memory_usage");

    /* by hand: every voxel centre within reach of the box, by its exact
     * distance; leaves as the set of 8^3 blocks holding one */
    const double zero[3] = {0, 0, 0};
    double origin[3];
    fm_stock_index_to_world(s, zero, origin);
    int32_t lo[3], hi[3], nb[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = (int32_t)floor((box_lo[k] - band - origin[k]) / h) - 1;
        hi[k] = (int32_t)ceil((box_hi[k] + band - origin[k]) / h) + 1;
        nb[k] = floor_div8(hi[k]) - floor_div8(lo[k]) + 1;
    }
    unsigned char *block = calloc((size_t)nb[0] * nb[1] * nb[2], 1);
    size_t want_active = 0, want_leaves = 0;
    for (int32_t i = lo[0]; i <= hi[0]; i++)
        for (int32_t j = lo[1]; j <= hi[1]; j++)
            for (int32_t k = lo[2]; k <= hi[2]; k++) {
                const double p[3] = {origin[0] + h * i, origin[1] + h * j, origin[2] + h * k};
                if (!(fabs(box_distance(p)) < band)) continue;
                want_active++;
                const size_t b = ((size_t)(floor_div8(i) - floor_div8(lo[0])) * nb[1] +
                                  (size_t)(floor_div8(j) - floor_div8(lo[1]))) * nb[2] +
                                 (size_t)(floor_div8(k) - floor_div8(lo[2]));
                if (!block[b]) want_leaves++;
                block[b] = 1;
            }
    free(block);

    fm_stock_memory m;
    fm_stock_memory_usage(s, &m);
    printf("box 12 x 7 x 5 mm at %g mm: %zu active voxels (by hand %zu), %zu leaves (by hand %zu), "
           "%zu internal nodes; band %zu bytes, internal %zu, leaf %zu; marks %zu bytes\n",
           h, m.active_voxels, want_active, m.leaves, want_leaves, m.internal_nodes, m.band_bytes,
           m.internal_bytes, m.leaf_bytes, m.marks_bytes);
    CHECK(m.active_voxels == want_active);
    CHECK(m.leaves == want_leaves);
    /* each leaf holds its 512 float values at least; a 128^3 internal
     * node its 16^3 child table of at least a pointer each */
    CHECK(m.leaf_bytes >= 512 * sizeof(float));
    CHECK(m.band_bytes >= m.leaves * 512 * sizeof(float) + m.internal_nodes * 4096 * sizeof(void *));
    CHECK(m.internal_nodes >= 1);
    CHECK(m.internal_bytes >= m.internal_nodes * 4096 * sizeof(void *));
    CHECK(m.marks_leaves == 0); /* no cut yet */

    /* a ball slot across the top: the walk's counts, and marks for the
     * leaves the cut set voxels in (at most all of them) */
    const double a[3] = {-2, 3.5, 5.5}, b[3] = {14, 3.5, 5.5};
    shape c = make_capsule(a, b, 2);
    fm_field f = shape_field(&c);
    CHECK(fm_stock_subtract(s, &f, NULL, NULL, &err) == FM_OK);
    fm_stock_memory_usage(s, &m);
    counts walk = {band * (1 - 1e-6), 0, 0};
    int32_t glo[3], ghi[3];
    CHECK(fm_stock_active_bounds(s, glo, ghi, &err) == FM_OK);
    for (int k = 0; k < 3; k++) {
        glo[k] -= 16;
        ghi[k] += 16;
    }
    CHECK(fm_stock_visit(s, glo, ghi, NULL, count_leaf, &walk, &err) == FM_OK);
    printf("after a slot: %zu active voxels (walk %zu), %zu leaves (walk %zu), marks %zu leaves %zu bytes\n",
           m.active_voxels, walk.active, m.leaves, walk.leaves, m.marks_leaves, m.marks_bytes);
    CHECK(m.active_voxels == walk.active);
    CHECK(m.leaves == walk.leaves);
    CHECK(m.marks_leaves > 0 && m.marks_leaves <= m.leaves);
    /* a record keeps at least the 512-bit mask of the voxels set */
    CHECK(m.marks_bytes >= m.marks_leaves * 64);
    fm_stock_free(s);
    return test_summary("stock_memory_usage");
}
