/* tooltable_internal.h: what the readers of toolpaths/tooltable share (one
 * reader per format: fusion.c, fusion_zip.c, freecad.c, camotics.c,
 * comments.c; tooltable.c tells the formats apart by content). Seen by this
 * folder's files and tests/tooltable only. */
#ifndef FM_TOOLTABLE_INTERNAL_H
#define FM_TOOLTABLE_INTERNAL_H

#include <jansson.h>
#include <stddef.h>

#include "tooltable.h"

/* One reader's run: the input's name for messages, where warnings go, the
 * error record. */
typedef struct tt_reader {
    const char *name;
    const fm_tooltable_options *opt;
    fm_error *err;
} tt_reader;

/* Hand a warning to opt->warning (nothing when there is none). */
void tt_warn(const tt_reader *r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Append s to t (capacity *cap), refusing a second tool with the same number
 * (where says which entry) and more than FM_TOOLTABLE_MAX_TOOLS. */
fm_status tt_push(const tt_reader *r, fm_tool_table *t, size_t *cap, const fm_tool_spec *s,
                  const char *where);

/* Check an entry with lib/tools' rules, the message prefixed by where. */
fm_status tt_validate(const tt_reader *r, const fm_tool_spec *s, const char *where);

/* Copy a label into a fixed buffer, cut at its size. */
void tt_copy(char *dst, size_t size, const char *src);

/* Does text hold word as a whole word (not inside a longer one)? */
int tt_has_word(const char *text, const char *word);

/* Case-insensitive equality of ASCII names. */
int tt_same(const char *a, const char *b);

/* Read a whole file of at most max bytes into *text (malloc'ed, owned by
 * the caller, NUL-terminated) and *len. */
fm_status tt_read_file(const char *path, size_t max, char **text, size_t *len, fm_error *err);

/* The readers. root is borrowed. */
fm_status tt_fusion_json(const tt_reader *r, json_t *root, fm_tool_table *out);
fm_status tt_fusion_zip(const tt_reader *r, const void *data, size_t len, fm_tool_table *out);
/* A FreeCAD tool bit as tool `number`. */
fm_status tt_freecad_bit(const tt_reader *r, json_t *root, int number, fm_tool_spec *s,
                         const char *where);
/* A FreeCAD library; its bits are read relative to dir (the library's folder;
 * NULL: refused, the library was not given as a file). */
fm_status tt_freecad_library(const tt_reader *r, json_t *root, const char *dir,
                             fm_tool_table *out);
fm_status tt_camotics(const tt_reader *r, json_t *root, fm_tool_table *out);

/* The largest Fusion .tools archive and its tools.json (bytes); the most
 * entries the archive may hold. */
#define TT_ZIP_MAX_BYTES FM_TOOLTABLE_MAX_BYTES
#define TT_ZIP_MAX_ENTRIES 64

#endif
