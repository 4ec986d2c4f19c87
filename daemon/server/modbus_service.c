/* modbus_service.c: the daemon's implementation of the Modbus server's
 * service interface (protocols/modbus/modbus_server.h) over the job
 * manager: the status registers show the selected job (by default the
 * newest), commands start (resume), pause, cancel and select it, and live
 * mode cuts a live job's stock along the controller's positions
 * (live.c). */
#include "modbus_service.h"

#include <stdatomic.h>
#include <string.h>

#include "log.h"

static atomic_int selected_slot; /* 0: the newest job */

static int current_slot(fm_jobs *jobs)
{
    int slot = atomic_load(&selected_slot);
    return slot > 0 ? slot : fm_jobs_count(jobs);
}

static void read_status(void *ctx, fm_modbus_status *out)
{
    fm_jobs *jobs = ctx;
    memset(out, 0, sizeof *out);
    int slot = current_slot(jobs);
    out->selected_slot = (uint16_t)slot;
    if (fm_jobs_live_active(jobs)) out->bits |= FM_MODBUS_BIT_LIVE;
    fm_job_view v;
    if (fm_jobs_view_slot(jobs, slot, &v) != 0) return;
    out->bits |= FM_MODBUS_BIT_JOB_LOADED;
    if (v.state == FM_JOB_RUNNING && !v.paused) out->bits |= FM_MODBUS_BIT_RUNNING;
    if (v.paused) out->bits |= FM_MODBUS_BIT_PAUSED;
    if (v.state == FM_JOB_DONE) out->bits |= FM_MODBUS_BIT_DONE;
    if (v.state == FM_JOB_FAILED) out->bits |= FM_MODBUS_BIT_ERROR;
    /* The alarm is for errors (contact deeper than the tolerance); warnings
     * (near misses) only count in register 23. */
    if (v.error_finding_count) out->bits |= FM_MODBUS_BIT_COLLISION;
    out->block = v.block >= 0 ? (uint32_t)v.block : 0;
    out->source_line = v.line > 0 ? (uint32_t)v.line : 0;
    out->progress_permille = (uint16_t)(v.progress * 1000 + 0.5);
    out->tool = (uint16_t)(v.tool > 0 ? v.tool : 0);
    memcpy(out->tool_tip, v.position, sizeof out->tool_tip);
    out->program_time_s = v.program_time_s;
    out->removed_mm3 = v.removed_mm3;
    out->remaining_mm3 = v.stock_mm3;
    out->removal_rate_mm3_s = v.removal_rate_mm3_s;
    out->finding_count = (uint16_t)v.finding_count;
    out->first_finding_line = (uint32_t)v.first_finding_line;
    out->last_error = (uint16_t)v.error_code;
}

static fm_status command(void *ctx, int cmd, uint32_t argument, fm_error *err)
{
    fm_jobs *jobs = ctx;
    if (cmd == FM_MODBUS_CMD_SELECT) {
        if (argument != 0 && (int)argument > fm_jobs_count(jobs))
            return fm_error_set_reason(err, FM_ERR_INPUT, "bad_slot", "no job in slot %u",
                                       (unsigned)argument);
        atomic_store(&selected_slot, (int)argument);
        return FM_OK;
    }
    fm_job_view v;
    if (fm_jobs_view_slot(jobs, current_slot(jobs), &v) != 0)
        return fm_error_set_reason(err, FM_ERR_INPUT, "no_job", "no job is selected");
    fm_status st;
    switch (cmd) {
    case FM_MODBUS_CMD_START: st = fm_jobs_pause(jobs, v.id, 0, err); break;
    case FM_MODBUS_CMD_PAUSE: st = fm_jobs_pause(jobs, v.id, 1, err); break;
    case FM_MODBUS_CMD_CANCEL: st = fm_jobs_cancel(jobs, v.id, err); break;
    default:
        return fm_error_set_reason(err, FM_ERR_INPUT, "unknown_command", "unknown command %d",
                                   cmd);
    }
    if (st == FM_OK) fm_log(FM_LOG_INFO, "modbus: command %d on job %s", cmd, v.id);
    return st;
}

static fm_status live_position(void *ctx, const double xyz[3], int tool, fm_error *err)
{
    fm_live_pose pose;
    fm_live_pose_init(&pose, xyz, tool);
    return fm_jobs_live_position(ctx, &pose, err);
}

/* On: a live job from the config's live_stock/live_tools, or from the
 * selected job's stock and tools; it becomes the newest job, so the status
 * registers follow it unless a slot is selected. Off: it ends once the
 * positions already written are cut. */
static fm_status live_mode(void *ctx, int on, fm_error *err)
{
    fm_jobs *jobs = ctx;
    if (!on) return fm_jobs_live_stop(jobs, err);
    return fm_jobs_live_start(jobs, current_slot(jobs), err);
}

static void watchdog_expired(void *ctx)
{
    fm_log(FM_LOG_WARN, "modbus: the HMI watchdog expired; pausing running jobs");
    fm_jobs_pause_all(ctx);
}

void fm_jobs_modbus_service(fm_jobs *jobs, fm_modbus_service *out)
{
    memset(out, 0, sizeof *out);
    out->ctx = jobs;
    out->read_status = read_status;
    out->command = command;
    out->live_position = live_position;
    out->live_mode = live_mode;
    out->watchdog_expired = watchdog_expired;
}
