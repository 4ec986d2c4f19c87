/* http_service.c: the daemon's implementation of the HTTP server's service
 * interface (protocols/http/http_server.h) over the job manager. Every
 * call reads what the workers published, under the job's lock, and copies
 * it out; the full mesh is assembled from the published chunk meshes, so a
 * download never touches the grid being cut. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "http_service.h"
#include "job_record.h"
#include "jobs_check.h"
#include "publish.h"
#include "runner/toolpath.h"

static fm_status not_found(const char *id, fm_error *err)
{
    return fm_error_set_reason(err, FM_ERR_INPUT, "not_found", "no job %.40s", id);
}

static int svc_ready(void *ctx)
{
    (void)ctx;
    return 1;
}

static fm_status svc_submit(void *ctx, json_t *document, char *id, size_t id_size,
                            fm_error *err)
{
    fm_job_doc *doc = NULL;
    const fm_job_doc_rules rules = fm_jobs_doc_rules(ctx, 0);
    fm_status st = fm_job_doc_from_json(document, &rules, &doc, err);
    if (st != FM_OK) return st;
    return fm_jobs_submit(ctx, doc, id, id_size, err);
}

static fm_status svc_status(void *ctx, const char *id, json_t **out, fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    *out = fm_publish_status_json(j);
    fm_jobs_put(ctx, j);
    return FM_OK;
}

static fm_status svc_list(void *ctx, json_t **out, fm_error *err)
{
    *out = fm_jobs_status_list(ctx);
    return *out ? FM_OK
                : fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
}

static fm_status svc_report(void *ctx, const char *id, json_t **out, fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_status rc = fm_publish_report_json(j, out, err);
    fm_jobs_put(ctx, j);
    return rc;
}

static fm_status svc_chunks(void *ctx, const char *id, uint64_t since, double at_s, json_t **out,
                            fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_status rc = fm_publish_ensure_meshes(j, err);
    if (rc == FM_OK) rc = fm_publish_chunk_list(j, since, at_s, out, err);
    fm_jobs_put(ctx, j);
    return rc;
}

static fm_status svc_chunk(void *ctx, const char *id, const char *name, uint64_t version,
                           fm_http_blob *out, fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_status rc = fm_publish_ensure_meshes(j, err);
    if (rc == FM_OK) rc = fm_publish_chunk_bytes(j, name, version, &out->data, &out->size, err);
    if (rc == FM_OK) out->content_type = "application/octet-stream";
    fm_jobs_put(ctx, j);
    return rc;
}

static fm_status svc_mesh(void *ctx, const char *id, const char *format, fm_http_blob *out,
                    fm_error *err)
{
    fm_mesh_format f = !strcmp(format, "drc")   ? FM_MESH_FORMAT_DRACO
                       : !strcmp(format, "stl") ? FM_MESH_FORMAT_STL
                       : !strcmp(format, "ply") ? FM_MESH_FORMAT_PLY
                       : !strcmp(format, "obj") ? FM_MESH_FORMAT_OBJ
                                                : FM_MESH_FORMAT_UNKNOWN;
    if (f == FM_MESH_FORMAT_UNKNOWN)
        return fm_error_set_reason(err, FM_ERR_INPUT, "bad_parameter",
                                   "format=%.16s: expected drc, stl, ply or obj", format);
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_status rc = fm_publish_ensure_meshes(j, err);
    if (rc) {
        fm_jobs_put(ctx, j);
        return rc;
    }
    fm_error ferr;
    fm_error_clear(&ferr);
    fm_mesh *mesh = fm_publish_mesh_copy(j, &ferr);
    fm_jobs_put(ctx, j);
    fm_status st = mesh ? FM_OK : FM_ERR_LIMIT;
    /* The chunk meshes share their boundary vertices bit for bit: welding
     * gives the whole-grid mesh (mesh.h). */
    if (st == FM_OK) st = fm_mesh_weld(mesh, &ferr);
    if (st == FM_OK) {
        switch (f) {
        case FM_MESH_FORMAT_DRACO:
            st = mesh->triangle_count ? fm_mesh_encode_draco(mesh, NULL, &out->data, &out->size, &ferr)
                                      : fm_error_set(&ferr, FM_ERR_INPUT, "the mesh is empty");
            break;
        case FM_MESH_FORMAT_STL: st = fm_mesh_encode_stl(mesh, &out->data, &out->size, &ferr); break;
        case FM_MESH_FORMAT_PLY: st = fm_mesh_encode_ply(mesh, &out->data, &out->size, &ferr); break;
        default: st = fm_mesh_encode_obj(mesh, &out->data, &out->size, &ferr); break;
        }
    }
    fm_mesh_free(mesh);
    if (st != FM_OK)
        return fm_error_set_reason(err, st, st == FM_ERR_INPUT ? "no_mesh" : "out_of_memory",
                                   "cannot build the mesh: %s", ferr.message);
    out->content_type = f == FM_MESH_FORMAT_OBJ ? "text/plain" : "application/octet-stream";
    return FM_OK;
}

static fm_status svc_cancel(void *ctx, const char *id, fm_error *err)
{
    return fm_jobs_cancel(ctx, id, err);
}

static fm_status svc_remove(void *ctx, const char *id, fm_error *err)
{
    return fm_jobs_remove(ctx, id, err);
}

static fm_status svc_stock_path(void *ctx, const char *id, char *path, size_t size, fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_job_file_path(j, "stock.vdb", path, size);
    fm_jobs_put(ctx, j);
    if (access(path, R_OK) != 0)
        return fm_error_set_reason(err, FM_ERR_INPUT, "no_snapshot",
                                   "job %s has no stock snapshot yet", id);
    return FM_OK;
}

static fm_status svc_stock_mesh_path(void *ctx, const char *id, char *path, size_t size,
                                    fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_status rc = fm_publish_stock_mesh(j, path, size, err);
    fm_jobs_put(ctx, j);
    return rc;
}

static fm_status svc_deviation_path(void *ctx, const char *id, int mesh, char *path, size_t size,
                                   fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    fm_job_file_path(j, mesh ? "deviation.drc" : "deviation.json", path, size);
    fm_jobs_put(ctx, j);
    if (access(path, R_OK) != 0)
        return fm_error_set_reason(err, FM_ERR_INPUT, "no_deviation",
                                   "job %s has no deviation: it has no design, or is not done", id);
    return FM_OK;
}

static int svc_events(void *ctx, const char *id, uint64_t after, int timeout_ms,
                      fm_http_event *out, int cap, int *finished)
{
    *finished = 0;
    job *j = fm_jobs_get(ctx, id);
    if (!j) return -1;
    int n = fm_publish_events_wait(j, after, timeout_ms, out, cap, finished);
    fm_jobs_put(ctx, j);
    return n;
}

/* ------------------------------------------------------------- toolpath -- */

/* GET /v1/jobs/{id}/toolpath: the job's program interpreted again (the same
 * front end, tool table and rapid rate as the run, without touching any
 * stock) into the runner's toolpath (runner/toolpath.h: its motions, points
 * and, on a rotary-table machine, the table's placement at every point),
 * with the job's id, the kind of program, its text and the error that
 * stopped it, if any:
 *   {..., "id", "kind": "gcode" | "trajectory" | "live", "program": TEXT,
 *    "error": null | TEXT}  (docs/api.md) */

#define TOOLPATH_MAX_POINTS 500000
#define TOOLPATH_FORM "{%s,\"id\":\"%s\",\"kind\":\"%s\",\"program\":%s,\"error\":%s}\n"

static int toolpath_sink(void *user, const fm_motion *m)
{
    fm_toolpath_add(user, m);
    return fm_toolpath_truncated(user);
}

/* The toolpath and how many motions reached it (from the motion log). */
typedef struct toolpath_from {
    fm_toolpath *path;
    long motions;
} toolpath_from;

static int toolpath_counted(void *user, const fm_motion *m)
{
    toolpath_from *tf = user;
    tf->motions++;
    return toolpath_sink(tf->path, m);
}

static fm_status svc_toolpath(void *ctx, const char *id, fm_http_blob *out, fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    /* The document is immutable while we hold a reference. */
    const fm_job_spec *spec = &fm_job_document(j)->spec;
    fm_toolpath *path = fm_toolpath_new(TOOLPATH_MAX_POINTS);
    if (!path) {
        fm_jobs_put(ctx, j);
        return fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
    }
    fm_error ferr;
    fm_error_clear(&ferr);
    /* what the job made (its motion log), else the program interpreted */
    char motion_log[JOB_DIR_MAX + 16];
    fm_job_file_path(j, "motions.log", motion_log, sizeof motion_log);
    toolpath_from tf = {path, 0};
    fm_status st = spec->program_kind == FM_PROGRAM_LIVE
                       ? FM_OK
                       : fm_job_motions_replay_file(motion_log, spec->machine, toolpath_counted,
                                                    &tf, &ferr);
    if (st != FM_OK && spec->program_kind != FM_PROGRAM_LIVE && tf.motions == 0) {
        fm_error_clear(&ferr);
        st = fm_job_interpret(spec, toolpath_sink, path, &ferr);
    }
    json_t *prog = json_stringn(spec->program_text ? spec->program_text : "", spec->program_length);
    const char *kind = spec->program_kind == FM_PROGRAM_GCODE  ? "gcode"
                       : spec->program_kind == FM_PROGRAM_LIVE ? "live"
                                                               : "trajectory";
    size_t members_len = 0;
    char *members = fm_toolpath_json_members(path, spec->machine, &members_len);
    fm_toolpath_free(path);
    fm_jobs_put(ctx, j);
    char *prog_json = prog ? json_dumps(prog, JSON_ENCODE_ANY) : NULL;
    json_decref(prog);
    char msg[1024] = "";
    json_t *emsg = st == FM_OK ? json_null() : json_string(fm_error_format(&ferr, msg, sizeof msg));
    char *err_json = json_dumps(emsg, JSON_ENCODE_ANY);
    json_decref(emsg);
    char *text = NULL;
    int n = -1;
    if (members && prog_json && err_json) {
        n = snprintf(NULL, 0, TOOLPATH_FORM, members, id, kind, prog_json, err_json);
        text = n >= 0 ? malloc((size_t)n + 1) : NULL;
        if (text) snprintf(text, (size_t)n + 1, TOOLPATH_FORM, members, id, kind, prog_json, err_json);
        else n = -1;
    }
    free(members);
    free(prog_json);
    free(err_json);
    if (n < 0) return fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
    out->data = (uint8_t *)text;
    out->size = (size_t)n;
    out->content_type = "application/json";
    return FM_OK;
}

/* Runs on the request's own connection thread (libmicrohttpd's thread per
 * connection), so a check blocks only its caller; size and concurrency are
 * bounded in fm_jobs_check_request. */
static fm_status svc_check(void *ctx, json_t *request, json_t **out, fm_error *err)
{
    fm_jobs *jobs = ctx;
    const fm_job_doc_rules rules = fm_jobs_doc_rules(jobs, 0);
    const fm_jobs_config *cfg = fm_jobs_config_of(jobs);
    return fm_jobs_check_request(cfg->state_dir, cfg->job_memory_bytes, &rules, request, out, err);
}

void fm_jobs_http_service(fm_jobs *jobs, fm_http_service *out)
{
    memset(out, 0, sizeof *out);
    out->ctx = jobs;
    out->ready = svc_ready;
    out->submit = svc_submit;
    out->status = svc_status;
    out->list = svc_list;
    out->report = svc_report;
    out->chunks = svc_chunks;
    out->cancel = svc_cancel;
    out->remove = svc_remove;
    out->mesh = svc_mesh;
    out->chunk = svc_chunk;
    out->stock_path = svc_stock_path;
    out->events = svc_events;
    out->check = svc_check;
    out->toolpath = svc_toolpath;
    out->deviation_path = svc_deviation_path;
    out->stock_mesh_path = svc_stock_mesh_path;
}
