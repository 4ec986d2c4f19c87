/* expr.c: the one expression engine of every dialect: numbers, [brackets],
 * binary operators by precedence levels, unary signs, function calls in
 * their argument forms, #references, errors at file:line:column and the
 * nesting bound. Which tokens are operators, how strongly each binds, what
 * operators and functions compute and how '#' is read come from the
 * dialect's table (gc_expr_lang in machine.h; linuxcnc/expr.c and
 * fanuc/expr.c define theirs). */
#include "machine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double deg(double r) { return r * 180.0 / FM_PI; }
static double rad(double d) { return d * FM_PI / 180.0; }
static double number_of(double v) { return isnan(v) ? 0.0 : v; } /* vacant: 0 */

static int is_number_start(char c) { return (c >= '0' && c <= '9') || c == '.'; }

/* One nesting level more (a bracket or a sign); the caller leaves it. */
static fm_status enter(gc_interp *g, const gc_line *ln, size_t at)
{
    if (++g->expr_depth > GC_MAX_EXPR_DEPTH)
        return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, at), "expression nested deeper than %d levels",
                       GC_MAX_EXPR_DEPTH);
    return FM_OK;
}

fm_status gc_expr_number(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                         double *out, int *point)
{
    const char *s = ln->s;
    size_t i = *p, start = *p;
    int digits = 0, dots = 0;
    if (s[i] == '+' || s[i] == '-') i++;
    while (is_number_start(s[i])) {
        if (s[i] == '.') dots++;
        else digits++;
        i++;
    }
    if (!digits || dots > 1)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, start),
                       "bad number '%.*s'; expected digits with at most one '.', a [expression], "
                       "a #%s or a function",
                       (int)(i - start > 20 ? 20 : (i > start ? i - start : 1)), s + start,
                       lang->ref_name);
    char buf[64];
    if (i - start >= sizeof buf)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, start),
                       "number with %zu characters; expected at most 63", i - start);
    memcpy(buf, s + start, i - start);
    buf[i - start] = '\0';
    *out = strtod(buf, NULL);
    if (point) *point = dots > 0;
    *p = i;
    return FM_OK;
}

static fm_status read_binary(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                             int min_level, double *out);

static fm_status close_bracket(gc_interp *g, const gc_line *ln, size_t *p, size_t open)
{
    if (ln->s[*p] == ']') {
        (*p)++;
        return FM_OK;
    }
    if (ln->s[*p] == '\0')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, open),
                       "'[' without ']'; expected ']' before the end of the line");
    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                   "unexpected '%c' in expression; expected an operator or ']'", ln->s[*p]);
}

/* [expression] at s[*p] == '['; with GC_ARGS_COMMA in args, [a,b] too
 * (*n: how many). */
static fm_status read_bracket(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                              int args, double *out, int *n)
{
    size_t open = *p;
    fm_status st = enter(g, ln, open);
    if (st) return st;
    (*p)++;
    st = read_binary(g, lang, ln, p, 1, &out[0]);
    *n = 1;
    if (!st && (args & GC_ARGS_COMMA) && ln->s[*p] == ',') {
        (*p)++;
        st = read_binary(g, lang, ln, p, 1, &out[1]);
        *n = 2;
    }
    g->expr_depth--;
    return st ? st : close_bracket(g, ln, p, open);
}

static const gc_expr_op *peek_op(const gc_expr_lang *lang, const char *s, size_t *len)
{
    for (const gc_expr_op *op = lang->ops; op < lang->ops + lang->nops; op++) {
        size_t n = 0;
        while (op->token[n] && s[n] == op->token[n]) n++;
        if (!op->token[n]) {
            *len = n;
            return op;
        }
    }
    return NULL;
}

static fm_status to_bits(gc_interp *g, int col, double v, long long *out)
{
    double t = trunc(v);
    *out = 0;
    if (!(t >= -2147483648.0 && t <= 2147483647.0))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "AND/OR/XOR on %g; expected a value that fits in 32 bits", v);
    *out = (long long)t;
    return FM_OK;
}

static fm_status apply_op(gc_interp *g, const gc_expr_lang *lang, int col, gc_expr_opcode code,
                          double a, double b, double *out)
{
    if (code == GC_OP_EQ || code == GC_OP_NE) {
        int eq;
        if (lang->vacancy && (isnan(a) || isnan(b))) eq = isnan(a) && isnan(b);
        else eq = lang->eq_tolerance > 0 ? fabs(a - b) < lang->eq_tolerance : a == b;
        *out = code == GC_OP_EQ ? eq : !eq;
        return FM_OK;
    }
    if (lang->vacancy) {
        a = number_of(a);
        b = number_of(b);
    }
    double r = 0;
    long long x, y;
    fm_status st;
    switch (code) {
    case GC_OP_POW:
        if (a < 0 && floor(b) != b)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "'**': %g raised to the non-integer power %g; expected a "
                           "non-negative base or an integer exponent", a, b);
        if (a == 0 && b < 0)
            return gc_fail(g, FM_ERR_INPUT, col, "'**': zero raised to the negative power %g", b);
        r = pow(a, b);
        break;
    case GC_OP_MUL: r = a * b; break;
    case GC_OP_DIV:
        if (b == 0)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "'/': division by zero; expected a non-zero divisor");
        r = a / b;
        break;
    case GC_OP_MOD:
    case GC_OP_MOD_NONNEG:
        if (b == 0)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "'MOD': modulo by zero; expected a non-zero divisor");
        r = fmod(a, b);
        if (code == GC_OP_MOD_NONNEG && r < 0) r += fabs(b);
        break;
    case GC_OP_ADD: r = a + b; break;
    case GC_OP_SUB: r = a - b; break;
    case GC_OP_GT: r = a > b; break;
    case GC_OP_GE: r = a >= b; break;
    case GC_OP_LT: r = a < b; break;
    case GC_OP_LE: r = a <= b; break;
    case GC_OP_AND: r = (a != 0) && (b != 0); break;
    case GC_OP_OR: r = (a != 0) || (b != 0); break;
    case GC_OP_XOR: r = (a != 0) != (b != 0); break;
    case GC_OP_BIT_AND:
    case GC_OP_BIT_OR:
    case GC_OP_BIT_XOR:
        if ((st = to_bits(g, col, a, &x)) || (st = to_bits(g, col, b, &y))) return st;
        r = (double)(code == GC_OP_BIT_AND ? (x & y) : code == GC_OP_BIT_OR ? (x | y) : (x ^ y));
        break;
    default: break;
    }
    if (!isfinite(r))
        return gc_fail(g, FM_ERR_INPUT, col, "expression result is not a finite number (%g)", r);
    *out = r;
    return FM_OK;
}

static fm_status read_binary(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                             int min_level, double *out)
{
    double lhs;
    fm_status st = gc_expr_operand(g, lang, ln, p, &lhs);
    if (st) return st;
    for (;;) {
        size_t len;
        const gc_expr_op *op = peek_op(lang, ln->s + *p, &len);
        if (!op || op->level < min_level) break;
        size_t at = *p;
        *p += len;
        double rhs;
        if ((st = read_binary(g, lang, ln, p, op->level + 1, &rhs))) return st;
        if ((st = apply_op(g, lang, gc_col(ln, at), op->code, lhs, rhs, &lhs))) return st;
    }
    *out = lhs;
    return FM_OK;
}

fm_status gc_expr_read(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                       double *out)
{
    return read_binary(g, lang, ln, p, 1, out);
}

/* BCD[a]: each decimal digit of a in 4 bits; BIN[a]: back. */
static fm_status bcd(gc_interp *g, int col, const char *name, int to_bcd, double a, double *out)
{
    double t = floor(a);
    if (t != a || a < 0 || a > 99999999)
        return gc_fail(g, FM_ERR_INPUT, col, "%s[%g]: expected a whole number from 0 to 99999999",
                       name, a);
    unsigned long long x = (unsigned long long)t, y = 0, m = 1;
    if (to_bcd) {
        for (; x; x /= 10, m <<= 4) y += (x % 10) * m;
    } else {
        for (; x; x >>= 4, m *= 10) {
            if ((x & 15) > 9)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "%s[%g]: not a BCD number (a 4-bit digit above 9)", name, a);
            y += (x & 15) * m;
        }
    }
    *out = (double)y;
    return FM_OK;
}

static fm_status apply_function(gc_interp *g, int col, const gc_expr_func *f, const double *x,
                                int n, double *out)
{
    double a = x[0], r = 0;
    fm_status st;
    switch (f->code) {
    case GC_FN_ABS: r = fabs(a); break;
    case GC_FN_ACOS:
    case GC_FN_ASIN:
    case GC_FN_ASIN_270_90:
        if (a < -1 || a > 1)
            return gc_fail(g, FM_ERR_INPUT, col, "%s[%g]: argument out of range; expected -1 to 1",
                           f->name, a);
        r = deg(f->code == GC_FN_ACOS ? acos(a) : asin(a));
        if (f->code == GC_FN_ASIN_270_90 && r < 0) r += 360.0;
        break;
    case GC_FN_ATAN: r = n == 2 ? deg(atan2(a, x[1])) : deg(atan(a)); break;
    case GC_FN_ATAN_0_360:
        if (a == 0 && x[1] == 0)
            return gc_fail(g, FM_ERR_INPUT, col, "%s[0]/[0]: no angle", f->name);
        r = deg(atan2(a, x[1]));
        if (r < 0) r += 360.0;
        if (r >= 360.0) r -= 360.0;
        break;
    case GC_FN_BCD:
    case GC_FN_BIN:
        if ((st = bcd(g, col, f->name, f->code == GC_FN_BCD, a, &r))) return st;
        break;
    case GC_FN_COS: r = cos(rad(a)); break;
    case GC_FN_EXP: r = exp(a); break;
    case GC_FN_LN:
        if (a <= 0)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s[%g]: logarithm of a non-positive number; expected a value > 0",
                           f->name, a);
        r = log(a);
        break;
    case GC_FN_SIN: r = sin(rad(a)); break;
    case GC_FN_SQRT:
        if (a < 0)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s[%g]: square root of a negative number; expected a value >= 0",
                           f->name, a);
        r = sqrt(a);
        break;
    case GC_FN_TAN: r = tan(rad(a)); break;
    case GC_FN_FLOOR: r = floor(a); break;
    case GC_FN_CEIL: r = ceil(a); break;
    case GC_FN_TRUNC: r = trunc(a); break;
    case GC_FN_AWAY: r = a < 0 ? -ceil(-a) : ceil(a); break;
    case GC_FN_ROUND: r = round(a); break;
    case GC_FN_OWN: break;
    }
    if (!isfinite(r))
        return gc_fail(g, FM_ERR_INPUT, col, "%s: result is not a finite number", f->name);
    *out = r;
    return FM_OK;
}

static fm_status unknown_function(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln,
                                  size_t at, size_t len)
{
    char names[256] = "";
    for (int i = 0; i < lang->nfuncs; i++)
        if (strlen(names) + strlen(lang->funcs[i].name) + 2 < sizeof names)
            strcat(strcat(names, i ? " " : ""), lang->funcs[i].name);
    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                   "unknown word or function '%.*s'; expected a number, [expression], #%s or one "
                   "of %s", (int)len, ln->s + at, lang->ref_name, names);
}

/* A function call: its name at s[*p], then its arguments in one of its forms. */
static fm_status read_function(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln,
                               size_t *p, double *out)
{
    const char *s = ln->s;
    size_t at = *p;
    char name[8];
    size_t k = 0;
    while (s[*p] >= 'a' && s[*p] <= 'z' && k < sizeof name - 1) name[k++] = (char)(s[(*p)++] - 32);
    name[k] = '\0';
    const gc_expr_func *f = NULL;
    for (int i = 0; i < lang->nfuncs && !f; i++)
        if (!strcmp(name, lang->funcs[i].name)) f = &lang->funcs[i];
    if (!f) return unknown_function(g, lang, ln, at, k);
    if (s[*p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "%s: expected '[' after the function name",
                       name);
    int col = gc_col(ln, at);
    if (f->code == GC_FN_OWN) return f->own(g, ln, p, col, out);
    double x[2] = {0, 0};
    int n;
    fm_status st = read_bracket(g, lang, ln, p, f->args, x, &n);
    if (st) return st;
    if (n == 1 && (f->args & GC_ARGS_SLASH) && s[*p] == '/') {
        if (s[*p + 1] == '[') {
            (*p)++;
            if ((st = read_bracket(g, lang, ln, p, 0, &x[1], &n))) return st;
            n = 2;
        } else if (f->args & GC_ARGS_ONE) {
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p + 1), "%s: expected %s[y]/[x]", name,
                           name);
        }
    }
    if (n == 1 && !(f->args & GC_ARGS_ONE))
        return gc_fail(g, FM_ERR_INPUT, col, "%s with one argument; expected %s[y]/[x]%s%s%s",
                       name, name, f->args & GC_ARGS_COMMA ? " or " : "",
                       f->args & GC_ARGS_COMMA ? name : "",
                       f->args & GC_ARGS_COMMA ? "[y,x]" : "");
    if (lang->vacancy) {
        x[0] = number_of(x[0]);
        x[1] = number_of(x[1]);
    }
    return apply_function(g, col, f, x, n, out);
}

fm_status gc_expr_operand(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                          double *out)
{
    const char *s = ln->s;
    char c = s[*p];
    fm_status st;
    if (is_number_start(c)) return gc_expr_number(g, lang, ln, p, out, NULL);
    if (c == '[') {
        int n;
        return read_bracket(g, lang, ln, p, 0, out, &n);
    }
    if (c == '+' || c == '-') {
        /* a sign before digits is the number's; otherwise it applies to
         * whatever operand follows (rs274 accepts -[..], -#1, --1) */
        if (is_number_start(s[*p + 1])) return gc_expr_number(g, lang, ln, p, out, NULL);
        if ((st = enter(g, ln, *p))) return st;
        (*p)++;
        st = gc_expr_operand(g, lang, ln, p, out);
        g->expr_depth--;
        if (!st && c == '-' && !isnan(*out)) *out = -*out; /* vacant stays vacant */
        return st;
    }
    if (c == '#') {
        if (++g->expr_depth > GC_MAX_EXPR_DEPTH)
            return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, *p),
                           "%s indirection nested deeper than %d levels", lang->ref_name,
                           GC_MAX_EXPR_DEPTH);
        st = lang->read_ref(g, ln, p, out);
        g->expr_depth--;
        return st;
    }
    if (c >= 'a' && c <= 'z') return read_function(g, lang, ln, p, out);
    if (c == '\0')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                       "missing value at the end of the line; expected a number, [expression] "
                       "or #%s", lang->ref_name);
    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                   "unexpected '%c'; expected a number, [expression] or #%s", c, lang->ref_name);
}
