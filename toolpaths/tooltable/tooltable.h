/* tooltable.h: reading tool tables into fm_tool_table (lib/tools/tools.h):
 * the project's JSON form (every field validated, docs/tooltable.md),
 * LinuxCNC .tbl files (T P D Z ;comment), the tool libraries of CAM systems
 * (Fusion 360 .json and .tools, FreeCAD .fctb and .fctl, CAMotics projects
 * and tool tables) and the tool comments CAM posts write into programs. One
 * loader tells the formats apart by content. */
#ifndef FM_TOOLTABLE_H
#define FM_TOOLTABLE_H

#include <jansson.h>
#include <stddef.h>

#include "core/core.h"
#include "tools/tools.h"

/* Load a table from a file, in whichever format its content is (a zip: a
 * Fusion .tools; JSON: frepmill's form, Fusion's library, a FreeCAD bit or
 * library, a CAMotics project or tool table; anything else: LinuxCNC .tbl).
 * On success *out owns its tools (free with fm_tool_table_free); on error
 * *out is empty and err says what and where (the file, the entry by its
 * number and description, the field). Warnings are dropped. */
fm_status fm_tooltable_load(const char *path, fm_tool_table *out, fm_error *err);

/* Where a reader's warnings go: a tool taken as the bounding solid of a
 * shape frepmill does not model, a field guessed, an entry skipped. */
typedef struct fm_tooltable_options {
    void (*warning)(void *user, const char *message);
    void *warning_user;
} fm_tooltable_options;

/* fm_tooltable_load with warnings (opt may be NULL). */
fm_status fm_tooltable_load_with(const char *path, const fm_tooltable_options *opt,
                                 fm_tool_table *out, fm_error *err);
/* The same for content held by the caller (every format but a FreeCAD
 * library, which names other files: refused here). */
fm_status fm_tooltable_parse(const char *data, size_t len, const char *name,
                             const fm_tooltable_options *opt, fm_tool_table *out, fm_error *err);

/* Tools from a program's comments (--tools-from-program): the headers CAM
 * posts write, "T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL" (Fusion and
 * posts like it) and LinuxCNC-style "T1 D6 ball". Feed every comment of the
 * program to fm_tooltable_comments_add (its signature is
 * fm_gcode_options.comment's), then finish: each tool from the first comment
 * that names it, every field the comment does not give guessed and listed in
 * a warning. inch: the program's lengths are inches (G20). */
typedef struct fm_tooltable_comments fm_tooltable_comments;
fm_tooltable_comments *fm_tooltable_comments_new(const char *name, int inch);
void fm_tooltable_comments_add(void *comments, int line, const char *text, size_t len);
/* An empty table (count 0) when no comment names a tool. */
fm_status fm_tooltable_comments_finish(fm_tooltable_comments *c, const fm_tooltable_options *opt,
                                       fm_tool_table *out, fm_error *err);
void fm_tooltable_comments_free(fm_tooltable_comments *c);

/* Parse text held by the caller; name is used in error messages. */
fm_status fm_tooltable_parse_json(const char *text, size_t len, const char *name,
                                  fm_tool_table *out, fm_error *err);
/* A table already parsed (a job document's "tools", read once with the
 * document), in any JSON format (frepmill's, a Fusion library, a FreeCAD
 * bit, a CAMotics project or table; a FreeCAD library, which names files,
 * is refused): the same validation, no text in between; a reference to
 * root is not taken. */
fm_status fm_tooltable_from_json(json_t *root, const char *name, fm_tool_table *out,
                                 fm_error *err);
/* The same with warnings (opt may be NULL). */
fm_status fm_tooltable_from_json_with(json_t *root, const char *name,
                                      const fm_tooltable_options *opt, fm_tool_table *out,
                                      fm_error *err);
fm_status fm_tooltable_parse_tbl(const char *text, size_t len, const char *name,
                                 fm_tool_table *out, fm_error *err);

/* The largest tool table file accepted (bytes). */
#define FM_TOOLTABLE_MAX_BYTES (16u << 20)
/* The most tools in one table. */
#define FM_TOOLTABLE_MAX_TOOLS 10000

#endif
