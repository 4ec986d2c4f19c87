/* offsets.c: offsets and coordinate systems: the G54-G59.3 tables
 * (#5221..) and their selection, G10 L2/L20, G92 and its variants, tool
 * length offsets (G43 H, G43.1, G49) and the G28/G30 reference points. The
 * interpreter keeps positions in program coordinates, so a changed offset
 * moves the current point the other way, as in LinuxCNC. */
#include "machine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static gc_tool_edit *tool_edit(gc_interp *g, int tool)
{
    for (int i = 0; i < g->ntool_edits; i++)
        if (g->tool_edits[i].tool == tool) return &g->tool_edits[i];
    return NULL;
}

int gc_register_tool(const gc_interp *g, char word, int n)
{
    const fm_tool_table *t = g->opt.tools;
    for (size_t i = 0; t && n > 0 && i < t->count; i++) {
        const fm_tool_spec *s = &t->tools[i];
        if ((word == 'd' ? s->diameter_register : s->length_register) == n) return s->number;
    }
    return n;
}

double gc_tool_length_mm(gc_interp *g, int tool)
{
    const gc_tool_edit *e = tool_edit(g, tool);
    if (e) return e->length;
    const fm_tool_spec *t = fm_tool_table_find(g->opt.tools, tool);
    return t ? t->length_offset : 0.0;
}

double gc_tool_comp_radius_mm(gc_interp *g, int tool)
{
    const gc_tool_edit *e = tool_edit(g, tool);
    const fm_tool_spec *t = fm_tool_table_find(g->opt.tools, tool);
    double wear = t ? t->radius_wear : 0.0;
    if (e) return e->diameter / 2 + wear;
    if (!t) return 0.0;
    return (t->radius_offset > 0 ? t->radius_offset : t->diameter / 2) + wear;
}

double gc_tool_diameter_mm(gc_interp *g, int tool)
{
    const gc_tool_edit *e = tool_edit(g, tool);
    if (e) return e->diameter;
    const fm_tool_spec *t = fm_tool_table_find(g->opt.tools, tool);
    return t ? t->diameter : 0.0;
}

void gc_refresh_tool_params(gc_interp *g)
{
    g->tool_param_z = gc_tool_length_mm(g, g->tool);
    g->tool_param_dia = gc_tool_diameter_mm(g, g->tool);
}

/* The editable copy of a tool's entry (G10 L1/L10/L11 change only what the
 * interpreter reads: G43 lengths and compensation diameters; the simulated
 * cutter keeps the table's shape). */
static fm_status edit_tool(gc_interp *g, int tool, gc_tool_edit **out)
{
    gc_tool_edit *e = tool_edit(g, tool);
    if (!e) {
        if (g->ntool_edits >= 100000)
            return gc_fail(g, FM_ERR_LIMIT, 0, "G10: more than 100000 edited tools");
        if (g->ntool_edits == g->captool_edits) {
            int cap = g->captool_edits ? g->captool_edits * 2 : 8;
            gc_tool_edit *t = realloc(g->tool_edits, (size_t)cap * sizeof *t);
            if (!t) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory (tool edits)");
            g->tool_edits = t;
            g->captool_edits = cap;
        }
        e = &g->tool_edits[g->ntool_edits++];
        e->tool = tool;
        e->length = gc_tool_length_mm(g, tool);
        e->diameter = gc_tool_diameter_mm(g, tool);
    }
    *out = e;
    return FM_OK;
}

/* The first of coordinate system cs's parameters (cs 1 = G54: #5221). */
static int cs_param_base(int cs) { return GC_PARAM_G5X_TABLE - 20 + 20 * cs; }

/* Select coordinate system cs: its origin and XY rotation (#5210 + 20 cs).
 * The machine does not move, so the current point's coordinates change. */
void gc_set_g5x(gc_interp *g, int cs)
{
    int base = cs_param_base(cs);
    double rot = g->params[base + 9];
    if (rot == 0 && g->rotation == 0) {
        for (int i = 0; i < 3; i++) {
            double nv = g->params[base + i];
            g->pos[i] += g->g5x[i] - nv;
            g->g5x[i] = nv;
        }
    } else {
        double m[3];
        gc_to_machine(g, g->pos, m);
        for (int i = 0; i < 3; i++) g->g5x[i] = g->params[base + i];
        g->rotation = rot;
        gc_from_machine(g, m, g->pos);
    }
    gc_rot_set_g5x(g, base);
    g->cs = cs;
    g->params[GC_PARAM_COORD_SYSTEM] = cs;
}

/* A tool length offset change does not move the machine: the programmed
 * point moves by the difference, and so does the machine position of the
 * programmed point (the tool tip stays where it is). */
void gc_set_tlo(gc_interp *g, const double nv[3])
{
    double before[3], after[3];
    gc_to_machine(g, g->pos, before);
    for (int i = 0; i < 3; i++) {
        g->pos[i] += g->tlo[i] - nv[i];
        g->tlo[i] = nv[i];
    }
    gc_to_machine(g, g->pos, after);
    for (int i = 0; i < 3; i++) g->mpos[i] += after[i] - before[i];
}

/* G10 L1 (tool table: R radius, Z length), L10 and L11 (the tool length
 * that makes the current point read the given Z in the current system, or
 * in G59.3 without G92). Lengths in mm in the edit copy. */
static fm_status exec_g10_tool(gc_interp *g, const gc_block *b, int l, int col)
{
    if (!HAS(b, 'p'))
        return gc_fail(g, FM_ERR_INPUT, col, "G10 L%d: P word missing; expected P<tool number>", l);
    int tool = 0;
    fm_status st = gc_int_word(g, b, 'p', &tool);
    if (st) return st;
    if (tool <= 0)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'), "G10 L%d P%d: expected a tool number > 0", l,
                       tool);
    if ((st = gc_check_tool(g, tool, COL(b, 'p'), "P"))) return st;
    gc_tool_edit *e = NULL;
    if ((st = edit_tool(g, tool, &e))) return st;
    if (l == 1) {
        if (HAS(b, 'r')) e->diameter = 2 * VAL(b, 'r') * g->unit;
        if (HAS(b, 'z')) e->length = VAL(b, 'z') * g->unit;
        gc_refresh_tool_params(g);
        return FM_OK;
    }
    if (!HAS(b, 'z')) {
        gc_refresh_tool_params(g);
        return FM_OK;
    }
    double z = VAL(b, 'z');
    double spindle_z = g->pos[2] + g->tlo[2]; /* where Z would read without a tool offset */
    if (l == 10) {
        e->length = (spindle_z - z) * g->unit;
    } else {
        int base = cs_param_base(9);
        e->length = (spindle_z + g->g5x[2] + g->g92[2] - g->params[base + 2] - z) * g->unit;
    }
    if (HAS(b, 'r')) e->diameter = 2 * VAL(b, 'r') * g->unit;
    gc_refresh_tool_params(g);
    return FM_OK;
}

fm_status gc_exec_g10(gc_interp *g, const gc_block *b, int col)
{
    if (!HAS(b, 'l'))
        return gc_fail(g, FM_ERR_INPUT, col, "G10: L word missing; expected L1, L2, L10, L11 or L20");
    double l = VAL(b, 'l');
    if (l == 1 || l == 10 || l == 11) return exec_g10_tool(g, b, (int)l, col);
    if (l != 2 && l != 20)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                       "G10 L%g: expected L1, L2, L10, L11 or L20", l);
    if (!HAS(b, 'p'))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G10 L%g: P word missing; expected P0 (active) or P1..P9", l);
    double pv = VAL(b, 'p');
    if (pv < 0 || pv > 9 || floor(pv) != pv)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'),
                       "G10 L%g P%g: expected a coordinate system P0 to P9", l, pv);
    int cs = pv == 0 ? g->cs : (int)pv;
    if (cs == g->cs && g->comp.side != GC_COMP_OFF)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G10 L%g: changing the active coordinate system with cutter radius "
                       "compensation on; expected G40 first", l);
    int base = cs_param_base(cs);
    const char ax[3] = {'x', 'y', 'z'};
    if (HAS(b, 'r')) g->params[base + 9] = VAL(b, 'r');
    if (l == 2) {
        for (int i = 0; i < 3; i++)
            if (b->has[L(ax[i])]) g->params[base + i] = b->v[L(ax[i])];
    } else {
        /* L20: the current point gets the given coordinates in system P: its
         * origin = the spindle point - R(rotation of P) (coordinates + G92) */
        double m[3], spindle[3], p[3];
        gc_to_machine(g, g->pos, m);
        for (int i = 0; i < 3; i++) spindle[i] = m[i] / g->unit + g->tlo[i];
        double t = g->params[base + 9] * FM_PI / 180.0, c = cos(t), sn = sin(t);
        /* the current point in system P, then the given axes replaced */
        double dx = spindle[0] - g->params[base], dy = spindle[1] - g->params[base + 1];
        p[0] = dx * c + dy * sn - g->g92[0];
        p[1] = -dx * sn + dy * c - g->g92[1];
        p[2] = spindle[2] - g->params[base + 2] - g->g92[2];
        for (int i = 0; i < 3; i++)
            if (b->has[L(ax[i])]) p[i] = b->v[L(ax[i])];
        double qx = p[0] + g->g92[0], qy = p[1] + g->g92[1];
        double nx = spindle[0] - (qx * c - qy * sn), ny = spindle[1] - (qx * sn + qy * c);
        double nz = spindle[2] - (p[2] + g->g92[2]);
        if (b->has[L('x')] || t != 0) g->params[base] = nx;
        if (b->has[L('y')] || t != 0) g->params[base + 1] = ny;
        if (b->has[L('z')]) g->params[base + 2] = nz;
    }
    gc_rot_g10(g, b, (int)l, base);
    if (cs == g->cs) gc_set_g5x(g, cs);
    return FM_OK;
}

fm_status gc_exec_g92(gc_interp *g, const gc_block *b, int code, int col)
{
    const char ax[3] = {'x', 'y', 'z'};
    if (code == GC_G52) {
        /* LinuxCNC keeps G52's offset in G92's: each given axis's offset
         * becomes the value */
        for (int i = 0; i < 3; i++) {
            if (!b->has[L(ax[i])]) continue;
            double w = b->v[L(ax[i])];
            g->pos[i] += g->g92[i] - w;
            g->g92[i] = w;
            g->params[GC_PARAM_G92 + i] = w;
        }
        gc_rot_g92(g, b, code);
        g->params[GC_PARAM_G92_ENABLED] = 1;
        return FM_OK;
    }
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
        gc_rot_g92(g, b, code);
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
    gc_rot_g92(g, b, code);
    g->params[GC_PARAM_G92_ENABLED] = code == GC_G92_3;
    return FM_OK;
}

/* G28/G30: optional intermediate point, then rapid to the stored position
 * (#5161.. / #5181.., machine millimetres). */
fm_status gc_exec_home(gc_interp *g, const gc_block *b, int code)
{
    int base = code == GC_G28 ? GC_PARAM_G28_HOME : GC_PARAM_G30_HOME;
    double mid[3], home[3], stored[3], m[3];
    fm_status st = gc_find_ends(g, b, 0, mid);
    if (st) return st;
    if ((st = gc_move_line(g, 1, mid))) return st;
    for (int i = 0; i < 3; i++) m[i] = g->params[base + i] - g->tlo[i] * g->unit;
    gc_from_machine(g, m, stored);
    const char ax[3] = {'x', 'y', 'z'};
    int any = HAS(b, 'x') || HAS(b, 'y') || HAS(b, 'z');
    for (int i = 0; i < 3; i++) {
        if (any && !b->has[L(ax[i])] && gc_block_has_axis(b)) home[i] = mid[i];
        else if (!any && gc_block_has_axis(b)) home[i] = mid[i];
        else home[i] = stored[i];
    }
    gc_rot_home(g, b, base);
    return gc_move_line(g, 1, home);
}

void gc_store_home(gc_interp *g, int code)
{
    int base = code == GC_G28_1 ? GC_PARAM_G28_HOME : GC_PARAM_G30_HOME;
    double m[3];
    gc_to_machine(g, g->pos, m);
    for (int i = 0; i < 3; i++) g->params[base + i] = m[i] + g->tlo[i] * g->unit;
    gc_rot_store_home(g, base);
}

/* G43 H (the table's length of tool H, or of the spindle tool without H),
 * G43.1 (the offset given by the axis words), G49 (none). */
fm_status gc_exec_tool_length(gc_interp *g, const gc_block *b, int code, int col)
{
    fm_status st;
    if (code == GC_G43 || code == GC_G43_4) {
        /* G43.4: the same length offset, and tool centre point control on */
        if (code == GC_G43_4 && (st = gc_rot_tcp(g, 1, col))) return st;
        int h = g->tool;
        if (HAS(b, 'h') && (st = gc_int_word(g, b, 'h', &h))) return st;
        h = gc_register_tool(g, 'h', h);
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
        gc_rot_tcp(g, 0, col);
    }
    return FM_OK;
}

/* ---- the ISO dialects' work offsets and reference returns ---- */

void gc_work_offset_apply(gc_interp *g)
{
    double work[3];
    gc_frame_to_work(g, g->frame.prog, work);
    for (int i = 0; i < 3; i++) {
        double table = g->ext_cs ? g->ext_offsets[g->ext_cs - 1][i]
                                 : g->params[5201 + 20 * g->cs + i];
        double w = table + g->params[5201 + i] + g->local_offset[i];
        double shift = g->g5x[i] - w;
        g->pos[i] += shift;
        work[i] += shift;
        g->g5x[i] = w;
    }
    /* a pending tool length move stays pending: shift the programmed point
     * by the same amount rather than recomputing it from pos */
    gc_frame_from_work(g, work, g->frame.prog);
}

void gc_work_offset_select(gc_interp *g, int cs, int ext)
{
    g->ext_cs = ext;
    if (!ext) g->cs = cs;
    gc_work_offset_apply(g);
}

void gc_work_offset_local(gc_interp *g, const int given[3], const double value[3])
{
    for (int i = 0; i < 3; i++)
        if (given[i]) g->local_offset[i] = value[i];
    gc_work_offset_apply(g);
}

/* Work coordinates of machine coordinate m (program units) on axis i. */
static double work_of_machine(const gc_interp *g, int i, double m)
{
    return m - g->g5x[i] - g->g92[i] - g->tlo[i];
}

fm_status gc_move_machine(gc_interp *g, const int given[3], const double value[3])
{
    double to[3];
    for (int i = 0; i < 3; i++) to[i] = given[i] ? work_of_machine(g, i, value[i]) : g->pos[i];
    fm_status st = gc_move_line(g, 1, to); /* G53 positions at rapid traverse */
    if (st) return st;
    gc_frame_reprogram(g);
    return FM_OK;
}

fm_status gc_move_reference(gc_interp *g, int ref, const int given[3], const double mid[3])
{
    fm_status st = gc_frame_move(g, 1, mid);
    if (st) return st;
    double to[3];
    for (int i = 0; i < 3; i++)
        to[i] = given[i] ? work_of_machine(g, i, g->opt.reference_points[ref][i] / g->unit)
                         : g->pos[i];
    if ((st = gc_move_line(g, 1, to))) return st;
    gc_frame_reprogram(g);
    return FM_OK;
}
