/* stock.h: the workpiece. lib/stock keeps the stock as an OpenVDB narrow-band
 * level set (C++ inside, this C header outside), creates it from a box, a
 * cylinder, an F-rep field, an STL mesh or a frepmill snapshot, subtracts
 * swept volumes from it, measures it, tracks which chunks changed, and saves
 * crash-safe snapshots. Everything in this header uses the F-rep sign:
 * positive inside, millimetres. No C++ type crosses it. */
#ifndef FM_STOCK_H
#define FM_STOCK_H

#include "core/core.h"
#include "frep/frep.h"

#include <stddef.h>
#include <stdint.h>

typedef struct fm_stock fm_stock;

typedef struct fm_stock_options {
    double voxel_mm;          /* edge of a voxel; default 0.1 */
    int band_voxels;          /* narrow-band half-width in voxels; default 3, at least 2 */
    size_t memory_budget;     /* bytes the grid may use; default 4 GiB */
    int threads;              /* 0: one per core */
    size_t block_table_size;  /* per-block entries kept (largest removals win); default 4096 */
} fm_stock_options;

void fm_stock_options_default(fm_stock_options *opt);

/* The memory a grid needs for a surface, before anything is allocated.
 * projected_area_mm2 is the sum over the surface of |nx|+|ny|+|nz| dA, i.e.
 * the areas of the surface projected on the three axis planes (a box's
 * plain surface area; about 1.27 times the area of a cylinder's side).
 * The formula is in docs/stock.md. */
size_t fm_stock_estimate_bytes(double projected_area_mm2, double voxel_mm, int band_voxels);

/* ------------------------------------------------------------ creation -- */
/* opt may be NULL (defaults). All return NULL and fill err on failure:
 * FM_ERR_INPUT for bad geometry or files, FM_ERR_LIMIT when the estimate
 * exceeds the budget (the message names both), FM_ERR_IO for files. */
fm_stock *fm_stock_new_box(const double lo[3], const double hi[3], const fm_stock_options *opt,
                           fm_error *err);
/* Upright cylinder: axis parallel to Z through (x, y), from z0 to z1. */
fm_stock *fm_stock_new_cylinder(double x, double y, double z0, double z1, double r,
                                const fm_stock_options *opt, fm_error *err);
/* Any field (a HyperFun model): rasterized in its narrow band; the interval
 * callback skips leaf-sized boxes. The memory estimate counts the boundary
 * leaves the interval pass finds. */
fm_stock *fm_stock_new_from_field(const fm_field *field, const fm_stock_options *opt,
                                  fm_error *err);
/* A HyperFun model (.hf) as a field (hf_model.c says how): values are the
 * model normalized to a first-order distance (f / |grad f|) cut by its
 * bounding box; a box the raw model's interval over the box widened by
 * reach (mm: the grid's band) shows all inside or all outside is reported
 * beyond the band (a tile), so interior leaves are never evaluated and the
 * grid's memory grows with the model's area, not its volume. The bounds
 * are searched within +-2000 mm down to voxel; what ("stock", "design")
 * names it in messages (file path first). The field owns the compiled
 * model: fm_field_release frees it (fm_design_from_field takes it over).
 * The one builder of models as fields, for stocks and designs. */
fm_status fm_stock_hf_field(const char *path, double voxel, double reach, const char *what,
                            fm_field *out, fm_error *err);
/* A stock from a HyperFun model: its field at the options' voxel, reach
 * the band. */
fm_stock *fm_stock_new_from_hf(const char *path, const fm_stock_options *opt, fm_error *err);
/* Binary or ASCII STL of a closed mesh (cast or pre-machined stock). An
 * open surface is refused (FM_ERR_INPUT) with its first open edge. The
 * _named form says what the solid is in its errors ("fixture", ...; the
 * first says "stock"). */
fm_stock *fm_stock_new_from_stl(const char *path, const fm_stock_options *opt, fm_error *err);
fm_stock *fm_stock_new_from_stl_named(const char *path, const char *what,
                                      const fm_stock_options *opt, fm_error *err);
/* A snapshot written by fm_stock_save (never a file a network client sent).
 * opt supplies the budget and threads; voxel and band come from the file. */
fm_stock *fm_stock_load_vdb(const char *path, const fm_stock_options *opt, fm_error *err);
/* Resume after a crash: path, or "<path>.prev" when path is missing or
 * damaged. *used_prev (may be NULL) says which. Errors name both files. */
fm_stock *fm_stock_load_latest(const char *path, const fm_stock_options *opt, int *used_prev,
                               fm_error *err);
void fm_stock_free(fm_stock *stock);

/* ----------------------------------------------------------- cutting -- */

typedef struct fm_stock_cut {
    int tool;       /* tool number: removed volume is summed per tool */
    int64_t block;  /* block / source line id: summed per block; negative = none */
    double t0, t1;  /* program time of the motion, seconds */
} fm_stock_cut;

/* What one subtraction did; for tests, benchmarks and the report. */
typedef struct fm_stock_cut_stats {
    double removed_mm3;      /* volume before - volume after, of the touched region */
    size_t intervals;        /* interval evaluations of the swept field (boxes and leaf octants) */
    size_t leaves_evaluated; /* 8^3 leaves that got voxel work */
    size_t voxels_evaluated; /* voxels the field was evaluated at: at most 512 per leaf, fewer
                                where the stock value there is at or above the field's bound */
    size_t interior_boxes;   /* boxes found all inside the swept volume */
    size_t leaves_changed;   /* leaves whose values changed */
    size_t voxels_changed;   /* voxels of those leaves whose value the cut changed (tiles not counted) */
    /* Voxels the cut may have left uncut: the swept field's search at them stopped at its
     * evaluation budget before proving its value (fm_field.batch_shortfall), and the value it
     * could not exclude would have cut more; and the most it could be, in mm. Should be 0. */
    size_t voxels_uncertain;
    double uncertain_max_mm;
    /* Where the time went (seconds; for benchmarks): wall time of the serial interval pass, of the
     * parallel voxel pass and of the serial topology/bookkeeping phase; thread-seconds of the leaf
     * jobs and of the field's calls within them (estimated from one job in eight). */
    double time_classify_s, time_voxels_s, time_apply_s;
    double time_leaves_cpu_s, time_field_cpu_s;
} fm_stock_cut_stats;

/* stock = stock \ swept. swept is positive inside, first-order distance,
 * negative outside its [lo, hi] (frep.h). cut may be NULL (tool 0, no
 * block). stats may be NULL. A cut refused for its budget (FM_ERR_LIMIT)
 * or bad input leaves the stock unchanged; after an out-of-memory or
 * internal error in the middle of a cut the stock may be partly cut. */
fm_status fm_stock_subtract(fm_stock *stock, const fm_field *swept, const fm_stock_cut *cut,
                            fm_stock_cut_stats *stats, fm_error *err);

/* ----------------------------------------------------------- measures -- */

/* Volume of the whole grid now (mm^3), summed voxel by voxel with a linear
 * smooth Heaviside; costs O(grid). */
double fm_stock_volume(const fm_stock *stock);
/* Volume when created (or the initial volume stored in a snapshot). */
double fm_stock_initial_volume(const fm_stock *stock);
/* Sum of the removed volumes of all cuts, computed on the touched region
 * only; equals initial - current volume up to rounding. */
double fm_stock_removed_volume(const fm_stock *stock);
/* Removed by one tool number (0 if it never cut). */
double fm_stock_removed_volume_tool(const fm_stock *stock, int tool);

typedef struct fm_stock_tool_volume {
    int tool;
    double removed_mm3;
} fm_stock_tool_volume;
/* Fills up to cap entries (ascending tool number); returns how many exist. */
size_t fm_stock_tool_volumes(const fm_stock *stock, fm_stock_tool_volume *out, size_t cap);

typedef struct fm_stock_block {
    int64_t block;
    double removed_mm3;
    double t0, t1; /* program time span of the block's cuts: rate = removed / (t1 - t0) */
} fm_stock_block;
/* Blocks by removed volume, largest first; up to cap; returns how many are
 * kept (at most opt.block_table_size: when full, the smallest is evicted). */
size_t fm_stock_blocks(const fm_stock *stock, fm_stock_block *out, size_t cap);
/* 1 and *out if the block is in the table, else 0. */
int fm_stock_block_removed(const fm_stock *stock, int64_t block, fm_stock_block *out);

/* The tool that last cut a voxel: 1 and *tool (may be NULL) when a cut
 * set voxel ijk's value, 0 where no cut did (uncut stock, or away from
 * the surface). Every cut records its tool on the voxels near the new
 * surface whose values it set (what colours meshes by tool); the records
 * take about 90 bytes per 8^3 leaf, 1 KB more where two tools share one,
 * within the memory budget, and are kept in snapshots. */
int fm_stock_voxel_tool(const fm_stock *stock, const int32_t ijk[3], int *tool);
/* The same at the voxel nearest a world point (mm). */
int fm_stock_point_tool(const fm_stock *stock, const double p[3], int *tool);

/* Surface area (mm^2), OpenVDB's levelSetArea; costs O(grid). */
fm_status fm_stock_surface_area(const fm_stock *stock, double *area_mm2, fm_error *err);
/* Change the memory budget later cuts are held to (bytes, > 0). */
void fm_stock_set_memory_budget(fm_stock *stock, size_t bytes);
/* Memory the grid uses now (bytes, OpenVDB's own count plus the tool
 * marks). */
size_t fm_stock_memory_bytes(const fm_stock *stock);

/* Where the stock's memory goes, for reports and benchmarks (bytes unless
 * named otherwise). band_bytes is OpenVDB's own count (Tree::memUsage:
 * the leaves' nodes and value buffers, the internal nodes, the root);
 * leaf_bytes is what one more leaf costs with malloc's headers (the
 * budget's figure), so leaves x leaf_bytes + internal_bytes is the band as
 * the allocator sees it. Costs a walk over the grid's nodes. */
typedef struct fm_stock_memory {
    size_t leaves;          /* 8^3 leaves */
    size_t active_voxels;   /* voxels in the narrow band */
    size_t internal_nodes;  /* 16^3 and 32^3 internal nodes */
    size_t leaf_bytes;      /* one leaf: node, value buffer, allocator headers */
    size_t internal_bytes;  /* the internal nodes and the root */
    size_t band_bytes;      /* OpenVDB's memUsage() of the grid */
    size_t marks_bytes;     /* the tool marks (fm_stock_voxel_tool) in use; the budget also
                               counts their spare capacity, which is never written */
    size_t marks_leaves;    /* leaves the tool marks keep a record for */
    size_t tables_bytes;    /* dirty chunks, per-tool and per-block tables */
} fm_stock_memory;
void fm_stock_memory_usage(const fm_stock *stock, fm_stock_memory *out);

/* For benchmarks (the floor of bench_simulate): the cost of OpenVDB's bare
 * update of the voxels the cuts set - read through a value accessor, max,
 * write back - timed on one thread over the voxels the tool marks record
 * (those still in the band whose value a cut set), best of three rounds.
 * The stock is left unchanged. Returns seconds per voxel, 0 before any cut;
 * *voxels (may be NULL) gets how many voxels were timed. */
double fm_stock_time_bare_update(fm_stock *stock, size_t *voxels);

/* ------------------------------------------------------------- chunks -- */

#define FM_STOCK_CHUNK_VOXELS 64

typedef struct fm_stock_chunk {
    int32_t index[3];  /* chunk coordinates: voxel index / 64, rounded down */
    uint64_t version;  /* stock version when it last changed */
    double lo[3], hi[3]; /* world bounds of the chunk's voxel centres, mm */
} fm_stock_chunk;

/* Bumped by every subtraction that changed the grid; 1 after creation. */
uint64_t fm_stock_version(const fm_stock *stock);
/* Chunks changed after version since (0: all chunks with surface): those
 * with a changed leaf and those within two voxels of one, whose meshes read
 * its values (faces one voxel beyond the chunk, normals two). Fills up to
 * cap entries and returns the number that match. */
size_t fm_stock_changed_chunks(const fm_stock *stock, uint64_t since, fm_stock_chunk *out,
                               size_t cap);
void fm_stock_chunk_bounds(const fm_stock *stock, const int32_t index[3], double lo[3],
                           double hi[3]);

/* ---------------------------------------------------------- accessors -- */

double fm_stock_voxel_size(const fm_stock *stock);
int fm_stock_band_voxels(const fm_stock *stock);
/* World position of voxel index ijk (voxel centres are at integer indices). */
void fm_stock_index_to_world(const fm_stock *stock, const double ijk[3], double xyz[3]);
/* Inclusive index box of the active voxels; FM_ERR_INPUT if the grid is empty. */
fm_status fm_stock_active_bounds(const fm_stock *stock, int32_t lo[3], int32_t hi[3],
                                 fm_error *err);
/* Signed distance at a world point, trilinear, positive inside; clamped to
 * +-band far from the surface. */
double fm_stock_sample(const fm_stock *stock, const double p[3]);

/* ------------------------------------------------------ thin material -- */

/* Material thinner than a voxel, which the volume counts and the mesh cannot
 * show: a wall, fin or needle lying between rows of voxel centres. Found as
 * the voxel centres outside the stock with the surface within half a voxel
 * and no inside voxel among their 26 neighbours (no marching cube touching
 * them has an inside corner, so no face stands for that material); such
 * voxels, 26-connected, make a region. A region is a wall when it is a
 * sheet: its second-longest side at least 4 voxels and at least 4 voxels
 * per voxel of its longest side. The others are the tips of sharp edges
 * and needles, which every voxel model rounds off by under a voxel. */
#define FM_STOCK_THIN_MAX_REGIONS 16
#define FM_STOCK_THIN_MAX_VOXELS ((size_t)1 << 18)
typedef struct fm_stock_thin_region {
    double position[3];  /* the region's voxel centre nearest its centroid, mm */
    double lo[3], hi[3]; /* bounds of its voxel centres, mm */
    size_t voxels;
    int wall;            /* a sheet (above), not an edge or needle */
} fm_stock_thin_region;
typedef struct fm_stock_thin_report {
    size_t voxels;  /* all such voxels */
    size_t regions; /* regions among the first FM_STOCK_THIN_MAX_VOXELS voxels found */
    size_t walls;   /* of which walls */
    int truncated;  /* voxels > FM_STOCK_THIN_MAX_VOXELS: regions counts only those */
    size_t count;   /* regions listed in region[]: walls first, each kind most voxels first */
    fm_stock_thin_region region[FM_STOCK_THIN_MAX_REGIONS];
} fm_stock_thin_report;
fm_status fm_stock_thin_material(const fm_stock *stock, fm_stock_thin_report *report, fm_error *err);

/* ------------------------------------------------------------ queries -- */

/* A region of the grid as fm_stock_visit meets it: an 8^3 leaf with its
 * voxel values, or a tile, a uniform block beyond the band. Values are the
 * grid's own (F-rep sign: positive inside, mm), clamped to +-band. */
typedef struct fm_stock_region {
    int32_t lo[3], hi[3];  /* inclusive index box of the region */
    /* leaf: 512 values, voxel lo + (x, y, z) at 64 x + 8 y + z (valid
     * during the callback only); NULL for a tile */
    const float *values;
    float value;           /* tile: +band (inside the stock) or -band (outside) */
} fm_stock_region;

/* Walk the regions that meet the index box [lo, hi] (inclusive), in
 * aligned blocks from 4096^3 down to 8^3 voxels: a block that is one tile
 * goes to visit whole (not clipped); before a block holding leaves is
 * opened, prune(user, block_lo, block_hi) (may be NULL) is asked and skips
 * it when non-zero; visit gets each leaf met and stops the walk when it
 * returns non-zero. Costs the blocks opened, not the grid: no accessor per
 * voxel. Read-only; do not cut the stock during the walk. */
fm_status fm_stock_visit(const fm_stock *stock, const int32_t lo[3], const int32_t hi[3],
                         int (*prune)(void *user, const int32_t lo[3], const int32_t hi[3]),
                         int (*visit)(void *user, const fm_stock_region *region), void *user,
                         fm_error *err);

/* A grid whose surface is the zero set of a field that need not be a
 * distance (a HyperFun model with any gradient, positive inside): the field
 * is rasterized like fm_stock_new_from_field, its zero set meshed and the
 * band rebuilt from that mesh, so that values near the surface are true
 * distances in millimetres whatever the field's scale. */
fm_stock *fm_stock_new_from_zero_set(const fm_field *field, const fm_stock_options *opt,
                                     fm_error *err);

/* -------------------------------------------------- design comparison -- */
/* The design part (the intended result of the program) as a level set on
 * the stock's transform: the same voxel size and voxel centres, so that the
 * two grids compare voxel by voxel. Deviation is measured on the stock's
 * surface: gouge where design material was removed (the surface lies
 * inside the design), excess where material outside the design remains
 * (docs/stock.md, "Design comparison"). */
typedef struct fm_design fm_design;

typedef struct fm_design_options {
    double tolerance_mm;  /* deviations up to this count as on the design; 0: half a voxel */
    size_t memory_budget; /* bytes the design grid may use; 0: the stock's budget */
    int threads;          /* 0: the stock's */
} fm_design_options;
void fm_design_options_default(fm_design_options *opt);

/* The design from a closed STL mesh (OpenVDB's mesh-to-volume), from an
 * F-rep field (a HyperFun model, rasterized like a field stock: the
 * comparison evaluates the field where it reads it, and the grid is made
 * only for fm_design_sample*; the design takes the field over, keeps a copy
 * of *field and calls field->release(field->ctx), when set, once it is
 * freed or fails, so ctx must live until then), or from a
 * frepmill snapshot (fm_stock_save: an earlier simulation's result), which
 * is rebuilt onto the stock's transform when its voxel, origin or band
 * differ. opt may be NULL. NULL and err on failure: FM_ERR_INPUT bad
 * files or options (a tolerance over 30 voxels), FM_ERR_LIMIT a budget,
 * FM_ERR_IO files. */
fm_design *fm_design_from_stl(const fm_stock *stock, const char *path,
                              const fm_design_options *opt, fm_error *err);
fm_design *fm_design_from_field(const fm_stock *stock, const fm_field *field,
                                const fm_design_options *opt, fm_error *err);
fm_design *fm_design_load_vdb(const fm_stock *stock, const char *path,
                              const fm_design_options *opt, fm_error *err);
void fm_design_free(fm_design *design);
/* The band half-width (voxels) a design for this stock and tolerance gets:
 * the stock's band, or ceil(tolerance / voxel) + 2 when that is more (0:
 * half a voxel). A field given to fm_design_from_field only needs to tell the
 * voxels within it from the rest. */
int fm_design_band_voxels(const fm_stock *stock, double tolerance_mm);
double fm_design_tolerance(const fm_design *design);
size_t fm_design_memory_bytes(const fm_design *design);
/* Signed distance to the design's surface at a world point (mm), positive
 * inside the design: trilinear within the design's band, beyond it from the
 * design's surface points (exact for a plane face; next to the design's
 * edges and corners an upper bound off by up to about half a voxel). At a point of the stock's surface: > 0 is a gouge that
 * deep, < 0 excess that thick. fm_design_sample_points does it for n points
 * (xyz: 3 floats each, a mesh's positions) at once, reading the surface
 * points around those that need them once; FM_ERR_LIMIT when they exceed
 * the design's memory budget (fm_design_sample then returns the sample
 * clamped to the band). */
double fm_design_sample(const fm_design *design, const double p[3]);
fm_status fm_design_sample_points(const fm_design *design, const float *xyz, size_t n,
                                  double *out, fm_error *err);

/* A connected region (26-neighbours) of voxels where the stock deviates
 * from the design by more than the tolerance. */
typedef struct fm_deviation_region {
    double depth_mm;     /* largest deviation of the stock's surface there (within half a voxel) */
    double position[3];  /* where: the point of the stock's surface, mm */
    double volume_mm3;   /* design material removed (gouge) or stock outside the design (excess) */
    double lo[3], hi[3]; /* bounds of the region's voxel centres, mm */
    size_t voxels;       /* voxels (tiles counted voxel by voxel) */
} fm_deviation_region;

typedef struct fm_deviation {
    double tolerance_mm;
    double max_gouge_mm, max_excess_mm; /* over the whole stock surface; 0 when none */
    /* Every bit of design material removed and of stock outside the design,
     * within the tolerance included, with the smooth-Heaviside voxel measure
     * of the removed volume (fm_stock_volume). */
    double gouge_volume_mm3, excess_volume_mm3;
    size_t gouge_total, excess_total;   /* regions found */
    fm_deviation_region *gouges;        /* deepest first, at most max_regions */
    size_t gouge_count;
    fm_deviation_region *excess;        /* deepest first, at most max_regions */
    size_t excess_count;
} fm_deviation;

/* Compare the stock with the design; out is filled (release it with
 * fm_deviation_free, also after an error). Costs one pass over both grids'
 * leaves plus work proportional to the deviating regions. */
fm_status fm_stock_compare_design(const fm_stock *stock, const fm_design *design,
                                  size_t max_regions, fm_deviation *out, fm_error *err);
void fm_deviation_free(fm_deviation *deviation);

/* ---------------------------------------------------------- snapshots -- */

/* Write a snapshot crash-safe: temporary file in the same folder, fsync,
 * the existing file kept as "<path>.prev", rename, fsync of the folder. Any
 * failure, fsync included, means not saved (FM_ERR_IO) and leaves the
 * previous files as they were. resume is an opaque string stored with the
 * snapshot (job id, next block...); may be NULL. */
fm_status fm_stock_save(const fm_stock *stock, const char *path, const char *resume,
                        fm_error *err);
/* The resume string of a loaded snapshot ("" otherwise). */
const char *fm_stock_resume_string(const fm_stock *stock);
/* Remove temporary files left in dir by snapshot writers that no longer
 * run. *removed (may be NULL) gets the count. Call at start. */
fm_status fm_stock_snapshot_cleanup(const char *dir, size_t *removed, fm_error *err);

#endif
