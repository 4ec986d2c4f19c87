/* report_json.c: a job's result as the JSON report shared by `frepmill
 * simulate --report` and the daemon's /v1/jobs/{id}/report. */
#include "report_json.h"

#include "findings_json.h"

json_t *fm_job_report_json(const fm_job_result *r)
{
    json_t *tools = json_array();
    for (size_t i = 0; i < r->tool_count; i++)
        json_array_append_new(tools, json_pack("{s:i, s:f}", "tool", r->tools[i].tool,
                                               "removed_volume_mm3", r->tools[i].removed_mm3));
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
    /* the collision check run in the same pass */
    if (out && r->check) {
        json_object_set_new(out, "findings", fm_findings_json_array(r->check));
        json_object_set_new(out, "check_time_s", json_real(r->check_time_s));
    }
    return out;
}
