/* test_gcode_expr.c: the expression engine (toolpaths/gcode/machine/expr.c)
 * through each dialect's table: every operator and function at sample
 * values worked out by hand (the comments show the arithmetic; LinuxCNC's
 * from its manual and rs274 2.9, which gives the same on these; Fanuc's from
 * the custom macro B tables docs/gcode.md cites), precedence and grouping,
 * vacancy, the same text meaning different things in the two dialects, the
 * errors with their line:column, and the nesting bound. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test.h"
#include "toolpaths/gcode/gcode.h"

#define MAXM 16

static fm_motion got[MAXM];
static int ngot;

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    return 0;
}

static fm_status run(int fanuc, const char *text, fm_error *err)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    if (fanuc) o.dialect = FM_GCODE_FANUC;
    ngot = 0;
    return fm_gcode_run_string(text, strlen(text), "t.nc", &o, collect, NULL, NULL, err);
}

/* The value of [expr] in a dialect. LinuxCNC: a rapid to X of it (mm, exact).
 * Fanuc: its addresses round to the least increment, so a dwell of 1000 + it
 * seconds (an expression's value is taken as it is). */
static int value_of(int fanuc, const char *expr, double *v)
{
    char text[4096];
    if (fanuc)
        snprintf(text, sizeof text, "G21\n#1=[%s]\nG04 X[1000+#1]\n", expr);
    else
        snprintf(text, sizeof text, "G21\n#1 = [%s]\nG0 X#1\n", expr);
    fm_error err;
    fm_status st = run(fanuc, text, &err);
    if (st || ngot != 1) {
        fprintf(stderr, "  %s [%s]: %s\n", fanuc ? "fanuc" : "linuxcnc", expr,
                st ? err.message : "not one motion");
        return 0;
    }
    *v = fanuc ? got[0].t1 - got[0].t0 - 1000 : got[0].end[0];
    return 1;
}

static void expect_value(int fanuc, const char *expr, double want)
{
    double v = NAN;
    int ok = value_of(fanuc, expr, &v) && fabs(v - want) <= 1e-9;
    CHECK(ok);
    if (!ok && !isnan(v))
        fprintf(stderr, "  %s [%s] = %.17g, expected %.17g\n", fanuc ? "fanuc" : "linuxcnc", expr,
                v, want);
}

static void expect_error(int fanuc, const char *text, int line, int column, const char *fragment)
{
    fm_error err;
    fm_status st = run(fanuc, text, &err);
    int ok = st != FM_OK && err.line == line && err.column == column &&
             strstr(err.message, fragment) != NULL;
    CHECK(ok);
    if (!ok)
        fprintf(stderr, "  for '%s': got %d:%d %s\n", fragment, err.line, err.column,
                st ? err.message : "(no error)");
}

#define LCNC 0
#define FANUC 1

/* sqrt(2), ln 10, e (from tables, not from the C library) */
#define SQRT2 1.4142135623730951
#define LN10 2.302585092994046
#define E 2.718281828459045

static void test_linuxcnc_operators(void)
{
    /* ** > * / MOD > + - > comparisons > AND OR XOR, left to right */
    expect_value(LCNC, "2 + 3 * 4", 14);
    expect_value(LCNC, "2 * 3 ** 2", 18);
    expect_value(LCNC, "2 ** 3 ** 2", 64);     /* (2 ** 3) ** 2, not 2 ** 9 */
    expect_value(LCNC, "-2 ** 2", 4);          /* the sign is the operand's: (-2) ** 2 */
    expect_value(LCNC, "-[2] ** 2", 4);
    expect_value(LCNC, "2 ** -1", 0.5);
    expect_value(LCNC, "[-8] ** 3", -512);     /* a negative base with a whole exponent */
    expect_value(LCNC, "10 - 4 - 3", 3);
    expect_value(LCNC, "8 / 2 / 2", 2);
    expect_value(LCNC, "1 + 2 EQ 3", 1);
    expect_value(LCNC, "1 EQ 1 AND 0", 0);
    expect_value(LCNC, "0 OR 1 EQ 1", 1);
    expect_value(LCNC, "2 + 3 AND 1", 1);      /* [2 + 3] AND 1 */
    expect_value(LCNC, "--1", 1);
    expect_value(LCNC, "1 + -1", 0);
    /* MOD is never negative: -7 = -3 * 3 + 2 */
    expect_value(LCNC, "7 MOD 3", 1);
    expect_value(LCNC, "-7 MOD 3", 2);
    expect_value(LCNC, "7 MOD -3", 1);
    expect_value(LCNC, "-7 MOD -3", 2);
    expect_value(LCNC, "2.5 MOD 1", 0.5);
    /* EQ and NE within 0.0001 */
    expect_value(LCNC, "1 EQ 1.00005", 1);
    expect_value(LCNC, "1 EQ 1.0002", 0);
    expect_value(LCNC, "1 NE 1.00005", 0);
    expect_value(LCNC, "1 NE 1.0002", 1);
    expect_value(LCNC, "2 GT 1", 1);
    expect_value(LCNC, "1 GT 1", 0);
    expect_value(LCNC, "1 GE 1", 1);
    expect_value(LCNC, "1 LT 1", 0);
    expect_value(LCNC, "1 LT 2", 1);
    expect_value(LCNC, "1 LE 1", 1);
    /* AND OR XOR on truth values */
    expect_value(LCNC, "2 AND 3", 1);
    expect_value(LCNC, "0.5 AND 1", 1);
    expect_value(LCNC, "2 AND 0", 0);
    expect_value(LCNC, "2 OR 0", 1);
    expect_value(LCNC, "0 OR 0", 0);
    expect_value(LCNC, "2 XOR 3", 0);
    expect_value(LCNC, "2 XOR 0", 1);
}

static void test_linuxcnc_functions(void)
{
    expect_value(LCNC, "ABS[-3.5]", 3.5);
    expect_value(LCNC, "ACOS[0.5]", 60);
    expect_value(LCNC, "ACOS[-1]", 180);
    expect_value(LCNC, "ASIN[0.5]", 30);
    expect_value(LCNC, "ASIN[-0.5]", -30);     /* -90..90 */
    expect_value(LCNC, "ATAN[1]", 45);
    expect_value(LCNC, "ATAN[-1]", -45);
    expect_value(LCNC, "ATAN[1]/[-1]", 135);
    expect_value(LCNC, "ATAN[-1]/[-1]", -135); /* -180..180 */
    expect_value(LCNC, "ATAN[0]/[0]", 0);
    expect_value(LCNC, "COS[60]", 0.5);
    expect_value(LCNC, "EXP[1]", E);
    expect_value(LCNC, "FIX[2.5]", 2);
    expect_value(LCNC, "FIX[-2.5]", -3);       /* rounds down */
    expect_value(LCNC, "FUP[2.5]", 3);
    expect_value(LCNC, "FUP[-2.5]", -2);       /* rounds up */
    expect_value(LCNC, "ROUND[2.5]", 3);
    expect_value(LCNC, "ROUND[-2.5]", -3);
    expect_value(LCNC, "ROUND[2.4]", 2);
    expect_value(LCNC, "LN[10]", LN10);
    expect_value(LCNC, "SIN[30]", 0.5);
    expect_value(LCNC, "SIN[-90]", -1);
    expect_value(LCNC, "SQRT[2]", SQRT2);
    expect_value(LCNC, "TAN[45]", 1);
    expect_value(LCNC, "SQRT[16] + ABS[-1] * 2", 6); /* a function binds as an operand */
    fm_error err;
    CHECK(run(LCNC, "#<a> = 1\nG0 X[EXISTS[#<a>]] Y[EXISTS[#<zz>]]\n", &err) == FM_OK);
    CHECK(ngot == 1 && got[0].end[0] == 1 && got[0].end[1] == 0);
}

static void test_fanuc_operators(void)
{
    /* functions > * / AND MOD > + - OR XOR > EQ NE GT GE LT LE */
    expect_value(FANUC, "2 + 3 * 4", 14);
    expect_value(FANUC, "2 + 3 AND 1", 3);     /* 2 + [3 AND 1] */
    expect_value(FANUC, "5 OR 3 * 2", 7);      /* 5 OR 6 = 101 | 110 */
    expect_value(FANUC, "1 + 1 EQ 2", 1);
    expect_value(FANUC, "10 - 4 - 3", 3);
    expect_value(FANUC, "12 / 2 / 3", 2);
    expect_value(FANUC, "-3 + 1", -2);
    expect_value(FANUC, "--3", 3);
    /* MOD with the dividend's sign (Haas: 27 MOD 20 is 7) */
    expect_value(FANUC, "27 MOD 20", 7);
    expect_value(FANUC, "-27 MOD 20", -7);
    expect_value(FANUC, "27 MOD -20", 7);
    /* AND OR XOR on the integer parts as 32-bit numbers */
    expect_value(FANUC, "12 AND 10", 8);       /* 1100 & 1010 */
    expect_value(FANUC, "12 OR 3", 15);
    expect_value(FANUC, "6 XOR 3", 5);         /* 110 ^ 011 */
    expect_value(FANUC, "5.9 AND 3.2", 1);     /* 5 & 3 */
    expect_value(FANUC, "-1 AND 255", 255);    /* all 32 bits of -1 */
    expect_value(FANUC, "2 XOR 3", 1);
    /* EQ and NE are exact */
    expect_value(FANUC, "1 EQ 1.00005", 0);
    expect_value(FANUC, "1 NE 1.00005", 1);
    expect_value(FANUC, "3 EQ 3", 1);
    expect_value(FANUC, "2 GT 1", 1);
    expect_value(FANUC, "1 GE 1", 1);
    expect_value(FANUC, "1 LT 1", 0);
    expect_value(FANUC, "1 LE 1", 1);
    /* vacancy: #0 equals only vacant; 0 to everything else; a sign or a
     * bracket keeps it vacant */
    expect_value(FANUC, "#0 EQ #0", 1);
    expect_value(FANUC, "0 EQ #0", 0);
    expect_value(FANUC, "#0 NE 0", 1);
    expect_value(FANUC, "[-#0] EQ #0", 1);
    expect_value(FANUC, "[[#0]] EQ #0", 1);
    expect_value(FANUC, "[#0 + 0] EQ #0", 0);
    expect_value(FANUC, "#0 + 2", 2);
    expect_value(FANUC, "#0 * 5", 0);
    expect_value(FANUC, "#0 LT 1", 1);
    expect_value(FANUC, "COS[#0]", 1);
    expect_value(FANUC, "ATAN[#0]/[-1]", 180);
}

static void test_fanuc_functions(void)
{
    expect_value(FANUC, "ABS[-3.5]", 3.5);
    expect_value(FANUC, "ACOS[0.5]", 60);
    expect_value(FANUC, "ACOS[-0.5]", 120);    /* 180..0 */
    expect_value(FANUC, "ACOS[1]", 0);
    expect_value(FANUC, "ASIN[0.5]", 30);
    expect_value(FANUC, "ASIN[-0.5]", 330);    /* 270..90: -30 + 360 */
    expect_value(FANUC, "ASIN[-1]", 270);
    expect_value(FANUC, "ASIN[1]", 90);
    expect_value(FANUC, "ATAN[1]/[1]", 45);
    expect_value(FANUC, "ATAN[1,-1]", 135);
    expect_value(FANUC, "ATAN[-1]/[-1]", 225); /* 0..360: -135 + 360 */
    expect_value(FANUC, "ATAN[-1,1]", 315);
    expect_value(FANUC, "ATAN[0]/[-1]", 180);
    expect_value(FANUC, "ATAN[-1]/[0]", 270);
    expect_value(FANUC, "ATAN[0,1]", 0);
    expect_value(FANUC, "BCD[99]", 153);       /* 1001 1001 */
    expect_value(FANUC, "BCD[1234]", 4660);    /* 0x1234 */
    expect_value(FANUC, "BIN[4660]", 1234);
    expect_value(FANUC, "BIN[0]", 0);
    expect_value(FANUC, "COS[60]", 0.5);
    expect_value(FANUC, "EXP[1]", E);
    expect_value(FANUC, "FIX[2.7]", 2);
    expect_value(FANUC, "FIX[-2.7]", -2);      /* toward zero */
    expect_value(FANUC, "FUP[2.2]", 3);
    expect_value(FANUC, "FUP[-2.2]", -3);      /* away from zero */
    expect_value(FANUC, "FUP[-2]", -2);
    expect_value(FANUC, "LN[10]", LN10);
    expect_value(FANUC, "ROUND[2.5]", 3);
    expect_value(FANUC, "ROUND[-2.5]", -3);    /* halves away from zero */
    expect_value(FANUC, "ROUND[0.4]", 0);
    expect_value(FANUC, "SIN[30]", 0.5);
    expect_value(FANUC, "SQRT[2]", SQRT2);
    expect_value(FANUC, "TAN[45]", 1);
    expect_value(FANUC, "SQRT[16] + ABS[-1] * 2", 6);
}

/* The same text, each dialect's meaning. */
static void test_same_text(void)
{
    static const struct {
        const char *expr;
        double linuxcnc, fanuc;
    } t[] = {
        {"2 + 3 AND 1", 1, 3},      /* AND binds loosest / as * */
        {"5 OR 3 * 2", 1, 7},       /* truth value / bits */
        {"-7 MOD 3", 2, -1},        /* never negative / the dividend's sign */
        {"1 EQ 1.00005", 1, 0},     /* within 0.0001 / exact */
        {"2 XOR 3", 0, 1},
        {"ASIN[-0.5]", -30, 330},
        {"ATAN[-1]/[-1]", -135, 225},
        {"FIX[-2.5]", -3, -2},
        {"FUP[-2.5]", -2, -3},
        {"ROUND[-2.5]", -3, -3},
    };
    for (size_t i = 0; i < sizeof t / sizeof t[0]; i++) {
        expect_value(LCNC, t[i].expr, t[i].linuxcnc);
        expect_value(FANUC, t[i].expr, t[i].fanuc);
    }
}

static void test_errors(void)
{
    expect_error(LCNC, "G0 X[2 / 0]\n", 1, 8, "'/': division by zero");
    expect_error(LCNC, "G0 X[1 MOD 0]\n", 1, 8, "'MOD': modulo by zero");
    expect_error(LCNC, "G0 X[[-8] ** 0.5]\n", 1, 11, "non-integer power");
    expect_error(LCNC, "G0 X[0 ** -1]\n", 1, 8, "zero raised to the negative power");
    expect_error(LCNC, "G0 X[10 ** 400]\n", 1, 9, "not a finite number");
    expect_error(LCNC, "G0 X[LN[0]]\n", 1, 6, "LN[0]: logarithm of a non-positive number");
    expect_error(LCNC, "G0 X[ACOS[1.5]]\n", 1, 6, "ACOS[1.5]: argument out of range");
    expect_error(LCNC, "G0 X[EXP[1000]]\n", 1, 6, "EXP: result is not a finite number");
    expect_error(LCNC, "G0 X[ATAN[1,1]]\n", 1, 12, "unexpected ','");
    expect_error(LCNC, "G0 X[ATAN[1]/2]\n", 1, 14, "ATAN: expected ATAN[y]/[x]");
    expect_error(LCNC, "G0 X[SIN 30]\n", 1, 10, "SIN: expected '[' after the function name");
    expect_error(LCNC, "G0 X[FOO[1]]\n", 1, 6,
                 "unknown word or function 'foo'; expected a number, [expression], #parameter or "
                 "one of ABS ACOS ASIN ATAN COS EXP FIX FUP ROUND LN SIN SQRT TAN EXISTS");
    expect_error(LCNC, "G0 X[1 + 2\n", 1, 5, "'[' without ']'");
    expect_error(LCNC, "G0 X[1 + ]\n", 1, 10, "unexpected ']'; expected a number");
    expect_error(LCNC, "G0 X[1.2.3]\n", 1, 6, "bad number '1.2.3'");

    expect_error(FANUC, "#1=2/0\n", 1, 5, "'/': division by zero");
    expect_error(FANUC, "#1=1 MOD 0\n", 1, 6, "'MOD': modulo by zero");
    expect_error(FANUC, "#1=3000000000 AND 1\n", 1, 15, "fits in 32 bits");
    expect_error(FANUC, "#1=ATAN[0]/[0]\n", 1, 4, "ATAN[0]/[0]: no angle");
    expect_error(FANUC, "#1=ATAN[1]\n", 1, 4, "ATAN with one argument");
    expect_error(FANUC, "#1=BIN[26]\n", 1, 4, "BIN[26]: not a BCD number"); /* 0x1A */
    expect_error(FANUC, "#1=BCD[1.5]\n", 1, 4, "BCD[1.5]: expected a whole number");
    expect_error(FANUC, "#1=2**2\n", 1, 6, "unexpected '*'; expected a number, [expression] or "
                                            "#variable");
    expect_error(FANUC, "#1=EXISTS[#1]\n", 1, 4,
                 "unknown word or function 'exists'; expected a number, [expression], #variable "
                 "or one of ABS ACOS ASIN ATAN BCD BIN COS EXP FIX FUP LN ROUND SIN SQRT TAN");
    expect_error(FANUC, "#1=#[#0]\n", 1, 4, "the variable number is vacant");
}

/* 64 nested brackets (each holding an operation) are read, 65 are not; the
 * same for # indirections. */
static void test_nesting(void)
{
    for (int fanuc = 0; fanuc <= 1; fanuc++) {
        for (int n = 64; n <= 65; n++) {
            char expr[1024] = "", text[1200];
            size_t k = 0;
            for (int i = 0; i < n - 1; i++) k += (size_t)snprintf(expr + k, sizeof expr - k, "1+[");
            k += (size_t)snprintf(expr + k, sizeof expr - k, "1");
            for (int i = 0; i < n - 1; i++) expr[k++] = ']';
            expr[k] = '\0';
            if (n == 64) {
                expect_value(fanuc, expr, 64); /* the outer bracket is value_of's */
            } else {
                /* the outer '[' is at column 4 (#1=[) or 6 (#1 = [), the 65th
                 * ends the 64th "1+[" after it */
                snprintf(text, sizeof text, fanuc ? "#1=[%s]\n" : "#1 = [%s]\n", expr);
                expect_error(fanuc, text, 1, (fanuc ? 4 : 6) + 64 * 3,
                             "expression nested deeper than 64 levels");
            }
        }
    }
    /* ##...#1 with #1 = 1: 64 '#' read #1, 65 do not */
    char text[256];
    for (int n = 64; n <= 65; n++) {
        size_t k = (size_t)snprintf(text, sizeof text, "#1 = 1\nG0 X");
        for (int i = 0; i < n; i++) text[k++] = '#';
        snprintf(text + k, sizeof text - k, "1\n");
        fm_error err;
        fm_status st = run(LCNC, text, &err);
        if (n == 64) {
            CHECK(st == FM_OK && ngot == 1 && got[0].end[0] == 1);
        } else {
            CHECK(st == FM_ERR_LIMIT && err.line == 2 && err.column == 4 + 65);
            CHECK_STR_CONTAINS(err.message, "parameter indirection nested deeper than 64 levels");
        }
    }
}

int main(void)
{
    test_linuxcnc_operators();
    test_linuxcnc_functions();
    test_fanuc_operators();
    test_fanuc_functions();
    test_same_text();
    test_errors();
    test_nesting();
    return test_summary("test_gcode_expr");
}
