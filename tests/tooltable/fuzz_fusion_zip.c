/* fuzz_fusion_zip.c: libFuzzer target for the Fusion .tools reader
 * (fusion_zip.c): any bytes as a zip archive; the entry bound, the names,
 * the inflated size limit. */
#include "fuzz_tool_libraries.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fm_error err;
    tt_reader r = {"fuzz.tools", &fuzz_options, &err};
    fm_tool_table t = {0};
    if (tt_fusion_zip(&r, data, size, &t) == FM_OK) fm_tool_table_free(&t);
    return 0;
}
