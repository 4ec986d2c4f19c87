/* comp_c.c: the machine's cutter radius compensation with intersected
 * corners (Fanuc's and Haas' G40/G41/G42, "cutter compensation C"): from
 * G41/G42 until its cancel block has run, a dialect hands its lines, arcs
 * and dwells here instead of to motion.c; they go through the type C engine
 * (comp_intersect.c) in the compensation plane with the state each block was
 * programmed with, and come back as the tool centre's motions. LinuxCNC's
 * compensation (arcs round convex corners) is comp.c. */
#include "comp_intersect.h"
#include "machine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What a queued block was programmed with: the motion takes it when it
 * leaves the engine. */
typedef struct comp_c_payload {
    gc_comp_snap snap;
    double seconds; /* dwells */
} comp_c_payload;

static void to_plane(gc_plane plane, const double xyz[3], double uvw[3])
{
    int a, b, c;
    gc_plane_axes(plane, &a, &b, &c);
    uvw[0] = xyz[a];
    uvw[1] = xyz[b];
    uvw[2] = xyz[c];
}

static void from_plane(gc_plane plane, const double uvw[3], double xyz[3])
{
    int a, b, c;
    gc_plane_axes(plane, &a, &b, &c);
    xyz[a] = uvw[0];
    xyz[b] = uvw[1];
    xyz[c] = uvw[2];
}

static fm_status emit(void *ctx, const gc_compc_elem *e, fm_error *err)
{
    gc_interp *g = ctx;
    (void)err; /* the motions fail into g->err, which is err */
    const comp_c_payload *p = e->payload;
    static const gc_comp_kind kinds[] = {[GC_COMPC_LINE] = GC_COMP_LINE,
                                         [GC_COMPC_RAPID] = GC_COMP_RAPID,
                                         [GC_COMPC_ARC] = GC_COMP_ARC,
                                         [GC_COMPC_OTHER] = GC_COMP_DWELL};
    double xyz[3];
    from_plane(g->comp_c_plane, e->end, xyz);
    return gc_emit_queued(g, &p->snap, kinds[e->kind], xyz, e->center, e->turn, p->seconds);
}

int gc_comp_c_routing(const gc_interp *g) { return g->comp_c && !gc_compc_idle(g->comp_c); }

int gc_comp_c_on(const gc_interp *g) { return g->comp_c && gc_compc_active(g->comp_c); }

fm_status gc_comp_c_start(gc_interp *g, int left, double radius, int col)
{
    if (gc_comp_c_on(g))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G4%d: cutter radius compensation is already on (G4%d); expected G40 "
                       "before changing sides", left ? 1 : 2, g->comp_c_left ? 1 : 2);
    if (radius < 0) { /* a negative offset compensates on the other side */
        radius = -radius;
        left = !left;
    }
    if (!g->comp_c) {
        g->comp_c = calloc(1, sizeof *g->comp_c);
        if (!g->comp_c) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    } else if (!gc_compc_idle(g->comp_c)) {
        /* G41/G42 again before the cancel block of a G40 ran: the
         * offset stays as it was, as on a control */
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G4%d before a move ended the compensation cancelled by G40; expected "
                       "a G00/G01 move after G40", left ? 1 : 2);
    }
    gc_compc_free(g->comp_c);
    double cur[3];
    to_plane(g->plane, g->pos, cur);
    g->comp_c_plane = g->plane;
    g->comp_c_left = left;
    fm_status st = gc_compc_init(g->comp_c, sizeof(comp_c_payload), emit, g, cur, g->err);
    if (st) return st;
    if (radius == 0) return FM_OK; /* D0: the tool centre follows the program */
    return gc_compc_start(g->comp_c, left ? GC_COMPC_LEFT : GC_COMPC_RIGHT, radius,
                          g->line_name ? g->line_name : g->name, g->lineno, col, g->err);
}

fm_status gc_comp_c_radius(gc_interp *g, double radius, int col)
{
    if (!gc_comp_c_on(g) || radius <= 0) return FM_OK;
    return gc_compc_set_radius(g->comp_c, radius, g->line_name ? g->line_name : g->name,
                               g->lineno, col, g->err);
}

fm_status gc_comp_c_cancel(gc_interp *g)
{
    if (!g->comp_c) return FM_OK;
    return gc_compc_cancel(g->comp_c, g->err);
}

/* The state the block is programmed with; the feed per minute as comp.c
 * keeps it (gc_queued_feed: G93 the programmed length over the block's
 * time, G95 F x S). */
static void payload_of(const gc_interp *g, double programmed_len, comp_c_payload *p)
{
    memset(p, 0, sizeof *p);
    p->snap.line = g->lineno;
    p->snap.block = g->cur_block;
    p->snap.feed = gc_queued_feed(g, programmed_len);
    p->snap.speed = g->speed;
    p->snap.spindle_dir = g->spindle_dir;
    p->snap.coolant = g->coolant;
}

static fm_status add(gc_interp *g, gc_compc_kind kind, const double end_xyz[3],
                     const double center_ab[2], int turn, double programmed_len, double seconds,
                     int col)
{
    if (g->plane != g->comp_c_plane)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "plane change with cutter radius compensation on; expected G40 first");
    comp_c_payload p;
    payload_of(g, programmed_len, &p);
    p.seconds = seconds;
    gc_compc_elem e;
    memset(&e, 0, sizeof e);
    e.kind = kind;
    to_plane(g->plane, end_xyz, e.end);
    if (center_ab) {
        e.center[0] = center_ab[0];
        e.center[1] = center_ab[1];
    }
    e.turn = turn;
    e.file = g->line_name ? g->line_name : g->name;
    e.line = g->lineno;
    e.column = col;
    e.payload = &p;
    return gc_compc_add(g->comp_c, &e, g->err);
}

fm_status gc_comp_c_line(gc_interp *g, int rapid, const double to[3], int col)
{
    double from[3];
    gc_compc_programmed_point(g->comp_c, from);
    double uvw[3];
    to_plane(g->plane, to, uvw);
    double len = sqrt((uvw[0] - from[0]) * (uvw[0] - from[0]) +
                      (uvw[1] - from[1]) * (uvw[1] - from[1]) +
                      (uvw[2] - from[2]) * (uvw[2] - from[2]));
    return add(g, rapid ? GC_COMPC_RAPID : GC_COMPC_LINE, to, NULL, 0, len, 0, col);
}

fm_status gc_comp_c_arc(gc_interp *g, const double to[3], const double center_ab[2], int turn,
                        int col)
{
    double from_uvw[3], from[3];
    gc_compc_programmed_point(g->comp_c, from_uvw);
    from_plane(g->plane, from_uvw, from);
    double r = hypot(from_uvw[0] - center_ab[0], from_uvw[1] - center_ab[1]);
    double sweep = fabs(gc_arc_sweep(g->plane, from, to, center_ab, turn));
    int a, b, c;
    gc_plane_axes(g->plane, &a, &b, &c);
    double len = hypot(r * sweep, to[c] - from[c]);
    return add(g, GC_COMPC_ARC, to, center_ab, turn, len, 0, col);
}

fm_status gc_comp_c_dwell(gc_interp *g, double seconds)
{
    return add(g, GC_COMPC_OTHER, g->pos, NULL, 0, 0, seconds, 0);
}

fm_status gc_comp_c_finish(gc_interp *g)
{
    if (!g->comp_c || gc_compc_idle(g->comp_c)) return FM_OK;
    return gc_compc_finish(g->comp_c, g->err);
}

void gc_comp_c_free(gc_interp *g)
{
    if (!g->comp_c) return;
    gc_compc_free(g->comp_c);
    free(g->comp_c);
    g->comp_c = NULL;
}
