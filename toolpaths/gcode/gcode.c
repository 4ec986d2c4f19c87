/* gcode.c: the RS274NGC interpreter's entry points: options, reading a
 * program file, LinuxCNC's start-up state, and the loop that runs the
 * program line by line (%, block delete, N numbers, then an O-word or a
 * block). The concerns it dispatches to are listed in gcode_internal.h.
 * Semantics follow LinuxCNC 2.9's interpreter; comments name the places where
 * that matters. All state is in program units as LinuxCNC keeps it; motions
 * are converted to machine millimetres when emitted. */
#include "gcode_fanuc.h"
#include "gcode_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

void fm_gcode_options_default(fm_gcode_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->rapid_rate = 5000.0;
    opt->max_program_bytes = (size_t)256 << 20;
    opt->max_iterations = 10000000L;
    opt->max_call_depth = 64;
    opt->peck_retract = 1.0;
    opt->peck_clearance = 1.0;
}

int fm_gcode_dialect_parse(const char *name, fm_gcode_dialect *out)
{
    if (!name) return 0;
    if (!strcasecmp(name, "linuxcnc")) *out = FM_GCODE_LINUXCNC;
    else if (!strcasecmp(name, "fanuc")) *out = FM_GCODE_FANUC;
    else return 0;
    return 1;
}

const char *fm_gcode_dialect_name(fm_gcode_dialect dialect)
{
    return dialect == FM_GCODE_FANUC ? "fanuc" : "linuxcnc";
}

/* ------------------------------------------------------------------ */
/* Running a program                                                   */

static fm_status run(gc_interp *g)
{
    if (g->fanuc) return gc_fanuc_run(g);
    fm_status st;
    gc_block *b = malloc(sizeof *b);
    if (!b) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    int seen_content = 0;
    g->cur = 0;
    /* a subroutine file's lines follow the program's: only a call runs them */
    while (!g->stop && g->cur < (g->depth ? g->nlines_all : g->nlines)) {
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
                g->percent_mode = 1;
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

static fm_status interp_init(gc_interp *g, const char *text, size_t len, const char *name,
                             const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                             fm_error *err)
{
    memset(g, 0, sizeof *g);
    if (opt) g->opt = *opt;
    else fm_gcode_options_default(&g->opt);
    if (g->opt.rapid_rate <= 0) g->opt.rapid_rate = 5000.0;
    if (g->opt.max_iterations <= 0) g->opt.max_iterations = 10000000L;
    if (g->opt.max_call_depth <= 0) g->opt.max_call_depth = 64;
    if (g->opt.max_program_bytes == 0) g->opt.max_program_bytes = (size_t)256 << 20;
    gc_rot_start(g);
    g->err = err;
    g->name = name ? name : "";
    g->text = text;
    g->len = len;
    g->sink = sink;
    g->user = user;
    if (len > g->opt.max_program_bytes)
        return fm_error_at(err, FM_ERR_LIMIT, g->name, 0, 0,
                           "program of %zu bytes is larger than the limit of %zu bytes "
                           "(max_program_bytes)", len, g->opt.max_program_bytes);
    size_t n = 1;
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n') n++;
    g->line_start = malloc((n + 1) * sizeof *g->line_start);
    g->frames = calloc((size_t)g->opt.max_call_depth + 1, sizeof *g->frames);
    if (!g->line_start || !g->frames)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory indexing %zu lines", n);
    size_t k = 0;
    g->line_start[k++] = 0;
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n') g->line_start[k++] = i + 1;
    g->line_start[k] = len;
    g->nlines = n;
    if (n > 1 && g->line_start[n - 1] == len) g->nlines = n - 1; /* trailing newline */
    /* LinuxCNC's start-up state */
    g->unit = g->opt.start_inch ? GC_INCH : 1.0;
    g->plane = GC_PLANE_XY;
    g->absolute = 1;
    g->arc_absolute = 0;
    g->motion = GC_G80;
    g->retract_r = 1; /* rs274 starts in G99 (retract to R) */
    g->cs = 1;
    g->params[GC_PARAM_COORD_SYSTEM] = 1;
    g->nlines_all = g->nlines;
    g->line_name = g->name;
    g->comp.firstmove = 1;
    g->nurbs_order = 3;
    if (g->opt.dialect == FM_GCODE_FANUC) return gc_fanuc_init(g);
    return FM_OK;
}

static void interp_free(gc_interp *g)
{
    gc_fanuc_free(g);
    if (g->frames)
        for (int i = 0; i <= g->depth; i++) gc_frame_free(&g->frames[i]);
    free(g->frames);
    free(g->line_start);
    gc_table_free(&g->globals);
    gc_table_free(&g->subs);
    free(g->ln.s);
    free(g->ln.col);
    free(g->scan.s);
    free(g->scan.col);
    gc_comp_free(&g->comp);
    gc_spline_free(&g->spline);
    free(g->nurbs);
    free(g->tool_edits);
    gc_sources_free(g);
}

static fm_status run_text(const char *text, size_t len, const char *name, int is_file,
                          const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                          fm_gcode_summary *summary, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    if (summary) memset(summary, 0, sizeof *summary);
    if (!text && len) return fm_error_set(err, FM_ERR_INPUT, "no program text");
    gc_interp *g = malloc(sizeof *g);
    if (!g) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_status st = interp_init(g, text ? text : "", len, name, opt, sink, user, err);
    g->program_is_file = is_file;
    if (!st) st = run(g);
    if (summary) {
        summary->motions = g->motion_index;
        summary->lines = g->lines_run;
        summary->seconds = g->t;
        summary->ended_by_m2 = g->ended;
        summary->stopped = g->stop && !g->ended;
    }
    interp_free(g);
    free(g);
    return st;
}

fm_status fm_gcode_run_string(const char *text, size_t len, const char *name,
                              const fm_gcode_options *opt, fm_motion_sink sink, void *user,
                              fm_gcode_summary *summary, fm_error *err)
{
    return run_text(text, len, name, 0, opt, sink, user, summary, err);
}

fm_status fm_gcode_run_file(const char *path, const fm_gcode_options *opt, fm_motion_sink sink,
                            void *user, fm_gcode_summary *summary, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    fm_gcode_options o;
    if (opt) o = *opt;
    else fm_gcode_options_default(&o);
    size_t limit = o.max_program_bytes ? o.max_program_bytes : (size_t)256 << 20;
    FILE *f = fopen(path, "rb");
    if (!f) return fm_error_at(err, FM_ERR_IO, path, 0, 0, "cannot open: %s", strerror(errno));
    struct stat sb;
    if (fstat(fileno(f), &sb) == 0 && S_ISREG(sb.st_mode) && (unsigned long long)sb.st_size > limit) {
        fclose(f);
        return fm_error_at(err, FM_ERR_LIMIT, path, 0, 0,
                           "program of %lld bytes is larger than the limit of %zu bytes "
                           "(max_program_bytes)", (long long)sb.st_size, limit);
    }
    size_t cap = S_ISREG(sb.st_mode) && sb.st_size > 0 ? (size_t)sb.st_size + 1 : 65536, len = 0;
    char *buf = malloc(cap);
    if (!buf) {
        fclose(f);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", path);
    }
    for (;;) {
        if (len == cap) {
            if (cap > limit) break;
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                fclose(f);
                return fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", path);
            }
            buf = nb;
            cap *= 2;
        }
        size_t r = fread(buf + len, 1, cap - len, f);
        if (r == 0) break;
        len += r;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return fm_error_at(err, FM_ERR_IO, path, 0, 0, "read error");
    }
    fm_status st = run_text(buf, len, path, 1, &o, sink, user, summary, err);
    free(buf);
    return st;
}
