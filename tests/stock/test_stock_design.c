/* test_stock_design.c: the design comparison of lib/stock against closed
 * forms. Box stocks at 0.1 mm are cut by closed-form fields and compared with
 * box designs given as fields, as STL files the test writes, and as
 * snapshots (same transform and rebuilt from another voxel size): slabs of
 * excess and gouge of known thickness and area, a plunge deeper than the
 * design's band (the exact depth search), a 5 mm excess slab (tiles), a
 * deviation inside the tolerance, and the refusals. Expected depths are the
 * offsets the test builds in (within half a voxel), volumes their products
 * (within 2%). */
#include "fields.h"
#include "stock/stock.h"
#include "test.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#define H 0.1

static char dir[256];

static fm_stock *box_stock(const double lo[3], const double hi[3], int band, double voxel)
{
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = voxel;
    o.band_voxels = band;
    o.threads = 2;
    fm_error err;
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    if (!s) fprintf(stderr, "box stock: %s\n", err.message);
    return s;
}

static void cut(fm_stock *s, const shape *sh)
{
    fm_field f = shape_field(sh);
    fm_error err;
    if (fm_stock_subtract(s, &f, NULL, NULL, &err) != FM_OK)
        fprintf(stderr, "cut: %s\n", err.message);
}

static fm_design *field_design(const fm_stock *s, const shape *sh, double tol)
{
    fm_field f = shape_field(sh);
    fm_design_options o;
    fm_design_options_default(&o);
    o.tolerance_mm = tol;
    fm_error err;
    fm_design *d = fm_design_from_field(s, &f, &o, &err);
    if (!d) fprintf(stderr, "design: %s\n", err.message);
    return d;
}

static void put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

/* A box as a binary STL, faces wound outward. */
static void write_box_stl(const char *path, const double lo[3], const double hi[3])
{
    float c[8][3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) c[i][k] = (float)((i >> k & 1) ? hi[k] : lo[k]);
    static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    FILE *f = fopen(path, "wb");
    unsigned char head[84] = "binary box";
    put_le32(head + 80, 12);
    fwrite(head, 1, 84, f);
    for (int face = 0; face < 6; face++) {
        const int t[2][3] = {{q[face][0], q[face][1], q[face][2]},
                             {q[face][0], q[face][2], q[face][3]}};
        for (int j = 0; j < 2; j++) {
            unsigned char rec[50] = {0};
            for (int v = 0; v < 3; v++)
                for (int k = 0; k < 3; k++) {
                    uint32_t u;
                    memcpy(&u, &c[t[j][v]][k], 4);
                    put_le32(rec + 12 + 4 * (3 * v + k), u);
                }
            fwrite(rec, 1, 50, f);
        }
    }
    fclose(f);
}

static int compare(const fm_stock *s, const fm_design *d, fm_deviation *dev)
{
    fm_error err;
    fm_status st = fm_stock_compare_design(s, d, 100, dev, &err);
    if (st != FM_OK) fprintf(stderr, "compare: %s\n", err.message);
    return st == FM_OK;
}

/* The stock's top 0.4 mm is not in the design: one excess region 0.4 deep
 * (beyond the clamp of the design band, so found by the surface
 * search) of 20 x 20 x 0.4 mm. */
static void check_top_excess(const fm_stock *s, const fm_design *d, const char *what,
                             double region_mm3)
{
    fm_deviation dev;
    CHECK(compare(s, d, &dev));
    printf("%s: excess %zu regions, max %.4f mm, %.3f mm3; gouge max %.4f mm, %.4f mm3\n", what,
           dev.excess_total, dev.max_excess_mm, dev.excess_volume_mm3, dev.max_gouge_mm,
           dev.gouge_volume_mm3);
    CHECK(dev.excess_total == 1);
    CHECK(dev.gouge_total == 0);
    CHECK_NEAR(dev.max_excess_mm, 0.4, H / 2);
    CHECK_NEAR(dev.excess_volume_mm3, 20 * 20 * 0.4, 0.02 * 160);
    CHECK(dev.max_gouge_mm < H / 2);
    CHECK(dev.gouge_volume_mm3 < 0.01 * 160);
    if (dev.excess_count == 1) {
        const fm_deviation_region *r = &dev.excess[0];
        printf("  region %.4f mm, %.3f mm3 (expected %.3f)\n", r->depth_mm, r->volume_mm3,
               region_mm3);
        CHECK_NEAR(r->depth_mm, 0.4, H / 2);
        CHECK_NEAR(r->volume_mm3, region_mm3, 0.02 * 160);
        CHECK_NEAR(r->position[2], 0, H / 2); /* on the stock's surface */
        CHECK(r->position[0] > -H && r->position[0] < 20 + H);
        CHECK(r->lo[2] > -0.4 - 2 * H && r->hi[2] < 4 * H);
    }
    fm_deviation_free(&dev);
}

/* Distances to the design box of test_excess (its top face at z = -0.4,
 * a face at x = 20): t mm above the top face, t below it (inside tiles of a
 * band-3 grid), t beyond the x = 20 face, and off the top x = 20 edge by e
 * mm in x and z (sqrt(2) e; within half a voxel, the surface points'
 * bound near edges). */
static void check_box_distances(const fm_design *d, const char *what, double t, double e)
{
    const double above[3] = {10, 10, -0.4 + t}, below[3] = {10, 10, -0.4 - t};
    const double side[3] = {20 + t, 10, -5}, edge[3] = {20 + e, 10, -0.4 + e};
    printf("%s: above %.4f below %.4f side %.4f edge %.4f\n", what, fm_design_sample(d, above),
           fm_design_sample(d, below), fm_design_sample(d, side), fm_design_sample(d, edge));
    CHECK_NEAR(fm_design_sample(d, above), -t, 1e-3);
    CHECK_NEAR(fm_design_sample(d, below), t, 1e-3);
    CHECK_NEAR(fm_design_sample(d, side), -t, 1e-3);
    CHECK_NEAR(fm_design_sample(d, edge), -sqrt(2) * e, H / 2);
}

static void test_excess(void)
{
    const double lo[3] = {0, 0, -10}, hi[3] = {20, 20, 0};
    const double dlo[3] = {0, 0, -10}, dhi[3] = {20, 20, -0.4};
    fm_stock *s = box_stock(lo, hi, 3, H);
    if (!s) return;
    const shape design = make_box(dlo, dhi);
    fm_design *d = field_design(s, &design, 0.05);
    CHECK(d != NULL);
    if (d) {
        CHECK_NEAR(fm_design_tolerance(d), 0.05, 1e-12);
        /* on the design's top face: 0 inside the stock's top 0.4 mm over it */
        const double p[3] = {10, 10, 0};
        CHECK_NEAR(fm_design_sample(d, p), -0.4, 1e-3);
        check_top_excess(s, d, "field design", 160);
        fm_design_free(d);
    }

    /* the same design as an STL on the box stock's offset grid */
    char path[512];
    snprintf(path, sizeof path, "%s/top.stl", dir);
    write_box_stl(path, dlo, dhi);
    fm_design_options o;
    fm_design_options_default(&o);
    o.tolerance_mm = 0.05;
    fm_error err;
    d = fm_design_from_stl(s, path, &o, &err);
    CHECK(d != NULL);
    if (!d) fprintf(stderr, "STL design: %s\n", err.message);
    if (d) {
        check_top_excess(s, d, "STL design", 160);
        fm_design_free(d);
    }

    /* as a snapshot of the same grid (band 5: taken as it is) and of a
     * 0.05 mm grid at another origin (rebuilt onto the stock's) */
    fm_stock *snap = box_stock(dlo, dhi, 5, H);
    snprintf(path, sizeof path, "%s/same.vdb", dir);
    CHECK(snap && fm_stock_save(snap, path, NULL, &err) == FM_OK);
    fm_stock_free(snap);
    d = fm_design_load_vdb(s, path, &o, &err);
    CHECK(d != NULL);
    if (!d) fprintf(stderr, "vdb design: %s\n", err.message);
    if (d) {
        check_top_excess(s, d, "snapshot design", 160);
        fm_design_free(d);
    }
    /* the same grid with the stock's band 3: at the default tolerance the
     * design's band is the stock's, and the snapshot is taken as it is;
     * samples beyond its band (0.3 mm) come from its surface points */
    snap = box_stock(dlo, dhi, 3, H);
    snprintf(path, sizeof path, "%s/narrow.vdb", dir);
    CHECK(snap && fm_stock_save(snap, path, NULL, &err) == FM_OK);
    fm_stock_free(snap);
    d = fm_design_load_vdb(s, path, &o, &err);
    CHECK(d != NULL);
    if (!d) fprintf(stderr, "narrow vdb design: %s\n", err.message);
    if (d) {
        CHECK(fm_design_band_voxels(s, o.tolerance_mm) == 3);
        /* beyond the band: from the design's surface points */
        check_box_distances(d, "beyond the band", 0.4, 0.3);
        check_top_excess(s, d, "band-3 snapshot design", 160);
        fm_design_free(d);
    }
    /* a tolerance of 0.25 mm needs a band of ceil(2.5) + 2 = 5 voxels, 2
     * more than the snapshot's: widened in place (layer by layer) */
    fm_design_options wide = o;
    wide.tolerance_mm = 0.25;
    d = fm_design_load_vdb(s, path, &wide, &err);
    CHECK(d != NULL);
    if (!d) fprintf(stderr, "widened vdb design: %s\n", err.message);
    if (d) {
        CHECK(fm_design_band_voxels(s, wide.tolerance_mm) == 5);
        /* the added layers (0.3 .. 0.5 mm from the surface) hold distances
         * to the design box; samples whose cell reaches into them but not
         * beyond the band are read from the grid */
        check_box_distances(d, "widened samples", 0.3, 0.2);
        /* the region is the excess deeper than the tolerance: the slab less,
         * along its 80 mm of side faces, the stock whose nearest surface is
         * a side face (depth t below the top, at most t from the side) at a
         * height where that face is within the tolerance of the design's
         * top edge (t >= 0.4 - tol): 80 * (0.4^2 - 0.15^2) / 2 = 5.5 mm3 */
        check_top_excess(s, d, "widened snapshot design", 160 - 80 * (0.16 - 0.15 * 0.15) / 2);
        fm_design_free(d);
    }
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = 0.05;
    const shape sh = make_box(dlo, dhi);
    fm_field f = shape_field(&sh);
    snap = fm_stock_new_from_field(&f, &so, &err);
    snprintf(path, sizeof path, "%s/fine.vdb", dir);
    CHECK(snap && fm_stock_save(snap, path, NULL, &err) == FM_OK);
    fm_stock_free(snap);
    d = fm_design_load_vdb(s, path, &o, &err);
    CHECK(d != NULL);
    if (!d) fprintf(stderr, "rebuilt vdb design: %s\n", err.message);
    if (d) {
        check_top_excess(s, d, "rebuilt snapshot design", 160);
        fm_design_free(d);
    }
    fm_stock_free(s);
}

/* A 10 x 10 mm pocket 0.2 deep and a plunge of r 1.5, 1.5 deep, in a
 * design that is the whole box: two gouges, the plunge first. The plunge
 * is deeper than the design's band. */
static void test_gouges(int threads, fm_deviation *keep)
{
    const double lo[3] = {0, 0, -10}, hi[3] = {20, 20, 0};
    fm_stock *s = box_stock(lo, hi, 3, H);
    if (!s) return;
    const double plo[3] = {5, 5, -0.2}, phi[3] = {15, 15, 1};
    const shape pocket = make_box(plo, phi);
    const shape plunge = make_cylinder(2.5, 17.5, -1.5, 1, 1.5);
    cut(s, &pocket);
    cut(s, &plunge);
    const shape design = make_box(lo, hi);
    fm_field f = shape_field(&design);
    fm_design_options o;
    fm_design_options_default(&o);
    o.tolerance_mm = 0.05;
    o.threads = threads;
    fm_error err;
    fm_design *d = fm_design_from_field(s, &f, &o, &err);
    CHECK(d != NULL);
    if (!d) {
        fm_stock_free(s);
        return;
    }
    fm_deviation dev;
    CHECK(compare(s, d, &dev));
    const double v_pocket = 10 * 10 * 0.2, v_plunge = FM_PI * 1.5 * 1.5 * 1.5;
    printf("gouges (%d threads): %zu regions, max %.4f mm, %.3f mm3 (expected %.3f)\n", threads,
           dev.gouge_total, dev.max_gouge_mm, dev.gouge_volume_mm3, v_pocket + v_plunge);
    CHECK(dev.gouge_total == 2);
    CHECK(dev.excess_total == 0);
    CHECK_NEAR(dev.max_gouge_mm, 1.5, H / 2);
    CHECK_NEAR(dev.gouge_volume_mm3, v_pocket + v_plunge, 0.02 * (v_pocket + v_plunge));
    CHECK(dev.excess_volume_mm3 < 0.1);
    if (dev.gouge_count == 2) {
        const fm_deviation_region *a = &dev.gouges[0], *b = &dev.gouges[1];
        printf("  plunge %.4f mm %.3f mm3 at (%.2f, %.2f, %.2f); pocket %.4f mm %.3f mm3 at "
               "(%.2f, %.2f, %.2f)\n",
               a->depth_mm, a->volume_mm3, a->position[0], a->position[1], a->position[2],
               b->depth_mm, b->volume_mm3, b->position[0], b->position[1], b->position[2]);
        CHECK_NEAR(a->depth_mm, 1.5, H / 2);
        CHECK_NEAR(a->volume_mm3, v_plunge, 0.02 * v_plunge);
        CHECK_NEAR(a->position[2], -1.5, H / 2);
        CHECK(hypot(a->position[0] - 2.5, a->position[1] - 17.5) < 1.5 + H);
        CHECK_NEAR(b->depth_mm, 0.2, H / 2);
        CHECK_NEAR(b->volume_mm3, v_pocket, 0.02 * v_pocket);
        CHECK_NEAR(b->position[2], -0.2, H / 2);
        CHECK(b->position[0] > 5 - H && b->position[0] < 15 + H);
    }
    if (keep)
        *keep = dev;
    else
        fm_deviation_free(&dev);
    fm_design_free(d);
    fm_stock_free(s);
}

/* A 5 mm slab of excess: its inside is tiles in both grids. */
static void test_thick_excess(void)
{
    const double lo[3] = {0, 0, -10}, hi[3] = {20, 20, 0};
    const double dhi[3] = {20, 20, -5};
    fm_stock *s = box_stock(lo, hi, 3, H);
    if (!s) return;
    const shape design = make_box(lo, dhi);
    fm_design *d = field_design(s, &design, 0.05);
    fm_deviation dev;
    if (d && compare(s, d, &dev)) {
        printf("thick excess: %zu regions, max %.4f mm, %.2f mm3\n", dev.excess_total,
               dev.max_excess_mm, dev.excess_volume_mm3);
        CHECK(dev.excess_total == 1);
        CHECK_NEAR(dev.max_excess_mm, 5, H / 2);
        CHECK_NEAR(dev.excess_volume_mm3, 2000, 0.02 * 2000);
        if (dev.excess_count == 1) CHECK_NEAR(dev.excess[0].volume_mm3, 2000, 0.02 * 2000);
        fm_deviation_free(&dev);
    }
    CHECK(d != NULL);
    fm_design_free(d);
    fm_stock_free(s);
}

/* 0.03 mm too deep over the top with a tolerance of 0.05: no region, the
 * figures still say how much. */
static void test_within_tolerance(void)
{
    const double lo[3] = {0, 0, -10}, hi[3] = {20, 20, 0};
    fm_stock *s = box_stock(lo, hi, 3, H);
    if (!s) return;
    const double clo[3] = {-1, -1, -0.03}, chi[3] = {21, 21, 1};
    const shape face = make_box(clo, chi);
    cut(s, &face);
    const shape design = make_box(lo, hi);
    fm_design *d = field_design(s, &design, 0.05);
    fm_deviation dev;
    if (d && compare(s, d, &dev)) {
        printf("within tolerance: %zu regions, max gouge %.4f mm, %.3f mm3\n", dev.gouge_total,
               dev.max_gouge_mm, dev.gouge_volume_mm3);
        CHECK(dev.gouge_total == 0 && dev.excess_total == 0);
        CHECK_NEAR(dev.max_gouge_mm, 0.03, H / 2);
        CHECK_NEAR(dev.gouge_volume_mm3, 20 * 20 * 0.03, 0.02 * 12);
        fm_deviation_free(&dev);
    }
    CHECK(d != NULL);
    fm_design_free(d);

    /* the design equal to the stock: nothing but rounding */
    const double rhi[3] = {20, 20, -0.03};
    const shape rest = make_box(lo, rhi);
    d = field_design(s, &rest, 0.05);
    if (d && compare(s, d, &dev)) {
        printf("equal: max gouge %.2g, excess %.2g mm; %.2g, %.2g mm3\n", dev.max_gouge_mm,
               dev.max_excess_mm, dev.gouge_volume_mm3, dev.excess_volume_mm3);
        CHECK(dev.gouge_total == 0 && dev.excess_total == 0);
        CHECK(dev.max_gouge_mm < 1e-3 && dev.max_excess_mm < 1e-3);
        CHECK(dev.gouge_volume_mm3 < 1e-3 && dev.excess_volume_mm3 < 1e-3);
        fm_deviation_free(&dev);
    }
    CHECK(d != NULL);
    fm_design_free(d);
    fm_stock_free(s);
}

/* A field's design is compared without a grid of its own: each cell the
 * rasterizer would make a leaf of is evaluated where the comparison reads
 * it (the field's batch at its voxel centres, the values the grid would
 * hold). Against that grid (the same field rasterized on the stock's
 * transform, saved and loaded as a snapshot design, which is taken as it
 * is) the comparison must find the same: the same regions, the volumes to
 * rounding (the cells are summed in another order), and the depths within
 * half a voxel (the field's own value at a foot point against the grid's
 * trilinear sample). A ball half sunk into a pocketed stock: gouge where
 * the pocket and the plunge cut into it, excess where the block stands
 * outside it, on the stock's surface and through its tiles. */
static void test_field_against_its_grid(void)
{
    const double lo[3] = {0, 0, -10}, hi[3] = {20, 20, 0};
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = H;
    so.band_voxels = 3;
    so.threads = 2;
    fm_error err;
    const shape block = make_box(lo, hi);
    fm_field bf = shape_field(&block);
    fm_stock *s = fm_stock_new_from_field(&bf, &so, &err);
    CHECK(s != NULL);
    if (!s) return;
    const double plo[3] = {5, 5, -0.2}, phi[3] = {15, 15, 1};
    const shape pocket = make_box(plo, phi);
    const shape plunge = make_cylinder(10, 10, -1.5, 1, 1.5);
    cut(s, &pocket);
    cut(s, &plunge);
    const shape ball = make_sphere(10, 10, -2, 6);
    fm_field f = shape_field(&ball);
    fm_stock *g = fm_stock_new_from_field(&f, &so, &err);
    char path[512];
    snprintf(path, sizeof path, "%s/ball.vdb", dir);
    CHECK(g && fm_stock_save(g, path, NULL, &err) == FM_OK);
    fm_stock_free(g);
    fm_design_options o;
    fm_design_options_default(&o);
    o.tolerance_mm = 0.05;
    fm_design *dg = fm_design_load_vdb(s, path, &o, &err);
    CHECK(dg != NULL);
    fm_design *df = fm_design_from_field(s, &f, &o, &err);
    CHECK(df != NULL);
    /* until something reads its values, the field's design holds no leaves:
     * its topology is a small part of its grid */
    if (df && dg) CHECK(fm_design_memory_bytes(df) < fm_design_memory_bytes(dg) / 4);
    fm_deviation a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    if (dg && df && compare(s, df, &a) && compare(s, dg, &b)) {
        printf("field against its grid: gouges %zu / %zu (%.4f / %.4f mm, %.3f / %.3f mm3), "
               "excess %zu / %zu (%.4f / %.4f mm, %.3f / %.3f mm3)\n",
               a.gouge_total, b.gouge_total, a.max_gouge_mm, b.max_gouge_mm, a.gouge_volume_mm3,
               b.gouge_volume_mm3, a.excess_total, b.excess_total, a.max_excess_mm,
               b.max_excess_mm, a.excess_volume_mm3, b.excess_volume_mm3);
        /* the ball's cap above the pocket floor and the plunge are gouged,
         * the block around the ball is excess: both kinds are there */
        CHECK(b.gouge_total >= 1 && b.excess_total >= 1);
        CHECK(a.gouge_total == b.gouge_total && a.excess_total == b.excess_total);
        CHECK_NEAR(a.gouge_volume_mm3, b.gouge_volume_mm3, 1e-9 * b.gouge_volume_mm3);
        CHECK_NEAR(a.excess_volume_mm3, b.excess_volume_mm3, 1e-9 * b.excess_volume_mm3);
        CHECK_NEAR(a.max_gouge_mm, b.max_gouge_mm, H / 2);
        CHECK_NEAR(a.max_excess_mm, b.max_excess_mm, H / 2);
        for (size_t i = 0; i < a.gouge_count && i < b.gouge_count; i++) {
            CHECK_NEAR(a.gouges[i].depth_mm, b.gouges[i].depth_mm, H / 2);
            CHECK_NEAR(a.gouges[i].volume_mm3, b.gouges[i].volume_mm3,
                       1e-9 * b.gouges[i].volume_mm3);
        }
        for (size_t i = 0; i < a.excess_count && i < b.excess_count; i++) {
            CHECK_NEAR(a.excess[i].depth_mm, b.excess[i].depth_mm, H / 2);
            CHECK_NEAR(a.excess[i].volume_mm3, b.excess[i].volume_mm3,
                       1e-9 * b.excess[i].volume_mm3);
        }
        /* samples beyond the band come from the grid (made for the
         * regions deeper than the band), as the snapshot's do */
        const double above[3] = {10, 10, 4.5}, inside[3] = {10, 10, -2};
        CHECK_NEAR(fm_design_sample(df, above), fm_design_sample(dg, above), 1e-9);
        CHECK_NEAR(fm_design_sample(df, above), -0.5, H / 2);
        CHECK_NEAR(fm_design_sample(df, inside), fm_design_sample(dg, inside), 1e-9);
    }
    fm_deviation_free(&a);
    fm_deviation_free(&b);
    fm_design_free(df);
    fm_design_free(dg);
    fm_stock_free(s);
}

static void test_refusals(void)
{
    const double lo[3] = {0, 0, -10}, hi[3] = {20, 20, 0};
    fm_stock *s = box_stock(lo, hi, 3, H);
    if (!s) return;
    const shape design = make_box(lo, hi);
    fm_field f = shape_field(&design);
    fm_design_options o;
    fm_design_options_default(&o);
    fm_error err;
    o.tolerance_mm = -1;
    CHECK(fm_design_from_field(s, &f, &o, &err) == NULL && err.code == FM_ERR_INPUT);
    o.tolerance_mm = 31 * H;
    CHECK(fm_design_from_field(s, &f, &o, &err) == NULL && err.code == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "coarser voxel");
    o.tolerance_mm = 0;
    o.memory_budget = 1 << 20;
    CHECK(fm_design_from_field(s, &f, &o, &err) == NULL && err.code == FM_ERR_LIMIT);
    o.memory_budget = 0;
    char path[512];
    snprintf(path, sizeof path, "%s/missing.stl", dir);
    CHECK(fm_design_from_stl(s, path, &o, &err) == NULL && err.code == FM_ERR_IO);
    /* default tolerance: half a voxel */
    fm_design *d = fm_design_from_field(s, &f, &o, &err);
    CHECK(d && fm_design_tolerance(d) == H / 2);
    /* a design made for another stock */
    fm_stock *other = box_stock(lo, hi, 3, 0.2);
    fm_deviation dev;
    CHECK(other && d && fm_stock_compare_design(other, d, 10, &dev, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "another stock");
    fm_deviation_free(&dev);
    fm_design_free(d);
    fm_stock_free(other);
    fm_stock_free(s);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/fm-stock-design-XXXXXX");
    if (!mkdtemp(dir)) return 1;
    test_excess();
    fm_deviation one, two;
    memset(&one, 0, sizeof one);
    memset(&two, 0, sizeof two);
    test_gouges(1, &one);
    test_gouges(2, &two);
    /* the same figures whatever the thread count */
    CHECK(one.gouge_count == two.gouge_count);
    CHECK(one.gouge_volume_mm3 == two.gouge_volume_mm3);
    for (size_t i = 0; i < one.gouge_count && i < two.gouge_count; i++) {
        CHECK(one.gouges[i].depth_mm == two.gouges[i].depth_mm);
        CHECK(one.gouges[i].volume_mm3 == two.gouges[i].volume_mm3);
        CHECK(!memcmp(one.gouges[i].position, two.gouges[i].position, sizeof one.gouges[i].position));
    }
    fm_deviation_free(&one);
    fm_deviation_free(&two);
    test_thick_excess();
    test_within_tolerance();
    test_field_against_its_grid();
    test_refusals();
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) perror("rm");
    return test_summary("stock_design");
}
