/* mtc_agent.c: the agent. Snapshots of the daemon become observations with
 * sequence numbers in a bounded circular buffer (a value enters only when
 * it changed); the requests of the REST protocol (probe, current, sample,
 * assets, asset) are answered from it, interval requests as a stream of
 * multipart/x-mixed-replace parts. One lock guards the buffer; a condition
 * variable wakes the streams when observations arrive. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mtc_internal.h"

struct fm_mtc_agent {
    fm_mtc_config cfg;
    fm_mtc_service svc;
    mtc_model model;
    double model_time;

    pthread_mutex_t update_lock; /* one update at a time: snapshots enter in the order taken */
    pthread_mutex_t lock;
    pthread_cond_t changed;
    mtc_obs *ring;            /* buffer_size observations; seq s at ring[s % buffer_size] */
    uint64_t first, next;     /* sequences kept: [first, next) */
    mtc_state latest[MTC_MAX_ITEMS];
    mtc_state at_first[MTC_MAX_ITEMS]; /* the state before ring's first observation */
    char values[MTC_MAX_ITEMS][MTC_VALUE_MAX]; /* the last value given per item, to diff */
    fm_mtc_finding findings[FM_MTC_MAX_FINDINGS];
    int finding_count;
    int stopping;

    pthread_t sampler;
    int sampler_started;
};

struct fm_mtc_stream {
    fm_mtc_agent *agent;
    int current;              /* 1: current every interval; 0: sample */
    fm_mtc_query query;
    unsigned char selected[MTC_MAX_ITEMS];
    uint64_t next;
    double last_sent;
    char boundary[40];
    char *pending;
    size_t pending_size, pending_off;
};

/* lib/core's clocks: timestamps on the wall clock, waits on the monotonic. */
static double now_s(void)
{
    return fm_clock_wall_s();
}

static double mono_s(void)
{
    return fm_clock_monotonic_s();
}

void fm_mtc_config_default(fm_mtc_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->device.name, sizeof cfg->device.name, "frepmill");
    snprintf(cfg->device.uuid, sizeof cfg->device.uuid, "frepmill-0");
    snprintf(cfg->sender, sizeof cfg->sender, "frepmilld");
    cfg->buffer_size = 16384;
    cfg->sample_ms = 0;
}

/* Text the documents can carry: printable ASCII; anything else '?', so
 * that no byte of a program name or an adapter's value can make the XML
 * ill-formed. */
static void clean_copy(char *dst, size_t cap, const char *src)
{
    size_t n = 0;
    for (; src[n] && n + 1 < cap; n++) {
        unsigned char c = (unsigned char)src[n];
        dst[n] = (c >= 0x20 && c < 0x7f) ? (char)c : '?';
    }
    dst[n] = '\0';
}

/* Add one observation (lock held). */
static void add_obs(fm_mtc_agent *a, int item, int level, const char *code, const char *value, double t)
{
    uint32_t size = a->cfg.buffer_size;
    if (a->next - a->first == size) {
        mtc_obs *old = &a->ring[a->first % size];
        mtc_state_apply(&a->at_first[old->item], old);
        a->first++;
    }
    mtc_obs *o = &a->ring[a->next % size];
    memset(o, 0, sizeof *o);
    o->seq = a->next++;
    o->time = t;
    o->item = item;
    o->level = level;
    clean_copy(o->native_code, sizeof o->native_code, code ? code : "");
    clean_copy(o->value, sizeof o->value, value ? value : "");
    mtc_state_apply(&a->latest[item], o);
}

static void set_value(fm_mtc_agent *a, const char *id, const char *value, double t)
{
    int i = mtc_model_find(&a->model, id);
    if (i < 0) return;
    char clean[MTC_VALUE_MAX];
    clean_copy(clean, sizeof clean, value);
    if (a->latest[i].last.seq && !strcmp(a->values[i], clean)) return;
    snprintf(a->values[i], sizeof a->values[i], "%s", clean);
    add_obs(a, i, MTC_LEVEL_VALUE, NULL, clean, t);
}

static void set_number(fm_mtc_agent *a, const char *id, double v, const char *format, double t)
{
    char text[64];
    if (!isfinite(v))
        snprintf(text, sizeof text, "UNAVAILABLE");
    else
        snprintf(text, sizeof text, format, v);
    set_value(a, id, text, t);
}

static const char *execution_name(fm_mtc_execution e)
{
    switch (e) {
    case FM_MTC_EXEC_READY: return "READY";
    case FM_MTC_EXEC_ACTIVE: return "ACTIVE";
    case FM_MTC_EXEC_INTERRUPTED: return "INTERRUPTED";
    case FM_MTC_EXEC_STOPPED: return "STOPPED";
    case FM_MTC_EXEC_PROGRAM_COMPLETED: return "PROGRAM_COMPLETED";
    default: return "UNAVAILABLE";
    }
}

static int same_finding(const fm_mtc_finding *x, const fm_mtc_finding *y)
{
    return x->line == y->line && x->level == y->level && !strcmp(x->text, y->text);
}

static void update_findings(fm_mtc_agent *a, const fm_mtc_snapshot *s, double t)
{
    int item = mtc_model_find(&a->model, "motion");
    int count = s->finding_count < 0 ? 0 : s->finding_count > FM_MTC_MAX_FINDINGS ? FM_MTC_MAX_FINDINGS
                                                                                   : s->finding_count;
    int first_time = a->latest[item].last.level == MTC_LEVEL_UNAVAILABLE;
    if (!count) {
        if (a->finding_count || first_time) add_obs(a, item, FM_MTC_NORMAL, NULL, NULL, t);
        a->finding_count = 0;
        return;
    }
    char code[24];
    for (int i = 0; i < a->finding_count; i++) {
        int kept = 0;
        for (int j = 0; j < count; j++) kept |= same_finding(&a->findings[i], &s->findings[j]);
        if (kept) continue;
        snprintf(code, sizeof code, "%ld", a->findings[i].line);
        add_obs(a, item, FM_MTC_NORMAL, code, NULL, t);
    }
    for (int j = 0; j < count; j++) {
        int known = 0;
        for (int i = 0; i < a->finding_count; i++) known |= same_finding(&a->findings[i], &s->findings[j]);
        if (known) continue;
        snprintf(code, sizeof code, "%ld", s->findings[j].line);
        add_obs(a, item, s->findings[j].level == FM_MTC_FAULT ? FM_MTC_FAULT : FM_MTC_WARNING, code,
                s->findings[j].text, t);
    }
    memcpy(a->findings, s->findings, sizeof a->findings[0] * (size_t)count);
    a->finding_count = count;
}

static void snapshot_blank(fm_mtc_snapshot *s)
{
    memset(s, 0, sizeof *s);
    s->line = -1;
    s->tool = -1;
    for (int i = 0; i < 3; i++) s->position[i] = NAN;
    for (int i = 0; i < 3; i++) s->rotary[i] = NAN;
    s->spindle_rpm = s->removed_mm3 = s->stock_mm3 = s->progress_percent = s->uncertain_voxels = NAN;
}

void fm_mtc_agent_update(fm_mtc_agent *a)
{
    fm_mtc_snapshot s;
    snapshot_blank(&s);
    pthread_mutex_lock(&a->update_lock);
    if (a->svc.snapshot) a->svc.snapshot(a->svc.ctx, &s);
    s.program[sizeof s.program - 1] = '\0';
    s.system_fault[sizeof s.system_fault - 1] = '\0';
    pthread_mutex_lock(&a->lock);
    uint64_t before = a->next;
    double t = now_s();
    char text[160];
    set_value(a, "avail", s.available ? "AVAILABLE" : "UNAVAILABLE", t);
    set_value(a, "exec", execution_name(s.execution), t);
    set_value(a, "program", s.program[0] ? s.program : "UNAVAILABLE", t);
    set_number(a, "line", s.line >= 0 ? (double)s.line : NAN, "%.0f", t);
    set_number(a, "tool", s.tool >= 0 ? (double)s.tool : NAN, "%.0f", t);
    if (s.tool >= 0)
        snprintf(text, sizeof text, "T%ld", s.tool);
    else
        snprintf(text, sizeof text, "UNAVAILABLE");
    set_value(a, "tool_asset", text, t);
    static const char *const linear[3] = {"Xpos", "Ypos", "Zpos"};
    for (int i = 0; i < 3; i++) set_number(a, linear[i], s.position[i], "%.4f", t);
    for (int i = 0; i < a->model.device.rotary_count; i++) {
        char id[8];
        snprintf(id, sizeof id, "%cpos", a->model.device.rotary[i]);
        set_number(a, id, s.rotary[a->model.device.rotary[i] - 'A'], "%.4f", t);
    }
    if (isfinite(s.position[0]) && isfinite(s.position[1]) && isfinite(s.position[2]))
        snprintf(text, sizeof text, "%.4f %.4f %.4f", s.position[0], s.position[1], s.position[2]);
    else
        snprintf(text, sizeof text, "UNAVAILABLE");
    set_value(a, "path_pos", text, t);
    set_number(a, "Srpm", s.spindle_rpm, "%.1f", t);
    set_number(a, "removed", s.removed_mm3, "%.3f", t);
    set_number(a, "stock_vol", s.stock_mm3, "%.3f", t);
    set_number(a, "progress", s.progress_percent, "%.2f", t);
    set_number(a, "uncertain", s.uncertain_voxels, "%.0f", t);
    int sys = mtc_model_find(&a->model, "system");
    const mtc_state *ss = &a->latest[sys];
    if (s.system_fault[0]) {
        if (!ss->active_count || strcmp(ss->active[0].value, s.system_fault))
            add_obs(a, sys, FM_MTC_FAULT, "job", s.system_fault, t);
    } else if (ss->active_count || ss->last.level != FM_MTC_NORMAL) {
        add_obs(a, sys, FM_MTC_NORMAL, NULL, NULL, t);
    }
    update_findings(a, &s, t);
    if (a->next != before) pthread_cond_broadcast(&a->changed);
    pthread_mutex_unlock(&a->lock);
    pthread_mutex_unlock(&a->update_lock);
}

static void *sampler_main(void *arg)
{
    fm_mtc_agent *a = arg;
    pthread_mutex_lock(&a->lock);
    while (!a->stopping) {
        pthread_mutex_unlock(&a->lock);
        fm_mtc_agent_update(a);
        pthread_mutex_lock(&a->lock);
        struct timespec until;
        fm_clock_deadline(&until, a->cfg.sample_ms / 1000.0);
        if (!a->stopping) pthread_cond_timedwait(&a->changed, &a->lock, &until);
    }
    pthread_mutex_unlock(&a->lock);
    return NULL;
}

fm_status fm_mtc_agent_new(const fm_mtc_config *cfg, const fm_mtc_service *svc, fm_mtc_agent **out,
                           fm_error *err)
{
    *out = NULL;
    if (cfg->buffer_size < 4 || cfg->buffer_size > (1u << 20))
        return fm_error_set(err, FM_ERR_INPUT, "the MTConnect buffer holds 4..1048576 observations, not %u",
                            cfg->buffer_size);
    if (cfg->device.rotary_count < 0 || cfg->device.rotary_count > FM_MTC_MAX_ROTARY)
        return fm_error_set(err, FM_ERR_INPUT, "at most %d rotary axes", FM_MTC_MAX_ROTARY);
    for (int i = 0; i < cfg->device.rotary_count; i++)
        if (cfg->device.rotary[i] < 'A' || cfg->device.rotary[i] > 'C')
            return fm_error_set(err, FM_ERR_INPUT, "rotary axes are A, B or C");
    fm_mtc_agent *a = calloc(1, sizeof *a);
    if (!a) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for the MTConnect agent");
    a->ring = calloc(cfg->buffer_size, sizeof *a->ring);
    if (!a->ring) {
        free(a);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for %u MTConnect observations",
                            cfg->buffer_size);
    }
    a->cfg = *cfg;
    a->cfg.device.name[sizeof a->cfg.device.name - 1] = '\0';
    a->cfg.device.uuid[sizeof a->cfg.device.uuid - 1] = '\0';
    clean_copy(a->cfg.device.name, sizeof a->cfg.device.name, a->cfg.device.name);
    clean_copy(a->cfg.device.uuid, sizeof a->cfg.device.uuid, a->cfg.device.uuid);
    clean_copy(a->cfg.sender, sizeof a->cfg.sender, cfg->sender);
    if (!a->cfg.instance_id) a->cfg.instance_id = (uint64_t)time(NULL);
    if (svc) a->svc = *svc;
    mtc_model_build(&a->model, &a->cfg.device);
    a->model_time = now_s();
    pthread_mutex_init(&a->update_lock, NULL);
    pthread_mutex_init(&a->lock, NULL);
    pthread_cond_init(&a->changed, NULL);
    a->first = a->next = 1;
    /* Every data item starts UNAVAILABLE (its first observation). */
    double t = now_s();
    for (int i = 0; i < a->model.item_count; i++) {
        a->at_first[i].last.level =
            a->model.items[i].category == MTC_CONDITION ? MTC_LEVEL_UNAVAILABLE : MTC_LEVEL_VALUE;
        if (a->model.items[i].category == MTC_CONDITION) {
            add_obs(a, i, MTC_LEVEL_UNAVAILABLE, NULL, NULL, t);
        } else {
            add_obs(a, i, MTC_LEVEL_VALUE, NULL, "UNAVAILABLE", t);
            snprintf(a->values[i], sizeof a->values[i], "UNAVAILABLE");
        }
    }
    fm_mtc_agent_update(a);
    if (cfg->sample_ms > 0) {
        if (pthread_create(&a->sampler, NULL, sampler_main, a) != 0) {
            fm_mtc_agent_free(a);
            return fm_error_set(err, FM_ERR_INTERNAL, "cannot start the MTConnect sampler thread");
        }
        a->sampler_started = 1;
    }
    *out = a;
    return FM_OK;
}

void fm_mtc_agent_free(fm_mtc_agent *a)
{
    if (!a) return;
    pthread_mutex_lock(&a->lock);
    a->stopping = 1;
    pthread_cond_broadcast(&a->changed);
    pthread_mutex_unlock(&a->lock);
    if (a->sampler_started) pthread_join(a->sampler, NULL);
    pthread_cond_destroy(&a->changed);
    pthread_mutex_destroy(&a->lock);
    pthread_mutex_destroy(&a->update_lock);
    free(a->ring);
    free(a);
}

void fm_mtc_agent_sequences(fm_mtc_agent *a, uint64_t *first, uint64_t *next)
{
    pthread_mutex_lock(&a->lock);
    *first = a->first;
    *next = a->next;
    pthread_mutex_unlock(&a->lock);
}

/* ---------------------------------------------------------- requests -- */

static void header_of(fm_mtc_agent *a, mtc_header *h)
{
    h->sender = a->cfg.sender;
    h->instance_id = a->cfg.instance_id;
    h->buffer_size = a->cfg.buffer_size;
    h->first = a->first;
    h->next = a->next;
    h->last = a->next - 1;
    h->model_time = a->model_time;
    h->asset_count = 0;
}

static fm_status reply_body(fm_mtc_reply *out, int status, char *body, size_t size, fm_error *err)
{
    if (!body) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for an MTConnect document");
    out->status = status;
    snprintf(out->content_type, sizeof out->content_type, "text/xml");
    out->body = body;
    out->size = size;
    return FM_OK;
}

static int status_of(const char *code);

static fm_status reply_error(fm_mtc_agent *a, fm_mtc_reply *out, const char *code,
                             const char *param, const char *uri, const char *message, fm_error *err)
{
    mtc_header h;
    pthread_mutex_lock(&a->lock);
    header_of(a, &h);
    pthread_mutex_unlock(&a->lock);
    size_t size = 0;
    char *body = mtc_write_error(&h, code, param, uri, message, &size);
    return reply_body(out, status_of(code), body, size, err);
}

static int status_of(const char *code)
{
    if (!strcmp(code, "NO_DEVICE") || !strcmp(code, "ASSET_NOT_FOUND")) return 404;
    if (!strcmp(code, "UNSUPPORTED")) return 406;
    return 400;
}

/* The current document (lock held); at: 0 for now, else the state at that
 * sequence. */
static char *write_current(fm_mtc_agent *a, const unsigned char *selected, uint64_t at, size_t *size)
{
    mtc_state *states = a->latest;
    mtc_state *rebuilt = NULL;
    if (at) {
        rebuilt = malloc(sizeof *rebuilt * MTC_MAX_ITEMS);
        if (!rebuilt) return NULL;
        memcpy(rebuilt, a->at_first, sizeof *rebuilt * MTC_MAX_ITEMS);
        for (uint64_t s = a->first; s <= at; s++) {
            const mtc_obs *o = &a->ring[s % a->cfg.buffer_size];
            mtc_state_apply(&rebuilt[o->item], o);
        }
        states = rebuilt;
    }
    const mtc_obs *list[MTC_MAX_ITEMS * (MTC_MAX_ACTIVE + 1)];
    size_t n = 0;
    for (int i = 0; i < a->model.item_count; i++) {
        if (selected && !selected[i]) continue;
        const mtc_state *s = &states[i];
        if (s->active_count) {
            for (int k = 0; k < s->active_count; k++) list[n++] = &s->active[k];
        } else if (s->last.seq) {
            list[n++] = &s->last;
        }
    }
    mtc_header h;
    header_of(a, &h);
    char *doc = mtc_write_streams(&a->model, &h, list, n, size);
    free(rebuilt);
    return doc;
}

/* The sample document from sequence from (lock held): up to count matching
 * observations; *next_out the sequence after the last one looked at. */
static char *write_sample(fm_mtc_agent *a, const unsigned char *selected, uint64_t from, long count,
                          int has_from, uint64_t *next_out, size_t *size)
{
    size_t cap = (size_t)(count < 0 ? -count : count);
    const mtc_obs **list = malloc(sizeof *list * (cap ? cap : 1));
    if (!list) return NULL;
    size_t n = 0;
    uint64_t next = from;
    if (count > 0) {
        uint64_t s = from;
        for (; s < a->next && n < cap; s++) {
            const mtc_obs *o = &a->ring[s % a->cfg.buffer_size];
            if (selected && !selected[o->item]) continue;
            list[n++] = o;
        }
        next = s;
    } else {
        /* Backwards from "from" (or the last), then given in order. */
        uint64_t s = has_from ? from : a->next - 1;
        if (s >= a->next) s = a->next - 1;
        next = s + 1;
        for (; s >= a->first && n < cap; s--) {
            const mtc_obs *o = &a->ring[s % a->cfg.buffer_size];
            if (!selected || selected[o->item]) list[n++] = o;
            if (s == a->first) break;
        }
        for (size_t i = 0; i < n / 2; i++) {
            const mtc_obs *tmp = list[i];
            list[i] = list[n - 1 - i];
            list[n - 1 - i] = tmp;
        }
    }
    mtc_header h;
    header_of(a, &h);
    h.next = next;
    *next_out = next;
    char *doc = mtc_write_streams(&a->model, &h, list, n, size);
    free(list);
    return doc;
}

static char *write_part(const char *boundary, const char *doc, size_t size, size_t *out_size)
{
    char head[160];
    int m = snprintf(head, sizeof head, "--%s\r\nContent-type: text/xml\r\nContent-length: %zu\r\n\r\n",
                     boundary, size);
    char *part = malloc((size_t)m + size + 3);
    if (!part) return NULL;
    memcpy(part, head, (size_t)m);
    memcpy(part + m, doc, size);
    memcpy(part + (size_t)m + size, "\r\n", 3);
    *out_size = (size_t)m + size + 2;
    return part;
}

fm_status fm_mtc_agent_request(fm_mtc_agent *a, const char *path, const char *query, fm_mtc_reply *out,
                               fm_error *err)
{
    memset(out, 0, sizeof *out);
    fm_error_clear(err);
    char uri[600];
    snprintf(uri, sizeof uri, "/%s%s%.400s", path ? path : "", query && query[0] ? "?" : "",
             query ? query : "");
    fm_mtc_query q;
    fm_error qerr;
    fm_error_clear(&qerr);
    if (fm_mtc_query_parse(query, query ? strlen(query) : 0, &q, &qerr) != FM_OK)
        return reply_error(a, out, qerr.reason, NULL, uri, qerr.message, err);
    /* The device's name may come first: NAME/current. */
    char req[128];
    snprintf(req, sizeof req, "%s", path ? path : "");
    const char *p = req;
    size_t nlen = strlen(a->model.device.name);
    if (!strncmp(p, a->model.device.name, nlen) && (p[nlen] == '/' || p[nlen] == '\0')) {
        p += nlen;
        if (*p == '/') p++;
    }
    if (!*p || !strcmp(p, "probe")) {
        mtc_header h;
        pthread_mutex_lock(&a->lock);
        header_of(a, &h);
        pthread_mutex_unlock(&a->lock);
        if (a->svc.tools) {
            fm_mtc_tool tools[FM_MTC_MAX_TOOLS];
            int n = a->svc.tools(a->svc.ctx, tools, FM_MTC_MAX_TOOLS);
            h.asset_count = n < 0 ? 0 : n > FM_MTC_MAX_TOOLS ? FM_MTC_MAX_TOOLS : n;
        }
        size_t size = 0;
        char *doc = mtc_write_probe(&a->model, &h, &size);
        return reply_body(out, 200, doc, size, err);
    }
    if (!strcmp(p, "assets") || !strncmp(p, "assets/", 7) || !strncmp(p, "asset/", 6)) {
        fm_mtc_tool tools[FM_MTC_MAX_TOOLS];
        int n = a->svc.tools ? a->svc.tools(a->svc.ctx, tools, FM_MTC_MAX_TOOLS) : 0;
        if (n < 0) n = 0;
        if (n > FM_MTC_MAX_TOOLS) n = FM_MTC_MAX_TOOLS;
        if (q.type[0] && strcmp(q.type, "CuttingTool")) n = 0;
        const char *id = strchr(p, '/');
        if (id) {
            id++;
            int found = -1;
            for (int i = 0; i < n; i++) {
                char name[32];
                snprintf(name, sizeof name, "T%d", tools[i].number);
                if (!strcmp(name, id)) found = i;
            }
            if (found < 0)
                return reply_error(a, out, "ASSET_NOT_FOUND", id, uri, "no asset with that id", err);
            tools[0] = tools[found];
            n = 1;
        } else if (q.has_count && q.count > 0 && q.count < n) {
            n = (int)q.count;
        }
        for (int i = 0; i < n; i++) {
            tools[i].description[sizeof tools[i].description - 1] = '\0';
            clean_copy(tools[i].description, sizeof tools[i].description, tools[i].description);
        }
        mtc_header h;
        pthread_mutex_lock(&a->lock);
        header_of(a, &h);
        pthread_mutex_unlock(&a->lock);
        h.asset_count = n;
        size_t size = 0;
        char *doc = mtc_write_assets(&a->model, &h, tools, n, now_s(), &size);
        return reply_body(out, 200, doc, size, err);
    }
    int current = !strcmp(p, "current"), sample = !strcmp(p, "sample");
    if (!current && !sample) {
        const char *slash = strchr(p, '/');
        if (slash && (!strcmp(slash, "/current") || !strcmp(slash, "/sample") || !strcmp(slash, "/probe")))
            return reply_error(a, out, "NO_DEVICE", NULL, uri,
                               "no such device; this agent has one device", err);
        return reply_error(a, out, "INVALID_URI", NULL, uri,
                           "the agent answers probe, current, sample, assets and asset/ID", err);
    }
    unsigned char selected[MTC_MAX_ITEMS];
    const unsigned char *sel = NULL;
    if (q.has_path) {
        fm_mtc_path xpath;
        fm_error perr;
        fm_error_clear(&perr);
        if (fm_mtc_path_parse(q.path, &xpath, &perr) != FM_OK ||
            mtc_model_select(&a->model, &xpath, selected, &perr) != 0)
            return reply_error(a, out, perr.reason, NULL, uri, perr.message, err);
        sel = selected;
    }
    if (current && q.has_from)
        return reply_error(a, out, "INVALID_REQUEST", NULL, uri, "current takes at, not from", err);
    if (sample && q.has_at)
        return reply_error(a, out, "INVALID_REQUEST", NULL, uri, "sample takes from, not at", err);
    long abs_count = q.count < 0 ? -q.count : q.count;
    if (!q.has_count && abs_count > (long)a->cfg.buffer_size) {
        q.count = (long)a->cfg.buffer_size; /* the default 100 of a smaller buffer */
    } else if (sample && abs_count > (long)a->cfg.buffer_size) {
        char m[128];
        snprintf(m, sizeof m, "count must be at most the buffer's %u", a->cfg.buffer_size);
        return reply_error(a, out, "OUT_OF_RANGE", "count", uri, m, err);
    }
    pthread_mutex_lock(&a->lock);
    uint64_t first = a->first, next = a->next;
    pthread_mutex_unlock(&a->lock);
    if (q.has_at && (q.at < first || q.at >= next)) {
        char m[160];
        snprintf(m, sizeof m, "at must be within %llu..%llu", (unsigned long long)first,
                 (unsigned long long)(next - 1));
        return reply_error(a, out, "QUERY_ERROR", NULL, uri, m, err); /* OutOfRange names no "at" */
    }
    if (q.has_from && (q.from < first || q.from > next)) {
        char m[160];
        snprintf(m, sizeof m, "from must be within %llu..%llu", (unsigned long long)first,
                 (unsigned long long)next);
        return reply_error(a, out, "OUT_OF_RANGE", "from", uri, m, err);
    }
    if (q.has_interval) {
        if (q.has_at)
            return reply_error(a, out, "INVALID_REQUEST", NULL, uri, "interval cannot be given with at", err);
        fm_mtc_stream *st = calloc(1, sizeof *st);
        if (!st) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for an MTConnect stream");
        st->agent = a;
        st->current = current;
        st->query = q;
        if (sel) memcpy(st->selected, selected, sizeof selected);
        else memset(st->selected, 1, sizeof st->selected);
        st->next = q.has_from ? q.from : next;
        if (sample && !q.has_from) st->next = next;
        st->last_sent = -1e9;
        snprintf(st->boundary, sizeof st->boundary, "frepmill%llx",
                 (unsigned long long)(a->cfg.instance_id * 2654435761u + next));
        out->status = 200;
        snprintf(out->content_type, sizeof out->content_type, "multipart/x-mixed-replace;boundary=%s",
                 st->boundary);
        out->stream = st;
        return FM_OK;
    }
    size_t size = 0;
    char *doc;
    pthread_mutex_lock(&a->lock);
    if (current) {
        doc = write_current(a, sel, q.has_at ? q.at : 0, &size);
    } else {
        uint64_t after;
        doc = write_sample(a, sel, q.has_from ? q.from : a->first, q.count, q.has_from, &after, &size);
    }
    pthread_mutex_unlock(&a->lock);
    return reply_body(out, 200, doc, size, err);
}

/* ------------------------------------------------------------ streams -- */

long fm_mtc_stream_read(fm_mtc_stream *st, char *buf, size_t max, int timeout_ms)
{
    fm_mtc_agent *a = st->agent;
    if (st->pending_off == st->pending_size) {
        free(st->pending);
        st->pending = NULL;
        st->pending_size = st->pending_off = 0;
        double wait_until = mono_s() + timeout_ms / 1000.0;
        pthread_mutex_lock(&a->lock);
        for (;;) {
            if (a->stopping) {
                pthread_mutex_unlock(&a->lock);
                return -1;
            }
            double now = mono_s();
            double since = now - st->last_sent;
            int due = 0;
            if (since * 1000.0 >= (double)st->query.interval_ms) {
                if (st->current) due = 1;
                else if (st->next < a->next) due = 1;
                else if (since * 1000.0 >= (double)st->query.heartbeat_ms) due = 1;
            }
            if (due) break;
            if (now >= wait_until) {
                pthread_mutex_unlock(&a->lock);
                return 0;
            }
            double until = wait_until;
            if (!st->current) {
                double hb = st->last_sent + st->query.heartbeat_ms / 1000.0;
                if (hb < until) until = hb;
            }
            double iv = st->last_sent + st->query.interval_ms / 1000.0;
            if (iv > now && iv < until) until = iv;
            if (until <= now) until = now + 0.001;
            struct timespec ts;
            fm_clock_deadline(&ts, until - now);
            pthread_cond_timedwait(&a->changed, &a->lock, &ts);
        }
        if (st->next < a->first) st->next = a->first; /* the stream fell behind the buffer */
        size_t size = 0;
        char *doc;
        if (st->current) {
            doc = write_current(a, st->selected, 0, &size);
        } else {
            uint64_t after;
            long count = st->query.count > 0 ? st->query.count : 100;
            doc = write_sample(a, st->selected, st->next, count, 1, &after, &size);
            st->next = after;
        }
        pthread_mutex_unlock(&a->lock);
        st->last_sent = mono_s();
        if (!doc) return -1;
        st->pending = write_part(st->boundary, doc, size, &st->pending_size);
        free(doc);
        if (!st->pending) return -1;
        st->pending_off = 0;
    }
    size_t n = st->pending_size - st->pending_off;
    if (n > max) n = max;
    memcpy(buf, st->pending + st->pending_off, n);
    st->pending_off += n;
    return (long)n;
}

void fm_mtc_stream_free(fm_mtc_stream *st)
{
    if (!st) return;
    free(st->pending);
    free(st);
}
