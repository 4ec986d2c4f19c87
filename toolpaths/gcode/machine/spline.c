/* spline.c: G5 (cubic), G5.1 (quadratic) and G5.2/G5.3 (NURBS)
 * curves as exact parametric motions (FM_MOTION_PARAM). A curve is kept as
 * a chain of rational Bezier segments (the NURBS decomposed at its knots),
 * so that the pose at any time is exact and the box of the curve over any
 * time interval is the box of the control points of the sub-curve over that
 * interval (de Casteljau subdivision): sound, because with positive weights
 * a rational Bezier curve lies in the convex hull of its control points, and
 * tight, because the hull shrinks with the interval.
 *
 * The definitions (docs/gcode.md): the NURBS of order k (degree k - 1) with
 * control points P0..Pn and weights w0..wn has the clamped uniform knot
 * vector of LinuxCNC: k zeros, then 1, 2, ..., n - k + 1, then k times
 * n - k + 2. G5 is the cubic Bezier curve (P0 = start, P1 = start + (I, J),
 * P2 = end + (P, Q), P3 = end), G5.1 the quadratic one (P0 = start,
 * P1 = start + (I, J), P2 = end); both have unit weights. Program time
 * maps linearly to the curve parameter. Positions are machine millimetres
 * of the programmed point; the motion's tip_offset applies as for lines. */
#include "machine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SPLINE_MAX_DEGREE 32

void gc_spline_free(gc_spline *s)
{
    free(s->cp);
    s->cp = NULL;
    s->nseg = 0;
    s->cap = 0;
}

/* Homogeneous point of segment s, index i: (w x, w y, w). */
static double *hp(const gc_spline *s, size_t seg, int i)
{
    return s->cp + 3 * (seg * (size_t)(s->degree + 1) + (size_t)i);
}

/* De Casteljau on homogeneous points: the point at t of a rational Bezier
 * segment, written into work[0]. */
static void casteljau(int degree, const double *pts, double t, double *work)
{
    memcpy(work, pts, 3 * (size_t)(degree + 1) * sizeof *work);
    for (int r = 1; r <= degree; r++)
        for (int i = 0; i <= degree - r; i++)
            for (int k = 0; k < 3; k++)
                work[3 * i + k] = (1 - t) * work[3 * i + k] + t * work[3 * (i + 1) + k];
}

/* The control points of the part of a segment over [a, b] (0 <= a < b <= 1). */
static void sub_segment(int degree, const double *pts, double a, double b, double *out)
{
    double tmp[3 * (SPLINE_MAX_DEGREE + 1)];
    int n = degree + 1;
    /* right part from a: the last points of each de Casteljau level */
    memcpy(tmp, pts, 3 * (size_t)n * sizeof *tmp);
    double right[3 * (SPLINE_MAX_DEGREE + 1)];
    for (int k = 0; k < 3; k++) right[3 * degree + k] = tmp[3 * degree + k];
    for (int r = 1; r <= degree; r++) {
        for (int i = 0; i <= degree - r; i++)
            for (int k = 0; k < 3; k++)
                tmp[3 * i + k] = (1 - a) * tmp[3 * i + k] + a * tmp[3 * (i + 1) + k];
        for (int k = 0; k < 3; k++) right[3 * (degree - r) + k] = tmp[3 * (degree - r) + k];
    }
    /* right[] now runs over [a, 1]: take its left part up to b */
    double tb = a < 1 ? (b - a) / (1 - a) : 1;
    for (int k = 0; k < 3; k++) out[k] = right[k];
    for (int r = 1; r <= degree; r++) {
        for (int i = 0; i <= degree - r; i++)
            for (int k = 0; k < 3; k++)
                right[3 * i + k] = (1 - tb) * right[3 * i + k] + tb * right[3 * (i + 1) + k];
        for (int k = 0; k < 3; k++) out[3 * r + k] = right[k];
    }
}

void gc_spline_point(const gc_spline *s, double u, double p[2])
{
    if (u < 0) u = 0;
    if (u > (double)s->nseg) u = (double)s->nseg;
    size_t seg = (size_t)u;
    if (seg >= s->nseg) seg = s->nseg - 1;
    double t = u - (double)seg;
    double work[3 * (SPLINE_MAX_DEGREE + 1)];
    casteljau(s->degree, hp(s, seg, 0), t, work);
    p[0] = work[0] / work[2];
    p[1] = work[1] / work[2];
}

void gc_spline_box(const gc_spline *s, double ua, double ub, double lo[2], double hi[2])
{
    if (ua > ub) {
        double t = ua;
        ua = ub;
        ub = t;
    }
    if (ua < 0) ua = 0;
    if (ub > (double)s->nseg) ub = (double)s->nseg;
    lo[0] = lo[1] = INFINITY;
    hi[0] = hi[1] = -INFINITY;
    size_t first = (size_t)ua, last = (size_t)ub;
    if (first >= s->nseg) first = s->nseg - 1;
    if (last >= s->nseg) last = s->nseg - 1;
    double sub[3 * (SPLINE_MAX_DEGREE + 1)];
    for (size_t seg = first; seg <= last; seg++) {
        double a = ua - (double)seg, b = ub - (double)seg;
        if (a < 0) a = 0;
        if (b > 1) b = 1;
        if (b < a) b = a;
        const double *pts = hp(s, seg, 0);
        if (a > 0 || b < 1) {
            sub_segment(s->degree, pts, a, b, sub);
            pts = sub;
        }
        for (int i = 0; i <= s->degree; i++) {
            double w = pts[3 * i + 2];
            for (int k = 0; k < 2; k++) {
                double v = pts[3 * i + k] / w;
                if (v < lo[k]) lo[k] = v;
                if (v > hi[k]) hi[k] = v;
            }
        }
    }
    /* the division rounds: widen by a few ulps of the coordinates */
    for (int k = 0; k < 2; k++) {
        double m = fmax(fabs(lo[k]), fabs(hi[k]));
        lo[k] -= 1e-12 * m;
        hi[k] += 1e-12 * m;
    }
}

double gc_spline_length(const gc_spline *s)
{
    /* chords of 64 pieces per segment: the length only sets the motion's
     * duration, never its geometry */
    double len = 0, prev[2], p[2];
    gc_spline_point(s, 0, prev);
    size_t n = 64 * s->nseg;
    for (size_t i = 1; i <= n; i++) {
        gc_spline_point(s, (double)i / 64.0, p);
        len += hypot(p[0] - prev[0], p[1] - prev[1]);
        prev[0] = p[0];
        prev[1] = p[1];
    }
    return len;
}

static size_t knot_count(size_t npts, int order)
{
    return npts + (size_t)order;
}

/* LinuxCNC's clamped uniform knot vector (nurbs knot_vector_creator). */
static double knot(size_t i, size_t npts, int order)
{
    size_t n = npts - 1, k = (size_t)order;
    if (i < k) return 0;
    if (i <= n) return (double)(i - k + 1);
    return (double)(n - k + 2);
}

fm_status gc_spline_build(gc_spline *s, const double *xyw, size_t npts, int order, fm_error *err)
{
    if (order < 2 || order - 1 > SPLINE_MAX_DEGREE)
        return fm_error_set(err, FM_ERR_INPUT, "spline order %d; expected 2 to %d", order,
                            SPLINE_MAX_DEGREE + 1);
    if (npts < (size_t)order)
        return fm_error_set(err, FM_ERR_INPUT, "%zu control points for order %d", npts, order);
    int p = order - 1;
    size_t nseg = npts - (size_t)order + 1; /* distinct interior spans of the uniform knots */
    size_t need = 3 * nseg * (size_t)(p + 1);
    if (need > s->cap) {
        double *cp = realloc(s->cp, need * sizeof *cp);
        if (!cp) return fm_error_set(err, FM_ERR_LIMIT, "out of memory (spline of %zu points)", npts);
        s->cp = cp;
        s->cap = need;
    }
    s->degree = p;
    s->nseg = nseg;
    /* Bezier decomposition by knot insertion (every interior knot raised to
     * multiplicity p), in homogeneous coordinates */
    size_t m = knot_count(npts, order) - 1;
    double alphas[SPLINE_MAX_DEGREE + 1];
    size_t a = (size_t)p, b = (size_t)p + 1, nb = 0;
    for (int i = 0; i <= p; i++) {
        double *q = hp(s, 0, i);
        const double *pt = xyw + 3 * (size_t)i;
        q[0] = pt[0] * pt[2];
        q[1] = pt[1] * pt[2];
        q[2] = pt[2];
    }
    while (b < m) {
        size_t i = b;
        while (b < m && knot(b + 1, npts, order) == knot(b, npts, order)) b++;
        int mult = (int)(b - i + 1);
        if (mult < p) {
            double numer = knot(b, npts, order) - knot(a, npts, order);
            for (int j = p; j > mult; j--)
                alphas[j - mult - 1] = numer / (knot(a + (size_t)j, npts, order) - knot(a, npts, order));
            int r = p - mult;
            for (int j = 1; j <= r; j++) {
                int save = r - j, st = mult + j;
                for (int k = p; k >= st; k--) {
                    double al = alphas[k - st];
                    double *qk = hp(s, nb, k), *qk1 = hp(s, nb, k - 1);
                    for (int c = 0; c < 3; c++) qk[c] = al * qk[c] + (1 - al) * qk1[c];
                }
                if (b < m && nb + 1 < nseg) memcpy(hp(s, nb + 1, save), hp(s, nb, p), 3 * sizeof(double));
            }
        }
        nb++;
        if (b < m) {
            if (nb >= nseg) break;
            for (int k = p - mult; k <= p; k++) {
                double *q = hp(s, nb, k);
                const double *pt = xyw + 3 * (b - (size_t)p + (size_t)k);
                q[0] = pt[0] * pt[2];
                q[1] = pt[1] * pt[2];
                q[2] = pt[2];
            }
            a = b;
            b++;
        }
    }
    return FM_OK;
}

/* fm_path callbacks: time -> parameter, plus the motion's fixed Z and tip. */
static double time_to_u(const gc_spline *s, double t)
{
    double span = s->t1 - s->t0;
    double f = span > 0 ? (t - s->t0) / span : 0;
    if (f < 0) f = 0;
    if (f > 1) f = 1;
    return f * (double)s->nseg;
}

static void path_pose(void *ctx, double t, double pos[3], double axis[3])
{
    const gc_spline *s = ctx;
    double p[2];
    gc_spline_point(s, time_to_u(s, t), p);
    pos[0] = p[0];
    pos[1] = p[1];
    pos[2] = s->z;
    axis[0] = axis[1] = 0;
    axis[2] = 1;
}

static void path_bounds(void *ctx, double ta, double tb, double pos_lo[3], double pos_hi[3],
                        double axis_lo[3], double axis_hi[3])
{
    const gc_spline *s = ctx;
    double lo[2], hi[2];
    gc_spline_box(s, time_to_u(s, ta), time_to_u(s, tb), lo, hi);
    for (int k = 0; k < 2; k++) {
        pos_lo[k] = lo[k];
        pos_hi[k] = hi[k];
    }
    pos_lo[2] = pos_hi[2] = s->z;
    axis_lo[0] = axis_lo[1] = axis_hi[0] = axis_hi[1] = 0;
    axis_lo[2] = axis_hi[2] = 1;
}

void gc_spline_path(gc_spline *s, double t0, double t1, double z)
{
    s->t0 = t0;
    s->t1 = t1;
    s->z = z;
    s->path.ctx = s;
    s->path.pose = path_pose;
    s->path.pose_bounds = path_bounds;
}

/* ------------------------------------------------ G5, G5.1, G5.2, G5.3 -- */

#define SPLINE_MAX_POINTS 1000000

/* Emit the curve through the nps control points (program units x, y,
 * weight) as one parametric motion at the current height. */
static fm_status emit_curve(gc_interp *g, const double *xyw, size_t npts, int order)
{
    double *m = malloc(3 * npts * sizeof *m);
    if (!m) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory (spline of %zu points)", npts);
    double z = 0;
    for (size_t i = 0; i < npts; i++) {
        double p[3] = {xyw[3 * i], xyw[3 * i + 1], g->pos[2]}, mm[3];
        gc_to_machine(g, p, mm);
        m[3 * i] = mm[0];
        m[3 * i + 1] = mm[1];
        m[3 * i + 2] = xyw[3 * i + 2];
        z = mm[2];
    }
    fm_status st = gc_spline_build(&g->spline, m, npts, order, g->err);
    free(m);
    if (st) return st;
    double end[3] = {xyw[3 * (npts - 1)], xyw[3 * (npts - 1) + 1], g->pos[2]};
    fm_motion mo;
    memset(&mo, 0, sizeof mo);
    mo.kind = FM_MOTION_PARAM;
    memcpy(mo.start, g->mpos, sizeof mo.start);
    gc_to_machine(g, end, mo.end);
    double sec = gc_feed_seconds(g, gc_spline_length(&g->spline), &mo.feed);
    gc_spline_path(&g->spline, g->t, g->t + sec, z);
    mo.path = &g->spline.path;
    memcpy(g->pos, end, sizeof g->pos);
    return gc_emit_motion(g, &mo, sec);
}

fm_status gc_exec_spline(gc_interp *g, const gc_block *b, int code, int explicit_code, int col)
{
    char name[16];
    gc_g_name(code, name, sizeof name);
    (void)explicit_code;
    fm_status st;
    if (g->plane != GC_PLANE_XY)
        return gc_fail(g, FM_ERR_INPUT, col, "%s in the G%d plane; splines need G17", name,
                       (int)g->plane);
    if (code != GC_G5_3) {
        if (g->inverse_time && !HAS(b, 'f'))
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s in inverse time (G93) without F; expected an F word", name);
        if (!g->inverse_time && (st = gc_check_feed(g, name, col))) return st;
        const char *no = "zabc";
        for (const char *c = no; *c; c++)
            if (HAS(b, *c))
                return gc_fail(g, FM_ERR_INPUT, COL(b, *c),
                               "%s with a %c word; splines move in X and Y only", name, *c - 32);
    }
    double end[3];
    if (code == GC_G5 || code == GC_G5_1) {
        g->motion = (gc_gcode)code;
        if ((st = gc_find_ends(g, b, 0, end))) return st;
        double cx = g->pos[0], cy = g->pos[1];
        if (code == GC_G5_1) {
            if (!HAS(b, 'i') || !HAS(b, 'j'))
                return gc_fail(g, FM_ERR_INPUT, col,
                               "G5.1: %c word missing; expected both I and J (the control point "
                               "relative to the start)", HAS(b, 'i') ? 'J' : 'I');
            double pts[9] = {cx, cy, 1, cx + VAL(b, 'i'), cy + VAL(b, 'j'), 1, end[0], end[1], 1};
            return emit_curve(g, pts, 3, 3);
        }
        double i, j;
        if (HAS(b, 'i') != HAS(b, 'j'))
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G5: %c word missing; expected both I and J, or neither (then the "
                           "previous G5's end tangent continues)", HAS(b, 'i') ? 'J' : 'I');
        if (HAS(b, 'i')) {
            i = VAL(b, 'i');
            j = VAL(b, 'j');
        } else {
            i = g->cycle_i;
            j = g->cycle_j;
        }
        if (!HAS(b, 'p') || !HAS(b, 'q'))
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G5: %c word missing; expected both P and Q (the end control point "
                           "relative to the end)", HAS(b, 'p') ? 'Q' : 'P');
        double p = VAL(b, 'p'), q = VAL(b, 'q');
        double pts[12] = {cx, cy, 1, cx + i, cy + j, 1, end[0] + p, end[1] + q, 1,
                          end[0], end[1], 1};
        g->cycle_i = -p;
        g->cycle_j = -q;
        return emit_curve(g, pts, 4, 4);
    }
    if (code == GC_G5_3) {
        if (g->motion != GC_G5_2)
            return gc_fail(g, FM_ERR_INPUT, col, "G5.3 without G5.2 first; expected G5.2 control "
                           "points before it");
        g->motion = GC_G80;
        if (g->nnurbs < (size_t)g->nurbs_order) {
            size_t n = g->nnurbs;
            g->nnurbs = 0;
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G5.3: %zu control points for a NURBS of order L%d; expected at least "
                           "%d", n, g->nurbs_order, g->nurbs_order);
        }
        st = emit_curve(g, g->nurbs, g->nnurbs, g->nurbs_order);
        g->nnurbs = 0;
        return st;
    }
    /* G5.2: a control point (the first is the current point) */
    if (g->motion != GC_G5_2) g->nnurbs = 0;
    g->motion = GC_G5_2;
    int xy = HAS(b, 'x') && HAS(b, 'y');
    if (HAS(b, 'x') != HAS(b, 'y'))
        return gc_fail(g, FM_ERR_INPUT, HAS(b, 'x') ? COL(b, 'x') : COL(b, 'y'),
                       "G5.2 control point with only %c; expected both X and Y",
                       HAS(b, 'x') ? 'X' : 'Y');
    if (HAS(b, 'p') && VAL(b, 'p') <= 0)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'), "G5.2 P%g: expected a weight P > 0",
                       VAL(b, 'p'));
    if (!xy && HAS(b, 'p') && g->nnurbs > 0)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'),
                       "G5.2 P without X and Y; a weight alone is only for the first (current) "
                       "point");
    if (xy && !HAS(b, 'p'))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G5.2 control point without P; expected a weight P > 0");
    if (HAS(b, 'l')) {
        double l = VAL(b, 'l');
        if (l != floor(l) || l < 2 || l > SPLINE_MAX_DEGREE + 1)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'), "G5.2 L%g: expected an order 2 to %d", l,
                           SPLINE_MAX_DEGREE + 1);
    }
    if (g->nnurbs + 2 > SPLINE_MAX_POINTS)
        return gc_fail(g, FM_ERR_LIMIT, col, "G5.2: more than %d control points",
                       SPLINE_MAX_POINTS);
    if (g->nnurbs + 2 > g->capnurbs) {
        size_t cap = g->capnurbs ? g->capnurbs * 2 : 16;
        double *n = realloc(g->nurbs, 3 * cap * sizeof *n);
        if (!n) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory (G5.2 points)");
        g->nurbs = n;
        g->capnurbs = cap;
    }
    if (g->nnurbs == 0) {
        double *q = g->nurbs;
        q[0] = g->pos[0];
        q[1] = g->pos[1];
        q[2] = !xy && HAS(b, 'p') ? VAL(b, 'p') : 1;
        g->nnurbs = 1;
        g->nurbs_order = 3;
    }
    /* LinuxCNC takes L only above 3 (L2 and L3 leave the order at 3) */
    if (HAS(b, 'l') && VAL(b, 'l') > 3) g->nurbs_order = (int)VAL(b, 'l');
    if (xy) {
        if ((st = gc_find_ends(g, b, 0, end))) return st;
        double *q = g->nurbs + 3 * g->nnurbs++;
        q[0] = end[0];
        q[1] = end[1];
        q[2] = VAL(b, 'p');
    }
    return FM_OK;
}
