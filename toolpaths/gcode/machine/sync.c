/* sync.c: motions whose speed or end come from outside the program:
 * G33 (spindle-synchronized feed: K is the distance per spindle turn) and
 * G33.1 (rigid tapping: in at that pitch, then out to the start), fed at
 * the feed the spindle speed and pitch give; and G38.2-G38.5 probing, where
 * the move ends where the probe trips, as the caller's probe callback finds
 * it (the runner: first contact with the stock), setting #5061-#5063 and
 * #5070 as LinuxCNC does. */
#include "machine.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PARAM_PROBE_X 5061
#define PARAM_PROBE_OK 5070

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* A feed line in machine mm taking `seconds`, spindle direction dir. */
static fm_status sync_line(gc_interp *g, const double to[3], double seconds, int dir)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_LINE;
    memcpy(m.start, g->mpos, sizeof m.start);
    gc_to_machine(g, to, m.end);
    double len = dist3(m.start, m.end);
    m.feed = seconds > 0 ? len / seconds * 60.0 : 0;
    int saved = g->spindle_dir;
    g->spindle_dir = dir;
    memcpy(g->pos, to, sizeof g->pos);
    fm_status st = gc_emit_motion(g, &m, seconds);
    g->spindle_dir = saved;
    return st;
}

fm_status gc_exec_sync(gc_interp *g, const gc_block *b, int code, int col)
{
    char name[16];
    gc_g_name(code, name, sizeof name);
    if (!HAS(b, 'k'))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: K word missing; expected K, the distance per spindle revolution", name);
    double k = VAL(b, 'k');
    if (!(k > 0))
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'k'), "%s K%g: expected a pitch K > 0", name, k);
    if (g->spindle_dir == 0 || g->speed <= 0)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: spindle not turning; expected M3 or M4 with S > 0 first", name);
    double end[3], start[3];
    memcpy(start, g->pos, sizeof start);
    fm_status st = gc_find_ends(g, b, 0, end);
    if (st) return st;
    /* K is the advance along Z per turn; a move with no Z advances K along
     * its path per turn */
    double dz = fabs(end[2] - start[2]);
    double along = dz > 0 ? dz : dist3(start, end);
    double seconds = along / (k * g->speed) * 60.0;
    if ((st = sync_line(g, end, seconds, g->spindle_dir))) return st;
    if (code == GC_G33_1) {
        /* the spindle reverses and the tap comes out the way it went in */
        st = sync_line(g, start, seconds, -g->spindle_dir);
    }
    return st;
}

fm_status gc_exec_probe(gc_interp *g, const gc_block *b, int code, int col)
{
    char name[16];
    gc_g_name(code, name, sizeof name);
    if (g->inverse_time)
        return gc_fail(g, FM_ERR_INPUT, col, "%s in inverse time (G93); expected G94 for probing",
                       name);
    if (g->feed <= 0)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s with a zero feed rate; expected an F word > 0 before or in this block",
                       name);
    double end[3];
    fm_status st = gc_find_ends(g, b, 0, end);
    if (st) return st;
    if (dist3(end, g->pos) < 1e-7)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: the probe target is the current point; expected a target away from "
                       "it", name);
    int toward = code == GC_G38_2 || code == GC_G38_3;
    int must_trip = code == GC_G38_2 || code == GC_G38_4;
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_LINE;
    memcpy(m.start, g->mpos, sizeof m.start);
    gc_to_machine(g, end, m.end);
    for (int i = 0; i < 3; i++) m.tip_offset[i] = g->tlo[i] * g->unit;
    m.tip_offset[2] -= gc_tool_length_mm(g, g->tool);
    m.tool = g->tool;
    m.line = g->lineno;
    m.block = g->cur_block;
    m.index = g->motion_index;
    gc_feed_seconds(g, 0, &m.feed);
    int tripped = 1, at_start = 0;
    double f = 1;
    if (g->opt.probe) {
        tripped = 0;
        st = g->opt.probe(g->opt.probe_user, &m, toward, &tripped, &f, &at_start, g->err);
        if (st) {
            if (g->err && g->err->line == 0) {
                fm_error e = *g->err;
                return gc_fail(g, st, col, "%s: %s", name, e.message);
            }
            return st;
        }
    }
    if (at_start)
        return gc_fail(g, FM_ERR_INPUT, col,
                       toward ? "%s: the probe already touches the stock at the start; expected "
                                "a start clear of it"
                              : "%s: the probe does not touch the stock at the start; expected "
                                "a start in contact",
                       name);
    if (!tripped && must_trip)
        return gc_fail(g, FM_ERR_INPUT, col,
                       toward ? "%s move finished without making contact; expected the stock "
                                "(or a fixture of the check) between the start and the target "
                                "(or G38.3)"
                              : "%s move finished without losing contact; expected the target "
                                "clear of the stock and fixtures (or G38.5)",
                       name);
    if (f < 0) f = 0;
    if (f > 1) f = 1;
    double stop_m[3], stop[3];
    for (int i = 0; i < 3; i++) stop_m[i] = m.start[i] + f * (m.end[i] - m.start[i]);
    gc_from_machine(g, stop_m, stop);
    if (!tripped) memcpy(stop, end, sizeof stop);
    if ((st = gc_move_line(g, 0, stop))) return st;
    for (int i = 0; i < 3; i++) g->params[PARAM_PROBE_X + i] = stop[i];
    for (int i = 3; i < 9; i++) g->params[PARAM_PROBE_X + i] = 0;
    g->params[PARAM_PROBE_OK] = tripped ? 1 : 0;
    return FM_OK;
}
