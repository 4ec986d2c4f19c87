/* design_private.h: what design.c (the C side of the design comparison)
 * and its C++ bridge vdb_design.cpp say to each other. Not part of the
 * public API. Grids here use OpenVDB's sign (phi < 0 inside). */
#ifndef FM_DESIGN_PRIVATE_H
#define FM_DESIGN_PRIVATE_H

#include "stock/stock_private.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Rebuild the level set of source onto target, an empty grid whose voxel,
 * origin and band say where (OpenVDB's levelSetRebuild: the zero surface
 * meshed and converted back). FM_ERR_LIMIT when the estimated grid is over
 * budget bytes. */
fm_status fm_vdb_rebuild_onto(fm_vdb *target, const fm_vdb *source, size_t budget, fm_error *err);
/* Widen a level set's band to band voxels in place (OpenVDB's fast sweeping,
 * dilateSdf): a snapshot on the stock's own grid whose band is narrower than
 * the design's. */
fm_status fm_vdb_widen_band(fm_vdb *v, int band, size_t budget, fm_error *err);

/* The design's signed distance (OpenVDB sign) at n points (3 floats each)
 * or one point, exact beyond its band too (from its surface points: docs/
 * stock.md, "Deviation colours"); budget bounds the surface points. */
fm_status fm_vdb_design_distances(const fm_vdb *design, const float *xyz, size_t n, double *out,
                                  size_t budget, fm_error *err);
fm_status fm_vdb_design_distance(const fm_vdb *design, const double p[3], double *out,
                                 size_t budget, fm_error *err);

/* Both grids on one transform (same voxel and origin). tolerance in mm;
 * budget bounds the comparison's own tables; threads 0 = one per core.
 * field: the design's field when its grid is a topology
 * (fm_vdb_rasterize_topology), whose marked cells are evaluated where they
 * are read; then full gives the grid with values (made once, on first
 * call; NULL and err when it cannot), which only a region deeper than the
 * design's band needs. */
typedef struct fm_vdb_compare_options {
    double tolerance;
    size_t max_regions;
    size_t budget;
    int threads;
    const fm_field *field;
    const fm_vdb *(*full)(void *user, fm_error *err);
    void *full_user;
} fm_vdb_compare_options;

/* Deviation of stock from design (docs/stock.md, "Design comparison"). out
 * must be zeroed; its arrays are malloc'd (fm_deviation_free). */
fm_status fm_vdb_compare(const fm_vdb *stock, const fm_vdb *design,
                         const fm_vdb_compare_options *opt, fm_deviation *out, fm_error *err);

#ifdef __cplusplus
}
#endif

#endif
