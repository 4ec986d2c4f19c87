/* sweep.c: the swept volume S(p) = max over t of the moving tool part:
 * poses of each motion kind, the closed forms (planar line and arc,
 * capsule), the certified search for concave cases (with a flat end
 * mill's ramp proven at a guessed maximum), the branch-and-bound on t for
 * everything else, and that branch-and-bound seeded by a helix's
 * structure for convex parts on helices about their axis. See docs/sweep.md for the
 * proofs behind each bound. */
#include "sweep/sweep.h"
#include "sweep/sweep_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }

/* ------------------------------------------------------------ poses -- */

/* Pose at parameter u in [0, 1]: tip c, unit axis a, and their derivatives
 * in u (dc, da may be NULL; for PARAM paths they are finite differences). */
static void pose_u(const fm_sweep *s, double u, double c[3], double a[3], double dc[3], double da[3])
{
    switch (s->kind) {
    case SW_LINE:
        for (int i = 0; i < 3; i++) {
            c[i] = s->c0[i] + u * s->d[i];
            if (dc) dc[i] = s->d[i];
        }
        if (s->axis_const) {
            memcpy(a, s->a0, sizeof s->a0);
            if (da) da[0] = da[1] = da[2] = 0;
        } else {
            /* Normalized linear interpolation of the axis. */
            double l[3], dl[3];
            for (int i = 0; i < 3; i++) {
                l[i] = (1 - u) * s->a0[i] + u * s->a1[i];
                dl[i] = s->a1[i] - s->a0[i];
            }
            double n = norm3(l);
            for (int i = 0; i < 3; i++) a[i] = l[i] / n;
            if (da) {
                double k = dot3(a, dl);
                for (int i = 0; i < 3; i++) da[i] = (dl[i] - k * a[i]) / n;
            }
        }
        return;
    case SW_ARC: {
        double th = s->th0 + u * s->dth, rr = s->r0 + u * s->drr;
        double co = cos(th), si = sin(th);
        memcpy(c, s->ctr, sizeof s->ctr);
        c[s->ai] += rr * co;
        c[s->aj] += rr * si;
        c[s->ak] += u * s->dh;
        if (dc) {
            dc[s->ai] = s->drr * co - rr * s->dth * si;
            dc[s->aj] = s->drr * si + rr * s->dth * co;
            dc[s->ak] = s->dh;
        }
        memcpy(a, s->a0, sizeof s->a0);
        if (da) da[0] = da[1] = da[2] = 0;
        return;
    }
    case SW_PARAM: {
        double t = s->t0 + u * (s->t1 - s->t0);
        s->path->pose(s->path->ctx, t, c, a);
        double n = norm3(a);
        if (n > 0)
            for (int i = 0; i < 3; i++) a[i] /= n;
        for (int i = 0; i < 3; i++) c[i] += s->tip_offset[i];
        if (dc || da) {
            double h = 1e-6, c1[3], a1[3], c2[3], a2[3];
            double ul = u - h < 0 ? 0 : u - h, uh = u + h > 1 ? 1 : u + h;
            s->path->pose(s->path->ctx, s->t0 + ul * (s->t1 - s->t0), c1, a1);
            s->path->pose(s->path->ctx, s->t0 + uh * (s->t1 - s->t0), c2, a2);
            double n1 = norm3(a1), n2 = norm3(a2);
            for (int i = 0; i < 3; i++) {
                if (dc) dc[i] = (c2[i] - c1[i]) / (uh - ul);
                if (da) da[i] = (a2[i] / n2 - a1[i] / n1) / (uh - ul);
            }
        }
        return;
    }
    case SW_KIN:
        fm_kin_pose(&s->kin, u, c, a, dc, da);
        return;
    case SW_STATIC:
    default:
        memcpy(c, s->c0, sizeof s->c0);
        memcpy(a, s->a0, sizeof s->a0);
        if (dc) dc[0] = dc[1] = dc[2] = 0;
        if (da) da[0] = da[1] = da[2] = 0;
        return;
    }
}

/* The moving part at p and parameter u, and dF/du (dF may be NULL). */
static double eval_F(const fm_sweep *s, void *pw, const double p[3], double u, double *dF)
{
    double c[3], a[3], dc[3], da[3];
    pose_u(s, u, c, a, dF ? dc : NULL, dF ? da : NULL);
    double v[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    double zeta = dot3(a, v);
    double w[3] = {v[0] - zeta * a[0], v[1] - zeta * a[1], v[2] - zeta * a[2]};
    double rho = norm3(w);
    if (!dF) return fm_tool_profile_eval(&s->part, pw, rho, zeta, NULL);
    double g[2];
    double f = fm_tool_profile_eval(&s->part, pw, rho, zeta, g);
    /* v' = -c'; zeta' = a'.v + a.v'; w' = v' - zeta' a - zeta a'. */
    double dzeta = dot3(da, v) - dot3(a, dc);
    double drho = 0;
    if (rho > 1e-300) {
        double dw[3];
        for (int i = 0; i < 3; i++) dw[i] = -dc[i] - dzeta * a[i] - zeta * da[i];
        drho = dot3(w, dw) / rho;
    }
    /* On the axis rho is not differentiable; 0 is a supergradient there
     * because the profile never increases with r. */
    *dF = g[0] * drho + g[1] * dzeta;
    return f;
}

/* ----------------------------------------------------- closed forms -- */

static double planar_line(const fm_sweep *s, void *pw, const double p[3], double *u_at)
{
    double v[3] = {p[0] - s->c0[0], p[1] - s->c0[1], p[2] - s->c0[2]};
    double zeta = dot3(s->a0, v);
    double w[3] = {v[0] - zeta * s->a0[0], v[1] - zeta * s->a0[1], v[2] - zeta * s->a0[2]};
    double u = dot3(w, s->d) / s->dd;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    double e[3] = {w[0] - u * s->d[0], w[1] - u * s->d[1], w[2] - u * s->d[2]};
    *u_at = u;
    return fm_tool_profile_eval(&s->part, pw, norm3(e), zeta, NULL);
}

static double planar_arc(const fm_sweep *s, void *pw, const double p[3], double *u_at)
{
    double ui = p[s->ai] - s->ctr[s->ai], uj = p[s->aj] - s->ctr[s->aj];
    double zeta = s->a0[s->ak] * (p[s->ak] - s->ctr[s->ak]);
    double rc = sqrt(ui * ui + uj * uj), rr = s->r0;
    double rho;
    if (s->full_turn || rc == 0) {
        rho = fabs(rc - rr);
        *u_at = rc == 0 ? 0 : fmod(atan2(uj, ui) - s->th0 + 4 * FM_PI, 2 * FM_PI) / fabs(s->dth);
        if (*u_at > 1) *u_at = 1;
    } else {
        double phi = atan2(uj, ui);
        double off = s->dth > 0 ? phi - s->th0 : s->th0 - phi;
        off = fmod(off, 2 * FM_PI);
        if (off < 0) off += 2 * FM_PI;
        if (off <= fabs(s->dth)) {
            rho = fabs(rc - rr);
            *u_at = off / fabs(s->dth);
        } else {
            double e0i = ui - rr * cos(s->th0), e0j = uj - rr * sin(s->th0);
            double th1 = s->th0 + s->dth;
            double e1i = ui - rr * cos(th1), e1j = uj - rr * sin(th1);
            double d0 = e0i * e0i + e0j * e0j, d1 = e1i * e1i + e1j * e1j;
            rho = sqrt(d0 <= d1 ? d0 : d1);
            *u_at = d0 <= d1 ? 0 : 1;
        }
    }
    return fm_tool_profile_eval(&s->part, pw, rho, zeta, NULL);
}

/* Squared distance from p to the strip {C0 + u d + s a : u in [0, 1],
 * s >= 0} swept by the ray up the axis from the ball centre C0 + u d, and
 * the u of a nearest ray. The squared distance to the ray at u is
 * |w⊥(u)|^2 where h(u) = a.w(u) >= 0 and |w(u)|^2 where h(u) <= 0
 * (w(u) = p - C0 - u d), two convex quadratics on the two sides of the
 * root of the linear h: minimize each over its side. */
static double ray_dist2(const double w0[3], const double d[3], const double a[3], double u)
{
    double w[3] = {w0[0] - u * d[0], w0[1] - u * d[1], w0[2] - u * d[2]};
    double h = dot3(w, a);
    if (h > 0)
        for (int i = 0; i < 3; i++) w[i] -= h * a[i];
    return dot3(w, w);
}

static double clampd(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

static double strip_dist2(const fm_sweep *s, const double p[3], double *u_at)
{
    const double *a = s->a0, *d = s->d;
    double off = s->part.z_lo + s->part.ball_radius;
    double w0[3];
    for (int i = 0; i < 3; i++) w0[i] = p[i] - s->c0[i] - off * a[i];
    double h0 = dot3(w0, a), da = dot3(d, a);
    /* Sides: "up" where h >= 0 (the ray's side), "down" where h <= 0. */
    double up_lo = 0, up_hi = 1, dn_lo = 0, dn_hi = 1;
    if (da > 0) {
        double ub = h0 / da;
        up_hi = fmin(1, ub);
        dn_lo = fmax(0, ub);
    } else if (da < 0) {
        double ub = h0 / da;
        up_lo = fmax(0, ub);
        dn_hi = fmin(1, ub);
    } else if (h0 >= 0) {
        dn_lo = 1, dn_hi = 0;
    } else {
        up_lo = 1, up_hi = 0;
    }
    double best = DBL_MAX, ubest = 0;
    if (up_lo <= up_hi) {
        double dp[3], wp[3];
        for (int i = 0; i < 3; i++) {
            dp[i] = d[i] - da * a[i];
            wp[i] = w0[i] - h0 * a[i];
        }
        double dd = dot3(dp, dp);
        double u = clampd(dd > 0 ? dot3(wp, dp) / dd : up_lo, up_lo, up_hi);
        double g = ray_dist2(w0, d, a, u);
        if (g < best) best = g, ubest = u;
    }
    if (dn_lo <= dn_hi) {
        double u = clampd(dot3(w0, d) / s->dd, dn_lo, dn_hi);
        double g = ray_dist2(w0, d, a, u);
        if (g < best) best = g, ubest = u;
    }
    *u_at = ubest;
    return best;
}

/* --------------------------------------------- local, concave search -- */

/* Maximize F on [ua, ub] from the values and derivatives at both ends.
 * When F is concave there (certify = 1) the tangents bound it, and the
 * search stops once that bound is within tol of the best value: *upper is
 * then proven. Otherwise it is a safeguarded secant search on F' that
 * finds a local maximum. Returns the best value, at *u_best. */
static double local_max(const fm_sweep *s, void *pw, const double p[3], double ua, double Fa, double Da,
                        double ub, double Fb, double Db, double tol, int certify, double *u_best,
                        double *upper, size_t *evals, size_t budget)
{
    double best = Fa >= Fb ? Fa : Fb;
    *u_best = Fa >= Fb ? ua : ub;
    *upper = DBL_MAX;
    if (Da <= 0 && Db >= 0 && !certify) {
        /* A valley: the maximum is at an end. */
        *upper = best;
        return best;
    }
    if (Da <= 0 && (certify || Db <= 0)) {
        if (certify) *upper = Fa;
        if (certify || Fa >= Fb) {
            *u_best = ua;
            return certify ? Fa : best;
        }
    }
    if (Db >= 0 && (certify || Da >= 0)) {
        if (certify) *upper = Fb;
        *u_best = ub;
        return certify ? Fb : best;
    }
    /* Now Da > 0 > Db: a maximum inside. */
    int side = 0; /* Illinois: which end stayed last time */
    double wa = 1, wb = 1;
    for (int it = 0; it < 200 && *evals < budget; it++) {
        double w = ub - ua;
        /* Tangent bound: the lines through (ua, Fa) and (ub, Fb) meet at uc. */
        double den = Da - Db;
        double uc = den > 0 ? (Fb - Fa + Da * ua - Db * ub) / den : 0.5 * (ua + ub);
        if (uc < ua) uc = ua;
        if (uc > ub) uc = ub;
        double U = Fa + Da * (uc - ua);
        if (Fb + Db * (uc - ub) < U) U = Fb + Db * (uc - ub);
        if (U < best) U = best;
        if (certify) *upper = U;
        if (U - best <= tol || w <= 1e-15 * (1 + fabs(ua))) break;
        /* Secant root of F' (weighted, Illinois), kept off the ends; when
         * the bracket stalls, the tangent meeting point, which is exact at
         * a kink. */
        double m = ua + w * (wa * Da) / (wa * Da - wb * Db);
        if (it % 4 == 3) m = uc;
        double lo = ua + 0.02 * w, hi = ub - 0.02 * w;
        if (m < lo) m = lo;
        if (m > hi) m = hi;
        double Dm;
        double Fm = eval_F(s, pw, p, m, &Dm);
        (*evals)++;
        if (Fm > best) {
            best = Fm;
            *u_best = m;
        }
        if (Dm > 0) {
            ua = m, Fa = Fm, Da = Dm;
            if (side == -1) wb *= 0.5; else wb = 1;
            wa = 1;
            side = -1;
        } else if (Dm < 0) {
            ub = m, Fb = Fm, Db = Dm;
            if (side == 1) wa *= 0.5; else wa = 1;
            wb = 1;
            side = 1;
        } else {
            if (certify) *upper = Fm; /* a stationary point of a concave function */
            break;
        }
    }
    if (*upper < best) *upper = best;
    return best;
}

/* ---------------------------------------------- branch and bound on u -- */

typedef struct bb_node {
    double ua, ub, Fa, Da, Fb, Db, U;
    /* helix_search: the distance to the tool axis at both ends, and
     * whether the ends are evaluated yet (a piece seeded by its bound) */
    double ra, rb;
    int ev, piece;
} bb_node;

#define BB_CAP 1024

typedef struct bb_heap {
    bb_node n[BB_CAP];
    int count;
} bb_heap;

static void heap_push(bb_heap *h, const bb_node *x)
{
    int i = h->count++;
    while (i > 0) {
        int parent = (i - 1) / 2;
        if (h->n[parent].U >= x->U) break;
        h->n[i] = h->n[parent];
        i = parent;
    }
    h->n[i] = *x;
}

static bb_node heap_pop(bb_heap *h)
{
    bb_node top = h->n[0], last = h->n[--h->count];
    int i = 0;
    for (;;) {
        int l = 2 * i + 1, r = l + 1, m = i;
        double mu = last.U;
        if (l < h->count && h->n[l].U > mu) m = l, mu = h->n[l].U;
        if (r < h->count && h->n[r].U > mu) m = r;
        if (m == i) break;
        h->n[i] = h->n[m];
        i = m;
    }
    if (h->count > 0) h->n[i] = last;
    return top;
}

/* Sound bound of (rho, zeta) over u in [ua, ub] for a point p, from a box
 * of tip positions and a box of axis directions. */
static void rz_bounds(const double p[3], const double clo[3], const double chi[3], const double alo[3],
                      const double ahi[3], fm_interval *rho, fm_interval *zeta)
{
    fm_interval v[3], z = {0, 0};
    for (int i = 0; i < 3; i++) {
        v[i].lo = p[i] - chi[i];
        v[i].hi = p[i] - clo[i];
        double c[4] = {alo[i] * v[i].lo, alo[i] * v[i].hi, ahi[i] * v[i].lo, ahi[i] * v[i].hi};
        double lo = c[0], hi = c[0];
        for (int k = 1; k < 4; k++) {
            if (c[k] < lo) lo = c[k];
            if (c[k] > hi) hi = c[k];
        }
        z.lo += lo;
        z.hi += hi;
    }
    /* w = v - zeta a, componentwise; |w| between the distance of 0 to its
     * box and its farthest corner. */
    double nlo = 0, nhi = 0;
    for (int i = 0; i < 3; i++) {
        double c[4] = {z.lo * alo[i], z.lo * ahi[i], z.hi * alo[i], z.hi * ahi[i]};
        double lo = c[0], hi = c[0];
        for (int k = 1; k < 4; k++) {
            if (c[k] < lo) lo = c[k];
            if (c[k] > hi) hi = c[k];
        }
        double wlo = v[i].lo - hi, whi = v[i].hi - lo;
        double nearest = wlo > 0 ? wlo : whi < 0 ? -whi : 0;
        double far = fmax(fabs(wlo), fabs(whi));
        nlo += nearest * nearest;
        nhi += far * far;
    }
    /* Also |w| <= |v| (w is v minus its component along a unit axis). */
    double vmax = 0;
    for (int i = 0; i < 3; i++) vmax += fmax(v[i].lo * v[i].lo, v[i].hi * v[i].hi);
    rho->lo = sqrt(nlo);
    rho->hi = sqrt(nhi < vmax ? nhi : vmax);
    *zeta = z;
}

/* Boxes of the tip and the axis over [ua, ub]. */
static void pose_box(const fm_sweep *s, double ua, double ub, double clo[3], double chi[3], double alo[3],
                     double ahi[3])
{
    if (s->kind == SW_KIN) {
        fm_kin_pose_box(&s->kin, ua, ub, clo, chi, alo, ahi);
        return;
    }
    if (s->kind == SW_PARAM) {
        double ta = s->t0 + ua * (s->t1 - s->t0), tb = s->t0 + ub * (s->t1 - s->t0);
        s->path->pose_bounds(s->path->ctx, ta, tb, clo, chi, alo, ahi);
        for (int i = 0; i < 3; i++) {
            clo[i] += s->tip_offset[i];
            chi[i] += s->tip_offset[i];
            /* The axis is unit (motion.h), so no component leaves [-1, 1]. */
            if (alo[i] < -1) alo[i] = -1;
            if (ahi[i] > 1) ahi[i] = 1;
        }
        return;
    }
    double ca[3], cb[3], aa[3], ab[3];
    pose_u(s, ua, ca, aa, NULL, NULL);
    pose_u(s, ub, cb, ab, NULL, NULL);
    /* Lines: the tip moves linearly (exact box). Arcs: within speed * w / 2
     * of the nearer end. */
    double grow = s->kind == SW_ARC ? s->speed * (ub - ua) * 0.5 : 0;
    for (int i = 0; i < 3; i++) {
        clo[i] = fmin(ca[i], cb[i]) - grow;
        chi[i] = fmax(ca[i], cb[i]) + grow;
    }
    if (s->axis_const || s->kind != SW_LINE) {
        memcpy(alo, s->a0, sizeof s->a0);
        memcpy(ahi, s->a0, sizeof s->a0);
    } else {
        /* nlerp: l(u) linear, |l| >= its value at the box's nearest point
         * to 0; a = l / |l| lies in the box of l divided by [lmin, 1]. */
        double llo[3], lhi[3];
        for (int i = 0; i < 3; i++) {
            double l0 = (1 - ua) * s->a0[i] + ua * s->a1[i], l1 = (1 - ub) * s->a0[i] + ub * s->a1[i];
            llo[i] = fmin(l0, l1);
            lhi[i] = fmax(l0, l1);
        }
        double lmin = s->lmin;
        for (int i = 0; i < 3; i++) {
            alo[i] = llo[i] >= 0 ? llo[i] : llo[i] / lmin;
            ahi[i] = lhi[i] <= 0 ? lhi[i] : lhi[i] / lmin;
            if (alo[i] < -1) alo[i] = -1;
            if (ahi[i] > 1) ahi[i] = 1;
        }
    }
}

/* Upper bound of F over [ua, ub]. */
static double node_bound(const fm_sweep *s, void *pw, const double p[3], const bb_node *n)
{
    double U = DBL_MAX, w = n->ub - n->ua;
    if (s->part.kind == FM_TOOL_PART_PROFILE && s->lipschitz > 0) {
        /* 1-Lipschitz part, |dq/du| <= lipschitz (+ lever arm of a turning axis). */
        double L = s->lipschitz;
        if (s->turn_rate > 0) {
            double c[3], a[3];
            pose_u(s, n->ua, c, a, NULL, NULL);
            double v[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
            L += s->turn_rate * (norm3(v) + s->lipschitz * w);
        }
        U = 0.5 * (n->Fa + n->Fb) + 0.5 * L * w;
    }
    if (s->second_order) {
        /* F'' <= A (convex part, fixed axis: F'' = q'Hq' + grad.q'' with
         * H <= 0): parabolas from both ends bound F; they differ by a
         * linear function, so the bound is at their crossing or an end. */
        double A = s->accel;
        if (s->kind == SW_KIN) {
            /* Rotary axes: |q''| grows with the distance from p to the tip,
             * at most the mean of the ends' plus speed * w / 2. */
            double ca[3], cb[3], aa[3];
            pose_u(s, n->ua, ca, aa, NULL, NULL);
            pose_u(s, n->ub, cb, aa, NULL, NULL);
            double va[3] = {p[0] - ca[0], p[1] - ca[1], p[2] - ca[2]}, vb[3] = {p[0] - cb[0], p[1] - cb[1], p[2] - cb[2]};
            A = fm_kin_second(&s->kin, 0.5 * (norm3(va) + norm3(vb) + s->lipschitz * w));
        }
        double Qa_b = n->Fa + n->Da * w + 0.5 * A * w * w;
        double Qb_a = n->Fb - n->Db * w + 0.5 * A * w * w;
        double U2 = fmax(fmin(n->Fa, Qb_a), fmin(Qa_b, n->Fb));
        double k = n->Da - n->Db + A * w;             /* slope of Qa - Qb */
        double c0 = n->Fa - Qb_a;                      /* (Qa - Qb)(ua) */
        if (k != 0) {
            double x = -c0 / k;
            if (x > 0 && x < w) {
                double q = n->Fa + n->Da * x + 0.5 * A * x * x;
                if (q > U2) U2 = q;
            }
        }
        if (U2 < U) U = U2;
    }
    if (s->part.kind != FM_TOOL_PART_PROFILE || s->kind == SW_PARAM || (s->kind == SW_KIN && !s->second_order) ||
        U == DBL_MAX) {
        double clo[3], chi[3], alo[3], ahi[3];
        pose_box(s, n->ua, n->ub, clo, chi, alo, ahi);
        fm_interval rho, zeta;
        rz_bounds(p, clo, chi, alo, ahi, &rho, &zeta);
        fm_interval f = fm_tool_profile_interval(&s->part, pw, rho, zeta);
        if (f.hi < U) U = f.hi;
    }
    double m = fmax(n->Fa, n->Fb);
    return U < m ? m : U;
}

static double bb_search(const fm_sweep *s, fm_sweep_worker *worker, const double p[3], fm_sweep_value *out)
{
    void *pw = worker ? worker->part_worker : NULL;
    /* the heap (57 KB) lives in the worker, made on its first search */
    if (worker && !worker->heap) worker->heap = malloc(sizeof(bb_heap));
    bb_heap *h = worker ? worker->heap : malloc(sizeof *h);
    size_t evals = 0, budget = s->max_evals;
    int pieces = s->pieces;
    double best = -DBL_MAX, ubest = 0;
    double cert_tol = s->certified ? s->tol : fmax(s->tol, FM_SWEEP_COARSE_TOL);
    /* Candidates dropped by the coarse proof that the local search still
     * visits (uncertified kinds only). */
    bb_node cand[64];
    int ncand = 0;
    double upper_rest = -DBL_MAX;
    if (!h) {
        /* No memory: an attained value and a loose but sound bound. */
        out->value = eval_F(s, pw, p, 0, NULL);
        out->upper = DBL_MAX;
        out->t = s->t0;
        out->evaluations = 1;
        out->exhausted = 1;
        return out->value;
    }
    h->count = 0;
    double Fprev, Dprev;
    Fprev = eval_F(s, pw, p, 0, &Dprev);
    evals++;
    best = Fprev;
    for (int i = 1; i <= pieces; i++) {
        double u = (double)i / pieces, D;
        double F = eval_F(s, pw, p, u, &D);
        evals++;
        if (F > best) best = F, ubest = u;
        bb_node n = {(double)(i - 1) / pieces, u, Fprev, Dprev, F, D, 0, 0, 0, 1, 0};
        n.U = node_bound(s, pw, p, &n);
        heap_push(h, &n);
        Fprev = F, Dprev = D;
    }
    while (h->count > 0) {
        if (h->n[0].U <= best + cert_tol) break;
        if (evals >= budget || h->count >= BB_CAP - 2) break;
        bb_node n = heap_pop(h);
        if (n.U <= best + cert_tol) {
            if (n.U > best && ncand < 64) cand[ncand++] = n;
            continue;
        }
        double w = n.ub - n.ua;
        double m = 0.5 * (n.ua + n.ub);
        if (s->second_order && n.Da > 0 && n.Db < 0) {
            m = n.ua + w * n.Da / (n.Da - n.Db);
            if (m < n.ua + 0.1 * w) m = n.ua + 0.1 * w;
            if (m > n.ub - 0.1 * w) m = n.ub - 0.1 * w;
        }
        double Dm, Fm = eval_F(s, pw, p, m, &Dm);
        evals++;
        if (Fm > best) best = Fm, ubest = m;
        bb_node l = {n.ua, m, n.Fa, n.Da, Fm, Dm, 0, 0, 0, 1, 0}, r = {m, n.ub, Fm, Dm, n.Fb, n.Db, 0, 0, 0, 1, 0};
        l.U = node_bound(s, pw, p, &l);
        r.U = node_bound(s, pw, p, &r);
        if (l.U > best + cert_tol) heap_push(h, &l);
        else if (l.U > best && ncand < 64) cand[ncand++] = l;
        if (r.U > best + cert_tol) heap_push(h, &r);
        else if (r.U > best && ncand < 64) cand[ncand++] = r;
    }
    for (int i = 0; i < h->count; i++) {
        if (h->n[i].U > upper_rest) upper_rest = h->n[i].U;
        if (!s->certified && h->n[i].U > best && ncand < 64) cand[ncand++] = h->n[i];
    }
    /* Local search in each candidate left (uncertified kinds): the proof
     * says none beats best by more than cert_tol; this finds by how much.
     * Certified kinds stop at their proof (tol). */
    for (int i = 0; i < ncand; i++) {
        const bb_node *n = &cand[i];
        if (n->U > upper_rest) upper_rest = n->U;
        if (n->U <= best || s->certified) continue;
        double ub_local, up_local;
        double v = local_max(s, pw, p, n->ua, n->Fa, n->Da, n->ub, n->Fb, n->Db, 0.01 * s->tol, 0, &ub_local,
                             &up_local, &evals, budget + 4000);
        if (v > best) best = v, ubest = ub_local;
    }
    if (!worker) free(h);
    out->value = best;
    out->upper = upper_rest > best + cert_tol ? upper_rest : best + cert_tol;
    out->t = s->t0 + ubest * (s->t1 - s->t0);
    out->evaluations = evals;
    out->exhausted = upper_rest > best + cert_tol;
    return best;
}

/* ------------------------------------------- helix about the tool axis -- */

/* FM_SWEEP_HELIX: a convex part whose axis is the helix's (a G17 helix
 * with a vertical tool, an arc with a rise). With (x, y) the point's offset
 * from the centre in the plane and th(u) the tip's angle, the distance to
 * the tool axis is d(u) = |(x, y) - r (cos th, sin th)| and zeta(u) =
 * a_k (p_k - ctr_k - u dh) is linear. d is monotone between the times where
 * th(u) passes the point's angle phi or its opposite (phi - th a multiple
 * of pi, where d = |rho - r| or rho + r: no trigonometry), so on each such
 * piece [ua, ub] the part, which never increases with r, is at most its
 * largest value over d in [min d, max d] and zeta between the ends', one
 * profile evaluation for the parts setup.c admits (profile_box_max). Those bounds
 * seed the branch-and-bound before any evaluation, so that of the two
 * pieces a turn only the one or two where the tool passes the point at the
 * right height are searched, and they keep bounding every sub-interval:
 * at a flat end mill's kink (side distance R - d falling while the height
 * term rises) the bound of the sub-interval on the wrong side of the kink
 * is the value at its end, so the tangents' meeting point closes the proof
 * in a few steps. Same tolerance and budget as the search. */

typedef struct hx_point {
    double x, y, rho, pk;
} hx_point;

/* The part at u (tip angle with cosine ct and sine st), dF/du, and the
 * distance to the tool axis. */
static double helix_F(const fm_sweep *s, void *pw, const hx_point *q, double u, double ct, double st, double *dF,
                      double *dist)
{
    const double r = s->r0, sa = s->a0[s->ak];
    const double wx = q->x - r * ct, wy = q->y - r * st;
    const double d = sqrt(wx * wx + wy * wy);
    const double zeta = sa * (q->pk - u * s->dh);
    double g[2];
    const double f = fm_tool_profile_eval(&s->part, pw, d, zeta, g);
    /* d d' = w . (-c') with c' = r dth (-sin th, cos th); on the axis 0 is
     * a supergradient (the profile never increases with r). */
    const double dd = d > 1e-300 ? -r * s->dth * (wy * ct - wx * st) / d : 0;
    *dF = g[0] * dd - g[1] * sa * s->dh;
    *dist = d;
    return f;
}

/* The largest value of the part over r in [rlo, rhi], z in [zlo, zhi]:
 * the part holds the ball of radius r_max about (0, zmid) (setup.c), so
 * every point (r, zmid) is at depth r_max - r, the most any point at
 * radius r can be, and zmid maximizes z -> f(r, z), which is concave (a
 * convex part): the maximum over the box is at rlo (f never increases with
 * r) and the z of [zlo, zhi] nearest zmid, exactly. */
static double profile_box_max(const fm_sweep *s, void *pw, double rlo, double zlo, double zhi)
{
    const double zm = s->hx_zmid;
    return fm_tool_profile_eval(&s->part, pw, rlo, zm < zlo ? zlo : zm > zhi ? zhi : zm, NULL);
}

/* Upper bound of F over a node inside one monotone piece (ra, rb: the
 * distances at its ends). */
static double helix_box(const fm_sweep *s, void *pw, const hx_point *q, const bb_node *n)
{
    const double sa = s->a0[s->ak];
    const double za = sa * (q->pk - n->ua * s->dh), zb = sa * (q->pk - n->ub * s->dh);
    const double v = profile_box_max(s, pw, fmin(n->ra, n->rb), fmin(za, zb), fmax(za, zb));
    /* rounding of the distances, and a radius that changes by |drr| */
    return v + 1e-12 * (1 + fabs(v) + s->r0 + q->rho + s->part.r_max) + fabs(s->drr);
}

#define HX_MAX_PIECES 130

static void helix_search(const fm_sweep *s, fm_sweep_worker *worker, const double p[3], fm_sweep_value *out)
{
    void *pw = worker ? worker->part_worker : NULL;
    if (worker && !worker->heap) worker->heap = malloc(sizeof(bb_heap));
    bb_heap *h = worker ? worker->heap : malloc(sizeof *h);
    if (!h) {
        bb_search(s, worker, p, out);
        return;
    }
    hx_point q;
    q.x = p[s->ai] - s->ctr[s->ai];
    q.y = p[s->aj] - s->ctr[s->aj];
    q.rho = sqrt(q.x * q.x + q.y * q.y);
    q.pk = p[s->ak] - s->ctr[s->ak];
    /* The pieces' ends: u = 0, the times where phi - th(u) = j pi in
     * increasing u (th(u) = phi - j pi: cos and sin from the point's own
     * direction), u = 1. */
    double bu[HX_MAX_PIECES + 1], bc[HX_MAX_PIECES + 1], bs[HX_MAX_PIECES + 1];
    int nb = 0;
    bu[0] = 0, bc[0] = s->hx_c0, bs[0] = s->hx_s0;
    if (q.rho > 0) {
        const double phi = atan2(q.y, q.x);
        const double a = (phi - s->th0) / FM_PI, b = (phi - s->th0 - s->dth) / FM_PI;
        const double jl = floor(fmin(a, b)) + 1, jh = ceil(fmax(a, b)) - 1;
        if (jh - jl + 1 > HX_MAX_PIECES - 1) {
            if (!worker) free(h);
            bb_search(s, worker, p, out);
            return;
        }
        const int count = jh >= jl ? (int)(jh - jl) + 1 : 0;
        for (int i = 0; i < count; i++) {
            const double j = s->dth > 0 ? jh - i : jl + i;
            const double u = (phi - s->th0 - j * FM_PI) / s->dth;
            if (!(u > bu[nb]) || !(u < 1)) continue;
            const double sg = fmod(fabs(j), 2) == 1 ? -1 : 1;
            nb++;
            bu[nb] = u, bc[nb] = sg * q.x / q.rho, bs[nb] = sg * q.y / q.rho;
        }
    }
    nb++;
    bu[nb] = 1, bc[nb] = s->hx_c1, bs[nb] = s->hx_s1;
    double bd[HX_MAX_PIECES + 1], bF[HX_MAX_PIECES + 1], bD[HX_MAX_PIECES + 1];
    unsigned char have[HX_MAX_PIECES + 1];
    for (int k = 0; k <= nb; k++) {
        const double wx = q.x - s->r0 * bc[k], wy = q.y - s->r0 * bs[k];
        bd[k] = sqrt(wx * wx + wy * wy);
        have[k] = 0;
    }
    h->count = 0;
    for (int k = 0; k < nb; k++) {
        bb_node n = {bu[k], bu[k + 1], 0, 0, 0, 0, 0, bd[k], bd[k + 1], 0, k};
        n.U = helix_box(s, pw, &q, &n);
        heap_push(h, &n);
    }
    const double tol = s->tol;
    const size_t budget = s->max_evals;
    size_t evals = 0;
    double best = -DBL_MAX, ubest = 0;
    while (h->count > 0) {
        if (h->n[0].U <= best + tol) break;
        if (evals >= budget || h->count >= BB_CAP - 2) break;
        bb_node n = heap_pop(h);
        if (!n.ev) {
            /* a piece seeded by its bound: evaluate its ends */
            for (int k = n.piece; k <= n.piece + 1; k++) {
                if (have[k]) continue;
                double dist;
                bF[k] = helix_F(s, pw, &q, bu[k], bc[k], bs[k], &bD[k], &dist);
                have[k] = 1;
                evals++;
                if (bF[k] > best) best = bF[k], ubest = bu[k];
            }
            n.Fa = bF[n.piece], n.Da = bD[n.piece], n.Fb = bF[n.piece + 1], n.Db = bD[n.piece + 1];
            n.ev = 1;
            const double U2 = node_bound(s, pw, p, &n) + fabs(s->drr);
            if (U2 < n.U) n.U = U2;
            if (n.U > best + tol) heap_push(h, &n);
            continue;
        }
        const double w = n.ub - n.ua;
        double m = 0.5 * (n.ua + n.ub);
        if (n.Da > 0 && n.Db < 0) {
            if (n.Da - n.Db > 2 * s->accel * w) {
                /* F' falls by more than the curvature bound allows: a kink
                 * (side against bottom of a flat end mill); the tangents
                 * from both ends meet there. */
                m = (n.Fb - n.Fa + n.Da * n.ua - n.Db * n.ub) / (n.Da - n.Db);
                if (!(m > n.ua + 0.01 * w)) m = n.ua + 0.01 * w;
                if (!(m < n.ub - 0.01 * w)) m = n.ub - 0.01 * w;
            } else {
                /* a smooth maximum: the secant root of F' */
                m = n.ua + w * n.Da / (n.Da - n.Db);
                if (m < n.ua + 0.1 * w) m = n.ua + 0.1 * w;
                if (m > n.ub - 0.1 * w) m = n.ub - 0.1 * w;
            }
        }
        const double th = s->th0 + m * s->dth;
        double Dm, dm;
        const double Fm = helix_F(s, pw, &q, m, cos(th), sin(th), &Dm, &dm);
        evals++;
        if (Fm > best) best = Fm, ubest = m;
        bb_node l = {n.ua, m, n.Fa, n.Da, Fm, Dm, 0, n.ra, dm, 1, n.piece};
        bb_node r = {m, n.ub, Fm, Dm, n.Fb, n.Db, 0, dm, n.rb, 1, n.piece};
        l.U = fmin(helix_box(s, pw, &q, &l), node_bound(s, pw, p, &l) + fabs(s->drr));
        r.U = fmin(helix_box(s, pw, &q, &r), node_bound(s, pw, p, &r) + fabs(s->drr));
        if (l.U > best + tol) heap_push(h, &l);
        if (r.U > best + tol) heap_push(h, &r);
    }
    double upper_rest = -DBL_MAX;
    for (int i = 0; i < h->count; i++)
        if (h->n[i].U > upper_rest) upper_rest = h->n[i].U;
    if (!worker) free(h);
    if (best == -DBL_MAX) { /* no evaluation allowed: one, for an attained value */
        double D, dist;
        best = helix_F(s, pw, &q, 0, bc[0], bs[0], &D, &dist);
        evals++;
    }
    out->value = best;
    out->upper = upper_rest > best + tol ? upper_rest : best + tol;
    out->t = s->t0 + ubest * (s->t1 - s->t0);
    out->evaluations = evals;
    out->exhausted = upper_rest > best + tol;
}

/* ------------------------------------------------------- evaluation -- */

/* A flat end mill (the plain cylinder: R, z_lo, z_hi) on a line with a
 * fixed axis (a ramp): where the maximum of F over u is likely. With
 * zeta(u) = z0 - u dz and the distance to the moving axis d(u) = sqrt(q(u)),
 * q a convex quadratic, F <= G = min(R - d, zeta - z_lo, z_hi - zeta)
 * everywhere, with equality unless both the side and the nearer end are
 * negative (below or above the tool and outside its radius: then F is minus
 * the distance to the rim). G is concave, the least of a concave and two
 * linear terms, so its maximum is at an end, at the peak of R - d, or where
 * two terms cross: a quadratic's roots. When that maximum is negative on
 * both sides, F = -sqrt((d - R)^2 + l^2) with l the nearer end's term, and
 * (d - R)^2 + l^2 is convex there (d is convex and above R): a few Newton
 * steps from it. Only a guess: concave_search proves it or searches. */
static double ramp_guess(const fm_sweep *s, const double p[3])
{
    const double *a = s->a0, *d = s->d;
    const double R = s->part.cylinder_radius, zlo = s->part.z_lo, zhi = s->part.z_hi;
    double v0[3] = {p[0] - s->c0[0], p[1] - s->c0[1], p[2] - s->c0[2]};
    const double z0 = dot3(a, v0), dz = dot3(a, d);
    double w0[3], dp[3];
    for (int i = 0; i < 3; i++) {
        w0[i] = v0[i] - z0 * a[i];
        dp[i] = d[i] - dz * a[i];
    }
    const double al = dot3(dp, dp), be = dot3(w0, dp), ga = dot3(w0, w0);
    /* the linear terms l0 + l1 u */
    const double lin0[2] = {z0 - zlo, zhi - z0}, lin1[2] = {-dz, dz};
    double cand[8];
    int nc = 0;
    cand[nc++] = 0;
    cand[nc++] = 1;
    if (al > 0) cand[nc++] = be / al;
    if (dz != 0) cand[nc++] = (z0 - 0.5 * (zlo + zhi)) / dz;
    for (int k = 0; k < 2; k++) {
        /* sqrt(q(u)) = c + e u with c + e u >= 0: (al - e^2) u^2 - 2 (be + c e) u + ga - c^2 = 0 */
        const double c = R - lin0[k], e = -lin1[k];
        const double A = al - e * e, B = -2 * (be + c * e), C = ga - c * c;
        if (fabs(A) > 1e-14 * (al + e * e)) {
            const double disc = B * B - 4 * A * C;
            if (disc >= 0) {
                const double sq = sqrt(disc), qq = -0.5 * (B + (B >= 0 ? sq : -sq));
                if (qq != 0) cand[nc++] = C / qq;
                cand[nc++] = qq / A;
            }
        } else if (B != 0) {
            cand[nc++] = -C / B;
        }
    }
    double best = -DBL_MAX, ub = 0;
    for (int i = 0; i < nc; i++) {
        const double u = cand[i];
        if (!(u >= 0 && u <= 1)) continue;
        const double q = ga - 2 * be * u + al * u * u;
        double g = R - sqrt(q > 0 ? q : 0);
        for (int k = 0; k < 2; k++) g = fmin(g, lin0[k] + lin1[k] * u);
        if (g > best) best = g, ub = u;
    }
    if (best >= 0) return ub;
    /* Both terms may be negative there: minimize (d - R)^2 + l^2. */
    double u = ub;
    for (int it = 0; it < 6; it++) {
        const double q = ga - 2 * be * u + al * u * u;
        const double dd = sqrt(q > 0 ? q : 0);
        const int k = lin0[0] + lin1[0] * u <= lin0[1] + lin1[1] * u ? 0 : 1;
        const double l = lin0[k] + lin1[k] * u, l1 = lin1[k];
        if (!(dd > R) || l >= 0) break;
        const double d1 = (al * u - be) / dd, d2 = (al - d1 * d1) / dd;
        const double E1 = (dd - R) * d1 + l * l1, E2 = d1 * d1 + (dd - R) * d2 + l1 * l1;
        if (!(E2 > 0)) break;
        double next = u - E1 / E2;
        next = next < 0 ? 0 : next > 1 ? 1 : next;
        if (fabs(next - u) <= 1e-15) {
            u = next;
            break;
        }
        u = next;
    }
    return u;
}

static double concave_search(const fm_sweep *s, void *pw, const double p[3], fm_sweep_value *out)
{
    const double along = dot3(s->d, s->a0);
    size_t used = 0;                 /* evaluations the guess spent, out of the same budget */
    double guess_best = -DBL_MAX, guess_u = 0; /* and the best value it found */
    if (s->part.cylinder_radius > 0 && s->kind == SW_LINE && along * along < s->dd * (1 - 1e-12) &&
        s->max_evals >= 2) {
        /* A flat end mill's ramp (not a plunge, which the ends settle): where the maximum should be (ramp_guess),
         * proven with two evaluations next to it: F is concave, so with a
         * supergradient >= 0 at u1 and <= 0 at u2 nothing before u1 beats
         * F(u1), nothing after u2 beats F(u2), and the tangents bound
         * [u1, u2] (local_max). Otherwise the search below. */
        const double ug = ramp_guess(s, p), h = 1e-9 / fmax(1, sqrt(s->dd)); /* 1e-9 mm of path */
        const double u1 = ug - h < 0 ? 0 : ug - h, u2 = ug + h > 1 ? 1 : ug + h;
        double D1, D2;
        const double F1 = eval_F(s, pw, p, u1, &D1), F2 = eval_F(s, pw, p, u2, &D2);
        size_t evals = 2;
        if ((u1 == 0 || D1 >= 0) && (u2 == 1 || D2 <= 0)) {
            double u, up;
            double v = local_max(s, pw, p, u1, F1, D1, u2, F2, D2, s->tol, 1, &u, &up, &evals,
                                 s->max_evals < 8 ? s->max_evals : 8);
            if (up - v <= s->tol) {
                out->value = v;
                out->upper = up + 1e-12 * (1 + fabs(up));
                out->t = s->t0 + u * (s->t1 - s->t0);
                out->evaluations = evals;
                out->exhausted = 0;
                return v;
            }
        }
        used = evals;
        guess_best = F1 >= F2 ? F1 : F2;
        guess_u = F1 >= F2 ? u1 : u2;
    }
    double Da, Db;
    double Fa = eval_F(s, pw, p, 0, &Da), Fb = eval_F(s, pw, p, 1, &Db);
    size_t evals = used + 2;
    double u, up;
    double v = local_max(s, pw, p, 0, Fa, Da, 1, Fb, Db, s->tol, 1, &u, &up, &evals, s->max_evals);
    if (guess_best > v) v = guess_best, u = guess_u;
    if (up < v) up = v;
    out->value = v;
    out->upper = up + 1e-12 * (1 + fabs(up));
    out->t = s->t0 + u * (s->t1 - s->t0);
    out->evaluations = evals;
    out->exhausted = up - v > s->tol;
    return v;
}

void fm_sweep_eval_ex(const fm_sweep *s, fm_sweep_worker *worker, const double p[3], fm_sweep_value *out)
{
    void *pw = worker ? worker->part_worker : NULL;
    double u = 0;
    out->exhausted = 0;
    switch (s->method) {
    case FM_SWEEP_STATIC:
        out->value = out->upper = eval_F(s, pw, p, 0, NULL);
        out->t = s->t0;
        out->evaluations = 1;
        return;
    case FM_SWEEP_PLANAR_LINE:
        out->value = out->upper = planar_line(s, pw, p, &u);
        out->t = s->t0 + u * (s->t1 - s->t0);
        out->evaluations = 1;
        return;
    case FM_SWEEP_PLANAR_ARC:
        out->value = out->upper = planar_arc(s, pw, p, &u);
        out->t = s->t0 + u * (s->t1 - s->t0);
        out->evaluations = 1;
        return;
    case FM_SWEEP_CAPSULE: {
        /* The part lies in B = ball(R) + ray up the axis from the ball
         * centre, whose signed distance is R - dist(q, ray) inside and out,
         * so S <= R - dist(p, strip) (strip: the rays from every centre of
         * the path). The part attains that bound at the nearest time unless
         * its top decides there; then the concave search (docs/sweep.md). */
        double R = s->part.ball_radius, uu;
        double bound = R - sqrt(strip_dist2(s, p, &uu));
        /* Below z_hi - R at the nearest time the top is not the nearest
         * boundary and the part equals the bound there (docs/sweep.md). */
        double zeta = 0;
        for (int i = 0; i < 3; i++) zeta += s->a0[i] * (p[i] - s->c0[i] - uu * s->d[i]);
        if (zeta <= s->part.z_hi - R) {
            out->value = out->upper = bound;
            out->t = s->t0 + uu * (s->t1 - s->t0);
            out->evaluations = 0;
            return;
        }
        double v = eval_F(s, pw, p, uu, NULL);
        double up = bound + 1e-12 * (1 + fabs(bound));
        if (up - v <= 0.5 * s->tol) {
            out->value = v;
            out->upper = up > v ? up : v;
            out->t = s->t0 + uu * (s->t1 - s->t0);
            out->evaluations = 1;
            return;
        }
        concave_search(s, pw, p, out);
        return;
    }
    case FM_SWEEP_CONCAVE:
        concave_search(s, pw, p, out);
        return;
    case FM_SWEEP_HELIX:
        helix_search(s, worker, p, out);
        return;
    case FM_SWEEP_SEARCH:
    default:
        bb_search(s, worker, p, out);
        return;
    }
}

double fm_sweep_eval(const fm_sweep *s, fm_sweep_worker *worker, const double p[3])
{
    fm_sweep_value v;
    fm_sweep_eval_ex(s, worker, p, &v);
    return v.value;
}

void fm_sweep_eval_batch(const fm_sweep *s, fm_sweep_worker *worker, size_t n, const double *x,
                         const double *y, const double *z, double *out)
{
    fm_sweep_batch_ex(s, worker, n, x, y, z, out, NULL);
}

fm_interval fm_sweep_interval(const fm_sweep *s, fm_sweep_worker *worker, const fm_interval box[3])
{
    void *pw = worker ? worker->part_worker : NULL;
    double c[3], hd2 = 0;
    for (int i = 0; i < 3; i++) {
        c[i] = 0.5 * (box[i].lo + box[i].hi);
        double h = 0.5 * (box[i].hi - box[i].lo);
        hd2 += h * h;
    }
    double hd = sqrt(hd2);
    fm_interval out;
    if (s->part.kind == FM_TOOL_PART_PROFILE) {
        /* S is a max of 1-Lipschitz functions, hence 1-Lipschitz. */
        fm_sweep_value v;
        fm_sweep_eval_ex(s, worker, c, &v);
        out.lo = v.value - hd;
        out.hi = v.upper + hd;
    } else {
        /* Custom parts need not be Lipschitz: enclose T over the box for
         * pieces of u, with the part's own interval evaluation. */
        double clo[3], chi[3], alo[3], ahi[3];
        out.lo = -DBL_MAX;
        out.hi = -DBL_MAX;
        int pieces = 16;
        for (int k = 0; k < pieces; k++) {
            pose_box(s, (double)k / pieces, (double)(k + 1) / pieces, clo, chi, alo, ahi);
            double blo[3], bhi[3];
            for (int i = 0; i < 3; i++) {
                blo[i] = clo[i] - box[i].hi + c[i];
                bhi[i] = chi[i] - box[i].lo + c[i];
            }
            /* p - tip over the box = c - (tip + (c - p)). */
            fm_interval rho, zeta;
            rz_bounds(c, blo, bhi, alo, ahi, &rho, &zeta);
            fm_interval f = fm_tool_profile_interval(&s->part, pw, rho, zeta);
            if (f.hi > out.hi) out.hi = f.hi;
            /* For the lower end, any single time gives a lower bound. */
            double u = (k + 0.5) / pieces;
            pose_box(s, u, u, clo, chi, alo, ahi);
            for (int i = 0; i < 3; i++) {
                blo[i] = clo[i] - box[i].hi + c[i];
                bhi[i] = chi[i] - box[i].lo + c[i];
            }
            rz_bounds(c, blo, bhi, alo, ahi, &rho, &zeta);
            f = fm_tool_profile_interval(&s->part, pw, rho, zeta);
            if (f.lo > out.lo) out.lo = f.lo;
        }
    }
    out.lo -= 1e-12 * (1 + fabs(out.lo));
    out.hi += 1e-12 * (1 + fabs(out.hi));
    return out;
}

void fm_sweep_bounds(const fm_sweep *s, double lo[3], double hi[3])
{
    memcpy(lo, s->lo, sizeof s->lo);
    memcpy(hi, s->hi, sizeof s->hi);
}

fm_sweep_method fm_sweep_method_of(const fm_sweep *s) { return s->method; }

void fm_sweep_pose(const fm_sweep *s, double t, double tip[3], double axis[3])
{
    double u = s->t1 > s->t0 ? (t - s->t0) / (s->t1 - s->t0) : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    pose_u(s, u, tip, axis, NULL, NULL);
}

double fm_sweep_tool_at(const fm_sweep *s, fm_sweep_worker *worker, const double p[3], double t)
{
    double u = s->t1 > s->t0 ? (t - s->t0) / (s->t1 - s->t0) : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    return eval_F(s, worker ? worker->part_worker : NULL, p, u, NULL);
}

/* Evaluate at a geometric parameter u in [0, 1] (for the brute-force
 * reference in tests, which needs more resolution than t for short moves). */
double fm_sweep_tool_at_u(const fm_sweep *s, fm_sweep_worker *worker, const double p[3], double u)
{
    return eval_F(s, worker ? worker->part_worker : NULL, p, u, NULL);
}

fm_sweep_worker *fm_sweep_worker_new(const fm_sweep *s)
{
    fm_sweep_worker *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    w->part = &s->part;
    w->part_worker = fm_tool_part_worker_new(&s->part);
    if (s->part.kind == FM_TOOL_PART_CUSTOM && s->part.custom.worker_new && !w->part_worker) {
        free(w);
        return NULL;
    }
    return w;
}

void fm_sweep_worker_free(fm_sweep_worker *w)
{
    if (!w) return;
    fm_tool_part_worker_free(w->part, w->part_worker);
    free(w->heap);
    free(w);
}
