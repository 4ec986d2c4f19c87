/* jobs_live.c: Modbus live mode. The controller writes its axis positions;
 * each new one is a straight feed move from the previous one, cut from a
 * live job's stock on this module's own thread (the Modbus thread only
 * queues), and published like any job's progress: status snapshots, events
 * and chunk meshes, so the viewer and the registers follow the real part.
 * One live session at a time: there is one set of live registers. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "runner/job.h"
#include "jobs_internal.h"
#include "log.h"
#include "sweep/sweep.h"
#include "toolpaths/tooltable/tooltable.h"

/* Positions waiting to be cut. A controller polled every few ms fills it
 * only if cutting falls far behind; then writes are refused (busy) rather
 * than silently dropped. */
#define LIVE_QUEUE 4096
#define LIVE_MAX_TOOLS 256

typedef struct live_pos {
    double xyz[3];
    int tool;
} live_pos;

typedef struct jobs_live {
    fm_jobs *jobs;
    job *j;                /* our reference */
    pthread_t thread;
    int thread_started;
    pthread_mutex_t lock;  /* guards the queue, stop, failed */
    pthread_cond_t cond;
    live_pos queue[LIVE_QUEUE];
    size_t head, count;
    long received;
    int stop;
    int failed;
    /* Set up by the thread; owned by it. */
    char stock_spec[1024];
    char tools_path[1024];
    json_t *tools_json;    /* from the selected job, or NULL */
} jobs_live;

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct live_tools {
    fm_tool_table table;
    fm_tool tools[LIVE_MAX_TOOLS];
    size_t count;
} live_tools;

static fm_status load_tools(jobs_live *L, live_tools *t, fm_error *err)
{
    fm_status st;
    if (L->tools_json) {
        char *text = json_dumps(L->tools_json, JSON_INDENT(1));
        st = text ? fm_tooltable_parse_json(text, strlen(text), "tools", &t->table, err)
                  : fm_error_set(err, FM_ERR_INPUT, "no tool table");
        free(text);
    } else {
        st = fm_tooltable_load(L->tools_path, &t->table, err);
    }
    if (st != FM_OK) return st;
    for (size_t i = 0; i < t->table.count && i < LIVE_MAX_TOOLS; i++) {
        if (t->table.tools[i].shape == FM_TOOL_HYPERFUN)
            return fm_error_set(err, FM_ERR_INPUT,
                                "tool %d is a HyperFun tool; live mode takes standard shapes",
                                t->table.tools[i].number);
        if ((st = fm_tool_build(&t->table.tools[i], &t->tools[i], err)) != FM_OK) return st;
        t->count++;
    }
    return t->count ? FM_OK : fm_error_set(err, FM_ERR_INPUT, "the tool table has no tools");
}

/* The tool of a move, as the job runner picks it: the numbered one, or the
 * only one when the controller reports tool 0. */
static const fm_tool *tool_for(const live_tools *t, int number)
{
    for (size_t i = 0; i < t->count; i++)
        if (t->tools[i].spec.number == number) return &t->tools[i];
    if (number == 0 && t->count == 1) return &t->tools[0];
    return NULL;
}

static void fail(jobs_live *L, const fm_error *err)
{
    job *j = L->j;
    pthread_mutex_lock(&L->lock);
    L->failed = 1;
    pthread_mutex_unlock(&L->lock);
    pthread_mutex_lock(&j->lock);
    j->state = FM_JOB_FAILED;
    j->view.error_code = (int)err->code;
    json_decref(j->error);
    j->error = json_pack("{s:s, s:i, s:s, s:n, s:n, s:s}", "code", "live", "status",
                         (int)err->code, "message", err->message, "line", "column", "file",
                         err->file);
    fm_publish_event(j, "end", json_pack("{s:s, s:O?}", "state", "failed", "error", j->error));
    pthread_mutex_unlock(&j->lock);
    fm_log(FM_LOG_WARN, "job %s: live mode failed: %s", j->id, err->message);
}

static void *live_main(void *arg)
{
    jobs_live *L = arg;
    job *j = L->j;
    fm_jobs *jobs = L->jobs;
    fm_error err;
    fm_error_clear(&err);
    live_tools *tools = calloc(1, sizeof *tools);
    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = jobs->cfg.live_voxel > 0 ? jobs->cfg.live_voxel : 0.25;
    opt.memory_budget = jobs->cfg.job_memory_bytes;
    opt.threads = jobs->cfg.threads_per_job;
    fm_stock *stock = NULL;
    fm_status st = tools ? load_tools(L, tools, &err) : fm_error_set(&err, FM_ERR_LIMIT, "out of memory");
    if (st == FM_OK) {
        stock = fm_job_make_stock(L->stock_spec, &opt, &err);
        if (!stock) st = err.code ? err.code : FM_ERR_INPUT;
    }
    if (st != FM_OK) {
        fail(L, &err);
        if (tools) fm_tool_table_free(&tools->table);
        free(tools);
        return NULL;
    }
    double initial = fm_stock_initial_volume(stock);
    double feed = jobs->cfg.live_feed > 0 ? jobs->cfg.live_feed : 1000;
    pthread_mutex_lock(&j->lock);
    j->state = FM_JOB_RUNNING;
    j->initial_mm3 = initial;
    j->view.stock_mm3 = initial;
    fm_publish_event(j, "state", json_pack("{s:s, s:b}", "state", "running", "live", 1));
    pthread_mutex_unlock(&j->lock);
    fm_publish_chunks(j, stock);
    fm_log(FM_LOG_INFO, "job %s: live mode on (stock %s, voxel %g mm)", j->id, L->stock_spec,
           opt.voxel_mm);

    int have_prev = 0;
    double prev[3] = {0, 0, 0}, program_time = 0, last_publish = mono_s();
    long motions = 0;
    for (;;) {
        live_pos batch[64];
        size_t n = 0;
        pthread_mutex_lock(&L->lock);
        while (!L->count && !L->stop) pthread_cond_wait(&L->cond, &L->lock);
        /* Drain what is queued even when stopping: every acknowledged
         * position is cut. */
        while (L->count && n < 64) {
            batch[n++] = L->queue[L->head];
            L->head = (L->head + 1) % LIVE_QUEUE;
            L->count--;
        }
        int stopping = L->stop && n == 0;
        pthread_mutex_unlock(&L->lock);
        if (stopping) break;
        int tool_number = 0;
        for (size_t i = 0; i < n && st == FM_OK; i++) {
            const live_pos *p = &batch[i];
            tool_number = p->tool;
            if (!have_prev) {
                /* The first position only places the tool. */
                memcpy(prev, p->xyz, sizeof prev);
                have_prev = 1;
                continue;
            }
            double d[3] = {p->xyz[0] - prev[0], p->xyz[1] - prev[1], p->xyz[2] - prev[2]};
            double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            fm_motion m;
            memset(&m, 0, sizeof m);
            m.kind = FM_MOTION_LINE;
            memcpy(m.start, prev, sizeof m.start);
            memcpy(m.end, p->xyz, sizeof m.end);
            m.axis_start[2] = m.axis_end[2] = 1;
            m.feed = feed;
            m.tool = p->tool;
            m.t0 = program_time;
            m.t1 = program_time + length / feed * 60.0;
            m.line = (int)(motions + 1); /* the move's number stands for a source line */
            m.block = -1;
            m.index = motions;
            program_time = m.t1;
            memcpy(prev, p->xyz, sizeof prev);
            motions++;
            const fm_tool *tool = tool_for(tools, p->tool);
            if (!tool || length <= 0) continue; /* nothing in the spindle cuts nothing */
            fm_field field;
            st = fm_sweep_field_many(&field, &m, 1, &tool->flutes, &err);
            if (st == FM_OK) {
                fm_stock_cut cut = {.tool = tool->spec.number, .block = m.line, .t0 = m.t0,
                                    .t1 = m.t1};
                st = fm_stock_subtract(stock, &field, &cut, NULL, &err);
                fm_field_release(&field);
            }
        }
        if (st != FM_OK) break;
        double removed = fm_stock_removed_volume(stock);
        pthread_mutex_lock(&j->lock);
        fm_job_view *v = &j->view;
        v->line = (int)motions;
        v->block = -1;
        v->tool = tool_number;
        memcpy(v->position, prev, sizeof v->position);
        v->program_time_s = program_time;
        v->removed_mm3 = removed;
        v->stock_mm3 = initial - removed;
        v->removal_rate_mm3_s = program_time > 0 ? removed / program_time : 0;
        j->motions_done = motions;
        pthread_mutex_lock(&L->lock);
        j->motions_total = L->received > 0 ? L->received - 1 : 0;
        int more = L->count > 0;
        pthread_mutex_unlock(&L->lock);
        fm_publish_event(j, "progress",
                     json_pack("{s:f, s:i, s:I, s:i, s:[f,f,f], s:f, s:f}", "progress", 0.0,
                               "line", v->line, "block", (json_int_t)-1, "tool", v->tool,
                               "position", prev[0], prev[1], prev[2], "removed_volume_mm3",
                               removed, "stock_volume_mm3", v->stock_mm3));
        pthread_mutex_unlock(&j->lock);
        /* Publish meshes at the configured pace, and whenever the queue
         * has run dry so that the view catches up with the machine. */
        if (!more || mono_s() - last_publish >= jobs->cfg.publish_interval_s) {
            fm_publish_chunks(j, stock);
            last_publish = mono_s();
        }
    }
    if (st != FM_OK) {
        fail(L, &err);
    } else {
        fm_publish_chunks(j, stock);
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/stock.vdb", j->dir);
        fm_error serr;
        if (fm_stock_save(stock, path, "live", &serr) != FM_OK)
            fm_log(FM_LOG_WARN, "job %s: live stock not saved: %s", j->id, serr.message);
        pthread_mutex_lock(&j->lock);
        j->state = FM_JOB_DONE;
        j->view.progress = 1;
        j->meshes_loaded = 1;
        fm_publish_event(j, "end", json_pack("{s:s}", "state", "done"));
        pthread_mutex_unlock(&j->lock);
        fm_log(FM_LOG_INFO, "job %s: live mode off after %ld moves, removed %.1f mm3", j->id,
               motions, fm_stock_removed_volume(stock));
    }
    fm_stock_free(stock);
    fm_tool_table_free(&tools->table);
    free(tools);
    return NULL;
}

/* Stop the session's thread (it cuts what is queued first) and free it. */
static void session_end(fm_jobs *jobs, jobs_live *L)
{
    pthread_mutex_lock(&L->lock);
    L->stop = 1;
    pthread_cond_broadcast(&L->cond);
    pthread_mutex_unlock(&L->lock);
    if (L->thread_started) pthread_join(L->thread, NULL);
    fm_jobs_put(jobs, L->j);
    json_decref(L->tools_json);
    pthread_mutex_destroy(&L->lock);
    pthread_cond_destroy(&L->cond);
    free(L);
}

int fm_jobs_live_start(fm_jobs *jobs, int from_slot)
{
    jobs_live *L = calloc(1, sizeof *L);
    if (!L) return -2;
    L->jobs = jobs;
    pthread_mutex_init(&L->lock, NULL);
    pthread_cond_init(&L->cond, NULL);
    const char *stock = jobs->cfg.live_stock && jobs->cfg.live_stock[0] ? jobs->cfg.live_stock : NULL;
    const char *tools = jobs->cfg.live_tools && jobs->cfg.live_tools[0] ? jobs->cfg.live_tools : NULL;
    if (stock) snprintf(L->stock_spec, sizeof L->stock_spec, "%s", stock);
    if (tools) snprintf(L->tools_path, sizeof L->tools_path, "%s", tools);
    if (!stock || !tools) {
        /* The selected job's stock and tools. */
        job *src = NULL;
        pthread_mutex_lock(&jobs->lock);
        if (from_slot >= 1 && (size_t)from_slot <= jobs->count) {
            src = jobs->table[from_slot - 1];
            src->refs++;
        }
        pthread_mutex_unlock(&jobs->lock);
        json_t *s = src ? json_object_get(src->spec, "stock") : NULL;
        int ok = src != NULL;
        if (ok && !stock) {
            if (json_is_string(s)) {
                snprintf(L->stock_spec, sizeof L->stock_spec, "%s", json_string_value(s));
            } else {
                /* An inline model was written to the job's folder when it ran. */
                snprintf(L->stock_spec, sizeof L->stock_spec, "%.1000s/stock.%s", src->dir,
                         json_object_get(s, "hyperfun") ? "hf" : "stl");
                ok = access(L->stock_spec, R_OK) == 0;
            }
        }
        if (ok && !tools) L->tools_json = json_incref(json_object_get(src->spec, "tools"));
        if (src) fm_jobs_put(jobs, src);
        if (!ok) {
            fm_log(FM_LOG_WARN, "live mode refused: no live_stock/live_tools configured and no "
                                "usable job selected");
            pthread_mutex_destroy(&L->lock);
            pthread_cond_destroy(&L->cond);
            json_decref(L->tools_json);
            free(L);
            return -1;
        }
    }
    json_t *spec = json_pack("{s:s, s:f, s:O?, s:{s:s}, s:[], s:{s:s, s:b}}", "stock",
                             L->stock_spec, "voxel", jobs->cfg.live_voxel, "tools", L->tools_json,
                             "program", "live", "modbus", "fixtures", "options", "name", "live",
                             "check", 0);
    pthread_mutex_lock(&jobs->live_lock);
    if (jobs->live) {
        pthread_mutex_unlock(&jobs->live_lock);
        json_decref(spec);
        pthread_mutex_destroy(&L->lock);
        pthread_cond_destroy(&L->cond);
        json_decref(L->tools_json);
        free(L);
        return 0; /* already on */
    }
    jobs_live *old = jobs->live_ending;
    jobs->live_ending = NULL;
    if (old) session_end(jobs, old); /* normally ended long ago */
    L->j = fm_jobs_add_unstored(jobs, spec);
    json_decref(spec);
    if (L->j && pthread_create(&L->thread, NULL, live_main, L) == 0) L->thread_started = 1;
    if (!L->thread_started) {
        pthread_mutex_unlock(&jobs->live_lock);
        if (L->j) fm_jobs_put(jobs, L->j);
        pthread_mutex_destroy(&L->lock);
        pthread_cond_destroy(&L->cond);
        json_decref(L->tools_json);
        free(L);
        return -2;
    }
    jobs->live = L;
    pthread_mutex_unlock(&jobs->live_lock);
    fm_log(FM_LOG_INFO, "job %s: live job created", L->j->id);
    return 0;
}

int fm_jobs_live_position(fm_jobs *jobs, const double xyz[3], int tool)
{
    pthread_mutex_lock(&jobs->live_lock);
    jobs_live *L = jobs->live;
    int rc = -1;
    if (L) {
        pthread_mutex_lock(&L->lock);
        if (L->failed || L->stop) {
            rc = -1;
        } else if (L->count == LIVE_QUEUE) {
            rc = -2;
        } else {
            live_pos *p = &L->queue[(L->head + L->count) % LIVE_QUEUE];
            memcpy(p->xyz, xyz, sizeof p->xyz);
            p->tool = tool;
            L->count++;
            L->received++;
            pthread_cond_signal(&L->cond);
            rc = 0;
        }
        pthread_mutex_unlock(&L->lock);
    }
    pthread_mutex_unlock(&jobs->live_lock);
    return rc;
}

int fm_jobs_live_stop(fm_jobs *jobs)
{
    /* The Modbus thread must not wait for the queued moves to be cut: the
     * session is told to stop and parked; its thread is joined at the next
     * start or at close (by then it has normally ended). */
    pthread_mutex_lock(&jobs->live_lock);
    jobs_live *L = jobs->live, *old = NULL;
    jobs->live = NULL;
    if (L) {
        pthread_mutex_lock(&L->lock);
        L->stop = 1;
        pthread_cond_broadcast(&L->cond);
        pthread_mutex_unlock(&L->lock);
        old = jobs->live_ending;
        jobs->live_ending = L;
    }
    pthread_mutex_unlock(&jobs->live_lock);
    if (old) session_end(jobs, old);
    return 0;
}

int fm_jobs_live_active(fm_jobs *jobs)
{
    pthread_mutex_lock(&jobs->live_lock);
    int on = jobs->live != NULL;
    pthread_mutex_unlock(&jobs->live_lock);
    return on;
}

void fm_jobs_live_close(fm_jobs *jobs)
{
    fm_jobs_live_stop(jobs);
    pthread_mutex_lock(&jobs->live_lock);
    jobs_live *L = jobs->live_ending;
    jobs->live_ending = NULL;
    pthread_mutex_unlock(&jobs->live_lock);
    if (L) session_end(jobs, L);
}
