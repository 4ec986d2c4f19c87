/* job_program.c: the one program dispatch: a job's program (G-code of
 * either dialect, or a parametric trajectory) interpreted into motions
 * with the spec's options; the machine's state at the start; and the
 * stop-at rule. */
#include <ctype.h>
#include <string.h>

#include "job_internal.h"
#include "toolpaths/tooltable/tooltable.h"

int fm_path_has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    if (n <= e) return 0;
    for (size_t i = 0; i < e; i++)
        if (tolower((unsigned char)path[n - e + i]) != tolower((unsigned char)ext[i])) return 0;
    return 1;
}

fm_program_kind job_program_kind(const fm_job_spec *spec)
{
    if (spec->program_kind != FM_PROGRAM_AUTO) return spec->program_kind;
    const char *name = spec->program_path ? spec->program_path : spec->program_name;
    if (name && fm_path_has_extension(name, ".json")) return FM_PROGRAM_TRAJECTORY;
    return FM_PROGRAM_GCODE;
}

fm_status fm_job_program_options(const fm_job_spec *spec, const fm_tool_table *tools,
                                 fm_gcode_options *gcode, fm_traj_options *traj, fm_error *err)
{
    fm_traj_options_default(traj);
    if (spec->rapid_rate > 0) traj->rapid_rate = spec->rapid_rate;
    fm_gcode_options_default(gcode);
    if (spec->rapid_rate > 0) gcode->rapid_rate = spec->rapid_rate;
    gcode->tools = tools;
    if (spec->dialect && !fm_gcode_dialect_parse(spec->dialect, &gcode->dialect))
        return fm_error_set(err, FM_ERR_INPUT, "dialect '%s': expected linuxcnc or fanuc",
                            spec->dialect);
    gcode->subroutine_path = spec->subroutine_path;
    memcpy(gcode->reference_points, spec->reference_points, sizeof gcode->reference_points);
    gcode->calculator_input = spec->calculator_input;
    gcode->machine = spec->machine;
    gcode->has_start = spec->has_start;
    memcpy(gcode->start, spec->start, sizeof gcode->start);
    gcode->initial_tool = spec->initial_tool;
    return FM_OK;
}

void fm_job_spec_start_state(fm_job_spec *spec, const fm_check_machine *machine, int initial_tool)
{
    fm_gcode_dialect dialect = FM_GCODE_LINUXCNC;
    if (spec->dialect) fm_gcode_dialect_parse(spec->dialect, &dialect);
    spec->has_start = 1;
    if (machine && machine->has_start)
        memcpy(spec->start, machine->start, sizeof spec->start);
    else if (dialect == FM_GCODE_FANUC) /* after power-on the machine returns to it */
        memcpy(spec->start, spec->reference_points[0], sizeof spec->start);
    else
        memset(spec->start, 0, sizeof spec->start);
    spec->initial_tool = initial_tool > 0 ? initial_tool : machine ? machine->initial_tool : 0;
}

fm_status fm_job_program_run(const fm_job_spec *spec, const fm_gcode_options *gcode,
                             const fm_traj_options *traj, fm_motion_sink sink, void *user,
                             fm_error *err)
{
    if (!spec->program_path && !spec->program_text)
        return fm_error_set(err, FM_ERR_INPUT, "no program given");
    if (job_program_kind(spec) == FM_PROGRAM_TRAJECTORY) {
        if (spec->program_path)
            return fm_traj_run_file(spec->program_path, traj, sink, user, NULL, err);
        return fm_traj_run_string(spec->program_text, spec->program_length,
                                  spec->program_name ? spec->program_name : "trajectory", traj,
                                  sink, user, NULL, err);
    }
    if (spec->program_path)
        return fm_gcode_run_file(spec->program_path, gcode, sink, user, NULL, err);
    return fm_gcode_run_string(spec->program_text, spec->program_length,
                               spec->program_name ? spec->program_name : "program", gcode, sink,
                               user, NULL, err);
}

fm_status job_run_program(const fm_job_spec *spec, const fm_tool_table *tools,
                          fm_motion_sink sink, void *user, job_probe_fn probe, fm_error *err)
{
    fm_gcode_options gopt;
    fm_traj_options topt;
    fm_status st = fm_job_program_options(spec, tools, &gopt, &topt, err);
    if (st != FM_OK) return st;
    gopt.probe = probe;
    gopt.probe_user = user;
    return fm_job_program_run(spec, &gopt, &topt, sink, user, err);
}

fm_status fm_job_interpret(const fm_job_spec *spec, fm_motion_sink sink, void *user,
                           fm_error *err)
{
    if (spec->tools) return job_run_program(spec, spec->tools, sink, user, NULL, err);
    fm_tool_table table;
    memset(&table, 0, sizeof table);
    fm_status st = spec->tools_path ? fm_tooltable_load(spec->tools_path, &table, err)
                                    : fm_error_set(err, FM_ERR_INPUT, "no tool table given");
    if (st == FM_OK) st = job_run_program(spec, &table, sink, user, NULL, err);
    fm_tool_table_free(&table);
    return st;
}

int job_stop_before(job_stop_rule *r, const fm_motion *m)
{
    if (r->line <= 0) return 0;
    if (m->line == r->line) {
        r->seen = 1;
        return 0;
    }
    return r->seen || m->line > r->line;
}
