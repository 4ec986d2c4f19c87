/* run.c: the LinuxCNC front end: its state, rs274's start-up modes, and the
 * loop that runs the program line by line (%, block delete, N numbers, then
 * an O-word or a block). Semantics follow LinuxCNC 2.9's interpreter. */
#include "linuxcnc.h"

#include <stdlib.h>
#include <string.h>

static fm_status run(gc_interp *g)
{
    gc_lcnc *lc = LC(g);
    fm_status st;
    gc_block *b = malloc(sizeof *b);
    if (!b) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    int seen_content = 0;
    g->cur = 0;
    /* a subroutine file's lines follow the program's: only a call runs them */
    while (!g->stop && g->cur < (lc->depth ? g->nlines_all : g->nlines)) {
        gc_set_line(g, g->cur);
        g->lines_run++;
        if ((st = gc_normalize(g, g->cur, &g->ln, 1))) goto out;
        const char *s = g->ln.s;
        if (g->ln.n == 0) {
            gc_emit_message(g, &g->ln);
            g->cur++;
            continue;
        }
        if (s[0] == '%') {
            if (g->ln.n > 1) {
                st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, 1),
                             "text after '%%'; expected '%%' alone on its line");
                goto out;
            }
            if (!seen_content) {
                lc->percent_mode = 1;
                seen_content = 1;
                g->cur++;
                continue;
            }
            g->ended = 1; /* the closing % ends the program, as in LinuxCNC */
            if ((st = gc_comp_finish(g))) goto out;
            break;
        }
        seen_content = 1;
        size_t p = 0;
        if (s[p] == '/') {
            if (g->opt.block_delete) {
                g->cur++;
                continue;
            }
            p++;
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
            if (s[p] == '.') {
                p++;
                while (s[p] >= '0' && s[p] <= '9') p++;
            }
            if (!digits) {
                st = gc_fail(g, FM_ERR_INPUT, gc_col(&g->ln, at),
                             "N word without a number; expected N followed by digits");
                goto out;
            }
            g->cur_block = n;
        }
        size_t next = g->cur + 1;
        if (s[p] == 'o') {
            if ((st = gc_run_oword(g, p, &next))) goto out;
        } else {
            memset(b, 0, offsetof(gc_block, assign));
            b->nassign = 0;
            b->n = g->cur_block;
            if ((st = gc_parse_block(g, p, b))) goto out;
            if ((st = gc_exec_block(g, b))) goto out;
        }
        g->cur = next;
    }
    st = g->stop ? FM_OK : gc_comp_finish(g);
out:
    free(b);
    return st;
}

static fm_status init(gc_interp *g)
{
    gc_lcnc *lc = calloc(1, sizeof *lc);
    if (!lc) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    g->dialect = lc;
    lc->frames = calloc((size_t)g->opt.max_call_depth + 1, sizeof *lc->frames);
    if (!lc->frames) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    g->retract_r = 1; /* rs274 starts in G99 (retract to R) */
    return FM_OK;
}

static void release(gc_interp *g)
{
    gc_lcnc *lc = LC(g);
    if (!lc) return;
    if (lc->frames)
        for (int i = 0; i <= lc->depth; i++) gc_frame_free(&lc->frames[i]);
    free(lc->frames);
    gc_table_free(&lc->globals);
    gc_table_free(&lc->subs);
    free(lc);
    g->dialect = NULL;
}

const gc_front_end gc_linuxcnc_front = {"linuxcnc", init, run, release};
