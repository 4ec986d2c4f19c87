/* machine.h: the one machine model every G-code dialect drives, and the
 * public header of toolpaths/gcode/machine for the dialects' front ends
 * (toolpaths/gcode/linuxcnc, toolpaths/gcode/fanuc). A front end reads a
 * program (lines, words, its expression language, its control flow, its
 * table of what each code means) and calls the machine, which keeps the
 * modal state, units, planes, work offsets and their tables, tool length,
 * cutter compensation, canned-cycle motions, arcs and helices, rotary axes
 * and TCP, probing and splines, and emits motions. Nothing here knows a
 * dialect: a front end keeps its own state in gc_interp.dialect. The files:
 *   machine.c   the state: creating and freeing it, units, tool numbers
 *   line.c      a normalized source line, errors at file:line:column, G names
 *   source.c    the program's lines and those of files loaded from the path
 *   motion.c    lines, arcs, dwells and canned cycles -> emitted motions
 *   offsets.c   coordinate systems (G5x, G10, G92, G53), G43, G28/G30
 *   comp.c      cutter radius compensation with LinuxCNC's geometry
 *   spline.c    G5/G5.1/G5.2 curves as exact parametric motions
 *   sync.c      G33/G33.1 spindle-synchronized moves, G38.x probing
 *   rotary.c    rotary axes A B C, TCP, the joint values of each motion
 *   expr.c      the one expression engine, driven by a dialect's table
 *   transform.c the ISO program frame: G16 polar, G51 scaling, G68 rotation,
 *               G51.1 mirror, and moves through it and compensation C
 *   cycles_iso.c the ISO canned cycles (G73 G74 G76 G81-G89, Fanuc's)
 *   pocket.c    G12/G13 circular pockets (Haas)
 * docs/gcode.md has the map of the front ends. */
#ifndef FM_GCODE_MACHINE_H
#define FM_GCODE_MACHINE_H

#include "toolpaths/gcode/gcode.h"

#include <stddef.h>

#define GC_INCH 25.4          /* mm per inch */

/* G codes as LinuxCNC keeps them: ten times the number, so that G28.1 is
 * 281 and one decimal fits an int. */
typedef enum gc_gcode {
    GC_G_NONE = -1,
    GC_G0 = 0, GC_G1 = 10, GC_G2 = 20, GC_G3 = 30, GC_G4 = 40,
    GC_G5 = 50, GC_G5_1 = 51, GC_G5_2 = 52, GC_G5_3 = 53, GC_G7 = 70, GC_G8 = 80, GC_G9 = 90,
    GC_G10 = 100, GC_G11 = 110, GC_G12 = 120, GC_G13 = 130, GC_G15 = 150, GC_G16 = 160,
    GC_G17 = 170, GC_G17_1 = 171, GC_G18 = 180, GC_G18_1 = 181, GC_G19 = 190, GC_G19_1 = 191,
    GC_G20 = 200, GC_G21 = 210, GC_G22 = 220, GC_G23 = 230, GC_G27 = 270, GC_G29 = 290,
    GC_G28 = 280, GC_G28_1 = 281, GC_G28_2 = 282, GC_G30 = 300, GC_G30_1 = 301, GC_G30_2 = 302,
    GC_G31 = 310, GC_G33 = 330, GC_G33_1 = 331, GC_G37 = 370,
    GC_G38_2 = 382, GC_G38_3 = 383, GC_G38_4 = 384, GC_G38_5 = 385,
    GC_G40 = 400, GC_G41 = 410, GC_G41_1 = 411, GC_G42 = 420, GC_G42_1 = 421,
    GC_G43 = 430, GC_G43_1 = 431, GC_G43_2 = 432, GC_G43_4 = 434, GC_G44 = 440, GC_G49 = 490,
    GC_G50 = 500, GC_G50_1 = 501, GC_G51 = 510, GC_G51_1 = 511, GC_G52 = 520, GC_G53 = 530,
    GC_G54 = 540, GC_G55 = 550, GC_G56 = 560, GC_G57 = 570, GC_G58 = 580, GC_G59 = 590,
    GC_G54_1 = 541, GC_G59_1 = 591, GC_G59_2 = 592, GC_G59_3 = 593,
    GC_G60 = 600, GC_G61 = 610, GC_G61_1 = 611, GC_G62 = 620, GC_G63 = 630, GC_G64 = 640,
    GC_G65 = 650, GC_G66 = 660, GC_G67 = 670, GC_G68 = 680, GC_G69 = 690,
    GC_G70 = 700, GC_G71 = 710, GC_G71_1 = 711, GC_G71_2 = 712, GC_G72 = 720, GC_G72_1 = 721,
    GC_G72_2 = 722,
    GC_G73 = 730, GC_G74 = 740, GC_G76 = 760,
    GC_G80 = 800, GC_G81 = 810, GC_G82 = 820, GC_G83 = 830, GC_G84 = 840, GC_G85 = 850,
    GC_G86 = 860, GC_G87 = 870, GC_G88 = 880, GC_G89 = 890,
    GC_G90 = 900, GC_G90_1 = 901, GC_G91 = 910, GC_G91_1 = 911,
    GC_G92 = 920, GC_G92_1 = 921, GC_G92_2 = 922, GC_G92_3 = 923,
    GC_G93 = 930, GC_G94 = 940, GC_G95 = 950, GC_G96 = 960, GC_G97 = 970,
    GC_G98 = 980, GC_G99 = 990, GC_G103 = 1030, GC_G154 = 1540, GC_G187 = 1870
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
    /* groups only the Fanuc dialect has (values past LinuxCNC's) */
    GC_GROUP_POLAR = 15,         /* G15 G16 */
    GC_GROUP_ROTATION = 16,      /* G68 G69 */
    GC_GROUP_SCALING = 17,       /* G50 G51 */
    GC_GROUP_MACRO_MODAL = 18,   /* G66 G67 */
    GC_GROUP_LOOKAHEAD = 19,     /* G05 G05.1 G08, Haas G103 G187: no effect on the path */
    GC_GROUP_CYCLE = 20,         /* G73 G74 G76 G80-G89 (Fanuc's group 09; LinuxCNC: motion) */
    GC_GROUP_MIRROR = 21,        /* G50.1 G51.1 (Fanuc's group 22) */
    GC_GROUP_COUNT = 22,
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
    GC_MGROUP_STATE = 11,      /* M70-M73 */
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

/* A subroutine file loaded by o<name> call (source.c); its lines
 * follow the program's and the files loaded before it. */
typedef struct gc_source {
    char *name;          /* path, for messages */
    char *text;
    size_t len;
    size_t *line_start;  /* nlines + 1 offsets into text */
    size_t nlines;
    size_t first;        /* index of its first line among all lines */
} gc_source;

#define GC_EXT_OFFSETS 99  /* extended work offsets: Haas G154 P1-P99, Fanuc G54.1 P1-P48 */

/* The ISO dialects' texts and numbered programs (source.c): the program's
 * text and the subprogram files loaded for O numbers it calls. */
#define GC_MAX_TEXTS 64

typedef struct gc_text {
    char *name;          /* for messages */
    const char *text;
    size_t len;
    size_t *line_start;  /* nlines + 1 offsets */
    size_t nlines;
    char *owned;         /* the text, when loaded here */
    /* the front end's jump cache: the line a loop statement jumps to, plus
     * one (0: not looked up yet); freed with the text */
    size_t *jump;
} gc_text;

/* A program of a text: from its O line (or the text's start) to the next O
 * line or '%'. */
typedef struct gc_program {
    long number;         /* -1: the text before any O number */
    int text;
    size_t first, end;   /* lines [first, end) */
    long *seq;           /* sorted (N number, line) pairs, built at the first jump */
    size_t nseq;
    int seq_built;
} gc_program;

typedef struct gc_programs {
    gc_text texts[GC_MAX_TEXTS];
    int ntexts;
    gc_program *programs;
    int nprograms, capprograms;
    int cur_text;        /* the text in use (gc_programs_use_text) */
    size_t loaded_bytes; /* all texts, against max_program_bytes */
} gc_programs;

/* Cutter radius compensation (comp.c). Queued motions wait until the
 * next programmed element fixes their end point. Coordinates are those of
 * the compensation plane: u, v in the plane (G18: u = Z, v = X), w along
 * its normal; program units. */
typedef enum gc_comp_side { GC_COMP_OFF = 0, GC_COMP_LEFT = 1, GC_COMP_RIGHT = 2 } gc_comp_side;
typedef enum gc_comp_kind { GC_COMP_RAPID, GC_COMP_LINE, GC_COMP_ARC, GC_COMP_DWELL } gc_comp_kind;

/* The state a queued motion was programmed with. */
typedef struct gc_comp_snap {
    int line;
    long block;
    double feed;         /* program units per minute (inverse time converted); 0 for rapids */
    double speed;
    int spindle_dir, coolant;
} gc_comp_snap;

typedef struct gc_comp_move {
    gc_comp_kind kind;
    double end[3];       /* u v w */
    double dir[2];       /* lines: the programmed direction (a reversed move would gouge) */
    double center[2];    /* arcs */
    int turn;            /* arcs: > 0 counter-clockwise, |turn| - 1 extra circles */
    double sweep;        /* arcs: the programmed sweep (an arc pulled further would gouge) */
    double seconds;      /* dwells */
    gc_comp_snap snap;
} gc_comp_move;

/* A programmed arc handed to compensation: end point, centre, turn. */
typedef struct gc_arc_data {
    double end[3];
    double center[2];
    int turn;
} gc_arc_data;

typedef struct gc_comp {
    gc_comp_side side;
    double radius;       /* > 0 when compensating */
    int orientation;     /* lathe tool orientation (G41.1/G42.1 L in G18); 0 or 9: none */
    int firstmove;       /* the next move is the entry move */
    int arc_not_allowed; /* the move after G40 must be straight */
    double prog[3];      /* the programmed point, u v w */
    double endpoint[2];  /* start of the queued motions, for the gouge tests */
    int endpoint_valid;
    gc_comp_move *q;
    size_t nq, capq;
} gc_comp;

/* A curve as rational Bezier segments (spline.c), machine mm. */
typedef struct gc_spline {
    int degree;
    size_t nseg, cap;
    double *cp;          /* nseg * (degree + 1) homogeneous points (w x, w y, w) */
    double t0, t1, z;    /* the motion's time interval and height */
    fm_path path;
} gc_spline;

/* A tool table entry changed by G10 L1/L10/L11 (lengths in mm). */
typedef struct gc_tool_edit {
    int tool;
    double length;       /* Z offset */
    double diameter;
} gc_tool_edit;

/* A line after LinuxCNC's normalization: lower case, no spaces or tabs,
 * comments removed. col[i] is the 1-based source column of s[i]; col[n] is
 * the column just past the last character. */
typedef struct gc_line {
    char *s;
    int *col;
    size_t n, cap;
    /* the last (debug,...) or (msg,...) comment of the line, as written:
     * msg_kind 1 debug, 2 msg, 0 none */
    const char *msg;
    size_t msg_len;
    int msg_kind;
} gc_line;

/* The program frame of the ISO dialects (transform.c): the programmed
 * point and the transforms from it to work coordinates, program units. */
typedef struct gc_program_frame {
    double prog[3];      /* the programmed point: before polar, scaling, rotation, mirror */
    int polar;           /* G16 */
    double polar_radius, polar_angle, polar_origin[2];
    int rotation;        /* G68 */
    double rot_center[2], rot_angle, rot_cos, rot_sin;
    gc_plane rot_plane;
    int scaling;         /* G51 */
    double scale_center[3], scale;
    int mirror[3];       /* G51.1: the axis is mirrored about mirror_center */
    double mirror_center[3];
} gc_program_frame;

/* A block's axis words as values: X Y Z in program units (in G16 the
 * plane's second axis is the angle in degrees), A B C in degrees. */
typedef struct gc_axis_words {
    int given[3];
    double value[3];
    int rgiven[3];
    double rvalue[3];
} gc_axis_words;

/* The hole data of the ISO canned cycles (cycles_iso.c): R and Z as
 * written until the first hole turns them into levels (G91: from the
 * initial level and from R), Q, P (seconds); program units. */
typedef struct gc_hole_data {
    int valid;           /* set by a cycle block, cleared by gc_cycle_iso_cancel */
    double z, r, q, p;
    int z_word, r_word, z_abs, r_abs; /* pending words and their mode */
    double level_r, level_z;
} gc_hole_data;

typedef struct gc_interp {
    /* program */
    const char *text;
    size_t len;
    const char *name;
    int program_is_file; /* name is the program's path (its folder holds subprograms) */
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
    long iterations;
    int expr_depth;

    /* modal state; lengths in program units, as LinuxCNC keeps them, so that
     * comparisons in cycles and arcs round exactly as rs274 does */
    double pos[3];      /* current point, program units and coordinates (rs274 prints these) */
    double g5x[3], g92[3], tlo[3];
    /* rotary axes A B C (rotary.c): program degrees now and at the end
     * of the pending move, their G5x and G92 offsets, TCP on */
    double rot[3], rot_next[3], rot_g5x[3], rot_g92[3];
    int tcp;
    int cs;             /* 1..9: G54..G59.3 */
    double unit;        /* mm per program unit: 1 or 25.4 */
    gc_plane plane;
    int absolute, arc_absolute;
    int inverse_time;
    int per_rev;        /* G95: F is program units per spindle revolution */
    double feed;        /* G94: program units/min; G93: 1/min; G95: units/rev */
    double speed;
    int spindle_dir, coolant;
    int tool, selected_tool;
    gc_gcode motion;    /* the active motion mode; GC_G80 = none */
    int retract_r;      /* G99 */
    /* path control (docs/plan.md "Path modes"): the mode and tolerances in
     * mm every motion carries; exact_stop_block makes this block's motions
     * stop (Fanuc G09) */
    fm_path_mode path_mode;
    double path_tolerance, naive_tolerance;
    int exact_stop_block;
    double cycle_r, cycle_cc, cycle_p, cycle_q, cycle_i, cycle_j, cycle_k, cycle_il;
    int cycle_il_flag;
    double rotation;    /* degrees: the active coordinate system's XY rotation (G10 L2 R) */
    gc_comp comp;
    /* compensation C (comp_c.c): the engine from the first G41/G42 on, the
     * plane and side it was started in */
    struct gc_compc *comp_c;
    gc_plane comp_c_plane;
    int comp_c_left;
    gc_tool_edit *tool_edits;
    int ntool_edits, captool_edits;
    double tool_param_z, tool_param_dia; /* #5403 and #5410 in mm (gc_refresh_tool_params) */

    /* splines: G5.2 control points (program units x, y, weight) until G5.3 */
    double *nurbs;
    size_t nnurbs, capnurbs;
    int nurbs_order;
    gc_spline spline;

    /* subroutine files loaded so far (lines after the program's) */
    gc_source *sources;
    int nsources, capsources;
    size_t nlines_all;
    const char *line_name; /* the file of the current line, for messages */
    /* the dialect's front end (gcode.c picks it) and its own state: O-word
     * frames and named parameters for LinuxCNC, programs, calls and Macro B
     * variables for Fanuc */
    const struct gc_front_end *front;
    void *dialect;

    /* output */
    double mpos[3];     /* machine mm where the last motion ended: the next one starts there */
    double canon[3];    /* the same, not moved by tool length offset changes: where rs274
                           takes the current point from after a tool change */
    fm_motion_sink sink;
    void *user;
    double t;
    long motion_index;
    long lines_run;
    int stop;           /* sink asked to stop, or the program ended */
    int ended;
    int cur_line_for_motion;
    long cur_block;

    /* the ISO program frame (transform.c), and the column of the block's
     * motion for compensation C's errors */
    gc_program_frame frame;
    int motion_col;
    gc_hole_data hole;   /* the ISO canned cycles' (cycles_iso.c) */
    gc_programs progs;   /* the ISO dialects' texts and O-number programs (source.c) */
    /* the ISO dialects' work offsets (offsets.c): the extended table (G54.1
     * P, G154 P; program units), the one in use (0: G54-G59 from params),
     * G52's local offset */
    double ext_offsets[GC_EXT_OFFSETS][3];
    int ext_cs;
    double local_offset[3];
} gc_interp;

/* A dialect's front end: gcode.c picks one by fm_gcode_options.dialect. init
 * makes its state (g->dialect) and sets the dialect's power-on modes on the
 * machine, run interprets the program line by line, release frees what init
 * made (also after a failed init). */
typedef struct gc_front_end {
    const char *name;
    fm_status (*init)(gc_interp *g);
    fm_status (*run)(gc_interp *g);
    void (*release)(gc_interp *g);
} gc_front_end;

/* ---- the machine's state (machine.c) ---- */

/* Set up *g for a program text (indexed into lines; bounded by
 * opt->max_program_bytes) with the machine's neutral state; the front end's
 * init then sets its dialect's power-on modes. */
fm_status gc_machine_init(gc_interp *g, const char *text, size_t len, const char *name,
                          const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                          fm_error *err);
/* After the front end's init: the options' state at the start (the tool in
 * the spindle, where the tool tip stands), over the dialect's power-on
 * state. */
fm_status gc_machine_start(gc_interp *g);
void gc_machine_free(gc_interp *g);

/* ---- a block: the words of one line (line.c) ---- */

#define GC_MAX_ASSIGN 256  /* parameter assignments on one line */

typedef struct gc_assign {
    int num;
    char name[GC_MAX_NAME];
    double v;
    int col;
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
    /* polar coordinates: @ radius, ^ angle in degrees (G17) */
    int has_radius, has_theta, radius_col, theta_col;
    double radius, theta;
    gc_assign assign[GC_MAX_ASSIGN];
    int nassign;
} gc_block;

#define L(c) ((c) - 'a')
#define HAS(b, c) ((b)->has[L(c)])
#define VAL(b, c) ((b)->v[L(c)])
#define COL(b, c) ((b)->col[L(c)])

/* ---- compensation (comp.c), splines (spline.c), sources (source.c) ---- */

void gc_comp_to_plane(gc_plane plane, const double xyz[3], double uvw[3]);
void gc_comp_from_plane(gc_plane plane, const double uvw[3], double xyz[3]);
int gc_comp_active(const gc_interp *g);
void gc_comp_free(gc_comp *c);
fm_status gc_comp_on(gc_interp *g, const gc_block *b, int code, int col);
fm_status gc_comp_off(gc_interp *g, int col);
/* Hand every queued motion to the sink (program end). */
fm_status gc_comp_finish(gc_interp *g);
/* Where unspecified and incremental axes of a block start from (LinuxCNC's
 * find_ends: the programmed point while compensating). */
void gc_comp_base(const gc_interp *g, double base[3]);
void gc_comp_scale(gc_interp *g, double f);
fm_status gc_comp_dwell(gc_interp *g, double seconds);
fm_status gc_comp_straight(gc_interp *g, int rapid, double feed, const double end_xyz[3], int col);
fm_status gc_comp_arc(gc_interp *g, const gc_arc_data *a, double feed, int col);
/* The feed a queued (compensated) block keeps, per minute: in G93 its
 * programmed length over its time, in G95 F x S (motion.c). */
double gc_queued_feed(const gc_interp *g, double programmed_len);
/* Emit a queued block's motion (a line, rapid, arc or dwell; xyz program
 * coordinates) with the state it was programmed with (motion.c). */
fm_status gc_emit_queued(gc_interp *g, const gc_comp_snap *snap, gc_comp_kind kind,
                         const double xyz[3], const double center_ab[2], int turn, double seconds);
/* Emit a queued motion (motion.c). */
fm_status gc_emit_comp_move(gc_interp *g, const gc_comp_move *m);

/* Cutter radius compensation with intersected corners, Fanuc's type C
 * (comp_c.c over comp_intersect.c): a dialect that uses it hands every line,
 * arc and dwell to gc_comp_c_line/arc/dwell while gc_comp_c_routing is true
 * (from G41/G42 until the cancel block after G40 has run). Coordinates as
 * gc_move_line's; radius in program units (negative: the other side, 0: no
 * offset). */
fm_status gc_comp_c_start(gc_interp *g, int left, double radius, int col);
fm_status gc_comp_c_radius(gc_interp *g, double radius, int col);
fm_status gc_comp_c_cancel(gc_interp *g);
int gc_comp_c_routing(const gc_interp *g);
int gc_comp_c_on(const gc_interp *g);
fm_status gc_comp_c_line(gc_interp *g, int rapid, const double to[3], int col);
fm_status gc_comp_c_arc(gc_interp *g, const double to[3], const double center_ab[2], int turn,
                        int col);
fm_status gc_comp_c_dwell(gc_interp *g, double seconds);
/* Program end: what waits leaves with the offset perpendicular to its end. */
fm_status gc_comp_c_finish(gc_interp *g);
void gc_comp_c_free(gc_interp *g);

void gc_spline_free(gc_spline *s);
fm_status gc_spline_build(gc_spline *s, const double *xyw, size_t npts, int order, fm_error *err);
void gc_spline_point(const gc_spline *s, double u, double p[2]);
void gc_spline_box(const gc_spline *s, double ua, double ub, double lo[2], double hi[2]);
double gc_spline_length(const gc_spline *s);
void gc_spline_path(gc_spline *s, double t0, double t1, double z);

/* Offsets of the lines of text into *line_start (*nlines + 1 of them; a
 * trailing newline ends the last line rather than starting an empty one). */
fm_status gc_index_lines(const char *text, size_t len, const char *name, size_t **line_start,
                         size_t *nlines, fm_error *err);
/* The text of line idx (any source) and its length. */
void gc_line_text(const gc_interp *g, size_t idx, const char **text, size_t *len);
/* Make line idx current for messages: g->lineno and g->line_name. */
void gc_set_line(gc_interp *g, size_t idx);
/* The line range [*lo, *hi) of the source holding line idx. */
void gc_source_range(const gc_interp *g, size_t idx, size_t *lo, size_t *hi);
/* Find <name>.ngc on the subroutine path and append it; *first is its first
 * line. 0 and no error when there is no such file. */
fm_status gc_load_subroutine_file(gc_interp *g, const char *name, int col, int *found,
                                  size_t *first);
void gc_sources_free(gc_interp *g);
/* The ISO dialects' numbered programs: index the program's text (text 0;
 * its first program starts at its first line), free them. */
fm_status gc_programs_init(gc_interp *g);
void gc_programs_free(gc_interp *g);
/* 1 if line idx of the current text is a tape's '%' line. */
int gc_programs_percent_line(const gc_interp *g, size_t idx);
/* Make text t the current one (g->text, g->line_start, the name). */
void gc_programs_use_text(gc_interp *g, int t);
/* Program O<number>: in the texts loaded so far, else from O<number>.nc
 * (.ngc, .tap; O%04ld, O%05ld, O%ld, either case) in the program's folder or
 * on the subroutine path; call names the caller in messages. */
fm_status gc_programs_locate(gc_interp *g, long number, const char *call, int col,
                             int *program);
/* The line of N<n> in program pi (the first if there are several); what
 * names the jump in messages. */
fm_status gc_programs_find_sequence(gc_interp *g, int pi, long n, const char *what, int col,
                                    size_t *line);

/* G5, G5.1, G5.2 (a control point) and G5.3 (spline.c); explicit: the
 * code is on the line (not only the modal motion). */
fm_status gc_exec_spline(gc_interp *g, const gc_block *b, int code, int explicit_code, int col);
/* G33, G33.1 and G38.2-G38.5 (sync.c). */
fm_status gc_exec_sync(gc_interp *g, const gc_block *b, int code, int col);
fm_status gc_exec_probe(gc_interp *g, const gc_block *b, int code, int col);

/* Hand a motion to the sink with the modal state's tool, spindle, time and
 * line (motion.c); seconds is its duration. */
fm_status gc_emit_motion(gc_interp *g, fm_motion *m, double seconds);
/* Duration of a feed move of len_mm at the modal feed; *feed_mm is mm/min. */
double gc_feed_seconds(gc_interp *g, double len_mm, double *feed_mm);
/* The plane's first and second axis and its normal, LinuxCNC's order. */
void gc_plane_axes(gc_plane plane, int *a, int *b, int *c);
/* The signed angle (radians, > 0 counter-clockwise in the plane) of an arc
 * from start to end about center_ab in the plane's axes, turn > 0
 * counter-clockwise with |turn| - 1 extra circles, the same start and end
 * angle a full circle: lib/sweep's fm_motion_arc_of, the one definition of
 * an arc. 0 for a degenerate arc (centre on the start point). */
double gc_arc_sweep(gc_plane plane, const double start[3], const double end[3],
                    const double center_ab[2], int turn);
/* Machine mm of program point p, and back (rotation, G5x, G92). */
void gc_to_machine(const gc_interp *g, const double p[3], double out[3]);
void gc_from_machine(const gc_interp *g, const double m[3], double p[3]);
/* #5403, #5410: the spindle tool's table values, refreshed at M6 and G10. */
void gc_refresh_tool_params(gc_interp *g);
/* The tool an offset register names (word 'h': H n and Fanuc's #2000 + n;
 * 'd': D n): the table's tool whose length_register or diameter_register is
 * n (a CAM library's numbering: Fusion's post-process length-offset and
 * diameter-offset), else tool n. */
int gc_register_tool(const gc_interp *g, char word, int n);
/* The radius G41/G42 compensate by for tool `tool`, mm: a G10 L1/L10/L11
 * edit's diameter / 2, else the table's radius_offset, else its diameter /
 * 2; plus the table's radius_wear. */
double gc_tool_comp_radius_mm(gc_interp *g, int tool);
/* Tool diameter and length in mm, after G10 L1/L10/L11 edits. */
double gc_tool_diameter_mm(gc_interp *g, int tool);
void gc_set_units(gc_interp *g, double unit);

/* Errors at a column of the current line. */
fm_status gc_fail(gc_interp *g, fm_status code, int column, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
int gc_col(const gc_line *ln, size_t p);

/* Normalize source line idx into *out (line.c). */
fm_status gc_normalize(gc_interp *g, size_t idx, gc_line *out, int report);

/* ---- reading blocks (line.c) ---- */

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

/* Word c as a whole number, or an error at its column. */
fm_status gc_int_word(gc_interp *g, const gc_block *b, char c, int *out);
/* Tool number `tool` of word `word` (T, H, Q) is >= 0 and in the table. */
fm_status gc_check_tool(gc_interp *g, int tool, int col, const char *word);

/* ---- motions (motion.c) ---- */

fm_status gc_check_feed(gc_interp *g, const char *what, int col);
fm_status gc_move_line(gc_interp *g, int rapid, const double to[3]);
/* An arc in the selected plane from the current point to `to` about
 * (center_ab[0], center_ab[1]) in the plane's axes; turns > 0 counter-clockwise. */
fm_status gc_move_arc(gc_interp *g, const double to[3], const double center_ab[2], int turns);
/* The plane's first and second axis and its normal (0 X, 1 Y, 2 Z; G18's first is Z). */
fm_status gc_dwell(gc_interp *g, double seconds);
/* The end point of a G0/G1/G2/G3 block in program coordinates; machine
 * coordinates with G53. */
fm_status gc_find_ends(gc_interp *g, const gc_block *b, int g53, double end[3]);
/* G0/G1 (through cutter compensation when it is on). */
fm_status gc_exec_straight(gc_interp *g, const gc_block *b, int rapid, int g53, int col);
fm_status gc_move_arc(gc_interp *g, const double to[3], const double center_ab[2], int turns);
fm_status gc_exec_arc(gc_interp *g, const gc_block *b, int code, int col);
/* An arc's R and I J K words as values (program units), with columns. */
typedef struct gc_arc_words {
    int has_r;
    double r;
    int r_col;
    int has[3];
    double v[3];
    int col[3];
} gc_arc_words;
void gc_arc_words_of(const gc_block *b, gc_arc_words *w);
/* The centre (cab, the plane's axes) of a G2/G3 (code) from start to end:
 * R wins over I J K; |R| must reach the end point. rs274 (iso 0): R with
 * the end on the start is refused, I J K are absolute in G90.1, neither end
 * may be the centre. ISO (iso 1, Fanuc's rule): R with the end on the start
 * is an arc of 0 degrees (*no_arc: the tool does not move in the plane),
 * I J K are always from the start point. */
fm_status gc_arc_center(gc_interp *g, int iso, int code, const gc_arc_words *w,
                        const double start[3], const double end[3], double cab[2], int *no_arc,
                        int col);
fm_status gc_exec_cycle(gc_interp *g, const gc_block *b, int code, int col);
/* The path control mode from here on (tolerances in mm, 0: none). */
void gc_set_path_mode(gc_interp *g, fm_path_mode mode, double tolerance_mm, double naive_mm);

/* ---- offsets and coordinate systems (offsets.c) ---- */

double gc_tool_length_mm(gc_interp *g, int tool);
void gc_set_g5x(gc_interp *g, int cs);
void gc_set_tlo(gc_interp *g, const double nv[3]);
fm_status gc_exec_g10(gc_interp *g, const gc_block *b, int col);
fm_status gc_exec_g92(gc_interp *g, const gc_block *b, int code, int col);
fm_status gc_exec_home(gc_interp *g, const gc_block *b, int code);
void gc_store_home(gc_interp *g, int code);
fm_status gc_exec_tool_length(gc_interp *g, const gc_block *b, int code, int col);
/* The ISO dialects' work offset: G54-G59 (#5221.. as cs 1-6) or extended
 * offset ext (1..GC_EXT_OFFSETS, 0: none), plus the external offset (#5201..)
 * and G52's local offset, into g->g5x; the current point keeps its machine
 * position, and a pending tool length move stays pending. */
void gc_work_offset_apply(gc_interp *g);
void gc_work_offset_select(gc_interp *g, int cs, int ext);
/* G52: the local offset of the axes given (program units). */
void gc_work_offset_local(gc_interp *g, const int given[3], const double value[3]);
/* G53: at rapid to the given axes' machine coordinates (program units). */
fm_status gc_move_machine(gc_interp *g, const int given[3], const double value[3]);
/* The ISO G28/G30: at rapid to the intermediate point mid (program frame),
 * then to reference point ref (0..3: fm_gcode_options.reference_points) of
 * the axes given; the others stay. */
fm_status gc_move_reference(gc_interp *g, int ref, const int given[3], const double mid[3]);

/* ---- the ISO program frame (transform.c) ----
 * Program frame -> work coordinates: scaling, rotation, then mirror (G51.1
 * reflects what the others make). */

void gc_frame_to_work(const gc_interp *g, const double prog[3], double work[3]);
void gc_frame_from_work(const gc_interp *g, const double work[3], double prog[3]);
/* The programmed point from the tool's (g->pos) after a change that does
 * not move the machine (offsets, G92, a transform, units). */
void gc_frame_reprogram(gc_interp *g);
/* 1 while G68, G51 or G51.1 is on. */
int gc_frame_transformed(const gc_interp *g);
/* -1 when an odd number of the plane's axes is mirrored (G02 <-> G03). */
int gc_frame_mirror_sense(const gc_interp *g);
/* A block's end point in the program frame from its axis words (G90/G91,
 * G16: the polar state follows the block); the rotary axes' targets too. */
void gc_frame_target(gc_interp *g, const gc_axis_words *w, double end[3]);
/* G16 (on: polar from the programmed point) and G15. */
void gc_frame_polar(gc_interp *g, int on);
/* G51 (k > 0: factor k about center) and G50 (k = 0). */
void gc_frame_scale(gc_interp *g, double k, const double center[3]);
/* G68 (on: degrees about center in the current plane) and G69. */
void gc_frame_rotate(gc_interp *g, int on, const double center[2], double degrees);
/* G51.1 (on) and G50.1 of the axes given. */
void gc_frame_mirror(gc_interp *g, const int axes[3], const double center[3], int on);
/* G20/G21: the frame's lengths times k (gc_set_units). */
void gc_frame_scale_units(gc_interp *g, double k);
/* Lines, arcs and dwells in work coordinates through compensation C while
 * it runs (gc_comp_c_routing), else straight to the motions. */
fm_status gc_frame_line_work(gc_interp *g, int rapid, const double work[3]);
fm_status gc_frame_arc_work(gc_interp *g, const double work[3], const double center_ab[2],
                            int turn);
fm_status gc_frame_dwell(gc_interp *g, double seconds);
/* To prog_end (program frame): the programmed point becomes it. */
fm_status gc_frame_move(gc_interp *g, int rapid, const double prog_end[3]);
/* An arc in the program frame (ccw before any mirror); compensate: through
 * compensation C while it runs. */
fm_status gc_frame_arc(gc_interp *g, const double prog_end[3], const double prog_center[3],
                       int ccw, int compensate);

/* ---- the ISO canned cycles (cycles_iso.c) ---- */

/* A cycle block's words as values: the hole position (the hole axis' word
 * is the bottom Z), R, Q (>= 0) in program units, P in seconds, the
 * repeat word (K or L; 0: none) as written. Columns for errors. */
typedef struct gc_hole_block {
    gc_axis_words at;
    int has_r, has_q, has_p;
    double r, q, p;
    char rep_letter;
    double rep_value;
    int r_col, q_col, rep_col;
} gc_hole_block;

/* G73 G74 G76 G81-G89 (code) with this block's words; a block without a
 * position, or with zero repeats, only stores the data. */
fm_status gc_cycle_iso(gc_interp *g, int code, const gc_hole_block *h, int col);
/* G80 and G00-G03: the hole data and the initial level are gone. */
void gc_cycle_iso_cancel(gc_interp *g);
/* G20/G21: the hole data's lengths times k. */
void gc_cycle_iso_scale_units(gc_interp *g, double k);

/* ---- circular pockets (pocket.c) ---- */

/* G12 (clockwise) / G13 (ccw) circular pocket: the centre's X Y (and the
 * depth Z if has_z) in the program frame; radii first to last in steps of
 * step (0: one circle at last), program units, checked by the front end
 * (first > tool_radius, last >= first); passes >= 1. */
typedef struct gc_pocket {
    int ccw;
    double target[3];
    int has_z;
    double first, last, step, tool_radius;
    long passes;
} gc_pocket;

fm_status gc_circular_pocket(gc_interp *g, const gc_pocket *p);

/* ---- rotary axes A, B, C (rotary.c) ---- */

void gc_rot_start(gc_interp *g);
/* rot_next from the block's A B C words (gc_find_ends calls it). */
fm_status gc_rot_find_ends(gc_interp *g, const gc_block *b, int g53);
/* The same from values already read (the Fanuc dialect's angles). */
void gc_rot_target(gc_interp *g, const int given[3], const double value[3]);
void gc_rot_hold(gc_interp *g);                 /* no rotary motion pending */
double gc_rot_degrees(const gc_interp *g);      /* the pending move's rotary length */
void gc_rot_emit(gc_interp *g, fm_motion *m);   /* joint values, machine, TCP; commits rot_next */
void gc_rot_set_g5x(gc_interp *g, int base);
void gc_rot_g10(gc_interp *g, const gc_block *b, int l, int base);
void gc_rot_g92(gc_interp *g, const gc_block *b, int code);
void gc_rot_home(gc_interp *g, const gc_block *b, int base);
void gc_rot_store_home(gc_interp *g, int base);
fm_status gc_rot_tcp(gc_interp *g, int on, int col);

/* ---- expressions (expr.c) ----
 * One engine reads every dialect's values: numbers, [brackets], binary
 * operators by precedence level (left to right within one), unary signs,
 * function calls, #references; errors at file:line:column; at most
 * GC_MAX_EXPR_DEPTH nested brackets, signs and indirections. The dialect's
 * table says what its operators and functions are and compute, and how '#'
 * is read. A vacant value (Fanuc's #0) is NaN. */

typedef enum gc_expr_opcode {
    GC_OP_POW, GC_OP_MUL, GC_OP_DIV, GC_OP_ADD, GC_OP_SUB,
    GC_OP_MOD,               /* the remainder with the dividend's sign (fmod) */
    GC_OP_MOD_NONNEG,        /* the remainder from 0 to |b| */
    GC_OP_EQ, GC_OP_NE,      /* within the table's eq_tolerance */
    GC_OP_GT, GC_OP_GE, GC_OP_LT, GC_OP_LE,
    GC_OP_AND, GC_OP_OR, GC_OP_XOR,             /* on truth values (non-zero is true) */
    GC_OP_BIT_AND, GC_OP_BIT_OR, GC_OP_BIT_XOR  /* on the integer parts as 32-bit numbers */
} gc_expr_opcode;

typedef struct gc_expr_op {
    const char *token;       /* as in the normalized (lower-case) line: "**", "mod" */
    int level;               /* precedence: 1 binds loosest */
    gc_expr_opcode code;
} gc_expr_op;

/* Functions; angles in degrees, results in the range named. */
typedef enum gc_expr_fncode {
    GC_FN_ABS, GC_FN_COS, GC_FN_EXP, GC_FN_LN, GC_FN_SIN, GC_FN_SQRT, GC_FN_TAN,
    GC_FN_ACOS,              /* 0..180 */
    GC_FN_ASIN,              /* -90..90 */
    GC_FN_ASIN_270_90,       /* negative angles + 360 */
    GC_FN_ATAN,              /* F[a] -90..90, F[y]/[x] -180..180 */
    GC_FN_ATAN_0_360,        /* 0 <= angle < 360, F[0]/[0] refused */
    GC_FN_BCD, GC_FN_BIN,    /* binary to BCD and back, 0..99999999 */
    GC_FN_FLOOR, GC_FN_CEIL, GC_FN_TRUNC, GC_FN_AWAY, /* down, up, toward and away from 0 */
    GC_FN_ROUND,             /* halves away from zero */
    GC_FN_OWN                /* the front end's own (gc_expr_func.own) */
} gc_expr_fncode;

#define GC_ARGS_ONE 1        /* argument forms: F[a] */
#define GC_ARGS_SLASH 2      /* F[y]/[x] */
#define GC_ARGS_COMMA 4      /* F[y,x] */

typedef struct gc_expr_func {
    const char *name;        /* upper case */
    gc_expr_fncode code;
    int args;                /* GC_ARGS_* */
    /* GC_FN_OWN: read the arguments at s[*p] ('[') and compute; col: the name's */
    fm_status (*own)(gc_interp *g, const gc_line *ln, size_t *p, int col, double *out);
} gc_expr_func;

typedef struct gc_expr_lang {
    const char *ref_name;    /* what '#' names, for messages: "parameter" */
    const gc_expr_op *ops;   /* tried in order: "**" before "*" */
    int nops;
    const gc_expr_func *funcs; /* in the order messages list them */
    int nfuncs;
    double eq_tolerance;     /* EQ: |a - b| < eq_tolerance; 0: a == b */
    /* NaN is vacant: alone, in brackets and under a sign it stays vacant;
     * operators and functions see 0, but EQ/NE: vacant equals only vacant */
    int vacancy;
    /* '#' at s[*p]: read the reference past it and its value */
    fm_status (*read_ref)(gc_interp *g, const gc_line *ln, size_t *p, double *out);
} gc_expr_lang;

/* One operand at s[*p] (a number, [expression], #reference or function
 * after unary signs), or a whole expression (operands and operators). */
fm_status gc_expr_operand(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                          double *out);
fm_status gc_expr_read(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                       double *out);
/* A number: a sign, digits with at most one '.' (*point: one; may be NULL). */
fm_status gc_expr_number(gc_interp *g, const gc_expr_lang *lang, const gc_line *ln, size_t *p,
                         double *out, int *point);

#endif
