/* dag.c: tool parts as frep DAGs, the same exact 2D distance as the native
 * evaluator in profile.c, for the 4D tool objects of lib/sweep, the
 * modeling language and tests. */
#include "tools/tools.h"

#include <math.h>

#define K(v) fm_const(g, (v))

static fm_node hypot_n(fm_graph *g, fm_node a, fm_node b)
{
    return fm_sqrt(g, fm_add(g, fm_square(g, a), fm_square(g, b)));
}

/* Unsigned distance from (r, z) to one element. */
static fm_node elem_dist(fm_graph *g, const fm_profile_elem *e, fm_node r, fm_node z)
{
    fm_node qa_r = fm_sub(g, r, K(e->a[0])), qa_z = fm_sub(g, z, K(e->a[1]));
    if (e->kind == FM_PROFILE_SEGMENT) {
        double dr = e->b[0] - e->a[0], dz = e->b[1] - e->a[1], len2 = dr * dr + dz * dz;
        if (len2 == 0) return hypot_n(g, qa_r, qa_z);
        fm_node s = fm_div(g, fm_add(g, fm_mul(g, qa_r, K(dr)), fm_mul(g, qa_z, K(dz))), K(len2));
        s = fm_max(g, K(0), fm_min(g, K(1), s));
        return hypot_n(g, fm_sub(g, qa_r, fm_mul(g, s, K(dr))), fm_sub(g, qa_z, fm_mul(g, s, K(dz))));
    }
    fm_node vr = fm_sub(g, r, K(e->c[0])), vz = fm_sub(g, z, K(e->c[1]));
    double ar = e->a[0] - e->c[0], az = e->a[1] - e->c[1];
    double br = e->b[0] - e->c[0], bz = e->b[1] - e->c[1];
    /* Sector test as in profile.c: cross(a - c, v) and cross(v, b - c). */
    fm_node c1 = fm_sub(g, fm_mul(g, K(ar), vz), fm_mul(g, K(az), vr));
    fm_node c2 = fm_sub(g, fm_mul(g, vr, K(bz)), fm_mul(g, vz, K(br)));
    fm_node in;
    if (e->ccw)
        in = fm_binary(g, FM_OP_AND, fm_binary(g, FM_OP_LE, K(0), c1), fm_binary(g, FM_OP_LE, K(0), c2));
    else
        in = fm_binary(g, FM_OP_AND, fm_binary(g, FM_OP_LE, c1, K(0)), fm_binary(g, FM_OP_LE, c2, K(0)));
    fm_node radial = fm_abs(g, fm_sub(g, hypot_n(g, vr, vz), K(e->radius)));
    fm_node ends = fm_min(g, hypot_n(g, qa_r, qa_z),
                          hypot_n(g, fm_sub(g, r, K(e->b[0])), fm_sub(g, z, K(e->b[1]))));
    return fm_select(g, in, radial, ends);
}

/* r of the element at height z (valid where the element spans z). */
static fm_node elem_radius(fm_graph *g, const fm_profile_elem *e, fm_node z)
{
    if (e->kind == FM_PROFILE_SEGMENT) {
        double dz = e->b[1] - e->a[1];
        if (dz == 0) return K(fmax(e->a[0], e->b[0]));
        return fm_add(g, K(e->a[0]), fm_mul(g, fm_sub(g, z, K(e->a[1])), K((e->b[0] - e->a[0]) / dz)));
    }
    fm_node h = fm_sub(g, K(e->radius * e->radius), fm_square(g, fm_sub(g, z, K(e->c[1]))));
    fm_node w = fm_sqrt(g, fm_max(g, h, K(0)));
    double side = (e->a[0] + e->b[0]) * 0.5 - e->c[0];
    return side >= 0 ? fm_add(g, K(e->c[0]), w) : fm_sub(g, K(e->c[0]), w);
}

fm_node fm_tool_part_build_rz(fm_graph *g, const fm_tool_part *part, fm_node r, fm_node z)
{
    if (part->kind != FM_TOOL_PART_PROFILE) {
        return FM_NONE; /* custom parts are functions already (their own tape) */
    }
    fm_node d = FM_NONE;
    for (size_t i = 0; i < part->count; i++) {
        fm_node di = elem_dist(g, &part->elem[i], r, z);
        d = d == FM_NONE ? di : fm_min(g, d, di);
    }
    /* R(z): the largest radius of the elements spanning z (as in profile.c),
     * -1 outside every span. */
    fm_node R = K(-1);
    for (size_t i = 0; i < part->count; i++) {
        const fm_profile_elem *e = &part->elem[i];
        fm_node span = fm_binary(g, FM_OP_AND, fm_binary(g, FM_OP_LE, K(e->a[1]), z),
                                 fm_binary(g, FM_OP_LE, z, K(e->b[1])));
        R = fm_select(g, span, fm_max(g, R, elem_radius(g, e, z)), R);
    }
    fm_node in = fm_binary(g, FM_OP_AND,
                           fm_binary(g, FM_OP_AND, fm_binary(g, FM_OP_LE, K(part->z_lo), z),
                                     fm_binary(g, FM_OP_LE, z, K(part->z_hi))),
                           fm_binary(g, FM_OP_LE, r, R));
    return fm_select(g, in, d, fm_neg(g, d));
}

fm_node fm_tool_part_build(fm_graph *g, const fm_tool_part *part)
{
    fm_node x = fm_var(g, FM_X), y = fm_var(g, FM_Y), z = fm_var(g, FM_Z);
    return fm_tool_part_build_rz(g, part, hypot_n(g, x, y), z);
}
