/* stock.c: the C side of lib/stock: options and the memory estimate, box and
 * cylinder stock as closed-form fields, the bookkeeping around each cut
 * (version, dirty chunks, removed volume per tool and per block) and the
 * measures and accessors of stock.h. The grid work is in the vdb_*.cpp files. */
#include "stock/stock_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MB (1024.0 * 1024.0)

void fm_stock_options_default(fm_stock_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->voxel_mm = 0.1;
    opt->band_voxels = 3;
    opt->memory_budget = (size_t)4 << 30;
    opt->threads = 0;
    opt->block_table_size = 4096;
}

fm_status fm_stock_options_resolve(const fm_stock_options *opt, fm_stock_options *out,
                                   fm_error *err)
{
    fm_stock_options d;
    fm_stock_options_default(&d);
    if (opt) {
        if (opt->voxel_mm != 0) d.voxel_mm = opt->voxel_mm;
        if (opt->band_voxels != 0) d.band_voxels = opt->band_voxels;
        if (opt->memory_budget != 0) d.memory_budget = opt->memory_budget;
        d.threads = opt->threads;
        if (opt->block_table_size != 0) d.block_table_size = opt->block_table_size;
    }
    if (!(d.voxel_mm >= 1e-4 && d.voxel_mm <= 100))
        return fm_error_set(err, FM_ERR_INPUT, "voxel size %g mm is outside 0.0001 .. 100 mm",
                            d.voxel_mm);
    if (d.band_voxels < 2 || d.band_voxels > 32)
        return fm_error_set(err, FM_ERR_INPUT, "band half-width %d voxels is outside 2 .. 32",
                            d.band_voxels);
    if (d.threads < 0 || d.threads > 4096)
        return fm_error_set(err, FM_ERR_INPUT, "thread count %d is outside 0 .. 4096",
                            d.threads);
    if (d.block_table_size > ((size_t)1 << 24))
        return fm_error_set(err, FM_ERR_INPUT, "block table of %zu entries is too large",
                            d.block_table_size);
    *out = d;
    return FM_OK;
}

size_t fm_stock_estimate_bytes(double projected_area_mm2, double voxel_mm, int band_voxels)
{
    /* A surface crosses about P / (8h)^2 leaf columns; a band 2w voxels
     * thick lands in (2w + 7) / 8 leaves per column on average over its
     * position in the leaf. Same for the 128^3 internal nodes. */
    const double h = voxel_mm, t = 2.0 * band_voxels;
    const double leaves = projected_area_mm2 / ((8 * h) * (8 * h)) * (t + 7) / 8;
    const double nodes = projected_area_mm2 / ((128 * h) * (128 * h)) * (t + 127) / 128 + 1;
    const double bytes = leaves * (double)fm_vdb_leaf_bytes() +
                         nodes * (double)fm_vdb_internal1_bytes() + 65536.0;
    return bytes >= (double)SIZE_MAX ? SIZE_MAX : (size_t)bytes;
}

static fm_status check_estimate(const fm_stock_options *opt, double projected_area,
                                const char *what, fm_error *err)
{
    const size_t need = fm_stock_estimate_bytes(projected_area, opt->voxel_mm, opt->band_voxels);
    if (need > opt->memory_budget)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "%s would need about %.0f MB (projected surface %.0f mm^2 at "
                            "%g mm voxels, band %d) but the memory budget is %.0f MB",
                            what, (double)need / MB, projected_area, opt->voxel_mm,
                            opt->band_voxels, (double)opt->memory_budget / MB);
    return FM_OK;
}

/* ------------------------------------------------------ closed forms -- */

typedef struct shape_ctx {
    int kind; /* 0 box, 1 cylinder */
    double a[3], b[3]; /* box: centre, half sizes; cylinder: x, y, r / z0, z1 */
} shape_ctx;

/* max and min of finite values (or -inf) without libm's calls: fmax and
 * fmin are not inlined without -ffinite-math-only, and this runs for every
 * voxel of a new stock's boundary leaves (a quarter of the set-up of a job
 * on a 0.1 mm box). */
static inline double max2(double a, double b) { return a > b ? a : b; }
static inline double min2(double a, double b) { return a < b ? a : b; }

/* Exact signed distance, positive inside. */
static double shape_value(const shape_ctx *c, double x, double y, double z)
{
    double dx, dy, dz;
    if (c->kind == 0) {
        dx = fabs(x - c->a[0]) - c->b[0];
        dy = fabs(y - c->a[1]) - c->b[1];
        dz = fabs(z - c->a[2]) - c->b[2];
    } else {
        dx = hypot(x - c->a[0], y - c->a[1]) - c->a[2];
        dy = -INFINITY;
        dz = max2(c->b[0] - z, z - c->b[1]);
    }
    const double ox = max2(dx, 0), oy = max2(dy, 0), oz = max2(dz, 0);
    const double outside = sqrt(ox * ox + oy * oy + oz * oz);
    const double inside = min2(max2(dx, max2(dy, dz)), 0);
    return -(outside + inside);
}

static void shape_batch(void *ctx, void *worker, size_t n, const double *x, const double *y,
                        const double *z, double *out)
{
    (void)worker;
    for (size_t i = 0; i < n; i++) out[i] = shape_value(ctx, x[i], y[i], z[i]);
}

/* The distance is 1-Lipschitz: the centre value +- the half diagonal. */
static fm_interval shape_interval(void *ctx, void *worker, const fm_interval box[3])
{
    (void)worker;
    double c[3], r2 = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (box[k].lo + box[k].hi);
        const double h = 0.5 * (box[k].hi - box[k].lo);
        r2 += h * h;
    }
    const double v = shape_value(ctx, c[0], c[1], c[2]), r = sqrt(r2);
    fm_interval out = {v - r, v + r};
    return out;
}

static fm_stock *new_from_shape(const shape_ctx *shape, const double lo[3], const double hi[3],
                                double projected_area, const char *what,
                                const fm_stock_options *opt_in, fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    if (check_estimate(&opt, projected_area, what, err)) return NULL;
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = (void *)shape;
    memcpy(f.lo, lo, sizeof f.lo);
    memcpy(f.hi, hi, sizeof f.hi);
    f.batch = shape_batch;
    f.interval = shape_interval;
    /* Voxel centres at lo - 3.5 h + k h: the low faces then sit in the
     * middle of a leaf, so their band fills one layer of leaves, not two. */
    double origin[3];
    for (int k = 0; k < 3; k++) origin[k] = lo[k] - 3.5 * opt.voxel_mm;
    fm_vdb *v = fm_vdb_new(opt.voxel_mm, opt.band_voxels, origin, opt.threads, err);
    if (!v) return NULL;
    if (fm_vdb_rasterize(v, &f, opt.memory_budget, err)) {
        fm_vdb_free(v);
        return NULL;
    }
    return fm_stock_wrap(v, &opt, err);
}

fm_stock *fm_stock_new_box(const double lo[3], const double hi[3], const fm_stock_options *opt,
                           fm_error *err)
{
    shape_ctx c;
    memset(&c, 0, sizeof c);
    for (int k = 0; k < 3; k++) {
        if (!isfinite(lo[k]) || !isfinite(hi[k]) || !(hi[k] > lo[k])) {
            fm_error_set(err, FM_ERR_INPUT,
                         "box stock needs finite corners with lo < hi (axis %c: %g .. %g)",
                         "XYZ"[k], lo[k], hi[k]);
            return NULL;
        }
        c.a[k] = 0.5 * (lo[k] + hi[k]);
        c.b[k] = 0.5 * (hi[k] - lo[k]);
    }
    const double sx = hi[0] - lo[0], sy = hi[1] - lo[1], sz = hi[2] - lo[2];
    const double area = 2 * (sx * sy + sy * sz + sz * sx);
    return new_from_shape(&c, lo, hi, area, "the box stock", opt, err);
}

fm_stock *fm_stock_new_cylinder(double x, double y, double z0, double z1, double r,
                                const fm_stock_options *opt, fm_error *err)
{
    if (!isfinite(x) || !isfinite(y) || !isfinite(z0) || !isfinite(z1) || !isfinite(r) ||
        !(r > 0) || !(z1 > z0)) {
        fm_error_set(err, FM_ERR_INPUT,
                     "cylinder stock needs a finite radius > 0 and z0 < z1 (r %g, z %g .. %g)",
                     r, z0, z1);
        return NULL;
    }
    shape_ctx c;
    memset(&c, 0, sizeof c);
    c.kind = 1;
    c.a[0] = x;
    c.a[1] = y;
    c.a[2] = r;
    c.b[0] = z0;
    c.b[1] = z1;
    const double lo[3] = {x - r, y - r, z0}, hi[3] = {x + r, y + r, z1};
    /* caps 2 pi r^2; the side projects to 4 r (z1 - z0) on each of the
     * XZ and YZ planes */
    const double area = 2 * FM_PI * r * r + 8 * r * (z1 - z0);
    return new_from_shape(&c, lo, hi, area, "the cylinder stock", opt, err);
}

fm_stock *fm_stock_new_from_field(const fm_field *field, const fm_stock_options *opt_in,
                                  fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    if (!field) {
        fm_error_set(err, FM_ERR_INPUT, "no field given for the stock");
        return NULL;
    }
    const double origin[3] = {0, 0, 0};
    fm_vdb *v = fm_vdb_new(opt.voxel_mm, opt.band_voxels, origin, opt.threads, err);
    if (!v) return NULL;
    if (fm_vdb_rasterize(v, field, opt.memory_budget, err)) {
        fm_vdb_free(v);
        return NULL;
    }
    return fm_stock_wrap(v, &opt, err);
}

fm_stock *fm_stock_new_from_zero_set(const fm_field *field, const fm_stock_options *opt_in,
                                     fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    if (!field) {
        fm_error_set(err, FM_ERR_INPUT, "no field given");
        return NULL;
    }
    const double origin[3] = {0, 0, 0};
    fm_vdb *raw = fm_vdb_new(opt.voxel_mm, opt.band_voxels, origin, opt.threads, err);
    if (!raw) return NULL;
    float *points = NULL;
    uint32_t *tris = NULL;
    size_t npoints = 0, ntris = 0;
    fm_vdb *v = NULL;
    if (fm_vdb_rasterize(raw, field, opt.memory_budget, err) == FM_OK &&
        fm_vdb_zero_set_mesh(raw, &points, &npoints, &tris, &ntris, err) == FM_OK) {
        v = fm_vdb_new(opt.voxel_mm, opt.band_voxels, origin, opt.threads, err);
        if (v && fm_vdb_from_mesh(v, points, npoints, tris, ntris, err) != FM_OK) {
            fm_vdb_free(v);
            v = NULL;
        }
    }
    free(points);
    free(tris);
    fm_vdb_free(raw);
    if (!v) return NULL;
    if (fm_vdb_memory(v) > opt.memory_budget) {
        fm_error_set(err, FM_ERR_LIMIT, "the grid needs %.0f MB but the memory budget is %.0f MB",
                     (double)fm_vdb_memory(v) / MB, (double)opt.memory_budget / MB);
        fm_vdb_free(v);
        return NULL;
    }
    return fm_stock_wrap(v, &opt, err);
}

/* ------------------------------------------------------------ tables -- */

static uint64_t chunk_hash(const int32_t k[3]) { return fm_stock_hash3(k); }

static fm_status chunk_grow(fm_stock *s)
{
    size_t cap = s->cap_chunks ? s->cap_chunks * 2 : 1024;
    fm_stock_chunk_slot *t = calloc(cap, sizeof *t);
    if (!t) return FM_ERR_LIMIT;
    for (size_t i = 0; i < s->cap_chunks; i++) {
        if (!s->chunks[i].used) continue;
        size_t j = chunk_hash(s->chunks[i].key) & (cap - 1);
        while (t[j].used) j = (j + 1) & (cap - 1);
        t[j] = s->chunks[i];
    }
    free(s->chunks);
    s->chunks = t;
    s->cap_chunks = cap;
    return FM_OK;
}

static fm_status chunk_set(fm_stock *s, const int32_t key[3], uint64_t version)
{
    if ((s->nchunks + 1) * 2 > s->cap_chunks && chunk_grow(s)) return FM_ERR_LIMIT;
    size_t j = chunk_hash(key) & (s->cap_chunks - 1);
    while (s->chunks[j].used) {
        fm_stock_chunk_slot *c = &s->chunks[j];
        if (c->key[0] == key[0] && c->key[1] == key[1] && c->key[2] == key[2]) {
            c->version = version;
            return FM_OK;
        }
        j = (j + 1) & (s->cap_chunks - 1);
    }
    s->chunks[j].used = 1;
    memcpy(s->chunks[j].key, key, sizeof s->chunks[j].key);
    s->chunks[j].version = version;
    s->nchunks++;
    return FM_OK;
}

static int32_t floor_div64(int32_t v) { return v >= 0 ? v / 64 : -((-(int64_t)v + 63) / 64); }

fm_status fm_stock_mark_box(fm_stock *s, const int32_t lo[3], const int32_t hi[3],
                            uint64_t version)
{
    int32_t a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = floor_div64(lo[k]);
        b[k] = floor_div64(hi[k]);
    }
    int32_t key[3];
    for (key[0] = a[0]; key[0] <= b[0]; key[0]++)
        for (key[1] = a[1]; key[1] <= b[1]; key[1]++)
            for (key[2] = a[2]; key[2] <= b[2]; key[2]++)
                if (chunk_set(s, key, version)) return FM_ERR_LIMIT;
    return FM_OK;
}

fm_status fm_stock_add_tool(fm_stock *s, int tool, double removed)
{
    size_t lo = 0, hi = s->ntools;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (s->tools[mid].tool < tool)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < s->ntools && s->tools[lo].tool == tool) {
        s->tools[lo].removed_mm3 += removed;
        return FM_OK;
    }
    if (s->ntools >= FM_STOCK_MAX_TOOLS) return FM_ERR_LIMIT;
    if (s->ntools == s->cap_tools) {
        size_t cap = s->cap_tools ? s->cap_tools * 2 : 16;
        fm_stock_tool_volume *t = realloc(s->tools, cap * sizeof *t);
        if (!t) return FM_ERR_LIMIT;
        s->tools = t;
        s->cap_tools = cap;
    }
    memmove(s->tools + lo + 1, s->tools + lo, (s->ntools - lo) * sizeof *s->tools);
    s->tools[lo].tool = tool;
    s->tools[lo].removed_mm3 = removed;
    s->ntools++;
    return FM_OK;
}

static int tool_known(const fm_stock *s, int tool)
{
    for (size_t i = 0; i < s->ntools; i++)
        if (s->tools[i].tool == tool) return 1;
    return 0;
}

static size_t block_slot_of(const fm_stock *s, int64_t block)
{
    return fm_stock_hash_mix((uint64_t)block) & (s->block_index_size - 1);
}

/* Index slot holding block, or the empty slot where it would go. */
static size_t block_find(const fm_stock *s, int64_t block)
{
    size_t j = block_slot_of(s, block);
    while (s->block_index[j] && s->blocks[s->block_index[j] - 1].block != block)
        j = (j + 1) & (s->block_index_size - 1);
    return j;
}

/* Linear-probing delete with backward shift, so no tombstones pile up. */
static void block_unindex(fm_stock *s, size_t j)
{
    const size_t mask = s->block_index_size - 1;
    s->block_index[j] = 0;
    size_t i = (j + 1) & mask;
    while (s->block_index[i]) {
        const size_t home = block_slot_of(s, s->blocks[s->block_index[i] - 1].block);
        /* move entry i back to j if j lies cyclically in [home, i) */
        if (((i - home) & mask) >= ((i - j) & mask)) {
            s->block_index[j] = s->block_index[i];
            s->block_index[i] = 0;
            j = i;
        }
        i = (i + 1) & mask;
    }
}

void fm_stock_add_block(fm_stock *s, int64_t block, double removed, double t0, double t1)
{
    if (block < 0 || s->opt.block_table_size == 0 || !s->block_index) return;
    size_t j = block_find(s, block);
    if (s->block_index[j]) {
        fm_stock_block *b = &s->blocks[s->block_index[j] - 1];
        b->removed_mm3 += removed;
        if (t0 < b->t0) b->t0 = t0;
        if (t1 > b->t1) b->t1 = t1;
        return;
    }
    size_t e;
    if (s->nblocks < s->opt.block_table_size) {
        e = s->nblocks++;
    } else {
        /* Full: the current block always gets in, in place of the one that
         * removed least, so the table keeps the largest removals. */
        e = 0;
        for (size_t i = 1; i < s->nblocks; i++)
            if (s->blocks[i].removed_mm3 < s->blocks[e].removed_mm3) e = i;
        block_unindex(s, block_find(s, s->blocks[e].block));
        j = block_find(s, block);
    }
    s->blocks[e].block = block;
    s->blocks[e].removed_mm3 = removed;
    s->blocks[e].t0 = t0;
    s->blocks[e].t1 = t1;
    s->block_index[j] = (uint32_t)(e + 1);
}

/* --------------------------------------------------------- lifecycle -- */

static void mark_leaf(void *user, const int32_t lo[3], const int32_t hi[3])
{
    fm_stock *s = user;
    if (fm_stock_mark_box(s, lo, hi, s->version)) s->version = 0; /* flags failure */
}

fm_stock *fm_stock_wrap(fm_vdb *vdb, const fm_stock_options *opt, fm_error *err)
{
    fm_stock *s = calloc(1, sizeof *s);
    if (!s) goto oom;
    s->vdb = vdb;
    s->opt = *opt;
    /* the grid's own voxel and band win (a snapshot or mesh sets them) */
    s->opt.voxel_mm = fm_vdb_voxel(vdb);
    s->opt.band_voxels = fm_vdb_band(vdb);
    if (opt->block_table_size) {
        size_t n = 16;
        while (n < 2 * opt->block_table_size) n *= 2;
        s->blocks = calloc(opt->block_table_size, sizeof *s->blocks);
        s->block_index = calloc(n, sizeof *s->block_index);
        if (!s->blocks || !s->block_index) goto oom;
        s->block_index_size = n;
    }
    s->resume = calloc(1, 1);
    if (!s->resume) goto oom;
    s->version = 1;
    fm_vdb_for_each_leaf(vdb, mark_leaf, s);
    if (s->version == 0) goto oom;
    s->initial_volume = fm_vdb_volume(vdb);
    return s;
oom:
    fm_error_set(err, FM_ERR_LIMIT, "out of memory setting up the stock tables");
    if (s)
        fm_stock_free(s);
    else
        fm_vdb_free(vdb);
    return NULL;
}

void fm_stock_free(fm_stock *s)
{
    if (!s) return;
    fm_vdb_free(s->vdb);
    free(s->tools);
    free(s->blocks);
    free(s->block_index);
    free(s->chunks);
    fm_tool_marks_free(&s->marks);
    free(s->resume);
    free(s);
}

/* ------------------------------------------------------------ cutting -- */

typedef struct touch_ctx {
    fm_stock *stock;
    uint64_t version;
    int slot; /* the cutting tool's mark slot */
    int touched;
    int failed;       /* the dirty-chunk table ran out of memory */
    int marks_failed; /* the tool marks did */
} touch_ctx;

/* A chunk's mesh reads values this many voxels outside the chunk (faces
 * one, their normals two: lib/mesh), so a change that near a chunk's faces
 * changes the chunk's mesh too. */
#define MESH_READS_VOXELS 2

static void touch_box(void *user, const int32_t lo[3], const int32_t hi[3])
{
    touch_ctx *t = user;
    t->touched = 1;
    /* the chunks whose mesh reads the box: its own and the neighbours
     * within reach (grid coordinates stay far inside int32, rasterize) */
    int32_t a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = lo[k] - MESH_READS_VOXELS;
        b[k] = hi[k] + MESH_READS_VOXELS;
    }
    if (fm_stock_mark_box(t->stock, a, b, t->version)) t->failed = 1;
}

static void leaf_set(void *user, const int32_t lo[3], const uint64_t set[8])
{
    touch_ctx *t = user;
    if (t->slot < 0 || fm_tool_marks_set(&t->stock->marks, lo, set, t->slot))
        t->marks_failed = 1;
}

static void cleared(void *user, const int32_t lo[3], const int32_t hi[3])
{
    touch_ctx *t = user;
    fm_tool_marks_clear(&t->stock->marks, lo, hi);
}

fm_status fm_stock_subtract(fm_stock *s, const fm_field *swept, const fm_stock_cut *cut,
                            fm_stock_cut_stats *stats, fm_error *err)
{
    if (!s || !swept) return fm_error_set(err, FM_ERR_INPUT, "no stock or no swept volume");
    fm_stock_cut c = {0, -1, 0, 0};
    if (cut) c = *cut;
    if (!tool_known(s, c.tool) && s->ntools >= FM_STOCK_MAX_TOOLS)
        return fm_error_set(err, FM_ERR_LIMIT, "more than %d distinct tool numbers",
                            FM_STOCK_MAX_TOOLS);
    /* zeroed: a field that misses the stock returns before any figure is set */
    fm_stock_cut_stats st = {0};
    touch_ctx t = {s, s->version + 1, fm_tool_marks_slot(&s->marks, c.tool), 0, 0, 0};
    const fm_vdb_cut_events ev = {&t, touch_box, leaf_set, cleared};
    /* the tool marks live beside the grid and share its budget */
    const size_t marks = fm_tool_marks_bytes(&s->marks);
    const size_t budget = s->opt.memory_budget > marks ? s->opt.memory_budget - marks : 0;
    fm_status rc = fm_vdb_subtract(s->vdb, swept, budget, &ev, &st, err);
    if (rc) return rc;
    if (t.touched) s->version = t.version;
    s->removed_total += st.removed_mm3;
    fm_stock_add_tool(s, c.tool, st.removed_mm3); /* room checked above */
    fm_stock_add_block(s, c.block, st.removed_mm3, c.t0, c.t1);
    if (stats) *stats = st;
    if (t.failed || t.marks_failed)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "the cut was made but the %s table ran out of memory",
                            t.failed ? "dirty-chunk" : "tool-mark");
    return FM_OK;
}

double fm_stock_time_bare_update(fm_stock *s, size_t *voxels)
{
    size_t n = s->marks.nleaves, count = 0;
    int32_t(*origins)[3] = n ? malloc(n * sizeof *origins) : NULL;
    uint64_t(*sets)[8] = n ? malloc(n * sizeof *sets) : NULL;
    double t = 0;
    if (origins && sets) {
        for (size_t i = 0; i < n; i++) {
            memcpy(origins[i], s->marks.leaves[i].origin, sizeof origins[i]);
            memcpy(sets[i], s->marks.leaves[i].set, sizeof sets[i]);
        }
        t = fm_vdb_time_bare_update(s->vdb, (const int32_t(*)[3])origins, (const uint64_t(*)[8])sets, n,
                                    &count);
    }
    free(origins);
    free(sets);
    if (voxels) *voxels = count;
    return t;
}

int fm_stock_voxel_tool(const fm_stock *s, const int32_t ijk[3], int *tool)
{
    return fm_tool_marks_get(&s->marks, ijk, tool);
}

int fm_stock_point_tool(const fm_stock *s, const double p[3], int *tool)
{
    double origin[3];
    const double zero[3] = {0, 0, 0};
    fm_stock_index_to_world(s, zero, origin);
    const double voxel = fm_vdb_voxel(s->vdb);
    int32_t ijk[3];
    for (int k = 0; k < 3; k++) {
        const double i = floor((p[k] - origin[k]) / voxel + 0.5);
        if (!(i > -2147483648.0 && i < 2147483647.0)) return 0;
        ijk[k] = (int32_t)i;
    }
    return fm_tool_marks_get(&s->marks, ijk, tool);
}

/* ----------------------------------------------------------- measures -- */

double fm_stock_volume(const fm_stock *s) { return fm_vdb_volume(s->vdb); }
double fm_stock_initial_volume(const fm_stock *s) { return s->initial_volume; }
double fm_stock_removed_volume(const fm_stock *s) { return s->removed_total; }

double fm_stock_removed_volume_tool(const fm_stock *s, int tool)
{
    for (size_t i = 0; i < s->ntools; i++)
        if (s->tools[i].tool == tool) return s->tools[i].removed_mm3;
    return 0;
}

size_t fm_stock_tool_volumes(const fm_stock *s, fm_stock_tool_volume *out, size_t cap)
{
    for (size_t i = 0; i < s->ntools && i < cap; i++) out[i] = s->tools[i];
    return s->ntools;
}

static int by_removed_desc(const void *a, const void *b)
{
    const fm_stock_block *x = a, *y = b;
    if (x->removed_mm3 != y->removed_mm3) return x->removed_mm3 > y->removed_mm3 ? -1 : 1;
    return x->block < y->block ? -1 : (x->block > y->block);
}

size_t fm_stock_blocks(const fm_stock *s, fm_stock_block *out, size_t cap)
{
    if (!out || cap == 0) return s->nblocks;
    if (cap >= s->nblocks) {
        memcpy(out, s->blocks, s->nblocks * sizeof *out);
        qsort(out, s->nblocks, sizeof *out, by_removed_desc);
        return s->nblocks;
    }
    fm_stock_block *tmp = malloc(s->nblocks * sizeof *tmp);
    if (!tmp) return 0;
    memcpy(tmp, s->blocks, s->nblocks * sizeof *tmp);
    qsort(tmp, s->nblocks, sizeof *tmp, by_removed_desc);
    memcpy(out, tmp, cap * sizeof *out);
    free(tmp);
    return s->nblocks;
}

int fm_stock_block_removed(const fm_stock *s, int64_t block, fm_stock_block *out)
{
    if (!s->block_index || block < 0) return 0;
    size_t j = block_find(s, block);
    if (!s->block_index[j]) return 0;
    if (out) *out = s->blocks[s->block_index[j] - 1];
    return 1;
}

fm_status fm_stock_surface_area(const fm_stock *s, double *area, fm_error *err)
{
    return fm_vdb_area(s->vdb, area, err);
}

size_t fm_stock_memory_bytes(const fm_stock *s)
{
    return fm_vdb_memory(s->vdb) + fm_tool_marks_bytes(&s->marks);
}

void fm_stock_memory_usage(const fm_stock *s, fm_stock_memory *out)
{
    memset(out, 0, sizeof *out);
    fm_vdb_counts g;
    fm_vdb_memory_usage(s->vdb, &g);
    out->leaves = g.leaves;
    out->active_voxels = g.active_voxels;
    out->internal_nodes = g.internal_nodes;
    out->leaf_bytes = fm_vdb_leaf_bytes();
    out->band_bytes = g.memusage;
    const size_t leaves_counted = g.leaves * fm_vdb_leaf_memusage();
    out->internal_bytes = g.memusage > leaves_counted ? g.memusage - leaves_counted : 0;
    out->marks_bytes = fm_tool_marks_used_bytes(&s->marks);
    out->marks_leaves = s->marks.nleaves;
    out->tables_bytes = s->cap_chunks * sizeof *s->chunks + s->cap_tools * sizeof *s->tools +
                        s->opt.block_table_size * sizeof *s->blocks +
                        s->block_index_size * sizeof *s->block_index;
}

void fm_stock_set_memory_budget(fm_stock *s, size_t bytes)
{
    if (bytes) s->opt.memory_budget = bytes;
}

fm_status fm_stock_validate(const fm_stock *s, fm_error *err) { return fm_vdb_validate(s->vdb, err); }

/* ------------------------------------------------------------- chunks -- */

uint64_t fm_stock_version(const fm_stock *s) { return s->version; }

void fm_stock_chunk_bounds(const fm_stock *s, const int32_t index[3], double lo[3], double hi[3])
{
    double origin[3];
    fm_vdb_origin(s->vdb, origin);
    const double h = fm_vdb_voxel(s->vdb);
    for (int k = 0; k < 3; k++) {
        lo[k] = origin[k] + h * ((double)index[k] * FM_STOCK_CHUNK_VOXELS);
        hi[k] = origin[k] + h * ((double)index[k] * FM_STOCK_CHUNK_VOXELS +
                                 (FM_STOCK_CHUNK_VOXELS - 1));
    }
}

size_t fm_stock_changed_chunks(const fm_stock *s, uint64_t since, fm_stock_chunk *out,
                               size_t cap)
{
    size_t n = 0;
    for (size_t i = 0; i < s->cap_chunks; i++) {
        const fm_stock_chunk_slot *c = &s->chunks[i];
        if (!c->used || c->version <= since) continue;
        if (out && n < cap) {
            memcpy(out[n].index, c->key, sizeof out[n].index);
            out[n].version = c->version;
            fm_stock_chunk_bounds(s, c->key, out[n].lo, out[n].hi);
        }
        n++;
    }
    return n;
}

/* ---------------------------------------------------------- accessors -- */

double fm_stock_voxel_size(const fm_stock *s) { return fm_vdb_voxel(s->vdb); }
int fm_stock_band_voxels(const fm_stock *s) { return fm_vdb_band(s->vdb); }

void fm_stock_index_to_world(const fm_stock *s, const double ijk[3], double xyz[3])
{
    double origin[3];
    fm_vdb_origin(s->vdb, origin);
    const double h = fm_vdb_voxel(s->vdb);
    for (int k = 0; k < 3; k++) xyz[k] = origin[k] + h * ijk[k];
}

fm_status fm_stock_active_bounds(const fm_stock *s, int32_t lo[3], int32_t hi[3], fm_error *err)
{
    if (!fm_vdb_active_bounds(s->vdb, lo, hi))
        return fm_error_set(err, FM_ERR_INPUT, "the stock has no surface left");
    return FM_OK;
}

double fm_stock_sample(const fm_stock *s, const double p[3]) { return -fm_vdb_sample(s->vdb, p); }

fm_status fm_stock_visit(const fm_stock *s, const int32_t lo[3], const int32_t hi[3],
                         int (*prune)(void *user, const int32_t lo[3], const int32_t hi[3]),
                         int (*visit)(void *user, const fm_stock_region *region), void *user,
                         fm_error *err)
{
    return fm_vdb_visit(s->vdb, lo, hi, prune, visit, user, err);
}

const char *fm_stock_resume_string(const fm_stock *s) { return s->resume ? s->resume : ""; }

void *fm_stock_vdb_grid(fm_stock *s) { return fm_vdb_grid_ptr(s->vdb); }
