/* publish.c: what readers of a job see, published by the thread that owns
 * the job's stock (its worker, or a reader loading a finished job's
 * snapshot): the status snapshot, the event ring that server-sent events
 * read, and the chunk meshes (remeshed where the stock changed,
 * Draco-encoded). Readers copy under the job's lock and never touch a grid
 * being cut. */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "publish.h"
#include "http/http_server.h"
#include "log.h"
#include "store.h"

/* progress and block events at most this often (the status itself is
 * updated after every cut) */
#define FM_PUBLISH_EVENT_INTERVAL_S 0.2

/* ------------------------------------------------------------- events -- */

void fm_publish_event(job *j, const char *type, json_t *data)
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
    if (!j->doc->color_tool) return out;
    const fm_tool_table *tools = &j->doc->tools;
    for (size_t i = 0; i < tools->count; i++) {
        int number = tools->tools[i].number;
        uint8_t rgb[3];
        fm_mesh_tool_color(number, rgb);
        char hex[8];
        snprintf(hex, sizeof hex, "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
        json_array_append_new(out, json_pack("{s:i, s:s}", "tool", number, "color", hex));
    }
    return out;
}

/* Each tool of the job's table with its description as the table or the
 * library names it: [{"tool": N, "description": "..."}] ("" when none). */
static json_t *tools_json(const job *j)
{
    json_t *out = json_array();
    const fm_tool_table *tools = &j->doc->tools;
    for (size_t i = 0; i < tools->count; i++)
        json_array_append_new(out, json_pack("{s:i, s:s}", "tool", tools->tools[i].number,
                                             "description", tools->tools[i].comment));
    return out;
}

/* The rotary joints' keys in a status ("rotary": {"A": DEG, ...}). */
static const char *const rotary_names[3] = {"A", "B", "C"};

json_t *fm_publish_status_json(job *j)
{
    pthread_mutex_lock(&j->lock);
    const fm_job_view *v = &j->view;
    json_t *name = j->doc->name[0] ? json_string(j->doc->name) : NULL;
    json_t *out = json_pack(
        "{s:s, s:s, s:b, s:f, s:i, s:I, s:i, s:[f,f,f], s:f, s:f, s:f, s:f, s:I, s:I, s:o, "
        "s:O?, s:I, s:f, s:o?}",
        "id", j->id, "state", fm_job_state_name(j->state), "paused", j->paused, "progress",
        v->progress, "line", v->line, "block", (json_int_t)v->block, "tool", v->tool, "position",
        v->position[0], v->position[1], v->position[2], "program_time_s", v->program_time_s,
        "removed_volume_mm3", v->removed_mm3, "stock_volume_mm3", v->stock_mm3,
        "initial_volume_mm3", j->initial_mm3, "motions_done", (json_int_t)j->motions_done,
        "motions_total", (json_int_t)j->motions_total, "findings",
        j->findings ? json_incref(j->findings) : json_array(), "error", j->error,
        "mesh_version", (json_int_t)j->mesh_version, "created", j->created, "name", name);
    if (out) {
        json_object_set_new(out, "tool_colors", tool_colors_json(j));
        json_object_set_new(out, "tools", tools_json(j));
        /* the viewer asks for GET .../deviation once such a job is done */
        json_object_set_new(out, "design", json_boolean(j->doc->spec.design_path != NULL));
        json_object_set_new(out, "voxels_uncertain", json_integer((json_int_t)v->voxels_uncertain));
        /* program_time_s is the controller's time when the machine's
         * dynamics planned it (docs/api.md), the feed-only total beside */
        json_object_set_new(out, "program_time_planned", json_boolean(v->time_planned));
        json_object_set_new(out, "program_time_total_s", json_real(v->program_time_total_s));
        json_object_set_new(out, "feed_only_total_s", json_real(v->feed_only_total_s));
        if (j->live_note[0]) json_object_set_new(out, "live_source", json_string(j->live_note));
        json_t *rotary = json_object();
        for (int a = 0; a < 3; a++)
            if (v->rotary_known & (1 << a))
                json_object_set_new(rotary, rotary_names[a], json_real(v->rotary[a]));
        json_object_set_new(out, "rotary", rotary);
        json_object_set_new(out, "spindle_rpm", v->has_spindle ? json_real(v->spindle_rpm) : json_null());
        json_object_set_new(out, "uncertain_line", v->voxels_uncertain && v->uncertain_line > 0
                                                       ? json_integer(v->uncertain_line)
                                                       : json_null());
    }
    pthread_mutex_unlock(&j->lock);
    return out;
}

/* ------------------------------------------------------------- status -- */

void fm_publish_findings(job *j, json_t *findings)
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

void fm_publish_view_from_status(job *j, json_t *status)
{
    fm_job_view *v = &j->view;
    v->progress = json_real_value(json_object_get(status, "progress"));
    v->line = (int)json_integer_value(json_object_get(status, "line"));
    v->block = (long)json_integer_value(json_object_get(status, "block"));
    v->tool = (int)json_integer_value(json_object_get(status, "tool"));
    json_t *pos = json_object_get(status, "position");
    for (int a = 0; a < 3; a++) v->position[a] = json_number_value(json_array_get(pos, (size_t)a));
    json_t *rotary = json_object_get(status, "rotary");
    v->rotary_known = 0;
    for (int a = 0; a < 3; a++) {
        json_t *angle = json_object_get(rotary, rotary_names[a]);
        if (json_is_number(angle)) {
            v->rotary[a] = json_number_value(angle);
            v->rotary_known |= 1 << a;
        }
    }
    json_t *rpm = json_object_get(status, "spindle_rpm");
    v->has_spindle = json_is_number(rpm);
    v->spindle_rpm = json_number_value(rpm);
    v->program_time_s = json_number_value(json_object_get(status, "program_time_s"));
    v->program_time_total_s = json_number_value(json_object_get(status, "program_time_total_s"));
    v->time_planned = json_is_true(json_object_get(status, "program_time_planned"));
    v->feed_only_total_s = json_number_value(json_object_get(status, "feed_only_total_s"));
    v->removed_mm3 = json_number_value(json_object_get(status, "removed_volume_mm3"));
    v->stock_mm3 = json_number_value(json_object_get(status, "stock_volume_mm3"));
    j->initial_mm3 = json_number_value(json_object_get(status, "initial_volume_mm3"));
    j->motions_done = (long)json_integer_value(json_object_get(status, "motions_done"));
    j->motions_total = (long)json_integer_value(json_object_get(status, "motions_total"));
    v->voxels_uncertain = (size_t)json_integer_value(json_object_get(status, "voxels_uncertain"));
    v->uncertain_line = (int)json_integer_value(json_object_get(status, "uncertain_line"));
    json_t *findings = json_object_get(status, "findings");
    if (json_is_array(findings)) {
        fm_publish_findings(j, findings);
    }
    json_t *error = json_object_get(status, "error");
    if (json_is_object(error)) {
        j->error = json_incref(error);
        v->error_code = (int)json_integer_value(json_object_get(error, "status"));
    }
}

void fm_publish_progress(job *j, const fm_job_progress *p, publish_pace *pace)
{
    double now = fm_clock_monotonic_s();
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
    v->rotary_known = 0;
    for (int a = 0; a < 3; a++) {
        v->rotary[a] = isfinite(p->rotary[a]) ? p->rotary[a] : 0.0;
        if (isfinite(p->rotary[a])) v->rotary_known |= 1 << a;
    }
    v->has_spindle = isfinite(p->spindle_rpm);
    v->spindle_rpm = v->has_spindle ? p->spindle_rpm : 0.0;
    v->program_time_s = p->program_time;
    v->program_time_total_s = p->program_time_total;
    v->time_planned = p->time_planned;
    v->feed_only_total_s = p->feed_only_time_total;
    v->removed_mm3 = p->removed_mm3;
    v->stock_mm3 = j->initial_mm3 - p->removed_mm3;
    v->removal_rate_mm3_s = p->program_time > 0 ? p->removed_mm3 / p->program_time : 0;
    j->motions_done = p->motions_done;
    j->motions_total = p->motions_total;
    v->voxels_uncertain = p->voxels_uncertain;
    v->uncertain_line = p->uncertain_line;
    if (now - pace->last_event >= FM_PUBLISH_EVENT_INTERVAL_S) {
        pace->last_event = now;
        if (p->line != pace->last_line) {
            pace->last_line = p->line;
            fm_publish_event(j, "block", json_pack("{s:i, s:I}", "line", p->line, "block",
                                                   (json_int_t)p->block));
        }
        fm_publish_event(j, "progress",
                         json_pack("{s:f, s:i, s:I, s:i, s:[f,f,f], s:f, s:f}", "progress",
                                   v->progress, "line", v->line, "block", (json_int_t)v->block,
                                   "tool", v->tool, "position", v->position[0], v->position[1],
                                   v->position[2], "removed_volume_mm3", v->removed_mm3,
                                   "stock_volume_mm3", v->stock_mm3));
    }
    pthread_mutex_unlock(&j->lock);
}

/* ------------------------------------------------------------ meshes -- */

void fm_publish_chunks_drop_caches(job *j)
{
    fm_publish_chunks_settle(j);
    pthread_mutex_lock(&j->lock);
    for (size_t i = 0; i < j->chunk_count; i++) {
        fm_mesh_chunk_cache_free(j->chunks[i].cache);
        j->chunks[i].cache = NULL;
    }
    pthread_mutex_unlock(&j->lock);
}

/* What a version costs the history once it is no longer current. */
static size_t history_cost(const chunk_version *v)
{
    return sizeof *v + v->drc_size;
}

/* Keep the history under the job's bound (caller holds j->lock): drop the
 * earlier version that stopped being valid first, over all chunks, so the
 * history stays complete from as early a time as it can. history_from_s
 * becomes the time that version stopped being valid: before it, that
 * chunk's mesh is gone. */
static void history_trim(job *j, size_t limit)
{
    while (j->history_bytes > limit) {
        job_chunk *oldest = NULL;
        for (size_t i = 0; i < j->chunk_count; i++) {
            job_chunk *c = &j->chunks[i];
            if (c->version_count < 2) continue;
            if (!oldest || c->versions[1].time_s < oldest->versions[1].time_s) oldest = c;
        }
        if (!oldest) break;
        size_t cost = history_cost(&oldest->versions[0]);
        j->history_bytes = j->history_bytes > cost ? j->history_bytes - cost : 0;
        if (oldest->versions[1].time_s > j->history_from_s)
            j->history_from_s = oldest->versions[1].time_s;
        free(oldest->versions[0].drc);
        memmove(oldest->versions, oldest->versions + 1,
                (oldest->version_count - 1) * sizeof *oldest->versions);
        oldest->version_count--;
    }
}

/* A remeshed chunk's new version appended (caller holds j->lock); its mesh
 * becomes the current one. On failure (out of memory) nothing changes and
 * the caller frees what it made. */
static int chunk_add_version(job *j, job_chunk *c, const chunk_version *v, fm_mesh *mesh)
{
    if (c->version_count == c->version_cap) {
        size_t ncap = c->version_cap ? c->version_cap * 2 : 4;
        chunk_version *t = realloc(c->versions, ncap * sizeof *t);
        if (!t) return -1;
        c->versions = t;
        c->version_cap = ncap;
    }
    if (c->version_count) j->history_bytes += history_cost(&c->versions[c->version_count - 1]);
    c->versions[c->version_count++] = *v;
    fm_mesh_free(c->mesh);
    c->mesh = mesh;
    return 0;
}

/* The chunks of one publication, remeshed and encoded by this thread and
 * one helper, each taking the next chunk not yet taken. */
typedef struct remesh_share {
    double mesh_s, encode_s; /* wall time in the mesher and in Draco */
    size_t triangles;
} remesh_share;

typedef struct remesh_work {
    fm_stock *stock;
    const fm_mesh_extract_options *opt;
    const fm_mesh_draco_options *draco;
    const fm_stock_chunk *changed;
    job_chunk *fresh;
    chunk_version *fresh_v;
    size_t n;
    uint64_t version;
    double time_s;
    int encode; /* 0: the encoder thread encodes after the event */
    atomic_size_t next;
    remesh_share helper;
} remesh_work;

static void remesh_chunks(remesh_work *w, remesh_share *share)
{
    for (;;) {
        const size_t i = atomic_fetch_add(&w->next, 1);
        if (i >= w->n) return;
        job_chunk *c = &w->fresh[i];
        chunk_version *v = &w->fresh_v[i];
        memcpy(c->index, w->changed[i].index, sizeof c->index);
        memcpy(c->lo, w->changed[i].lo, sizeof c->lo);
        memcpy(c->hi, w->changed[i].hi, sizeof c->hi);
        v->version = w->version;
        v->time_s = w->time_s;
        fm_error err;
        const double tm = fm_clock_monotonic_s();
        c->mesh = fm_mesh_from_stock_chunk_cached(w->stock, c->index, w->opt, c->cache, &err);
        share->mesh_s += fm_clock_monotonic_s() - tm;
        v->triangles = c->mesh ? c->mesh->triangle_count : 0;
        share->triangles += v->triangles;
        if (!w->encode) {
            v->encoding = v->triangles > 0;
            continue;
        }
        const double te = fm_clock_monotonic_s();
        if (v->triangles > 0 &&
            fm_mesh_encode_draco(c->mesh, w->draco, &v->drc, &v->drc_size, &err) != FM_OK) {
            v->drc = NULL;
            v->drc_size = 0;
        }
        share->encode_s += fm_clock_monotonic_s() - te;
    }
}

static void *remesh_helper(void *arg)
{
    remesh_work *w = arg;
    remesh_chunks(w, &w->helper);
    return NULL;
}

/* ----------------------------------------------- encoding after the event -- */

/* A live job's publication is announced as soon as its chunks are meshed:
 * Draco (about half of a move's publication) runs after the event, on the
 * encoder thread and one helper, while the worker takes the next position.
 * The meshes it encodes are the chunks' current ones, which stay alive
 * until the next publication swaps in its own, and that first waits for
 * the encoder (fm_publish_chunks_settle). Readers of the bytes (the chunk
 * list's sizes, a chunk's .drc) wait until they exist. */
typedef struct encode_item {
    int32_t index[3];
    uint64_t version;
    const fm_mesh *mesh;
    uint8_t *drc;
    size_t drc_size;
} encode_item;

typedef struct encode_work {
    job *j;
    fm_mesh_draco_options draco;
    encode_item *items;
    size_t n;
    atomic_size_t next;
    double started;
} encode_work;

static void encode_items(encode_work *w)
{
    for (;;) {
        const size_t i = atomic_fetch_add(&w->next, 1);
        if (i >= w->n) return;
        fm_error err;
        encode_item *it = &w->items[i];
        if (fm_mesh_encode_draco(it->mesh, &w->draco, &it->drc, &it->drc_size, &err) != FM_OK) {
            it->drc = NULL;
            it->drc_size = 0;
        }
    }
}

static void *encode_helper(void *arg)
{
    encode_items(arg);
    return NULL;
}

/* The encoder: every item encoded (on two threads when there are two),
 * then the bytes put in their versions under the job's lock and the
 * waiting readers woken. */
static void *encoder_main(void *arg)
{
    encode_work *w = arg;
    job *j = w->j;
    const double cpu0 = fm_clock_cpu_s();
    pthread_t helper;
    int helped = w->n >= 2 && pthread_create(&helper, NULL, encode_helper, w) == 0;
    encode_items(w);
    if (helped) pthread_join(helper, NULL);
    size_t bytes = 0;
    pthread_mutex_lock(&j->lock);
    for (size_t i = 0; i < w->n; i++) {
        encode_item *it = &w->items[i];
        chunk_version *v = NULL;
        for (size_t k = 0; !v && k < j->chunk_count; k++) {
            job_chunk *c = &j->chunks[k];
            if (memcmp(c->index, it->index, sizeof it->index) || !c->version_count) continue;
            chunk_version *cur = &c->versions[c->version_count - 1];
            if (cur->version == it->version && cur->encoding) v = cur;
        }
        if (!v) { /* cannot happen: the current version stays until the next publication */
            free(it->drc);
            continue;
        }
        v->drc = it->drc;
        v->drc_size = it->drc_size;
        v->encoding = 0;
        bytes += it->drc_size;
    }
    j->encoding_pending = 0;
    pthread_cond_broadcast(&j->cond);
    pthread_mutex_unlock(&j->lock);
    fm_log(FM_LOG_DEBUG,
           "job %s: encoded %zu chunks (%zu bytes) %.1f ms after their event, %.1f ms daemon CPU "
           "meanwhile",
           j->id, w->n, bytes, (fm_clock_monotonic_s() - w->started) * 1e3,
           (fm_clock_cpu_s() - cpu0) * 1e3);
    free(w->items);
    free(w);
    return NULL;
}

void fm_publish_chunks_settle(job *j)
{
    if (!j->encoder_started) return;
    pthread_join(j->encoder, NULL);
    j->encoder_started = 0;
}

/* The encoder's work for up to count versions (filled as they are swapped
 * in); NULL without memory. */
static encode_work *encode_work_new(job *j, const fm_mesh_draco_options *draco, size_t count)
{
    encode_work *w = calloc(1, sizeof *w);
    encode_item *items = calloc(count ? count : 1, sizeof *items);
    if (!w || !items) {
        free(w);
        free(items);
        return NULL;
    }
    *w = (encode_work){.j = j, .draco = *draco, .items = items};
    return w;
}

/* Encode now, on this thread, what was to be encoded after the event (no
 * memory for the encoder's work). */
static void encode_fresh_now(const fm_mesh_draco_options *draco, const job_chunk *fresh,
                             chunk_version *fresh_v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        chunk_version *v = &fresh_v[i];
        fm_error err;
        if (v->encoding &&
            fm_mesh_encode_draco(fresh[i].mesh, draco, &v->drc, &v->drc_size, &err) != FM_OK) {
            v->drc = NULL;
            v->drc_size = 0;
        }
        v->encoding = 0;
    }
}

/* The same vertices (positions, normals, colours) and triangles; a chunk
 * with no surface has a mesh of no triangles (or none, when its meshing
 * failed: never equal). */
static int mesh_equal(const fm_mesh *a, const fm_mesh *b)
{
    if (!a || !b || a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count ||
        !a->normals != !b->normals || !a->colors != !b->colors)
        return 0;
    const size_t nv = a->vertex_count, nt = a->triangle_count;
    return (!nv || !memcmp(a->positions, b->positions, 3 * nv * sizeof *a->positions)) &&
           (!nv || !a->normals || !memcmp(a->normals, b->normals, 3 * nv * sizeof *a->normals)) &&
           (!nv || !a->colors || !memcmp(a->colors, b->colors, 3 * nv * sizeof *a->colors)) &&
           (!nt || !memcmp(a->triangles, b->triangles, 3 * nt * sizeof *a->triangles));
}

/* A live move's chunks, the one at the tool first: it remeshes most of its
 * leaves (150-250 of 512 on bench_live's rows, 6-8 ms under load; the
 * chunks beside it a few, 1-3 ms), and the two threads take chunks in
 * order, so taken last it would finish alone after the others. */
typedef struct chunk_order {
    double distance;
    size_t index;
} chunk_order;

static int cmp_chunk_order(const void *a, const void *b)
{
    const chunk_order *x = a, *y = b;
    return x->distance < y->distance ? -1 : x->distance > y->distance ? 1
           : x->index < y->index     ? -1
                                     : x->index > y->index;
}

static void nearest_first(fm_stock_chunk *chunks, size_t n, const double tool[3])
{
    chunk_order *order = n > 1 ? malloc(n * sizeof *order) : NULL;
    fm_stock_chunk *sorted = order ? malloc(n * sizeof *sorted) : NULL;
    if (!sorted) { /* one chunk, or no memory: the order is only speed */
        free(order);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            const double out = fmax(chunks[i].lo[k] - tool[k], tool[k] - chunks[i].hi[k]);
            if (out > 0) d2 += out * out;
        }
        order[i] = (chunk_order){d2, i};
    }
    qsort(order, n, sizeof *order, cmp_chunk_order);
    for (size_t i = 0; i < n; i++) sorted[i] = chunks[order[i].index];
    memcpy(chunks, sorted, n * sizeof *chunks);
    free(sorted);
    free(order);
}

/* Remesh the chunks that changed since the last publication and swap them
 * in. Runs on the worker's thread (or a reader's, for a finished job whose
 * stock was loaded from its snapshot) with exclusive use of stock. With
 * cache, each chunk keeps its faces per leaf (fm_mesh_chunk_cache) and the
 * next publication remeshes only the leaves that changed and their
 * neighbours: a live move changes about a fifth of a chunk's leaves. */
static void publish_chunks(job *j, fm_stock *stock, double program_time_s, int cache)
{
    /* The previous publication's encoding is left running while this one
     * finds and meshes its chunks (new meshes): it ends before they are
     * swapped in (fm_publish_chunks_settle below). */
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
    if (cache) {
        pthread_mutex_lock(&j->lock);
        double tool[3];
        memcpy(tool, j->view.position, sizeof tool);
        pthread_mutex_unlock(&j->lock);
        nearest_first(changed, n, tool);
    }
    fm_mesh_extract_options opt;
    fm_mesh_extract_default(&opt);
    opt.coloring = j->doc->color_tool ? FM_MESH_COLOR_TOOL : FM_MESH_COLOR_NONE;
    job_chunk *fresh = calloc(n ? n : 1, sizeof *fresh);
    chunk_version *fresh_v = calloc(n ? n : 1, sizeof *fresh_v);
    if (!fresh || !fresh_v) {
        free(fresh);
        free(fresh_v);
        free(changed);
        return;
    }
    /* Each changed chunk's cache moves to its fresh copy while it is
     * remeshed, and back when the new version is swapped in. */
    if (cache) {
        pthread_mutex_lock(&j->lock);
        for (size_t i = 0; i < n; i++) {
            for (size_t k = 0; k < j->chunk_count; k++)
                if (!memcmp(j->chunks[k].index, changed[i].index, sizeof changed[i].index)) {
                    fresh[i].cache = j->chunks[k].cache;
                    j->chunks[k].cache = NULL;
                    break;
                }
        }
        pthread_mutex_unlock(&j->lock);
        for (size_t i = 0; i < n; i++)
            if (!fresh[i].cache) fresh[i].cache = fm_mesh_chunk_cache_new();
    }
    const double t0 = fm_clock_monotonic_s(), cpu0 = fm_clock_cpu_s();
    /* Draco speed 7 instead of the default 5: on the live bench's chunks
     * (bench_remesh --speed 7) 30-40 % less encoding time, and the files
     * came out 0.4 % smaller, not larger. */
    fm_mesh_draco_options draco;
    fm_mesh_draco_default(&draco);
    draco.speed = 7;
    /* A live job (cache) announces its meshes before encoding them. */
    remesh_work w = {stock, &opt, &draco, changed, fresh, fresh_v, n, version, program_time_s,
                     !cache, 0, {0, 0, 0}};
    /* One helper thread beside this one when there are chunks to share: the
     * chunks are independent (each reads the stock, which nothing changes
     * meanwhile), and a live move's 2-4 chunks then take about half the
     * wall time on two cores. */
    pthread_t helper;
    int helped = n >= 2 && pthread_create(&helper, NULL, remesh_helper, &w) == 0;
    remesh_share share = {0, 0, 0};
    remesh_chunks(&w, &share);
    if (helped) pthread_join(helper, NULL);
    const double t_mesh = share.mesh_s + w.helper.mesh_s;
    const double t_encode = share.encode_s + w.helper.encode_s;
    const size_t triangles = share.triangles + w.helper.triangles;
    free(changed);
    size_t to_encode = 0;
    for (size_t i = 0; i < n; i++) to_encode += fresh_v[i].encoding;
    encode_work *enc = to_encode ? encode_work_new(j, &draco, to_encode) : NULL;
    if (to_encode && !enc) encode_fresh_now(&draco, fresh, fresh_v, n);
    const double t_settle = fm_clock_monotonic_s();
    fm_publish_chunks_settle(j);
    const double settle_s = fm_clock_monotonic_s() - t_settle;
    fm_log(FM_LOG_DEBUG,
           "job %s: published %zu chunks (%zu triangles) at version %llu in %.1f ms on %d "
           "threads: mesh %.1f ms, encode %.1f ms wall (summed over the threads), %.1f ms "
           "daemon CPU; %.1f ms waiting for the previous encoding",
           j->id, n, triangles, (unsigned long long)version, (fm_clock_monotonic_s() - t0) * 1e3,
           helped ? 2 : 1, t_mesh * 1e3, t_encode * 1e3, (fm_clock_cpu_s() - cpu0) * 1e3,
           settle_s * 1e3);
    json_t *ids = json_array();
    size_t kept = 0;
    pthread_mutex_lock(&j->lock);
    if (j->history_from_s < 0) j->history_from_s = program_time_s;
    for (size_t i = 0; i < n; i++) {
        job_chunk *c = &fresh[i];
        char name[48];
        snprintf(name, sizeof name, "%d_%d_%d", c->index[0], c->index[1], c->index[2]);
        size_t k = 0;
        while (k < j->chunk_count && memcmp(j->chunks[k].index, c->index, sizeof c->index)) k++;
        /* A chunk the stock marked (a leaf the cut touched lies within two
         * voxels of it) whose mesh came out as its current one: the change
         * reached none of its faces (the chunks along a seam the move runs
         * beside, a chunk above the stock's top with no faces). It keeps
         * that version: no encoding, nothing for clients to fetch again. */
        if (cache && c->mesh && k < j->chunk_count && j->chunks[k].version_count &&
            !j->chunks[k].cache && mesh_equal(c->mesh, j->chunks[k].mesh)) {
            fm_mesh_free(c->mesh);
            j->chunks[k].cache = c->cache;
            kept++;
            continue;
        }
        if (k == j->chunk_count && j->chunk_count == j->chunk_cap) {
            size_t ncap = j->chunk_cap ? j->chunk_cap * 2 : 64;
            job_chunk *t = realloc(j->chunks, ncap * sizeof *t);
            if (!t) {
                fm_mesh_free(c->mesh);
                fm_mesh_chunk_cache_free(c->cache);
                free(fresh_v[i].drc);
                continue;
            }
            j->chunks = t;
            j->chunk_cap = ncap;
        }
        if (k == j->chunk_count) {
            j->chunks[k] = (job_chunk){0};
            memcpy(j->chunks[k].index, c->index, sizeof c->index);
            memcpy(j->chunks[k].lo, c->lo, sizeof c->lo);
            memcpy(j->chunks[k].hi, c->hi, sizeof c->hi);
            j->chunk_count++;
        }
        if (chunk_add_version(j, &j->chunks[k], &fresh_v[i], c->mesh) != 0) {
            if (!j->chunks[k].version_count) j->chunk_count--; /* the one just added */
            fm_mesh_free(c->mesh);
            fm_mesh_chunk_cache_free(c->cache);
            free(fresh_v[i].drc);
            continue;
        }
        fm_mesh_chunk_cache_free(j->chunks[k].cache); /* none: it was moved out above */
        j->chunks[k].cache = c->cache;
        json_array_append_new(ids, json_string(name));
        if (enc && fresh_v[i].encoding) {
            encode_item *it = &enc->items[enc->n++];
            memcpy(it->index, c->index, sizeof it->index);
            it->version = version;
            it->mesh = c->mesh;
        }
    }
    if (enc) j->encoding_pending = enc->n;
    history_trim(j, j->history_limit);
    j->mesh_version = version;
    j->mesh_time_s = program_time_s;
    fm_publish_event(j, "chunks", json_pack("{s:I, s:f, s:o}", "version", (json_int_t)version,
                                            "program_time_s", program_time_s, "changed", ids));
    pthread_mutex_unlock(&j->lock);
    if (kept)
        fm_log(FM_LOG_DEBUG, "job %s: version %llu kept %zu marked chunks whose meshes did not change",
               j->id, (unsigned long long)version, kept);
    if (enc) {
        enc->started = fm_clock_monotonic_s();
        if (pthread_create(&j->encoder, NULL, encoder_main, enc) == 0)
            j->encoder_started = 1;
        else
            encoder_main(enc); /* no thread: encoded here, as before */
    }
    free(fresh);
    free(fresh_v);
}

/* Only live jobs keep the caches: there the operator waits for each move's
 * meshes, and a live stock is the HMI's one part. A G-code job publishes
 * every publish_interval_s, its wait is not a person's, and on a large stock
 * the caches would about double the meshes' memory (a chunk's faces again,
 * plus 116 kB of leaf hashes per chunk). */
void fm_publish_chunks(job *j, fm_stock *stock, double program_time_s)
{
    publish_chunks(j, stock, program_time_s, j->doc->spec.program_kind == FM_PROGRAM_LIVE);
}

fm_status fm_publish_ensure_meshes(job *j, fm_error *err)
{
    pthread_mutex_lock(&j->lock);
    int ready = j->meshes_loaded || j->state < FM_JOB_DONE;
    pthread_mutex_unlock(&j->lock);
    if (ready) return FM_OK;
    pthread_mutex_lock(&j->load_lock);
    pthread_mutex_lock(&j->lock);
    ready = j->meshes_loaded;
    pthread_mutex_unlock(&j->lock);
    fm_status rc = FM_OK;
    if (!ready) {
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/stock.vdb", j->dir);
        fm_stock_options opt;
        fm_stock_options_default(&opt);
        fm_error ferr;
        fm_stock *stock = access(path, R_OK) == 0 ? fm_stock_load_vdb(path, &opt, &ferr) : NULL;
        if (!stock) {
            rc = fm_error_set_reason(err, FM_ERR_INPUT, "no_mesh",
                                     "job %s has no stored stock to mesh", j->id);
        } else {
            /* the history starts here: the earlier meshes died with the
             * daemon that made them */
            pthread_mutex_lock(&j->lock);
            double t = j->view.program_time_s;
            pthread_mutex_unlock(&j->lock);
            publish_chunks(j, stock, t, 0); /* done: no more changes to remesh */
            fm_stock_free(stock);
            pthread_mutex_lock(&j->lock);
            j->meshes_loaded = 1;
            pthread_mutex_unlock(&j->lock);
        }
    }
    pthread_mutex_unlock(&j->load_lock);
    return rc;
}

/* --------------------------------------------------------- whole view -- */

/* The finished stock as one mesh for the viewer (GET /v1/jobs/{id}/stock.drc):
 * meshed once from stock.vdb with OpenVDB's adaptivity, which merges the
 * cells of flat faces into larger polygons (the demo's 4.83 M triangles in
 * 717 chunks become one mesh of far fewer; docs/daemon.md gives the figures
 * and the deviation), and kept as stock.drc beside the job's other files:
 * every later request, and a restarted daemon, serves the file. Running
 * jobs and replays keep the chunk meshes (their seams need adaptivity 0). */
fm_status fm_publish_stock_mesh(job *j, char *path, size_t size, fm_error *err)
{
    pthread_mutex_lock(&j->lock);
    int done = j->state == FM_JOB_DONE;
    pthread_mutex_unlock(&j->lock);
    if (!done)
        return fm_error_set_reason(err, FM_ERR_INPUT, "not_finished",
                                   "job %s is not done; its whole stock mesh exists once it is", j->id);
    fm_job_file_path(j, "stock.drc", path, size);
    pthread_mutex_lock(&j->load_lock);
    fm_status st = FM_OK;
    if (access(path, R_OK) != 0) {
        char vdb[PATH_MAX];
        fm_job_file_path(j, "stock.vdb", vdb, sizeof vdb);
        fm_stock_options sopt;
        fm_stock_options_default(&sopt);
        fm_error ferr;
        fm_error_clear(&ferr);
        fm_stock *stock = access(vdb, R_OK) == 0 ? fm_stock_load_vdb(vdb, &sopt, &ferr) : NULL;
        fm_mesh *mesh = NULL;
        if (stock) {
            fm_mesh_extract_options opt;
            fm_mesh_extract_default(&opt);
            opt.adaptivity = FM_PUBLISH_VIEW_ADAPTIVITY;
            opt.coloring = j->doc->color_tool ? FM_MESH_COLOR_TOOL : FM_MESH_COLOR_NONE;
            mesh = fm_mesh_from_stock(stock, &opt, &ferr);
            fm_stock_free(stock);
        }
        uint8_t *drc = NULL;
        size_t drc_size = 0;
        if (!mesh || !mesh->triangle_count)
            st = fm_error_set_reason(err, FM_ERR_INPUT, "no_mesh", "job %s has no stock to mesh%s%s",
                                     j->id, ferr.message[0] ? ": " : "", ferr.message);
        else if ((st = fm_mesh_encode_draco(mesh, NULL, &drc, &drc_size, err)) == FM_OK)
            st = fm_store_write_atomic(j->dir, "stock.drc", drc, drc_size, err);
        free(drc);
        fm_mesh_free(mesh);
    }
    pthread_mutex_unlock(&j->load_lock);
    return st;
}

/* ---------------------------------------------------------- deviation -- */

/* The viewer's deviation mode (docs/api.md, GET /v1/jobs/{id}/deviation):
 * the finished stock's whole mesh coloured by its deviation from the
 * design (lib/mesh's FM_MESH_COLOR_DEVIATION, the colours of frepmill
 * simulate --color deviation) and its key in mm, written once beside the
 * job's other files: the design's level set is gone after the job, and a
 * restarted daemon serves the files as they are. */
fm_status fm_publish_deviation(job *j, fm_stock *stock, const fm_design *design,
                               const fm_deviation *dev, fm_error *err)
{
    fm_mesh_extract_options opt;
    fm_mesh_extract_default(&opt);
    opt.coloring = FM_MESH_COLOR_DEVIATION;
    opt.design = design;
    const double tol = fm_design_tolerance(design);
    const double range = 10 * tol; /* the mesh's default span (mesh.h) */
    fm_mesh *mesh = fm_mesh_from_stock(stock, &opt, err);
    if (!mesh) return err->code;
    uint8_t *drc = NULL;
    size_t drc_size = 0;
    fm_status st = mesh->triangle_count
                       ? fm_mesh_encode_draco(mesh, NULL, &drc, &drc_size, err)
                       : fm_error_set(err, FM_ERR_INPUT, "the stock has no surface to colour");
    size_t triangles = mesh->triangle_count;
    fm_mesh_free(mesh);
    if (st == FM_OK) st = fm_store_write_atomic(j->dir, "deviation.drc", drc, drc_size, err);
    free(drc);
    if (st != FM_OK) return st;
    fm_render_legend legend;
    fm_mesh_deviation_legend(tol, range, &legend);
    json_t *keys = json_array();
    for (size_t i = 0; i < legend.count; i++) {
        char hex[8];
        snprintf(hex, sizeof hex, "#%02x%02x%02x", legend.colors[i][0], legend.colors[i][1],
                 legend.colors[i][2]);
        json_array_append_new(keys, json_pack("{s:s, s:s}", "label", legend.labels[i], "color", hex));
    }
    json_t *doc = json_pack("{s:s, s:s, s:f, s:f, s:o, s:I, s:f, s:f, s:I, s:I}", "id", j->id, "mesh",
                            "deviation.drc", "tolerance_mm", tol, "range_mm", range, "legend", keys,
                            "triangles", (json_int_t)triangles, "max_gouge_mm", dev->max_gouge_mm,
                            "max_excess_mm", dev->max_excess_mm, "gouge_regions",
                            (json_int_t)dev->gouge_total, "excess_regions",
                            (json_int_t)dev->excess_total);
    char *text = doc ? json_dumps(doc, JSON_COMPACT | JSON_REAL_PRECISION(10)) : NULL;
    json_decref(doc);
    if (!text) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for the deviation's key");
    st = fm_store_write_atomic(j->dir, "deviation.json", text, strlen(text), err);
    free(text);
    return st;
}

/* ------------------------------------------------------------ readers -- */

fm_status fm_publish_report_json(job *j, json_t **out, fm_error *err)
{
    pthread_mutex_lock(&j->lock);
    fm_status rc = FM_OK;
    if (j->report) {
        *out = json_deep_copy(j->report);
        json_object_set_new(*out, "id", json_string(j->id));
        json_object_set_new(*out, "state", json_string(fm_job_state_name(j->state)));
    } else if (j->state == FM_JOB_FAILED) {
        *out = json_pack("{s:s, s:s, s:O?}", "id", j->id, "state", "failed", "error", j->error);
    } else {
        rc = fm_error_set_reason(err, FM_ERR_INPUT, "not_finished",
                                 "job %s is %s; its report exists once it is done", j->id,
                                 fm_job_state_name(j->state));
    }
    pthread_mutex_unlock(&j->lock);
    return rc;
}

/* Readers of Draco bytes (sizes, files) wait for the encoding of a live
 * job's last publication, announced before it (caller holds j->lock).
 * Returns how long they waited (s), 0 when the bytes were there. */
static double wait_encoded(job *j)
{
    if (!j->encoding_pending) return 0;
    const double t0 = fm_clock_monotonic_s();
    while (j->encoding_pending) pthread_cond_wait(&j->cond, &j->lock);
    return fm_clock_monotonic_s() - t0;
}

static void log_wait(const job *j, const char *what, double waited_s)
{
    if (waited_s > 0)
        fm_log(FM_LOG_DEBUG, "job %s: %s waited %.1f ms for its meshes' Draco bytes", j->id, what,
               waited_s * 1e3);
}

static void chunk_name(const job_chunk *c, char *out, size_t size)
{
    snprintf(out, size, "%d_%d_%d", c->index[0], c->index[1], c->index[2]);
}

/* The version of c that showed it at program time at_s (the last one
 * published at or before it), or NULL if it was first published later. */
static const chunk_version *version_at(const job_chunk *c, double at_s)
{
    const chunk_version *found = NULL;
    for (size_t v = 0; v < c->version_count && c->versions[v].time_s <= at_s + 1e-9; v++)
        found = &c->versions[v];
    return found;
}

static json_t *chunk_json(const job_chunk *c, const chunk_version *v)
{
    char name[48];
    chunk_name(c, name, sizeof name);
    return json_pack("{s:s, s:[i,i,i], s:I, s:f, s:I, s:I, s:[f,f,f], s:[f,f,f]}", "id", name,
                     "index", c->index[0], c->index[1], c->index[2], "version",
                     (json_int_t)v->version, "time_s", v->time_s, "triangles",
                     (json_int_t)v->triangles, "bytes", (json_int_t)v->drc_size, "lo", c->lo[0],
                     c->lo[1], c->lo[2], "hi", c->hi[0], c->hi[1], c->hi[2]);
}

fm_status fm_publish_chunk_list(job *j, uint64_t since, double at_s, json_t **out,
                                fm_error *err)
{
    fm_status rc;
    json_t *list = json_array();
    pthread_mutex_lock(&j->lock);
    const double waited = wait_encoded(j);
    if (at_s >= 0 && (j->history_from_s < 0 || at_s < j->history_from_s - 1e-9)) {
        rc = j->history_from_s < 0
                 ? fm_error_set_reason(err, FM_ERR_INPUT, "no_mesh",
                                       "job %s has published no mesh yet", j->id)
                 : fm_error_set_reason(
                       err, FM_ERR_INPUT, "history_dropped",
                       "job %s: the meshes before program time %.3f s are not kept (the daemon "
                       "keeps %.3g MB of mesh history per job; an uncut stock of more than a million "
                       "triangles is first published after its first cuts; or it was restarted since)",
                       j->id, j->history_from_s, (double)j->history_limit / 1048576.0);
        pthread_mutex_unlock(&j->lock);
        json_decref(list);
        return rc;
    }
    uint64_t newest = 0;
    for (size_t i = 0; i < j->chunk_count; i++) {
        const job_chunk *c = &j->chunks[i];
        const chunk_version *v = at_s >= 0 ? version_at(c, at_s) : job_chunk_current(c);
        if (!v || (at_s < 0 && v->version <= since)) continue;
        if (v->version > newest) newest = v->version;
        json_array_append_new(list, chunk_json(c, v));
    }
    *out = json_pack("{s:s, s:I, s:f, s:f, s:I, s:I, s:o}", "id", j->id, "version",
                     (json_int_t)(at_s >= 0 ? newest : j->mesh_version), "program_time_s",
                     j->mesh_time_s, "history_from_s", j->history_from_s, "history_bytes",
                     (json_int_t)j->history_bytes, "since", (json_int_t)since, "chunks", list);
    if (*out && at_s >= 0) json_object_set_new(*out, "at", json_real(at_s));
    pthread_mutex_unlock(&j->lock);
    log_wait(j, "a chunk list", waited);
    return *out ? FM_OK
                : fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
}

fm_status fm_publish_chunk_bytes(job *j, const char *name, uint64_t version, uint8_t **data,
                                 size_t *size, fm_error *err)
{
    fm_status rc = fm_error_set_reason(err, FM_ERR_INPUT, "not_found", "job %s has no chunk %.64s",
                                       j->id, name);
    pthread_mutex_lock(&j->lock);
    const double waited = wait_encoded(j);
    for (size_t i = 0; i < j->chunk_count; i++) {
        char n[48];
        chunk_name(&j->chunks[i], n, sizeof n);
        if (strcmp(n, name) != 0) continue;
        const job_chunk *c = &j->chunks[i];
        const chunk_version *v = version ? NULL : job_chunk_current(c);
        for (size_t k = 0; !v && k < c->version_count; k++)
            if (c->versions[k].version == version) v = &c->versions[k];
        if (!v) {
            rc = version < c->versions[0].version
                     ? fm_error_set_reason(err, FM_ERR_INPUT, "history_dropped",
                                           "version %llu of chunk %s is no longer kept (mesh "
                                           "history bound); list the chunks again",
                                           (unsigned long long)version, n)
                     : fm_error_set_reason(err, FM_ERR_INPUT, "not_found",
                                           "chunk %s has no version %llu", n,
                                           (unsigned long long)version);
            break;
        }
        *size = v->drc_size;
        *data = malloc(*size ? *size : 1);
        if (!*data) {
            rc = fm_error_set_reason(err, FM_ERR_LIMIT, "out_of_memory", "out of memory");
            break;
        }
        if (*size) memcpy(*data, v->drc, *size);
        rc = FM_OK;
        break;
    }
    pthread_mutex_unlock(&j->lock);
    log_wait(j, "a chunk's mesh", waited);
    return rc;
}

fm_mesh *fm_publish_mesh_copy(job *j, fm_error *err)
{
    pthread_mutex_lock(&j->lock);
    /* the chunks' colours (options.color) go into the whole mesh too */
    unsigned attrs = FM_MESH_NORMALS;
    for (size_t i = 0; i < j->chunk_count; i++)
        if (j->chunks[i].mesh && j->chunks[i].mesh->colors) attrs |= FM_MESH_COLORS;
    fm_mesh *mesh = fm_mesh_new(0, 0, attrs, NULL, err);
    fm_status st = mesh ? FM_OK : FM_ERR_LIMIT;
    for (size_t i = 0; st == FM_OK && i < j->chunk_count; i++)
        if (j->chunks[i].mesh) st = fm_mesh_append(mesh, j->chunks[i].mesh, err);
    pthread_mutex_unlock(&j->lock);
    if (st != FM_OK) {
        fm_mesh_free(mesh);
        return NULL;
    }
    return mesh;
}

int fm_publish_events_wait(job *j, uint64_t after, int timeout_ms, fm_http_event *out, int cap,
                           int *finished)
{
    struct timespec until;
    fm_clock_deadline(&until, timeout_ms / 1000.0);
    pthread_mutex_lock(&j->lock);
    while (j->next_event - 1 <= after && !j->ended) {
        if (pthread_cond_timedwait(&j->cond, &j->lock, &until) != 0) break;
    }
    /* Events older than the ring are gone: start from the oldest kept. */
    uint64_t first = after + 1;
    if (j->next_event > JOB_EVENT_RING && first < j->next_event - JOB_EVENT_RING)
        first = j->next_event - JOB_EVENT_RING;
    int n = 0;
    for (uint64_t e = first; e < j->next_event && n < cap; e++) {
        const job_event *ev = &j->ring[e % JOB_EVENT_RING];
        out[n].id = ev->id;
        snprintf(out[n].type, sizeof out[n].type, "%s", ev->type);
        out[n].data = strdup(ev->data ? ev->data : "{}");
        if (!out[n].data) break;
        n++;
    }
    uint64_t last = n ? out[n - 1].id : after;
    *finished = j->ended && last + 1 >= j->next_event;
    pthread_mutex_unlock(&j->lock);
    return n;
}
