/* dag.c: the 4D tool object T(p, t) of a motion as an frep DAG (Pasko 1995
 * sec. 2.2.6-2.2.7: a moving solid is a time-dependent mapping of a static
 * one, cut to its time segment), and its projection on t. The pose uses
 * the same parameters as the native evaluator (setup.c), so the two agree. */
#include "sweep/sweep_internal.h"

#include <math.h>

#define K(v) fm_const(g, (v))

fm_node fm_sweep_build_4d(fm_graph *g, const fm_motion *m, const fm_tool_part *part, const fm_node *pose)
{
    if (!g) return FM_NONE;
    fm_sweep_options opt = {0};
    opt.no_fast_paths = 1;
    fm_sweep *s;
    if (fm_sweep_new(m, part, &opt, &s, NULL) != FM_OK) return FM_NONE;
    fm_node t = fm_var(g, FM_T);
    fm_node u = s->t1 > s->t0 ? fm_div(g, fm_sub(g, t, K(s->t0)), K(s->t1 - s->t0)) : K(0);
    fm_node c[3], a[3];
    switch (s->kind) {
    case SW_LINE:
        for (int i = 0; i < 3; i++) c[i] = fm_add(g, K(s->c0[i]), fm_mul(g, u, K(s->d[i])));
        if (s->axis_const) {
            for (int i = 0; i < 3; i++) a[i] = K(s->a0[i]);
        } else {
            fm_node l[3];
            for (int i = 0; i < 3; i++) l[i] = fm_add(g, K(s->a0[i]), fm_mul(g, u, K(s->a1[i] - s->a0[i])));
            fm_node n = fm_sqrt(g, fm_add(g, fm_add(g, fm_square(g, l[0]), fm_square(g, l[1])), fm_square(g, l[2])));
            for (int i = 0; i < 3; i++) a[i] = fm_div(g, l[i], n);
        }
        break;
    case SW_ARC: {
        fm_node th = fm_add(g, K(s->th0), fm_mul(g, u, K(s->dth)));
        fm_node rr = fm_add(g, K(s->r0), fm_mul(g, u, K(s->drr)));
        c[s->ai] = fm_add(g, K(s->ctr[s->ai]), fm_mul(g, rr, fm_unary(g, FM_OP_COS, th)));
        c[s->aj] = fm_add(g, K(s->ctr[s->aj]), fm_mul(g, rr, fm_unary(g, FM_OP_SIN, th)));
        c[s->ak] = fm_add(g, K(s->ctr[s->ak]), fm_mul(g, u, K(s->dh)));
        for (int i = 0; i < 3; i++) a[i] = K(s->a0[i]);
        break;
    }
    case SW_KIN:
        fm_kin_build_pose(g, &s->kin, u, c, a);
        break;
    case SW_PARAM:
        if (!pose) {
            fm_sweep_free(s);
            return FM_NONE;
        }
        for (int i = 0; i < 3; i++) {
            c[i] = fm_add(g, pose[i], K(s->tip_offset[i]));
            a[i] = pose[3 + i];
        }
        break;
    case SW_STATIC:
    default:
        for (int i = 0; i < 3; i++) {
            c[i] = K(s->c0[i]);
            a[i] = K(s->a0[i]);
        }
        break;
    }
    fm_node v[3], zeta = K(0);
    for (int i = 0; i < 3; i++) {
        v[i] = fm_sub(g, fm_var(g, i), c[i]);
        zeta = fm_add(g, zeta, fm_mul(g, a[i], v[i]));
    }
    fm_node w2 = K(0);
    for (int i = 0; i < 3; i++) w2 = fm_add(g, w2, fm_square(g, fm_sub(g, v[i], fm_mul(g, zeta, a[i]))));
    fm_node f = fm_tool_part_build_rz(g, part, fm_sqrt(g, w2), zeta);
    /* Time segment (eq. 14) with min, which keeps the distance. */
    fm_node seg = fm_min(g, fm_sub(g, t, K(s->t0)), fm_sub(g, K(s->t1), t));
    fm_sweep_free(s);
    return fm_min(g, f, seg);
}

fm_node fm_sweep_build_projection(fm_graph *g, const fm_motion *m, const fm_tool_part *part,
                                  const fm_node *pose)
{
    fm_node T = fm_sweep_build_4d(g, m, part, pose);
    if (T == FM_NONE) return FM_NONE;
    return fm_project(g, T, FM_T, m->t0, m->t1);
}
