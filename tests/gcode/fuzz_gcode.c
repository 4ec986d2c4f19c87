/* fuzz_gcode.c: libFuzzer target for the G-code interpreter: any input must
 * end in FM_OK or a clean error, never a crash, a hang or a leak. A first
 * byte 0x01 selects the Fanuc dialect (the program is the rest), 0x00 the
 * LinuxCNC dialect; any other first byte is the first character of a
 * LinuxCNC program, so that plain .ngc seeds keep their meaning. */
#include <stddef.h>
#include <stdint.h>

#include "toolpaths/gcode/gcode.h"

static int count_sink(void *user, const fm_motion *m)
{
    long *n = user;
    (*n)++;
    /* a parametric motion's path must answer while the sink runs */
    if (m->kind == FM_MOTION_PARAM && m->path) {
        double p[3], a[3], lo[3], hi[3], alo[3], ahi[3];
        m->path->pose(m->path->ctx, 0.5 * (m->t0 + m->t1), p, a);
        m->path->pose_bounds(m->path->ctx, m->t0, m->t1, lo, hi, alo, ahi);
    }
    /* stop very long outputs so each input stays fast */
    return *n > 200000 || m->t1 < m->t0;
}

static void drop_message(void *user, int line, const char *text)
{
    (void)user;
    (void)line;
    (void)text;
}

/* A probe that trips half way toward contact and never away from it, so
 * both the tripped and the untripped paths run. */
static fm_status half_probe(void *user, const fm_motion *move, int toward, int *tripped,
                            double *fraction, int *at_start, fm_error *err)
{
    (void)user;
    (void)move;
    (void)err;
    *tripped = toward;
    *fraction = 0.5;
    *at_start = 0;
    return FM_OK;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fm_tool_spec tools[2];
    static fm_tool_table table = {2, tools};
    tools[0].number = 1;
    tools[0].length_offset = 12.5;
    tools[0].diameter = 6;
    tools[1].number = 2;
    tools[1].length_offset = -3;
    fm_gcode_options opt;
    fm_gcode_options_default(&opt);
    opt.max_iterations = 5000; /* keep each run short; the limit itself is what we test */
    opt.max_program_bytes = 1 << 20;
    opt.tools = (size & 1) ? &table : NULL;
    opt.message = drop_message;
    opt.probe = (size & 2) ? half_probe : NULL;
    opt.subroutine_path = "tests/gcode/programs/subs";
    if (size > 0 && (data[0] == 0 || data[0] == 1)) {
        opt.dialect = data[0] ? FM_GCODE_FANUC : FM_GCODE_LINUXCNC;
        data++;
        size--;
    }
    long n = 0;
    fm_error err;
    fm_gcode_run_string((const char *)data, size, "fuzz", &opt, count_sink, &n, NULL, &err);
    return 0;
}
