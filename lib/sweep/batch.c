/* batch.c: S at many points at once. The closed forms (planar line,
 * capsule) as straight-line loops over blocks of points that the compiler
 * vectorizes, with the same operations in the same order as the point forms
 * in sweep.c, so that batch and point values are identical bit for bit (the
 * tests compare them); the points a closed form does not settle, and every
 * other method, go point by point through fm_sweep_eval_ex. */
#include "sweep/sweep_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* The loops below are also compiled for AVX2 (4 doubles a step instead of
 * SSE2's 2), picked at load time where the CPU has it. AVX2 without FMA
 * rounds every operation as SSE2 does, so the values are the same bits. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FM_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FM_VECTOR_CLONES
#endif

/* Points per block: the scratch arrays stay on the stack. */
#define BLOCK 256

static double clampd(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

/* PLANAR_LINE: the in-plane distance to the segment, then the profile. */
FM_VECTOR_CLONES static void planar_line_block(const fm_sweep *s, void *pw, size_t n, const double *x, const double *y,
                              const double *z, double *out)
{
    double rho[BLOCK], zeta[BLOCK];
    const double *a = s->a0, *d = s->d, *c0 = s->c0, dd = s->dd;
    for (size_t k = 0; k < n; k++) {
        const double v0 = x[k] - c0[0], v1 = y[k] - c0[1], v2 = z[k] - c0[2];
        const double ze = a[0] * v0 + a[1] * v1 + a[2] * v2;
        const double w0 = v0 - ze * a[0], w1 = v1 - ze * a[1], w2 = v2 - ze * a[2];
        const double u = clampd((w0 * d[0] + w1 * d[1] + w2 * d[2]) / dd, 0, 1);
        const double e0 = w0 - u * d[0], e1 = w1 - u * d[1], e2 = w2 - u * d[2];
        rho[k] = sqrt(e0 * e0 + e1 * e1 + e2 * e2);
        zeta[k] = ze;
    }
    fm_tool_profile_eval_batch(&s->part, pw, n, rho, zeta, out);
}

/* CAPSULE: R - dist(p, strip) wherever the part's top does not decide at
 * the nearest time (sweep.c, strip_dist2 and fm_sweep_eval_ex); the other
 * points are flagged for the point form. */
FM_VECTOR_CLONES static void capsule_block(const fm_sweep *s, size_t n, const double *x, const double *y, const double *z,
                          double *out, unsigned char *slow, size_t *nslow)
{
    const double *a = s->a0, *d = s->d, *c0 = s->c0;
    const double R = s->part.ball_radius, off = s->part.z_lo + R, top = s->part.z_hi - R;
    const double da = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
    const double dp0 = d[0] - da * a[0], dp1 = d[1] - da * a[1], dp2 = d[2] - da * a[2];
    const double ddp = dp0 * dp0 + dp1 * dp1 + dp2 * dp2, dd = s->dd;
    /* Which side of the root of h(u) is the ray's: the sign of a . d. A
     * line perpendicular to the axis (a . d = 0) is PLANAR_LINE's unless
     * its direction is within 1e-10 of it: then point by point. */
    if (da == 0) {
        memset(slow, 1, n);
        *nslow = n;
        return;
    }
    const int pos = da > 0;
    double zt[BLOCK]; /* the axial coordinate at the nearest time */
    const double a0 = a[0], a1 = a[1], a2 = a[2], d0 = d[0], d1 = d[1], d2 = d[2];
    const double c00 = c0[0], c01 = c0[1], c02 = c0[2];
    for (size_t k = 0; k < n; k++) {
        const double p0 = x[k], p1 = y[k], p2 = z[k];
        const double w00 = p0 - c00 - off * a0, w01 = p1 - c01 - off * a1, w02 = p2 - c02 - off * a2;
        const double h0 = w00 * a0 + w01 * a1 + w02 * a2;
        const double ub = h0 / da, ub_lo = ub > 0 ? ub : 0, ub_hi = ub < 1 ? ub : 1;
        const double up_lo = pos ? 0 : ub_lo, up_hi = pos ? ub_hi : 1;
        const double dn_lo = pos ? ub_lo : 0, dn_hi = pos ? 1 : ub_hi;
        /* up side: nearest on the line perpendicular to a */
        const double wp0 = w00 - h0 * a0, wp1 = w01 - h0 * a1, wp2 = w02 - h0 * a2;
        const double num = wp0 * dp0 + wp1 * dp1 + wp2 * dp2, quot = num / ddp;
        const double uu = clampd(ddp > 0 ? quot : up_lo, up_lo, up_hi);
        /* down side: nearest to the ball centre */
        const double ud = clampd((w00 * d0 + w01 * d1 + w02 * d2) / dd, dn_lo, dn_hi);
        /* squared distance to the ray at each (sweep.c, ray_dist2) */
        const double e00 = w00 - uu * d0, e01 = w01 - uu * d1, e02 = w02 - uu * d2;
        const double hu = e00 * a0 + e01 * a1 + e02 * a2, hpu = hu > 0 ? hu : 0;
        const double f00 = e00 - hpu * a0, f01 = e01 - hpu * a1, f02 = e02 - hpu * a2;
        const double gu = f00 * f00 + f01 * f01 + f02 * f02;
        const double e10 = w00 - ud * d0, e11 = w01 - ud * d1, e12 = w02 - ud * d2;
        const double hd = e10 * a0 + e11 * a1 + e12 * a2, hpd = hd > 0 ? hd : 0;
        const double f10 = e10 - hpd * a0, f11 = e11 - hpd * a1, f12 = e12 - hpd * a2;
        const double gd = f10 * f10 + f11 * f11 + f12 * f12;
        const int up_ok = up_lo <= up_hi, dn_ok = dn_lo <= dn_hi;
        const double best0 = up_ok ? gu : DBL_MAX, u0 = up_ok ? uu : 0;
        const int take_dn = dn_ok && gd < best0;
        const double best = take_dn ? gd : best0, u = take_dn ? ud : u0;
        out[k] = R - sqrt(best);
        const double zeta = ((0 + a0 * (p0 - c00 - u * d0)) + a1 * (p1 - c01 - u * d1)) + a2 * (p2 - c02 - u * d2);
        zt[k] = zeta;
    }
    size_t count = 0;
    for (size_t k = 0; k < n; k++) {
        slow[k] = !(zt[k] <= top);
        count += slow[k];
    }
    *nslow = count;
}

void fm_sweep_batch_ex(const fm_sweep *s, fm_sweep_worker *worker, size_t n, const double *x, const double *y,
                       const double *z, double *out, double *shortfall)
{
    void *pw = worker ? worker->part_worker : NULL;
    double zeros[BLOCK];
    if (!z) memset(zeros, 0, sizeof zeros);
    for (size_t b = 0; b < n; b += BLOCK) {
        const size_t m = n - b < BLOCK ? n - b : BLOCK;
        const double *xb = x + b, *yb = y + b, *zb = z ? z + b : zeros;
        double *ob = out + b;
        if (shortfall) memset(shortfall + b, 0, m * sizeof *shortfall);
        if (s->method == FM_SWEEP_PLANAR_LINE) {
            planar_line_block(s, pw, m, xb, yb, zb, ob);
            continue;
        }
        if (s->method == FM_SWEEP_CAPSULE) {
            unsigned char slow[BLOCK];
            size_t nslow;
            capsule_block(s, m, xb, yb, zb, ob, slow, &nslow);
            for (size_t k = 0; nslow && k < m; k++) {
                if (!slow[k]) continue;
                nslow--;
                const double p[3] = {xb[k], yb[k], zb[k]};
                fm_sweep_value v;
                fm_sweep_eval_ex(s, worker, p, &v);
                ob[k] = v.value;
                if (shortfall && v.exhausted) shortfall[b + k] = v.upper - v.value;
            }
            continue;
        }
        for (size_t k = 0; k < m; k++) {
            const double p[3] = {xb[k], yb[k], zb[k]};
            fm_sweep_value v;
            fm_sweep_eval_ex(s, worker, p, &v);
            ob[k] = v.value;
            if (shortfall && v.exhausted) shortfall[b + k] = v.upper - v.value;
        }
    }
}
