/* block.c: reading a Fanuc block: its words (a vacant variable
 * leaves its address out), the G codes checked against Fanuc's modal groups
 * (codes a mill has but this simulation refuses get a message saying why),
 * G65's arguments A-Z into #1-#26 by Fanuc's argument specification I, and
 * which numbers were written without a decimal point (fanuc/exec.c
 * reads those in the least input increment). */
#include "fanuc.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

gc_group gc_fanuc_g_group(int code)
{
    switch (code) {
    case GC_G0: case GC_G1: case GC_G2: case GC_G3: return GC_GROUP_MOTION;
    case GC_G73: case GC_G74: case GC_G76: case GC_G80: case GC_G81: case GC_G82: case GC_G83:
    case GC_G84: case GC_G85: case GC_G86: case GC_G87: case GC_G88: case GC_G89:
        return GC_GROUP_CYCLE;
    case GC_G4: case GC_G9: case GC_G10: case GC_G11: case GC_G12: case GC_G13: case GC_G27:
    case GC_G28: case GC_G30: case GC_G52: case GC_G53: case GC_G65: case GC_G92:
        return GC_GROUP_NON_MODAL;
    case GC_G17: case GC_G18: case GC_G19: return GC_GROUP_PLANE;
    case GC_G90: case GC_G91: return GC_GROUP_DISTANCE;
    case GC_G93: case GC_G94: case GC_G95: return GC_GROUP_FEED_MODE;
    case GC_G20: case GC_G21: return GC_GROUP_UNITS;
    case GC_G40: case GC_G41: case GC_G42: return GC_GROUP_CUTTER_COMP;
    case GC_G43: case GC_G43_4: case GC_G44: case GC_G49: return GC_GROUP_TOOL_LENGTH;
    case GC_G98: case GC_G99: return GC_GROUP_RETURN_MODE;
    case GC_G54: case GC_G55: case GC_G56: case GC_G57: case GC_G58: case GC_G59: case GC_G54_1:
    case GC_G154:
        return GC_GROUP_COORD_SYSTEM;
    case GC_G61: case GC_G62: case GC_G63: case GC_G64: return GC_GROUP_PATH_MODE;
    case GC_G96: case GC_G97: return GC_GROUP_SPINDLE_MODE;
    case GC_G15: case GC_G16: return GC_GROUP_POLAR;
    case GC_G68: case GC_G69: return GC_GROUP_ROTATION;
    case GC_G50: case GC_G51: return GC_GROUP_SCALING;
    case GC_G66: case GC_G67: return GC_GROUP_MACRO_MODAL;
    case GC_G50_1: case GC_G51_1: return GC_GROUP_MIRROR;
    case GC_G5: case GC_G5_1: case GC_G8: case GC_G103: case GC_G187: return GC_GROUP_LOOKAHEAD;
    case GC_G7: case GC_G22: case GC_G23: case GC_G29: case GC_G31:
    case GC_G33: case GC_G37: case 450: case 460: case 470: case 480:
    case GC_G60: case GC_G43_1: case GC_G43_2: case 121: case 131: case 71:
        return GC_GROUP_REFUSED;
    default: return GC_GROUP_UNKNOWN;
    }
}

static const char *refused(int code)
{
    switch (code) {
    case GC_G7: case 71: return "cylindrical interpolation is not supported";
    case 121: case 131: return "polar coordinate interpolation is not supported";
    case GC_G22: case GC_G23: return "stored stroke check is a machine setting; remove it";
    case GC_G29: return "return from the reference point is not supported; program the move";
    case GC_G31: return "skip function (probing) is not supported by a simulation";
    case GC_G33: return "thread cutting is not supported";
    case GC_G37: return "automatic tool length measurement is not supported by a simulation";
    case 450: case 460: case 470: case 480:
        return "tool position offset is not supported; program the offset path";
    case GC_G60: return "single direction positioning is not supported; use G00";
    case GC_G43_1: case GC_G43_2: return "is not a Fanuc tool length code; use G43 or G44 H";
    default: return "is not supported";
    }
}

/* Argument specification I: the variable of each letter, 0 if not an argument. */
static int argument_variable(char c)
{
    static const int var[26] = {
        /* a */ 1, 2, 3, 7, 8, 9, /* g */ 0, 11, 4, 5, 6, /* l */ 0, 13, /* n */ 0, 0, 0,
        /* q */ 17, 18, 19, 20, 21, 22, 23, 24, 25, 26};
    return var[c - 'a'];
}

static int is_length_letter(char c) { return strchr("xyzuvwijkqr", c) != NULL; }
static int is_angle_letter(char c) { return c == 'a' || c == 'b' || c == 'c'; }

/* The least input increment of an argument written without a decimal point:
 * lengths in mm or inches, angles in degrees, other addresses whole. */
static double argument_increment(const gc_interp *g, char c)
{
    if (g->opt.calculator_input) return 1.0;
    if (is_length_letter(c)) return g->unit == 1.0 ? 0.001 : 0.0001;
    if (is_angle_letter(c)) return 0.001;
    return 1.0;
}

fm_status gc_fanuc_parse_block(gc_interp *g, size_t p, gc_fanuc_block *fb)
{
    gc_fanuc *f = FANUC(g);
    gc_block *b = &fb->b;
    const gc_line *ln = &g->ln;
    const char *s = ln->s;
    int words = 0;
    while (s[p]) {
        char c = s[p];
        size_t at = p;
        int col = gc_col(ln, at);
        if (c < 'a' || c > 'z') {
            if (c == '#')
                return gc_fail(g, FM_ERR_INPUT, col,
                               "variable assignment after other words; expected '#i = ...' as a "
                               "block of its own");
            return gc_fail(g, FM_ERR_INPUT, col,
                           "unexpected '%c'; expected an address letter (G, M, X, ...)", c);
        }
        if (c == 'n')
            return gc_fail(g, FM_ERR_INPUT, col,
                           "N word after other words; expected the sequence number first");
        if (c == 'o')
            return gc_fail(g, FM_ERR_INPUT, col,
                           "O word after other words; expected the program number alone on its "
                           "line");
        p++;
        gc_fanuc_value v;
        f->in_address = 1;
        f->address_increment = is_length_letter(c) ? (g->unit == 1.0 ? 0.001 : 0.0001)
                               : is_angle_letter(c) ? 0.001 : 0.0;
        fm_status st = gc_fanuc_read_value(g, ln, &p, &v);
        f->in_address = 0;
        if (st) return st;
        words++;
        if (v.vacant) continue; /* Fanuc: an address with a vacant variable is left out */
        if (fb->g65 && c != 'g') {
            if (c == 'p' || c == 'l') {
                if (b->has[L(c)])
                    return gc_fail(g, FM_ERR_INPUT, col, "G65: second %c word", c - 32);
                b->has[L(c)] = 1;
                b->v[L(c)] = v.v;
                b->col[L(c)] = col;
                fb->form[L(c)] = (unsigned char)v.form;
                continue;
            }
            int var = argument_variable(c);
            if (!var)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "G65: %c is not an argument; expected A-Z except G L N O P", c - 32);
            if (!isnan(fb->args[var]))
                return gc_fail(g, FM_ERR_INPUT, col,
                               "G65: second %c argument (argument specification II, repeated "
                               "I J K, is not supported); expected each letter once", c - 32);
            fb->args[var] = v.form == GC_FORM_INTEGER ? v.v * argument_increment(g, c) : v.v;
            continue;
        }
        if (c == 'g') {
            double t = v.v * 10.0;
            double r = floor(t + 0.5);
            char name[32];
            if (fabs(t - r) > 1e-6 || r < 0 || r > 10000)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "G%g: not a G code; expected a number with at most one decimal",
                               v.v);
            int code = (int)r;
            gc_g_name(code, name, sizeof name);
            gc_group grp = gc_fanuc_g_group(code);
            if (grp == GC_GROUP_UNKNOWN)
                return gc_fail(g, FM_ERR_INPUT, col, "%s: unknown G code in the Fanuc dialect",
                               name);
            if (grp == GC_GROUP_REFUSED)
                return gc_fail(g, FM_ERR_INPUT, col, "%s: %s", name, refused(code));
            if (fb->g65)
                return gc_fail(g, FM_ERR_INPUT, col,
                               "%s after G65; expected G65's arguments only", name);
            if (code == GC_G65 || code == GC_G66) {
                /* G66 reads its arguments as G65 does (haas.c keeps them) */
                if (words > 1)
                    return gc_fail(g, FM_ERR_INPUT, col,
                                   "%s after other words; expected %s P<program> first", name,
                                   name);
                fb->g65 = 1;
                fb->g66 = code == GC_G66;
                fb->g65_col = col;
            }
            if (b->ghas[grp]) {
                char other[32];
                gc_g_name(b->gcode[grp], other, sizeof other);
                return gc_fail(g, FM_ERR_INPUT, col,
                               "%s: same modal group as %s on this line; expected one G code per "
                               "group", name, other);
            }
            b->ghas[grp] = 1;
            b->gcode[grp] = code;
            b->gcol[grp] = col;
        } else if (c == 'm') {
            double r = floor(v.v + 0.5);
            if (fabs(v.v - r) > 1e-6 || r < 0 || r > 99999999)
                return gc_fail(g, FM_ERR_INPUT, col, "M%g: not an M code", v.v);
            if (b->nm >= 4)
                return gc_fail(g, FM_ERR_INPUT, col, "more than four M words on one line");
            b->m[b->nm] = (int)r;
            b->mcol[b->nm] = col;
            b->nm++;
        } else {
            if (b->has[L(c)])
                return gc_fail(g, FM_ERR_INPUT, col,
                               "second %c word on one line (first at column %d); expected one",
                               c - 32, b->col[L(c)]);
            b->has[L(c)] = 1;
            b->v[L(c)] = v.v;
            b->col[L(c)] = col;
            fb->form[L(c)] = (unsigned char)v.form;
        }
    }
    return FM_OK;
}
