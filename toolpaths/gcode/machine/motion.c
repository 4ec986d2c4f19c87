/* motion.c: motions: straight lines, arcs and helices (IJK and R
 * centres, LinuxCNC's tolerances), dwells, and the canned cycles G73 and
 * G81-G89 with LinuxCNC's rules for R, the initial level, G98/G99, L
 * repeats and G91. Each motion is converted from program units and
 * coordinates to machine millimetres and handed to the sink (emit). */
#include "machine.h"

#include "sweep/sweep.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* LinuxCNC's canon: machine = G5x + R(rotation) (p + G92), the rotation
 * (G10 L2 R) turning X and Y about the coordinate system's origin. */
void gc_to_machine(const gc_interp *g, const double p[3], double out[3])
{
    double x = p[0] + g->g92[0], y = p[1] + g->g92[1];
    if (g->rotation != 0) {
        double t = g->rotation * FM_PI / 180.0, c = cos(t), s = sin(t);
        double xr = x * c - y * s;
        y = x * s + y * c;
        x = xr;
    }
    out[0] = (x + g->g5x[0]) * g->unit;
    out[1] = (y + g->g5x[1]) * g->unit;
    out[2] = (p[2] + g->g92[2] + g->g5x[2]) * g->unit;
}

void gc_from_machine(const gc_interp *g, const double m[3], double p[3])
{
    double x = m[0] / g->unit - g->g5x[0], y = m[1] / g->unit - g->g5x[1];
    if (g->rotation != 0) {
        double t = -g->rotation * FM_PI / 180.0, c = cos(t), s = sin(t);
        double xr = x * c - y * s;
        y = x * s + y * c;
        x = xr;
    }
    p[0] = x - g->g92[0];
    p[1] = y - g->g92[1];
    p[2] = m[2] / g->unit - g->g5x[2] - g->g92[2];
}

#define to_machine gc_to_machine

/* Motions start where the last one ended (g->mpos): after G40 the program's
 * current point is the programmed one while the tool is still where the
 * compensated path left it. */
fm_status gc_emit_motion(gc_interp *g, fm_motion *m, double seconds)
{
    m->axis_start[0] = m->axis_start[1] = 0;
    m->axis_start[2] = 1;
    memcpy(m->axis_end, m->axis_start, sizeof m->axis_end);
    for (int i = 0; i < 3; i++) m->tip_offset[i] = g->tlo[i] * g->unit;
    m->tip_offset[2] -= gc_tool_length_mm(g, g->tool);
    m->spindle_rpm = g->spindle_dir ? g->speed : 0.0;
    m->spindle_dir = g->spindle_dir;
    m->coolant = g->coolant;
    m->tool = g->tool;
    m->path_mode = g->exact_stop_block ? FM_PATH_EXACT_STOP : g->path_mode;
    m->path_tolerance = g->path_tolerance;
    m->naive_tolerance = g->naive_tolerance;
    m->t0 = g->t;
    m->t1 = g->t + seconds;
    g->t = m->t1;
    m->line = g->lineno;
    m->block = g->cur_block;
    m->index = g->motion_index++;
    memcpy(g->mpos, m->end, sizeof g->mpos);
    memcpy(g->canon, m->end, sizeof g->canon);
    gc_rot_emit(g, m);
    if (m->index >= g->opt.skip_motions && g->sink && g->sink(g->user, m)) g->stop = 1;
    return FM_OK;
}

fm_status gc_check_feed(gc_interp *g, const char *what, int col)
{
    if (g->feed <= 0)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: feed rate is zero; expected an F word > 0 before or in this block",
                       what);
    /* per revolution, the feed rate is F x S: a stopped spindle would not move */
    if (g->per_rev && (g->spindle_dir == 0 || !(g->speed > 0)))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: feed per revolution (G95) with the spindle %s; expected M03/M04 "
                       "with S > 0 before this block, or G94", what,
                       g->spindle_dir == 0 ? "stopped" : "at S0");
    return FM_OK;
}

/* The modal feed in program units per minute (G94, G95; not G93). */
static double feed_per_minute(const gc_interp *g)
{
    return g->per_rev ? g->feed * g->speed : g->feed;
}

double gc_feed_seconds(gc_interp *g, double len_mm, double *feed_mm)
{
    if (g->inverse_time) {
        double sec = 60.0 / g->feed;
        *feed_mm = sec > 0 ? len_mm / sec * 60.0 : 0;
        return sec;
    }
    *feed_mm = feed_per_minute(g) * g->unit;
    return len_mm / *feed_mm * 60.0;
}

fm_status gc_move_line(gc_interp *g, int rapid, const double to[3])
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = rapid ? FM_MOTION_RAPID : FM_MOTION_LINE;
    memcpy(m.start, g->mpos, sizeof m.start);
    to_machine(g, to, m.end);
    double len = sqrt((m.end[0] - m.start[0]) * (m.end[0] - m.start[0]) +
                      (m.end[1] - m.start[1]) * (m.end[1] - m.start[1]) +
                      (m.end[2] - m.start[2]) * (m.end[2] - m.start[2]));
    double sec, turn = gc_rot_degrees(g);
    if (rapid) {
        /* rotary axes at the same rate in degrees per minute, coordinated */
        sec = fmax(len, turn) / g->opt.rapid_rate * 60.0;
    } else if (len == 0 && turn > 0 && !g->inverse_time) {
        /* only rotary axes move: F is degrees per minute (LinuxCNC) */
        m.feed = feed_per_minute(g);
        sec = turn / m.feed * 60.0;
    } else {
        sec = gc_feed_seconds(g, len, &m.feed);
    }
    memcpy(g->pos, to, sizeof g->pos);
    return gc_emit_motion(g, &m, sec);
}

fm_status gc_dwell(gc_interp *g, double seconds)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_DWELL;
    memcpy(m.start, g->mpos, sizeof m.start);
    memcpy(m.end, m.start, sizeof m.end);
    return gc_emit_motion(g, &m, seconds > 0 ? seconds : 0);
}

/* Plane axes: first and second in-plane axis and the normal, in LinuxCNC's
 * order (G18's first axis is Z), so that ARC_FEED's rotation sign is the
 * counter-clockwise sense about +normal. */
void gc_plane_axes(gc_plane plane, int *a, int *b, int *c)
{
    if (plane == GC_PLANE_XZ) { *a = 2; *b = 0; *c = 1; }
    else if (plane == GC_PLANE_YZ) { *a = 1; *b = 2; *c = 0; }
    else { *a = 0; *b = 1; *c = 2; }
}

fm_status gc_move_arc(gc_interp *g, const double to[3], const double center_ab[2], int turns)
{
    int a, b, c;
    gc_plane_axes(g->plane, &a, &b, &c);
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_ARC;
    double cen[3];
    cen[a] = center_ab[0];
    cen[b] = center_ab[1];
    cen[c] = g->pos[c];
    memcpy(m.start, g->mpos, sizeof m.start);
    to_machine(g, to, m.end);
    to_machine(g, cen, m.center);
    m.center[c] = m.start[c];
    m.plane_axis = c;
    m.turns = turns;
    /* the arc's angle and length as lib/sweep runs it (one definition of an
     * arc: the sweep, the check and the pictures read the same motion) */
    fm_motion_arc arc;
    double len;
    if (fm_motion_arc_of(&m, &arc)) {
        double r1 = arc.r0 + arc.dr;
        len = hypot(0.5 * (arc.r0 + r1) * arc.dth, arc.dh);
    } else {
        /* a centre on the start point: no circle; the time of the chord */
        len = hypot(hypot(m.end[0] - m.start[0], m.end[1] - m.start[1]), m.end[2] - m.start[2]);
    }
    double sec = gc_feed_seconds(g, len, &m.feed);
    memcpy(g->pos, to, sizeof g->pos);
    return gc_emit_motion(g, &m, sec);
}

/* The end point of a motion block in program coordinates (LinuxCNC's
 * find_ends): absolute or incremental from the current point (the
 * programmed point while compensating), machine coordinates with G53, and
 * polar coordinates (@ radius, ^ angle, about the program origin, G17). */
fm_status gc_find_ends(gc_interp *g, const gc_block *b, int g53, double end[3])
{
    const char ax[3] = {'x', 'y', 'z'};
    fm_status rst = gc_rot_find_ends(g, b, g53); /* A B C */
    if (rst) return rst;
    int polar = b->has_radius || b->has_theta;
    if (g53) {
        if (polar)
            return gc_fail(g, FM_ERR_INPUT, b->has_radius ? b->radius_col : b->theta_col,
                           "polar coordinates with G53; expected X, Y, Z machine coordinates");
        double m[3], cur[3];
        gc_to_machine(g, g->pos, m);
        for (int i = 0; i < 3; i++) {
            cur[i] = m[i] / g->unit;
            if (b->has[L(ax[i])]) cur[i] = b->v[L(ax[i])] - g->tlo[i];
            cur[i] *= g->unit;
        }
        gc_from_machine(g, cur, end);
        return FM_OK;
    }
    double base[3];
    gc_comp_base(g, base);
    for (int i = 0; i < 3; i++) {
        if (!b->has[L(ax[i])]) end[i] = base[i];
        else if (g->absolute) end[i] = b->v[L(ax[i])];
        else end[i] = base[i] + b->v[L(ax[i])];
    }
    if (!polar) return FM_OK;
    double x = end[0], y = end[1];
    int col = b->has_radius ? b->radius_col : b->theta_col;
    if (g->absolute) {
        if (b->has_radius && b->has_theta) {
            x = b->radius * cos(b->theta * FM_PI / 180.0);
            y = b->radius * sin(b->theta * FM_PI / 180.0);
        } else if (b->has_radius) {
            if (x == 0 && y == 0)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "@ without ^ at the origin; expected an angle ^ there");
            double th = atan2(y, x);
            x = b->radius * cos(th);
            y = b->radius * sin(th);
        } else {
            double r = hypot(x, y);
            x = r * cos(b->theta * FM_PI / 180.0);
            y = r * sin(b->theta * FM_PI / 180.0);
        }
    } else {
        if (x == 0 && y == 0)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "incremental polar motion (G91 %c) at the origin is indeterminate; "
                           "expected a move away from the origin first", b->has_radius ? '@' : '^');
        if (b->has_radius) {
            double th = atan2(y, x), r = hypot(x, y) + b->radius;
            x = r * cos(th);
            y = r * sin(th);
        }
        if (b->has_theta) {
            double th = atan2(y, x) + b->theta * FM_PI / 180.0, r = hypot(x, y);
            x = r * cos(th);
            y = r * sin(th);
        }
    }
    end[0] = x;
    end[1] = y;
    return FM_OK;
}

/* The centre of an arc block starting at `start` (program coordinates),
 * with LinuxCNC's tolerances (arc_data_r, arc_data_ijk). */
void gc_arc_words_of(const gc_block *b, gc_arc_words *w)
{
    w->has_r = HAS(b, 'r');
    w->r = VAL(b, 'r');
    w->r_col = COL(b, 'r');
    for (int i = 0; i < 3; i++) {
        w->has[i] = HAS(b, "ijk"[i]);
        w->v[i] = VAL(b, "ijk"[i]);
        w->col[i] = COL(b, "ijk"[i]);
    }
}

fm_status gc_arc_center(gc_interp *g, int iso, int code, const gc_arc_words *w,
                        const double start[3], const double end[3], double cab[2], int *no_arc,
                        int col)
{
    char name[32];
    gc_g_name(code, name, sizeof name);
    int a, bb, c;
    gc_plane_axes(g->plane, &a, &bb, &c);
    char oa = "ijk"[a], ob = "ijk"[bb], oc = "ijk"[c];
    double ca, cb;
    double tol = g->unit == 1.0 ? 0.005 : 0.0005; /* LinuxCNC's TOLERANCE_MM / _INCH */
    *no_arc = 0;
    if (w->has_r) {
        /* R wins over I J K */
        double radius = w->r, ar = fabs(radius), half;
        double mid_a = (end[a] + start[a]) / 2.0, mid_b = (end[bb] + start[bb]) / 2.0;
        if (iso) {
            double chord = hypot(end[a] - start[a], end[bb] - start[bb]);
            /* Fanuc: a full circle cannot be given with R; start = end is
             * an arc of 0 degrees and the tool does not move in the plane */
            if (chord <= 1e-9 * (1 + ar)) {
                *no_arc = 1;
                return FM_OK;
            }
            half = chord / 2;
        } else {
            if (end[a] == start[a] && end[bb] == start[bb])
                return gc_fail(g, FM_ERR_INPUT, w->r_col,
                               "%s R: the end point equals the start point; a full circle needs "
                               "the centre (I J K), not R", name);
            half = hypot(mid_a - end[a], mid_b - end[bb]);
        }
        if (ar == 0 || half - ar > tol)
            return gc_fail(g, FM_ERR_INPUT, w->r_col,
                           "%s R%g: radius too small to reach the end point; expected |R| >= %.6g",
                           name, radius, half);
        /* a semicircle within rounding */
        if (iso ? half > ar : half / ar > 1 - 1e-12) half = ar;
        /* positive R: the arc of at most 180 degrees; negative: the longer one */
        double theta;
        if ((code == GC_G2 && radius > 0) || (code == GC_G3 && radius < 0))
            theta = atan2(end[bb] - start[bb], end[a] - start[a]) - FM_PI / 2;
        else
            theta = atan2(end[bb] - start[bb], end[a] - start[a]) + FM_PI / 2;
        double off = iso ? sqrt(ar * ar - half * half) : ar * cos(asin(half / ar));
        ca = mid_a + off * cos(theta);
        cb = mid_b + off * sin(theta);
    } else {
        if (w->has[c])
            return gc_fail(g, FM_ERR_INPUT, w->col[c],
                           "%s: %c word in the G%d plane; expected %c and %c for the centre",
                           name, oc - 32, g->plane, oa - 32, ob - 32);
        if (!w->has[a] && !w->has[bb])
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s: no centre; expected %c and/or %c (or R) in the G%d plane", name,
                           oa - 32, ob - 32, g->plane);
        if (g->arc_absolute && !iso) {
            ca = w->has[a] ? w->v[a] : start[a];
            cb = w->has[bb] ? w->v[bb] : start[bb];
        } else {
            /* I J K from the start point (ISO: in G90 and G91 alike) */
            ca = start[a] + (w->has[a] ? w->v[a] : 0);
            cb = start[bb] + (w->has[bb] ? w->v[bb] : 0);
        }
        double r0 = hypot(ca - start[a], cb - start[bb]);
        double r1 = hypot(ca - end[a], cb - end[bb]);
        if (iso && r0 < tol / 10)
            return gc_fail(g, FM_ERR_INPUT, col, "%s: zero-radius arc (centre on the start point)",
                           name);
        if (!iso && (r0 < tol / 10 || r1 < tol / 10))
            return gc_fail(g, FM_ERR_INPUT, col, "%s: zero-radius arc (centre on an end point)",
                           name);
        double abs_err = fabs(r0 - r1);
        if (abs_err > tol * 20 || (abs_err > tol && abs_err / fmax(r0, r1) > 0.001))
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s: radius to the end point (%.6g) differs from the radius to the "
                           "start point (%.6g); expected the same circle", name, r1, r0);
    }
    cab[0] = ca;
    cab[1] = cb;
    return FM_OK;
}

double gc_arc_sweep(gc_plane plane, const double start[3], const double end[3],
                    const double center_ab[2], int turn)
{
    int a, b, c;
    gc_plane_axes(plane, &a, &b, &c);
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_ARC;
    memcpy(m.start, start, sizeof m.start);
    memcpy(m.end, end, sizeof m.end);
    m.center[a] = center_ab[0];
    m.center[b] = center_ab[1];
    m.center[c] = start[c];
    m.plane_axis = c;
    m.turns = turn;
    fm_motion_arc arc;
    if (turn == 0 || !fm_motion_arc_of(&m, &arc)) return 0;
    return arc.dth;
}

/* The feed a compensated motion keeps while queued: program units per
 * minute; in inverse time, the programmed length over the block's time. */
double gc_queued_feed(const gc_interp *g, double programmed_len)
{
    return g->inverse_time ? g->feed * programmed_len : feed_per_minute(g);
}

fm_status gc_exec_arc(gc_interp *g, const gc_block *b, int code, int col)
{
    char name[32];
    gc_g_name(code, name, sizeof name);
    int a, bb, c;
    gc_plane_axes(g->plane, &a, &bb, &c);
    static const char offl[3] = {'i', 'j', 'k'};
    if (!HAS(b, 'r') && !HAS(b, offl[a]) && !HAS(b, offl[bb]) && !HAS(b, offl[c]))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: no centre and no radius; expected I, J, K or R", name);
    if (g->comp.arc_not_allowed)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s just after G40; expected a straight move to end cutter compensation",
                       name);
    if (g->rotation != 0 && g->plane != GC_PLANE_XY)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s in the G%d plane of a rotated coordinate system (G10 L2 R%g); "
                       "expected G17 there", name, (int)g->plane, g->rotation);
    fm_status st = gc_check_feed(g, name, col);
    if (st) return st;
    int turns = 1;
    if (HAS(b, 'p')) {
        double p = VAL(b, 'p');
        if (p < 1 || floor(p) != p || p > 1e6)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'),
                           "%s P%g: expected a whole number of turns >= 1", name, p);
        turns = (int)p;
    }
    /* an arc without end point words is a full circle (LinuxCNC 2.9) */
    double end[3];
    if ((st = gc_find_ends(g, b, 0, end))) return st;
    double start[3];
    gc_comp_base(g, start);
    if (gc_comp_active(g) && g->comp.firstmove) memcpy(start, g->pos, sizeof start);
    int inside = (g->comp.side == GC_COMP_LEFT && code == GC_G3) ||
                 (g->comp.side == GC_COMP_RIGHT && code == GC_G2);
    /* LinuxCNC checks an entry arc's R against the tool before the arc itself */
    if (gc_comp_active(g) && g->comp.firstmove && HAS(b, 'r') && inside &&
        fabs(VAL(b, 'r')) < g->comp.radius)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: the tool radius %.4f is larger than the radius %.4f of this inside "
                       "arc; expected a smaller tool", name, g->comp.radius, fabs(VAL(b, 'r')));
    double cab[2];
    gc_arc_words aw;
    int no_arc;
    gc_arc_words_of(b, &aw);
    if ((st = gc_arc_center(g, 0, code, &aw, start, end, cab, &no_arc, col))) return st;
    int turn = code == GC_G2 ? -turns : turns;
    if (!gc_comp_active(g)) return gc_move_arc(g, end, cab, turn);
    /* compensating: the programmed arc, in the compensation plane */
    gc_arc_data arc;
    gc_comp_to_plane(g->plane, end, arc.end);
    arc.center[0] = cab[0];
    arc.center[1] = cab[1];
    arc.turn = turn;
    double arc_r = hypot(cab[0] - start[a], cab[1] - start[bb]);
    if (g->comp.firstmove && arc_r < g->comp.radius && inside)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: the tool radius %.4f is larger than the radius %.4f of this "
                       "inside arc; expected a smaller tool", name, g->comp.radius, arc_r);
    double sweep = fabs(gc_arc_sweep(g->plane, start, end, cab, turn));
    return gc_comp_arc(g, &arc, gc_queued_feed(g, arc_r * sweep), col);
}

fm_status gc_exec_straight(gc_interp *g, const gc_block *b, int rapid, int g53, int col)
{
    double end[3];
    fm_status st = gc_find_ends(g, b, g53, end);
    if (st) return st;
    if (gc_comp_active(g)) {
        if (g53)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G53 with cutter radius compensation on; expected G40 first");
        double base[3];
        gc_comp_base(g, base);
        double len = sqrt((end[0] - base[0]) * (end[0] - base[0]) +
                          (end[1] - base[1]) * (end[1] - base[1]) +
                          (end[2] - base[2]) * (end[2] - base[2]));
        return gc_comp_straight(g, rapid, rapid ? 0 : gc_queued_feed(g, len), end, col);
    }
    g->comp.arc_not_allowed = 0;
    return gc_move_line(g, rapid, end);
}

fm_status gc_emit_queued(gc_interp *g, const gc_comp_snap *snap, gc_comp_kind kind,
                         const double xyz[3], const double center_ab[2], int turn, double seconds)
{
    /* the motion carries the state it was programmed with */
    double feed = g->feed, speed = g->speed;
    int inverse = g->inverse_time, per_rev = g->per_rev, dir = g->spindle_dir;
    int coolant = g->coolant;
    int lineno = g->lineno;
    long block = g->cur_block;
    g->feed = snap->feed; /* per minute (gc_queued_feed) */
    g->inverse_time = 0;
    g->per_rev = 0;
    g->speed = snap->speed;
    g->spindle_dir = snap->spindle_dir;
    g->coolant = snap->coolant;
    g->lineno = snap->line;
    g->cur_block = snap->block;
    fm_status st;
    switch (kind) {
    case GC_COMP_RAPID: st = gc_move_line(g, 1, xyz); break;
    case GC_COMP_LINE: st = gc_move_line(g, 0, xyz); break;
    case GC_COMP_ARC: st = gc_move_arc(g, xyz, center_ab, turn); break;
    default: st = gc_dwell(g, seconds); break;
    }
    g->feed = feed;
    g->inverse_time = inverse;
    g->per_rev = per_rev;
    g->speed = speed;
    g->spindle_dir = dir;
    g->coolant = coolant;
    g->lineno = lineno;
    g->cur_block = block;
    return st;
}

fm_status gc_emit_comp_move(gc_interp *g, const gc_comp_move *m)
{
    double xyz[3];
    gc_comp_from_plane(g->plane, m->end, xyz);
    return gc_emit_queued(g, &m->snap, m->kind, xyz, m->center, m->turn, m->seconds);
}

/* Canned cycles: LinuxCNC's convert_cycle_xy/yz/zx with aa, bb in the plane
 * and cc along its normal. */
typedef struct gc_cyc {
    int a, b, c;
} gc_cyc;

static fm_status cyc_move(gc_interp *g, const gc_cyc *k, int rapid, double aa, double bb, double cc)
{
    double to[3];
    to[k->a] = aa;
    to[k->b] = bb;
    to[k->c] = cc;
    return gc_move_line(g, rapid, to);
}

void gc_set_path_mode(gc_interp *g, fm_path_mode mode, double tolerance_mm, double naive_mm)
{
    g->path_mode = mode;
    g->path_tolerance = tolerance_mm > 0 ? tolerance_mm : 0;
    g->naive_tolerance = naive_mm > 0 ? naive_mm : 0;
}

/* rs274 runs a canned cycle in exact path mode (G61) and restores the mode
 * after it (convert_cycle): the cycle's corners are stops. */
static fm_status exec_cycle_moves(gc_interp *g, const gc_block *b, int code, int col);

fm_status gc_exec_cycle(gc_interp *g, const gc_block *b, int code, int col)
{
    fm_path_mode mode = g->path_mode;
    double tol = g->path_tolerance, naive = g->naive_tolerance;
    if (mode != FM_PATH_EXACT_PATH) gc_set_path_mode(g, FM_PATH_EXACT_PATH, 0, 0);
    fm_status st = exec_cycle_moves(g, b, code, col);
    gc_set_path_mode(g, mode, tol, naive);
    return st;
}

static fm_status exec_cycle_moves(gc_interp *g, const gc_block *b, int code, int col)
{
    char name[32];
    gc_g_name(code, name, sizeof name);
    if (g->feed <= 0) return gc_check_feed(g, name, col);
    if (g->inverse_time)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: canned cycles need G94, not inverse time G93",
                       name);
    double r_word;
    if (HAS(b, 'r')) r_word = VAL(b, 'r');
    else if (g->motion == code) r_word = g->cycle_r;
    else
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: R clearance plane unspecified; expected an R word", name);
    long reps = 1;
    if (HAS(b, 'l')) {
        double l = VAL(b, 'l');
        if (l < 1 || floor(l) != l || l > 1e6)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                           "%s L%g: expected a whole number of repeats >= 1", name, l);
        reps = (long)l;
    }
    gc_cyc k;
    gc_plane_axes(g->plane, &k.a, &k.b, &k.c);
    static const char axl[3] = {'x', 'y', 'z'};
    char la = axl[k.a], lb = axl[k.b], lc = axl[k.c];
    if (g->motion != code && !HAS(b, lc))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: %c value unspecified; expected %c on the first block of a cycle",
                       name, lc - 32, lc - 32);
    double c_word = HAS(b, lc) ? VAL(b, lc) : g->cycle_cc;
    double current_cc = g->pos[k.c], old_cc;
    if (g->cycle_il_flag) {
        old_cc = g->cycle_il;
    } else {
        old_cc = g->cycle_il = current_cc;
        g->cycle_il_flag = 1;
    }
    double aa, bb, aa_inc = 0, bb_inc = 0, r, cc, radius_inc = 0, theta_inc = 0;
    if (g->absolute) {
        r = r_word;
        cc = c_word;
        aa = HAS(b, la) ? VAL(b, la) : g->pos[k.a];
        bb = HAS(b, lb) ? VAL(b, lb) : g->pos[k.b];
        if (b->has_radius || b->has_theta) {
            /* polar (G17 only): about the program origin */
            double rad = b->has_radius ? b->radius : hypot(g->pos[1], g->pos[0]);
            double th = b->has_theta ? b->theta * FM_PI / 180.0 : atan2(g->pos[1], g->pos[0]);
            aa = rad * cos(th);
            bb = rad * sin(th);
        }
    } else {
        if (HAS(b, la)) aa_inc = VAL(b, la);
        if (HAS(b, lb)) bb_inc = VAL(b, lb);
        if (b->has_radius) radius_inc = b->radius;
        if (b->has_theta) theta_inc = b->theta * FM_PI / 180.0;
        r = r_word + old_cc;
        cc = r + c_word;
        aa = g->pos[k.a];
        bb = g->pos[k.b];
    }
    if (r < cc)
        return gc_fail(g, FM_ERR_INPUT, HAS(b, 'r') ? COL(b, 'r') : col,
                       "%s: R (%g) below the bottom %c (%g); expected R above the hole", name, r,
                       lc - 32, cc);
    /* check the words the cycle needs before moving */
    double p = -1, q = -1, ci = 0, cj = 0, ck = 0;
    if (HAS(b, 'p')) p = VAL(b, 'p');
    if (HAS(b, 'q')) q = VAL(b, 'q');
    switch (code) {
    case GC_G82: case GC_G86: case GC_G88: case GC_G89:
        if (p < 0 && g->motion != code)
            return gc_fail(g, FM_ERR_INPUT, col, "%s: dwell time P missing; expected P seconds",
                           name);
        if (p < 0) p = g->cycle_p;
        break;
    case GC_G73: case GC_G83:
        if (q < 0 && g->motion != code)
            return gc_fail(g, FM_ERR_INPUT, col, "%s: peck depth Q missing; expected Q > 0", name);
        if (q < 0) q = g->cycle_q;
        if (q <= 0)
            return gc_fail(g, FM_ERR_INPUT, HAS(b, 'q') ? COL(b, 'q') : col,
                           "%s: Q%g; expected a peck depth Q > 0", name, q);
        break;
    case GC_G87:
        if (g->motion != code) {
            const char *ijk = "ijk";
            for (int i = 0; i < 3; i++)
                if (!b->has[L(ijk[i])])
                    return gc_fail(g, FM_ERR_INPUT, col, "%s: %c missing; expected I, J and K",
                                   name, ijk[i] - 32);
        }
        {
            double ijk[3];
            ijk[0] = HAS(b, 'i') ? VAL(b, 'i') : g->cycle_i;
            ijk[1] = HAS(b, 'j') ? VAL(b, 'j') : g->cycle_j;
            ijk[2] = HAS(b, 'k') ? VAL(b, 'k') : g->cycle_k;
            g->cycle_i = ijk[0];
            g->cycle_j = ijk[1];
            g->cycle_k = ijk[2];
            /* the offset words along the plane's axes, the height word
             * along its normal (G18: K, I and J; G19: J, K and I) */
            ci = ijk[k.a];
            cj = ijk[k.b];
            ck = ijk[k.c];
        }
        if (!g->absolute) ck = cc + ck;
        break;
    default: break;
    }
    if (code == GC_G84 && g->spindle_dir != 1)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G84: spindle not turning clockwise; expected M3 before a right-hand tap");
    if (code == GC_G84 && p < 0) p = g->cycle_p;
    if ((code == GC_G86 || code == GC_G87 || code == GC_G88) && !g->spindle_dir)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: spindle not turning; expected M3 or M4 first",
                       name);
    fm_status st;
    if (old_cc < r) {
        double to[3] = {g->pos[0], g->pos[1], g->pos[2]};
        to[k.c] = r;
        if ((st = gc_move_line(g, 1, to))) return st;
        old_cc = r;
        current_cc = old_cc;
    }
    double clear = g->retract_r ? r : old_cc;
    /* G83's small rapid back into the hole: 0.010 inch in either unit system */
    double delta = g->unit == 1.0 ? 0.010 * GC_INCH : 0.010;
    for (long rep = reps; rep > 0 && !g->stop; rep--) {
        if (radius_inc != 0 || theta_inc != 0) {
            /* G91 polar: each repeat steps the radius and angle about the origin */
            double rad = hypot(bb, aa) + radius_inc, th = atan2(bb, aa) + theta_inc;
            aa = rad * cos(th);
            bb = rad * sin(th);
        } else {
            aa += aa_inc;
            bb += bb_inc;
        }
        if (rep == reps && current_cc > r) {
            if ((st = cyc_move(g, &k, 1, aa, bb, current_cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa, bb, r))) return st;
        } else {
            if ((st = cyc_move(g, &k, 1, aa, bb, clear))) return st;
            if (clear > r && (st = cyc_move(g, &k, 1, aa, bb, r))) return st;
        }
        switch (code) {
        case GC_G81:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case GC_G82:
        case GC_G89:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = gc_dwell(g, p))) return st;
            st = cyc_move(g, &k, code == GC_G82, aa, bb, clear);
            break;
        case GC_G73:
        case GC_G83: {
            long pecks = 0;
            for (double d = r - q; d > cc; d -= q) {
                if (++pecks > 1000000)
                    return gc_fail(g, FM_ERR_LIMIT, col, "%s: more than 10^6 pecks", name);
                if ((st = cyc_move(g, &k, 0, aa, bb, d))) return st;
                if (code == GC_G83 && (st = cyc_move(g, &k, 1, aa, bb, r))) return st;
                if ((st = cyc_move(g, &k, 1, aa, bb, d + delta))) return st;
            }
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        }
        case GC_G84:
            /* floating tap: feed in, reverse (dwell P), feed out to the clear plane */
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = gc_dwell(g, p))) return st;
            st = cyc_move(g, &k, 0, aa, bb, clear);
            break;
        case GC_G85:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = cyc_move(g, &k, 0, aa, bb, r))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case GC_G86:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = gc_dwell(g, p))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case GC_G87:
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, r))) return st;
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa, bb, cc))) return st;
            if ((st = cyc_move(g, &k, 0, aa, bb, ck))) return st;
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, clear))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case GC_G88:
            /* the operator retracts by hand at LinuxCNC's program stop */
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            st = gc_dwell(g, p);
            break;
        default: st = FM_OK;
        }
        if (st) return st;
    }
    g->pos[k.a] = aa;
    g->pos[k.b] = bb;
    g->pos[k.c] = clear;
    g->cycle_cc = c_word;
    g->cycle_r = r_word;
    if (p >= 0) g->cycle_p = p;
    if (q > 0) g->cycle_q = q;
    g->motion = (gc_gcode)code;
    return FM_OK;
}

