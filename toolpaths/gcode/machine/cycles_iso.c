/* cycles_iso.c: the canned cycles of the ISO dialects (Fanuc, Haas and
 * the controls that follow them) for drilling, tapping and boring in the
 * selected plane (G17: holes along Z): G73 high-speed peck (retract
 * fm_gcode_options.peck_retract after each peck of Q), G74 left-hand and G84
 * right-hand tapping, G76 fine boring (oriented stop, shift Q, retract), G81
 * drilling, G82 with a dwell, G83 peck drilling (back to R after each peck,
 * down again to peck_clearance above the last depth), G85 and G89 boring out
 * at feed, G86 with the spindle stopped, G87 back boring, G88 boring with a
 * manual retract (here a rapid). Hole data (Z, R, Q, P) stay until the front
 * end cancels them (G80, G00-G03); repeats drill the hole again, at
 * increments in G91; zero repeats store the data only. In G90, R and Z are
 * levels; in G91, R is measured from the initial level and Z from R (in the
 * mode they are written in; later holes keep the levels). G98 returns to the
 * initial level (where the cycle mode began), G99 to R. The shift of G76 and
 * G87 is along +X of the plane (Fanuc's parameter default). The positions go
 * through the program frame (transform.c). LinuxCNC's cycles (rs274's
 * semantics: G76 threading, its own G87 and levels) are motion.c's. */
#include "machine.h"

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

fm_status gc_cycle_iso(gc_interp *g, int code, const gc_hole_block *h, int col)
{
    gc_hole_data *f = &g->hole;
    char name[8];
    gc_g_name(code, name, sizeof name);
    cyc k = {g, 0, 0, 0, 0, 0};
    gc_plane_axes(g->plane, &k.a, &k.b, &k.c);
    char lc = "xyz"[k.c];
    fm_status st;

    /* hole data */
    int first = !f->valid;
    int has_z = h->at.given[k.c];
    if (has_z) {
        f->z = h->at.value[k.c];
        f->z_word = 1;
        f->z_abs = g->absolute;
    }
    if (h->has_r) {
        f->r = h->r;
        f->r_word = 1;
        f->r_abs = g->absolute;
    }
    if (h->has_q) f->q = h->q;
    if (h->has_p) f->p = h->p;
    if (first && (!has_z || !h->has_r))
        return gc_fail(g, FM_ERR_INPUT, col,
                       "%s: %s missing; expected the hole bottom %c and the R point on the first "
                       "block of a canned cycle", name,
                       !has_z ? (h->has_r ? "the hole bottom" : "hole bottom and R") : "R",
                       lc - 32);
    f->valid = 1;
    g->motion = (gc_gcode)code;
    long reps = 1;
    if (h->rep_letter) {
        double v = h->rep_value;
        if (floor(v) != v || v < 0 || v > 9999)
            return gc_fail(g, FM_ERR_INPUT, h->rep_col,
                           "%s %c%g: expected a whole number of repeats from 0 to 9999", name,
                           h->rep_letter - 32, v);
        reps = (long)v;
    }
    int drill = h->at.given[k.a] || h->at.given[k.b] || has_z || h->has_r;
    if (!drill || reps == 0) return FM_OK; /* K0 or no position: the data are kept */

    if (g->inverse_time)
        return gc_fail(g, FM_ERR_INPUT, col, "%s: canned cycles need G94, not inverse time G93",
                       name);
    if ((st = gc_check_feed(g, name, col))) return st;
    if ((code == GC_G73 || code == GC_G83) && !(f->q > 0))
        return gc_fail(g, FM_ERR_INPUT, h->has_q ? h->q_col : col,
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
    if (f->r_word) {
        f->level_r = f->r_abs ? f->r : initial + f->r;
        f->r_word = 0;
    }
    if (f->z_word) {
        f->level_z = f->z_abs ? f->z : f->level_r + f->z;
        f->z_word = 0;
    }
    double r = f->level_r, z = f->level_z;
    int rcol = h->has_r ? h->r_col : col;
    if (code == GC_G87 && !(r < z))
        return gc_fail(g, FM_ERR_INPUT, rcol,
                       "G87: R (%g) not below %c (%g); back boring starts at R under the part "
                       "and cuts up to %c", r, lc - 32, z, lc - 32);
    if (code != GC_G87 && r < z)
        return gc_fail(g, FM_ERR_INPUT, rcol,
                       "%s: R (%g) below the hole bottom %c (%g); expected R above the hole", name,
                       r, lc - 32, z);
    double ret = g->retract_r ? r : initial;
    double q = f->q, p = f->p;
    double d73 = g->opt.peck_retract / g->unit, d83 = g->opt.peck_clearance / g->unit;
    int spindle = g->spindle_dir;

    for (long rep = 0; rep < reps && !g->stop; rep++) {
        double end[3], work[3];
        gc_frame_target(g, &h->at, end);
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

void gc_cycle_iso_cancel(gc_interp *g)
{
    g->hole.valid = 0;
    g->cycle_il_flag = 0;
}

void gc_cycle_iso_scale_units(gc_interp *g, double k)
{
    gc_hole_data *f = &g->hole;
    f->z *= k;
    f->r *= k;
    f->level_z *= k;
    f->level_r *= k;
    f->q *= k;
    g->cycle_il *= k;
}
