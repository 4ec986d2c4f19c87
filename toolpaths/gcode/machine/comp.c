/* comp.c: cutter radius compensation (G40, G41, G42, G41.1, G42.1)
 * with LinuxCNC's geometry, so that the compensated path equals rs274's:
 * the entry move ends tangent to the first programmed element, convex
 * corners get an arc about the programmed corner, concave corners are
 * intersected by moving the end of the previous move back (which needs the
 * previous motions held in a queue until the next programmed element is
 * known), and G40 ends compensation where the last element ended.
 *
 * Everything here works in the coordinates of the compensation plane
 * (u, v along the plane in LinuxCNC's order - G18's first axis is Z - and
 * w along its normal), in program units; gc_comp_to_plane and
 * gc_comp_from_plane map to and from X, Y, Z. LinuxCNC allows compensation
 * in G17 and G18 only. */
#include "machine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* LinuxCNC's TOLERANCE_CONCAVE_CORNER (radians) and TOLERANCE_EQUAL. */
#define COMP_CORNER_TOL 0.01
#define COMP_TOL_EQUAL 0.0001

void gc_comp_to_plane(gc_plane plane, const double xyz[3], double uvw[3])
{
    if (plane == GC_PLANE_XZ) {
        uvw[0] = xyz[2];
        uvw[1] = xyz[0];
        uvw[2] = xyz[1];
    } else {
        uvw[0] = xyz[0];
        uvw[1] = xyz[1];
        uvw[2] = xyz[2];
    }
}

void gc_comp_from_plane(gc_plane plane, const double uvw[3], double xyz[3])
{
    if (plane == GC_PLANE_XZ) {
        xyz[2] = uvw[0];
        xyz[0] = uvw[1];
        xyz[1] = uvw[2];
    } else {
        xyz[0] = uvw[0];
        xyz[1] = uvw[1];
        xyz[2] = uvw[2];
    }
}

int gc_comp_active(const gc_interp *g)
{
    return g->comp.side != GC_COMP_OFF && g->comp.radius > 0;
}

void gc_comp_free(gc_comp *c)
{
    free(c->q);
    c->q = NULL;
    c->nq = c->capq = 0;
}

/* The signed angle an arc sweeps from (x1, y1) to (x2, y2) about (cx, cy);
 * turn > 0 counter-clockwise, |turn| - 1 extra full circles, the same start
 * and end angle a full circle (gc_arc_sweep: lib/sweep's definition). */
static double arc_sweep(double x1, double y1, double cx, double cy, int turn, double x2, double y2)
{
    const double start[3] = {x1, y1, 0}, end[3] = {x2, y2, 0}, center[2] = {cx, cy};
    return gc_arc_sweep(GC_PLANE_XY, start, end, center, turn);
}

/* The tool is inside the arc (on the side of its centre). */
static int tool_inside(gc_comp_side side, int turn)
{
    return (side == GC_COMP_LEFT && turn > 0) || (side == GC_COMP_RIGHT && turn < 0);
}

static gc_comp_snap snapshot(const gc_interp *g, double feed)
{
    gc_comp_snap s;
    s.line = g->lineno;
    s.block = g->cur_block;
    s.feed = feed;
    s.speed = g->speed;
    s.spindle_dir = g->spindle_dir;
    s.coolant = g->coolant;
    return s;
}

static fm_status enqueue(gc_interp *g, const gc_comp_move *m)
{
    gc_comp *c = &g->comp;
    if (c->nq == c->capq) {
        size_t cap = c->capq ? c->capq * 2 : 8;
        gc_comp_move *q = realloc(c->q, cap * sizeof *q);
        if (!q) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory (compensation queue)");
        c->q = q;
        c->capq = cap;
    }
    c->q[c->nq++] = *m;
    return FM_OK;
}

static fm_status enqueue_line(gc_interp *g, int rapid, double feed, const double dir[2],
                              const double end[3])
{
    gc_comp_move m;
    memset(&m, 0, sizeof m);
    m.kind = rapid ? GC_COMP_RAPID : GC_COMP_LINE;
    memcpy(m.end, end, sizeof m.end);
    m.dir[0] = dir[0];
    m.dir[1] = dir[1];
    m.snap = snapshot(g, rapid ? 0 : feed);
    return enqueue(g, &m);
}

static fm_status enqueue_arc(gc_interp *g, double feed, const double end[3], const double center[2],
                             int turn, double sweep)
{
    gc_comp_move m;
    memset(&m, 0, sizeof m);
    m.kind = GC_COMP_ARC;
    memcpy(m.end, end, sizeof m.end);
    m.center[0] = center[0];
    m.center[1] = center[1];
    m.turn = turn;
    m.sweep = sweep;
    m.snap = snapshot(g, feed);
    return enqueue(g, &m);
}

/* Hand the queued motions to the sink, in order, and empty the queue. */
static fm_status dequeue(gc_interp *g)
{
    gc_comp *c = &g->comp;
    c->endpoint_valid = 0;
    fm_status st = FM_OK;
    for (size_t i = 0; i < c->nq && st == FM_OK; i++) st = gc_emit_comp_move(g, &c->q[i]);
    c->nq = 0;
    return st;
}

static void set_endpoint(gc_comp *c, double u, double v)
{
    c->endpoint[0] = u;
    c->endpoint[1] = v;
    c->endpoint_valid = 1;
}

/* Move the in-plane end of every queued motion to (u, v), refusing when a
 * move would then run backwards or an arc would sweep further than
 * programmed (the tool cannot reach the corner without gouging), and flush. */
static fm_status move_endpoint_and_flush(gc_interp *g, double u, double v, int col)
{
    gc_comp *c = &g->comp;
    if (c->nq == 0) return FM_OK;
    for (size_t i = 0; i < c->nq; i++) {
        gc_comp_move *m = &c->q[i];
        if (m->kind == GC_COMP_ARC) {
            double r1 = hypot(m->end[0] - m->center[0], m->end[1] - m->center[1]);
            double r2 = hypot(u - m->center[0], v - m->center[1]);
            double swept = arc_sweep(c->endpoint[0], c->endpoint[1], m->center[0], m->center[1],
                                     m->turn, u, v);
            if (fabs(r1 - r2) > 0.01) /* defensive: corners meet on the circle */
                return gc_fail(g, FM_ERR_INPUT, col,
                               "cutter compensation made an arc with mismatched radii (%.4f and "
                               "%.4f); the corner cannot be compensated", r1, r2);
            if (m->sweep != 0 && c->endpoint_valid && fabs(swept) > fabs(m->sweep) + 0.001)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "cutter compensation: the arc of line %d in this concave corner "
                               "cannot be reached by the tool without gouging; expected a larger "
                               "corner or a smaller tool", m->snap.line);
        } else if (m->kind == GC_COMP_LINE || m->kind == GC_COMP_RAPID) {
            double dot = m->dir[0] * (u - c->endpoint[0]) + m->dir[1] * (v - c->endpoint[1]);
            if (c->endpoint_valid && dot < 0)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "cutter compensation: the %s of line %d in this concave corner "
                               "cannot be reached by the tool without gouging (it would run "
                               "backwards); expected a longer move or a smaller tool",
                               m->kind == GC_COMP_RAPID ? "traverse" : "feed", m->snap.line);
        } else {
            continue;
        }
        m->end[0] = u;
        m->end[1] = v;
    }
    fm_status st = dequeue(g);
    set_endpoint(c, u, v);
    return st;
}

static void current_uvw(const gc_interp *g, double cur[3])
{
    gc_comp_to_plane(g->plane, g->pos, cur);
}

static void set_current(gc_interp *g, const double uvw[3])
{
    gc_comp_from_plane(g->plane, uvw, g->pos);
}

fm_status gc_comp_on(gc_interp *g, const gc_block *b, int code, int col)
{
    gc_comp *c = &g->comp;
    char name[16];
    gc_g_name(code, name, sizeof name);
    if (g->plane != GC_PLANE_XY && g->plane != GC_PLANE_XZ)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: cutter radius compensation in the G%d plane; LinuxCNC compensates "
                       "in G17 or G18 only", name, (int)g->plane);
    if (c->side != GC_COMP_OFF)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: cutter radius compensation is already on; expected G40 first", name);
    gc_comp_side side = (code == GC_G41 || code == GC_G41_1) ? GC_COMP_LEFT : GC_COMP_RIGHT;
    double radius;
    int orientation = 0;
    if (code == GC_G41_1 || code == GC_G42_1) {
        if (!HAS(b, 'd'))
            return gc_fail(g, FM_ERR_INPUT, col, "%s: D word missing; expected D<diameter>",
                           name);
        radius = VAL(b, 'd') / 2;
        if (HAS(b, 'l')) {
            if (g->plane != GC_PLANE_XZ)
                return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                               "%s L: a lathe tool orientation needs the G18 plane", name);
            double l = VAL(b, 'l');
            if (l != floor(l) || l < 0 || l > 9)
                return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                               "%s L%g: expected a tool orientation 0 to 9", name, l);
            orientation = (int)l;
        }
    } else {
        int tool = g->tool;
        if (HAS(b, 'd')) {
            double d = VAL(b, 'd');
            double r = floor(d + 0.5);
            if (fabs(r - d) >= 0.0001)
                return gc_fail(g, FM_ERR_INPUT, COL(b, 'd'),
                               "%s D%g: expected a whole tool number", name, d);
            if (r < 0)
                return gc_fail(g, FM_ERR_INPUT, COL(b, 'd'),
                               "%s D%g: expected a tool number >= 0", name, d);
            /* the bound of every whole word (gc_int_word): beyond it the
             * conversion to int would be undefined */
            if (r > 1e9)
                return gc_fail(g, FM_ERR_INPUT, COL(b, 'd'),
                               "%s D%g: expected a tool number up to 1000000000", name, d);
            tool = gc_register_tool(g, 'd', (int)r);
            fm_status st = gc_check_tool(g, tool, COL(b, 'd'), "D");
            if (st) return st;
        }
        radius = gc_tool_comp_radius_mm(g, tool) / g->unit;
    }
    if (radius < 0) { /* a negative diameter in the table: the other side */
        radius = -radius;
        side = side == GC_COMP_LEFT ? GC_COMP_RIGHT : GC_COMP_LEFT;
    }
    c->radius = radius;
    c->orientation = orientation;
    c->side = side;
    c->firstmove = 1;
    return FM_OK;
}

fm_status gc_comp_off(gc_interp *g, int col)
{
    gc_comp *c = &g->comp;
    if (gc_comp_active(g) && !c->firstmove) {
        double cur[3];
        current_uvw(g, cur);
        fm_status st = move_endpoint_and_flush(g, cur[0], cur[1], col);
        if (!st) st = dequeue(g);
        if (st) return st;
        /* from here the programmed point is the current point; the tool is
         * still where the last compensated move left it, and the next move
         * (the exit move) starts there */
        set_current(g, c->prog);
        c->arc_not_allowed = 1;
    }
    c->side = GC_COMP_OFF;
    c->firstmove = 1;
    return FM_OK;
}

fm_status gc_comp_finish(gc_interp *g)
{
    return dequeue(g);
}

void gc_comp_base(const gc_interp *g, double base[3])
{
    memcpy(base, g->pos, 3 * sizeof base[0]);
    if (!gc_comp_active(g) || g->comp.firstmove) return;
    /* LinuxCNC's find_ends: unspecified (and incremental) in-plane axes
     * start from the programmed point; X is in-plane in G17 and G18, Y only
     * in G17, Z only in G18 */
    double prog[3];
    gc_comp_from_plane(g->plane, g->comp.prog, prog);
    base[0] = prog[0];
    if (g->plane == GC_PLANE_XY) base[1] = prog[1];
    if (g->plane == GC_PLANE_XZ) base[2] = prog[2];
}

void gc_comp_scale(gc_interp *g, double f)
{
    gc_comp *c = &g->comp;
    c->radius *= f;
    for (int i = 0; i < 3; i++) c->prog[i] *= f;
    c->endpoint[0] *= f;
    c->endpoint[1] *= f;
    for (size_t i = 0; i < c->nq; i++) {
        gc_comp_move *m = &c->q[i];
        for (int k = 0; k < 3; k++) m->end[k] *= f;
        m->center[0] *= f;
        m->center[1] *= f;
    }
}

fm_status gc_comp_dwell(gc_interp *g, double seconds)
{
    if (g->comp.nq == 0) return gc_dwell(g, seconds);
    gc_comp_move m;
    memset(&m, 0, sizeof m);
    m.kind = GC_COMP_DWELL;
    m.seconds = seconds;
    m.snap = snapshot(g, 0);
    return enqueue(g, &m);
}

/* The first move after G41/G42, a line: it ends where the tool touches the
 * programmed end point, on a line from the start tangent to the tool there. */
static fm_status straight_first(gc_interp *g, int rapid, double feed, const double p[3], int col)
{
    gc_comp *c = &g->comp;
    double cur[3];
    current_uvw(g, cur);
    double r = c->radius;
    double dist = hypot(p[0] - cur[0], p[1] - cur[1]);
    if (dist < r) /* rs274 2.9 accepts an entry exactly one radius long */
        return gc_fail(g, FM_ERR_INPUT, col,
                       "cutter compensation entry move of length %.4f is shorter than the tool "
                       "radius %.4f; expected a longer entry move", dist, r);
    double alpha = atan2(p[1] - cur[1], p[0] - cur[0]) +
                   (c->side == GC_COMP_LEFT ? FM_PI / 2 : -FM_PI / 2);
    double end[3] = {p[0] + r * cos(alpha), p[1] + r * sin(alpha), p[2]};
    set_endpoint(c, cur[0], cur[1]);
    double dir[2] = {cos(alpha), sin(alpha)};
    fm_status st = enqueue_line(g, rapid, feed, dir, end);
    if (st) return st;
    c->firstmove = 0;
    set_current(g, end);
    memcpy(c->prog, p, sizeof c->prog);
    return FM_OK;
}

static fm_status straight_next(gc_interp *g, int rapid, double feed, const double p[3], int col)
{
    gc_comp *c = &g->comp;
    double cur[3], o[3];
    current_uvw(g, cur);
    memcpy(o, c->prog, sizeof o);
    fm_status st;
    double end[3] = {cur[0], cur[1], p[2]};
    if (p[0] == o[0] && p[1] == o[1]) {
        /* no motion in the plane: the tool moves along the normal only */
        double dir[2] = {0, 0};
        if ((st = enqueue_line(g, rapid, feed, dir, end))) return st;
    } else {
        double r = c->radius;
        int left = c->side == GC_COMP_LEFT;
        double theta = atan2(cur[1] - o[1], cur[0] - o[0]); /* from the corner to the tool */
        double alpha = atan2(p[1] - o[1], p[0] - o[0]);     /* the new direction */
        double beta, gamma;
        if (left) {
            if (theta < alpha) theta += 2 * FM_PI;
            beta = theta - alpha - FM_PI / 2;
            gamma = FM_PI / 2;
        } else {
            if (alpha < theta) alpha += 2 * FM_PI;
            beta = alpha - theta - FM_PI / 2;
            gamma = -FM_PI / 2;
        }
        end[0] = p[0] + r * cos(alpha + gamma);
        end[1] = p[1] + r * sin(alpha + gamma);
        double mid[2] = {o[0] + r * cos(alpha + gamma), o[1] + r * sin(alpha + gamma)};
        const gc_comp_move *front = c->nq ? &c->q[0] : NULL;
        int front_arc = front && front->kind == GC_COMP_ARC;
        int concave = beta < -COMP_CORNER_TOL || beta > FM_PI + COMP_CORNER_TOL;
        /* an "h" shape: over a round top and down beside a straight side;
         * LinuxCNC keeps the tool above and beside rather than looping round */
        if (!concave && beta > FM_PI - COMP_CORNER_TOL && front_arc &&
            ((!left && front->turn > 0) || (left && front->turn < 0)))
            concave = 1;
        if (!concave && beta > COMP_CORNER_TOL) {
            /* convex corner: round it with an arc about the programmed corner
             * (a traverse cannot arc: it goes straight to the arc's end) */
            if ((st = move_endpoint_and_flush(g, cur[0], cur[1], col))) return st;
            double arc_end[3] = {mid[0], mid[1], cur[2]};
            if (rapid) {
                double none[2] = {0, 0};
                st = enqueue_line(g, 1, 0, none, arc_end);
            } else {
                st = enqueue_arc(g, feed, arc_end, o, left ? -1 : 1, 0.0);
            }
            if (!st) st = dequeue(g);
            if (st) return st;
            set_endpoint(c, mid[0], mid[1]);
        } else if (concave) {
            double meet[2];
            if (!front_arc) {
                /* line to line: pull the previous end back along its path (beta
                 * >= -pi/2 by construction, so half the corner is >= pi/4) */
                double halfcorner = (beta + FM_PI) / 2;
                double retreat = r / tan(halfcorner);
                meet[0] = cur[0] + retreat * cos(theta + gamma);
                meet[1] = cur[1] + retreat * sin(theta + gamma);
            } else {
                /* arc to line: where the compensated arc meets the new line's
                 * offset */
                const gc_comp_move *prev = front;
                double oldrad = hypot(prev->center[1] - prev->end[1], prev->center[0] - prev->end[0]);
                double base_dir = atan2(p[1] - o[1], p[0] - o[0]);
                double th = prev->turn > 0 ? base_dir + FM_PI / 2 : base_dir - FM_PI / 2;
                double phi = atan2(prev->center[1] - o[1], prev->center[0] - o[0]);
                int inside = tool_inside(c->side, prev->turn);
                double oldrad_uncomp = inside ? oldrad + r : oldrad - r;
                double d = oldrad_uncomp * cos(th - phi);
                double l = (inside ? d - r : d + r) / oldrad;
                if (l > 1.0 || l < -1.0)
                    return gc_fail(g, FM_ERR_INPUT, col,
                                   "cutter compensation: the corner from the arc of line %d to "
                                   "this line is too tight for the tool without gouging",
                                   prev->snap.line);
                double ang;
                if (inside) ang = (prev->turn > 0 ? -acos(l) : acos(l)) + th + FM_PI;
                else ang = (prev->turn > 0 ? acos(l) : -acos(l)) + th + FM_PI;
                meet[0] = prev->center[0] + oldrad * cos(ang);
                meet[1] = prev->center[1] + oldrad * sin(ang);
            }
            if ((st = move_endpoint_and_flush(g, meet[0], meet[1], col))) return st;
        } else {
            /* straight on (or tangent): nothing to add */
            if ((st = dequeue(g))) return st;
            set_endpoint(c, cur[0], cur[1]);
        }
        double dir[2] = {p[0] - o[0], p[1] - o[1]};
        if ((st = enqueue_line(g, rapid, feed, dir, end))) return st;
    }
    set_current(g, end);
    memcpy(c->prog, p, sizeof c->prog);
    return FM_OK;
}

fm_status gc_comp_straight(gc_interp *g, int rapid, double feed, const double end_xyz[3], int col)
{
    double p[3];
    gc_comp_to_plane(g->plane, end_xyz, p);
    g->comp.arc_not_allowed = 0;
    if (g->comp.firstmove) return straight_first(g, rapid, feed, p, col);
    return straight_next(g, rapid, feed, p, col);
}

/* The first move after G41/G42, an arc: the tool moves on a circle about a
 * new centre so that it ends touching the programmed end point while staying
 * tangent to the programmed arc through it. */
static fm_status arc_first(gc_interp *g, const gc_arc_data *a, double feed, int col)
{
    gc_comp *c = &g->comp;
    double cur[3];
    current_uvw(g, cur);
    double r = c->radius;
    const double *p = a->end;
    if (hypot(p[0] - cur[0], p[1] - cur[1]) < r)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "cutter compensation entry arc: its end is nearer than the tool radius "
                       "%.4f to the start; expected a longer entry move", r);
    int turn = a->turn;
    double gamma;
    if (tool_inside(c->side, turn)) gamma = atan2(a->center[1] - p[1], a->center[0] - p[0]);
    else gamma = atan2(p[1] - a->center[1], p[0] - a->center[0]);
    double end[3] = {p[0] + r * cos(gamma), p[1] + r * sin(gamma), p[2]};
    double b_len = hypot(cur[1] - end[1], cur[0] - end[0]) / 2.0;
    double ab_ang = atan2(a->center[1] - end[1], a->center[0] - end[0]);
    double a_ang = atan2(cur[1] - end[1], cur[0] - end[0]) - ab_ang;
    if (fabs(cos(a_ang)) < COMP_TOL_EQUAL)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "cutter compensation entry arc: the tool radius %.4f is not less than "
                       "the arc radius", r);
    double c_len = b_len / cos(a_ang);
    double center[2] = {end[0] + c_len * cos(ab_ang), end[1] + c_len * sin(ab_ang)};
    double tol = g->unit == 1.0 ? 0.005 : 0.0005;
    if (fabs(hypot(center[0] - end[0], center[1] - end[1]) -
             hypot(center[0] - cur[0], center[1] - cur[1])) > tol)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "cutter compensation entry arc cannot be computed for this geometry; "
                       "expected a straight entry move");
    fm_status st;
    if (c->orientation != 0 && c->orientation != 9) {
        /* a lathe tool's origin moves first, so that the arc stays an arc */
        double none[2] = {0, 0};
        if ((st = enqueue_line(g, 0, feed, none, cur))) return st;
        set_endpoint(c, cur[0], cur[1]);
    }
    st = enqueue_arc(g, feed, end, center, turn,
                     arc_sweep(cur[0], cur[1], center[0], center[1], turn, end[0], end[1]));
    if (st) return st;
    c->firstmove = 0;
    memcpy(c->prog, p, sizeof c->prog);
    set_current(g, end);
    return FM_OK;
}

static fm_status arc_next(gc_interp *g, const gc_arc_data *a, double feed, int col)
{
    gc_comp *c = &g->comp;
    double cur[3], o[3];
    current_uvw(g, cur);
    memcpy(o, c->prog, sizeof o);
    const double *p = a->end;
    const double *center = a->center;
    int turn = a->turn;
    double r = c->radius;
    int left = c->side == GC_COMP_LEFT;
    double arc_radius = hypot(center[0] - p[0], center[1] - p[1]);
    double theta = atan2(cur[1] - o[1], cur[0] - o[0]);
    theta = left ? theta - FM_PI / 2 : theta + FM_PI / 2; /* direction of the last move */
    double delta = atan2(center[1] - o[1], center[0] - o[0]);
    double alpha = turn > 0 ? delta - FM_PI / 2 : delta + FM_PI / 2; /* the arc's start direction */
    double beta = left ? theta - alpha : alpha - theta;
    if (beta > 1.5 * FM_PI) beta -= 2 * FM_PI;
    else if (beta < -FM_PI / 2) beta += 2 * FM_PI;
    double gamma;
    int inside = tool_inside(c->side, turn);
    if (inside) {
        gamma = atan2(center[1] - p[1], center[0] - p[0]);
        if (arc_radius < r)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "cutter compensation: the tool radius %.4f is larger than the radius "
                           "%.4f of this inside arc; expected a smaller tool", r, arc_radius);
    } else {
        gamma = atan2(p[1] - center[1], p[0] - center[0]);
        delta += FM_PI;
    }
    double new_end[3] = {p[0] + r * cos(gamma), p[1] + r * sin(gamma), p[2]};
    double sweep = arc_sweep(o[0], o[1], center[0], center[1], turn, p[0], p[1]);
    const gc_comp_move *front = c->nq ? &c->q[0] : NULL;
    fm_status st;
    if (beta < -COMP_CORNER_TOL || beta > FM_PI + COMP_CORNER_TOL ||
        (fabs(beta - FM_PI) < COMP_CORNER_TOL && !inside)) {
        /* concave */
        double meet[2];
        if (!front || front->kind != GC_COMP_ARC) {
            /* line to arc */
            double cy = arc_radius * sin(beta - FM_PI / 2);
            double dist, l, ang;
            if (inside) {
                dist = arc_radius - r;
                l = (cy + r) / dist;
            } else {
                dist = arc_radius + r;
                l = (cy - r) / dist;
            }
            if (l > 1.0 || l < -1.0)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "cutter compensation: this arc in a concave corner cannot be "
                               "reached by the tool without gouging");
            if (inside) ang = turn > 0 ? theta + asin(l) : theta - asin(l);
            else ang = turn > 0 ? theta + FM_PI - asin(l) : theta + FM_PI + asin(l);
            meet[0] = center[0] + dist * cos(ang);
            meet[1] = center[1] + dist * sin(ang);
        } else {
            /* arc to arc: where the two offset circles meet */
            const gc_comp_move *prev = front;
            double oldrad = hypot(prev->center[1] - prev->end[1], prev->center[0] - prev->end[0]);
            double newrad = inside ? arc_radius - r : arc_radius + r;
            double arc_cc = hypot(prev->center[1] - center[1], prev->center[0] - center[0]);
            if (oldrad == 0 || arc_cc == 0)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "cutter compensation: this arc and the arc of line %d have the "
                               "same centre", prev->snap.line);
            double ca = (oldrad * oldrad + arc_cc * arc_cc - newrad * newrad) / (2 * oldrad * arc_cc);
            if (ca > 1.0 || ca < -1.0)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "cutter compensation: the corner from the arc of line %d to this "
                               "arc is too tight for the tool without gouging", prev->snap.line);
            double pullback = acos(ca);
            double cc_dir = atan2(center[1] - prev->center[1], center[0] - prev->center[0]);
            double dir;
            if (tool_inside(c->side, prev->turn)) dir = turn > 0 ? cc_dir + pullback : cc_dir - pullback;
            else dir = turn > 0 ? cc_dir - pullback : cc_dir + pullback;
            meet[0] = prev->center[0] + oldrad * cos(dir);
            meet[1] = prev->center[1] + oldrad * sin(dir);
        }
        if ((st = move_endpoint_and_flush(g, meet[0], meet[1], col))) return st;
    } else if (beta > COMP_CORNER_TOL) {
        /* convex: an arc about the programmed corner first */
        double mid[3] = {o[0] + r * cos(delta), o[1] + r * sin(delta), cur[2]};
        if ((st = dequeue(g))) return st;
        if ((st = enqueue_arc(g, feed, mid, o, left ? -1 : 1, 0.0))) return st;
        if ((st = dequeue(g))) return st;
        set_endpoint(c, mid[0], mid[1]);
    } else {
        if ((st = dequeue(g))) return st;
        set_endpoint(c, cur[0], cur[1]);
    }
    if ((st = enqueue_arc(g, feed, new_end, center, turn, sweep))) return st;
    memcpy(c->prog, p, sizeof c->prog);
    set_current(g, new_end);
    return FM_OK;
}

fm_status gc_comp_arc(gc_interp *g, const gc_arc_data *a, double feed, int col)
{
    if (g->comp.firstmove) return arc_first(g, a, feed, col);
    return arc_next(g, a, feed, col);
}
