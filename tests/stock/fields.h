/* fields.h: closed-form swept volumes and solids for the stock tests, as
 * fm_field implementations (positive inside, exact distance): a sphere, a
 * capsule (a ball moved along a segment), an upright cylinder (a flat end
 * mill plunged), a box and a ring (a flat end mill moved around a circle).
 * The tests compare what lib/stock measures with volumes computed from
 * these shapes' formulas, never with the library's own output. */
#ifndef FM_TEST_STOCK_FIELDS_H
#define FM_TEST_STOCK_FIELDS_H

#include "stock/stock.h"

#include <math.h>
#include <string.h>

enum { SHAPE_SPHERE, SHAPE_CAPSULE, SHAPE_CYLINDER, SHAPE_BOX, SHAPE_RING, SHAPE_MAX };

typedef struct shape {
    int kind;
    double a[3], b[3]; /* sphere: centre; capsule: ends; box: lo, hi;
                          cylinder: a = (x, y, z0), b[0] = z1; ring: centre */
    double r, R;       /* radius; ring: tube half width r, circle radius R, half height b[0] */
    /* SHAPE_MAX: the maximum (union) of n shapes */
    const struct shape *parts;
    int nparts;
} shape;

static inline double shape_eval(const shape *s, double x, double y, double z)
{
    switch (s->kind) {
    case SHAPE_SPHERE:
        return s->r - sqrt((x - s->a[0]) * (x - s->a[0]) + (y - s->a[1]) * (y - s->a[1]) +
                           (z - s->a[2]) * (z - s->a[2]));
    case SHAPE_CAPSULE: {
        double d[3] = {s->b[0] - s->a[0], s->b[1] - s->a[1], s->b[2] - s->a[2]};
        double p[3] = {x - s->a[0], y - s->a[1], z - s->a[2]};
        double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double t = dd > 0 ? (p[0] * d[0] + p[1] * d[1] + p[2] * d[2]) / dd : 0;
        if (t < 0) t = 0;
        if (t > 1) t = 1;
        double q[3] = {p[0] - t * d[0], p[1] - t * d[1], p[2] - t * d[2]};
        return s->r - sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    }
    case SHAPE_CYLINDER:
    case SHAPE_RING: {
        double rho = hypot(x - s->a[0], y - s->a[1]);
        double dx, dz;
        if (s->kind == SHAPE_CYLINDER) {
            dx = rho - s->r;
            dz = fmax(s->a[2] - z, z - s->b[0]);
        } else {
            dx = fabs(rho - s->R) - s->r;
            dz = fabs(z - s->a[2]) - s->b[0];
        }
        double ox = fmax(dx, 0), oz = fmax(dz, 0);
        return -(sqrt(ox * ox + oz * oz) + fmin(fmax(dx, dz), 0));
    }
    case SHAPE_BOX: {
        double q[3], o = 0, in = -INFINITY;
        const double p[3] = {x, y, z};
        for (int k = 0; k < 3; k++) {
            q[k] = fabs(p[k] - 0.5 * (s->a[k] + s->b[k])) - 0.5 * (s->b[k] - s->a[k]);
            o += fmax(q[k], 0) * fmax(q[k], 0);
            in = fmax(in, q[k]);
        }
        return -(sqrt(o) + fmin(in, 0));
    }
    case SHAPE_MAX: {
        double v = -INFINITY;
        for (int i = 0; i < s->nparts; i++) v = fmax(v, shape_eval(&s->parts[i], x, y, z));
        return v;
    }
    }
    return -INFINITY;
}

static inline void shape_batch(void *ctx, void *worker, size_t n, const double *x, const double *y,
                        const double *z, double *out)
{
    (void)worker;
    for (size_t i = 0; i < n; i++) out[i] = shape_eval(ctx, x[i], y[i], z[i]);
}

/* Every shape here is a distance, so 1-Lipschitz: centre value +- half
 * diagonal encloses the box. */
static inline fm_interval shape_interval(void *ctx, void *worker, const fm_interval box[3])
{
    (void)worker;
    double c[3], r2 = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (box[k].lo + box[k].hi);
        r2 += 0.25 * (box[k].hi - box[k].lo) * (box[k].hi - box[k].lo);
    }
    double v = shape_eval(ctx, c[0], c[1], c[2]), r = sqrt(r2);
    fm_interval out = {v - r, v + r};
    return out;
}

static inline void shape_bounds(const shape *s, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        switch (s->kind) {
        case SHAPE_SPHERE: lo[k] = s->a[k] - s->r; hi[k] = s->a[k] + s->r; break;
        case SHAPE_CAPSULE:
            lo[k] = fmin(s->a[k], s->b[k]) - s->r;
            hi[k] = fmax(s->a[k], s->b[k]) + s->r;
            break;
        case SHAPE_CYLINDER:
            lo[k] = k < 2 ? s->a[k] - s->r : s->a[2];
            hi[k] = k < 2 ? s->a[k] + s->r : s->b[0];
            break;
        case SHAPE_RING:
            lo[k] = k < 2 ? s->a[k] - s->R - s->r : s->a[2] - s->b[0];
            hi[k] = k < 2 ? s->a[k] + s->R + s->r : s->a[2] + s->b[0];
            break;
        case SHAPE_BOX: lo[k] = s->a[k]; hi[k] = s->b[k]; break;
        case SHAPE_MAX: {
            lo[k] = INFINITY;
            hi[k] = -INFINITY;
            for (int i = 0; i < s->nparts; i++) {
                double l[3], h[3];
                shape_bounds(&s->parts[i], l, h);
                lo[k] = fmin(lo[k], l[k]);
                hi[k] = fmax(hi[k], h[k]);
            }
            break;
        }
        }
    }
}

static inline fm_field shape_field(const shape *s)
{
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = (void *)s;
    shape_bounds(s, f.lo, f.hi);
    f.batch = shape_batch;
    f.interval = shape_interval;
    return f;
}

static inline shape make_sphere(double x, double y, double z, double r)
{
    shape s = {SHAPE_SPHERE, {x, y, z}, {0, 0, 0}, r, 0, NULL, 0};
    return s;
}

static inline shape make_capsule(const double a[3], const double b[3], double r)
{
    shape s = {SHAPE_CAPSULE, {a[0], a[1], a[2]}, {b[0], b[1], b[2]}, r, 0, NULL, 0};
    return s;
}

static inline shape make_cylinder(double x, double y, double z0, double z1, double r)
{
    shape s = {SHAPE_CYLINDER, {x, y, z0}, {z1, 0, 0}, r, 0, NULL, 0};
    return s;
}

static inline shape make_box(const double lo[3], const double hi[3])
{
    shape s = {SHAPE_BOX, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, 0, 0, NULL, 0};
    return s;
}

/* Flat end mill of radius r moved once around a circle of radius R in the
 * plane z = zc, cutting z in [zc - hz, zc + hz]. */
static inline shape make_ring(double x, double y, double zc, double R, double r, double hz)
{
    shape s = {SHAPE_RING, {x, y, zc}, {hz, 0, 0}, r, R, NULL, 0};
    return s;
}

#endif
