/* cycle_times.c: a program's planned time per tool, per operation and for
 * its slowest blocks, with the feed-only figures beside (cycle_times.h):
 * the one breakdown `frepmill time` prints and the report holds. */
#include "cycle_times.h"

#include <stdlib.h>
#include <string.h>

void fm_cycle_times_init(fm_cycle_times *ct, int top_blocks)
{
    memset(ct, 0, sizeof *ct);
    if (top_blocks > 0) {
        ct->top = calloc((size_t)top_blocks, sizeof *ct->top);
        if (ct->top) ct->top_max = top_blocks;
        else ct->failed = 1;
    }
}

void fm_cycle_times_free(fm_cycle_times *ct)
{
    free(ct->tools);
    free(ct->operations);
    free(ct->top);
    memset(ct, 0, sizeof *ct);
}

/* A finished block into the slowest ones (kept sorted, slowest first). */
static void offer_block(fm_cycle_times *ct, const fm_cycle_block *b)
{
    int i;
    if (ct->top_count < ct->top_max) i = ct->top_count++;
    else if (ct->top_max == 0 || ct->top[ct->top_max - 1].time_s >= b->time_s) return;
    else i = ct->top_max - 1;
    ct->top[i] = *b;
    for (; i > 0 && ct->top[i - 1].time_s < ct->top[i].time_s; i--) {
        fm_cycle_block t = ct->top[i - 1];
        ct->top[i - 1] = ct->top[i];
        ct->top[i] = t;
    }
}

/* Room for one more element of size bytes in *items (count of *cap). */
static int grow(void **items, int count, int *cap, size_t size)
{
    if (count < *cap) return 1;
    int n = *cap ? 2 * *cap : 8;
    void *p = realloc(*items, (size_t)n * size);
    if (!p) return 0;
    *items = p;
    *cap = n;
    return 1;
}

void fm_cycle_times_add(fm_cycle_times *ct, const fm_plan_motion *pm)
{
    const fm_motion *m = &pm->motion;
    const double dt = m->t1 - m->t0, df = pm->feed_t1 - pm->feed_t0;
    ct->time_s += dt;
    ct->feed_only_s += df;
    ct->motions++;
    int k = 0;
    while (k < ct->tool_count && ct->tools[k].tool != m->tool) k++;
    if (k == ct->tool_count) {
        if (!grow((void **)&ct->tools, ct->tool_count, &ct->tool_cap, sizeof *ct->tools)) {
            ct->failed = 1;
            return;
        }
        ct->tools[ct->tool_count++] = (fm_cycle_tool){m->tool, 0, 0};
    }
    ct->tools[k].time_s += dt;
    ct->tools[k].feed_only_s += df;
    /* an operation: from one change of tool to the next */
    if (ct->operation_total == 0 || m->tool != ct->operation_tool) {
        ct->operation_total++;
        ct->operation_tool = m->tool;
        if (ct->operation_count < FM_CYCLE_MAX_OPERATIONS) {
            if (!grow((void **)&ct->operations, ct->operation_count, &ct->operation_cap,
                      sizeof *ct->operations)) {
                ct->failed = 1;
                return;
            }
            ct->operations[ct->operation_count++] =
                (fm_cycle_operation){m->tool, m->line, m->line, m->t0, m->t1, 0, 0};
        }
    }
    if (ct->operation_total == ct->operation_count) {
        fm_cycle_operation *op = &ct->operations[ct->operation_count - 1];
        op->last_line = m->line;
        op->t1 = m->t1;
        op->time_s += dt;
        op->feed_only_s += df;
    }
    if (ct->have_current && ct->current.line != m->line) {
        offer_block(ct, &ct->current);
        ct->have_current = 0;
    }
    if (!ct->have_current) {
        ct->current = (fm_cycle_block){m->line, m->block, 0, 0};
        ct->have_current = 1;
    }
    ct->current.time_s += dt;
    ct->current.feed_only_s += df;
}

void fm_cycle_times_finish(fm_cycle_times *ct)
{
    if (ct->have_current) offer_block(ct, &ct->current);
    ct->have_current = 0;
}

int fm_cycle_times_sink(void *user, const fm_plan_motion *pm)
{
    fm_cycle_times_add(user, pm);
    return 0;
}

static int smaller(int a, int b) { return a < b ? a : b; }

void fm_cycle_times_summarize(const fm_cycle_times *ct, fm_cycle_summary *out)
{
    memset(out, 0, sizeof *out);
    /* A program without motions has no lists at all (NULL): memcpy takes
     * no NULL even for 0 bytes (UBSan, simulate_examples). */
    out->tool_count = smaller(ct->tool_count, FM_CYCLE_SUMMARY_TOOLS);
    if (out->tool_count > 0) memcpy(out->tools, ct->tools, (size_t)out->tool_count * sizeof *out->tools);
    out->operation_count = smaller(ct->operation_count, FM_CYCLE_SUMMARY_OPERATIONS);
    if (out->operation_count > 0)
        memcpy(out->operations, ct->operations, (size_t)out->operation_count * sizeof *out->operations);
    out->operation_total = ct->operation_total;
    out->block_count = smaller(ct->top_count, FM_CYCLE_SUMMARY_BLOCKS);
    if (out->block_count > 0) memcpy(out->blocks, ct->top, (size_t)out->block_count * sizeof *out->blocks);
}

void fm_cycle_summary_view(const fm_cycle_summary *s, fm_cycle_times *view)
{
    memset(view, 0, sizeof *view);
    view->tools = (fm_cycle_tool *)s->tools;
    view->tool_count = s->tool_count;
    view->operations = (fm_cycle_operation *)s->operations;
    view->operation_count = s->operation_count;
    view->operation_total = s->operation_total;
    view->top = (fm_cycle_block *)s->blocks;
    view->top_count = s->block_count;
}

json_t *fm_cycle_times_json(const fm_cycle_times *ct)
{
    json_t *tools = json_array(), *ops = json_array(), *blocks = json_array();
    json_t *out = json_object();
    int ok = tools && ops && blocks && out;
    for (int k = 0; ok && k < ct->tool_count; k++)
        ok = !json_array_append_new(tools, json_pack("{s:i, s:f, s:f}", "tool", ct->tools[k].tool,
                                                     "time_s", ct->tools[k].time_s, "feed_only_s",
                                                     ct->tools[k].feed_only_s));
    for (int k = 0; ok && k < ct->operation_count; k++) {
        const fm_cycle_operation *o = &ct->operations[k];
        ok = !json_array_append_new(
            ops, json_pack("{s:i, s:i, s:i, s:f, s:f, s:f, s:f}", "tool", o->tool, "first_line",
                           o->first_line, "last_line", o->last_line, "t0", o->t0, "t1", o->t1,
                           "time_s", o->time_s, "feed_only_s", o->feed_only_s));
    }
    for (int k = 0; ok && k < ct->top_count; k++) {
        const fm_cycle_block *b = &ct->top[k];
        json_t *o = json_pack("{s:i, s:f, s:f}", "line", b->line, "time_s", b->time_s,
                              "feed_only_s", b->feed_only_s);
        if (o && b->block >= 0) json_object_set_new(o, "block", json_integer((json_int_t)b->block));
        ok = !json_array_append_new(blocks, o);
    }
    if (ok) {
        ok = !json_object_set(out, "tools", tools) && !json_object_set(out, "operations", ops) &&
             !json_object_set_new(out, "operation_count", json_integer((json_int_t)ct->operation_total)) &&
             !json_object_set(out, "blocks", blocks);
    }
    json_decref(tools);
    json_decref(ops);
    json_decref(blocks);
    if (!ok) {
        json_decref(out);
        return NULL;
    }
    return out;
}
