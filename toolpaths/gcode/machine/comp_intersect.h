/* comp_intersect.h: Fanuc's "cutter compensation C" (G40/G41/G42 on Fanuc
 * 0i/16i/18i and Haas) as a streaming engine, independent of any dialect's
 * interpreter. Private to toolpaths/gcode; the rules and what is
 * approximated are at the top of comp_intersect.c.
 *
 * Coordinates are those of the compensation plane: u, v in the plane (in
 * the dialect's order, so that "left" is left when looking down the normal)
 * and w along the normal, in program units. Arcs are a centre and a turn:
 * turn > 0 counter-clockwise, |turn| - 1 extra full circles.
 *
 * Use: gc_compc_init with the current point, then every motion of the
 * program through gc_compc_add in order (also while compensation is off:
 * they pass through), gc_compc_start at G41/G42, gc_compc_cancel at G40,
 * gc_compc_finish at the program's end, gc_compc_free. The compensated
 * elements arrive in order at the emit callback. After an error the engine
 * can only be freed. */
#ifndef FM_GCODE_COMP_INTERSECT_H
#define FM_GCODE_COMP_INTERSECT_H

#include "core/core.h"

/* How many elements without motion in the plane (w-only moves, dwells, ...)
 * the engine reads past to find the next direction in the plane. Fanuc
 * reads 3 to 8 blocks ahead (parameter 19625 on the 0i-F); beyond the
 * limit, as Fanuc does, the previous element ends at the vector
 * perpendicular to its end, and the next element in the plane starts with
 * a straight move from there to its own offset start. */
#define GC_COMPC_LOOKAHEAD 8

typedef enum gc_compc_kind {
    GC_COMPC_LINE,  /* feed line */
    GC_COMPC_RAPID, /* traverse line (compensated like a feed line) */
    GC_COMPC_ARC,
    GC_COMPC_OTHER  /* no motion: dwell, spindle, ... (only the payload matters) */
} gc_compc_kind;

typedef enum gc_compc_side { GC_COMPC_LEFT = 1, GC_COMPC_RIGHT = -1 } gc_compc_side;

/* One element, in and out. In: kind, end (u, v, w), center and turn for an
 * arc, file/line/column (for errors; file is kept as a pointer and must
 * outlive the element's output), payload (payload_size bytes, copied;
 * NULL when payload_size is 0). A line whose end is its start in the plane
 * is a w-only move (not a plane element). start and corner are ignored.
 * Out: start and end (u, v, w) of the tool centre, center and turn for an
 * arc, the position and payload of the block the element belongs to (the
 * pointer is valid during the callback only), corner = 1 for an element the
 * engine inserted at a corner (a LINE, or a RAPID when its block is one). */
typedef struct gc_compc_elem {
    gc_compc_kind kind;
    double start[3];
    double end[3];
    double center[2];
    int turn;
    const char *file;
    int line;
    int column;
    const void *payload;
    int corner;
} gc_compc_elem;

/* Receives each compensated element in order; a non-FM_OK return (with err
 * filled) stops the engine and is returned by the call that emitted. */
typedef fm_status (*gc_compc_emit_fn)(void *ctx, const gc_compc_elem *e, fm_error *err);

/* Private: an element waiting in the engine. */
typedef struct gc_compc_item {
    gc_compc_elem e; /* as given, with start set to the programmed point */
    double radius;   /* the radius in force when it was given */
    double from[2];  /* plane element: where its compensated path starts */
} gc_compc_item;

/* The engine. Fields are private. */
typedef struct gc_compc {
    gc_compc_emit_fn emit;
    void *ctx;
    size_t payload_size;
    unsigned char *payloads; /* GC_COMPC_LOOKAHEAD + 2 slots */
    int state;               /* off, armed (G41/G42 given), on, cancelling */
    int side;
    double radius;
    double prog[3];          /* the programmed current point */
    double tool[3];          /* where the last emitted element ended */
    int have_prev;           /* prev's end waits for the next plane element */
    int prev_startup;        /* prev is the start-up block */
    gc_compc_item prev;
    gc_compc_item queue[GC_COMPC_LOOKAHEAD]; /* non-plane elements after prev */
    int nq;
} gc_compc;

/* Set up with the current (uncompensated) point; compensation is off.
 * Allocates the payload slots (FM_ERR_LIMIT when that fails). */
fm_status gc_compc_init(gc_compc *c, size_t payload_size, gc_compc_emit_fn emit, void *ctx,
                        const double current[3], fm_error *err);
void gc_compc_free(gc_compc *c);

/* G41 (GC_COMPC_LEFT) / G42 (GC_COMPC_RIGHT) with radius > 0 (a negative
 * offset is the other side: the caller swaps). The next plane element is
 * the start-up block (a line; an arc is refused, Fanuc's alarm 034). Refused
 * while compensation is on (a side change in offset mode is not
 * supported). file/line/column say where, for errors. */
fm_status gc_compc_start(gc_compc *c, gc_compc_side side, double radius, const char *file,
                         int line, int column, fm_error *err);

/* A new radius (D) while compensation is on or armed: it applies to the
 * plane elements given after it; the corner between the last element of the
 * old radius and the first of the new one is formed by the same rules with
 * each element's own offset (Fanuc changes the vector at the end of the
 * block that gives the new D: the same corner point, reached one block
 * earlier). radius > 0. */
fm_status gc_compc_set_radius(gc_compc *c, double radius, const char *file, int line,
                              int column, fm_error *err);

/* G40: the element waiting for its corner ends at the vector perpendicular
 * to its end (emitted now); the next plane element is the cancel block,
 * from there to its programmed end (an arc is refused, alarm 034). Nothing
 * happens when compensation is off; when armed it is simply turned off.
 * Fails only as the emit callback or the element's interference check
 * (at that element's position) does. */
fm_status gc_compc_cancel(gc_compc *c, fm_error *err);

/* One programmed element (see gc_compc_elem). */
fm_status gc_compc_add(gc_compc *c, const gc_compc_elem *in, fm_error *err);

/* Program end: emit what waits (the last element ends at the vector
 * perpendicular to its end) and turn compensation off. */
fm_status gc_compc_finish(gc_compc *c, fm_error *err);

/* Nothing waits and compensation is off: no G41/G42, or its cancel block
 * has run. */
int gc_compc_idle(const gc_compc *c);

/* Compensation is armed or on (a G41/G42 not yet cancelled). */
int gc_compc_active(const gc_compc *c);

/* The programmed current point (u, v, w): where the program is, whatever
 * the tool's offset. */
void gc_compc_programmed_point(const gc_compc *c, double out[3]);

#endif
