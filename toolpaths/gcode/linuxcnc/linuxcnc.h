/* linuxcnc.h: the LinuxCNC (RS274NGC 2.9) front end's state and the
 * functions its files share; private to toolpaths/gcode/linuxcnc, which
 * includes nothing of the other dialects. Its files:
 *   run.c     the front end: start-up state, the line loop (%, /, N, O-word or block)
 *   block.c   the words of a block, G codes checked against LinuxCNC's modal groups
 *   expr.c    its expression table (machine/expr.c evaluates), numbered and named parameters
 *   modal.c   executing a block in LinuxCNC's order: modal state, M codes
 *   oword.c   O-word control flow: subroutines, conditions, loops
 *   state.c   M70-M73 saved modal state, (debug,...) and (msg,...) messages */
#ifndef FM_GCODE_LINUXCNC_H
#define FM_GCODE_LINUXCNC_H

#include "toolpaths/gcode/machine/machine.h"

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

/* The modal state M70/M73 save and M72 restores (LinuxCNC's list: units,
 * plane, distance modes, feed mode, coordinate system, tool length offset,
 * retract mode, F, S, spindle, coolant). */
typedef struct gc_modal_state {
    double unit;
    int plane, absolute, arc_absolute, inverse_time, cs, retract_r;
    double tlo[3];
    double feed, speed;
    int spindle_dir, coolant;
} gc_modal_state;

/* One O-word call in progress. */
typedef struct gc_frame {
    size_t return_line;            /* line index to continue at after return */
    double saved[GC_SUB_PARAMS];   /* the caller's #1..#30 */
    gc_table locals;               /* #<name> local to this call */
    gc_repeat *repeats;
    int nrepeats, caprepeats;
    char sub[GC_MAX_NAME];
    gc_modal_state state;          /* saved by M70 or M73 at this call level */
    int state_valid, state_autorestore;
} gc_frame;

/* The front end's state (g->dialect). */
typedef struct gc_lcnc {
    gc_table globals;
    gc_table subs;      /* "o<name>" -> line index of its sub definition */
    gc_frame *frames;   /* frames[0] is the main program */
    int depth;          /* index of the active frame */
    int percent_mode;
    int assign_col;     /* column of the assignment being made, for its errors */
    double value;       /* #<_value> and #<_value_returned> (read-only) */
    int value_returned;
} gc_lcnc;

#define LC(g) ((gc_lcnc *)(g)->dialect)

/* The front end (run.c). */
extern const gc_front_end gc_linuxcnc_front;

/* ---- reading a block (block.c) ---- */

/* Read the words of the current line from s[p] into *b (zeroed by the caller). */
fm_status gc_parse_block(gc_interp *g, size_t p, gc_block *b);
gc_group gc_g_group(int code);

/* ---- executing a block (modal.c) ---- */

fm_status gc_exec_block(gc_interp *g, gc_block *b);

/* ---- O-words (oword.c) ---- */

/* Run the O-word line whose 'o' is at g->ln.s[p]; *next is the line to run next. */
fm_status gc_run_oword(gc_interp *g, size_t p, size_t *next);
void gc_frame_free(gc_frame *f);

/* ---- values (expr.c) ---- */

/* Read a real value at s[*p] (number, [expr], #param, function). */
fm_status gc_read_real(gc_interp *g, const gc_line *ln, size_t *p, double *out);
/* Read the target of an assignment after '#': numbered (sets *num) or named (fills name). */
fm_status gc_read_param_ref(gc_interp *g, const gc_line *ln, size_t *p, int *num, char *name);
fm_status gc_set_named(gc_interp *g, const char *name, double v);
int gc_get_named(gc_interp *g, const char *name, double *v);
/* The value of numbered parameter n as a program reads it. */
double gc_param_value(gc_interp *g, int n);
int gc_table_get(const gc_table *t, const char *key, double *v);
int gc_table_set(gc_table *t, const char *key, double v);
void gc_table_free(gc_table *t);

/* ---- M70-M73 and messages (state.c) ---- */

fm_status gc_exec_modal_state(gc_interp *g, int m, int col);
/* Leaving a call level: M73's automatic restore. */
fm_status gc_leave_level(gc_interp *g);
/* Hand the line's (debug,...) / (msg,...) text to the message callback. */
void gc_emit_message(gc_interp *g, const gc_line *ln);

#endif
