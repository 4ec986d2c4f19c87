/* rotary.c: the rotary axes A, B and C (degrees): end values of a
 * block (absolute, incremental, G53, LinuxCNC's unwrapping of wrapped
 * axes), their G5x and G92 offsets and G28/G30 positions (LinuxCNC's
 * parameters #5224.., #5214.., #5164..), the time a move takes (F in
 * degrees per minute when only rotary axes move), TCP on and off (G43.4,
 * G49), and the joint values and machine each motion carries. Without a
 * machine (fm_gcode_options.machine) the words are followed, as rs274
 * does, but move nothing. */
#include "machine.h"

#include <math.h>
#include <string.h>

#include "sweep/sweep.h"

static const char rot_letter[3] = {'a', 'b', 'c'};

static const fm_rotary_axis *machine_axis(const gc_interp *g, int i)
{
    int k = fm_machine_axis_of(g->opt.machine, i);
    return k < 0 ? NULL : &g->opt.machine->rotary[k];
}

void gc_rot_start(gc_interp *g)
{
    g->tcp = g->opt.machine && g->opt.machine->rotary_count > 0 && g->opt.machine->tcp;
}

/* LinuxCNC's wrapped rotary: |w| (below 360) is the target modulo 360, the
 * sign of the word as written (-0 included) the direction of travel from
 * the current value. */
static fm_status unwrap(gc_interp *g, const gc_block *b, int i, double word, double w, double current,
                        double *out)
{
    if (!(word > -360 && word < 360))
        return gc_fail(g, FM_ERR_INPUT, COL(b, rot_letter[i]),
                       "%c%g: a wrapped rotary axis takes targets between -360 and 360 (the sign gives "
                       "the direction)", rot_letter[i] - 32, word);
    int neg = signbit(word);
    double r = fabs(w) + 360.0 * floor(current / 360.0);
    if (!neg && r < current) r += 360;
    if (neg && r > current) r -= 360;
    *out = r;
    return FM_OK;
}

fm_status gc_rot_find_ends(gc_interp *g, const gc_block *b, int g53)
{
    if (g->comp.side != GC_COMP_OFF && (b->has[L('a')] || b->has[L('b')] || b->has[L('c')]) &&
        g->opt.machine && g->opt.machine->rotary_count > 0) {
        char l = b->has[L('a')] ? 'a' : b->has[L('b')] ? 'b' : 'c';
        return gc_fail(g, FM_ERR_INPUT, COL(b, l),
                       "%c word with cutter radius compensation on: rotary moves under G41/G42 are not "
                       "supported; expected G40 first", l - 32);
    }
    for (int i = 0; i < 3; i++) {
        char l = rot_letter[i];
        if (!b->has[L(l)]) {
            g->rot_next[i] = g->rot[i];
            continue;
        }
        double w = b->v[L(l)];
        const fm_rotary_axis *ax = machine_axis(g, i);
        if (g53) {
            g->rot_next[i] = w - g->rot_g5x[i] - g->rot_g92[i];
        } else if (g->absolute) {
            if (ax && ax->wrapped) {
                /* in machine values, then back to the program's */
                double off = g->rot_g5x[i] + g->rot_g92[i], r = 0;
                fm_status st = unwrap(g, b, i, w, w + off, g->rot[i] + off, &r);
                if (st) return st;
                g->rot_next[i] = r - off;
            } else {
                g->rot_next[i] = w;
            }
        } else {
            g->rot_next[i] = g->rot[i] + w;
        }
    }
    return FM_OK;
}

/* Fanuc: A B C already read as degrees; a wrapped axis (Fanuc's rollover)
 * takes the shorter way to an absolute target modulo 360. */
void gc_rot_target(gc_interp *g, const int given[3], const double value[3])
{
    for (int i = 0; i < 3; i++) {
        g->rot_next[i] = g->rot[i];
        if (!given[i]) continue;
        const fm_rotary_axis *ax = machine_axis(g, i);
        if (!g->absolute) {
            g->rot_next[i] = g->rot[i] + value[i];
        } else if (ax && ax->wrapped) {
            double off = g->rot_g5x[i] + g->rot_g92[i], cur = g->rot[i] + off;
            double d = fmod(value[i] + off - cur, 360.0);
            if (d > 180) d -= 360;
            if (d < -180) d += 360;
            g->rot_next[i] = g->rot[i] + d;
        } else {
            g->rot_next[i] = value[i];
        }
    }
}

void gc_rot_hold(gc_interp *g) { memcpy(g->rot_next, g->rot, sizeof g->rot); }

int gc_rot_moves(const gc_interp *g)
{
    return g->rot_next[0] != g->rot[0] || g->rot_next[1] != g->rot[1] || g->rot_next[2] != g->rot[2];
}

double gc_rot_degrees(const gc_interp *g)
{
    double d = 0;
    for (int i = 0; i < 3; i++) d += (g->rot_next[i] - g->rot[i]) * (g->rot_next[i] - g->rot[i]);
    return sqrt(d);
}

void gc_rot_emit(gc_interp *g, fm_motion *m)
{
    for (int i = 0; i < 3; i++) {
        m->rotary_start[i] = g->rot[i] + g->rot_g5x[i] + g->rot_g92[i];
        m->rotary_end[i] = g->rot_next[i] + g->rot_g5x[i] + g->rot_g92[i];
    }
    memcpy(g->rot, g->rot_next, sizeof g->rot);
    const fm_machine *mc = g->opt.machine;
    if (!mc || mc->rotary_count <= 0) return;
    m->machine = mc;
    m->tcp = g->tcp;
    m->tool_length = gc_tool_length_mm(g, g->tool);
    /* the tool axis in the workpiece frame at both ends, for reports */
    double tip[3];
    fm_motion_pose_at(m, 0, tip, m->axis_start);
    fm_motion_pose_at(m, 1, tip, m->axis_end);
}

void gc_rot_set_g5x(gc_interp *g, int base)
{
    for (int i = 0; i < 3; i++) {
        double nv = g->params[base + 3 + i];
        g->rot[i] += g->rot_g5x[i] - nv;
        g->rot_g5x[i] = nv;
    }
    gc_rot_hold(g);
}

void gc_rot_g10(gc_interp *g, const gc_block *b, int l, int base)
{
    for (int i = 0; i < 3; i++) {
        if (!b->has[L(rot_letter[i])]) continue;
        double w = b->v[L(rot_letter[i])];
        g->params[base + 3 + i] = l == 2 ? w : g->rot[i] + g->rot_g5x[i] - w;
    }
}

void gc_rot_g92(gc_interp *g, const gc_block *b, int code)
{
    if (code == GC_G52) {
        /* kept in G92's offsets, as LinuxCNC does: a given axis's offset
         * becomes the value */
        for (int i = 0; i < 3; i++) {
            if (!b->has[L(rot_letter[i])]) continue;
            double w = b->v[L(rot_letter[i])];
            g->rot[i] += g->rot_g92[i] - w;
            g->rot_g92[i] = w;
            g->params[GC_PARAM_G92 + 3 + i] = w;
        }
    } else if (code == GC_G92) {
        for (int i = 0; i < 3; i++) {
            if (!b->has[L(rot_letter[i])]) continue;
            double w = b->v[L(rot_letter[i])];
            g->rot_g92[i] = g->rot[i] + g->rot_g92[i] - w;
            g->rot[i] = w;
            g->params[GC_PARAM_G92 + 3 + i] = g->rot_g92[i];
        }
    } else {
        for (int i = 0; i < 3; i++) {
            double nv = code == GC_G92_3 ? g->params[GC_PARAM_G92 + 3 + i] : 0;
            g->rot[i] += g->rot_g92[i] - nv;
            g->rot_g92[i] = nv;
            if (code == GC_G92_1) g->params[GC_PARAM_G92 + 3 + i] = 0;
        }
    }
    gc_rot_hold(g);
}

/* G28/G30's second move: the rotary axes named in the block (or all of
 * them when the block names no axis) go to the stored position. */
void gc_rot_home(gc_interp *g, const gc_block *b, int base)
{
    int named = gc_block_has_axis(b);
    for (int i = 0; i < 3; i++)
        if (!named || b->has[L(rot_letter[i])])
            g->rot_next[i] = g->params[base + 3 + i] - g->rot_g5x[i] - g->rot_g92[i];
}

void gc_rot_store_home(gc_interp *g, int base)
{
    for (int i = 0; i < 3; i++) g->params[base + 3 + i] = g->rot[i] + g->rot_g5x[i] + g->rot_g92[i];
}

fm_status gc_rot_tcp(gc_interp *g, int on, int col)
{
    const fm_machine *mc = g->opt.machine;
    if (on && !(mc && mc->rotary_count > 0 && mc->tcp))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G43.4: tool centre point control needs a machine with rotary axes and \"tcp\": true "
                       "(--machine)");
    g->tcp = on && mc && mc->rotary_count > 0;
    return FM_OK;
}
