/* interval.c: interval arithmetic over a box for every op (sound: every
 * value the point evaluator can return at a point of the box lies inside),
 * and tape shortening: the min/max (and select) branches decided over the
 * box are replaced by the winning operand and the rest is removed.
 *
 * NaN: an interval encloses the non-NaN values; a separate flag says the
 * value may be NaN somewhere in the box (sqrt of a negative, 0/0, ...).
 * Comparisons and logic ops turn NaN into 0 or 1, and min/max return their
 * second operand when the first is NaN, so the flag feeds the enclosures
 * there. An interval with no non-NaN value is [NaN, NaN].
 *
 * Rounding: bounds computed in round-to-nearest are moved outward: by one
 * ulp for + - * / only when the operation was inexact (checked exactly with
 * two-sum / fma), by two ulps for libm functions (glibc's are within one
 * ulp, and the point evaluator's value at an interior point can err the
 * other way by one more), and clamped to the function's exact range. */
#include "frep/tape_internal.h"

#include <stdlib.h>
#include <string.h>

typedef struct ival {
    double lo, hi;
    int nan; /* may be NaN */
} ival;

static const ival EMPTY_NAN = {NAN, NAN, 1};

static int empty(ival a)
{
    return isnan(a.lo);
}

static double dn(double x)
{
    return nextafter(x, -INFINITY);
}

static double up(double x)
{
    return nextafter(x, INFINITY);
}

static double dn2(double x)
{
    return dn(dn(x));
}

static double up2(double x)
{
    return up(up(x));
}

static ival mk(double lo, double hi, int nan)
{
    ival r = {lo, hi, nan};
    if (isnan(lo) || isnan(hi)) {
        /* Only from inf - inf and the like: unknown. */
        r.lo = -INFINITY;
        r.hi = INFINITY;
        r.nan = 1;
    }
    return r;
}

static ival hull(ival a, ival b)
{
    if (empty(a)) {
        b.nan |= a.nan;
        return b;
    }
    if (empty(b)) {
        a.nan |= b.nan;
        return a;
    }
    ival r = {a.lo < b.lo ? a.lo : b.lo, a.hi > b.hi ? a.hi : b.hi, a.nan | b.nan};
    return r;
}

static ival point_ival(double v)
{
    ival r = {v, v, 0};
    return r;
}

/* Sum bounds, moved outward only when the rounded sum is inexact. */
static double add_dn(double a, double b)
{
    double s = a + b;
    if (!isfinite(s)) return s;
    double bb = s - a, err = (a - (s - bb)) + (b - bb);
    return err < 0 ? dn(s) : s;
}

static double add_up(double a, double b)
{
    double s = a + b;
    if (!isfinite(s)) return s;
    double bb = s - a, err = (a - (s - bb)) + (b - bb);
    return err > 0 ? up(s) : s;
}

/* Products with 0 * inf taken as 0 (the limit; the NaN a point may give
 * there is flagged by the caller). */
static double mul0(double a, double b)
{
    return (a == 0.0 || b == 0.0) ? 0.0 : a * b;
}

static double mul_dn(double a, double b)
{
    double p = mul0(a, b);
    if (!isfinite(p)) return p;
    if (p == 0.0) return (a != 0.0 && b != 0.0) ? dn(0.0) : 0.0; /* underflow */
    return fma(a, b, -p) < 0 ? dn(p) : p;
}

static double mul_up(double a, double b)
{
    double p = mul0(a, b);
    if (!isfinite(p)) return p;
    if (p == 0.0) return (a != 0.0 && b != 0.0) ? up(0.0) : 0.0;
    return fma(a, b, -p) > 0 ? up(p) : p;
}

static double div_dn(double a, double b)
{
    double q = a / b;
    if (!isfinite(q) || !isfinite(b) || !isfinite(a)) return q;
    double e = -fma(q, b, -a); /* a - q b, exact */
    /* a / b - q has the sign of e / b. */
    return (b > 0 ? e < 0 : e > 0) ? dn(q) : q;
}

static double div_up(double a, double b)
{
    double q = a / b;
    if (!isfinite(q) || !isfinite(b) || !isfinite(a)) return q;
    double e = -fma(q, b, -a);
    return (b > 0 ? e > 0 : e < 0) ? up(q) : q;
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* Increasing libm function over [lo, hi], range clamped to [rlo, rhi]. */
static ival mono_up(double (*f)(double), ival a, double rlo, double rhi)
{
    return mk(clampd(dn2(f(a.lo)), rlo, rhi), clampd(up2(f(a.hi)), rlo, rhi), a.nan);
}

/* Does [lo, hi] contain a point offset + k * period for an integer k?
 * Slack toward yes, so that rounding never hides an extremum or a pole. */
static int contains_periodic(double lo, double hi, double offset, double period)
{
    double kl = (lo - offset) / period, kh = (hi - offset) / period;
    double slack = 1e-9 + 1e-15 * (fabs(kl) + fabs(kh));
    return floor(kh + slack) >= ceil(kl - slack);
}

static ival sin_cos(ival a, int is_cos)
{
    if (!isfinite(a.lo) || !isfinite(a.hi)) {
        if (a.lo == a.hi) return EMPTY_NAN; /* sin(inf) is NaN */
        return mk(-1.0, 1.0, 1);
    }
    if (a.hi - a.lo >= 2 * FM_PI || fabs(a.lo) > 1e8 || fabs(a.hi) > 1e8)
        return mk(-1.0, 1.0, a.nan);
    double fl = is_cos ? cos(a.lo) : sin(a.lo), fh = is_cos ? cos(a.hi) : sin(a.hi);
    double lo = fl < fh ? fl : fh, hi = fl < fh ? fh : fl;
    lo = dn2(lo);
    hi = up2(hi);
    double max_at = is_cos ? 0.0 : FM_PI / 2, min_at = is_cos ? FM_PI : -FM_PI / 2;
    if (contains_periodic(a.lo, a.hi, max_at, 2 * FM_PI)) hi = 1.0;
    if (contains_periodic(a.lo, a.hi, min_at, 2 * FM_PI)) lo = -1.0;
    return mk(clampd(lo, -1, 1), clampd(hi, -1, 1), a.nan);
}

/* Truth of a condition value over the box: can it be non-zero (NaN counts
 * as non-zero), can it be zero? */
static void truth(ival a, int *can_true, int *can_false)
{
    *can_true = a.nan || (!empty(a) && !(a.lo == 0.0 && a.hi == 0.0));
    *can_false = !empty(a) && a.lo <= 0.0 && a.hi >= 0.0;
}

static ival bool_ival(int can_true, int can_false)
{
    ival r = {can_false ? 0.0 : 1.0, can_true ? 1.0 : 0.0, 0};
    return r;
}

static ival ival_unary(fm_op op, ival a)
{
    if (op == FM_OP_NOT) {
        int t, f;
        truth(a, &t, &f);
        return bool_ival(f, t); /* NOT is 1 where a is 0 */
    }
    if (op == FM_OP_SIGN) {
        ival r = a.nan ? point_ival(0.0) : EMPTY_NAN; /* sign(NaN) = 0 */
        r.nan = 0;
        if (empty(a)) return r;
        ival s = {(double)((a.lo > 0) - (a.lo < 0)), (double)((a.hi > 0) - (a.hi < 0)), 0};
        return hull(r, s);
    }
    if (empty(a)) return EMPTY_NAN;
    switch (op) {
    case FM_OP_NEG: return mk(-a.hi, -a.lo, a.nan);
    case FM_OP_ABS:
        if (a.lo >= 0) return mk(a.lo, a.hi, a.nan);
        if (a.hi <= 0) return mk(-a.hi, -a.lo, a.nan);
        return mk(0.0, -a.lo > a.hi ? -a.lo : a.hi, a.nan);
    case FM_OP_SQUARE: {
        double l = a.lo >= 0 ? a.lo : a.hi <= 0 ? -a.hi : 0.0;
        double h = -a.lo > a.hi ? -a.lo : a.hi;
        double lo = mul_dn(l, l);
        return mk(lo < 0 ? 0.0 : lo, mul_up(h, h), a.nan);
    }
    case FM_OP_SQRT: {
        if (a.hi < 0) return EMPTY_NAN;
        int nan = a.nan || a.lo < 0;
        double l = a.lo < 0 ? 0.0 : a.lo;
        /* sqrt is correctly rounded: one ulp out is enough. */
        double lo = dn(sqrt(l)), hi = up(sqrt(a.hi));
        return mk(lo < 0 ? 0.0 : lo, hi, nan);
    }
    case FM_OP_EXP: return mono_up(exp, a, 0.0, INFINITY);
    case FM_OP_LOG: {
        if (a.hi < 0) return EMPTY_NAN;
        int nan = a.nan || a.lo < 0;
        double l = a.lo < 0 ? 0.0 : a.lo;
        return mk(dn2(log(l)), up2(log(a.hi)), nan);
    }
    case FM_OP_SIN: return sin_cos(a, 0);
    case FM_OP_COS: return sin_cos(a, 1);
    case FM_OP_TAN: {
        if (!isfinite(a.lo) || !isfinite(a.hi)) return mk(-INFINITY, INFINITY, 1);
        if (a.hi - a.lo >= FM_PI || fabs(a.lo) > 1e8 || fabs(a.hi) > 1e8 ||
            contains_periodic(a.lo, a.hi, FM_PI / 2, FM_PI))
            return mk(-INFINITY, INFINITY, a.nan);
        return mk(dn2(tan(a.lo)), up2(tan(a.hi)), a.nan);
    }
    case FM_OP_ASIN:
    case FM_OP_ACOS: {
        if (a.hi < -1.0 || a.lo > 1.0) return EMPTY_NAN;
        int nan = a.nan || a.lo < -1.0 || a.hi > 1.0;
        double l = a.lo < -1.0 ? -1.0 : a.lo, h = a.hi > 1.0 ? 1.0 : a.hi;
        if (op == FM_OP_ASIN) return mk(dn2(asin(l)), up2(asin(h)), nan);
        double lo = dn2(acos(h));
        return mk(lo < 0 ? 0.0 : lo, up2(acos(l)), nan);
    }
    case FM_OP_ATAN: return mono_up(atan, a, -INFINITY, INFINITY);
    case FM_OP_SINH: return mono_up(sinh, a, -INFINITY, INFINITY);
    case FM_OP_TANH: return mono_up(tanh, a, -1.0, 1.0);
    case FM_OP_COSH: {
        double l = a.lo >= 0 ? a.lo : a.hi <= 0 ? -a.hi : 0.0;
        double h = -a.lo > a.hi ? -a.lo : a.hi;
        double lo = dn2(cosh(l));
        return mk(lo < 1.0 ? 1.0 : lo, up2(cosh(h)), a.nan);
    }
    case FM_OP_FLOOR: return mk(floor(a.lo), floor(a.hi), a.nan);
    case FM_OP_CEIL: return mk(ceil(a.lo), ceil(a.hi), a.nan);
    case FM_OP_TRUNC: return mk(trunc(a.lo), trunc(a.hi), a.nan);
    default: return mk(-INFINITY, INFINITY, 1);
    }
}

static ival ival_add(ival a, ival b)
{
    int nan = a.nan || b.nan || (a.lo == -INFINITY && b.hi == INFINITY) ||
              (a.hi == INFINITY && b.lo == -INFINITY);
    return mk(add_dn(a.lo, b.lo), add_up(a.hi, b.hi), nan);
}

static ival ival_mul(ival a, ival b)
{
    int a0 = a.lo <= 0 && a.hi >= 0, b0 = b.lo <= 0 && b.hi >= 0;
    int ainf = isinf(a.lo) || isinf(a.hi), binf = isinf(b.lo) || isinf(b.hi);
    int nan = a.nan || b.nan || (a0 && binf) || (b0 && ainf);
    double c[4][2] = {{a.lo, b.lo}, {a.lo, b.hi}, {a.hi, b.lo}, {a.hi, b.hi}};
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 4; i++) {
        double l = mul_dn(c[i][0], c[i][1]), h = mul_up(c[i][0], c[i][1]);
        if (l < lo) lo = l;
        if (h > hi) hi = h;
    }
    return mk(lo, hi, nan);
}

static ival ival_div(ival a, ival b)
{
    int a0 = a.lo <= 0 && a.hi >= 0;
    if (b.lo <= 0 && b.hi >= 0) return mk(-INFINITY, INFINITY, a.nan || b.nan || a0);
    int ainf = isinf(a.lo) || isinf(a.hi), binf = isinf(b.lo) || isinf(b.hi);
    if (ainf && binf) return mk(-INFINITY, INFINITY, 1);
    double c[4][2] = {{a.lo, b.lo}, {a.lo, b.hi}, {a.hi, b.lo}, {a.hi, b.hi}};
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 4; i++) {
        double l = div_dn(c[i][0], c[i][1]), h = div_up(c[i][0], c[i][1]);
        if (l < lo) lo = l;
        if (h > hi) hi = h;
    }
    return mk(lo, hi, a.nan || b.nan);
}

static int is_integer(double v)
{
    return isfinite(v) && floor(v) == v;
}

/* pow over a box part with x >= 0: y ln x is bilinear in (y, ln x), so
 * the extremes are at the corners (pow's own rules for 0 and inf give the
 * limits there). */
static ival pow_nonneg(double xl, double xh, double yl, double yh)
{
    double v[4] = {pow(xl, yl), pow(xl, yh), pow(xh, yl), pow(xh, yh)};
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 4; i++) {
        if (v[i] < lo) lo = v[i];
        if (v[i] > hi) hi = v[i];
    }
    lo = dn2(lo);
    return mk(lo < 0 ? 0.0 : lo, up2(hi), 0);
}

static ival ival_pow(ival a, ival b)
{
    ival r = EMPTY_NAN;
    r.nan = 0;
    /* pow(NaN, 0) = 1 and pow(1, NaN) = 1. */
    if (a.nan) {
        if (!empty(b) && b.lo <= 0 && b.hi >= 0) r = hull(r, point_ival(1.0));
        r.nan = 1;
    }
    if (b.nan) {
        if (!empty(a) && a.lo <= 1 && a.hi >= 1) r = hull(r, point_ival(1.0));
        r.nan = 1;
    }
    if (empty(a) || empty(b)) return r;
    if (b.lo == b.hi && b.lo == 0.0) return hull(r, point_ival(1.0)); /* pow(x, 0) = 1 */
    if (a.hi >= 0) r = hull(r, pow_nonneg(a.lo > 0 ? a.lo : 0.0, a.hi, b.lo, b.hi));
    if (a.lo == 0.0 && b.lo < 0 && floor(b.hi) >= ceil(b.lo))
        r = hull(r, mk(-INFINITY, 0.0, 0)); /* pow(-0, odd negative) = -inf */
    if (a.lo < 0) {
        double xl = a.hi < 0 ? -a.hi : 0.0, xh = -a.lo; /* |x| for the negative part */
        if (b.lo == b.hi && is_integer(b.lo)) {
            ival m = pow_nonneg(xl, xh, b.lo, b.lo);
            if (fmod(b.lo, 2.0) == 0.0) r = hull(r, m);
            else r = hull(r, mk(-m.hi, -m.lo, 0));
        } else {
            /* Non-integer exponents give NaN; integer ones +-|x|^y. */
            r.nan = 1;
            if (floor(b.hi) >= ceil(b.lo)) {
                ival m = pow_nonneg(xl, xh, b.lo, b.hi);
                r = hull(r, mk(-m.hi, m.hi, 0));
            }
        }
    }
    return r;
}

static ival ival_atan2(ival a, ival b)
{
    int nan = a.nan || b.nan;
    /* Around the origin or across the branch cut (x < 0, y through 0,
     * where +0 and -0 give +pi and -pi): the whole range. */
    if ((a.lo <= 0 && a.hi >= 0) && b.lo <= 0) return mk(-up2(FM_PI), up2(FM_PI), nan);
    double c[4] = {atan2(a.lo, b.lo), atan2(a.lo, b.hi), atan2(a.hi, b.lo), atan2(a.hi, b.hi)};
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 4; i++) {
        if (c[i] < lo) lo = c[i];
        if (c[i] > hi) hi = c[i];
    }
    return mk(dn2(lo), up2(hi), nan);
}

static ival ival_mod(ival a, ival b)
{
    int nan = a.nan || b.nan || (b.lo <= 0 && b.hi >= 0) || isinf(a.lo) || isinf(a.hi);
    if (b.lo == 0 && b.hi == 0) return EMPTY_NAN;
    if (isinf(a.lo) && a.lo == a.hi) return EMPTY_NAN;
    double bm = fabs(b.lo) > fabs(b.hi) ? fabs(b.lo) : fabs(b.hi);
    /* Within one period of a constant divisor fmod (exact) is monotonic. */
    if (b.lo == b.hi && (a.lo >= 0 || a.hi <= 0) && isfinite(a.lo) && isfinite(a.hi) &&
        a.hi - a.lo < bm) {
        double fl = fmod(a.lo, b.lo), fh = fmod(a.hi, b.lo);
        if (fl <= fh) return mk(fl, fh, nan);
    }
    double am = fabs(a.lo) > fabs(a.hi) ? fabs(a.lo) : fabs(a.hi);
    double m = am < bm ? am : bm;
    if (a.lo >= 0) return mk(0.0, m, nan);
    if (a.hi <= 0) return mk(-m, 0.0, nan);
    return mk(-m, m, nan);
}

/* min(a, b) = a < b ? a : b: where a is NaN it gives b, where b is NaN it
 * gives NaN. max likewise. */
static ival ival_minmax(fm_op op, ival a, ival b)
{
    ival r = EMPTY_NAN;
    r.nan = 0;
    if (!empty(a) && !empty(b)) {
        r = op == FM_OP_MIN ? mk(fmin(a.lo, b.lo), fmin(a.hi, b.hi), 0)
                            : mk(fmax(a.lo, b.lo), fmax(a.hi, b.hi), 0);
    }
    if (a.nan) r = hull(r, b);
    r.nan = b.nan;
    return r;
}

static ival ival_compare(fm_op op, ival a, ival b)
{
    int can_t = 0, can_f = 0;
    if (a.nan || b.nan) {
        if (op == FM_OP_NE) can_t = 1;
        else can_f = 1;
    }
    if (!empty(a) && !empty(b)) {
        switch (op) {
        case FM_OP_LT:
            can_t |= a.lo < b.hi;
            can_f |= a.hi >= b.lo;
            break;
        case FM_OP_LE:
            can_t |= a.lo <= b.hi;
            can_f |= a.hi > b.lo;
            break;
        case FM_OP_EQ:
        case FM_OP_NE: {
            int may_eq = a.lo <= b.hi && b.lo <= a.hi;
            int must_eq = a.lo == a.hi && b.lo == b.hi && a.lo == b.lo;
            int t = may_eq, f = !must_eq;
            if (op == FM_OP_NE) {
                t = !must_eq;
                f = may_eq;
            }
            can_t |= t;
            can_f |= f;
            break;
        }
        default: break;
        }
    }
    return bool_ival(can_t, can_f);
}

static ival ival_binary(fm_op op, ival a, ival b)
{
    switch (op) {
    case FM_OP_MIN:
    case FM_OP_MAX: return ival_minmax(op, a, b);
    case FM_OP_LT:
    case FM_OP_LE:
    case FM_OP_EQ:
    case FM_OP_NE: return ival_compare(op, a, b);
    case FM_OP_AND:
    case FM_OP_OR: {
        int at, af, bt, bf;
        truth(a, &at, &af);
        truth(b, &bt, &bf);
        if (op == FM_OP_AND) return bool_ival(at && bt, af || bf);
        return bool_ival(at || bt, af && bf);
    }
    case FM_OP_POW: return ival_pow(a, b);
    default: break;
    }
    if (empty(a) || empty(b)) return EMPTY_NAN;
    switch (op) {
    case FM_OP_ADD: return ival_add(a, b);
    case FM_OP_SUB: {
        ival nb = {-b.hi, -b.lo, b.nan};
        return ival_add(a, nb);
    }
    case FM_OP_MUL: return ival_mul(a, b);
    case FM_OP_DIV: return ival_div(a, b);
    case FM_OP_ATAN2: return ival_atan2(a, b);
    case FM_OP_MOD: return ival_mod(a, b);
    default: return mk(-INFINITY, INFINITY, 1);
    }
}

/* Branch choices recorded for shortening. */
enum { CHOOSE_NONE = 0, CHOOSE_A = 1, CHOOSE_B = 2, CHOOSE_C = 3 };

static ival operand(const fm_evaluator *ev, const fm_insn *in, int which)
{
    ival r;
    uint32_t slot;
    if ((which == 0 && (in->imm_mask & FM_IMM_A)) || (which == 1 && (in->imm_mask & FM_IMM_B))) {
        r.lo = r.hi = in->imm;
        r.nan = isnan(in->imm);
        return r;
    }
    slot = which == 0 ? in->a : which == 1 ? in->b : in->c;
    r.lo = ev->ivl[slot].lo;
    r.hi = ev->ivl[slot].hi;
    r.nan = ev->ivl_nan[slot];
    return r;
}

fm_interval fm_eval_interval_nan(fm_evaluator *ev, const fm_interval box[4], int *maybe_nan)
{
    const fm_tape *t = ev->tape;
    for (int i = 0; i < FM_AXES; i++) {
        ev->ivl[i] = box[i];
        ev->ivl_nan[i] = isnan(box[i].lo) || isnan(box[i].hi);
    }
    for (uint32_t i = FM_AXES; i < t->nleaf; i++) {
        double v = t->param_values[i - FM_AXES];
        ev->ivl[i].lo = ev->ivl[i].hi = v;
        ev->ivl_nan[i] = isnan(v);
    }
    for (size_t k = 0; k < t->ninsns; k++) {
        const fm_insn *in = &t->insns[k];
        fm_op op = (fm_op)in->op;
        uint8_t choice = CHOOSE_NONE;
        ival r;
        switch (fm_op_arity(op)) {
        case 0:
            r.lo = r.hi = in->imm;
            r.nan = isnan(in->imm);
            break;
        case 1: r = ival_unary(op, operand(ev, in, 0)); break;
        case 2: {
            ival a = operand(ev, in, 0), b = operand(ev, in, 1);
            r = ival_binary(op, a, b);
            /* A branch is decided when it wins at every point of the box,
             * ties included as a < b ? a : b resolves them, and neither
             * side can be NaN (then min's answer depends on which is). */
            if ((op == FM_OP_MIN || op == FM_OP_MAX) && !a.nan && !b.nan && !empty(a) && !empty(b)) {
                if (op == FM_OP_MIN) choice = a.hi < b.lo ? CHOOSE_A : b.hi <= a.lo ? CHOOSE_B : 0;
                else choice = a.lo > b.hi ? CHOOSE_A : a.hi <= b.lo ? CHOOSE_B : 0;
            }
            break;
        }
        case 3: {
            ival c = operand(ev, in, 0), b = operand(ev, in, 1), e = operand(ev, in, 2);
            int ct, cf;
            truth(c, &ct, &cf);
            r = EMPTY_NAN;
            r.nan = 0;
            if (ct) r = hull(r, b);
            if (cf) r = hull(r, e);
            choice = ct && !cf ? CHOOSE_B : cf && !ct ? CHOOSE_C : 0;
            break;
        }
        default: {
            int nan = 0;
            fm_interval s;
            if (op == FM_OP_VOXELS) {
                ival x = operand(ev, in, 0), y = operand(ev, in, 1), z = operand(ev, in, 2);
                nan = x.nan || y.nan || z.nan;
                if (empty(x) || empty(y) || empty(z)) {
                    r = EMPTY_NAN;
                    break;
                }
                fm_interval xyz[3] = {{x.lo, x.hi}, {y.lo, y.hi}, {z.lo, z.hi}};
                s = fm_voxels_interval(&t->shared->specials[in->aux].grid, xyz);
            } else {
                s = fm_special_interval(ev, in, box, &nan);
            }
            r.lo = s.lo;
            r.hi = s.hi;
            r.nan = nan;
            break;
        }
        }
        ev->ivl[in->out].lo = r.lo;
        ev->ivl[in->out].hi = r.hi;
        ev->ivl_nan[in->out] = (uint8_t)(r.nan != 0);
        ev->choice[k] = choice;
    }
    if (maybe_nan) *maybe_nan = ev->ivl_nan[t->result];
    return ev->ivl[t->result];
}

fm_interval fm_eval_interval(fm_evaluator *ev, const fm_interval box[4])
{
    return fm_eval_interval_nan(ev, box, NULL);
}

/* Room in ev's shortening scratch for a tape of nleaf leaves and n
 * instructions (the evaluator's root bounds every tape it shortens, so the
 * scratch grows once). */
static int shorten_scratch(fm_evaluator *ev, size_t nvn, size_t n)
{
    if (nvn > ev->sh_nvn_cap) {
        size_t bytes;
        if (!fm_size_mul(nvn, 3 * sizeof *ev->sh_map, &bytes)) return 0;
        uint32_t *map = malloc(bytes);
        uint8_t *live = malloc(nvn);
        if (!map || !live) {
            free(map);
            free(live);
            return 0;
        }
        free(ev->sh_map);
        free(ev->sh_live);
        ev->sh_map = map;
        ev->sh_live = live;
        ev->sh_nvn_cap = nvn;
    }
    if (n > ev->sh_code_cap) {
        fm_insn *code = malloc((n ? n : 1) * sizeof *code);
        if (!code) return 0;
        free(ev->sh_code);
        ev->sh_code = code;
        ev->sh_code_cap = n;
    }
    return 1;
}

/* The instructions of the evaluator's tape that can still win inside the
 * box its last interval evaluation saw (ev->choice), into ev->sh_code in
 * value-number form; *res gets the result's value number. Returns their
 * number: the tape's length when nothing is dropped, and 0 with *res ==
 * FM_NO_OPERAND when the scratch cannot be had. */
static size_t shorten_code(fm_evaluator *ev, uint32_t *res)
{
    const fm_tape *t = ev->tape;
    size_t n = t->ninsns;
    uint32_t nleaf = t->nleaf;
    size_t nvn = nleaf + n;
    *res = FM_NO_OPERAND;
    if (!shorten_scratch(ev, nvn, n)) return 0;
    uint32_t *alias = ev->sh_map, *renum = ev->sh_map + nvn;
    uint8_t *live = ev->sh_live;
    fm_insn *code = ev->sh_code;
    memset(live, 0, nvn);
    for (size_t v = 0; v < nvn; v++) alias[v] = (uint32_t)v;
    /* Forward: operands through aliases; a decided instruction becomes an
     * alias of its winner (or a constant when the winner is immediate). */
    for (size_t k = 0; k < n; k++) {
        fm_insn in = t->insns[k];
        if (in.sa != FM_NO_OPERAND) in.sa = alias[in.sa];
        if (in.sb != FM_NO_OPERAND) in.sb = alias[in.sb];
        if (in.sc != FM_NO_OPERAND) in.sc = alias[in.sc];
        uint8_t c = ev->choice[k];
        if (c != CHOOSE_NONE) {
            int imm = (c == CHOOSE_A && (in.imm_mask & FM_IMM_A)) ||
                      (c == CHOOSE_B && (in.imm_mask & FM_IMM_B));
            if (imm) {
                double v = in.imm;
                memset(&in, 0, sizeof in);
                in.op = FM_OP_CONST;
                in.imm = v;
                in.sa = in.sb = in.sc = FM_NO_OPERAND;
            } else {
                alias[nleaf + k] = c == CHOOSE_A ? in.sa : c == CHOOSE_B ? in.sb : in.sc;
            }
        }
        code[k] = in;
    }
    /* Backward: what the result still needs. */
    live[alias[t->result_ssa]] = 1;
    for (size_t k = n; k-- > 0;) {
        uint32_t v = nleaf + (uint32_t)k;
        if (!live[v] || alias[v] != v) continue;
        if (code[k].sa != FM_NO_OPERAND) live[code[k].sa] = 1;
        if (code[k].sb != FM_NO_OPERAND) live[code[k].sb] = 1;
        if (code[k].sc != FM_NO_OPERAND) live[code[k].sc] = 1;
    }
    size_t m = 0;
    for (uint32_t v = 0; v < nleaf; v++) renum[v] = v;
    for (size_t k = 0; k < n; k++) {
        uint32_t v = nleaf + (uint32_t)k;
        if (!live[v] || alias[v] != v) continue;
        fm_insn in = code[k];
        if (in.sa != FM_NO_OPERAND) in.sa = renum[in.sa];
        if (in.sb != FM_NO_OPERAND) in.sb = renum[in.sb];
        if (in.sc != FM_NO_OPERAND) in.sc = renum[in.sc];
        renum[v] = nleaf + (uint32_t)m;
        code[m++] = in;
    }
    *res = renum[alias[t->result_ssa]];
    return m;
}

/* Did the last interval evaluation decide any branch? */
static int any_decided(const fm_evaluator *ev)
{
    for (size_t k = 0; k < ev->tape->ninsns; k++)
        if (ev->choice[k] != CHOOSE_NONE) return 1;
    return 0;
}

fm_tape *fm_eval_interval_shorten(fm_evaluator *ev, const fm_interval box[4],
                                  fm_interval *result)
{
    fm_interval r = fm_eval_interval_nan(ev, box, NULL);
    if (result) *result = r;
    if (!any_decided(ev)) return NULL;
    const fm_tape *t = ev->tape;
    uint32_t res;
    size_t m = shorten_code(ev, &res);
    if (res == FM_NO_OPERAND || m >= t->ninsns) return NULL;
    fm_insn *code = malloc((m ? m : 1) * sizeof *code);
    if (!code) return NULL;
    memcpy(code, ev->sh_code, m * sizeof *code);
    fm_tape *s = fm_tape_from_ssa(t->shared, t->param_values, code, m, res, t->root_ninsns);
    if (s && s->reg_capacity < t->reg_capacity) s->reg_capacity = t->reg_capacity;
    return s;
}

fm_tape *fm_eval_interval_shorten_in(fm_evaluator *ev, const fm_interval box[4],
                                     fm_interval *result, fm_tape **slot)
{
    fm_interval r = fm_eval_interval_nan(ev, box, NULL);
    if (result) *result = r;
    const fm_tape *t = ev->tape;
    fm_tape *s = *slot;
    /* the tape in use is not rewritten under the evaluator; keeping it is
     * correct (a tape is valid wherever its shortenings are) */
    if (s == t || !any_decided(ev)) return NULL;
    uint32_t res;
    size_t m = shorten_code(ev, &res);
    if (res == FM_NO_OPERAND || m >= t->ninsns) return NULL;
    if (!s || s->shared != t->shared || s->insns_cap < m) {
        /* room for any shortening of the same root */
        size_t cap = t->root_ninsns > m ? t->root_ninsns : m;
        fm_insn *code = malloc((cap ? cap : 1) * sizeof *code);
        if (!code) return NULL;
        memcpy(code, ev->sh_code, m * sizeof *code);
        fm_tape *made = fm_tape_from_ssa(t->shared, t->param_values, code, m, res, t->root_ninsns);
        if (!made) return NULL;
        made->insns_cap = cap;
        if (made->reg_capacity < t->reg_capacity) made->reg_capacity = t->reg_capacity;
        fm_tape_free(s);
        *slot = made;
        return made;
    }
    /* in place: the same family, so the same leaves and parameters */
    memcpy(s->insns, ev->sh_code, m * sizeof *s->insns);
    if (t->shared->nparams)
        memcpy(s->param_values, t->param_values, t->shared->nparams * sizeof *s->param_values);
    /* the value-number maps are free again: the slots' scratch */
    s->nregs = fm_tape_assign_slots(s->insns, m, s->nleaf, res, ev->sh_map, &s->result);
    s->ninsns = m;
    s->result_ssa = res;
    s->root_ninsns = t->root_ninsns > m ? t->root_ninsns : m;
    s->reg_capacity = s->nregs > t->reg_capacity ? s->nregs : t->reg_capacity;
    return s;
}
