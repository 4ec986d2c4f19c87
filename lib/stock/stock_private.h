/* stock_private.h: what lib/stock's C files and its C++ bridge
 * (vdb_*.cpp) say to each other, and the one door lib/mesh's C++ bridge
 * may use (fm_stock_vdb_grid). Not part of the public API. Signs here are
 * OpenVDB's (phi < 0 inside) unless a comment says otherwise. */
#ifndef FM_STOCK_PRIVATE_H
#define FM_STOCK_PRIVATE_H

/* core.h and frep.h are plain C headers without C++ guards. */
#ifdef __cplusplus
extern "C" {
#endif

#include "stock/stock.h"

/* The grid plus its thread arena; defined in vdb_bridge.hpp. */
typedef struct fm_vdb fm_vdb;

/* Chunk and budget bookkeeping the bridge reports back to C. */
typedef void (*fm_vdb_touch_fn)(void *user, const int32_t lo[3], const int32_t hi[3]);

/* Empty grid: background +band*voxel, voxel centres at origin + voxel*i. */
fm_vdb *fm_vdb_new(double voxel, int band, const double origin[3], int threads, fm_error *err);
void fm_vdb_free(fm_vdb *v);

/* Rasterize field (positive inside) into an empty grid. Refuses with
 * FM_ERR_LIMIT, before allocating leaves, when the boundary leaves found by
 * the interval pass would exceed budget bytes. */
fm_status fm_vdb_rasterize(fm_vdb *v, const fm_field *field, size_t budget, fm_error *err);
/* fm_vdb_rasterize's interval pass alone, into an empty grid: the inside
 * tiles it makes, and each leaf it would evaluate as an active leaf-sized
 * tile of value FM_VDB_LEAF_MARK (a value no level-set tile has: those are
 * +-band), whose values are the field's batch over the leaf's voxel centres,
 * -f clamped to the band (the design comparison evaluates them where it
 * reads them, without a grid). Same budget check, for the leaves a
 * rasterization would take. */
#define FM_VDB_LEAF_MARK 0.0f
fm_status fm_vdb_rasterize_topology(fm_vdb *v, const fm_field *field, size_t budget,
                                    fm_error *err);

/* What a subtraction reports, on the calling thread, after the parallel
 * work. Any callback may be NULL. */
typedef struct fm_vdb_cut_events {
    void *user;
    /* an index box whose values changed */
    void (*touch)(void *user, const int32_t lo[3], const int32_t hi[3]);
    /* the leaf at index box [lo, hi] (8^3 voxels) keeps a surface; bit
     * (i & 63) of set[i >> 6] says voxel i = 64 x + 8 y + z (offsets in
     * the leaf) got its value from this cut */
    void (*leaf_set)(void *user, const int32_t lo[3], const uint64_t set[8]);
    /* the index box holds no surface any more (a tile now) */
    void (*cleared)(void *user, const int32_t lo[3], const int32_t hi[3]);
} fm_vdb_cut_events;

/* grid = grid \ field, restricted to the region that can change; events
 * (may be NULL) hears what changed. Refuses with FM_ERR_LIMIT, grid
 * unchanged, when the new leaves would take the grid over budget. */
fm_status fm_vdb_subtract(fm_vdb *v, const fm_field *field, size_t budget,
                          const fm_vdb_cut_events *events, fm_stock_cut_stats *stats,
                          fm_error *err);

/* Closed triangle soup (world mm) to a level set; grid must be empty. */
fm_status fm_vdb_from_mesh(fm_vdb *v, const float *points, size_t npoints, const uint32_t *tris,
                           size_t ntris, fm_error *err);

double fm_vdb_volume(const fm_vdb *v);
fm_status fm_vdb_area(const fm_vdb *v, double *area, fm_error *err);
size_t fm_vdb_memory(const fm_vdb *v);
/* The grid's counts behind fm_stock_memory_usage. */
typedef struct fm_vdb_counts {
    size_t memusage;       /* OpenVDB's Tree::memUsage() */
    size_t leaves;
    size_t internal_nodes; /* 16^3 and 32^3 internal nodes */
    size_t active_voxels;
} fm_vdb_counts;
void fm_vdb_memory_usage(const fm_vdb *v, fm_vdb_counts *out);
/* Bytes one more leaf costs (for the estimate formula). */
size_t fm_vdb_leaf_bytes(void);
/* What OpenVDB's memUsage() counts for one leaf (no allocator headers). */
size_t fm_vdb_leaf_memusage(void);
size_t fm_vdb_internal1_bytes(void);
/* Bytes of one root child (4096^3 voxels). */
size_t fm_vdb_internal2_bytes(void);
double fm_vdb_voxel(const fm_vdb *v);
int fm_vdb_band(const fm_vdb *v);
void fm_vdb_origin(const fm_vdb *v, double origin[3]);
/* Inclusive index box of the active voxels; 0 if there are none. */
int fm_vdb_active_bounds(const fm_vdb *v, int32_t lo[3], int32_t hi[3]);
/* Trilinear phi at a world point (OpenVDB sign). */
double fm_vdb_sample(const fm_vdb *v, const double p[3]);
/* Call touch for the index box of every leaf (initial chunk marking). */
void fm_vdb_for_each_leaf(const fm_vdb *v, fm_vdb_touch_fn touch, void *user);

/* fm_stock_visit's walk (vdb_query.cpp). */
fm_status fm_vdb_visit(const fm_vdb *v, const int32_t lo[3], const int32_t hi[3],
                       int (*prune)(void *user, const int32_t lo[3], const int32_t hi[3]),
                       int (*visit)(void *user, const fm_stock_region *region), void *user,
                       fm_error *err);
/* The zero set of the grid as triangles (world mm; malloc'd, the caller
 * frees both). FM_ERR_INPUT when there is no surface. */
fm_status fm_vdb_zero_set_mesh(const fm_vdb *v, float **points, size_t *npoints, uint32_t **tris,
                               size_t *ntris, fm_error *err);
/* For benchmarks: OpenVDB's bare update of the given voxels (bit (i & 63) of
 * sets[j][i >> 6] marks voxel i of the leaf at origins[j]): read through a
 * value accessor, max with -background (which never changes a value), write
 * back with setValueOnly; timed on the calling thread, best of three rounds.
 * Returns seconds per voxel (0 when there are none); *voxels gets their
 * count. The grid's values are unchanged. */
double fm_vdb_time_bare_update(fm_vdb *v, const int32_t (*origins)[3], const uint64_t (*sets)[8],
                               size_t n, size_t *voxels);

/* Serialize to a malloc'd buffer (OpenVDB stream, Blosc when available). */
fm_status fm_vdb_write(const fm_vdb *v, unsigned char **buf, size_t *len, fm_error *err);
/* Parse bytes already verified by the snapshot wrapper. */
fm_vdb *fm_vdb_read(const unsigned char *buf, size_t len, int threads, fm_error *err);

/* Check the level-set invariants (for tests; costs O(grid)): values within
 * +-background, a voxel active exactly when |phi| < background, tiles
 * inactive at +-background, and no face-neighbours at +background and
 * -background (a hole in the band). FM_ERR_INTERNAL names the first
 * violation. */
fm_status fm_vdb_validate(const fm_vdb *v, fm_error *err);
/* Index coordinates of the voxels beside material thinner than a voxel
 * (vdb_thin.cpp): at most cap of them in *ijk (3 per voxel, malloc'd, NULL
 * when none), *total counts all. */
fm_status fm_vdb_thin_voxels(const fm_vdb *v, size_t cap, int32_t **ijk, size_t *count, size_t *total,
                             fm_error *err);
fm_status fm_stock_validate(const fm_stock *stock, fm_error *err);

/* For lib/mesh's C++ bridge only: a pointer to the stock's
 * openvdb::FloatGrid::Ptr (cast it back to that type). Valid until the stock
 * is freed; do not modify the grid, and never use it from C. */
void *fm_stock_vdb_grid(fm_stock *stock);
void *fm_vdb_grid_ptr(fm_vdb *v);

#ifdef __cplusplus
}
#endif

#endif
