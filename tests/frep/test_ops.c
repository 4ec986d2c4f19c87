/* test_ops.c: the operations of lib/frep (R-functions, blends, offsets,
 * mappings, dimension operations) against the papers' formulas written out
 * by hand here, forward maps applied by hand (the mapped object at the
 * moved point equals the original at the point), deduplication, budgets and
 * the error messages for bad arguments. */
#include "frep/ops_internal.h"
#include "test.h"

#include <stdlib.h>

#include "reference_tape.h"

static double ev4(const fm_graph *g, fm_node n, double x, double y, double z, double t)
{
    double p[4] = {x, y, z, t};
    return reference_and_tape(g, n, p);
}

static double ev2(const fm_graph *g, fm_node n, double a, double b)
{
    return ev4(g, n, a, b, 0, 0);
}

static void expect_error(fm_graph *g, fm_node n, fm_status code, const char *needle)
{
    CHECK(n == FM_NONE);
    const fm_error *e = fm_graph_error(g);
    CHECK(e != NULL);
    if (e) {
        CHECK(e->code == code);
        CHECK_STR_CONTAINS(e->message, needle);
    }
}

/* A fresh graph for each expected error: only the first error is kept. */
#define EXPECT_ERROR(build, code, needle)                         \
    do {                                                          \
        fm_graph *eg = fm_graph_new(0);                           \
        fm_node ex = fm_var(eg, FM_X), ey = fm_var(eg, FM_Y);     \
        (void)ex;                                                 \
        (void)ey;                                                 \
        expect_error(eg, (build), code, needle);                  \
        free_graph(eg);                                        \
    } while (0)

static int sign_of(double v) { return (v > 0) - (v < 0); }

/* Test function of all four coordinates, not symmetric in any of them. */
static double shape(double x, double y, double z, double t)
{
    return 1.0 - x * x - 0.5 * y * y - 0.25 * (z - 0.3) * (z - 0.3) + 0.1 * x * y + 0.2 * sin(t) * x;
}

static fm_node shape_node(fm_graph *g)
{
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z), t = fm_var(g, FM_T);
    fm_node v = fm_sub(g, fm_const(g, 1.0), fm_square(g, x));
    v = fm_sub(g, v, fm_mul(g, fm_const(g, 0.5), fm_square(g, y)));
    v = fm_sub(g, v, fm_mul(g, fm_const(g, 0.25), fm_square(g, fm_sub(g, z, fm_const(g, 0.3)))));
    v = fm_add(g, v, fm_mul(g, fm_const(g, 0.1), fm_mul(g, x, y)));
    v = fm_add(g, v, fm_mul(g, fm_mul(g, fm_const(g, 0.2), fm_unary(g, FM_OP_SIN, t)), x));
    return v;
}

static void test_r_alpha(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
    const double alphas[5] = {-0.9, -0.5, 0.0, 0.3, 0.999};
    for (int ai = 0; ai < 5; ai++) {
        double al = alphas[ai];
        fm_node u = fm_r_union(g, x, y, al), in = fm_r_inter(g, x, y, al);
        fm_node sub = fm_r_subtract(g, x, y, al);
        for (int i = 0; i < 200; i++) {
            double a = test_uniform(-3, 3), b = test_uniform(-3, 3);
            double root = sqrt(a * a + b * b - 2 * al * a * b);
            CHECK_NEAR(ev2(g, u, a, b), (a + b + root) / (1 + al), 1e-12);
            CHECK_NEAR(ev2(g, in, a, b), (a + b - root) / (1 + al), 1e-12);
            double rs = sqrt(a * a + b * b + 2 * al * a * b);
            CHECK_NEAR(ev2(g, sub, a, b), (a - b - rs) / (1 + al), 1e-12);
            /* The R-function sign rule: the sign of max / min. */
            CHECK(sign_of(ev2(g, u, a, b)) == sign_of(fmax(a, b)));
            CHECK(sign_of(ev2(g, in, a, b)) == sign_of(fmin(a, b)));
        }
        /* On the diagonal the radicand must not go negative by rounding. */
        for (int i = 0; i < 50; i++) {
            double a = test_uniform(-1e3, 1e3);
            CHECK(!isnan(ev2(g, u, a, a)) && !isnan(ev2(g, in, a, a)));
        }
    }
    /* alpha = 1: plain MAX / MIN nodes (Pasko eq. 3, Ricci). */
    CHECK(fm_node_op(g, fm_r_union(g, x, y, 1.0)) == FM_OP_MAX);
    CHECK(fm_node_op(g, fm_r_inter(g, x, y, 1.0)) == FM_OP_MIN);
    CHECK(fm_r_union(g, x, y, 1.0) == fm_max(g, x, y));
    CHECK_NEAR(ev2(g, fm_r_subtract(g, x, y, 1.0), 2, 1.5), -1.5, 0);
    /* Complement. */
    CHECK_NEAR(ev2(g, fm_complement(g, x), 2.5, 0), -2.5, 0);
    /* Deduplication: the same operation twice is the same node. */
    size_t count = fm_graph_node_count(g);
    CHECK(fm_r_union(g, x, y, 0.3) == fm_r_union(g, x, y, 0.3));
    CHECK(fm_r_union(g, y, x, 0.0) == fm_r_union(g, x, y, 0.0));
    CHECK(fm_graph_node_count(g) == count);
    CHECK(fm_graph_error(g) == NULL);
    free_graph(g);

    EXPECT_ERROR(fm_r_union(eg, ex, ey, 1.5), FM_ERR_INPUT, "alpha = 1.5 is outside (-1, 1]");
    EXPECT_ERROR(fm_r_inter(eg, ex, ey, -1.0), FM_ERR_INPUT, "alpha = -1 is outside");
    EXPECT_ERROR(fm_r_subtract(eg, ex, ey, NAN), FM_ERR_INPUT, "alpha");
    EXPECT_ERROR(fm_r_union(eg, FM_NONE, ey, 0.0), FM_ERR_INPUT, "missing");
}

static void test_r_m_and_p(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
    for (int m = 0; m <= 3; m++) {
        fm_node u = fm_r_union_m(g, x, y, m), in = fm_r_inter_m(g, x, y, m);
        for (int i = 0; i < 100; i++) {
            double a = test_uniform(-2, 2), b = test_uniform(-2, 2), s = a * a + b * b;
            CHECK_NEAR(ev2(g, u, a, b), (a + b + sqrt(s)) * pow(s, m / 2.0), 1e-11);
            CHECK_NEAR(ev2(g, in, a, b), (a + b - sqrt(s)) * pow(s, m / 2.0), 1e-11);
        }
    }
    CHECK(fm_r_union_m(g, x, y, 0) == fm_r_union(g, x, y, 0.0));
    /* R_p with p = 2 is R_0 (Shapiro's footnote 3): the same nodes. */
    CHECK(fm_rp_union(g, x, y, 2.0) == fm_r_union(g, x, y, 0.0));
    CHECK(fm_rp_inter(g, x, y, 2.0) == fm_r_inter(g, x, y, 0.0));
    const double ps[4] = {1.5, 3.0, 4.0, 7.0};
    for (int pi = 0; pi < 4; pi++) {
        double p = ps[pi];
        fm_node u = fm_rp_union(g, x, y, p), in = fm_rp_inter(g, x, y, p);
        for (int i = 0; i < 100; i++) {
            double a = test_uniform(-2, 2), b = test_uniform(-2, 2);
            double nrm = pow(pow(fabs(a), p) + pow(fabs(b), p), 1 / p);
            CHECK_NEAR(ev2(g, u, a, b), a + b + nrm, 1e-12);
            CHECK_NEAR(ev2(g, in, a, b), a + b - nrm, 1e-12);
            CHECK(sign_of(ev2(g, u, a, b)) == sign_of(fmax(a, b)));
            CHECK(sign_of(ev2(g, in, a, b)) == sign_of(fmin(a, b)));
        }
    }
    free_graph(g);
    EXPECT_ERROR(fm_r_union_m(eg, ex, ey, -1), FM_ERR_INPUT, "m = -1 must be >= 0");
    EXPECT_ERROR(fm_rp_union(eg, ex, ey, 1.0), FM_ERR_INPUT, "p = 1 must be a finite number > 1");
    EXPECT_ERROR(fm_rp_inter(eg, ex, ey, INFINITY), FM_ERR_INPUT, "p = inf");
}

static void test_blends(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
    double a0 = 0.7, a1 = 1.3, a2 = -0.6;
    fm_node bu = fm_blend_union(g, x, y, a0, a1, a2), bi = fm_blend_inter(g, x, y, -a0, a1, a2);
    fm_node ru = fm_rho_blend_union(g, x, y, 0.8), ri = fm_rho_blend_inter(g, x, y, 0.8);
    fm_node hu = fm_hyperbolic_blend_union(g, x, y, 0.5), hi = fm_hyperbolic_blend_inter(g, x, y, 0.5);
    for (int i = 0; i < 300; i++) {
        double a = test_uniform(-2, 2), b = test_uniform(-2, 2), s = a * a + b * b;
        /* Pasko eq. 6-8. */
        double d = 1 / (1 + (a / a1) * (a / a1) + (b / a2) * (b / a2));
        CHECK_NEAR(ev2(g, bu, a, b), a + b + sqrt(s) + a0 * d, 1e-12);
        CHECK_NEAR(ev2(g, bi, a, b), a + b - sqrt(s) - a0 * d, 1e-12);
        /* Shapiro eq. 6.2 as printed. */
        double sr = s - 0.64;
        double root = sqrt(s + sr * (sr - fabs(sr)) / (8 * 0.64));
        CHECK_NEAR(ev2(g, ru, a, b), a + b + root, 1e-12);
        CHECK_NEAR(ev2(g, ri, a, b), a + b - root, 1e-12);
        /* Inside the disc the root is (s + rho^2) / (2 rho); outside it is R_0. */
        double closed = s < 0.64 ? (s + 0.64) / 1.6 : sqrt(s);
        CHECK_NEAR(ev2(g, ru, a, b), a + b + closed, 1e-12);
        /* Hasan sec. 5.2. */
        CHECK_NEAR(ev2(g, hu, a, b), fmax(fmax(a, b), 0.25 - a * b), 0);
        CHECK_NEAR(ev2(g, hi, a, b), fmin(fmin(a, b), a * b - 0.25), 0);
    }
    /* The coefficients as expressions (a language's values): a0 a parameter,
     * a1 a constant, a2 an expression of z; the same eq. 6-8. */
    fm_node z = fm_var(g, FM_Z);
    fm_node bue = fm_blend_union_expr(g, x, y, fm_param(g, "a0", a0), fm_const(g, a1),
                                      fm_add(g, fm_const(g, a2), z));
    fm_node bie = fm_blend_inter_expr(g, x, y, fm_param(g, "a0", a0), fm_const(g, a1),
                                      fm_add(g, fm_const(g, a2), z));
    for (int i = 0; i < 300; i++) {
        double a = test_uniform(-2, 2), b = test_uniform(-2, 2), c = test_uniform(-0.3, 0.3);
        double d = 1 / (1 + (a / a1) * (a / a1) + (b / (a2 + c)) * (b / (a2 + c)));
        double s = a * a + b * b;
        CHECK_NEAR(ev4(g, bue, a, b, c, 0), a + b + sqrt(s) + a0 * d, 1e-12);
        CHECK_NEAR(ev4(g, bie, a, b, c, 0), a + b - sqrt(s) + a0 * d, 1e-12);
    }
    /* At the corner the displacement is a0 exactly. */
    CHECK_NEAR(ev2(g, bu, 0, 0), a0, 1e-15);
    CHECK_NEAR(ev2(g, ri, 0, 0), -0.4, 1e-15);
    free_graph(g);
    EXPECT_ERROR(fm_blend_union(eg, ex, ey, 1, 0, 1), FM_ERR_INPUT, "non-zero");
    EXPECT_ERROR(fm_blend_inter(eg, ex, ey, NAN, 1, 1), FM_ERR_INPUT, "a0 = nan");
    EXPECT_ERROR(fm_blend_union_expr(eg, ex, ey, fm_const(eg, 1), fm_const(eg, 1), fm_const(eg, 0)),
                 FM_ERR_INPUT, "a2 = 0 must be finite and non-zero");
    EXPECT_ERROR(fm_blend_inter_expr(eg, ex, ey, FM_NONE, ex, ey), FM_ERR_INPUT, "missing");
    EXPECT_ERROR(fm_rho_blend_union(eg, ex, ey, 0), FM_ERR_INPUT, "rho = 0 must be");
    EXPECT_ERROR(fm_rho_blend_inter(eg, ex, ey, -1), FM_ERR_INPUT, "rho = -1");
    EXPECT_ERROR(fm_hyperbolic_blend_union(eg, ex, ey, INFINITY), FM_ERR_INPUT, "a = inf");
}

static void test_lp(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node v[4] = {fm_var(g, FM_X), fm_var(g, FM_Y), fm_var(g, FM_Z), fm_var(g, FM_T)};
    CHECK(fm_lp_union(g, v, 1, 3.0) == v[0]);
    CHECK(fm_lp_union(g, v, 2, 3.0) == fm_rp_union(g, v[0], v[1], 3.0));
    double p = 3.0;
    fm_node u3 = fm_lp_union(g, v, 3, p), i4 = fm_lp_inter(g, v, 4, p);
    for (int i = 0; i < 300; i++) {
        double a[4];
        for (int j = 0; j < 4; j++) a[j] = test_uniform(-2, 2);
        /* Balanced pairs: f0 | (f1 | f2) and (f0 & f1) & (f2 & f3), each with R_p. */
#define RPU(s, t) ((s) + (t) + pow(pow(fabs(s), p) + pow(fabs(t), p), 1 / p))
#define RPI(s, t) ((s) + (t) - pow(pow(fabs(s), p) + pow(fabs(t), p), 1 / p))
        CHECK_NEAR(ev4(g, u3, a[0], a[1], a[2], a[3]), RPU(a[0], RPU(a[1], a[2])), 1e-12);
        CHECK_NEAR(ev4(g, i4, a[0], a[1], a[2], a[3]), RPI(RPI(a[0], a[1]), RPI(a[2], a[3])), 1e-12);
        CHECK(sign_of(ev4(g, u3, a[0], a[1], a[2], a[3])) == sign_of(fmax(a[0], fmax(a[1], a[2]))));
        CHECK(sign_of(ev4(g, i4, a[0], a[1], a[2], a[3])) ==
              sign_of(fmin(fmin(a[0], a[1]), fmin(a[2], a[3]))));
        /* Positive arguments (the paper's setting): the intersection is
         * below the exact min and the union above the exact max. */
        double b[4];
        for (int j = 0; j < 4; j++) b[j] = fabs(a[j]) + 0.01;
        CHECK(ev4(g, i4, b[0], b[1], b[2], b[3]) < fmin(fmin(b[0], b[1]), fmin(b[2], b[3])));
        CHECK(ev4(g, u3, b[0], b[1], b[2], b[3]) > fmax(b[0], fmax(b[1], b[2])));
    }
    free_graph(g);
    EXPECT_ERROR(fm_lp_union(eg, NULL, 0, 2.0), FM_ERR_INPUT, "at least one");
    fm_node pair[2] = {1, 2};
    EXPECT_ERROR(fm_lp_inter(eg, pair, 2, 0.5), FM_ERR_INPUT, "p = 0.5");
}

static void test_offsets_and_specials(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node f = shape_node(g);
    fm_node iso = fm_offset_iso(g, f, 0.25);
    CHECK_NEAR(ev4(g, iso, 0.3, 0.2, 0.1, 0.5), shape(0.3, 0.2, 0.1, 0.5) + 0.25, 1e-15);

    fm_node no = fm_offset_normal(g, f, 0.5), bm = fm_offset_radius(g, f, -0.25);
    fm_node nz = fm_normalize(g, f);
    CHECK(fm_node_op(g, no) == FM_OP_NORMAL_OFFSET && fm_node_child(g, no, 0) == f);
    CHECK(g->nodes[no].value == 0.5);
    CHECK(fm_node_op(g, bm) == FM_OP_BALL_MAX && fm_node_child(g, bm, 0) == f);
    CHECK(g->nodes[bm].value == -0.25);
    CHECK(fm_node_op(g, nz) == FM_OP_NORMALIZE && fm_node_child(g, nz, 0) == f);
    CHECK(fm_offset_normal(g, f, 0.5) == no); /* deduplicated */
    CHECK(fm_offset_radius(g, f, 0.0) == f);

    fm_node pr = fm_project(g, f, FM_T, 0.0, 2.0);
    CHECK(fm_node_op(g, pr) == FM_OP_PROJECT && fm_node_child(g, pr, 0) == f);
    CHECK(g->nodes[pr].aux == FM_T && g->nodes[pr].value == 0.0 && g->nodes[pr].value2 == 2.0);
    CHECK(!fm_node_depends_on(g, pr, FM_T) && fm_node_depends_on(g, pr, FM_X));
    /* Nothing to project, or a degenerate interval: no PROJECT node. */
    fm_node fx = fm_square(g, fm_var(g, FM_X));
    CHECK(fm_project(g, fx, FM_Y, -1, 1) == fx);
    fm_node fixed = fm_project(g, f, FM_T, 1.5, 1.5);
    CHECK(!fm_node_depends_on(g, fixed, FM_T));
    CHECK_NEAR(ev4(g, fixed, 0.2, 0.4, 0.6, 9.0), shape(0.2, 0.4, 0.6, 1.5), 1e-15);
    CHECK(fm_graph_error(g) == NULL);
    free_graph(g);

    EXPECT_ERROR(fm_project(eg, ex, 4, 0, 1), FM_ERR_INPUT, "axis 4");
    EXPECT_ERROR(fm_project(eg, ex, FM_X, 2, 1), FM_ERR_INPUT, "lo <= hi");
    EXPECT_ERROR(fm_offset_normal(eg, ex, NAN), FM_ERR_INPUT, "distance nan");
    EXPECT_ERROR(fm_offset_iso(eg, ex, INFINITY), FM_ERR_INPUT, "c = inf");
    EXPECT_ERROR(fm_normalize(eg, FM_NONE), FM_ERR_INPUT, "missing");
}

static void test_remap(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z), t = fm_var(g, FM_T);
    fm_node f = shape_node(g);
    /* Simultaneous substitution: x -> y^2, y -> x + t, z kept, t -> 2. */
    fm_node map[FM_AXES] = {fm_square(g, y), fm_add(g, x, t), FM_NONE, fm_const(g, 2.0)};
    fm_node r = fm_remap(g, f, map);
    for (int i = 0; i < 100; i++) {
        double a = test_uniform(-1, 1), b = test_uniform(-1, 1), c = test_uniform(-1, 1),
               d = test_uniform(-1, 1);
        CHECK_NEAR(ev4(g, r, a, b, c, d), shape(b * b, a + d, c, 2.0), 1e-14);
    }
    /* Memoized: remapping the same thing again adds no node, and a shared
     * subexpression is rebuilt once (sin(x) below appears twice). */
    size_t count = fm_graph_node_count(g);
    CHECK(fm_remap(g, f, map) == r);
    CHECK(fm_graph_node_count(g) == count);
    fm_node s = fm_unary(g, FM_OP_SIN, x);
    fm_node twice = fm_add(g, fm_mul(g, s, y), fm_mul(g, s, z));
    fm_node shift[FM_AXES] = {fm_add(g, x, fm_const(g, 1.0)), FM_NONE, FM_NONE, FM_NONE};
    count = fm_graph_node_count(g);
    fm_node moved = fm_remap(g, twice, shift);
    /* New (x + 1 exists already): sin(x + 1), two products, their sum. */
    CHECK(fm_graph_node_count(g) - count == 4);
    CHECK_NEAR(ev4(g, moved, 0.5, 2, 3, 0), sin(1.5) * 5, 1e-15);
    /* Identity maps return the node itself. */
    fm_node ident[FM_AXES] = {x, FM_NONE, z, FM_NONE};
    CHECK(fm_remap(g, f, ident) == f);

    /* A projection binds its axis: the outer map of that axis does not
     * reach inside; other axes are substituted. */
    fm_node inner = fm_add(g, fm_mul(g, x, y), z);
    fm_node pr = fm_project(g, inner, FM_X, 0.0, 1.0);
    fm_node pmap[FM_AXES] = {fm_const(g, 5.0), fm_const(g, 2.0), fm_add(g, z, fm_const(g, 1.0)), FM_NONE};
    fm_node rp = fm_remap(g, pr, pmap);
    CHECK(fm_node_op(g, rp) == FM_OP_PROJECT);
    fm_node child = fm_node_child(g, rp, 0);
    CHECK_NEAR(ev4(g, child, 0.25, 9, 1, 0), 0.25 * 2 + 2, 1e-15);
    CHECK(fm_graph_error(g) == NULL);
    /* A map of y that uses x would be captured by the projection over x. */
    fm_node capture[FM_AXES] = {FM_NONE, fm_add(g, x, fm_const(g, 1.0)), FM_NONE, FM_NONE};
    expect_error(g, fm_remap(g, pr, capture), FM_ERR_INPUT, "capture");
    free_graph(g);

    /* Offsets and normalization commute with rigid motions only. */
    g = fm_graph_new(0);
    f = shape_node(g);
    fm_node bm = fm_offset_radius(g, f, 0.5);
    fm_node tb = fm_translate(g, bm, 1, 2, 3);
    CHECK(fm_node_op(g, tb) == FM_OP_BALL_MAX && g->nodes[tb].value == 0.5);
    CHECK_NEAR(ev4(g, fm_node_child(g, tb, 0), 1.5, 2.5, 3.5, 0.1), shape(0.5, 0.5, 0.5, 0.1), 1e-15);
    fm_node rb = fm_rotate(g, fm_normalize(g, f), FM_Z, 0.3);
    CHECK(fm_node_op(g, rb) == FM_OP_NORMALIZE);
    fm_node tmap[FM_AXES] = {FM_NONE, FM_NONE, FM_NONE, fm_mul(g, fm_var(g, FM_T), fm_const(g, 2))};
    CHECK(fm_node_op(g, fm_remap(g, bm, tmap)) == FM_OP_BALL_MAX); /* time only: fine */
    CHECK(fm_graph_error(g) == NULL);
    expect_error(g, fm_taper(g, bm, FM_Z, 0.1), FM_ERR_INPUT, "rigid");
    free_graph(g);
    EXPECT_ERROR(fm_remap(eg, ex, NULL), FM_ERR_INPUT, "no map");
}

/* f mapped by a forward map F: mapped(F(p)) must equal f(p). */
typedef void (*forward_map)(const double p[3], double out[3]);

static void check_forward(const fm_graph *g, fm_node orig, fm_node mapped, forward_map fwd,
                          double lo, double hi, double tol)
{
    for (int i = 0; i < 300; i++) {
        double p[3] = {test_uniform(lo, hi), test_uniform(lo, hi), test_uniform(lo, hi)}, q[3];
        double t = test_uniform(0, 1);
        fwd(p, q);
        CHECK_NEAR(ev4(g, mapped, q[0], q[1], q[2], t), ev4(g, orig, p[0], p[1], p[2], t), tol);
    }
}

static const double affine_m[16] = {0.8, -0.6, 0.0, 1.0, 0.3, 0.4, 2.0, -2.0,
                                    0.0, 0.5, 1.5, 0.5, 0.0, 0.0, 0.0, 1.0};

static void fwd_affine(const double p[3], double q[3])
{
    for (int i = 0; i < 3; i++)
        q[i] = affine_m[4 * i] * p[0] + affine_m[4 * i + 1] * p[1] + affine_m[4 * i + 2] * p[2] +
               affine_m[4 * i + 3];
}

static void fwd_translate(const double p[3], double q[3])
{
    q[0] = p[0] + 1;
    q[1] = p[1] - 2;
    q[2] = p[2] + 0.5;
}

/* Rotation about y by 0.7, right-handed: z -> x. */
static void fwd_rotate_y(const double p[3], double q[3])
{
    double c = cos(0.7), s = sin(0.7);
    q[0] = c * p[0] + s * p[2];
    q[1] = p[1];
    q[2] = -s * p[0] + c * p[2];
}

/* Twist about z at 0.8 rad per unit of z. */
static void fwd_twist_z(const double p[3], double q[3])
{
    double a = 0.8 * p[2], c = cos(a), s = sin(a);
    q[0] = c * p[0] - s * p[1];
    q[1] = s * p[0] + c * p[1];
    q[2] = p[2];
}

/* Taper along x: y, z scaled by 1 + 0.2 x. */
static void fwd_taper_x(const double p[3], double q[3])
{
    double s = 1 + 0.2 * p[0];
    q[0] = p[0];
    q[1] = s * p[1];
    q[2] = s * p[2];
}

/* Bend of x (along) about z with curvature 0.4: the x axis onto the circle
 * of radius 2.5 through the origin centred at y = 2.5. */
static void fwd_bend(const double p[3], double q[3])
{
    double kk = 0.4, th = kk * p[0], rr = 1 / kk - p[1];
    q[0] = sin(th) * rr;
    q[1] = 1 / kk - cos(th) * rr;
    q[2] = p[2];
}

/* The same with negative curvature: centre at y = -2.5. */
static void fwd_bend_neg(const double p[3], double q[3])
{
    double kk = -0.4, th = kk * p[0], rr = 1 / kk - p[1];
    q[0] = sin(th) * rr;
    q[1] = 1 / kk - cos(th) * rr;
    q[2] = p[2];
}

static void test_mappings(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node f = shape_node(g);
    check_forward(g, f, fm_affine(g, f, affine_m), fwd_affine, -2, 2, 1e-12);
    check_forward(g, f, fm_translate(g, f, 1, -2, 0.5), fwd_translate, -2, 2, 1e-14);
    check_forward(g, f, fm_rotate(g, f, FM_Y, 0.7), fwd_rotate_y, -2, 2, 1e-14);
    check_forward(g, f, fm_twist(g, f, FM_Z, 0.8), fwd_twist_z, -2, 2, 1e-13);
    check_forward(g, f, fm_taper(g, f, FM_X, 0.2), fwd_taper_x, -2, 2, 1e-13);
    /* The bend is inverted on one turn, |k x| < pi, and the near side, y < 1/k. */
    check_forward(g, f, fm_bend(g, f, FM_X, FM_Z, 0.4), fwd_bend, -2, 2, 1e-12);
    check_forward(g, f, fm_bend(g, f, FM_X, FM_Z, -0.4), fwd_bend_neg, -2, 2, 1e-12);
    /* Rotations about each axis, right-handed: a feature at +i goes to +j. */
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z);
    fm_node coord[3] = {x, y, z};
    for (int a = 0; a < 3; a++) {
        int i = (a + 1) % 3, j = (a + 2) % 3;
        fm_node rot = fm_rotate(g, coord[i], a, FM_PI / 2);
        double p[4] = {0, 0, 0, 0};
        p[j] = 1.0; /* the object's value at +i is now found at +j */
        CHECK_NEAR(reference_and_tape(g, rot, p), 1.0, 1e-15);
    }
    /* The time-dependent affine map: rotation about z by t, scaling z by
     * 2, translation (t, 1, 0). */
    fm_node t = fm_var(g, FM_T), c = fm_unary(g, FM_OP_COS, t), s = fm_unary(g, FM_OP_SIN, t);
    fm_node zero = fm_const(g, 0.0), one = fm_const(g, 1.0);
    fm_node m[12] = {c, fm_neg(g, s), zero, t, s, c, zero, one, zero, zero, fm_const(g, 2.0), zero};
    fm_node moving = fm_affine_t(g, f, m);
    for (int i = 0; i < 300; i++) {
        double p[3] = {test_uniform(-2, 2), test_uniform(-2, 2), test_uniform(-2, 2)};
        double tt = test_uniform(-3, 3);
        double q[3] = {cos(tt) * p[0] - sin(tt) * p[1] + tt, sin(tt) * p[0] + cos(tt) * p[1] + 1,
                       2 * p[2]};
        CHECK_NEAR(ev4(g, moving, q[0], q[1], q[2], tt), shape(p[0], p[1], p[2], tt), 1e-12);
    }
    /* A constant matrix through fm_affine_t gives the same values as fm_affine. */
    fm_node mc[12];
    for (int i = 0; i < 12; i++) mc[i] = fm_const(g, affine_m[i]);
    check_forward(g, f, fm_affine_t(g, f, mc), fwd_affine, -2, 2, 1e-12);
    /* The same maps applied to coordinate expressions, then to f: rotation
     * by a constant angle, a twist (angle 0.8 z), the affine map. */
    fm_node p[3] = {x, y, z};
    CHECK(fm_rotate_coords(g, p, FM_Y, fm_const(g, 0.7)));
    fm_node map[FM_AXES] = {p[0], p[1], p[2], FM_NONE};
    check_forward(g, f, fm_remap(g, f, map), fwd_rotate_y, -2, 2, 1e-14);
    fm_node q[3] = {x, y, z};
    CHECK(fm_rotate_coords(g, q, FM_Z, fm_mul(g, fm_const(g, 0.8), z)));
    fm_node tmap[FM_AXES] = {q[0], q[1], q[2], FM_NONE};
    check_forward(g, f, fm_remap(g, f, tmap), fwd_twist_z, -2, 2, 1e-13);
    fm_node r[3] = {x, y, z};
    CHECK(fm_affine_t_coords(g, r, mc));
    fm_node amap[FM_AXES] = {r[0], r[1], r[2], FM_NONE};
    check_forward(g, f, fm_remap(g, f, amap), fwd_affine, -2, 2, 1e-12);
    CHECK(fm_graph_error(g) == NULL);
    free_graph(g);

    double singular[16] = {1, 2, 3, 0, 2, 4, 6, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    EXPECT_ERROR(fm_affine(eg, ex, singular), FM_ERR_INPUT, "singular");
    double projective[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1};
    EXPECT_ERROR(fm_affine(eg, ex, projective), FM_ERR_INPUT, "last row");
    EXPECT_ERROR(fm_rotate(eg, ex, 3, 1.0), FM_ERR_INPUT, "rotation axis 3");
    EXPECT_ERROR(fm_twist(eg, ex, -1, 1.0), FM_ERR_INPUT, "twist axis -1");
    EXPECT_ERROR(fm_bend(eg, ex, FM_X, FM_X, 1.0), FM_ERR_INPUT, "must differ");
    EXPECT_ERROR(fm_translate(eg, ex, NAN, 0, 0), FM_ERR_INPUT, "not finite");
    {
        fm_graph *eg = fm_graph_new(0);
        fm_node ms[12];
        for (int i = 0; i < 12; i++) ms[i] = fm_const(eg, i < 4 ? (double)(i % 4 == 0) : 0.0);
        expect_error(eg, fm_affine_t(eg, fm_var(eg, FM_X), ms), FM_ERR_INPUT, "singular");
        free_graph(eg);
        /* A failed coordinate map leaves the point as it was. */
        eg = fm_graph_new(0);
        for (int i = 0; i < 12; i++) ms[i] = fm_const(eg, i < 4 ? (double)(i % 4 == 0) : 0.0);
        fm_node pa[3] = {fm_var(eg, FM_X), fm_var(eg, FM_Y), fm_var(eg, FM_Z)}, p0 = pa[0];
        CHECK(!fm_affine_t_coords(eg, pa, ms));
        CHECK(pa[0] == p0);
        CHECK_STR_CONTAINS(fm_graph_error(eg)->message, "singular");
        free_graph(eg);
        eg = fm_graph_new(0);
        fm_node pr[3] = {fm_var(eg, FM_X), fm_var(eg, FM_Y), fm_var(eg, FM_Z)};
        CHECK(!fm_rotate_coords(eg, pr, 3, fm_const(eg, 1)));
        CHECK_STR_CONTAINS(fm_graph_error(eg)->message, "rotation axis 3");
        free_graph(eg);
    }
}

static void test_dimension_ops(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
    /* Product of the segment [0, 1] in E^1 and the unit disc in its own
     * (x, y), which becomes (y, z). */
    fm_node seg = fm_min(g, x, fm_sub(g, fm_const(g, 1.0), x));
    fm_node disc = fm_sub(g, fm_const(g, 1.0), fm_add(g, fm_square(g, x), fm_square(g, y)));
    fm_node prod = fm_product(g, seg, 1, disc, 1.0);
    fm_node prod0 = fm_product(g, seg, 1, disc, 0.0);
    for (int i = 0; i < 200; i++) {
        double a = test_uniform(-1, 2), b = test_uniform(-2, 2), c = test_uniform(-2, 2);
        double f1 = fmin(a, 1 - a), f2 = 1 - b * b - c * c;
        CHECK_NEAR(ev4(g, prod, a, b, c, 7), fmin(f1, f2), 1e-15);
        CHECK_NEAR(ev4(g, prod0, a, b, c, 7), f1 + f2 - sqrt(f1 * f1 + f2 * f2), 1e-14);
    }
    /* Time segment (eq. 14) and the 4D product of eq. 14. */
    fm_node ts = fm_time_segment(g, 1.0, 3.0);
    for (double tt = -1; tt <= 5; tt += 0.25) CHECK_NEAR(ev4(g, ts, 9, 9, 9, tt), fmin(tt - 1, 3 - tt), 0);
    /* Metamorphosis (eq. 15) from x to y over t in [2, 4]. */
    fm_node mm = fm_metamorph(g, x, y, 2.0, 4.0);
    for (int i = 0; i < 100; i++) {
        double a = test_uniform(-1, 1), b = test_uniform(-1, 1), tt = test_uniform(0, 6);
        double sv = fmin(fmax((tt - 2) / 2, 0), 1);
        CHECK_NEAR(ev4(g, mm, a, b, 0, tt), a * (1 - sv) + b * sv, 1e-15);
    }
    CHECK(fm_graph_error(g) == NULL);
    expect_error(g, fm_product(g, disc, 1, seg, 1.0), FM_ERR_INPUT, "depends on y");
    free_graph(g);
    EXPECT_ERROR(fm_product(eg, ex, 4, ey, 1.0), FM_ERR_INPUT, "n1 = 4");
    EXPECT_ERROR(fm_product(eg, ex, 3, ey, 1.0), FM_ERR_INPUT, "beyond t");
    EXPECT_ERROR(fm_time_segment(eg, 3.0, 1.0), FM_ERR_INPUT, "t0 <= t1");
    EXPECT_ERROR(fm_metamorph(eg, ex, ey, 1.0, 1.0), FM_ERR_INPUT, "t0 < t1");
}

static void test_voxel_placement(void)
{
    fm_graph *g = fm_graph_new(0);
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    float v[8] = {0, 1, 0, 1, 0, 1, 0, 1}; /* value = x */
    fm_node vox = fm_voxels(g, lo, hi, 2, 2, 2, v);
    fm_node moved = fm_translate(g, vox, 2, 0, 0);
    if (!FM_VOXELS_SAMPLE_CHILDREN) {
        expect_error(g, moved, FM_ERR_INPUT, "voxel grid cannot be moved");
        free_graph(g);
        return;
    }
    CHECK(fm_node_op(g, moved) == FM_OP_VOXELS);
    /* The sample point is now (x - 2, y, z). */
    CHECK_NEAR(ev4(g, fm_node_child(g, moved, 0), 2.5, 0, 0, 0), 0.5, 0);
    CHECK(fm_node_child(g, moved, 1) == fm_var(g, FM_Y));
    /* Through the tape: the moved grid holds x - 2 on [2, 3] x [0, 1]^2. */
    fm_tape *tape = fm_tape_compile(g, moved, NULL);
    fm_evaluator *ev = tape ? fm_evaluator_new(tape, NULL) : NULL;
    CHECK(ev != NULL);
    if (ev) {
        for (int i = 0; i < 50; i++) {
            double p[4] = {test_uniform(2, 3), test_uniform(0, 1), test_uniform(0, 1), 0};
            CHECK_NEAR(fm_eval_point(ev, p), p[0] - 2, 1e-6);
        }
        for (int i = 0; i < 50; i++) {
            fm_interval box[4];
            for (int k = 0; k < 3; k++) {
                double a = test_uniform(1.5, 3.5), b = test_uniform(1.5, 3.5);
                if (k > 0) a -= 2, b -= 2;
                box[k].lo = a < b ? a : b;
                box[k].hi = a < b ? b : a;
            }
            box[3].lo = box[3].hi = 0;
            fm_interval iv = fm_eval_interval(ev, box);
            for (int j = 0; j < 40; j++) {
                double p[4] = {test_uniform(box[0].lo, box[0].hi), test_uniform(box[1].lo, box[1].hi),
                               test_uniform(box[2].lo, box[2].hi), 0};
                double value = fm_eval_point(ev, p);
                CHECK(value >= iv.lo && value <= iv.hi);
            }
        }
    }
    fm_evaluator_free(ev);
    fm_tape_free(tape);
    fm_node tmap[FM_AXES] = {fm_add(g, fm_var(g, FM_X), fm_var(g, FM_T)), FM_NONE, FM_NONE, FM_NONE};
    expect_error(g, fm_remap(g, vox, tmap), FM_ERR_INPUT, "neither t nor parameters");
    free_graph(g);
}

static void test_budget(void)
{
    fm_graph *g = fm_graph_new(6);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
    expect_error(g, fm_r_union(g, x, y, 0.0), FM_ERR_LIMIT, "node budget");
    /* Everything after the first error returns FM_NONE, error unchanged. */
    CHECK(fm_translate(g, x, 1, 0, 0) == FM_NONE);
    CHECK(fm_graph_error(g)->code == FM_ERR_LIMIT);
    free_graph(g);
}

int main(void)
{
    test_r_alpha();
    test_r_m_and_p();
    test_blends();
    test_lp();
    test_offsets_and_specials();
    test_remap();
    test_mappings();
    test_dimension_ops();
    test_voxel_placement();
    test_budget();
    return test_summary("frep_ops");
}
