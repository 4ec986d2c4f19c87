/* jobs.c: the job manager. Jobs live in state_dir/jobs/<id>/: spec.json
 * (written before the job is acknowledged), stock.vdb (the crash-safe stock
 * snapshot with "resume_from=N" as its resume string: every motion before
 * N is in it) and result.json (written when the job ends). At start every
 * folder is read back: a result means the job is finished; no result means
 * it is queued again and resumes from its snapshot, if any, at motion N.
 *
 * Workers run fm_job_run (job.c, shared with the CLI) with a progress hook
 * that, between cuts and on the worker's own thread, publishes the status,
 * snapshots the stock every snapshot_interval_s of work, and remeshes the
 * chunks that changed every publish_interval_s (Draco-encoded for the
 * viewer). Readers get copies under the job's lock and never see the grid
 * being cut. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "runner/job.h"
#include "runner/report_json.h"
#include "jobs_check.h"
#include "jobs_internal.h"
#include "log.h"
#include "store.h"
#include "toolpaths/tooltable/tooltable.h"

#define JOB_SPEC_MAX_BYTES ((size_t)1 << 30)
#define JOB_EVENT_MIN_INTERVAL_S 0.2

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

const char *fm_job_state_name(fm_job_state state)
{
    static const char *const names[] = {"queued", "running", "done", "failed", "cancelled"};
    return (unsigned)state < 5 ? names[state] : "unknown";
}

static int state_from_name(const char *name)
{
    for (int i = 0; i < 5; i++)
        if (name && !strcmp(name, fm_job_state_name((fm_job_state)i))) return i;
    return -1;
}

/* ------------------------------------------------------------ records -- */

static job *job_new(const char *id, const char *jobs_dir, json_t *spec, double created)
{
    job *j = calloc(1, sizeof *j);
    if (!j) return NULL;
    snprintf(j->id, sizeof j->id, "%s", id);
    snprintf(j->dir, sizeof j->dir, "%.1200s/%.40s", jobs_dir, id);
    j->spec = json_incref(spec);
    j->created = created;
    j->refs = 1; /* the table's */
    pthread_mutex_init(&j->lock, NULL);
    pthread_mutex_init(&j->load_lock, NULL);
    pthread_cond_init(&j->cond, NULL);
    j->next_event = 1;
    j->view.block = -1;
    snprintf(j->view.id, sizeof j->view.id, "%s", id);
    return j;
}

static void chunks_free(job *j)
{
    for (size_t i = 0; i < j->chunk_count; i++) {
        fm_mesh_free(j->chunks[i].mesh);
        free(j->chunks[i].drc);
    }
    free(j->chunks);
    j->chunks = NULL;
    j->chunk_count = j->chunk_cap = 0;
}

static void job_free(job *j)
{
    chunks_free(j);
    for (int i = 0; i < JOB_EVENT_RING; i++) free(j->ring[i].data);
    json_decref(j->spec);
    json_decref(j->error);
    json_decref(j->report);
    json_decref(j->findings);
    pthread_mutex_destroy(&j->lock);
    pthread_mutex_destroy(&j->load_lock);
    pthread_cond_destroy(&j->cond);
    free(j);
}

job *fm_jobs_get(fm_jobs *jobs, const char *id)
{
    job *found = NULL;
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++)
        if (!strcmp(jobs->table[i]->id, id) && !jobs->table[i]->deleted) {
            found = jobs->table[i];
            found->refs++;
            break;
        }
    pthread_mutex_unlock(&jobs->lock);
    return found;
}

void fm_jobs_put(fm_jobs *jobs, job *j)
{
    if (!j) return;
    pthread_mutex_lock(&jobs->lock);
    int last = --j->refs == 0;
    pthread_mutex_unlock(&jobs->lock);
    if (last) job_free(j);
}

/* Emit an event (caller holds j->lock). data is a JSON object; stolen. */
static void emit(job *j, const char *type, json_t *data)
{
    char *text = json_dumps(data, JSON_COMPACT | JSON_REAL_PRECISION(10));
    json_decref(data);
    if (!text) return;
    job_event *e = &j->ring[j->next_event % JOB_EVENT_RING];
    free(e->data);
    e->id = j->next_event++;
    snprintf(e->type, sizeof e->type, "%s", type);
    e->data = text;
    if (!strcmp(type, "end")) j->ended = 1;
    pthread_cond_broadcast(&j->cond);
}

/* The colour of each tool of the job's table in its meshes (options.color
 * "tool", the default), for a legend: [{"tool": N, "color": "#rrggbb"}];
 * an empty array when the meshes have no colours. */
static json_t *tool_colors_json(const job *j)
{
    json_t *out = json_array();
    const char *color =
        json_string_value(json_object_get(json_object_get(j->spec, "options"), "color"));
    if (color && !strcmp(color, "none")) return out;
    json_t *tools = json_object_get(json_object_get(j->spec, "tools"), "tools");
    size_t i;
    json_t *t;
    json_array_foreach(tools, i, t) {
        json_t *number = json_object_get(t, "number");
        if (!json_is_integer(number)) continue;
        uint8_t rgb[3];
        fm_mesh_tool_color((int)json_integer_value(number), rgb);
        char hex[8];
        snprintf(hex, sizeof hex, "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
        json_array_append_new(out, json_pack("{s:I, s:s}", "tool", json_integer_value(number),
                                             "color", hex));
    }
    return out;
}

json_t *fm_jobs_status_json(job *j)
{
    pthread_mutex_lock(&j->lock);
    const fm_job_view *v = &j->view;
    json_t *name = json_object_get(json_object_get(j->spec, "options"), "name");
    json_t *out = json_pack(
        "{s:s, s:s, s:b, s:f, s:i, s:I, s:i, s:[f,f,f], s:f, s:f, s:f, s:f, s:I, s:I, s:o, "
        "s:O?, s:I, s:f, s:O?}",
        "id", j->id, "state", fm_job_state_name(j->state), "paused", j->paused, "progress",
        v->progress, "line", v->line, "block", (json_int_t)v->block, "tool", v->tool, "position",
        v->position[0], v->position[1], v->position[2], "program_time_s", v->program_time_s,
        "removed_volume_mm3", v->removed_mm3, "stock_volume_mm3", v->stock_mm3,
        "initial_volume_mm3", j->initial_mm3, "motions_done", (json_int_t)j->motions_done,
        "motions_total", (json_int_t)j->motions_total, "findings",
        j->findings ? json_incref(j->findings) : json_array(), "error", j->error,
        "mesh_version", (json_int_t)j->mesh_version, "created", j->created, "name", name);
    if (out) json_object_set_new(out, "tool_colors", tool_colors_json(j));
    pthread_mutex_unlock(&j->lock);
    return out;
}

/* ---------------------------------------------------------- persistence -- */

static fm_status write_json(const char *dir, const char *name, json_t *value, fm_error *err)
{
    char *text = json_dumps(value, JSON_COMPACT | JSON_REAL_PRECISION(17));
    if (!text) return fm_error_set(err, FM_ERR_LIMIT, "cannot serialize %s", name);
    fm_status st = fm_store_write_atomic(dir, name, text, strlen(text), err);
    free(text);
    return st;
}

/* The terminal record: state, last status, error and report. */
static void write_result(fm_jobs *jobs, job *j)
{
    (void)jobs;
    json_t *status = fm_jobs_status_json(j);
    pthread_mutex_lock(&j->lock);
    json_t *result = json_pack("{s:O, s:O?}", "status", status, "report", j->report);
    pthread_mutex_unlock(&j->lock);
    json_decref(status);
    fm_error err;
    if (write_json(j->dir, "result.json", result, &err) != FM_OK)
        fm_log(FM_LOG_ERROR, "job %s: cannot store its result: %s", j->id, err.message);
    json_decref(result);
}

/* Publish the check's findings (caller holds j->lock, or owns j alone). */
static void set_findings(job *j, json_t *findings)
{
    json_decref(j->findings);
    j->findings = json_incref(findings);
    fm_job_view *v = &j->view;
    v->finding_count = (int)json_array_size(findings);
    v->error_finding_count = 0;
    size_t i;
    json_t *f;
    json_array_foreach(findings, i, f)
    {
        const char *severity = json_string_value(json_object_get(f, "severity"));
        if (severity && !strcmp(severity, "error")) v->error_finding_count++;
    }
    v->first_finding_line =
        v->finding_count ? (int)json_integer_value(json_object_get(json_array_get(findings, 0), "line"))
                         : 0;
}

static void view_from_status(job *j, json_t *status)
{
    fm_job_view *v = &j->view;
    v->progress = json_real_value(json_object_get(status, "progress"));
    v->line = (int)json_integer_value(json_object_get(status, "line"));
    v->block = (long)json_integer_value(json_object_get(status, "block"));
    v->tool = (int)json_integer_value(json_object_get(status, "tool"));
    json_t *pos = json_object_get(status, "position");
    for (int a = 0; a < 3; a++) v->position[a] = json_number_value(json_array_get(pos, (size_t)a));
    v->program_time_s = json_number_value(json_object_get(status, "program_time_s"));
    v->removed_mm3 = json_number_value(json_object_get(status, "removed_volume_mm3"));
    v->stock_mm3 = json_number_value(json_object_get(status, "stock_volume_mm3"));
    j->initial_mm3 = json_number_value(json_object_get(status, "initial_volume_mm3"));
    j->motions_done = (long)json_integer_value(json_object_get(status, "motions_done"));
    j->motions_total = (long)json_integer_value(json_object_get(status, "motions_total"));
    json_t *findings = json_object_get(status, "findings");
    if (json_is_array(findings)) {
        set_findings(j, findings);
    }
    json_t *error = json_object_get(status, "error");
    if (json_is_object(error)) {
        j->error = json_incref(error);
        v->error_code = (int)json_integer_value(json_object_get(error, "status"));
    }
}

static void table_add(fm_jobs *jobs, job *j)
{
    if (jobs->count == jobs->cap) {
        size_t cap = jobs->cap ? jobs->cap * 2 : 64;
        job **t = realloc(jobs->table, cap * sizeof *t);
        if (!t) return;
        jobs->table = t;
        jobs->cap = cap;
    }
    /* Keep creation order: slots (Modbus) and listings rely on it. */
    size_t i = jobs->count;
    while (i > 0 && jobs->table[i - 1]->created > j->created) {
        jobs->table[i] = jobs->table[i - 1];
        i--;
    }
    jobs->table[i] = j;
    jobs->count++;
}

static void enqueue(fm_jobs *jobs, job *j)
{
    j->next_queued = NULL;
    j->refs++; /* the queue's */
    if (jobs->queue_tail) jobs->queue_tail->next_queued = j;
    else jobs->queue_head = j;
    jobs->queue_tail = j;
    pthread_cond_signal(&jobs->queue_cond);
}

/* Read back one job folder at start. */
static void load_job(fm_jobs *jobs, const char *id)
{
    char dir[JOB_DIR_MAX], path[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/%.40s", jobs->jobs_dir, id);
    snprintf(path, sizeof path, "%s/spec.json", dir);
    char *text;
    size_t size;
    fm_error err;
    if (fm_store_read(path, JOB_SPEC_MAX_BYTES, &text, &size, &err) != FM_OK) {
        /* A folder without its spec was never acknowledged: the daemon
         * died between mkdir and the rename of spec.json. */
        fm_log(FM_LOG_WARN, "job %s: no stored spec (%s); removing the unacknowledged folder", id,
               err.message);
        fm_store_remove_dir(dir, &err);
        return;
    }
    json_error_t jerr;
    json_t *stored = json_loadb(text, size, 0, &jerr);
    free(text);
    json_t *spec_json = json_object_get(stored, "job");
    char *spec_text = spec_json ? json_dumps(spec_json, JSON_COMPACT) : NULL;
    fm_http_error herr;
    json_t *spec = spec_text ? fm_http_job_parse(spec_text, strlen(spec_text), &herr) : NULL;
    free(spec_text);
    if (!spec) {
        fm_log(FM_LOG_ERROR, "job %s: its stored spec is unreadable; left in place", id);
        json_decref(stored);
        return;
    }
    job *j = job_new(id, jobs->jobs_dir, spec, json_number_value(json_object_get(stored, "created")));
    json_decref(spec);
    json_decref(stored);
    if (!j) return;
    snprintf(path, sizeof path, "%s/result.json", dir);
    if (fm_store_read(path, JOB_SPEC_MAX_BYTES, &text, &size, &err) == FM_OK) {
        json_t *result = json_loadb(text, size, 0, &jerr);
        free(text);
        json_t *status = json_object_get(result, "status");
        int state = state_from_name(json_string_value(json_object_get(status, "state")));
        if (state >= FM_JOB_DONE) {
            j->state = (fm_job_state)state;
            view_from_status(j, status);
            j->report = json_incref(json_object_get(result, "report"));
            if (json_is_null(j->report)) {
                json_decref(j->report);
                j->report = NULL;
            }
            emit(j, "end", json_pack("{s:s}", "state", fm_job_state_name(j->state)));
            json_decref(result);
            pthread_mutex_lock(&jobs->lock);
            table_add(jobs, j);
            pthread_mutex_unlock(&jobs->lock);
            return;
        }
        json_decref(result);
    }
    fm_log(FM_LOG_INFO, "job %s: unfinished; queued to resume", id);
    pthread_mutex_lock(&jobs->lock);
    table_add(jobs, j);
    pthread_mutex_unlock(&jobs->lock);
}

static void load_all(fm_jobs *jobs)
{
    DIR *d = opendir(jobs->jobs_dir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        size_t n = strlen(e->d_name);
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/%s", jobs->jobs_dir, e->d_name);
        if (n > 8 && !strcmp(e->d_name + n - 8, ".deleted")) {
            fm_error err;
            fm_store_remove_dir(path, &err); /* a delete the daemon did not finish */
            continue;
        }
        if (n >= 32) continue;
        fm_error err;
        size_t removed = 0;
        fm_stock_snapshot_cleanup(path, &removed, &err);
        load_job(jobs, e->d_name);
    }
    closedir(d);
    /* Resume in creation order (load_all read folders in any order). */
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++)
        if (jobs->table[i]->state < FM_JOB_DONE) enqueue(jobs, jobs->table[i]);
    pthread_mutex_unlock(&jobs->lock);
}

/* ------------------------------------------------------------ submit -- */

static void make_id(fm_jobs *jobs, char *id, size_t size)
{
    unsigned char r[3] = {0};
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        if (read(fd, r, sizeof r) != (ssize_t)sizeof r) memset(r, 0, sizeof r);
        close(fd);
    }
    unsigned counter = atomic_fetch_add(&jobs->id_counter, 1u);
    /* Time first, so ids sort by creation; the counter and random bytes
     * keep two ids of one second (or of two daemons) apart. */
    snprintf(id, size, "%08llx-%04x%02x%02x", (unsigned long long)time(NULL), counter & 0xffffu,
             r[0], r[1]);
}

/* A cheap check before acknowledging: a box or cylinder stock whose grid
 * estimate is over the per-job budget is refused now, not after queueing. */
static int check_budget(fm_jobs *jobs, json_t *spec, fm_http_error *err)
{
    const char *stock = json_string_value(json_object_get(spec, "stock"));
    double voxel = json_number_value(json_object_get(spec, "voxel"));
    json_t *band_json = json_object_get(json_object_get(spec, "options"), "band");
    int band = band_json ? (int)json_integer_value(band_json) : 3;
    if (!stock) return 0;
    double v[6], area = -1;
    if (sscanf(stock, "box:%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5]) ==
        6) {
        double dx = fabs(v[3] - v[0]), dy = fabs(v[4] - v[1]), dz = fabs(v[5] - v[2]);
        area = 2 * (dx * dy + dy * dz + dx * dz);
    } else if (sscanf(stock, "cylinder:%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4]) ==
               5) {
        /* Caps project on z; the side projects to 8 r h on x and y. */
        area = 2 * 3.14159265358979323846 * v[4] * v[4] + 8 * fabs(v[4]) * fabs(v[3] - v[2]);
    }
    if (!(area > 0) || !isfinite(area)) return 0;
    size_t need = fm_stock_estimate_bytes(area, voxel, band);
    size_t budget = jobs->cfg.job_memory_bytes;
    json_t *mb = json_object_get(json_object_get(spec, "options"), "memory_budget_mb");
    if (mb && json_number_value(mb) * 1048576.0 < (double)budget)
        budget = (size_t)(json_number_value(mb) * 1048576.0);
    if (need > budget) {
        fm_http_error_set(err, 413, "memory_budget",
                          "the stock needs about %.0f MB at voxel %g mm; the budget per job is "
                          "%.0f MB (job_memory_mb); use a coarser voxel or a smaller stock",
                          (double)need / 1048576.0, voxel, (double)budget / 1048576.0);
        return -1;
    }
    return 0;
}

/* The tool table is parsed now so that a bad one is a 400 with its line
 * and column, not a failed job. */
static int check_tools(json_t *spec, fm_http_error *err)
{
    char *text = json_dumps(json_object_get(spec, "tools"), JSON_INDENT(1));
    if (!text) return fm_http_error_set(err, 400, "bad_tools", "the tool table is not valid");
    fm_tool_table table;
    fm_error ferr;
    fm_error_clear(&ferr);
    fm_status st = fm_tooltable_parse_json(text, strlen(text), "tools", &table, &ferr);
    free(text);
    if (st != FM_OK)
        return fm_http_error_set(err, 400, "bad_tools", "tools: %s", ferr.message) ? -1 : -1;
    int rc = 0;
    for (size_t i = 0; i < table.count; i++)
        if (table.tools[i].shape == FM_TOOL_HYPERFUN) {
            /* Such a tool names a model file on this machine; over the
             * network that would read the server's files. */
            fm_http_error_set(err, 400, "bad_tools",
                              "tools: tool %d is a HyperFun tool that names a file; not accepted "
                              "over HTTP",
                              table.tools[i].number);
            rc = -1;
            break;
        }
    fm_tool_table_free(&table);
    return rc;
}

int fm_jobs_submit(fm_jobs *jobs, json_t *spec, char *id, size_t id_size, fm_http_error *err)
{
    if (check_tools(spec, err) || check_budget(jobs, spec, err)) return err->status;
    if (fm_jobs_check_validate(spec, err)) return err->status;
    pthread_mutex_lock(&jobs->lock);
    size_t live = 0;
    for (size_t i = 0; i < jobs->count; i++) live += !jobs->table[i]->deleted;
    int stopping = jobs->stopping;
    pthread_mutex_unlock(&jobs->lock);
    if (stopping) return fm_http_error_set(err, 503, "shutting_down", "the daemon is stopping");
    if ((int)live >= jobs->cfg.max_jobs)
        return fm_http_error_set(err, 429, "job_limit",
                                 "%zu jobs are stored, the most allowed (max_jobs); delete "
                                 "finished jobs first",
                                 live);
    char new_id[32];
    make_id(jobs, new_id, sizeof new_id);
    double created = wall_s();
    char dir[JOB_DIR_MAX];
    snprintf(dir, sizeof dir, "%s/%.40s", jobs->jobs_dir, new_id);
    fm_error ferr;
    json_t *stored = json_pack("{s:s, s:f, s:O}", "id", new_id, "created", created, "job", spec);
    /* Durable before acknowledged: the folder, the spec (temp, fsync,
     * rename, fsync folder) and the new folder's entry in jobs/. */
    fm_status st = mkdir(dir, 0750) == 0 ? FM_OK
                                         : fm_error_set(&ferr, FM_ERR_IO, "cannot create %s: %s",
                                                        dir, strerror(errno));
    if (st == FM_OK) st = write_json(dir, "spec.json", stored, &ferr);
    if (st == FM_OK) st = fm_store_fsync_dir(jobs->jobs_dir, &ferr);
    json_decref(stored);
    if (st != FM_OK) {
        fm_store_remove_dir(dir, NULL);
        fm_log(FM_LOG_ERROR, "cannot store a new job: %s", ferr.message);
        return fm_http_error_set(err, 507, "storage", "the job could not be stored: %s",
                                 ferr.message);
    }
    job *j = job_new(new_id, jobs->jobs_dir, spec, created);
    if (!j) return fm_http_error_set(err, 503, "out_of_memory", "out of memory");
    pthread_mutex_lock(&j->lock);
    emit(j, "state", json_pack("{s:s}", "state", "queued"));
    pthread_mutex_unlock(&j->lock);
    pthread_mutex_lock(&jobs->lock);
    table_add(jobs, j);
    enqueue(jobs, j);
    pthread_mutex_unlock(&jobs->lock);
    snprintf(id, id_size, "%s", new_id);
    json_t *name = json_object_get(json_object_get(spec, "options"), "name");
    fm_log(FM_LOG_INFO, "job %s: accepted%s%s", new_id, name ? " as " : "",
           name ? json_string_value(name) : "");
    return 0;
}

int fm_jobs_remove(fm_jobs *jobs, const char *id, fm_http_error *err)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return fm_http_error_set(err, 404, "not_found", "no job %s", id);
    atomic_store(&j->cancel_requested, 1);
    pthread_mutex_lock(&j->lock);
    j->paused = 0;
    pthread_cond_broadcast(&j->cond);
    pthread_mutex_unlock(&j->lock);
    /* Renamed first: one atomic step makes the job gone for a restart even
     * if the files are not all unlinked yet. */
    char gone[PATH_MAX];
    snprintf(gone, sizeof gone, "%s.deleted", j->dir);
    fm_error ferr;
    if (rename(j->dir, gone) != 0) {
        fm_jobs_put(jobs, j);
        return fm_http_error_set(err, 500, "storage", "cannot delete job %s: %s", id,
                                 strerror(errno));
    }
    fm_store_fsync_dir(jobs->jobs_dir, &ferr);
    pthread_mutex_lock(&jobs->lock);
    j->deleted = 1;
    int running = 0;
    for (size_t i = 0; i < jobs->count; i++)
        if (jobs->table[i] == j) {
            memmove(&jobs->table[i], &jobs->table[i + 1],
                    (jobs->count - i - 1) * sizeof *jobs->table);
            jobs->count--;
            j->refs--; /* the table's */
            break;
        }
    pthread_mutex_lock(&j->lock);
    running = j->state == FM_JOB_RUNNING;
    emit(j, "end", json_pack("{s:s}", "state", "deleted"));
    pthread_mutex_unlock(&j->lock);
    pthread_mutex_unlock(&jobs->lock);
    /* A running job's worker may still write its snapshot into the renamed
     * folder; it removes the folder when it ends. */
    if (!running) fm_store_remove_dir(gone, &ferr);
    fm_log(FM_LOG_INFO, "job %s: deleted", id);
    fm_jobs_put(jobs, j);
    return 0;
}

/* ------------------------------------------------------------ meshes -- */

/* Remesh the chunks that changed since the last publication and swap them
 * in. Runs on the worker's thread (or a reader's, for a finished job whose
 * stock was loaded from its snapshot) with exclusive use of stock. */
static void publish_chunks(job *j, fm_stock *stock)
{
    uint64_t version = fm_stock_version(stock);
    pthread_mutex_lock(&j->lock);
    uint64_t since = j->chunk_count ? j->mesh_version : 0;
    pthread_mutex_unlock(&j->lock);
    if (j->chunk_count && version == since) return;
    size_t cap = 256;
    fm_stock_chunk *changed = malloc(cap * sizeof *changed);
    if (!changed) return;
    size_t n = fm_stock_changed_chunks(stock, since, changed, cap);
    if (n > cap) {
        fm_stock_chunk *bigger = realloc(changed, n * sizeof *changed);
        if (!bigger) {
            free(changed);
            return;
        }
        changed = bigger;
        cap = n;
        n = fm_stock_changed_chunks(stock, since, changed, cap);
    }
    fm_mesh_extract_options opt;
    fm_mesh_extract_default(&opt);
    /* options.color (validated on submission): "tool" unless "none" */
    const char *color =
        json_string_value(json_object_get(json_object_get(j->spec, "options"), "color"));
    opt.coloring = color && !strcmp(color, "none") ? FM_MESH_COLOR_NONE : FM_MESH_COLOR_TOOL;
    job_chunk *fresh = calloc(n ? n : 1, sizeof *fresh);
    if (!fresh) {
        free(changed);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        job_chunk *c = &fresh[i];
        memcpy(c->index, changed[i].index, sizeof c->index);
        c->version = version;
        memcpy(c->lo, changed[i].lo, sizeof c->lo);
        memcpy(c->hi, changed[i].hi, sizeof c->hi);
        fm_error err;
        c->mesh = fm_mesh_from_stock_chunk(stock, c->index, &opt, &err);
        if (c->mesh && c->mesh->triangle_count > 0 &&
            fm_mesh_encode_draco(c->mesh, NULL, &c->drc, &c->drc_size, &err) != FM_OK) {
            c->drc = NULL;
            c->drc_size = 0;
        }
    }
    free(changed);
    json_t *ids = json_array();
    pthread_mutex_lock(&j->lock);
    for (size_t i = 0; i < n; i++) {
        job_chunk *c = &fresh[i];
        char name[48];
        snprintf(name, sizeof name, "%d_%d_%d", c->index[0], c->index[1], c->index[2]);
        json_array_append_new(ids, json_string(name));
        size_t k = 0;
        while (k < j->chunk_count && memcmp(j->chunks[k].index, c->index, sizeof c->index)) k++;
        if (k == j->chunk_count) {
            if (j->chunk_count == j->chunk_cap) {
                size_t ncap = j->chunk_cap ? j->chunk_cap * 2 : 64;
                job_chunk *t = realloc(j->chunks, ncap * sizeof *t);
                if (!t) {
                    fm_mesh_free(c->mesh);
                    free(c->drc);
                    continue;
                }
                j->chunks = t;
                j->chunk_cap = ncap;
            }
            j->chunk_count++;
        } else {
            fm_mesh_free(j->chunks[k].mesh);
            free(j->chunks[k].drc);
        }
        j->chunks[k] = *c;
    }
    j->mesh_version = version;
    emit(j, "chunks", json_pack("{s:I, s:o}", "version", (json_int_t)version, "changed", ids));
    pthread_mutex_unlock(&j->lock);
    free(fresh);
}

int fm_jobs_ensure_meshes(fm_jobs *jobs, job *j, fm_http_error *err)
{
    (void)jobs;
    pthread_mutex_lock(&j->lock);
    int ready = j->meshes_loaded || j->state < FM_JOB_DONE;
    pthread_mutex_unlock(&j->lock);
    if (ready) return 0;
    pthread_mutex_lock(&j->load_lock);
    pthread_mutex_lock(&j->lock);
    ready = j->meshes_loaded;
    pthread_mutex_unlock(&j->lock);
    int rc = 0;
    if (!ready) {
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/stock.vdb", j->dir);
        fm_stock_options opt;
        fm_stock_options_default(&opt);
        fm_error ferr;
        fm_stock *stock = access(path, R_OK) == 0 ? fm_stock_load_vdb(path, &opt, &ferr) : NULL;
        if (!stock) {
            rc = fm_http_error_set(err, 404, "no_mesh", "job %s has no stored stock to mesh",
                                   j->id);
        } else {
            publish_chunks(j, stock);
            fm_stock_free(stock);
            pthread_mutex_lock(&j->lock);
            j->meshes_loaded = 1;
            pthread_mutex_unlock(&j->lock);
        }
    }
    pthread_mutex_unlock(&j->load_lock);
    return rc;
}

/* ------------------------------------------------------------ workers -- */

typedef struct run_ctx {
    fm_jobs *jobs;
    job *j;
    double last_snapshot, last_publish, last_event;
    int last_line;
    long resume_from;
    int stopped_for_shutdown;
} run_ctx;

static void save_snapshot(run_ctx *rc, fm_stock *stock, long resume_from)
{
    char path[PATH_MAX], resume[64];
    snprintf(path, sizeof path, "%s/stock.vdb", rc->j->dir);
    snprintf(resume, sizeof resume, "resume_from=%ld", resume_from);
    fm_error err;
    double t0 = mono_s();
    if (fm_stock_save(stock, path, resume, &err) != FM_OK)
        fm_log(FM_LOG_ERROR, "job %s: snapshot failed: %s", rc->j->id, err.message);
    else
        fm_log(FM_LOG_DEBUG, "job %s: snapshot at motion %ld in %.2f s", rc->j->id, resume_from,
               mono_s() - t0);
}

static int on_progress(void *user, const fm_job_progress *p)
{
    run_ctx *rc = user;
    job *j = rc->j;
    double now = mono_s();
    rc->resume_from = p->resume_from;
    pthread_mutex_lock(&j->lock);
    /* The stock (made by the runner, or a snapshot with its stored initial
     * volume) is first seen here. */
    if (j->initial_mm3 <= 0) j->initial_mm3 = fm_stock_initial_volume(p->stock);
    fm_job_view *v = &j->view;
    v->progress = p->program_time_total > 0 ? p->program_time / p->program_time_total
                  : p->motions_total > 0    ? (double)p->motions_done / (double)p->motions_total
                                            : 1.0;
    if (v->progress > 1) v->progress = 1;
    v->line = p->line;
    v->block = p->block;
    v->tool = p->tool;
    memcpy(v->position, p->position, sizeof v->position);
    v->program_time_s = p->program_time;
    v->removed_mm3 = p->removed_mm3;
    v->stock_mm3 = j->initial_mm3 - p->removed_mm3;
    v->removal_rate_mm3_s = p->program_time > 0 ? p->removed_mm3 / p->program_time : 0;
    j->motions_done = p->motions_done;
    j->motions_total = p->motions_total;
    if (now - rc->last_event >= JOB_EVENT_MIN_INTERVAL_S) {
        rc->last_event = now;
        if (p->line != rc->last_line) {
            rc->last_line = p->line;
            emit(j, "block", json_pack("{s:i, s:I}", "line", p->line, "block", (json_int_t)p->block));
        }
        emit(j, "progress",
             json_pack("{s:f, s:i, s:I, s:i, s:[f,f,f], s:f, s:f}", "progress", v->progress,
                       "line", v->line, "block", (json_int_t)v->block, "tool", v->tool, "position",
                       v->position[0], v->position[1], v->position[2], "removed_volume_mm3",
                       v->removed_mm3, "stock_volume_mm3", v->stock_mm3));
    }
    /* Paused (Modbus): wait here, between cuts, until resumed. */
    while (j->paused && !atomic_load(&j->cancel_requested) && !rc->jobs->stopping)
        pthread_cond_wait(&j->cond, &j->lock);
    pthread_mutex_unlock(&j->lock);

    if (atomic_load(&j->cancel_requested)) return 1;
    pthread_mutex_lock(&rc->jobs->lock);
    int stopping = rc->jobs->stopping;
    pthread_mutex_unlock(&rc->jobs->lock);
    if (stopping) {
        rc->stopped_for_shutdown = 1;
        return 1;
    }
    if (now - rc->last_snapshot >= rc->jobs->cfg.snapshot_interval_s) {
        save_snapshot(rc, p->stock, p->resume_from);
        rc->last_snapshot = mono_s();
    }
    if (now - rc->last_publish >= rc->jobs->cfg.publish_interval_s) {
        publish_chunks(j, p->stock);
        rc->last_publish = mono_s();
    }
    return 0;
}

/* Inline stock models are written into the job's folder once, so that the
 * runner (and a resumed run) reads them like the CLI reads files. */
static fm_status materialize_stock(job *j, char *path, size_t size, const char **spec_out,
                                   fm_error *err)
{
    json_t *stock = json_object_get(j->spec, "stock");
    if (json_is_string(stock)) {
        *spec_out = json_string_value(stock);
        return FM_OK;
    }
    json_t *hf = json_object_get(stock, "hyperfun");
    if (hf) {
        snprintf(path, size, "%s/stock.hf", j->dir);
        *spec_out = path;
        return fm_store_write_atomic(j->dir, "stock.hf", json_string_value(hf),
                                     json_string_length(hf), err);
    }
    json_t *stl = json_object_get(stock, "stl_base64");
    uint8_t *bytes;
    size_t n;
    if (fm_http_base64_decode(json_string_value(stl), json_string_length(stl), &bytes, &n) != 0)
        return fm_error_set(err, FM_ERR_INPUT, "stock.stl_base64 is not valid base64");
    snprintf(path, size, "%s/stock.stl", j->dir);
    *spec_out = path;
    fm_status st = fm_store_write_atomic(j->dir, "stock.stl", bytes, n, err);
    free(bytes);
    return st;
}

static json_t *error_json(const fm_error *err)
{
    static const char *const codes[] = {"ok", "", "input", "limit", "io", "internal"};
    const char *code = (unsigned)err->code < 6 ? codes[err->code] : "internal";
    return json_pack("{s:s, s:i, s:s, s:o, s:o, s:s}", "code", code, "status", (int)err->code,
                     "message", err->message, "line",
                     err->line > 0 ? json_integer(err->line) : json_null(), "column",
                     err->column > 0 ? json_integer(err->column) : json_null(), "file", err->file);
}

static void finish(fm_jobs *jobs, job *j, fm_job_state state, const char *what)
{
    pthread_mutex_lock(&j->lock);
    j->state = state;
    if (state == FM_JOB_DONE) j->view.progress = 1;
    j->meshes_loaded = state != FM_JOB_FAILED;
    pthread_mutex_unlock(&j->lock);
    write_result(jobs, j);
    pthread_mutex_lock(&j->lock);
    emit(j, "end", json_pack("{s:s, s:O?}", "state", fm_job_state_name(state), "error", j->error));
    pthread_mutex_unlock(&j->lock);
    fm_log(state == FM_JOB_FAILED ? FM_LOG_WARN : FM_LOG_INFO, "job %s: %s", j->id, what);
}

/* The check pass of a job stops for cancel, delete and shutdown like the
 * simulation does. */
static int check_keep_going(void *user)
{
    run_ctx *rc = user;
    if (atomic_load(&rc->j->cancel_requested)) return 0;
    pthread_mutex_lock(&rc->jobs->lock);
    int stopping = rc->jobs->stopping;
    pthread_mutex_unlock(&rc->jobs->lock);
    return !stopping;
}

static void run_job(fm_jobs *jobs, job *j)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    fm_error err;
    fm_error_clear(&err);
    run_ctx rc = {.jobs = jobs, .j = j, .last_line = -1};
    rc.last_snapshot = rc.last_publish = mono_s();

    pthread_mutex_lock(&j->lock);
    j->state = FM_JOB_RUNNING;
    emit(j, "state", json_pack("{s:s}", "state", "running"));
    pthread_mutex_unlock(&j->lock);

    json_t *options = json_object_get(j->spec, "options");
    spec.stock.voxel_mm = json_number_value(json_object_get(j->spec, "voxel"));
    spec.stock.threads = jobs->cfg.threads_per_job;
    spec.stock.memory_budget = jobs->cfg.job_memory_bytes;
    json_t *v;
    if ((v = json_object_get(options, "memory_budget_mb")) &&
        json_number_value(v) * 1048576.0 < (double)spec.stock.memory_budget)
        spec.stock.memory_budget = (size_t)(json_number_value(v) * 1048576.0);
    if ((v = json_object_get(options, "band"))) spec.stock.band_voxels = (int)json_integer_value(v);
    if ((v = json_object_get(options, "threads")))
        spec.stock.threads = (int)json_integer_value(v);
    if ((v = json_object_get(options, "batch"))) spec.batch_diameters = json_number_value(v);
    if ((v = json_object_get(options, "rapid_rate"))) spec.rapid_rate = json_number_value(v);

    fm_tool_table table;
    memset(&table, 0, sizeof table);
    char *tools_text = json_dumps(json_object_get(j->spec, "tools"), JSON_INDENT(1));
    char *trajectory_text = NULL;
    char stock_path[PATH_MAX];
    fm_status st = tools_text ? fm_tooltable_parse_json(tools_text, strlen(tools_text), "tools",
                                                        &table, &err)
                              : fm_error_set(&err, FM_ERR_INPUT, "no tool table");
    spec.tools = &table;
    if (st == FM_OK) st = materialize_stock(j, stock_path, sizeof stock_path, &spec.stock_spec, &err);
    json_t *program = json_object_get(j->spec, "program");
    json_t *gcode = json_object_get(program, "gcode");
    if (gcode) {
        spec.program_text = json_string_value(gcode);
        spec.program_length = json_string_length(gcode);
        spec.program_name = "program";
        spec.program_kind = FM_PROGRAM_GCODE;
    } else {
        trajectory_text = json_dumps(json_object_get(program, "trajectory"), JSON_INDENT(1));
        spec.program_text = trajectory_text ? trajectory_text : "";
        spec.program_length = strlen(spec.program_text);
        spec.program_name = "trajectory";
        spec.program_kind = FM_PROGRAM_TRAJECTORY;
    }

    /* Resume from the last snapshot, if any. */
    char snap[PATH_MAX];
    snprintf(snap, sizeof snap, "%s/stock.vdb", j->dir);
    if (st == FM_OK && access(snap, R_OK) == 0) {
        fm_stock *stock = fm_stock_load_vdb(snap, &spec.stock, &err);
        long from = -1;
        if (stock && sscanf(fm_stock_resume_string(stock), "resume_from=%ld", &from) == 1 &&
            from >= 0) {
            spec.resume_stock = stock;
            spec.skip_motions = from;
            fm_log(FM_LOG_INFO, "job %s: resuming from its snapshot at motion %ld", j->id, from);
        } else {
            fm_stock_free(stock);
            fm_log(FM_LOG_WARN, "job %s: its snapshot cannot be resumed; starting over", j->id);
            fm_error_clear(&err);
        }
    }
    /* The collision check first, as its own coarse pass (check_pass.h):
     * the findings are known before the simulation starts (a gate wants
     * them early) and are the ones `frepmill check` gives. */
    if (st == FM_OK && fm_jobs_check_enabled(j->spec)) {
        fm_jobs_check_result cr;
        double t0 = mono_s();
        int stopped = 0;
        st = fm_jobs_check_run_until(j->spec, j->dir, spec.stock.memory_budget, check_keep_going,
                                     &rc, &cr, &stopped, &err);
        /* Stopped (cancel, shutdown): the runner below stops at its first
         * cut and takes the usual path (cancelled, or resumed next start). */
        if (st == FM_OK && !stopped) {
            pthread_mutex_lock(&j->lock);
            set_findings(j, cr.findings);
            size_t i;
            json_t *f;
            json_array_foreach(cr.findings, i, f) emit(j, "finding", json_incref(f));
            pthread_mutex_unlock(&j->lock);
            fm_log(cr.errors ? FM_LOG_WARN : FM_LOG_INFO,
                   "job %s: check: %d errors, %d warnings (first at line %d) in %.2f s", j->id,
                   cr.errors, cr.warnings, cr.first_line, mono_s() - t0);
            json_decref(cr.findings);
        }
    }
    if (st == FM_OK) fm_log(FM_LOG_INFO, "job %s: running", j->id);

    fm_job_result result;
    memset(&result, 0, sizeof result);
    fm_job_hooks hooks = {.user = &rc, .progress = on_progress};
    if (st == FM_OK) {
        st = fm_job_run(&spec, &hooks, &result, &err);
        spec.resume_stock = NULL; /* the runner took it */
    } else {
        fm_stock_free(spec.resume_stock);
        spec.resume_stock = NULL;
    }
    free(tools_text);
    free(trajectory_text);
    fm_tool_table_free(&table);

    if (st != FM_OK) {
        pthread_mutex_lock(&j->lock);
        json_decref(j->error);
        j->error = error_json(&err);
        j->view.error_code = (int)err.code;
        pthread_mutex_unlock(&j->lock);
        char buf[1024];
        char what[1200];
        snprintf(what, sizeof what, "failed: %s", fm_error_format(&err, buf, sizeof buf));
        finish(jobs, j, FM_JOB_FAILED, what);
        return;
    }
    pthread_mutex_lock(&j->lock);
    j->initial_mm3 = result.initial_volume_mm3;
    pthread_mutex_unlock(&j->lock);
    if (result.stopped && rc.stopped_for_shutdown && !atomic_load(&j->cancel_requested)) {
        /* Stopping: keep the work done, resume at the next start. */
        save_snapshot(&rc, result.stock, rc.resume_from);
        fm_stock_free(result.stock);
        pthread_mutex_lock(&j->lock);
        j->state = FM_JOB_QUEUED;
        pthread_mutex_unlock(&j->lock);
        fm_log(FM_LOG_INFO, "job %s: stopped by shutdown at motion %ld; will resume", j->id,
               rc.resume_from);
        return;
    }
    pthread_mutex_lock(&jobs->lock);
    int deleted = j->deleted;
    pthread_mutex_unlock(&jobs->lock);
    if (deleted) {
        fm_stock_free(result.stock);
        char gone[PATH_MAX];
        snprintf(gone, sizeof gone, "%s.deleted", j->dir);
        fm_store_remove_dir(gone, &err);
        fm_log(FM_LOG_INFO, "job %s: stopped (deleted)", j->id);
        return;
    }
    publish_chunks(j, result.stock);
    pthread_mutex_lock(&j->lock);
    j->view.removed_mm3 = result.initial_volume_mm3 - result.final_volume_mm3;
    j->view.stock_mm3 = result.final_volume_mm3;
    j->report = fm_job_report_json(&result);
    pthread_mutex_unlock(&j->lock);
    save_snapshot(&rc, result.stock, result.stopped ? rc.resume_from : result.motions);
    fm_stock_free(result.stock);
    if (result.stopped) {
        finish(jobs, j, FM_JOB_CANCELLED, "cancelled");
    } else {
        char what[256];
        snprintf(what, sizeof what, "done: %ld motions, removed %.1f mm3 in %.2f s",
                 result.motions, result.removed_volume_mm3, result.wall_time_s);
        finish(jobs, j, FM_JOB_DONE, what);
    }
}

static void *worker_main(void *arg)
{
    fm_jobs *jobs = arg;
    pthread_mutex_lock(&jobs->lock);
    for (;;) {
        while (!jobs->stopping && !jobs->queue_head) pthread_cond_wait(&jobs->queue_cond, &jobs->lock);
        if (jobs->stopping) break;
        job *j = jobs->queue_head;
        jobs->queue_head = j->next_queued;
        if (!jobs->queue_head) jobs->queue_tail = NULL;
        int skip = j->deleted;
        pthread_mutex_unlock(&jobs->lock);
        pthread_mutex_lock(&j->lock);
        skip = skip || j->state >= FM_JOB_DONE; /* cancelled while queued */
        pthread_mutex_unlock(&j->lock);
        if (!skip && atomic_load(&j->cancel_requested)) {
            finish(jobs, j, FM_JOB_CANCELLED, "cancelled before it started");
        } else if (!skip) {
            run_job(jobs, j);
        }
        fm_jobs_put(jobs, j); /* the queue's reference */
        pthread_mutex_lock(&jobs->lock);
    }
    pthread_mutex_unlock(&jobs->lock);
    return NULL;
}

/* ---------------------------------------------------------- lifecycle -- */

fm_jobs *fm_jobs_open(const fm_jobs_config *cfg, fm_error *err)
{
    fm_jobs *jobs = calloc(1, sizeof *jobs);
    if (!jobs) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    jobs->cfg = *cfg;
    snprintf(jobs->state_dir, sizeof jobs->state_dir, "%s", cfg->state_dir);
    snprintf(jobs->jobs_dir, sizeof jobs->jobs_dir, "%s/jobs", cfg->state_dir);
    jobs->cfg.state_dir = jobs->state_dir;
    if (fm_store_mkdirs(jobs->jobs_dir, err) != FM_OK) {
        free(jobs);
        return NULL;
    }
    pthread_mutex_init(&jobs->lock, NULL);
    pthread_mutex_init(&jobs->live_lock, NULL);
    pthread_cond_init(&jobs->queue_cond, NULL);
    load_all(jobs);
    jobs->workers = calloc((size_t)cfg->workers, sizeof *jobs->workers);
    for (int i = 0; jobs->workers && i < cfg->workers; i++)
        if (pthread_create(&jobs->workers[i], NULL, worker_main, jobs) == 0) jobs->worker_count++;
    if (jobs->worker_count == 0) {
        fm_error_set(err, FM_ERR_INTERNAL, "cannot start worker threads");
        fm_jobs_close(jobs);
        return NULL;
    }
    return jobs;
}

job *fm_jobs_add_unstored(fm_jobs *jobs, json_t *spec)
{
    char id[32];
    make_id(jobs, id, sizeof id);
    job *j = job_new(id, jobs->jobs_dir, spec, wall_s());
    if (!j) return NULL;
    /* The folder lets DELETE work like for any job; without spec.json the
     * next start removes it. */
    if (mkdir(j->dir, 0750) != 0)
        fm_log(FM_LOG_WARN, "job %s: cannot create %s: %s", id, j->dir, strerror(errno));
    pthread_mutex_lock(&jobs->lock);
    table_add(jobs, j);
    j->refs++;
    pthread_mutex_unlock(&jobs->lock);
    return j;
}

void fm_jobs_emit(job *j, const char *type, json_t *data)
{
    emit(j, type, data);
}

void fm_jobs_publish_chunks(job *j, fm_stock *stock)
{
    publish_chunks(j, stock);
}

void fm_jobs_begin_shutdown(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    jobs->stopping = 1;
    pthread_cond_broadcast(&jobs->queue_cond);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        pthread_mutex_lock(&j->lock);
        pthread_cond_broadcast(&j->cond);
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&jobs->lock);
}

void fm_jobs_close(fm_jobs *jobs)
{
    if (!jobs) return;
    fm_jobs_begin_shutdown(jobs);
    fm_jobs_live_close(jobs);
    for (int i = 0; i < jobs->worker_count; i++) pthread_join(jobs->workers[i], NULL);
    free(jobs->workers);
    /* Drop the queue's references of jobs that never ran. */
    for (job *j = jobs->queue_head; j;) {
        job *next = j->next_queued;
        j->refs--;
        j = next;
    }
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        if (--j->refs == 0) job_free(j);
    }
    free(jobs->table);
    pthread_mutex_destroy(&jobs->lock);
    pthread_mutex_destroy(&jobs->live_lock);
    pthread_cond_destroy(&jobs->queue_cond);
    free(jobs);
}

/* ------------------------------------------------------------- Modbus -- */

int fm_jobs_count(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    int n = (int)jobs->count;
    pthread_mutex_unlock(&jobs->lock);
    return n;
}

int fm_jobs_view_slot(fm_jobs *jobs, int slot, fm_job_view *out)
{
    job *j = NULL;
    pthread_mutex_lock(&jobs->lock);
    if (slot >= 1 && (size_t)slot <= jobs->count) {
        j = jobs->table[slot - 1];
        j->refs++;
    }
    pthread_mutex_unlock(&jobs->lock);
    if (!j) return -1;
    pthread_mutex_lock(&j->lock);
    *out = j->view;
    out->state = j->state;
    out->paused = j->paused;
    pthread_mutex_unlock(&j->lock);
    fm_jobs_put(jobs, j);
    return 0;
}

int fm_jobs_pause(fm_jobs *jobs, const char *id, int pause)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return -1;
    pthread_mutex_lock(&j->lock);
    int ok = j->state <= FM_JOB_RUNNING;
    if (ok) {
        j->paused = pause;
        pthread_cond_broadcast(&j->cond);
        emit(j, "state", json_pack("{s:s, s:b}", "state", fm_job_state_name(j->state), "paused",
                                   pause));
    }
    pthread_mutex_unlock(&j->lock);
    fm_jobs_put(jobs, j);
    return ok ? 0 : -2;
}

void fm_jobs_pause_all(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->lock);
    for (size_t i = 0; i < jobs->count; i++) {
        job *j = jobs->table[i];
        pthread_mutex_lock(&j->lock);
        if (j->state == FM_JOB_RUNNING) j->paused = 1;
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&jobs->lock);
}

int fm_jobs_cancel(fm_jobs *jobs, const char *id)
{
    job *j = fm_jobs_get(jobs, id);
    if (!j) return -1;
    pthread_mutex_lock(&j->lock);
    int ok = j->state <= FM_JOB_RUNNING;
    int queued = j->state == FM_JOB_QUEUED;
    if (ok) {
        atomic_store(&j->cancel_requested, 1);
        j->paused = 0;
        pthread_cond_broadcast(&j->cond);
        /* A queued job ends now; its worker will skip it. */
        if (queued) j->state = FM_JOB_CANCELLED;
    }
    pthread_mutex_unlock(&j->lock);
    if (queued) finish(jobs, j, FM_JOB_CANCELLED, "cancelled before it started");
    fm_jobs_put(jobs, j);
    return ok ? 0 : -2;
}
