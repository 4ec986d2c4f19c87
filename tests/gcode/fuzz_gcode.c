/* fuzz_gcode.c: libFuzzer target for the G-code interpreter: any input must
 * end in FM_OK or a clean error, never a crash, a hang or a leak. A first
 * byte 0x01 selects the Fanuc dialect (the program is the rest), 0x00 the
 * LinuxCNC dialect; any other first byte is the first character of a
 * LinuxCNC program, so that plain .ngc seeds keep their meaning. Both
 * dialects run with a machine too (bits 2-3 of the input's size pick none,
 * an AC trunnion table or a BC head, both with TCP on from the start, or a
 * wrapped A indexer without TCP), so that the rotary words, TCP, G43.4 and
 * G49 are fuzzed through the machine's kinematics (the corpus's
 * machine_*.ngc and fanuc_machine_*.nc are sized for each; bit 0 gives a
 * tool table, bit 1 a probe).
 * FUZZ_GCODE_VERBOSE=1 prints what each input did. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

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

/* The machines an input may run on (docs/check.md, "Machine file"). */
static const fm_machine *pick_machine(size_t size)
{
    static fm_machine machines[3];
    static int made;
    if (!made) {
        fm_machine *t = &machines[0]; /* AC trunnion, TCP on from the start */
        t->rotary_count = 2;
        t->tcp = 1;
        t->rotary[0] = (fm_rotary_axis){.letter = 0, .carries = FM_ROTARY_TABLE,
                                         .around = {1, 0, 0}, .has_limits = 1,
                                         .limit_lo = -10, .limit_hi = 110};
        t->rotary[1] = (fm_rotary_axis){.letter = 2, .carries = FM_ROTARY_TABLE,
                                         .around = {0, 0, 1}};
        fm_machine *h = &machines[1]; /* BC head with a pivot, TCP on from the start */
        h->rotary_count = 2;
        h->tcp = 1; /* else G43.4 is refused, and a head's TCP is never fuzzed */
        h->rotary[0] = (fm_rotary_axis){.letter = 2, .carries = FM_ROTARY_HEAD,
                                         .around = {0, 0, 1}, .pivot_length = 150};
        h->rotary[1] = (fm_rotary_axis){.letter = 1, .carries = FM_ROTARY_HEAD,
                                         .around = {0, 1, 0}, .pivot_length = 150};
        fm_machine *a = &machines[2]; /* a wrapped A indexer along X */
        a->rotary_count = 1;
        a->rotary[0] = (fm_rotary_axis){.letter = 0, .carries = FM_ROTARY_TABLE,
                                         .around = {1, 0, 0}, .through = {0, 0, 20},
                                         .wrapped = 1};
        made = 1;
    }
    size_t pick = (size >> 2) & 3;
    return pick ? &machines[pick - 1] : NULL;
}

static void drop_comment(void *user, int line, const char *text, size_t len)
{
    (void)user;
    (void)line;
    (void)text;
    (void)len;
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
    opt.comment = drop_comment;
    opt.probe = (size & 2) ? half_probe : NULL;
    opt.subroutine_path = "tests/gcode/programs/subs";
    opt.machine = pick_machine(size);
    const size_t whole = size;
    if (size > 0 && (data[0] == 0 || data[0] == 1)) {
        opt.dialect = data[0] ? FM_GCODE_FANUC : FM_GCODE_LINUXCNC;
        data++;
        size--;
    }
    long n = 0;
    fm_error err;
    fm_status st = fm_gcode_run_string((const char *)data, size, "fuzz", &opt, count_sink, &n, NULL, &err);
    if (getenv("FUZZ_GCODE_VERBOSE")) {
        /* What an input did (fuzz_gcode INPUT...): to check that a seed
         * runs to its end on the machine its size picks. */
        static const char *const machine_names[4] = {"no machine", "AC trunnion with TCP", "BC head with TCP",
                                                     "wrapped A indexer"};
        fprintf(stderr, "fuzz_gcode: %zu bytes, %s, %s, tools %s, probe %s: %ld motions, %s\n", whole,
                opt.dialect == FM_GCODE_FANUC ? "Fanuc" : "LinuxCNC", machine_names[(whole >> 2) & 3],
                opt.tools ? "yes" : "no", opt.probe ? "yes" : "no", n, st == FM_OK ? "ok" : err.message);
    }
    return 0;
}
