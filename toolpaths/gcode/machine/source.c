/* source.c: the program's lines and those of subroutine files. An
 * `o<name> call` whose subroutine is not in the program loads <name>.ngc
 * from the first folder of the subroutine path that has it
 * (fm_gcode_options.subroutine_path, ':'-separated, as LinuxCNC's
 * SUBROUTINE_PATH; like rs274, the program's own folder is not searched). A loaded file's lines follow the program's
 * (and those of files loaded before it), so that O-word scans, calls and
 * error positions work on it as on the program; messages name the file and
 * its own line numbers.
 *
 * The ISO dialects' numbered programs: a text's programs run from an O
 * number (or the text's start) to the next O number or '%'; a called number
 * not in the texts loaded so far is loaded from O<number>.nc (.ngc, .tap) in
 * the program's folder, then on the subroutine path, by the same reading. */
#include "machine.h"

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
static fm_status read_file(gc_interp *g, const char *path, size_t limit, const char *what,
                           char **text, size_t *len, int col)
{
    fm_error ferr;
    fm_status st = fm_file_read(path, NULL, limit, text, len, &ferr);
    if (st != FM_OK && !strcmp(ferr.reason, "too_large"))
        return gc_fail(g, FM_ERR_LIMIT, col,
                       "%s file %s makes the program larger than %zu bytes "
                       "(max_program_bytes)", what, path, g->opt.max_program_bytes);
    if (st != FM_OK) return gc_fail(g, st, col, "%s", ferr.message);
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
    fm_status st = read_file(g, path, limit, "subroutine", &text, &len, col);
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

/* ---- numbered programs (ISO dialects) ---- */

void gc_programs_use_text(gc_interp *g, int t)
{
    const gc_text *x = &g->progs.texts[t];
    g->progs.cur_text = t;
    g->text = x->text;
    g->len = x->len;
    g->line_start = x->line_start;
    g->nlines = x->nlines;
    g->name = x->name;
    g->line_name = x->name;
}

typedef enum { RAW_EMPTY, RAW_PERCENT, RAW_O, RAW_CONTENT } raw_kind;

/* What a raw line is, without normalizing it. */
static raw_kind classify(const char *t, size_t i, size_t e, long *number)
{
    while (i < e && (t[i] == ' ' || t[i] == '\t' || t[i] == '\r' || t[i] == '\n')) i++;
    if (i == e || t[i] == '(' || t[i] == ';') return RAW_EMPTY;
    if (t[i] == '%') return RAW_PERCENT;
    if ((t[i] == 'O' || t[i] == 'o' || t[i] == ':') && i + 1 < e && t[i + 1] >= '0' &&
        t[i + 1] <= '9') {
        long n = 0;
        for (i++; i < e && t[i] >= '0' && t[i] <= '9'; i++)
            if (n < 100000000L) n = n * 10 + (t[i] - '0');
        *number = n;
        return RAW_O;
    }
    return RAW_CONTENT;
}

static fm_status add_program(gc_interp *g, long number, int text, size_t first)
{
    gc_programs *f = &g->progs;
    if (f->nprograms == f->capprograms) {
        int cap = f->capprograms ? f->capprograms * 2 : 8;
        if (cap > 100000)
            return fm_error_set(g->err, FM_ERR_LIMIT, "more than 100000 programs in the texts");
        gc_program *p = realloc(f->programs, (size_t)cap * sizeof *p);
        if (!p) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory indexing programs");
        f->programs = p;
        f->capprograms = cap;
    }
    gc_program *p = &f->programs[f->nprograms++];
    memset(p, 0, sizeof *p);
    p->number = number;
    p->text = text;
    p->first = first;
    p->end = first;
    return FM_OK;
}

/* Programs of text t; *first_program: the index of its first. */
static fm_status index_text(gc_interp *g, int t, int *first_program)
{
    gc_programs *f = &g->progs;
    const gc_text *x = &f->texts[t];
    int open = -1; /* the program being extended, or -1 */
    *first_program = f->nprograms;
    fm_status st;
    for (size_t i = 0; i < x->nlines; i++) {
        long number = 0;
        raw_kind k = classify(x->text, x->line_start[i], x->line_start[i + 1], &number);
        if (k == RAW_O) {
            if ((st = add_program(g, number, t, i))) return st;
            open = f->nprograms - 1;
        } else if (k == RAW_PERCENT) {
            open = -1;
        } else if (k == RAW_CONTENT && open < 0) {
            /* content outside any O number: a program without a number */
            if ((st = add_program(g, -1, t, i))) return st;
            open = f->nprograms - 1;
        }
        if (open >= 0) f->programs[open].end = i + 1;
    }
    if (f->nprograms == *first_program && (st = add_program(g, -1, t, 0))) return st;
    return FM_OK;
}

int gc_programs_percent_line(const gc_interp *g, size_t idx)
{
    long number = 0;
    return classify(g->text, g->line_start[idx], g->line_start[idx + 1], &number) == RAW_PERCENT;
}

static int find_program(const gc_programs *f, long number)
{
    for (int i = 0; i < f->nprograms; i++)
        if (f->programs[i].number == number) return i;
    return -1;
}

/* Read a subprogram file as a new text. */
static fm_status load_text(gc_interp *g, const char *path, int col, int *text)
{
    gc_programs *f = &g->progs;
    if (f->ntexts >= GC_MAX_TEXTS)
        return gc_fail(g, FM_ERR_LIMIT, col, "more than %d subprogram files", GC_MAX_TEXTS - 1);
    size_t limit = g->opt.max_program_bytes - (f->loaded_bytes < g->opt.max_program_bytes
                                                   ? f->loaded_bytes
                                                   : g->opt.max_program_bytes);
    char *buf = NULL;
    size_t n = 0;
    fm_status st = read_file(g, path, limit, "subprogram", &buf, &n, col);
    if (st) return st;
    gc_text *x = &f->texts[f->ntexts];
    memset(x, 0, sizeof *x);
    x->owned = buf;
    x->text = buf;
    x->len = n;
    x->name = malloc(strlen(path) + 1);
    if (!x->name) {
        free(buf);
        return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    }
    strcpy(x->name, path);
    f->ntexts++;
    f->loaded_bytes += n;
    if ((st = gc_index_lines(x->text, x->len, x->name, &x->line_start, &x->nlines, g->err)))
        return st;
    *text = f->ntexts - 1;
    return FM_OK;
}

fm_status gc_programs_locate(gc_interp *g, long number, const char *call, int col,
                             int *program)
{
    gc_programs *f = &g->progs;
    int pi = find_program(f, number);
    if (pi >= 0) {
        *program = pi;
        return FM_OK;
    }
    /* folders: the program's own, then the subroutine path */
    char dirs[4096];
    const char *main_name = f->texts[0].name;
    const char *slash = strrchr(main_name, '/');
    size_t nd = 0;
    if (g->program_is_file) {
        if (slash) nd = (size_t)snprintf(dirs, sizeof dirs, "%.*s", (int)(slash - main_name),
                                         main_name);
        else nd = (size_t)snprintf(dirs, sizeof dirs, ".");
    }
    if (g->opt.subroutine_path && *g->opt.subroutine_path)
        snprintf(dirs + nd, sizeof dirs - nd, "%s%s", nd ? ":" : "", g->opt.subroutine_path);
    else if (!nd)
        dirs[0] = '\0';
    static const char *forms[] = {"O%04ld", "O%05ld", "O%ld", "o%04ld", "o%05ld", "o%ld"};
    static const char *exts[] = {".nc", ".ngc", ".tap", ".NC", ".NGC", ".TAP"};
    const char *d = dirs;
    char path[4600], base[32];
    while (*d) {
        const char *e = strchr(d, ':');
        size_t dl = e ? (size_t)(e - d) : strlen(d);
        for (size_t fi = 0; fi < sizeof forms / sizeof forms[0]; fi++) {
            snprintf(base, sizeof base, forms[fi], number);
            for (size_t xi = 0; xi < sizeof exts / sizeof exts[0]; xi++) {
                snprintf(path, sizeof path, "%.*s/%s%s", (int)dl, d, base, exts[xi]);
                if (!is_file(path)) continue;
                int t = 0, first = 0;
                fm_status st = load_text(g, path, col, &t);
                if (st) return st;
                if ((st = index_text(g, t, &first))) return st;
                pi = find_program(f, number);
                if (pi < 0 && f->programs[first].number < 0) pi = first;
                if (pi < 0)
                    return gc_fail(g, FM_ERR_INPUT, col, "%s: %s has no program O%04ld", call,
                                   path, number);
                *program = pi;
                return FM_OK;
            }
        }
        d = e ? e + 1 : d + dl;
    }
    return gc_fail(g, FM_ERR_INPUT, col,
                   "%s: no program O%04ld in this file, nor a file O%04ld.nc (.ngc, .tap) in the "
                   "program's folder or on the subroutine path", call, number, number);
}

/* ---- sequence numbers ---- */

static int seq_cmp(const void *a, const void *b)
{
    const long *x = a, *y = b;
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    return x[1] < y[1] ? -1 : x[1] > y[1];
}

fm_status gc_programs_find_sequence(gc_interp *g, int pi, long n, const char *what, int col,
                                    size_t *line)
{
    gc_programs *f = &g->progs;
    gc_program *p = &f->programs[pi];
    const gc_text *x = &f->texts[p->text];
    if (!p->seq_built) {
        size_t cap = 0;
        for (size_t i = p->first; i < p->end; i++) {
            const char *t = x->text;
            size_t a = x->line_start[i], e = x->line_start[i + 1];
            while (a < e && (t[a] == ' ' || t[a] == '\t')) a++;
            if (a < e && t[a] == '/') {
                a++;
                if (a < e && t[a] >= '0' && t[a] <= '9') a++;
            }
            while (a < e && (t[a] == ' ' || t[a] == '\t')) a++;
            if (a >= e || (t[a] != 'N' && t[a] != 'n')) continue;
            a++;
            while (a < e && (t[a] == ' ' || t[a] == '\t')) a++;
            if (a >= e || t[a] < '0' || t[a] > '9') continue;
            long v = 0;
            for (; a < e && t[a] >= '0' && t[a] <= '9'; a++)
                if (v < 100000000L) v = v * 10 + (t[a] - '0');
            if (p->nseq == cap) {
                cap = cap ? cap * 2 : 64;
                long *s = realloc(p->seq, cap * 2 * sizeof *s);
                if (!s) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
                p->seq = s;
            }
            p->seq[2 * p->nseq] = v;
            p->seq[2 * p->nseq + 1] = (long)i;
            p->nseq++;
        }
        if (p->nseq) qsort(p->seq, p->nseq, 2 * sizeof *p->seq, seq_cmp);
        p->seq_built = 1;
    }
    size_t lo = 0, hi = p->nseq;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (p->seq[2 * mid] < n) lo = mid + 1;
        else hi = mid;
    }
    if (lo == p->nseq || p->seq[2 * lo] != n) {
        char pname[32];
        if (p->number >= 0) snprintf(pname, sizeof pname, "program O%04ld", p->number);
        else snprintf(pname, sizeof pname, "this program");
        return gc_fail(g, FM_ERR_INPUT, col, "%s: no sequence number N%ld in %s", what, n, pname);
    }
    *line = (size_t)p->seq[2 * lo + 1];
    return FM_OK;
}

fm_status gc_programs_init(gc_interp *g)
{
    gc_programs *f = &g->progs;
    gc_text *x = &f->texts[0];
    x->name = (char *)g->name;
    x->text = g->text;
    x->len = g->len;
    x->line_start = g->line_start;
    x->nlines = g->nlines;
    f->ntexts = 1;
    f->loaded_bytes = g->len;
    int first;
    fm_status st = index_text(g, 0, &first);
    if (st) return st;
    f->programs[0].first = 0; /* the main program starts with the text */
    return FM_OK;
}

void gc_programs_free(gc_interp *g)
{
    gc_programs *f = &g->progs;
    free(f->texts[0].jump);
    for (int i = 1; i < f->ntexts; i++) {
        free(f->texts[i].name);
        free(f->texts[i].owned);
        free(f->texts[i].line_start);
        free(f->texts[i].jump);
    }
    for (int i = 0; i < f->nprograms; i++) free(f->programs[i].seq);
    free(f->programs);
    memset(f, 0, sizeof *f);
}
