/* http_service.c: the daemon's implementation of the HTTP server's service
 * interface (protocols/http/http_server.h) over the job manager. Every
 * call reads what the workers published, under the job's lock, and copies
 * it out; the full mesh is assembled from the published chunk meshes, so a
 * download never touches the grid being cut. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "http_service.h"
#include "job_record.h"
#include "jobs_check.h"
#include "publish.h"
#include "sweep/sweep.h"

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
 * stock) into a compact polyline of tool tip positions for the viewer:
 *   {"id", "kind": "gcode" | "trajectory", "program": TEXT, "motions":
 *    [[kind, line, t0, t1, tool, first, count], ...], "points": [x, y, z, ...],
 *    "truncated": bool, "error": null | TEXT}
 * kind 0 rapid, 1 feed line, 2 arc, 3 parametric, 4 dwell; a motion's points
 * are points[first .. first + count - 1] (start included). Arcs are split
 * every 5 degrees, parametric segments into 32 pieces. */

#define TOOLPATH_MAX_POINTS 500000
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct tp_buf {
    char *text;
    size_t len, cap;
    int failed;
} tp_buf;

static void tp_printf(tp_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void tp_printf(tp_buf *b, const char *fmt, ...)
{
    if (b->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        /* NULL + 0 is undefined in C (clang's UBSan stops there): the
         * first call, before any allocation, only measures. */
        int n = vsnprintf(b->text ? b->text + b->len : NULL, b->cap - b->len, fmt, ap);
        va_end(ap);
        if (n < 0) {
            b->failed = 1;
            return;
        }
        if ((size_t)n < b->cap - b->len) {
            b->len += (size_t)n;
            return;
        }
        size_t cap = b->cap * 2 + (size_t)n + 1;
        char *t = realloc(b->text, cap);
        if (!t) {
            b->failed = 1;
            return;
        }
        b->text = t;
        b->cap = cap;
    }
}

typedef struct tp_ctx {
    tp_buf motions, points;
    long point_count, motion_count;
    int truncated;
} tp_ctx;

static void tp_point(tp_ctx *c, const double p[3])
{
    tp_printf(&c->points, "%s%.3f,%.3f,%.3f", c->point_count ? "," : "", p[0], p[1], p[2]);
    c->point_count++;
}

static int tp_sink(void *user, const fm_motion *m)
{
    tp_ctx *c = user;
    if (c->point_count > TOOLPATH_MAX_POINTS) {
        c->truncated = 1;
        return 1;
    }
    long first = c->point_count;
    double p[3], axis[3];
    int kind = m->kind == FM_MOTION_RAPID ? 0
               : m->kind == FM_MOTION_LINE ? 1
               : m->kind == FM_MOTION_ARC  ? 2
               : m->kind == FM_MOTION_PARAM ? 3
                                           : 4;
    /* lib/sweep's motion geometry: the tool tip in the workpiece frame,
     * arcs and rotary moves every 5 degrees, parametric paths in 32 pieces */
    if (kind == 4) {
        fm_motion_pose_at(m, 0, p, axis);
        tp_point(c, p);
    } else {
        int n = fm_motion_pieces(m, 5.0 * M_PI / 180.0, 32, 20000);
        if (kind == 2 && n < 2) n = 2;
        for (int i = 0; i <= n; i++) {
            fm_motion_pose_at(m, (double)i / n, p, axis);
            tp_point(c, p);
        }
    }
    tp_printf(&c->motions, "%s[%d,%d,%.4f,%.4f,%d,%ld,%ld", c->motion_count ? "," : "", kind,
              m->line, m->t0, m->t1, m->tool, first, c->point_count - first);
    /* on a rotary machine the joints at both ends, for the viewer's table */
    if (m->machine && m->machine->rotary_count)
        tp_printf(&c->motions, ",%.6f,%.6f,%.6f,%.6f,%.6f,%.6f", m->rotary_start[0], m->rotary_start[1],
                  m->rotary_start[2], m->rotary_end[0], m->rotary_end[1], m->rotary_end[2]);
    tp_printf(&c->motions, "]");
    c->motion_count++;
    return c->motions.failed || c->points.failed;
}

/* The opening of the document with "machine": {"table": [{"axis", "around",
 * "through"}, ...]} (the axes that turn the workpiece, in chain order from
 * the base) when the job's machine has any, so the viewer can turn the
 * workpiece as fm_machine_table_transform does. */
static void tp_machine(tp_buf *b, const fm_machine *mc)
{
    tp_printf(b, "{");
    int n = 0;
    for (int i = 0; mc && i < mc->rotary_count; i++) {
        const fm_rotary_axis *ax = &mc->rotary[i];
        if (ax->carries != FM_ROTARY_TABLE) continue;
        tp_printf(b, "%s{\"axis\":\"%c\",\"around\":[%.9g,%.9g,%.9g],\"through\":[%.9g,%.9g,%.9g]}",
                  n++ ? "," : "\"machine\":{\"table\":[", 'a' + ax->letter, ax->around[0], ax->around[1],
                  ax->around[2], ax->through[0], ax->through[1], ax->through[2]);
    }
    if (n) tp_printf(b, "]},");
}

static fm_status svc_toolpath(void *ctx, const char *id, fm_http_blob *out, fm_error *err)
{
    job *j = fm_jobs_get(ctx, id);
    if (!j) return not_found(id, err);
    /* The document is immutable: no lock needed while we hold a reference. */
    const fm_job_spec *spec = &fm_job_document(j)->spec;
    int is_gcode = spec->program_kind == FM_PROGRAM_GCODE;
    fm_error ferr;
    fm_error_clear(&ferr);
    tp_ctx c;
    memset(&c, 0, sizeof c);
    fm_status st = spec->program_kind == FM_PROGRAM_LIVE ? FM_OK
                                                          : fm_job_interpret(spec, tp_sink, &c, &ferr);
    json_t *prog = json_stringn(spec->program_text ? spec->program_text : "", spec->program_length);
    const char *kind = is_gcode ? "gcode"
                       : spec->program_kind == FM_PROGRAM_LIVE ? "live"
                                                               : "trajectory";
    fm_jobs_put(ctx, j);
    char *prog_json = prog ? json_dumps(prog, JSON_ENCODE_ANY) : NULL;
    json_decref(prog);
    char msg[1024] = "";
    json_t *emsg = st == FM_OK ? json_null() : json_string(fm_error_format(&ferr, msg, sizeof msg));
    char *err_json = json_dumps(emsg, JSON_ENCODE_ANY);
    json_decref(emsg);

    tp_buf b = {0};
    tp_machine(&b, spec->machine);
    tp_printf(&b, "\"id\":\"%s\",\"kind\":\"%s\",\"program\":%s,\"motions\":[%s],\"points\":[%s],"
                  "\"truncated\":%s,\"error\":%s}\n",
              id, kind, prog_json ? prog_json : "\"\"",
              c.motions.text ? c.motions.text : "", c.points.text ? c.points.text : "",
              c.truncated ? "true" : "false", err_json ? err_json : "null");
    free(prog_json);
    free(err_json);
    int failed = b.failed || c.motions.failed || c.points.failed;
    free(c.motions.text);
    free(c.points.text);
    if (failed) {
        free(b.text);
        return fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
    }
    out->data = (uint8_t *)b.text;
    out->size = b.len;
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
}
