/* mtconnect_service.c: the daemon's implementation of the MTConnect
 * agent's service interface (protocols/mtconnect/mtconnect.h) over the job
 * manager, and the agent mounted on the HTTP server under /mtconnect. The
 * device follows the newest job (the one Modbus shows by default): its
 * published status (state, line, tool, position, rotary joints, spindle
 * speed, volumes, progress, findings, error) and its tool table; the rotary
 * axes come from the machine file of the mtconnect_machine setting. */
#include "mtconnect_service.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check/check.h"
#include "job_record.h"
#include "log.h"
#include "publish.h"
#include "runner/machine.h"

/* The newest job, referenced (fm_jobs_put), or NULL. */
static job *newest_job(fm_jobs *jobs)
{
    fm_job_view v;
    int slot = fm_jobs_count(jobs);
    if (slot <= 0 || fm_jobs_view_slot(jobs, slot, &v) != 0) return NULL;
    return fm_jobs_get(jobs, v.id);
}

static fm_mtc_execution execution_of(const char *state, int paused)
{
    if (!state) return FM_MTC_EXEC_READY;
    if (!strcmp(state, "running")) return paused ? FM_MTC_EXEC_INTERRUPTED : FM_MTC_EXEC_ACTIVE;
    if (!strcmp(state, "done")) return FM_MTC_EXEC_PROGRAM_COMPLETED;
    if (!strcmp(state, "failed") || !strcmp(state, "cancelled")) return FM_MTC_EXEC_STOPPED;
    return FM_MTC_EXEC_READY; /* queued */
}

static void svc_snapshot(void *ctx, fm_mtc_snapshot *out)
{
    fm_jobs *jobs = ctx;
    out->available = 1;
    out->execution = FM_MTC_EXEC_READY;
    job *j = newest_job(jobs);
    if (!j) return;
    json_t *st = fm_publish_status_json(j);
    fm_jobs_put(jobs, j);
    if (!st) return;
    const char *state = json_string_value(json_object_get(st, "state"));
    out->execution = execution_of(state, json_is_true(json_object_get(st, "paused")));
    const char *name = json_string_value(json_object_get(st, "name"));
    const char *id = json_string_value(json_object_get(st, "id"));
    snprintf(out->program, sizeof out->program, "%s", name && name[0] ? name : id ? id : "");
    json_int_t line = json_integer_value(json_object_get(st, "line"));
    json_int_t tool = json_integer_value(json_object_get(st, "tool"));
    out->line = line > 0 ? (long)line : -1;
    out->tool = tool > 0 ? (long)tool : -1;
    /* A position once the job has moved (a queued job has none yet). */
    if (state && strcmp(state, "queued") != 0) {
        json_t *pos = json_object_get(st, "position");
        for (int a = 0; a < 3; a++) out->position[a] = json_number_value(json_array_get(pos, (size_t)a));
        /* The joints of the job's machine's rotary axes ("rotary": {"A":
         * DEG, ...}) and the spindle speed of the motion last cut. */
        static const char *const rotary[3] = {"A", "B", "C"};
        for (int a = 0; a < 3; a++) {
            json_t *angle = json_object_get(json_object_get(st, "rotary"), rotary[a]);
            if (json_is_number(angle)) out->rotary[a] = json_number_value(angle);
        }
        json_t *rpm = json_object_get(st, "spindle_rpm");
        if (json_is_number(rpm)) out->spindle_rpm = json_number_value(rpm);
    }
    out->removed_mm3 = json_number_value(json_object_get(st, "removed_volume_mm3"));
    out->stock_mm3 = json_number_value(json_object_get(st, "stock_volume_mm3"));
    out->progress_percent = 100.0 * json_number_value(json_object_get(st, "progress"));
    out->uncertain_voxels = (double)json_integer_value(json_object_get(st, "voxels_uncertain"));
    /* A live job: where the machine is (its latest position), which the
     * cut reaches a little later; so a follower sees every position. */
    fm_live_pose live;
    if (fm_jobs_live_machine(jobs, &live)) {
        memcpy(out->position, live.xyz, sizeof live.xyz);
        out->tool = live.tool > 0 ? live.tool : out->tool;
        /* what the source maps: joints, line, speed */
        for (int a = 0; a < 3; a++)
            if (isfinite(live.abc[a])) out->rotary[a] = live.abc[a];
        if (live.line > 0) out->line = live.line;
        if (isfinite(live.spindle_rpm)) out->spindle_rpm = live.spindle_rpm;
    }
    json_t *error = json_object_get(st, "error");
    if (json_is_object(error)) {
        const char *m = json_string_value(json_object_get(error, "message"));
        snprintf(out->system_fault, sizeof out->system_fault, "%s", m ? m : "the job failed");
    }
    size_t i;
    json_t *f;
    json_array_foreach(json_object_get(st, "findings"), i, f)
    {
        if (out->finding_count == FM_MTC_MAX_FINDINGS) break;
        fm_mtc_finding *mf = &out->findings[out->finding_count++];
        const char *severity = json_string_value(json_object_get(f, "severity"));
        const char *kind = json_string_value(json_object_get(f, "kind"));
        const char *part = json_string_value(json_object_get(f, "part"));
        /* Errors (a collision: contact deeper than the tolerance) are
         * faults, as they are the Modbus collision alarm; the rest warnings. */
        mf->level = severity && !strcmp(severity, "error") ? FM_MTC_FAULT : FM_MTC_WARNING;
        mf->line = (long)json_integer_value(json_object_get(f, "line"));
        snprintf(mf->text, sizeof mf->text, "%s of the %s, %.3f mm deep", kind ? kind : "finding",
                 part ? part : "tool", json_number_value(json_object_get(f, "penetration_mm")));
    }
    json_decref(st);
}

static int svc_tools(void *ctx, fm_mtc_tool *out, int cap)
{
    fm_jobs *jobs = ctx;
    job *j = newest_job(jobs);
    if (!j) return 0;
    /* The document is immutable while the record lives. */
    const fm_tool_table *table = &fm_job_document(j)->tools;
    int n = 0;
    for (size_t i = 0; i < table->count && n < cap; i++) {
        const fm_tool_spec *t = &table->tools[i];
        fm_mtc_tool *m = &out[n++];
        memset(m, 0, sizeof *m);
        m->number = t->number;
        snprintf(m->description, sizeof m->description, "%.95s", t->comment);
        m->diameter = t->diameter > 0 ? t->diameter : NAN;
        m->flute_length = t->flute_length > 0 ? t->flute_length : NAN;
        m->overall_length = t->length > 0 ? t->length : NAN;
        m->corner_radius = t->corner_radius > 0 ? t->corner_radius : NAN;
        m->shank_diameter = t->shank_diameter > 0 ? t->shank_diameter : t->diameter > 0 ? t->diameter : NAN;
    }
    fm_jobs_put(jobs, j);
    return n;
}

static long stream_read(void *stream, char *buf, size_t max, int timeout_ms)
{
    return fm_mtc_stream_read(stream, buf, max, timeout_ms);
}

static void stream_free(void *stream)
{
    fm_mtc_stream_free(stream);
}

static fm_status svc_mounted(void *ctx, const char *path, const char *query, fm_http_reply *out,
                             fm_error *err)
{
    fm_mtc_reply r;
    fm_status st = fm_mtc_agent_request(ctx, path, query, &r, err);
    if (st != FM_OK) return st;
    memset(out, 0, sizeof *out);
    out->status = r.status;
    snprintf(out->content_type, sizeof out->content_type, "%s", r.content_type);
    out->body = r.body;
    out->size = r.size;
    if (r.stream) {
        out->stream = r.stream;
        out->read = stream_read;
        out->free = stream_free;
    }
    return FM_OK;
}

/* Each live position observed at once, not only when the sampler next
 * looks: a follower of this agent sees every one. */
static void live_position_seen(void *agent)
{
    fm_mtc_agent_update(agent);
}

fm_status fm_mtconnect_start(fm_jobs *jobs, const fm_daemon_config *cfg, fm_mtc_agent **out,
                             fm_error *err)
{
    fm_mtc_config mcfg;
    fm_mtc_config_default(&mcfg);
    snprintf(mcfg.device.name, sizeof mcfg.device.name, "%s", cfg->mtconnect_device);
    snprintf(mcfg.device.uuid, sizeof mcfg.device.uuid, "%s", cfg->mtconnect_uuid);
    mcfg.buffer_size = (uint32_t)cfg->mtconnect_buffer;
    mcfg.sample_ms = cfg->mtconnect_sample_ms;
    if (cfg->mtconnect_machine[0]) {
        fm_check_machine machine;
        if (fm_check_machine_load(cfg->mtconnect_machine, &machine, err) != FM_OK) return err->code;
        for (int i = 0; i < machine.chain.rotary_count && i < FM_MTC_MAX_ROTARY; i++)
            mcfg.device.rotary[mcfg.device.rotary_count++] = (char)('A' + machine.chain.rotary[i].letter);
    }
    fm_mtc_service svc = {jobs, svc_snapshot, svc_tools};
    fm_status st = fm_mtc_agent_new(&mcfg, &svc, out, err);
    if (st == FM_OK) fm_jobs_live_on_position(jobs, live_position_seen, *out);
    return st;
}

void fm_mtconnect_stop(fm_jobs *jobs, fm_mtc_agent *agent)
{
    if (!agent) return;
    fm_jobs_live_on_position(jobs, NULL, NULL); /* waits for a call in progress */
    fm_mtc_agent_free(agent);
}

void fm_mtconnect_mount(fm_mtc_agent *agent, fm_http_service *http)
{
    http->mount_prefix = "/mtconnect";
    http->mount_ctx = agent;
    http->mounted = svc_mounted;
}
