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
    /* stop very long outputs so each input stays fast */
    return *n > 200000 || m->t1 < m->t0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fm_tool_spec tools[2];
    static fm_tool_table table = {2, tools};
    tools[0].number = 1;
    tools[0].length_offset = 12.5;
    tools[1].number = 2;
    tools[1].length_offset = -3;
    fm_gcode_options opt;
    fm_gcode_options_default(&opt);
    opt.max_iterations = 5000; /* keep each run short; the limit itself is what we test */
    opt.max_program_bytes = 1 << 20;
    opt.tools = (size & 1) ? &table : NULL;
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
