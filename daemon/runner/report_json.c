/* report_json.c: a job's result as the JSON report shared by `frepmill
 * simulate --report` and the daemon's /v1/jobs/{id}/report. */
#include "report_json.h"

#include "findings_json.h"

static json_t *position_json(const double p[3])
{
    return json_pack("[f, f, f]", p[0], p[1], p[2]);
}

/* "design": the deviation from the design (docs/simulate.md). */
static json_t *design_json(const fm_job_result *r)
{
    const fm_deviation *d = &r->deviation;
    json_t *gouges = json_array(), *excess = json_array();
    for (size_t i = 0; i < d->gouge_count; i++) {
        const fm_deviation_region *g = &d->gouges[i];
        const fm_job_blame *b = &r->gouge_blame[i];
        json_array_append_new(
            gouges, json_pack("{s:o, s:o, s:f, s:o, s:f}", "line",
                              b->line > 0 ? json_integer(b->line) : json_null(), "tool",
                              b->line > 0 ? json_integer(b->tool) : json_null(), "depth_mm",
                              g->depth_mm, "position", position_json(g->position), "volume_mm3",
                              g->volume_mm3));
    }
    for (size_t i = 0; i < d->excess_count; i++) {
        const fm_deviation_region *e = &d->excess[i];
        json_array_append_new(excess, json_pack("{s:f, s:o, s:f}", "depth_mm", e->depth_mm,
                                                "position", position_json(e->position),
                                                "volume_mm3", e->volume_mm3));
    }
    return json_pack("{s:f, s:f, s:f, s:f, s:f, s:I, s:I, s:o, s:o}", "tolerance_mm",
                     d->tolerance_mm, "max_gouge_mm", d->max_gouge_mm, "max_excess_mm",
                     d->max_excess_mm, "gouge_volume_mm3", d->gouge_volume_mm3,
                     "excess_volume_mm3", d->excess_volume_mm3, "gouge_regions",
                     (json_int_t)d->gouge_total, "excess_regions", (json_int_t)d->excess_total,
                     "gouges", gouges, "excess", excess);
}

static json_t *xyz_json(const double p[3])
{
    return json_pack("[f, f, f]", p[0], p[1], p[2]);
}

/* The thin-wall warning: material the volume counts and the mesh cannot
 * show (docs/simulate.md). */
static json_t *thin_json(const fm_stock_thin_report *t)
{
    json_t *places = json_array();
    for (size_t i = 0; i < t->count; i++) {
        const fm_stock_thin_region *g = &t->region[i];
        json_array_append_new(places, json_pack("{s:s, s:o, s:o, s:o, s:I}", "kind", g->wall ? "wall" : "edge",
                                                "position", xyz_json(g->position), "lo", xyz_json(g->lo),
                                                "hi", xyz_json(g->hi), "voxels", (json_int_t)g->voxels));
    }
    return json_pack("{s:I, s:I, s:I, s:b, s:o}", "walls", (json_int_t)t->walls, "voxels",
                     (json_int_t)t->voxels, "regions", (json_int_t)t->regions, "truncated", t->truncated,
                     "places", places);
}

json_t *fm_job_report_json(const fm_job_result *r)
{
    json_t *tools = json_array();
    for (size_t i = 0; i < r->tool_count; i++) {
        /* the tool as its library names it, and the library's presets */
        json_t *t = json_pack("{s:i, s:f, s:s}", "tool", r->tools[i].tool, "removed_volume_mm3",
                              r->tools[i].removed_mm3, "description",
                              r->tool_info[i].description);
        if (t && r->tool_info[i].flute_count > 0)
            json_object_set_new(t, "flutes", json_integer(r->tool_info[i].flute_count));
        if (t && r->tool_info[i].preset_count > 0) {
            json_t *presets = json_array();
            for (int k = 0; k < r->tool_info[i].preset_count && k < FM_TOOL_MAX_PRESETS; k++) {
                const fm_tool_preset *p = &r->tool_info[i].presets[k];
                json_array_append_new(
                    presets, json_pack("{s:s, s:f, s:f, s:f, s:f, s:f}", "name", p->name,
                                       "spindle_rpm", p->spindle_rpm, "cutting_speed_m_per_min",
                                       p->cutting_speed, "feed_mm_per_min", p->feed,
                                       "plunge_feed_mm_per_min", p->plunge_feed,
                                       "feed_per_tooth_mm", p->feed_per_tooth));
            }
            json_object_set_new(t, "presets", presets);
        }
        json_array_append_new(tools, t);
    }
    json_t *blocks = json_array();
    for (size_t i = 0; i < r->top_block_count; i++) {
        const fm_stock_block *b = &r->top_blocks[i];
        double span = b->t1 - b->t0;
        json_array_append_new(
            blocks, json_pack("{s:I, s:f, s:f, s:f, s:f}", "line", (json_int_t)b->block,
                              "removed_volume_mm3", b->removed_mm3, "t0", b->t0, "t1", b->t1,
                              "removal_rate_mm3_per_s", span > 0 ? b->removed_mm3 / span : 0.0));
    }
    json_t *out = json_pack("{s:f, s:f, s:f, s:f, s:I, s:I, s:f, s:f, s:I, s:f, s:o, s:o, s:b}",
                     "initial_volume_mm3", r->initial_volume_mm3, "final_volume_mm3",
                     r->final_volume_mm3, "removed_volume_mm3", r->removed_volume_mm3,
                     "surface_area_mm2", r->surface_area_mm2, "motions", (json_int_t)r->motions,
                     "blocks", (json_int_t)r->blocks, "program_time_s", r->program_time_s,
                     "wall_time_s", r->wall_time_s, "peak_memory_bytes",
                     (json_int_t)r->peak_memory_bytes, "voxel_mm", r->voxel_mm, "tools", tools,
                     "top_blocks", blocks, "stopped", r->stopped);
    /* the budget warning (docs/simulate.md): always there, 0 when the
     * cuts are exact to the sweep's tolerance */
    if (out) {
        /* the controller's time beside the feed-only program_time_s
         * (docs/plan.md); without dynamics the two are the same */
        json_object_set_new(out, "cycle_time_s", json_real(r->cycle_time_s));
        json_object_set_new(out, "cycle_time_planned", json_boolean(r->cycle_time_planned));
        /* cycle_time_s per tool, operation and block, feed-only beside */
        if (r->has_cycle_times) {
            fm_cycle_times view;
            fm_cycle_summary_view(&r->cycle_times, &view);
            json_t *ct = fm_cycle_times_json(&view);
            if (ct) json_object_set_new(out, "cycle_times", ct);
        }
        json_object_set_new(out, "voxels_uncertain", json_integer((json_int_t)r->voxels_uncertain));
        json_object_set_new(out, "uncertain_max_mm", json_real(r->uncertain_max_mm));
        json_object_set_new(out, "uncertain_line", r->voxels_uncertain && r->uncertain_line > 0
                                                       ? json_integer(r->uncertain_line)
                                                       : json_null());
    }
        /* the collision check run in the same pass */
    if (out && r->check) {
        json_object_set_new(out, "findings", fm_findings_json_array(r->check));
        json_object_set_new(out, "check_time_s", json_real(r->check_time_s));
    }
    if (out && r->has_thin) json_object_set_new(out, "thin_walls", thin_json(&r->thin));
    if (out && r->stopped_at_line)
        json_object_set_new(out, "stopped_at_line", json_integer(r->stopped_at_line));
    if (out && r->has_deviation) json_object_set_new(out, "design", design_json(r));
    /* the no-tool warning (docs/simulate.md): always there, null when no
     * feed motion went into the stock with an empty spindle */
    if (out)
        json_object_set_new(
            out, "no_tool",
            r->no_tool_motions
                ? json_pack("{s:i, s:I, s:s}", "line", r->no_tool_line, "motions",
                            (json_int_t)r->no_tool_motions, "message",
                            "feed motions with no tool in the spindle go into the stock and cut "
                            "nothing; give the tool in the spindle at the start "
                            "(--initial-tool N, options.initial_tool or the machine's "
                            "initial_tool) or load it with M6")
                : json_null());
    return out;
}
