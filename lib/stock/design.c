/* design.c: the design part for the design comparison (stock.h): a level
 * set built on the stock's own transform (voxel size and voxel centres)
 * from an STL mesh, an F-rep field or a frepmill snapshot, with a band wide
 * enough to tell deviations beyond the tolerance (a field's: the field and
 * its grid's topology, the values evaluated where they are read); and the
 * C side of the comparison, whose grid work is in vdb_design.cpp. */
#include "stock/design_private.h"
#include "stock/stock_impl.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Tolerances above this many voxels would need bands the budget formula
 * was not made for; a coarser voxel measures them as well. */
#define DESIGN_MAX_TOLERANCE_VOXELS 30

/* A field's design keeps the field and, in vdb, only the topology of its
 * grid (inside tiles and marks where the rasterizer would make leaves): the
 * comparison evaluates the field at the marked cells it reads, so that the
 * leaves are never stored (docs/stock.md, "A field's design without a
 * grid"). Readers that need the grid itself (the distances beyond the band
 * of fm_design_sample*, the depth of a region deeper than the band) get it
 * made once, on first use: full. */
struct fm_design {
    fm_vdb *vdb;
    double tolerance;
    int threads;
    size_t budget;
    int has_field;
    fm_field field;
    pthread_mutex_t full_lock;
    fm_vdb *full;
};

void fm_design_options_default(fm_design_options *opt)
{
    memset(opt, 0, sizeof *opt);
}

/* Resolve opt against the stock, and the grid options the design is built
 * with: the stock's voxel and band widened so that a deviation of the
 * tolerance is read from unclamped values (docs/stock.md). */
static fm_status design_setup(const fm_stock *stock, const fm_design_options *opt_in,
                              fm_design_options *opt, fm_stock_options *grid, double origin[3],
                              fm_error *err)
{
    if (!stock) return fm_error_set(err, FM_ERR_INPUT, "no stock to compare the design with");
    if (opt_in)
        *opt = *opt_in;
    else
        fm_design_options_default(opt);
    const double h = fm_vdb_voxel(stock->vdb);
    if (opt->tolerance_mm == 0) opt->tolerance_mm = 0.5 * h;
    if (!(opt->tolerance_mm > 0) || !isfinite(opt->tolerance_mm))
        return fm_error_set(err, FM_ERR_INPUT, "design tolerance %g mm: expected a positive number",
                            opt->tolerance_mm);
    if (opt->tolerance_mm > DESIGN_MAX_TOLERANCE_VOXELS * h)
        return fm_error_set(err, FM_ERR_INPUT,
                            "design tolerance %g mm is more than %d voxels of %g mm; use a "
                            "coarser voxel",
                            opt->tolerance_mm, DESIGN_MAX_TOLERANCE_VOXELS, h);
    if (opt->memory_budget == 0) opt->memory_budget = stock->opt.memory_budget;
    if (opt->threads == 0) opt->threads = stock->opt.threads;
    fm_stock_options_default(grid);
    grid->voxel_mm = h;
    grid->band_voxels = fm_design_band_voxels(stock, opt->tolerance_mm);
    grid->memory_budget = opt->memory_budget;
    grid->threads = opt->threads;
    fm_vdb_origin(stock->vdb, origin);
    return FM_OK;
}

int fm_design_band_voxels(const fm_stock *stock, double tolerance_mm)
{
    const double h = fm_vdb_voxel(stock->vdb);
    if (tolerance_mm == 0) tolerance_mm = 0.5 * h;
    /* the stock's band, or wider when the tolerance needs it: a deviation
     * of the tolerance must read unclamped samples, and the trilinear
     * sample at a surface point reads the 8 corners of its cell, up to
     * sqrt(3) voxels away. Deeper deviations are measured from the design's
     * surface points (the comparison's depths, fm_design_sample) */
    int band = fm_vdb_band(stock->vdb);
    const double need = ceil(tolerance_mm / h) + 2;
    if (need > band) band = need < 64 ? (int)need : 64;
    return band;
}

static fm_design *design_wrap(fm_vdb *v, const fm_design_options *opt, fm_error *err)
{
    fm_design *d = calloc(1, sizeof *d);
    if (!d) {
        fm_vdb_free(v);
        fm_error_set(err, FM_ERR_LIMIT, "out of memory for the design");
        return NULL;
    }
    d->vdb = v;
    d->tolerance = opt->tolerance_mm;
    d->threads = opt->threads;
    d->budget = opt->memory_budget;
    pthread_mutex_init(&d->full_lock, NULL);
    return d;
}

/* The grid with values: the design's own, or a field design's made on
 * first use (under the lock: readers may be threads of their own). */
static const fm_vdb *design_full(const fm_design *dc, fm_error *err)
{
    if (!dc->has_field) return dc->vdb;
    fm_design *d = (fm_design *)dc; /* the cache only */
    pthread_mutex_lock(&d->full_lock);
    if (!d->full) {
        double origin[3];
        fm_vdb_origin(d->vdb, origin);
        fm_vdb *v = fm_vdb_new(fm_vdb_voxel(d->vdb), fm_vdb_band(d->vdb), origin, d->threads, err);
        if (v && fm_vdb_rasterize(v, &d->field, d->budget, err) != FM_OK) {
            fm_vdb_free(v);
            v = NULL;
        }
        d->full = v;
    }
    const fm_vdb *v = d->full;
    pthread_mutex_unlock(&d->full_lock);
    return v;
}

static const fm_vdb *full_for_compare(void *user, fm_error *err)
{
    return design_full(user, err);
}

fm_design *fm_design_from_stl(const fm_stock *stock, const char *path,
                              const fm_design_options *opt_in, fm_error *err)
{
    fm_design_options opt;
    fm_stock_options grid;
    double origin[3];
    if (design_setup(stock, opt_in, &opt, &grid, origin, err)) return NULL;
    fm_vdb *v = fm_stl_to_vdb(path, &grid, origin, "design", err);
    return v ? design_wrap(v, &opt, err) : NULL;
}

fm_design *fm_design_from_field(const fm_stock *stock, const fm_field *field,
                                const fm_design_options *opt_in, fm_error *err)
{
    fm_design_options opt;
    fm_stock_options grid;
    double origin[3];
    if (design_setup(stock, opt_in, &opt, &grid, origin, err)) return NULL;
    if (!field) {
        fm_error_set(err, FM_ERR_INPUT, "no field given for the design");
        return NULL;
    }
    fm_vdb *v = fm_vdb_new(grid.voxel_mm, grid.band_voxels, origin, grid.threads, err);
    fm_design *d = NULL;
    if (v && fm_vdb_rasterize_topology(v, field, grid.memory_budget, err) == FM_OK) {
        d = design_wrap(v, &opt, err);
        v = NULL;
    }
    fm_vdb_free(v);
    if (!d) {
        if (field->release) field->release(field->ctx);
        return NULL;
    }
    d->has_field = 1;
    d->field = *field;
    return d;
}

fm_design *fm_design_load_vdb(const fm_stock *stock, const char *path,
                              const fm_design_options *opt_in, fm_error *err)
{
    fm_design_options opt;
    fm_stock_options grid;
    double origin[3];
    if (design_setup(stock, opt_in, &opt, &grid, origin, err)) return NULL;
    fm_stock *snap = fm_stock_load_vdb(path, &grid, err);
    if (!snap) return NULL;
    double snap_origin[3];
    fm_vdb_origin(snap->vdb, snap_origin);
    /* a wider band than needed serves as well; a narrower one (a job's own
     * snapshot has the stock's band) is widened in place, not rebuilt
     * through a mesh (79 s of CPU on 3D_Chips at 0.1 mm, bench/design) */
    int same = fm_vdb_voxel(snap->vdb) == grid.voxel_mm;
    for (int k = 0; k < 3; k++) same = same && snap_origin[k] == origin[k];
    if (same && fm_vdb_band(snap->vdb) < grid.band_voxels &&
        fm_vdb_widen_band(snap->vdb, grid.band_voxels, grid.memory_budget, err) != FM_OK) {
        fm_stock_free(snap);
        return NULL;
    }
    fm_vdb *v = NULL;
    if (same) {
        /* take the grid over as it is */
        v = snap->vdb;
        snap->vdb = fm_vdb_new(grid.voxel_mm, grid.band_voxels, origin, 1, err);
        if (!snap->vdb) {
            snap->vdb = v;
            v = NULL;
        }
    } else {
        v = fm_vdb_new(grid.voxel_mm, grid.band_voxels, origin, grid.threads, err);
        if (v && fm_vdb_rebuild_onto(v, snap->vdb, grid.memory_budget, err)) {
            fm_vdb_free(v);
            v = NULL;
        }
    }
    fm_stock_free(snap);
    return v ? design_wrap(v, &opt, err) : NULL;
}

void fm_design_free(fm_design *d)
{
    if (!d) return;
    fm_vdb_free(d->vdb);
    fm_vdb_free(d->full);
    if (d->has_field && d->field.release) d->field.release(d->field.ctx);
    pthread_mutex_destroy(&d->full_lock);
    free(d);
}

double fm_design_tolerance(const fm_design *d) { return d->tolerance; }

size_t fm_design_memory_bytes(const fm_design *dc)
{
    fm_design *d = (fm_design *)dc; /* the lock only */
    pthread_mutex_lock(&d->full_lock);
    const size_t full = d->full ? fm_vdb_memory(d->full) : 0;
    pthread_mutex_unlock(&d->full_lock);
    return fm_vdb_memory(d->vdb) + full;
}

double fm_design_sample(const fm_design *d, const double p[3])
{
    double v;
    fm_error err;
    const fm_vdb *g = design_full(d, &err);
    if (!g) {
        /* over budget: the field's own value, clamped to the band as the
         * grid would hold it (a lower bound of the distance beyond it) */
        void *w = d->field.worker_new ? d->field.worker_new(d->field.ctx) : NULL;
        double f = NAN;
        if (w || !d->field.worker_new) d->field.batch(d->field.ctx, w, 1, &p[0], &p[1], &p[2], &f);
        if (w && d->field.worker_free) d->field.worker_free(d->field.ctx, w);
        const double bg = fm_vdb_band(d->vdb) * fm_vdb_voxel(d->vdb);
        return f != f ? -bg : f < -bg ? -bg : f > bg ? bg : f;
    }
    if (fm_vdb_design_distance(g, p, &v, d->budget, &err) != FM_OK)
        v = fm_vdb_sample(g, p); /* the clamped sample: a lower bound */
    return -v;
}

fm_status fm_design_sample_points(const fm_design *d, const float *xyz, size_t n, double *out,
                                  fm_error *err)
{
    const fm_vdb *g = design_full(d, err);
    if (!g) return err ? err->code : FM_ERR_LIMIT;
    const fm_status st = fm_vdb_design_distances(g, xyz, n, out, d->budget, err);
    if (st != FM_OK) return st;
    for (size_t i = 0; i < n; i++) out[i] = -out[i];
    return FM_OK;
}

fm_status fm_stock_compare_design(const fm_stock *stock, const fm_design *design,
                                  size_t max_regions, fm_deviation *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    if (!stock || !design)
        return fm_error_set(err, FM_ERR_INPUT, "no stock or no design to compare");
    double a[3], b[3];
    fm_vdb_origin(stock->vdb, a);
    fm_vdb_origin(design->vdb, b);
    if (fm_vdb_voxel(stock->vdb) != fm_vdb_voxel(design->vdb) || a[0] != b[0] || a[1] != b[1] ||
        a[2] != b[2])
        return fm_error_set(err, FM_ERR_INPUT,
                            "the design was built for another stock (voxel %g mm against %g mm, "
                            "or another origin)",
                            fm_vdb_voxel(design->vdb), fm_vdb_voxel(stock->vdb));
    out->tolerance_mm = design->tolerance;
    fm_vdb_compare_options o = {design->tolerance, max_regions, design->budget, design->threads,
                                design->has_field ? &design->field : NULL,
                                full_for_compare, (void *)design};
    return fm_vdb_compare(stock->vdb, design->vdb, &o, out, err);
}

void fm_deviation_free(fm_deviation *d)
{
    if (!d) return;
    free(d->gouges);
    free(d->excess);
    d->gouges = d->excess = NULL;
    d->gouge_count = d->excess_count = 0;
}
