/* profile.c: tool parts as solids of revolution of an (r, z) profile chain:
 * validation of the chain, the exact 2D signed distance with its gradient,
 * sound interval bounds, and the 3D evaluators built on them. */
#include "tools/tools.h"

#include <float.h>
#include <math.h>
#include <string.h>

static double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

/* Nearest point of element e to q; returns the squared distance. */
static double elem_nearest(const fm_profile_elem *e, const double q[2], double n[2])
{
    if (e->kind == FM_PROFILE_SEGMENT) {
        double dr = e->b[0] - e->a[0], dz = e->b[1] - e->a[1];
        double len2 = dr * dr + dz * dz;
        double s = len2 > 0 ? ((q[0] - e->a[0]) * dr + (q[1] - e->a[1]) * dz) / len2 : 0;
        s = s < 0 ? 0 : s > 1 ? 1 : s;
        n[0] = e->a[0] + s * dr;
        n[1] = e->a[1] + s * dz;
    } else {
        double vr = q[0] - e->c[0], vz = q[1] - e->c[1];
        double ar = e->a[0] - e->c[0], az = e->a[1] - e->c[1];
        double br = e->b[0] - e->c[0], bz = e->b[1] - e->c[1];
        double c1 = cross2(ar, az, vr, vz), c2 = cross2(vr, vz, br, bz);
        int in = e->ccw ? (c1 >= 0 && c2 >= 0) : (c1 <= 0 && c2 <= 0);
        double vl = sqrt(vr * vr + vz * vz);
        if (in && vl > 0) {
            n[0] = e->c[0] + e->radius * vr / vl;
            n[1] = e->c[1] + e->radius * vz / vl;
        } else {
            double da = (q[0] - e->a[0]) * (q[0] - e->a[0]) + (q[1] - e->a[1]) * (q[1] - e->a[1]);
            double db = (q[0] - e->b[0]) * (q[0] - e->b[0]) + (q[1] - e->b[1]) * (q[1] - e->b[1]);
            const double *p = da <= db ? e->a : e->b;
            n[0] = p[0];
            n[1] = p[1];
        }
    }
    return (q[0] - n[0]) * (q[0] - n[0]) + (q[1] - n[1]) * (q[1] - n[1]);
}

/* The inward normal of e at its nearest point n (used when q is on the
 * boundary and the direction q - n is undefined). */
static void elem_inward_normal(const fm_profile_elem *e, const double n[2], double out[2])
{
    double tr, tz;
    if (e->kind == FM_PROFILE_SEGMENT) {
        tr = e->b[0] - e->a[0];
        tz = e->b[1] - e->a[1];
    } else {
        double vr = n[0] - e->c[0], vz = n[1] - e->c[1];
        tr = e->ccw ? -vz : vz;
        tz = e->ccw ? vr : -vr;
    }
    /* The chain runs counter-clockwise round the region: inside is on the left. */
    double l = sqrt(tr * tr + tz * tz);
    if (l > 0) {
        out[0] = -tz / l;
        out[1] = tr / l;
    } else {
        out[0] = 0;
        out[1] = 1;
    }
}

/* r of the profile at height z on element e, or -1 when e does not span z. */
static double elem_radius_at(const fm_profile_elem *e, double z)
{
    double z0 = e->a[1], z1 = e->b[1];
    if (z < z0 || z > z1) return -1;
    if (e->kind == FM_PROFILE_SEGMENT) {
        if (z1 == z0) return e->a[0] > e->b[0] ? e->a[0] : e->b[0];
        return e->a[0] + (z - z0) * (e->b[0] - e->a[0]) / (z1 - z0);
    }
    double h = e->radius * e->radius - (z - e->c[1]) * (z - e->c[1]);
    double w = h > 0 ? sqrt(h) : 0;
    double side = (e->a[0] + e->b[0]) * 0.5 - e->c[0];
    return side >= 0 ? e->c[0] + w : e->c[0] - w;
}

static int profile_inside(const fm_tool_part *part, double r, double z)
{
    if (z < part->z_lo || z > part->z_hi) return 0;
    double R = -1;
    for (size_t i = 0; i < part->count; i++) {
        double ri = elem_radius_at(&part->elem[i], z);
        if (ri > R) R = ri;
    }
    return r <= R;
}

static double profile_eval(const fm_tool_part *part, double r, double z, double grad[2])
{
    double q[2] = {r, z}, best = DBL_MAX, bn[2] = {0, 0};
    size_t bi = 0;
    for (size_t i = 0; i < part->count; i++) {
        double n[2];
        double d2 = elem_nearest(&part->elem[i], q, n);
        if (d2 < best) {
            best = d2;
            bn[0] = n[0];
            bn[1] = n[1];
            bi = i;
        }
    }
    double d = sqrt(best);
    int in = profile_inside(part, r, z);
    if (grad) {
        if (d > 1e-300) {
            /* Inside the value grows away from the nearest point, outside it
             * grows toward it. */
            double s = in ? 1.0 / d : -1.0 / d;
            grad[0] = (r - bn[0]) * s;
            grad[1] = (z - bn[1]) * s;
        } else {
            elem_inward_normal(&part->elem[bi], bn, grad);
        }
    }
    return in ? d : -d;
}

double fm_tool_profile_eval(const fm_tool_part *part, void *worker, double r, double z,
                            double grad[2])
{
    if (part->kind == FM_TOOL_PART_CUSTOM) {
        const fm_tool_custom *c = &part->custom;
        double f = c->eval(c->ctx, worker, r, z);
        if (grad) {
            /* Central differences: custom models have no analytic gradient
             * here, and only local searches use it. */
            double h = 1e-6 * (1 + fabs(r) + fabs(z));
            double rl = r - h < 0 ? 0 : r - h;
            grad[0] = (c->eval(c->ctx, worker, r + h, z) - c->eval(c->ctx, worker, rl, z)) /
                      (r + h - rl);
            grad[1] = (c->eval(c->ctx, worker, r, z + h) - c->eval(c->ctx, worker, r, z - h)) /
                      (2 * h);
        }
        return f;
    }
    if (part->ball_radius > 0) {
        /* Ball under a cylinder of the same radius: below z_hi - R the flat
         * top is farther than any other boundary (depth <= R), so the exact
         * distance is that of the ball swept up the axis for ever:
         * R - |(r, min(0, z - centre))|. The 3-element search below gives
         * the same value; this is the hot path of ball end mill sweeps. */
        double R = part->ball_radius, dz = z - (part->z_lo + R);
        if (z <= part->z_hi - R) {
            if (dz >= 0) {
                if (grad) grad[0] = -1, grad[1] = 0;
                return R - r;
            }
            double h = sqrt(r * r + dz * dz);
            if (h > 1e-300) {
                if (grad) grad[0] = -r / h, grad[1] = -dz / h;
                return R - h;
            }
        }
    }
    if (part->cylinder_radius > 0) {
        /* A plain cylinder: inside, the nearest of side, bottom and top
         * (the same order of preference as the element search); outside,
         * the distance to the rectangle. */
        double R = part->cylinder_radius;
        double ds = R - r, db = z - part->z_lo, dt = part->z_hi - z;
        if (ds >= 0 && db >= 0 && dt >= 0) {
            double d = db, g0 = 0, g1 = 1;
            if (ds < d) d = ds, g0 = -1, g1 = 0;
            if (dt < d) d = dt, g0 = 0, g1 = -1;
            if (grad) grad[0] = g0, grad[1] = g1;
            return d;
        }
        double er = ds < 0 ? -ds : 0, ez = db < 0 ? db : dt < 0 ? -dt : 0;
        double d = sqrt(er * er + ez * ez);
        if (grad) grad[0] = -er / d, grad[1] = -ez / d;
        return -d;
    }
    return profile_eval(part, r, z, grad);
}

/* Many points at once: the two direct formulas above as straight-line loops
 * the compiler vectorizes (the same operations in the same order, so the
 * values are bit for bit those of fm_tool_profile_eval), the rest and the
 * points the formulas do not cover point by point. */
void fm_tool_profile_eval_batch(const fm_tool_part *part, void *worker, size_t n, const double *r,
                                const double *z, double *out)
{
    if (part->kind == FM_TOOL_PART_PROFILE && part->ball_radius > 0) {
        const double R = part->ball_radius, zc = part->z_lo + R, ztop = part->z_hi - R;
        for (size_t i = 0; i < n; i++) {
            /* R - |(r, min(0, z - centre))| */
            const double dz = z[i] - zc;
            const double h = sqrt(r[i] * r[i] + dz * dz);
            out[i] = dz >= 0 ? R - r[i] : R - h;
        }
        /* above z_hi - R the top may be nearer; at the centre itself the
         * element search decides */
        int slow = 0;
        for (size_t i = 0; i < n; i++) slow |= z[i] > ztop || (z[i] < zc && !(out[i] < R));
        if (slow)
            for (size_t i = 0; i < n; i++) {
                if (z[i] > ztop || (z[i] < zc && !(out[i] < R)))
                    out[i] = fm_tool_profile_eval(part, worker, r[i], z[i], NULL);
            }
        return;
    }
    if (part->kind == FM_TOOL_PART_PROFILE && part->cylinder_radius > 0) {
        const double R = part->cylinder_radius, zlo = part->z_lo, zhi = part->z_hi;
        for (size_t i = 0; i < n; i++) {
            const double ds = R - r[i], db = z[i] - zlo, dt = zhi - z[i];
            double d = db < ds ? db : ds;
            d = dt < d ? dt : d;
            const double er = ds < 0 ? -ds : 0, ez = db < 0 ? db : dt < 0 ? -dt : 0;
            const double o = -sqrt(er * er + ez * ez);
            out[i] = (ds >= 0 && db >= 0 && dt >= 0) ? d : o;
        }
        return;
    }
    for (size_t i = 0; i < n; i++) out[i] = fm_tool_profile_eval(part, worker, r[i], z[i], NULL);
}

/* A tiny relative widening so that rounding in the centre evaluation cannot
 * make an enclosure unsound. */
static double widen(double v) { return 1e-12 * (1 + fabs(v)); }

fm_interval fm_tool_profile_interval(const fm_tool_part *part, void *worker, fm_interval r,
                                     fm_interval z)
{
    if (part->kind == FM_TOOL_PART_CUSTOM)
        return part->custom.interval(part->custom.ctx, worker, r, z);
    if (r.lo < 0) r.lo = 0;
    /* The distance is 1-Lipschitz, so the centre value +- the half diagonal
     * encloses it; it also never increases with r, so the upper end comes
     * from the r.lo edge alone. */
    double zm = 0.5 * (z.lo + z.hi), hz = 0.5 * (z.hi - z.lo), hr = 0.5 * (r.hi - r.lo);
    double fc = profile_eval(part, 0.5 * (r.lo + r.hi), zm, NULL);
    double fl = profile_eval(part, r.lo, zm, NULL);
    double hd = sqrt(hr * hr + hz * hz);
    fm_interval out;
    out.lo = fc - hd;
    out.hi = fl + hz;
    if (fc + hd < out.hi) out.hi = fc + hd;
    out.lo -= widen(out.lo);
    out.hi += widen(out.hi);
    return out;
}

double fm_tool_part_eval(const fm_tool_part *part, void *worker, const double p[3])
{
    return fm_tool_profile_eval(part, worker, sqrt(p[0] * p[0] + p[1] * p[1]), p[2], NULL);
}

void fm_tool_part_eval_batch(const fm_tool_part *part, void *worker, size_t n, const double *x,
                             const double *y, const double *z, double *out)
{
    for (size_t i = 0; i < n; i++)
        out[i] = fm_tool_profile_eval(part, worker, sqrt(x[i] * x[i] + y[i] * y[i]),
                                      z ? z[i] : 0.0, NULL);
}

fm_interval fm_tool_part_interval(const fm_tool_part *part, void *worker,
                                  const fm_interval box[3])
{
    /* r over the box: from the distance of the z axis to the xy rectangle
     * to the farthest corner. */
    double nx = box[0].lo > 0 ? box[0].lo : box[0].hi < 0 ? -box[0].hi : 0;
    double ny = box[1].lo > 0 ? box[1].lo : box[1].hi < 0 ? -box[1].hi : 0;
    double fx = fmax(fabs(box[0].lo), fabs(box[0].hi));
    double fy = fmax(fabs(box[1].lo), fabs(box[1].hi));
    fm_interval r = {sqrt(nx * nx + ny * ny), sqrt(fx * fx + fy * fy)};
    return fm_tool_profile_interval(part, worker, r, box[2]);
}

void *fm_tool_part_worker_new(const fm_tool_part *part)
{
    if (part->kind == FM_TOOL_PART_CUSTOM && part->custom.worker_new)
        return part->custom.worker_new(part->custom.ctx);
    return NULL;
}

void fm_tool_part_worker_free(const fm_tool_part *part, void *worker)
{
    if (part->kind == FM_TOOL_PART_CUSTOM && part->custom.worker_free && worker)
        part->custom.worker_free(part->custom.ctx, worker);
}

/* ------------------------------------------------------- validation -- */

static void elem_tangent(const fm_profile_elem *e, int at_end, double t[2])
{
    if (e->kind == FM_PROFILE_SEGMENT) {
        t[0] = e->b[0] - e->a[0];
        t[1] = e->b[1] - e->a[1];
    } else {
        const double *p = at_end ? e->b : e->a;
        double vr = p[0] - e->c[0], vz = p[1] - e->c[1];
        t[0] = e->ccw ? -vz : vz;
        t[1] = e->ccw ? vr : -vr;
    }
    double l = sqrt(t[0] * t[0] + t[1] * t[1]);
    if (l > 0) {
        t[0] /= l;
        t[1] /= l;
    }
}

fm_status fm_tool_part_from_profile(const fm_profile_elem *elems, size_t n, fm_tool_part *part,
                                    fm_error *err)
{
    if (n < 2 || n > FM_PROFILE_MAX)
        return fm_error_set(err, FM_ERR_INPUT, "a tool profile needs 2 to %d elements, not %zu",
                            FM_PROFILE_MAX, n);
    memset(part, 0, sizeof *part);
    part->kind = FM_TOOL_PART_PROFILE;
    double scale = 0;
    for (size_t i = 0; i < n; i++) {
        const fm_profile_elem *e = &elems[i];
        for (int k = 0; k < 2; k++) {
            if (!isfinite(e->a[k]) || !isfinite(e->b[k]))
                return fm_error_set(err, FM_ERR_INPUT, "tool profile element %zu: not a finite point", i);
            scale = fmax(scale, fmax(fabs(e->a[k]), fabs(e->b[k])));
        }
    }
    double eps = 1e-9 * (1 + scale);
    if (fabs(elems[0].a[0]) > eps || fabs(elems[n - 1].b[0]) > eps)
        return fm_error_set(err, FM_ERR_INPUT, "a tool profile must start and end on the axis (r = 0)");
    for (size_t i = 0; i < n; i++) {
        fm_profile_elem e = elems[i];
        if (e.a[0] < -eps || e.b[0] < -eps)
            return fm_error_set(err, FM_ERR_INPUT, "tool profile element %zu has r < 0", i);
        if (e.b[1] < e.a[1] - eps)
            return fm_error_set(err, FM_ERR_INPUT,
                                "tool profile element %zu goes down (z from %g to %g): the profile "
                                "must be a radius function of z", i, e.a[1], e.b[1]);
        if (e.b[1] < e.a[1]) e.b[1] = e.a[1];
        if (i > 0 && (fabs(e.a[0] - elems[i - 1].b[0]) > eps || fabs(e.a[1] - elems[i - 1].b[1]) > eps))
            return fm_error_set(err, FM_ERR_INPUT, "tool profile element %zu does not start where %zu ends",
                                i, i - 1);
        if (e.kind == FM_PROFILE_ARC) {
            double ar = e.a[0] - e.c[0], az = e.a[1] - e.c[1], br = e.b[0] - e.c[0], bz = e.b[1] - e.c[1];
            if (!(e.radius > 0) || fabs(sqrt(ar * ar + az * az) - e.radius) > 1e-7 * (1 + e.radius) ||
                fabs(sqrt(br * br + bz * bz) - e.radius) > 1e-7 * (1 + e.radius))
                return fm_error_set(err, FM_ERR_INPUT, "tool profile arc %zu: its ends are not on its circle", i);
            if (ar * br < -eps * eps || az * bz < -eps * eps)
                return fm_error_set(err, FM_ERR_INPUT,
                                    "tool profile arc %zu crosses a quadrant of its circle: split it", i);
            e.ccw = cross2(ar, az, br, bz) >= 0;
        }
        part->elem[i] = e;
    }
    part->elem[0].a[0] = 0;
    part->elem[n - 1].b[0] = 0;
    part->count = n;
    part->z_lo = part->elem[0].a[1];
    part->z_hi = part->elem[n - 1].b[1];
    if (!(part->z_hi > part->z_lo))
        return fm_error_set(err, FM_ERR_INPUT, "a tool profile must have a positive height");
    part->r_max = 0;
    int convex = 1;
    for (size_t i = 0; i < n; i++) {
        const fm_profile_elem *e = &part->elem[i];
        part->r_max = fmax(part->r_max, fmax(e->a[0], e->b[0]));
        if (e->kind == FM_PROFILE_ARC) {
            /* An arc reaching beyond both ends in r (the outer quadrant part)
             * is covered by the quadrant rule: r is monotone along it. */
            if (!e->ccw) convex = 0;
        }
        if (i + 1 < n) {
            double t0[2], t1[2];
            elem_tangent(e, 1, t0);
            elem_tangent(&part->elem[i + 1], 0, t1);
            if (cross2(t0[0], t0[1], t1[0], t1[1]) < -1e-9) convex = 0;
        }
    }
    /* The chain must turn left overall; the joints at the axis are convex
     * whenever z is monotone (see docs/tools.md). */
    part->convex = convex;
    /* A plain cylinder: bottom disc, side, top disc. */
    if (n == 3 && part->elem[0].kind == FM_PROFILE_SEGMENT && part->elem[1].kind == FM_PROFILE_SEGMENT &&
        part->elem[2].kind == FM_PROFILE_SEGMENT) {
        const fm_profile_elem *b = &part->elem[0], *sd = &part->elem[1], *t = &part->elem[2];
        double R = sd->a[0];
        if (R > 0 && b->a[1] == b->b[1] && b->b[0] == R && sd->b[0] == R && sd->a[1] == b->a[1] &&
            sd->b[1] == t->a[1] && t->a[0] == R && t->b[1] == t->a[1] && t->b[0] == 0)
            part->cylinder_radius = R;
    }
    /* Ball tip under a cylinder of the same radius, at least 2 radii tall. */
    if (n == 3 && part->elem[0].kind == FM_PROFILE_ARC && part->elem[1].kind == FM_PROFILE_SEGMENT) {
        const fm_profile_elem *a = &part->elem[0], *s = &part->elem[1];
        double R = a->radius;
        if (fabs(a->c[0]) <= eps && fabs(a->c[1] - (part->z_lo + R)) <= eps &&
            fabs(a->b[0] - R) <= eps && fabs(a->b[1] - a->c[1]) <= eps && fabs(s->a[0] - R) <= eps &&
            fabs(s->b[0] - R) <= eps && part->z_hi - part->z_lo >= 2 * R)
            part->ball_radius = R;
    }
    return FM_OK;
}
