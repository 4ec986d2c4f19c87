/* test_interval.c: interval soundness for every non-special op (sampled
 * values always inside the enclosure; NaN values only where the evaluator
 * says NaN is possible), on boxes that straddle discontinuities and domain
 * edges, and tape shortening: shortened tapes give the same values as the
 * full tape inside their box and are shorter where min/max is decided. */
#include "frep/tape_internal.h"
#include "test.h"
#include "frep_random.h"

static const double special_points[] = {0.0,       1.0,        -1.0,  0.5,           -0.5, 2.0,
                                        FM_PI / 2, -FM_PI / 2, FM_PI, 3 * FM_PI / 2};
#define NSPECIAL (sizeof special_points / sizeof special_points[0])

static void random_box(fm_interval box[4])
{
    static const double widths[] = {0.0, 1e-9, 1e-3, 0.1, 0.5, 1.0, 3.0};
    for (int i = 0; i < 4; i++) {
        double c = test_rand01() < 0.5 ? special_points[(size_t)(test_rand01() * NSPECIAL)]
                                       : test_uniform(-3, 3);
        double w = widths[(size_t)(test_rand01() * 7)];
        /* Boxes that end exactly at a special point, and ones around it. */
        double u = test_rand01();
        box[i].lo = u < 0.2 ? c : c - w * test_rand01();
        box[i].hi = u > 0.8 ? c : c + w * test_rand01();
        if (box[i].hi < box[i].lo) box[i].hi = box[i].lo;
    }
}

static void sample_in(const fm_interval box[4], int k, double p[4])
{
    for (int i = 0; i < 4; i++) {
        double lo = box[i].lo, hi = box[i].hi;
        if (k < 16) {
            p[i] = (k >> i) & 1 ? hi : lo; /* corners */
        } else if (k < 40) {
            /* special points and half-integers inside the box */
            double s = k < 28 ? special_points[(size_t)(test_rand01() * NSPECIAL)]
                              : 0.5 * floor(test_uniform(2 * lo, 2 * hi + 1));
            p[i] = s >= lo && s <= hi ? s : test_uniform(lo, hi);
        } else {
            p[i] = test_uniform(lo, hi);
        }
    }
}

static int bad_reports;

/* Every sampled value of the tape's function inside the box lies in the
 * enclosure (or is NaN where NaN was declared possible). */
static void check_sound(fm_evaluator *ev, const fm_interval box[4], int samples, const char *what)
{
    int maybe_nan = 0;
    fm_interval r = fm_eval_interval_nan(ev, box, &maybe_nan);
    for (int k = 0; k < samples; k++) {
        double p[4];
        sample_in(box, k, p);
        double v = fm_eval_point(ev, p);
        int ok = isnan(v) ? maybe_nan : (r.lo <= v && v <= r.hi);
        CHECK(ok);
        if (!ok && bad_reports++ < 10)
            fprintf(stderr,
                    "%s: value %.17g at (%.17g %.17g %.17g %.17g) outside [%.17g, %.17g] nan %d\n",
                    what, v, p[0], p[1], p[2], p[3], r.lo, r.hi, maybe_nan);
    }
}

static void check_one(fm_graph *g, fm_node f, const char *what)
{
    fm_error err;
    fm_tape *t = fm_tape_compile(g, f, &err);
    CHECK(t != NULL);
    if (!t) return;
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    for (int b = 0; b < 60; b++) {
        fm_interval box[4];
        random_box(box);
        check_sound(ev, box, 80, what);
    }
    fm_evaluator_free(ev);
    fm_tape_free(t);
}

/* Each op alone, on coordinates and on constants, so that every node kind
 * is covered on its own discontinuities. */
static void check_each_op(void)
{
    static const double consts[] = {0.0, 1.0, -1.0, 2.0, 0.5, -3.0, 1.5};
    for (size_t i = 0; i < NUNARY; i++) {
        fm_graph *g = fm_graph_new(0);
        fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
        check_one(g, fm_unary(g, unary_ops[i], x), "unary(x)");
        check_one(g, fm_unary(g, unary_ops[i], fm_sub(g, fm_mul(g, x, fm_const(g, 3.0)), y)),
                  "unary(3x - y)");
        fm_graph_free(g);
    }
    for (size_t i = 0; i < NBINARY; i++) {
        fm_graph *g = fm_graph_new(0);
        fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y);
        check_one(g, fm_binary(g, binary_ops[i], x, y), "binary(x, y)");
        for (size_t c = 0; c < sizeof consts / sizeof consts[0]; c++) {
            check_one(g, fm_binary(g, binary_ops[i], x, fm_const(g, consts[c])), "binary(x, c)");
            check_one(g, fm_binary(g, binary_ops[i], fm_const(g, consts[c]), y), "binary(c, y)");
        }
        fm_graph_free(g);
    }
    fm_graph *g = fm_graph_new(0);
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z);
    check_one(g, fm_select(g, x, y, z), "select(x, y, z)");
    check_one(g, fm_select(g, fm_binary(g, FM_OP_LT, x, y), fm_sqrt(g, y), z), "select(x<y, ...)");
    /* NaN sources feeding NaN-absorbing ops. */
    check_one(g, fm_min(g, fm_unary(g, FM_OP_LOG, x), y), "min(log x, y)");
    check_one(g, fm_max(g, y, fm_unary(g, FM_OP_LOG, x)), "max(y, log x)");
    check_one(g, fm_binary(g, FM_OP_POW, fm_unary(g, FM_OP_SQRT, x), fm_const(g, 0.0)),
              "pow(sqrt x, 0)");
    fm_graph_free(g);
}

static void check_random_soundness(int minmax_heavy)
{
    for (int trial = 0; trial < 200; trial++) {
        fm_graph *g = fm_graph_new(0);
        fm_node root = random_dag(g, 5 + (size_t)(test_rand01() * 40), minmax_heavy);
        fm_error err;
        fm_tape *t = fm_tape_compile(g, root, &err);
        fm_evaluator *ev = fm_evaluator_new(t, &err);
        for (int b = 0; b < 20; b++) {
            fm_interval box[4];
            random_box(box);
            check_sound(ev, box, 60, minmax_heavy ? "random min/max DAG" : "random DAG");
        }
        fm_evaluator_free(ev);
        fm_tape_free(t);
        fm_graph_free(g);
    }
}

/* The lower half of each of the box's four ranges. */
static void lower_corner(const fm_interval box[4], fm_interval sub[4])
{
    for (int i = 0; i < 4; i++) {
        sub[i].lo = box[i].lo;
        sub[i].hi = 0.5 * (box[i].lo + box[i].hi);
    }
}

/* Does tape s (the evaluator's family) differ from the full tape at p?
 * Says so for the first few of *mismatches. */
static int point_differs(fm_evaluator *ev, const fm_tape *s, const double p[4], const char *what,
                         int *mismatches)
{
    fm_evaluator_use(ev, NULL);
    const double full = fm_eval_point(ev, p);
    fm_evaluator_use(ev, s);
    const double shorter = fm_eval_point(ev, p);
    fm_evaluator_use(ev, NULL);
    if (same(full, shorter)) return 0;
    if ((*mismatches)++ < 5) fprintf(stderr, "%s %.17g, full %.17g\n", what, shorter, full);
    return 1;
}

/* Batch on tape s at 50 points of the box against the full tape's points. */
static void check_batch_on(fm_evaluator *ev, const fm_tape *s, const fm_interval box[4],
                           const char *what, int *mismatches)
{
    double xs[50], ys[50], zs[50], ts[50], out[50];
    for (int k = 0; k < 50; k++) {
        double p[4];
        sample_in(box, k + 40, p);
        xs[k] = p[0];
        ys[k] = p[1];
        zs[k] = p[2];
        ts[k] = p[3];
    }
    fm_evaluator_use(ev, s);
    fm_eval_batch(ev, 50, xs, ys, zs, ts, out);
    fm_evaluator_use(ev, NULL);
    for (int k = 0; k < 50; k++) {
        double p[4] = {xs[k], ys[k], zs[k], ts[k]};
        if (!same(out[k], fm_eval_point(ev, p)) && (*mismatches)++ < 5)
            fprintf(stderr, "%s's batch %.17g\n", what, out[k]);
    }
}

/* Shortened tapes agree with the full tape inside the box, bit for bit. */
static void check_random_shortening(void)
{
    int shortened = 0, mismatches = 0;
    for (int trial = 0; trial < 200; trial++) {
        fm_graph *g = fm_graph_new(0);
        fm_node root = random_dag(g, 10 + (size_t)(test_rand01() * 50), trial & 1);
        fm_error err;
        fm_tape *t = fm_tape_compile(g, root, &err);
        fm_evaluator *ev = fm_evaluator_new(t, &err);
        for (int b = 0; b < 20; b++) {
            fm_interval box[4], r;
            random_box(box);
            fm_tape *s = fm_eval_interval_shorten(ev, box, &r);
            if (!s) continue;
            CHECK(fm_tape_length(s) < fm_tape_length(t));
            shortened++;
            /* Shorten again in a corner of the box: a tape of a tape. */
            fm_interval sub[4];
            lower_corner(box, sub);
            fm_evaluator_use(ev, s);
            fm_tape *s2 = fm_eval_interval_shorten(ev, sub, NULL);
            for (int k = 0; k < 60; k++) {
                double p[4];
                sample_in(box, k, p);
                point_differs(ev, s, p, "shortened", &mismatches);
                if (s2) {
                    sample_in(sub, k, p);
                    point_differs(ev, s2, p, "twice shortened", &mismatches);
                }
            }
            /* Batch on the shortened tape equals point on the full one. */
            check_batch_on(ev, s, box, "shortened", &mismatches);
            fm_tape_free(s2);
            fm_tape_free(s);
        }
        fm_evaluator_free(ev);
        fm_tape_free(t);
        fm_graph_free(g);
    }
    CHECK(shortened > 100);
    CHECK(mismatches == 0);
}

static fm_node sphere(fm_graph *g, double cx, double cy, double cz, double r)
{
    fm_node dx = fm_sub(g, fm_var(g, FM_X), fm_const(g, cx));
    fm_node dy = fm_sub(g, fm_var(g, FM_Y), fm_const(g, cy));
    fm_node dz = fm_sub(g, fm_var(g, FM_Z), fm_const(g, cz));
    fm_node d = fm_sqrt(g, fm_add(g, fm_add(g, fm_square(g, dx), fm_square(g, dy)), fm_square(g, dz)));
    return fm_sub(g, fm_const(g, r), d);
}

/* Union of two far-apart spheres: near one, the shortened tape is exactly
 * that sphere's tape. */
static void check_csg_shortening(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node s1 = sphere(g, 0, 0, 0, 1), s2 = sphere(g, 10, 0, 0, 1);
    fm_node u = fm_max(g, s1, s2);
    fm_error err;
    fm_tape *t = fm_tape_compile(g, u, &err), *t1 = fm_tape_compile(g, s1, &err);
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    fm_interval box[4] = {{-1.5, 1.5}, {-1.5, 1.5}, {-1.5, 1.5}, {0, 0}}, r;
    fm_tape *s = fm_eval_interval_shorten(ev, box, &r);
    CHECK(s != NULL);
    CHECK(s && fm_tape_length(s) == fm_tape_length(t1));
    /* The enclosure of a sphere over the box: r - |p| in [1 - sqrt(3 * 1.5^2), 1]. */
    CHECK(r.lo <= 1.0 - sqrt(3 * 2.25) && r.hi >= 1.0);
    CHECK(r.hi <= 1.0 + 1e-12 && r.lo >= 1.0 - sqrt(3 * 2.25) - 1e-12);
    /* Between the spheres nothing is decided. */
    fm_interval mid[4] = {{3, 7}, {-1, 1}, {-1, 1}, {0, 0}};
    fm_tape *none = fm_eval_interval_shorten(ev, mid, &r);
    CHECK(none == NULL);
    fm_tape_free(none);
    fm_tape_free(s);
    fm_evaluator_free(ev);
    fm_tape_free(t);
    fm_tape_free(t1);
    fm_graph_free(g);
}

/* fm_eval_interval_shorten_in gives the tape fm_eval_interval_shorten
 * gives (same length, same values bit for bit, against the full tape), a
 * tape of a tape too (a grid's block, then its leaf), and rewrites its slot
 * in place: one tape per slot however many boxes. */
static void check_shortening_in_place(void)
{
    int rewritten = 0, mismatches = 0, moved = 0;
    for (int trial = 0; trial < 200; trial++) {
        fm_graph *g = fm_graph_new(0);
        fm_node root = random_dag(g, 10 + (size_t)(test_rand01() * 50), trial & 1);
        fm_error err;
        fm_tape *t = fm_tape_compile(g, root, &err);
        fm_evaluator *ev = fm_evaluator_new(t, &err);
        fm_tape *slot = NULL, *slot2 = NULL, *first = NULL, *first2 = NULL;
        for (int b = 0; b < 20; b++) {
            fm_interval box[4], r1, r2;
            random_box(box);
            fm_evaluator_use(ev, NULL);
            fm_tape *ref = fm_eval_interval_shorten(ev, box, &r1);
            fm_tape *in = fm_eval_interval_shorten_in(ev, box, &r2, &slot);
            CHECK(same(r1.lo, r2.lo) && same(r1.hi, r2.hi));
            CHECK((ref == NULL) == (in == NULL));
            if (!ref || !in) {
                fm_tape_free(ref);
                continue;
            }
            CHECK(in == slot);
            CHECK(fm_tape_length(in) == fm_tape_length(ref));
            if (!first) first = in;
            moved += in != first;
            rewritten++;
            /* in the box's lower corner, from the shortened tape */
            fm_interval sub[4];
            lower_corner(box, sub);
            fm_evaluator_use(ev, in);
            fm_tape *ref2 = fm_eval_interval_shorten(ev, sub, NULL);
            fm_tape *in2 = fm_eval_interval_shorten_in(ev, sub, NULL, &slot2);
            CHECK((ref2 == NULL) == (in2 == NULL));
            CHECK(!ref2 || !in2 || fm_tape_length(in2) == fm_tape_length(ref2));
            if (in2 && !first2) first2 = in2;
            moved += in2 && in2 != first2;
            /* the tape in use is left alone */
            fm_evaluator_use(ev, in);
            CHECK(fm_eval_interval_shorten_in(ev, sub, NULL, &slot) == NULL && slot == in);
            for (int k = 0; k < 60; k++) {
                double p[4];
                const int in_sub = in2 && (k & 1);
                sample_in(in_sub ? sub : box, k, p);
                point_differs(ev, in_sub ? in2 : in, p, "rewritten tape", &mismatches);
            }
            check_batch_on(ev, in, box, "rewritten tape", &mismatches);
            fm_tape_free(ref2);
            fm_tape_free(ref);
        }
        fm_evaluator_free(ev);
        fm_tape_free(slot);
        fm_tape_free(slot2);
        fm_tape_free(t);
        fm_graph_free(g);
    }
    CHECK(rewritten > 100);
    CHECK(mismatches == 0);
    CHECK(moved == 0);
}

int main(void)
{
    check_each_op();
    check_random_soundness(0);
    check_random_soundness(1);
    check_random_shortening();
    check_csg_shortening();
    check_shortening_in_place();
    return test_summary("test_interval");
}
