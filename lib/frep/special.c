/* special.c: evaluation of the ops that need a search or data (projection,
 * constant-radius offset, normal offset, normalization, voxel grids).
 * Placeholder until the evaluators land: the reference evaluator reports
 * NaN for them. */
#include "frep/frep_internal.h"

double fm_reference_special(const fm_graph *g, fm_node n, const double p[4])
{
    (void)g;
    (void)n;
    (void)p;
    return NAN;
}
