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

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
        if ((st = gc_programs_find_sequence(g, program, number, call, col, &start))) return st;
    } else {
        if ((st = gc_programs_locate(g, number, call, col, &program))) return st;
        start = g->progs.programs[program].first;
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
    gc_programs_use_text(g, g->progs.programs[program].text);
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
        if ((st = gc_programs_find_sequence(g, f->cur_program, p, "M99 P", col, &line))) return st;
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
    gc_programs_use_text(g, g->progs.programs[f->cur_program].text);
    if (has_p) {
        if ((st = gc_programs_find_sequence(g, f->cur_program, p, "M99 P", col, &line))) return st;
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
    gc_text *x = &g->progs.texts[g->progs.cur_text];
    if (!x->jump) {
        x->jump = calloc(x->nlines + 1, sizeof *x->jump);
        if (!x->jump) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    }
    size_t cur = g->cur;
    if (x->jump[cur]) {
        *to = x->jump[cur] - 1;
        return FM_OK;
    }
    const gc_program *pr = &g->progs.programs[f->cur_program];
    if (dir > 0) {
        for (size_t i = cur + 1; i < pr->end; i++) {
            int mm;
            if (loop_statement(g, i, &mm) == LOOP_END && mm == m) {
                *to = i + 1;
                x->jump[cur] = *to + 1;
                return FM_OK;
            }
        }
        return gc_fail(g, FM_ERR_INPUT, col, "WHILE [..] DO %d without a matching END %d", m, m);
    }
    for (size_t i = cur; i-- > pr->first;) {
        int mm;
        if (loop_statement(g, i, &mm) == LOOP_DO && mm == m) {
            *to = i;
            x->jump[cur] = *to + 1;
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
    if ((st = gc_programs_find_sequence(g, FANUC(g)->cur_program, (long)v, "GOTO", col, &line))) return st;
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
        const gc_program *pr = &g->progs.programs[f->cur_program];
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
                if (gc_programs_percent_line(g, g->cur))
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
    gc_programs_use_text(g, 0);
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
    fm_status st = gc_programs_init(g);
    if (st) return st;
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
    gc_programs_free(g);
    free(f);
    g->dialect = NULL;
}

const gc_front_end gc_fanuc_front = {"fanuc", fanuc_init, fanuc_run, fanuc_release};
