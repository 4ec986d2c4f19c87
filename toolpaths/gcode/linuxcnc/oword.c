/* oword.c: O-word control flow: sub/endsub/call/return with
 * arguments in #1-#30 and return values, if/elseif/else/endif, while,
 * do-while, repeat, break and continue. Lines are found by scanning the
 * program text for the O-word of the same name. */
#include "linuxcnc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GC_MAX_REPEATS 1000

enum { KW_SUB, KW_ENDSUB, KW_CALL, KW_RETURN, KW_IF, KW_ELSEIF, KW_ELSE, KW_ENDIF, KW_WHILE,
       KW_ENDWHILE, KW_DO, KW_REPEAT, KW_ENDREPEAT, KW_BREAK, KW_CONTINUE, KW_COUNT };
static const char *kw_names[KW_COUNT] = {"sub", "endsub", "call", "return", "if", "elseif",
                                         "else", "endif", "while", "endwhile", "do", "repeat",
                                         "endrepeat", "break", "continue"};
#define KWM(k) (1u << (k))

typedef struct gc_oword {
    char name[GC_MAX_NAME];
    int kw;
    size_t after; /* index in the line after the keyword */
    int col;
} gc_oword;

/* Parse "o<name> keyword" at s[p] (just past optional '/' and N). Returns 1
 * if it is an O-word line, 0 if not, -1 on error (reported if report). */
static int parse_oword(gc_interp *g, const gc_line *ln, size_t p, gc_oword *o, int report)
{
    const char *s = ln->s;
    if (s[p] != 'o') return 0;
    o->col = gc_col(ln, p);
    p++;
    size_t k = 0;
    if (s[p] == '<') {
        p++;
        while (s[p] && s[p] != '>' && k + 1 < GC_MAX_NAME) o->name[k++] = s[p++];
        if (s[p] != '>' || k == 0) {
            if (report)
                gc_fail(g, FM_ERR_INPUT, o->col, "bad O-word name; expected o<name> or o<number>");
            return -1;
        }
        p++;
    } else {
        while (s[p] == '0' && s[p + 1] >= '0' && s[p + 1] <= '9') p++; /* o0100 is o100 */
        while (s[p] >= '0' && s[p] <= '9' && k + 1 < GC_MAX_NAME) o->name[k++] = s[p++];
        if (k == 0) {
            if (report)
                gc_fail(g, FM_ERR_INPUT, o->col,
                        "O word without a number or <name>; expected e.g. o100 sub");
            return -1;
        }
    }
    o->name[k] = '\0';
    int best = -1;
    size_t best_len = 0;
    for (int i = 0; i < KW_COUNT; i++) {
        size_t n = strlen(kw_names[i]);
        if (!strncmp(s + p, kw_names[i], n) && n > best_len) {
            best = i;
            best_len = n;
        }
    }
    if (best < 0) {
        if (report)
            gc_fail(g, FM_ERR_INPUT, gc_col(ln, p),
                    "o%s: unknown O-word keyword '%.12s'; expected sub, endsub, call, return, if, "
                    "elseif, else, endif, while, endwhile, do, repeat, endrepeat, break or "
                    "continue", o->name, s + p);
        return -1;
    }
    o->kw = best;
    o->after = p + best_len;
    return 1;
}

/* Quick check on the raw text before normalizing a line during scans. */
static int maybe_oword(const gc_interp *g, size_t idx)
{
    const char *t;
    size_t i = 0, e;
    gc_line_text(g, idx, &t, &e);
    while (i < e && (t[i] == ' ' || t[i] == '\t')) i++;
    if (i < e && t[i] == '/') i++;
    while (i < e && (t[i] == ' ' || t[i] == '\t')) i++;
    if (i < e && (t[i] == 'n' || t[i] == 'N')) {
        i++;
        while (i < e && ((t[i] >= '0' && t[i] <= '9') || t[i] == ' ' || t[i] == '\t' || t[i] == '.'))
            i++;
    }
    return i < e && (t[i] == 'o' || t[i] == 'O');
}

static size_t skip_prefix(const gc_line *ln)
{
    size_t p = 0;
    if (ln->s[p] == '/') p++;
    if (ln->s[p] == 'n') {
        p++;
        while ((ln->s[p] >= '0' && ln->s[p] <= '9') || ln->s[p] == '.') p++;
    }
    return p;
}

/* Next (dir +1) or previous (dir -1) line after `from` in [lo, hi) with an
 * O-word of the given name and a keyword in mask. */
static size_t scan_range(gc_interp *g, size_t lo, size_t hi, size_t from, int dir,
                         const char *name, unsigned mask, int *kw)
{
    size_t i = from;
    for (;;) {
        if (dir > 0) {
            if (i + 1 >= hi) return (size_t)-1;
            i++;
        } else {
            if (i <= lo) return (size_t)-1;
            i--;
        }
        if (!maybe_oword(g, i)) continue;
        if (gc_normalize(g, i, &g->scan, 0) != FM_OK) continue;
        gc_oword o;
        if (parse_oword(g, &g->scan, skip_prefix(&g->scan), &o, 0) != 1) continue;
        if (strcmp(o.name, name) || !(mask & KWM(o.kw))) continue;
        if (kw) *kw = o.kw;
        return i;
    }
}

/* The same within the file of line `from` ((size_t)-1: the program, from
 * its first line). */
static size_t scan(gc_interp *g, size_t from, int dir, const char *name, unsigned mask, int *kw)
{
    size_t lo = 0, hi = g->nlines;
    if (from != (size_t)-1) gc_source_range(g, from, &lo, &hi);
    return scan_range(g, lo, hi, from, dir, name, mask, kw);
}

static fm_status count_iteration(gc_interp *g, int col)
{
    if (++g->iterations > g->opt.max_iterations)
        return gc_fail(g, FM_ERR_LIMIT, col,
                       "more than %ld loop iterations and calls; the program may loop forever "
                       "(raise max_iterations if it is meant to)", g->opt.max_iterations);
    return FM_OK;
}

static fm_status read_cond(gc_interp *g, const gc_oword *o, double *v)
{
    size_t p = o->after;
    if (g->ln.s[p] != '[')
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p), "o%s %s: expected a [condition]",
                       o->name, kw_names[o->kw]);
    return gc_read_real(g, &g->ln, &p, v);
}

static fm_status missing(gc_interp *g, const gc_oword *o, const char *what)
{
    return gc_fail(g, FM_ERR_INPUT, o->col, "o%s %s without a matching o%s %s", o->name,
                   kw_names[o->kw], o->name, what);
}

void gc_frame_free(gc_frame *f)
{
    gc_table_free(&f->locals);
    free(f->repeats);
    f->repeats = NULL;
    f->nrepeats = f->caprepeats = 0;
}

static fm_status do_return(gc_interp *g, const gc_oword *o, size_t *next)
{
    if (LC(g)->depth == 0)
        return gc_fail(g, FM_ERR_INPUT, o->col, "o%s %s outside a subroutine call", o->name,
                       kw_names[o->kw]);
    gc_frame *f = &LC(g)->frames[LC(g)->depth];
    /* `return` may carry the label of the block it sits in (LinuxCNC's
     * retval.ngc returns from inside an if); endsub closes its own sub */
    if (o->kw == KW_ENDSUB && strcmp(f->sub, o->name))
        return gc_fail(g, FM_ERR_INPUT, o->col, "o%s %s inside subroutine o%s; expected o%s",
                       o->name, kw_names[o->kw], f->sub, f->sub);
    double v = 0;
    int has_value = g->ln.s[o->after] == '[';
    if (has_value) {
        size_t p = o->after;
        fm_status st = gc_read_real(g, &g->ln, &p, &v);
        if (st) return st;
    }
    fm_status st = gc_leave_level(g);
    if (st) return st;
    memcpy(g->params + 1, f->saved, sizeof f->saved);
    *next = f->return_line;
    gc_frame_free(f);
    LC(g)->depth--;
    LC(g)->value_returned = has_value;
    LC(g)->value = v;
    return FM_OK;
}

static fm_status do_call(gc_interp *g, const gc_oword *o, size_t *next)
{
    fm_status st = count_iteration(g, o->col);
    if (st) return st;
    double line;
    char key[GC_MAX_NAME + 2];
    snprintf(key, sizeof key, "o%s", o->name);
    size_t subline;
    if (!gc_table_get(&LC(g)->subs, key, &line)) {
        /* not seen yet: look for the definition anywhere in the program,
         * then for a file <name>.ngc on the subroutine path */
        int kw;
        subline = scan(g, (size_t)-1, 1, o->name, KWM(KW_SUB), &kw);
        int named = strspn(o->name, "0123456789") != strlen(o->name);
        if (subline == (size_t)-1 && named) {
            int found = 0;
            size_t first = 0;
            if ((st = gc_load_subroutine_file(g, o->name, o->col, &found, &first))) return st;
            if (found) {
                const gc_source *src = &g->sources[g->nsources - 1];
                subline = scan_range(g, first, first + src->nlines, first - 1, 1, o->name,
                                     KWM(KW_SUB), &kw);
                if (subline == (size_t)-1)
                    return gc_fail(g, FM_ERR_INPUT, o->col,
                                   "o<%s> call: %s has no o<%s> sub; expected the subroutine's "
                                   "definition in its file", o->name, src->name, o->name);
            }
        }
        if (subline == (size_t)-1)
            return gc_fail(g, FM_ERR_INPUT, o->col,
                           "o%s call: no subroutine o%s in this program%s; expected an "
                           "o%s sub ... o%s endsub", o->name, o->name,
                           named ? " or on the subroutine path" : "", o->name, o->name);
        gc_table_set(&LC(g)->subs, key, (double)subline);
    } else {
        subline = (size_t)line;
    }
    double args[GC_SUB_PARAMS] = {0};
    int nargs = 0;
    size_t p = o->after;
    while (g->ln.s[p] == '[') {
        if (nargs >= GC_SUB_PARAMS)
            return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p),
                           "o%s call: more than %d arguments", o->name, GC_SUB_PARAMS);
        if ((st = gc_read_real(g, &g->ln, &p, &args[nargs]))) return st;
        nargs++;
    }
    if (g->ln.s[p])
        return gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, p),
                       "o%s call: unexpected '%c'; expected [argument] words", o->name,
                       g->ln.s[p]);
    if (LC(g)->depth + 1 > g->opt.max_call_depth)
        return gc_fail(g, FM_ERR_LIMIT, o->col,
                       "o%s call: calls nested deeper than %d; expected bounded recursion",
                       o->name, g->opt.max_call_depth);
    gc_frame *f = &LC(g)->frames[++LC(g)->depth];
    memset(f, 0, sizeof *f);
    memcpy(f->saved, g->params + 1, sizeof f->saved);
    memcpy(g->params + 1, args, sizeof args);
    f->return_line = g->cur + 1;
    snprintf(f->sub, sizeof f->sub, "%s", o->name);
    *next = subline + 1;
    return FM_OK;
}

static fm_status control(gc_interp *g, gc_oword *o, size_t *next)
{
    fm_status st;
    int kw;
    size_t j;
    double v;
    *next = g->cur + 1;
    switch (o->kw) {
    case KW_SUB: {
        char key[GC_MAX_NAME + 2];
        snprintf(key, sizeof key, "o%s", o->name);
        gc_table_set(&LC(g)->subs, key, (double)g->cur);
        j = scan(g, g->cur, 1, o->name, KWM(KW_ENDSUB), NULL);
        if (j == (size_t)-1) return missing(g, o, "endsub");
        *next = j + 1;
        return FM_OK;
    }
    case KW_ENDSUB:
    case KW_RETURN:
        return do_return(g, o, next);
    case KW_CALL:
        return do_call(g, o, next);
    case KW_IF:
        if ((st = read_cond(g, o, &v))) return st;
        j = g->cur;
        while (v == 0) {
            j = scan(g, j, 1, o->name, KWM(KW_ELSEIF) | KWM(KW_ELSE) | KWM(KW_ENDIF), &kw);
            if (j == (size_t)-1) return missing(g, o, "endif");
            if (kw != KW_ELSEIF) break;
            /* evaluate the elseif condition on its own line */
            g->cur = j;
            gc_set_line(g, j);
            if ((st = gc_normalize(g, j, &g->ln, 1))) return st;
            gc_oword e;
            if (parse_oword(g, &g->ln, skip_prefix(&g->ln), &e, 1) != 1) return g->err->code;
            if ((st = read_cond(g, &e, &v))) return st;
        }
        *next = j + 1;
        return FM_OK;
    case KW_ELSEIF:
    case KW_ELSE:
        j = scan(g, g->cur, 1, o->name, KWM(KW_ENDIF), NULL);
        if (j == (size_t)-1) return missing(g, o, "endif");
        *next = j + 1;
        return FM_OK;
    case KW_ENDIF:
    case KW_DO:
        return FM_OK;
    case KW_WHILE: {
        if ((st = read_cond(g, o, &v))) return st;
        /* a while that closes a do loop follows its do with nothing of the same
         * label between them but break and continue */
        unsigned mask = ((1u << KW_COUNT) - 1) & ~(KWM(KW_BREAK) | KWM(KW_CONTINUE));
        size_t d = scan(g, g->cur, -1, o->name, mask, &kw);
        if (d != (size_t)-1 && kw == KW_DO) {
            if (v != 0) {
                if ((st = count_iteration(g, o->col))) return st;
                *next = d + 1;
            }
            return FM_OK;
        }
        if (v == 0) {
            j = scan(g, g->cur, 1, o->name, KWM(KW_ENDWHILE), NULL);
            if (j == (size_t)-1) return missing(g, o, "endwhile");
            *next = j + 1;
        }
        return FM_OK;
    }
    case KW_ENDWHILE:
        j = scan(g, g->cur, -1, o->name, KWM(KW_WHILE), NULL);
        if (j == (size_t)-1) return missing(g, o, "while");
        if ((st = count_iteration(g, o->col))) return st;
        *next = j;
        return FM_OK;
    case KW_REPEAT: {
        if ((st = read_cond(g, o, &v))) return st;
        gc_frame *f = &LC(g)->frames[LC(g)->depth];
        if (v < 1) {
            j = scan(g, g->cur, 1, o->name, KWM(KW_ENDREPEAT), NULL);
            if (j == (size_t)-1) return missing(g, o, "endrepeat");
            *next = j + 1;
            return FM_OK;
        }
        if (f->nrepeats >= GC_MAX_REPEATS)
            return gc_fail(g, FM_ERR_LIMIT, o->col, "more than %d nested repeat loops",
                           GC_MAX_REPEATS);
        if (f->nrepeats == f->caprepeats) {
            int cap = f->caprepeats ? f->caprepeats * 2 : 4;
            gc_repeat *r = realloc(f->repeats, (size_t)cap * sizeof *r);
            if (!r) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
            f->repeats = r;
            f->caprepeats = cap;
        }
        gc_repeat *r = &f->repeats[f->nrepeats++];
        snprintf(r->label, sizeof r->label, "%s", o->name);
        r->line = g->cur;
        r->left = v > 1e15 ? (long)1e15 : (long)v;
        return FM_OK;
    }
    case KW_ENDREPEAT: {
        gc_frame *f = &LC(g)->frames[LC(g)->depth];
        int i = f->nrepeats - 1;
        while (i >= 0 && strcmp(f->repeats[i].label, o->name)) i--;
        if (i < 0) return missing(g, o, "repeat");
        f->nrepeats = i + 1;
        if (--f->repeats[i].left > 0) {
            if ((st = count_iteration(g, o->col))) return st;
            *next = f->repeats[i].line + 1;
        } else {
            f->nrepeats = i;
        }
        return FM_OK;
    }
    case KW_BREAK:
    case KW_CONTINUE: {
        j = scan(g, g->cur, 1, o->name, KWM(KW_ENDWHILE) | KWM(KW_ENDREPEAT) | KWM(KW_WHILE), &kw);
        if (j == (size_t)-1) return missing(g, o, "endwhile, endrepeat or do-while");
        if (o->kw == KW_CONTINUE) {
            *next = j; /* run the loop's end line: it decides whether to go round again */
            return FM_OK;
        }
        if (kw == KW_ENDREPEAT) {
            gc_frame *f = &LC(g)->frames[LC(g)->depth];
            int i = f->nrepeats - 1;
            while (i >= 0 && strcmp(f->repeats[i].label, o->name)) i--;
            if (i >= 0) f->nrepeats = i;
        }
        *next = j + 1;
        return FM_OK;
    }
    default:
        return FM_OK;
    }
}

fm_status gc_run_oword(gc_interp *g, size_t p, size_t *next)
{
    gc_oword o;
    if (parse_oword(g, &g->ln, p, &o, 1) != 1) {
        fm_status st = g->err ? g->err->code : FM_ERR_INPUT;
        if (!st) st = FM_ERR_INPUT;
        return st;
    }
    return control(g, &o, next);
}
