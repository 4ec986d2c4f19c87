/* job_tools.c: the job's tool table built into cutters: the standard
 * shapes by lib/tools, custom cutters from their HyperFun models (a file
 * named relative to the tool table's). */
#include <ctype.h>
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

/* Does the G-code select inches (a G20 word outside comments)? The text,
 * or the first MiB of the program's file: posts write G20 in the header,
 * with the tool comments. */
static int gcode_selects_inch(const char *text, size_t len)
{
    int depth = 0, line_comment = 0;
    for (size_t i = 0; i < len; i++) {
        char c = text[i];
        if (c == '\n') line_comment = depth = 0;
        else if (line_comment) continue;
        else if (c == '(') depth++;
        else if (c == ')' && depth) depth--;
        else if (depth) continue;
        else if (c == ';') line_comment = 1;
        else if ((c == 'G' || c == 'g') && !(i > 0 && isalpha((unsigned char)text[i - 1]))) {
            size_t j = i + 1;
            while (j < len && text[j] == ' ') j++;
            while (j < len && text[j] == '0') j++; /* G020 */
            if (j + 1 < len && text[j] == '2' && text[j + 1] == '0' &&
                (j + 2 >= len || (!isdigit((unsigned char)text[j + 2]) && text[j + 2] != '.')))
                return 1;
        }
    }
    return 0;
}

static int ignore_motion(void *user, const fm_motion *motion)
{
    (void)user;
    (void)motion;
    return 0;
}

fm_status fm_job_tools_from_program(const fm_job_spec *spec, const fm_tooltable_options *opt,
                                    fm_tool_table *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    if (job_program_kind(spec) != FM_PROGRAM_GCODE)
        return fm_error_set(err, FM_ERR_INPUT, "tools from the program: the program is not G-code "
                            "(only G-code programs carry the tool comments CAM posts write)");
    const char *name = spec->program_path ? spec->program_path
                                          : spec->program_name ? spec->program_name : "program";
    int inch = 0;
    if (spec->program_text) {
        inch = gcode_selects_inch(spec->program_text, spec->program_length);
    } else if (spec->program_path) {
        /* within the interpreter's own default budget; a file it cannot read
         * is reported by the interpretation below */
        char *text = NULL;
        size_t len = 0;
        fm_error ignored;
        if (fm_file_read(spec->program_path, "program", (size_t)256 << 20, &text, &len,
                         &ignored) == FM_OK)
            inch = gcode_selects_inch(text, len);
        free(text);
    }
    fm_tooltable_comments *c = fm_tooltable_comments_new(name, inch);
    if (!c) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_gcode_options gopt;
    fm_traj_options topt;
    fm_status st = fm_job_program_options(spec, NULL, &gopt, &topt, err);
    gopt.comment = fm_tooltable_comments_add;
    gopt.comment_user = c;
    if (st == FM_OK) st = fm_job_program_run(spec, &gopt, &topt, ignore_motion, NULL, err);
    if (st == FM_OK) st = fm_tooltable_comments_finish(c, opt, out, err);
    fm_tooltable_comments_free(c);
    if (st == FM_OK && out->count == 0)
        st = fm_error_at(err, FM_ERR_INPUT, name, 0, 0,
                         "tools from the program: no comment names a tool (\"T1 D=6. CR=0. - "
                         "FLAT END MILL\", \"T1 D6\"); give a tool table");
    return st;
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
