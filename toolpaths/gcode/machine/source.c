/* source.c: the program's lines and those of subroutine files. An
 * `o<name> call` whose subroutine is not in the program loads <name>.ngc
 * from the first folder of the subroutine path that has it
 * (fm_gcode_options.subroutine_path, ':'-separated, as LinuxCNC's
 * SUBROUTINE_PATH; like rs274, the program's own folder is not searched). A loaded file's lines follow the program's
 * (and those of files loaded before it), so that O-word scans, calls and
 * error positions work on it as on the program; messages name the file and
 * its own line numbers. */
#include "machine.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define GC_MAX_SOURCES 256

void gc_line_text(const gc_interp *g, size_t idx, const char **text, size_t *len)
{
    if (idx < g->nlines || g->nsources == 0) {
        *text = g->text + g->line_start[idx];
        *len = g->line_start[idx + 1] - g->line_start[idx];
        return;
    }
    for (int i = g->nsources - 1; i >= 0; i--) {
        const gc_source *s = &g->sources[i];
        if (idx >= s->first) {
            size_t k = idx - s->first;
            *text = s->text + s->line_start[k];
            *len = s->line_start[k + 1] - s->line_start[k];
            return;
        }
    }
    *text = "";
    *len = 0;
}

void gc_source_range(const gc_interp *g, size_t idx, size_t *lo, size_t *hi)
{
    if (idx < g->nlines || g->nsources == 0) {
        *lo = 0;
        *hi = g->nlines;
        return;
    }
    for (int i = g->nsources - 1; i >= 0; i--) {
        const gc_source *s = &g->sources[i];
        if (idx >= s->first) {
            *lo = s->first;
            *hi = s->first + s->nlines;
            return;
        }
    }
    *lo = 0;
    *hi = g->nlines;
}

void gc_set_line(gc_interp *g, size_t idx)
{
    if (idx < g->nlines || g->nsources == 0) {
        g->lineno = (int)idx + 1;
        g->line_name = g->name;
        return;
    }
    for (int i = g->nsources - 1; i >= 0; i--) {
        const gc_source *s = &g->sources[i];
        if (idx >= s->first) {
            g->lineno = (int)(idx - s->first) + 1;
            g->line_name = s->name;
            return;
        }
    }
}

fm_status gc_index_lines(const char *text, size_t len, const char *name, size_t **line_start,
                         size_t *nlines, fm_error *err)
{
    size_t n = 1;
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n') n++;
    size_t *ls = malloc((n + 1) * sizeof *ls);
    if (!ls) return fm_error_set(err, FM_ERR_LIMIT, "out of memory indexing %zu lines of %s", n, name);
    size_t k = 0;
    ls[k++] = 0;
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n') ls[k++] = i + 1;
    ls[k] = len;
    *nlines = n > 1 && ls[n - 1] == len ? n - 1 : n; /* a trailing newline ends the last line */
    *line_start = ls;
    return FM_OK;
}

void gc_sources_free(gc_interp *g)
{
    for (int i = 0; i < g->nsources; i++) {
        free(g->sources[i].name);
        free(g->sources[i].text);
        free(g->sources[i].line_start);
    }
    free(g->sources);
    g->sources = NULL;
    g->nsources = g->capsources = 0;
}

/* The whole file, bounded by what the program may still read. */
static fm_status read_file(gc_interp *g, const char *path, size_t limit, char **text, size_t *len,
                           int col)
{
    FILE *f = fopen(path, "rb");
    if (!f) return gc_fail(g, FM_ERR_IO, col, "cannot open %s: %s", path, strerror(errno));
    size_t cap = 65536, n = 0;
    char *buf = malloc(cap);
    if (!buf) {
        fclose(f);
        return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory reading %s", path);
    }
    for (;;) {
        if (n == cap) {
            if (cap > limit) break;
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                fclose(f);
                return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory reading %s", path);
            }
            buf = nb;
            cap *= 2;
        }
        size_t r = fread(buf + n, 1, cap - n, f);
        if (r == 0) break;
        n += r;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return gc_fail(g, FM_ERR_IO, col, "read error in %s", path);
    }
    if (n > limit) {
        free(buf);
        return gc_fail(g, FM_ERR_LIMIT, col,
                       "subroutine file %s makes the program larger than %zu bytes "
                       "(max_program_bytes)", path, g->opt.max_program_bytes);
    }
    *text = buf;
    *len = n;
    return FM_OK;
}

static int is_file(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* Next folder of a ':'-separated list into dir; 0 at the end. */
static int next_folder(const char **list, char *dir, size_t cap)
{
    const char *p = *list;
    if (!p || !*p) return 0;
    const char *e = strchr(p, ':');
    size_t n = e ? (size_t)(e - p) : strlen(p);
    if (n >= cap) n = cap - 1;
    memcpy(dir, p, n);
    dir[n] = '\0';
    *list = e ? e + 1 : p + strlen(p);
    return 1;
}

fm_status gc_load_subroutine_file(gc_interp *g, const char *name, int col, int *found,
                                  size_t *first)
{
    *found = 0;
    if (strchr(name, '/') || !strcmp(name, "..")) return FM_OK; /* a name, never a path */
    char path[4096], dir[4096];
    int have = 0;
    const char *list = g->opt.subroutine_path;
    while (!have && next_folder(&list, dir, sizeof dir)) {
        if (!dir[0]) continue;
        if (snprintf(path, sizeof path, "%s/%s.ngc", dir, name) >= (int)sizeof path) continue;
        have = is_file(path);
    }
    if (!have) return FM_OK;
    if (g->nsources >= GC_MAX_SOURCES)
        return gc_fail(g, FM_ERR_LIMIT, col, "more than %d subroutine files", GC_MAX_SOURCES);
    size_t used = g->len;
    for (int i = 0; i < g->nsources; i++) used += g->sources[i].len;
    size_t limit = g->opt.max_program_bytes > used ? g->opt.max_program_bytes - used : 0;
    char *text = NULL;
    size_t len = 0;
    fm_status st = read_file(g, path, limit, &text, &len, col);
    if (st) return st;
    size_t *ls = NULL, nlines = 0;
    if ((st = gc_index_lines(text, len, path, &ls, &nlines, g->err))) {
        free(text);
        return st;
    }
    char *pname = strdup(path);
    if (g->nsources == g->capsources) {
        int cap = g->capsources ? g->capsources * 2 : 4;
        gc_source *s = realloc(g->sources, (size_t)cap * sizeof *s);
        if (s) {
            g->sources = s;
            g->capsources = cap;
        }
    }
    if (!ls || !pname || g->nsources == g->capsources) {
        free(ls);
        free(pname);
        free(text);
        return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory loading %s", path);
    }
    gc_source *s = &g->sources[g->nsources++];
    s->name = pname;
    s->text = text;
    s->len = len;
    s->line_start = ls;
    s->nlines = nlines;
    s->first = g->nlines_all;
    g->nlines_all += nlines;
    *first = s->first;
    *found = 1;
    return FM_OK;
}
