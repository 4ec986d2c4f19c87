/* fuzz_tool_comments.c: libFuzzer target for tools from program comments
 * (comments.c): the input split at newlines into comments, as the G-code
 * interpreter hands them over, in millimetres and in inches. */
#include "fuzz_tool_libraries.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (int inch = 0; inch < 2; inch++) {
        fm_tooltable_comments *c = fm_tooltable_comments_new("fuzz.nc", inch);
        size_t start = 0;
        int line = 1;
        for (size_t i = 0; i <= size; i++)
            if (i == size || data[i] == '\n') {
                fm_tooltable_comments_add(c, line++, (const char *)data + start, i - start);
                start = i + 1;
            }
        fm_error err;
        fm_tool_table t = {0};
        if (fm_tooltable_comments_finish(c, &fuzz_options, &t, &err) == FM_OK)
            fm_tool_table_free(&t);
        fm_tooltable_comments_free(c);
    }
    return 0;
}
