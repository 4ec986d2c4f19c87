/* fuzz_tool_libraries.h: what the fuzz targets of the tool-library readers
 * share: any input gives a table or an error, never a crash, a leak or an
 * unbounded allocation; warnings are taken and dropped. */
#ifndef FM_FUZZ_TOOL_LIBRARIES_H
#define FM_FUZZ_TOOL_LIBRARIES_H

#include <stddef.h>
#include <stdint.h>

#include "toolpaths/tooltable/tooltable_internal.h"

static inline void fuzz_drop_warning(void *user, const char *message)
{
    (void)user;
    (void)message;
}

static const fm_tooltable_options fuzz_options = {fuzz_drop_warning, NULL};

/* The input as JSON for one reader (inputs that are not JSON objects stop
 * here: jansson has its own fuzzing). */
static inline void fuzz_json_reader(const uint8_t *data, size_t size,
                             fm_status (*reader)(const tt_reader *, json_t *, fm_tool_table *))
{
    json_t *root = json_loadb((const char *)data, size, JSON_REJECT_DUPLICATES, NULL);
    if (!json_is_object(root)) {
        json_decref(root);
        return;
    }
    fm_error err;
    tt_reader r = {"fuzz", &fuzz_options, &err};
    fm_tool_table t = {0};
    if (reader(&r, root, &t) == FM_OK) fm_tool_table_free(&t);
    json_decref(root);
}

#endif
