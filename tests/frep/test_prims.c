/* test_prims.c: the primitives of lib/frep against distances computed
 * another way (clamping for the block, 2D geometry for cylinder and cone,
 * the nearest circle point for the torus), against hand-written forms of
 * the papers' field functions, and for first-order normalization
 * (|grad f| = 1 by central differences, value / distance -> 1 near the
 * surface). */
#include "frep/ops_internal.h"
#include "test.h"

#include <stdlib.h>

#include "reference_tape.h"

static double ev(const fm_graph *g, fm_node n, const double p[3])
{
    double q[4] = {p[0], p[1], p[2], 0.0};
    return reference_and_tape(g, n, q);
}

static double grad_norm(const fm_graph *g, fm_node n, const double p[3])
{
    const double h = 1e-6;
    double s = 0.0;
    for (int i = 0; i < 3; i++) {
        double a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
        a[i] += h;
        b[i] -= h;
        double d = (ev(g, n, a) - ev(g, n, b)) / (2 * h);
        s += d * d;
    }
    return sqrt(s);
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }

static void random_point(double p[3], double lo, double hi)
{
    for (int i = 0; i < 3; i++) p[i] = test_uniform(lo, hi);
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

/* Distance from a 2D point to a segment, by projection. */
static double seg_dist(double px, double py, double ax, double ay, double bx, double by)
{
    double ex = bx - ax, ey = by - ay;
    double t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey);
    if (t < 0) t = 0;
    if (t > 1) t = 1;
    return hypot(px - ax - t * ex, py - ay - t * ey);
}

static void test_halfspace(void)
{
    fm_graph *g = fm_graph_new(0);
    double n[3] = {1, 2, 2};
    fm_node f = fm_halfspace(g, n, 3.0);
    for (int i = 0; i < 100; i++) {
        double p[3];
        random_point(p, -5, 5);
        /* |n| = 3: signed distance to the plane x + 2y + 2z = 3. */
        CHECK_NEAR(ev(g, f, p), (3.0 - (p[0] + 2 * p[1] + 2 * p[2])) / 3.0, 1e-12);
        CHECK_NEAR(grad_norm(g, f, p), 1.0, 1e-6);
    }
    double zero[3] = {0, 0, 0};
    expect_error(g, fm_halfspace(g, zero, 1.0), FM_ERR_INPUT, "normal");
    free_graph(g);
}

static void test_sphere(void)
{
    fm_graph *g = fm_graph_new(0);
    double c[3] = {1, -2, 0.5};
    fm_node f = fm_sphere(g, c, 2.5);
    for (int i = 0; i < 200; i++) {
        double p[3], d[3];
        random_point(p, -5, 5);
        for (int j = 0; j < 3; j++) d[j] = p[j] - c[j];
        CHECK_NEAR(ev(g, f, p), 2.5 - norm3(d), 1e-12);
        if (norm3(d) > 0.1) CHECK_NEAR(grad_norm(g, f, p), 1.0, 1e-6);
    }
    /* Same sphere twice: the same node, no new nodes. */
    size_t count = fm_graph_node_count(g);
    CHECK(fm_sphere(g, c, 2.5) == f);
    CHECK(fm_graph_node_count(g) == count);
    expect_error(g, fm_sphere(g, c, -1.0), FM_ERR_INPUT, "radius -1");
    free_graph(g);
    g = fm_graph_new(0);
    expect_error(g, fm_sphere(g, c, 0.0), FM_ERR_INPUT, "radius 0");
    free_graph(g);
}

static void test_block(void)
{
    fm_graph *g = fm_graph_new(0);
    double lo[3] = {-1, 0, 2}, hi[3] = {3, 1, 5};
    fm_node f = fm_block(g, lo, hi);
    for (int i = 0; i < 2000; i++) {
        double p[3], q[3], d[3];
        random_point(p, -3, 7);
        int inside = 1;
        double face = 1e300;
        for (int j = 0; j < 3; j++) {
            q[j] = p[j] < lo[j] ? lo[j] : p[j] > hi[j] ? hi[j] : p[j];
            d[j] = p[j] - q[j];
            if (p[j] < lo[j] || p[j] > hi[j]) inside = 0;
            face = fmin(face, fmin(p[j] - lo[j], hi[j] - p[j]));
        }
        double expect = inside ? face : -norm3(d);
        CHECK_NEAR(ev(g, f, p), expect, 1e-12);
        CHECK_NEAR(grad_norm(g, f, p), 1.0, 1e-5);
    }
    expect_error(g, fm_block(g, hi, lo), FM_ERR_INPUT, "lo < hi");
    free_graph(g);
}

/* (distance along the axis, distance from the axis) of p. */
static void axial(const double base[3], const double u[3], const double p[3], double *a,
                  double *rho)
{
    double d[3] = {p[0] - base[0], p[1] - base[1], p[2] - base[2]};
    *a = dot3(d, u);
    double w[3] = {d[0] - *a * u[0], d[1] - *a * u[1], d[2] - *a * u[2]};
    *rho = norm3(w);
}

static void test_cylinder(void)
{
    fm_graph *g = fm_graph_new(0);
    double base[3] = {0.5, -1, 2}, axis[3] = {1, 2, -2}, u[3] = {1 / 3.0, 2 / 3.0, -2 / 3.0};
    double r = 1.5, h = 4;
    fm_node f = fm_cylinder(g, base, axis, r, h);
    for (int i = 0; i < 2000; i++) {
        double p[3], a, rho;
        random_point(p, -5, 6);
        axial(base, u, p, &a, &rho);
        double expect;
        if (a >= 0 && a <= h && rho <= r) {
            expect = fmin(r - rho, fmin(a, h - a));
        } else {
            double dx = fmax(rho - r, 0), dy = fmax(fmax(-a, a - h), 0);
            expect = -hypot(dx, dy);
        }
        CHECK_NEAR(ev(g, f, p), expect, 1e-12);
        if (rho > 1e-3) CHECK_NEAR(grad_norm(g, f, p), 1.0, 1e-5);
    }
    /* Along a coordinate axis the frame is the other two axes. */
    double zaxis[3] = {0, 0, 3}, origin[3] = {0, 0, 0};
    fm_node fz = fm_cylinder(g, origin, zaxis, 1.0, 2.0);
    double p[3] = {0.3, 0.4, 1.0};
    CHECK_NEAR(ev(g, fz, p), 0.5, 1e-15);
    double zero[3] = {0, 0, 0};
    expect_error(g, fm_cylinder(g, base, zero, 1, 1), FM_ERR_INPUT, "axis");
    free_graph(g);
    g = fm_graph_new(0);
    expect_error(g, fm_cylinder(g, base, axis, -2, 1), FM_ERR_INPUT, "radius -2");
    free_graph(g);
}

static void test_cone(void)
{
    fm_graph *g = fm_graph_new(0);
    double base[3] = {1, 1, -1}, axis[3] = {0, -3, 4}, u[3] = {0, -0.6, 0.8};
    const double cases[3][3] = {{2.0, 0.5, 3.0}, {0.0, 1.5, 2.0}, {1.0, 2.5, 1.5}};
    for (int c = 0; c < 3; c++) {
        double r0 = cases[c][0], r1 = cases[c][1], h = cases[c][2];
        fm_node f = fm_cone(g, base, axis, r0, r1, h);
        for (int i = 0; i < 1500; i++) {
            double p[3], a, rho;
            random_point(p, -4, 6);
            axial(base, u, p, &a, &rho);
            double d = fmin(seg_dist(rho, a, 0, 0, r0, 0),
                            fmin(seg_dist(rho, a, r0, 0, r1, h), seg_dist(rho, a, 0, h, r1, h)));
            int inside = a >= 0 && a <= h && rho <= r0 + (r1 - r0) * a / h;
            CHECK_NEAR(ev(g, f, p), inside ? d : -d, 1e-12);
            if (rho > 1e-3) CHECK_NEAR(grad_norm(g, f, p), 1.0, 1e-5);
        }
    }
    expect_error(g, fm_cone(g, base, axis, 0, 0, 1), FM_ERR_INPUT, "not both 0");
    free_graph(g);
    g = fm_graph_new(0);
    expect_error(g, fm_cone(g, base, axis, 1, 1, -1), FM_ERR_INPUT, "height -1");
    free_graph(g);
}

static void test_torus(void)
{
    fm_graph *g = fm_graph_new(0);
    double c[3] = {0.5, 0, 1}, axis[3] = {1, 1, 0}, u[3] = {0.70710678118654752440, 0.70710678118654752440, 0};
    double R = 3, r = 1;
    fm_node f = fm_torus(g, c, axis, R, r);
    for (int i = 0; i < 2000; i++) {
        double p[3], d[3];
        random_point(p, -5, 5);
        for (int j = 0; j < 3; j++) d[j] = p[j] - c[j];
        double a = dot3(d, u);
        double w[3] = {d[0] - a * u[0], d[1] - a * u[1], d[2] - a * u[2]};
        double wl = norm3(w);
        if (wl < 1e-3) continue;
        /* Nearest point of the core circle, then the tube around it. */
        double near[3], e[3];
        for (int j = 0; j < 3; j++) {
            near[j] = c[j] + R * w[j] / wl;
            e[j] = p[j] - near[j];
        }
        CHECK_NEAR(ev(g, f, p), r - norm3(e), 1e-12);
        if (norm3(e) > 1e-3) CHECK_NEAR(grad_norm(g, f, p), 1.0, 1e-5);
    }
    expect_error(g, fm_torus(g, c, axis, 3, -1), FM_ERR_INPUT, "r = -1");
    free_graph(g);

    /* fm_torus_expr: the torus about a coordinate axis at a point and with a
     * centre and radii given as expressions, against the closed form
     * r - sqrt((sqrt(l1^2 + l2^2) - R)^2 + l0^2), l = p - c; here p is x
     * shifted by 0.25 and R a parameter. */
    g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z);
    fm_node pt[3] = {fm_sub(g, x, fm_const(g, 0.25)), y, z};
    fm_node cc[3] = {fm_const(g, c[0]), fm_const(g, c[1]), fm_const(g, c[2])};
    for (int ax = 0; ax < 3; ax++) {
        fm_node fe = fm_torus_expr(g, pt, cc, ax, fm_param(g, "R", R), fm_const(g, r));
        for (int i = 0; i < 300; i++) {
            double p[3], l[3];
            random_point(p, -5, 5);
            l[0] = p[0] - 0.25 - c[0];
            l[1] = p[1] - c[1];
            l[2] = p[2] - c[2];
            double ring = sqrt(l[(ax + 1) % 3] * l[(ax + 1) % 3] + l[(ax + 2) % 3] * l[(ax + 2) % 3]);
            CHECK_NEAR(ev(g, fe, p), r - sqrt((ring - R) * (ring - R) + l[ax] * l[ax]), 1e-12);
        }
    }
    /* About z through c it is fm_torus with axis (0, 0, 1) at the unshifted point. */
    fm_node id[3] = {x, y, z};
    const double zaxis[3] = {0, 0, 1};
    fm_node fz = fm_torus_expr(g, id, cc, FM_Z, fm_const(g, R), fm_const(g, r));
    fm_node tz = fm_torus(g, c, zaxis, R, r);
    for (int i = 0; i < 300; i++) {
        double p[3];
        random_point(p, -5, 5);
        CHECK_NEAR(ev(g, fz, p), ev(g, tz, p), 1e-14);
    }
    CHECK(fm_graph_error(g) == NULL);
    expect_error(g, fm_torus_expr(g, id, cc, 3, cc[0], cc[1]), FM_ERR_INPUT, "axis 3");
    free_graph(g);
}

static void test_ellipsoid(void)
{
    fm_graph *g = fm_graph_new(0);
    double c[3] = {1, 0, -1}, rad[3] = {3, 1, 2};
    fm_node f = fm_ellipsoid(g, c, rad);
    for (int i = 0; i < 1000; i++) {
        double p[3];
        random_point(p, -4, 5);
        double s = 0;
        for (int j = 0; j < 3; j++) s += pow((p[j] - c[j]) / rad[j], 2);
        double v = ev(g, f, p);
        if (fabs(s - 1) > 1e-9) CHECK((v > 0) == (s < 1));
    }
    /* First order: from a surface point s along the unit normal by delta,
     * the distance is |delta| (delta below the smallest curvature radius). */
    for (int i = 0; i < 300; i++) {
        double th = test_uniform(0, 2 * FM_PI), ph = test_uniform(0.05, FM_PI - 0.05);
        double s[3] = {c[0] + rad[0] * cos(th) * sin(ph), c[1] + rad[1] * sin(th) * sin(ph),
                       c[2] + rad[2] * cos(ph)};
        double nrm[3];
        for (int j = 0; j < 3; j++) nrm[j] = (s[j] - c[j]) / (rad[j] * rad[j]);
        double l = norm3(nrm);
        for (double delta = -1e-4; delta <= 1e-4; delta += 2e-4) {
            double p[3];
            for (int j = 0; j < 3; j++) p[j] = s[j] + delta * nrm[j] / l;
            CHECK_NEAR(ev(g, f, p) / -delta, 1.0, 2e-3);
        }
        CHECK_NEAR(grad_norm(g, f, s), 1.0, 1e-5);
    }
    CHECK_NEAR(ev(g, f, c), 1.0, 0.0); /* the centre: smallest radius */
    double bad[3] = {1, 0, 2};
    expect_error(g, fm_ellipsoid(g, c, bad), FM_ERR_INPUT, "radii");
    free_graph(g);
}

/* The standard inside-outside function of a superellipsoid, by hand. */
static double super_s(const double c[3], const double r[3], double e1, double e2, const double p[3])
{
    double x = fabs((p[0] - c[0]) / r[0]), y = fabs((p[1] - c[1]) / r[1]),
           z = fabs((p[2] - c[2]) / r[2]);
    return pow(pow(x, 2 / e2) + pow(y, 2 / e2), e2 / e1) + pow(z, 2 / e1);
}

static void test_superellipsoid(void)
{
    fm_graph *g = fm_graph_new(0);
    double c[3] = {0, 1, 0}, rad[3] = {2, 1.5, 1};
    const double exps[3][2] = {{0.5, 0.7}, {1.0, 1.0}, {1.5, 0.4}};
    for (int e = 0; e < 3; e++) {
        double e1 = exps[e][0], e2 = exps[e][1];
        fm_node f = fm_superellipsoid(g, c, rad, e1, e2);
        for (int i = 0; i < 500; i++) {
            double p[3];
            random_point(p, -3, 3);
            double s = super_s(c, rad, e1, e2, p);
            if (fabs(s - 1) > 1e-9) CHECK((ev(g, f, p) > 0) == (s < 1));
        }
        /* Surface points away from the axes; normal by differences of S. */
        for (int i = 0; i < 200; i++) {
            double eta = test_uniform(0.2, 1.3) * (i & 1 ? 1 : -1), om = test_uniform(0.2, 1.3);
            double ce = cos(eta), se = sin(eta), co = cos(om), so = sin(om);
            double s[3] = {c[0] + rad[0] * pow(ce, e1) * pow(co, e2),
                           c[1] + rad[1] * pow(ce, e1) * pow(so, e2),
                           c[2] + rad[2] * (se < 0 ? -1 : 1) * pow(fabs(se), e1)};
            CHECK_NEAR(super_s(c, rad, e1, e2, s), 1.0, 1e-9);
            double nrm[3];
            for (int j = 0; j < 3; j++) {
                double a[3] = {s[0], s[1], s[2]}, b[3] = {s[0], s[1], s[2]};
                a[j] += 1e-7;
                b[j] -= 1e-7;
                nrm[j] = super_s(c, rad, e1, e2, a) - super_s(c, rad, e1, e2, b);
            }
            double l = norm3(nrm);
            for (double delta = -1e-5; delta <= 1e-5; delta += 2e-5) {
                double p[3];
                for (int j = 0; j < 3; j++) p[j] = s[j] + delta * nrm[j] / l;
                CHECK_NEAR(ev(g, f, p) / -delta, 1.0, 1e-3);
            }
        }
        /* Finite on the axes and at the centre (the guarded powers). */
        double on_axis[3] = {c[0], c[1], c[2] + 0.5};
        CHECK(isfinite(ev(g, f, on_axis)) && ev(g, f, on_axis) > 0);
        CHECK(isfinite(ev(g, f, c)) && ev(g, f, c) > 0);
    }
    expect_error(g, fm_superellipsoid(g, c, rad, 0.0, 1.0), FM_ERR_INPUT, "exponents");
    free_graph(g);
}

/* Eq. 4.9 by hand: w / sqrt(w^2 + |grad w|^2), grad by central differences. */
static double normalized_by_hand(double (*w)(const double *), const double p[3])
{
    double v = w(p), s = v * v;
    for (int j = 0; j < 3; j++) {
        double a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
        a[j] += 1e-6;
        b[j] -= 1e-6;
        double d = (w(a) - w(b)) / 2e-6;
        s += d * d;
    }
    return v / sqrt(s);
}

static const double blob_c[6] = {0, 0, 0, 1.2, 0.3, 0};
static const double blob_a[2] = {1.5, 2.0}, blob_b[2] = {1.0, 0.8}, blob_t = 0.4;

static double blobby_w(const double *p)
{
    double w = -blob_t;
    for (int i = 0; i < 2; i++) {
        double r2 = 0;
        for (int j = 0; j < 3; j++) r2 += pow(p[j] - blob_c[3 * i + j], 2);
        w += blob_b[i] * exp(-blob_a[i] * r2);
    }
    return w;
}

static const double soft_c[6] = {0, 0, 0, 1.0, 0.5, 0}, soft_r[2] = {1.5, 1.0}, soft_t = 0.3;

static double wyvill(double s)
{
    if (s >= 1) return 0;
    return 1 - 4.0 / 9 * pow(s, 6) + 17.0 / 9 * pow(s, 4) - 22.0 / 9 * s * s;
}

static double soft_w(const double *p)
{
    double w = -soft_t;
    for (int i = 0; i < 2; i++) {
        double r2 = 0;
        for (int j = 0; j < 3; j++) r2 += pow(p[j] - soft_c[3 * i + j], 2);
        w += wyvill(sqrt(r2) / soft_r[i]);
    }
    return w;
}

/* Surface points on rays from `from`, by bisection on the hand-written w,
 * and the first-order check along the normal there. */
static void first_order_on_rays(const fm_graph *g, fm_node f, double (*w)(const double *),
                                const double from[3], double reach)
{
    for (int i = 0; i < 100; i++) {
        double dir[3];
        random_point(dir, -1, 1);
        double l = norm3(dir);
        if (l < 0.1) continue;
        double lo = 0, hi = reach, s[3];
        for (int it = 0; it < 200; it++) {
            double mid = 0.5 * (lo + hi), p[3];
            for (int j = 0; j < 3; j++) p[j] = from[j] + mid * dir[j] / l;
            if (w(p) > 0) lo = mid;
            else hi = mid;
        }
        for (int j = 0; j < 3; j++) s[j] = from[j] + lo * dir[j] / l;
        double nrm[3];
        for (int j = 0; j < 3; j++) {
            double a[3] = {s[0], s[1], s[2]}, b[3] = {s[0], s[1], s[2]};
            a[j] += 1e-7;
            b[j] -= 1e-7;
            nrm[j] = w(b) - w(a); /* outward: w falls outside */
        }
        double nl = norm3(nrm);
        for (double delta = -1e-5; delta <= 1e-5; delta += 2e-5) {
            double p[3];
            for (int j = 0; j < 3; j++) p[j] = s[j] + delta * nrm[j] / nl;
            CHECK_NEAR(ev(g, f, p) / -delta, 1.0, 1e-3);
        }
    }
}

static void test_blobby_soft(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node f = fm_blobby(g, 2, blob_c, blob_a, blob_b, blob_t);
    for (int i = 0; i < 300; i++) {
        double p[3];
        random_point(p, -2, 3);
        CHECK_NEAR(ev(g, f, p), normalized_by_hand(blobby_w, p), 1e-7);
    }
    double origin[3] = {0, 0, 0};
    first_order_on_rays(g, f, blobby_w, origin, 3.0);

    fm_node s = fm_soft(g, 2, soft_c, soft_r, soft_t);
    CHECK_NEAR(wyvill(0.5), 0.5, 1e-12); /* Wyvill's property C(1/2) = 1/2 */
    for (int i = 0; i < 300; i++) {
        double p[3];
        random_point(p, -2, 3);
        CHECK_NEAR(ev(g, s, p), normalized_by_hand(soft_w, p), 1e-7);
    }
    first_order_on_rays(g, s, soft_w, origin, 3.0);
    double far[3] = {10, 0, 0};
    CHECK_NEAR(ev(g, s, far), -1.0, 1e-15); /* w = -T, no gradient */

    double bad_a[2] = {1, -1};
    expect_error(g, fm_blobby(g, 2, blob_c, bad_a, blob_b, 0.5), FM_ERR_INPUT, "a > 0");
    free_graph(g);
    g = fm_graph_new(0);
    expect_error(g, fm_soft(g, 2, soft_c, soft_r, 0.0), FM_ERR_INPUT, "threshold");
    free_graph(g);
}

static double linear_field(double x, double y, double z) { return 2 * x - y + 3 * z + 1; }

static void test_voxels(void)
{
    fm_graph *g = fm_graph_new(0);
    double lo[3] = {-1, 0, 1}, hi[3] = {2, 1, 3};
    size_t n[3] = {7, 3, 5};
    float *v = malloc(n[0] * n[1] * n[2] * sizeof *v);
    for (size_t k = 0; k < n[2]; k++)
        for (size_t j = 0; j < n[1]; j++)
            for (size_t i = 0; i < n[0]; i++) {
                /* Values exactly representable in float: a linear field on
                 * the lattice (trilinear interpolation reproduces it). */
                double x = lo[0] + (hi[0] - lo[0]) * (double)i / (double)(n[0] - 1);
                double y = lo[1] + (hi[1] - lo[1]) * (double)j / (double)(n[1] - 1);
                double z = lo[2] + (hi[2] - lo[2]) * (double)k / (double)(n[2] - 1);
                v[i + n[0] * (j + n[1] * k)] = (float)linear_field(x, y, z);
            }
    fm_node f = fm_voxels(g, lo, hi, n[0], n[1], n[2], v);
    CHECK(f != FM_NONE);
    CHECK(fm_node_op(g, f) == FM_OP_VOXELS);
    CHECK(g->grid_count == 1);
    v[0] = 1e6f; /* the graph holds a copy */
    const fm_voxel_grid *grid = &g->grids[g->nodes[f].aux];
    double probe[4] = {lo[0], lo[1], lo[2], 0.0};
    int reference_ready = !isnan(fm_graph_eval_reference(g, f, probe));
    for (int i = 0; i < 500; i++) {
        double p[3], q[3], d[3];
        random_point(p, -3, 4);
        for (int j = 0; j < 3; j++) {
            q[j] = fmin(fmax(p[j], lo[j]), hi[j]);
            d[j] = p[j] - q[j];
        }
        double expect = linear_field(q[0], q[1], q[2]) - norm3(d);
        CHECK_NEAR(fm_voxel_sample(grid, p[0], p[1], p[2]), expect, 1e-5);
        if (reference_ready) CHECK_NEAR(ev(g, f, p), expect, 1e-5);
    }
    if (!reference_ready) printf("voxels: reference evaluation of VOXELS not available yet, skipped\n");
    expect_error(g, fm_voxels(g, lo, hi, 1, 3, 3, v), FM_ERR_INPUT, "at least 2");
    free_graph(g);
    g = fm_graph_new(0);
    expect_error(g, fm_voxels(g, lo, hi, (size_t)1 << 20, (size_t)1 << 20, 4, v), FM_ERR_LIMIT,
                 "budget");
    free_graph(g);
    g = fm_graph_new(0);
    expect_error(g, fm_voxels(g, lo, hi, SIZE_MAX / 2, 4, 4, v), FM_ERR_LIMIT, "budget");
    free_graph(g);
    g = fm_graph_new(0);
    v[3] = NAN;
    expect_error(g, fm_voxels(g, lo, hi, n[0], n[1], n[2], v), FM_ERR_INPUT, "sample 3");
    free_graph(g);
    free(v);
}

static void test_budget(void)
{
    fm_graph *g = fm_graph_new(8);
    double c[3] = {0, 0, 0};
    expect_error(g, fm_sphere(g, c, 1.0), FM_ERR_LIMIT, "node budget");
    free_graph(g);
}

int main(void)
{
    test_halfspace();
    test_sphere();
    test_block();
    test_cylinder();
    test_cone();
    test_torus();
    test_ellipsoid();
    test_superellipsoid();
    test_blobby_soft();
    test_voxels();
    test_budget();
    return test_summary("frep_prims");
}
