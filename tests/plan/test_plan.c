/* test_plan: the planner's profile maths against closed forms worked by
 * hand (docs/plan.md has the formulas): a move reaching its feed and one
 * too short to reach it (a triangle), a move limited by the axis rather
 * than the feed, a diagonal rapid with each axis at its own limit, a full
 * circle at its normal-acceleration limit, a 90 degree corner blended at
 * G64 P0.1 (the blend radius and speed), the same corner in exact stop, a
 * dwell, the feed-only default, and that motions stream out before the
 * program ends. */
#include "test.h"
#include "toolpaths/gcode/gcode.h"
#include "toolpaths/plan/plan_internal.h"

typedef struct collected {
    fm_plan_motion m[64];
    int n;
} collected;

static int collect(void *user, const fm_plan_motion *pm)
{
    collected *c = user;
    if (c->n < 64) c->m[c->n] = *pm;
    c->n++;
    return 0;
}

/* A machine with the same limits on X, Y and Z. */
static fm_plan_machine machine(double v, double a)
{
    fm_plan_machine m;
    fm_plan_machine_default(&m);
    m.given = 1;
    for (int i = 0; i < 3; i++) {
        m.linear[i].max_velocity = v;
        m.linear[i].max_acceleration = a;
    }
    return m;
}

static fm_motion line(double x0, double y0, double x1, double y1, double feed)
{
    fm_motion mo = {0};
    mo.kind = feed > 0.0 ? FM_MOTION_LINE : FM_MOTION_RAPID;
    mo.start[0] = x0;
    mo.start[1] = y0;
    mo.end[0] = x1;
    mo.end[1] = y1;
    mo.feed = feed;
    mo.axis_start[2] = mo.axis_end[2] = 1.0;
    return mo;
}

static double plan(const fm_plan_machine *m, const fm_motion *mo, int n, collected *c)
{
    fm_error err = {0};
    fm_planner *p = fm_planner_new(m, collect, c, &err);
    CHECK(p != NULL);
    double t = 0.0;
    for (int i = 0; i < n; i++) {
        fm_motion x = mo[i];
        double len = hypot(x.end[0] - x.start[0], x.end[1] - x.start[1]);
        x.t0 = t;
        if (x.kind != FM_MOTION_DWELL) t += len / (x.feed > 0 ? x.feed / 60.0 : 5000.0 / 60.0);
        else t = x.t1;
        x.t1 = t;
        x.index = i;
        CHECK(fm_planner_push(p, &x, &err) == FM_OK);
    }
    fm_plan_totals tot;
    CHECK(fm_planner_finish(p, &tot, &err) == FM_OK);
    fm_planner_free(p);
    return tot.cycle_time_s;
}

/* rest to rest over L at most at v with acceleration a */
static double rest_to_rest(double L, double v, double a)
{
    if (v * v / a >= L) return 2.0 * sqrt(L / a); /* triangle */
    return L / v + v / a;
}

static void test_single_moves(void)
{
    fm_plan_machine m = machine(100.0, 500.0);
    collected c = {0};
    /* 100 mm at F1200: reaches 20 mm/s; 5 s at speed plus v/a */
    fm_motion a = line(0, 0, 100, 0, 1200);
    CHECK_NEAR(plan(&m, &a, 1, &c), 100.0 / 20.0 + 20.0 / 500.0, 1e-9);
    CHECK(c.n == 1);
    CHECK_NEAR(c.m[0].motion.t0, 0.0, 1e-12);
    CHECK_NEAR(c.m[0].feed_t1, 5.0, 1e-9);
    /* 1 mm at F6000: too short for 100 mm/s, a triangle to sqrt(a L) */
    c.n = 0;
    fm_motion b = line(0, 0, 1, 0, 6000);
    CHECK_NEAR(plan(&m, &b, 1, &c), 2.0 * sqrt(1.0 / 500.0), 1e-9);
    CHECK_NEAR(rest_to_rest(1.0, 100.0, 500.0), 2.0 * sqrt(1.0 / 500.0), 1e-12);
    /* F9000 (150 mm/s) on a 100 mm/s axis: the axis limits it */
    c.n = 0;
    fm_motion d = line(0, 0, 100, 0, 9000);
    CHECK_NEAR(plan(&m, &d, 1, &c), 100.0 / 100.0 + 100.0 / 500.0, 1e-9);
}

static void test_rapid_per_axis(void)
{
    /* X 100 mm/s, 1000 mm/s^2; Y 50 mm/s, 500 mm/s^2: a rapid to (100, 100)
     * moves along its line as fast as Y allows: 50 mm/s and 500 mm/s^2 on
     * Y, 70.7 mm/s and 707 mm/s^2 along the line. */
    fm_plan_machine m = machine(100.0, 1000.0);
    m.linear[1].max_velocity = 50.0;
    m.linear[1].max_acceleration = 500.0;
    collected c = {0};
    fm_motion r = line(0, 0, 100, 100, 0);
    double L = 100.0 * sqrt(2.0), v = 50.0 * sqrt(2.0), a = 500.0 * sqrt(2.0);
    CHECK_NEAR(plan(&m, &r, 1, &c), L / v + v / a, 1e-9);
    /* separate rapid rates: G0 at 80 mm/s on X alone */
    m.rapid_velocity[0] = 80.0;
    c.n = 0;
    fm_motion x = line(0, 0, 100, 0, 0);
    CHECK_NEAR(plan(&m, &x, 1, &c), 100.0 / 80.0 + 80.0 / 1000.0, 1e-9);
}

static void test_circle_at_normal_limit(void)
{
    /* A full circle of radius 5 at F6000 on 100 mm/s, 500 mm/s^2 axes: the
     * normal acceleration v^2/R may use 0.866 a, so v = sqrt(0.866 * 500 * 5)
     * = 46.53 mm/s; speeding up and slowing down use half of a. */
    fm_plan_machine m = machine(100.0, 500.0);
    fm_motion mo = {0};
    mo.kind = FM_MOTION_ARC;
    mo.start[0] = mo.end[0] = 5.0;
    mo.plane_axis = 2;
    mo.turns = -1;
    mo.feed = 6000.0;
    collected c = {0};
    double v = sqrt(sqrt(3.0) / 2.0 * 500.0 * 5.0);
    CHECK_NEAR(v, 46.5302, 1e-4);
    CHECK_NEAR(plan(&m, &mo, 1, &c), rest_to_rest(2.0 * PLAN_PI * 5.0, v, 250.0), 1e-9);
    /* slower than the limit, the tangential share is what the normal
     * acceleration leaves: F1200 gives 20^2/5 = 80 mm/s^2 normal, so
     * sqrt(1 - (80/500)^2) of 500 along the path -- but the share is taken
     * at the machine's velocity (100 mm/s) capped by the limit: 0.5 */
    double vmax, ratio;
    plan_curvature_limits(50.0, 100.0, 500.0, &vmax, &ratio);
    CHECK_NEAR(vmax, 100.0, 1e-12);
    CHECK_NEAR(ratio, sqrt(1.0 - (200.0 / 500.0) * (200.0 / 500.0)), 1e-12);
}

static void test_blend_corner(void)
{
    /* Two 50 mm lines at 90 degrees, F1200, G64 P0.1, 500 mm/s^2 axes. By
     * hand: theta = 45 deg; the tolerance allows d = cos(theta) T / (1 -
     * sin(theta)) = 0.24142 mm from the corner, so R = tan(theta) d =
     * 0.24142 mm; the normal acceleration 0.866 * 500 there allows v =
     * sqrt(433.01 * 0.24142) = 10.224 mm/s, below the feed. */
    fm_plan_machine m = machine(100.0, 500.0);
    fm_motion mo[2] = {line(0, 0, 50, 0, 1200), line(50, 0, 50, 50, 1200)};
    mo[0].path_tolerance = mo[1].path_tolerance = 0.1;
    collected c = {0};
    double t = plan(&m, mo, 2, &c);
    double th = PLAN_PI / 4.0, T = 0.1;
    double d = cos(th) * T / (1.0 - sin(th));
    double R = tan(th) * d;
    double an = sqrt(3.0) / 2.0 * 500.0;
    double vb = sqrt(an * R);
    CHECK_NEAR(R, 0.241421, 1e-6);
    CHECK_NEAR(vb, 10.2244, 1e-4);
    CHECK(c.n == 2);
    CHECK(c.m[0].has_blend);
    CHECK_NEAR(c.m[0].blend_out.radius, R, 1e-9);
    CHECK_NEAR(c.m[0].blend_out.speed, vb, 1e-9);
    CHECK_NEAR(c.m[0].blend_out.angle, PLAN_PI / 2.0, 1e-12);
    CHECK_NEAR(c.m[0].blend_out.start[0], 50.0 - d, 1e-9);
    CHECK_NEAR(c.m[0].blend_out.end[1], d, 1e-9);
    CHECK_NEAR(c.m[0].blend_out.center[0], 50.0 - R, 1e-9);
    CHECK_NEAR(c.m[0].blend_out.center[1], R, 1e-9);
    /* each line: from rest to 20 mm/s, down to vb at the blend (and the
     * mirror after it); the arc at vb */
    double a = 500.0, v = 20.0, L = 50.0 - d;
    double s_up = v * v / (2 * a), s_down = (v * v - vb * vb) / (2 * a);
    double t_line = v / a + (v - vb) / a + (L - s_up - s_down) / v;
    double t_arc = R * PLAN_PI / 2.0 / vb;
    CHECK_NEAR(t, 2.0 * t_line + t_arc, 1e-9);
    /* the corner's time is split at the middle of the arc */
    CHECK_NEAR(c.m[0].motion.t1, t_line + t_arc / 2.0, 1e-9);
    CHECK_NEAR(c.m[1].motion.t0, c.m[0].motion.t1, 1e-12);
    CHECK_NEAR(c.m[1].motion.t1, t, 1e-12);
    /* exact stop: both lines rest to rest */
    mo[0].path_mode = mo[1].path_mode = FM_PATH_EXACT_STOP;
    c.n = 0;
    CHECK_NEAR(plan(&m, mo, 2, &c), 2.0 * rest_to_rest(50.0, 20.0, 500.0), 1e-9);
    CHECK(!c.m[0].has_blend);
    /* LinuxCNC's G61 also stops at a corner, and both feed moves keep the
     * kink's acceleration reduction (ARC_BLEND_TANGENT_KINK_RATIO, 0.1):
     * 450 mm/s^2 */
    mo[0].path_mode = mo[1].path_mode = FM_PATH_EXACT_PATH;
    c.n = 0;
    CHECK_NEAR(plan(&m, mo, 2, &c), 2.0 * rest_to_rest(50.0, 20.0, 450.0), 1e-9);
    /* but flows through a collinear joint in G61 */
    fm_motion col[2] = {line(0, 0, 25, 0, 1200), line(25, 0, 50, 0, 1200)};
    col[0].path_mode = col[1].path_mode = FM_PATH_EXACT_PATH;
    c.n = 0;
    CHECK_NEAR(plan(&m, col, 2, &c), rest_to_rest(50.0, 20.0, 500.0), 1e-9);
}

typedef struct pieces {
    fm_motion m[64];
    int blend[64], continues[64];
    int n;
} pieces;

static int collect_piece(void *user, const fm_motion *m, int blend, int continues)
{
    pieces *c = user;
    if (c->n < 64) {
        c->m[c->n] = *m;
        c->blend[c->n] = blend;
        c->continues[c->n] = continues;
    }
    c->n++;
    return 0;
}

/* The planner's motions through the path follower. */
static void plan_path(const fm_plan_machine *m, const fm_motion *mo, int n, int planned_times,
                      pieces *out)
{
    collected c = {0};
    plan(m, mo, n, &c);
    fm_plan_path_options opt;
    fm_plan_path_options_default(&opt);
    opt.planned_times = planned_times;
    fm_error err = {0};
    fm_plan_path *path = fm_plan_path_new(&opt, collect_piece, out, &err);
    CHECK(path != NULL);
    for (int i = 0; i < c.n && i < 64; i++) CHECK(fm_plan_path_push(path, &c.m[i]) == 0);
    CHECK(fm_plan_path_finish(path) == 0);
    fm_plan_path_free(path);
}

static void test_blend_path(void)
{
    /* test_blend_corner's corner (d = R = 0.24142 mm): the path is the
     * first line to (50 - d, 0), a counter-clockwise XY arc about
     * (50 - R, R) to (50, d), the second line from there. */
    fm_plan_machine m = machine(100.0, 500.0);
    fm_motion mo[2] = {line(0, 0, 50, 0, 1200), line(50, 0, 50, 50, 1200)};
    mo[0].path_tolerance = mo[1].path_tolerance = 0.1;
    double th = PLAN_PI / 4.0, T = 0.1;
    double d = cos(th) * T / (1.0 - sin(th)), R = tan(th) * d;
    pieces pc = {0};
    plan_path(&m, mo, 2, 0, &pc);
    CHECK(pc.n == 3);
    CHECK(!pc.blend[0] && pc.continues[0] && pc.blend[1] && !pc.continues[1] && !pc.blend[2]);
    CHECK(pc.m[0].kind == FM_MOTION_LINE && pc.m[1].kind == FM_MOTION_ARC && pc.m[2].kind == FM_MOTION_LINE);
    CHECK_NEAR(pc.m[0].start[0], 0.0, 1e-12);
    CHECK_NEAR(pc.m[0].end[0], 50.0 - d, 1e-9);
    CHECK_NEAR(pc.m[0].end[1], 0.0, 1e-12);
    const fm_motion *a = &pc.m[1];
    CHECK(a->plane_axis == 2 && a->turns == 1 && a->index == 0);
    CHECK_NEAR(a->center[0], 50.0 - R, 1e-9);
    CHECK_NEAR(a->center[1], R, 1e-9);
    CHECK_NEAR(hypot(a->start[0] - a->center[0], a->start[1] - a->center[1]), R, 1e-9);
    CHECK_NEAR(hypot(a->end[0] - a->center[0], a->end[1] - a->center[1]), R, 1e-9);
    CHECK_NEAR(a->end[0], 50.0, 1e-9);
    CHECK_NEAR(a->end[1], d, 1e-9);
    CHECK_NEAR(pc.m[2].start[1], d, 1e-9);
    CHECK_NEAR(pc.m[2].end[1], 50.0, 1e-12);
    CHECK(pc.m[2].index == 1);
    /* feed-only times (20 mm/s): each piece its share of its motion's */
    CHECK_NEAR(pc.m[0].t1, (50.0 - d) / 20.0, 1e-9);
    CHECK_NEAR(a->t0, (50.0 - d) / 20.0, 1e-9);
    CHECK_NEAR(a->t1, (50.0 + d) / 20.0, 1e-9);
    CHECK_NEAR(pc.m[2].t1, 5.0, 1e-9);
    /* planned times: test_blend_corner's line and arc times */
    double vb = sqrt(sqrt(3.0) / 2.0 * 500.0 * R), acc = 500.0, v = 20.0, L = 50.0 - d;
    double s_up = v * v / (2 * acc), s_down = (v * v - vb * vb) / (2 * acc);
    double t_line = v / acc + (v - vb) / acc + (L - s_up - s_down) / v;
    double t_arc = R * PLAN_PI / 2.0 / vb;
    pieces pt = {0};
    plan_path(&m, mo, 2, 1, &pt);
    CHECK(pt.n == 3);
    CHECK_NEAR(pt.m[0].t0, 0.0, 1e-12);
    CHECK_NEAR(pt.m[0].t1, t_line, 1e-9);
    CHECK_NEAR(pt.m[1].t0, t_line, 1e-9);
    CHECK_NEAR(pt.m[1].t1, t_line + t_arc, 1e-9);
    CHECK_NEAR(pt.m[2].t1, 2.0 * t_line + t_arc, 1e-9);

    /* A corner out of the axis planes: X, then up Y and Z at 45 degrees
     * (the angle between the directions is 90 degrees again, so d and R
     * are as above at P0.1). Chords within 1 um of the arc: their ends on
     * the circle about the corner's bisector at R / sin(45) from it, each
     * chord's middle within the tolerance of the circle. */
    fm_motion sk[2] = {line(0, 0, 20, 0, 1200), line(20, 0, 20, 10, 1200)};
    sk[1].end[2] = 10.0;
    sk[0].path_tolerance = sk[1].path_tolerance = 0.1;
    pieces ps = {0};
    plan_path(&m, sk, 2, 0, &ps);
    CHECK(ps.n >= 4 && ps.n < 64);
    double s2 = sqrt(0.5), cen[3] = {20.0 - R, R * s2, R * s2}; /* corner + (u2 - u1)/|u2 - u1| R / sin(45) */
    CHECK_NEAR(ps.m[0].end[0], 20.0 - d, 1e-9);
    double chord0 = -1.0;
    for (int i = 1; i < ps.n - 1; i++) {
        const fm_motion *c = &ps.m[i];
        CHECK(ps.blend[i] && c->kind == FM_MOTION_LINE && c->index == 0);
        CHECK(ps.continues[i] == (i < ps.n - 2));
        double e[3], mid[3];
        for (int k = 0; k < 3; k++) {
            e[k] = c->end[k] - cen[k];
            mid[k] = 0.5 * (c->start[k] + c->end[k]) - cen[k];
        }
        CHECK_NEAR(sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]), R, 1e-9);
        double rm = sqrt(mid[0] * mid[0] + mid[1] * mid[1] + mid[2] * mid[2]);
        CHECK(R - rm <= 0.001 + 1e-12);
        double len = hypot(hypot(c->end[0] - c->start[0], c->end[1] - c->start[1]), c->end[2] - c->start[2]);
        if (chord0 < 0.0) chord0 = len;
        CHECK_NEAR(len, chord0, 1e-9); /* equal chords: the short way round */
    }
    CHECK_NEAR(ps.m[ps.n - 1].start[0], 20.0, 1e-9);
    CHECK_NEAR(ps.m[ps.n - 1].start[1], d * s2, 1e-9);
    CHECK_NEAR(ps.m[ps.n - 1].start[2], d * s2, 1e-9);

    /* A corner between a line and an arc keeps the programmed corner */
    fm_motion la[2] = {line(0, 0, 20, 0, 1200), line(20, 0, 10, 10, 1200)};
    la[1].kind = FM_MOTION_ARC; /* starting up +Y: a 90 degree corner, blended */
    la[1].plane_axis = 2;
    la[1].turns = 1;
    la[1].center[0] = 10.0;
    la[0].path_tolerance = la[1].path_tolerance = 0.1;
    pieces pa = {0};
    collected ca = {0};
    plan(&m, la, 2, &ca);
    CHECK(ca.m[0].has_blend);
    plan_path(&m, la, 2, 0, &pa);
    CHECK(pa.n == 2);
    CHECK_NEAR(pa.m[0].end[0], 20.0, 1e-12);
    CHECK(pa.m[1].kind == FM_MOTION_ARC && !pa.blend[1]);
}

static void test_dwell_and_feed_only(void)
{
    fm_plan_machine m = machine(100.0, 500.0);
    fm_motion mo[3] = {line(0, 0, 10, 0, 600), {0}, line(10, 0, 20, 0, 600)};
    mo[1].kind = FM_MOTION_DWELL;
    mo[1].start[0] = mo[1].end[0] = 10.0;
    mo[1].t0 = 1.0;
    mo[1].t1 = 3.0; /* plan() keeps a dwell's producer times: 2 s */
    collected c = {0};
    CHECK_NEAR(plan(&m, mo, 3, &c), 2.0 * rest_to_rest(10.0, 10.0, 500.0) + 2.0, 1e-9);
    CHECK(c.n == 3);
    /* no dynamics: the times the motions came with */
    fm_plan_machine none;
    fm_plan_machine_default(&none);
    c.n = 0;
    fm_motion l = line(0, 0, 100, 0, 1200);
    CHECK_NEAR(plan(&none, &l, 1, &c), 5.0, 1e-12);
}

static int count_only(void *user, const fm_plan_motion *pm)
{
    (void)pm;
    (*(long *)user)++;
    return 0;
}

static void test_streaming(void)
{
    /* A zigzag of 10 000 short lines: motions come out while it is pushed,
     * never more than the look-ahead window behind. */
    fm_plan_machine m = machine(100.0, 500.0);
    long delivered = 0, worst_lag = 0;
    fm_error err = {0};
    fm_planner *p = fm_planner_new(&m, count_only, &delivered, &err);
    for (long i = 0; i < 10000; i++) {
        fm_motion mo = line((double)i, (double)(i % 2), (double)(i + 1), (double)((i + 1) % 2), 3000);
        CHECK(fm_planner_push(p, &mo, &err) == FM_OK);
        if (i + 1 - delivered > worst_lag) worst_lag = i + 1 - delivered;
    }
    CHECK(fm_planner_finish(p, NULL, &err) == FM_OK);
    fm_planner_free(p);
    CHECK(delivered == 10000);
    CHECK(worst_lag <= 2 * (m.lookahead + 8));
}

/* Fanuc's path modes through the interpreter and the planner (docs/plan.md,
 * "Fanuc and Haas"): around a 20 mm square's 90 degree corners, Haas G187
 * P1 blends within 0.1 mm and P3 within 0.01 mm: the blend radius is
 * T sin(45) / (1 - sin(45)); G64 takes a quarter of the 20 mm side as its
 * tolerance; G61 and G09 stop (no blend, the motion ends at rest). */
static void test_fanuc_modes(void)
{
    static const struct {
        const char *code;
        double tol; /* 0: a stop */
    } modes[] = {{"G187 P1", 0.1}, {"G187 P3", 0.01}, {"G187 P2", 0.05}, {"G64", 5.0}, {"G61", 0}, {"G09", 0}};
    double s45 = sin(PLAN_PI / 4.0);
    for (size_t k = 0; k < sizeof modes / sizeof modes[0]; k++) {
        char prog[256];
        snprintf(prog, sizeof prog, "O1\nG21 G90 G17\nG01 X0 Y0 F600\n%s X20.\nY20.\nM30\n", modes[k].code);
        fm_plan_machine m = machine(100.0, 500.0);
        collected c = {0};
        fm_error err = {0};
        fm_planner *p = fm_planner_new(&m, collect, &c, &err);
        fm_gcode_options o;
        fm_gcode_options_default(&o);
        o.dialect = FM_GCODE_FANUC;
        CHECK(fm_gcode_run_string(prog, strlen(prog), "t.nc", &o, fm_planner_motion_sink, p, NULL, &err) ==
              FM_OK);
        CHECK(fm_planner_finish(p, NULL, &err) == FM_OK);
        fm_planner_free(p);
        /* the first block (X0 Y0 from the origin) has no length */
        CHECK(c.n == 3);
        if (c.n != 3) continue;
        const fm_plan_motion *first = &c.m[1];
        if (modes[k].tol > 0 && modes[k].tol < 1.0) {
            /* the tolerance bounds the radius (its speed is below the feed) */
            double d = cos(PLAN_PI / 4.0) * modes[k].tol / (1.0 - s45);
            CHECK(first->has_blend);
            CHECK_NEAR(first->blend_out.radius, tan(PLAN_PI / 4.0) * d, 1e-9);
        } else if (modes[k].tol > 0) {
            /* G64: the radius a parabolic blend at the feed sweeps, 10 mm/s
             * for 10 / 250 s over the 90 degree turn */
            CHECK(first->has_blend);
            CHECK_NEAR(first->blend_out.radius, 10.0 * (10.0 / 250.0) / (PLAN_PI / 2.0), 1e-9);
        } else {
            CHECK(!first->has_blend);
            CHECK_NEAR(first->v_end, 0.0, 1e-12);
            CHECK_NEAR(first->motion.t1, rest_to_rest(20.0, 10.0, 500.0), 1e-9);
        }
    }
}

/* Random programs (lines, arcs, helices, rapids, dwells, tool changes,
 * every path mode and tolerance, zero-length moves and reversals): every
 * motion comes back once, in order, with finite times that never go
 * backwards, and the totals keep the feed-only figure. (A run under the
 * sanitizers is the point: no read out of the queues, no NaN.) */
static int check_order(void *user, const fm_plan_motion *pm)
{
    long *next = user;
    CHECK(pm->motion.index == *next);
    CHECK(isfinite(pm->motion.t0) && isfinite(pm->motion.t1));
    CHECK(pm->motion.t1 >= pm->motion.t0);
    (*next)++;
    return 0;
}

/* The path after the planner (fm_plan_path) over the same random programs:
 * continuous, every motion once and in order, times never backwards, and
 * every blend arc within its corner's tolerance and reach. */
typedef struct path_check {
    long next;               /* the planner's next index (check_order) */
    fm_plan_path *path;
    int have_end;
    double end[3];           /* the last piece's end */
    long next_piece;         /* the next programmed motion's index */
    double t;                /* the last piece's end time */
    fm_motion programmed[1000];
    double reach;            /* the current blend's start from its corner */
    int in_blend;
    long arcs, chords;
} path_check;

static int path_piece(void *user, const fm_motion *m, int blend, int continues)
{
    path_check *pc = user;
    (void)continues;
    if (pc->have_end) CHECK(hypot(hypot(m->start[0] - pc->end[0], m->start[1] - pc->end[1]),
                                  m->start[2] - pc->end[2]) < 1e-9);
    CHECK(m->t0 >= pc->t - 1e-9 && m->t1 >= m->t0 - 1e-12);
    if (!blend) {
        CHECK(m->index == pc->next_piece);
        pc->next_piece++;
        pc->in_blend = 0;
    } else {
        CHECK(m->index == pc->next_piece - 1);
        const fm_motion *mo = &pc->programmed[m->index];
        const double *corner = mo->end;
        if (!pc->in_blend) {
            pc->reach = hypot(hypot(m->start[0] - corner[0], m->start[1] - corner[1]), m->start[2] - corner[2]);
            pc->in_blend = 1;
        }
        double far = hypot(hypot(m->end[0] - corner[0], m->end[1] - corner[1]), m->end[2] - corner[2]);
        CHECK(far <= pc->reach + 1e-9);
        if (m->kind == FM_MOTION_ARC) {
            pc->arcs++;
            double R = hypot(m->start[0] - m->center[0], m->start[1] - m->center[1]);
            double gap = hypot(corner[0] - m->center[0], corner[1] - m->center[1]) - R;
            if (mo->path_tolerance > 0.0) CHECK(gap <= mo->path_tolerance + 1e-9);
        } else {
            pc->chords++;
            CHECK(m->kind == mo->kind);
        }
    }
    memcpy(pc->end, m->end, sizeof pc->end);
    pc->have_end = 1;
    pc->t = m->t1;
    return 0;
}

static int check_order_then_path(void *user, const fm_plan_motion *pm)
{
    path_check *pc = user;
    check_order(&pc->next, pm);
    return fm_plan_path_push(pc->path, pm);
}

static void test_random_programs(void)
{
    long arcs = 0, chords = 0, followed = 0;
    fm_plan_machine m = machine(60.0, 800.0);
    m.linear[2].max_velocity = 20.0;
    m.linear[2].max_acceleration = 300.0;
    m.max_feed_override = 1.2;
    m.tool_change_s = 1.0;
    for (int prog = 0; prog < 40; prog++) {
        static path_check pc;
        memset(&pc, 0, sizeof pc);
        fm_error err = {0};
        pc.path = fm_plan_path_new(NULL, path_piece, &pc, &err);
        CHECK(pc.path != NULL);
        fm_planner *p = fm_planner_new(&m, check_order_then_path, &pc, &err);
        double pos[3] = {0, 0, 0}, t = 0.0;
        int n = 200 + (int)(test_rand01() * 800);
        for (int i = 0; i < n; i++) {
            fm_motion mo = {0};
            mo.index = i;
            mo.line = i + 1;
            mo.axis_start[2] = mo.axis_end[2] = 1.0;
            memcpy(mo.start, pos, sizeof pos);
            double r = test_rand01();
            mo.kind = r < 0.1 ? FM_MOTION_RAPID : r < 0.75 ? FM_MOTION_LINE : r < 0.95 ? FM_MOTION_ARC : FM_MOTION_DWELL;
            mo.path_mode = (fm_path_mode)(int)(test_rand01() * 3);
            mo.path_tolerance = test_rand01() < 0.5 ? 0.0 : test_uniform(0.001, 0.5);
            mo.naive_tolerance = test_rand01() < 0.5 ? 0.0 : mo.path_tolerance;
            mo.tool = test_rand01() < 0.02 ? 2 : 1;
            mo.feed = test_uniform(100.0, 6000.0);
            double len = 0.0;
            if (mo.kind == FM_MOTION_ARC) {
                double rad = test_uniform(0.2, 20.0), a0 = test_uniform(0, 2 * PLAN_PI);
                mo.plane_axis = 2;
                mo.turns = test_rand01() < 0.5 ? 1 : -1;
                mo.center[0] = pos[0] - rad * cos(a0);
                mo.center[1] = pos[1] - rad * sin(a0);
                mo.center[2] = pos[2];
                double a1 = a0 + mo.turns * test_uniform(0.05, 2 * PLAN_PI - 0.05);
                mo.end[0] = mo.center[0] + rad * cos(a1);
                mo.end[1] = mo.center[1] + rad * sin(a1);
                mo.end[2] = pos[2] + (test_rand01() < 0.3 ? test_uniform(-2, 2) : 0.0);
                len = rad * fabs(a1 - a0);
            } else if (mo.kind != FM_MOTION_DWELL) {
                double step = test_rand01() < 0.3 ? test_uniform(0.01, 0.5) : test_uniform(0.5, 50.0);
                if (test_rand01() < 0.05) step = 0.0;
                double zs = test_rand01() < 0.5 ? 0.0 : 0.3; /* half of them in the XY plane */
                for (int k = 0; k < 3; k++) mo.end[k] = pos[k] + step * test_uniform(-1, 1) * (k == 2 ? zs : 1.0);
                len = sqrt((mo.end[0] - pos[0]) * (mo.end[0] - pos[0]) + (mo.end[1] - pos[1]) * (mo.end[1] - pos[1]) +
                           (mo.end[2] - pos[2]) * (mo.end[2] - pos[2]));
            } else {
                memcpy(mo.end, pos, sizeof pos);
            }
            if (mo.kind == FM_MOTION_RAPID) mo.feed = 0.0;
            mo.t0 = t;
            t += mo.kind == FM_MOTION_DWELL ? test_uniform(0, 1) : len / (mo.feed > 0 ? mo.feed / 60.0 : 100.0);
            mo.t1 = t;
            memcpy(pos, mo.end, sizeof pos);
            pc.programmed[i] = mo;
            CHECK(fm_planner_push(p, &mo, &err) == FM_OK);
        }
        fm_plan_totals tot;
        CHECK(fm_planner_finish(p, &tot, &err) == FM_OK);
        fm_planner_free(p);
        CHECK(pc.next == n);
        CHECK(fm_plan_path_finish(pc.path) == 0);
        CHECK(pc.next_piece == n);
        CHECK(fm_plan_path_blends(pc.path) <= tot.blends);
        followed += fm_plan_path_blends(pc.path);
        arcs += pc.arcs;
        chords += pc.chords;
        fm_plan_path_free(pc.path);
        CHECK(isfinite(tot.cycle_time_s) && tot.cycle_time_s > 0.0);
        CHECK_NEAR(tot.feed_only_s, t, 1e-9);
    }
    /* the programs exercise the path: arcs in the XY plane, chords out of it */
    printf("random programs: %ld blends followed, %ld as arcs, %ld chords\n", followed, arcs, chords);
    CHECK(followed > 100 && arcs > 10 && chords > 100);
}

int main(void)
{
    test_single_moves();
    test_rapid_per_axis();
    test_circle_at_normal_limit();
    test_blend_corner();
    test_blend_path();
    test_dwell_and_feed_only();
    test_streaming();
    test_fanuc_modes();
    test_random_programs();
    return test_summary("plan");
}
