/* test_hf_papers.c: the two programs of the papers, Hasan's my_model
 * (sec. 2.7) and Pasko et al.'s metamorphosis program (Fig. 6, written in
 * HyperFun syntax), compile and evaluate to the formulas written out by hand
 * here, at chosen points and at random points. */
#include "frep/frep_internal.h"
#include "hf/hf.h"
#include "test.h"

static double eval_model(const fm_graph *g, fm_node root, double x, double y, double z, double t)
{
    double p[4] = {x, y, z, t};
    return fm_graph_eval_reference(g, root, p);
}

/* R_0 union (alpha = 0, HyperFun's default). */
static double r0_union(double a, double b) { return a + b + sqrt(a * a + b * b); }

static double hasan_expected(double x, double y, double z)
{
    double super_ell = 1 - pow(x / 0.8, 4) - pow(y / 10, 4) - pow(z / 0.8, 4);
    /* hfTorusY(x, [0,-9,0], R = 3.5, r0 = 1) */
    double dx = x, dy = y + 9, dz = z;
    double torus = 1 - (dx * dx + dy * dy + dz * dz) - 3.5 * 3.5 + 2 * 3.5 * sqrt(dx * dx + dz * dz);
    static const double x0[9] = {2., 1.4, -1.4, -3, -3, 0, 2.5, 5., 6.5};
    static const double y0[9] = {8, 8, 8, 6.5, 5, 4.5, 3, 2, 1};
    static const double z0[9] = {0, -1.4, -1.4, 0, 3, 4, 2.5, 0, -1};
    static const double d[9] = {2.5, 2.5, 2.5, 2.5, 2.5, 2.5, 2.5, 2.7, 3};
    double sum = 0;
    for (int i = 0; i < 9; i++) {
        double r = sqrt((x - x0[i]) * (x - x0[i]) + (y - y0[i]) * (y - y0[i]) + (z - z0[i]) * (z - z0[i]));
        if (r <= d[i]) {
            double q = r / d[i];
            sum += 1 - 22.0 / 9 * q * q + 17.0 / 9 * pow(q, 4) - 4.0 / 9 * pow(q, 6);
        }
    }
    double soft = sum - 0.2;
    return r0_union(r0_union(super_ell, torus), soft);
}

static void test_hasan(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_hf_model m;
    fm_error err;
    fm_status st = fm_hf_compile_file(g, "hf/corpus/hasan_my_model.hf", NULL, &m, &err);
    char buf[800];
    if (st != FM_OK) fprintf(stderr, "%s\n", fm_error_format(&err, buf, sizeof buf));
    CHECK(st == FM_OK);
    if (st != FM_OK) {
        fm_graph_free(g);
        return;
    }
    CHECK(m.dimension == 3);
    CHECK(!strcmp(m.name, "my_model"));
    CHECK(m.param_count == 1 && !strcmp(m.param_names[0], "a1"));
    /* Chosen points: the origin (inside the superellipsoid), the torus
     * centre line, inside the first soft blob, and far away. */
    const double pts[][3] = {{0, 0, 0}, {3.5, -9, 0}, {2, 8, 0}, {0.5, 6, 0.3},
                             {-3, 5, 3}, {20, 20, 20}, {6.5, 1, -1}, {0, -9, 3.5}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++)
        CHECK_NEAR(eval_model(g, m.root, pts[i][0], pts[i][1], pts[i][2], 0),
                   hasan_expected(pts[i][0], pts[i][1], pts[i][2]),
                   1e-9 * (1 + fabs(hasan_expected(pts[i][0], pts[i][1], pts[i][2]))));
    /* At the origin by hand: superEll = 1, torus = 1 - 81 - 12.25 + 0 = -92.25,
     * soft: only blob 9 at (6.5, 1, -1), d = 3? r = sqrt(42.25+1+1) > 3: none,
     * blob 7 at (2.5, 3, 2.5): r = sqrt(6.25+9+6.25) = 4.64 > 2.5: none; so
     * soft = -0.2. */
    double u1 = 1 - 92.25 + sqrt(1 + 92.25 * 92.25);
    CHECK_NEAR(eval_model(g, m.root, 0, 0, 0, 0), -0.2 + u1 + sqrt(0.04 + u1 * u1), 1e-9);
    for (int i = 0; i < 500; i++) {
        double x = test_uniform(-8, 8), y = test_uniform(-14, 12), z = test_uniform(-6, 6);
        double e = hasan_expected(x, y, z);
        CHECK_NEAR(eval_model(g, m.root, x, y, z, 0), e, 1e-9 * (1 + fabs(e)));
    }
    fm_graph_free(g);
}

/* Pasko Fig. 6 by hand, with r_alpha = 1 (| = max, & = @ = min). */
static double mn(double a, double b) { return a < b ? a : b; }
static double mx(double a, double b) { return a > b ? a : b; }

static double pasko_csg(double x1, double x2, double x3)
{
    double bl1 = mn(mn(mn(x1 + 9, 9 - x1), mn(x2 + 8, 8 - x2)), mn(x3 + 9, 9 - x3));
    double cyl1 = mn(mn(16 - x1 * x1 - x3 * x3, 10.5 - x2), x2 + 10.5);
    double cyl2 = 36 - x1 * x1 - x2 * x2;
    double bl2 = mn(mn(x2 + 5, 5 - x2), mn(x3 + 5, 5 - x3));
    return mn(mn(mx(bl1, cyl1), -cyl2), -bl2);
}

static double pasko_swept(double x1, double x2, double x3)
{
    double s = sin(-1 + x2 / 2.5), c = cos(-1 + x2 / 2.5);
    double tube = 3.5 * 3.5 - pow(x1 + 8 * s, 2) - pow(x3 + 8 * c, 2);
    return mn(tube, mn(x2 + 10, 10 - x2));
}

static double pasko_vox(double x1, double x2, double x3)
{
    double ell = 1 - pow(x1 / 8, 2) - pow(x2 / 6, 2) - pow(x3 / 6, 2);
    double torus = 1.5 * 1.5 - (x1 * x1 + x2 * x2 + x3 * x3) - 36 + 12 * sqrt(x2 * x2 + x3 * x3);
    return mx(ell, torus);
}

static double pasko_blobby(double x1, double x2, double x3)
{
    static const double a[8] = {1.5, 1., 1., 0.8, 0.5, 0.3, 0.4, 0.35};
    static const double px[8] = {0., 6., -4., -5., 5., 6., 5., 8.};
    static const double py[8] = {0., 6., -4., 3., -5., -7., -6., -9.};
    static const double pz[8] = {0., 6., -4., 7., 5., 9., -3., -4.};
    double f = -0.07;
    for (int i = 0; i < 8; i++)
        f += a[i] * exp(-sqrt(pow(x1 - px[i], 2) + pow(x2 - py[i], 2) + pow(x3 - pz[i], 2)));
    return f;
}

static double pasko_expected(double x1, double x2, double x3, double x4)
{
    double csg = pasko_csg(x1, x2, x3), swept = pasko_swept(x1, x2, x3);
    double vox = pasko_vox(x1, x2, x3), blob = pasko_blobby(x1, x2, x3);
    if (0 <= x4 && x4 <= 1) return csg * (1 - x4) + swept * x4;
    if (1 < x4 && x4 <= 2) return swept * (2 - x4) + vox * (x4 - 1);
    if (2 < x4 && x4 <= 3) return vox * (3 - x4) + blob * (x4 - 2);
    if (3 < x4 && x4 <= 4) return blob * (4 - x4) + csg * (x4 - 3);
    return -1;
}

static void test_pasko(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_hf_model m;
    fm_error err;
    fm_status st = fm_hf_compile_file(g, "hf/corpus/pasko_fig6.hf", NULL, &m, &err);
    char buf[800];
    if (st != FM_OK) fprintf(stderr, "%s\n", fm_error_format(&err, buf, sizeof buf));
    CHECK(st == FM_OK);
    if (st != FM_OK) {
        fm_graph_free(g);
        return;
    }
    CHECK(m.dimension == 4);
    CHECK(!strcmp(m.name, "gob_metamorp"));
    /* Key frames: at x4 = 0 the CSG object, at 1 the swept one, at 4 the CSG
     * object again (cycled). Chosen points by hand: at the origin the CSG
     * object is min(max(bl1 = 8, cyl1 = 10.5), -36, -5) = -36. */
    CHECK_NEAR(eval_model(g, m.root, 0, 0, 0, 0), -36, 1e-12);
    CHECK_NEAR(eval_model(g, m.root, 0, 0, 0, 4), -36, 1e-12);
    /* Swept object at x2 = 2.5 (angle 0): the tube centre is (-8 sin 0, ., -8 cos 0)
     * = (0, ., -8), where the tube gives r3^2 = 12.25; the slab gives
     * min(x2 + 10, 10 - x2) = 7.5, the smaller. At x2 = 0 (angle -1) the
     * centre is (c1 sin(-1), 0, c1 cos(-1)); with c1 = -8 that is
     * (8 sin 1, 0, -8 cos 1): min(12.25, 10) = 10; 3 further along x3 the
     * tube gives 12.25 - 9 = 3.25. */
    CHECK_NEAR(eval_model(g, m.root, 0, 2.5, -8, 1), 7.5, 1e-12);
    CHECK_NEAR(eval_model(g, m.root, 8 * sin(1.0), 0, -8 * cos(1.0), 1), 10, 1e-12);
    CHECK_NEAR(eval_model(g, m.root, 8 * sin(1.0), 0, -8 * cos(1.0) + 3, 1), 3.25, 1e-12);
    /* Half way between the blobby object and the CSG object at t = 3.5. */
    CHECK_NEAR(eval_model(g, m.root, 1, 2, 3, 3.5),
               0.5 * pasko_blobby(1, 2, 3) + 0.5 * pasko_csg(1, 2, 3), 1e-12);
    CHECK_NEAR(eval_model(g, m.root, 1, 2, 3, 5), -1, 0);
    for (int i = 0; i < 1000; i++) {
        double x = test_uniform(-11, 11), y = test_uniform(-11, 11), z = test_uniform(-11, 11);
        double t = test_uniform(-0.5, 4.5);
        double e = pasko_expected(x, y, z, t);
        CHECK_NEAR(eval_model(g, m.root, x, y, z, t), e, 1e-9 * (1 + fabs(e)));
    }
    /* The key times exactly (boundaries of the if chain). */
    for (int k = 0; k <= 4; k++) {
        double e = pasko_expected(1, -2, 3, k);
        CHECK_NEAR(eval_model(g, m.root, 1, -2, 3, k), e, 1e-9 * (1 + fabs(e)));
    }
    fm_graph_free(g);
}

int main(void)
{
    test_hasan();
    test_pasko();
    return test_summary("hf_papers");
}
