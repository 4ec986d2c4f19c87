/* transform.c: the program frame of the ISO dialects (Fanuc, Haas and the
 * controls that follow them): the programmed point and the programmable
 * transforms between it and work coordinates. From the program frame: G16
 * polar coordinates (in how an end point is read), G51 uniform scaling about
 * a centre, G68 rotation about a centre in a plane, then G51.1 mirror image,
 * which reflects all the rest (given first, it mirrors what the program's
 * own scaling and rotation make, so a rotation turns the other way). The
 * front end reads the words and decides what its dialect refuses; the
 * machine keeps the state (gc_interp.frame), maps points both ways and moves
 * through the frame and cutter compensation C. LinuxCNC keeps its own G10
 * L2 R rotation and @^ polar words (rs274's). */
#include "machine.h"

#include <math.h>
#include <string.h>

static void mirror_point(const gc_program_frame *f, double p[3])
{
    for (int i = 0; i < 3; i++)
        if (f->mirror[i]) p[i] = 2 * f->mirror_center[i] - p[i];
}

void gc_frame_to_work(const gc_interp *g, const double prog[3], double work[3])
{
    const gc_program_frame *f = &g->frame;
    memcpy(work, prog, 3 * sizeof *work);
    if (f->scaling)
        for (int i = 0; i < 3; i++)
            work[i] = f->scale_center[i] + f->scale * (work[i] - f->scale_center[i]);
    if (f->rotation) {
        int a, b, c;
        gc_plane_axes(f->rot_plane, &a, &b, &c);
        double ca = f->rot_center[0], cb = f->rot_center[1];
        if (f->scaling) {
            ca = f->scale_center[a] + f->scale * (ca - f->scale_center[a]);
            cb = f->scale_center[b] + f->scale * (cb - f->scale_center[b]);
        }
        double da = work[a] - ca, db = work[b] - cb;
        work[a] = ca + f->rot_cos * da - f->rot_sin * db;
        work[b] = cb + f->rot_sin * da + f->rot_cos * db;
    }
    mirror_point(f, work);
}

void gc_frame_from_work(const gc_interp *g, const double work[3], double prog[3])
{
    const gc_program_frame *f = &g->frame;
    memcpy(prog, work, 3 * sizeof *prog);
    mirror_point(f, prog);
    if (f->rotation) {
        int a, b, c;
        gc_plane_axes(f->rot_plane, &a, &b, &c);
        double ca = f->rot_center[0], cb = f->rot_center[1];
        if (f->scaling) {
            ca = f->scale_center[a] + f->scale * (ca - f->scale_center[a]);
            cb = f->scale_center[b] + f->scale * (cb - f->scale_center[b]);
        }
        double da = prog[a] - ca, db = prog[b] - cb;
        prog[a] = ca + f->rot_cos * da + f->rot_sin * db;
        prog[b] = cb - f->rot_sin * da + f->rot_cos * db;
    }
    if (f->scaling)
        for (int i = 0; i < 3; i++)
            prog[i] = f->scale_center[i] + (prog[i] - f->scale_center[i]) / f->scale;
}

void gc_frame_reprogram(gc_interp *g) { gc_frame_from_work(g, g->pos, g->frame.prog); }

int gc_frame_transformed(const gc_interp *g)
{
    const gc_program_frame *f = &g->frame;
    return f->rotation || f->scaling || f->mirror[0] || f->mirror[1] || f->mirror[2];
}

int gc_frame_mirror_sense(const gc_interp *g)
{
    int a, b, c;
    gc_plane_axes(g->plane, &a, &b, &c);
    return (g->frame.mirror[a] ^ g->frame.mirror[b]) ? -1 : 1;
}

void gc_frame_target(gc_interp *g, const gc_axis_words *w, double end[3])
{
    gc_program_frame *f = &g->frame;
    const int *given = w->given;
    const double *value = w->value;
    gc_rot_target(g, w->rgiven, w->rvalue);
    int a, bb, c;
    gc_plane_axes(g->plane, &a, &bb, &c);
    for (int i = 0; i < 3; i++) {
        if (f->polar && (i == a || i == bb)) continue;
        if (!given[i]) end[i] = f->prog[i];
        else if (g->absolute) end[i] = value[i];
        else end[i] = f->prog[i] + value[i];
    }
    if (!f->polar) return;
    if (!given[a] && !given[bb]) {
        end[a] = f->prog[a];
        end[bb] = f->prog[bb];
        return;
    }
    /* Fanuc G16: a radius given in G90 is measured from the work zero, in
     * G91 from the current point; without a radius the last radius and
     * origin stay. The angle is absolute in G90, added to the last one in
     * G91. */
    if (given[a]) {
        f->polar_radius = value[a];
        f->polar_origin[0] = g->absolute ? 0.0 : f->prog[a];
        f->polar_origin[1] = g->absolute ? 0.0 : f->prog[bb];
    }
    if (given[bb]) f->polar_angle = (g->absolute ? 0.0 : f->polar_angle) + value[bb];
    double r = f->polar_radius, ang = f->polar_angle * FM_PI / 180.0;
    end[a] = f->polar_origin[0] + r * cos(ang);
    end[bb] = f->polar_origin[1] + r * sin(ang);
}

void gc_frame_polar(gc_interp *g, int on)
{
    gc_program_frame *f = &g->frame;
    if (!on) {
        f->polar = 0;
        return;
    }
    if (f->polar) return;
    int a, b, c;
    gc_plane_axes(g->plane, &a, &b, &c);
    f->polar = 1;
    f->polar_radius = hypot(f->prog[a], f->prog[b]);
    f->polar_angle = atan2(f->prog[b], f->prog[a]) * 180.0 / FM_PI;
    f->polar_origin[0] = f->polar_origin[1] = 0;
}

void gc_frame_scale(gc_interp *g, double k, const double center[3])
{
    gc_program_frame *f = &g->frame;
    if (k > 0) {
        memcpy(f->scale_center, center, sizeof f->scale_center);
        f->scale = k;
    }
    f->scaling = k > 0;
    gc_frame_reprogram(g);
}

void gc_frame_rotate(gc_interp *g, int on, const double center[2], double degrees)
{
    gc_program_frame *f = &g->frame;
    f->rotation = on;
    if (on) {
        f->rot_plane = g->plane;
        f->rot_center[0] = center[0];
        f->rot_center[1] = center[1];
        f->rot_angle = degrees;
        f->rot_cos = cos(degrees * FM_PI / 180.0);
        f->rot_sin = sin(degrees * FM_PI / 180.0);
    }
    gc_frame_reprogram(g);
}

void gc_frame_mirror(gc_interp *g, const int axes[3], const double center[3], int on)
{
    gc_program_frame *f = &g->frame;
    for (int i = 0; i < 3; i++) {
        if (!axes[i]) continue;
        if (on) f->mirror_center[i] = center[i];
        f->mirror[i] = on;
    }
    /* the tool stays where it is: its programmed point is seen through the
     * new mirror */
    gc_frame_reprogram(g);
}

void gc_frame_scale_units(gc_interp *g, double k)
{
    gc_program_frame *f = &g->frame;
    for (int i = 0; i < 3; i++) {
        f->prog[i] *= k;
        f->scale_center[i] *= k;
    }
    f->rot_center[0] *= k;
    f->rot_center[1] *= k;
    f->polar_radius *= k;
    f->polar_origin[0] *= k;
    f->polar_origin[1] *= k;
}

/* ---- moves through the frame and compensation C ---- */

fm_status gc_frame_line_work(gc_interp *g, int rapid, const double work[3])
{
    if (gc_comp_c_routing(g)) return gc_comp_c_line(g, rapid, work, g->motion_col);
    return gc_move_line(g, rapid, work);
}

fm_status gc_frame_arc_work(gc_interp *g, const double work[3], const double center_ab[2], int turn)
{
    if (gc_comp_c_routing(g)) return gc_comp_c_arc(g, work, center_ab, turn, g->motion_col);
    return gc_move_arc(g, work, center_ab, turn);
}

fm_status gc_frame_dwell(gc_interp *g, double seconds)
{
    if (gc_comp_c_routing(g)) return gc_comp_c_dwell(g, seconds);
    return gc_dwell(g, seconds);
}

fm_status gc_frame_move(gc_interp *g, int rapid, const double prog_end[3])
{
    double work[3];
    gc_frame_to_work(g, prog_end, work);
    memcpy(g->frame.prog, prog_end, sizeof g->frame.prog);
    return gc_frame_line_work(g, rapid, work);
}

fm_status gc_frame_arc(gc_interp *g, const double prog_end[3], const double prog_center[3], int ccw,
                       int compensate)
{
    int a, b, c;
    gc_plane_axes(g->plane, &a, &b, &c);
    double wend[3], wcen[3];
    gc_frame_to_work(g, prog_end, wend);
    gc_frame_to_work(g, prog_center, wcen);
    double cab[2] = {wcen[a], wcen[b]};
    memcpy(g->frame.prog, prog_end, sizeof g->frame.prog);
    int turn = (ccw ? 1 : -1) * gc_frame_mirror_sense(g);
    return compensate ? gc_frame_arc_work(g, wend, cab, turn) : gc_move_arc(g, wend, cab, turn);
}
