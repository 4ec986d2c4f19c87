/* test_stock_cuts.c: subtracting swept volumes. Removed volumes of
 * closed-form cuts (buried and half-buried ball slots, a flat plunge, a
 * full ring, a box pocket) against their formulas at 0.1 mm (0.5%) and
 * 0.05 mm (0.1%); a program of many cuts stays a valid narrow-band level set
 * equal to the rasterized closed form of the result; the work of a cut does
 * not grow with the stock; a field within its box (frep.h) skips the
 * voxels a retraced pocket floor already holds and leaves every voxel as
 * evaluating them would; chunks, versions, per-tool and per-block sums,
 * and the memory budget of a cut. */
#include "fields.h"
#include "stock/stock_private.h"
#include "test.h"

#include <stdint.h>
#include <stdlib.h>
#include <time.h>

static fm_stock_options opts(double voxel)
{
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = voxel;
    return o;
}

static int cut(fm_stock *s, const shape *sh, int tool, int64_t block, fm_stock_cut_stats *st)
{
    fm_error err;
    fm_field f = shape_field(sh);
    fm_stock_cut c = {tool, block, 0, 1};
    fm_status rc = fm_stock_subtract(s, &f, &c, st, &err);
    if (rc) fprintf(stderr, "cut failed: %s\n", err.message);
    return rc;
}

/* Five disjoint cuts in a 60 x 40 x 20 block, one tool number each. */
static void test_accuracy(double voxel, double tol)
{
    fm_error err;
    fm_stock_options o = opts(voxel);
    const double lo[3] = {0, 0, 0}, hi[3] = {60, 40, 20};
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    const double v0 = fm_stock_volume(s);
    double t = fm_clock_monotonic_s();

    /* 1: ball r 3 along 20 mm, buried: cylinder + sphere */
    const double a1[3] = {8, 10, 10}, b1[3] = {28, 10, 10};
    shape s1 = make_capsule(a1, b1, 3);
    const double want1 = FM_PI * 9 * 20 + 4.0 / 3.0 * FM_PI * 27;
    /* 2: the same slot with the ball's centre on the top face: half of it,
     * along a direction that is not an axis */
    const double a2[3] = {6, 24, 20}, b2[3] = {6 + 16 * 0.8, 24 + 16 * 0.6, 20};
    shape s2 = make_capsule(a2, b2, 3);
    const double want2 = 0.5 * (FM_PI * 9 * 16 + 4.0 / 3.0 * FM_PI * 27);
    /* 3: flat end mill r 4 plunged 6 mm from the top */
    shape s3 = make_cylinder(40, 10, 14, 30, 4);
    const double want3 = FM_PI * 16 * 6;
    /* 4: flat end mill r 2 once around a circle of radius 6, 4 mm deep */
    shape s4 = make_ring(45, 28, 20, 6, 2, 4);
    const double want4 = 4 * FM_PI * 6 * 2 * 4;
    /* 5: box pocket sticking out of the top and the side */
    const double p5lo[3] = {48, -2, 15}, p5hi[3] = {58.3, 12.1, 25};
    shape s5 = make_box(p5lo, p5hi);
    const double want5 = 10.3 * 12.1 * 5;

    const shape *cuts[5] = {&s1, &s2, &s3, &s4, &s5};
    const double want[5] = {want1, want2, want3, want4, want5};
    const char *names[5] = {"buried ball slot", "half ball slot", "flat plunge", "ring",
                            "box pocket"};
    double sum = 0;
    fm_error_clear(&err);
    for (int i = 0; i < 5; i++) {
        fm_stock_cut_stats st;
        CHECK(cut(s, cuts[i], i + 1, i, &st) == FM_OK);
        const double got = fm_stock_removed_volume_tool(s, i + 1);
        CHECK_NEAR(got, st.removed_mm3, 1e-9 * want[i]);
        CHECK_NEAR(got, want[i], tol * want[i]);
        printf("%.2f mm %-17s removed %10.4f mm3, exact %10.4f, error %+.4f%%\n", voxel,
               names[i], got, want[i], 100 * (got - want[i]) / want[i]);
        sum += want[i];
    }
    t = fm_clock_monotonic_s() - t;
    /* the incremental sums agree with the whole-grid volume */
    const double v1 = fm_stock_volume(s);
    CHECK_NEAR(fm_stock_removed_volume(s), v0 - v1, 1e-9 * v0);
    CHECK_NEAR(v0 - v1, sum, tol * sum);
    fm_error_clear(&err);
    CHECK(fm_stock_validate(s, &err) == FM_OK);
    if (err.code) printf("validate: %s\n", err.message);
    printf("%.2f mm: 5 cuts in %.3f s, grid %.1f MB\n", voxel, t,
           fm_stock_memory_bytes(s) / 1048576.0);
    fm_stock_free(s);
}

/* The result of a program as one closed form: min(box, -max(cuts)). */
static fm_interval composed_interval(void *ctx, void *w, const fm_interval box[3]);
typedef struct composed {
    shape box;
    shape cuts; /* SHAPE_MAX */
} composed;

static void composed_batch(void *ctx, void *w, size_t n, const double *x, const double *y,
                           const double *z, double *out)
{
    (void)w;
    const composed *c = ctx;
    for (size_t i = 0; i < n; i++)
        out[i] = fmin(shape_eval(&c->box, x[i], y[i], z[i]),
                      -shape_eval(&c->cuts, x[i], y[i], z[i]));
}

static void test_program(void)
{
    fm_error err;
    fm_stock_options o = opts(0.2);
    /* box stock puts its voxel centres at lo - 3.5 voxels + k voxels; the
     * field stock at k voxels: this lo gives both the same lattice, so
     * their voxels can be compared one by one */
    const double lo[3] = {0.7, 0.7, 0.7}, hi[3] = {30.7, 30.7, 10.7};
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    enum { N = 150 };
    static shape parts[N];
    /* a random walk of ball and flat cuts over and into the block, some of
     * them plunging through the bottom */
    double p[3] = {15, 15, 10};
    double t0 = fm_clock_monotonic_s();
    for (int i = 0; i < N; i++) {
        double q[3] = {p[0] + test_uniform(-6, 6), p[1] + test_uniform(-6, 6),
                       test_uniform(-1, 12)};
        for (int k = 0; k < 2; k++) q[k] = fmin(fmax(q[k], -2), 32);
        if (i % 5 == 4)
            parts[i] = make_cylinder(q[0], q[1], q[2], q[2] + 15, test_uniform(0.5, 3));
        else
            parts[i] = make_capsule(p, q, test_uniform(0.5, 3));
        CHECK(cut(s, &parts[i], 1 + i % 3, i, NULL) == FM_OK);
        memcpy(p, q, sizeof p);
    }
    t0 = fm_clock_monotonic_s() - t0;
    fm_error_clear(&err);
    CHECK(fm_stock_validate(s, &err) == FM_OK);
    if (err.code) printf("validate: %s\n", err.message);

    composed c;
    c.box = make_box(lo, hi);
    memset(&c.cuts, 0, sizeof c.cuts);
    c.cuts.kind = SHAPE_MAX;
    c.cuts.parts = parts;
    c.cuts.nparts = N;
    fm_field f = shape_field(&c.box);
    f.ctx = &c;
    f.batch = composed_batch;
    f.interval = composed_interval;
    fm_stock *direct = fm_stock_new_from_field(&f, &o, &err);
    CHECK(direct != NULL);
    if (direct) {
        const double vi = fm_stock_volume(s), vd = fm_stock_volume(direct);
        CHECK_NEAR(vi, vd, 1e-9 * vd);
        CHECK_NEAR(fm_stock_removed_volume(s), fm_stock_initial_volume(s) - vi, 1e-9 * vi);
        double worst = 0;
        for (int i = 0; i < 3000; i++) {
            const double x[3] = {test_uniform(-1, 31), test_uniform(-1, 31),
                                 test_uniform(-1, 11)};
            worst = fmax(worst, fabs(fm_stock_sample(s, x) - fm_stock_sample(direct, x)));
        }
        CHECK(worst <= 1e-6);
        printf("program of %d cuts in %.3f s: volume %.4f, direct %.4f, worst sample "
               "difference %.2g\n",
               N, t0, vi, vd, worst);
        /* per-tool sums add up to the total */
        fm_stock_tool_volume tv[8];
        size_t nt = fm_stock_tool_volumes(s, tv, 8);
        CHECK(nt == 3);
        double tsum = 0;
        for (size_t i = 0; i < nt && i < 8; i++) tsum += tv[i].removed_mm3;
        CHECK_NEAR(tsum, fm_stock_removed_volume(s), 1e-9 * vi);
        fm_stock_free(direct);
    }
    fm_stock_free(s);
}

/* min/max of distances is 1-Lipschitz: centre value +- half diagonal */
static fm_interval composed_interval(void *ctx, void *w, const fm_interval box[3])
{
    (void)w;
    const composed *c = ctx;
    double m[3], r2 = 0;
    for (int k = 0; k < 3; k++) {
        m[k] = 0.5 * (box[k].lo + box[k].hi);
        r2 += 0.25 * (box[k].hi - box[k].lo) * (box[k].hi - box[k].lo);
    }
    double v;
    composed_batch((void *)c, NULL, 1, &m[0], &m[1], &m[2], &v);
    fm_interval out = {v - sqrt(r2), v + sqrt(r2)};
    return out;
}

/* The same small cut in a small and a large stock: the same work. */
static void test_work_independent_of_stock(void)
{
    fm_error err;
    fm_stock_options o = opts(0.2);
    const double lo[3] = {0, 0, 0}, hi_small[3] = {16, 16, 16}, hi_big[3] = {80, 80, 60};
    fm_stock *small = fm_stock_new_box(lo, hi_small, &o, &err);
    fm_stock *big = fm_stock_new_box(lo, hi_big, &o, &err);
    CHECK(small && big);
    if (!small || !big) {
        fm_stock_free(small);
        fm_stock_free(big);
        return;
    }
    double time[2] = {0, 0};
    fm_stock_cut_stats st[2];
    fm_stock *both[2] = {small, big};
    for (int j = 0; j < 2; j++) {
        double t = fm_clock_monotonic_s();
        for (int i = 0; i < 40; i++) {
            const double a[3] = {3 + 0.2 * i, 4, 5}, b[3] = {3 + 0.2 * i, 12, 5};
            shape c = make_capsule(a, b, 2);
            CHECK(cut(both[j], &c, 1, -1, &st[j]) == FM_OK);
        }
        time[j] = fm_clock_monotonic_s() - t;
    }
    CHECK(st[0].intervals == st[1].intervals);
    CHECK(st[0].leaves_evaluated == st[1].leaves_evaluated);
    CHECK(st[0].leaves_changed == st[1].leaves_changed);
    CHECK_NEAR(fm_stock_removed_volume(small), fm_stock_removed_volume(big),
               1e-9 * fm_stock_removed_volume(big));
    printf("same 40 cuts: %zu intervals, %zu leaves each; %.4f s in %.0f mm3 stock, %.4f s in "
           "%.0f mm3 (%.0fx the volume)\n",
           st[1].intervals, st[1].leaves_evaluated, time[0], fm_stock_initial_volume(small),
           time[1], fm_stock_initial_volume(big),
           fm_stock_initial_volume(big) / fm_stock_initial_volume(small));
    fm_stock_free(small);
    fm_stock_free(big);
}

/* Twenty flat passes at one floor, each 0.5 mm beside the last, as a
 * zigzag pocket cuts: the same cuts with and without the field's promise
 * to stay within its box. With it, the voxels of the floor that the
 * previous passes already took to this depth are not evaluated again; the
 * grids must agree voxel for voxel, and the removed volume is the union's
 * box, 15.5 x 14 x (10 - 6.03) mm. */
static void test_box_bound_skips_retraced_floor(void)
{
    fm_error err;
    fm_stock_options o = opts(0.2);
    const double lo[3] = {0, 0, 0}, hi[3] = {20, 20, 10};
    fm_stock *plain = fm_stock_new_box(lo, hi, &o, &err), *boxed = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(plain && boxed);
    if (!plain || !boxed) {
        fm_stock_free(plain);
        fm_stock_free(boxed);
        return;
    }
    size_t evaluated[2] = {0, 0};
    for (int i = 0; i < 20; i++) {
        shape pass = {.kind = SHAPE_BOX, .a = {2 + 0.5 * i, 3, 6.03}, .b = {8 + 0.5 * i, 17, 12}};
        for (int j = 0; j < 2; j++) {
            fm_field f = shape_field(&pass);
            f.within_box = j;
            fm_stock_cut c = {1, i, 0, 1};
            fm_stock_cut_stats st;
            CHECK(fm_stock_subtract(j ? boxed : plain, &f, &c, &st, &err) == FM_OK);
            evaluated[j] += st.voxels_evaluated;
        }
    }
    const double expect = 15.5 * 14 * (10 - 6.03);
    CHECK_NEAR(fm_stock_removed_volume(boxed), expect, 0.005 * expect);
    CHECK_NEAR(fm_stock_removed_volume(plain), fm_stock_removed_volume(boxed), 0);
    size_t differ = 0, voxels = 0;
    /* every voxel within five of the passes' union (index = mm / 0.2) */
    for (int i = 5; i <= 93; i++)
        for (int j = 10; j <= 90; j++)
            for (int k = 25; k <= 54; k++) {
                const double ijk[3] = {i, j, k};
                double p[3];
                fm_stock_index_to_world(boxed, ijk, p);
                differ += fm_stock_sample(plain, p) != fm_stock_sample(boxed, p);
                voxels++;
            }
    CHECK(differ == 0);
    /* the first pass has nothing to skip; each later one retraces 5.5 of
     * its 6 mm of floor: well over half of what it evaluates */
    CHECK(evaluated[1] < evaluated[0] / 2);
    printf("retraced floor: %zu voxels evaluated without the box bound, %zu with it; %zu of %zu voxels "
           "differ; removed %.3f mm3 (box %.3f)\n",
           evaluated[0], evaluated[1], differ, voxels, fm_stock_removed_volume(boxed), expect);
    fm_stock_free(plain);
    fm_stock_free(boxed);
}

static void test_chunks_and_tables(void)
{
    fm_error err;
    fm_stock_options o = opts(0.1);
    o.block_table_size = 4;
    const double lo[3] = {0, 0, 0}, hi[3] = {30, 20, 10};
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    /* a cut that misses the stock changes nothing */
    shape miss = make_sphere(50, 50, 50, 3);
    fm_stock_cut_stats st;
    CHECK(cut(s, &miss, 9, 1, &st) == FM_OK);
    CHECK(fm_stock_version(s) == 1);
    CHECK(st.removed_mm3 == 0);

    const double a[3] = {5, 5, 10}, b[3] = {12, 5, 10};
    shape c = make_capsule(a, b, 2);
    CHECK(cut(s, &c, 1, 7, &st) == FM_OK);
    CHECK(fm_stock_version(s) == 2);
    size_t n = fm_stock_changed_chunks(s, 1, NULL, 0);
    CHECK(n >= 1);
    fm_stock_chunk ch[64];
    CHECK(fm_stock_changed_chunks(s, 1, ch, 64) == n);
    int holds_centre = 0;
    for (size_t i = 0; i < n && i < 64; i++) {
        CHECK(ch[i].version == 2);
        /* each changed chunk meets the cut's box widened by band and leaf */
        const double m = 0.3 + 0.8;
        CHECK(ch[i].hi[0] >= 3 - m && ch[i].lo[0] <= 14 + m);
        CHECK(ch[i].hi[1] >= 3 - m && ch[i].lo[1] <= 7 + m);
        CHECK(ch[i].hi[2] >= 8 - m && ch[i].lo[2] <= 12 + m);
        if (ch[i].lo[0] <= 8 && ch[i].hi[0] >= 8 && ch[i].lo[1] <= 5 && ch[i].hi[1] >= 5 &&
            ch[i].lo[2] <= 8.1 && ch[i].hi[2] >= 8.1)
            holds_centre = 1;
    }
    CHECK(holds_centre);
    /* per block: the slot is half a capsule (centre on the top face) */
    fm_stock_block bl;
    CHECK(fm_stock_block_removed(s, 7, &bl) == 1);
    const double half = 0.5 * (FM_PI * 4 * 7 + 4.0 / 3.0 * FM_PI * 8);
    CHECK_NEAR(bl.removed_mm3, half, 0.005 * half);
    /* a full table keeps the largest blocks and the current one */
    for (int i = 0; i < 6; i++) {
        shape sp = make_sphere(3 + 4 * i, 15, 10, 0.5 + 0.3 * i);
        CHECK(cut(s, &sp, 2, 100 + i, NULL) == FM_OK);
    }
    fm_stock_block top[8];
    size_t nb = fm_stock_blocks(s, top, 8);
    CHECK(nb == 4);
    CHECK(top[0].block == 7);
    CHECK(top[1].block == 105 && top[2].block == 104 && top[3].block == 103);
    for (size_t i = 1; i < nb && i < 8; i++) CHECK(top[i - 1].removed_mm3 >= top[i].removed_mm3);
    CHECK(fm_stock_block_removed(s, 100, NULL) == 0);
    fm_stock_free(s);
}

static void test_cut_budget(void)
{
    fm_error err;
    fm_stock_options o = opts(0.1);
    const double lo[3] = {0, 0, 0}, hi[3] = {20, 20, 20};
    fm_stock *s = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(s != NULL);
    if (!s) return;
    const double v0 = fm_stock_volume(s);
    const uint64_t ver = fm_stock_version(s);
    fm_stock_set_memory_budget(s, fm_stock_memory_bytes(s) + (100u << 10));
    shape sp = make_sphere(10, 10, 10, 6); /* buried: 450 mm^2 of new surface */
    fm_field f = shape_field(&sp);
    CHECK(fm_stock_subtract(s, &f, NULL, NULL, &err) == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "memory budget");
    printf("cut refused: %s\n", err.message);
    CHECK(fm_stock_volume(s) == v0);
    CHECK(fm_stock_version(s) == ver);
    CHECK(fm_stock_validate(s, &err) == FM_OK);
    fm_stock_set_memory_budget(s, (size_t)1 << 30);
    CHECK(fm_stock_subtract(s, &f, NULL, NULL, &err) == FM_OK);
    const double want = 4.0 / 3.0 * FM_PI * 216;
    CHECK_NEAR(v0 - fm_stock_volume(s), want, 0.005 * want);
    fm_stock_free(s);
}

int main(int argc, char **argv)
{
    test_accuracy(0.1, 0.005);
    if (!(argc > 1 && strcmp(argv[1], "--quick") == 0)) test_accuracy(0.05, 0.001);
    test_program();
    test_work_independent_of_stock();
    test_box_bound_skips_retraced_floor();
    test_chunks_and_tables();
    test_cut_budget();
    return test_summary("stock_cuts");
}
