/* gcode.h: the G-code front end. It interprets a program in LinuxCNC's
 * RS274NGC dialect (the default; semantics follow LinuxCNC's interpreter,
 * rs274) or in the Fanuc/Haas dialect (Fanuc's documented semantics) and
 * streams the resulting motions (lib/sweep/motion.h) to a callback, one at a
 * time, so that a program of any length never has its motions in memory at
 * once. See docs/gcode.md for what each dialect supports, what it refuses
 * and how the machine coordinates and tool tip offsets in each motion are
 * defined. */
#ifndef FM_GCODE_H
#define FM_GCODE_H

#include <stddef.h>

#include "core/core.h"
#include "sweep/motion.h"
#include "tools/tools.h"

/* The family of G-code a program is written in. */
typedef enum fm_gcode_dialect {
    FM_GCODE_LINUXCNC = 0, /* RS274NGC as LinuxCNC 2.9 reads it */
    FM_GCODE_FANUC = 1     /* Fanuc / Haas: O numbers, M98/M97/M99, Macro B, Fanuc cycles */
} fm_gcode_dialect;

typedef struct fm_gcode_options {
    double rapid_rate;          /* mm/min for G0 and canned-cycle rapids (default 5000) */
    int start_inch;             /* 1: the program starts in G20 (default 0: G21, mm) */
    const fm_tool_table *tools; /* NULL: any T is accepted and every length offset is 0 */
    size_t max_program_bytes;   /* refuse larger programs (default 256 MiB) */
    long max_iterations;        /* loop iterations + subroutine calls (default 10^7) */
    int max_call_depth;         /* nested O-word calls (default 64) */
    long skip_motions;          /* interpret everything, but do not emit motions with
                                   index < skip_motions (resume after a restart) */
    int block_delete;           /* 1: skip lines starting with '/' (default 0, as rs274) */
    /* Folders holding subprogram files, ':'-separated (NULL or "": none).
     * LinuxCNC: `o<name> call` loads <name>.ngc, as LinuxCNC's
     * SUBROUTINE_PATH. Fanuc: M98 P1234 / G65 P1234 load O1234.nc, .ngc or
     * .tap from the program's own folder first, then these. */
    const char *subroutine_path;
    /* (debug, ...) comments, with LinuxCNC's parameter substitution, and
     * (msg, ...) comments, in program order (NULL: dropped). */
    void (*message)(void *user, int line, const char *text);
    void *message_user;
    /* Every comment of each line the interpreter reads, as written (the
     * text between '(' and ')', or after ';'), with its line number, in
     * program order and in both dialects: CAM posts list the tools there,
     * "T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL". A line read again (a
     * loop, a repeated call) hands its comments over again. The text is not
     * NUL-terminated and is valid during the call only. NULL: dropped. */
    void (*comment)(void *user, int line, const char *text, size_t len);
    void *comment_user;
    /* G38.2-G38.5: where the probe trips along `move` (a feed line, machine
     * mm; the tool tip is move->start/end + tip_offset). toward_contact: 1
     * stops at the first contact (G38.2/G38.3), 0 at the first loss of it
     * (G38.4/G38.5). Set *tripped and *fraction (0..1 along the move) when
     * it trips, *at_start when the probe is already in that state at the
     * start. Called before the move is emitted; NULL: the probe trips at the
     * end of every probe move (no stock to touch, as `frepmill motions`). */
    fm_status (*probe)(void *user, const fm_motion *move, int toward_contact, int *tripped,
                       double *fraction, int *at_start, fm_error *err);
    void *probe_user;
    fm_gcode_dialect dialect;   /* default FM_GCODE_LINUXCNC */
    /* Fanuc G28 / G30 P2-P4: the 1st to 4th reference points, machine mm
     * (default: all at the machine origin). */
    double reference_points[4][3];
    /* Fanuc machine parameters (mm): G73's retract after each peck
     * (parameter 5114) and G83's clearance above the last depth (5115);
     * default 1 mm each. */
    double peck_retract;
    double peck_clearance;
    /* Fanuc: 1 reads a number without a decimal point as whole units (X5 =
     * 5 mm: Fanuc's DPI parameter, Haas setting 162); default 0 reads it in
     * the least input increment (X5 = 0.005 mm, 0.0005 in), as Fanuc and Haas
     * do out of the box. */
    int calculator_input;
    /* The machine's rotary axes (docs/check.md "Machine file"): A B C words
     * turn them and motions carry their joint values. NULL: the words are
     * followed (as rs274 prints them) but move nothing. Must outlive the run. */
    const fm_machine *machine;
    /* The machine's state before the first block (docs/check.md "Machine
     * file"). has_start 1: the tool tip stands at start (machine mm): the
     * machine's position is start less the tip offset of the tool in the
     * spindle (no length offset is active yet: its length above the tip);
     * 0: the dialect's power-on place (LinuxCNC the origin, Fanuc the first
     * reference point). initial_tool: the tool in the spindle before the
     * first M6 (0: none), as if M6 had loaded it (T only selects, M6 loads:
     * a program with T1 and no M6 runs with this tool); it must be in the
     * tool table when there is one. */
    int has_start;
    double start[3];
    int initial_tool;
} fm_gcode_options;

/* Fill *opt with the defaults above. */
void fm_gcode_options_default(fm_gcode_options *opt);

/* "linuxcnc" or "fanuc" (any case) -> *out; 0 if the name is neither. */
int fm_gcode_dialect_parse(const char *name, fm_gcode_dialect *out);
const char *fm_gcode_dialect_name(fm_gcode_dialect dialect);

/* What a run did, for callers that want totals (may be NULL). */
typedef struct fm_gcode_summary {
    long motions;      /* motions produced, including skipped ones */
    long lines;        /* source lines interpreted (a line in a loop counts each time) */
    double seconds;    /* program time at the end */
    int ended_by_m2;   /* 1 if M2/M30 or a closing % ended the program */
    int stopped;       /* 1 if the sink asked to stop */
} fm_gcode_summary;

/* Interpret the program in `path` (read whole, bounded by max_program_bytes)
 * and call sink for each motion in order. A sink that returns non-zero stops
 * the run early (FM_OK). On error, err says file:line:column, the offending
 * word and what was expected; motions already emitted stay valid. opt may be
 * NULL for defaults. */
fm_status fm_gcode_run_file(const char *path, const fm_gcode_options *opt, fm_motion_sink sink,
                            void *user, fm_gcode_summary *summary, fm_error *err);

/* Same for a program held by the caller; `name` is used in error messages. */
fm_status fm_gcode_run_string(const char *text, size_t len, const char *name,
                              const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                              fm_gcode_summary *summary, fm_error *err);

#endif
