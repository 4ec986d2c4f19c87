/* test_hf_library.c: every library function of lib/hf against its
 * HyperFun formula, written out independently here, at random points. The
 * programs use the fixed arrays below (centre c, axis u, key points x0, y0,
 * z0 and coefficient arrays p, q). */
#include "frep/frep_internal.h"
#include "hf/hf.h"
#include "test.h"

static const double C[3] = {0.5, -0.25, 1};
static const double U[3] = {0.3, -0.4, 1.2};
static const double X0[3] = {0, 1, -1}, Y0[3] = {0, 1, 0.5}, Z0[3] = {0, -1, 0.5};
static const double P[3] = {1, 2, 0.5}, Q[3] = {2, 3, 1.5};

static const char *prologue =
    "array c[3], u[3], x0[3], y0[3], z0[3], p[3], q[3], xt[3];\n"
    "c = [0.5, -0.25, 1]; u = [0.3, -0.4, 1.2];\n"
    "x0 = [0, 1, -1]; y0 = [0, 1, 0.5]; z0 = [0, -1, 0.5]; p = [1, 2, 0.5]; q = [2, 3, 1.5];\n"
    "xt[1] = x[1]; xt[2] = x[2]; xt[3] = x[3];\n";

typedef double (*formula)(const double x[3]);

static double sqr(double v) { return v * v; }

/* Compile `t = <expr>;` (after optional statements) and compare with f at
 * random points in [-3, 3]^3. */
static void check(const char *stmts, const char *expr, formula f, double tol)
{
    char src[4096];
    snprintf(src, sizeof src, "t(x[3], a[1])\n{\n%s%s\nt = %s;\n}\n", prologue, stmts, expr);
    fm_graph *g = fm_graph_new(0);
    fm_hf_model m;
    fm_error err;
    fm_status st = fm_hf_compile_string(g, src, strlen(src), "lib", NULL, NULL, &m, &err);
    if (st != FM_OK) {
        char buf[800];
        fprintf(stderr, "%s: %s\n", expr, fm_error_format(&err, buf, sizeof buf));
    }
    CHECK(st == FM_OK);
    int bad = 0;
    for (int i = 0; st == FM_OK && i < 300 && bad < 3; i++) {
        double p[4] = {test_uniform(-3, 3), test_uniform(-3, 3), test_uniform(-3, 3), 0};
        double want = f(p), got = fm_graph_eval_reference(g, m.root, p);
        if (isnan(want) && isnan(got)) continue;
        if (!(fabs(got - want) <= tol * (1 + fabs(want)))) {
            bad++;
            fprintf(stderr, "%s at (%g, %g, %g): got %.15g, want %.15g\n", expr, p[0], p[1], p[2],
                    got, want);
        }
    }
    CHECK(bad == 0);
    fm_graph_free(g);
}

/* ---- primitives (d = x - c) ---- */
#define D0 (x[0] - C[0])
#define D1 (x[1] - C[1])
#define D2 (x[2] - C[2])
static double f_sphere(const double x[3]) { return 4 - sqr(D0) - sqr(D1) - sqr(D2); }
static double f_ellipsoid(const double x[3]) { return 1 - sqr(D0 / 1) - sqr(D1 / 2) - sqr(D2 / 3); }
static double f_cyl_x(const double x[3]) { return 2.25 - sqr(D1) - sqr(D2); }
static double f_cyl_y(const double x[3]) { return 2.25 - sqr(D0) - sqr(D2); }
static double f_cyl_z(const double x[3]) { return 2.25 - sqr(D0) - sqr(D1); }
static double f_ellcyl_x(const double x[3]) { return 1 - sqr(D1 / 1.5) - sqr(D2 / 0.5); }
static double f_ellcyl_y(const double x[3]) { return 1 - sqr(D0 / 1.5) - sqr(D2 / 0.5); }
static double f_ellcyl_z(const double x[3]) { return 1 - sqr(D0 / 1.5) - sqr(D1 / 0.5); }
static double f_cone_x(const double x[3]) { return sqr(D0) - sqr(D1 / 0.5) - sqr(D2 / 0.5); }
static double f_cone_y(const double x[3]) { return sqr(D1) - sqr(D0 / 0.5) - sqr(D2 / 0.5); }
static double f_cone_z(const double x[3]) { return sqr(D2) - sqr(D0 / 0.5) - sqr(D1 / 0.5); }
static double f_ellcone_x(const double x[3]) { return sqr(D0) - sqr(D1 / 0.5) - sqr(D2 / 2); }
static double f_ellcone_y(const double x[3]) { return sqr(D1) - sqr(D0 / 0.5) - sqr(D2 / 2); }
static double f_ellcone_z(const double x[3]) { return sqr(D2) - sqr(D0 / 0.5) - sqr(D1 / 2); }
static double torus(const double x[3], double ring2)
{
    return 0.25 - (sqr(D0) + sqr(D1) + sqr(D2)) - 4 + 4 * sqrt(ring2);
}
static double f_torus_x(const double x[3]) { return torus(x, sqr(D1) + sqr(D2)); }
static double f_torus_y(const double x[3]) { return torus(x, sqr(D0) + sqr(D2)); }
static double f_torus_z(const double x[3]) { return torus(x, sqr(D0) + sqr(D1)); }
static double block(const double x[3], double alpha)
{
    double s[3];
    const double len[3] = {1, 2, 3};
    for (int i = 0; i < 3; i++) s[i] = (x[i] - C[i]) * (C[i] + len[i] - x[i]);
    if (alpha == 1) return fmin(fmin(s[0], s[1]), s[2]);
    double f = s[0] + s[1] - sqrt(s[0] * s[0] + s[1] * s[1] - 2 * alpha * s[0] * s[1]);
    return f + s[2] - sqrt(f * f + s[2] * s[2] - 2 * alpha * f * s[2]);
}
static double f_block0(const double x[3]) { return block(x, 0); }
static double f_block_half(const double x[3]) { return block(x, 0.5); }
static double f_block1(const double x[3]) { return block(x, 1); }
static double f_block_03(const double x[3]) { return block(x, 0.3); }
static double f_superell(const double x[3])
{
    double xy = pow(fabs(D0 / 1), 2 / 0.7) + pow(fabs(D1 / 2), 2 / 0.7);
    return 1 - pow(xy, 0.7 / 0.5) - pow(fabs(D2 / 3), 2 / 0.5);
}
static double r2k(const double x[3], int i)
{
    return sqr(x[0] - X0[i]) + sqr(x[1] - Y0[i]) + sqr(x[2] - Z0[i]);
}
static double f_blobby(const double x[3])
{
    double s = 0;
    for (int i = 0; i < 3; i++) s += Q[i] * exp(-P[i] * r2k(x, i));
    return s - 0.5;
}
static double f_metaball(const double x[3]) /* b = q, d = p */
{
    double s = 0;
    for (int i = 0; i < 3; i++) {
        double r = sqrt(r2k(x, i)), dd = P[i], b = Q[i];
        if (r <= dd / 3) s += b * (1 - 3 * r * r / (dd * dd));
        else if (r < dd) s += 1.5 * b * sqr(1 - r / dd);
    }
    return s - 0.5;
}
static double f_soft(const double x[3]) /* d = q */
{
    double s = 0;
    for (int i = 0; i < 3; i++) {
        double r = sqrt(r2k(x, i)), dd = Q[i];
        if (r <= dd) {
            double k = r / dd;
            s += 1 - 22.0 / 9 * pow(k, 2) + 17.0 / 9 * pow(k, 4) - 4.0 / 9 * pow(k, 6);
        }
    }
    return s - 0.2;
}
static double f_blend_uni(const double x[3])
{
    double f1 = x[0], f2 = x[1];
    return f1 + f2 + sqrt(f1 * f1 + f2 * f2) + 0.5 / (1 + sqr(f1 / 1.5) + sqr(f2 / 0.7));
}
static double f_blend_int(const double x[3])
{
    double f1 = x[0], f2 = x[1];
    return f1 + f2 - sqrt(f1 * f1 + f2 * f2) + 0.5 / (1 + sqr(f1 / 1.5) + sqr(f2 / 0.7));
}

/* ---- transforms: the test reads back w . xt with weights 1, sqrt 2, pi ---- */
static double weigh(const double y[3]) { return y[0] + sqrt(2.0) * y[1] + FM_PI * y[2]; }
static const char *weighed = "xt[1] + sqrt(2)*xt[2] + 3.14159265358979323846*xt[3]";
static double f_shift(const double x[3])
{
    double y[3] = {x[0] - 1, x[1] - 2, x[2] - 3};
    return weigh(y);
}
static double f_scale(const double x[3])
{
    double y[3] = {x[0] / 1, x[1] / 2, x[2] / 4};
    return weigh(y);
}
static void rot(double *p, double *q, double th)
{
    double np = *p * cos(th) + *q * sin(th), nq = -*p * sin(th) + *q * cos(th);
    *p = np;
    *q = nq;
}
static double f_rot_x(const double x[3]) { double y[3] = {x[0], x[1], x[2]}; rot(&y[1], &y[2], 0.5); return weigh(y); }
static double f_rot_y(const double x[3]) { double y[3] = {x[0], x[1], x[2]}; rot(&y[2], &y[0], 0.5); return weigh(y); }
static double f_rot_z(const double x[3]) { double y[3] = {x[0], x[1], x[2]}; rot(&y[0], &y[1], 0.5); return weigh(y); }
static double twist_angle(double s) { double t = (s + 1) / 3; return (1 - t) * 0.3 + t * 1.2; }
static double f_twist_x(const double x[3]) { double y[3] = {x[0], x[1], x[2]}; rot(&y[1], &y[2], twist_angle(x[0])); return weigh(y); }
static double f_twist_y(const double x[3]) { double y[3] = {x[0], x[1], x[2]}; rot(&y[2], &y[0], twist_angle(x[1])); return weigh(y); }
static double f_twist_z(const double x[3]) { double y[3] = {x[0], x[1], x[2]}; rot(&y[0], &y[1], twist_angle(x[2])); return weigh(y); }
static double taper_scale(double s)
{
    if (s < -1) return 0.5;
    if (s > 1) return 2;
    double t = (s + 1) / 2;
    return (1 - t) * 0.5 + t * 2;
}
static double f_taper_x(const double x[3]) { double k = taper_scale(x[0]); double y[3] = {x[0], x[1] / k, x[2] / k}; return weigh(y); }
static double f_taper_y(const double x[3]) { double k = taper_scale(x[1]); double y[3] = {x[0] / k, x[1], x[2] / k}; return weigh(y); }
static double f_taper_z(const double x[3]) { double k = taper_scale(x[2]); double y[3] = {x[0] / k, x[1] / k, x[2]}; return weigh(y); }
static double f_stretch(const double x[3])
{
    double y[3] = {C[0] + (x[0] - C[0]) / 1, C[1] + (x[1] - C[1]) / 2, C[2] + (x[2] - C[2]) / 4};
    return weigh(y);
}
/* a transform applied to x before a primitive: the sphere moved by (1, 2, 3) */
static double f_shifted_sphere(const double x[3])
{
    return 4 - sqr(x[0] - 1 - C[0]) - sqr(x[1] - 2 - C[1]) - sqr(x[2] - 3 - C[2]);
}

/* ---- distance variants ---- */
static double f_dcylinder(const double x[3])
{
    double w[3] = {C[0] - x[0], C[1] - x[1], C[2] - x[2]};
    double cr[3] = {U[1] * w[2] - U[2] * w[1], U[2] * w[0] - U[0] * w[2], U[0] * w[1] - U[1] * w[0]};
    double along = sqrt(sqr(cr[0]) + sqr(cr[1]) + sqr(cr[2])) / sqrt(sqr(U[0]) + sqr(U[1]) + sqr(U[2]));
    return 1 - along;
}
static double dcone(double axial, double radial)
{
    double t = atan(0.5);
    return -(radial * cos(t) - fabs(axial) * sin(t));
}
static double f_dcone_x(const double x[3]) { return dcone(D0, sqrt(sqr(D1) + sqr(D2))); }
static double f_dcone_y(const double x[3]) { return dcone(D1, sqrt(sqr(D0) + sqr(D2))); }
static double f_dcone_z(const double x[3]) { return dcone(D2, sqrt(sqr(D0) + sqr(D1))); }
static double dtorus(double axial, double radial) { return 0.5 - sqrt(sqr(radial - 2) + sqr(axial)); }
static double f_dtorus_x(const double x[3]) { return dtorus(D0, sqrt(sqr(D1) + sqr(D2))); }
static double f_dtorus_y(const double x[3]) { return dtorus(D1, sqrt(sqr(D0) + sqr(D2))); }
static double f_dtorus_z(const double x[3]) { return dtorus(D2, sqrt(sqr(D0) + sqr(D1))); }


/* ---- SARDF set operations (HyperFun sardf.c, uni_sardef_1 / int_sardef_1),
 * written out here case by case as HyperFun does, with its quadratics in
 * their textbook form and its quartics solved by bisection on the quartic
 * polynomial itself (the library uses Newton on the circle distance). ---- */

/* The root of HyperFun's quartic m^4 - 4s m^3 - 4R m^2 + 4s k m - (x^2 + y^2)
 * (k = -(x + y) for the union, x + y for the intersection) in
 * [lo, s], where it is positive at lo and negative at s. */
static double quartic_root(double x, double y, double r, double k, double lo)
{
    double s = sqrt(r), hi = s;
    for (int i = 0; i < 200; i++) {
        double m = 0.5 * (lo + hi);
        double h = m * m * m * m - 4 * s * m * m * m - 4 * r * m * m + 4 * s * k * m - (x * x + y * y);
        if (h > 0) lo = m;
        else hi = m;
    }
    return 0.5 * (lo + hi);
}

static double ref_union(double x, double y, double r, double alpha)
{
    if (x > 0 && y > 0) {
        double t = tan(alpha), g = 1 / t, g2 = t, gt = x / y;
        if (gt < g && gt > g2) {
            double a = t * t + 2 * t - 1, b = -2 * t * (x + y), c = x * x + y * y;
            return (-b - sqrt(b * b - 4 * a * c)) / (2 * a);
        }
        return gt >= g ? x : y;
    }
    if (x < 0 && y < 0) {
        double lim2 = sqr(x + 2 * r) + sqr(y + 2 * r);
        if (x >= -r || y >= -r || (x >= -2 * r && y >= -2 * r && lim2 >= r * r)) {
            double xx = -x * x / (4 * r), yy = -y * y / (4 * r);
            if (x <= yy && y <= xx) {
                double m = quartic_root(x, y, r, -(x + y), fmax(-x, -y) / (2 * sqrt(r)));
                return -m * m;
            }
            return y > xx ? y : x;
        }
        if (y <= x + r && y >= x - r) {
            double a = 2, b = -2 * x - 4 * r - 2 * y, c = x * x + y * y + r * r + 2 * x * r + 2 * y * r;
            return (-b - sqrt(b * b - 4 * a * c)) / (2 * a);
        }
        return y < x - r ? x : y;
    }
    return x > y ? x : y;
}

static double ref_inter(double x, double y, double r, double alpha)
{
    if (x > 0 && y > 0) {
        double lim = sqr(x - 2 * r) + sqr(y - 2 * r);
        if (x <= r || y <= r || (x <= 2 * r && y <= 2 * r && lim >= r * r)) {
            double xx = x * x / (4 * r), yy = y * y / (4 * r);
            if (xx <= y && yy <= x) {
                double m = quartic_root(x, y, r, x + y, fmax(x, y) / (2 * sqrt(r)));
                return m * m;
            }
            return xx > y ? y : x;
        }
        if (y <= x + r && y >= x - r) {
            double a = 2, b = -2 * x + 4 * r - 2 * y, c = x * x + y * y + r * r - 2 * x * r - 2 * y * r;
            return (-b + sqrt(b * b - 4 * a * c)) / (2 * a);
        }
        return y < x - r ? y : x;
    }
    if (x < 0 && y < 0) {
        double t = tan(alpha), g = 1 / t, g2 = t, gt = x / y;
        if (gt < g && gt > g2) {
            double a = 1 - t * t - 2 * t, b = 2 * t * (x + y), c = -x * x - y * y;
            return (-b - sqrt(b * b - 4 * a * c)) / (2 * a);
        }
        return gt >= g ? x : y;
    }
    return x < y ? x : y;
}

static double f_duni(const double x[3]) { return ref_union(x[0], x[1], 1, 0.3); }
static double f_duni_a0(const double x[3]) { return ref_union(x[0], x[1], 0.5, 0); }
static double f_duni_a45(const double x[3]) { return ref_union(x[0], x[1], 2, 0.45); }
static double f_dint(const double x[3]) { return ref_inter(x[0] - x[2], x[1], 0.7, 0.2); }
static double f_dsub(const double x[3]) { return ref_inter(x[0], -(0.5 * x[1] + x[2]), 1.3, 0.1); }
/* a torus minus a cylinder, the way a model uses them */
static double f_dsub_solids(const double x[3])
{
    return ref_inter(dtorus(D2, sqrt(sqr(D0) + sqr(D1))), -f_dcylinder(x), 0.25, 0.15);
}

/* Values worked by hand at chosen points. */
static double eval_at(const char *expr, double x, double y)
{
    char src[512];
    snprintf(src, sizeof src, "t(x[3], a[1])\n{\nt = %s;\n}\n", expr);
    fm_graph *g = fm_graph_new(0);
    fm_hf_model m;
    fm_error err;
    double v = NAN;
    if (fm_hf_compile_string(g, src, strlen(src), "lib", NULL, NULL, &m, &err) == FM_OK) {
        double p[4] = {x, y, 0, 0};
        v = fm_graph_eval_reference(g, m.root, p);
    }
    fm_graph_free(g);
    return v;
}

static void check_sardf_by_hand(void)
{
    const char *uni0 = "hfDUni(x[1], x[2], 1, 0)";
    /* alpha = 0: the quadrant I circle has centre 0, radius d: |(x, y)| */
    CHECK_NEAR(eval_at(uni0, 3, 4), 5.0, 1e-14);
    CHECK_NEAR(eval_at(uni0, -1, 2), 2.0, 1e-14); /* quadrant II: the positive one */
    /* far in quadrant III, in the strip: circle radius R centre (d - R, d - R)
     * through (-10, -10): d = -10 + R - R / sqrt 2 */
    CHECK_NEAR(eval_at(uni0, -10, -10), -10 + 1 - sqrt(0.5), 1e-14);
    CHECK_NEAR(eval_at(uni0, -10, -20), -10.0, 1e-14); /* outside the strip: x */
    /* quadrant III near the corner: on the diagonal the quartic factors,
     * x = y = -2sm + (2sm - m^2)/sqrt 2; m = 1/2, R = 1 gives
     * x = -1 + 0.75/sqrt 2 and d = -1/4 */
    CHECK_NEAR(eval_at(uni0, -1 + 0.75 * sqrt(0.5), -1 + 0.75 * sqrt(0.5)), -0.25, 1e-14);
    /* intersection, quadrant I beyond 2R, in the strip: the circle radius
     * R = 1 centre (d + 1, d + 1) through (3, 4) has d = 3 */
    CHECK_NEAR(eval_at("hfDInt(x[1], x[2], 1, 0.2)", 3, 4), 3.0, 1e-14);
    /* subtraction of a positive f2 from f1 in quadrant IV: min(f1, -f2) */
    CHECK_NEAR(eval_at("hfDSub(x[1], x[2], 1, 0.2)", 2, 0.5), -0.5, 1e-14);
}

/* A program compiled to a tape with its evaluator (NULLs where a step
 * failed, which the CHECKs report). */
typedef struct compiled {
    fm_graph *g;
    fm_hf_model m;
    fm_tape *tape;
    fm_evaluator *ev;
} compiled;

static void compile_for_eval(const char *src, compiled *c)
{
    fm_error err;
    c->g = fm_graph_new(0);
    CHECK(fm_hf_compile_string(c->g, src, strlen(src), "lib", NULL, NULL, &c->m, &err) == FM_OK);
    c->tape = fm_tape_compile(c->g, c->m.root, &err);
    CHECK(c->tape != NULL);
    c->ev = c->tape ? fm_evaluator_new(c->tape, &err) : NULL;
    CHECK(c->ev != NULL);
}

static void compiled_free(compiled *c)
{
    fm_evaluator_free(c->ev);
    fm_tape_free(c->tape);
    fm_graph_free(c->g);
}

/* A random box in [-3, 3]^3 with sides up to max_side (t = 0). */
static void random_box(fm_interval box[4], double max_side)
{
    double w = test_uniform(0.001, max_side);
    box[3].lo = box[3].hi = 0;
    for (int i = 0; i < 3; i++) {
        box[i].lo = test_uniform(-3, 3);
        box[i].hi = box[i].lo + w * test_rand01();
    }
}

/* Interval soundness on random boxes (every sampled value inside the
 * enclosure, the enclosure finite) and the gradient against central
 * differences wherever the function is smooth at the step's scale. */
static void check_sardf_eval(const char *expr)
{
    char src[512];
    snprintf(src, sizeof src, "t(x[3], a[1])\n{\nt = %s;\n}\n", expr);
    compiled c;
    compile_for_eval(src, &c);
    fm_graph *g = c.g;
    fm_evaluator *ev = c.ev;
    int unsound = 0, infinite = 0, grad_bad = 0, smooth = 0;
    for (int b = 0; ev && b < 400; b++) {
        fm_interval box[4];
        random_box(box, 2);
        fm_interval r = fm_eval_interval(ev, box);
        if ((!isfinite(r.lo) || !isfinite(r.hi)) && infinite++ < 2)
            fprintf(stderr, "%s: [%g, %g] on [%g, %g] x [%g, %g] x [%g, %g]\n", expr, r.lo, r.hi,
                    box[0].lo, box[0].hi, box[1].lo, box[1].hi, box[2].lo, box[2].hi);
        for (int k = 0; k < 40; k++) {
            double p[4] = {0, 0, 0, 0};
            for (int i = 0; i < 3; i++) p[i] = test_uniform(box[i].lo, box[i].hi);
            double v = fm_eval_point(ev, p);
            if (!(v >= r.lo && v <= r.hi) && unsound++ < 3)
                fprintf(stderr, "%s: f(%g, %g, %g) = %.17g outside [%.17g, %.17g]\n", expr, p[0],
                        p[1], p[2], v, r.lo, r.hi);
        }
        double p[4] = {test_uniform(-3, 3), test_uniform(-3, 3), test_uniform(-3, 3), 0}, gr[4];
        double v = fm_eval_grad(ev, p, gr);
        CHECK_NEAR(v, fm_graph_eval_reference(g, c.m.root, p), 1e-12);
        const double h = 1e-6;
        for (int i = 0; i < 3; i++) {
            double q[4] = {p[0], p[1], p[2], 0};
            q[i] = p[i] + h;
            double up = fm_eval_point(ev, q);
            q[i] = p[i] - h;
            double down = fm_eval_point(ev, q);
            /* a branch boundary within h shows as unequal one-sided slopes */
            if (fabs((up - v) / h - (v - down) / h) > 1e-4) continue;
            smooth++;
            if (!(fabs(gr[i] - (up - down) / (2 * h)) <= 1e-5 * (1 + fabs(gr[i]))) && grad_bad++ < 3)
                fprintf(stderr, "%s: df/dx%d at (%g, %g, %g) = %.12g, differences %.12g\n", expr,
                        i + 1, p[0], p[1], p[2], gr[i], (up - down) / (2 * h));
        }
    }
    CHECK(unsound == 0);
    CHECK(infinite == 0);
    CHECK(grad_bad == 0);
    CHECK(smooth > 900);
    compiled_free(&c);
}

static void check_sardf_errors(void)
{
    const char *bad[][2] = {
        {"hfDUni(x[1], x[2], 0, 0.2)", "hfDUni: the radius R must be positive"},
        {"hfDInt(x[1], x[2], -1, 0.2)", "hfDInt: the radius R must be positive"},
        {"hfDSub(x[1], x[2], 1, 0.8)", "hfDSub: the angle alpha must be in [0, pi/4)"},
        {"hfDUni(x[1], x[2], 1, -0.1)", "hfDUni: the angle alpha must be in [0, pi/4)"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char src[256], buf[800];
        snprintf(src, sizeof src, "t(x[3], a[1])\n{\nt = %s;\n}\n", bad[i][0]);
        fm_graph *g = fm_graph_new(0);
        fm_hf_model m;
        fm_error err;
        CHECK(fm_hf_compile_string(g, src, strlen(src), "lib", NULL, NULL, &m, &err) != FM_OK);
        CHECK_STR_CONTAINS(fm_error_format(&err, buf, sizeof buf), bad[i][1]);
        fm_graph_free(g);
    }
}

/* ---- the operations hf builds with lib/frep's builders, pinned to the
 * papers' formulas written out here: Pasko et al. 1995 eq. 2 for | & \ with
 * r_alpha, eq. 6-8 for the blends, the exact torus, the twist. Point values
 * must match, and the interval of a box must contain the formula's value at
 * every sampled point of the box. ---- */

/* Pasko eq. 2: (f1 + f2 + s sqrt(f1^2 + f2^2 - 2 alpha f1 f2)) / (1 + alpha) */
static double pasko_eq2(double f1, double f2, double alpha, int s)
{
    return (f1 + f2 + s * sqrt(f1 * f1 + f2 * f2 - 2 * alpha * f1 * f2)) / (1 + alpha);
}
static double op_f1(const double x[3]) { return 1 - x[0] * x[0] - 0.5 * x[1]; }
static double op_f2(const double x[3]) { return x[1] + 0.5 * x[2] - 0.25; }
#define OP_F1 "(1 - x[1]^2 - 0.5*x[2])"
#define OP_F2 "(x[2] + 0.5*x[3] - 0.25)"
static double f_uni0(const double x[3]) { return pasko_eq2(op_f1(x), op_f2(x), 0, 1); }
static double f_int0(const double x[3]) { return pasko_eq2(op_f1(x), op_f2(x), 0, -1); }
static double f_sub0(const double x[3]) { return pasko_eq2(op_f1(x), -op_f2(x), 0, -1); }
static double f_uni3(const double x[3]) { return pasko_eq2(op_f1(x), op_f2(x), 0.3, 1); }
static double f_int3(const double x[3]) { return pasko_eq2(op_f1(x), op_f2(x), 0.3, -1); }
static double f_sub3(const double x[3]) { return pasko_eq2(op_f1(x), -op_f2(x), 0.3, -1); }
static double f_uni1(const double x[3]) { return pasko_eq2(op_f1(x), op_f2(x), 1, 1); }
static double f_int1(const double x[3]) { return pasko_eq2(op_f1(x), op_f2(x), 1, -1); }
static double f_sub1(const double x[3]) { return pasko_eq2(op_f1(x), -op_f2(x), 1, -1); }
/* alpha = 1: eq. 3, max and min, to the bit */
static double f_max(const double x[3]) { return fmax(op_f1(x), op_f2(x)); }
static double f_min(const double x[3]) { return fmin(op_f1(x), op_f2(x)); }
/* eq. 6-8 with the same f1, f2 */
static double f_blend_uni_ops(const double x[3])
{
    double f1 = op_f1(x), f2 = op_f2(x);
    return f1 + f2 + sqrt(f1 * f1 + f2 * f2) + 0.8 / (1 + sqr(f1 / 0.6) + sqr(f2 / 1.1));
}
static double f_blend_int_ops(const double x[3])
{
    double f1 = op_f1(x), f2 = op_f2(x);
    return f1 + f2 - sqrt(f1 * f1 + f2 * f2) - 0.8 / (1 + sqr(f1 / 0.6) + sqr(f2 / 1.1));
}
/* a twisted exact torus: the twist about Z from 0.3 at z = -1 to 1.2 at
 * z = 2 (twist_angle), then the distance torus about Z through c */
static double f_twisted_torus(const double x[3])
{
    double y[3] = {x[0], x[1], x[2]};
    rot(&y[0], &y[1], twist_angle(x[2]));
    double ring = sqrt(sqr(y[0] - C[0]) + sqr(y[1] - C[1])) - 2;
    return 0.5 - sqrt(sqr(ring) + sqr(y[2] - C[2]));
}

static void check_eval(const char *stmts, const char *expr, formula f, double tol)
{
    check(stmts, expr, f, tol);
    char src[4096];
    snprintf(src, sizeof src, "t(x[3], a[1])\n{\n%s%s\nt = %s;\n}\n", prologue, stmts, expr);
    compiled c;
    compile_for_eval(src, &c);
    fm_evaluator *ev = c.ev;
    int outside = 0, point_bad = 0;
    for (int b = 0; ev && b < 200; b++) {
        fm_interval box[4];
        random_box(box, 1.5);
        fm_interval r = fm_eval_interval(ev, box);
        for (int k = 0; k < 30; k++) {
            double p[4] = {0, 0, 0, 0};
            for (int i = 0; i < 3; i++) p[i] = test_uniform(box[i].lo, box[i].hi);
            double want = f(p), got = fm_eval_point(ev, p);
            /* the formula's value, less its rounding, lies in the enclosure */
            double slack = tol * (1 + fabs(want));
            if (!(want >= r.lo - slack && want <= r.hi + slack) && outside++ < 3)
                fprintf(stderr, "%s%s: formula %.17g at (%g, %g, %g) outside [%.17g, %.17g]\n",
                        stmts, expr, want, p[0], p[1], p[2], r.lo, r.hi);
            if (!(fabs(got - want) <= slack) && point_bad++ < 3)
                fprintf(stderr, "%s%s at (%g, %g, %g): tape %.17g, formula %.17g\n", stmts, expr,
                        p[0], p[1], p[2], got, want);
        }
    }
    CHECK(outside == 0);
    CHECK(point_bad == 0);
    compiled_free(&c);
}

static void check_ops_against_papers(void)
{
    const double tol = 1e-12;
    check_eval("", OP_F1 " | " OP_F2, f_uni0, tol);
    check_eval("", OP_F1 " & " OP_F2, f_int0, tol);
    check_eval("", OP_F1 " \\ " OP_F2, f_sub0, tol);
    check_eval("r_alpha = 0.3;", OP_F1 " | " OP_F2, f_uni3, tol);
    check_eval("r_alpha = 0.3;", OP_F1 " & " OP_F2, f_int3, tol);
    check_eval("r_alpha = 0.3;", OP_F1 " \\ " OP_F2, f_sub3, tol);
    check_eval("r_alpha = 1;", OP_F1 " | " OP_F2, f_uni1, tol);
    check_eval("r_alpha = 1;", OP_F1 " & " OP_F2, f_int1, tol);
    check_eval("r_alpha = 1;", OP_F1 " \\ " OP_F2, f_sub1, tol);
    check_eval("r_alpha = 1;", OP_F1 " | " OP_F2, f_max, 0);
    check_eval("r_alpha = 1;", OP_F1 " & " OP_F2, f_min, 0);
    check_eval("r_alpha = 0.3;", "hfBlock(x, c, 1, 2, 3)", f_block_03, tol);
    check_eval("", "hfBlendUni(" OP_F1 ", " OP_F2 ", 0.8, 0.6, 1.1)", f_blend_uni_ops, tol);
    check_eval("", "hfBlendInt(" OP_F1 ", " OP_F2 ", -0.8, 0.6, 1.1)", f_blend_int_ops, tol);
    check_eval("r = hfTwistZ(xt, -1, 2, 0.3, 1.2);", "hfDTorusZ(xt, c, 2, 0.5)", f_twisted_torus,
               tol);
}

int main(void)
{
    const double tol = 1e-12;
    check("", "hfSphere(x, c, 2)", f_sphere, tol);
    check("", "hfEllipsoid(x, c, 1, 2, 3)", f_ellipsoid, tol);
    check("", "hfCylinderX(x, c, 1.5)", f_cyl_x, tol);
    check("", "hfCylinderY(x, c, 1.5)", f_cyl_y, tol);
    check("", "hfCylinderZ(x, c, 1.5)", f_cyl_z, tol);
    check("", "hfEllCylX(x, c, 1.5, 0.5)", f_ellcyl_x, tol);
    check("", "hfEllCylY(x, c, 1.5, 0.5)", f_ellcyl_y, tol);
    check("", "hfEllCylZ(x, c, 1.5, 0.5)", f_ellcyl_z, tol);
    check("", "hfConeX(x, c, 0.5)", f_cone_x, tol);
    check("", "hfConeY(x, c, 0.5)", f_cone_y, tol);
    check("", "hfConeZ(x, c, 0.5)", f_cone_z, tol);
    check("", "hfEllConeX(x, c, 0.5, 2)", f_ellcone_x, tol);
    check("", "hfEllConeY(x, c, 0.5, 2)", f_ellcone_y, tol);
    check("", "hfEllConeZ(x, c, 0.5, 2)", f_ellcone_z, tol);
    check("", "hfTorusX(x, c, 2, 0.5)", f_torus_x, tol);
    check("", "hfTorusY(x, c, 2, 0.5)", f_torus_y, tol);
    check("", "hfTorusZ(x, c, 2, 0.5)", f_torus_z, tol);
    check("", "hfBlock(x, c, 1, 2, 3)", f_block0, tol);
    check("r_alpha = 0.5;", "hfBlock(x, c, 1, 2, 3)", f_block_half, tol);
    check("r_alpha = 1;", "hfBlock(x, c, 1, 2, 3)", f_block1, tol);
    check("", "hfSuperell(x, c, 1, 2, 3, 0.5, 0.7)", f_superell, 1e-10);
    check("", "hfBlobby(x, x0, y0, z0, p, q, 0.5)", f_blobby, tol);
    check("", "hfMetaball(x, x0, y0, z0, q, p, 0.5)", f_metaball, tol);
    check("", "hfSoft(x, x0, y0, z0, q, 0.2)", f_soft, tol);
    check("", "hfBlendUni(x[1], x[2], 0.5, 1.5, 0.7)", f_blend_uni, tol);
    check("", "hfBlendInt(x[1], x[2], 0.5, 1.5, 0.7)", f_blend_int, tol);
    /* transforms return 1 and change xt in place */
    char expr[256];
    snprintf(expr, sizeof expr, "r * (%s)", weighed);
    check("r = hfShift3D(xt, 1, 2, 3);", expr, f_shift, tol);
    check("r = hfScale3D(xt, 1, 2, 4);", expr, f_scale, tol);
    check("r = hfRotate3DX(xt, 0.5);", expr, f_rot_x, tol);
    check("r = hfRotate3DY(xt, 0.5);", expr, f_rot_y, tol);
    check("r = hfRotate3DZ(xt, 0.5);", expr, f_rot_z, tol);
    check("r = hfTwistX(xt, -1, 2, 0.3, 1.2);", expr, f_twist_x, tol);
    check("r = hfTwistY(xt, -1, 2, 0.3, 1.2);", expr, f_twist_y, tol);
    check("r = hfTwistZ(xt, -1, 2, 0.3, 1.2);", expr, f_twist_z, tol);
    check("r = hfTaperX(xt, -1, 1, 0.5, 2);", expr, f_taper_x, tol);
    check("r = hfTaperY(xt, -1, 1, 0.5, 2);", expr, f_taper_y, tol);
    check("r = hfTaperZ(xt, -1, 1, 0.5, 2);", expr, f_taper_z, tol);
    check("r = hfStretch3D(xt, c, 1, 2, 4);", expr, f_stretch, tol);
    check("r = hfShift3D(x, 1, 2, 3);", "hfSphere(x, c, 2)", f_shifted_sphere, tol);
    check("", "hfDCylinder(x, c, u, 1)", f_dcylinder, tol);
    check("", "hfDConeX(x, c, 0.5)", f_dcone_x, tol);
    check("", "hfDConeY(x, c, 0.5)", f_dcone_y, tol);
    check("", "hfDConeZ(x, c, 0.5)", f_dcone_z, tol);
    check("", "hfDTorusX(x, c, 2, 0.5)", f_dtorus_x, tol);
    check("", "hfDTorusY(x, c, 2, 0.5)", f_dtorus_y, tol);
    check("", "hfDTorusZ(x, c, 2, 0.5)", f_dtorus_z, tol);
    check("", "hfDUni(x[1], x[2], 1, 0.3)", f_duni, tol);
    check("", "hfDUni(x[1], x[2], 0.5, 0)", f_duni_a0, tol);
    check("", "hfDUni(x[1], x[2], 2, 0.45)", f_duni_a45, tol);
    check("", "hfDInt(x[1] - x[3], x[2], 0.7, 0.2)", f_dint, tol);
    check("", "hfDSub(x[1], 0.5*x[2] + x[3], 1.3, 0.1)", f_dsub, tol);
    check("", "hfDSub(hfDTorusZ(x, c, 2, 0.5), hfDCylinder(x, c, u, 1), 0.25, 0.15)",
          f_dsub_solids, tol);
    check_sardf_by_hand();
    check_sardf_eval("hfDUni(x[1], x[2], 1, 0.3)");
    check_sardf_eval("hfDInt(x[1] - x[3], x[2], 0.7, 0.2)");
    check_sardf_eval("hfDSub(x[1], 0.5*x[2] + x[3], 1.3, 0.1)");
    check_sardf_errors();
    check_ops_against_papers();
    return test_summary("hf_library");
}
