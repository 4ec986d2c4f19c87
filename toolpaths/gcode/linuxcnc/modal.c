/* modal.c: executing a block in LinuxCNC's order of execution
 * (feed mode, feed, speed, tool, M codes, dwell, plane, units, tool length,
 * coordinate system, distance modes, retract mode, non-modal codes, motion,
 * stops), which updates the modal state and calls the motions and offsets
 * the block asks for. */
#include "linuxcnc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Codes LinuxCNC refuses while cutter radius compensation is on. */
static fm_status comp_refuses(gc_interp *g, int col, const char *what)
{
    if (g->comp.side == GC_COMP_OFF) return FM_OK;
    return gc_fail(g, FM_ERR_INPUT, col, "%s with cutter radius compensation on; expected G40 first",
                   what);
}


fm_status gc_exec_block(gc_interp *g, gc_block *b)
{
    fm_status st;
    int col = 0, code;
    for (int i = 0; i < b->nassign; i++) {
        gc_assign *a = &b->assign[i];
        if (a->name[0]) {
            LC(g)->assign_col = a->col;
            if ((st = gc_set_named(g, a->name, a->v))) return st;
        } else {
            g->params[a->num] = a->v;
        }
    }
    gc_emit_message(g, &g->ln);
    /* M codes: reject unknown ones and conflicting groups before doing anything */
    int mgroups[GC_MGROUP_COUNT] = {0};
    for (int i = 0; i < b->nm; i++) {
        int m = b->m[i];
        gc_mgroup grp;
        switch (m) {
        case 0: case 1: case 2: case 30: case 60: grp = GC_MGROUP_STOP; break;
        case 6: case 61: grp = GC_MGROUP_TOOL_CHANGE; break;
        case 3: case 4: case 5: grp = GC_MGROUP_SPINDLE; break;
        case 7: case 8: case 9: grp = GC_MGROUP_COOLANT; break;
        case 48: case 49: case 50: case 51: case 52: case 53: grp = GC_MGROUP_OVERRIDE; break;
        case 62: case 63: case 64: case 65: case 66: case 67: case 68: grp = GC_MGROUP_IO; break;
        case 70: case 71: case 72: case 73: grp = GC_MGROUP_STATE; break;
        default:
            if (m >= 100 && m <= 199) { grp = GC_MGROUP_USER; break; }
            return gc_fail(g, FM_ERR_INPUT, b->mcol[i], "M%d: unknown M code", m);
        }
        if (grp == GC_MGROUP_USER) continue; /* user M codes run external programs: no motion */
        if (grp != GC_MGROUP_COOLANT && mgroups[grp])
            return gc_fail(g, FM_ERR_INPUT, b->mcol[i],
                           "M%d: same modal group as another M code on this line", m);
        mgroups[grp] = 1;
    }
    /* 1-2: feed mode, feed */
    code = gc_block_g(b, GC_GROUP_FEED_MODE, &col);
    if (code == GC_G93) g->inverse_time = 1;
    else if (code == GC_G94) g->inverse_time = 0;
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
        if ((st = gc_int_word(g, b, 't', &t))) return st;
        if ((st = gc_check_tool(g, t, COL(b, 't'), "T"))) return st;
        g->selected_tool = t;
    }
    if (gc_block_has_m(b, 6, &col)) {
        if ((st = comp_refuses(g, col, "M6 (tool change)"))) return st;
        g->tool = g->selected_tool;
        g->spindle_dir = 0; /* LinuxCNC stops the spindle for a tool change */
        gc_refresh_tool_params(g);
    }
    if (gc_block_has_m(b, 61, &col)) {
        if (!HAS(b, 'q'))
            return gc_fail(g, FM_ERR_INPUT, col, "M61: Q word missing; expected M61 Q<tool>");
        int t = 0;
        if ((st = gc_int_word(g, b, 'q', &t))) return st;
        if ((st = gc_check_tool(g, t, COL(b, 'q'), "Q"))) return st;
        g->tool = g->selected_tool = t;
    }
    /* 6-7: spindle, coolant */
    if (gc_block_has_m(b, 3, NULL)) g->spindle_dir = 1;
    if (gc_block_has_m(b, 4, NULL)) g->spindle_dir = -1;
    if (gc_block_has_m(b, 5, NULL)) g->spindle_dir = 0;
    if (gc_block_has_m(b, 7, NULL)) g->coolant |= 1;
    if (gc_block_has_m(b, 8, NULL)) g->coolant |= 2;
    if (gc_block_has_m(b, 9, NULL)) g->coolant = 0;
    for (int m = 70; m <= 73; m++)
        if (gc_block_has_m(b, m, &col) && (st = gc_exec_modal_state(g, m, col))) return st;
    /* 8: dwell */
    int nonmodal = gc_block_g(b, GC_GROUP_NON_MODAL, &col);
    int nonmodal_col = col;
    if (nonmodal == GC_G4) {
        if (!HAS(b, 'p'))
            return gc_fail(g, FM_ERR_INPUT, nonmodal_col,
                           "G4: dwell time missing; expected P seconds");
        if (VAL(b, 'p') < 0)
            return gc_fail(g, FM_ERR_INPUT, COL(b, 'p'), "G4 P%g: expected P >= 0 seconds",
                           VAL(b, 'p'));
        if ((st = gc_comp_dwell(g, VAL(b, 'p')))) return st;
    }
    /* 9-10: plane, units */
    code = gc_block_g(b, GC_GROUP_PLANE, &col);
    if (code != GC_G_NONE && code / 10 != (int)g->plane &&
        (st = comp_refuses(g, col, "a plane change")))
        return st;
    if (code != GC_G_NONE) g->plane = (gc_plane)(code / 10);
    code = gc_block_g(b, GC_GROUP_UNITS, NULL);
    if (code == GC_G20) gc_set_units(g, GC_INCH);
    else if (code == GC_G21) gc_set_units(g, 1.0);
    /* 11-12: cutter radius compensation, tool length offset */
    code = gc_block_g(b, GC_GROUP_CUTTER_COMP, &col);
    if (code == GC_G40 && (st = gc_comp_off(g, col))) return st;
    if (code != GC_G_NONE && code != GC_G40 && (st = gc_comp_on(g, b, code, col))) return st;
    int tool_length = gc_block_g(b, GC_GROUP_TOOL_LENGTH, &col);
    if (tool_length != GC_G_NONE && (st = comp_refuses(g, col, "a tool length offset change")))
        return st;
    if (tool_length != GC_G_NONE && (st = gc_exec_tool_length(g, b, tool_length, col)))
        return st;
    /* 13-16: coordinate system, path mode, distance modes, retract */
    code = gc_block_g(b, GC_GROUP_COORD_SYSTEM, &col);
    if (code != GC_G_NONE && (st = comp_refuses(g, col, "a coordinate system change"))) return st;
    if (code != GC_G_NONE) gc_set_g5x(g, code <= GC_G59 ? (code - GC_G54) / 10 + 1 : 6 + code - GC_G59);
    code = gc_block_g(b, GC_GROUP_PATH_MODE, NULL);
    if (code == GC_G61) gc_set_path_mode(g, FM_PATH_EXACT_PATH, 0, 0);
    else if (code == GC_G61_1) gc_set_path_mode(g, FM_PATH_EXACT_STOP, 0, 0);
    else if (code == GC_G64) {
        /* G64 P- Q-: Q defaults to P (rs274's convert_control_mode) */
        double p = HAS(b, 'p') ? VAL(b, 'p') * g->unit : 0;
        gc_set_path_mode(g, FM_PATH_BLEND, p, HAS(b, 'q') ? VAL(b, 'q') * g->unit : p);
    }
    code = gc_block_g(b, GC_GROUP_DISTANCE, NULL);
    if (code == GC_G90) g->absolute = 1;
    else if (code == GC_G91) g->absolute = 0;
    code = gc_block_g(b, GC_GROUP_ARC_DISTANCE, NULL);
    if (code == GC_G90_1) g->arc_absolute = 1;
    else if (code == GC_G91_1) g->arc_absolute = 0;
    code = gc_block_g(b, GC_GROUP_RETURN_MODE, NULL);
    if (code == GC_G98) g->retract_r = 0;
    else if (code == GC_G99) g->retract_r = 1;
    /* 17-18: non-modal codes and motion */
    int mcol = 0;
    int mcode = gc_block_g(b, GC_GROUP_MOTION, &mcol);
    int axes = gc_block_has_axis(b) || b->has_radius || b->has_theta;
    /* codes whose X Y Z are not a motion's end point */
    int other_uses_axes = nonmodal == GC_G10 || nonmodal == GC_G28 || nonmodal == GC_G30 ||
                          nonmodal == GC_G92 || nonmodal == GC_G52 || tool_length == GC_G43_1;
    if (b->has_radius || b->has_theta) {
        int pcol = b->has_radius ? b->radius_col : b->theta_col;
        if (g->plane != GC_PLANE_XY)
            return gc_fail(g, FM_ERR_INPUT, pcol,
                           "polar coordinates in the G%d plane; expected G17", (int)g->plane);
        if (HAS(b, 'x') || HAS(b, 'y'))
            return gc_fail(g, FM_ERR_INPUT, HAS(b, 'x') ? COL(b, 'x') : COL(b, 'y'),
                           "%c word with polar coordinates; expected @ and ^ or X and Y",
                           HAS(b, 'x') ? 'X' : 'Y');
        if (other_uses_axes)
            return gc_fail(g, FM_ERR_INPUT, pcol,
                           "polar coordinates with a code that is not a motion; expected them "
                           "with G0, G1, G2, G3 or a canned cycle");
    }
    if (mcode != GC_G_NONE && other_uses_axes && axes && mcode != GC_G80) {
        char a1[32], a2[32];
        gc_g_name(mcode, a1, sizeof a1);
        gc_g_name(nonmodal != GC_G_NONE ? nonmodal : GC_G43_1, a2, sizeof a2);
        return gc_fail(g, FM_ERR_INPUT, mcol,
                       "%s and %s on one line both use the axis words; expected one of them",
                       a1, a2);
    }
    switch (nonmodal) {
    case GC_G10: if ((st = gc_exec_g10(g, b, nonmodal_col))) return st; break;
    case GC_G28: case GC_G30:
        if ((st = comp_refuses(g, nonmodal_col, nonmodal == GC_G28 ? "G28" : "G30"))) return st;
        if ((st = gc_exec_home(g, b, nonmodal))) return st;
        break;
    case GC_G28_1: case GC_G30_1: gc_store_home(g, nonmodal); break;
    case GC_G92: case GC_G52:
        if ((st = comp_refuses(g, nonmodal_col, nonmodal == GC_G92 ? "G92" : "G52"))) return st;
        /* fall through */
    case GC_G92_1: case GC_G92_2: case GC_G92_3:
        if ((st = gc_exec_g92(g, b, nonmodal, nonmodal_col))) return st;
        break;
    default: break;
    }
    if (mcode == GC_G80) {
        g->motion = GC_G80;
        g->cycle_il_flag = 0;
        if (axes && !other_uses_axes)
            return gc_fail(g, FM_ERR_INPUT, gc_first_axis_col(b),
                           "axis words with G80; expected G0, G1, G2, G3 or a canned cycle");
    }
    int motion = mcode != GC_G_NONE ? mcode
                 : (axes && !other_uses_axes ? (int)g->motion : GC_G_NONE);
    if (nonmodal == GC_G53 && motion != GC_G0 && motion != GC_G1)
        return gc_fail(g, FM_ERR_INPUT, nonmodal_col, "G53: expected G0 or G1 on the same line");
    if (nonmodal == GC_G53 && !g->absolute)
        return gc_fail(g, FM_ERR_INPUT, nonmodal_col,
                       "G53 in incremental mode (G91); expected G90");
    if (motion != GC_G_NONE && motion != GC_G80) {
        if (mcol == 0) mcol = gc_first_axis_col(b);
        int has_words = (axes || b->has_radius || b->has_theta) && !other_uses_axes;
        if (motion == GC_G0 || motion == GC_G1 || motion == GC_G2 || motion == GC_G3)
            g->cycle_il_flag = 0;
        if (motion == GC_G0 || motion == GC_G1) {
            g->motion = (gc_gcode)motion;
            /* a G0 or G1 without axis words still moves, nowhere (rs274) */
            if (has_words || mcode != GC_G_NONE) {
                if (motion == GC_G1) {
                    if ((st = gc_check_feed(g, "G1", mcol))) return st;
                    if (g->inverse_time && !HAS(b, 'f'))
                        return gc_fail(g, FM_ERR_INPUT, mcol,
                                       "G1 in inverse time (G93) without F; expected an F word "
                                       "on every feed line");
                }
                if ((st = gc_exec_straight(g, b, motion == GC_G0, nonmodal == GC_G53, mcol)))
                    return st;
            }
        } else if (motion == GC_G2 || motion == GC_G3) {
            g->motion = (gc_gcode)motion;
            if (g->inverse_time && !HAS(b, 'f'))
                return gc_fail(g, FM_ERR_INPUT, mcol,
                               "G%d in inverse time (G93) without F; expected an F word on every "
                               "feed line", motion / 10);
            if (has_words || mcode != GC_G_NONE || HAS(b, 'i') || HAS(b, 'j') || HAS(b, 'k') ||
                HAS(b, 'r'))
                if ((st = gc_exec_arc(g, b, motion, mcol))) return st;
        } else if (motion == GC_G5 || motion == GC_G5_1 || motion == GC_G5_2 ||
                   motion == GC_G5_3) {
            if ((st = comp_refuses(g, mcol, "a spline (G5.x)"))) return st;
            if ((st = gc_exec_spline(g, b, motion, mcode != GC_G_NONE, mcol))) return st;
        } else if (motion == GC_G33 || motion == GC_G33_1) {
            if ((st = comp_refuses(g, mcol, motion == GC_G33 ? "G33" : "G33.1"))) return st;
            g->motion = (gc_gcode)motion;
            if ((st = gc_exec_sync(g, b, motion, mcol))) return st;
        } else if (motion == GC_G38_2 || motion == GC_G38_3 || motion == GC_G38_4 ||
                   motion == GC_G38_5) {
            if ((st = comp_refuses(g, mcol, "probing (G38.x)"))) return st;
            g->motion = (gc_gcode)motion;
            if ((st = gc_exec_probe(g, b, motion, mcol))) return st;
        } else {
            if ((st = comp_refuses(g, mcol, "a canned cycle"))) return st;
            if ((st = gc_exec_cycle(g, b, motion, mcol))) return st;
        }
    } else if ((axes || b->has_radius || b->has_theta) && !other_uses_axes &&
               g->motion == GC_G80) {
        return gc_fail(g, FM_ERR_INPUT, gc_first_axis_col(b),
                       "axis words without a motion mode; expected G0, G1, G2, G3 or a canned "
                       "cycle");
    }
    /* 19: stops */
    /* after a tool change rs274 takes the current point back from its canon,
     * which knows nothing of tool length offsets: an offset changed since the
     * last motion does not shift the current point */
    if (gc_block_has_m(b, 6, NULL) || gc_block_has_m(b, 61, NULL)) {
        gc_from_machine(g, g->canon, g->pos);
        memcpy(g->mpos, g->canon, sizeof g->mpos);
    }
    if (gc_block_has_m(b, 2, NULL) || gc_block_has_m(b, 30, NULL)) {
        if ((st = gc_comp_finish(g))) return st;
        g->ended = 1;
        g->stop = 1;
    }
    return FM_OK;
}

