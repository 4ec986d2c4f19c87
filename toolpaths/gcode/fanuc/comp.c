/* comp.c: cutter radius compensation in the Fanuc dialect: G40, G41 and G42
 * with D (the offset number: tool D's radius, half the table's diameter, or
 * what G10 set), handed to the machine's compensation C (machine.h,
 * gc_comp_c_*) and the codes a control refuses while compensating; moves
 * go through compensation by the machine's gc_frame_* (transform.c). */
#include "fanuc.h"

/* Codes a Fanuc control refuses (or that change what compensation was set
 * up with) between G41/G42 and the end of the cancel block. */
static fm_status refuse(gc_interp *g, int col, const char *what)
{
    return gc_fail(g, FM_ERR_INPUT, col,
                   "%s with cutter radius compensation on; expected G40 and its cancel move "
                   "first", what);
}

fm_status gc_fanuc_comp_check(gc_interp *g, const gc_fanuc_block *fb, int motion)
{
    if (!gc_comp_c_routing(g)) return FM_OK;
    const gc_block *b = &fb->b;
    static const struct {
        gc_group group;
        const char *what;
    } groups[] = {
        {GC_GROUP_PLANE, "a plane change"},
        {GC_GROUP_UNITS, "G20/G21"},
        {GC_GROUP_TOOL_LENGTH, "a tool length offset change"},
        {GC_GROUP_COORD_SYSTEM, "a work offset change"},
        {GC_GROUP_POLAR, "G15/G16"},
        {GC_GROUP_ROTATION, "G68/G69"},
        {GC_GROUP_SCALING, "G50/G51"},
    };
    int col;
    for (size_t i = 0; i < sizeof groups / sizeof groups[0]; i++)
        if (gc_block_g(b, groups[i].group, &col) != GC_G_NONE) return refuse(g, col, groups[i].what);
    int code = gc_block_g(b, GC_GROUP_NON_MODAL, &col);
    switch (code) {
    case GC_G10: return refuse(g, col, "G10");
    case GC_G27: case GC_G28: case GC_G30: return refuse(g, col, "a reference point return");
    case GC_G52: return refuse(g, col, "G52");
    case GC_G53: return refuse(g, col, "G53");
    case GC_G92: return refuse(g, col, "G92");
    default: break;
    }
    code = gc_block_g(b, GC_GROUP_CYCLE, &col);
    if (code != GC_G_NONE && code != GC_G80) return refuse(g, col, "a canned cycle");
    if (motion >= GC_G73 && motion != GC_G80 && (b->has[L('x')] || b->has[L('y')]))
        return refuse(g, b->col[L(b->has[L('x')] ? 'x' : 'y')], "a canned cycle");
    int mcol;
    if (gc_block_has_m(b, 6, &mcol)) return refuse(g, mcol, "a tool change (M06)");
    for (int i = 0; i < 3; i++)
        if (b->has[L("abc"[i])] && g->opt.machine && g->opt.machine->rotary_count)
            return refuse(g, b->col[L("abc"[i])], "a rotary axis word");
    return FM_OK;
}

fm_status gc_fanuc_comp_mode(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    gc_fanuc *f = FANUC(g);
    const gc_block *b = &fb->b;
    int dcol = b->has[L('d')] ? b->col[L('d')] : col;
    int tool = gc_register_tool(g, 'd', f->d);
    if (b->has[L('d')] && f->d) {
        fm_status st = gc_check_tool(g, tool, dcol, "D");
        if (st) return st;
    }
    double radius = f->d ? gc_tool_comp_radius_mm(g, tool) / g->unit : 0.0;
    if (code == GC_G40) return gc_comp_c_cancel(g);
    if (code == GC_G41 || code == GC_G42) {
        /* a mirror of one plane axis (G51.1) turns G41 into G42 (transform.c) */
        int left = (code == GC_G41) != (gc_frame_mirror_sense(g) < 0);
        return gc_comp_c_start(g, left, radius, col);
    }
    /* a D word alone in offset mode: the new radius from the next element */
    if (b->has[L('d')] && gc_comp_c_on(g)) return gc_comp_c_radius(g, radius, dcol);
    return FM_OK;
}
