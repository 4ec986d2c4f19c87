/* ops_internal.h: contracts between the builders of lib/frep (ops.c,
 * prims.c) and the evaluators that are not visible in frep_internal.h.
 * Not part of the public API. */
#ifndef FM_OPS_INTERNAL_H
#define FM_OPS_INTERNAL_H

#include "frep/frep_internal.h"

/* A VOXELS node samples its grid at the point (a, b, c): its three children
 * are the x, y and z coordinate expressions. fm_voxels creates them as the
 * plain coordinates; fm_remap (translate, rotate, affine, ...) substitutes
 * into them, which is how a voxel object is moved. Evaluators must sample
 * at the children's values, not at the raw point. */
#define FM_VOXELS_MAX_SAMPLES ((size_t)1 << 28)

/* 1 once the evaluators (special.c, tape.c) sample VOXELS at the children's
 * values. While 0, fm_remap refuses to move a voxel grid, since the tape
 * would sample the unmoved grid at the raw point and be silently wrong. */
#ifndef FM_VOXELS_SAMPLE_CHILDREN
#define FM_VOXELS_SAMPLE_CHILDREN 1
#endif

#endif
