/* test_stock_shapes.c: creating stock: box, cylinder and F-rep field volumes
 * and areas against their closed forms, the memory estimate and its
 * refusal, options checking, sampling and the initial chunk set. */
#include "fields.h"
#include "test.h"

#include <stdint.h>
#include <stdlib.h>

static fm_stock_options opts(double voxel)
{
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = voxel;
    return o;
}

static void test_box(void)
{
    fm_error err;
    fm_stock_options o = opts(0.1);
    const double lo[3] = {-3.02, 1.5, 0}, hi[3] = {17.01, 13.5, 9.33};
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    const double a = hi[0] - lo[0], b = hi[1] - lo[1], c = hi[2] - lo[2];
    const double vol = a * b * c, area = 2 * (a * b + b * c + c * a);
    CHECK_NEAR(fm_stock_volume(s), vol, 1e-3 * vol);
    CHECK_NEAR(fm_stock_initial_volume(s), vol, 1e-3 * vol);
    CHECK_NEAR(fm_stock_removed_volume(s), 0, 0);
    double ar = 0;
    CHECK(fm_stock_surface_area(s, &ar, &err) == FM_OK);
    CHECK_NEAR(ar, area, 0.01 * area);
    printf("box: volume %.4f (exact %.4f, %.4f%%), area %.3f (exact %.3f, %.3f%%)\n",
           fm_stock_volume(s), vol, 100 * (fm_stock_volume(s) - vol) / vol, ar, area,
           100 * (ar - area) / area);

    /* samples: distance to the nearest face, positive inside */
    const double p_in[3] = {5, 7, 9.33 - 0.12};
    CHECK_NEAR(fm_stock_sample(s, p_in), 0.12, 0.01);
    const double p_out[3] = {5, 7, 9.33 + 0.07};
    CHECK_NEAR(fm_stock_sample(s, p_out), -0.07, 0.01);
    const double p_deep[3] = {5, 7, 4};
    CHECK_NEAR(fm_stock_sample(s, p_deep), 0.3, 1e-6); /* clamped to the band */
    CHECK(fm_stock_voxel_size(s) == 0.1);
    CHECK(fm_stock_band_voxels(s) == 3);

    /* the active voxels cover the box within the band */
    int32_t ilo[3], ihi[3];
    CHECK(fm_stock_active_bounds(s, ilo, ihi, &err) == FM_OK);
    double wlo[3], whi[3], d[3];
    for (int k = 0; k < 3; k++) d[k] = ilo[k];
    fm_stock_index_to_world(s, d, wlo);
    for (int k = 0; k < 3; k++) d[k] = ihi[k];
    fm_stock_index_to_world(s, d, whi);
    for (int k = 0; k < 3; k++) {
        CHECK(wlo[k] > lo[k] - 0.3 - 1e-9 && wlo[k] < lo[k] - 0.2 + 1e-9);
        CHECK(whi[k] < hi[k] + 0.3 + 1e-9 && whi[k] > hi[k] + 0.2 - 1e-9);
    }

    /* every chunk with surface is reported once at version 1 */
    CHECK(fm_stock_version(s) == 1);
    size_t n = fm_stock_changed_chunks(s, 0, NULL, 0);
    CHECK(n > 0);
    fm_stock_chunk *ch = calloc(n, sizeof *ch);
    CHECK(fm_stock_changed_chunks(s, 0, ch, n) == n);
    for (size_t i = 0; i < n; i++) {
        CHECK(ch[i].version == 1);
        CHECK_NEAR(ch[i].hi[0] - ch[i].lo[0], 63 * 0.1, 1e-9);
        /* each chunk meets the box widened by the band */
        for (int k = 0; k < 3; k++)
            CHECK(ch[i].hi[k] >= lo[k] - 0.3 && ch[i].lo[k] <= hi[k] + 0.3);
    }
    /* 20 x 12 x 9.3 mm at 0.1 mm = 200 x 120 x 93 voxels: 4 x 2 x 2 chunks
     * of 64, all on the surface except none (every chunk touches a face) */
    CHECK(n == 4 * 3 * 3 || n <= 5 * 3 * 3);
    CHECK(fm_stock_changed_chunks(s, 1, NULL, 0) == 0);
    free(ch);
    fm_stock_free(s);
}

static void test_cylinder(void)
{
    fm_error err;
    fm_stock_options o = opts(0.1);
    const double r = 7.3, z0 = -2, z1 = 11;
    fm_stock *s = fm_stock_new_cylinder(3, -4, z0, z1, r, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    const double vol = FM_PI * r * r * (z1 - z0), area = 2 * FM_PI * r * r + 2 * FM_PI * r * (z1 - z0);
    double ar = 0;
    CHECK(fm_stock_surface_area(s, &ar, &err) == FM_OK);
    CHECK_NEAR(fm_stock_volume(s), vol, 1e-3 * vol);
    CHECK_NEAR(ar, area, 0.01 * area);
    printf("cylinder: volume %.4f (exact %.4f, %.4f%%), area %.3f (exact %.3f, %.3f%%)\n",
           fm_stock_volume(s), vol, 100 * (fm_stock_volume(s) - vol) / vol, ar, area,
           100 * (ar - area) / area);
    const double p[3] = {3 + r - 0.15, -4, 5};
    CHECK_NEAR(fm_stock_sample(s, p), 0.15, 0.01);
    fm_stock_free(s);
}

static void test_field(void)
{
    fm_error err;
    fm_stock_options o = opts(0.1);
    shape sp = make_sphere(1.3, -2.1, 0.4, 6.0);
    fm_field f = shape_field(&sp);
    fm_stock *s = fm_stock_new_from_field(&f, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    const double vol = 4.0 / 3.0 * FM_PI * 216, area = 4 * FM_PI * 36;
    double ar = 0;
    CHECK(fm_stock_surface_area(s, &ar, &err) == FM_OK);
    CHECK_NEAR(fm_stock_volume(s), vol, 1e-3 * vol);
    CHECK_NEAR(ar, area, 0.01 * area);
    printf("sphere field: volume %.4f (exact %.4f, %.4f%%), area %.3f (exact %.3f)\n",
           fm_stock_volume(s), vol, 100 * (fm_stock_volume(s) - vol) / vol, ar, area);
    fm_stock_free(s);
}

static void test_budget(void)
{
    fm_error err;
    fm_stock_options o = opts(0.1);
    o.memory_budget = 64u << 20;
    const double lo[3] = {0, 0, 0}, hi[3] = {100, 100, 50};
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(s == NULL);
    CHECK(err.code == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "would need about");
    CHECK_STR_CONTAINS(err.message, "budget is 64 MB");
    /* the estimate named is the formula's: at least the voxel values of a
     * 6-voxel band over 40000 mm^2 at 0.1 mm */
    const size_t est = fm_stock_estimate_bytes(40000, 0.1, 3);
    CHECK(est > (size_t)(40000 / 0.01 * 6 * 4));
    char want[64];
    snprintf(want, sizeof want, "about %.0f MB", (double)est / 1048576.0);
    CHECK_STR_CONTAINS(err.message, want);
    printf("refusal: %s\n", err.message);

    /* a field's estimate comes from the boundary leaves the interval pass
     * finds: refused before its leaves exist */
    shape sp = make_sphere(0, 0, 0, 40);
    fm_field f = shape_field(&sp);
    o.memory_budget = 8u << 20;
    s = fm_stock_new_from_field(&f, &o, &err);
    CHECK(s == NULL);
    CHECK(err.code == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "budget is 8 MB");
}

static void test_options(void)
{
    fm_error err;
    fm_stock_options o = opts(-1);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    CHECK(fm_stock_new_box(lo, hi, &o, &err) == NULL && err.code == FM_ERR_INPUT);
    o = opts(0.1);
    o.band_voxels = 1;
    CHECK(fm_stock_new_box(lo, hi, &o, &err) == NULL && err.code == FM_ERR_INPUT);
    o = opts(0.1);
    const double bad_hi[3] = {1, NAN, 1};
    CHECK(fm_stock_new_box(lo, bad_hi, &o, &err) == NULL && err.code == FM_ERR_INPUT);
    CHECK(fm_stock_new_cylinder(0, 0, 1, 0, 2, &o, &err) == NULL && err.code == FM_ERR_INPUT);
    /* NULL options: defaults (0.1 mm) */
    fm_stock *s = fm_stock_new_box(lo, hi, NULL, &err);
    CHECK(s && fm_stock_voxel_size(s) == 0.1);
    fm_stock_free(s);
}

/* One thread or several: the same grid, to the bit. */
static void test_threads(void)
{
    fm_error err;
    double vol[2];
    for (int j = 0; j < 2; j++) {
        fm_stock_options o = opts(0.1);
        o.threads = j ? 2 : 1;
        const double lo[3] = {0, 0, 0}, hi[3] = {12, 10, 8};
        fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
        CHECK(s != NULL);
        if (!s) return;
        shape sp = make_sphere(6, 5, 8, 3);
        fm_field f = shape_field(&sp);
        CHECK(fm_stock_subtract(s, &f, NULL, NULL, &err) == FM_OK);
        vol[j] = fm_stock_volume(s);
        fm_stock_free(s);
    }
    CHECK(vol[0] == vol[1]);
}

int main(void)
{
    test_threads();
    test_box();
    test_cylinder();
    test_field();
    test_budget();
    test_options();
    return test_summary("stock_shapes");
}
