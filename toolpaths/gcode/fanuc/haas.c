/* haas.c: codes Haas adds to Fanuc's, and Fanuc's own that CAM posts and
 * shop programs write, kept apart from the block executor (exec.c) that
 * calls them: G154 P1-P99 extended work offsets (one table with G54.1
 * P1-P48, read and written as #7001.. and #14001..), G95 feed per
 * revolution, G50.1/G51.1 programmable mirror image, G66/G67 modal macro
 * calls, and the words of Haas' G12/G13 circular pockets (the machine's
 * pocket.c cuts them). docs/gcode.md ("The Fanuc/Haas dialect") says what each does
 * and where the manuals leave it open. */
#include "fanuc.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- G54.1 P / G154 P ---- */

int gc_fanuc_ext_offset_var(gc_interp *g, long n, double **slot)
{
    /* 20 numbers per offset, X Y Z first: #7001 is G54.1 P1 X (Fanuc, 48
     * sets), #14001 is G154 P1 X (Haas; Fanuc's 300-set option numbers the
     * same way), so that #14021 is P2 X and #15961 is P99 X */
    long k;
    if (n >= 7001 && n <= 7000 + 20 * GC_FANUC_G54_1_OFFSETS) k = n - 7001;
    else if (n >= 14001 && n <= 14000 + 20 * GC_EXT_OFFSETS) k = n - 14001;
    else return 0;
    *slot = k % 20 < 3 ? &g->ext_offsets[k / 20][k % 20] : NULL;
    return 1;
}

fm_status gc_fanuc_select_ext_offset(gc_interp *g, const gc_block *b, int code, int col)
{
    int max = code == GC_G154 ? GC_EXT_OFFSETS : GC_FANUC_G54_1_OFFSETS;
    const char *name = code == GC_G154 ? "G154" : "G54.1";
    if (!HAS(b, 'p'))
        return gc_fail(g, FM_ERR_INPUT, col, "%s: P missing; expected %s P1 to P%d", name, name,
                       max);
    double v = VAL(b, 'p');
    if (floor(v) != v || v < 1 || v > max)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'), "P%g: expected a whole number from 1 to %d",
                       v, max);
    FANUC(g)->ext_g154 = code == GC_G154;
    gc_work_offset_select(g, g->cs, (int)v);
    return FM_OK;
}

/* ---- feed modes ---- */

fm_status gc_fanuc_feed_mode(gc_interp *g, const gc_block *b)
{
    gc_fanuc *f = FANUC(g);
    int css_col = 0, col = 0;
    int css = gc_block_g(b, GC_GROUP_SPINDLE_MODE, &css_col);
    if (css == GC_G96) f->css = 1;
    else if (css == GC_G97) f->css = 0;
    int code = gc_block_g(b, GC_GROUP_FEED_MODE, &col);
    if (code != GC_G_NONE) {
        g->inverse_time = code == GC_G93;
        g->per_rev = code == GC_G95;
    }
    if (g->per_rev && f->css)
        return gc_fail(g, FM_ERR_INPUT, col ? col : css_col,
                       "G95 feed per revolution with G96 constant surface speed: the spindle "
                       "speed would follow the cutting diameter, which is not simulated; "
                       "expected G97 S<rpm>");
    return FM_OK;
}

/* ---- G50.1 / G51.1 ---- */

static const char axis_letter[3] = {'x', 'y', 'z'};

fm_status gc_fanuc_mirror(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    const gc_block *b = &fb->b;
    int any = 0;
    for (int i = 0; i < 3; i++) any |= b->has[L(axis_letter[i])];
    if (gc_comp_c_routing(g))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s with cutter radius compensation on; expected G40 and its cancel move "
                       "first", code == GC_G50_1 ? "G50.1" : "G51.1");
    int axes[3];
    double centre[3] = {0, 0, 0};
    if (code == GC_G50_1) {
        /* the axes given are cancelled (their values are ignored, as Fanuc);
         * G50.1 alone cancels every axis */
        for (int i = 0; i < 3; i++) axes[i] = !any || b->has[L(axis_letter[i])];
        gc_frame_mirror(g, axes, centre, 0);
    } else {
        if (!any)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G51.1: no axis; expected X and/or Y, the position of the mirror axis");
        if (b->has[L('z')])
            return gc_fail(g, FM_ERR_INPUT, b->col[L('z')],
                           "G51.1 Z: mirroring the tool axis is not supported; expected X and/or "
                           "Y");
        if (g->plane != GC_PLANE_XY)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G51.1 in G%d: mirror image is supported in G17 only", g->plane);
        if (g->frame.scaling || g->frame.rotation)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "G51.1 in G51 or G68 mode: Fanuc mirrors first; give G51.1 before G51 "
                           "and G68");
        for (int i = 0; i < 3; i++) {
            axes[i] = b->has[L(axis_letter[i])];
            double v = axes[i] ? gc_fanuc_length(g, fb, axis_letter[i]) : 0;
            centre[i] = g->absolute ? v : g->frame.prog[i] + v;
        }
        gc_frame_mirror(g, axes, centre, 1);
    }
    return FM_OK;
}

/* ---- G66 / G67 ---- */

fm_status gc_fanuc_modal_call_set(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    gc_fanuc *f = FANUC(g);
    const gc_block *b = &fb->b;
    if (code == GC_G67) {
        /* this level's G66, or else the most recent one (Fanuc cancels
         * nested modal calls in reverse order) */
        for (int l = f->level; l >= 0; l--)
            if (f->modal[l].on) {
                f->modal[l].on = 0;
                break;
            }
        return FM_OK;
    }
    if (!b->has[L('p')])
        return gc_fail(g, FM_ERR_INPUT, col, "G66: P missing; expected G66 P<program>");
    double p = b->v[L('p')], l = b->has[L('l')] ? b->v[L('l')] : 1;
    if (floor(p) != p || p < 0 || p > 99999999)
        return gc_fail(g, FM_ERR_INPUT, b->col[L('p')],
                       "P%g: expected a whole number from 0 to 99999999", p);
    if (floor(l) != l || l < 0 || l > 999999999)
        return gc_fail(g, FM_ERR_INPUT, b->col[L('l')],
                       "L%g: expected a whole number from 0 to 999999999", l);
    struct gc_fanuc_modal_call *mc = &f->modal[f->level];
    mc->on = 1;
    mc->program = (long)p;
    mc->repeats = (long)l;
    mc->col = col;
    memcpy(mc->args, fb->args, sizeof mc->args);
    return FM_OK;
}

fm_status gc_fanuc_modal_call_run(gc_interp *g)
{
    gc_fanuc *f = FANUC(g);
    /* the macro's own moves (a level deeper) do not call it again */
    const struct gc_fanuc_modal_call *mc = &f->modal[f->level];
    if (!mc->on || g->stop) return FM_OK;
    return gc_fanuc_call(g, GC_CALL_G65, mc->program, mc->repeats, mc->args, mc->col);
}

int gc_fanuc_modal_call_on(const gc_fanuc *f)
{
    for (int l = 0; l <= f->level; l++)
        if (f->modal[l].on) return 1;
    return 0;
}

/* ---- G12 / G13 ---- */

fm_status gc_fanuc_circular_pocket(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    gc_fanuc *f = FANUC(g);
    const gc_block *b = &fb->b;
    const char *name = code == GC_G12 ? "G12 (circular pocket)" : "G13 (circular pocket)";
    int ccw = code == GC_G13;
    fm_status st;
    if (g->plane != GC_PLANE_XY)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: circular pockets are in G17 only (Haas)", name);
    if (gc_comp_c_routing(g))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s with cutter radius compensation on (the cycle compensates by its D); "
                       "expected G40 and its cancel move first", name);
    if (g->frame.scaling)
        return gc_fail(g, FM_ERR_INPUT, col, "%s in G51 scaling mode is not supported; cancel G51 "
                       "first", name);
    if (g->inverse_time)
        return gc_fail(g, FM_ERR_INPUT, col, "%s needs G94 or G95, not inverse time G93", name);
    if (!b->has[L('i')])
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: I missing; expected I, the radius of the first (or only) circle", name);
    if (b->has[L('k')] != b->has[L('q')])
        return gc_fail(g, FM_ERR_INPUT, b->has[L('k')] ? b->col[L('k')] : b->col[L('q')],
                       "%s: %c without %c; expected K (finished radius) and Q (step) together, or "
                       "I alone", name, b->has[L('k')] ? 'K' : 'Q', b->has[L('k')] ? 'Q' : 'K');
    long reps = 1;
    if (b->has[L('l')]) {
        double v = b->v[L('l')];
        if (floor(v) != v || v < 1 || v > 9999)
            return gc_fail(g, FM_ERR_INPUT, b->col[L('l')],
                           "%s L%g: expected a whole number of passes from 1 to 9999", name, v);
        reps = (long)v;
    }
    /* D: the tool's radius from the table (D0: the tool centre follows the
     * circles) */
    double rt = 0;
    if (f->d) {
        if ((st = gc_check_tool(g, f->d, b->has[L('d')] ? b->col[L('d')] : col, "D"))) return st;
        rt = gc_tool_diameter_mm(g, f->d) / 2 / g->unit;
    }
    double first = gc_fanuc_length(g, fb, 'i');
    double last = b->has[L('k')] ? gc_fanuc_length(g, fb, 'k') : first;
    double step = b->has[L('q')] ? gc_fanuc_length(g, fb, 'q') : 0;
    if (!(first > rt))
        return gc_fail(g, FM_ERR_INPUT, b->col[L('i')],
                       "%s I%g: expected a radius larger than the tool's (%g, D%d)", name, first,
                       rt, f->d);
    if (b->has[L('k')] && !(last >= first))
        return gc_fail(g, FM_ERR_INPUT, b->col[L('k')],
                       "%s K%g: expected the finished radius K >= I (%g)", name, last, first);
    if (b->has[L('q')] && !(step > 0))
        return gc_fail(g, FM_ERR_INPUT, b->col[L('q')], "%s Q%g: expected a step Q > 0", name,
                       step);
    if (b->has[L('q')] && (last - first) / step > 100000)
        return gc_fail(g, FM_ERR_LIMIT, b->col[L('q')], "%s: more than 100000 circles", name);
    if ((st = gc_check_feed(g, name, col))) return st;

    gc_pocket pk = {.ccw = ccw, .has_z = b->has[L('z')], .first = first, .last = last,
                    .step = step, .tool_radius = rt, .passes = reps};
    gc_fanuc_target(g, fb, pk.target);
    return gc_circular_pocket(g, &pk);
}
