/* library.c: HyperFun's standard library (primitives, operations,
 * coordinate transforms, distance variants) under HyperFun's names and
 * argument orders, built as frep nodes from plain arithmetic with the
 * formulas of the HyperFun library (docs/hf.md lists them). Transforms
 * change the coordinate array in place and return 1, as in HyperFun. */
#include "hf/hf_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* HyperFun's EPS (interpreter and library). */
#define HF_EPS 1e-6

typedef hf_lib_ctx ctx_t;

static fm_node K(ctx_t *c, double v) { return fm_const(c->g, v); }
static fm_node add(ctx_t *c, fm_node a, fm_node b) { return fm_add(c->g, a, b); }
static fm_node sub(ctx_t *c, fm_node a, fm_node b) { return fm_sub(c->g, a, b); }
static fm_node mul(ctx_t *c, fm_node a, fm_node b) { return fm_mul(c->g, a, b); }
static fm_node dvd(ctx_t *c, fm_node a, fm_node b) { return fm_div(c->g, a, b); }
static fm_node sq(ctx_t *c, fm_node a) { return fm_square(c->g, a); }
static fm_node rt(ctx_t *c, fm_node a) { return fm_sqrt(c->g, a); }
static fm_node un(ctx_t *c, fm_op op, fm_node a) { return fm_unary(c->g, op, a); }
static fm_node bin(ctx_t *c, fm_op op, fm_node a, fm_node b) { return fm_binary(c->g, op, a, b); }

static fm_node bad(ctx_t *c, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static fm_node bad(ctx_t *c, const char *fmt, ...)
{
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    snprintf(c->message, sizeof c->message, "%s: %s", c->fname, msg);
    return FM_NONE;
}

/* Reject a constant argument equal to zero (HyperFun returns a sentinel
 * value there; a compile-time error is more useful). */
static int nonzero(ctx_t *c, fm_node v, const char *what)
{
    double k;
    if (fm_node_is_const(c->g, v, &k) && fabs(k) < HF_EPS) {
        bad(c, "%s must not be zero", what);
        return 0;
    }
    return 1;
}

/* x[i] - center[i] */
static fm_node d(ctx_t *c, hf_value *args, int i)
{
    return sub(c, args[0].elems[i], args[1].elems[i]);
}

/* The three axes with `axis` first, the others in increasing order. */
static void axes(int axis, int *u, int *v)
{
    *u = axis == 0 ? 1 : 0;
    *v = axis == 2 ? 1 : 2;
}

/* --------------------------------------------------------- primitives -- */

/* hfSphere(x, center, R) = R^2 - |x - center|^2 */
static fm_node lib_sphere(ctx_t *c, hf_value *a)
{
    fm_node f = sq(c, a[2].scalar);
    for (int i = 0; i < 3; i++) f = sub(c, f, sq(c, d(c, a, i)));
    return f;
}

/* hfEllipsoid(x, center, a, b, c) = 1 - sum ((x_i - c_i) / r_i)^2 */
static fm_node lib_ellipsoid(ctx_t *c, hf_value *a)
{
    fm_node f = K(c, 1.0);
    for (int i = 0; i < 3; i++) {
        if (!nonzero(c, a[2 + i].scalar, "the half-axes")) return FM_NONE;
        f = sub(c, f, sq(c, dvd(c, d(c, a, i), a[2 + i].scalar)));
    }
    return f;
}

/* hfCylinderX(x, center, R) = R^2 - (y - cy)^2 - (z - cz)^2 (and Y, Z) */
static fm_node cylinder(ctx_t *c, hf_value *a, int axis)
{
    int u, v;
    axes(axis, &u, &v);
    return sub(c, sub(c, sq(c, a[2].scalar), sq(c, d(c, a, u))), sq(c, d(c, a, v)));
}
static fm_node lib_cyl_x(ctx_t *c, hf_value *a) { return cylinder(c, a, 0); }
static fm_node lib_cyl_y(ctx_t *c, hf_value *a) { return cylinder(c, a, 1); }
static fm_node lib_cyl_z(ctx_t *c, hf_value *a) { return cylinder(c, a, 2); }

/* hfEllCylX(x, center, a, b) = 1 - ((y - cy)/a)^2 - ((z - cz)/b)^2 */
static fm_node ellcyl(ctx_t *c, hf_value *a, int axis)
{
    int u, v;
    axes(axis, &u, &v);
    if (!nonzero(c, a[2].scalar, "a") || !nonzero(c, a[3].scalar, "b")) return FM_NONE;
    return sub(c, sub(c, K(c, 1.0), sq(c, dvd(c, d(c, a, u), a[2].scalar))),
               sq(c, dvd(c, d(c, a, v), a[3].scalar)));
}
static fm_node lib_ellcyl_x(ctx_t *c, hf_value *a) { return ellcyl(c, a, 0); }
static fm_node lib_ellcyl_y(ctx_t *c, hf_value *a) { return ellcyl(c, a, 1); }
static fm_node lib_ellcyl_z(ctx_t *c, hf_value *a) { return ellcyl(c, a, 2); }

/* hfConeX(x, center, R) = (x - cx)^2 - ((y - cy)/R)^2 - ((z - cz)/R)^2:
 * a double cone with radius R at distance 1 from the apex. */
static fm_node cone(ctx_t *c, hf_value *a, int axis, fm_node ra, fm_node rb)
{
    int u, v;
    axes(axis, &u, &v);
    if (!nonzero(c, ra, "the radius") || !nonzero(c, rb, "the radius")) return FM_NONE;
    return sub(c, sub(c, sq(c, d(c, a, axis)), sq(c, dvd(c, d(c, a, u), ra))),
               sq(c, dvd(c, d(c, a, v), rb)));
}
static fm_node lib_cone_x(ctx_t *c, hf_value *a) { return cone(c, a, 0, a[2].scalar, a[2].scalar); }
static fm_node lib_cone_y(ctx_t *c, hf_value *a) { return cone(c, a, 1, a[2].scalar, a[2].scalar); }
static fm_node lib_cone_z(ctx_t *c, hf_value *a) { return cone(c, a, 2, a[2].scalar, a[2].scalar); }
/* hfEllConeX(x, center, a, b) = (x - cx)^2 - ((y - cy)/a)^2 - ((z - cz)/b)^2 */
static fm_node lib_ellcone_x(ctx_t *c, hf_value *a) { return cone(c, a, 0, a[2].scalar, a[3].scalar); }
static fm_node lib_ellcone_y(ctx_t *c, hf_value *a) { return cone(c, a, 1, a[2].scalar, a[3].scalar); }
static fm_node lib_ellcone_z(ctx_t *c, hf_value *a) { return cone(c, a, 2, a[2].scalar, a[3].scalar); }

/* hfTorusX(x, center, R, r0) =
 *   r0^2 - |x - c|^2 - R^2 + 2 R sqrt((y - cy)^2 + (z - cz)^2) */
static fm_node torus(ctx_t *c, hf_value *a, int axis)
{
    int u, v;
    axes(axis, &u, &v);
    fm_node R = a[2].scalar, r0 = a[3].scalar;
    fm_node ring = rt(c, add(c, sq(c, d(c, a, u)), sq(c, d(c, a, v))));
    fm_node f = sq(c, r0);
    for (int i = 0; i < 3; i++) f = sub(c, f, sq(c, d(c, a, i)));
    f = sub(c, f, sq(c, R));
    return add(c, f, mul(c, mul(c, K(c, 2.0), R), ring));
}
static fm_node lib_torus_x(ctx_t *c, hf_value *a) { return torus(c, a, 0); }
static fm_node lib_torus_y(ctx_t *c, hf_value *a) { return torus(c, a, 1); }
static fm_node lib_torus_z(ctx_t *c, hf_value *a) { return torus(c, a, 2); }

/* hfBlock(x, vertex, dx, dy, dz): the slabs s_i = (x_i - v_i)(v_i + d_i - x_i)
 * intersected with HyperFun's library formula for the current alpha:
 * min for alpha = 1, else f = s1 + s2 - sqrt(s1^2 + s2^2 - 2 alpha s1 s2)
 * and again with s3, which is (1 + alpha) times lib/frep's R_alpha
 * intersection (HyperFun's hfBlock leaves out the 1/(1+alpha) factor). */
static fm_node block_join(ctx_t *c, fm_node a, fm_node b)
{
    fm_node r = fm_r_inter(c->g, a, b, c->alpha);
    return c->alpha == 1.0 ? r : mul(c, K(c, 1.0 + c->alpha), r);
}

static fm_node lib_block(ctx_t *c, hf_value *a)
{
    fm_node s[3];
    for (int i = 0; i < 3; i++) {
        double k;
        if (fm_node_is_const(c->g, a[2 + i].scalar, &k) && k < 0)
            return bad(c, "the edge lengths must not be negative, found %g", k);
        fm_node lo = d(c, a, i);
        fm_node hi = sub(c, add(c, a[1].elems[i], a[2 + i].scalar), a[0].elems[i]);
        s[i] = mul(c, lo, hi);
    }
    return block_join(c, block_join(c, s[0], s[1]), s[2]);
}

/* hfSuperell(x, center, a, b, c, s1, s2) =
 *   1 - (|xt|^(2/s2) + |yt|^(2/s2))^(s2/s1) - |zt|^(2/s1), xt = (x - cx)/a, ... */
static fm_node lib_superell(ctx_t *c, hf_value *a)
{
    fm_node t[3];
    for (int i = 0; i < 3; i++) {
        if (!nonzero(c, a[2 + i].scalar, "the half-axes")) return FM_NONE;
        t[i] = un(c, FM_OP_ABS, dvd(c, d(c, a, i), a[2 + i].scalar));
    }
    fm_node s1 = a[5].scalar, s2 = a[6].scalar;
    if (!nonzero(c, s1, "s1") || !nonzero(c, s2, "s2")) return FM_NONE;
    fm_node p = dvd(c, K(c, 2.0), s2);
    fm_node xy = add(c, bin(c, FM_OP_POW, t[0], p), bin(c, FM_OP_POW, t[1], p));
    fm_node f = sub(c, K(c, 1.0), bin(c, FM_OP_POW, xy, dvd(c, s2, s1)));
    return sub(c, f, bin(c, FM_OP_POW, t[2], dvd(c, K(c, 2.0), s1)));
}

/* The number of key points of hfBlobby / hfMetaball / hfSoft: the length of
 * x0 (HyperFun reads every array with that length). */
static int keypoints(ctx_t *c, hf_value *a, int first, int count, size_t *n)
{
    *n = a[first].n;
    for (int i = first + 1; i < first + count; i++)
        if (a[i].n < *n)
            return bad(c, "argument %d has %zu items, fewer than the %zu of x0", i + 1, a[i].n,
                       *n) != FM_NONE;
    return 1;
}

static fm_node r2_at(ctx_t *c, hf_value *a, size_t i)
{
    fm_node f = K(c, 0.0);
    for (int k = 0; k < 3; k++) f = add(c, f, sq(c, sub(c, a[0].elems[k], a[1 + k].elems[i])));
    return f;
}

/* hfBlobby(x, x0, y0, z0, a, b, T) = sum b_i exp(-a_i r_i^2) - T (Blinn) */
static fm_node lib_blobby(ctx_t *c, hf_value *a)
{
    size_t n;
    if (!keypoints(c, a, 1, 5, &n)) return FM_NONE;
    fm_node f = K(c, 0.0);
    for (size_t i = 0; i < n; i++)
        f = add(c, f, mul(c, a[5].elems[i],
                          un(c, FM_OP_EXP, fm_neg(c->g, mul(c, a[4].elems[i], r2_at(c, a, i))))));
    return sub(c, f, a[6].scalar);
}

/* hfMetaball(x, x0, y0, z0, b, d, T) = sum m_i - T (Nishimura):
 * m = b (1 - 3 r^2/d^2) for r <= d/3, 1.5 b (1 - r/d)^2 for d/3 < r < d,
 * 0 beyond, and 0 for every r when d <= 0. */
static fm_node lib_metaball(ctx_t *c, hf_value *a)
{
    size_t n;
    if (!keypoints(c, a, 1, 5, &n)) return FM_NONE;
    fm_node f = K(c, 0.0);
    for (size_t i = 0; i < n; i++) {
        fm_node b = a[4].elems[i], dd = a[5].elems[i];
        fm_node r = rt(c, r2_at(c, a, i));
        fm_node rd = dvd(c, r, dd);
        fm_node inner = mul(c, b, sub(c, K(c, 1.0), mul(c, K(c, 3.0), sq(c, rd))));
        fm_node outer = mul(c, mul(c, K(c, 1.5), b), sq(c, sub(c, K(c, 1.0), rd)));
        fm_node m = fm_select(c->g, bin(c, FM_OP_LE, r, dvd(c, dd, K(c, 3.0))), inner,
                              fm_select(c->g, bin(c, FM_OP_LT, r, dd), outer, K(c, 0.0)));
        m = fm_select(c->g, bin(c, FM_OP_LT, K(c, 0.0), dd), m, K(c, 0.0));
        f = add(c, f, m);
    }
    return sub(c, f, a[6].scalar);
}

/* hfSoft(x, x0, y0, z0, d, T) = sum s_i - T (Wyvill):
 * s = 1 - 22 r^2/(9 d^2) + 17 r^4/(9 d^4) - 4 r^6/(9 d^6) for r <= d, else 0. */
static fm_node lib_soft(ctx_t *c, hf_value *a)
{
    size_t n;
    if (!keypoints(c, a, 1, 4, &n)) return FM_NONE;
    fm_node f = K(c, 0.0);
    for (size_t i = 0; i < n; i++) {
        fm_node dd = a[4].elems[i];
        fm_node r2 = r2_at(c, a, i), r4 = sq(c, r2);
        fm_node d2 = sq(c, dd), d4 = sq(c, d2);
        fm_node s = sub(c, K(c, 1.0), dvd(c, mul(c, K(c, 22.0), r2), mul(c, K(c, 9.0), d2)));
        s = add(c, s, dvd(c, mul(c, K(c, 17.0), r4), mul(c, K(c, 9.0), d4)));
        s = sub(c, s, dvd(c, mul(c, K(c, 4.0), mul(c, r4, r2)), mul(c, K(c, 9.0), mul(c, d4, d2))));
        f = add(c, f, fm_select(c->g, bin(c, FM_OP_LE, rt(c, r2), dd), s, K(c, 0.0)));
    }
    return sub(c, f, a[5].scalar);
}

/* ------------------------------------------------------------- blends -- */

/* hfBlendUni(f1, f2, a0, a1, a2) = f1 + f2 + sqrt(f1^2 + f2^2)
 *                                  + a0 / (1 + (f1/a1)^2 + (f2/a2)^2),
 * hfBlendInt the same with f1 + f2 - sqrt(...), plus the displacement
 * (HyperFun adds a0 for both; a negative a0 removes material): lib/frep's
 * displacement blends (Pasko eq. 6-8). */
static fm_node blend(ctx_t *c, hf_value *a, int sign)
{
    if (!nonzero(c, a[3].scalar, "a1") || !nonzero(c, a[4].scalar, "a2")) return FM_NONE;
    fm_node (*op)(fm_graph *, fm_node, fm_node, fm_node, fm_node, fm_node) =
        sign > 0 ? fm_blend_union_expr : fm_blend_inter_expr;
    return op(c->g, a[0].scalar, a[1].scalar, a[2].scalar, a[3].scalar, a[4].scalar);
}
static fm_node lib_blend_uni(ctx_t *c, hf_value *a) { return blend(c, a, 1); }
static fm_node lib_blend_int(ctx_t *c, hf_value *a) { return blend(c, a, -1); }

/* ---------------------------------------------------------- transforms -- */

/* hfShift3D(x, dx, dy, dz): x_i = x_i - d_i */
static fm_node lib_shift(ctx_t *c, hf_value *a)
{
    for (int i = 0; i < 3; i++) a[0].elems[i] = sub(c, a[0].elems[i], a[1 + i].scalar);
    return K(c, 1.0);
}

/* hfScale3D(x, sx, sy, sz): x_i = x_i / s_i */
static fm_node lib_scale(ctx_t *c, hf_value *a)
{
    for (int i = 0; i < 3; i++)
        if (!nonzero(c, a[1 + i].scalar, "the scale factors")) return FM_NONE;
    for (int i = 0; i < 3; i++) a[0].elems[i] = dvd(c, a[0].elems[i], a[1 + i].scalar);
    return K(c, 1.0);
}

/* Rotation of the coordinates about `axis` by theta as HyperFun's inverse
 * mappings write it: p' = p cos + q sin, q' = -p sin + q cos, where
 * (p, q) = (y, z) about X, (z, x) about Y and (x, y) about Z: lib/frep's
 * inverse rotation. */
static fm_node rotate(ctx_t *c, hf_value *a, int axis, fm_node theta)
{
    return fm_rotate_coords(c->g, a[0].elems, axis, theta) ? K(c, 1.0) : FM_NONE;
}

/* hfRotate3DX(x, theta) (and Y, Z) */
static fm_node lib_rot_x(ctx_t *c, hf_value *a) { return rotate(c, a, 0, a[1].scalar); }
static fm_node lib_rot_y(ctx_t *c, hf_value *a) { return rotate(c, a, 1, a[1].scalar); }
static fm_node lib_rot_z(ctx_t *c, hf_value *a) { return rotate(c, a, 2, a[1].scalar); }

/* hfTwistX(x, x1, x2, theta1, theta2): t = (x - x1)/(x2 - x1),
 * theta = (1 - t) theta1 + t theta2, then the rotation about X by theta
 * (lib/frep's twist is this rotation with theta = rate * x). */
static fm_node twist(ctx_t *c, hf_value *a, int axis)
{
    fm_node span = sub(c, a[2].scalar, a[1].scalar);
    if (!nonzero(c, span, "the interval (x2 - x1)")) return FM_NONE;
    fm_node t = dvd(c, sub(c, a[0].elems[axis], a[1].scalar), span);
    fm_node theta = add(c, mul(c, sub(c, K(c, 1.0), t), a[3].scalar), mul(c, t, a[4].scalar));
    return rotate(c, a, axis, theta);
}
static fm_node lib_twist_x(ctx_t *c, hf_value *a) { return twist(c, a, 0); }
static fm_node lib_twist_y(ctx_t *c, hf_value *a) { return twist(c, a, 1); }
static fm_node lib_twist_z(ctx_t *c, hf_value *a) { return twist(c, a, 2); }

/* hfTaperX(x, x1, x2, s1, s2): scale = s1 for x < x1, s2 for x > x2, the
 * linear blend between; |scale| < EPS counts as 1 (as HyperFun); the other
 * two coordinates are divided by scale. s1, s2 must be positive. */
static fm_node taper(ctx_t *c, hf_value *a, int axis)
{
    for (int i = 3; i <= 4; i++) {
        double k;
        if (fm_node_is_const(c->g, a[i].scalar, &k) && k <= 0)
            return bad(c, "the scale factors s1, s2 must be positive, found %g", k);
    }
    fm_node s = a[0].elems[axis], x1 = a[1].scalar, x2 = a[2].scalar;
    fm_node t = dvd(c, sub(c, s, x1), sub(c, x2, x1));
    fm_node lerp = add(c, mul(c, sub(c, K(c, 1.0), t), a[3].scalar), mul(c, t, a[4].scalar));
    fm_node scale = fm_select(c->g, bin(c, FM_OP_LT, s, x1), a[3].scalar,
                              fm_select(c->g, bin(c, FM_OP_LT, x2, s), a[4].scalar, lerp));
    scale = fm_select(c->g, bin(c, FM_OP_LT, un(c, FM_OP_ABS, scale), K(c, HF_EPS)), K(c, 1.0),
                      scale);
    int u, v;
    axes(axis, &u, &v);
    a[0].elems[u] = dvd(c, a[0].elems[u], scale);
    a[0].elems[v] = dvd(c, a[0].elems[v], scale);
    return K(c, 1.0);
}
static fm_node lib_taper_x(ctx_t *c, hf_value *a) { return taper(c, a, 0); }
static fm_node lib_taper_y(ctx_t *c, hf_value *a) { return taper(c, a, 1); }
static fm_node lib_taper_z(ctx_t *c, hf_value *a) { return taper(c, a, 2); }

/* hfStretch3D(x, x0, sx, sy, sz): x_i = x0_i + (x_i - x0_i) / s_i */
static fm_node lib_stretch(ctx_t *c, hf_value *a)
{
    for (int i = 0; i < 3; i++)
        if (!nonzero(c, a[2 + i].scalar, "the scale factors")) return FM_NONE;
    for (int i = 0; i < 3; i++)
        a[0].elems[i] = add(c, a[1].elems[i],
                            dvd(c, sub(c, a[0].elems[i], a[1].elems[i]), a[2 + i].scalar));
    return K(c, 1.0);
}

/* ---------------------------------------------------- distance variants -- */

/* hfDCylinder(x, center, u, R) = R - |u x (center - x)| / |u|: an infinite
 * cylinder about the line through center along u, exact distance. */
static fm_node lib_dcylinder(ctx_t *c, hf_value *a)
{
    fm_node *u = a[2].elems, w[3];
    for (int i = 0; i < 3; i++) w[i] = sub(c, a[1].elems[i], a[0].elems[i]);
    fm_node cx = sub(c, mul(c, u[1], w[2]), mul(c, w[1], u[2]));
    fm_node cy = sub(c, mul(c, u[2], w[0]), mul(c, u[0], w[2]));
    fm_node cz = sub(c, mul(c, u[0], w[1]), mul(c, u[1], w[0]));
    fm_node cross2 = add(c, add(c, sq(c, cx), sq(c, cy)), sq(c, cz));
    fm_node u2 = add(c, add(c, sq(c, u[0]), sq(c, u[1])), sq(c, u[2]));
    if (!nonzero(c, u2, "the axis u")) return FM_NONE;
    return sub(c, a[3].scalar, rt(c, dvd(c, cross2, u2)));
}

/* hfDConeX(x, center, R) = -(sqrt((y-cy)^2 + (z-cz)^2) cos t - |x - cx| sin t),
 * t = atan(R): the signed distance to the infinite double cone. */
static fm_node dcone(ctx_t *c, hf_value *a, int axis)
{
    int u, v;
    axes(axis, &u, &v);
    fm_node t = un(c, FM_OP_ATAN, a[2].scalar);
    fm_node ring = rt(c, add(c, sq(c, d(c, a, u)), sq(c, d(c, a, v))));
    fm_node dist = sub(c, mul(c, ring, un(c, FM_OP_COS, t)),
                       mul(c, un(c, FM_OP_ABS, d(c, a, axis)), un(c, FM_OP_SIN, t)));
    return fm_neg(c->g, dist);
}
static fm_node lib_dcone_x(ctx_t *c, hf_value *a) { return dcone(c, a, 0); }
static fm_node lib_dcone_y(ctx_t *c, hf_value *a) { return dcone(c, a, 1); }
static fm_node lib_dcone_z(ctx_t *c, hf_value *a) { return dcone(c, a, 2); }

/* hfDTorusX(x, center, R, r0) = r0 - sqrt((sqrt((y-cy)^2 + (z-cz)^2) - R)^2 + (x-cx)^2):
 * lib/frep's exact torus. */
static fm_node dtorus(ctx_t *c, hf_value *a, int axis)
{
    return fm_torus_expr(c->g, a[0].elems, a[1].elems, axis, a[2].scalar, a[3].scalar);
}
static fm_node lib_dtorus_x(ctx_t *c, hf_value *a) { return dtorus(c, a, 0); }
static fm_node lib_dtorus_y(ctx_t *c, hf_value *a) { return dtorus(c, a, 1); }
static fm_node lib_dtorus_z(ctx_t *c, hf_value *a) { return dtorus(c, a, 2); }

/* ------------------------------------------- SARDF set operations -- */

/* hfDUni, hfDInt, hfDSub: HyperFun's signed approximate real distance
 * set operations (Fayolle, Pasko, Schmitt, Mirenkov; HyperFun library
 * sardf.c, uni_sardef_1 / int_sardef_1). In the plane of the two values
 * (x, y) = (f1, f2) the level curve of value d of the union is the corner
 * of max(x, y) = d with the corner rounded:
 *   quadrant I   the arc of the circle centre (t d, t d), radius (1 - t) d,
 *                t = tan(alpha), between the rays x/y = t and x/y = 1/t;
 *                outside those rays x or y;
 *   quadrant III near the origin (level >= -R, HyperFun's "bounded" test)
 *                the circle centre (-2 s m, -2 s m), radius 2 s m - m^2,
 *                d = -m^2, s = sqrt(R), between the parabolas
 *                x = -y^2 / 4R and y = -x^2 / 4R; farther out, the circle
 *                of fixed radius R centre (d - R, d - R) in the strip
 *                |x - y| <= R; outside those, x or y;
 *   quadrants II, IV and the axes: max(x, y).
 * Intersection is the mirror image: int(x, y) = -uni(-x, -y) holds
 * branch by branch in HyperFun's code, and hfDSub(f1, f2) = hfDInt(f1, -f2)
 * as HyperFun computes it. */

/* Newton steps for the quartic branch. The branch solves
 * psi(m) = (2 s m - m^2) - |(x, y) + 2 s m (1, 1)| = 0, which HyperFun
 * expands to m^4 - 4 s m^3 - 4 R m^2 - 4 s (x + y) m - (x^2 + y^2) = 0 and
 * solves with Ferrari's formulas. psi is concave (a concave radius minus the
 * norm of an affine function) and decreasing on the branch, so Newton from
 * a point right of the root converges monotonically; measured over 10^6
 * points with |x|, |y| from 1e-8 R to 3 R, 9 steps reach the root to 4e-16
 * (HyperFun's Ferrari root is off by up to 4e-10 at small scales). */
#define SARDF_NEWTON_STEPS 10

static fm_node lt(ctx_t *c, fm_node a, fm_node b) { return bin(c, FM_OP_LT, a, b); }
static fm_node le(ctx_t *c, fm_node a, fm_node b) { return bin(c, FM_OP_LE, a, b); }
static fm_node and2(ctx_t *c, fm_node a, fm_node b) { return bin(c, FM_OP_AND, a, b); }
static fm_node or2(ctx_t *c, fm_node a, fm_node b) { return bin(c, FM_OP_OR, a, b); }
static fm_node sel(ctx_t *c, fm_node cond, fm_node a, fm_node b) { return fm_select(c->g, cond, a, b); }
/* v limited to [lo, hi]: where v is a root the limits are true bounds of,
 * the value is unchanged and the interval of the result stays within
 * [lo, hi] even where the root's own interval is unbounded. */
static fm_node clamp(ctx_t *c, fm_node v, fm_node lo, fm_node hi)
{
    return fm_min(c->g, fm_max(c->g, v, lo), hi);
}

/* Quadrant I of the union (x, y > 0), HyperFun's angle approach. The
 * circle's quadratic (t^2 + 2t - 1) d^2 - 2t (x + y) d + x^2 + y^2 = 0 is
 * solved in the conjugate form d = (x^2 + y^2) / (t (x + y) + sqrt(D)),
 * D = 2 t^2 x y + (1 - 2t)(x^2 + y^2): the same root as HyperFun's
 * (-b - sqrt(b^2 - 4ac)) / 2a, without its 0/0 at t = sqrt(2) - 1. */
static fm_node sardf_q1(ctx_t *c, fm_node x, fm_node y, fm_node t)
{
    fm_node xx_yy = add(c, sq(c, x), sq(c, y));
    fm_node disc = add(c, mul(c, K(c, 2.0), mul(c, sq(c, t), mul(c, x, y))),
                       mul(c, sub(c, K(c, 1.0), mul(c, K(c, 2.0), t)), xx_yy));
    fm_node circle = dvd(c, xx_yy, add(c, mul(c, t, add(c, x, y)), rt(c, fm_max(c->g, disc, K(c, 0.0)))));
    /* On the arc max(x, y) <= d <= x + y (the arc lies in x, y <= d and
     * its ends (d, t d), (t d, d) are its points nearest the line x + y = d). */
    circle = clamp(c, circle, fm_max(c->g, x, y), add(c, x, y));
    /* x/y >= 1/t: x; x/y <= t: y (multiplied out, y > 0) */
    return sel(c, le(c, y, mul(c, t, x)), x, sel(c, le(c, x, mul(c, t, y)), y, circle));
}

/* Quadrant III of the union (x, y < 0), HyperFun's bounded approach. */
static fm_node sardf_q3(ctx_t *c, fm_node x, fm_node y, fm_node r)
{
    fm_node s = rt(c, r), two_s = mul(c, K(c, 2.0), s);
    fm_node minus_r = fm_neg(c->g, r), minus_2r = mul(c, K(c, -2.0), r);
    fm_node lim2 = add(c, sq(c, sub(c, x, minus_2r)), sq(c, sub(c, y, minus_2r)));
    fm_node bounded = or2(c, or2(c, le(c, minus_r, x), le(c, minus_r, y)),
                          and2(c, and2(c, le(c, minus_2r, x), le(c, minus_2r, y)),
                               le(c, sq(c, r), lim2)));
    fm_node four_r = mul(c, K(c, 4.0), r);
    fm_node xx = fm_neg(c->g, dvd(c, sq(c, x), four_r)); /* the parabola y = -x^2 / 4R */
    fm_node yy = fm_neg(c->g, dvd(c, sq(c, y), four_r));
    fm_node inside_angle = and2(c, le(c, x, yy), le(c, y, xx));

    /* The root lies in [max(-x, -y) / 2s, min(s, sqrt(min(-x, -y)))]: at the
     * lower end P - C has a zero component (the parabolas are where it
     * becomes negative), at the upper end the level -m^2 is below both x and
     * y or below -R. Newton starts at the upper end, where psi <= 0. */
    fm_node neg_min = fm_neg(c->g, fm_min(c->g, x, y)), neg_max = fm_neg(c->g, fm_max(c->g, x, y));
    fm_node m_lo = dvd(c, neg_min, two_s);
    /* max(.., 0): the same value on the branch (x, y < 0), and never NaN
     * elsewhere, since a maybe-NaN operand of min/max makes its interval
     * take the other operand whole, and the Newton iterate's is unbounded. */
    fm_node m_hi = fm_min(c->g, s, rt(c, fm_max(c->g, neg_max, K(c, 0.0))));
    fm_node m = m_hi;
    for (int i = 0; i < SARDF_NEWTON_STEPS; i++) {
        fm_node shift = mul(c, two_s, m);
        fm_node px = add(c, x, shift), py = add(c, y, shift);
        fm_node dist = rt(c, add(c, sq(c, px), sq(c, py)));
        fm_node psi = sub(c, sub(c, shift, sq(c, m)), dist);
        fm_node dpsi = sub(c, sub(c, two_s, mul(c, K(c, 2.0), m)),
                           dvd(c, mul(c, two_s, add(c, px, py)), dist));
        m = sub(c, m, dvd(c, psi, dpsi));
    }
    m = clamp(c, m, m_lo, m_hi);
    fm_node angle = sel(c, inside_angle, fm_neg(c->g, sq(c, m)), sel(c, lt(c, xx, y), y, x));

    /* Fixed radius R: (x - d + R)^2 + (y - d + R)^2 = R^2, HyperFun's root
     * (-b - sqrt(b^2 - 8c)) / 4 of 2d^2 - 2(x + y + 2R) d + c = 0, which
     * simplifies to d = (x + y + 2R - sqrt(2R^2 - (x - y)^2)) / 2. */
    fm_node diff = sub(c, x, y);
    fm_node disc = sub(c, mul(c, K(c, 2.0), sq(c, r)), sq(c, diff));
    fm_node strip_d = mul(c, K(c, 0.5), sub(c, add(c, add(c, x, y), mul(c, K(c, 2.0), r)),
                                            rt(c, fm_max(c->g, disc, K(c, 0.0)))));
    fm_node strip = sel(c, lt(c, y, sub(c, x, r)), x, sel(c, lt(c, add(c, x, r), y), y, strip_d));
    return sel(c, bounded, angle, strip);
}

/* HyperFun's uni_sardef_1(f1, f2, R, alpha). HyperFun snaps |f| < 1e-7 to
 * the axis cases; those values are the limits of the neighbouring cases,
 * so the cases are taken here on the exact signs (a continuous function,
 * within 1e-7 of HyperFun's in that band). */
static fm_node sardf_union(ctx_t *c, fm_node x, fm_node y, fm_node r, fm_node alpha)
{
    fm_node zero = K(c, 0.0);
    fm_node t = un(c, FM_OP_TAN, alpha);
    fm_node q1 = and2(c, lt(c, zero, x), lt(c, zero, y));
    fm_node q3 = and2(c, lt(c, x, zero), lt(c, y, zero));
    return sel(c, q1, sardf_q1(c, x, y, t), sel(c, q3, sardf_q3(c, x, y, r), fm_max(c->g, x, y)));
}

/* R > 0 (it divides) and 0 <= alpha < pi/4 (tan alpha < 1 keeps the rays
 * x/y = tan alpha and x/y = 1/tan alpha in order) when they are constants. */
static int sardf_args(ctx_t *c, hf_value *a)
{
    double k;
    if (fm_node_is_const(c->g, a[2].scalar, &k) && !(k > 0)) {
        bad(c, "the radius R must be positive, found %g", k);
        return 0;
    }
    if (fm_node_is_const(c->g, a[3].scalar, &k) && !(k >= 0 && k < atan(1.0))) {
        bad(c, "the angle alpha must be in [0, pi/4) radians, found %g", k);
        return 0;
    }
    return 1;
}

/* hfDUni(f1, f2, R, alpha) */
static fm_node lib_duni(ctx_t *c, hf_value *a)
{
    if (!sardf_args(c, a)) return FM_NONE;
    return sardf_union(c, a[0].scalar, a[1].scalar, a[2].scalar, a[3].scalar);
}

/* hfDInt(f1, f2, R, alpha) = -uni(-f1, -f2): R bounds quadrant I, alpha
 * shapes quadrant III. */
static fm_node lib_dint(ctx_t *c, hf_value *a)
{
    if (!sardf_args(c, a)) return FM_NONE;
    fm_graph *g = c->g;
    return fm_neg(g, sardf_union(c, fm_neg(g, a[0].scalar), fm_neg(g, a[1].scalar), a[2].scalar,
                                 a[3].scalar));
}

/* hfDSub(f1, f2, R, alpha) = hfDInt(f1, -f2, R, alpha) = -uni(-f1, f2) */
static fm_node lib_dsub(ctx_t *c, hf_value *a)
{
    if (!sardf_args(c, a)) return FM_NONE;
    fm_graph *g = c->g;
    return fm_neg(g, sardf_union(c, fm_neg(g, a[0].scalar), a[1].scalar, a[2].scalar, a[3].scalar));
}

/* The table. Signatures: p a point array (read), x a point array changed in
 * place, c a 3-element array (centre, vertex, vector), a an array, r a
 * number. */
static const hf_lib_fn library[] = {
    {"hfSphere", "pcr", lib_sphere},
    {"hfEllipsoid", "pcrrr", lib_ellipsoid},
    {"hfCylinderX", "pcr", lib_cyl_x},
    {"hfCylinderY", "pcr", lib_cyl_y},
    {"hfCylinderZ", "pcr", lib_cyl_z},
    {"hfEllCylX", "pcrr", lib_ellcyl_x},
    {"hfEllCylY", "pcrr", lib_ellcyl_y},
    {"hfEllCylZ", "pcrr", lib_ellcyl_z},
    {"hfConeX", "pcr", lib_cone_x},
    {"hfConeY", "pcr", lib_cone_y},
    {"hfConeZ", "pcr", lib_cone_z},
    {"hfEllConeX", "pcrr", lib_ellcone_x},
    {"hfEllConeY", "pcrr", lib_ellcone_y},
    {"hfEllConeZ", "pcrr", lib_ellcone_z},
    {"hfTorusX", "pcrr", lib_torus_x},
    {"hfTorusY", "pcrr", lib_torus_y},
    {"hfTorusZ", "pcrr", lib_torus_z},
    {"hfBlock", "pcrrr", lib_block},
    {"hfSuperell", "pcrrrrr", lib_superell},
    {"hfBlobby", "paaaaar", lib_blobby},
    {"hfMetaball", "paaaaar", lib_metaball},
    {"hfSoft", "paaaar", lib_soft},
    {"hfBlendUni", "rrrrr", lib_blend_uni},
    {"hfBlendInt", "rrrrr", lib_blend_int},
    {"hfShift3D", "xrrr", lib_shift},
    {"hfScale3D", "xrrr", lib_scale},
    {"hfRotate3DX", "xr", lib_rot_x},
    {"hfRotate3DY", "xr", lib_rot_y},
    {"hfRotate3DZ", "xr", lib_rot_z},
    {"hfTwistX", "xrrrr", lib_twist_x},
    {"hfTwistY", "xrrrr", lib_twist_y},
    {"hfTwistZ", "xrrrr", lib_twist_z},
    {"hfTaperX", "xrrrr", lib_taper_x},
    {"hfTaperY", "xrrrr", lib_taper_y},
    {"hfTaperZ", "xrrrr", lib_taper_z},
    {"hfStretch3D", "xcrrr", lib_stretch},
    {"hfDCylinder", "pccr", lib_dcylinder},
    {"hfDConeX", "pcr", lib_dcone_x},
    {"hfDConeY", "pcr", lib_dcone_y},
    {"hfDConeZ", "pcr", lib_dcone_z},
    {"hfDTorusX", "pcrr", lib_dtorus_x},
    {"hfDTorusY", "pcrr", lib_dtorus_y},
    {"hfDTorusZ", "pcrr", lib_dtorus_z},
    {"hfDUni", "rrrr", lib_duni},
    {"hfDInt", "rrrr", lib_dint},
    {"hfDSub", "rrrr", lib_dsub},
};

#define LIBRARY_SIZE (sizeof library / sizeof library[0])

const hf_lib_fn *fm_hf_library_find(const char *lower_name)
{
    for (size_t i = 0; i < LIBRARY_SIZE; i++) {
        const char *a = library[i].name, *b = lower_name;
        while (*a && *b && (*a | 0x20) == *b) {
            a++;
            b++;
        }
        if (!*a && !*b) return &library[i];
    }
    return NULL;
}

const hf_lib_fn *fm_hf_library_at(size_t i)
{
    return i < LIBRARY_SIZE ? &library[i] : NULL;
}
