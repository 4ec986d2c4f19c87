/* job_tools.c: the job's tool table built into cutters: the standard
 * shapes by lib/tools, custom cutters from their HyperFun models (a file
 * named relative to the tool table's). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hf/hf.h"
#include "job_internal.h"
#include "toolpaths/tooltable/tooltable.h"

void job_tools_free(job_tools *t)
{
    for (size_t i = 0; i < t->count; i++) {
        if (t->built[i].tool.flutes.kind == FM_TOOL_PART_CUSTOM)
            fm_tool_custom_release(&t->built[i].tool.flutes.custom);
        fm_tape_free(t->built[i].tape);
        fm_graph_free(t->built[i].graph);
    }
    free(t->built);
    fm_tool_table_free(&t->table);
    memset(t, 0, sizeof *t);
}

/* The folder part of path (with its slash), or "" for a bare name. */
static void folder_of(const char *path, char *out, size_t size)
{
    const char *slash = path ? strrchr(path, '/') : NULL;
    size_t n = slash ? (size_t)(slash - path + 1) : 0;
    if (n >= size) n = 0;
    if (n) memcpy(out, path, n); /* path may be NULL: memcpy's arguments never may */
    out[n] = '\0';
}

static fm_status build_custom_tool(const fm_tool_spec *spec, const char *tools_path, job_tool *jt,
                                   fm_error *err)
{
    char file[1024];
    if (spec->hyperfun_file[0] == '/') {
        snprintf(file, sizeof file, "%s", spec->hyperfun_file);
    } else {
        char folder[512];
        folder_of(tools_path, folder, sizeof folder);
        snprintf(file, sizeof file, "%s%s", folder, spec->hyperfun_file);
    }
    jt->graph = fm_graph_new(0);
    if (!jt->graph) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_hf_model model;
    fm_status st = fm_hf_compile_file(jt->graph, file, NULL, &model, err);
    if (st != FM_OK) return st;
    jt->tape = fm_tape_compile(jt->graph, model.root, err);
    if (!jt->tape) return err ? err->code : FM_ERR_INPUT;
    fm_tool_custom custom;
    st = fm_tool_custom_from_tape(jt->tape, spec->bound_radius, spec->flute_length, &custom, err);
    if (st != FM_OK) return st;
    st = fm_tool_build_custom(spec, &custom, &jt->tool, err);
    /* once in the tool, job_tools_free releases the table */
    if (st != FM_OK && jt->tool.flutes.custom.ctx != custom.ctx) fm_tool_custom_release(&custom);
    return st;
}

fm_status job_tools_load(const fm_job_spec *spec, job_tools *t, fm_error *err)
{
    memset(t, 0, sizeof *t);
    if (spec->tools) {
        t->use = spec->tools;
    } else if (spec->tools_path) {
        fm_status st = fm_tooltable_load(spec->tools_path, &t->table, err);
        if (st != FM_OK) return st;
        t->use = &t->table;
    } else {
        return fm_error_set(err, FM_ERR_INPUT, "no tool table given (--tools TOOLS.json or .tbl)");
    }
    if (t->use->count == 0)
        return fm_error_set(err, FM_ERR_INPUT, "the tool table %s has no tools",
                            spec->tools_path ? spec->tools_path : "");
    t->built = calloc(t->use->count, sizeof *t->built);
    if (!t->built) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    t->count = t->use->count;
    for (size_t i = 0; i < t->count; i++) {
        const fm_tool_spec *ts = &t->use->tools[i];
        fm_status st = ts->shape == FM_TOOL_HYPERFUN
                           ? build_custom_tool(ts, spec->tools_path, &t->built[i], err)
                           : fm_tool_build(ts, &t->built[i].tool, err);
        if (st != FM_OK) {
            if (err && spec->tools_path && !err->file[0])
                snprintf(err->file, sizeof err->file, "%s", spec->tools_path);
            return st;
        }
    }
    return FM_OK;
}

/* The tool that cuts for a motion: the spindle's, or the table's only tool
 * when the program never loaded one (T0: many single-tool programs have no
 * M6). NULL: nothing cuts. */
const fm_tool *job_tool_for(const job_tools *t, int number)
{
    for (size_t i = 0; i < t->count; i++)
        if (t->built[i].tool.spec.number == number) return &t->built[i].tool;
    if (number == 0 && t->count == 1) return &t->built[0].tool;
    return NULL;
}
