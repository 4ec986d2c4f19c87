/* fuzz_machine.c: libFuzzer target for the collision check's machine file
 * reader (fm_check_machine_load in daemon/runner/findings_json.c: jansson's file
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

#include "findings_json.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* What lib/check relies on: finite numbers, lo <= hi on a limited axis, a
 * rapid rate that is 0 (not given) or above 0. */
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
