/* comp_intersect.c: Fanuc's "cutter compensation C" (Series 0i/16i/18i;
 * Haas follows it) as a streaming engine: programmed elements in the
 * compensation plane in, tool-centre elements out. The offset vector has
 * the tool's radius r and points from the programmed path to the tool's side
 * (G41 left, G42 right). alpha is the angle between two blocks at their
 * corner, on the workpiece side: alpha = 180 degrees straight on, >= 180 an
 * inner corner (the path turns toward the tool), < 180 an outer one.
 *
 * - Start-up (the first plane element after G41/G42, a line): from the
 *   uncompensated point to the programmed end plus the offset vector
 *   perpendicular to the NEXT element's start (for an arc: along its radius
 *   at its start), where that element then starts. Used for inner and
 *   outer start-ups alike (Fanuc's type A start-up).
 * - Inner corners: the two offset paths meet (line-line, line-arc, arc-arc:
 *   the intersection nearest the programmed corner); the earlier element
 *   ends there and the later starts there. None: Fanuc's alarm 033.
 * - Outer corners, 90 <= alpha < 180 (a boss's square corner has alpha 90
 *   and is one): the offset lines meet; for an arc its tangent line at the
 *   corner stands for it, as in Fanuc's figures: the arc ends at its offset
 *   end and a straight move reaches the tangent lines' intersection (and,
 *   for an arc after the corner, one leaves it for the arc's offset start).
 * - Outer corners, alpha < 90 (Fanuc's two extra vectors): the earlier
 *   element's offset end moved on by r along its end tangent (a line is
 *   lengthened; an arc gets a straight move), a straight move to the later
 *   element's offset start moved back by r along its start tangent, and the
 *   later element (a line shortened from there; an arc after a straight
 *   move to its offset start). A reversal (alpha 0) is such a corner.
 * - Tangent junctions (within TANGENT_TOL, as CAM output rounded to 4
 *   decimals makes them): no extra element; when the two offset points still
 *   differ (the tolerance, or a radius change) a straight move joins them.
 * - Cancel (G40): the element before ends at the vector perpendicular to
 *   its end; the cancel block (a line; an arc is Fanuc's alarm 034) runs
 *   from there to its programmed end. Program end does the same without a
 *   cancel block.
 * - Arcs: the offset arc has radius R + r (tool outside) or R - r (inside);
 *   an inside arc with R <= r is refused.
 * - Interference (Fanuc's alarm 041): a compensated line that runs against
 *   its programmed direction (more than 90 degrees off), or a compensated
 *   arc whose sweep vanishes or reverses, is refused at that element.
 * - Elements without motion in the plane (w-only moves, dwells) wait, up to
 *   GC_COMPC_LOOKAHEAD of them, for the next plane element, and come out at
 *   the corner: after the earlier element's own part of it, before the
 *   later's. Beyond the limit the earlier element ends at the vector
 *   perpendicular to its end and the later one starts with a straight move
 *   to its offset start (Fanuc: "overcutting may occur").
 * - A D change in offset mode applies to the plane elements given after it,
 *   each offset by its own radius at the corners (Fanuc changes the vector
 *   at the end of the block giving D: the same corner point, one block
 *   earlier).
 * Corner moves belong to (carry the payload of) the element they extend or
 * lead into. Not done: a side change (G41 <-> G42) in offset mode, Fanuc's
 * types B and C start-up, the extra vector limit when an offset end lies far
 * past a short element (the interference check refuses those). Memory: the
 * look-ahead only (fixed size); no recursion. */
#include "comp_intersect.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define EPS 1e-9         /* lengths (program units) and angles (radians) */
#define TANGENT_TOL 1e-3 /* radians: a junction this close to tangent is one */

enum { OFF, ARMED, ON, CANCELLING };

typedef struct pt {
    double u, v;
} pt;

static pt P(double u, double v)
{
    pt p = {u, v};
    return p;
}
static pt at(const double *a) { return P(a[0], a[1]); }
static pt add(pt a, pt b) { return P(a.u + b.u, a.v + b.v); }
static pt sub(pt a, pt b) { return P(a.u - b.u, a.v - b.v); }
static pt scale(pt a, double k) { return P(a.u * k, a.v * k); }
static double dot(pt a, pt b) { return a.u * b.u + a.v * b.v; }
static double cross(pt a, pt b) { return a.u * b.v - a.v * b.u; }
static double len(pt a) { return hypot(a.u, a.v); }
static pt unit(pt a) { return scale(a, 1 / len(a)); }
static double angle(pt a) { return atan2(a.v, a.u); }

static double wrap_pi(double a)
{
    while (a > FM_PI) a -= 2 * FM_PI;
    while (a <= -FM_PI) a += 2 * FM_PI;
    return a;
}

/* The signed angle an arc sweeps from `from` to `to` about cen. */
static double arc_sweep(pt from, pt cen, int turn, pt to)
{
    double d = angle(sub(to, cen)) - angle(sub(from, cen));
    if (turn > 0 && d <= 0) d += 2 * FM_PI;
    if (turn < 0 && d >= 0) d -= 2 * FM_PI;
    return d + (turn > 0 ? turn - 1 : turn + 1) * 2 * FM_PI;
}

static int is_arc(const gc_compc_elem *e) { return e->kind == GC_COMPC_ARC; }

/* The unit tangent of a plane element at its start or end. */
static pt tangent(const gc_compc_elem *e, int at_end)
{
    if (!is_arc(e)) return unit(sub(at(e->end), at(e->start)));
    pt d = unit(sub(at(at_end ? e->end : e->start), at(e->center)));
    return e->turn > 0 ? P(-d.v, d.u) : P(d.v, -d.u);
}

/* The unit normal toward the tool's side (side 1 left, -1 right). */
static pt normal(int side, pt t) { return P(-side * t.v, side * t.u); }

/* The curvature vector of a plane element at its point p: toward the
 * centre, of length 1/R; 0 for a line. */
static pt curvature(const gc_compc_item *it, pt p)
{
    if (!is_arc(&it->e)) return P(0, 0);
    pt d = sub(at(it->e.center), p);
    return scale(d, 1 / dot(d, d));
}

static pt offset_point(const gc_compc_item *it, int side, int at_end)
{
    pt p = at(at_end ? it->e.end : it->e.start);
    return add(p, scale(normal(side, tangent(&it->e, at_end)), it->radius));
}

/* An offset path: the line p + s t, or the circle about p of radius r. */
typedef struct curve {
    int circle;
    pt p, t;
    double r;
} curve;

static double offset_arc_radius(const gc_compc_item *it, int side, int at_end)
{
    double r = len(sub(at(at_end ? it->e.end : it->e.start), at(it->e.center)));
    return r - side * (it->e.turn > 0 ? 1 : -1) * it->radius;
}

static curve offset_curve(const gc_compc_item *it, int side, int at_end)
{
    curve k = {0, {0, 0}, {0, 0}, 0};
    if (is_arc(&it->e)) {
        k.circle = 1;
        k.p = at(it->e.center);
        k.r = offset_arc_radius(it, side, at_end);
    } else {
        k.p = offset_point(it, side, 0);
        k.t = tangent(&it->e, 0);
    }
    return k;
}

static int line_line(pt p1, pt t1, pt p2, pt t2, pt *out)
{
    double det = cross(t1, t2);
    if (fabs(det) < 1e-12) return 0;
    *out = add(p1, scale(t1, cross(sub(p2, p1), t2) / det));
    return 1;
}

/* Where two offset paths meet: the number of points (0 to 2) in cand. */
static int meet(curve a, curve b, pt cand[2])
{
    if (!a.circle && !b.circle) return line_line(a.p, a.t, b.p, b.t, &cand[0]);
    if (a.circle && b.circle) {
        pt d = sub(b.p, a.p);
        double dd = len(d);
        if (dd < EPS) return 0;
        double x = (a.r * a.r - b.r * b.r + dd * dd) / (2 * dd), h2 = a.r * a.r - x * x;
        if (h2 < 0) return 0;
        pt e = scale(d, 1 / dd), m = add(a.p, scale(e, x)), hv = scale(P(-e.v, e.u), sqrt(h2));
        cand[0] = add(m, hv);
        cand[1] = sub(m, hv);
        return 2;
    }
    curve l = a.circle ? b : a, c = a.circle ? a : b;
    pt d = sub(l.p, c.p);
    double bq = dot(d, l.t), disc = bq * bq - (dot(d, d) - c.r * c.r);
    if (disc < 0) return 0;
    cand[0] = add(l.p, scale(l.t, -bq + sqrt(disc)));
    cand[1] = add(l.p, scale(l.t, -bq - sqrt(disc)));
    return 2;
}

/* How far x lies past the offset point a of an element (t: its tangent
 * there; for an arc a signed arc length about its centre): < 0 before it. */
static double past(const gc_compc_item *it, pt a, pt t, pt x)
{
    if (!is_arc(&it->e)) return dot(sub(x, a), t);
    pt cen = at(it->e.center);
    double d = wrap_pi(angle(sub(x, cen)) - angle(sub(a, cen)));
    return (it->e.turn > 0 ? d : -d) * len(sub(a, cen));
}

/* The inner corner's point: where the offset paths meet, before the
 * earlier one's offset end a1 and after the later one's offset start a2;
 * of two such (or of none), the nearer to the programmed corner p. */
static int inner_point(const gc_compc_item *pv, const gc_compc_item *nx, int side, pt p, pt *out)
{
    pt cand[2];
    int n = meet(offset_curve(pv, side, 1), offset_curve(nx, side, 0), cand);
    int best = -1, best_in_order = 0;
    double best_dist = 0;
    pt t1 = tangent(&pv->e, 1), t2 = tangent(&nx->e, 0);
    pt a1 = offset_point(pv, side, 1), a2 = offset_point(nx, side, 0);
    for (int i = 0; i < n; i++) {
        int in_order = past(pv, a1, t1, cand[i]) <= EPS && past(nx, a2, t2, cand[i]) >= -EPS;
        double dist = len(sub(cand[i], p));
        if (best < 0 || in_order > best_in_order || (in_order == best_in_order && dist < best_dist)) {
            best = i;
            best_in_order = in_order;
            best_dist = dist;
        }
    }
    if (best >= 0) *out = cand[best];
    return best >= 0;
}

static unsigned char *slot(gc_compc *c, int i) { return c->payloads + (size_t)i * c->payload_size; }

static void copy_payload(gc_compc *c, int to, const void *from)
{
    if (c->payload_size) memcpy(slot(c, to), from, c->payload_size);
}

static fm_status emit(gc_compc *c, const gc_compc_elem *e, fm_error *err)
{
    memcpy(c->tool, e->end, sizeof c->tool);
    return c->emit(c->ctx, e, err);
}

/* A straight corner move from the tool's point to `to`, part of owner's
 * block. */
static fm_status emit_corner(gc_compc *c, const gc_compc_item *owner, pt to, fm_error *err)
{
    if (len(sub(to, at(c->tool))) <= EPS) return FM_OK;
    gc_compc_elem e = owner->e;
    e.kind = e.kind == GC_COMPC_RAPID ? GC_COMPC_RAPID : GC_COMPC_LINE;
    memcpy(e.start, c->tool, sizeof e.start);
    e.end[0] = to.u;
    e.end[1] = to.v;
    e.end[2] = c->tool[2];
    e.turn = 0;
    e.corner = 1;
    return emit(c, &e, err);
}

/* A plane element from its compensated start to `to`; with check, refused
 * when its direction or sweep would reverse (Fanuc's alarm 041). */
static fm_status emit_plane(gc_compc *c, const gc_compc_item *it, pt to, int check, fm_error *err)
{
    gc_compc_elem e = it->e;
    pt from = at(it->from);
    e.start[0] = from.u;
    e.start[1] = from.v;
    e.corner = 0;
    if (is_arc(&e)) {
        pt cen = at(e.center), ps = at(it->e.start), pe = at(it->e.end);
        double ds = wrap_pi(angle(sub(from, cen)) - angle(sub(ps, cen)));
        double de = wrap_pi(angle(sub(to, cen)) - angle(sub(pe, cen)));
        double sweep = arc_sweep(ps, cen, e.turn, pe) + de - ds;
        int sign = e.turn > 0 ? 1 : -1;
        if (check && sweep * sign <= EPS)
            return fm_error_at(err, FM_ERR_INPUT, e.file, e.line, e.column,
                               "cutter compensation: the compensated arc would run backwards "
                               "(its sweep vanishes or reverses) with a tool of radius %g; "
                               "expected a smaller tool or a longer arc (Fanuc alarm 041, "
                               "interference)", it->radius);
        double turns = fabs(sweep) / (2 * FM_PI);
        if (len(sub(to, from)) <= EPS) { /* a full circle: the same point */
            to = from;
            e.turn = sign * (int)fmax(1, floor(turns + 0.5));
        } else {
            e.turn = sign * (int)fmax(1, ceil(turns - EPS));
        }
    } else if (check && dot(sub(to, from), tangent(&it->e, 0)) < -EPS) {
        return fm_error_at(err, FM_ERR_INPUT, e.file, e.line, e.column,
                           "cutter compensation: the compensated path would reverse here (the "
                           "tool of radius %g does not fit this move between its corners); "
                           "expected a smaller tool or a longer move (Fanuc alarm 041, "
                           "interference)", it->radius);
    }
    e.end[0] = to.u;
    e.end[1] = to.v;
    return emit(c, &e, err);
}

/* An element without motion in the plane, where the tool is now. */
static fm_status emit_still(gc_compc *c, const gc_compc_item *it, fm_error *err)
{
    gc_compc_elem e = it->e;
    e.start[0] = e.end[0] = c->tool[0];
    e.start[1] = e.end[1] = c->tool[1];
    e.corner = 0;
    return emit(c, &e, err);
}

static fm_status flush_queue(gc_compc *c, fm_error *err)
{
    fm_status st = FM_OK;
    for (int i = 0; i < c->nq && st == FM_OK; i++) st = emit_still(c, &c->queue[i], err);
    c->nq = 0;
    return st;
}

/* The waiting element ends at the vector perpendicular to its end (cancel,
 * program end, look-ahead exhausted); what waited after it follows. */
static fm_status end_prev_perpendicular(gc_compc *c, fm_error *err)
{
    if (!c->have_prev) return FM_OK;
    c->have_prev = 0;
    fm_status st = emit_plane(c, &c->prev, offset_point(&c->prev, c->side, 1), !c->prev_startup,
                              err);
    return st ? st : flush_queue(c, err);
}

/* The corner between the waiting element and nx: emit the waiting one up to
 * the corner, the elements queued after it, nx's lead into the corner, and
 * set where nx starts. */
static fm_status corner(gc_compc *c, gc_compc_item *nx, fm_error *err)
{
    gc_compc_item *pv = &c->prev;
    int s = c->side;
    pt p = at(nx->e.start), t1 = tangent(&pv->e, 1), t2 = tangent(&nx->e, 0);
    pt a1 = add(p, scale(normal(s, t1), pv->radius));
    pt a2 = add(p, scale(normal(s, t2), nx->radius));
    /* turn > 0 turns toward the tool: alpha = 180 degrees + turn */
    double turn = s * atan2(cross(t1, t2), dot(t1, t2));
    if (dot(t1, t2) < 0 && fabs(cross(t1, t2)) < 1e-12) {
        /* a reversal: the side nx bends to (the difference of the two
         * curvature vectors) decides; two lines are an outer corner */
        double bend = cross(t1, sub(curvature(nx, p), curvature(pv, p)));
        turn = fabs(bend) < 1e-12 ? -FM_PI : s * (bend > 0 ? FM_PI : -FM_PI);
    }
    pt end1, tail = a1, head[2] = {a2, a2};
    int ntail = 0, nhead = 0;
    if (fabs(turn) < TANGENT_TOL) {
        end1 = a1;
        nhead = 1;
    } else if (turn > 0) {
        if (!inner_point(pv, nx, s, p, &end1))
            return fm_error_at(err, FM_ERR_INPUT, nx->e.file, nx->e.line, nx->e.column,
                               "cutter compensation: the offset paths of this block and of "
                               "line %d do not meet in their inner corner (tool radius %g); "
                               "expected a smaller tool (Fanuc alarm 033)", pv->e.line,
                               nx->radius);
        head[0] = end1;
        nhead = 1;
    } else {
        pt x1, x2; /* the earlier path's last point, the later's first */
        if (turn >= -FM_PI / 2 - EPS) { /* 90 <= alpha < 180 */
            if (!line_line(a1, t1, a2, t2, &x1)) x1 = a1; /* not reached: |turn| <= 90 */
            x2 = x1;
        } else {
            x1 = add(a1, scale(t1, pv->radius));
            x2 = sub(a2, scale(t2, nx->radius));
        }
        if (is_arc(&pv->e)) {
            end1 = a1;
            tail = x1;
            ntail = 1;
        } else {
            end1 = x1;
        }
        head[0] = x2;
        nhead = is_arc(&nx->e) ? 2 : 1;
    }
    fm_status st = emit_plane(c, pv, end1, 1, err);
    if (!st && ntail) st = emit_corner(c, pv, tail, err);
    if (!st) st = flush_queue(c, err);
    for (int i = 0; i < nhead && !st; i++) st = emit_corner(c, nx, head[i], err);
    nx->from[0] = c->tool[0];
    nx->from[1] = c->tool[1];
    return st;
}

/* A plane element in offset mode: it closes the waiting element's corner
 * and waits for its own. */
static fm_status plane_on(gc_compc *c, gc_compc_item *nx, fm_error *err)
{
    fm_status st = FM_OK;
    pt a2 = offset_point(nx, c->side, 0);
    if (c->have_prev && c->prev_startup) {
        st = emit_plane(c, &c->prev, a2, 0, err);
        if (!st) st = flush_queue(c, err);
        nx->from[0] = a2.u;
        nx->from[1] = a2.v;
    } else if (c->have_prev) {
        st = corner(c, nx, err);
    } else { /* after the look-ahead ran out */
        st = emit_corner(c, nx, a2, err);
        nx->from[0] = a2.u;
        nx->from[1] = a2.v;
    }
    if (st) return st;
    copy_payload(c, 0, nx->e.payload);
    c->prev = *nx;
    c->prev.e.payload = slot(c, 0);
    c->have_prev = 1;
    c->prev_startup = 0;
    return FM_OK;
}

fm_status gc_compc_init(gc_compc *c, size_t payload_size, gc_compc_emit_fn emit_fn, void *ctx,
                        const double current[3], fm_error *err)
{
    memset(c, 0, sizeof *c);
    c->payloads = calloc(GC_COMPC_LOOKAHEAD + 2, payload_size ? payload_size : 1);
    if (!c->payloads)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory (cutter compensation)");
    c->payload_size = payload_size;
    c->emit = emit_fn;
    c->ctx = ctx;
    memcpy(c->prog, current, sizeof c->prog);
    memcpy(c->tool, current, sizeof c->tool);
    c->state = OFF;
    return FM_OK;
}

void gc_compc_free(gc_compc *c)
{
    free(c->payloads);
    c->payloads = NULL;
}

static fm_status check_radius(double radius, const char *file, int line, int column,
                              fm_error *err)
{
    if (radius > 0 && isfinite(radius)) return FM_OK;
    return fm_error_at(err, FM_ERR_INPUT, file, line, column,
                       "cutter compensation: tool radius %g; expected a radius > 0", radius);
}

fm_status gc_compc_start(gc_compc *c, gc_compc_side side, double radius, const char *file,
                         int line, int column, fm_error *err)
{
    if (c->state == ON || c->state == ARMED)
        return fm_error_at(err, FM_ERR_INPUT, file, line, column,
                           "cutter compensation is already on; expected G40 before G41/G42");
    fm_status st = check_radius(radius, file, line, column, err);
    if (st) return st;
    c->state = ARMED;
    c->side = side == GC_COMPC_RIGHT ? -1 : 1;
    c->radius = radius;
    return FM_OK;
}

fm_status gc_compc_set_radius(gc_compc *c, double radius, const char *file, int line,
                              int column, fm_error *err)
{
    fm_status st = check_radius(radius, file, line, column, err);
    if (!st) c->radius = radius;
    return st;
}

fm_status gc_compc_cancel(gc_compc *c, fm_error *err)
{
    if (c->state == ARMED) c->state = OFF;
    if (c->state != ON) return FM_OK;
    c->state = CANCELLING;
    return end_prev_perpendicular(c, err);
}

fm_status gc_compc_add(gc_compc *c, const gc_compc_elem *in, fm_error *err)
{
    gc_compc_item it;
    memset(&it, 0, sizeof it);
    it.e = *in;
    it.e.corner = 0;
    it.radius = c->radius;
    memcpy(it.e.start, c->prog, sizeof it.e.start);
    if (in->kind == GC_COMPC_OTHER) memcpy(it.e.end, c->prog, sizeof it.e.end);
    int plane = in->kind == GC_COMPC_ARC || len(sub(at(it.e.end), at(it.e.start))) > EPS;
    if (is_arc(in) && (in->turn == 0 || len(sub(at(in->end), at(in->center))) <= EPS ||
                       len(sub(at(it.e.start), at(in->center))) <= EPS))
        return fm_error_at(err, FM_ERR_INPUT, in->file, in->line, in->column,
                           "cutter compensation: an arc without a radius or a direction");
    if (c->state == ON && is_arc(in) &&
        fmin(offset_arc_radius(&it, c->side, 0), offset_arc_radius(&it, c->side, 1)) <= EPS)
        return fm_error_at(err, FM_ERR_INPUT, in->file, in->line, in->column,
                           "cutter compensation: the tool (radius %g) is inside an arc of "
                           "radius %g, no larger than it; expected a smaller tool or a larger "
                           "arc (Fanuc alarm 041, interference)", c->radius,
                           len(sub(at(in->end), at(in->center))));
    if ((c->state == ARMED || c->state == CANCELLING) && plane && is_arc(in))
        return fm_error_at(err, FM_ERR_INPUT, in->file, in->line, in->column,
                           "cutter compensation: an arc cannot %s compensation; expected a "
                           "G00 or G01 move (Fanuc alarm 034)",
                           c->state == ARMED ? "start" : "cancel");
    memcpy(c->prog, it.e.end, sizeof c->prog);
    int incoming = GC_COMPC_LOOKAHEAD + 1;
    copy_payload(c, incoming, in->payload);
    it.e.payload = slot(c, incoming);

    if (!plane) {
        if (c->state != ON || !c->have_prev) return emit_still(c, &it, err);
        if (c->nq == GC_COMPC_LOOKAHEAD) {
            fm_status st = end_prev_perpendicular(c, err);
            return st ? st : emit_still(c, &it, err);
        }
        copy_payload(c, 1 + c->nq, slot(c, incoming));
        it.e.payload = slot(c, 1 + c->nq);
        c->queue[c->nq++] = it;
        return FM_OK;
    }
    switch (c->state) {
    case ARMED: /* the start-up block: waits for the next direction */
        copy_payload(c, 0, slot(c, incoming));
        c->prev = it;
        c->prev.e.payload = slot(c, 0);
        c->prev.from[0] = c->tool[0];
        c->prev.from[1] = c->tool[1];
        c->have_prev = 1;
        c->prev_startup = 1;
        c->state = ON;
        return FM_OK;
    case ON:
        return plane_on(c, &it, err);
    case CANCELLING: /* the cancel block: to its programmed end */
        c->state = OFF;
        /* fall through */
    default:
        it.from[0] = c->tool[0];
        it.from[1] = c->tool[1];
        return emit_plane(c, &it, at(it.e.end), 0, err);
    }
}

fm_status gc_compc_finish(gc_compc *c, fm_error *err)
{
    fm_status st = end_prev_perpendicular(c, err);
    if (!st) st = flush_queue(c, err);
    c->state = OFF;
    return st;
}

int gc_compc_active(const gc_compc *c) { return c->state == ARMED || c->state == ON; }

void gc_compc_programmed_point(const gc_compc *c, double out[3])
{
    memcpy(out, c->prog, sizeof c->prog);
}

int gc_compc_idle(const gc_compc *c) { return c->state == OFF; }
