/* fuzz_fusion.c: libFuzzer target for the Fusion 360 library reader
 * (fusion.c) on JSON inputs. */
#include "fuzz_tool_libraries.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_json_reader(data, size, tt_fusion_json);
    return 0;
}
