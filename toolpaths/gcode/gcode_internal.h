/* gcode_internal.h: the interpreter's state shared by gcode.c (blocks,
 * motions, control flow) and gcode_expr.c (line normalization, numbers,
 * expressions and parameters). Private to toolpaths/gcode. */
#ifndef FM_GCODE_INTERNAL_H
#define FM_GCODE_INTERNAL_H

#include "gcode.h"

#include <stddef.h>

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
    int plane;          /* 17, 18, 19 */
    int absolute, arc_absolute;
    int inverse_time;
    double feed;        /* G94: program units/min; G93: 1/min */
    double speed;
    int spindle_dir, coolant;
    int tool, selected_tool;
    int motion;         /* G code x10 of the active motion mode; 800 = none */
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

/* Errors at a column of the current line. */
fm_status gc_fail(gc_interp *g, fm_status code, int column, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
int gc_col(const gc_line *ln, size_t p);

/* Normalize source line idx into *out. */
fm_status gc_normalize(gc_interp *g, size_t idx, gc_line *out, int report);

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
