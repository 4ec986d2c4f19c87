/* machine.c: the machine's state: made for a program text (its lines
 * indexed, bounded by max_program_bytes) in a neutral state that a front end
 * completes with its dialect's power-on modes, and freed; unit changes,
 * tool numbers and whole-number words, which every dialect checks alike. */
#include "machine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

fm_status gc_machine_init(gc_interp *g, const char *text, size_t len, const char *name,
                          const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                          fm_error *err)
{
    memset(g, 0, sizeof *g);
    if (opt) g->opt = *opt;
    else fm_gcode_options_default(&g->opt);
    if (g->opt.rapid_rate <= 0) g->opt.rapid_rate = 5000.0;
    if (g->opt.max_iterations <= 0) g->opt.max_iterations = 10000000L;
    if (g->opt.max_call_depth <= 0) g->opt.max_call_depth = 64;
    if (g->opt.max_program_bytes == 0) g->opt.max_program_bytes = (size_t)256 << 20;
    gc_rot_start(g);
    g->err = err;
    g->name = name ? name : "";
    g->text = text;
    g->len = len;
    g->sink = sink;
    g->user = user;
    if (len > g->opt.max_program_bytes)
        return fm_error_at(err, FM_ERR_LIMIT, g->name, 0, 0,
                           "program of %zu bytes is larger than the limit of %zu bytes "
                           "(max_program_bytes)", len, g->opt.max_program_bytes);
    fm_status st = gc_index_lines(text, len, g->name, &g->line_start, &g->nlines, err);
    if (st) return st;
    g->unit = g->opt.start_inch ? GC_INCH : 1.0;
    g->plane = GC_PLANE_XY;
    g->absolute = 1;
    g->arc_absolute = 0;
    g->motion = GC_G80;
    g->cs = 1;
    g->params[GC_PARAM_COORD_SYSTEM] = 1;
    g->nlines_all = g->nlines;
    g->line_name = g->name;
    g->comp.firstmove = 1;
    g->nurbs_order = 3;
    return FM_OK;
}

fm_status gc_machine_start(gc_interp *g)
{
    int tool = g->opt.initial_tool;
    if (tool < 0 || (tool > 0 && g->opt.tools && !fm_tool_table_find(g->opt.tools, tool)))
        return fm_error_at(g->err, FM_ERR_INPUT, g->name, 0, 0,
                           "the initial tool %d is not in the tool table; expected one of its "
                           "numbers (--initial-tool, options.initial_tool, the machine's "
                           "initial_tool)",
                           tool);
    if (tool > 0) {
        g->tool = g->selected_tool = tool;
        gc_refresh_tool_params(g);
    }
    if (g->opt.has_start) {
        /* the tip at start: the spindle's point is the tool's length above */
        for (int i = 0; i < 3; i++) g->mpos[i] = g->opt.start[i];
        g->mpos[2] += gc_tool_length_mm(g, g->tool);
        memcpy(g->canon, g->mpos, sizeof g->canon);
        gc_from_machine(g, g->mpos, g->pos);
        gc_frame_reprogram(g);
    }
    return FM_OK;
}

void gc_machine_free(gc_interp *g)
{
    free(g->line_start);
    free(g->ln.s);
    free(g->ln.col);
    free(g->scan.s);
    free(g->scan.col);
    gc_comp_free(&g->comp);
    gc_comp_c_free(g);
    gc_spline_free(&g->spline);
    free(g->nurbs);
    free(g->tool_edits);
    gc_sources_free(g);
}

void gc_set_units(gc_interp *g, double unit)
{
    if (unit == g->unit) return;
    double f = g->unit / unit;
    for (int i = 0; i < 3; i++) {
        g->pos[i] *= f;
        g->g5x[i] *= f;
        g->g92[i] *= f;
        g->tlo[i] *= f;
    }
    gc_comp_scale(g, f);
    gc_frame_scale_units(g, f);
    for (int i = 0; i < 3; i++) g->local_offset[i] *= f;
    g->unit = unit;
}

fm_status gc_check_tool(gc_interp *g, int tool, int col, const char *word)
{
    if (tool < 0)
        return gc_fail(g, FM_ERR_INPUT, col, "%s%d: expected a tool number >= 0", word, tool);
    if (g->opt.tools && tool != 0 && !fm_tool_table_find(g->opt.tools, tool))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s%d: tool %d is not in the tool table; expected one of its numbers",
                       word, tool, tool);
    return FM_OK;
}

fm_status gc_int_word(gc_interp *g, const gc_block *b, char c, int *out)
{
    double v = VAL(b, c);
    if (floor(v) != v || fabs(v) > 1e9)
        return gc_fail(g, FM_ERR_INPUT, COL(b, c), "%c%g: expected a whole number", c - 32, v);
    *out = (int)v;
    return FM_OK;
}
