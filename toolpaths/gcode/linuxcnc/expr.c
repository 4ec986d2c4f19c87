/* expr.c: LinuxCNC's values: its table for the expression engine
 * (machine/expr.c: operators, precedence, functions, EXISTS), numbered and
 * named parameters and the stores that keep them. */
#include "linuxcnc.h"

#include <math.h>
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

/* ---- references and the expression table ---- */

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

/* '#' in an expression: the parameter's value; a named one must exist. */
static fm_status read_param(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    size_t at = *p;
    int num;
    char name[GC_MAX_NAME];
    fm_status st = gc_read_param_ref(g, ln, p, &num, name);
    if (st) return st;
    if (!name[0]) {
        *out = gc_param_value(g, num);
    } else if (!gc_get_named(g, name, out)) {
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                       "#<%s> is not defined; expected a parameter assigned earlier "
                       "(or EXISTS[#<%s>] to test it)", name, name);
    }
    return FM_OK;
}

/* EXISTS[#<name>]: 1 if the named parameter has a value (at '['). */
static fm_status exists(gc_interp *g, const gc_line *ln, size_t *p, int col, double *out)
{
    if (ln->s[*p + 1] != '#' || ln->s[*p + 2] != '<')
        return gc_fail(g, FM_ERR_INPUT, col, "EXISTS: expected EXISTS[#<name>]");
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

/* LinuxCNC's expressions: ** > * / MOD > + - > comparisons > AND OR XOR,
 * EQ/NE within TOLERANCE_EQUAL (0.0001), MOD never negative, logic on
 * truth values; FIX and FUP are floor and ceiling, angles -180..180. */
static const gc_expr_op lcnc_ops[] = {
    {"**", 5, GC_OP_POW}, {"*", 4, GC_OP_MUL}, {"/", 4, GC_OP_DIV}, {"mod", 4, GC_OP_MOD_NONNEG},
    {"+", 3, GC_OP_ADD}, {"-", 3, GC_OP_SUB},
    {"eq", 2, GC_OP_EQ}, {"ne", 2, GC_OP_NE}, {"gt", 2, GC_OP_GT}, {"ge", 2, GC_OP_GE},
    {"lt", 2, GC_OP_LT}, {"le", 2, GC_OP_LE},
    {"and", 1, GC_OP_AND}, {"or", 1, GC_OP_OR}, {"xor", 1, GC_OP_XOR}};

static const gc_expr_func lcnc_funcs[] = {
    {"ABS", GC_FN_ABS, GC_ARGS_ONE, NULL}, {"ACOS", GC_FN_ACOS, GC_ARGS_ONE, NULL},
    {"ASIN", GC_FN_ASIN, GC_ARGS_ONE, NULL},
    {"ATAN", GC_FN_ATAN, GC_ARGS_ONE | GC_ARGS_SLASH, NULL},
    {"COS", GC_FN_COS, GC_ARGS_ONE, NULL}, {"EXP", GC_FN_EXP, GC_ARGS_ONE, NULL},
    {"FIX", GC_FN_FLOOR, GC_ARGS_ONE, NULL}, {"FUP", GC_FN_CEIL, GC_ARGS_ONE, NULL},
    {"ROUND", GC_FN_ROUND, GC_ARGS_ONE, NULL}, {"LN", GC_FN_LN, GC_ARGS_ONE, NULL},
    {"SIN", GC_FN_SIN, GC_ARGS_ONE, NULL}, {"SQRT", GC_FN_SQRT, GC_ARGS_ONE, NULL},
    {"TAN", GC_FN_TAN, GC_ARGS_ONE, NULL}, {"EXISTS", GC_FN_OWN, GC_ARGS_ONE, exists}};

static const gc_expr_lang lcnc_expr = {
    "parameter", lcnc_ops, (int)(sizeof lcnc_ops / sizeof lcnc_ops[0]),
    lcnc_funcs, (int)(sizeof lcnc_funcs / sizeof lcnc_funcs[0]),
    GC_TOLERANCE_EQUAL, 0, read_param};

fm_status gc_read_real(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    return gc_expr_operand(g, &lcnc_expr, ln, p, out);
}
