/* jobs_check.c: the collision check over a canonical job, for jobs and for
 * POST /v1/check (jobs_check.h). */
#include "jobs_check.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "runner/check_pass.h"
#include "runner/findings_json.h"
#include "store.h"
#include "toolpaths/tooltable/tooltable.h"

static json_t *check_options_of(json_t *spec)
{
    return json_object_get(json_object_get(spec, "options"), "check");
}

int fm_jobs_check_enabled(json_t *spec)
{
    return !json_is_false(check_options_of(spec));
}

/* options.check -> lib/check options and the check's voxel. */
static int parse_options(json_t *check, fm_job_check *in, fm_http_error *err)
{
    if (!check || json_is_boolean(check)) return 0;
    if (!json_is_object(check))
        return fm_http_error_set(err, 400, "bad_type", "options.check must be false or an object");
    const char *key;
    json_t *v;
    json_object_foreach(check, key, v)
    {
        double d = json_is_number(v) ? json_number_value(v) : NAN;
        if (!strcmp(key, "machine")) {
            fm_error ferr;
            fm_error_clear(&ferr);
            if (fm_check_machine_from_json(v, "options.check.machine", &in->options.machine,
                                           &ferr) != FM_OK)
                return fm_http_error_set(err, 400, "bad_value", "%s", ferr.message);
            /* a component names a model file on this machine: not from a client */
            if (in->options.machine.component_count)
                return fm_http_error_set(err, 400, "bad_value",
                                         "options.check.machine.components name files on the server; "
                                         "give machine components as fixtures");
            continue;
        }
        int ok = isfinite(d);
        if (!strcmp(key, "clearance") && ok && d >= 0 && d <= 1000) {
            in->options.clearance_mm[FM_CHECK_PART_SHANK] = d;
            in->options.clearance_mm[FM_CHECK_PART_HOLDER] = d;
        } else if (!strcmp(key, "rapid_clearance") && ok && d >= 0 && d <= 1000) {
            in->options.clearance_mm[FM_CHECK_PART_FLUTES] = d;
        } else if (!strcmp(key, "tolerance") && ok && d > 0 && d <= 100) {
            in->options.tolerance_mm = d;
        } else if (!strcmp(key, "max_ramp") && ok && d >= 0 && d <= 90) {
            in->options.max_ramp_deg = d;
        } else if (!strcmp(key, "voxel") && ok && d >= 0.01 && d <= 100) {
            in->voxel_mm = d;
        } else if (!strcmp(key, "clearance") || !strcmp(key, "rapid_clearance") ||
                   !strcmp(key, "tolerance") || !strcmp(key, "max_ramp") ||
                   !strcmp(key, "voxel")) {
            return fm_http_error_set(err, 400, "bad_value", "options.check.%s: not a valid value",
                                     key);
        } else {
            return fm_http_error_set(err, 400, "unknown_key",
                                     "options.check.%s: unknown (clearance, rapid_clearance, "
                                     "tolerance, max_ramp, voxel, machine)",
                                     key);
        }
    }
    return 0;
}

int fm_jobs_check_validate(json_t *spec, fm_http_error *err)
{
    fm_job_check in;
    fm_job_check_default(&in);
    return parse_options(check_options_of(spec), &in, err);
}

/* Write an inline model (HyperFun text or base64 STL) to dir/name. */
static fm_status write_model(json_t *model, const char *dir, const char *stem, char *path,
                             size_t size, fm_error *err)
{
    json_t *hf = json_object_get(model, "hyperfun");
    if (hf) {
        snprintf(path, size, "%s/%s.hf", dir, stem);
        char name[64];
        snprintf(name, sizeof name, "%s.hf", stem);
        return fm_store_write_atomic(dir, name, json_string_value(hf), json_string_length(hf), err);
    }
    json_t *stl = json_object_get(model, "stl_base64");
    uint8_t *bytes;
    size_t n;
    if (fm_http_base64_decode(json_string_value(stl), json_string_length(stl), &bytes, &n) != 0)
        return fm_error_set(err, FM_ERR_INPUT, "%s: stl_base64 is not valid base64", stem);
    snprintf(path, size, "%s/%s.stl", dir, stem);
    char name[64];
    snprintf(name, sizeof name, "%s.stl", stem);
    fm_status st = fm_store_write_atomic(dir, name, bytes, n, err);
    free(bytes);
    return st;
}

struct fm_jobs_check_setup {
    fm_job_check check;
    char paths[FM_JOB_MAX_FIXTURES][PATH_MAX];
};

const fm_job_check *fm_jobs_check_of(const fm_jobs_check_setup *setup) { return &setup->check; }

void fm_jobs_check_setup_free(fm_jobs_check_setup *setup) { free(setup); }

fm_status fm_jobs_check_prepare(json_t *spec, const char *dir, fm_jobs_check_setup **out,
                                fm_error *err)
{
    *out = NULL;
    fm_jobs_check_setup *cs = calloc(1, sizeof *cs);
    if (!cs) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_job_check_default(&cs->check);
    fm_http_error herr;
    if (parse_options(check_options_of(spec), &cs->check, &herr)) {
        free(cs);
        return fm_error_set(err, FM_ERR_INPUT, "%s", herr.message);
    }
    json_t *fixtures = json_object_get(spec, "fixtures");
    size_t i;
    json_t *f;
    json_array_foreach(fixtures, i, f)
    {
        if (i >= FM_JOB_MAX_FIXTURES) break;
        char stem[32];
        snprintf(stem, sizeof stem, "check-fixture%zu", i);
        fm_status st = write_model(f, dir, stem, cs->paths[i], sizeof cs->paths[i], err);
        if (st != FM_OK) {
            free(cs);
            return st;
        }
        cs->check.fixtures[cs->check.fixture_count++] = cs->paths[i];
    }
    *out = cs;
    return FM_OK;
}

fm_status fm_jobs_check_run(json_t *spec, const char *dir, size_t memory_budget,
                            const char *dialect, const char *subroutine_path,
                            fm_jobs_check_result *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    fm_check_pass_input *in = calloc(1, sizeof *in);
    char *stock_path = calloc(1, PATH_MAX);
    fm_jobs_check_setup *cs = NULL;
    fm_tool_table table;
    memset(&table, 0, sizeof table);
    char *tools_text = NULL, *trajectory_text = NULL;
    fm_status st = FM_OK;
    if (!in || !stock_path) {
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        goto done;
    }
    fm_check_pass_input_default(in);
    if ((st = fm_jobs_check_prepare(spec, dir, &cs, err)) != FM_OK) goto done;
    in->check = cs->check;
    json_t *options = json_object_get(spec, "options");
    json_t *v;
    if ((v = json_object_get(options, "rapid_rate"))) in->spec.rapid_rate = json_number_value(v);
    else if (in->check.options.machine.rapid_rate > 0)
        in->spec.rapid_rate = in->check.options.machine.rapid_rate;
    in->spec.stock.memory_budget = memory_budget;
    in->spec.stock.threads = 1; /* a request's thread; leave the cores to the jobs */
    in->spec.dialect = dialect; /* the server's G-code settings, as for jobs */
    if ((v = json_object_get(options, "dialect"))) in->spec.dialect = json_string_value(v);
    in->spec.calculator_input = json_is_true(json_object_get(options, "calculator_input"));
    in->spec.subroutine_path = subroutine_path;

    tools_text = json_dumps(json_object_get(spec, "tools"), JSON_INDENT(1));
    st = tools_text ? fm_tooltable_parse_json(tools_text, strlen(tools_text), "tools", &table, err)
                    : fm_error_set(err, FM_ERR_INPUT, "no tool table");
    if (st != FM_OK) goto done;
    in->spec.tools = &table;
    for (size_t t = 0; t < table.count; t++)
        if (table.tools[t].shape == FM_TOOL_HYPERFUN) {
            /* Such a tool names a model file on this machine (see jobs.c). */
            st = fm_error_set(err, FM_ERR_INPUT,
                              "tools: tool %d is a HyperFun tool that names a file; not accepted "
                              "over HTTP",
                              table.tools[t].number);
            goto done;
        }

    json_t *stock = json_object_get(spec, "stock");
    if (json_is_string(stock)) in->spec.stock_spec = json_string_value(stock);
    else if ((st = write_model(stock, dir, "check-stock", stock_path, PATH_MAX, err)) != FM_OK)
        goto done;
    else in->spec.stock_spec = stock_path;

    json_t *program = json_object_get(spec, "program");
    json_t *gcode = json_object_get(program, "gcode");
    if (gcode) {
        in->spec.program_text = json_string_value(gcode);
        in->spec.program_length = json_string_length(gcode);
        in->spec.program_name = "program";
        in->spec.program_kind = FM_PROGRAM_GCODE;
    } else {
        trajectory_text = json_dumps(json_object_get(program, "trajectory"), JSON_INDENT(1));
        in->spec.program_text = trajectory_text ? trajectory_text : "";
        in->spec.program_length = strlen(in->spec.program_text);
        in->spec.program_name = "trajectory";
        in->spec.program_kind = FM_PROGRAM_TRAJECTORY;
    }

    fm_check *check = NULL;
    st = fm_check_pass_run(in, &check, NULL, err);
    if (st != FM_OK) goto done;
    out->findings = fm_findings_json_array(check);
    out->count = (int)fm_check_count(check);
    out->errors = (int)fm_check_count_severity(check, FM_CHECK_ERROR);
    out->warnings = (int)fm_check_count_severity(check, FM_CHECK_WARNING);
    out->first_line = out->count ? fm_check_get(check, 0)->line : 0;
    fm_check_free(check);
done:
    free(tools_text);
    free(trajectory_text);
    fm_tool_table_free(&table);
    fm_jobs_check_setup_free(cs);
    free(stock_path);
    free(in);
    return st;
}

static atomic_int sync_running;

static size_t program_bytes(json_t *spec)
{
    json_t *program = json_object_get(spec, "program");
    json_t *gcode = json_object_get(program, "gcode");
    if (gcode) return json_string_length(gcode);
    char *text = json_dumps(json_object_get(program, "trajectory"), JSON_COMPACT);
    size_t n = text ? strlen(text) : 0;
    free(text);
    return n;
}

int fm_jobs_check_request(const char *state_dir, size_t memory_budget, const char *dialect,
                          const char *subroutine_path, json_t *request,
                          json_t **out, fm_http_error *err)
{
    char *text = json_dumps(request, JSON_COMPACT);
    if (!text) return fm_http_error_set(err, 400, "bad_job", "the request is not a job");
    json_t *spec = fm_http_job_parse(text, strlen(text), err);
    free(text);
    if (!spec) return err->status;
    int rc = 0;
    size_t bytes = program_bytes(spec);
    if (bytes > FM_JOBS_CHECK_SYNC_MAX_PROGRAM) {
        rc = fm_http_error_set(err, 413, "check_too_large",
                               "the program is %zu bytes; POST /v1/check answers programs up to "
                               "%zu bytes at once. Submit it with POST /v1/jobs: the job's status "
                               "carries the findings",
                               bytes, FM_JOBS_CHECK_SYNC_MAX_PROGRAM);
        goto done;
    }
    if ((rc = fm_jobs_check_validate(spec, err))) goto done;
    if (!fm_jobs_check_enabled(spec)) {
        rc = fm_http_error_set(err, 400, "bad_value", "options.check is false: nothing to do");
        goto done;
    }
    if (atomic_fetch_add(&sync_running, 1) >= FM_JOBS_CHECK_SYNC_MAX_RUNNING) {
        atomic_fetch_sub(&sync_running, 1);
        rc = fm_http_error_set(err, 503, "busy",
                               "%d checks are running; retry, or submit a job",
                               FM_JOBS_CHECK_SYNC_MAX_RUNNING);
        goto done;
    }
    /* A private folder for the inline models (mkdtemp: mode 0700, a name
     * no other request can guess or share). */
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%.3000s/check-XXXXXX", state_dir);
    if (!mkdtemp(dir)) {
        atomic_fetch_sub(&sync_running, 1);
        rc = fm_http_error_set(err, 507, "storage", "cannot create a temporary folder: %s",
                               strerror(errno));
        goto done;
    }
    fm_jobs_check_result res;
    fm_error ferr;
    fm_error_clear(&ferr);
    fm_status st = fm_jobs_check_run(spec, dir, memory_budget, dialect, subroutine_path, &res,
                                     &ferr);
    fm_store_remove_dir(dir, NULL);
    atomic_fetch_sub(&sync_running, 1);
    if (st != FM_OK) {
        int status = st == FM_ERR_INPUT ? 400 : st == FM_ERR_LIMIT ? 413 : 500;
        const char *code = st == FM_ERR_INPUT ? "bad_job" : st == FM_ERR_LIMIT ? "limit" : "internal";
        rc = fm_http_error_set(err, status, code, "%s", ferr.message);
        err->line = ferr.line > 0 ? ferr.line : 0;
        err->column = ferr.column > 0 ? ferr.column : 0;
        goto done;
    }
    *out = json_pack("{s:o, s:i, s:i}", "findings", res.findings, "errors", res.errors, "warnings",
                     res.warnings);
done:
    json_decref(spec);
    return rc;
}
