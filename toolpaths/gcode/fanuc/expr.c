/* expr.c: Fanuc Custom Macro B values: the table of Fanuc's operators and
 * functions for the expression engine (machine/expr.c: precedence, output
 * ranges, rounding, vacancy), and the variables: #0 (always vacant), locals
 * #1-#33 per call level, commons #100-#999, and the system variables a
 * program needs to run (#3000 alarm, timers, #4001-#4120 modal information,
 * #5001.. positions, work offsets). Vacancy follows Fanuc's rules: a vacant
 * variable alone is vacant, in arithmetic it is 0, and EQ/NE tell it from 0. */
#include "fanuc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    case 5: return g->inverse_time ? 93 : g->per_rev ? 95 : 94;
    case 6: return g->unit == 1.0 ? 21 : 20;
    case 7: return 40;
    case 8: return g_value(f->tool_length_mode);
    case 9: return g->motion == GC_G80 || g->motion < GC_G73 ? 80 : g_value(g->motion);
    case 10: return g->retract_r ? 99 : 98;
    case 11: return g->frame.scaling ? 51 : 50;
    case 12: return gc_fanuc_modal_call_on(f) ? 66 : 67;
    case 13: return 97;
    case 14: return g->ext_cs ? (f->ext_g154 ? 154 : 54.1) : 53 + g->cs;
    case 15: return 64;
    case 16: return g->frame.rotation ? 68 : 69;
    case 17: return g->frame.polar ? 16 : 15;
    case 18: return 40.1;
    case 19: return 50.1;
    default: return GC_VACANT;
    }
}

fm_status gc_fanuc_get_var(gc_interp *g, long n, int col, double *out)
{
    gc_fanuc *f = FANUC(g);
    int table, axis;
    double *slot;
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
        *out = gc_tool_length_mm(g, gc_register_tool(g, 'h', (int)(n - 2000))) / g->unit;
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
            long pn = g->progs.programs[f->cur_program].number;
            *out = pn < 0 ? 0 : (double)pn;
            break;
        }
        case 4119: *out = g->speed; break;
        case 4120: *out = g->selected_tool; break;
        default: *out = GC_VACANT; break;
        }
    } else if (n >= 5001 && n <= 5006) {
        double w[3];
        gc_frame_to_work(g, g->frame.prog, w);
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
    } else if (gc_fanuc_ext_offset_var(g, n, &slot)) {
        *out = slot ? *slot : 0.0;
    } else {
        return bad_var(g, n, col,
                       "not a variable this simulation has; expected #0, #1-#33, #100-#999, "
                       "#2001-#2200, #3000-#3004, #3901-#3902, #4001-#4120, #5001-#5086, "
                       "#5201-#5326, #7001-#7960 or #14001-#15980");
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
    double *slot;
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
            gc_work_offset_apply(g);
        }
    } else if (gc_fanuc_ext_offset_var(g, n, &slot)) {
        if (slot) {
            *slot = isnan(v) ? 0.0 : v;
            gc_work_offset_apply(g);
        }
    } else {
        double dummy;
        fm_status st = gc_fanuc_get_var(g, n, col, &dummy);
        if (st) return st;
        return bad_var(g, n, col, "is read-only");
    }
    return FM_OK;
}

/* ---- the expression table ---- */

static const gc_expr_lang fanuc_expr;

/* '#' in an expression: the variable's value (NaN: vacant). */
static fm_status read_variable(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    size_t at = *p;
    long n;
    fm_status st = gc_fanuc_read_var_ref(g, ln, p, &n);
    if (st) return st;
    return gc_fanuc_get_var(g, n, gc_col(ln, at), out);
}

/* ROUND[a]: half away from zero; in an address, to the address's least
 * increment (Haas: X[ROUND[#1]]). */
static fm_status round_function(gc_interp *g, const gc_line *ln, size_t *p, int col, double *out)
{
    (void)col;
    double a;
    fm_status st = gc_expr_operand(g, &fanuc_expr, ln, p, &a);
    if (st) return st;
    if (isnan(a)) a = 0;
    gc_fanuc *f = FANUC(g);
    if (f->in_address && f->address_increment > 0)
        *out = gc_fanuc_round(a / f->address_increment) * f->address_increment;
    else
        *out = gc_fanuc_round(a);
    return FM_OK;
}

/* Fanuc's Macro B: functions > * / AND MOD > + - OR XOR > EQ NE GT GE LT
 * LE; EQ/NE exact (meant for whole numbers); MOD with the dividend's sign
 * (Haas: 27 MOD 20 is 7); AND OR XOR on the integer parts as 32-bit numbers;
 * angles in Fanuc's output ranges with parameter NAT = 0 (ASIN 270..90, ACOS
 * 180..0, ATAN 0..360, one-argument ATAN refused); FIX and FUP toward and
 * away from zero; vacancy. */
static const gc_expr_op fanuc_ops[] = {
    {"*", 3, GC_OP_MUL}, {"/", 3, GC_OP_DIV}, {"and", 3, GC_OP_BIT_AND}, {"mod", 3, GC_OP_MOD},
    {"+", 2, GC_OP_ADD}, {"-", 2, GC_OP_SUB}, {"or", 2, GC_OP_BIT_OR}, {"xor", 2, GC_OP_BIT_XOR},
    {"eq", 1, GC_OP_EQ}, {"ne", 1, GC_OP_NE}, {"gt", 1, GC_OP_GT}, {"ge", 1, GC_OP_GE},
    {"lt", 1, GC_OP_LT}, {"le", 1, GC_OP_LE}};

static const gc_expr_func fanuc_funcs[] = {
    {"ABS", GC_FN_ABS, GC_ARGS_ONE, NULL}, {"ACOS", GC_FN_ACOS, GC_ARGS_ONE, NULL},
    {"ASIN", GC_FN_ASIN_270_90, GC_ARGS_ONE, NULL},
    {"ATAN", GC_FN_ATAN_0_360, GC_ARGS_SLASH | GC_ARGS_COMMA, NULL},
    {"BCD", GC_FN_BCD, GC_ARGS_ONE, NULL}, {"BIN", GC_FN_BIN, GC_ARGS_ONE, NULL},
    {"COS", GC_FN_COS, GC_ARGS_ONE, NULL}, {"EXP", GC_FN_EXP, GC_ARGS_ONE, NULL},
    {"FIX", GC_FN_TRUNC, GC_ARGS_ONE, NULL}, {"FUP", GC_FN_AWAY, GC_ARGS_ONE, NULL},
    {"LN", GC_FN_LN, GC_ARGS_ONE, NULL}, {"ROUND", GC_FN_OWN, GC_ARGS_ONE, round_function},
    {"SIN", GC_FN_SIN, GC_ARGS_ONE, NULL}, {"SQRT", GC_FN_SQRT, GC_ARGS_ONE, NULL},
    {"TAN", GC_FN_TAN, GC_ARGS_ONE, NULL}};

static const gc_expr_lang fanuc_expr = {
    "variable", fanuc_ops, (int)(sizeof fanuc_ops / sizeof fanuc_ops[0]),
    fanuc_funcs, (int)(sizeof fanuc_funcs / sizeof fanuc_funcs[0]),
    0, 1, read_variable};

fm_status gc_fanuc_read_var_ref(gc_interp *g, const gc_line *ln, size_t *p, long *num)
{
    size_t at = *p;
    const char *s = ln->s;
    (*p)++;
    double v;
    fm_status st;
    if (s[*p] == '[') {
        if ((st = gc_expr_operand(g, &fanuc_expr, ln, p, &v))) return st;
        if (isnan(v))
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "#[...]: the variable number is vacant; expected a number");
    } else if ((s[*p] >= '0' && s[*p] <= '9') || s[*p] == '.') {
        if ((st = gc_expr_number(g, &fanuc_expr, ln, p, &v, NULL))) return st;
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

fm_status gc_fanuc_read_expr(gc_interp *g, const gc_line *ln, size_t *p, double *out)
{
    return gc_expr_read(g, &fanuc_expr, ln, p, out);
}

fm_status gc_fanuc_read_value(gc_interp *g, const gc_line *ln, size_t *p, gc_fanuc_value *out)
{
    const char *s = ln->s;
    size_t i = *p + (s[*p] == '+' || s[*p] == '-');
    fm_status st;
    if ((s[i] >= '0' && s[i] <= '9') || s[i] == '.') {
        /* a literal number, with its sign: the decimal point rule applies */
        int point;
        if ((st = gc_expr_number(g, &fanuc_expr, ln, p, &out->v, &point))) return st;
        out->vacant = 0;
        out->form = point ? GC_FORM_DECIMAL : GC_FORM_INTEGER;
        return FM_OK;
    }
    if ((st = gc_expr_operand(g, &fanuc_expr, ln, p, &out->v))) return st;
    out->vacant = isnan(out->v);
    if (out->vacant) out->v = 0;
    out->form = GC_FORM_EXPRESSION;
    return FM_OK;
}
