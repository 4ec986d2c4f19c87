/* fanuc.h: the Fanuc/Haas front end's state and the functions its files
 * share; private to toolpaths/gcode/fanuc, which includes only the machine's
 * header (machine/machine.h) and nothing of the other dialects. It reads
 * blocks with Fanuc's decimal point rule, evaluates Macro B, runs Fanuc's
 * control flow and tells the machine what each code means in Fanuc's table:
 *   program.c  programs (%, O numbers, files on the search path), the line
 *              loop, IF/GOTO/WHILE/DO/END, M98/M97/G65 calls, M99
 *   expr.c     Macro B: its expression table (machine/expr.c evaluates),
 *              variables (#0 vacant, locals per call level, commons, system)
 *   block.c    words of a block, Fanuc's G-code groups, the decimal point
 *              and rounding rules of addresses
 *   exec.c     executing a block: modal state, offsets, G68/G51/G16, lines,
 *              arcs, dwells, G28/G30/G53, canned cycles' words
 *   haas.c     what Haas adds and CAM posts write: G154 P1-P99 work offsets
 *              (#14001..), G12/G13 circular pockets, G95 feed per revolution,
 *              G50.1/G51.1 mirror image, G66/G67 modal macro calls */
#ifndef FM_GCODE_FANUC_H
#define FM_GCODE_FANUC_H

#include "toolpaths/gcode/machine/machine.h"

#define GC_FANUC_LEVELS 5      /* local variable levels: main program 0, G65 calls 1-4 */
#define GC_FANUC_MACRO_DEPTH 4 /* G65 calls nested (Fanuc's limit) */
#define GC_FANUC_SUB_DEPTH 4   /* M98/M97 subprogram calls nested (Fanuc's limit) */
#define GC_FANUC_FRAMES (GC_FANUC_MACRO_DEPTH + GC_FANUC_SUB_DEPTH)
#define GC_FANUC_LOCALS 34     /* #1 .. #33 */
#define GC_FANUC_COMMON_LO 100 /* #100 .. #999 */
#define GC_FANUC_COMMON_HI 999
#define GC_FANUC_G54_1_OFFSETS 48 /* G54.1 P1 .. P48 (Fanuc's 48 sets; #7001-#7960) */

/* A vacant (null) variable is stored as NaN: no computed value is NaN, since
 * every operation's result is checked to be finite. */
#define GC_VACANT NAN

typedef enum gc_call_kind { GC_CALL_M98, GC_CALL_M97, GC_CALL_G65 } gc_call_kind;

/* A subprogram or macro call in progress. */
typedef struct gc_fanuc_frame {
    gc_call_kind kind;
    int caller_program;  /* index into programs */
    size_t return_line;  /* the line after the call, in the caller's text */
    int program;         /* the called program */
    size_t start_line;   /* first line of the body, for repeats */
    long repeats_left;
    int col;             /* column of the call, for messages */
} gc_fanuc_frame;

typedef struct gc_fanuc {
    int cur_program;     /* the program running now (g->progs) */
    int jumped;          /* the line just run set g->cur (jump, call, return) */

    gc_fanuc_frame frames[GC_FANUC_FRAMES];
    int nframes;
    int sub_depth;       /* M98/M97 calls in progress */
    int level;           /* local variable level: G65 calls in progress */

    /* variables (GC_VACANT when vacant) */
    double locals[GC_FANUC_LEVELS][GC_FANUC_LOCALS];
    double common[GC_FANUC_COMMON_HI + 1 - GC_FANUC_COMMON_LO];
    double timer_base_ms, timer_base_h;          /* #3001, #3002 set by the program */
    double sys3003, sys3004, parts[2];           /* #3003 #3004 #3901 #3902 */

    /* modal state Fanuc has beyond LinuxCNC's */
    int group1;          /* 0 1 2 3: G00-G03, the motion after G80 */
    int tool_length_mode; /* GC_G43, GC_G44 or GC_G49 */
    int h;               /* the offset number in use (modal H) */
    int d;               /* modal D (read only by #4107) */
    int last_m;          /* #4113 */
    long sequence;       /* #4114 */
    int ext_g154;        /* it was selected with G154 (#4014 reads 154) */
    double block_end[3]; /* #5001-#5003: where the previous block ended */

    /* Haas and the codes CAM posts write (haas.c) */
    int css;             /* G96 constant surface speed (S is not rpm: G95 is refused) */
    /* G66 modal calls, one per level of locals (the level of the G66
     * block): a move at that level calls it, so a G66 given in the called
     * macro nests (its moves call the inner macro); the macro's return ends
     * the G66 it gave */
    struct gc_fanuc_modal_call {
        int on;
        long program, repeats;
        int col;
        double args[GC_FANUC_LOCALS];
    } modal[GC_FANUC_LEVELS];

    /* the current block */
    int in_address;      /* evaluating an address: ROUND rounds to its increment */
    double address_increment;
    const char *alarm_text; /* #3000's message, found in the raw line */
} gc_fanuc;

#define FANUC(g) ((gc_fanuc *)(g)->dialect)

/* ---- program.c ---- */
extern const gc_front_end gc_fanuc_front;
/* Subprogram and macro calls from a block (M98, M97, G65) and M99. */
fm_status gc_fanuc_call(gc_interp *g, gc_call_kind kind, long number, long repeats,
                        const double args[GC_FANUC_LOCALS], int col);
fm_status gc_fanuc_return(gc_interp *g, int has_p, long p, int col);
/* The raw text of the current line (comments kept), for #3000's message. */
void gc_fanuc_raw_line(const gc_interp *g, const char **text, size_t *len);

/* ---- expr.c ---- */

/* How an address's number was written: the decimal point rule and the
 * dwell units depend on it. */
typedef enum gc_number_form {
    GC_FORM_EXPRESSION = 0, /* a variable or [expression]: a value with its decimals */
    GC_FORM_INTEGER = 1,    /* digits without a decimal point: the least input increment */
    GC_FORM_DECIMAL = 2     /* a number with a decimal point */
} gc_number_form;

/* A value read where an address or an argument expects one. */
typedef struct gc_fanuc_value {
    double v;
    int vacant;          /* a lone vacant variable: the address is ignored */
    gc_number_form form;
} gc_fanuc_value;

fm_status gc_fanuc_read_value(gc_interp *g, const gc_line *ln, size_t *p, gc_fanuc_value *out);
/* A whole expression (assignment right-hand sides, conditions). */
fm_status gc_fanuc_read_expr(gc_interp *g, const gc_line *ln, size_t *p, double *out);
/* '#' at s[*p]: the variable number. */
fm_status gc_fanuc_read_var_ref(gc_interp *g, const gc_line *ln, size_t *p, long *num);
fm_status gc_fanuc_get_var(gc_interp *g, long num, int col, double *out);
fm_status gc_fanuc_set_var(gc_interp *g, long num, double v, int col);
/* Fanuc's rounding: half away from zero. */
double gc_fanuc_round(double v);

/* ---- block.c ---- */

typedef struct gc_fanuc_block {
    unsigned char form[26];  /* gc_number_form of each word */
    int g65;             /* G65 or G66 on the line: every word after it is an argument */
    int g66;             /* it was G66 */
    int g65_col;
    double args[GC_FANUC_LOCALS]; /* G65 arguments (argument specification I) */
    gc_block b;          /* last: only its head up to the assignments is cleared per line */
} gc_fanuc_block;

fm_status gc_fanuc_parse_block(gc_interp *g, size_t p, gc_fanuc_block *fb);
gc_group gc_fanuc_g_group(int code);

/* ---- exec.c ---- */
fm_status gc_fanuc_exec_block(gc_interp *g, gc_fanuc_block *fb);
/* Word c as a length in program units (the decimal point rule, rounded to
 * the least input increment), or as an angle in degrees. */
double gc_fanuc_length(const gc_interp *g, const gc_fanuc_block *fb, char c);
double gc_fanuc_angle(const gc_interp *g, const gc_fanuc_block *fb, char c);
/* P or X of a dwell: seconds. */
double gc_fanuc_dwell_seconds(const gc_interp *g, const gc_fanuc_block *fb, char c);
/* The block's end point in the program frame (G90/G91, G16: the machine's
 * gc_frame_target) from its words. */
void gc_fanuc_target(gc_interp *g, const gc_fanuc_block *fb, double prog_end[3]);
/* The block's X Y Z A B C as values (gc_fanuc_length, gc_fanuc_angle). */
void gc_fanuc_axis_words(const gc_interp *g, const gc_fanuc_block *fb, gc_axis_words *w);

/* ---- comp.c ---- */
/* G40/G41/G42 and D of a block (code GC_G_NONE: only D). */
fm_status gc_fanuc_comp_mode(gc_interp *g, const gc_fanuc_block *fb, int code, int col);
/* What a control refuses while compensating; motion is the block's motion mode. */
fm_status gc_fanuc_comp_check(gc_interp *g, const gc_fanuc_block *fb, int motion);

/* ---- fanuc/haas.c ---- */

/* #7001-#7960 (G54.1 P1-P48) and #14001-#15966 (G154 P1-P99): 1 if n is
 * one of them; *slot is its value, or NULL for an axis past Z (read 0,
 * written nowhere). */
int gc_fanuc_ext_offset_var(gc_interp *g, long n, double **slot);
/* G54.1 P1-P48 or G154 P1-P99 of the block: the machine's extended
 * offset (gc_work_offset_select). */
fm_status gc_fanuc_select_ext_offset(gc_interp *g, const gc_block *b, int code, int col);
/* G12/G13 circular pocket (Haas). */
fm_status gc_fanuc_circular_pocket(gc_interp *g, const gc_fanuc_block *fb, int code, int col);
/* G93/G94/G95 and G96/G97 of the block (G95 with G96 is refused). */
fm_status gc_fanuc_feed_mode(gc_interp *g, const gc_block *b);
/* G50.1/G51.1 of the block. */
fm_status gc_fanuc_mirror(gc_interp *g, const gc_fanuc_block *fb, int code, int col);
/* G66 (store the call at this level) and G67 of the block (cancel this
 * level's, or else the most recent). */
fm_status gc_fanuc_modal_call_set(gc_interp *g, const gc_fanuc_block *fb, int code, int col);
/* After a block that moved: the G66 call, if one is on at this level. */
fm_status gc_fanuc_modal_call_run(gc_interp *g);
/* 1 if a G66 is on at this level or below (#4012). */
int gc_fanuc_modal_call_on(const gc_fanuc *f);

#endif
