/* sweep_internal.h: the sweep object shared by the files of lib/sweep
 * (evaluation, set-up, fields). Not part of the public interface. */
#ifndef FM_SWEEP_INTERNAL_H
#define FM_SWEEP_INTERNAL_H

#include "sweep/kin_internal.h"
#include "sweep/sweep.h"

typedef enum sw_kind { SW_STATIC = 0, SW_LINE, SW_ARC, SW_PARAM, SW_KIN } sw_kind;

struct fm_sweep {
    fm_tool_part part;
    fm_sweep_method method;
    sw_kind kind;
    double t0, t1;
    double tol;
    size_t max_evals;
    /* line: tip(u) = c0 + u d; static: tip = c0 */
    double c0[3], d[3], dd;
    /* axis: a0 (fixed) or nlerp from a0 to a1 */
    double a0[3], a1[3], lmin;
    int axis_const;
    /* arc: tip(u) = ctr + r(u) (cos th(u) e_ai + sin th(u) e_aj) + u dh e_ak */
    int ai, aj, ak, full_turn;
    double ctr[3], th0, dth, r0, drr, dh;
    /* helix (FM_SWEEP_HELIX): cos and sin of the start and end angles */
    double hx_c0, hx_s0, hx_c1, hx_s1;
    /* the part holds the ball of radius r_max about (0, hx_zmid) */
    double hx_zmid;
    /* parametric */
    const fm_path *path;
    /* rotary axes (kinematics.c) */
    fm_kin kin;
    double tip_offset[3];
    /* search: |dtip/du| <= lipschitz, |daxis/du| <= turn_rate,
     * |d2tip/du2| <= accel; pieces to start the branch-and-bound with */
    double lipschitz, turn_rate, accel, speed;
    int second_order, certified, pieces;
    double lo[3], hi[3];
};

/* S at n points (z may be NULL: 0), values identical to fm_sweep_eval.
 * shortfall (may be NULL) gets upper - value where the point's search
 * stopped at its budget before its proof closed, 0 elsewhere (batch.c). */
void fm_sweep_batch_ex(const fm_sweep *s, fm_sweep_worker *worker, size_t n, const double *x, const double *y,
                       const double *z, double *out, double *shortfall);

struct fm_sweep_worker {
    const fm_tool_part *part;
    void *part_worker;
    void *heap; /* the branch-and-bound heap of sweep.c, made on first use */
};

#endif
