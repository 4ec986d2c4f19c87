/* gcode_internal.h: the interpreter's state and the functions its files
 * share. Private to toolpaths/gcode. The files, by concern:
 *   gcode.c          entry points, options, loading a program, the line loop
 *   gcode_block.c    reading blocks: line normalization, words, modal groups
 *   gcode_expr.c     numbers, [expressions], functions, parameters, errors
 *   gcode_modal.c    executing a block in LinuxCNC's order: modal state, M codes
 *   gcode_motion.c   lines, arcs, dwells and canned cycles -> emitted motions
 *   gcode_offsets.c  coordinate systems (G5x, G10, G92, G53), G43, G28/G30
 *   gcode_oword.c    O-word control flow: subroutines, conditions, loops */
#ifndef FM_GCODE_INTERNAL_H
#define FM_GCODE_INTERNAL_H

#include "gcode.h"

#include <stddef.h>

#define GC_PI 3.14159265358979323846
#define GC_INCH 25.4          /* mm per inch */

/* G codes as LinuxCNC keeps them: ten times the number, so that G28.1 is
 * 281 and one decimal fits an int. */
typedef enum gc_gcode {
    GC_G_NONE = -1,
    GC_G0 = 0, GC_G1 = 10, GC_G2 = 20, GC_G3 = 30, GC_G4 = 40,
    GC_G5 = 50, GC_G5_1 = 51, GC_G5_2 = 52, GC_G5_3 = 53, GC_G7 = 70, GC_G8 = 80,
    GC_G10 = 100,
    GC_G17 = 170, GC_G17_1 = 171, GC_G18 = 180, GC_G18_1 = 181, GC_G19 = 190, GC_G19_1 = 191,
    GC_G20 = 200, GC_G21 = 210,
    GC_G28 = 280, GC_G28_1 = 281, GC_G28_2 = 282, GC_G30 = 300, GC_G30_1 = 301, GC_G30_2 = 302,
    GC_G33 = 330, GC_G33_1 = 331,
    GC_G38_2 = 382, GC_G38_3 = 383, GC_G38_4 = 384, GC_G38_5 = 385,
    GC_G40 = 400, GC_G41 = 410, GC_G41_1 = 411, GC_G42 = 420, GC_G42_1 = 421,
    GC_G43 = 430, GC_G43_1 = 431, GC_G43_2 = 432, GC_G49 = 490,
    GC_G52 = 520, GC_G53 = 530,
    GC_G54 = 540, GC_G55 = 550, GC_G56 = 560, GC_G57 = 570, GC_G58 = 580, GC_G59 = 590,
    GC_G59_1 = 591, GC_G59_2 = 592, GC_G59_3 = 593,
    GC_G61 = 610, GC_G61_1 = 611, GC_G64 = 640,
    GC_G73 = 730, GC_G74 = 740, GC_G76 = 760,
    GC_G80 = 800, GC_G81 = 810, GC_G82 = 820, GC_G83 = 830, GC_G84 = 840, GC_G85 = 850,
    GC_G86 = 860, GC_G87 = 870, GC_G88 = 880, GC_G89 = 890,
    GC_G90 = 900, GC_G90_1 = 901, GC_G91 = 910, GC_G91_1 = 911,
    GC_G92 = 920, GC_G92_1 = 921, GC_G92_2 = 922, GC_G92_3 = 923,
    GC_G93 = 930, GC_G94 = 940, GC_G95 = 950, GC_G96 = 960, GC_G97 = 970,
    GC_G98 = 980, GC_G99 = 990
} gc_gcode;

/* LinuxCNC's modal groups of G codes (the values are its group numbers). */
typedef enum gc_group {
    GC_GROUP_UNKNOWN = -1,
    GC_GROUP_NON_MODAL = 0,      /* G4 G10 G28 G30 G53 G92 ... */
    GC_GROUP_MOTION = 1,         /* G0 G1 G2 G3 G73 G80-G89 */
    GC_GROUP_PLANE = 2,          /* G17 G18 G19 */
    GC_GROUP_DISTANCE = 3,       /* G90 G91 */
    GC_GROUP_ARC_DISTANCE = 4,   /* G90.1 G91.1 */
    GC_GROUP_FEED_MODE = 5,      /* G93 G94 G95 */
    GC_GROUP_UNITS = 6,          /* G20 G21 */
    GC_GROUP_CUTTER_COMP = 7,    /* G40 G41 G42 */
    GC_GROUP_TOOL_LENGTH = 8,    /* G43 G43.1 G49 */
    GC_GROUP_RETURN_MODE = 10,   /* G98 G99 */
    GC_GROUP_COORD_SYSTEM = 12,  /* G54 .. G59.3 */
    GC_GROUP_PATH_MODE = 13,     /* G61 G61.1 G64 */
    GC_GROUP_SPINDLE_MODE = 14,  /* G96 G97 */
    GC_GROUP_COUNT = 15,
    GC_GROUP_REFUSED = 99        /* codes LinuxCNC knows that this interpreter refuses */
} gc_group;

/* LinuxCNC's modal groups of M codes. */
typedef enum gc_mgroup {
    GC_MGROUP_STOP = 4,        /* M0 M1 M2 M30 M60 */
    GC_MGROUP_IO = 5,          /* M62-M68 */
    GC_MGROUP_TOOL_CHANGE = 6, /* M6 M61 */
    GC_MGROUP_SPINDLE = 7,     /* M3 M4 M5 */
    GC_MGROUP_COOLANT = 8,     /* M7 M8 M9 (M7 and M8 may share a line) */
    GC_MGROUP_OVERRIDE = 9,    /* M48-M53 */
    GC_MGROUP_USER = 10,       /* M100-M199 */
    GC_MGROUP_COUNT
} gc_mgroup;

/* The selected plane, valued as its G code's number (G17 G18 G19), which
 * is how messages name it. */
typedef enum gc_plane { GC_PLANE_XY = 17, GC_PLANE_XZ = 18, GC_PLANE_YZ = 19 } gc_plane;

/* Numbered parameters the interpreter itself reads or writes. */
#define GC_PARAM_G28_HOME 5161      /* #5161-#5163: G28 position, machine mm */
#define GC_PARAM_G30_HOME 5181      /* #5181-#5183: G30 position, machine mm */
#define GC_PARAM_G92_ENABLED 5210
#define GC_PARAM_G92 5211           /* #5211-#5213 */
#define GC_PARAM_COORD_SYSTEM 5220  /* 1..9: G54..G59.3 */
#define GC_PARAM_G5X_TABLE 5221     /* #5221-#5223 G54, then every 20 */

#define GC_NUM_PARAMS 5603   /* #1 .. #5602 */
#define GC_SUB_PARAMS 30     /* #1 .. #30 are local to a call */
#define GC_MAX_EXPR_DEPTH 64 /* nested brackets and parameter indirections */
#define GC_MAX_NAME 128

/* A string -> double table (named parameters). Open addressing. */
typedef struct gc_table {
    char **keys;
    double *vals;
    size_t cap, count;
} gc_table;

/* A repeat loop in progress: its label and the iterations left. */
typedef struct gc_repeat {
    char label[GC_MAX_NAME];
    size_t line; /* the repeat line */
    long left;
} gc_repeat;

/* One O-word call in progress. */
typedef struct gc_frame {
    size_t return_line;            /* line index to continue at after return */
    double saved[GC_SUB_PARAMS];   /* the caller's #1..#30 */
    gc_table locals;               /* #<name> local to this call */
    gc_repeat *repeats;
    int nrepeats, caprepeats;
    char sub[GC_MAX_NAME];
} gc_frame;

/* A line after LinuxCNC's normalization: lower case, no spaces or tabs,
 * comments removed. col[i] is the 1-based source column of s[i]; col[n] is
 * the column just past the last character. */
typedef struct gc_line {
    char *s;
    int *col;
    size_t n, cap;
} gc_line;

typedef struct gc_interp {
    /* program */
    const char *text;
    size_t len;
    const char *name;
    size_t *line_start; /* line i is text[line_start[i] .. line_start[i+1]) */
    size_t nlines;
    size_t cur;         /* current line index */
    int lineno;         /* 1-based, for errors */
    gc_line ln;         /* the current normalized line */
    gc_line scan;       /* scratch for O-word scans */

    fm_gcode_options opt;
    fm_error *err;

    /* parameters */
    double params[GC_NUM_PARAMS];
    gc_table globals;
    gc_table subs;      /* "o<name>" -> line index of its sub definition */
    gc_frame *frames;   /* frames[0] is the main program */
    int depth;          /* index of the active frame */
    long iterations;
    int expr_depth;

    /* modal state; lengths in program units, as LinuxCNC keeps them, so that
     * comparisons in cycles and arcs round exactly as rs274 does */
    double pos[3];      /* current point, program units and coordinates (rs274 prints these) */
    double g5x[3], g92[3], tlo[3];
    int cs;             /* 1..9: G54..G59.3 */
    double unit;        /* mm per program unit: 1 or 25.4 */
    gc_plane plane;
    int absolute, arc_absolute;
    int inverse_time;
    double feed;        /* G94: program units/min; G93: 1/min */
    double speed;
    int spindle_dir, coolant;
    int tool, selected_tool;
    gc_gcode motion;    /* the active motion mode; GC_G80 = none */
    int retract_r;      /* G99 */
    double cycle_r, cycle_cc, cycle_p, cycle_q, cycle_i, cycle_j, cycle_k, cycle_il;
    int cycle_il_flag;
    int percent_mode;

    /* output */
    fm_motion_sink sink;
    void *user;
    double t;
    long motion_index;
    long lines_run;
    int stop;           /* sink asked to stop, or the program ended */
    int ended;
    int cur_line_for_motion;
    long cur_block;
} gc_interp;

/* ---- a block: the words of one line (gcode_block.c) ---- */

#define GC_MAX_ASSIGN 256  /* parameter assignments on one line */

typedef struct gc_assign {
    int num;
    char name[GC_MAX_NAME];
    double v;
} gc_assign;

typedef struct gc_block {
    int has[26];
    double v[26];
    int col[26];
    /* the G code of each modal group on the line, if ghas[group] */
    int gcode[GC_GROUP_COUNT], gcol[GC_GROUP_COUNT];
    unsigned char ghas[GC_GROUP_COUNT];
    int m[8], mcol[8], nm;
    long n;
    gc_assign assign[GC_MAX_ASSIGN];
    int nassign;
} gc_block;

#define L(c) ((c) - 'a')
#define HAS(b, c) ((b)->has[L(c)])
#define VAL(b, c) ((b)->v[L(c)])
#define COL(b, c) ((b)->col[L(c)])

/* Errors at a column of the current line. */
fm_status gc_fail(gc_interp *g, fm_status code, int column, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
int gc_col(const gc_line *ln, size_t p);

/* Normalize source line idx into *out (gcode_block.c). */
fm_status gc_normalize(gc_interp *g, size_t idx, gc_line *out, int report);

/* ---- reading blocks (gcode_block.c) ---- */

/* Read the words of the current line from s[p] into *b (zeroed by the caller). */
fm_status gc_parse_block(gc_interp *g, size_t p, gc_block *b);
gc_group gc_g_group(int code);
void gc_g_name(int code, char *buf, size_t n);
/* The block's G code of `group` (GC_G_NONE if none) and its column. */
static inline int gc_block_g(const gc_block *b, gc_group group, int *col)
{
    if (!b->ghas[group]) return GC_G_NONE;
    if (col) *col = b->gcol[group];
    return b->gcode[group];
}
int gc_block_has_m(const gc_block *b, int m, int *col);
int gc_block_has_axis(const gc_block *b);
int gc_first_axis_col(const gc_block *b);

/* ---- executing a block (gcode_modal.c) ---- */

fm_status gc_exec_block(gc_interp *g, gc_block *b);
/* Word c as a whole number, or an error at its column. */
fm_status gc_int_word(gc_interp *g, const gc_block *b, char c, int *out);
/* Tool number `tool` of word `word` (T, H, Q) is >= 0 and in the table. */
fm_status gc_check_tool(gc_interp *g, int tool, int col, const char *word);

/* ---- motions (gcode_motion.c) ---- */

fm_status gc_check_feed(gc_interp *g, const char *what, int col);
fm_status gc_move_line(gc_interp *g, int rapid, const double to[3]);
fm_status gc_dwell(gc_interp *g, double seconds);
/* The end point of a G0/G1/G2/G3 block in program coordinates; machine
 * coordinates with G53. */
void gc_find_ends(gc_interp *g, const gc_block *b, int g53, double end[3]);
fm_status gc_exec_arc(gc_interp *g, const gc_block *b, int code, int col);
fm_status gc_exec_cycle(gc_interp *g, const gc_block *b, int code, int col);

/* ---- offsets and coordinate systems (gcode_offsets.c) ---- */

double gc_tool_length_mm(gc_interp *g, int tool);
void gc_set_g5x(gc_interp *g, int cs);
void gc_set_tlo(gc_interp *g, const double nv[3]);
fm_status gc_exec_g10(gc_interp *g, const gc_block *b, int col);
fm_status gc_exec_g92(gc_interp *g, const gc_block *b, int code, int col);
fm_status gc_exec_home(gc_interp *g, const gc_block *b, int code);
void gc_store_home(gc_interp *g, int code);
fm_status gc_exec_tool_length(gc_interp *g, const gc_block *b, int code, int col);

/* ---- O-words (gcode_oword.c) ---- */

/* Run the O-word line whose 'o' is at g->ln.s[p]; *next is the line to run next. */
fm_status gc_run_oword(gc_interp *g, size_t p, size_t *next);
void gc_frame_free(gc_frame *f);

/* Expressions: read a real value at s[*p] (number, [expr], #param, function). */
fm_status gc_read_real(gc_interp *g, const gc_line *ln, size_t *p, double *out);
/* Read the target of an assignment after '#': numbered (sets *num) or named (fills name). */
fm_status gc_read_param_ref(gc_interp *g, const gc_line *ln, size_t *p, int *num, char *name);
fm_status gc_set_named(gc_interp *g, const char *name, double v);
int gc_get_named(gc_interp *g, const char *name, double *v);

/* Tables. */
int gc_table_get(const gc_table *t, const char *key, double *v);
int gc_table_set(gc_table *t, const char *key, double v);
void gc_table_free(gc_table *t);

#endif
