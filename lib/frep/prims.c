/* prims.c: the primitives of frep.h as DAG builders (half-space, sphere,
 * ellipsoid, block, cylinder, cone, torus, superellipsoid, blobby and soft
 * objects, voxel grids) and the trilinear voxel sampler. Every primitive is
 * positive inside and normalized to at least first order; docs/frep.md
 * says which are exact distances and which formula each uses. */
#include "frep/ops_internal.h"

#include <stdlib.h>
#include <string.h>

static fm_node k(fm_graph *g, double v) { return fm_const(g, v); }

static fm_node scale(fm_graph *g, double c, fm_node a)
{
    if (c == 0.0) return k(g, 0.0);
    return fm_mul(g, k(g, c), a);
}

static int finite3(const double v[3])
{
    return v && isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static int usable(fm_graph *g) { return g && !g->failed; }

/* e . (X - o), skipping zero components so that axis-aligned frames stay
 * small. */
static fm_node dot_from(fm_graph *g, const double e[3], const double o[3])
{
    fm_node sum = k(g, -(e[0] * o[0] + e[1] * o[1] + e[2] * o[2]));
    for (int i = 0; i < 3; i++)
        if (e[i] != 0.0) sum = fm_add(g, sum, scale(g, e[i], fm_var(g, i)));
    return sum;
}

/* The length of a direction by hypot, which scales before squaring: the sum
 * of squares overflows above 1.3e154 and vanishes below 1e-154, which
 * refused directions like (1e200, 0, 0) or (1e-200, 0, 0). */
static double length3(const double a[3])
{
    return hypot(hypot(a[0], a[1]), a[2]);
}

/* Unit axis from a direction; 0 if it has no length. */
static int unit_axis(const double axis[3], double u[3])
{
    if (!finite3(axis)) return 0;
    double len = length3(axis);
    if (!(len > 0.0) || !isfinite(len)) return 0;
    for (int i = 0; i < 3; i++) u[i] = axis[i] / len;
    return 1;
}

/* Local coordinates about an axis: along = (X - o) . u and the two
 * coordinates across it in an orthonormal basis {e1, e2, u} (Duff et al.
 * 2017, "Building an orthonormal basis, revisited"), which for the
 * coordinate axes gives the other two coordinate axes exactly. */
static void axis_frame(fm_graph *g, const double o[3], const double u[3], fm_node *across1,
                       fm_node *across2, fm_node *along)
{
    double sign = u[2] >= 0.0 ? 1.0 : -1.0;
    double a = -1.0 / (sign + u[2]);
    double b = u[0] * u[1] * a;
    double e1[3] = {1.0 + sign * u[0] * u[0] * a, sign * b, -sign * u[0]};
    double e2[3] = {b, sign + u[1] * u[1] * a, -u[1]};
    *across1 = dot_from(g, e1, o);
    *across2 = dot_from(g, e2, o);
    *along = dot_from(g, u, o);
}

static fm_node radial(fm_graph *g, fm_node l1, fm_node l2)
{
    return fm_sqrt(g, fm_add(g, fm_square(g, l1), fm_square(g, l2)));
}

static fm_node pos(fm_graph *g, fm_node a) { return fm_max(g, a, k(g, 0.0)); }

/* ---------------------------------------------------------- analytic -- */

fm_node fm_halfspace(fm_graph *g, const double n[3], double d)
{
    if (!usable(g)) return FM_NONE;
    double u[3];
    if (!unit_axis(n, u) || !isfinite(d))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "half-space: the normal must be finite and non-zero, d finite");
    double len = length3(n);
    double origin[3] = {0.0, 0.0, 0.0};
    return fm_sub(g, k(g, d / len), dot_from(g, u, origin));
}

static fm_node dist_to_point(fm_graph *g, const double c[3])
{
    fm_node sum = k(g, 0.0);
    for (int i = 0; i < 3; i++) sum = fm_add(g, sum, fm_square(g, fm_sub(g, fm_var(g, i), k(g, c[i]))));
    return fm_sqrt(g, sum);
}

fm_node fm_sphere(fm_graph *g, const double c[3], double r)
{
    if (!usable(g)) return FM_NONE;
    if (!finite3(c)) return fm_graph_fail(g, FM_ERR_INPUT, "sphere: the centre must be finite");
    if (!(r > 0.0) || !isfinite(r))
        return fm_graph_fail(g, FM_ERR_INPUT, "sphere: radius %g must be a finite number > 0", r);
    return fm_sub(g, k(g, r), dist_to_point(g, c));
}

fm_node fm_ellipsoid(fm_graph *g, const double c[3], const double radii[3])
{
    if (!usable(g)) return FM_NONE;
    if (!finite3(c) || !finite3(radii) || !(radii[0] > 0.0) || !(radii[1] > 0.0) ||
        !(radii[2] > 0.0))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "ellipsoid: the centre must be finite and the radii finite numbers > 0");
    /* k0 = |q|, k1 = |q / r| with q = (X - c) / r; f = k0 (1 - k0) / k1 has
     * |grad f| = 1 on k0 = 1 (first order). At the centre k1 = 0: there the
     * value is the smallest radius, the distance from the centre. */
    fm_node s0 = k(g, 0.0), s1 = k(g, 0.0);
    double rmin = radii[0];
    for (int i = 0; i < 3; i++) {
        fm_node q = scale(g, 1.0 / radii[i], fm_sub(g, fm_var(g, i), k(g, c[i])));
        s0 = fm_add(g, s0, fm_square(g, q));
        s1 = fm_add(g, s1, fm_square(g, scale(g, 1.0 / radii[i], q)));
        if (radii[i] < rmin) rmin = radii[i];
    }
    fm_node k0 = fm_sqrt(g, s0), k1 = fm_sqrt(g, s1);
    fm_node value = fm_div(g, fm_mul(g, k0, fm_sub(g, k(g, 1.0), k0)), k1);
    return fm_select(g, fm_binary(g, FM_OP_LT, k(g, 0.0), k1), value, k(g, rmin));
}

fm_node fm_block(fm_graph *g, const double lo[3], const double hi[3])
{
    if (!usable(g)) return FM_NONE;
    if (!finite3(lo) || !finite3(hi) || !(lo[0] < hi[0]) || !(lo[1] < hi[1]) || !(lo[2] < hi[2]))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "block: corners must be finite with lo < hi on every axis");
    /* q = |X - centre| - half size; distance outside |max(q, 0)|, inside
     * max_i q_i (<= 0); positive inside, so the sum is negated. */
    fm_node q[3], outside = k(g, 0.0);
    for (int i = 0; i < 3; i++) {
        double centre = 0.5 * (lo[i] + hi[i]), half = 0.5 * (hi[i] - lo[i]);
        q[i] = fm_sub(g, fm_abs(g, fm_sub(g, fm_var(g, i), k(g, centre))), k(g, half));
        outside = fm_add(g, outside, fm_square(g, pos(g, q[i])));
    }
    fm_node inside = fm_min(g, fm_max(g, fm_max(g, q[0], q[1]), q[2]), k(g, 0.0));
    return fm_neg(g, fm_add(g, fm_sqrt(g, outside), inside));
}

fm_node fm_cylinder(fm_graph *g, const double base[3], const double axis[3], double r, double h)
{
    if (!usable(g)) return FM_NONE;
    double u[3];
    if (!finite3(base)) return fm_graph_fail(g, FM_ERR_INPUT, "cylinder: the base must be finite");
    if (!unit_axis(axis, u))
        return fm_graph_fail(g, FM_ERR_INPUT, "cylinder: the axis must be finite and non-zero");
    if (!(r > 0.0) || !isfinite(r) || !(h > 0.0) || !isfinite(h))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "cylinder: radius %g and height %g must be finite numbers > 0", r, h);
    fm_node l1, l2, along;
    axis_frame(g, base, u, &l1, &l2, &along);
    /* The 2D box distance in (radius, height) about (r, h / 2). */
    fm_node dr = fm_sub(g, radial(g, l1, l2), k(g, r));
    fm_node dh = fm_sub(g, fm_abs(g, fm_sub(g, along, k(g, 0.5 * h))), k(g, 0.5 * h));
    fm_node outside = fm_sqrt(g, fm_add(g, fm_square(g, pos(g, dr)), fm_square(g, pos(g, dh))));
    fm_node inside = fm_min(g, fm_max(g, dr, dh), k(g, 0.0));
    return fm_neg(g, fm_add(g, outside, inside));
}

fm_node fm_cone(fm_graph *g, const double base[3], const double axis[3], double r0, double r1,
                double h)
{
    if (!usable(g)) return FM_NONE;
    double u[3];
    if (!finite3(base)) return fm_graph_fail(g, FM_ERR_INPUT, "cone: the base must be finite");
    if (!unit_axis(axis, u))
        return fm_graph_fail(g, FM_ERR_INPUT, "cone: the axis must be finite and non-zero");
    if (!(r0 >= 0.0) || !(r1 >= 0.0) || !isfinite(r0) || !isfinite(r1) || !(r0 > 0.0 || r1 > 0.0))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "cone: radii %g and %g must be finite, >= 0 and not both 0", r0, r1);
    if (!(h > 0.0) || !isfinite(h))
        return fm_graph_fail(g, FM_ERR_INPUT, "cone: height %g must be a finite number > 0", h);
    fm_node l1, l2, a;
    axis_frame(g, base, u, &l1, &l2, &a);
    fm_node rho = radial(g, l1, l2);
    /* The section is the trapezoid (0,0) (r0,0) (r1,h) (0,h) in the
     * (radius, height) half-plane; the boundary of the solid is its bottom,
     * slanted and top edges (not the axis). Distance = the nearest of the
     * three segments; the sign says whether the point is in the trapezoid. */
    fm_node bottom = fm_add(g, fm_square(g, pos(g, fm_sub(g, rho, k(g, r0)))), fm_square(g, a));
    fm_node top = fm_add(g, fm_square(g, pos(g, fm_sub(g, rho, k(g, r1)))),
                         fm_square(g, fm_sub(g, a, k(g, h))));
    double er = r1 - r0, len2 = er * er + h * h;
    fm_node rr = fm_sub(g, rho, k(g, r0));
    fm_node t = fm_div(g, fm_add(g, scale(g, er, rr), scale(g, h, a)), k(g, len2));
    t = fm_min(g, fm_max(g, t, k(g, 0.0)), k(g, 1.0));
    fm_node side = fm_add(g, fm_square(g, fm_sub(g, rr, scale(g, er, t))),
                          fm_square(g, fm_sub(g, a, scale(g, h, t))));
    fm_node dist = fm_sqrt(g, fm_min(g, fm_min(g, bottom, top), side));
    /* Inside the slanted edge: r0 + er a / h - rho >= 0. */
    fm_node slant = fm_sub(g, fm_add(g, k(g, r0), scale(g, er / h, a)), rho);
    fm_node in = fm_min(g, fm_min(g, a, fm_sub(g, k(g, h), a)), slant);
    return fm_select(g, fm_binary(g, FM_OP_LT, in, k(g, 0.0)), fm_neg(g, dist), dist);
}

/* r - sqrt((sqrt(l1^2 + l2^2) - R)^2 + along^2): the torus in its local
 * frame (l1, l2 across the axis, along it). */
static fm_node torus_local(fm_graph *g, fm_node l1, fm_node l2, fm_node along, fm_node R,
                           fm_node r)
{
    fm_node tube = fm_sqrt(g, fm_add(g, fm_square(g, fm_sub(g, radial(g, l1, l2), R)),
                                     fm_square(g, along)));
    return fm_sub(g, r, tube);
}

fm_node fm_torus(fm_graph *g, const double c[3], const double axis[3], double R, double r)
{
    if (!usable(g)) return FM_NONE;
    double u[3];
    if (!finite3(c)) return fm_graph_fail(g, FM_ERR_INPUT, "torus: the centre must be finite");
    if (!unit_axis(axis, u))
        return fm_graph_fail(g, FM_ERR_INPUT, "torus: the axis must be finite and non-zero");
    if (!(R > 0.0) || !(r > 0.0) || !isfinite(R) || !isfinite(r))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "torus: radii R = %g and r = %g must be finite numbers > 0", R, r);
    fm_node l1, l2, along;
    axis_frame(g, c, u, &l1, &l2, &along);
    return torus_local(g, l1, l2, along, k(g, R), k(g, r));
}

fm_node fm_torus_expr(fm_graph *g, const fm_node p[3], const fm_node c[3], int axis, fm_node R,
                      fm_node r)
{
    if (!usable(g)) return FM_NONE;
    if (!p || !c) return fm_graph_fail(g, FM_ERR_INPUT, "torus: no point or centre given");
    if (axis < 0 || axis > 2)
        return fm_graph_fail(g, FM_ERR_INPUT, "torus: axis %d is not 0 (x), 1 (y) or 2 (z)", axis);
    for (int i = 0; i < 3; i++)
        if (p[i] == FM_NONE || c[i] == FM_NONE)
            return fm_graph_fail(g, FM_ERR_INPUT, "torus: a coordinate or the centre is missing");
    if (R == FM_NONE || r == FM_NONE)
        return fm_graph_fail(g, FM_ERR_INPUT, "torus: a radius is missing");
    fm_node l1 = fm_sub(g, p[(axis + 1) % 3], c[(axis + 1) % 3]);
    fm_node l2 = fm_sub(g, p[(axis + 2) % 3], c[(axis + 2) % 3]);
    return torus_local(g, l1, l2, fm_sub(g, p[axis], c[axis]), R, r);
}

/* w / sqrt(w^2 + |grad w|^2) (Shapiro eq. 4.9) with the gradient given as
 * nodes. */
static fm_node normalize_49(fm_graph *g, fm_node w, const fm_node grad[3])
{
    fm_node sum = fm_square(g, w);
    for (int i = 0; i < 3; i++) sum = fm_add(g, sum, fm_square(g, grad[i]));
    return fm_div(g, w, fm_sqrt(g, sum));
}

/* |a|^e and its derivative factor |a|^(e-1) sign(a); where e - 1 < 0 the
 * base is kept away from 0 so that 0^negative never appears (the sign
 * factor then makes the product 0 exactly at a = 0). */
#define FM_SUPER_GUARD 1e-12

fm_node fm_superellipsoid(fm_graph *g, const double c[3], const double radii[3], double e1,
                          double e2)
{
    if (!usable(g)) return FM_NONE;
    if (!finite3(c) || !finite3(radii) || !(radii[0] > 0.0) || !(radii[1] > 0.0) ||
        !(radii[2] > 0.0))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "superellipsoid: the centre must be finite and the radii finite numbers > 0");
    if (!(e1 >= 0.1 && e1 <= 10.0) || !(e2 >= 0.1 && e2 <= 10.0))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "superellipsoid: exponents e1 = %g, e2 = %g must be in [0.1, 10]", e1, e2);
    fm_node q[3], aq[3];
    for (int i = 0; i < 3; i++) {
        q[i] = scale(g, 1.0 / radii[i], fm_sub(g, fm_var(g, i), k(g, c[i])));
        aq[i] = fm_abs(g, q[i]);
    }
    double pxy = 2.0 / e2, pz = 2.0 / e1, outer = e2 / e1;
    fm_node pw[3] = {fm_binary(g, FM_OP_POW, aq[0], k(g, pxy)),
                     fm_binary(g, FM_OP_POW, aq[1], k(g, pxy)),
                     fm_binary(g, FM_OP_POW, aq[2], k(g, pz))};
    fm_node uxy = fm_add(g, pw[0], pw[1]);
    fm_node s = fm_add(g, fm_binary(g, FM_OP_POW, uxy, k(g, outer)), pw[2]);
    fm_node w = fm_sub(g, k(g, 1.0), s);
    /* dS/dx = (2/e1) u^(e2/e1 - 1) |qx|^(2/e2 - 1) sign(qx) / a, likewise
     * y; dS/dz = (2/e1) |qz|^(2/e1 - 1) sign(qz) / c. grad w = -grad S. */
    fm_node ub = outer - 1.0 < 0.0 ? fm_max(g, uxy, k(g, FM_SUPER_GUARD)) : uxy;
    fm_node ufac = fm_binary(g, FM_OP_POW, ub, k(g, outer - 1.0));
    fm_node grad[3];
    for (int i = 0; i < 3; i++) {
        double p = i < 2 ? pxy : pz;
        fm_node base = p - 1.0 < 0.0 ? fm_max(g, aq[i], k(g, FM_SUPER_GUARD)) : aq[i];
        fm_node d = fm_mul(g, fm_binary(g, FM_OP_POW, base, k(g, p - 1.0)),
                           fm_unary(g, FM_OP_SIGN, q[i]));
        if (i < 2) d = fm_mul(g, d, ufac);
        grad[i] = scale(g, -(2.0 / e1) / radii[i], d);
    }
    return normalize_49(g, w, grad);
}

fm_node fm_blobby(fm_graph *g, size_t n, const double *centers, const double *a, const double *b,
                  double threshold)
{
    if (!usable(g)) return FM_NONE;
    if (n == 0 || !centers || !a || !b)
        return fm_graph_fail(g, FM_ERR_INPUT, "blobby: needs at least one blob with centre, a and b");
    if (!isfinite(threshold))
        return fm_graph_fail(g, FM_ERR_INPUT, "blobby: threshold %g must be finite", threshold);
    for (size_t i = 0; i < n; i++)
        if (!finite3(centers + 3 * i) || !(a[i] > 0.0) || !isfinite(a[i]) || !isfinite(b[i]))
            return fm_graph_fail(g, FM_ERR_INPUT,
                                 "blobby: blob %zu needs a finite centre, a > 0 (got %g) and finite b",
                                 i, a[i]);
    /* w = sum b_i exp(-a_i r_i^2) - T, grad w = sum -2 a_i b_i exp(.) (X - c_i). */
    fm_node w = k(g, -threshold);
    fm_node grad[3] = {k(g, 0.0), k(g, 0.0), k(g, 0.0)};
    for (size_t i = 0; i < n; i++) {
        const double *c = centers + 3 * i;
        fm_node d[3], r2 = k(g, 0.0);
        for (int j = 0; j < 3; j++) {
            d[j] = fm_sub(g, fm_var(g, j), k(g, c[j]));
            r2 = fm_add(g, r2, fm_square(g, d[j]));
        }
        fm_node e = fm_unary(g, FM_OP_EXP, scale(g, -a[i], r2));
        w = fm_add(g, w, scale(g, b[i], e));
        fm_node coef = scale(g, -2.0 * a[i] * b[i], e);
        for (int j = 0; j < 3; j++) grad[j] = fm_add(g, grad[j], fm_mul(g, coef, d[j]));
    }
    return normalize_49(g, w, grad);
}

fm_node fm_soft(fm_graph *g, size_t n, const double *centers, const double *radii, double threshold)
{
    if (!usable(g)) return FM_NONE;
    if (n == 0 || !centers || !radii)
        return fm_graph_fail(g, FM_ERR_INPUT, "soft object: needs at least one centre and radius");
    if (!(threshold > 0.0) || !isfinite(threshold))
        return fm_graph_fail(g, FM_ERR_INPUT, "soft object: threshold %g must be a finite number > 0",
                             threshold);
    for (size_t i = 0; i < n; i++)
        if (!finite3(centers + 3 * i) || !(radii[i] > 0.0) || !isfinite(radii[i]))
            return fm_graph_fail(g, FM_ERR_INPUT,
                                 "soft object: centre %zu must be finite and its radius (%g) > 0", i,
                                 radii[i]);
    /* With q = min(r^2 / R^2, 1): C = 1 - 4/9 q^3 + 17/9 q^2 - 22/9 q, which is
     * Wyvill's C(s) for s < 1 and 0 beyond (C(1) = C'(1) = 0), and
     * grad C = C'(q) 2 (X - c) / R^2 (C'(1) = 0 too, so the clamp is exact). */
    fm_node w = k(g, -threshold);
    fm_node grad[3] = {k(g, 0.0), k(g, 0.0), k(g, 0.0)};
    for (size_t i = 0; i < n; i++) {
        const double *c = centers + 3 * i;
        double inv_r2 = 1.0 / (radii[i] * radii[i]);
        fm_node d[3], r2 = k(g, 0.0);
        for (int j = 0; j < 3; j++) {
            d[j] = fm_sub(g, fm_var(g, j), k(g, c[j]));
            r2 = fm_add(g, r2, fm_square(g, d[j]));
        }
        fm_node q = fm_min(g, scale(g, inv_r2, r2), k(g, 1.0));
        fm_node q2 = fm_square(g, q);
        fm_node value = fm_add(g, fm_add(g, k(g, 1.0), scale(g, -4.0 / 9.0, fm_mul(g, q2, q))),
                               fm_add(g, scale(g, 17.0 / 9.0, q2), scale(g, -22.0 / 9.0, q)));
        w = fm_add(g, w, value);
        fm_node dc = fm_add(g, fm_add(g, scale(g, -12.0 / 9.0, q2), scale(g, 34.0 / 9.0, q)),
                            k(g, -22.0 / 9.0));
        fm_node coef = scale(g, 2.0 * inv_r2, dc);
        for (int j = 0; j < 3; j++) grad[j] = fm_add(g, grad[j], fm_mul(g, coef, d[j]));
    }
    return normalize_49(g, w, grad);
}

/* ------------------------------------------------------------ voxels -- */

fm_node fm_voxels(fm_graph *g, const double lo[3], const double hi[3], size_t nx, size_t ny,
                  size_t nz, const float *values)
{
    if (!usable(g)) return FM_NONE;
    if (!finite3(lo) || !finite3(hi) || !(lo[0] < hi[0]) || !(lo[1] < hi[1]) || !(lo[2] < hi[2]))
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "voxels: the grid box must be finite with lo < hi on every axis");
    if (nx < 2 || ny < 2 || nz < 2)
        return fm_graph_fail(g, FM_ERR_INPUT,
                             "voxels: %zu x %zu x %zu samples: need at least 2 along every axis", nx,
                             ny, nz);
    if (!values) return fm_graph_fail(g, FM_ERR_INPUT, "voxels: no sample values given");
    size_t count, bytes;
    if (!fm_size_mul(nx, ny, &count) || !fm_size_mul(count, nz, &count) ||
        count > FM_VOXELS_MAX_SAMPLES || !fm_size_mul(count, sizeof(float), &bytes))
        return fm_graph_fail(g, FM_ERR_LIMIT,
                             "voxels: %zu x %zu x %zu samples exceed the budget of %zu samples", nx,
                             ny, nz, FM_VOXELS_MAX_SAMPLES);
    for (size_t i = 0; i < count; i++)
        if (!isfinite(values[i]))
            return fm_graph_fail(g, FM_ERR_INPUT, "voxels: sample %zu is not a finite number", i);
    float *copy = malloc(bytes);
    fm_voxel_grid *grids = copy ? realloc(g->grids, (g->grid_count + 1) * sizeof *grids) : NULL;
    if (!grids) {
        free(copy);
        return fm_graph_fail(g, FM_ERR_LIMIT, "voxels: out of memory copying %zu samples", count);
    }
    memcpy(copy, values, bytes);
    g->grids = grids;
    fm_voxel_grid *grid = &g->grids[g->grid_count];
    for (int i = 0; i < 3; i++) {
        grid->lo[i] = lo[i];
        grid->hi[i] = hi[i];
    }
    grid->n[0] = nx;
    grid->n[1] = ny;
    grid->n[2] = nz;
    grid->values = copy;
    fm_node_rec r = {0};
    r.op = FM_OP_VOXELS;
    r.aux = (uint32_t)g->grid_count;
    g->grid_count++;
    /* The sample point (see ops_internal.h): plain x, y, z until remapped. */
    r.a = fm_var(g, FM_X);
    r.b = fm_var(g, FM_Y);
    r.c = fm_var(g, FM_Z);
    return fm_graph_intern(g, &r);
}

double fm_voxel_sample(const fm_voxel_grid *grid, double x, double y, double z)
{
    double p[3] = {x, y, z}, frac[3], outside2 = 0.0;
    size_t cell[3];
    for (int i = 0; i < 3; i++) {
        double v = p[i];
        if (isnan(v)) return NAN;
        /* Outside the box: the value at the nearest point of the box minus
         * the distance to it, so the field keeps falling at slope 1. */
        if (v < grid->lo[i]) v = grid->lo[i];
        if (v > grid->hi[i]) v = grid->hi[i];
        if (v != p[i]) outside2 += (p[i] - v) * (p[i] - v);
        double cells = (double)(grid->n[i] - 1);
        double s = (v - grid->lo[i]) / (grid->hi[i] - grid->lo[i]) * cells;
        double f = floor(s);
        if (f > cells - 1.0) f = cells - 1.0;
        if (f < 0.0) f = 0.0;
        cell[i] = (size_t)f;
        frac[i] = s - f;
    }
    size_t nx = grid->n[0], nxy = grid->n[0] * grid->n[1];
    const float *base = grid->values + cell[0] + nx * cell[1] + nxy * cell[2];
    double value = 0.0;
    for (int corner = 0; corner < 8; corner++) {
        int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
        double weight = (dx ? frac[0] : 1.0 - frac[0]) * (dy ? frac[1] : 1.0 - frac[1]) *
                        (dz ? frac[2] : 1.0 - frac[2]);
        value += weight * (double)base[dx + nx * (size_t)dy + nxy * (size_t)dz];
    }
    return value - sqrt(outside2);
}
