/* pocket.c: Haas' G12/G13 circular pocket milling as the machine's lines
 * and arcs, for any dialect that has it: from the centre, a half-turn
 * lead-in to the first circle (radius I), full circles out to the finished
 * radius K in steps of Q joined by half turns, and a half turn back to the
 * centre; the tool centre runs the tool's radius (D) inside; passes (L)
 * deeper by the same Z increment in G91. Points are in the program frame
 * (transform.c: a mirror reverses the direction). The front end reads and
 * checks the words (Haas' manual). */
#include "machine.h"

#include <math.h>

/* An arc of the pocket in the program frame, direction ccw (before any
 * mirror), about cen, to end. */
static fm_status pocket_arc(gc_interp *g, const double end[3], const double cen[3], int ccw)
{
    return gc_frame_arc(g, end, cen, ccw, 0);
}

/* From radius r0 on one side of the centre (side = +1: +X, -1: -X) to
 * radius r1 on the other side: a half circle whose centre is on the X
 * line through the pocket's centre (r0 = 0: the lead-in from the centre,
 * r1 = 0: the lead-out back to it). */
static fm_status half_turn(gc_interp *g, const double c[2], double z, double r0, double r1,
                           int side, int ccw)
{
    double end[3] = {c[0] - side * r1, c[1], z};
    double cen[3] = {c[0] + side * (r0 - r1) / 2, c[1], z};
    return pocket_arc(g, end, cen, ccw);
}

fm_status gc_circular_pocket(gc_interp *g, const gc_pocket *p)
{
    /* the centre: X Y of the block (G90/G91), reached at the current
     * height; Z: the depth of the first pass, each L pass deeper by the
     * same increment in G91 */
    const double *target = p->target;
    double first = p->first, last = p->last, step = p->step, rt = p->tool_radius;
    int ccw = p->ccw;
    fm_status st;
    double c[2] = {target[0], target[1]};
    double z0 = g->frame.prog[2];
    double dz = p->has_z ? target[2] - z0 : 0;
    if (c[0] != g->frame.prog[0] || c[1] != g->frame.prog[1]) {
        double to[3] = {c[0], c[1], z0};
        if ((st = gc_frame_move(g, 1, to))) return st;
    }
    for (long rep = 0; rep < p->passes && !g->stop; rep++) {
        double z = p->has_z ? (g->absolute ? target[2] : z0 + (rep + 1) * dz) : z0;
        if (z != g->frame.prog[2]) {
            double to[3] = {c[0], c[1], z};
            if ((st = gc_frame_move(g, 0, to))) return st;
        }
        /* circles from I out to K in steps of Q, each a full turn, joined
         * by half turns; the tool centre runs the tool's radius inside */
        double r = 0;
        int side = -1; /* the lead-in ends on +X */
        for (long n = 0;; n++) {
            double next = first + n * step;
            if (!(step > 0) || next > last - 1e-9 * (1 + fabs(last))) next = last;
            next -= rt;
            if ((st = half_turn(g, c, z, r, next, side, ccw))) return st;
            side = -side;
            double at[3] = {c[0] + side * next, c[1], z}, cen[3] = {c[0], c[1], z};
            if ((st = pocket_arc(g, at, cen, ccw))) return st;
            r = next;
            if (next >= last - rt) break;
        }
        if ((st = half_turn(g, c, z, r, 0, side, ccw))) return st;
    }
    return FM_OK;
}
