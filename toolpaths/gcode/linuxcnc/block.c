/* block.c: reading blocks: a source line normalized as LinuxCNC
 * does (lower case, no spaces, comments removed, each character's source
 * column kept for errors), then its words (G and M codes checked against
 * their modal groups, letters, parameter assignments) gathered into a
 * gc_block for linuxcnc/modal.c to execute. */
#include "linuxcnc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


/* ------------------------------------------------------------------ */
/* Words of a block                                                    */

/* Modal group of a G code; GC_GROUP_UNKNOWN if unknown. Codes LinuxCNC
 * knows but this interpreter refuses are GC_GROUP_REFUSED, with a message in
 * refused_g(). */
gc_group gc_g_group(int code)
{
    switch (code) {
    case GC_G0: case GC_G1: case GC_G2: case GC_G3: case GC_G73: case GC_G80: case GC_G81:
    case GC_G82: case GC_G83: case GC_G84: case GC_G85: case GC_G86: case GC_G87: case GC_G88:
    case GC_G89:
        return GC_GROUP_MOTION;
    case GC_G4: case GC_G10: case GC_G28: case GC_G28_1: case GC_G30: case GC_G30_1: case GC_G53:
    case GC_G92: case GC_G92_1: case GC_G92_2: case GC_G92_3:
        return GC_GROUP_NON_MODAL;
    case GC_G17: case GC_G18: case GC_G19: return GC_GROUP_PLANE;
    case GC_G90: case GC_G91: return GC_GROUP_DISTANCE;
    case GC_G90_1: case GC_G91_1: return GC_GROUP_ARC_DISTANCE;
    case GC_G93: case GC_G94: case GC_G95: return GC_GROUP_FEED_MODE;
    case GC_G20: case GC_G21: return GC_GROUP_UNITS;
    case GC_G40: case GC_G41: case GC_G42: case GC_G41_1: case GC_G42_1:
        return GC_GROUP_CUTTER_COMP;
    case GC_G43: case GC_G43_1: case GC_G43_4: case GC_G49: return GC_GROUP_TOOL_LENGTH;
    case GC_G98: case GC_G99: return GC_GROUP_RETURN_MODE;
    case GC_G54: case GC_G55: case GC_G56: case GC_G57: case GC_G58: case GC_G59: case GC_G59_1:
    case GC_G59_2: case GC_G59_3:
        return GC_GROUP_COORD_SYSTEM;
    case GC_G61: case GC_G61_1: case GC_G64: return GC_GROUP_PATH_MODE;
    case GC_G96: case GC_G97: return GC_GROUP_SPINDLE_MODE;
    case GC_G5: case GC_G5_1: case GC_G5_2: case GC_G5_3: case GC_G33: case GC_G33_1:
    case GC_G38_2: case GC_G38_3: case GC_G38_4: case GC_G38_5:
        return GC_GROUP_MOTION;
    case GC_G52: return GC_GROUP_NON_MODAL;
    case GC_G7: case GC_G8: case GC_G43_2: case GC_G74: case GC_G76: case GC_G17_1:
    case GC_G18_1: case GC_G19_1: case GC_G28_2: case GC_G30_2: case GC_G70: case GC_G71:
    case GC_G71_1: case GC_G71_2: case GC_G72: case GC_G72_1: case GC_G72_2:
        return GC_GROUP_REFUSED;
    default: return GC_GROUP_UNKNOWN;
    }
}

static const char *refused_g(int code)
{
    switch (code) {
    case GC_G7: case GC_G8:
        return "lathe diameter/radius mode is for lathes; frepmill simulates milling";
    case GC_G70: case GC_G71: case GC_G71_1: case GC_G71_2: case GC_G72: case GC_G72_1:
    case GC_G72_2:
        return "lathe finishing and roughing cycles are for lathes; frepmill simulates milling";
    case GC_G76: return "the lathe threading cycle is for lathes; frepmill simulates milling";
    case GC_G74: return "left-hand tapping (G74) is not supported; use G84 with M4 or G33.1";
    case GC_G43_2: return "G43.2 (additional tool offsets) is not supported; use G43 H or G43.1";
    case GC_G17_1: case GC_G18_1: case GC_G19_1: return "UVW planes are not supported";
    case GC_G28_2: case GC_G30_2: return "homing (G28.2/G30.2) is not supported";
    case GC_G95: return "G95 (feed per revolution) is not supported; use G94 or G93";
    default: return "is not supported";
    }
}

fm_status gc_parse_block(gc_interp *g, size_t p, gc_block *b)
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
            a->col = gc_col(ln, at);
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
            if (c == '@' || c == '^') {
                int *has = c == '@' ? &b->has_radius : &b->has_theta;
                if (*has)
                    return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                                   "second '%c' word on one line; expected one", c);
                p++;
                fm_status st = gc_read_real(g, ln, &p, c == '@' ? &b->radius : &b->theta);
                if (st) return st;
                *has = 1;
                if (c == '@') b->radius_col = gc_col(ln, at);
                else b->theta_col = gc_col(ln, at);
                continue;
            }
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
            gc_g_name(code, name, sizeof name);
            gc_group grp = gc_g_group(code);
            if (grp == GC_GROUP_UNKNOWN)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: unknown G code", name);
            if (grp == GC_GROUP_REFUSED)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: %s", name, refused_g(code));
            if (code == GC_G95)
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at), "%s: %s", name, refused_g(code));
            /* rs274 takes G80 beside another motion code as that code */
            if (grp == GC_GROUP_MOTION && b->ghas[grp] && (code == GC_G80 || b->gcode[grp] == GC_G80)) {
                if (code != GC_G80) {
                    b->gcode[grp] = code;
                    b->gcol[grp] = gc_col(ln, at);
                }
                continue;
            }
            if (b->ghas[grp]) {
                char other[32];
                gc_g_name(b->gcode[grp], other, sizeof other);
                return gc_fail(g, FM_ERR_INPUT, gc_col(ln, at),
                               "%s: same modal group as %s on this line; expected one G code "
                               "per group", name, other);
            }
            b->ghas[grp] = 1;
            b->gcode[grp] = code;
            b->gcol[grp] = gc_col(ln, at);
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

