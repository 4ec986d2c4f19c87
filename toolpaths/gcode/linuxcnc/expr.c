/* expr.c: values in the G-code interpreter: number syntax, [...]
 * expressions with every LinuxCNC operator and function, numbered and named
 * parameters, and the error helper every file uses (file:line:column). */
#include "linuxcnc.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* LinuxCNC compares EQ and NE with this tolerance (TOLERANCE_EQUAL). */
#define GC_TOLERANCE_EQUAL 0.0001

/* ---- tables ---- */

static size_t hash_str(const char *s)
{
    size_t h = 1469598103934665603ULL & (size_t)-1;
    for (; *s; s++) h = (h ^ (unsigned char)*s) * (size_t)1099511628211ULL;
    return h;
}

int gc_table_get(const gc_table *t, const char *key, double *v)
{
    if (!t->cap) return 0;
    size_t i = hash_str(key) & (t->cap - 1);
    while (t->keys[i]) {
        if (!strcmp(t->keys[i], key)) {
            if (v) *v = t->vals[i];
            return 1;
        }
        i = (i + 1) & (t->cap - 1);
    }
    return 0;
}

static int table_grow(gc_table *t)
{
    size_t cap = t->cap ? t->cap * 2 : 16;
    char **keys = calloc(cap, sizeof *keys);
    double *vals = calloc(cap, sizeof *vals);
    if (!keys || !vals) {
        free(keys);
        free(vals);
        return 0;
    }
    for (size_t j = 0; j < t->cap; j++) {
        if (!t->keys[j]) continue;
        size_t i = hash_str(t->keys[j]) & (cap - 1);
        while (keys[i]) i = (i + 1) & (cap - 1);
        keys[i] = t->keys[j];
        vals[i] = t->vals[j];
    }
    free(t->keys);
    free(t->vals);
    t->keys = keys;
    t->vals = vals;
    t->cap = cap;
    return 1;
}

int gc_table_set(gc_table *t, const char *key, double v)
{
    if ((t->count + 1) * 2 > t->cap && !table_grow(t)) return 0;
    size_t i = hash_str(key) & (t->cap - 1);
    while (t->keys[i]) {
        if (!strcmp(t->keys[i], key)) {
            t->vals[i] = v;
            return 1;
        }
        i = (i + 1) & (t->cap - 1);
    }
    size_t n = strlen(key);
    char *k = malloc(n + 1);
    if (!k) return 0;
    memcpy(k, key, n + 1);
    t->keys[i] = k;
    t->vals[i] = v;
    t->count++;
    return 1;
}

void gc_table_free(gc_table *t)
{
    for (size_t i = 0; i < t->cap; i++) free(t->keys[i]);
    free(t->keys);
    free(t->vals);
    memset(t, 0, sizeof *t);
}

/* ---- parameters ---- */

/* LinuxCNC's read-only named parameters, computed from the state when read
 * (the values rs274 2.9 gives; _vmajor/_vminor report that version).
 * Returns 0 if name is not one of them. */
static int predefined_named(gc_interp *g, const char *name, double *v)
{
    const char *n = name + 1;
    switch (n[0]) {
    case 'a':
        if (!strcmp(n, "absolute")) *v = g->absolute;
        else if (!strcmp(n, "adaptive_feed")) *v = 0;
        else if (!strcmp(n, "a")) *v = 0;
        else return 0;
        return 1;
    case 'b': if (strcmp(n, "b")) return 0; *v = 0; return 1;
    case 'c':
        if (!strcmp(n, "c")) *v = 0;
        else if (!strcmp(n, "ccomp"))
            *v = g->comp.side == GC_COMP_OFF ? GC_G40 : g->comp.side == GC_COMP_LEFT ? GC_G41 : GC_G42;
        else if (!strcmp(n, "coord_system"))
            *v = g->cs <= 6 ? GC_G54 + 10 * (g->cs - 1) : GC_G59 + (g->cs - 6);
        else if (!strcmp(n, "current_tool") || !strcmp(n, "current_pocket")) *v = g->tool;
        else if (!strcmp(n, "call_level")) *v = LC(g)->depth;
        else return 0;
        return 1;
    case 'f':
        if (!strcmp(n, "feed")) *v = g->feed;
        else if (!strcmp(n, "flood")) *v = (g->coolant & 2) != 0;
        else if (!strcmp(n, "feed_override") || !strcmp(n, "feed_hold")) *v = 1;
        else return 0;
        return 1;
    case 'i':
        if (!strcmp(n, "imperial")) *v = g->unit != 1.0;
        else if (!strcmp(n, "incremental")) *v = !g->absolute;
        else if (!strcmp(n, "inverse_time")) *v = g->inverse_time;
        else if (!strcmp(n, "ijk_absolute_mode")) *v = g->arc_absolute;
        else return 0;
        return 1;
    case 'l':
        if (!strcmp(n, "line")) *v = g->lineno;
        else if (!strcmp(n, "lathe_diameter_mode")) *v = 0;
        else if (!strcmp(n, "lathe_radius_mode")) *v = 1;
        else return 0;
        return 1;
    case 'm':
        if (!strcmp(n, "metric")) *v = g->unit == 1.0;
        else if (!strcmp(n, "motion_mode")) *v = g->motion;
        else if (!strcmp(n, "mist")) *v = (g->coolant & 1) != 0;
        else return 0;
        return 1;
    case 'p': if (strcmp(n, "plane")) return 0; *v = (double)g->plane * 10; return 1;
    case 'r':
        if (!strcmp(n, "rpm")) *v = g->speed;
        else if (!strcmp(n, "retract_r_plane")) *v = g->retract_r;
        else if (!strcmp(n, "retract_old_z")) *v = !g->retract_r;
        else if (!strcmp(n, "remap_level")) *v = 0;
        else return 0;
        return 1;
    case 's':
        if (!strcmp(n, "selected_tool") || !strcmp(n, "selected_pocket")) *v = g->selected_tool;
        else if (!strcmp(n, "spindle_on")) *v = g->spindle_dir != 0;
        else if (!strcmp(n, "spindle_cw")) *v = g->spindle_dir == 1;
        else if (!strcmp(n, "spindle_rpm_mode")) *v = 1;
        else if (!strcmp(n, "spindle_css_mode")) *v = 0;
        else if (!strcmp(n, "speed_override")) *v = 1;
        else return 0;
        return 1;
    case 't':
        if (!strcmp(n, "tool_offset")) *v = g->tlo[0] != 0 || g->tlo[1] != 0 || g->tlo[2] != 0;
        else if (!strcmp(n, "task")) *v = 0;
        else return 0;
        return 1;
    case 'u':
        if (!strcmp(n, "units_per_minute")) *v = !g->inverse_time;
        else if (!strcmp(n, "units_per_rev")) *v = 0;
        else if (!strcmp(n, "u")) *v = 0;
        else return 0;
        return 1;
    case 'v':
        if (!strcmp(n, "value")) *v = LC(g)->value;
        else if (!strcmp(n, "value_returned")) *v = LC(g)->value_returned;
        else if (!strcmp(n, "vmajor")) *v = 2.9;
        else if (!strcmp(n, "vminor")) *v = 0;
        else if (!strcmp(n, "v")) *v = 0;
        else return 0;
        return 1;
    case 'w': if (strcmp(n, "w")) return 0; *v = 0; return 1;
    case 'x': if (n[1]) return 0; *v = g->pos[0]; return 1;
    case 'y': if (n[1]) return 0; *v = g->pos[1]; return 1;
    case 'z': if (n[1]) return 0; *v = g->pos[2]; return 1;
    default: return 0;
    }
}

int gc_get_named(gc_interp *g, const char *name, double *v)
{
    if (name[0] == '_') {
        if (predefined_named(g, name, v)) return 1;
        return gc_table_get(&LC(g)->globals, name, v);
    }
    return gc_table_get(&LC(g)->frames[LC(g)->depth].locals, name, v);
}

fm_status gc_set_named(gc_interp *g, const char *name, double v)
{
    double old;
    if (name[0] == '_' && predefined_named(g, name, &old))
        return gc_fail(g, FM_ERR_INPUT, LC(g)->assign_col,
                       "#<%s> is a read-only parameter; expected a name of your own", name);
    gc_table *t = name[0] == '_' ? &LC(g)->globals : &LC(g)->frames[LC(g)->depth].locals;
    if (t->count > 100000)
        return gc_fail(g, FM_ERR_LIMIT, 0, "#<%s>: too many named parameters (limit 100000)", name);
    if (!gc_table_set(t, name, v))
        return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory storing #<%s>", name);
    return FM_OK;
}

/* Parameters whose value LinuxCNC derives from the state when read. */
double gc_param_value(gc_interp *g, int n)
{
    switch (n) {
    case 5400: return g->tool;
    /* the offsets and diameter of the tool M6 last loaded, as LinuxCNC
     * refreshes them (at M6 and G10 L1/L10/L11, not M61) */
    case 5401: case 5402: return 0;
    case 5403: return g->tool_param_z / g->unit;
    case 5410: return g->tool_param_dia / g->unit;
    case 5420: return g->pos[0];
    case 5421: return g->pos[1];
    case 5422: return g->pos[2];
    default: return g->params[n];
    }
}

/* ---- numbers and expressions ---- */

static fm_status read_number(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    const char *s = ln->s;
    size_t i = *p, start = *p;
    int digits = 0, dots = 0;
    if (s[i] == '+' || s[i] == '-') i++;
    while ((s[i] >= '0' && s[i] <= '9') || s[i] == '.') {
        if (s[i] == '.') dots++;
        else digits++;
        i++;
    }
    if (!digits || dots > 1)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, start),
                       "bad number '%.*s'; expected digits with at most one '.', "
                       "a [expression], a #parameter or a function",
                       (int)(i - start > 20 ? 20 : (i - start ? i - start : 1)), s + start);
    char buf[64];
    if (i - start >= sizeof buf)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, start),
                       "number with %zu characters; expected at most 63", i - start);
    memcpy(buf, s + start, i - start);
    buf[i - start] = '\0';
    *out = strtod(buf, NULL);
    *p = i;
    return FM_OK;
}

static fm_status read_name(gc_interp *g, const gc_line *ln, size_t *p, char *name)
{
    /* at '<' */
    size_t i = *p + 1, k = 0;
    while (ln->s[i] && ln->s[i] != '>') {
        if (k + 1 >= GC_MAX_NAME)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                           "parameter name longer than %d characters", GC_MAX_NAME - 1);
        name[k++] = ln->s[i++];
    }
    if (ln->s[i] != '>')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "'#<' without '>'; expected #<name>");
    if (k == 0) return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "empty parameter name '#<>'");
    name[k] = '\0';
    *p = i + 1;
    return FM_OK;
}

static fm_status param_index(gc_interp *g, const gc_line *ln, size_t at, double v, int *num)
{
    double r = floor(v + 0.5);
    if (!isfinite(v) || fabs(v - r) > 0.0001)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "parameter number %g is not an integer; expected #1 to #%d", v,
                       GC_NUM_PARAMS - 1);
    if (r < 1 || r >= GC_NUM_PARAMS)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "parameter number #%.0f out of range; expected #1 to #%d", r,
                       GC_NUM_PARAMS - 1);
    *num = (int)r;
    return FM_OK;
}

fm_status gc_read_param_ref(gc_interp *g, const gc_line *ln, size_t *p, int *num, char *name)
{
    /* at '#' */
    size_t at = *p;
    (*p)++;
    *num = 0;
    name[0] = '\0';
    if (ln->s[*p] == '<') return read_name(g, ln, p, name);
    double v;
    fm_status st = gc_read_real(g, ln, p, &v);
    if (st) return st;
    return param_index(g, ln, at, v, num);
}

static fm_status read_bracket(gc_interp *g, const gc_line *ln, size_t *p, double *out);

typedef enum { OP_NONE, OP_POW, OP_MUL, OP_DIV, OP_MOD, OP_ADD, OP_SUB, OP_EQ, OP_NE, OP_GT,
               OP_GE, OP_LT, OP_LE, OP_AND, OP_OR, OP_XOR } gc_op;

static gc_op peek_op(const char *s, size_t *len)
{
    static const struct { const char *t; gc_op op; } ops[] = {
        {"**", OP_POW}, {"*", OP_MUL}, {"/", OP_DIV}, {"mod", OP_MOD}, {"+", OP_ADD},
        {"-", OP_SUB}, {"eq", OP_EQ}, {"ne", OP_NE}, {"gt", OP_GT}, {"ge", OP_GE},
        {"lt", OP_LT}, {"le", OP_LE}, {"and", OP_AND}, {"or", OP_OR}, {"xor", OP_XOR}};
    for (size_t i = 0; i < sizeof ops / sizeof ops[0]; i++) {
        size_t n = strlen(ops[i].t);
        if (!strncmp(s, ops[i].t, n)) {
            *len = n;
            return ops[i].op;
        }
    }
    return OP_NONE;
}

/* LinuxCNC's precedence: ** > * / MOD > + - > comparisons > AND OR XOR. */
static int precedence(gc_op op)
{
    switch (op) {
    case OP_POW: return 5;
    case OP_MUL: case OP_DIV: case OP_MOD: return 4;
    case OP_ADD: case OP_SUB: return 3;
    case OP_EQ: case OP_NE: case OP_GT: case OP_GE: case OP_LT: case OP_LE: return 2;
    case OP_AND: case OP_OR: case OP_XOR: return 1;
    default: return 0;
    }
}

static fm_status apply_op(gc_interp *g, const gc_line *ln, size_t at, gc_op op, double a, double b,
                          double *out)
{
    double r = 0;
    switch (op) {
    case OP_POW:
        if (a < 0 && floor(b) != b)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "'**': %g raised to the non-integer power %g; expected a "
                           "non-negative base or an integer exponent", a, b);
        if (a == 0 && b < 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "'**': zero raised to the negative power %g", b);
        r = pow(a, b);
        break;
    case OP_MUL: r = a * b; break;
    case OP_DIV:
        if (b == 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "'/': division by zero; expected a non-zero divisor");
        r = a / b;
        break;
    case OP_MOD:
        if (b == 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "'MOD': modulo by zero; expected a non-zero divisor");
        r = fmod(a, b);
        if (r < 0) r += fabs(b); /* LinuxCNC's MOD is never negative */
        break;
    case OP_ADD: r = a + b; break;
    case OP_SUB: r = a - b; break;
    case OP_EQ: r = fabs(a - b) < GC_TOLERANCE_EQUAL; break;
    case OP_NE: r = fabs(a - b) >= GC_TOLERANCE_EQUAL; break;
    case OP_GT: r = a > b; break;
    case OP_GE: r = a >= b; break;
    case OP_LT: r = a < b; break;
    case OP_LE: r = a <= b; break;
    case OP_AND: r = (a != 0) && (b != 0); break;
    case OP_OR: r = (a != 0) || (b != 0); break;
    case OP_XOR: r = (a != 0) != (b != 0); break;
    default: break;
    }
    if (!isfinite(r))
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "expression result is not a finite number (%g)", r);
    *out = r;
    return FM_OK;
}

static fm_status read_binary(gc_interp *g, const gc_line *ln, size_t *p, int min_prec, double *out)
{
    double lhs;
    fm_status st = gc_read_real(g, ln, p, &lhs);
    if (st) return st;
    for (;;) {
        size_t len;
        gc_op op = peek_op(ln->s + *p, &len);
        if (op == OP_NONE) break;
        int prec = precedence(op);
        if (prec < min_prec) break;
        size_t at = *p;
        *p += len;
        double rhs;
        st = read_binary(g, ln, p, prec + 1, &rhs);
        if (st) return st;
        st = apply_op(g, ln, at, op, lhs, rhs, &lhs);
        if (st) return st;
    }
    *out = lhs;
    return FM_OK;
}

static fm_status read_bracket(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    size_t open = *p;
    if (ln->s[*p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "expected '[' at '%.10s'", ln->s + *p);
    if (++g->expr_depth > GC_MAX_EXPR_DEPTH)
        return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, *p),
                       "expression nested deeper than %d levels", GC_MAX_EXPR_DEPTH);
    (*p)++;
    fm_status st = read_binary(g, ln, p, 1, out);
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

static fm_status read_function(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    size_t at = *p;
    char fn[8];
    size_t k = 0;
    while (ln->s[*p] >= 'a' && ln->s[*p] <= 'z' && k < sizeof fn - 1) fn[k++] = ln->s[(*p)++];
    fn[k] = '\0';
    if (!strcmp(fn, "exists")) {
        if (ln->s[*p] != '[' || ln->s[*p + 1] != '#' || ln->s[*p + 2] != '<')
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "EXISTS: expected EXISTS[#<name>]");
        size_t q = *p + 2;
        char name[GC_MAX_NAME];
        fm_status st = read_name(g, ln, &q, name);
        if (st) return st;
        if (ln->s[q] != ']')
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, q), "EXISTS: expected ']' after #<%s>", name);
        double v;
        *out = gc_get_named(g, name, &v);
        *p = q + 1;
        return FM_OK;
    }
    static const char *names[] = {"abs", "acos", "asin", "atan", "cos", "exp", "fix",
                                  "fup", "round", "ln", "sin", "sqrt", "tan"};
    int which = -1;
    for (int i = 0; i < (int)(sizeof names / sizeof names[0]); i++)
        if (!strcmp(fn, names[i])) which = i;
    if (which < 0)
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "unknown word or function '%s'; expected a number, [expression], "
                       "#parameter or one of ABS ACOS ASIN ATAN COS EXP FIX FUP ROUND LN SIN "
                       "SQRT TAN EXISTS", fn);
    if (ln->s[*p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "%s: expected '[' after the function name",
                       fn);
    double a;
    fm_status st = read_bracket(g, ln, p, &a);
    if (st) return st;
    double r = 0;
    switch (which) {
    case 0: r = fabs(a); break;
    case 1:
    case 2:
        if (a < -1 || a > 1)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "%s[%g]: argument out of range; expected -1 to 1", which == 1 ? "ACOS" : "ASIN", a);
        r = deg(which == 1 ? acos(a) : asin(a));
        break;
    case 3:
        if (ln->s[*p] == '/') {
            (*p)++;
            double b;
            if (ln->s[*p] != '[')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p), "ATAN: expected ATAN[y]/[x]");
            st = read_bracket(g, ln, p, &b);
            if (st) return st;
            r = deg(atan2(a, b));
        } else {
            r = deg(atan(a));
        }
        break;
    case 4: r = cos(rad(a)); break;
    case 5: r = exp(a); break;
    case 6: r = floor(a); break;
    case 7: r = ceil(a); break;
    case 8: r = round(a); break;
    case 9:
        if (a <= 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "LN[%g]: logarithm of a non-positive number; expected a value > 0", a);
        r = log(a);
        break;
    case 10: r = sin(rad(a)); break;
    case 11:
        if (a < 0)
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "SQRT[%g]: square root of a negative number; expected a value >= 0", a);
        r = sqrt(a);
        break;
    case 12: r = tan(rad(a)); break;
    }
    if (!isfinite(r))
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: result is not a finite number", fn);
    *out = r;
    return FM_OK;
}

fm_status gc_read_real(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    const char *s = ln->s;
    char c = s[*p];
    if (c == '+' || c == '-') {
        /* a sign applies to whatever operand follows (rs274 accepts -[..], -#1, --1) */
        if ((s[*p + 1] >= '0' && s[*p + 1] <= '9') || s[*p + 1] == '.')
            return read_number(g, ln, p, out);
        if (++g->expr_depth > GC_MAX_EXPR_DEPTH)
            return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, *p),
                           "expression nested deeper than %d levels", GC_MAX_EXPR_DEPTH);
        (*p)++;
        double v;
        fm_status st = gc_read_real(g, ln, p, &v);
        g->expr_depth--;
        if (st) return st;
        *out = c == '-' ? -v : v;
        return FM_OK;
    }
    if (c == '[') return read_bracket(g, ln, p, out);
    if (c == '#') {
        size_t at = *p;
        if (++g->expr_depth > GC_MAX_EXPR_DEPTH)
            return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, *p),
                           "parameter indirection nested deeper than %d levels", GC_MAX_EXPR_DEPTH);
        int num;
        char name[GC_MAX_NAME];
        fm_status st = gc_read_param_ref(g, ln, p, &num, name);
        g->expr_depth--;
        if (st) return st;
        if (name[0]) {
            if (!gc_get_named(g, name, out))
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "#<%s> is not defined; expected a parameter assigned earlier "
                               "(or EXISTS[#<%s>] to test it)", name, name);
        } else {
            *out = gc_param_value(g, num);
        }
        return FM_OK;
    }
    if (c >= 'a' && c <= 'z') return read_function(g, ln, p, out);
    if ((c >= '0' && c <= '9') || c == '.') return read_number(g, ln, p, out);
    if (c == '\0')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                       "missing value at the end of the line; expected a number, [expression] "
                       "or #parameter");
    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                   "unexpected '%c'; expected a number, [expression] or #parameter", c);
}
