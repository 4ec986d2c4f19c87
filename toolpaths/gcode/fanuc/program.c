/* program.c: running a program in the Fanuc/Haas dialect: the programs
 * of a text (from an O number, or the text's start, to the next O number or
 * '%'), the line loop (tape '%', block delete '/', sequence numbers N, the
 * program's own O line), macro statements (#i = expression, IF [..] GOTO n,
 * IF [..] THEN #i = .., GOTO n, WHILE [..] DO m ... END m), and calls:
 * M98 P<program> (L repeats, or Fanuc's P<repeats><4 digits>), Haas M97
 * P<sequence number> in the same program, G65 P<program> with arguments on
 * a new level of local variables, M99 (P<n>: back to sequence number n).
 * Called programs are looked up in the texts loaded so far, then as files
 * O<number>.nc, .ngc or .tap in the program's folder and on the subroutine
 * path. */
#include "fanuc.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* ---- texts and programs ---- */

static void use_text(gc_interp *g, int t)
{
    const gc_fanuc_text *x = &FANUC(g)->texts[t];
    FANUC(g)->cur_text = t;
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
    gc_fanuc *f = FANUC(g);
    if (f->nprograms == f->capprograms) {
        int cap = f->capprograms ? f->capprograms * 2 : 8;
        if (cap > 100000)
            return fm_error_set(g->err, FM_ERR_LIMIT, "more than 100000 programs in the texts");
        gc_fanuc_program *p = realloc(f->programs, (size_t)cap * sizeof *p);
        if (!p) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory indexing programs");
        f->programs = p;
        f->capprograms = cap;
    }
    gc_fanuc_program *p = &f->programs[f->nprograms++];
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
    gc_fanuc *f = FANUC(g);
    const gc_fanuc_text *x = &f->texts[t];
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

static int find_program(const gc_fanuc *f, long number)
{
    for (int i = 0; i < f->nprograms; i++)
        if (f->programs[i].number == number) return i;
    return -1;
}

static int is_file(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* Read a subprogram file as a new text. */
static fm_status load_text(gc_interp *g, const char *path, int col, int *text)
{
    gc_fanuc *f = FANUC(g);
    if (f->ntexts >= GC_FANUC_MAX_TEXTS)
        return gc_fail(g, FM_ERR_LIMIT, col, "more than %d subprogram files", GC_FANUC_MAX_TEXTS - 1);
    FILE *fp = fopen(path, "rb");
    if (!fp) return gc_fail(g, FM_ERR_IO, col, "cannot open %s: %s", path, strerror(errno));
    size_t limit = g->opt.max_program_bytes - (f->loaded_bytes < g->opt.max_program_bytes
                                                   ? f->loaded_bytes
                                                   : g->opt.max_program_bytes);
    size_t cap = 65536, n = 0;
    char *buf = malloc(cap);
    if (!buf) {
        fclose(fp);
        return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory reading %s", path);
    }
    for (;;) {
        if (n == cap) {
            if (cap > limit) break;
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                fclose(fp);
                return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory reading %s", path);
            }
            buf = nb;
            cap *= 2;
        }
        size_t r = fread(buf + n, 1, cap - n, fp);
        if (r == 0) break;
        n += r;
    }
    int bad = ferror(fp);
    fclose(fp);
    if (bad || n > limit) {
        free(buf);
        if (bad) return gc_fail(g, FM_ERR_IO, col, "read error in %s", path);
        return gc_fail(g, FM_ERR_LIMIT, col,
                       "subprogram file %s makes the program larger than %zu bytes "
                       "(max_program_bytes)", path, g->opt.max_program_bytes);
    }
    gc_fanuc_text *x = &f->texts[f->ntexts];
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
    fm_status st = gc_index_lines(x->text, x->len, x->name, &x->line_start, &x->nlines, g->err);
    if (st) return st;
    *text = f->ntexts - 1;
    return FM_OK;
}

/* O<number> in the texts loaded so far, else a file on the search path. */
static fm_status locate_program(gc_interp *g, long number, const char *call, int col, int *program)
{
    gc_fanuc *f = FANUC(g);
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

/* The line of N<n> in program pi (the first if there are several). */
static fm_status find_sequence(gc_interp *g, int pi, long n, const char *what, int col, size_t *line)
{
    gc_fanuc *f = FANUC(g);
    gc_fanuc_program *p = &f->programs[pi];
    const gc_fanuc_text *x = &f->texts[p->text];
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

/* ---- calls ---- */

static fm_status count_iteration(gc_interp *g, int col)
{
    if (++g->iterations > g->opt.max_iterations)
        return gc_fail(g, FM_ERR_LIMIT, col,
                       "more than %ld loop iterations, jumps and calls; the program may loop "
                       "forever (raise max_iterations if it is meant to)", g->opt.max_iterations);
    return FM_OK;
}

static void jump(gc_interp *g, size_t line)
{
    g->cur = line;
    FANUC(g)->jumped = 1;
}

fm_status gc_fanuc_call(gc_interp *g, gc_call_kind kind, long number, long repeats,
                        const double args[GC_FANUC_LOCALS], int col)
{
    gc_fanuc *f = FANUC(g);
    char call[48];
    snprintf(call, sizeof call, "%s P%ld", kind == GC_CALL_G65 ? "G65" : kind == GC_CALL_M97
                                                                          ? "M97" : "M98", number);
    fm_status st;
    if (repeats <= 0) return FM_OK; /* L0: not called */
    if ((st = count_iteration(g, col))) return st;
    if (kind == GC_CALL_G65 && f->level >= GC_FANUC_MACRO_DEPTH)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: macro calls nested deeper than %d levels (Fanuc's limit)", call,
                       GC_FANUC_MACRO_DEPTH);
    if (kind != GC_CALL_G65 && f->sub_depth >= GC_FANUC_SUB_DEPTH)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: subprograms nested deeper than %d levels (Fanuc's limit)", call,
                       GC_FANUC_SUB_DEPTH);
    int program;
    size_t start;
    if (kind == GC_CALL_M97) {
        program = f->cur_program;
        if ((st = find_sequence(g, program, number, call, col, &start))) return st;
    } else {
        if ((st = locate_program(g, number, call, col, &program))) return st;
        start = f->programs[program].first;
    }
    gc_fanuc_frame *fr = &f->frames[f->nframes++];
    fr->kind = kind;
    fr->caller_program = f->cur_program;
    fr->return_line = g->cur + 1;
    fr->program = program;
    fr->start_line = start;
    fr->repeats_left = repeats;
    fr->col = col;
    if (kind == GC_CALL_G65) {
        f->level++;
        for (int i = 0; i < GC_FANUC_LOCALS; i++) f->locals[f->level][i] = GC_VACANT;
        if (args)
            for (int i = 1; i <= 26; i++) f->locals[f->level][i] = args[i];
    } else {
        f->sub_depth++;
    }
    f->cur_program = program;
    use_text(g, f->programs[program].text);
    jump(g, start);
    return FM_OK;
}

fm_status gc_fanuc_return(gc_interp *g, int has_p, long p, int col)
{
    gc_fanuc *f = FANUC(g);
    fm_status st;
    size_t line;
    if (f->nframes == 0) {
        if (!has_p) {
            /* M99 in the main program: a control repeats it for ever; one
             * pass is what a simulation shows */
            g->ended = 1;
            g->stop = 1;
            return FM_OK;
        }
        if ((st = count_iteration(g, col))) return st;
        if ((st = find_sequence(g, f->cur_program, p, "M99 P", col, &line))) return st;
        jump(g, line);
        return FM_OK;
    }
    gc_fanuc_frame *fr = &f->frames[f->nframes - 1];
    if (--fr->repeats_left > 0) {
        if ((st = count_iteration(g, col))) return st;
        jump(g, fr->start_line);
        return FM_OK;
    }
    f->nframes--;
    if (fr->kind == GC_CALL_G65) f->modal[f->level--].on = 0; /* its G66 ends with it */
    else f->sub_depth--;
    f->cur_program = fr->caller_program;
    use_text(g, f->programs[f->cur_program].text);
    if (has_p) {
        if ((st = find_sequence(g, f->cur_program, p, "M99 P", col, &line))) return st;
        jump(g, line);
    } else {
        jump(g, fr->return_line);
    }
    return FM_OK;
}

void gc_fanuc_raw_line(const gc_interp *g, const char **text, size_t *len)
{
    size_t a = g->line_start[g->cur], b = g->line_start[g->cur + 1];
    *text = g->text + a;
    *len = b - a;
}

/* ---- macro statements ---- */

/* Does the line idx hold a DO m (WHILE [..] DO m, or DO m) or an END m? */
enum { LOOP_NONE, LOOP_DO, LOOP_END };

static int loop_statement(gc_interp *g, size_t idx, int *m)
{
    const char *t = g->text;
    size_t a = g->line_start[idx], e = g->line_start[idx + 1];
    int maybe = 0;
    for (size_t i = a; i + 1 < e; i++) {
        char c = (char)(t[i] | 0x20);
        if ((c == 'd' && (t[i + 1] | 0x20) == 'o') || (c == 'e' && (t[i + 1] | 0x20) == 'n')) {
            maybe = 1;
            break;
        }
    }
    if (!maybe || gc_normalize(g, idx, &g->scan, 0) != FM_OK) return LOOP_NONE;
    const char *s = g->scan.s;
    size_t p = 0;
    if (s[p] == '/') {
        p++;
        if (s[p] >= '0' && s[p] <= '9') p++;
    }
    if (s[p] == 'n') {
        p++;
        while (s[p] >= '0' && s[p] <= '9') p++;
    }
    int kind = LOOP_NONE;
    if (!strncmp(s + p, "while[", 6)) {
        p += 5;
        int depth = 0;
        do {
            if (s[p] == '[') depth++;
            else if (s[p] == ']') depth--;
            p++;
        } while (s[p] && depth > 0);
        if (strncmp(s + p, "do", 2)) return LOOP_NONE;
        p += 2;
        kind = LOOP_DO;
    } else if (!strncmp(s + p, "do", 2)) {
        p += 2;
        kind = LOOP_DO;
    } else if (!strncmp(s + p, "end", 3)) {
        p += 3;
        kind = LOOP_END;
    } else {
        return LOOP_NONE;
    }
    if (s[p] < '0' || s[p] > '9') return LOOP_NONE;
    int v = 0;
    while (s[p] >= '0' && s[p] <= '9' && v < 1000) v = v * 10 + (s[p++] - '0');
    if (s[p]) return LOOP_NONE;
    *m = v;
    return kind;
}

/* Where the loop statement on the current line jumps: dir +1 (a WHILE
 * whose condition fails) past its END m, dir -1 (an END m) to its DO m. The
 * scan runs once per line; later turns of the loop read the answer. */
static fm_status loop_target(gc_interp *g, int m, int dir, int col, size_t *to)
{
    gc_fanuc *f = FANUC(g);
    gc_fanuc_text *x = &f->texts[f->cur_text];
    if (!x->loop_jump) {
        x->loop_jump = calloc(x->nlines + 1, sizeof *x->loop_jump);
        if (!x->loop_jump) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    }
    size_t cur = g->cur;
    if (x->loop_jump[cur]) {
        *to = x->loop_jump[cur] - 1;
        return FM_OK;
    }
    const gc_fanuc_program *pr = &f->programs[f->cur_program];
    if (dir > 0) {
        for (size_t i = cur + 1; i < pr->end; i++) {
            int mm;
            if (loop_statement(g, i, &mm) == LOOP_END && mm == m) {
                *to = i + 1;
                x->loop_jump[cur] = *to + 1;
                return FM_OK;
            }
        }
        return gc_fail(g, FM_ERR_INPUT, col, "WHILE [..] DO %d without a matching END %d", m, m);
    }
    for (size_t i = cur; i-- > pr->first;) {
        int mm;
        if (loop_statement(g, i, &mm) == LOOP_DO && mm == m) {
            *to = i;
            x->loop_jump[cur] = *to + 1;
            return FM_OK;
        }
    }
    return gc_fail(g, FM_ERR_INPUT, col, "END %d without a matching DO %d before it", m, m);
}

static fm_status loop_id(gc_interp *g, size_t *p, int *m)
{
    const char *s = g->ln.s;
    size_t at = *p;
    if (s[*p] < '0' || s[*p] > '9')
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, at), "expected a loop number 1, 2 or 3");
    int v = 0;
    while (s[*p] >= '0' && s[*p] <= '9' && v < 1000) v = v * 10 + (s[(*p)++] - '0');
    if (v < 1 || v > 3)
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, at),
                       "loop number %d; expected 1, 2 or 3 (Fanuc's DO/END identifiers)", v);
    if (s[*p])
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, *p),
                       "unexpected '%c' after the loop number; expected the end of the block",
                       s[*p]);
    *m = v;
    return FM_OK;
}

static fm_status expect_end(gc_interp *g, size_t p, const char *what)
{
    if (g->ln.s[p])
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p),
                       "unexpected '%c' after %s; expected the end of the block", g->ln.s[p], what);
    return FM_OK;
}

static fm_status assignment(gc_interp *g, size_t *p)
{
    const gc_line *ln = &g->ln;
    size_t at = *p;
    long n;
    fm_status st = gc_fanuc_read_var_ref(g, ln, p, &n);
    if (st) return st;
    if (ln->s[*p] != '=')
        return gc_fail(g, FM_ERR_INPUT, gc_col(ln, *p),
                       "#%ld outside an assignment; expected '=' after it", n);
    (*p)++;
    double v;
    if ((st = gc_fanuc_read_expr(g, ln, p, &v))) return st;
    return gc_fanuc_set_var(g, n, v, gc_col(ln, at));
}

static fm_status go_to(gc_interp *g, size_t p, int col)
{
    double v;
    fm_status st = gc_fanuc_read_expr(g, &g->ln, &p, &v);
    if (st) return st;
    if ((st = expect_end(g, p, "GOTO n"))) return st;
    if (isnan(v) || v != floor(v) || v < 0 || v > 99999999)
        return gc_fail(g, FM_ERR_INPUT, col, "GOTO %g: expected a sequence number", v);
    size_t line;
    if ((st = count_iteration(g, col))) return st;
    if ((st = find_sequence(g, FANUC(g)->cur_program, (long)v, "GOTO", col, &line))) return st;
    jump(g, line);
    return FM_OK;
}

static fm_status condition(gc_interp *g, size_t *p, int *truth)
{
    if (g->ln.s[*p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, *p), "expected a [condition]");
    double v;
    fm_status st = gc_fanuc_read_expr(g, &g->ln, p, &v);
    if (st) return st;
    *truth = !isnan(v) && v != 0;
    return FM_OK;
}

/* A macro statement at g->ln.s[p]: 1 if it was one (run, or failed with
 * *st set), 0 if the line is an NC block. */
static int macro_statement(gc_interp *g, size_t p, fm_status *st)
{
    const char *s = g->ln.s;
    int col = gc_col(&g->ln, p);
    int truth = 0, m = 0;
    *st = FM_OK;
    if (s[p] == '#') {
        while (!*st && s[p] == '#') *st = assignment(g, &p);
        if (!*st) *st = expect_end(g, p, "the assignment");
        return 1;
    }
    if (!strncmp(s + p, "if", 2) && s[p + 2] == '[') {
        p += 2;
        if ((*st = condition(g, &p, &truth))) return 1;
        if (!strncmp(s + p, "goto", 4)) {
            if (truth) *st = go_to(g, p + 4, col);
            return 1;
        }
        if (!strncmp(s + p, "then", 4)) {
            p += 4;
            if (s[p] != '#') {
                *st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p),
                              "IF [..] THEN: expected an assignment #i = ... after THEN");
                return 1;
            }
            if (truth) {
                *st = assignment(g, &p);
                if (!*st) *st = expect_end(g, p, "the assignment");
            }
            return 1;
        }
        *st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p),
                      "IF [..]: expected GOTO n or THEN #i = ... after the condition");
        return 1;
    }
    if (!strncmp(s + p, "goto", 4)) {
        *st = go_to(g, p + 4, col);
        return 1;
    }
    if (!strncmp(s + p, "while", 5) && s[p + 5] == '[') {
        p += 5;
        if ((*st = condition(g, &p, &truth))) return 1;
        if (strncmp(s + p, "do", 2)) {
            *st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p),
                          "WHILE [..]: expected DO m after the condition");
            return 1;
        }
        p += 2;
        if ((*st = loop_id(g, &p, &m))) return 1;
        if (!truth) {
            /* past the matching END m */
            size_t to;
            if (!(*st = loop_target(g, m, +1, col, &to))) jump(g, to);
        }
        return 1;
    }
    if (!strncmp(s + p, "do", 2) && s[p + 2] >= '0' && s[p + 2] <= '9') {
        p += 2;
        *st = loop_id(g, &p, &m); /* DO m without WHILE: a loop left only by GOTO */
        return 1;
    }
    if (!strncmp(s + p, "end", 3) && s[p + 3] >= '0' && s[p + 3] <= '9') {
        p += 3;
        if ((*st = loop_id(g, &p, &m))) return 1;
        size_t to;
        if ((*st = loop_target(g, m, -1, col, &to))) return 1;
        if ((*st = count_iteration(g, col))) return 1;
        jump(g, to);
        return 1;
    }
    return 0;
}

/* ---- the line loop ---- */

static fm_status fanuc_run(gc_interp *g)
{
    gc_fanuc *f = FANUC(g);
    fm_status st = FM_OK;
    gc_fanuc_block *fb = malloc(sizeof *fb);
    if (!fb) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    f->cur_program = 0;
    g->cur = 0;
    while (!g->stop) {
        const gc_fanuc_program *pr = &f->programs[f->cur_program];
        if (g->cur >= pr->end || g->cur >= g->nlines) {
            if (f->nframes) {
                g->lineno = (int)(pr->end > 0 ? pr->end : 1);
                st = gc_fail(g, FM_ERR_INPUT, 1,
                             "end of subprogram O%04ld without M99; expected M99 to return to "
                             "the caller (called at column %d)",
                             pr->number < 0 ? 0 : pr->number, f->frames[f->nframes - 1].col);
                goto out;
            }
            if (g->cur < g->nlines) {
                long number = 0;
                if (classify(g->text, g->line_start[g->cur], g->line_start[g->cur + 1],
                             &number) == RAW_PERCENT)
                    g->ended = 1; /* the closing % ends the tape */
            }
            break;
        }
        g->lineno = (int)g->cur + 1;
        g->lines_run++;
        f->jumped = 0;
        if ((st = gc_normalize(g, g->cur, &g->ln, 1))) goto out;
        const char *s = g->ln.s;
        if (g->ln.n == 0) {
            g->cur++;
            continue;
        }
        if (s[0] == '%') {
            if (g->ln.n > 1) {
                st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, 1),
                             "text after '%%'; expected '%%' alone on its line");
                goto out;
            }
            g->cur++;
            continue;
        }
        size_t p = 0;
        if (s[p] == '/') {
            p++;
            if (s[p] >= '1' && s[p] <= '9') p++;
            if (g->opt.block_delete) {
                g->cur++;
                continue;
            }
        }
        if ((s[p] == 'o' || s[p] == ':') && s[p + 1] >= '0' && s[p + 1] <= '9') {
            /* the program's own number */
            size_t q = p + 1;
            while (s[q] >= '0' && s[q] <= '9') q++;
            if (s[q]) {
                st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, q),
                             "text after the program number; expected O<number> alone on its "
                             "line (a comment may follow)");
                goto out;
            }
            g->cur++;
            continue;
        }
        g->cur_block = -1;
        if (s[p] == 'n') {
            size_t at = p++;
            long n = 0;
            int digits = 0;
            while (s[p] >= '0' && s[p] <= '9') {
                if (n < 100000000L) n = n * 10 + (s[p] - '0');
                p++;
                digits++;
            }
            if (!digits) {
                st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, at),
                             "N without a number; expected N followed by digits");
                goto out;
            }
            g->cur_block = n;
            f->sequence = n;
        }
        if (!macro_statement(g, p, &st)) {
            memset(fb, 0, offsetof(gc_fanuc_block, args));
            memset(&fb->b, 0, offsetof(gc_block, assign));
            for (int i = 0; i < GC_FANUC_LOCALS; i++) fb->args[i] = GC_VACANT;
            fb->b.n = g->cur_block;
            if ((st = gc_fanuc_parse_block(g, p, fb))) goto out;
            st = gc_fanuc_exec_block(g, fb);
        }
        if (st) goto out;
        if (!f->jumped) g->cur++;
    }
    /* the program's end: what compensation holds leaves (unless the sink
     * stopped the run) */
    st = g->stop && !g->ended ? FM_OK : gc_comp_c_finish(g);
out:
    free(fb);
    use_text(g, 0);
    return st;
}

static fm_status fanuc_init(gc_interp *g)
{
    gc_fanuc *f = calloc(1, sizeof *f);
    if (!f) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    g->dialect = f;
    for (int l = 0; l < GC_FANUC_LEVELS; l++)
        for (int i = 0; i < GC_FANUC_LOCALS; i++) f->locals[l][i] = GC_VACANT;
    for (size_t i = 0; i < sizeof f->common / sizeof f->common[0]; i++) f->common[i] = GC_VACANT;
    gc_fanuc_text *x = &f->texts[0];
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
    /* Fanuc's power-on state: G00 G17 G90 G94 G40 G49 G80 G98 G54 G15 G50 G69 */
    f->group1 = 0;
    g->motion = GC_G0;
    g->retract_r = 0;
    f->tool_length_mode = GC_G49;
    g->frame.scale = 1;
    /* the machine has returned to its (first) reference point after power-on */
    for (int i = 0; i < 3; i++) g->pos[i] = g->frame.prog[i] = g->opt.reference_points[0][i] / g->unit;
    gc_to_machine(g, g->pos, g->mpos);
    memcpy(g->canon, g->mpos, sizeof g->canon);
    return FM_OK;
}

static void fanuc_release(gc_interp *g)
{
    gc_fanuc *f = FANUC(g);
    if (!f) return;
    free(f->texts[0].loop_jump);
    for (int i = 1; i < f->ntexts; i++) {
        free(f->texts[i].name);
        free(f->texts[i].owned);
        free(f->texts[i].line_start);
        free(f->texts[i].loop_jump);
    }
    for (int i = 0; i < f->nprograms; i++) free(f->programs[i].seq);
    free(f->programs);
    free(f);
    g->dialect = NULL;
}

const gc_front_end gc_fanuc_front = {"fanuc", fanuc_init, fanuc_run, fanuc_release};
