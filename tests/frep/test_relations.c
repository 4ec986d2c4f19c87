/* test_relations.c: point membership, maximum search and the intersection
 * and inclusion relations on spheres, against closed forms (two spheres
 * meet iff the centre distance <= r1 + r2; one is inside the other iff
 * distance + r1 <= r2; the maximum of r - |p - c| over a box is r minus the
 * distance from c to the box; a sphere's inside bounds are [c - r, c + r]
 * up to the subdivision's smallest box). */
#include "frep/tape_internal.h"
#include "test.h"
#include "frep_shapes.h"

static const fm_interval world[4] = {{-6, 6}, {-6, 6}, {-6, 6}, {0, 0}};

static void check_classify(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_node s = shape_sphere(g, 1, 0, 0, 2);
    fm_error err;
    fm_tape *t = fm_tape_compile(g, s, &err);
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    double in[4] = {1.5, 0.2, 0, 0}, on[4] = {3.0, 0, 0, 0}, out[4] = {3.5, 1, 0, 0};
    CHECK(fm_classify_point(ev, in, 1e-9) == FM_INSIDE);
    CHECK(fm_classify_point(ev, on, 1e-9) == FM_ON_BOUNDARY);
    CHECK(fm_classify_point(ev, out, 1e-9) == FM_OUTSIDE);
    double near[4] = {3.0 + 1e-4, 0, 0, 0};
    CHECK(fm_classify_point(ev, near, 1e-3) == FM_ON_BOUNDARY);
    CHECK(fm_classify_point(ev, near, 1e-6) == FM_OUTSIDE);
    fm_evaluator_free(ev);
    fm_tape_free(t);
    fm_graph_free(g);
}

static void check_maximize(void)
{
    for (int k = 0; k < 20; k++) {
        fm_graph *g = fm_graph_new(0);
        double c[3] = {test_uniform(-3, 3), test_uniform(-3, 3), test_uniform(-3, 3)};
        double r = test_uniform(0.5, 2);
        fm_node s = shape_sphere(g, c[0], c[1], c[2], r);
        fm_error err;
        fm_tape *t = fm_tape_compile(g, s, &err);
        fm_interval box[4] = {{-1, 1}, {-1.5, 0.5}, {0, 2}, {0, 0}};
        double d2 = 0;
        for (int i = 0; i < 3; i++) {
            double e = c[i] < box[i].lo ? box[i].lo - c[i] : c[i] > box[i].hi ? c[i] - box[i].hi : 0;
            d2 += e * e;
        }
        double exact = r - sqrt(d2);
        fm_max_result m;
        CHECK(fm_maximize(t, box, 1e-6, 200000, &m, &err) == FM_OK);
        CHECK(m.value <= exact + 1e-12);
        CHECK(m.upper >= exact - 1e-12);
        CHECK(m.upper - m.value <= 1e-6);
        CHECK(m.evaluations <= 200000);
        double at = fm_graph_eval_reference(g, s, m.at);
        CHECK(at == m.value);
        fm_tape_free(t);
        fm_graph_free(g);
    }
}

static void check_sphere_relations(void)
{
    int decided = 0;
    for (int k = 0; k < 60; k++) {
        fm_graph *g = fm_graph_new(0);
        double c1[3], c2[3];
        for (int i = 0; i < 3; i++) {
            c1[i] = test_uniform(-2, 2);
            c2[i] = test_uniform(-2, 2);
        }
        double r1 = test_uniform(0.3, 1.5), r2 = test_uniform(0.3, 2.5);
        double d = sqrt((c1[0] - c2[0]) * (c1[0] - c2[0]) + (c1[1] - c2[1]) * (c1[1] - c2[1]) +
                        (c1[2] - c2[2]) * (c1[2] - c2[2]));
        fm_node s1 = shape_sphere(g, c1[0], c1[1], c1[2], r1);
        fm_node s2 = shape_sphere(g, c2[0], c2[1], c2[2], r2);
        fm_error err;
        int meet = fm_intersects(g, s1, s2, world, 1e-9, &err);
        if (fabs(d - (r1 + r2)) > 1e-3) {
            CHECK(meet == (d <= r1 + r2 ? 1 : 0));
            decided++;
        }
        int inside = fm_includes(g, s1, s2, world, 1e-9, &err);
        if (fabs(d + r1 - r2) > 1e-2) CHECK(inside == (d + r1 <= r2 ? 1 : 0));
        fm_graph_free(g);
    }
    CHECK(decided > 50);
    /* Tangent spheres touch: within the tolerance they meet. */
    fm_graph *g = fm_graph_new(0);
    fm_node a = shape_sphere(g, 0, 0, 0, 1), b = shape_sphere(g, 2, 0, 0, 1);
    fm_error err;
    CHECK(fm_intersects(g, a, b, world, 1e-6, &err) == 1);
    fm_graph_free(g);
}

static void check_inside_bounds(void)
{
    const fm_interval cube[3] = {{-8, 8}, {-8, 8}, {-8, 8}};
    for (int k = 0; k < 10; k++) {
        fm_graph *g = fm_graph_new(0);
        double c[3] = {test_uniform(-3, 3), test_uniform(-3, 3), test_uniform(-3, 3)};
        double r = test_uniform(0.5, 2);
        fm_error err;
        fm_tape *t = fm_tape_compile(g, shape_sphere(g, c[0], c[1], c[2], r), &err);
        fm_evaluator *ev = fm_evaluator_new(t, &err);
        fm_inside_bounds b;
        const double min_size = 16.0 / 256; /* the 16 mm cube halved ... */
        CHECK(fm_find_inside_bounds(ev, cube, min_size, 1000000, &b) == FM_OK && b.found);
        for (int a = 0; a < 3; a++) {
            /* ... 8 halvings: the kept boxes hold the sphere and reach at
             * most one box edge (plus the interval's looseness, here a
             * second) beyond it */
            CHECK(b.lo[a] <= c[a] - r && b.lo[a] >= c[a] - r - 2 * min_size);
            CHECK(b.hi[a] >= c[a] + r && b.hi[a] <= c[a] + r + 2 * min_size);
        }
        /* a budget too small to decide is a limit, not a wrong box */
        CHECK(fm_find_inside_bounds(ev, cube, min_size, 20, &b) == FM_ERR_LIMIT);
        fm_evaluator_free(ev);
        fm_tape_free(t);
        fm_graph_free(g);
    }
    /* a sphere outside the cube: nothing found */
    fm_graph *g = fm_graph_new(0);
    fm_error err;
    fm_tape *t = fm_tape_compile(g, shape_sphere(g, 20, 0, 0, 1), &err);
    fm_evaluator *ev = fm_evaluator_new(t, &err);
    fm_inside_bounds b;
    CHECK(fm_find_inside_bounds(ev, cube, 0.1, 1000000, &b) == FM_OK && !b.found);
    fm_evaluator_free(ev);
    fm_tape_free(t);
    fm_graph_free(g);
}

int main(void)
{
    check_inside_bounds();
    check_classify();
    check_maximize();
    check_sphere_relations();
    return test_summary("test_relations");
}
