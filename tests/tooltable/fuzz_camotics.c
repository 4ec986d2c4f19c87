/* fuzz_camotics.c: libFuzzer target for the CAMotics tool table reader
 * (camotics.c): projects and tool tables alone. */
#include "fuzz_tool_libraries.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_json_reader(data, size, tt_camotics);
    return 0;
}
