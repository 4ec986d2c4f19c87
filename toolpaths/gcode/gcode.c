/* gcode.c: the RS274NGC interpreter: blocks (words, modal groups, execution
 * order), motions (lines, arcs, helices, dwells, canned cycles, G28/G30,
 * G53), offsets (G5x, G10, G92, G43), O-word control flow, and the public
 * entry points. Semantics follow LinuxCNC 2.9's interpreter; comments name
 * the places where that matters. All state is in program units as LinuxCNC
 * keeps it; motions are converted to machine millimetres when emitted. */
#include "gcode_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define GC_PI 3.14159265358979323846
#define GC_MAX_ASSIGN 256  /* parameter assignments on one line */
#define GC_MAX_REPEATS 1000
#define GC_INCH 25.4

void fm_gcode_options_default(fm_gcode_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->rapid_rate = 5000.0;
    opt->max_program_bytes = (size_t)256 << 20;
    opt->max_iterations = 10000000L;
    opt->max_call_depth = 64;
}

/* ------------------------------------------------------------------ */
/* Blocks                                                              */

typedef struct gc_assign {
    int num;
    char name[GC_MAX_NAME];
    double v;
} gc_assign;

typedef struct gc_block {
    int has[26];
    double v[26];
    int col[26];
    int g[16], gcol[16], ng;
    int m[8], mcol[8], nm;
    long n;
    gc_assign assign[GC_MAX_ASSIGN];
    int nassign;
} gc_block;

#define L(c) ((c) - 'a')
#define HAS(b, c) ((b)->has[L(c)])
#define VAL(b, c) ((b)->v[L(c)])
#define COL(b, c) ((b)->col[L(c)])

/* Modal group of a G code (x10), -1 if unknown. Codes LinuxCNC knows but
 * this interpreter refuses get group 99 and a message in refused_g(). */
static int g_group(int code)
{
    switch (code) {
    case 0: case 10: case 20: case 30: case 730: case 800: case 810: case 820: case 830:
    case 840: case 850: case 860: case 870: case 880: case 890:
        return 1;
    case 40: case 100: case 280: case 281: case 300: case 301: case 530: case 920: case 921:
    case 922: case 923:
        return 0;
    case 170: case 180: case 190: return 2;
    case 900: case 910: return 3;
    case 901: case 911: return 4;
    case 930: case 940: case 950: return 5;
    case 200: case 210: return 6;
    case 400: case 410: case 420: case 411: case 421: return 7;
    case 430: case 431: case 490: return 8;
    case 980: case 990: return 10;
    case 540: case 550: case 560: case 570: case 580: case 590: case 591: case 592: case 593:
        return 12;
    case 610: case 611: case 640: return 13;
    case 960: case 970: return 14;
    case 50: case 51: case 52: case 53: case 70: case 80: case 330: case 331: case 382: case 383:
    case 384: case 385: case 432: case 520: case 740: case 760: case 171: case 181: case 191:
    case 282: case 302:
        return 99;
    default: return -1;
    }
}

static const char *refused_g(int code)
{
    switch (code) {
    case 410: case 420: case 411: case 421:
        return "cutter radius compensation is not supported; give the toolpath of the tool "
               "centre (G40) instead";
    case 50: case 51: case 52: case 53: return "splines and NURBS (G5.x) are not supported";
    case 70: case 80: return "lathe diameter/radius mode is not supported (milling only)";
    case 330: case 331: case 760: case 740:
        return "spindle-synchronized motion is not supported";
    case 382: case 383: case 384: case 385: return "probing is not supported by a simulation";
    case 432: return "G43.2 (additional tool offsets) is not supported; use G43 H or G43.1";
    case 520: return "G52 local offsets are not supported; use G92";
    case 171: case 181: case 191: return "UVW planes are not supported";
    case 282: case 302: return "homing (G28.2/G30.2) is not supported";
    case 950: return "G95 (feed per revolution) is not supported; use G94 or G93";
    default: return "is not supported";
    }
}

static void g_name(int code, char *buf, size_t n)
{
    if (code % 10) snprintf(buf, n, "G%d.%d", code / 10, code % 10);
    else snprintf(buf, n, "G%d", code / 10);
}

static fm_status parse_block(gc_interp *g, size_t p, gc_block *b)
{
    const gc_line *ln = &g->ln;
    const char *s = ln->s;
    while (s[p]) {
        char c = s[p];
        size_t at = p;
        if (c == '#') {
            if (b->nassign >= GC_MAX_ASSIGN)
                return gc_fail(g, FM_ERR_LIMIT, gc_col(ln, at),
                               "more than %d parameter assignments on one line", GC_MAX_ASSIGN);
            gc_assign *a = &b->assign[b->nassign];
            fm_status st = gc_read_param_ref(g, ln, &p, &a->num, a->name);
            if (st) return st;
            if (s[p] != '=')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, p),
                               "parameter outside an assignment; expected '=' after #%s",
                               a->name[0] ? a->name : "N");
            p++;
            st = gc_read_real(g, ln, &p, &a->v);
            if (st) return st;
            b->nassign++;
            continue;
        }
        if (c < 'a' || c > 'z' || !strchr("abcdfghijklmpqrstuvwxyz", c)) {
            if (c == 'n')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "N word after other words; expected the line number first");
            if (c == 'o')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "O word after other words; expected it at the start of the line");
            if (c == '@' || c == '^')
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "polar coordinates ('%c') are not supported", c);
            return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                           "unexpected '%c'; expected a word letter (G, M, X, ...) or #parameter", c);
        }
        p++;
        double v;
        fm_status st = gc_read_real(g, ln, &p, &v);
        if (st) return st;
        if (c == 'g') {
            double t = v * 10.0;
            double r = floor(t + 0.5);
            char name[32];
            if (fabs(t - r) > 1e-6 || r < 0 || r > 10000)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "G%g: not a G code; expected a number with at most one decimal", v);
            int code = (int)r;
            g_name(code, name, sizeof name);
            int grp = g_group(code);
            if (grp < 0)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: unknown G code", name);
            if (grp == 99)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: %s", name, refused_g(code));
            if (grp == 7 && code != 400)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: %s", name, refused_g(code));
            if (code == 950)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: %s", name, refused_g(code));
            for (int i = 0; i < b->ng; i++)
                if (g_group(b->g[i]) == grp) {
                    char other[32];
                    g_name(b->g[i], other, sizeof other);
                    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                                   "%s: same modal group as %s on this line; expected one G code "
                                   "per group", name, other);
                }
            b->g[b->ng] = code;
            b->gcol[b->ng] = gc_col(ln, at);
            b->ng++;
        } else if (c == 'm') {
            double r = floor(v + 0.5);
            if (fabs(v - r) > 1e-6 || r < 0 || r > 1000)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "M%g: not an M code", v);
            if (b->nm >= 4)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "more than four M words on one line");
            b->m[b->nm] = (int)r;
            b->mcol[b->nm] = gc_col(ln, at);
            b->nm++;
        } else {
            if (b->has[L(c)])
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "second %c word on one line (first at column %d); expected one",
                               c - 'a' + 'A', b->col[L(c)]);
            b->has[L(c)] = 1;
            b->v[L(c)] = v;
            b->col[L(c)] = gc_col(ln, at);
        }
    }
    return FM_OK;
}

static int block_g(const gc_block *b, int group, int *col)
{
    for (int i = 0; i < b->ng; i++)
        if (g_group(b->g[i]) == group) {
            if (col) *col = b->gcol[i];
            return b->g[i];
        }
    return -1;
}

static int block_has_m(const gc_block *b, int m, int *col)
{
    for (int i = 0; i < b->nm; i++)
        if (b->m[i] == m) {
            if (col) *col = b->mcol[i];
            return 1;
        }
    return 0;
}

static int block_has_axis(const gc_block *b)
{
    return HAS(b, 'x') || HAS(b, 'y') || HAS(b, 'z') || HAS(b, 'a') || HAS(b, 'b') ||
           HAS(b, 'c') || HAS(b, 'u') || HAS(b, 'v') || HAS(b, 'w');
}

static int first_axis_col(const gc_block *b)
{
    const char *ax = "xyzabcuvw";
    int best = 0;
    for (const char *a = ax; *a; a++)
        if (HAS(b, *a) && (!best || COL(b, *a) < best)) best = COL(b, *a);
    return best;
}

/* ------------------------------------------------------------------ */
/* Motions                                                             */

static double tool_length_mm(gc_interp *g, int tool)
{
    const fm_tool_spec *t = fm_tool_table_find(g->opt.tools, tool);
    return t ? t->length_offset : 0.0;
}

static void to_machine(const gc_interp *g, const double p[3], double out[3])
{
    for (int i = 0; i < 3; i++) out[i] = (p[i] + g->g5x[i] + g->g92[i]) * g->unit;
}

static fm_status emit(gc_interp *g, fm_motion *m, double seconds)
{
    m->axis_start[0] = m->axis_start[1] = 0;
    m->axis_start[2] = 1;
    memcpy(m->axis_end, m->axis_start, sizeof m->axis_end);
    for (int i = 0; i < 3; i++) m->tip_offset[i] = g->tlo[i] * g->unit;
    m->tip_offset[2] -= tool_length_mm(g, g->tool);
    m->spindle_rpm = g->spindle_dir ? g->speed : 0.0;
    m->spindle_dir = g->spindle_dir;
    m->coolant = g->coolant;
    m->tool = g->tool;
    m->t0 = g->t;
    m->t1 = g->t + seconds;
    g->t = m->t1;
    m->line = g->lineno;
    m->block = g->cur_block;
    m->index = g->motion_index++;
    m->path = NULL;
    if (m->index >= g->opt.skip_motions && g->sink && g->sink(g->user, m)) g->stop = 1;
    return FM_OK;
}

static fm_status check_feed(gc_interp *g, const char *what, int col)
{
    if (g->feed <= 0)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: feed rate is zero; expected an F word > 0 before or in this block",
                       what);
    return FM_OK;
}

static double feed_seconds(gc_interp *g, double len_mm, double *feed_mm)
{
    if (g->inverse_time) {
        double sec = 60.0 / g->feed;
        *feed_mm = sec > 0 ? len_mm / sec * 60.0 : 0;
        return sec;
    }
    *feed_mm = g->feed * g->unit;
    return len_mm / *feed_mm * 60.0;
}

static fm_status move_line(gc_interp *g, int rapid, const double to[3])
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = rapid ? FM_MOTION_RAPID : FM_MOTION_LINE;
    to_machine(g, g->pos, m.start);
    to_machine(g, to, m.end);
    double len = sqrt((m.end[0] - m.start[0]) * (m.end[0] - m.start[0]) +
                      (m.end[1] - m.start[1]) * (m.end[1] - m.start[1]) +
                      (m.end[2] - m.start[2]) * (m.end[2] - m.start[2]));
    double sec;
    if (rapid) {
        sec = len / g->opt.rapid_rate * 60.0;
    } else {
        sec = feed_seconds(g, len, &m.feed);
    }
    memcpy(g->pos, to, sizeof g->pos);
    return emit(g, &m, sec);
}

static fm_status dwell(gc_interp *g, double seconds)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_DWELL;
    to_machine(g, g->pos, m.start);
    memcpy(m.end, m.start, sizeof m.end);
    return emit(g, &m, seconds > 0 ? seconds : 0);
}

/* Plane axes: first and second in-plane axis and the normal, in LinuxCNC's
 * order (G18's first axis is Z), so that ARC_FEED's rotation sign is the
 * counter-clockwise sense about +normal. */
static void plane_axes(int plane, int *a, int *b, int *c)
{
    if (plane == 18) { *a = 2; *b = 0; *c = 1; }
    else if (plane == 19) { *a = 1; *b = 2; *c = 0; }
    else { *a = 0; *b = 1; *c = 2; }
}

static fm_status move_arc(gc_interp *g, const double to[3], const double center_ab[2], int turns)
{
    int a, b, c;
    plane_axes(g->plane, &a, &b, &c);
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = FM_MOTION_ARC;
    double cen[3];
    cen[a] = center_ab[0];
    cen[b] = center_ab[1];
    cen[c] = g->pos[c];
    to_machine(g, g->pos, m.start);
    to_machine(g, to, m.end);
    to_machine(g, cen, m.center);
    m.plane_axis = c;
    m.turns = turns;
    double sa = atan2(m.start[b] - m.center[b], m.start[a] - m.center[a]);
    double ea = atan2(m.end[b] - m.center[b], m.end[a] - m.center[a]);
    double r0 = hypot(m.start[a] - m.center[a], m.start[b] - m.center[b]);
    double r1 = hypot(m.end[a] - m.center[a], m.end[b] - m.center[b]);
    double sweep = turns > 0 ? ea - sa : sa - ea;
    double chord = hypot(m.end[a] - m.start[a], m.end[b] - m.start[b]);
    if (chord <= 1e-12 * (1 + r0)) sweep = 0;
    while (sweep <= 1e-12) sweep += 2 * GC_PI;
    while (sweep > 2 * GC_PI + 1e-12) sweep -= 2 * GC_PI;
    sweep += 2 * GC_PI * (abs(turns) - 1);
    double axial = m.end[c] - m.start[c];
    double len = hypot(0.5 * (r0 + r1) * sweep, axial);
    double sec = feed_seconds(g, len, &m.feed);
    memcpy(g->pos, to, sizeof g->pos);
    return emit(g, &m, sec);
}

/* The end point of a G0/G1/G2/G3 block in program coordinates (LinuxCNC's
 * find_ends): absolute or incremental, or machine coordinates with G53. */
static void find_ends(gc_interp *g, const gc_block *b, int g53, double end[3])
{
    const char ax[3] = {'x', 'y', 'z'};
    for (int i = 0; i < 3; i++) {
        if (!b->has[L(ax[i])]) {
            end[i] = g->pos[i];
        } else if (g53) {
            end[i] = b->v[L(ax[i])] - g->g5x[i] - g->g92[i] - g->tlo[i];
        } else if (g->absolute) {
            end[i] = b->v[L(ax[i])];
        } else {
            end[i] = g->pos[i] + b->v[L(ax[i])];
        }
    }
}

static fm_status exec_arc(gc_interp *g, const gc_block *b, int code, int col)
{
    char name[32];
    g_name(code, name, sizeof name);
    int a, bb, c;
    plane_axes(g->plane, &a, &bb, &c);
    static const char axl[3] = {'x', 'y', 'z'};
    static const char offl[3] = {'i', 'j', 'k'};
    char la = axl[a], lb = axl[bb];
    char oa = offl[a], ob = offl[bb], oc = offl[c];
    if (!HAS(b, la) && !HAS(b, lb) && !HAS(b, axl[c]))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: no end point; expected %c or %c words in the G%d plane", name,
                       la - 32, lb - 32, g->plane);
    fm_status st = check_feed(g, name, col);
    if (st) return st;
    int turns = 1;
    if (HAS(b, 'p')) {
        double p = VAL(b, 'p');
        if (p < 1 || floor(p) != p || p > 1e6)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'),
                           "%s P%g: expected a whole number of turns >= 1", name, p);
        turns = (int)p;
    }
    double end[3];
    find_ends(g, b, 0, end);
    double ca, cb;
    double tol = g->unit == 1.0 ? 0.005 : 0.0005; /* LinuxCNC's TOLERANCE_MM / _INCH */
    if (HAS(b, 'r')) {
        double radius = VAL(b, 'r');
        if (end[a] == g->pos[a] && end[bb] == g->pos[bb])
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'r'),
                           "%s R: the end point equals the start point; a full circle needs "
                           "the centre (I J K), not R", name);
        double ar = fabs(radius);
        double mid_a = (end[a] + g->pos[a]) / 2.0, mid_b = (end[bb] + g->pos[bb]) / 2.0;
        double half = hypot(mid_a - end[a], mid_b - end[bb]);
        if (ar == 0 || half - ar > tol)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'r'),
                           "%s R%g: radius too small to reach the end point; expected |R| >= %.6g",
                           name, radius, half);
        if (half / ar > 1 - 1e-12) half = ar; /* a semicircle within rounding */
        double theta;
        if ((code == 20 && radius > 0) || (code == 30 && radius < 0))
            theta = atan2(end[bb] - g->pos[bb], end[a] - g->pos[a]) - GC_PI / 2;
        else
            theta = atan2(end[bb] - g->pos[bb], end[a] - g->pos[a]) + GC_PI / 2;
        double turn2 = asin(half / ar);
        double off = ar * cos(turn2);
        ca = mid_a + off * cos(theta);
        cb = mid_b + off * sin(theta);
    } else {
        if (HAS(b, oc))
            return gc_fail(g, FM_ERR_INPUT, COL(b, oc),
                           "%s: %c word in the G%d plane; expected %c and %c for the centre",
                           name, oc - 32, g->plane, oa - 32, ob - 32);
        if (!HAS(b, oa) && !HAS(b, ob))
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s: no centre; expected %c and/or %c (or R) in the G%d plane", name,
                           oa - 32, ob - 32, g->plane);
        if (g->arc_absolute) {
            ca = HAS(b, oa) ? VAL(b, oa) : g->pos[a];
            cb = HAS(b, ob) ? VAL(b, ob) : g->pos[bb];
        } else {
            ca = g->pos[a] + (HAS(b, oa) ? VAL(b, oa) : 0);
            cb = g->pos[bb] + (HAS(b, ob) ? VAL(b, ob) : 0);
        }
        double r0 = hypot(ca - g->pos[a], cb - g->pos[bb]);
        double r1 = hypot(ca - end[a], cb - end[bb]);
        if (r0 < tol / 10 || r1 < tol / 10)
            return gc_fail(g, FM_ERR_INPUT, col, "%s: zero-radius arc (centre on an end point)",
                           name);
        double abs_err = fabs(r0 - r1);
        if (abs_err > tol * 20 || (abs_err > tol && abs_err / fmax(r0, r1) > 0.001))
            return gc_fail(g, FM_ERR_INPUT, col,
                           "%s: radius to the end point (%.6g) differs from the radius to the "
                           "start point (%.6g); expected the same circle", name, r1, r0);
    }
    double cab[2] = {ca, cb};
    return move_arc(g, end, cab, code == 20 ? -turns : turns);
}

/* Canned cycles: LinuxCNC's convert_cycle_xy/yz/zx with aa, bb in the plane
 * and cc along its normal. */
typedef struct gc_cyc {
    int a, b, c;
} gc_cyc;

static fm_status cyc_move(gc_interp *g, const gc_cyc *k, int rapid, double aa, double bb, double cc)
{
    double to[3];
    to[k->a] = aa;
    to[k->b] = bb;
    to[k->c] = cc;
    return move_line(g, rapid, to);
}

static fm_status exec_cycle(gc_interp *g, const gc_block *b, int code, int col)
{
    char name[32];
    g_name(code, name, sizeof name);
    if (g->feed <= 0) return check_feed(g, name, col);
    if (g->inverse_time)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: canned cycles need G94, not inverse time G93",
                       name);
    double r_word;
    if (HAS(b, 'r')) r_word = VAL(b, 'r');
    else if (g->motion == code) r_word = g->cycle_r;
    else
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: R clearance plane unspecified; expected an R word", name);
    long reps = 1;
    if (HAS(b, 'l')) {
        double l = VAL(b, 'l');
        if (l < 1 || floor(l) != l || l > 1e6)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                           "%s L%g: expected a whole number of repeats >= 1", name, l);
        reps = (long)l;
    }
    gc_cyc k;
    plane_axes(g->plane, &k.a, &k.b, &k.c);
    static const char axl[3] = {'x', 'y', 'z'};
    char la = axl[k.a], lb = axl[k.b], lc = axl[k.c];
    if (g->motion != code && !HAS(b, lc))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: %c value unspecified; expected %c on the first block of a cycle",
                       name, lc - 32, lc - 32);
    double c_word = HAS(b, lc) ? VAL(b, lc) : g->cycle_cc;
    double current_cc = g->pos[k.c], old_cc;
    if (g->cycle_il_flag) {
        old_cc = g->cycle_il;
    } else {
        old_cc = g->cycle_il = current_cc;
        g->cycle_il_flag = 1;
    }
    double aa, bb, aa_inc = 0, bb_inc = 0, r, cc;
    if (g->absolute) {
        r = r_word;
        cc = c_word;
        aa = HAS(b, la) ? VAL(b, la) : g->pos[k.a];
        bb = HAS(b, lb) ? VAL(b, lb) : g->pos[k.b];
    } else {
        if (HAS(b, la)) aa_inc = VAL(b, la);
        if (HAS(b, lb)) bb_inc = VAL(b, lb);
        r = r_word + old_cc;
        cc = r + c_word;
        aa = g->pos[k.a];
        bb = g->pos[k.b];
    }
    if (r < cc)
        return gc_fail(g, FM_ERR_INPUT, HAS(b, 'r') ? COL(b, 'r') : col,
                       "%s: R (%g) below the bottom %c (%g); expected R above the hole", name, r,
                       lc - 32, cc);
    /* check the words the cycle needs before moving */
    double p = -1, q = -1, ci = 0, cj = 0, ck = 0;
    if (HAS(b, 'p')) p = VAL(b, 'p');
    if (HAS(b, 'q')) q = VAL(b, 'q');
    switch (code) {
    case 820: case 860: case 880: case 890:
        if (p < 0 && g->motion != code)
            return gc_fail(g, FM_ERR_INPUT, col, "%s: dwell time P missing; expected P seconds",
                           name);
        if (p < 0) p = g->cycle_p;
        break;
    case 730: case 830:
        if (q < 0 && g->motion != code)
            return gc_fail(g, FM_ERR_INPUT, col, "%s: peck depth Q missing; expected Q > 0", name);
        if (q < 0) q = g->cycle_q;
        if (q <= 0)
            return gc_fail(g, FM_ERR_INPUT, HAS(b, 'q') ? COL(b, 'q') : col,
                           "%s: Q%g; expected a peck depth Q > 0", name, q);
        break;
    case 870:
        if (g->motion != code) {
            const char *ijk = "ijk";
            for (int i = 0; i < 3; i++)
                if (!b->has[L(ijk[i])])
                    return gc_fail(g, FM_ERR_INPUT, col, "%s: %c missing; expected I, J and K",
                                   name, ijk[i] - 32);
        }
        ci = HAS(b, 'i') ? VAL(b, 'i') : g->cycle_i;
        cj = HAS(b, 'j') ? VAL(b, 'j') : g->cycle_j;
        ck = HAS(b, 'k') ? VAL(b, 'k') : g->cycle_k;
        g->cycle_i = ci;
        g->cycle_j = cj;
        g->cycle_k = ck;
        if (!g->absolute) ck = cc + ck;
        break;
    default: break;
    }
    if (code == 840 && g->spindle_dir != 1)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G84: spindle not turning clockwise; expected M3 before a right-hand tap");
    if (code == 840 && p < 0) p = g->cycle_p;
    if ((code == 860 || code == 870 || code == 880) && !g->spindle_dir)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: spindle not turning; expected M3 or M4 first",
                       name);
    fm_status st;
    if (old_cc < r) {
        double to[3] = {g->pos[0], g->pos[1], g->pos[2]};
        to[k.c] = r;
        if ((st = move_line(g, 1, to))) return st;
        old_cc = r;
        current_cc = old_cc;
    }
    double clear = g->retract_r ? r : old_cc;
    /* G83's small rapid back into the hole: 0.010 inch in either unit system */
    double delta = g->unit == 1.0 ? 0.010 * GC_INCH : 0.010;
    for (long rep = reps; rep > 0 && !g->stop; rep--) {
        aa += aa_inc;
        bb += bb_inc;
        if (rep == reps && current_cc > r) {
            if ((st = cyc_move(g, &k, 1, aa, bb, current_cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa, bb, r))) return st;
        } else {
            if ((st = cyc_move(g, &k, 1, aa, bb, clear))) return st;
            if (clear > r && (st = cyc_move(g, &k, 1, aa, bb, r))) return st;
        }
        switch (code) {
        case 810:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case 820:
        case 890:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = dwell(g, p))) return st;
            st = cyc_move(g, &k, code == 820, aa, bb, clear);
            break;
        case 730:
        case 830: {
            long pecks = 0;
            for (double d = r - q; d > cc; d -= q) {
                if (++pecks > 1000000)
                    return gc_fail(g, FM_ERR_LIMIT, col, "%s: more than 10^6 pecks", name);
                if ((st = cyc_move(g, &k, 0, aa, bb, d))) return st;
                if (code == 830 && (st = cyc_move(g, &k, 1, aa, bb, r))) return st;
                if ((st = cyc_move(g, &k, 1, aa, bb, d + delta))) return st;
            }
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        }
        case 840:
            /* floating tap: feed in, reverse (dwell P), feed out to the clear plane */
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = dwell(g, p))) return st;
            st = cyc_move(g, &k, 0, aa, bb, clear);
            break;
        case 850:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = cyc_move(g, &k, 0, aa, bb, r))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case 860:
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = dwell(g, p))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case 870:
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, r))) return st;
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa, bb, cc))) return st;
            if ((st = cyc_move(g, &k, 0, aa, bb, ck))) return st;
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, cc))) return st;
            if ((st = cyc_move(g, &k, 1, aa + ci, bb + cj, clear))) return st;
            st = cyc_move(g, &k, 1, aa, bb, clear);
            break;
        case 880:
            /* the operator retracts by hand at LinuxCNC's program stop */
            if ((st = cyc_move(g, &k, 0, aa, bb, cc))) return st;
            st = dwell(g, p);
            break;
        default: st = FM_OK;
        }
        if (st) return st;
    }
    g->pos[k.a] = aa;
    g->pos[k.b] = bb;
    g->pos[k.c] = clear;
    g->cycle_cc = c_word;
    g->cycle_r = r_word;
    if (p >= 0) g->cycle_p = p;
    if (q > 0) g->cycle_q = q;
    g->motion = code;
    return FM_OK;
}

/* ------------------------------------------------------------------ */
/* Offsets                                                             */

static int cs_param_base(int cs) { return 5201 + 20 * cs; }

static void set_g5x(gc_interp *g, int cs)
{
    int base = cs_param_base(cs);
    for (int i = 0; i < 3; i++) {
        double nv = g->params[base + i];
        g->pos[i] += g->g5x[i] - nv;
        g->g5x[i] = nv;
    }
    g->cs = cs;
    g->params[5220] = cs;
}

static void set_tlo(gc_interp *g, const double nv[3])
{
    for (int i = 0; i < 3; i++) {
        g->pos[i] += g->tlo[i] - nv[i];
        g->tlo[i] = nv[i];
    }
}

static fm_status exec_g10(gc_interp *g, const gc_block *b, int col)
{
    if (!HAS(b, 'l'))
        return gc_fail(g, FM_ERR_INPUT, col, "G10: L word missing; expected L2 or L20");
    double l = VAL(b, 'l');
    if (l == 1 || l == 10 || l == 11)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'),
                       "G10 L%g: tool table edits are not supported; give the tool table "
                       "(--tools) instead", l);
    if (l != 2 && l != 20)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'l'), "G10 L%g: expected L2 or L20", l);
    if (!HAS(b, 'p'))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G10 L%g: P word missing; expected P0 (active) or P1..P9", l);
    double pv = VAL(b, 'p');
    if (pv < 0 || pv > 9 || floor(pv) != pv)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'),
                       "G10 L%g P%g: expected a coordinate system P0 to P9", l, pv);
    if (HAS(b, 'r') && VAL(b, 'r') != 0)
        return gc_fail(g, FM_ERR_INPUT, COL(b, 'r'),
                       "G10 R%g: rotated coordinate systems are not supported", VAL(b, 'r'));
    int cs = pv == 0 ? g->cs : (int)pv;
    int base = cs_param_base(cs);
    const char ax[3] = {'x', 'y', 'z'};
    for (int i = 0; i < 3; i++) {
        if (!b->has[L(ax[i])]) continue;
        double w = b->v[L(ax[i])];
        /* L20: the current point gets coordinate w in system P (rs274: G92 not included) */
        g->params[base + i] = l == 2 ? w : g->pos[i] + g->g5x[i] + g->tlo[i] - w;
    }
    if (cs == g->cs) set_g5x(g, cs);
    return FM_OK;
}

static fm_status exec_g92(gc_interp *g, const gc_block *b, int code, int col)
{
    const char ax[3] = {'x', 'y', 'z'};
    if (code == 920) {
        if (!block_has_axis(b))
            return gc_fail(g, FM_ERR_INPUT, col, "G92: no axis words; expected X, Y or Z values");
        for (int i = 0; i < 3; i++) {
            if (!b->has[L(ax[i])]) continue;
            double w = b->v[L(ax[i])];
            g->g92[i] = g->pos[i] + g->g92[i] - w;
            g->pos[i] = w;
            g->params[5211 + i] = g->g92[i];
        }
        g->params[5210] = 1;
        return FM_OK;
    }
    double nv[3] = {0, 0, 0};
    if (code == 923)
        for (int i = 0; i < 3; i++) nv[i] = g->params[5211 + i];
    for (int i = 0; i < 3; i++) {
        g->pos[i] += g->g92[i] - nv[i];
        g->g92[i] = nv[i];
        if (code == 921) g->params[5211 + i] = 0;
    }
    g->params[5210] = code == 923;
    return FM_OK;
}

/* G28/G30: optional intermediate point, then rapid to the stored position
 * (#5161.. / #5181.., machine millimetres). */
static fm_status exec_home(gc_interp *g, const gc_block *b, int code)
{
    int base = code == 280 ? 5161 : 5181;
    double mid[3], home[3];
    find_ends(g, b, 0, mid);
    fm_status st = move_line(g, 1, mid);
    if (st) return st;
    const char ax[3] = {'x', 'y', 'z'};
    int any = HAS(b, 'x') || HAS(b, 'y') || HAS(b, 'z');
    for (int i = 0; i < 3; i++) {
        if (any && !b->has[L(ax[i])] && block_has_axis(b)) home[i] = mid[i];
        else if (!any && block_has_axis(b)) home[i] = mid[i];
        else home[i] = g->params[base + i] / g->unit - g->g5x[i] - g->g92[i] - g->tlo[i];
    }
    return move_line(g, 1, home);
}

static void store_home(gc_interp *g, int code)
{
    int base = code == 281 ? 5161 : 5181;
    for (int i = 0; i < 3; i++)
        g->params[base + i] = (g->pos[i] + g->g5x[i] + g->g92[i] + g->tlo[i]) * g->unit;
}

static void set_units(gc_interp *g, double unit)
{
    if (unit == g->unit) return;
    double f = g->unit / unit;
    for (int i = 0; i < 3; i++) {
        g->pos[i] *= f;
        g->g5x[i] *= f;
        g->g92[i] *= f;
        g->tlo[i] *= f;
    }
    g->unit = unit;
}

static fm_status check_tool(gc_interp *g, int tool, int col, const char *word)
{
    if (tool < 0)
        return gc_fail(g, FM_ERR_INPUT, col, "%s%d: expected a tool number >= 0", word, tool);
    if (g->opt.tools && tool != 0 && !fm_tool_table_find(g->opt.tools, tool))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s%d: tool %d is not in the tool table; expected one of its numbers",
                       word, tool, tool);
    return FM_OK;
}

static fm_status int_word(gc_interp *g, const gc_block *b, char c, int *out)
{
    double v = VAL(b, c);
    if (floor(v) != v || fabs(v) > 1e9)
        return gc_fail(g, FM_ERR_INPUT, COL(b, c), "%c%g: expected a whole number", c - 32, v);
    *out = (int)v;
    return FM_OK;
}

/* ------------------------------------------------------------------ */
/* Executing a block, in LinuxCNC's order of execution                 */

static fm_status exec_block(gc_interp *g, gc_block *b)
{
    fm_status st;
    int col = 0, code;
    for (int i = 0; i < b->nassign; i++) {
        gc_assign *a = &b->assign[i];
        if (a->name[0]) {
            if ((st = gc_set_named(g, a->name, a->v))) return st;
        } else {
            g->params[a->num] = a->v;
        }
    }
    /* M codes: reject unknown ones and conflicting groups before doing anything */
    int mgroups[10] = {0};
    for (int i = 0; i < b->nm; i++) {
        int m = b->m[i], grp;
        switch (m) {
        case 0: case 1: case 2: case 30: case 60: grp = 4; break;
        case 6: case 61: grp = 6; break;
        case 3: case 4: case 5: grp = 7; break;
        case 7: case 8: case 9: grp = 8; break;
        case 48: case 49: case 50: case 51: case 52: case 53: grp = 9; break;
        case 62: case 63: case 64: case 65: case 66: case 67: case 68: grp = 5; break;
        case 70: case 71: case 72: case 73:
            return gc_fail(g, FM_ERR_INPUT, b->mcol[i],
                           "M%d: saving and restoring modal state is not supported", m);
        default:
            if (m >= 100 && m <= 199) { grp = 10 - 1; break; }
            return gc_fail(g, FM_ERR_INPUT, b->mcol[i], "M%d: unknown M code", m);
        }
        if (m >= 100) continue; /* user M codes run external programs: no motion */
        if (grp != 8 && mgroups[grp])
            return gc_fail(g, FM_ERR_INPUT, b->mcol[i],
                           "M%d: same modal group as another M code on this line", m);
        mgroups[grp] = 1;
    }
    /* 1-2: feed mode, feed */
    code = block_g(b, 5, &col);
    if (code == 930) g->inverse_time = 1;
    else if (code == 940) g->inverse_time = 0;
    if (HAS(b, 'f')) {
        if (VAL(b, 'f') < 0)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'f'), "F%g: expected a feed rate >= 0",
                           VAL(b, 'f'));
        g->feed = VAL(b, 'f');
    }
    /* 3-5: speed, tool selection, tool change */
    if (HAS(b, 's')) {
        if (VAL(b, 's') < 0)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 's'), "S%g: expected a speed >= 0",
                           VAL(b, 's'));
        g->speed = VAL(b, 's');
    }
    if (HAS(b, 't')) {
        int t = 0;
        if ((st = int_word(g, b, 't', &t))) return st;
        if ((st = check_tool(g, t, COL(b, 't'), "T"))) return st;
        g->selected_tool = t;
    }
    if (block_has_m(b, 6, &col)) {
        g->tool = g->selected_tool;
        g->spindle_dir = 0; /* LinuxCNC stops the spindle for a tool change */
    }
    if (block_has_m(b, 61, &col)) {
        if (!HAS(b, 'q'))
            return gc_fail(g, FM_ERR_INPUT, col, "M61: Q word missing; expected M61 Q<tool>");
        int t = 0;
        if ((st = int_word(g, b, 'q', &t))) return st;
        if ((st = check_tool(g, t, COL(b, 'q'), "Q"))) return st;
        g->tool = g->selected_tool = t;
    }
    /* 6-7: spindle, coolant */
    if (block_has_m(b, 3, NULL)) g->spindle_dir = 1;
    if (block_has_m(b, 4, NULL)) g->spindle_dir = -1;
    if (block_has_m(b, 5, NULL)) g->spindle_dir = 0;
    if (block_has_m(b, 7, NULL)) g->coolant |= 1;
    if (block_has_m(b, 8, NULL)) g->coolant |= 2;
    if (block_has_m(b, 9, NULL)) g->coolant = 0;
    /* 8: dwell */
    int g0code = block_g(b, 0, &col);
    int g0col = col;
    if (g0code == 40) {
        if (!HAS(b, 'p'))
            return gc_fail(g, FM_ERR_INPUT, g0col, "G4: dwell time missing; expected P seconds");
        if (VAL(b, 'p') < 0)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'), "G4 P%g: expected P >= 0 seconds",
                           VAL(b, 'p'));
        if ((st = dwell(g, VAL(b, 'p')))) return st;
    }
    /* 9-10: plane, units */
    code = block_g(b, 2, NULL);
    if (code > 0) g->plane = code / 10;
    code = block_g(b, 6, NULL);
    if (code == 200) set_units(g, GC_INCH);
    else if (code == 210) set_units(g, 1.0);
    /* 11-12: cutter compensation (only G40 parses), tool length offset */
    code = block_g(b, 8, &col);
    if (code == 430) {
        int h = g->tool;
        if (HAS(b, 'h') && (st = int_word(g, b, 'h', &h))) return st;
        if ((st = check_tool(g, h, HAS(b, 'h') ? COL(b, 'h') : col, "H"))) return st;
        double nv[3] = {0, 0, tool_length_mm(g, h) / g->unit};
        set_tlo(g, nv);
    } else if (code == 431) {
        double nv[3] = {0, 0, 0};
        const char ax[3] = {'x', 'y', 'z'};
        for (int i = 0; i < 3; i++)
            if (b->has[L(ax[i])]) nv[i] = b->v[L(ax[i])];
        set_tlo(g, nv);
    } else if (code == 490) {
        double nv[3] = {0, 0, 0};
        set_tlo(g, nv);
    }
    /* 13-16: coordinate system, path mode (ignored), distance modes, retract */
    code = block_g(b, 12, &col);
    if (code > 0) {
        set_g5x(g, code <= 590 ? code / 10 - 53 : 6 + code - 590);
    }
    code = block_g(b, 3, NULL);
    if (code == 900) g->absolute = 1;
    else if (code == 910) g->absolute = 0;
    code = block_g(b, 4, NULL);
    if (code == 901) g->arc_absolute = 1;
    else if (code == 911) g->arc_absolute = 0;
    code = block_g(b, 10, NULL);
    if (code == 980) g->retract_r = 0;
    else if (code == 990) g->retract_r = 1;
    /* 17-18: non-modal codes and motion */
    int mcol = 0;
    int mcode = block_g(b, 1, &mcol);
    int axes = block_has_axis(b);
    int g0_uses_axes = g0code == 100 || g0code == 280 || g0code == 300 || g0code == 920 ||
                       g0code == 431;
    if (block_g(b, 8, NULL) == 431) g0_uses_axes = 1;
    if (mcode >= 0 && g0_uses_axes && axes && mcode != 800) {
        char a1[32], a2[32];
        g_name(mcode, a1, sizeof a1);
        g_name(g0code >= 0 ? g0code : 431, a2, sizeof a2);
        return gc_fail(g, FM_ERR_INPUT, mcol,
                       "%s and %s on one line both use the axis words; expected one of them",
                       a1, a2);
    }
    switch (g0code) {
    case 100: if ((st = exec_g10(g, b, g0col))) return st; break;
    case 280: case 300:
        if ((st = exec_home(g, b, g0code))) return st;
        break;
    case 281: case 301: store_home(g, g0code); break;
    case 920: case 921: case 922: case 923:
        if ((st = exec_g92(g, b, g0code, g0col))) return st;
        break;
    default: break;
    }
    if (mcode == 800) {
        g->motion = 800;
        g->cycle_il_flag = 0;
        if (axes && !g0_uses_axes)
            return gc_fail(g, FM_ERR_INPUT, first_axis_col(b),
                           "axis words with G80; expected G0, G1, G2, G3 or a canned cycle");
    }
    int motion = mcode >= 0 ? mcode : (axes && !g0_uses_axes ? g->motion : -1);
    if (g0code == 530 && motion != 0 && motion != 10)
        return gc_fail(g, FM_ERR_INPUT, g0col, "G53: expected G0 or G1 on the same line");
    if (g0code == 530 && !g->absolute)
        return gc_fail(g, FM_ERR_INPUT, g0col, "G53 in incremental mode (G91); expected G90");
    if (motion >= 0 && motion != 800) {
        if (mcol == 0) mcol = first_axis_col(b);
        if (motion <= 30) g->cycle_il_flag = 0;
        if (motion == 0 || motion == 10) {
            g->motion = motion;
            if (axes && !g0_uses_axes) {
                if (motion == 10) {
                    if ((st = check_feed(g, "G1", mcol))) return st;
                    if (g->inverse_time && !HAS(b, 'f'))
                        return gc_fail(g, FM_ERR_INPUT, mcol,
                                       "G1 in inverse time (G93) without F; expected an F word "
                                       "on every feed line");
                }
                double end[3];
                find_ends(g, b, g0code == 530, end);
                if ((st = move_line(g, motion == 0, end))) return st;
            }
        } else if (motion == 20 || motion == 30) {
            g->motion = motion;
            if (g->inverse_time && !HAS(b, 'f'))
                return gc_fail(g, FM_ERR_INPUT, mcol,
                               "G%d in inverse time (G93) without F; expected an F word on every "
                               "feed line", motion / 10);
            if (axes || HAS(b, 'i') || HAS(b, 'j') || HAS(b, 'k') || HAS(b, 'r'))
                if ((st = exec_arc(g, b, motion, mcol))) return st;
        } else {
            if ((st = exec_cycle(g, b, motion, mcol))) return st;
        }
    } else if (axes && !g0_uses_axes && g->motion == 800) {
        return gc_fail(g, FM_ERR_INPUT, first_axis_col(b),
                       "axis words without a motion mode; expected G0, G1, G2, G3 or a canned "
                       "cycle");
    }
    /* 19: stops */
    if (block_has_m(b, 2, NULL) || block_has_m(b, 30, NULL)) {
        g->ended = 1;
        g->stop = 1;
    }
    return FM_OK;
}

/* ------------------------------------------------------------------ */
/* O-word control flow                                                 */

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
    const char *t = g->text;
    size_t i = g->line_start[idx], e = g->line_start[idx + 1];
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

/* Next (dir +1) or previous (dir -1) line after `from` with an O-word of
 * the given name and a keyword in mask. */
static size_t scan(gc_interp *g, size_t from, int dir, const char *name, unsigned mask, int *kw)
{
    size_t i = from;
    for (;;) {
        if (dir > 0) {
            if (i + 1 >= g->nlines) return (size_t)-1;
            i++;
        } else {
            if (i == 0) return (size_t)-1;
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

static void frame_free(gc_frame *f)
{
    gc_table_free(&f->locals);
    free(f->repeats);
    f->repeats = NULL;
    f->nrepeats = f->caprepeats = 0;
}

static fm_status do_return(gc_interp *g, const gc_oword *o, size_t *next)
{
    if (g->depth == 0)
        return gc_fail(g, FM_ERR_INPUT, o->col, "o%s %s outside a subroutine call", o->name,
                       kw_names[o->kw]);
    gc_frame *f = &g->frames[g->depth];
    if (strcmp(f->sub, o->name))
        return gc_fail(g, FM_ERR_INPUT, o->col, "o%s %s inside subroutine o%s; expected o%s",
                       o->name, kw_names[o->kw], f->sub, f->sub);
    double v = 0;
    int has_value = g->ln.s[o->after] == '[';
    if (has_value) {
        size_t p = o->after;
        fm_status st = gc_read_real(g, &g->ln, &p, &v);
        if (st) return st;
    }
    memcpy(g->params + 1, f->saved, sizeof f->saved);
    *next = f->return_line;
    frame_free(f);
    g->depth--;
    gc_table_set(&g->globals, "_value_returned", has_value ? 1.0 : 0.0);
    if (has_value) gc_table_set(&g->globals, "_value", v);
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
    if (!gc_table_get(&g->subs, key, &line)) {
        /* not seen yet: look for the definition anywhere in the file */
        int kw;
        subline = scan(g, (size_t)-1, 1, o->name, KWM(KW_SUB), &kw);
        if (subline == (size_t)-1)
            return gc_fail(g, FM_ERR_INPUT, o->col,
                           "o%s call: no subroutine o%s in this program; expected an "
                           "o%s sub ... o%s endsub", o->name, o->name, o->name, o->name);
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
    if (g->depth + 1 > g->opt.max_call_depth)
        return gc_fail(g, FM_ERR_LIMIT, o->col,
                       "o%s call: calls nested deeper than %d; expected bounded recursion",
                       o->name, g->opt.max_call_depth);
    gc_frame *f = &g->frames[++g->depth];
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
        gc_table_set(&g->subs, key, (double)g->cur);
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
            g->lineno = (int)j + 1;
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
        gc_frame *f = &g->frames[g->depth];
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
        gc_frame *f = &g->frames[g->depth];
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
            gc_frame *f = &g->frames[g->depth];
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

/* ------------------------------------------------------------------ */
/* Running a program                                                   */

static fm_status run(gc_interp *g)
{
    fm_status st;
    gc_block *b = malloc(sizeof *b);
    if (!b) return fm_error_set(g->err, FM_ERR_LIMIT, "out of memory");
    int seen_content = 0;
    g->cur = 0;
    while (!g->stop && g->cur < g->nlines) {
        g->lineno = (int)g->cur + 1;
        g->lines_run++;
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
            if (!seen_content) {
                g->percent_mode = 1;
                seen_content = 1;
                g->cur++;
                continue;
            }
            g->ended = 1; /* the closing % ends the program, as in LinuxCNC */
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
            gc_oword o;
            if (parse_oword(g, &g->ln, p, &o, 1) != 1) {
                st = g->err ? g->err->code : FM_ERR_INPUT;
                if (!st) st = FM_ERR_INPUT;
                goto out;
            }
            if ((st = control(g, &o, &next))) goto out;
        } else {
            memset(b, 0, offsetof(gc_block, assign));
            b->nassign = 0;
            b->n = g->cur_block;
            if ((st = parse_block(g, p, b))) goto out;
            if ((st = exec_block(g, b))) goto out;
        }
        g->cur = next;
    }
    st = FM_OK;
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
    g->plane = 17;
    g->absolute = 1;
    g->arc_absolute = 0;
    g->motion = 800;
    g->retract_r = 1; /* rs274 starts in G99 (retract to R) */
    g->cs = 1;
    g->params[5220] = 1;
    return FM_OK;
}

static void interp_free(gc_interp *g)
{
    if (g->frames)
        for (int i = 0; i <= g->depth; i++) frame_free(&g->frames[i]);
    free(g->frames);
    free(g->line_start);
    gc_table_free(&g->globals);
    gc_table_free(&g->subs);
    free(g->ln.s);
    free(g->ln.col);
    free(g->scan.s);
    free(g->scan.col);
}

fm_status fm_gcode_run_string(const char *text, size_t len, const char *name,
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
    fm_status st = fm_gcode_run_string(buf, len, path, &o, sink, user, summary, err);
    free(buf);
    return st;
}
