/* exec.c: executing a Fanuc block: feed, speed, tool and M
 * codes, plane and units, tool length (G43/G44 H with Fanuc's move of the
 * offset), work offsets (G54-G59, G54.1 P, G52, G92, G10 L2/L20), the
 * words of the programmed-point transforms (G16 polar, G51 uniform scaling,
 * G68 rotation: the machine's program frame, transform.c), dwells (X seconds, P milliseconds), G27/G28/G30/G53, lines and
 * arcs (I J K always incremental; R, and Fanuc's rule that a full circle
 * cannot be given with R). The interpreter's motion output (motion.c)
 * turns the work coordinates into machine millimetres.
 *
 * Two points are kept: g->pos, where the tool is in work coordinates (as in
 * the LinuxCNC dialect, shifted by a new tool length offset until the next
 * move), and g->frame.prog, the programmed point before polar coordinates,
 * scaling, rotation and mirror, from which the next absolute or incremental
 * end point is computed. */
#include "fanuc.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static double length_increment(const gc_interp *g) { return g->unit == 1.0 ? 0.001 : 0.0001; }

/* Round to the least increment, half away from zero, leaving numbers that
 * are already on it unchanged (so that 12.345 stays the double it was). */
static double to_increment(double v, double inc)
{
    double r = gc_fanuc_round(v / inc) * inc;
    return fabs(r - v) <= 1e-9 * inc ? v : r;
}

double gc_fanuc_length(const gc_interp *g, const gc_fanuc_block *fb, char c)
{
    double inc = length_increment(g);
    double v = fb->b.v[L(c)];
    if (fb->form[L(c)] == GC_FORM_INTEGER && !g->opt.calculator_input) v *= inc;
    return to_increment(v, inc);
}

double gc_fanuc_angle(const gc_interp *g, const gc_fanuc_block *fb, char c)
{
    double v = fb->b.v[L(c)];
    if (fb->form[L(c)] == GC_FORM_INTEGER && !g->opt.calculator_input) v *= 0.001;
    return to_increment(v, 0.001);
}

double gc_fanuc_dwell_seconds(const gc_interp *g, const gc_fanuc_block *fb, char c)
{
    double v = fb->b.v[L(c)];
    gc_number_form form = (gc_number_form)fb->form[L(c)];
    if (c == 'p')
        /* P is milliseconds (Fanuc); Haas reads P with a decimal point as seconds */
        return form == GC_FORM_DECIMAL ? v : gc_fanuc_round(v) / 1000.0;
    /* X: seconds; without a decimal point in the least increment, 1 ms */
    if (form == GC_FORM_INTEGER && !g->opt.calculator_input) v *= 0.001;
    return v;
}

/* ---- end points and moves ---- */

static const char axis_letter[3] = {'x', 'y', 'z'};

void gc_fanuc_axis_words(const gc_interp *g, const gc_fanuc_block *fb, gc_axis_words *w)
{
    const gc_block *b = &fb->b;
    int a, bb, c;
    gc_plane_axes(g->plane, &a, &bb, &c);
    for (int i = 0; i < 3; i++) {
        /* A B C in degrees: the rotary axes (rotary.c) */
        w->rgiven[i] = b->has[L("abc"[i])];
        w->rvalue[i] = w->rgiven[i] ? gc_fanuc_angle(g, fb, "abc"[i]) : 0;
        /* in G16 the plane's second axis is the angle */
        w->given[i] = b->has[L(axis_letter[i])];
        w->value[i] = !w->given[i] ? 0
                      : g->frame.polar && i == bb ? gc_fanuc_angle(g, fb, axis_letter[i])
                                                  : gc_fanuc_length(g, fb, axis_letter[i]);
    }
}

void gc_fanuc_target(gc_interp *g, const gc_fanuc_block *fb, double end[3])
{
    gc_axis_words w;
    gc_fanuc_axis_words(g, fb, &w);
    gc_frame_target(g, &w, end);
}

/* A canned cycle block: its hole data as values for the machine's ISO
 * cycles (cycles_iso.c). */
static fm_status exec_cycle(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    const gc_block *b = &fb->b;
    gc_hole_block h;
    memset(&h, 0, sizeof h);
    gc_fanuc_axis_words(g, fb, &h.at);
    h.has_r = b->has[L('r')];
    h.has_q = b->has[L('q')];
    h.has_p = b->has[L('p')];
    if (h.has_r) h.r = gc_fanuc_length(g, fb, 'r');
    if (h.has_q) h.q = fabs(gc_fanuc_length(g, fb, 'q'));
    if (h.has_p) h.p = gc_fanuc_dwell_seconds(g, fb, 'p');
    h.r_col = b->col[L('r')];
    h.q_col = b->col[L('q')];
    h.rep_letter = b->has[L('k')] ? 'k' : b->has[L('l')] ? 'l' : 0;
    if (h.rep_letter) {
        h.rep_value = b->v[L(h.rep_letter)];
        h.rep_col = b->col[L(h.rep_letter)];
    }
    return gc_cycle_iso(g, code, &h, col);
}

/* X Y Z of the block as lengths (G52, G53: never polar). */
static void lengths(const gc_interp *g, const gc_fanuc_block *fb, int given[3], double value[3])
{
    for (int i = 0; i < 3; i++) {
        given[i] = fb->b.has[L(axis_letter[i])];
        value[i] = given[i] ? gc_fanuc_length(g, fb, axis_letter[i]) : 0;
    }
}

static int has_plane_word(const gc_block *b)
{
    return b->has[L('x')] || b->has[L('y')] || b->has[L('z')];
}

/* ---- arcs ---- */

static fm_status exec_arc(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    const gc_block *b = &fb->b;
    char name[8];
    gc_g_name(code, name, sizeof name);
    int a, bb, c;
    gc_plane_axes(g->plane, &a, &bb, &c);
    fm_status st = gc_check_feed(g, name, col);
    if (st) return st;
    double end[3], cab[2];
    gc_fanuc_target(g, fb, end);
    gc_arc_words w;
    gc_arc_words_of(b, &w);
    if (w.has_r) w.r = gc_fanuc_length(g, fb, 'r');
    for (int i = 0; i < 3; i++)
        if (w.has[i]) w.v[i] = gc_fanuc_length(g, fb, "ijk"[i]);
    int no_arc;
    if ((st = gc_arc_center(g, 1, code, &w, g->frame.prog, end, cab, &no_arc, col))) return st;
    if (no_arc) {
        if (end[c] != g->frame.prog[c]) return gc_frame_move(g, 0, end);
        memcpy(g->frame.prog, end, sizeof g->frame.prog);
        return FM_OK;
    }
    double cen[3];
    cen[a] = cab[0];
    cen[bb] = cab[1];
    cen[c] = g->frame.prog[c];
    return gc_frame_arc(g, end, cen, code == GC_G3, 1);
}

/* ---- modal state ---- */

/* G20/G21: the machine's lengths and the ISO hole data (LinuxCNC keeps
 * its cycle levels as written). */
static void set_units(gc_interp *g, double unit)
{
    if (unit == g->unit) return;
    double k = g->unit / unit;
    gc_cycle_iso_scale_units(g, k);
    gc_set_units(g, unit);
}

static fm_status whole_word(gc_interp *g, const gc_block *b, char c, long lo, long hi, long *out)
{
    double v = b->v[L(c)];
    *out = 0;
    if (floor(v) != v || v < lo || v > hi)
        return gc_fail(g, FM_ERR_INPUT, b->col[L(c)], "%c%g: expected a whole number from %ld to %ld",
                       c - 32, v, lo, hi);
    *out = (long)v;
    return FM_OK;
}

static fm_status tool_length(gc_interp *g, const gc_fanuc_block *fb, int code, int col, int *changed)
{
    gc_fanuc *f = FANUC(g);
    const gc_block *b = &fb->b;
    fm_status st;
    *changed = 0;
    if (b->has[L('h')]) {
        long h;
        if ((st = whole_word(g, b, 'h', 0, 999999, &h))) return st;
        f->h = gc_register_tool(g, 'h', (int)h);
        if ((st = gc_check_tool(g, f->h, b->col[L('h')], "H"))) return st;
    }
    /* G43.4: G43 with tool centre point control on (rotary.c); G49 off */
    if (code == GC_G43_4 && (st = gc_rot_tcp(g, 1, col))) return st;
    if (code == GC_G49) gc_rot_tcp(g, 0, col);
    if (code == GC_G43_4) code = GC_G43;
    if (code != GC_G_NONE) f->tool_length_mode = code;
    if (code == GC_G_NONE && !b->has[L('h')]) return FM_OK;
    double len = f->h ? gc_tool_length_mm(g, f->h) / g->unit : 0.0;
    double nv[3] = {0, 0, 0};
    if (f->tool_length_mode == GC_G43) nv[2] = len;
    else if (f->tool_length_mode == GC_G44) nv[2] = -len;
    if (nv[2] != g->tlo[2]) *changed = 1;
    gc_set_tlo(g, nv);
    return FM_OK;
}

static fm_status select_work_offset(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    if (code == GC_G54_1 || code == GC_G154) return gc_fanuc_select_ext_offset(g, &fb->b, code, col);
    gc_work_offset_select(g, (code - GC_G54) / 10 + 1, 0);
    return FM_OK;
}

static fm_status exec_g10(gc_interp *g, const gc_fanuc_block *fb, int col)
{
    const gc_block *b = &fb->b;
    long l, pn;
    fm_status st;
    if (!b->has[L('l')])
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G10: L missing; expected L2 (G54-G59) or L20 (G54.1, G154)");
    if ((st = whole_word(g, b, 'l', 0, 1000, &l))) return st;
    if (l >= 10 && l <= 13)
        return gc_fail(g, FM_ERR_INPUT, b->col[L('l')],
                       "G10 L%ld: tool offsets come from the tool table (--tools); remove the "
                       "G10 L%ld block", l, l);
    if (l != 2 && l != 20)
        return gc_fail(g, FM_ERR_INPUT, b->col[L('l')],
                       "G10 L%ld: expected L2 (G54-G59, P0 the external offset) or L20 (G54.1 P, "
                       "G154 P)",
                       l);
    if (!b->has[L('p')])
        return gc_fail(g, FM_ERR_INPUT, col, "G10 L%ld: P missing", l);
    if ((st = whole_word(g, b, 'p', l == 2 ? 0 : 1, l == 2 ? 6 : GC_EXT_OFFSETS, &pn)))
        return st;
    for (int i = 0; i < 3; i++) {
        char c = axis_letter[i];
        if (!b->has[L(c)]) continue;
        double v = gc_fanuc_length(g, fb, c);
        double *slot = l == 2 ? &g->params[5201 + 20 * pn + i] : &g->ext_offsets[pn - 1][i];
        /* G90 sets the offset, G91 adds to it */
        *slot = g->absolute ? v : *slot + v;
    }
    gc_work_offset_apply(g);
    return FM_OK;
}

static fm_status exec_g92(gc_interp *g, const gc_fanuc_block *fb, int col)
{
    const gc_block *b = &fb->b;
    if (!has_plane_word(b))
        return gc_fail(g, FM_ERR_INPUT, col, "G92: no axis words; expected X, Y or Z values");
    if (gc_frame_transformed(g))
        return gc_fail(g, FM_ERR_INPUT, col, "G92 in G68, G51 or G51.1 mode; cancel them first");
    for (int i = 0; i < 3; i++) {
        char c = axis_letter[i];
        if (!b->has[L(c)]) continue;
        double w = gc_fanuc_length(g, fb, c);
        g->g92[i] = g->pos[i] + g->g92[i] - w;
        g->pos[i] = w;
    }
    gc_frame_reprogram(g);
    return FM_OK;
}

/* G28 / G30: through the intermediate point (the axes given) to the
 * reference point of those axes; the others stay. */
static fm_status exec_reference(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    const gc_block *b = &fb->b;
    int ref = 0;
    fm_status st;
    if (code == GC_G30) {
        long pn = 2;
        if (b->has[L('p')] && (st = whole_word(g, b, 'p', 2, 4, &pn))) return st;
        ref = (int)pn - 1;
    } else if (b->has[L('p')]) {
        return gc_fail(g, FM_ERR_INPUT, b->col[L('p')], "G28 P: expected G30 P2-P4 for other "
                       "reference points");
    }
    if (!has_plane_word(b)) return FM_OK; /* no axis: nothing moves */
    (void)col;
    double mid[3];
    gc_fanuc_target(g, fb, mid);
    int given[3] = {b->has[L('x')], b->has[L('y')], b->has[L('z')]};
    return gc_move_reference(g, ref, given, mid);
}

static fm_status exec_g53(gc_interp *g, const gc_fanuc_block *fb, int col)
{
    if (!g->absolute)
        return gc_fail(g, FM_ERR_INPUT, col, "G53 in incremental mode (G91); expected G90");
    int given[3];
    double value[3];
    lengths(g, fb, given, value);
    return gc_move_machine(g, given, value);
}

/* Axis i of a G51/G68/G51.1 centre: the block's (G90/G91) or the
 * programmed point's. */
static double centre_coord(gc_interp *g, const gc_fanuc_block *fb, int i)
{
    char l = axis_letter[i];
    if (!fb->b.has[L(l)]) return g->frame.prog[i];
    double v = gc_fanuc_length(g, fb, l);
    return g->absolute ? v : g->frame.prog[i] + v;
}

static fm_status exec_rotation(gc_interp *g, const gc_fanuc_block *fb, int col)
{
    const gc_block *b = &fb->b;
    int a, bb, c;
    gc_plane_axes(g->plane, &a, &bb, &c);
    if (!b->has[L('r')])
        return gc_fail(g, FM_ERR_INPUT, col, "G68: R missing; expected the angle R in degrees");
    double cen[2] = {centre_coord(g, fb, a), centre_coord(g, fb, bb)};
    gc_frame_rotate(g, 1, cen, gc_fanuc_angle(g, fb, 'r'));
    return FM_OK;
}

static fm_status exec_scaling(gc_interp *g, const gc_fanuc_block *fb, int col)
{
    const gc_block *b = &fb->b;
    double k = 0;
    int have = 0;
    if (b->has[L('i')] || b->has[L('j')] || b->has[L('k')]) {
        /* per-axis factors: only accepted when they are all the same */
        const char *ijk = "ijk";
        for (int i = 0; i < 3; i++) {
            if (!b->has[L(ijk[i])])
                return gc_fail(g, FM_ERR_INPUT, col,
                               "G51 with I J K: per-axis scaling is not supported; expected one "
                               "factor P (or I, J and K all equal)");
            double v = b->v[L(ijk[i])];
            if (fb->form[L(ijk[i])] != GC_FORM_DECIMAL) v *= 0.001;
            if (have && v != k)
                return gc_fail(g, FM_ERR_INPUT, b->col[L(ijk[i])],
                               "G51 I J K differ: per-axis scaling is not supported; expected one "
                               "factor P");
            k = v;
            have = 1;
        }
    }
    if (b->has[L('p')]) {
        double v = b->v[L('p')];
        /* P without a decimal point counts 0.001 (Fanuc's default unit) */
        if (fb->form[L('p')] != GC_FORM_DECIMAL) v *= 0.001;
        if (have && v != k)
            return gc_fail(g, FM_ERR_INPUT, b->col[L('p')], "G51: P and I J K differ");
        k = v;
        have = 1;
    }
    if (!have)
        return gc_fail(g, FM_ERR_INPUT, col, "G51: scaling factor missing; expected P");
    if (!(k > 0) || k > 1e6)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G51: factor %g; expected a positive factor (mirroring is not supported)", k);
    if (g->motion >= GC_G73)
        return gc_fail(g, FM_ERR_INPUT, col, "G51 in a canned cycle mode; cancel it (G80) first");
    if (g->frame.rotation)
        return gc_fail(g, FM_ERR_INPUT, col, "G51 in G68 mode; Fanuc scales first: give G51 "
                       "before G68");
    double cen[3];
    for (int i = 0; i < 3; i++) cen[i] = centre_coord(g, fb, i);
    gc_frame_scale(g, k, cen);
    return FM_OK;
}

/* ---- M codes ---- */

typedef struct mcodes {
    int call;            /* 97, 98 or 0 */
    int call_col;
    int ret, ret_col;    /* M99 */
    int end;             /* M2 / M30 */
} mcodes;

static fm_status scan_m(gc_interp *g, const gc_block *b, mcodes *mc)
{
    gc_fanuc *f = FANUC(g);
    memset(mc, 0, sizeof *mc);
    for (int i = 0; i < b->nm; i++) {
        int m = b->m[i];
        f->last_m = m;
        switch (m) {
        case 97: case 98:
            if (mc->call || mc->ret)
                return gc_fail(g, FM_ERR_INPUT, b->mcol[i],
                               "M%d with another call or return on this line; expected one", m);
            mc->call = m;
            mc->call_col = b->mcol[i];
            break;
        case 99:
            if (mc->call)
                return gc_fail(g, FM_ERR_INPUT, b->mcol[i],
                               "M99 with M97/M98 on this line; expected one");
            mc->ret = 1;
            mc->ret_col = b->mcol[i];
            break;
        case 2: case 30: mc->end = 1; break;
        case 198:
            return gc_fail(g, FM_ERR_INPUT, b->mcol[i],
                           "M198: calling a program from external memory is not supported; use "
                           "M98 with the file on the subroutine path");
        default: break;
        }
    }
    return FM_OK;
}

static int has_m(const gc_block *b, int m)
{
    for (int i = 0; i < b->nm; i++)
        if (b->m[i] == m) return 1;
    return 0;
}

/* ---- the block ---- */

fm_status gc_fanuc_exec_block(gc_interp *g, gc_fanuc_block *fb)
{
    gc_fanuc *f = FANUC(g);
    gc_block *b = &fb->b;
    fm_status st;
    int col = 0, code;
    mcodes mc;
    if ((st = scan_m(g, b, &mc))) return st;

    if (fb->g66) return gc_fanuc_modal_call_set(g, fb, GC_G66, fb->g65_col);
    if (gc_block_g(b, GC_GROUP_MACRO_MODAL, &col) == GC_G67 &&
        (st = gc_fanuc_modal_call_set(g, fb, GC_G67, col)))
        return st;
    if (fb->g65) {
        /* G65 P<program> L<repeats> arguments: a macro call, nothing else */
        long pn, reps = 1;
        if (!b->has[L('p')])
            return gc_fail(g, FM_ERR_INPUT, fb->g65_col, "G65: P missing; expected G65 P<program>");
        if ((st = whole_word(g, b, 'p', 0, 99999999, &pn))) return st;
        if (b->has[L('l')] && (st = whole_word(g, b, 'l', 0, 999999999, &reps))) return st;
        return gc_fanuc_call(g, GC_CALL_G65, pn, reps, fb->args, fb->g65_col);
    }

    int ccheck = gc_block_g(b, GC_GROUP_CYCLE, NULL);
    if ((st = gc_fanuc_comp_check(g, fb, ccheck != GC_G_NONE ? ccheck : (int)g->motion)))
        return st;

    /* feed mode, feed, speed, tool, tool change, spindle, coolant */
    if ((st = gc_fanuc_feed_mode(g, b))) return st;
    if (b->has[L('f')]) {
        if (b->v[L('f')] < 0)
            return gc_fail(g, FM_ERR_INPUT, b->col[L('f')], "F%g: expected a feed rate >= 0",
                           b->v[L('f')]);
        g->feed = b->v[L('f')];
    }
    if (b->has[L('s')]) {
        if (b->v[L('s')] < 0)
            return gc_fail(g, FM_ERR_INPUT, b->col[L('s')], "S%g: expected a speed >= 0",
                           b->v[L('s')]);
        g->speed = b->v[L('s')];
    }
    if (b->has[L('d')]) {
        long d;
        if ((st = whole_word(g, b, 'd', 0, 999999, &d))) return st;
        f->d = (int)d;
    }
    if (b->has[L('t')]) {
        long t;
        if ((st = whole_word(g, b, 't', 0, 99999999, &t))) return st;
        if ((st = gc_check_tool(g, (int)t, b->col[L('t')], "T"))) return st;
        g->selected_tool = (int)t;
    }
    if (has_m(b, 6)) {
        g->tool = g->selected_tool;
        g->spindle_dir = 0; /* the spindle stops for a tool change */
    }
    if (has_m(b, 3)) g->spindle_dir = 1;
    if (has_m(b, 4)) g->spindle_dir = -1;
    if (has_m(b, 5) || has_m(b, 19)) g->spindle_dir = 0;
    if (has_m(b, 7)) g->coolant |= 1;
    if (has_m(b, 8)) g->coolant |= 2;
    if (has_m(b, 9)) g->coolant = 0;

    /* plane, units */
    code = gc_block_g(b, GC_GROUP_PLANE, &col);
    if (code != GC_G_NONE) {
        if (g->frame.rotation && code / 10 != (int)g->frame.rot_plane)
            return gc_fail(g, FM_ERR_INPUT, col, "plane change in G68 mode; cancel G68 first");
        if ((g->frame.mirror[0] || g->frame.mirror[1]) && code != GC_G17)
            return gc_fail(g, FM_ERR_INPUT, col, "plane change in G51.1 mode; cancel G51.1 "
                           "(G50.1) first");
        g->plane = (gc_plane)(code / 10);
    }
    code = gc_block_g(b, GC_GROUP_UNITS, NULL);
    if (code == GC_G20) set_units(g, GC_INCH);
    else if (code == GC_G21) set_units(g, 1.0);

    /* distance mode, return mode, polar coordinates */
    code = gc_block_g(b, GC_GROUP_DISTANCE, NULL);
    if (code == GC_G90) g->absolute = 1;
    else if (code == GC_G91) g->absolute = 0;
    code = gc_block_g(b, GC_GROUP_RETURN_MODE, NULL);
    if (code == GC_G98) g->retract_r = 0;
    else if (code == GC_G99) g->retract_r = 1;
    code = gc_block_g(b, GC_GROUP_POLAR, NULL);
    if (code == GC_G16 || code == GC_G15) gc_frame_polar(g, code == GC_G16);

    /* path control (docs/plan.md, "Fanuc and Haas"): G61 exact stop, G64
     * cutting mode, Haas G187 P1-P3 (E: the tolerance), G09 for this block */
    code = gc_block_g(b, GC_GROUP_PATH_MODE, NULL);
    if (code == GC_G61) gc_set_path_mode(g, FM_PATH_EXACT_STOP, 0, 0);
    else if (code == GC_G64) gc_set_path_mode(g, FM_PATH_BLEND, 0, 0);
    if (gc_block_g(b, GC_GROUP_LOOKAHEAD, NULL) == GC_G187) {
        /* Haas: P1 rough, P2 medium, P3 finish; E the corner tolerance,
         * else setting 85's 0.05 mm scaled by the smoothness asked for */
        static const double haas_tolerance_mm[4] = {0.05, 0.1, 0.05, 0.01};
        int level = b->has[L('p')] ? (int)b->v[L('p')] : 0;
        if (level < 0 || level > 3) level = 0;
        double tol = b->has[L('e')] ? b->v[L('e')] * g->unit : haas_tolerance_mm[level];
        gc_set_path_mode(g, FM_PATH_BLEND, tol, 0);
    }
    g->exact_stop_block = gc_block_g(b, GC_GROUP_NON_MODAL, NULL) == GC_G9;

    /* dwell */
    int nonmodal = gc_block_g(b, GC_GROUP_NON_MODAL, &col);
    int nonmodal_col = col;
    if (nonmodal == GC_G4) {
        double sec = 0;
        if (b->has[L('p')] && b->has[L('x')])
            return gc_fail(g, FM_ERR_INPUT, nonmodal_col, "G04 with both X and P; expected one");
        if (b->has[L('p')]) sec = gc_fanuc_dwell_seconds(g, fb, 'p');
        else if (b->has[L('x')]) sec = gc_fanuc_dwell_seconds(g, fb, 'x');
        else if (b->has[L('u')]) sec = b->v[L('u')];
        if (sec < 0)
            return gc_fail(g, FM_ERR_INPUT, nonmodal_col, "G04: negative dwell time %g s", sec);
        if ((st = gc_frame_dwell(g, sec))) return st;
    }

    /* motion mode of this block */
    int mcode = gc_block_g(b, GC_GROUP_MOTION, &col);
    int mcol = col;
    int ccode = gc_block_g(b, GC_GROUP_CYCLE, &col);
    int ccol = col;
    if (mcode != GC_G_NONE && ccode != GC_G_NONE && ccode != GC_G80) {
        char a1[8], a2[8];
        gc_g_name(mcode, a1, sizeof a1);
        gc_g_name(ccode, a2, sizeof a2);
        return gc_fail(g, FM_ERR_INPUT, ccol, "%s and %s on one line; expected one motion", a1, a2);
    }
    int rotation = gc_block_g(b, GC_GROUP_ROTATION, &col);
    int rotation_col = col;
    int scaling = gc_block_g(b, GC_GROUP_SCALING, &col);
    int scaling_col = col;
    int mirror = gc_block_g(b, GC_GROUP_MIRROR, &col);
    int mirror_col = col;
    /* codes whose X Y Z are not this block's end point */
    int other_uses_axes = nonmodal == GC_G4 || nonmodal == GC_G10 || nonmodal == GC_G27 ||
                          nonmodal == GC_G28 || nonmodal == GC_G30 || nonmodal == GC_G52 ||
                          nonmodal == GC_G53 || nonmodal == GC_G92 || rotation == GC_G68 ||
                          scaling == GC_G51 || nonmodal == GC_G12 || nonmodal == GC_G13 ||
                          mirror != GC_G_NONE;
    if (mcode != GC_G_NONE) {
        f->group1 = mcode / 10;
        g->motion = (gc_gcode)mcode;
        gc_cycle_iso_cancel(g);
    }
    if (ccode == GC_G80) {
        g->motion = (gc_gcode)(f->group1 * 10);
        gc_cycle_iso_cancel(g);
    } else if (ccode != GC_G_NONE) {
        if (g->frame.scaling)
            return gc_fail(g, FM_ERR_INPUT, ccol,
                           "canned cycle in G51 scaling mode is not supported; cancel G51 first");
    }
    int axes = has_plane_word(b);
    int motion = ccode != GC_G_NONE && ccode != GC_G80 ? ccode : (int)g->motion;
    int is_arc = motion == GC_G2 || motion == GC_G3;
    int will_move = !other_uses_axes &&
                    (axes || (is_arc && (b->has[L('i')] || b->has[L('j')] || b->has[L('k')] ||
                                         b->has[L('r')])) ||
                     (motion >= GC_G73 && b->has[L('r')]));

    /* tool length: Fanuc moves the axis by the new offset in this block */
    int tl_code = gc_block_g(b, GC_GROUP_TOOL_LENGTH, &col), tl_changed = 0;
    if ((st = tool_length(g, fb, tl_code, col, &tl_changed))) return st;
    if (tl_changed && !will_move) {
        int rapid = f->group1 == 0 || motion >= GC_G73;
        if (!rapid && (st = gc_check_feed(g, "tool length offset move", col))) return st;
        if ((st = gc_frame_move(g, rapid, g->frame.prog))) return st;
    }

    /* work offsets */
    code = gc_block_g(b, GC_GROUP_COORD_SYSTEM, &col);
    if (code != GC_G_NONE && (st = select_work_offset(g, fb, code, col))) return st;

    /* cutter radius compensation: this block's move starts or cancels it */
    code = gc_block_g(b, GC_GROUP_CUTTER_COMP, &col);
    if ((code != GC_G_NONE || b->has[L('d')]) && (st = gc_fanuc_comp_mode(g, fb, code, col)))
        return st;

    /* mirror, scaling and rotation (their axis words are centres) */
    if (mirror != GC_G_NONE && (st = gc_fanuc_mirror(g, fb, mirror, mirror_col))) return st;
    if (scaling == GC_G50) {
        gc_frame_scale(g, 0, NULL);
    } else if (scaling == GC_G51 && (st = exec_scaling(g, fb, scaling_col))) {
        return st;
    }
    if (rotation == GC_G69) {
        gc_frame_rotate(g, 0, NULL, 0);
    } else if (rotation == GC_G68 && (st = exec_rotation(g, fb, rotation_col))) {
        return st;
    }

    /* non-modal codes */
    switch (nonmodal) {
    case GC_G10: if ((st = exec_g10(g, fb, nonmodal_col))) return st; break;
    case GC_G27: {
        double to[3];
        gc_fanuc_target(g, fb, to);
        if ((st = gc_frame_move(g, 1, to))) return st;
        break;
    }
    case GC_G28: case GC_G30:
        if ((st = exec_reference(g, fb, nonmodal, nonmodal_col))) return st;
        break;
    case GC_G52: {
        int given[3];
        double value[3];
        lengths(g, fb, given, value);
        gc_work_offset_local(g, given, value);
        break;
    }
    case GC_G53: if ((st = exec_g53(g, fb, nonmodal_col))) return st; break;
    case GC_G12: case GC_G13:
        if ((st = gc_fanuc_circular_pocket(g, fb, nonmodal, nonmodal_col))) return st;
        break;
    case GC_G92: if ((st = exec_g92(g, fb, nonmodal_col))) return st; break;
    default: break;
    }

    /* motion */
    if (will_move) {
        if (mcol == 0) mcol = ccode != GC_G_NONE ? ccol : 0;
        if (!mcol) {
            int best = 0;
            for (int i = 0; i < 26; i++)
                if (b->has[i] && (!best || b->col[i] < best)) best = b->col[i];
            mcol = best;
        }
        g->motion_col = mcol;
        if (motion == GC_G0 || motion == GC_G1) {
            if (motion == GC_G1) {
                if ((st = gc_check_feed(g, "G01", mcol))) return st;
                if (g->inverse_time && !b->has[L('f')])
                    return gc_fail(g, FM_ERR_INPUT, mcol,
                                   "G01 in inverse time (G93) without F; expected an F word on "
                                   "every feed line");
            }
            double end[3];
            gc_fanuc_target(g, fb, end);
            if ((st = gc_frame_move(g, motion == GC_G0, end))) return st;
        } else if (is_arc) {
            if (g->inverse_time && !b->has[L('f')])
                return gc_fail(g, FM_ERR_INPUT, mcol,
                               "G0%d in inverse time (G93) without F; expected an F word on every "
                               "feed line", motion / 10);
            if ((st = exec_arc(g, fb, motion, mcol))) return st;
        } else if (motion >= GC_G73 && motion != GC_G80) {
            if ((st = exec_cycle(g, fb, motion, mcol))) return st;
        }
    } else if (ccode != GC_G_NONE && ccode != GC_G80) {
        /* a cycle code without a position: its data are kept for later blocks */
        if ((st = exec_cycle(g, fb, ccode, ccol))) return st;
    }
    for (int i = 0; i < 3; i++) f->block_end[i] = g->pos[i];
    /* G66: the macro is called after each block that moved */
    if (will_move && !mc.call && !mc.ret && !mc.end && (st = gc_fanuc_modal_call_run(g)))
        return st;

    /* calls, returns, stops */
    if (mc.call) {
        long pn, reps = 1;
        if (!b->has[L('p')])
            return gc_fail(g, FM_ERR_INPUT, mc.call_col, "M%d: P missing; expected M%d P<%s>",
                           mc.call, mc.call, mc.call == 98 ? "program" : "sequence number");
        if ((st = whole_word(g, b, 'p', 0, 99999999, &pn))) return st;
        if (b->has[L('l')]) {
            if ((st = whole_word(g, b, 'l', 0, 9999, &reps))) return st;
        } else if (mc.call == 98 && pn > 9999) {
            /* Fanuc: M98 P<repeats><4-digit program>, e.g. P30010 = O0010 three times */
            reps = pn / 10000;
            pn %= 10000;
        }
        return gc_fanuc_call(g, mc.call == 98 ? GC_CALL_M98 : GC_CALL_M97, pn, reps, NULL,
                             mc.call_col);
    }
    if (mc.ret) {
        long pn = 0;
        if (b->has[L('p')] && (st = whole_word(g, b, 'p', 0, 99999999, &pn))) return st;
        return gc_fanuc_return(g, b->has[L('p')], pn, mc.ret_col);
    }
    if (mc.end) {
        g->ended = 1;
        g->stop = 1;
    }
    return FM_OK;
}
