/* state.c: M70-M73 (saving and restoring modal state per call
 * level, LinuxCNC's list of what is saved) and the (debug, ...) /
 * (msg, ...) messages with LinuxCNC's parameter substitution. */
#include "linuxcnc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void save_state(const gc_interp *g, gc_modal_state *s)
{
    s->unit = g->unit;
    s->plane = g->plane;
    s->absolute = g->absolute;
    s->arc_absolute = g->arc_absolute;
    s->inverse_time = g->inverse_time;
    s->cs = g->cs;
    s->retract_r = g->retract_r;
    memcpy(s->tlo, g->tlo, sizeof s->tlo);
    s->feed = g->feed;
    s->speed = g->speed;
    s->spindle_dir = g->spindle_dir;
    s->coolant = g->coolant;
}

/* Restore in the order LinuxCNC executes the codes: units first, so that
 * the saved lengths (kept in the units they were saved in) convert. */
static void restore_state(gc_interp *g, const gc_modal_state *s)
{
    gc_set_units(g, s->unit);
    g->plane = (gc_plane)s->plane;
    g->absolute = s->absolute;
    g->arc_absolute = s->arc_absolute;
    g->inverse_time = s->inverse_time;
    if (s->cs != g->cs) gc_set_g5x(g, s->cs);
    g->retract_r = s->retract_r;
    double tlo[3];
    for (int i = 0; i < 3; i++) tlo[i] = s->tlo[i] * s->unit / g->unit;
    gc_set_tlo(g, tlo);
    g->feed = s->feed;
    g->speed = s->speed;
    g->spindle_dir = s->spindle_dir;
    g->coolant = s->coolant;
}

fm_status gc_exec_modal_state(gc_interp *g, int m, int col)
{
    gc_frame *f = &LC(g)->frames[LC(g)->depth];
    switch (m) {
    case 70:
    case 73:
        save_state(g, &f->state);
        f->state_valid = 1;
        f->state_autorestore = m == 73 && LC(g)->depth > 0;
        return FM_OK;
    case 71:
        f->state_valid = 0;
        f->state_autorestore = 0;
        return FM_OK;
    case 72:
        if (!f->state_valid)
            return gc_fail(g, FM_ERR_INPUT, col,
                           "M72: no modal state saved at this call level; expected M70 or M73 "
                           "first (M71 forgets it)");
        restore_state(g, &f->state);
        return FM_OK;
    default:
        return FM_OK;
    }
}

fm_status gc_leave_level(gc_interp *g)
{
    gc_frame *f = &LC(g)->frames[LC(g)->depth];
    if (f->state_valid && f->state_autorestore) restore_state(g, &f->state);
    f->state_valid = f->state_autorestore = 0;
    return FM_OK;
}

/* ---------------------------------------------------------- messages -- */

typedef struct msg_buf {
    char *s;
    size_t n, cap;
    int failed;
} msg_buf;

static void put(msg_buf *b, const char *s, size_t n)
{
    if (b->failed) return;
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->n + n + 1) cap *= 2;
        char *p = realloc(b->s, cap);
        if (!p) {
            b->failed = 1;
            return;
        }
        b->s = p;
        b->cap = cap;
    }
    memcpy(b->s + b->n, s, n);
    b->n += n;
    b->s[b->n] = '\0';
}

static void put_value(msg_buf *b, double v)
{
    char num[64];
    int k = snprintf(num, sizeof num, "%f", v);
    put(b, num, k > 0 ? (size_t)k : 0);
}

/* #<name> and #number become their values (printf's %f, as LinuxCNC);
 * an unknown name becomes ######; any other '#' stays. */
static void substitute(gc_interp *g, const char *t, size_t n, msg_buf *b)
{
    size_t i = 0;
    while (i < n) {
        if (t[i] != '#') {
            size_t j = i;
            while (j < n && t[j] != '#') j++;
            put(b, t + i, j - i);
            i = j;
            continue;
        }
        if (i + 1 < n && t[i + 1] == '<') {
            size_t j = i + 2;
            char name[GC_MAX_NAME];
            size_t k = 0;
            while (j < n && t[j] != '>') {
                char c = t[j++];
                if (c == ' ' || c == '\t') continue;
                if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
                if (k + 1 < sizeof name) name[k++] = c;
            }
            if (j < n) {
                name[k] = '\0';
                double v;
                if (k && gc_get_named(g, name, &v)) put_value(b, v);
                else put(b, "######", 6);
                i = j + 1;
                continue;
            }
        } else if (i + 1 < n && t[i + 1] >= '0' && t[i + 1] <= '9') {
            size_t j = i + 1;
            long num = 0;
            while (j < n && t[j] >= '0' && t[j] <= '9') {
                if (num < 100000) num = num * 10 + (t[j] - '0');
                j++;
            }
            if (num >= 1 && num < GC_NUM_PARAMS) put_value(b, gc_param_value(g, (int)num));
            else put(b, "######", 6);
            i = j;
            continue;
        }
        put(b, "#", 1);
        i++;
    }
}

void gc_emit_message(gc_interp *g, const gc_line *ln)
{
    if (!ln->msg_kind || !g->opt.message) return;
    msg_buf b = {NULL, 0, 0, 0};
    put(&b, "", 0);
    if (ln->msg_kind == 1) substitute(g, ln->msg, ln->msg_len, &b);
    else put(&b, ln->msg, ln->msg_len);
    if (!b.failed) g->opt.message(g->opt.message_user, g->lineno, b.s);
    free(b.s);
}
