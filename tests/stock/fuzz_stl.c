/* fuzz_stl.c: libFuzzer target for the STL reader (fm_stock_new_from_stl in
 * lib/stock/stl.c: binary and ASCII STL, then the memory estimate and
 * OpenVDB's meshToLevelSet). Jobs may carry STL from network clients, so
 * any input must give either a stock within the memory budget or an error
 * that says why, never a crash, a leak or an unbounded allocation. The
 * reader takes a path, so each input is written to one unlinked temporary
 * file, opened through /proc/self/fd. A 64 MB budget and 0.5 mm voxels keep
 * each run short; the budget refusals are part of what is tested. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_input_file.h"

#include "stock/stock.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define BUDGET ((size_t)64 << 20)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *input_path = fuzz_input_file("fuzz_stl", data, size);

    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = 0.5;
    opt.memory_budget = BUDGET;
    opt.threads = 1; /* the machine's other core belongs to other jobs */
    fm_error err;
    fm_error_clear(&err);
    fm_stock *s = fm_stock_new_from_stl(input_path, &opt, &err);
    if (s) {
        /* the estimate let it through: the grid must fit the budget */
        if (fm_stock_memory_bytes(s) > BUDGET) abort();
        fm_stock_free(s);
    } else {
        if (err.code != FM_ERR_INPUT && err.code != FM_ERR_LIMIT) abort();
        if (!memchr(err.message, '\0', sizeof err.message) || !err.message[0]) abort();
    }
    return 0;
}
