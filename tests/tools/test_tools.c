/* test_tools.c: cutter shapes. Checks the exact profile distance against a
 * brute-force distance to a dense sampling of the boundary, the geometry of
 * every shape against volumes and points from its own definition, the
 * validation messages, the DAG builder against the native evaluator,
 * interval soundness, gradients and the custom-cutter hook. */
#include "test.h"
#include "tools/dag_eval.h"
#include "tools/tools.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

static fm_tool_spec base_spec(fm_tool_shape shape)
{
    fm_tool_spec s;
    memset(&s, 0, sizeof s);
    s.number = 7;
    s.shape = shape;
    s.diameter = 6;
    s.flute_length = 12;
    s.length = 30;
    s.center_cutting = 1;
    switch (shape) {
    case FM_TOOL_BULL: s.corner_radius = 1; break;
    case FM_TOOL_VBIT: s.angle = 90; s.tip_diameter = 0.4; break;
    case FM_TOOL_DRILL: s.point_angle = 118; break;
    case FM_TOOL_TAPERED: s.taper_angle = 5; break;
    case FM_TOOL_DOVETAIL: s.diameter = 12; s.angle = 30; s.neck_diameter = 5; break;
    case FM_TOOL_LOLLIPOP: s.diameter = 8; s.neck_diameter = 3; s.shank_diameter = 6; break;
    default: break;
    }
    s.holder_count = 2;
    s.holder[0].diameter = 20;
    s.holder[0].length = 25;
    s.holder[1].diameter = 40;
    s.holder[1].diameter_top = 30;
    s.holder[1].length = 20;
    return s;
}

/* Dense boundary samples of a part: segments exactly, arcs every 1e-3 rad. */
typedef struct samples {
    double (*pt)[2];
    size_t n;
} samples;

static samples sample_boundary(const fm_tool_part *part)
{
    samples s;
    s.pt = malloc(sizeof *s.pt * 400000);
    s.n = 0;
    for (size_t i = 0; i < part->count; i++) {
        const fm_profile_elem *e = &part->elem[i];
        if (e->kind == FM_PROFILE_SEGMENT) {
            s.pt[s.n][0] = e->a[0];
            s.pt[s.n][1] = e->a[1];
            s.n++;
        } else {
            double a0 = atan2(e->a[1] - e->c[1], e->a[0] - e->c[0]);
            double a1 = atan2(e->b[1] - e->c[1], e->b[0] - e->c[0]);
            double d = a1 - a0;
            if (d > FM_PI) d -= 2 * FM_PI;
            if (d < -FM_PI) d += 2 * FM_PI;
            int k = (int)(fabs(d) / 1e-3) + 1;
            for (int j = 0; j < k; j++) {
                double a = a0 + d * j / k;
                s.pt[s.n][0] = e->c[0] + e->radius * cos(a);
                s.pt[s.n][1] = e->c[1] + e->radius * sin(a);
                s.n++;
            }
        }
    }
    s.pt[s.n][0] = part->elem[part->count - 1].b[0];
    s.pt[s.n][1] = part->elem[part->count - 1].b[1];
    s.n++;
    return s;
}

static double seg_dist(const double q[2], const double a[2], const double b[2])
{
    double dr = b[0] - a[0], dz = b[1] - a[1], l2 = dr * dr + dz * dz;
    double t = l2 > 0 ? ((q[0] - a[0]) * dr + (q[1] - a[1]) * dz) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(q[0] - a[0] - t * dr, q[1] - a[1] - t * dz);
}

/* Inside by the crossing number of a ray toward +r (the polygon closed
 * along the axis). */
static int poly_inside(const samples *s, const double q[2])
{
    int c = 0;
    for (size_t i = 0; i + 1 <= s->n; i++) {
        const double *a = s->pt[i], *b = s->pt[(i + 1) % s->n];
        if ((a[1] > q[1]) != (b[1] > q[1])) {
            double r = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if (q[0] < r) c ^= 1;
        }
    }
    return c;
}

static double brute_profile(const samples *s, double r, double z)
{
    double q[2] = {r, z}, d = DBL_MAX;
    for (size_t i = 0; i + 1 < s->n; i++) {
        double di = seg_dist(q, s->pt[i], s->pt[i + 1]);
        if (di < d) d = di;
    }
    return poly_inside(s, q) ? d : -d;
}

static void check_part_distance(const fm_tool_part *part, const char *name)
{
    samples s = sample_boundary(part);
    int bad = 0;
    for (int k = 0; k < 300; k++) {
        double r = test_uniform(0, part->r_max * 1.3 + 1);
        double z = test_uniform(part->z_lo - 2, part->z_hi + 2);
        double f = fm_tool_profile_eval(part, NULL, r, z, NULL);
        double b = brute_profile(&s, r, z);
        /* Chord error of arcs sampled every 1e-3 rad: radius * 1.25e-7. */
        if (fabs(f - b) > 1e-6 && bad++ < 3)
            fprintf(stderr, "%s: profile(%g, %g) = %.9g, brute force %.9g\n", name, r, z, f, b);
        CHECK_NEAR(f, b, 1e-6);
    }
    free(s.pt);
}

/* Radius of the part at height z from its own profile function (bisection
 * on the sign). */
static double radius_at(const fm_tool_part *part, double z)
{
    double lo = 0, hi = part->r_max + 1;
    if (fm_tool_profile_eval(part, NULL, 0, z, NULL) < 0) return 0;
    for (int it = 0; it < 60; it++) {
        double m = 0.5 * (lo + hi);
        if (fm_tool_profile_eval(part, NULL, m, z, NULL) >= 0) lo = m; else hi = m;
    }
    return lo;
}

/* Volume pi * int R(z)^2 dz by Simpson's rule, split where the radius may
 * jump (at the heights of profile vertices) so each piece is smooth. */
static double part_volume(const fm_tool_part *part)
{
    double cuts[FM_PROFILE_MAX + 2];
    int nc = 0;
    for (size_t i = 0; i < part->count; i++) {
        double z = part->elem[i].a[1];
        if (nc == 0 || z > cuts[nc - 1]) cuts[nc++] = z;
    }
    if (part->z_hi > cuts[nc - 1]) cuts[nc++] = part->z_hi;
    double total = 0;
    for (int c = 0; c + 1 < nc; c++) {
        int n = 2000;
        double a = cuts[c] + 1e-11, b = cuts[c + 1] - 1e-11, h = (b - a) / n, sum = 0;
        for (int i = 0; i <= n; i++) {
            double r = radius_at(part, a + i * h);
            double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
            sum += w * r * r;
        }
        total += FM_PI * sum * h / 3;
    }
    return total;
}

static void check_shapes(void)
{
    fm_error err;
    fm_tool t;
    const double R = 3, F = 12;
    /* Flat: cylinder. */
    fm_tool_spec s = base_spec(FM_TOOL_FLAT);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    CHECK_NEAR(part_volume(&t.flutes), FM_PI * R * R * F, 1e-3);
    CHECK(t.flutes.convex);
    double p[3] = {0, 0, -1};
    CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, p), -1, 1e-15);
    double p2[3] = {1, 1, 5};
    CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, p2), R - sqrt(2), 1e-15);
    check_part_distance(&t.flutes, "flat");
    /* Shank and holder. */
    CHECK(t.has_shank && t.has_holder);
    CHECK_NEAR(part_volume(&t.shank), FM_PI * R * R * (30 - F), 1e-3);
    double hv = FM_PI * 100 * 25 + FM_PI * 20.0 / 3 * (400 + 20 * 15 + 225);
    CHECK_NEAR(part_volume(&t.holder), hv, 1e-3 * hv / 1000);
    check_part_distance(&t.holder, "holder");
    /* Ball: hemisphere + cylinder. */
    s = base_spec(FM_TOOL_BALL);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    CHECK_NEAR(part_volume(&t.flutes), 2.0 / 3 * FM_PI * R * R * R + FM_PI * R * R * (F - R), 1e-3);
    CHECK_NEAR(t.flutes.ball_radius, R, 0);
    double pb[3] = {0, 0, R};
    CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, pb), R, 1e-15);
    check_part_distance(&t.flutes, "ball");
    /* Bull: corner radius rc. Pappus for the corner: the quarter disc's
     * area pi rc^2 / 4 at centroid radius (R - rc) + 4 rc / (3 pi). */
    s = base_spec(FM_TOOL_BULL);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double rc = 1, a = R - rc;
        double v = FM_PI * a * a * rc                                            /* inner cylinder under the corners */
                   + 2 * FM_PI * (a + 4 * rc / (3 * FM_PI)) * FM_PI * rc * rc / 4        /* corner ring */
                   + FM_PI * R * R * (F - rc);
        CHECK_NEAR(part_volume(&t.flutes), v, 1e-3);
    }
    check_part_distance(&t.flutes, "bull");
    /* V-bit: frustum then cylinder. */
    s = base_spec(FM_TOOL_VBIT);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double rt = 0.2, h = (R - rt) / tan(45 * FM_DEG);
        double v = FM_PI * h / 3 * (rt * rt + rt * R + R * R) + FM_PI * R * R * (F - h);
        CHECK_NEAR(part_volume(&t.flutes), v, 1e-3);
        double on[3] = {0.5 * (rt + R), 0, 0.5 * h};
        CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, on), 0, 1e-14);
    }
    check_part_distance(&t.flutes, "vbit");
    /* Drill: cone of the point angle. */
    s = base_spec(FM_TOOL_DRILL);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double h = R / tan(59 * FM_DEG);
        CHECK_NEAR(part_volume(&t.flutes), FM_PI * R * R * h / 3 + FM_PI * R * R * (F - h), 1e-3);
        double below[3] = {0, 0, -2};
        CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, below), -2, 1e-15);
    }
    check_part_distance(&t.flutes, "drill");
    /* Tapered flat: frustum widening upward. */
    s = base_spec(FM_TOOL_TAPERED);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double R1 = R + F * tan(5 * FM_DEG);
        CHECK_NEAR(part_volume(&t.flutes), FM_PI * F / 3 * (R * R + R * R1 + R1 * R1), 1e-3);
    }
    check_part_distance(&t.flutes, "tapered");
    /* Tapered ball: cap of the tip ball below the tangent circle, frustum above. */
    s = base_spec(FM_TOOL_TAPERED);
    s.diameter = 0;
    s.tip_radius = 1;
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double a = 5 * FM_DEG, rt = 1, tz = rt * (1 - sin(a)), tr = rt * cos(a);
        double cap = FM_PI * tz * tz * (3 * rt - tz) / 3;
        double R1 = tr + (F - tz) * tan(a);
        double fr = FM_PI * (F - tz) / 3 * (tr * tr + tr * R1 + R1 * R1);
        CHECK_NEAR(part_volume(&t.flutes), cap + fr, 1e-3);
        CHECK(t.flutes.convex);
    }
    check_part_distance(&t.flutes, "tapered ball");
    /* Dovetail: inverted frustum and neck. */
    s = base_spec(FM_TOOL_DOVETAIL);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double Rb = 6, rn = 2.5, h = (Rb - rn) / tan(30 * FM_DEG);
        CHECK_NEAR(part_volume(&t.flutes), FM_PI * h / 3 * (Rb * Rb + Rb * rn + rn * rn) + FM_PI * rn * rn * (F - h),
                   1e-3);
        CHECK(!t.flutes.convex);
    }
    check_part_distance(&t.flutes, "dovetail");
    /* Lollipop: ball minus the cap the neck cuts off, plus the neck. */
    s = base_spec(FM_TOOL_LOLLIPOP);
    CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
    {
        double Rb = 4, rn = 1.5, zn = Rb + sqrt(Rb * Rb - rn * rn), capH = 2 * Rb - zn;
        double v = 4.0 / 3 * FM_PI * Rb * Rb * Rb - FM_PI * capH * capH * (3 * Rb - capH) / 3 + FM_PI * rn * rn * (F - zn);
        CHECK_NEAR(part_volume(&t.flutes), v, 1e-3);
        CHECK(!t.flutes.convex);
        double c[3] = {0, 0, Rb};
        CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, c), Rb, 1e-12);
        CHECK_NEAR(t.shank.elem[0].b[0], 3, 0); /* shank_diameter given */
    }
    check_part_distance(&t.flutes, "lollipop");
}

static void check_validation(void)
{
    fm_error err;
    fm_tool t;
    fm_tool_spec s = base_spec(FM_TOOL_BULL);
    s.corner_radius = 4;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "corner_radius");
    s = base_spec(FM_TOOL_FLAT);
    s.length = -1;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "length");
    s = base_spec(FM_TOOL_FLAT);
    s.flute_length = 40;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "flute_length 40 is longer than the stick-out length 30");
    s = base_spec(FM_TOOL_VBIT);
    s.angle = 180;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "angle");
    s = base_spec(FM_TOOL_VBIT);
    s.tip_diameter = 6;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "tip_diameter");
    s = base_spec(FM_TOOL_DRILL);
    s.point_angle = -3;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "point_angle");
    s = base_spec(FM_TOOL_FLAT);
    s.diameter = NAN;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "diameter");
    s = base_spec(FM_TOOL_FLAT);
    s.holder[1].length = 0;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "holder segment 2");
    s = base_spec(FM_TOOL_LOLLIPOP);
    s.neck_diameter = 9;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "neck_diameter");
    s = base_spec(FM_TOOL_DOVETAIL);
    s.flute_length = 2;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "head height");
    s = base_spec(FM_TOOL_TAPERED);
    s.tip_radius = 1; /* diameter 6 disagrees */
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "tip_radius");
    s = base_spec(FM_TOOL_BALL);
    s.flute_length = 2;
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "ball radius");
    s = base_spec(FM_TOOL_HYPERFUN);
    CHECK(fm_tool_build(&s, &t, &err) == FM_ERR_INPUT);
    /* A profile that goes down is refused. */
    fm_profile_elem e[3] = {{FM_PROFILE_SEGMENT, {0, 0}, {1, 0}, {0, 0}, 0, 0},
                            {FM_PROFILE_SEGMENT, {1, 0}, {1, -1}, {0, 0}, 0, 0},
                            {FM_PROFILE_SEGMENT, {1, -1}, {0, -1}, {0, 0}, 0, 0}};
    fm_tool_part part;
    CHECK(fm_tool_part_from_profile(e, 3, &part, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "radius function");
}

static void check_dag_interval_grad(void)
{
    fm_tool_shape shapes[] = {FM_TOOL_FLAT, FM_TOOL_BALL, FM_TOOL_BULL, FM_TOOL_VBIT, FM_TOOL_DRILL,
                              FM_TOOL_TAPERED, FM_TOOL_DOVETAIL, FM_TOOL_LOLLIPOP};
    for (size_t k = 0; k < sizeof shapes / sizeof *shapes; k++) {
        fm_error err;
        fm_tool t;
        fm_tool_spec s = base_spec(shapes[k]);
        CHECK(fm_tool_build(&s, &t, &err) == FM_OK);
        const fm_tool_part *parts[3] = {&t.flutes, &t.shank, &t.holder};
        for (int pi = 0; pi < 3; pi++) {
            const fm_tool_part *part = parts[pi];
            fm_graph *g = fm_graph_new(0);
            fm_node root = fm_tool_part_build(g, part);
            CHECK(root != FM_NONE && fm_graph_error(g) == NULL);
            double ext = part->r_max + 2;
            for (int i = 0; i < 200; i++) {
                double p[4] = {test_uniform(-ext, ext), test_uniform(-ext, ext),
                               test_uniform(part->z_lo - 2, part->z_hi + 2), 0};
                double f = fm_tool_part_eval(part, NULL, p);
                CHECK_NEAR(test_dag_eval(g, root, p), f, 1e-12);
                /* Gradient against central differences (skip kinks: the
                 * difference quotient then disagrees with either side). */
                double r = hypot(p[0], p[1]), gr[2], h = 1e-6;
                fm_tool_profile_eval(part, NULL, r, p[2], gr);
                double fr1 = fm_tool_profile_eval(part, NULL, r + h, p[2], NULL);
                double fr0 = fm_tool_profile_eval(part, NULL, r - h, p[2], NULL);
                double fz1 = fm_tool_profile_eval(part, NULL, r, p[2] + h, NULL);
                double fz0 = fm_tool_profile_eval(part, NULL, r, p[2] - h, NULL);
                int smooth = fabs(fr1 - 2 * fm_tool_profile_eval(part, NULL, r, p[2], NULL) + fr0) < 1e-9 &&
                             fabs(fz1 - 2 * fm_tool_profile_eval(part, NULL, r, p[2], NULL) + fz0) < 1e-9 && r > h;
                if (smooth) {
                    CHECK_NEAR(gr[0], (fr1 - fr0) / (2 * h), 1e-5);
                    CHECK_NEAR(gr[1], (fz1 - fz0) / (2 * h), 1e-5);
                }
            }
            /* The batch profile (vectorized direct formulas for cylinders
             * and balls) equals the point form bit for bit, also on the
             * axis, at the ball's centre and above z_hi - R. */
            {
                enum { NB = 203 };
                double rs[NB], zs[NB], ob[NB];
                for (int i = 0; i < NB; i++) {
                    rs[i] = i % 7 == 0 ? 0 : test_uniform(0, ext);
                    zs[i] = test_uniform(part->z_lo - 2, part->z_hi + 2);
                }
                zs[1] = part->z_lo + part->ball_radius;
                zs[2] = part->z_hi - part->ball_radius;
                fm_tool_profile_eval_batch(part, NULL, NB, rs, zs, ob);
                int same = 1;
                for (int i = 0; i < NB; i++) same &= ob[i] == fm_tool_profile_eval(part, NULL, rs[i], zs[i], NULL);
                CHECK(same);
            }
            /* Interval soundness over random boxes. */
            for (int i = 0; i < 100; i++) {
                fm_interval box[3];
                for (int a = 0; a < 3; a++) {
                    double c = a < 2 ? test_uniform(-ext, ext) : test_uniform(part->z_lo - 2, part->z_hi + 2);
                    double w = test_uniform(0, 3);
                    box[a].lo = c - w;
                    box[a].hi = c + w;
                }
                fm_interval iv = fm_tool_part_interval(part, NULL, box);
                double xs[64], ys[64], zs[64], out[64];
                for (int j = 0; j < 64; j++) {
                    xs[j] = test_uniform(box[0].lo, box[0].hi);
                    ys[j] = test_uniform(box[1].lo, box[1].hi);
                    zs[j] = test_uniform(box[2].lo, box[2].hi);
                }
                fm_tool_part_eval_batch(part, NULL, 64, xs, ys, zs, out);
                for (int j = 0; j < 64; j++) {
                    double q[3] = {xs[j], ys[j], zs[j]};
                    CHECK(out[j] == fm_tool_part_eval(part, NULL, q));
                    CHECK(out[j] >= iv.lo && out[j] <= iv.hi);
                }
            }
            fm_graph_free(g);
        }
    }
}

/* A custom cutter through the hook: a sphere of radius 2 centred at z = 2. */
static double sphere_eval(void *ctx, void *w, double r, double z)
{
    (void)ctx;
    (void)w;
    return 2 - hypot(r, z - 2);
}
static fm_interval sphere_interval(void *ctx, void *w, fm_interval r, fm_interval z)
{
    (void)ctx;
    (void)w;
    double rn = r.lo > 0 ? r.lo : 0, zn = z.lo > 2 ? z.lo - 2 : z.hi < 2 ? 2 - z.hi : 0;
    double rf = fmax(fabs(r.lo), fabs(r.hi)), zf = fmax(fabs(z.lo - 2), fabs(z.hi - 2));
    fm_interval out = {2 - hypot(rf, zf), 2 - hypot(rn, zn)};
    return out;
}

static void check_custom(void)
{
    fm_error err;
    fm_tool t;
    fm_tool_spec s = base_spec(FM_TOOL_HYPERFUN);
    s.bound_radius = 2;
    s.flute_length = 4;
    fm_tool_custom c = {NULL, NULL, NULL, sphere_eval, sphere_interval, 2, 4, NULL};
    CHECK(fm_tool_build_custom(&s, &c, &t, &err) == FM_OK);
    double p[3] = {1, 0, 2};
    CHECK_NEAR(fm_tool_part_eval(&t.flutes, NULL, p), 1, 1e-15);
    CHECK(t.flutes.kind == FM_TOOL_PART_CUSTOM && t.has_shank);
    /* And from a compiled tape when the kernel compiles one. */
    fm_graph *g = fm_graph_new(0);
    double ctr[3] = {0, 0, 2};
    fm_node sph = fm_sphere(g, ctr, 2);
    fm_tape *tape = sph != FM_NONE ? fm_tape_compile(g, sph, &err) : NULL;
    if (tape) {
        fm_tool_custom tc;
        CHECK(fm_tool_custom_from_tape(tape, 2, 4, &tc, &err) == FM_OK);
        fm_tape_free(tape); /* the part keeps its own table */
        fm_tool tt;
        CHECK(fm_tool_build_custom(&s, &tc, &tt, &err) == FM_OK);
        void *w = fm_tool_part_worker_new(&tt.flutes);
        /* The table (cells of 4 / 512 mm) interpolates the sphere's distance:
         * bilinear error at most h^2 / 4 times its second derivatives (<= 1 /
         * distance from the centre, 1.22 here) = 2e-5 mm. */
        double q[3] = {0.5, 0.5, 1};
        CHECK_NEAR(fm_tool_part_eval(&tt.flutes, w, q), 2 - sqrt(0.5 + 1), 2e-5);
        /* Intervals enclose the table's values over boxes of every size. */
        const double rs[4][2] = {{0, 3}, {0.3, 0.31}, {1.9, 2.5}, {0, 0.001}};
        const double zs[4][2] = {{-1, 5}, {1.0, 1.01}, {3.9, 4.2}, {0, 4}};
        for (int b = 0; b < 4; b++) {
            fm_interval ri = {rs[b][0], rs[b][1]}, zi = {zs[b][0], zs[b][1]};
            fm_interval iv = fm_tool_profile_interval(&tt.flutes, w, ri, zi);
            int ok = 1;
            for (int a = 0; a <= 40; a++)
                for (int k = 0; k <= 40; k++) {
                    double v = fm_tool_profile_eval(&tt.flutes, w, ri.lo + (ri.hi - ri.lo) * a / 40,
                                                    zi.lo + (zi.hi - zi.lo) * k / 40, NULL);
                    ok &= v >= iv.lo && v <= iv.hi;
                }
            CHECK(ok);
        }
        /* Outside the bound: minus the distance to it, and a box wholly
         * outside is bounded by minus its distance (a search below the tool
         * must be able to finish). */
        CHECK_NEAR(fm_tool_profile_eval(&tt.flutes, w, 5, 2, NULL), -3, 1e-12);
        fm_interval out_r = {2.5, 3}, out_z = {1, 2}, below_r = {0, 1}, below_z = {-0.7, -0.5};
        CHECK(fm_tool_profile_interval(&tt.flutes, w, out_r, out_z).hi <= -0.5 + 1e-9);
        CHECK(fm_tool_profile_interval(&tt.flutes, w, below_r, below_z).hi <= -0.5 + 1e-9);
        fm_tool_part_worker_free(&tt.flutes, w);
        fm_tool_custom_release(&tc);
    } else {
        printf("custom cutter from a tape: kernel cannot compile yet, skipped\n");
    }
    fm_graph_free(g);
}

/* The direct formulas for a flat end mill (plain cylinder) and a ball end
 * mill (below z_hi - R) against the element search they stand in for (the
 * same part with the flag cleared), values and gradients, including points
 * on faces, edges and the axis. */
static void check_direct_formulas(void)
{
    fm_tool_shape shapes[2] = {FM_TOOL_FLAT, FM_TOOL_BALL};
    for (int k = 0; k < 2; k++) {
        fm_tool_spec spec;
        memset(&spec, 0, sizeof spec);
        spec.number = 1;
        spec.shape = shapes[k];
        spec.diameter = 6;
        spec.flute_length = 12;
        spec.length = 30;
        fm_tool t;
        CHECK(fm_tool_build(&spec, &t, NULL) == FM_OK);
        fm_tool_part fast = t.flutes, slow = t.flutes;
        if (k == 0) {
            CHECK_NEAR(fast.cylinder_radius, 3, 0);
            slow.cylinder_radius = 0;
        } else {
            CHECK_NEAR(fast.ball_radius, 3, 0);
            CHECK(fast.cylinder_radius == 0);
            slow.ball_radius = 0;
        }
        for (int i = 0; i < 20000; i++) {
            double r = test_uniform(0, 6), z = test_uniform(-3, 15);
            if (i % 5 == 0) r = (i / 5) % 3 == 0 ? 0 : 3;            /* axis, side */
            if (i % 7 == 0) z = (i / 7) % 2 ? 0 : 12;                /* bottom, top */
            double gf[2], gs[2];
            double vf = fm_tool_profile_eval(&fast, NULL, r, z, gf);
            double vs = fm_tool_profile_eval(&slow, NULL, r, z, gs);
            CHECK_NEAR(vf, vs, 1e-12);
            CHECK_NEAR(fm_tool_profile_eval(&fast, NULL, r, z, NULL), vf, 0);
            /* Away from ties between faces the gradient is unique. */
            double ds = fabs(3 - r), db = fabs(z), dt = fabs(12 - z);
            int tie = fabs(ds - db) < 1e-6 || fabs(ds - dt) < 1e-6 || fabs(db - dt) < 1e-6 || vf == 0 ||
                      (k == 1 && fabs(z - 3) < 1e-6);
            if (!tie) {
                CHECK_NEAR(gf[0], gs[0], 1e-9);
                CHECK_NEAR(gf[1], gs[1], 1e-9);
            }
        }
    }
}

int main(void)
{
    check_shapes();
    check_direct_formulas();
    check_validation();
    check_dag_interval_grad();
    check_custom();
    return test_summary("tools");
}
