/* gcode_offsets.c: offsets and coordinate systems: the G54-G59.3 tables
 * (#5221..) and their selection, G10 L2/L20, G92 and its variants, tool
 * length offsets (G43 H, G43.1, G49) and the G28/G30 reference points. The
 * interpreter keeps positions in program coordinates, so a changed offset
 * moves the current point the other way, as in LinuxCNC. */
#include "gcode_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double gc_tool_length_mm(gc_interp *g, int tool)
{
    const fm_tool_spec *t = fm_tool_table_find(g->opt.tools, tool);
    return t ? t->length_offset : 0.0;
}

/* The first of coordinate system cs's parameters (cs 1 = G54: #5221). */
static int cs_param_base(int cs) { return GC_PARAM_G5X_TABLE - 20 + 20 * cs; }

void gc_set_g5x(gc_interp *g, int cs)
{
    int base = cs_param_base(cs);
    for (int i = 0; i < 3; i++) {
        double nv = g->params[base + i];
        g->pos[i] += g->g5x[i] - nv;
        g->g5x[i] = nv;
    }
    g->cs = cs;
    g->params[GC_PARAM_COORD_SYSTEM] = cs;
}

void gc_set_tlo(gc_interp *g, const double nv[3])
{
    for (int i = 0; i < 3; i++) {
        g->pos[i] += g->tlo[i] - nv[i];
        g->tlo[i] = nv[i];
    }
}

fm_status gc_exec_g10(gc_interp *g, const gc_block *b, int col)
{
    if (!HAS(b, 'l'))
        return gc_fail(g, FM_ERR_INPUT, col, "G10: L word missing; expected L2 or L20");
    double l = VAL(b, 'l');
    if (l == 1 || l == 10 || l == 11)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                       "G10 L%g: tool table edits are not supported; give the tool table "
                       "(--tools) instead", l);
    if (l != 2 && l != 20)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'), "G10 L%g: expected L2 or L20", l);
    if (!HAS(b, 'p'))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G10 L%g: P word missing; expected P0 (active) or P1..P9", l);
    double pv = VAL(b, 'p');
    if (pv < 0 || pv > 9 || floor(pv) != pv)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'),
                       "G10 L%g P%g: expected a coordinate system P0 to P9", l, pv);
    if (HAS(b, 'r') && VAL(b, 'r') != 0)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'r'),
                       "G10 R%g: rotated coordinate systems are not supported", VAL(b, 'r'));
    int cs = pv == 0 ? g->cs : (int)pv;
    int base = cs_param_base(cs);
    const char ax[3] = {'x', 'y', 'z'};
    for (int i = 0; i < 3; i++) {
        if (!b->has[L(ax[i])]) continue;
        double w = b->v[L(ax[i])];
        /* L20: the current point gets coordinate w in system P (rs274: G92 not included) */
        g->params[base + i] = l == 2 ? w : g->pos[i] + g->g5x[i] + g->tlo[i] - w;
    }
    if (cs == g->cs) gc_set_g5x(g, cs);
    return FM_OK;
}

fm_status gc_exec_g92(gc_interp *g, const gc_block *b, int code, int col)
{
    const char ax[3] = {'x', 'y', 'z'};
    if (code == GC_G92) {
        if (!gc_block_has_axis(b))
            return gc_fail(g, FM_ERR_INPUT, col, "G92: no axis words; expected X, Y or Z values");
        for (int i = 0; i < 3; i++) {
            if (!b->has[L(ax[i])]) continue;
            double w = b->v[L(ax[i])];
            g->g92[i] = g->pos[i] + g->g92[i] - w;
            g->pos[i] = w;
            g->params[GC_PARAM_G92 + i] = g->g92[i];
        }
        g->params[GC_PARAM_G92_ENABLED] = 1;
        return FM_OK;
    }
    double nv[3] = {0, 0, 0};
    if (code == GC_G92_3)
        for (int i = 0; i < 3; i++) nv[i] = g->params[GC_PARAM_G92 + i];
    for (int i = 0; i < 3; i++) {
        g->pos[i] += g->g92[i] - nv[i];
        g->g92[i] = nv[i];
        if (code == GC_G92_1) g->params[GC_PARAM_G92 + i] = 0;
    }
    g->params[GC_PARAM_G92_ENABLED] = code == GC_G92_3;
    return FM_OK;
}

/* G28/G30: optional intermediate point, then rapid to the stored position
 * (#5161.. / #5181.., machine millimetres). */
fm_status gc_exec_home(gc_interp *g, const gc_block *b, int code)
{
    int base = code == GC_G28 ? GC_PARAM_G28_HOME : GC_PARAM_G30_HOME;
    double mid[3], home[3];
    gc_find_ends(g, b, 0, mid);
    fm_status st = gc_move_line(g, 1, mid);
    if (st) return st;
    const char ax[3] = {'x', 'y', 'z'};
    int any = HAS(b, 'x') || HAS(b, 'y') || HAS(b, 'z');
    for (int i = 0; i < 3; i++) {
        if (any && !b->has[L(ax[i])] && gc_block_has_axis(b)) home[i] = mid[i];
        else if (!any && gc_block_has_axis(b)) home[i] = mid[i];
        else home[i] = g->params[base + i] / g->unit - g->g5x[i] - g->g92[i] - g->tlo[i];
    }
    return gc_move_line(g, 1, home);
}

void gc_store_home(gc_interp *g, int code)
{
    int base = code == GC_G28_1 ? GC_PARAM_G28_HOME : GC_PARAM_G30_HOME;
    for (int i = 0; i < 3; i++)
        g->params[base + i] = (g->pos[i] + g->g5x[i] + g->g92[i] + g->tlo[i]) * g->unit;
}

/* G43 H (the table's length of tool H, or of the spindle tool without H),
 * G43.1 (the offset given by the axis words), G49 (none). */
fm_status gc_exec_tool_length(gc_interp *g, const gc_block *b, int code, int col)
{
    fm_status st;
    if (code == GC_G43) {
        int h = g->tool;
        if (HAS(b, 'h') && (st = gc_int_word(g, b, 'h', &h))) return st;
        if ((st = gc_check_tool(g, h, HAS(b, 'h') ? COL(b, 'h') : col, "H"))) return st;
        double nv[3] = {0, 0, gc_tool_length_mm(g, h) / g->unit};
        gc_set_tlo(g, nv);
    } else if (code == GC_G43_1) {
        double nv[3] = {0, 0, 0};
        const char ax[3] = {'x', 'y', 'z'};
        for (int i = 0; i < 3; i++)
            if (b->has[L(ax[i])]) nv[i] = b->v[L(ax[i])];
        gc_set_tlo(g, nv);
    } else if (code == GC_G49) {
        double nv[3] = {0, 0, 0};
        gc_set_tlo(g, nv);
    }
    return FM_OK;
}
