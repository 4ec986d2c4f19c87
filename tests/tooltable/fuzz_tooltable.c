/* fuzz_tooltable.c: libFuzzer target for the tool table parsers (JSON and
 * LinuxCNC .tbl) and the loader that tells every format apart by content.
 * Any input must give either a valid table or an error, never a crash, a
 * leak or an unbounded allocation. */
#include <stddef.h>
#include <stdint.h>

#include "toolpaths/tooltable/tooltable.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fm_tool_table table;
    fm_error err;
    if (fm_tooltable_parse_json((const char *)data, size, "fuzz.json", &table, &err) == FM_OK)
        fm_tool_table_free(&table);
    if (fm_tooltable_parse_tbl((const char *)data, size, "fuzz.tbl", &table, &err) == FM_OK)
        fm_tool_table_free(&table);
    if (fm_tooltable_parse((const char *)data, size, "fuzz", NULL, &table, &err) == FM_OK)
        fm_tool_table_free(&table);
    return 0;
}
