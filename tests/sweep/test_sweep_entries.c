/* test_sweep_entries.c: a tool's ways into the material other than the
 * plunge. FM_SWEEP_HELIX (a convex part on a helix about its own axis,
 * sweep.c) against the general branch-and-bound of the same sweep
 * (no_fast_paths) and the sampled brute force of sweep_cases.h, over flat,
 * bull, ball and drill flutes on ten helices: the demo's entries (one and
 * four turns), a bore narrower than the tool, a helix through the tool's
 * axis, partial arcs, shallow and steep pitches, clockwise and rising, G18
 * and G19 helices with the tool along their axis, and a tool pointing down
 * its helix's axis. Then a flat end mill's ramps (CONCAVE with the guess of
 * ramp_guess proven by two evaluations) the same way. Each value must lie
 * within the other's proof ([value, upper], certified to FM_SWEEP_TOL), be
 * attained at the time reported, and interval enclosures must hold at
 * points of their box. */
#include "test.h"
#include "sweep/sweep_cases.h"

#include <stdlib.h>

typedef struct helix_case {
    const char *name;
    int k;                 /* plane axis */
    double radius, a0, a1; /* start and end angles */
    int turns;
    double rise;
    double axis_sign; /* the tool along +k or -k */
} helix_case;

static const helix_case cases[] = {
    {"demo entry: r2, one turn, down 3", 2, 2, 0, 0, 1, -3, 1},
    {"demo pocket: r2, four turns, down 9", 2, 2, 0, 0, 4, -9, 1},
    {"bore: r0.5 (inside the tool), two turns clockwise, down 2", 2, 0.5, 1, 1, -2, -2, 1},
    {"partial arc r7, 0.3 to 2.5 rad, down 1.2", 2, 7, 0.3, 2.5, 1, -1.2, 1},
    {"rising r4, three turns clockwise, up 6", 2, 4, 0, 0, -3, 6, 1},
    {"through the axis: r3, one turn, down 0.2", 2, 3, 0.5, 0.5, 1, -0.2, 1},
    {"steep: r1.5, one turn, down 12", 2, 1.5, 2, 2, 1, -12, 1},
    {"G18: r5 about Y, two turns, down 4", 1, 5, 0.2, 1.7, 2, -4, 1},
    {"G19: r3 about X, tool along -X, clockwise, up 2.5", 0, 3, -1, 2, -1, 2.5, -1},
    {"tool pointing down the axis: r2.5, two turns, down 3", 2, 2.5, 0, 3, 2, -3, -1},
};
#define NCASES (sizeof cases / sizeof cases[0])

static fm_motion case_motion(const helix_case *hc)
{
    const double c[3] = {1.5, -2, 0.5};
    fm_motion m = sc_arc(hc->k, c, hc->radius, hc->a0, hc->a1, hc->turns, hc->rise);
    for (int i = 0; i < 3; i++) m.axis_start[i] = m.axis_end[i] = i == hc->k ? hc->axis_sign : 0;
    return m;
}

/* A point near the bottom and the side of the moving tool at a random
 * time, where the sweep's surface is; or anywhere in the sweep's box. */
static void near_point(const fm_sweep *s, const fm_motion *m, const fm_tool_part *part, int near, double p[3])
{
    double lo[3], hi[3];
    fm_sweep_bounds(s, lo, hi);
    if (!near) {
        for (int i = 0; i < 3; i++) p[i] = test_uniform(lo[i] - 1, hi[i] + 1);
        return;
    }
    double c[3], a[3];
    fm_sweep_pose(s, m->t0 + test_rand01() * (m->t1 - m->t0), c, a);
    double along = part->z_lo + test_uniform(-1, 4);
    for (int i = 0; i < 3; i++) {
        double side = fabs(a[i]) > 0.5 ? 0 : test_uniform(-part->r_max - 1, part->r_max + 1);
        p[i] = c[i] + along * a[i] + side;
    }
}

static long points, ramp_points, brute_points;
static double evals_helix, evals_search, evals_ramp, evals_ramp_search;
static int shown;

static void check_motion(const char *cutter, const fm_tool_part *part, const char *what, fm_motion m,
                         fm_sweep_method method, double *evals_fast, double *evals_general, long *count, int npoints)
{
    fm_sweep *fast, *slow;
    fm_sweep_options general = {0};
    general.no_fast_paths = 1;
    fm_error err;
    if (fm_sweep_new(&m, part, NULL, &fast, &err) != FM_OK) {
        fprintf(stderr, "%s, %s: %s\n", cutter, what, err.message);
        CHECK(0);
        return;
    }
    CHECK(fm_sweep_new(&m, part, &general, &slow, NULL) == FM_OK);
    CHECK(fm_sweep_method_of(fast) == method);
    CHECK(fm_sweep_method_of(slow) == FM_SWEEP_SEARCH);
    fm_sweep_worker *w = fm_sweep_worker_new(fast);
    sc_speed speed = sc_motion_speed(&m);
    for (int i = 0; i < npoints; i++) {
        double p[3];
        near_point(fast, &m, part, i % 4 != 0, p);
        fm_sweep_value a, b;
        fm_sweep_eval_ex(fast, w, p, &a);
        fm_sweep_eval_ex(slow, w, p, &b);
        (*count)++;
        *evals_fast += (double)a.evaluations;
        *evals_general += (double)b.evaluations;
        /* both proofs hold the true maximum: each value lies below the
         * other's upper bound, and the helix's proof is certified */
        int ok = !a.exhausted && a.upper - a.value <= FM_SWEEP_TOL + 1e-12 && a.value <= b.upper + 1e-9 &&
                 b.value <= a.upper + 1e-9;
        if (!ok && shown++ < 10)
            fprintf(stderr, "%s, %s at (%.9g, %.9g, %.9g): fast %.12g [upper %.12g, %zu evaluations%s], search %.12g "
                            "[upper %.12g]\n",
                    cutter, what, p[0], p[1], p[2], a.value, a.upper, a.evaluations,
                    a.exhausted ? ", exhausted" : "", b.value, b.upper);
        CHECK(ok);
        /* attained at the time reported */
        CHECK_NEAR(fm_sweep_tool_at(fast, w, p, a.t), a.value, 1e-9);
        if (i % 8 == 0) {
            double brute = sc_brute_sparse(fast, w, &speed, p);
            brute_points++;
            if (!(a.value <= brute + 1e-9 && brute <= a.upper + 1e-9) && shown++ < 10)
                fprintf(stderr, "%s, %s at (%.9g, %.9g, %.9g): fast %.12g [upper %.12g], brute force %.12g\n", cutter,
                        what, p[0], p[1], p[2], a.value, a.upper, brute);
            CHECK(a.value <= brute + 1e-9);
            CHECK(brute <= a.upper + 1e-9);
        }
    }
    /* Enclosures over boxes (the voxel pass relies on them): S at points
     * of the box lies within the interval. */
    double lo[3], hi[3];
    fm_sweep_bounds(fast, lo, hi);
    for (int i = 0; i < 20; i++) {
        fm_interval box[3];
        double c[3];
        near_point(fast, &m, part, i % 2, c);
        for (int k = 0; k < 3; k++) {
            double h = test_uniform(0.02, 0.8);
            box[k].lo = c[k] - h;
            box[k].hi = c[k] + h;
        }
        fm_interval iv = fm_sweep_interval(fast, w, box);
        for (int j = 0; j < 10; j++) {
            double p[3] = {test_uniform(box[0].lo, box[0].hi), test_uniform(box[1].lo, box[1].hi),
                           test_uniform(box[2].lo, box[2].hi)};
            double v = fm_sweep_eval(slow, w, p);
            CHECK(v >= iv.lo - 1e-9 && v <= iv.hi + 1e-9);
        }
    }
    fm_sweep_worker_free(w);
    fm_sweep_free(fast);
    fm_sweep_free(slow);
}

/* A flat end mill's ramps: 3D lines (CONCAVE, proven at ramp_guess's u). */
typedef struct ramp_case {
    const char *name;
    double from[3], to[3], axis[3];
} ramp_case;

static const ramp_case ramps[] = {
    {"ramp 10.8 mm down 3.5", {0, 0, 2}, {10, -4, -1.5}, {0, 0, 1}},
    {"shallow ramp 20.6 mm down 0.3", {0, 0, 0}, {20, 5, -0.3}, {0, 0, 1}},
    {"steep ramp down 10", {1, 1, 5}, {1.5, 0.8, -5}, {0, 0, 1}},
    {"rising ramp", {0, 0, -3}, {8, 3, 1}, {0, 0, 1}},
    {"short ramp 0.05 mm", {0, 0, 0}, {0.05, 0, -0.01}, {0, 0, 1}},
    {"ramp with a tilted tool", {0, 0, 0}, {6, 6, -2}, {0.3, -0.2, 1}},
    {"ramp with the tool pointing down", {2, 1, 0}, {-5, 3, 2.5}, {0, 0, -1}},
};

/* Which sweeps take the helix: not the V-bit or tapered cutters (no ball of
 * their full radius about their middle), not a tilted tool, not a spiral. */
static void check_selection(void)
{
    fm_error err;
    fm_tool_shape other[] = {FM_TOOL_VBIT, FM_TOOL_TAPERED};
    fm_motion m = case_motion(&cases[0]);
    for (int i = 0; i < 2; i++) {
        fm_tool_spec spec = sc_spec(other[i]);
        fm_tool t;
        CHECK(fm_tool_build(&spec, &t, &err) == FM_OK);
        fm_sweep *s;
        CHECK(fm_sweep_new(&m, &t.flutes, NULL, &s, NULL) == FM_OK);
        CHECK(fm_sweep_method_of(s) == FM_SWEEP_SEARCH);
        fm_sweep_free(s);
    }
    fm_tool_spec spec = sc_spec(FM_TOOL_FLAT);
    fm_tool t;
    CHECK(fm_tool_build(&spec, &t, &err) == FM_OK);
    fm_motion tilted = m;
    tilted.axis_start[0] = tilted.axis_end[0] = 0.1;
    fm_motion spiral = m;
    spiral.end[0] += 0.5; /* the end radius differs from the start's */
    fm_sweep *s;
    CHECK(fm_sweep_new(&tilted, &t.flutes, NULL, &s, NULL) == FM_OK);
    CHECK(fm_sweep_method_of(s) == FM_SWEEP_SEARCH);
    fm_sweep_free(s);
    CHECK(fm_sweep_new(&spiral, &t.flutes, NULL, &s, NULL) == FM_OK);
    CHECK(fm_sweep_method_of(s) == FM_SWEEP_SEARCH);
    fm_sweep_free(s);
}

int main(int argc, char **argv)
{
    int npoints = argc > 1 ? atoi(argv[1]) : 1500;
    struct {
        const char *name;
        fm_tool_spec spec;
    } cutters[6];
    cutters[0].name = "flat d6 x 10", cutters[0].spec = sc_spec(FM_TOOL_FLAT);
    cutters[1].name = "flat d6 x 20", cutters[1].spec = sc_spec(FM_TOOL_FLAT);
    cutters[1].spec.flute_length = 20;
    cutters[2].name = "bull d6 r1", cutters[2].spec = sc_spec(FM_TOOL_BULL);
    cutters[3].name = "bull d10 r2.5", cutters[3].spec = sc_spec(FM_TOOL_BULL);
    cutters[3].spec.diameter = 10, cutters[3].spec.corner_radius = 2.5, cutters[3].spec.flute_length = 12;
    cutters[4].name = "ball d6", cutters[4].spec = sc_spec(FM_TOOL_BALL);
    cutters[5].name = "drill d5 118", cutters[5].spec = sc_spec(FM_TOOL_DRILL);
    cutters[5].spec.diameter = 5;
    for (size_t c = 0; c < sizeof cutters / sizeof cutters[0]; c++) {
        fm_tool t;
        fm_error err;
        if (fm_tool_build(&cutters[c].spec, &t, &err) != FM_OK) {
            fprintf(stderr, "%s: %s\n", cutters[c].name, err.message);
            CHECK(0);
            continue;
        }
        for (size_t k = 0; k < NCASES; k++)
            check_motion(cutters[c].name, &t.flutes, cases[k].name, case_motion(&cases[k]), FM_SWEEP_HELIX,
                         &evals_helix, &evals_search, &points, npoints);
        if (cutters[c].spec.shape != FM_TOOL_FLAT) continue;
        for (size_t k = 0; k < sizeof ramps / sizeof ramps[0]; k++) {
            const ramp_case *rc = &ramps[k];
            fm_motion m = sc_line(rc->from[0], rc->from[1], rc->from[2], rc->to[0], rc->to[1], rc->to[2]);
            for (int i = 0; i < 3; i++) m.axis_start[i] = m.axis_end[i] = rc->axis[i];
            check_motion(cutters[c].name, &t.flutes, rc->name, m, FM_SWEEP_CONCAVE, &evals_ramp, &evals_ramp_search,
                         &ramp_points, npoints);
        }
    }
    check_selection();
    printf("against the search: helices %ld points, ramps %ld (%ld in all also against the brute force); part "
           "evaluations per point: helix %.2f (search %.2f), flat ramp %.2f (search %.2f)\n",
           points, ramp_points, brute_points, evals_helix / (double)points, evals_search / (double)points,
           evals_ramp / (double)ramp_points, evals_ramp_search / (double)ramp_points);
    return test_summary("sweep_entries");
}
