/* fuzz_freecad.c: libFuzzer target for the FreeCAD tool bit reader
 * (freecad.c): quantities with units, every shipped shape. Libraries name
 * files and are read from tests only. */
#include "fuzz_tool_libraries.h"

static fm_status bit_as_table(const tt_reader *r, json_t *root, fm_tool_table *out)
{
    fm_tool_spec s;
    size_t cap = 0;
    fm_status st = tt_freecad_bit(r, root, 1, &s, "bit");
    if (!st) st = tt_push(r, out, &cap, &s, "bit");
    if (st) fm_tool_table_free(out);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_json_reader(data, size, bit_as_table);
    return 0;
}
