/* cycle.c: Fanuc's canned cycles for drilling, tapping and
 * boring in the selected plane (G17: holes along Z): G73 high-speed peck
 * (retract d after each peck of Q), G74 left-hand and G84 right-hand
 * tapping, G76 fine boring (oriented stop, shift Q, retract), G81 drilling,
 * G82 with a dwell, G83 peck drilling (back to R after each peck, down again
 * to d above the last depth), G85 and G89 boring out at feed, G86 with the
 * spindle stopped, G87 back boring, G88 boring with a manual retract (here a
 * rapid). Hole data (Z, R, Q, P) stay until G80 or a G00-G03; K (or L)
 * repeats the hole, at increments in G91; K0 stores the data only. In G90, R
 * and Z are levels; in G91, R is measured from the initial level and Z from
 * R (in the mode they are written in; later holes keep the levels). G98
 * returns to the initial level (where the cycle mode began), G99 to R.
 * The shift of G76 and G87 is along +X of the plane (Fanuc's parameter
 * default). */
#include "fanuc.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct cyc {
    gc_interp *g;
    int a, b, c;         /* plane axes and the hole axis */
    double aa, bb;       /* the hole, work coordinates */
} cyc;

static fm_status mv(cyc *k, int rapid, double da, double cc)
{
    double to[3];
    to[k->a] = k->aa + da;
    to[k->b] = k->bb;
    to[k->c] = cc;
    return gc_move_line(k->g, rapid, to);
}

fm_status gc_fanuc_exec_cycle(gc_interp *g, const gc_fanuc_block *fb, int code, int col)
{
    gc_fanuc *f = FANUC(g);
    const gc_block *b = &fb->b;
    char name[8];
    gc_g_name(code, name, sizeof name);
    cyc k = {g, 0, 0, 0, 0, 0};
    gc_plane_axes(g->plane, &k.a, &k.b, &k.c);
    static const char axl[3] = {'x', 'y', 'z'};
    char la = axl[k.a], lb = axl[k.b], lc = axl[k.c];
    fm_status st;

    /* hole data */
    int first = !f->cycle_data;
    if (b->has[L(lc)]) {
        f->cycle_z = gc_fanuc_length(g, fb, lc);
        f->cycle_z_word = 1;
        f->cycle_z_abs = g->absolute;
    }
    if (b->has[L('r')]) {
        f->cycle_r = gc_fanuc_length(g, fb, 'r');
        f->cycle_r_word = 1;
        f->cycle_r_abs = g->absolute;
    }
    if (b->has[L('q')]) f->cycle_q = fabs(gc_fanuc_length(g, fb, 'q'));
    if (b->has[L('p')]) f->cycle_p = gc_fanuc_dwell_seconds(g, fb, 'p');
    if (first && (!b->has[L(lc)] || !b->has[L('r')]))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: %s missing; expected the hole bottom %c and the R point on the first "
                       "block of a canned cycle", name,
                       !b->has[L(lc)] ? (b->has[L('r')] ? "the hole bottom" : "hole bottom and R")
                                      : "R", lc - 32);
    f->cycle_data = 1;
    g->motion = (gc_gcode)code;
    long reps = 1;
    char kl = b->has[L('k')] ? 'k' : b->has[L('l')] ? 'l' : 0;
    if (kl) {
        double v = b->v[L(kl)];
        if (floor(v) != v || v < 0 || v > 9999)
            return gc_fail(g, FM_ERR_INPUT, b->col[L(kl)],
                           "%s %c%g: expected a whole number of repeats from 0 to 9999", name,
                           kl - 32, v);
        reps = (long)v;
    }
    int drill = b->has[L(la)] || b->has[L(lb)] || b->has[L(lc)] || b->has[L('r')];
    if (!drill || reps == 0) return FM_OK; /* K0 or no position: the data are kept */

    if (g->inverse_time)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: canned cycles need G94, not inverse time G93",
                       name);
    if ((st = gc_check_feed(g, name, col))) return st;
    if ((code == GC_G73 || code == GC_G83) && !(f->cycle_q > 0))
        return gc_fail(g, FM_ERR_INPUT, b->has[L('q')] ? b->col[L('q')] : col,
                       "%s: peck depth Q missing or zero; expected Q > 0", name);
    if (code == GC_G87 && g->retract_r)
        return gc_fail(g, FM_ERR_INPUT, col,
                       "G87 in G99 mode: back boring returns to the initial level; expected G98");

    if (!g->cycle_il_flag) {
        g->cycle_il = g->pos[k.c];
        g->cycle_il_flag = 1;
    }
    double initial = g->cycle_il;
    /* R and Z become levels when a hole is drilled with them, in the mode
     * they were written in; later holes keep those levels */
    if (f->cycle_r_word) {
        f->level_r = f->cycle_r_abs ? f->cycle_r : initial + f->cycle_r;
        f->cycle_r_word = 0;
    }
    if (f->cycle_z_word) {
        f->level_z = f->cycle_z_abs ? f->cycle_z : f->level_r + f->cycle_z;
        f->cycle_z_word = 0;
    }
    double r = f->level_r, z = f->level_z;
    int rcol = b->has[L('r')] ? b->col[L('r')] : col;
    if (code == GC_G87 && !(r < z))
        return gc_fail(g, FM_ERR_INPUT, rcol,
                       "G87: R (%g) not below %c (%g); back boring starts at R under the part "
                       "and cuts up to %c", r, lc - 32, z, lc - 32);
    if (code != GC_G87 && r < z)
        return gc_fail(g, FM_ERR_INPUT, rcol,
                       "%s: R (%g) below the hole bottom %c (%g); expected R above the hole", name,
                       r, lc - 32, z);
    double ret = g->retract_r ? r : initial;
    double q = f->cycle_q, p = f->cycle_p;
    double d73 = g->opt.peck_retract / g->unit, d83 = g->opt.peck_clearance / g->unit;
    int spindle = g->spindle_dir;

    for (long rep = 0; rep < reps && !g->stop; rep++) {
        double end[3], work[3];
        gc_fanuc_target(g, fb, end);
        end[k.c] = g->frame.prog[k.c];
        gc_frame_to_work(g, end, work);
        k.aa = work[k.a];
        k.bb = work[k.b];
        /* position at the current level (a move only if the hole is
         * elsewhere), then down (or up) to R */
        if ((k.aa != g->pos[k.a] || k.bb != g->pos[k.b]) && (st = mv(&k, 1, 0, g->pos[k.c])))
            return st;
        double start_level = code == GC_G87 ? initial : r;
        if (code == GC_G87) {
            /* back boring: oriented stop, shift, down through the bore to R */
            g->spindle_dir = 0;
            if ((st = mv(&k, 1, q, g->pos[k.c]))) return st;
            if ((st = mv(&k, 1, q, r))) return st;
            if ((st = mv(&k, 1, 0, r))) return st;
            g->spindle_dir = 1;
            if ((st = mv(&k, 0, 0, z))) return st;
            g->spindle_dir = 0;
            if ((st = mv(&k, 1, q, z))) return st;
            if ((st = mv(&k, 1, q, initial))) return st;
            if ((st = mv(&k, 1, 0, initial))) return st;
            g->spindle_dir = spindle ? spindle : 1;
        } else {
            if (g->pos[k.c] != start_level && (st = mv(&k, 1, 0, start_level))) return st;
            switch (code) {
            case GC_G81:
                if ((st = mv(&k, 0, 0, z)) || (st = mv(&k, 1, 0, ret))) return st;
                break;
            case GC_G82:
                if ((st = mv(&k, 0, 0, z)) || (st = gc_dwell(g, p)) || (st = mv(&k, 1, 0, ret)))
                    return st;
                break;
            case GC_G73: {
                double depth = r;
                for (long n = 0;; n++) {
                    if (n > 1000000)
                        return gc_fail(g, FM_ERR_LIMIT, col, "%s: more than 10^6 pecks", name);
                    double next = depth - q;
                    if (next <= z) {
                        if ((st = mv(&k, 0, 0, z))) return st;
                        break;
                    }
                    if ((st = mv(&k, 0, 0, next)) || (st = mv(&k, 1, 0, next + d73))) return st;
                    depth = next;
                }
                if ((st = mv(&k, 1, 0, ret))) return st;
                break;
            }
            case GC_G83: {
                double depth = r;
                for (long n = 0;; n++) {
                    if (n > 1000000)
                        return gc_fail(g, FM_ERR_LIMIT, col, "%s: more than 10^6 pecks", name);
                    double next = depth - q;
                    if (n > 0 && (st = mv(&k, 1, 0, depth + d83))) return st;
                    if (next <= z) {
                        if ((st = mv(&k, 0, 0, z))) return st;
                        break;
                    }
                    if ((st = mv(&k, 0, 0, next)) || (st = mv(&k, 1, 0, r))) return st;
                    depth = next;
                }
                if ((st = mv(&k, 1, 0, ret))) return st;
                break;
            }
            case GC_G74:
            case GC_G84: {
                int in = code == GC_G84 ? 1 : -1;
                g->spindle_dir = in;
                if ((st = mv(&k, 0, 0, z)) || (st = gc_dwell(g, p))) return st;
                g->spindle_dir = -in;
                if ((st = mv(&k, 0, 0, r))) return st;
                g->spindle_dir = in;
                if (ret != r && (st = mv(&k, 1, 0, ret))) return st;
                break;
            }
            case GC_G85:
            case GC_G89:
                if ((st = mv(&k, 0, 0, z))) return st;
                if (code == GC_G89 && (st = gc_dwell(g, p))) return st;
                if ((st = mv(&k, 0, 0, r))) return st;
                if (ret != r && (st = mv(&k, 1, 0, ret))) return st;
                break;
            case GC_G86:
            case GC_G88:
                if ((st = mv(&k, 0, 0, z))) return st;
                if (code == GC_G88 && (st = gc_dwell(g, p))) return st;
                g->spindle_dir = 0;
                if ((st = mv(&k, 1, 0, ret))) return st;
                g->spindle_dir = spindle;
                break;
            case GC_G76:
                if ((st = mv(&k, 0, 0, z)) || (st = gc_dwell(g, p))) return st;
                g->spindle_dir = 0; /* oriented spindle stop, then the tool moves off the wall */
                if ((st = mv(&k, 1, q, z)) || (st = mv(&k, 1, q, ret)) || (st = mv(&k, 1, 0, ret)))
                    return st;
                g->spindle_dir = spindle;
                break;
            default: break;
            }
        }
        g->frame.prog[k.a] = end[k.a];
        g->frame.prog[k.b] = end[k.b];
        gc_frame_from_work(g, g->pos, work);
        g->frame.prog[k.c] = work[k.c];
    }
    return FM_OK;
}
