/* live.c: Modbus live mode. A live job is a job like any other: a stored
 * job document (program {"live": ...}) run by the job runner (queue.c,
 * daemon/runner/job.c), the same cut, check and publishing. Its motions
 * come from the controller: each position written (registers 110-116) is
 * queued here by the Modbus thread and appended to the job's journal
 * (live.journal in its folder), and the runner takes them through the
 * motion source below as straight feed moves from the previous position
 * (the first position only places the tool). A restarted daemon replays
 * the journal (the runner skips what its stock snapshot already holds) and
 * the live job continues where the machine is. One live job at a time: there
 * is one set of live registers. A position may carry more than Modbus
 * writes (live mode from MTConnect, live_source.c): the program line, which
 * the move then carries, and the rotary joints, which move the tool through
 * the live job's machine (live_machine) as a program's A/B/C words do. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "live.h"
#include "log.h"
#include "store.h"
#include "sweep/sweep.h"
#include "toolpaths/tooltable/tooltable.h"

/* Positions waiting to be cut. A controller polled every few ms fills it
 * only if cutting falls far behind; then writes are refused (busy) rather
 * than silently dropped. */
#define LIVE_QUEUE 4096
/* The journal: one line per position written, "X Y Z TOOL LINE A B C"
 * (nan for a joint not given; journals written before the line and the
 * joints were kept have "X Y Z TOOL"). A line cut short by a crash in the
 * middle of a write is ignored. */
#define LIVE_JOURNAL "live.journal"
#define LIVE_JOURNAL_MAX_BYTES ((size_t)256 << 20)
#define LIVE_LINE_MAX 256

typedef fm_live_pose live_pos;

struct job_live {
    /* Guarded by the job's lock; the job's cond wakes the source. */
    live_pos queue[LIVE_QUEUE];
    size_t head, count;
    int ending;          /* live mode off: cut what is queued, then end */
    int journal_fd;
    int journal_failed;  /* logged once */
    /* The journal read back at start, replayed before new positions. */
    live_pos *replay;
    size_t replay_count, replay_next;
    /* The source's own state (the job's thread only). */
    int have_prev;
    double prev[3];
    double prev_abc[3]; /* the joints, 0 for those not given */
    double program_time;
    long next_index;
    double feed;
};

static job_live *live_new(void)
{
    job_live *L = calloc(1, sizeof *L);
    if (L) L->journal_fd = -1;
    return L;
}

static void live_free(job_live *L)
{
    if (!L) return;
    if (L->journal_fd >= 0) close(L->journal_fd);
    free(L->replay);
    free(L);
}

/* ------------------------------------------------------------ journal -- */

static void journal_append(job *j, const live_pos *p)
{
    job_live *L = j->live;
    if (L->journal_fd < 0) return;
    char line[LIVE_LINE_MAX];
    int n = snprintf(line, sizeof line, "%.17g %.17g %.17g %d %d %.17g %.17g %.17g\n", p->xyz[0],
                     p->xyz[1], p->xyz[2], p->tool, p->line, p->abc[0], p->abc[1], p->abc[2]);
    /* One write of a short line with O_APPEND: a SIGKILL leaves it whole
     * or not at all in practice; a torn line is skipped when read back.
     * No fsync per position (the Modbus thread must not wait for the
     * disk): the page cache survives a killed daemon; the snapshot's
     * fsync bounds what a power cut loses. */
    if (n <= 0 || write(L->journal_fd, line, (size_t)n) != n) {
        if (!L->journal_failed)
            fm_log(FM_LOG_ERROR, "job %s: cannot write the live journal: %s", j->id,
                   strerror(errno));
        L->journal_failed = 1;
    }
}

/* Read the journal back (at start: every position the controller wrote). */
static fm_status journal_load(job *j, fm_error *err)
{
    job_live *L = j->live;
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", j->dir, LIVE_JOURNAL);
    if (access(path, F_OK) != 0) return FM_OK;
    char *text = NULL;
    size_t size = 0;
    fm_status st = fm_file_read(path, NULL, LIVE_JOURNAL_MAX_BYTES, &text, &size, err);
    if (st != FM_OK) return st;
    size_t lines = 0;
    for (size_t i = 0; i < size; i++) lines += text[i] == '\n';
    L->replay = calloc(lines ? lines : 1, sizeof *L->replay);
    if (!L->replay) {
        free(text);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for %zu journaled positions", lines);
    }
    char *line = text;
    for (char *nl; (nl = memchr(line, '\n', size - (size_t)(line - text))); line = nl + 1) {
        *nl = '\0';
        live_pos p;
        fm_live_pose_init(&p, (double[3]){0, 0, 0}, 0);
        char tail;
        int n = sscanf(line, "%lf %lf %lf %d %d %lf %lf %lf %c", &p.xyz[0], &p.xyz[1], &p.xyz[2],
                       &p.tool, &p.line, &p.abc[0], &p.abc[1], &p.abc[2], &tail);
        if ((n == 4 || n == 8) && isfinite(p.xyz[0]) && isfinite(p.xyz[1]) && isfinite(p.xyz[2])) {
            if (n == 4) p.line = 0;
            L->replay[L->replay_count++] = p;
        }
    }
    free(text);
    return FM_OK;
}

static fm_status journal_open(job *j, fm_error *err)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", j->dir, LIVE_JOURNAL);
    j->live->journal_fd = open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0640);
    if (j->live->journal_fd < 0)
        return fm_error_set(err, FM_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    return FM_OK;
}

/* ------------------------------------------------------------- source -- */

/* The runner's motion source (fm_job_motion_source.next), on the job's
 * thread. */
static int live_next(void *user, fm_motion *out, int *more)
{
    job *j = user;
    job_live *L = j->live;
    for (;;) {
        live_pos p;
        pthread_mutex_lock(&j->lock);
        int from_replay = L->replay_next < L->replay_count;
        while (!from_replay && !L->count && !L->ending && !atomic_load(&j->cancel_requested) &&
               !atomic_load(j->stopping))
            pthread_cond_wait(&j->cond, &j->lock);
        if (!from_replay && (atomic_load(&j->cancel_requested) || atomic_load(j->stopping))) {
            pthread_mutex_unlock(&j->lock);
            return -1; /* cancelled, deleted or stopping: the runner stops */
        }
        if (from_replay) {
            p = L->replay[L->replay_next++];
        } else if (L->count) {
            p = L->queue[L->head];
            L->head = (L->head + 1) % LIVE_QUEUE;
            L->count--;
        } else {
            pthread_mutex_unlock(&j->lock); /* ending, and every position is cut */
            return 0;
        }
        *more = L->count > 0 || L->replay_next < L->replay_count;
        pthread_mutex_unlock(&j->lock);

        double abc[3];
        for (int a = 0; a < 3; a++) abc[a] = isfinite(p.abc[a]) ? p.abc[a] : 0.0;
        if (!L->have_prev) {
            /* The first position only places the tool. */
            memcpy(L->prev, p.xyz, sizeof L->prev);
            memcpy(L->prev_abc, abc, sizeof L->prev_abc);
            L->have_prev = 1;
            continue;
        }
        double d[3] = {p.xyz[0] - L->prev[0], p.xyz[1] - L->prev[1], p.xyz[2] - L->prev[2]};
        double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        memset(out, 0, sizeof *out);
        out->kind = FM_MOTION_LINE;
        memcpy(out->start, L->prev, sizeof out->start);
        memcpy(out->end, p.xyz, sizeof out->end);
        out->axis_start[2] = out->axis_end[2] = 1;
        out->feed = L->feed;
        /* The register map carries no spindle state: a live move is taken
         * as cutting with the spindle on (speed unknown, so nominal). */
        out->spindle_rpm = 1;
        out->spindle_dir = 1;
        out->tool = p.tool;
        out->t0 = L->program_time;
        out->t1 = L->program_time + length / L->feed * 60.0;
        /* The machine's rotary axes: the position's X/Y/Z and A/B/C are its
         * joints, each moving linearly in time (no tool centre point
         * control: a machine's axes, not a programmed tip). */
        const fm_machine *machine = j->doc->spec.machine;
        if (machine && machine->rotary_count > 0) {
            out->machine = machine;
            memcpy(out->rotary_start, L->prev_abc, sizeof out->rotary_start);
            memcpy(out->rotary_end, abc, sizeof out->rotary_end);
            out->tcp = 0;
            const fm_tool_spec *t = fm_tool_table_find(&j->doc->tools, p.tool);
            out->tool_length = t ? t->length_offset : 0.0;
            double tip[3];
            fm_motion_pose_at(out, 0, tip, out->axis_start);
            fm_motion_pose_at(out, 1, tip, out->axis_end);
            /* A turn of the joints alone is a move too: its time from the
             * largest joint travel at the feed taken as degrees/min. */
            double turn = 0;
            for (int a = 0; a < 3; a++) turn = fmax(turn, fabs(abc[a] - L->prev_abc[a]));
            if (turn > length) out->t1 = L->program_time + turn / L->feed * 60.0;
        }
        /* The machine's program line when the source gives it; else the
         * move's number stands for one. */
        out->line = p.line > 0 ? p.line : (int)(L->next_index + 1);
        out->block = -1;
        out->index = L->next_index++;
        L->program_time = out->t1;
        memcpy(L->prev, p.xyz, sizeof L->prev);
        memcpy(L->prev_abc, abc, sizeof L->prev_abc);
        return 1;
    }
}

/* The live state with the journal read back and open for appending; the
 * caller holds the job's lock. Idempotent. */
static fm_status live_setup(job *j, fm_error *err)
{
    if (!j->live && !(j->live = live_new()))
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    j->live_free = live_free;
    job_live *L = j->live;
    L->feed = j->doc->live_feed > 0 ? j->doc->live_feed : 1000;
    fm_status st = FM_OK;
    if (!L->replay && L->journal_fd < 0) {
        st = journal_load(j, err);
        if (st == FM_OK && L->replay_count)
            fm_log(FM_LOG_INFO, "job %s: replaying %zu journaled live positions", j->id,
                   L->replay_count);
    }
    if (st == FM_OK && L->journal_fd < 0) st = journal_open(j, err);
    return st;
}

fm_status fm_live_prepare(job *j, fm_job_motion_source *src, fm_error *err)
{
    pthread_mutex_lock(&j->lock);
    fm_status st = live_setup(j, err);
    pthread_mutex_unlock(&j->lock);
    src->user = j;
    src->next = live_next;
    return st;
}

void fm_live_session_init(fm_live_session *s)
{
    pthread_mutex_init(&s->lock, NULL);
    s->job = NULL;
    s->has_last = 0;
    pthread_mutex_init(&s->hook_lock, NULL);
    s->on_position = NULL;
    s->on_position_user = NULL;
}

int fm_live_machine(fm_live_session *s, fm_live_pose *out)
{
    pthread_mutex_lock(&s->lock);
    int has = s->job && s->has_last;
    if (has) *out = s->last;
    pthread_mutex_unlock(&s->lock);
    return has;
}

void fm_live_on_position(fm_live_session *s, void (*fn)(void *user), void *user)
{
    pthread_mutex_lock(&s->hook_lock);
    s->on_position = fn;
    s->on_position_user = user;
    pthread_mutex_unlock(&s->hook_lock);
}

void fm_live_session_destroy(fm_live_session *s)
{
    fm_job_unref(s->job);
    s->job = NULL;
    pthread_mutex_destroy(&s->hook_lock);
    pthread_mutex_destroy(&s->lock);
}

fm_status fm_live_attach(fm_live_session *s, job *j, fm_error *err)
{
    /* The live state exists before the job is the live job: a position the
     * controller writes right after "live on" is queued and journaled, not
     * refused because the job's thread has not started yet. */
    pthread_mutex_lock(&j->lock);
    fm_status st = live_setup(j, err);
    pthread_mutex_unlock(&j->lock);
    if (st != FM_OK) return st;
    pthread_mutex_lock(&s->lock);
    job *old = s->job;
    fm_job_ref(j); /* the live session's */
    s->job = j;
    s->has_last = 0;
    pthread_mutex_unlock(&s->lock);
    fm_job_unref(old);
    return FM_OK;
}

void fm_live_detach(fm_live_session *s, job *j)
{
    pthread_mutex_lock(&s->lock);
    int attached = s->job == j;
    if (attached) s->job = NULL;
    pthread_mutex_unlock(&s->lock);
    if (attached) fm_job_unref(j);
}

int fm_live_active(fm_live_session *s)
{
    pthread_mutex_lock(&s->lock);
    int on = s->job != NULL;
    pthread_mutex_unlock(&s->lock);
    return on;
}

/* --------------------------------------------------------- live mode -- */

fm_status fm_live_document(const fm_live_config *cfg, const job *src, const fm_job_doc_rules *rules,
                           fm_job_doc **out, fm_error *err)
{
    const char *stock = cfg->stock && cfg->stock[0] ? cfg->stock : NULL;
    const char *tools = cfg->tools && cfg->tools[0] ? cfg->tools : NULL;
    char stock_spec[1024] = "";
    json_t *tools_json = NULL;
    if (stock) snprintf(stock_spec, sizeof stock_spec, "%s", stock);
    if (tools) {
        char *text = NULL;
        size_t size = 0;
        fm_error terr;
        fm_error_clear(&terr);
        if (fm_file_read(tools, NULL, FM_TOOLTABLE_MAX_BYTES, &text, &size, &terr) != FM_OK)
            return fm_error_set(err, FM_ERR_INPUT, "live_tools: %s", terr.message);
        json_error_t jerr;
        tools_json = json_loadb(text, size, 0, &jerr);
        free(text);
        if (!tools_json)
            return fm_error_set(err, FM_ERR_INPUT, "live_tools %s: not a JSON tool table: %s",
                                tools, jerr.text);
    }
    if (!stock || !tools) {
        /* The selected job's stock and tools. */
        int ok = src != NULL;
        if (ok && !stock) {
            /* The job's stock spec, or the file its inline model was
             * written to when it was stored. */
            const char *s = src->doc->spec.stock_spec;
            ok = s && (!strncmp(s, "box:", 4) || !strncmp(s, "cylinder:", 9) ||
                       access(s, R_OK) == 0);
            if (ok) snprintf(stock_spec, sizeof stock_spec, "%s", s);
        }
        if (ok && !tools) {
            /* a job whose tools came from its program's comments has no
             * table to hand on: not usable for live mode */
            tools_json = json_incref(json_object_get(src->doc->json, "tools"));
            ok = tools_json != NULL;
        }
        if (!ok) {
            json_decref(tools_json);
            return fm_error_set(err, FM_ERR_INPUT,
                                "no live_stock/live_tools configured and no usable job selected");
        }
    }
    json_t *spec = json_pack("{s:s, s:f, s:o, s:{s:{s:f}}, s:{s:s}}", "stock", stock_spec,
                             "voxel", cfg->voxel > 0 ? cfg->voxel : 0.25, "tools", tools_json,
                             "program", "live", "feed", cfg->feed > 0 ? cfg->feed : 1000,
                             "options", "name", "live");
    if (!spec) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    /* The machine's rotary axes move the tool by the joints a position
     * carries; its limits and components are the check's. */
    if (cfg->machine && cfg->machine[0]) json_object_set_new(spec, "machine", json_string(cfg->machine));
    fm_status st = fm_job_doc_from_json(spec, rules, out, err);
    json_decref(spec);
    return st;
}

fm_status fm_live_position(fm_live_session *s, const fm_live_pose *pose, fm_error *err)
{
    pthread_mutex_lock(&s->lock);
    job *j = s->job;
    fm_status rc = FM_OK;
    if (!j) {
        rc = fm_error_set(err, FM_ERR_INPUT, "live mode is off");
    } else {
        pthread_mutex_lock(&j->lock);
        job_live *L = j->live;
        if (!L || L->ending || j->state >= FM_JOB_DONE) {
            rc = fm_error_set(err, FM_ERR_INPUT, "the live job has ended");
        } else if (L->count == LIVE_QUEUE) {
            rc = fm_error_set_reason(err, FM_ERR_LIMIT, "busy", "%d positions are waiting",
                                     LIVE_QUEUE);
        } else {
            live_pos *p = &L->queue[(L->head + L->count) % LIVE_QUEUE];
            *p = *pose;
            L->count++;
            journal_append(j, p);
            pthread_cond_broadcast(&j->cond);
            s->last = *pose;
            s->has_last = 1;
        }
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&s->lock);
    if (rc == FM_OK) {
        pthread_mutex_lock(&s->hook_lock);
        if (s->on_position) s->on_position(s->on_position_user);
        pthread_mutex_unlock(&s->hook_lock);
    }
    return rc;
}

void fm_live_note(fm_live_session *s, const char *note)
{
    pthread_mutex_lock(&s->lock);
    job *j = s->job;
    if (j) {
        pthread_mutex_lock(&j->lock);
        snprintf(j->live_note, sizeof j->live_note, "%s", note);
        pthread_mutex_unlock(&j->lock);
    }
    pthread_mutex_unlock(&s->lock);
}

void fm_live_stop(fm_live_session *s)
{
    /* The Modbus thread does not wait for the queued moves to be cut: the
     * job is told to end and its thread finishes on its own. */
    pthread_mutex_lock(&s->lock);
    job *j = s->job;
    s->job = NULL;
    pthread_mutex_unlock(&s->lock);
    if (!j) return;
    pthread_mutex_lock(&j->lock);
    if (j->live) j->live->ending = 1;
    pthread_cond_broadcast(&j->cond);
    pthread_mutex_unlock(&j->lock);
    fm_log(FM_LOG_INFO, "job %s: live mode off", j->id);
    fm_job_unref(j); /* the live session's reference */
}
