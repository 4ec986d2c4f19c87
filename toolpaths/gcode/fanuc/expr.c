/* expr.c: Fanuc Custom Macro B values: numbers, [expressions]
 * with Fanuc's precedence (functions; * / AND MOD; + - OR XOR; EQ NE GT GE
 * LT LE), the functions SIN COS TAN ASIN ACOS ATAN SQRT ABS ROUND FIX FUP BIN
 * BCD LN EXP in degrees with Fanuc's output ranges and rounding, and the
 * variables: #0 (always vacant), locals #1-#33 per call level, commons
 * #100-#999, and the system variables a program needs to run (#3000 alarm,
 * timers, #4001-#4120 modal information, #5001.. positions, work offsets).
 * Vacancy follows Fanuc's rules: a vacant variable alone is vacant, in
 * arithmetic it is 0, and EQ/NE tell it from 0. */
#include "fanuc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_DEPTH 64 /* brackets and indirections (Fanuc allows 5 bracket levels) */

typedef struct val {
    double v;
    int vacant;
} val;

static double num(val a) { return a.vacant ? 0.0 : a.v; }

double gc_fanuc_round(double v) { return v < 0 ? -floor(-v + 0.5) : floor(v + 0.5); }

/* ---- variables ---- */

static fm_status bad_var(gc_interp *g, long n, int col, const char *why)
{
    return gc_fail(g, FM_ERR_INPUT, col, "#%ld: %s", n, why);
}

static int offset_var(long n, int *table, int *axis)
{
    /* #5201-#5206 external offset (table 0), #5221.. G54..G59 (tables 1-6),
     * 20 numbers apart */
    if (n >= 5201 && n <= 5326) {
        long k = n - 5201;
        if (k % 20 >= 6) return 0;
        *table = (int)(k / 20);
        *axis = (int)(k % 20);
        return 1;
    }
    return 0;
}

static double g_value(int code) { return code / 10.0; }

/* #4001-#4022: the modal G codes of the groups Fanuc numbers 1-22. */
static double modal_info(gc_interp *g, int group)
{
    gc_fanuc *f = FANUC(g);
    switch (group) {
    case 1: return f->group1;
    case 2: return g->plane;
    case 3: return g->absolute ? 90 : 91;
    case 4: return 23;
    case 5: return g->inverse_time ? 93 : 94;
    case 6: return g->unit == 1.0 ? 21 : 20;
    case 7: return 40;
    case 8: return g_value(f->tool_length_mode);
    case 9: return g->motion == GC_G80 || g->motion < GC_G73 ? 80 : g_value(g->motion);
    case 10: return g->retract_r ? 99 : 98;
    case 11: return f->scaling ? 51 : 50;
    case 12: return 67;
    case 13: return 97;
    case 14: return f->ext_cs ? 54.1 : 53 + g->cs;
    case 15: return 64;
    case 16: return f->rotation ? 68 : 69;
    case 17: return f->polar ? 16 : 15;
    case 18: return 40.1;
    case 19: return 50.1;
    default: return GC_VACANT;
    }
}

fm_status gc_fanuc_get_var(gc_interp *g, long n, int col, double *out)
{
    gc_fanuc *f = FANUC(g);
    int table, axis;
    if (n == 0) {
        *out = GC_VACANT;
    } else if (n >= 1 && n <= 33) {
        *out = f->locals[f->level][n];
    } else if (n >= GC_FANUC_COMMON_LO && n <= GC_FANUC_COMMON_HI) {
        *out = f->common[n - GC_FANUC_COMMON_LO];
    } else if (n >= 1000 && n <= 1999) {
        return bad_var(g, n, col, "interface signals (#1000-#1999) are not simulated");
    } else if (n >= 2001 && n <= 2200) {
        /* the tool table's length of offset number n - 2000 (Haas: length
         * geometry; Fanuc memory A: the offset value) */
        *out = gc_tool_length_mm(g, (int)(n - 2000)) / g->unit;
    } else if (n == 3001) {
        *out = g->t * 1000.0 + f->timer_base_ms;
    } else if (n == 3002) {
        *out = g->t / 3600.0 + f->timer_base_h;
    } else if (n == 3003) {
        *out = f->sys3003;
    } else if (n == 3004) {
        *out = f->sys3004;
    } else if (n == 3901 || n == 3902) {
        *out = f->parts[n - 3901];
    } else if (n >= 4001 && n <= 4022) {
        *out = modal_info(g, (int)(n - 4000));
    } else if (n >= 4101 && n <= 4130) {
        switch (n) {
        case 4107: *out = f->d; break;
        case 4109: *out = g->feed; break;
        case 4111: *out = f->h; break;
        case 4113: *out = f->last_m; break;
        case 4114: *out = (double)f->sequence; break;
        case 4115: {
            long pn = f->programs[f->cur_program].number;
            *out = pn < 0 ? 0 : (double)pn;
            break;
        }
        case 4119: *out = g->speed; break;
        case 4120: *out = g->selected_tool; break;
        default: *out = GC_VACANT; break;
        }
    } else if (n >= 5001 && n <= 5006) {
        double w[3];
        gc_fanuc_to_work(g, f->prog, w);
        *out = n <= 5003 ? w[n - 5001] : 0.0;
    } else if (n >= 5021 && n <= 5026) {
        *out = n <= 5023 ? g->pos[n - 5021] + g->g5x[n - 5021] + g->g92[n - 5021] +
                               g->tlo[n - 5021]
                         : 0.0;
    } else if (n >= 5041 && n <= 5046) {
        *out = n <= 5043 ? g->pos[n - 5041] : 0.0;
    } else if (n >= 5081 && n <= 5086) {
        *out = n <= 5083 ? g->tlo[n - 5081] : 0.0;
    } else if (offset_var(n, &table, &axis)) {
        *out = axis < 3 ? g->params[n] : 0.0;
    } else if (n >= 7001 && n <= 7000 + 20 * GC_FANUC_EXT_OFFSETS) {
        long k = n - 7001;
        *out = k % 20 < 3 ? f->ext_offsets[k / 20][k % 20] : 0.0;
    } else {
        return bad_var(g, n, col,
                       "not a variable this simulation has; expected #0, #1-#33, #100-#999, "
                       "#2001-#2200, #3000-#3004, #3901-#3902, #4001-#4120, #5001-#5086, "
                       "#5201-#5326 or #7001-#7960");
    }
    return FM_OK;
}

/* #3000 = n (MESSAGE): the alarm, as an error with the message. */
static fm_status alarm(gc_interp *g, double v, int col)
{
    const char *text;
    size_t len;
    gc_fanuc_raw_line(g, &text, &len);
    size_t i = 0, a = 0, b = 0;
    /* the message is the comment after the '=' of the assignment */
    while (i < len && text[i] != '=') i++;
    while (i < len && text[i] != '(') i++;
    if (i < len) {
        a = ++i;
        while (i < len && text[i] != ')') i++;
        b = i;
    }
    long n = isnan(v) ? 0 : (long)gc_fanuc_round(v);
    return gc_fail(g, FM_ERR_INPUT, col, "alarm %ld (#3000 = %ld): %.*s", 3000 + n, n,
                   b > a ? (int)(b - a) : 9, b > a ? text + a : "no message");
}

fm_status gc_fanuc_set_var(gc_interp *g, long n, double v, int col)
{
    gc_fanuc *f = FANUC(g);
    int table, axis;
    (void)table;
    if (n == 0) return bad_var(g, n, col, "#0 is always vacant; it cannot be assigned");
    if (n >= 1 && n <= 33) {
        f->locals[f->level][n] = v;
    } else if (n >= GC_FANUC_COMMON_LO && n <= GC_FANUC_COMMON_HI) {
        f->common[n - GC_FANUC_COMMON_LO] = v;
    } else if (n == 3000) {
        return alarm(g, v, col);
    } else if (n == 3001) {
        f->timer_base_ms = (isnan(v) ? 0 : v) - g->t * 1000.0;
    } else if (n == 3002) {
        f->timer_base_h = (isnan(v) ? 0 : v) - g->t / 3600.0;
    } else if (n == 3003) {
        f->sys3003 = v;
    } else if (n == 3004) {
        f->sys3004 = v;
    } else if (n == 3006) {
        /* stop with a message: a simulation does not stop */
    } else if (n == 3901 || n == 3902) {
        f->parts[n - 3901] = v;
    } else if (offset_var(n, &table, &axis)) {
        if (axis < 3) {
            g->params[n] = isnan(v) ? 0.0 : v;
            gc_fanuc_apply_work_offset(g);
        }
    } else if (n >= 7001 && n <= 7000 + 20 * GC_FANUC_EXT_OFFSETS) {
        long k = n - 7001;
        if (k % 20 < 3) {
            f->ext_offsets[k / 20][k % 20] = isnan(v) ? 0.0 : v;
            gc_fanuc_apply_work_offset(g);
        }
    } else {
        double dummy;
        fm_status st = gc_fanuc_get_var(g, n, col, &dummy);
        if (st) return st;
        return bad_var(g, n, col, "is read-only");
    }
    return FM_OK;
}

/* ---- expressions ---- */

static fm_status read_expr_val(gc_interp *g, const gc_line *ln, size_t *p, val *out);
static fm_status read_primary(gc_interp *g, const gc_line *ln, size_t *p, val *out);

static fm_status read_number(gc_interp *g, const gc_line *ln, size_t *p, double *out, int *integer)
{
    const char *s = ln->s;
    size_t i = *p, start = *p;
    int digits = 0, dots = 0;
    while ((s[i] >= '0' && s[i] <= '9') || s[i] == '.') {
        if (s[i] == '.') dots++;
        else digits++;
        i++;
    }
    if (!digits || dots > 1)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, start),
                       "bad number '%.*s'; expected digits with at most one '.', a [expression] "
                       "or a #variable",
                       (int)(i - start > 20 ? 20 : (i > start ? i - start : 1)), s + start);
    char buf[64];
    if (i - start >= sizeof buf)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, start),
                       "number with %zu characters; expected at most 63", i - start);
    memcpy(buf, s + start, i - start);
    buf[i - start] = '\0';
    *out = strtod(buf, NULL);
    if (integer) *integer = dots == 0;
    *p = i;
    return FM_OK;
}

fm_status gc_fanuc_read_var_ref(gc_interp *g, const gc_line *ln, size_t *p, long *num)
{
    size_t at = *p;
    const char *s = ln->s;
    (*p)++;
    double v;
    fm_status st;
    if (s[*p] == '[') {
        val e;
        if ((st = read_primary(g, ln, p, &e))) return st;
        if (e.vacant)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "#[...]: the variable number is vacant; expected a number");
        v = e.v;
    } else if ((s[*p] >= '0' && s[*p] <= '9') || s[*p] == '.') {
        if ((st = read_number(g, ln, p, &v, NULL))) return st;
    } else {
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "'#' without a variable number; expected #<number> or #[expression]");
    }
    double r = floor(v + 0.5);
    if (!isfinite(v) || fabs(v - r) > 1e-4 || r < 0 || r > 99999)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "variable number %g; expected a whole number from 0 to 99999", v);
    *num = (long)r;
    return FM_OK;
}

typedef enum { OP_NONE, OP_MUL, OP_DIV, OP_AND, OP_MOD, OP_ADD, OP_SUB, OP_OR, OP_XOR, OP_EQ,
               OP_NE, OP_GT, OP_GE, OP_LT, OP_LE } fop;

static fop peek_op(const char *s, size_t *len)
{
    static const struct { const char *t; fop op; } ops[] = {
        {"*", OP_MUL}, {"/", OP_DIV}, {"and", OP_AND}, {"mod", OP_MOD}, {"+", OP_ADD},
        {"-", OP_SUB}, {"or", OP_OR}, {"xor", OP_XOR}, {"eq", OP_EQ}, {"ne", OP_NE},
        {"gt", OP_GT}, {"ge", OP_GE}, {"lt", OP_LT}, {"le", OP_LE}};
    for (size_t i = 0; i < sizeof ops / sizeof ops[0]; i++) {
        size_t n = strlen(ops[i].t);
        if (!strncmp(s, ops[i].t, n)) {
            *len = n;
            return ops[i].op;
        }
    }
    return OP_NONE;
}

/* Fanuc: functions > * / AND MOD > + - OR XOR > comparisons. */
static int precedence(fop op)
{
    switch (op) {
    case OP_MUL: case OP_DIV: case OP_AND: case OP_MOD: return 3;
    case OP_ADD: case OP_SUB: case OP_OR: case OP_XOR: return 2;
    case OP_EQ: case OP_NE: case OP_GT: case OP_GE: case OP_LT: case OP_LE: return 1;
    default: return 0;
    }
}

static fm_status to_bits(gc_interp *g, const gc_line *ln, size_t at, double v, long long *out)
{
    double t = trunc(v);
    *out = 0;
    if (!(t >= -2147483648.0 && t <= 2147483647.0))
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "AND/OR/XOR on %g; expected a value that fits in 32 bits", v);
    *out = (long long)t;
    return FM_OK;
}

static fm_status apply_op(gc_interp *g, const gc_line *ln, size_t at, fop op, val a, val b,
                          val *out)
{
    double r = 0;
    long long x, y;
    fm_status st;
    out->vacant = 0;
    switch (op) {
    case OP_EQ:
    case OP_NE: {
        /* vacant equals only vacant; every other value is compared exactly
         * (Fanuc: EQ and NE are meant for whole numbers) */
        int eq = a.vacant || b.vacant ? a.vacant == b.vacant : a.v == b.v;
        r = op == OP_EQ ? eq : !eq;
        break;
    }
    case OP_GT: r = num(a) > num(b); break;
    case OP_GE: r = num(a) >= num(b); break;
    case OP_LT: r = num(a) < num(b); break;
    case OP_LE: r = num(a) <= num(b); break;
    case OP_MUL: r = num(a) * num(b); break;
    case OP_DIV:
        if (num(b) == 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "'/': division by zero; expected a non-zero divisor");
        r = num(a) / num(b);
        break;
    case OP_MOD:
        if (num(b) == 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "'MOD': remainder of a division by zero; expected a non-zero divisor");
        r = fmod(num(a), num(b));
        break;
    case OP_ADD: r = num(a) + num(b); break;
    case OP_SUB: r = num(a) - num(b); break;
    case OP_AND:
    case OP_OR:
    case OP_XOR:
        if ((st = to_bits(g, ln, at, num(a), &x)) || (st = to_bits(g, ln, at, num(b), &y)))
            return st;
        r = (double)(op == OP_AND ? (x & y) : op == OP_OR ? (x | y) : (x ^ y));
        break;
    default: break;
    }
    if (!isfinite(r))
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "expression result is not a finite number (%g)", r);
    out->v = r;
    return FM_OK;
}

static fm_status read_binary(gc_interp *g, const gc_line *ln, size_t *p, int min_prec, val *out)
{
    val lhs;
    fm_status st = read_primary(g, ln, p, &lhs);
    if (st) return st;
    for (;;) {
        size_t len;
        fop op = peek_op(ln->s + *p, &len);
        if (op == OP_NONE) break;
        int prec = precedence(op);
        if (prec < min_prec) break;
        size_t at = *p;
        *p += len;
        val rhs;
        if (++g->expr_depth > MAX_DEPTH)
            return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, at), "expression nested deeper than %d",
                           MAX_DEPTH);
        st = read_binary(g, ln, p, prec + 1, &rhs);
        g->expr_depth--;
        if (st) return st;
        if ((st = apply_op(g, ln, at, op, lhs, rhs, &lhs))) return st;
    }
    *out = lhs;
    return FM_OK;
}

static fm_status read_expr_val(gc_interp *g, const gc_line *ln, size_t *p, val *out)
{
    return read_binary(g, ln, p, 1, out);
}

static fm_status read_bracket(gc_interp *g, const gc_line *ln, size_t *p, val *out)
{
    size_t open = *p;
    if (ln->s[*p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "expected '[' at '%.10s'", ln->s + *p);
    if (++g->expr_depth > MAX_DEPTH)
        return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, *p), "expression nested deeper than %d levels",
                       MAX_DEPTH);
    (*p)++;
    fm_status st = read_expr_val(g, ln, p, out);
    g->expr_depth--;
    if (st) return st;
    if (ln->s[*p] != ']') {
        if (ln->s[*p] == '\0')
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, open),
                           "'[' without ']'; expected ']' before the end of the line");
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                       "unexpected '%c' in expression; expected an operator or ']'", ln->s[*p]);
    }
    (*p)++;
    return FM_OK;
}

static double deg(double r) { return r * 180.0 / GC_PI; }
static double rad(double d) { return d * GC_PI / 180.0; }

static fm_status read_function(gc_interp *g, const gc_line *ln, size_t *p, val *out)
{
    static const char *names[] = {"abs", "acos", "asin", "atan", "bcd", "bin", "cos", "exp",
                                  "fix", "fup", "ln", "round", "sin", "sqrt", "tan"};
    enum { F_ABS, F_ACOS, F_ASIN, F_ATAN, F_BCD, F_BIN, F_COS, F_EXP, F_FIX, F_FUP, F_LN,
           F_ROUND, F_SIN, F_SQRT, F_TAN };
    size_t at = *p;
    char fn[8];
    size_t k = 0;
    while (ln->s[*p] >= 'a' && ln->s[*p] <= 'z' && k < sizeof fn - 1) fn[k++] = ln->s[(*p)++];
    fn[k] = '\0';
    int which = -1;
    for (int i = 0; i < (int)(sizeof names / sizeof names[0]); i++)
        if (!strcmp(fn, names[i])) which = i;
    if (which < 0 || ln->s[*p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "unknown word or function '%s'; expected a number, [expression], "
                       "#variable or one of ABS ACOS ASIN ATAN BCD BIN COS EXP FIX FUP LN ROUND "
                       "SIN SQRT TAN followed by [", fn);
    val av;
    fm_status st;
    double b = 0;
    if (which == F_ATAN) {
        /* ATAN[y]/[x] or ATAN[y,x] */
        size_t open = *p;
        (*p)++;
        if ((st = read_expr_val(g, ln, p, &av))) return st;
        if (ln->s[*p] == ',') {
            (*p)++;
            val bv;
            if ((st = read_expr_val(g, ln, p, &bv))) return st;
            b = num(bv);
            if (ln->s[*p] != ']')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, open), "ATAN: expected ATAN[y,x]");
            (*p)++;
        } else {
            if (ln->s[*p] != ']')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, open),
                               "ATAN: '[' without ']'; expected ATAN[y]/[x]");
            (*p)++;
            if (ln->s[*p] != '/' || ln->s[*p + 1] != '[')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "ATAN with one argument; expected ATAN[y]/[x] (the angle of the "
                               "point x, y, 0 to 360 degrees)");
            (*p)++;
            val bv;
            if ((st = read_bracket(g, ln, p, &bv))) return st;
            b = num(bv);
        }
    } else if ((st = read_bracket(g, ln, p, &av))) {
        return st;
    }
    double a = num(av), r = 0;
    switch (which) {
    case F_ABS: r = fabs(a); break;
    case F_ACOS:
    case F_ASIN:
        if (a < -1 || a > 1)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "%s[%g]: argument out of range; expected -1 to 1",
                           which == F_ACOS ? "ACOS" : "ASIN", a);
        /* Fanuc's ranges (parameter NAT = 0): ACOS 180..0, ASIN 270..90 */
        r = which == F_ACOS ? deg(acos(a)) : deg(asin(a));
        if (which == F_ASIN && r < 0) r += 360.0;
        break;
    case F_ATAN:
        if (a == 0 && b == 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "ATAN[0]/[0]: no angle");
        r = deg(atan2(a, b)); /* Fanuc (NAT = 0): 0 to 360 */
        if (r < 0) r += 360.0;
        if (r >= 360.0) r -= 360.0;
        break;
    case F_BCD:
    case F_BIN: {
        double t = floor(a);
        if (t != a || a < 0 || a > 99999999)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "%s[%g]: expected a whole number from 0 to 99999999",
                           which == F_BCD ? "BCD" : "BIN", a);
        unsigned long long x = (unsigned long long)t, y = 0, m = 1;
        if (which == F_BCD) { /* binary -> BCD: each decimal digit in 4 bits */
            for (; x; x /= 10, m <<= 4) y += (x % 10) * m;
        } else { /* BCD -> binary */
            for (; x; x >>= 4, m *= 10) {
                if ((x & 15) > 9)
                    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                                   "BIN[%g]: not a BCD number (a 4-bit digit above 9)", a);
                y += (x & 15) * m;
            }
        }
        r = (double)y;
        break;
    }
    case F_COS: r = cos(rad(a)); break;
    case F_EXP: r = exp(a); break;
    case F_FIX: r = trunc(a); break;                 /* toward zero: FIX[-1.2] = -1 */
    case F_FUP: r = a < 0 ? -ceil(-a) : ceil(a); break; /* away from zero: FUP[-1.2] = -2 */
    case F_LN:
        if (a <= 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "LN[%g]: logarithm of a non-positive number; expected a value > 0", a);
        r = log(a);
        break;
    case F_ROUND:
        /* in an address, ROUND rounds to the address's least increment
         * (Haas: X[ROUND[#1]]); elsewhere to a whole number, half away from 0 */
        if (FANUC(g)->in_address && FANUC(g)->address_increment > 0) {
            double inc = FANUC(g)->address_increment;
            r = gc_fanuc_round(a / inc) * inc;
        } else {
            r = gc_fanuc_round(a);
        }
        break;
    case F_SIN: r = sin(rad(a)); break;
    case F_SQRT:
        if (a < 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "SQRT[%g]: square root of a negative number; expected a value >= 0", a);
        r = sqrt(a);
        break;
    case F_TAN: r = tan(rad(a)); break;
    }
    if (!isfinite(r))
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: result is not a finite number", fn);
    out->v = r;
    out->vacant = 0;
    return FM_OK;
}

static fm_status read_primary(gc_interp *g, const gc_line *ln, size_t *p, val *out)
{
    const char *s = ln->s;
    char c = s[*p];
    fm_status st;
    if (c == '+' || c == '-') {
        size_t at = *p;
        if (++g->expr_depth > MAX_DEPTH)
            return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, at), "expression nested deeper than %d",
                           MAX_DEPTH);
        (*p)++;
        st = read_primary(g, ln, p, out);
        g->expr_depth--;
        if (st) return st;
        if (c == '-' && !out->vacant) out->v = -out->v;
        return FM_OK;
    }
    if (c == '[') return read_bracket(g, ln, p, out);
    if (c == '#') {
        size_t at = *p;
        long n;
        if (++g->expr_depth > MAX_DEPTH)
            return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, at),
                           "variable indirection nested deeper than %d", MAX_DEPTH);
        st = gc_fanuc_read_var_ref(g, ln, p, &n);
        g->expr_depth--;
        if (st) return st;
        double v;
        if ((st = gc_fanuc_get_var(g, n, gc_col(ln, at), &v))) return st;
        out->vacant = isnan(v);
        out->v = out->vacant ? 0.0 : v;
        return FM_OK;
    }
    if (c >= 'a' && c <= 'z') return read_function(g, ln, p, out);
    if ((c >= '0' && c <= '9') || c == '.') {
        out->vacant = 0;
        return read_number(g, ln, p, &out->v, NULL);
    }
    if (c == '\0')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                       "missing value at the end of the line; expected a number, [expression] "
                       "or #variable");
    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                   "unexpected '%c'; expected a number, [expression] or #variable", c);
}

fm_status gc_fanuc_read_expr(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    val v;
    fm_status st = read_expr_val(g, ln, p, &v);
    if (st) return st;
    *out = v.vacant ? GC_VACANT : v.v;
    return FM_OK;
}

fm_status gc_fanuc_read_value(gc_interp *g, const gc_line *ln, size_t *p, gc_fanuc_value *out)
{
    const char *s = ln->s;
    size_t i = *p;
    out->form = GC_FORM_EXPRESSION;
    /* a literal number, with its sign: the decimal point rule applies */
    if (s[i] == '+' || s[i] == '-') i++;
    if ((s[i] >= '0' && s[i] <= '9') || s[i] == '.') {
        int integer;
        double v;
        fm_status st = read_number(g, ln, &i, &v, &integer);
        if (st) return st;
        out->v = s[*p] == '-' ? -v : v;
        out->vacant = 0;
        out->form = integer ? GC_FORM_INTEGER : GC_FORM_DECIMAL;
        *p = i;
        return FM_OK;
    }
    val v;
    fm_status st = read_primary(g, ln, p, &v);
    if (st) return st;
    out->v = v.v;
    out->vacant = v.vacant;
    return FM_OK;
}
