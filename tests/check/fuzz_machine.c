/* fuzz_machine.c: libFuzzer target for the machine file reader
 * (fm_check_machine_load in daemon/runner/machine.c: jansson's file
 * reader, then fm_check_machine_from_json, which the daemon also uses for a
 * job's options.check.machine). The reader takes a path, so each input is
 * written to one unlinked temporary file, opened through /proc/self/fd. Any
 * input must give either a machine the check can use or an error naming
 * the file, never a crash or a leak. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_input_file.h"

#include "runner/machine.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* What lib/check and lib/sweep rely on: finite numbers, lo <= hi on a
 * limited axis, a rapid rate that is 0 (not given) or above 0; at most
 * three rotary axes with distinct letters, unit directions, a known link,
 * and TCP only with rotary axes. */
static void check_machine(const fm_check_machine *m)
{
    for (int a = 0; a < 3; a++) {
        if (m->has_limit[a] != 0 && m->has_limit[a] != 1) abort();
        if (m->has_limit[a] && !(isfinite(m->limit_lo[a]) && isfinite(m->limit_hi[a]) &&
                                 m->limit_lo[a] <= m->limit_hi[a]))
            abort();
        if (!isfinite(m->start[a])) abort();
    }
    if (!(isfinite(m->rapid_rate) && m->rapid_rate >= 0)) abort();
    const fm_machine *c = &m->chain;
    if (c->rotary_count < 0 || c->rotary_count > FM_MACHINE_MAX_ROTARY) abort();
    if (c->tcp && c->rotary_count == 0) abort();
    for (int i = 0; i < c->rotary_count; i++) {
        const fm_rotary_axis *r = &c->rotary[i];
        if (r->letter < 0 || r->letter > 2) abort();
        for (int j = 0; j < i; j++)
            if (c->rotary[j].letter == r->letter) abort();
        if (r->carries != FM_ROTARY_TABLE && r->carries != FM_ROTARY_HEAD) abort();
        double n = sqrt(r->around[0] * r->around[0] + r->around[1] * r->around[1] + r->around[2] * r->around[2]);
        if (!(fabs(n - 1) < 1e-9)) abort();
        for (int k = 0; k < 3; k++)
            if (!isfinite(r->through[k])) abort();
        if (!isfinite(r->pivot_length)) abort();
        if (r->has_limits && !(r->limit_lo <= r->limit_hi)) abort();
    }
    /* head: 1 to 8 round segments of positive diameter and length */
    if (m->head_count < 0 || m->head_count > FM_TOOL_MAX_HOLDER) abort();
    for (int i = 0; i < m->head_count; i++)
        if (!(m->head[i].diameter > 0) || !(m->head[i].length > 0) || !(m->head[i].diameter_top >= 0)) abort();
    /* components: NUL-terminated .hf / .stl paths on a table link (0 to the
     * number of table axes below the workpiece's) */
    int ntable = 0;
    for (int i = 0; i < c->rotary_count; i++) ntable += c->rotary[i].carries == FM_ROTARY_TABLE;
    if (m->component_count < 0 || m->component_count > FM_CHECK_MAX_COMPONENTS) abort();
    for (int i = 0; i < m->component_count; i++) {
        if (m->component_frame_up[i] < 0 || m->component_frame_up[i] > ntable) abort();
        const char *p = m->component_path[i];
        const char *end = memchr(p, '\0', FM_CHECK_COMPONENT_PATH);
        if (!end) abort();
        size_t n = (size_t)(end - p);
        if (!((n > 3 && !strcmp(p + n - 3, ".hf")) || (n > 4 && !strcmp(p + n - 4, ".stl")))) abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *input_path = fuzz_input_file("fuzz_machine", data, size);

    fm_check_machine m;
    fm_error err;
    fm_error_clear(&err);
    if (fm_check_machine_load(input_path, &m, &err) == FM_OK) {
        check_machine(&m);
    } else {
        if (err.code != FM_ERR_INPUT || strcmp(err.file, input_path) != 0) abort();
        char text[1024];
        fm_error_format(&err, text, sizeof text);
        if (!memchr(text, '\0', sizeof text)) abort();
    }
    return 0;
}
