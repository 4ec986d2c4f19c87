/* tooltable.h: reading tool tables into fm_tool_table (lib/tools/tools.h):
 * the project's JSON form (every field validated, docs/tooltable.md) and
 * LinuxCNC .tbl files (T P D Z ;comment). */
#ifndef FM_TOOLTABLE_H
#define FM_TOOLTABLE_H

#include <jansson.h>
#include <stddef.h>

#include "core/core.h"
#include "tools/tools.h"

/* Load a table from a file: JSON if its first non-blank character is '{',
 * otherwise LinuxCNC .tbl. On success *out owns its tools (free with
 * fm_tool_table_free); on error *out is empty and err says what and where. */
fm_status fm_tooltable_load(const char *path, fm_tool_table *out, fm_error *err);

/* Parse text held by the caller; name is used in error messages. */
fm_status fm_tooltable_parse_json(const char *text, size_t len, const char *name,
                                  fm_tool_table *out, fm_error *err);
/* The JSON form already parsed (a job document's "tools", read once with
 * the document): the same validation, no text in between; a reference to
 * root is not taken. */
fm_status fm_tooltable_from_json(json_t *root, const char *name, fm_tool_table *out,
                                 fm_error *err);
fm_status fm_tooltable_parse_tbl(const char *text, size_t len, const char *name,
                                 fm_tool_table *out, fm_error *err);

/* The largest tool table file accepted (bytes). */
#define FM_TOOLTABLE_MAX_BYTES (16u << 20)
/* The most tools in one table. */
#define FM_TOOLTABLE_MAX_TOOLS 10000

#endif
