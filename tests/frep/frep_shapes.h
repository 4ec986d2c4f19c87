/* frep_shapes.h: small shapes built from basic nodes, with closed forms,
 * for the special-op, gradient and relation tests. Include after test.h. */
#ifndef FM_TEST_FREP_SHAPES_H
#define FM_TEST_FREP_SHAPES_H

#include "frep/frep_internal.h"

/* r - |p - c| over x, y, z (exact distance, positive inside). */
static inline fm_node shape_sphere(fm_graph *g, double cx, double cy, double cz, double r)
{
    fm_node dx = fm_sub(g, fm_var(g, FM_X), fm_const(g, cx));
    fm_node dy = fm_sub(g, fm_var(g, FM_Y), fm_const(g, cy));
    fm_node dz = fm_sub(g, fm_var(g, FM_Z), fm_const(g, cz));
    fm_node d = fm_sqrt(g, fm_add(g, fm_add(g, fm_square(g, dx), fm_square(g, dy)), fm_square(g, dz)));
    return fm_sub(g, fm_const(g, r), d);
}

static inline double sphere_value(double cx, double cy, double cz, double r, const double p[4])
{
    return r - sqrt((p[0] - cx) * (p[0] - cx) + (p[1] - cy) * (p[1] - cy) + (p[2] - cz) * (p[2] - cz));
}

#endif
