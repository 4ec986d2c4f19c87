/* gcode.c: the G-code module's entry points: options, the table of
 * dialects (each a front end in its own folder, driving the one machine of
 * machine/), reading a program file, and a run: the machine's state made,
 * the dialect's front end started on it, the summary taken. */
#include "machine/machine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

void fm_gcode_options_default(fm_gcode_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->rapid_rate = 5000.0;
    opt->max_program_bytes = (size_t)256 << 20;
    opt->max_iterations = 10000000L;
    opt->max_call_depth = 64;
    opt->peck_retract = 1.0;
    opt->peck_clearance = 1.0;
}

/* The front ends, indexed by fm_gcode_dialect. A new dialect is a folder
 * beside linuxcnc/ and fanuc/ exporting its gc_front_end, and a line here. */
extern const gc_front_end gc_linuxcnc_front, gc_fanuc_front;
static const gc_front_end *const front_ends[] = {
    [FM_GCODE_LINUXCNC] = &gc_linuxcnc_front,
    [FM_GCODE_FANUC] = &gc_fanuc_front,
};
#define FRONT_ENDS (sizeof front_ends / sizeof front_ends[0])

int fm_gcode_dialect_parse(const char *name, fm_gcode_dialect *out)
{
    if (!name) return 0;
    for (size_t i = 0; i < FRONT_ENDS; i++)
        if (!strcasecmp(name, front_ends[i]->name)) {
            *out = (fm_gcode_dialect)i;
            return 1;
        }
    return 0;
}

const char *fm_gcode_dialect_name(fm_gcode_dialect dialect)
{
    if ((size_t)dialect >= FRONT_ENDS) dialect = FM_GCODE_LINUXCNC;
    return front_ends[dialect]->name;
}

static fm_status run_text(const char *text, size_t len, const char *name, int is_file,
                          const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                          fm_gcode_summary *summary, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    if (summary) memset(summary, 0, sizeof *summary);
    if (!text && len) return fm_error_set(err, FM_ERR_INPUT, "no program text");
    gc_interp *g = malloc(sizeof *g);
    if (!g) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_status st = gc_machine_init(g, text ? text : "", len, name, opt, sink, user, err);
    g->program_is_file = is_file;
    fm_gcode_dialect d = g->opt.dialect;
    g->front = front_ends[(size_t)d < FRONT_ENDS ? d : FM_GCODE_LINUXCNC];
    if (!st) st = g->front->init(g);
    if (!st) st = gc_machine_start(g);
    if (!st) st = g->front->run(g);
    if (summary) {
        summary->motions = g->motion_index;
        summary->lines = g->lines_run;
        summary->seconds = g->t;
        summary->ended_by_m2 = g->ended;
        summary->stopped = g->stop && !g->ended;
    }
    g->front->release(g);
    gc_machine_free(g);
    free(g);
    return st;
}

fm_status fm_gcode_run_string(const char *text, size_t len, const char *name,
                              const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                              fm_gcode_summary *summary, fm_error *err)
{
    return run_text(text, len, name, 0, opt, sink, user, summary, err);
}

fm_status fm_gcode_run_file(const char *path, const fm_gcode_options *opt, fm_motion_sink sink,
                            void *user, fm_gcode_summary *summary, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    fm_gcode_options o;
    if (opt) o = *opt;
    else fm_gcode_options_default(&o);
    size_t limit = o.max_program_bytes ? o.max_program_bytes : (size_t)256 << 20;
    char *buf;
    size_t len;
    fm_error ferr;
    fm_status st = fm_file_read(path, "program", limit, &buf, &len, &ferr);
    if (st != FM_OK && !strcmp(ferr.reason, "too_large"))
        return fm_error_at(err, FM_ERR_LIMIT, path, 0, 0,
                           "program is larger than the limit of %zu bytes (max_program_bytes)",
                           limit);
    if (st != FM_OK) {
        if (err) *err = ferr;
        return st;
    }
    st = run_text(buf, len, path, 1, &o, sink, user, summary, err);
    free(buf);
    return st;
}
