/* test_fanuc.c: unit tests of the Fanuc/Haas dialect. There is no Fanuc
 * interpreter to compare with, so every expected motion is worked out by hand
 * from Fanuc's documented semantics (the comments show the arithmetic):
 * reading (%, O numbers, comments, block delete, the decimal point rule),
 * subprograms (M98 repeats and nesting, M97, M99 P, files on the path), G65
 * arguments, Macro B expressions and variables, IF/GOTO and WHILE loops,
 * G68 rotation, G54.1 offsets, every canned cycle, G16 bolt circles, arcs,
 * tool length offsets, G28/G30, G51, dwells, and every error with its
 * line:column. Programs that mean the same in both dialects must give the
 * same motions in both. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test.h"
#include "toolpaths/gcode/gcode.h"

#define MAXM 4000

static fm_motion got[MAXM];
static int ngot;

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    return 0;
}

static fm_gcode_options fanuc(void)
{
    fm_gcode_options o;
    fm_gcode_options_default(&o);
    o.dialect = FM_GCODE_FANUC;
    return o;
}

static fm_status run_opt(const char *text, const fm_gcode_options *opt, fm_error *err)
{
    ngot = 0;
    return fm_gcode_run_string(text, strlen(text), "t.nc", opt, collect, NULL, NULL, err);
}

static fm_status run(const char *text, fm_error *err)
{
    fm_gcode_options o = fanuc();
    return run_opt(text, &o, err);
}

/* Expected motions: kind R rapid, L line, A arc, D dwell (x = seconds). */
typedef struct em {
    char kind;
    double x, y, z;
} em;

static void expect_motions_opt(const char *what, const char *text, const fm_gcode_options *opt,
                               const em *e, int n)
{
    fm_error err;
    fm_status st = run_opt(text, opt, &err);
    CHECK(st == FM_OK);
    if (st) {
        char buf[700];
        fprintf(stderr, "  %s: %s\n", what, fm_error_format(&err, buf, sizeof buf));
        return;
    }
    CHECK(ngot == n);
    if (ngot != n) fprintf(stderr, "  %s: %d motions, expected %d\n", what, ngot, n);
    for (int i = 0; i < n && i < ngot; i++) {
        const fm_motion *m = &got[i];
        char k = m->kind == FM_MOTION_RAPID ? 'R' : m->kind == FM_MOTION_LINE ? 'L'
                 : m->kind == FM_MOTION_ARC ? 'A' : 'D';
        int ok = k == e[i].kind;
        if (k == 'D') {
            ok = ok && fabs((m->t1 - m->t0) - e[i].x) < 1e-9;
        } else {
            ok = ok && fabs(m->end[0] - e[i].x) < 1e-6 && fabs(m->end[1] - e[i].y) < 1e-6 &&
                 fabs(m->end[2] - e[i].z) < 1e-6;
        }
        CHECK(ok);
        if (!ok)
            fprintf(stderr, "  %s: motion %d (line %d) is %c %.6f %.6f %.6f (t %.6f), expected "
                    "%c %.6f %.6f %.6f\n", what, i, m->line, k, m->end[0], m->end[1], m->end[2],
                    m->t1 - m->t0, e[i].kind, e[i].x, e[i].y, e[i].z);
    }
}

static void expect_motions(const char *what, const char *text, const em *e, int n)
{
    fm_gcode_options o = fanuc();
    expect_motions_opt(what, text, &o, e, n);
}

#define N(a) ((int)(sizeof(a) / sizeof((a)[0])))

static void expect_error(const char *text, int line, int column, const char *fragment)
{
    fm_error err;
    fm_status st = run(text, &err);
    CHECK(st != FM_OK);
    CHECK(err.line == line);
    CHECK(err.column == column);
    CHECK_STR_CONTAINS(err.message, fragment);
    if (st == FM_OK || err.line != line || err.column != column || !strstr(err.message, fragment))
        fprintf(stderr, "  for '%s': got %d:%d %s\n", fragment, err.line, err.column,
                err.message);
}

/* ---- reading ---- */

static void test_reading(void)
{
    const char *prog = "%\n"
                       "O0001 (READ TEST)\n"
                       "N10 G21 G90 G00 X5 Y5. ; X5 is 0.005 mm\n"
                       "N20 X1.23456 Y-0.0004\n"
                       "/N30 X100.\n"
                       "N40 G20 X5 Y0.5\n"
                       "M30\n"
                       "%\n"
                       "G00 X999.\n";
    /* X5 without a decimal point: 5 x 0.001 mm; X1.23456 rounds to the
     * least increment 0.001 (1.235), Y-0.0004 to 0; in G20 X5 = 0.0005 in */
    em e[] = {{'R', 0.005, 5, 0}, {'R', 1.235, 0, 0}, {'R', 100, 0, 0},
              {'R', 0.0005 * 25.4, 0.5 * 25.4, 0}};
    expect_motions("reading", prog, e, N(e));
    fm_gcode_options o = fanuc();
    o.block_delete = 1;
    em e2[] = {{'R', 0.005, 5, 0}, {'R', 1.235, 0, 0}, {'R', 0.0005 * 25.4, 0.5 * 25.4, 0}};
    expect_motions_opt("block delete", prog, &o, e2, N(e2));
    o = fanuc();
    o.calculator_input = 1;
    em e3[] = {{'R', 5, 5, 0}, {'R', 1.235, 0, 0}, {'R', 100, 0, 0}, {'R', 5 * 25.4, 0.5 * 25.4, 0}};
    expect_motions_opt("calculator input", prog, &o, e3, N(e3));
    fm_gcode_summary sum;
    fm_error err;
    o = fanuc();
    CHECK(fm_gcode_run_string(prog, strlen(prog), "t.nc", &o, collect, NULL, &sum, &err) == FM_OK);
    CHECK(sum.ended_by_m2 == 1);
    /* the closing % ends the tape without M30 */
    const char *tape = "%\nG00 X1.\n%\nG00 X2.\n";
    CHECK(fm_gcode_run_string(tape, strlen(tape), "t.nc", &o, collect, NULL, &sum, &err) == FM_OK);
    CHECK(sum.motions == 1 && sum.ended_by_m2 == 1);
}

/* ---- subprograms ---- */

static void test_subprograms(void)
{
    /* M98 P10 L3: O0010 three times; P20011: O0011 twice (Fanuc's repeat
     * count in the digits above the four of the program number) */
    em e[] = {{'R', 0, 0, 0}, {'L', 1, 0, 0}, {'L', 2, 0, 0}, {'L', 3, 0, 0},
              {'R', 3, 1, 0}, {'R', 3, 2, 0}};
    expect_motions("M98 repeats",
                   "O0001\nG90 G00 X0 Y0 Z0\nM98 P0010 L3\nM98 P20011\nM30\n"
                   "O0010\nG91 G01 X1. F100\nG90\nM99\n"
                   "O0011\nG91 G00 Y1.\nG90\nM99\n%\n",
                   e, N(e));
    /* nesting: 4 levels are allowed */
    const char *nest4 = "O0100\nG91 G01 F100\nM98 P1\nM30\n"
                        "O0001\nX1.\nM98 P2\nM99\n"
                        "O0002\nX1.\nM98 P3\nM99\n"
                        "O0003\nX1.\nM98 P4\nM99\n"
                        "O0004\nX1.\nM99\n";
    em e4[] = {{'L', 1, 0, 0}, {'L', 2, 0, 0}, {'L', 3, 0, 0}, {'L', 4, 0, 0}};
    expect_motions("nesting 4", nest4, e4, N(e4));
    /* a fifth level: the error names O0004's M98 (line 19, column 1) */
    expect_error("O0100\nG91 G01 F100\nM98 P1\nM30\n"
                 "O0001\nX1.\nM98 P2\nM99\n"
                 "O0002\nX1.\nM98 P3\nM99\n"
                 "O0003\nX1.\nM98 P4\nM99\n"
                 "O0004\nX1.\nM98 P5\nM99\n"
                 "O0005\nX1.\nM99\n",
                 19, 1, "subprograms nested deeper than 4 levels");
    /* Haas M97: a local call to N100 twice */
    em e97[] = {{'R', 0, 0, 0}, {'L', 5, 0, 0}, {'L', 10, 0, 0}, {'R', 50, 0, 0}};
    expect_motions("M97", "O0200\nG90 G00 X0 Y0\nM97 P100 L2\nG00 X50.\nM30\n"
                          "N100 G91 G01 X5. F200\nG90\nM99\n", e97, N(e97));
    /* M99 P20: back to N20 of the caller, skipping N10 */
    em e99[] = {{'R', 0, 0, 0}, {'R', 1, 0, 0}, {'R', 20, 0, 0}};
    expect_motions("M99 P", "O0300\nG90 G00 X0\nM98 P301\nN10 G00 X10.\nN20 G00 X20.\nM30\n"
                            "O0301\nG00 X1.\nM99 P20\n", e99, N(e99));
    /* M99 in the main program ends it (a control would repeat it) */
    em em99[] = {{'R', 1, 0, 0}};
    expect_motions("M99 main", "G00 X1.\nM99\nG00 X2.\n", em99, N(em99));
    /* L0: not called */
    em el0[] = {{'R', 7, 0, 0}};
    expect_motions("L0", "M98 P10 L0\nG00 X7.\nM30\nO0010\nG00 X1.\nM99\n", el0, N(el0));

    /* subprogram files: O4000.nc on the subroutine path, and in the
     * program's own folder for a program file */
    char dir[] = "/tmp/fm_fanuc_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[256];
    snprintf(path, sizeof path, "%s/O4000.nc", dir);
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs("%\nO4000 (FROM A FILE)\nG91 G01 X2. F100\nG90\nM99\n%\n", f);
    fclose(f);
    fm_gcode_options o = fanuc();
    o.subroutine_path = dir;
    em ef[] = {{'R', 1, 0, 0}, {'L', 3, 0, 0}, {'L', 5, 0, 0}};
    expect_motions_opt("file on the path", "G00 X1.\nM98 P4000 L2\nM30\n", &o, ef, N(ef));
    char main_path[256];
    snprintf(main_path, sizeof main_path, "%s/main.nc", dir);
    f = fopen(main_path, "w");
    CHECK(f != NULL);
    if (f) {
        fputs("O0001\nG00 X1.\nM98 P4000\nM30\n", f);
        fclose(f);
        fm_error err;
        o = fanuc();
        ngot = 0;
        CHECK(fm_gcode_run_file(main_path, &o, collect, NULL, NULL, &err) == FM_OK);
        CHECK(ngot == 2 && fabs(got[1].end[0] - 3) < 1e-9);
        /* an error in the subprogram file names that file and its line */
        f = fopen(path, "w");
        if (f) {
            fputs("O4000\nG91 G01 X2. F100\nG02 X1.\nM99\n", f);
            fclose(f);
        }
        CHECK(fm_gcode_run_file(main_path, &o, collect, NULL, NULL, &err) != FM_OK);
        CHECK(strcmp(err.file, path) == 0);
        CHECK(err.line == 3 && err.column == 1);
        CHECK_STR_CONTAINS(err.message, "no centre");
        remove(main_path);
    }
    remove(path);
    rmdir(dir);
    expect_error("G00 X1.\nM98 P4001\nM30\n", 2, 1, "no program O4001");
    /* a subprogram that runs into the next program without M99 */
    expect_error("M98 P10\nM30\nO0010\nG00 X1.\nO0011\nM99\n", 4, 1, "without M99");
}

/* ---- G65 ---- */

static void test_g65(void)
{
    /* argument specification I: A B C I J K D E F H M Q R S T U V W X Y Z ->
     * #1 #2 #3 #4 #5 #6 #7 #8 #9 #11 #13 #17 .. #26; their sum is
     * 1+...+9 = 45, + 11 + 13 = 69, + 17 + ... + 26 = 215: 284. The caller's
     * #1 is back after M99. #10 (no letter) stays vacant. */
    em e[] = {{'R', 0, 0, 0}, {'R', 24, 25, 26}, {'R', 100, 25, 26}, {'R', 100, 284, 26}};
    expect_motions("G65 arguments",
                   "O0001\nG90 G00 X0 Y0 Z0\n#1=100.\n"
                   "G65 P9000 A1. B2. C3. I4. J5. K6. D7. E8. F9. H11. M13. Q17. R18. S19. T20. "
                   "U21. V22. W23. X24. Y25. Z26.\n"
                   "G00 X#1\nG00 Y#100\nM30\n"
                   "O9000\n"
                   "#100=#1+#2+#3+#4+#5+#6+#7+#8+#9+#11+#13+#17+#18+#19+#20+#21+#22+#23+#24+#25"
                   "+#26\n"
                   "IF [#10 NE #0] GOTO 99\nG00 X#24 Y#25 Z#26\nM99\nN99 #3000=1(NOT VACANT)\n",
                   e, N(e));
    /* arguments without a decimal point: X5 -> 0.005 (mm), A5 -> 0.005 (deg),
     * D5 -> 5 (a whole-number address) */
    em e2[] = {{'R', 5, 5, 5}};
    expect_motions("G65 decimal point", "G65 P9001 X5 A5 D5\nM30\nO9001\n"
                   "G00 X[#24*1000] Y[#1*1000] Z#7\nM99\n", e2, N(e2));
    /* L repeats the macro */
    em e3[] = {{'L', 2, 0, 0}, {'L', 4, 0, 0}, {'L', 6, 0, 0}};
    expect_motions("G65 L", "G65 P9002 L3 A2.\nM30\nO9002\nG91 G01 X#1 F100\nG90\nM99\n", e3,
                   N(e3));
    /* macro calls nest 4 levels; the 5th fails at O9100's G65 */
    expect_error("G65 P9100\nM30\nO9100\nG65 P9100\nM99\n", 4, 1,
                 "macro calls nested deeper than 4 levels");
}

/* ---- control flow ---- */

static void test_control(void)
{
    /* IF/GOTO loop: X1 X2 X3; nested WHILE: (0,0) (10,0) (0,10) (10,10); IF
     * THEN: #4 = 7 */
    em e[] = {{'L', 0, 0, 0}, {'L', 1, 0, 0}, {'L', 2, 0, 0}, {'L', 3, 0, 0}, {'R', 0, 0, 0},
              {'R', 10, 0, 0}, {'R', 0, 10, 0}, {'R', 10, 10, 0}, {'R', 10, 10, 7}};
    expect_motions("control",
                   "O0001\nG90 G01 F100 X0 Y0\n#1=1\n"
                   "N10 IF [#1 GT 3] GOTO 20\nG01 X#1\n#1=#1+1\nGOTO 10\n"
                   "N20 #2=0\nWHILE [#2 LT 2] DO1\n#3=0\nWHILE [#3 LT 2] DO2\n"
                   "G00 X[#3*10] Y[#2*10]\n#3=#3+1\nEND2\n#2=#2+1\nEND1\n"
                   "IF [#2 EQ 2] THEN #4=7.\nG00 Z#4\nM30\n",
                   e, N(e));
    /* a loop that never ends stops at max_iterations */
    fm_gcode_options o = fanuc();
    o.max_iterations = 1000;
    fm_error err;
    CHECK(run_opt("N1 G00 X1.\nGOTO 1\n", &o, &err) == FM_ERR_LIMIT);
    CHECK(run_opt("WHILE [1 GT 0] DO1\nEND1\n", &o, &err) == FM_ERR_LIMIT);
}

/* ---- expressions and variables ---- */

static void test_expressions(void)
{
    em e[] = {
        {'R', 7, 0, 0},      /* 1+2*3 */
        {'R', 9, 0, 0},      /* [1+2]*3 */
        {'R', 1, 0, 0},      /* 5 AND 3 = 0101 & 0011 */
        {'R', 7, 0, 0},      /* 5 OR 3 */
        {'R', 6, 0, 0},      /* 5 XOR 3 */
        {'R', 7, 0, 0},      /* 27 MOD 20 */
        {'R', 225, 0, 0},    /* ATAN[-1]/[-1]: third quadrant, 0..360 */
        {'R', 45, 0, 0},     /* ATAN[1,1] */
        {'R', 330, 0, 0},    /* ASIN[-0.5]: Fanuc's range 270..90 */
        {'R', 180, 0, 0},    /* ACOS[-1] */
        {'R', -2, 0, 0},     /* ROUND[-1.5]: half away from zero */
        {'R', -1, 0, 0},     /* FIX[-1.2]: toward zero */
        {'R', -2, 0, 0},     /* FUP[-1.2]: away from zero */
        {'R', 18, 0, 0},     /* BCD[12] = 0x12 */
        {'R', 12, 0, 0},     /* BIN[18] */
        {'R', 4, 0, 0},      /* SQRT[16] */
        {'R', 3, 0, 0},      /* ABS[-3] */
        {'R', 2, 0, 0},      /* LN[EXP[2]] */
        {'R', 0.5, 0, 0},    /* SIN[30] */
        {'R', 0.5, 0, 0},    /* COS[60] */
        {'R', 1, 0, 0},      /* TAN[45] */
        {'R', 1.235, 0, 0},  /* X[ROUND[1.23456]]: ROUND in an address rounds to 0.001 */
        {'R', 2.47, 0, 0},   /* X[ROUND[#1]+ROUND[#1]] = 1.235 + 1.235 */
        {'R', 2.469, 0, 0},  /* X[#1+#1] = 2.46912 rounded to 0.001 */
    };
    expect_motions("expressions",
                   "#1=1+2*3\nG00 X#1\n#1=[1+2]*3\nG00 X#1\n#1=5 AND 3\nG00 X#1\n"
                   "#1=5 OR 3\nG00 X#1\n#1=5 XOR 3\nG00 X#1\n#1=27 MOD 20\nG00 X#1\n"
                   "#1=ATAN[-1]/[-1]\nG00 X#1\n#1=ATAN[1,1]\nG00 X#1\n#1=ASIN[-0.5]\nG00 X#1\n"
                   "#1=ACOS[-1]\nG00 X#1\n#1=ROUND[-1.5]\nG00 X#1\n#1=FIX[-1.2]\nG00 X#1\n"
                   "#1=FUP[-1.2]\nG00 X#1\n#1=BCD[12]\nG00 X#1\n#1=BIN[18]\nG00 X#1\n"
                   "#1=SQRT[16]\nG00 X#1\n#1=ABS[-3]\nG00 X#1\n#1=LN[EXP[2]]\nG00 X#1\n"
                   "#1=SIN[30]\nG00 X#1\n#1=COS[60]\nG00 X#1\n#1=TAN[45]\nG00 X#1\n"
                   "#1=1.23456\nG00 X[ROUND[#1]]\nG00 X[ROUND[#1]+ROUND[#1]]\nG00 X[#1+#1]\n",
                   e, N(e));
    /* vacancy: an address with a vacant variable is left out; #2=#1 stays
     * vacant; #1*5 is 0; EQ tells vacant from 0; LT treats vacant as 0 */
    em v[] = {{'R', 0, 4, 0}, {'R', 5, 4, 0}, {'R', 5, 0, 0}, {'R', 1, 3, 0}};
    expect_motions("vacancy",
                   "G00 Y4.\n#1=#0\nG00 X5. Y#1\n#2=#1\nG00 Y#2\n#3=#1*5\nG00 Y#3\n"
                   "IF [#1 EQ #0] THEN #5=1.\nIF [#3 EQ #0] THEN #5=2.\n"
                   "IF [#1 LT 1] THEN #6=3.\nG00 X#5 Y#6\n",
                   v, N(v));
    /* system variables: #4001 (G01), #4003 (G90),
     * #5001 (the last end point), #4120 (T), #4109 (F) */
    em s[] = {{'L', 1, 0, 0}, {'R', 1, 90, 0}, {'R', 1, 90, 7}, {'R', 1, 90, 1}, {'R', 100, 90, 1}};
    expect_motions("system variables",
                   "G90 G01 X1. F100\n#10=#4001\n#11=#4003\n#12=#5001\nT7\n#13=#4120\n"
                   "#14=#4109\nG00 Y#11\nZ#13\nZ#10\nX#14\n",
                   s, N(s));
    /* commons survive calls; #100 set in a subprogram is seen by the caller */
    em c[] = {{'R', 42, 0, 0}};
    expect_motions("commons", "M98 P5\nG00 X#100\nM30\nO0005\n#100=42.\nM99\n", c, N(c));
    /* #3000: the alarm is an error with its message and position */
    expect_error("G00 X1.\n#3000=7(TOOL BROKEN)\n", 2, 1, "alarm 3007 (#3000 = 7): TOOL BROKEN");
}

/* ---- coordinates ---- */

static void test_rotation(void)
{
    /* a 10 mm square rotated 30 degrees about the origin: (x, y) ->
     * (x c - y s, x s + y c), c = cos 30, s = sin 30 */
    double c = cos(FM_PI / 6), s = 0.5;
    em e[] = {{'R', 0, 0, 0}, {'L', 10 * c, 10 * s, 0}, {'L', 10 * c - 10 * s, 10 * s + 10 * c, 0},
              {'L', -10 * s, 10 * c, 0}, {'L', 0, 0, 0}, {'R', 10, 0, 0}};
    expect_motions("G68 square",
                   "G90 G00 X0 Y0\nG68 X0 Y0 R30.\nG01 X10. F100\nY10.\nX0\nY0\nG69\nG00 X10. Y0\n",
                   e, N(e));
    /* about (5, 5) by 90 degrees: (10, 5) -> (5, 10); G91 X-5. turns into
     * (0, -5): (5, 5); an R arc turns with it: G02 from (5,5) to program
     * (10,5)... the end (5,10), centre program (7.5,5) -> (5, 7.5) */
    em e2[] = {{'R', 0, 0, 0}, {'L', 5, 10, 0}, {'L', 5, 5, 0}, {'A', 5, 10, 0}};
    expect_motions("G68 centre",
                   "G90 G00 X0 Y0\nG68 X5. Y5. R90.\nG01 X10. Y5. F100\nG91 X-5.\nG90\n"
                   "G02 X10. Y5. R2.5\n",
                   e2, N(e2));
    CHECK(ngot == 4 && fabs(got[3].center[0] - 5) < 1e-9 && fabs(got[3].center[1] - 7.5) < 1e-9 &&
          got[3].turns == -1);
    /* R without a decimal point is in 0.001 degree */
    em e3[] = {{'L', 0, 10, 0}};
    expect_motions("G68 R90000", "G68 R90000\nG01 X10. F100\n", e3, N(e3));
}

static void test_offsets(void)
{
    /* G10 L20 P3 writes G54.1 P3 (#7041 = its X); G91 G10 adds; G10 L2 P2
     * is G55. Positions are machine coordinates: program + offset. */
    em e[] = {{'R', 100, 50, -10}, {'R', 200, 50, -10}, {'R', 101, 50, -10},
              {'R', -5, -5, -10}, {'R', -5, -5, 0}};
    expect_motions("G54.1",
                   "G10 L20 P3 X100. Y50. Z-10.\nG54.1 P3\nG00 X0 Y0 Z0\n#1=#7041\nG00 X#1\n"
                   "G91 G10 L20 P3 X1.\nG90 G00 X0\nG10 L2 P2 X-5. Y-5.\nG55 G00 X0 Y0\nZ0\n",
                   e, N(e));
    /* the external offset (G10 L2 P0) adds to every system; G52 shifts the
     * current one; G92 makes the current point (0, 0) */
    em e2[] = {{'R', 11, 0, 0}, {'R', 13, 0, 0}, {'R', 10, 0, 0}, {'R', 11, 0, 0}};
    expect_motions("EXOFS G52 G92",
                   "G10 L2 P0 X1.\nG10 L2 P1 X10.\nG54 G00 X0\nG52 X2.\nG00 X0\nG52 X0\n"
                   "G00 X-1.\nG92 X0\nG00 X1.\n",
                   e2, N(e2));
    expect_error("G54.1 P49\n", 1, 7, "expected a whole number from 1 to 48");
}

/* ---- canned cycles ---- */

static void test_cycles(void)
{
    /* From (0, 0, 10): the initial level is Z10, R2, bottom Z-5. */
    em e81[] = {{'R', 0, 0, 10},
                {'R', 10, 0, 10}, {'R', 10, 0, 2}, {'L', 10, 0, -5}, {'R', 10, 0, 10},  /* G98 */
                {'R', 20, 0, 10}, {'R', 20, 0, 2}, {'L', 20, 0, -5}, {'R', 20, 0, 2},   /* G99 */
                {'R', 30, 0, 2}, {'L', 30, 0, -5}, {'R', 30, 0, 2}};
    expect_motions("G81", "G90 G00 X0 Y0 Z10.\nG98 G81 X10. Y0 Z-5. R2. F100\nG99 X20.\nX30.\nG80\n",
                   e81, N(e81));
    /* G82 P1000: one second at the bottom */
    em e82[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'D', 1, 0, 0}, {'R', 0, 0, 10}};
    expect_motions("G82", "G00 Z10.\nG98 G82 X0 Y0 Z-5. R2. P1000 F100\n", e82, N(e82));
    /* G73 Q2, retract d = 1: pecks to 0, -2, -4, then -5 */
    em e73[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, 0}, {'R', 0, 0, 1}, {'L', 0, 0, -2},
                {'R', 0, 0, -1}, {'L', 0, 0, -4}, {'R', 0, 0, -3}, {'L', 0, 0, -5}, {'R', 0, 0, 10}};
    expect_motions("G73", "G00 Z10.\nG98 G73 X0 Y0 Z-5. R2. Q2. F100\n", e73, N(e73));
    /* G83 Q2, clearance d = 1: back to R after each peck, down to d above */
    em e83[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, 0}, {'R', 0, 0, 2}, {'R', 0, 0, 1},
                {'L', 0, 0, -2}, {'R', 0, 0, 2}, {'R', 0, 0, -1}, {'L', 0, 0, -4}, {'R', 0, 0, 2},
                {'R', 0, 0, -3}, {'L', 0, 0, -5}, {'R', 0, 0, 10}};
    expect_motions("G83", "G00 Z10.\nG98 G83 X0 Y0 Z-5. R2. Q2. F100\n", e83, N(e83));
    /* G84 (G99): in at feed with the spindle forward, dwell, out reversed */
    em e84[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'D', 0.5, 0, 0}, {'L', 0, 0, 2}};
    expect_motions("G84", "G00 Z10. M03 S500\nG99 G84 X0 Y0 Z-5. R2. P500 F100\n", e84, N(e84));
    CHECK(ngot == 5 && got[2].spindle_dir == 1 && got[4].spindle_dir == -1);
    expect_motions("G74", "G00 Z10. M04 S500\nG99 G74 X0 Y0 Z-5. R2. P500 F100\n", e84, N(e84));
    CHECK(ngot == 5 && got[2].spindle_dir == -1 && got[4].spindle_dir == 1);
    /* G85: out at feed; G98 then rapids to the initial level */
    em e85[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'L', 0, 0, 2}, {'R', 0, 0, 10}};
    expect_motions("G85", "G00 Z10.\nG98 G85 X0 Y0 Z-5. R2. F100\n", e85, N(e85));
    /* G86: the spindle stops, rapid out */
    em e86[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'R', 0, 0, 10}};
    expect_motions("G86", "G00 Z10. M03 S500\nG98 G86 X0 Y0 Z-5. R2. F100\n", e86, N(e86));
    CHECK(ngot == 4 && got[3].spindle_dir == 0 && got[2].spindle_dir == 1);
    /* G88: dwell, then the manual retract (a rapid) */
    em e88[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'D', 0.2, 0, 0}, {'R', 0, 0, 10}};
    expect_motions("G88", "G00 Z10. M03 S500\nG98 G88 X0 Y0 Z-5. R2. P200 F100\n", e88, N(e88));
    /* G89: dwell, out at feed */
    em e89[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'D', 0.2, 0, 0}, {'L', 0, 0, 2},
                {'R', 0, 0, 10}};
    expect_motions("G89", "G00 Z10.\nG98 G89 X0 Y0 Z-5. R2. P200 F100\n", e89, N(e89));
    /* G76 Q1.: dwell, oriented stop, shift +X 1, out, shift back */
    em e76[] = {{'R', 0, 0, 10}, {'R', 0, 0, 2}, {'L', 0, 0, -5}, {'D', 0.2, 0, 0}, {'R', 1, 0, -5},
                {'R', 1, 0, 10}, {'R', 0, 0, 10}};
    expect_motions("G76", "G00 Z10. M03 S500\nG98 G76 X0 Y0 Z-5. R2. Q1. P200 F100\n", e76,
                   N(e76));
    /* G87: shift, down to R under the part, shift back, cut up to Z, shift,
     * up to the initial level, shift back */
    em e87[] = {{'R', 0, 0, 10}, {'R', 1, 0, 10}, {'R', 1, 0, -8}, {'R', 0, 0, -8}, {'L', 0, 0, -2},
                {'R', 1, 0, -2}, {'R', 1, 0, 10}, {'R', 0, 0, 10}};
    expect_motions("G87", "G00 Z10. M03 S500\nG98 G87 X0 Y0 Z-2. R-8. Q1. F100\n", e87, N(e87));
    /* K repeats in G91: R-8. from the initial level 10 is 2, Z-7. from R is -5 */
    em ek[] = {{'R', 0, 0, 10},
               {'R', 10, 0, 10}, {'R', 10, 0, 2}, {'L', 10, 0, -5}, {'R', 10, 0, 10},
               {'R', 20, 0, 10}, {'R', 20, 0, 2}, {'L', 20, 0, -5}, {'R', 20, 0, 10},
               {'R', 30, 0, 10}, {'R', 30, 0, 2}, {'L', 30, 0, -5}, {'R', 30, 0, 10}};
    expect_motions("K", "G90 G00 X0 Y0 Z10.\nG91 G98 G81 X10. Y0 Z-7. R-8. K3 F100\n", ek, N(ek));
    /* K0 stores the data; the next block drills */
    em ek0[] = {{'R', 0, 0, 10}, {'R', 5, 0, 10}, {'R', 5, 0, 2}, {'L', 5, 0, -5}, {'R', 5, 0, 10}};
    expect_motions("K0", "G90 G00 X0 Y0 Z10.\nG98 G81 X1. Z-5. R2. K0 F100\nX5.\n", ek0, N(ek0));
    /* G80 then axis words: the G00 mode from before the cycle */
    em e80[] = {{'R', 0, 0, 10}, {'R', 5, 0, 10}, {'R', 5, 0, 2}, {'L', 5, 0, -5}, {'R', 5, 0, 10},
                {'R', 7, 0, 10}};
    expect_motions("G80", "G90 G00 X0 Y0 Z10.\nG98 G81 X5. Z-5. R2. F100\nG80 X7.\n", e80,
                   N(e80));
}

static void test_polar(void)
{
    /* G16 bolt circle of radius 50 at 0, 60 and 120 degrees:
     * (50, 0), (25, 43.30127), (-25, 43.30127) */
    double h = 50 * sin(FM_PI / 3);
    em e[] = {{'R', 0, 0, 10},
              {'R', 50, 0, 10}, {'R', 50, 0, 2}, {'L', 50, 0, -5}, {'R', 50, 0, 2},
              {'R', 25, h, 2}, {'L', 25, h, -5}, {'R', 25, h, 2},
              {'R', -25, h, 2}, {'L', -25, h, -5}, {'R', -25, h, 2},
              {'R', 0, 0, 2}};
    expect_motions("G16 bolt circle",
                   "G90 G17 G00 X0 Y0 Z10.\nG16\nG99 G81 X50. Y0 Z-5. R2. F100\nY60.\nY120.\n"
                   "G15 G80\nG00 X0 Y0\n",
                   e, N(e));
    /* G91 angles add: six holes 60 degrees apart from one block with K6 */
    fm_error err;
    CHECK(run("G90 G00 X0 Y0 Z10.\nG16\nG99 G81 X30. Y0 Z-5. R2. F100\nG91 Y60. K5\n", &err) ==
          FM_OK);
    int holes = 0;
    for (int i = 0; i < ngot; i++)
        if (got[i].kind == FM_MOTION_LINE) {
            double a = holes * 60 * FM_PI / 180;
            CHECK_NEAR(got[i].end[0], 30 * cos(a), 1e-9);
            CHECK_NEAR(got[i].end[1], 30 * sin(a), 1e-9);
            holes++;
        }
    CHECK(holes == 6);
}

static void test_arcs(void)
{
    /* G02 (0,0) -> (10,10) R10: centre (10,0), 90 degrees; R-10: centre
     * (0,10), the 270-degree arc. A full circle cannot be given with R: no
     * motion. I J: always from the start point; only I: a full circle. */
    fm_error err;
    CHECK(run("G90 G00 X0 Y0\nG02 X10. Y10. R10. F100\n", &err) == FM_OK);
    CHECK(ngot == 2 && fabs(got[1].center[0] - 10) < 1e-9 && fabs(got[1].center[1]) < 1e-9);
    CHECK_NEAR(got[1].t1 - got[1].t0, FM_PI * 10 / 2 / 100 * 60, 1e-9);
    CHECK(run("G90 G00 X0 Y0\nG02 X10. Y10. R-10. F100\n", &err) == FM_OK);
    CHECK(ngot == 2 && fabs(got[1].center[0]) < 1e-9 && fabs(got[1].center[1] - 10) < 1e-9);
    CHECK_NEAR(got[1].t1 - got[1].t0, 3 * FM_PI * 10 / 2 / 100 * 60, 1e-9);
    CHECK(run("G90 G00 X10. Y0\nG02 X10. Y0 R5. F100\nG00 X1.\n", &err) == FM_OK);
    CHECK(ngot == 2 && got[1].kind == FM_MOTION_RAPID);
    CHECK(run("G90 G00 X10. Y0\nG02 I5. F100\n", &err) == FM_OK);
    CHECK(ngot == 2 && got[1].kind == FM_MOTION_ARC && got[1].turns == -1);
    CHECK(ngot == 2 && fabs(got[1].center[0] - 15) < 1e-9 && fabs(got[1].end[0] - 10) < 1e-9);
    CHECK_NEAR(got[1].t1 - got[1].t0, 2 * FM_PI * 5 / 100 * 60, 1e-9);
    /* G90 with I J: still incremental from the start (10, 0): centre (10, 5) */
    CHECK(run("G90 G00 X10. Y0\nG03 X10. Y10. J5. F100\n", &err) == FM_OK);
    CHECK(ngot == 2 && fabs(got[1].center[0] - 10) < 1e-9 && fabs(got[1].center[1] - 5) < 1e-9);
}

static void test_tool_length(void)
{
    static fm_tool_spec tools[2];
    static fm_tool_table table = {2, tools};
    tools[0].number = 1;
    tools[0].length_offset = 50;
    tools[1].number = 2;
    tools[1].length_offset = 20;
    fm_gcode_options o = fanuc();
    o.tools = &table;
    /* T1 (50 mm) without G43: the tip is 50 below the point. G43 H1 alone:
     * Fanuc moves Z so that the tip is at the programmed Z100 (the motion's
     * point goes from 100 - 50 to 100, tip offset 0). G44 H2 Z10.: offset
     * -20, tip offset -20 - 50. G49 alone: the gauge line back to Z10. */
    em e[] = {{'R', 0, 0, 100}, {'R', 0, 0, 100}, {'L', 0, 0, 5}, {'L', 0, 0, 10}, {'L', 0, 0, 10}};
    expect_motions_opt("G43 G44 G49",
                       "T1 M06\nG90 G00 X0 Y0 Z100.\nG43 H1\nG01 Z5. F100\nG44 H2 Z10.\nG49\n", &o,
                       e, N(e));
    if (ngot == 5) {
        CHECK_NEAR(got[0].tip_offset[2], -50, 1e-12);
        CHECK_NEAR(got[1].start[2], 50, 1e-12);
        CHECK_NEAR(got[1].tip_offset[2], 0, 1e-12);
        CHECK_NEAR(got[3].start[2], 75, 1e-12);     /* 5 + (50 - (-20)) */
        CHECK_NEAR(got[3].tip_offset[2], -70, 1e-12);
        CHECK_NEAR(got[4].start[2], -10, 1e-12);    /* 10 + (-20 - 0) */
        CHECK_NEAR(got[4].tip_offset[2], -50, 1e-12);
    }
}

static void test_reference(void)
{
    fm_gcode_options o = fanuc();
    o.reference_points[0][0] = 100;
    o.reference_points[0][1] = 200;
    o.reference_points[0][2] = 300;
    o.reference_points[1][0] = -1;
    /* G91 G28 Z0: through the current point to the reference Z only; G90
     * G28 X20. Y20.: through (20, 20), then X and Y of the reference point;
     * G30 P2 X0: through X0 to the second reference point's X */
    em e[] = {{'R', 10, 10, 10}, {'R', 10, 10, 10}, {'R', 10, 10, 300}, {'R', 20, 20, 300},
              {'R', 100, 200, 300}, {'R', 0, 200, 300}, {'R', -1, 200, 300}};
    expect_motions_opt("G28 G30",
                       "G90 G00 X10. Y10. Z10.\nG91 G28 Z0\nG90 G28 X20. Y20.\nG30 P2 X0\n", &o, e,
                       N(e));
    /* the program starts where the machine is after its reference return */
    CHECK(ngot > 0 && got[0].start[0] == 100 && got[0].start[1] == 200 && got[0].start[2] == 300);
}

static void test_scaling_dwell(void)
{
    /* G51 P2000: factor 2 about the origin; P1.5 (Haas, decimal): 1.5 */
    em e[] = {{'L', 20, 10, 0}, {'L', 10, 10, 0}, {'L', 15, 0, 0}};
    expect_motions("G51", "G51 X0 Y0 Z0 P2000\nG01 X10. Y5. F100\nG50\nX10.\nG51 P1.5 X0 Y0\n"
                          "G01 X10. Y0\n", e, N(e));
    expect_error("G51 X0 Y0 I1000 J2000 K1000\n", 1, 17, "per-axis scaling");
    /* G04 X1.5, X1500 (0.001 s each), P1500 (ms), P1.5 (Haas: seconds) */
    em d[] = {{'D', 1.5, 0, 0}, {'D', 1.5, 0, 0}, {'D', 1.5, 0, 0}, {'D', 1.5, 0, 0}};
    expect_motions("G04", "G04 X1.5\nG04 X1500\nG04 P1500\nG04 P1.5\n", d, N(d));
}

/* ---- the same program in both dialects ---- */

static int keep(const fm_motion *m)
{
    /* a zero-length rapid moves nothing (LinuxCNC emits one after G85 in G99) */
    return !(m->kind == FM_MOTION_RAPID && m->start[0] == m->end[0] && m->start[1] == m->end[1] &&
             m->start[2] == m->end[2]);
}

static void same_in_both(const char *what, const char *text)
{
    static fm_motion a[MAXM];
    static fm_tool_spec tools[1];
    static fm_tool_table table = {1, tools};
    tools[0].number = 1;
    tools[0].length_offset = 30;
    fm_gcode_options lin, fan;
    fm_gcode_options_default(&lin);
    lin.tools = &table;
    fan = lin;
    fan.dialect = FM_GCODE_FANUC;
    /* LinuxCNC's G73/G83 use 0.010 inch; give Fanuc the same parameters */
    fan.peck_retract = fan.peck_clearance = 0.254;
    fm_error err;
    CHECK(run_opt(text, &lin, &err) == FM_OK);
    int na = 0;
    for (int i = 0; i < ngot; i++)
        if (keep(&got[i])) a[na++] = got[i];
    fm_status st = run_opt(text, &fan, &err);
    CHECK(st == FM_OK);
    if (st) {
        char buf[700];
        fprintf(stderr, "  %s: %s\n", what, fm_error_format(&err, buf, sizeof buf));
    }
    int nb = 0, bad = 0;
    for (int i = 0; i < ngot; i++) {
        if (!keep(&got[i])) continue;
        const fm_motion *x = &a[nb], *y = &got[i];
        if (nb >= na || x->kind != y->kind || x->turns != y->turns ||
            x->plane_axis != y->plane_axis || fabs(x->t1 - y->t1) > 1e-9 ||
            fabs(x->tip_offset[2] - y->tip_offset[2]) > 1e-12) {
            bad++;
        } else {
            for (int k = 0; k < 3; k++)
                if (fabs(x->end[k] - y->end[k]) > 1e-9 || fabs(x->start[k] - y->start[k]) > 1e-9 ||
                    (x->kind == FM_MOTION_ARC && fabs(x->center[k] - y->center[k]) > 1e-9))
                    bad++;
        }
        if (bad == 1) {
            fprintf(stderr, "  %s: motion %d (line %d) differs between the dialects\n", what, nb,
                    y->line);
            bad++;
        }
        nb++;
    }
    CHECK(na == nb && na > 0);
    CHECK(bad == 0);
    if (na != nb) fprintf(stderr, "  %s: %d motions in LinuxCNC, %d in Fanuc\n", what, na, nb);
}

static void test_same_meaning(void)
{
    same_in_both("lines and arcs",
                 "G21 G17 G90 G94\nT1 M06\nG00 G54 X0 Y0 S1000 M03\nG43 H1 Z20.\n"
                 "G01 Z-1. F200\nX10. Y5.\nG02 X20. Y5. R5.\nG03 X20. Y15. I0 J5.\n"
                 "G02 X20. Y15. I0 J-3.\nG91 G01 X-5. Y-5.\nG03 X-10. Y0 R5.\nG90 G17\n"
                 "G18 G02 X10. Z-1. I2.5 K0\nG19 G03 Y5. Z-1. J-2.5 K0\nG17\n"
                 "G02 X0 Y0 Z-4. I-5. J-2.5\nG00 Z20.\nM05\nM30\n");
    same_in_both("offsets",
                 "G21 G90\nG10 L2 P1 X10. Y20. Z-5.\nG10 L2 P2 X-30. Y0 Z0\nG54 G00 X0 Y0 Z10.\n"
                 "G55 G00 X5. Y5.\nG92 X0 Y0\nG00 X2. Y3.\nG54 G01 X1. F500\n"
                 "G53 G00 Z0\nG91 G28 Z0.\nG90 G00 X0 Y0\nM30\n");
    same_in_both("cycles",
                 "G21 G17 G90 G94 F150\nT1 M06\nG00 G43 H1 Z30. S800 M03\nG00 X0 Y0 Z30.\n"
                 "G98 G81 X10. Y10. Z-5. R2.\nX20.\nG99 X30. Y15.\nG80\nG00 Z30.\n"
                 "G98 G83 X40. Y0 Z-9. R3. Q2.5\nG99 X50.\nG80\nG00 Z30.\n"
                 "G99 G73 X60. Y0 Z-7. R1. Q1.5\nX70.\nG80\nG00 Z30.\n"
                 "G99 G85 X0 Y30. Z-4. R2.\nX10.\nG80\nG00 Z30.\n"
                 "G91 G98 G81 X5. Y0 Z-10. R-25. L3\nG90 G80\n"
                 "G18 G00 X0 Y30. Z0\nG99 G81 X10. Y-5. Z5. R25.\nG80 G17\nM30\n");
    same_in_both("expressions",
                 "G21 G90 G00 X[1.5 + 2 * 3] Y[[1 + 2] * 3 - 0.25]\n#1=60.\n"
                 "G01 X[10. * COS[#1]] Y[10. * SIN[#1 - 30.]] F300\n#2=[#1 + 15.]\n"
                 "G00 X#2 Y[SQRT[16.]]\nG00 X[ABS[-2.5]] Y[FIX[2.4]]\nM30\n");
}

/* ---- errors ---- */

static void test_errors(void)
{
    expect_error("G90\nG31 X1.\n", 2, 1, "skip function");
    expect_error("WHILE [1 LT 2] DO4\nEND4\n", 1, 18, "loop number 4");
    expect_error("G00 X1.\nEND1\n", 2, 1, "END 1 without a matching DO 1");
    expect_error("WHILE [#1 GT 0] DO1\nG00 X1.\n", 1, 1, "WHILE [..] DO 1 without a matching END 1");
    expect_error("G00 X1.\nGOTO 50\n", 2, 1, "no sequence number N50");
    expect_error("#0=1.\n", 1, 1, "#0 is always vacant");
    expect_error("#1=SQRT[-1]\n", 1, 4, "square root of a negative number");
    expect_error("#1=1/0\n", 1, 5, "division by zero");
    expect_error("G01 X#1+1. F100\n", 1, 8, "unexpected '+'");
    expect_error("G02 X10. Y0 F100\n", 1, 1, "no centre");
    expect_error("G00 Z10.\nG99 G87 X0 Y0 Z-2. R-8. Q1. F100\n", 2, 5, "G87 in G99 mode");
    expect_error("G81 X1. Y1. F100\n", 1, 1, "hole bottom and R missing");
    expect_error("O0001 G00 X1.\n", 1, 7, "text after the program number");
    expect_error("IF [#1 EQ 1] X1.\n", 1, 14, "expected GOTO n or THEN");
    expect_error("G65 P1 A1. G00\n", 1, 12, "after G65");
    expect_error("#1=ATAN[1]\n", 1, 4, "ATAN with one argument");
    expect_error("#1=ASIN[2]\n", 1, 4, "argument out of range");
    expect_error("#1=#1001\n", 1, 4, "interface signals");
    expect_error("#5001=1.\n", 1, 1, "is read-only");
    expect_error("G00 X1. #1=2\n", 1, 9, "variable assignment after other words");
    expect_error("G10 L10 P1 R5.\n", 1, 5, "tool offsets come from the tool table");
    expect_error("G68 X0 Y0\n", 1, 1, "R missing");
    /* G95 is accepted now: a feed move with the spindle stopped is the error */
    expect_error("G95 G01 X1. F0.1\n", 1, 5, "feed per revolution (G95) with the spindle stopped");
    expect_error("G12 I5.\n", 1, 1, "circular pocket");
    expect_error("M98\n", 1, 1, "P missing");
    expect_error("N10 G00 X1.\nM97 P20\n", 2, 1, "no sequence number N20");
    expect_error("G73 X0 Y0 Z-5. R2. F100\n", 1, 1, "peck depth Q missing");
    expect_error("G01 X1.\n", 1, 1, "feed rate is zero");
    expect_error("G00 X1.\nG02 X10. Y0 R2. F100\n", 2, 13, "radius too small");
}

/* ---- Haas codes and the codes CAM posts write (fanuc/haas.c) ---- */

static void test_g154(void)
{
    /* Haas: G154 P1-P99 at #14001 + 20 (P - 1) (X Y Z first), P1-P20 the
     * same offsets as G54.1 P1-P20 (#7001..). From the machine origin:
     * P1 = (10, 20, -5), P21 = (100, -50, 0); X#1 Y[#2 + #3] in P21 with
     * #14401 (P21 X = 100), #14002 and #7002 (both P1 Y = 20) is X100 Y40,
     * machine (200, -10, 0); G91 G10 L20 P21 X5. adds 5 to P21 X; #15961 is
     * P99 X */
    em e[] = {{'R', 10, 20, -5},  {'R', 11, 21, -4}, {'R', 100, -50, 0}, {'R', 200, -10, 0},
              {'R', 105, -50, 0}, {'R', 7, 0, 0}};
    expect_motions("G154",
                   "G10 L20 P1 X10. Y20. Z-5.\nG10 L20 P21 X100. Y-50. Z0\n"
                   "G154 P1\nG00 X0 Y0 Z0\nG54.1 P1\nG00 X1. Y1. Z1.\n"
                   "G154 P21\nG00 X0 Y0 Z0\n#1=#14401\n#2=#14002\n#3=#7002\nG00 X#1 Y[#2+#3]\n"
                   "G91 G10 L20 P21 X5.\nG90 G00 X0 Y0\n#15961=7.\nG154 P99\nG00 X0 Y0 Z0\n",
                   e, N(e));
    /* #4014 (the work offset group): 154 in G154, 54.1 in G54.1, 54 in G54 */
    em e4[] = {{'R', 154, 0, 0}, {'R', 154, 54.1, 0}, {'R', 154, 54.1, 54}};
    expect_motions("#4014", "G154 P2\n#1=#4014\nG54.1 P2\n#2=#4014\nG54\n#3=#4014\n"
                            "G00 X#1\nY#2\nZ#3\n", e4, N(e4));
    expect_error("G154 P100\n", 1, 6, "expected a whole number from 1 to 99");
    expect_error("G154\n", 1, 1, "G154: P missing");
    expect_error("G10 L20 P100 X1.\n", 1, 9, "expected a whole number from 1 to 99");
}

/* Two programs give the same motions (kind, end, time). */
static void expect_same(const char *what, const char *a, const char *b)
{
    static fm_motion first[200];
    fm_error err;
    CHECK(run(a, &err) == FM_OK);
    int n = ngot < 200 ? ngot : 200;
    memcpy(first, got, (size_t)n * sizeof *first);
    CHECK(run(b, &err) == FM_OK);
    CHECK(ngot == n && n > 0);
    for (int i = 0; i < n && i < ngot; i++) {
        int ok = first[i].kind == got[i].kind && first[i].line + 2 == got[i].line &&
                 fabs(first[i].t1 - got[i].t1) < 1e-9;
        for (int k = 0; k < 3; k++) ok = ok && fabs(first[i].end[k] - got[i].end[k]) < 1e-9;
        CHECK(ok);
        if (!ok) fprintf(stderr, "  %s: motion %d differs\n", what, i);
    }
}

static void test_lookahead_codes(void)
{
    /* G187 (Haas accuracy: P1 rough, P2 medium, P3 finish, E the corner
     * tolerance) and G103 (look-ahead limit P) change the servo behaviour,
     * not the path: the motions are those of the program without them (two
     * lines earlier) */
    const char *body = "G90 G00 X0 Y0 Z5.\nG01 Z-1. F200.\nX20.\nG02 X40. R10.\nG00 Z5.\n";
    char with[512];
    snprintf(with, sizeof with, "G187 P3 E0.01\nG103 P4\n%sG187\nG103\nM30\n", body);
    char without[512];
    snprintf(without, sizeof without, "%sM30\n", body);
    expect_same("G187 G103", without, with);
}

static void test_g95(void)
{
    /* G95: F is mm per revolution, the feed rate F x S. S1000 F0.2: 200
     * mm/min, 10 mm take 3 s; the half circle R5 (5 pi mm) 1.5 pi s; at S500
     * 100 mm/min, 10 mm 6 s; G94 F300.: 10 mm 2 s */
    fm_error err;
    CHECK(run("G90 G00 X0 Y0 Z0\nS1000 M03\nG95 G01 X10. F0.2\nG02 X20. R5.\nS500\nG01 X30.\n"
              "#1=#4005\nG94 G01 X40. F300.\n#2=#4005\n#3=#1*1000+#2\nG00 Y#3\n", &err) == FM_OK);
    CHECK(ngot == 6);
    if (ngot == 6) {
        CHECK_NEAR(got[1].feed, 200, 1e-9);
        CHECK_NEAR(got[1].t1 - got[1].t0, 3, 1e-9);
        CHECK_NEAR(got[2].t1 - got[2].t0, 5 * FM_PI / 200 * 60, 1e-9);
        CHECK_NEAR(got[3].feed, 100, 1e-9);
        CHECK_NEAR(got[3].t1 - got[3].t0, 6, 1e-9);
        CHECK_NEAR(got[4].t1 - got[4].t0, 2, 1e-9);
        CHECK_NEAR(got[5].end[1], 95 * 1000 + 94, 1e-9); /* #4005: 95, then 94 */
    }
    /* a canned cycle in G95: G81 from Z10., R2., Z-10.: the 12 mm feed at
     * 0.1 x 2000 = 200 mm/min take 3.6 s */
    CHECK(run("G90 G00 X0 Y0 Z10.\nS2000 M03\nG95 F0.1\nG81 X5. Y0 Z-10. R2.\n", &err) == FM_OK);
    CHECK(ngot == 5);
    if (ngot == 5) {
        CHECK(got[3].kind == FM_MOTION_LINE);
        CHECK_NEAR(got[3].end[2], -10, 1e-9);
        CHECK_NEAR(got[3].t1 - got[3].t0, 3.6, 1e-9);
    }
    /* in G20: F0.01 in/rev at S1000 is 10 in/min = 254 mm/min: 1 in in 6 s */
    CHECK(run("G20 G90 G00 X0 Y0 Z0\nS1000 M03\nG95 G01 X1. F0.01\n", &err) == FM_OK);
    CHECK(ngot == 2);
    if (ngot == 2) {
        CHECK_NEAR(got[1].feed, 254, 1e-9);
        CHECK_NEAR(got[1].t1 - got[1].t0, 6, 1e-9);
    }
    expect_error("S0 M03\nG95 G01 X1. F0.1\n", 2, 5, "feed per revolution (G95) with the spindle "
                 "at S0");
    expect_error("G96 S200 M03\nG95 G01 X1. F0.1\n", 2, 1, "G95 feed per revolution with G96");
}

static void test_circular_pocket(void)
{
    static fm_tool_spec tools[2];
    static fm_tool_table table = {2, tools};
    tools[0].number = 1;
    tools[0].diameter = 10;
    tools[1].number = 2;
    tools[1].diameter = 6;
    fm_gcode_options o = fanuc();
    o.tools = &table;
    fm_error err;
    /* G12 I15. D1 (radius 5): one finished circle, the tool centre on
     * radius 10 about (50, 50): feed down to Z-3., a clockwise half circle
     * from the centre out to (60, 50) (about (55, 50), radius 5), the full
     * circle, a half circle back to the centre (about (55, 50) again) */
    em e1[] = {{'R', 50, 50, 2}, {'L', 50, 50, -3}, {'A', 60, 50, -3}, {'A', 60, 50, -3},
               {'A', 50, 50, -3}};
    expect_motions_opt("G12 finish", "G90 G00 X50. Y50. Z2.\nG12 I15. Z-3. D1 F300.\n", &o, e1,
                       N(e1));
    if (ngot == 5) {
        CHECK(got[2].turns == -1 && got[3].turns == -1 && got[4].turns == -1);
        CHECK_NEAR(got[2].center[0], 55, 1e-9);
        CHECK_NEAR(got[3].center[0], 50, 1e-9);
        CHECK_NEAR(got[4].center[0], 55, 1e-9);
        CHECK_NEAR(got[1].t1 - got[1].t0, 1, 1e-9);                        /* 5 mm at 300 */
        CHECK_NEAR(got[2].t1 - got[2].t0, 5 * FM_PI / 300 * 60, 1e-9); /* half of r 5 */
        CHECK_NEAR(got[3].t1 - got[3].t0, 20 * FM_PI / 300 * 60, 1e-9); /* r 10 */
    }
    /* Haas' example G13 G91 Z-.5 I.4 K2. Q.4 D1 L4 in mm: G13 G91 Z-5. I4.
     * K20. Q4. D2 (radius 3) L2: circles of radius 4, 8, 12, 16, 20, the tool
     * centre 3 inside (1, 5, 9, 13, 17), counter-clockwise, alternately
     * ending on +X and -X: the lead-in from (0,0) to (1,0) about (0.5,0),
     * then each step a half circle from r on one side to the next r on the
     * other (about the midpoint: (1,0) -> (-5,0) about (-2,0), (-5,0) ->
     * (9,0) about (2,0), ...), the last circle at (17,0), the lead-out to the
     * centre about (8.5,0); the second pass 5 mm deeper */
    em e2[26];
    int n = 0;
    e2[n++] = (em){'R', 0, 0, 0};
    for (int pass = 1; pass <= 2; pass++) {
        double z = -5.0 * pass;
        e2[n++] = (em){'L', 0, 0, z};
        const double ends[5] = {1, -5, 9, -13, 17};
        for (int c = 0; c < 5; c++) {
            e2[n++] = (em){'A', ends[c], 0, z}; /* the half turn out to this circle */
            e2[n++] = (em){'A', ends[c], 0, z}; /* the circle */
        }
        e2[n++] = (em){'A', 0, 0, z};
    }
    expect_motions_opt("G13 I K Q L", "G90 G00 X0 Y0 Z0\nG13 G91 Z-5. I4. K20. Q4. D2 L2 F100.\n",
                       &o, e2, n);
    if (ngot == n) {
        const double step_centres[5] = {0.5, -2, 2, -2, 2};
        for (int c = 0; c < 5; c++) {
            CHECK_NEAR(got[2 + 2 * c].center[0], step_centres[c], 1e-9);
            CHECK(got[2 + 2 * c].turns == 1 && got[3 + 2 * c].turns == 1);
        }
        CHECK_NEAR(got[12].center[0], 8.5, 1e-9);
        CHECK_NEAR(got[11].t1 - got[11].t0, 34 * FM_PI / 100 * 60, 1e-9); /* r 17 */
    }
    /* Haas' manual's own example, in inches: G13 G91 Z-.5 I.4 K2. Q.4 D1 L4
     * F20. with a 0.5 in end mill (radius .25): circles .4 .8 1.2 1.6 2.0,
     * the tool centre on .15 .55 .95 1.35 1.75 in, alternately on +X and -X;
     * four passes 0.5 in deeper each, the last at Z-2. in; the last circle
     * of each pass, 2 pi 1.75 in at 20 in/min, takes 2 pi 1.75 / 20 min */
    static fm_tool_spec half_inch[1];
    static fm_tool_table half_inch_table = {1, half_inch};
    half_inch[0].number = 1;
    half_inch[0].diameter = 12.7;
    fm_gcode_options oi = fanuc();
    oi.tools = &half_inch_table;
    em e5[49];
    int n5 = 0;
    e5[n5++] = (em){'R', 0, 0, 0};
    for (int pass = 1; pass <= 4; pass++) {
        double z = -0.5 * pass * 25.4;
        e5[n5++] = (em){'L', 0, 0, z};
        const double ends[5] = {0.15, -0.55, 0.95, -1.35, 1.75};
        for (int c = 0; c < 5; c++) {
            e5[n5++] = (em){'A', ends[c] * 25.4, 0, z};
            e5[n5++] = (em){'A', ends[c] * 25.4, 0, z};
        }
        e5[n5++] = (em){'A', 0, 0, z};
    }
    expect_motions_opt("Haas G13 example (inch)",
                       "G20 G90 G00 X0 Y0 Z0\nG13 G91 Z-.5 I.4 K2. Q.4 D1 L4 F20.\n", &oi, e5, n5);
    if (ngot == n5) {
        CHECK_NEAR(got[11].t1 - got[11].t0, 2 * FM_PI * 1.75 / 20 * 60, 1e-9);
        CHECK_NEAR(got[11].feed, 20 * 25.4, 1e-9);
    }
    /* Q that does not divide K - I: radii 4, 8, then 10 (D0: the centre on them) */
    em e3[] = {{'R', 0, 0, 0},  {'L', 0, 0, -1},  {'A', 4, 0, -1}, {'A', 4, 0, -1},
               {'A', -8, 0, -1}, {'A', -8, 0, -1}, {'A', 10, 0, -1}, {'A', 10, 0, -1},
               {'A', 0, 0, -1}};
    expect_motions("G12 Q uneven", "G90 G00 X0 Y0 Z0\nG12 I4. K10. Q4. Z-1. F100.\n", e3, N(e3));
    CHECK(run_opt("G12 I5. D1 F100.\n", &o, &err) != FM_OK);
    CHECK_STR_CONTAINS(err.message, "expected a radius larger than the tool's");
    expect_error("G13 I5. K10. F100.\n", 1, 9, "K without Q");
}

/* G41 in G51.1 X0: the compensated contour is the reflection of the
 * contour cut without the mirror (G41 acts as G42 there: the tool stays on
 * the reflected side), each end and centre x -> -x, each arc reversed. */
static void test_mirror_comp(void)
{
    static fm_tool_spec tools[1];
    static fm_tool_table table = {1, tools};
    tools[0].number = 1;
    tools[0].diameter = 10;
    fm_gcode_options o = fanuc();
    o.tools = &table;
    const char *body = "G01 F500.\nG41 D1 X0 Y-10.\nY20.\nX30.\nG02 X40. Y10. R10.\nG01 Y-10.\n"
                       "X0\nG40 X-20. Y-20.\n";
    char plain[512], mirrored[512];
    snprintf(plain, sizeof plain, "G90 G00 X-20. Y-20. Z0\n%s", body);
    snprintf(mirrored, sizeof mirrored, "G51.1 X0\nG90 G00 X-20. Y-20. Z0\n%s", body);
    static fm_motion first[64];
    fm_error err;
    CHECK(run_opt(plain, &o, &err) == FM_OK);
    int n = ngot < 64 ? ngot : 64;
    memcpy(first, got, (size_t)n * sizeof *first);
    CHECK(run_opt(mirrored, &o, &err) == FM_OK);
    CHECK(ngot == n && n >= 8);
    for (int i = 0; i < n && i < ngot; i++) {
        const fm_motion *a = &first[i], *m = &got[i];
        int ok = a->kind == m->kind && fabs(a->end[0] + m->end[0]) < 1e-9 &&
                 fabs(a->end[1] - m->end[1]) < 1e-9 && fabs(a->end[2] - m->end[2]) < 1e-9;
        if (a->kind == FM_MOTION_ARC)
            ok = ok && a->turns == -m->turns && fabs(a->center[0] + m->center[0]) < 1e-9 &&
                 fabs(a->center[1] - m->center[1]) < 1e-9;
        CHECK(ok);
        if (!ok)
            fprintf(stderr, "  G51.1 G41: motion %d is %.4f %.4f, unmirrored %.4f %.4f\n", i,
                    m->end[0], m->end[1], a->end[0], a->end[1]);
    }
    /* G51.1 and G12 refused while compensating (line 3, column 1) */
    CHECK(run_opt("G90 G00 X0 Y0\nG01 G41 D1 X10. F100.\nG51.1 X0\n", &o, &err) != FM_OK);
    CHECK(err.line == 3 && err.column == 1);
    CHECK_STR_CONTAINS(err.message, "G51.1 with cutter radius compensation on");
    CHECK(run_opt("G90 G00 X0 Y0\nG01 G41 D1 X10. F100.\nG12 I15.\n", &o, &err) != FM_OK);
    CHECK(err.line == 3 && err.column == 1);
    CHECK_STR_CONTAINS(err.message, "the cycle compensates by its D");
}

static void test_mirror(void)
{
    /* G51.1 X50.: X mirrored about 50. The contour G01 X10. Y0, Y10., G02
     * X20. Y20. R10. (centre (20,10)), G91 X10. becomes X 100 - x: (90,0),
     * (90,10), a counter-clockwise arc to (80,20) about (80,10), (70,20);
     * G50.1 X0 cancels and G00 X0 Y0 goes to (0,0) unmirrored */
    em e[] = {{'R', 0, 0, 0}, {'L', 90, 0, 0}, {'L', 90, 10, 0}, {'A', 80, 20, 0}, {'L', 70, 20, 0},
              {'R', 0, 0, 0}};
    expect_motions("G51.1",
                   "G90 G00 X0 Y0 Z0\nG51.1 X50.\nG01 X10. Y0 F100.\nY10.\nG02 X20. Y20. R10.\n"
                   "G91 G01 X10.\nG90 G50.1 X0\nG00 X0 Y0\n",
                   e, N(e));
    if (ngot == N(e)) {
        CHECK(got[3].turns == 1);
        CHECK_NEAR(got[3].center[0], 80, 1e-9);
        CHECK_NEAR(got[3].center[1], 10, 1e-9);
    }
    /* both axes mirrored (about (0,0)): the arc keeps its direction; the
     * canned cycle's hole (5, 2) becomes (-5, -2) */
    em e2[] = {{'R', 0, 0, 10}, {'R', -10, 0, 10}, {'A', -20, -10, 10}, {'R', -5, -2, 10},
               {'R', -5, -2, 1}, {'L', -5, -2, -3}, {'R', -5, -2, 10}};
    expect_motions("G51.1 X Y",
                   "G90 G00 X0 Y0 Z10.\nG51.1 X0 Y0\nX10.\nG02 X20. Y10. R10. F100.\n"
                   "G81 X5. Y2. Z-3. R1.\n",
                   e2, N(e2));
    if (ngot == N(e2)) CHECK(got[2].turns == -1);
    /* G51.1 given before G68 reflects what the rotation makes (Fanuc: a
     * rotation in mirror mode turns the other way): X10. turned 90 degrees
     * is (0, 10), reflected about Y0 (0, -10) */
    em e3[] = {{'R', 0, 0, 0}, {'L', 0, -10, 0}};
    expect_motions("G51.1 G68", "G90 G00 X0 Y0 Z0\nG51.1 Y0\nG68 X0 Y0 R90.\nG01 X10. F100.\n",
                   e3, N(e3));
    expect_error("G68 X0 Y0 R90.\nG51.1 Y0\n", 2, 1, "Fanuc mirrors first");
    expect_error("G51.1 Y0\nG92 X0 Y0\n", 2, 1, "G92 in G68, G51 or G51.1 mode");
    expect_error("G51.1 Z0\n", 1, 7, "mirroring the tool axis is not supported");
    test_mirror_comp();
    expect_error("G51.1 X0\nG18\n", 2, 1, "plane change in G51.1 mode");
}

static void test_modal_call(void)
{
    /* G66 P9000 with Z (#26) R (#18) F (#9): after each move the macro
     * goes down to R, feeds to Z and back up; its own moves call nothing;
     * G67 ends the calls */
    em e[] = {{'R', 0, 0, 10},  {'R', 10, 10, 10}, {'R', 10, 10, 2}, {'L', 10, 10, -5},
              {'R', 10, 10, 10}, {'R', 20, 10, 10}, {'R', 20, 10, 2}, {'L', 20, 10, -5},
              {'R', 20, 10, 10}, {'R', 30, 10, 10}};
    expect_motions("G66",
                   "O0001\nG90 G00 X0 Y0 Z10.\nG66 P9000 Z-5. R2. F100.\nX10. Y10.\nX20.\nG67\n"
                   "X30.\nM30\n"
                   "O9000\nG00 Z#18\nG01 Z#26 F#9\nG00 Z10.\nM99\n",
                   e, N(e));
    /* #4012 is 66 while the call is on */
    em e2[] = {{'R', 66, 0, 0}, {'R', 67, 0, 0}};
    expect_motions("#4012", "G66 P1\n#1=#4012\nG67\n#2=#4012\nG00 X#1\nX#2\nM30\nO0001\nM99\n", e2,
                   N(e2));
    /* nesting: a G66 given in the called macro makes the macro's own moves
     * call the inner macro (Fanuc calls nested modal calls from the last
     * given), whose moves call nothing; its G67 leaves the outer G66 on */
    em e3[] = {{'R', 0, 0, 10}, {'R', 10, 0, 10}, {'R', 10, 1, 10}, {'R', 10, 1, 9},
               {'R', 10, 2, 9}, {'R', 20, 2, 9}, {'R', 20, 3, 9}, {'R', 20, 3, 8},
               {'R', 20, 4, 8}, {'R', 50, 4, 8}};
    expect_motions("G66 nested",
                   "O0001\nG90 G00 X0 Y0 Z10.\nG66 P9000\nX10.\nX20.\nG67\nX50.\nM30\n"
                   "O9000\nG66 P9100\nG91 G00 Y1.\nG67\nY1.\nG90\nM99\n"
                   "O9100\nG91 G00 Z-1.\nM99\n",
                   e3, N(e3));
    /* a G66 given in a macro ends with its return: a later macro at that
     * level does not call it */
    em e4[] = {{'R', 5, 0, 0}, {'R', 6, 0, 0}};
    expect_motions("G66 ends with its macro",
                   "G65 P9200\nG00 X5.\nG65 P9300\nM30\nO9200\nG66 P9100\nM99\n"
                   "O9300\nG91 G00 X1.\nG90\nM99\nO9100\nG00 Z-1.\nM99\n",
                   e4, N(e4));
    expect_error("G66 X1.\n", 1, 1, "G66: P missing");
}

/* Comments handed to fm_gcode_options.comment: "line|text" joined by '\n'. */
static void keep_comment(void *user, int line, const char *text, size_t len)
{
    char *buf = user;
    size_t n = strlen(buf);
    snprintf(buf + n, 1024 - n, "%d|%.*s\n", line, (int)len, text);
}

static void test_comments(void)
{
    /* a CAM post's header: each comment as written, with its line, in both
     * dialects; a line run twice (the M98 body) hands its comment over twice */
    const char *both = "%\n(T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL)\n(T2  D=10. (x\n"
                       "G90 G00 X1. (MSG, hi) ; rest; of line\nM30\n%\n";
    const char *expect = "2|T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL\n";
    for (int d = 0; d < 2; d++) {
        char buf[1024] = "";
        fm_gcode_options o = fanuc();
        o.dialect = d ? FM_GCODE_FANUC : FM_GCODE_LINUXCNC;
        o.comment = keep_comment;
        o.comment_user = buf;
        fm_error err;
        /* line 3 has an unclosed comment: the error comes after line 2's */
        CHECK(run_opt(both, &o, &err) != FM_OK);
        CHECK(err.line == 3);
        CHECK(strcmp(buf, expect) == 0);
        buf[0] = '\0';
        const char *ok = "%\n(T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL)\n"
                         "G90 G00 X1. (MSG, hi) ; rest; of line\nM30\n%\n";
        CHECK(run_opt(ok, &o, &err) == FM_OK);
        CHECK(strcmp(buf, "2|T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL\n3|MSG, hi\n"
                          "3| rest; of line\n") == 0);
        if (strcmp(buf, "2|T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL\n3|MSG, hi\n"
                        "3| rest; of line\n"))
            fprintf(stderr, "  comments (%s): %s", d ? "fanuc" : "linuxcnc", buf);
    }
    char buf[1024] = "";
    fm_gcode_options o = fanuc();
    o.comment = keep_comment;
    o.comment_user = buf;
    fm_error err;
    CHECK(run_opt("O0001 (MAIN)\nM98 P10 L2\nM30\nO0010 (SUB)\nG00 X1. (IN SUB)\nM99\n", &o, &err) ==
          FM_OK);
    /* the O line of the subprogram is read at each call */
    CHECK(strcmp(buf, "1|MAIN\n4|SUB\n5|IN SUB\n4|SUB\n5|IN SUB\n") == 0);
    if (strcmp(buf, "1|MAIN\n4|SUB\n5|IN SUB\n4|SUB\n5|IN SUB\n")) fprintf(stderr, "%s", buf);
}

/* Path control (docs/plan.md, "Fanuc and Haas"): each mode reaches the
 * motions it governs. G64 cutting mode blends with no tolerance of its own;
 * G61 stops at every block; G09 stops at its own block only; Haas G187
 * P1/P2/P3 blend within 0.1 / 0.05 / 0.01 mm and E gives the tolerance. */
static void test_path_modes(void)
{
    fm_error err = {0};
    CHECK(run("O1\nG21 G90 G17\nG01 X1. F100.\nG61 X2.\nX3.\nG64 X4.\nG09 X5.\nX6.\n"
              "G187 P1 X7.\nG187 P2 X8.\nG187 P3 X9.\nG187 P1 E0.02 X10.\nG20 G187 E0.001 X1.\nM30\n",
              &err) == FM_OK);
    CHECK(ngot == 11);
    if (ngot < 11) return;
    CHECK(got[0].path_mode == FM_PATH_BLEND && got[0].path_tolerance == 0);
    CHECK(got[1].path_mode == FM_PATH_EXACT_STOP);
    CHECK(got[2].path_mode == FM_PATH_EXACT_STOP);
    CHECK(got[3].path_mode == FM_PATH_BLEND && got[3].path_tolerance == 0);
    CHECK(got[4].path_mode == FM_PATH_EXACT_STOP); /* G09: this block */
    CHECK(got[5].path_mode == FM_PATH_BLEND);      /* and not the next */
    CHECK(got[6].path_mode == FM_PATH_BLEND);
    CHECK_NEAR(got[6].path_tolerance, 0.1, 1e-12);
    CHECK_NEAR(got[7].path_tolerance, 0.05, 1e-12);
    CHECK_NEAR(got[8].path_tolerance, 0.01, 1e-12);
    CHECK_NEAR(got[9].path_tolerance, 0.02, 1e-12);
    CHECK_NEAR(got[10].path_tolerance, 0.0254, 1e-12); /* E in inches */
}

int main(void)
{
    test_reading();
    test_subprograms();
    test_g65();
    test_control();
    test_expressions();
    test_rotation();
    test_offsets();
    test_cycles();
    test_polar();
    test_arcs();
    test_tool_length();
    test_reference();
    test_scaling_dwell();
    test_same_meaning();
    test_errors();
    test_g154();
    test_lookahead_codes();
    test_g95();
    test_circular_pocket();
    test_mirror();
    test_modal_call();
    test_comments();
    test_path_modes();
    return test_summary("test_fanuc");
}
