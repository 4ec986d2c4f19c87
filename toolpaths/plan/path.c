/* path.c: where the tool really goes (docs/plan.md, "Where the tool
 * goes"): the planner's motions with their blend arcs -> the path the
 * machine follows, as motions: a line that ends in a blended corner is
 * trimmed to its blend arc's start, the arc follows (a G17/G18/G19 arc when
 * the corner lies in an axis plane, chords within a tolerance otherwise),
 * and the next line starts at the arc's end. Corners whose geometry is not
 * two straight lines meeting at the programmed point keep the programmed
 * corner (see the docs for which). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "toolpaths/plan/plan.h"

struct fm_plan_path {
    fm_plan_path_options opt;
    fm_plan_path_sink sink;
    void *user;
    int held;             /* a motion waits for the next one (its corner) */
    fm_plan_motion h;     /* that motion */
    double h_start[3];    /* where it starts: its start, or the arc before's end */
    double h_f0;          /* that point's share of its length */
    double h_t0;          /* planned times: when it starts */
    long blends;
    int stopped;
};

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double dist3(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(dot3(d, d));
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

void fm_plan_path_options_default(fm_plan_path_options *o)
{
    memset(o, 0, sizeof *o);
    o->chord_tolerance = 0.001;
}

fm_plan_path *fm_plan_path_new(const fm_plan_path_options *opt, fm_plan_path_sink sink, void *user,
                               fm_error *err)
{
    fm_plan_path *p = calloc(1, sizeof *p);
    if (!p) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory for the blended path");
        return NULL;
    }
    if (opt)
        p->opt = *opt;
    else
        fm_plan_path_options_default(&p->opt);
    if (!(p->opt.chord_tolerance > 0.0)) p->opt.chord_tolerance = 0.001;
    p->sink = sink;
    p->user = user;
    return p;
}

void fm_plan_path_free(fm_plan_path *p) { free(p); }

long fm_plan_path_blends(const fm_plan_path *p) { return p->blends; }

static int straight(const fm_motion *m)
{
    return (m->kind == FM_MOTION_LINE || m->kind == FM_MOTION_RAPID) &&
           !(m->machine && m->machine->rotary_count > 0);
}

/* The share of m's length at which point q lies on it, or -1 when q is
 * not on its segment (within 1e-7 mm). */
static double share_on(const fm_motion *m, const double q[3])
{
    double d[3] = {m->end[0] - m->start[0], m->end[1] - m->start[1], m->end[2] - m->start[2]};
    double L2 = dot3(d, d);
    if (!(L2 > 1e-18)) return -1.0;
    double w[3] = {q[0] - m->start[0], q[1] - m->start[1], q[2] - m->start[2]};
    double s = dot3(w, d) / L2;
    double off[3] = {w[0] - s * d[0], w[1] - s * d[1], w[2] - s * d[2]};
    double L = sqrt(L2);
    if (sqrt(dot3(off, off)) > 1e-7 || s < -1e-9 / L || s > 1.0 + 1e-9 / L) return -1.0;
    return fmax(0.0, fmin(1.0, s));
}

/* Can the held motion's blend arc be followed into next: two straight
 * moves of the same kind and tool meeting at the programmed corner, the
 * arc's ends on them (a naive-CAM chain's merged line or an arc's
 * neighbour does not qualify: docs/plan.md). *f1, *g0: the arc's ends'
 * shares of the two motions. */
static int followable(const fm_plan_path *p, const fm_motion *next, double *f1, double *g0)
{
    const fm_plan_motion *h = &p->h;
    const fm_motion *a = &h->motion;
    if (!h->has_blend || !straight(a) || !straight(next) || a->kind != next->kind) return 0;
    if (a->tool != next->tool || dist3(a->end, next->start) > 1e-9) return 0;
    for (int i = 0; i < 3; i++)
        if (a->tip_offset[i] != next->tip_offset[i] || a->axis_end[i] != next->axis_start[i] ||
            a->axis_start[i] != a->axis_end[i] || next->axis_start[i] != next->axis_end[i])
            return 0;
    *f1 = share_on(a, h->blend_out.start);
    *g0 = share_on(next, h->blend_out.end);
    return *f1 >= p->h_f0 - 1e-12 && *g0 >= 0.0;
}

static int emit(fm_plan_path *p, const fm_motion *m, int blend, int continues)
{
    if (p->sink(p->user, m, blend, continues)) {
        p->stopped = 1;
        return 1;
    }
    return 0;
}

static double lerp(double a, double b, double f) { return a + (b - a) * f; }

/* The blend arc after the held motion, from its own time t0 to t1. */
static int emit_arc(fm_plan_path *p, double t0, double t1)
{
    const fm_plan_blend *b = &p->h.blend_out;
    const fm_motion *a = &p->h.motion;
    double u1[3], u2[3], n[3];
    for (int i = 0; i < 3; i++) {
        u1[i] = b->center[i] - b->start[i]; /* the arc's radius vectors, centre - point */
        u2[i] = b->center[i] - b->end[i];
    }
    /* the turn's axis: start radius to end radius about it, positively */
    double r0[3] = {-u1[0], -u1[1], -u1[2]}, r1[3] = {-u2[0], -u2[1], -u2[2]};
    cross3(r0, r1, n);
    double nn = sqrt(dot3(n, n));
    if (!(nn > 0.0)) return 0;
    for (int i = 0; i < 3; i++) n[i] /= nn;
    fm_motion arc = *a;
    arc.t0 = t0;
    arc.t1 = t1;
    int axis = -1;
    for (int k = 0; k < 3; k++)
        if (fabs(n[k]) >= 1.0 - 1e-12) axis = k;
    if (axis >= 0 && a->kind == FM_MOTION_LINE) {
        /* a corner in an axis plane: the arc itself (G17/G18/G19) */
        arc.kind = FM_MOTION_ARC;
        memcpy(arc.start, b->start, sizeof arc.start);
        memcpy(arc.end, b->end, sizeof arc.end);
        memcpy(arc.center, b->center, sizeof arc.center);
        arc.center[axis] = b->start[axis];
        arc.end[axis] = b->start[axis];
        arc.plane_axis = axis;
        arc.turns = n[axis] > 0.0 ? 1 : -1;
        return emit(p, &arc, 1, 0);
    }
    /* Out of the axis planes (or a rapid's corner, which stays a rapid for
     * the check): chords whose sagitta is within the tolerance. */
    double R = b->radius, tol = fmin(p->opt.chord_tolerance, R);
    double step = 2.0 * acos(1.0 - tol / R);
    int count = (int)ceil(b->angle / fmax(step, 1e-6));
    if (count < 1) count = 1;
    if (count > 10000) count = 10000;
    double v[3]; /* n x r0: the radius a quarter turn on */
    cross3(n, r0, v);
    double prev[3];
    memcpy(prev, b->start, sizeof prev);
    for (int j = 1; j <= count; j++) {
        double phi = b->angle * j / count, q[3];
        for (int i = 0; i < 3; i++) q[i] = j == count ? b->end[i] : b->center[i] + cos(phi) * r0[i] + sin(phi) * v[i];
        fm_motion chord = arc;
        chord.kind = a->kind;
        memcpy(chord.start, prev, sizeof chord.start);
        memcpy(chord.end, q, sizeof chord.end);
        chord.t0 = lerp(t0, t1, (double)(j - 1) / count);
        chord.t1 = j == count ? t1 : lerp(t0, t1, (double)j / count);
        if (emit(p, &chord, 1, j < count)) return 1;
        memcpy(prev, q, sizeof prev);
    }
    return 0;
}

/* The held motion goes out: trimmed to its blend arc and the arc after it
 * when next follows it through the corner (next NULL: the program ended). */
static int release(fm_plan_path *p, const fm_plan_motion *next, double *next_start, double *next_f0,
                   double *next_t0)
{
    fm_plan_motion *h = &p->h;
    fm_motion piece = h->motion;
    const int planned = p->opt.planned_times;
    double f1 = 1.0, g0 = 0.0;
    int follow = next && followable(p, &next->motion, &f1, &g0);
    memcpy(piece.start, p->h_start, sizeof piece.start);
    double ft0 = h->feed_t0, ft1 = h->feed_t1;
    piece.t0 = planned ? p->h_t0 : lerp(ft0, ft1, p->h_f0);
    if (follow) {
        memcpy(piece.end, h->blend_out.start, sizeof piece.end);
        piece.t1 = planned ? h->blend_out.t0 : lerp(ft0, ft1, f1);
    } else {
        piece.t1 = planned ? h->motion.t1 : ft1;
    }
    if (next) {
        memcpy(next_start, next->motion.start, 3 * sizeof *next_start);
        *next_f0 = 0.0;
        *next_t0 = next->motion.t0;
    }
    if (emit(p, &piece, 0, follow)) return 1;
    if (!follow) return 0;
    p->blends++;
    double arc_t1 = planned ? h->blend_out.t1 : lerp(next->feed_t0, next->feed_t1, g0);
    memcpy(next_start, h->blend_out.end, 3 * sizeof *next_start);
    *next_f0 = g0;
    *next_t0 = arc_t1;
    return emit_arc(p, piece.t1, arc_t1);
}

int fm_plan_path_push(void *path, const fm_plan_motion *m)
{
    fm_plan_path *p = path;
    if (p->stopped) return 1;
    double start[3], f0 = 0.0, t0 = m->motion.t0;
    memcpy(start, m->motion.start, sizeof start);
    if (p->held && release(p, m, start, &f0, &t0)) return 1;
    p->h = *m;
    memcpy(p->h_start, start, sizeof start);
    p->h_f0 = f0;
    p->h_t0 = t0;
    p->held = 1;
    return 0;
}

int fm_plan_path_finish(fm_plan_path *p)
{
    if (p->stopped) return 1;
    if (!p->held) return 0;
    p->held = 0;
    return release(p, NULL, NULL, NULL, NULL);
}
