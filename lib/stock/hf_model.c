/* hf_model.c: a HyperFun model (.hf) as the field lib/stock rasterizes:
 * the one builder for stocks and designs given as models, beside the STL
 * (stl.c) and snapshot (snapshot.c) sources. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "hf/hf.h"
#include "stock.h"

/* Models are searched for within this cube (mm). */
#define STOCK_MODEL_SEARCH_MM 2000.0
#define STOCK_MODEL_MAX_BOXES 4000000u

/* The compiled model behind the field (its ctx). */
typedef struct model_field {
    fm_graph *graph;
    fm_tape *tape;
    fm_field field;
    double reach; /* mm */
    double voxel; /* mm: the grid's, sizes the blocks of shortened tapes */
} model_field;

/* A HyperFun model as a field for a stock or a design.
 *
 * Values: HyperFun functions are rarely distances (hfSphere is R^2 - r^2)
 * and the narrow band needs first-order distances, so the model is
 * normalized, f / |grad f|, with the
 * gradient from forward differences of batch evaluations (three more
 * points a step of 1e-6 of the coordinates' size away; one forward-mode
 * gradient per point costs ten times as much; where that gradient is
 * short, at exact min/max ties, backward differences too), on the model's tape
 * shortened to the points' box (the min/max branches of features far
 * away dropped). The value is then cut by the distance to the model's
 * bounding box, as fm_field asks.
 *
 * Not Shapiro's eq. 4.9, f / sqrt(f^2 + |grad f|^2), which is first order
 * as well and bounded, but adds f^2 in mm^2 to a gradient without units:
 * its values depend on the unit and fall short of a distance by f^3 / 2
 * (0.013 mm at a band of 0.3 mm). f / |grad f| is a model's distance
 * wherever the model is one (a min/max of exact distances, as the demo's
 * part is): there a design's planes hold the same values as the stock's
 * box, and the comparison finds nothing to measure (bench/design: its
 * compare step 0.52 -> 0.18 s of CPU). A short gradient makes the value
 * large; the band clamps it, and 0 / 0 at a flat zero takes the box
 * distance (NaN below).
 *
 * Boxes: the normalized function's interval is useless for classifying
 * boxes (its modulus is below 1 everywhere, so no box would ever be found
 * deep inside or outside, and the rasterizer would evaluate every voxel of
 * the bounding box). A box whose widening by `reach` (the grid's band) the
 * model's interval shows all inside or all outside is at least the band
 * from the surface: a tile. Other boxes get voxel work. */

#define MODEL_CHUNK 256

typedef struct model_worker {
    fm_evaluator *ev;
    unsigned plain_leaves; /* leaves to evaluate point by point before the next grid try */
    fm_tape *leaf_tape; /* the tape shortened to the leaf at hand, rewritten per leaf */
    /* blocks by the parity of their keys (a box's neighbours across a
     * block's face go to another slot) */
    struct model_block {
        int set;       /* key and tape are set */
        double key[3]; /* the block: [key, key + 1] * BLOCK_VOXELS voxels per axis */
        fm_tape *tape; /* shortened to the block and around it; NULL: nothing dropped */
        fm_tape *own;  /* the slot's tape, rewritten for each new block */
    } block[8];
    double x[4 * MODEL_CHUNK], y[4 * MODEL_CHUNK], z[4 * MODEL_CHUNK], f[4 * MODEL_CHUNK];
} model_worker;

static void *model_worker_new(void *ctx)
{
    model_field *mf = ctx;
    model_worker *w = malloc(sizeof *w);
    if (!w) return NULL;
    w->ev = fm_evaluator_new(mf->tape, NULL);
    w->plain_leaves = 0;
    w->leaf_tape = NULL;
    memset(w->block, 0, sizeof w->block);
    if (!w->ev) {
        free(w);
        return NULL;
    }
    return w;
}

static void model_worker_free(void *ctx, void *worker)
{
    (void)ctx;
    model_worker *w = worker;
    if (!w) return;
    fm_evaluator_free(w->ev);
    for (int b = 0; b < 8; b++) fm_tape_free(w->block[b].own);
    fm_tape_free(w->leaf_tape);
    free(w);
}

/* Exact signed distance to the field's bounds, positive inside. */
static double model_box_distance(const fm_field *f, const double p[3])
{
    double out2 = 0, in = INFINITY;
    for (int k = 0; k < 3; k++) {
        const double below = f->lo[k] - p[k], above = p[k] - f->hi[k];
        const double d = below > above ? below : above;
        if (d > 0) out2 += d * d;
        if (-d < in) in = -d;
    }
    return out2 > 0 ? -sqrt(out2) : in;
}

/* Shortened tapes by block: the space is cut in cubes of BLOCK_VOXELS
 * voxels, and a worker keeps the model's tape shortened to the cubes it
 * last worked in, each widened by half a cube each side. A box up to a
 * cube across whose centre lies in such a cube (a leaf with its layer, or
 * widened by the band; the rasterizer hands out a box's children one after
 * another) is evaluated on that tape, or shortened further from it: the
 * interval pass's leaf-level bounds and each leaf's own shortening then run
 * over a short tape, not the whole model. Values and bounds are the same as
 * on the whole tape: a shortened tape drops only the min/max branches that
 * cannot win inside its box, where the bounds of the two did not overlap,
 * so no sub-box bound changes either. */
#define BLOCK_VOXELS 32

/* Set the evaluator on a block's tape when box (mm) fits its block, making
 * the block's tape first when the slot holds another block; on the whole
 * tape otherwise. */
static void use_block_tape(const model_field *mf, model_worker *w, const fm_interval box[3])
{
    const double side = BLOCK_VOXELS * mf->voxel;
    double key[3];
    int fits = side > 0;
    for (int k = 0; k < 3 && fits; k++) {
        fits = box[k].hi - box[k].lo <= side;
        key[k] = floor(0.5 * (box[k].lo + box[k].hi) / side);
        fits = fits && fabs(key[k]) < 1e15;
    }
    fm_evaluator_use(w->ev, NULL);
    if (!fits) return;
    /* the box inside the block's region, rounding included */
    for (int k = 0; k < 3; k++)
        if (box[k].lo < (key[k] - 0.5) * side || box[k].hi > (key[k] + 1.5) * side) return;
    struct model_block *b = &w->block[((long long)key[0] & 1) << 2 | ((long long)key[1] & 1) << 1 |
                                      ((long long)key[2] & 1)];
    if (!b->set || key[0] != b->key[0] || key[1] != b->key[1] || key[2] != b->key[2]) {
        b->tape = NULL;
        fm_interval region[4];
        for (int k = 0; k < 3; k++) {
            region[k].lo = (key[k] - 0.5) * side;
            region[k].hi = (key[k] + 1.5) * side;
            region[k].lo -= 1e-6 * (1 + fabs(region[k].lo));
            region[k].hi += 1e-6 * (1 + fabs(region[k].hi));
            b->key[k] = key[k];
        }
        region[3].lo = region[3].hi = 0;
        fm_interval range;
        b->tape = fm_eval_interval_shorten_in(w->ev, region, &range, &b->own);
        b->set = 1;
    }
    if (b->tape) fm_evaluator_use(w->ev, b->tape);
}

/* The normalized values at n points, on the tape the worker's evaluator
 * uses (the caller's shortened one): four evaluations a point. */
static void model_values(const model_field *mf, model_worker *w, size_t n, const double *x,
                         const double *y, const double *z, double *out)
{
    for (size_t start = 0; start < n; start += MODEL_CHUNK) {
        const size_t m = n - start < MODEL_CHUNK ? n - start : MODEL_CHUNK;
        /* the point, then its +x, +y and +z neighbours, each block m long */
        for (size_t i = 0; i < m; i++) {
            const double p[3] = {x[start + i], y[start + i], z[start + i]};
            for (int j = 0; j < 4; j++) {
                double q[3] = {p[0], p[1], p[2]};
                if (j > 0) q[j - 1] += 1e-6 * (1 + fabs(p[j - 1]));
                w->x[j * m + i] = q[0];
                w->y[j * m + i] = q[1];
                w->z[j * m + i] = q[2];
            }
        }
        fm_eval_batch(w->ev, 4 * m, w->x, w->y, w->z, NULL, w->f);
        double value[MODEL_CHUNK], grad[3][MODEL_CHUNK];
        size_t flat[MODEL_CHUNK], nflat = 0;
        for (size_t i = 0; i < m; i++) {
            const double f = w->f[i];
            double g2 = 0;
            for (int k = 0; k < 3; k++) {
                const size_t j = (1 + (size_t)k) * m + i;
                const double step = k == 0 ? w->x[j] - w->x[i] : k == 1 ? w->y[j] - w->y[i]
                                                                        : w->z[j] - w->z[i];
                grad[k][i] = (w->f[j] - f) / step;
                g2 += grad[k][i] * grad[k][i];
            }
            value[i] = f;
            /* Where a min or max ties exactly (a box's edge with its faces
             * half a voxel off the grid puts voxel centres on the ties), every
             * forward difference can follow the branch that does not change:
             * a gradient of 0 would make the value infinite (the band's
             * clamp) and the box distance would take over. Such points (and any whose gradient is short
             * of a distance's 1) get backward differences as well, and each
             * axis the larger of the two: a gradient no shorter than a
             * one-sided one, so the value stays a lower bound of a distance. */
            if (g2 < 0.81) flat[nflat++] = i;
        }
        if (nflat > 0) {
            for (size_t a = 0; a < nflat; a++) {
                const size_t i = flat[a];
                const double p[3] = {x[start + i], y[start + i], z[start + i]};
                for (int k = 0; k < 3; k++) {
                    double q[3] = {p[0], p[1], p[2]};
                    q[k] -= 1e-6 * (1 + fabs(p[k]));
                    w->x[k * nflat + a] = q[0];
                    w->y[k * nflat + a] = q[1];
                    w->z[k * nflat + a] = q[2];
                }
            }
            fm_eval_batch(w->ev, 3 * nflat, w->x, w->y, w->z, NULL, w->f);
            for (size_t a = 0; a < nflat; a++) {
                const size_t i = flat[a];
                const double p[3] = {x[start + i], y[start + i], z[start + i]};
                for (int k = 0; k < 3; k++) {
                    const size_t j = (size_t)k * nflat + a;
                    const double q = k == 0 ? w->x[j] : k == 1 ? w->y[j] : w->z[j];
                    const double back = (value[i] - w->f[j]) / (p[k] - q);
                    if (fabs(back) > fabs(grad[k][i])) grad[k][i] = back;
                }
            }
        }
        for (size_t i = 0; i < m; i++) {
            const double f = value[i];
            const double g2 =
                grad[0][i] * grad[0][i] + grad[1][i] * grad[1][i] + grad[2][i] * grad[2][i];
            const double v = f / sqrt(g2);
            const double p[3] = {x[start + i], y[start + i], z[start + i]};
            const double b = model_box_distance(&mf->field, p);
            /* NaN (and 0 / 0 at a flat zero) takes the box distance */
            out[start + i] = v < b ? v : b;
        }
    }
}

/* A whole leaf from the rasterizer: 8^3 points, x set by i >> 6, y by
 * (i >> 3) & 7, z by i & 7, each axis increasing. Fills the leaf's
 * coordinates along each axis into axis[k][1..8], and one step beyond each
 * end into axis[k][0] and axis[k][9]. */
#define LEAF_SIDE 8
#define GRID_SIDE (LEAF_SIDE + 2)
_Static_assert(GRID_SIDE * GRID_SIDE * GRID_SIDE <= 4 * MODEL_CHUNK,
               "a leaf's grid with its layer around fits a worker's buffers");

static int leaf_grid(size_t n, const double *x, const double *y, const double *z,
                     double axis[3][GRID_SIDE])
{
    if (n != LEAF_SIDE * LEAF_SIDE * LEAF_SIDE) return 0;
    for (int a = 0; a < LEAF_SIDE; a++) {
        axis[0][a + 1] = x[a * LEAF_SIDE * LEAF_SIDE];
        axis[1][a + 1] = y[a * LEAF_SIDE];
        axis[2][a + 1] = z[a];
    }
    size_t i = 0;
    int same = 1;
    for (int a = 1; a <= LEAF_SIDE; a++)
        for (int b = 1; b <= LEAF_SIDE; b++)
            for (int c = 1; c <= LEAF_SIDE; c++, i++)
                same &= (x[i] == axis[0][a]) & (y[i] == axis[1][b]) & (z[i] == axis[2][c]);
    if (!same) return 0;
    for (int k = 0; k < 3; k++) {
        for (int a = 1; a < LEAF_SIDE; a++)
            if (!(axis[k][a + 1] > axis[k][a])) return 0;
        axis[k][0] = axis[k][1] - (axis[k][2] - axis[k][1]);
        axis[k][GRID_SIDE - 1] = axis[k][LEAF_SIDE] + (axis[k][LEAF_SIDE] - axis[k][LEAF_SIDE - 1]);
    }
    return 1;
}

/* One-sided differences a grid step either side that agree this closely
 * (relative) say the model is linear along that axis over the step: the
 * forward difference a 1e-6 step away would give the same slope, up to its
 * own rounding (~1e-8 relative at 100 mm coordinates). Curved surfaces
 * differ by about step / radius, min/max kinks by the change of slope. */
#define LINEAR_TOL 1e-9
/* leaves done point by point after a leaf the grid did not serve */
#define PLAIN_LEAVES 8

/* normalize_leaf is also compiled for AVX2 (4 doubles a step instead of
 * SSE2's 2), picked at load time where the CPU has it: AVX2 without FMA
 * rounds every operation as SSE2 does, so the values are the same bits
 * (this file is compiled without math errno: CMakeLists.txt). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MODEL_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define MODEL_VECTOR_CLONES
#endif

/* A leaf's normalized values from the model on its grid with a layer
 * around it (f: GRID_SIDE^3, x slowest): the gradient from the neighbours,
 * and again[i] set where the one-sided differences a step either side do
 * not agree (curved, a min/max kink, or a short gradient: model_values
 * decides there). inv: 1 / step between grid layers per axis; beyond: the
 * signed distance beyond the bounds box's faces per axis (model_box_distance,
 * separated). Written without branches, so that it vectorizes along z. */
static MODEL_VECTOR_CLONES void normalize_leaf(const double *restrict f,
                                               const double inv[3][GRID_SIDE - 1],
                                               const double beyond[3][LEAF_SIDE],
                                               double *restrict out,
                                               int64_t *restrict again)
{
    /* signed: a neighbour below is row[c - sx] */
    const ptrdiff_t sx = GRID_SIDE * GRID_SIDE, sy = GRID_SIDE;
    for (int a = 1; a <= LEAF_SIDE; a++)
        for (int b = 1; b <= LEAF_SIDE; b++) {
            const double *restrict row = f + a * sx + b * sy;
            const double ixu = inv[0][a], ixd = inv[0][a - 1];
            const double iyu = inv[1][b], iyd = inv[1][b - 1];
            const double bx = beyond[0][a - 1], by = beyond[1][b - 1];
            const double ox = bx > 0 ? bx : 0, oy = by > 0 ? by : 0;
            const double mxy = bx > by ? bx : by;
            double *restrict o = out + ((size_t)(a - 1) * LEAF_SIDE + (size_t)(b - 1)) * LEAF_SIDE;
            int64_t *restrict ag = again + ((size_t)(a - 1) * LEAF_SIDE + (size_t)(b - 1)) * LEAF_SIDE;
            for (int c = 1; c <= LEAF_SIDE; c++) {
                const double v0 = row[c];
                const double ux = (row[c + sx] - v0) * ixu, dx = (v0 - row[c - sx]) * ixd;
                const double uy = (row[c + sy] - v0) * iyu, dy = (v0 - row[c - sy]) * iyd;
                const double uz = (row[c + 1] - v0) * inv[2][c], dz = (v0 - row[c - 1]) * inv[2][c - 1];
                /* relative to the whole gradient: along a face the
                 * slope is 0 up to rounding. NaN fails the test too. */
                const double tol = LINEAR_TOL * (fabs(ux) + fabs(dx) + fabs(uy) + fabs(dy) +
                                                 fabs(uz) + fabs(dz));
                const double gx = 0.5 * (ux + dx), gy = 0.5 * (uy + dy), gz = 0.5 * (uz + dz);
                const double g2 = gx * gx + gy * gy + gz * gz;
                /* a short gradient: model_values' backward differences
                 * decide, as they do for every point */
                ag[c - 1] = !((fabs(ux - dx) <= tol) & (fabs(uy - dy) <= tol) &
                              (fabs(uz - dz) <= tol) & (g2 >= 0.81));
                const double v = v0 / sqrt(g2);
                /* model_box_distance: the sum of the squares beyond the
                 * faces outside, the nearest face inside */
                const double bz = beyond[2][c - 1];
                const double oz = bz > 0 ? bz : 0;
                const double out2 = ox * ox + oy * oy + oz * oz;
                const double mx = mxy > bz ? mxy : bz;
                const double root = sqrt(out2); /* unconditional: no branch in the loop */
                const double bd = out2 > 0 ? -root : -mx;
                o[c - 1] = v < bd ? v : bd;
            }
        }
}

static void model_batch(void *ctx, void *worker, size_t n, const double *x, const double *y,
                        const double *z, double *out)
{
    model_field *mf = ctx;
    model_worker *w = worker;
    if (n == 0) return;
    /* One shortened tape for the whole batch (a leaf's voxels, from the
     * rasterizer), not one per chunk: shortening costs about as much as
     * evaluating a chunk (perf of bench/design: half of this function's time
     * when it ran per chunk, allocations included, which the worker's slot
     * now spares). A shortened tape gives the same values as the full one
     * inside its box, so the values do not change. */
    fm_interval box[4] = {{INFINITY, -INFINITY}, {INFINITY, -INFINITY}, {INFINITY, -INFINITY},
                          {0, 0}};
    double axis[3][GRID_SIDE];
    int grid = leaf_grid(n, x, y, z, axis);
    if (grid && w->plain_leaves > 0) {
        w->plain_leaves--;
        grid = 0;
    }
    if (grid) {
        for (int k = 0; k < 3; k++) {
            box[k].lo = axis[k][0];
            box[k].hi = axis[k][GRID_SIDE - 1];
        }
    } else {
        for (size_t i = 0; i < n; i++) {
            const double p[3] = {x[i], y[i], z[i]};
            for (int k = 0; k < 3; k++) {
                if (p[k] < box[k].lo) box[k].lo = p[k];
                if (p[k] > box[k].hi) box[k].hi = p[k];
            }
        }
    }
    /* the neighbours lie a step above (and, for the points below, a step
     * below) */
    for (int k = 0; k < 3; k++) {
        box[k].hi += 2e-6 * (1 + fabs(box[k].hi));
        box[k].lo -= 2e-6 * (1 + fabs(box[k].lo));
    }
    use_block_tape(mf, w, box);
    fm_interval range;
    fm_tape *shorter = fm_eval_interval_shorten_in(w->ev, box, &range, &w->leaf_tape);
    if (shorter) fm_evaluator_use(w->ev, shorter);
    if (!grid) {
        model_values(mf, w, n, x, y, z, out);
    } else {
        /* A leaf: the model once at each voxel and at a layer of voxels
         * around the leaf (1000 evaluations instead of 2048 and more), and
         * the gradient from the neighbours' values where the model is
         * linear along each axis over a step either side (planar faces,
         * the bulk of a machined part): there the slope is the same as a
         * 1e-6 step's. Elsewhere (curved surfaces, min/max kinks within a
         * step: the 05bb468 tie case among them) the four evaluations of
         * model_values, so those values are the same as ever. */
        size_t g = 0;
        for (int a = 0; a < GRID_SIDE; a++)
            for (int b = 0; b < GRID_SIDE; b++)
                for (int c = 0; c < GRID_SIDE; c++, g++) {
                    w->x[g] = axis[0][a];
                    w->y[g] = axis[1][b];
                    w->z[g] = axis[2][c];
                }
        fm_eval_batch(w->ev, g, w->x, w->y, w->z, NULL, w->f);
        const double *f = w->f;
        /* per axis: 1 / step between grid layers, and the signed distance
         * beyond the bounds box's faces (model_box_distance, separated) */
        double inv[3][GRID_SIDE - 1], beyond[3][LEAF_SIDE];
        for (int k = 0; k < 3; k++) {
            for (int a = 0; a < GRID_SIDE - 1; a++) inv[k][a] = 1 / (axis[k][a + 1] - axis[k][a]);
            for (int a = 0; a < LEAF_SIDE; a++) {
                const double below = mf->field.lo[k] - axis[k][a + 1];
                const double above = axis[k][a + 1] - mf->field.hi[k];
                beyond[k][a] = below > above ? below : above;
            }
        }
        double px[LEAF_SIDE * LEAF_SIDE * LEAF_SIDE], py[LEAF_SIDE * LEAF_SIDE * LEAF_SIDE],
            pz[LEAF_SIDE * LEAF_SIDE * LEAF_SIDE], pv[LEAF_SIDE * LEAF_SIDE * LEAF_SIDE];
        size_t redo[LEAF_SIDE * LEAF_SIDE * LEAF_SIDE], nredo = 0;
        /* 64-bit flags: the same width as the values, so that the loop
         * vectorizes */
        int64_t again[LEAF_SIDE * LEAF_SIDE * LEAF_SIDE];
        normalize_leaf(f, inv, beyond, out, again);
        size_t i;
        for (i = 0; i < n; i++) {
            if (!again[i]) continue;
            px[nredo] = x[i];
            py[nredo] = y[i];
            pz[nredo] = z[i];
            redo[nredo++] = i;
        }
        if (nredo > 0) model_values(mf, w, nredo, px, py, pz, pv);
        /* Curved nearly all over (a sphere's leaves are): the grid's 1000
         * evaluations came on top of the 2048; the next leaves, likely
         * alike, go point by point. */
        if (8 * nredo > 7 * n) w->plain_leaves = PLAIN_LEAVES;
        for (size_t a = 0; a < nredo; a++) out[redo[a]] = pv[a];
    }
    fm_evaluator_use(w->ev, NULL);
}

static fm_interval model_interval(void *ctx, void *worker, const fm_interval box[3])
{
    model_field *mf = ctx;
    model_worker *w = worker;
    fm_interval wide[4];
    for (int k = 0; k < 3; k++) {
        wide[k].lo = box[k].lo - mf->reach;
        wide[k].hi = box[k].hi + mf->reach;
    }
    wide[3].lo = wide[3].hi = 0;
    use_block_tape(mf, w, wide);
    const fm_interval f = fm_eval_interval(w->ev, wide);
    fm_evaluator_use(w->ev, NULL);
    /* a hair beyond the band, so that the float band compares below it */
    const double beyond = mf->reach * (1 + 1e-6);
    if (f.lo > 0) return (fm_interval){beyond, INFINITY};
    /* outside the model, or beyond the bounds box by more than the band */
    double c[3], half2 = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (box[k].lo + box[k].hi);
        half2 += 0.25 * (box[k].hi - box[k].lo) * (box[k].hi - box[k].lo);
    }
    const double bound = model_box_distance(&mf->field, c) + sqrt(half2);
    if (f.hi < 0 || bound <= -beyond) return (fm_interval){-INFINITY, -beyond};
    return (fm_interval){-1, fmin(1, bound)};
}

static void model_field_close(model_field *mf)
{
    fm_tape_free(mf->tape);
    fm_graph_free(mf->graph);
    memset(mf, 0, sizeof *mf);
}

static fm_status model_field_open(const char *path, double voxel, double reach,
                                  const char *what, model_field *mf, fm_error *err)
{
    memset(mf, 0, sizeof *mf);
    mf->reach = reach;
    mf->voxel = voxel;
    mf->graph = fm_graph_new(0);
    if (!mf->graph) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_graph *g = mf->graph;
    fm_evaluator *ev = NULL;
    fm_status st = FM_OK;
    fm_hf_model model;
    if ((st = fm_hf_compile_file(g, path, NULL, &model, err)) != FM_OK) goto done;
    if (model.dimension > 3) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                         "the %s model '%s' is %dD; a %s is a 3D object (x[3])", what,
                         model.name, model.dimension, what);
        goto done;
    }
    mf->tape = fm_tape_compile(g, model.root, err);
    if (!mf->tape) {
        st = err && err->code ? err->code : FM_ERR_INPUT;
        goto done;
    }
    ev = fm_evaluator_new(mf->tape, err);
    if (!ev) {
        st = err && err->code ? err->code : FM_ERR_INPUT;
        goto done;
    }
    fm_inside_bounds s;
    fm_interval start[3];
    for (int a = 0; a < 3; a++) start[a] = (fm_interval){-STOCK_MODEL_SEARCH_MM, STOCK_MODEL_SEARCH_MM};
    double min_size = fmax(voxel, 2 * STOCK_MODEL_SEARCH_MM / 1024.0);
    if (fm_find_inside_bounds(ev, start, min_size, STOCK_MODEL_MAX_BOXES, &s) != FM_OK) {
        st = fm_error_at(err, FM_ERR_LIMIT, path, 0, 0,
                         "the %s model's boundary is too complex to bound (over %u boxes)", what,
                         STOCK_MODEL_MAX_BOXES);
        goto done;
    }
    if (!s.found) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "the %s model '%s' is empty within +-%.0f mm",
                         what, model.name, STOCK_MODEL_SEARCH_MM);
        goto done;
    }
    for (int a = 0; a < 3; a++) {
        if (s.lo[a] <= -STOCK_MODEL_SEARCH_MM || s.hi[a] >= STOCK_MODEL_SEARCH_MM) {
            st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                             "the %s model '%s' is not bounded within +-%.0f mm along %c; "
                             "intersect it with a block",
                             what, model.name, STOCK_MODEL_SEARCH_MM, "xyz"[a]);
            goto done;
        }
        mf->field.lo[a] = s.lo[a] - 4 * voxel;
        mf->field.hi[a] = s.hi[a] + 4 * voxel;
    }
    mf->field.ctx = mf;
    mf->field.worker_new = model_worker_new;
    mf->field.worker_free = model_worker_free;
    mf->field.batch = model_batch;
    mf->field.interval = model_interval;
done:
    fm_evaluator_free(ev);
    if (st != FM_OK) model_field_close(mf);
    return st;
}


static void model_field_release(void *ctx)
{
    model_field_close(ctx);
    free(ctx);
}

fm_status fm_stock_hf_field(const char *path, double voxel, double reach, const char *what,
                            fm_field *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    model_field *mf = malloc(sizeof *mf);
    if (!mf) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for the %s's model", what);
    fm_status st = model_field_open(path, voxel, reach, what, mf, err);
    if (st != FM_OK) {
        free(mf);
        return st;
    }
    mf->field.release = model_field_release;
    *out = mf->field;
    return FM_OK;
}

fm_stock *fm_stock_new_from_hf(const char *path, const fm_stock_options *opt, fm_error *err)
{
    fm_stock_options o;
    fm_stock_options_default(&o);
    if (opt && opt->voxel_mm > 0) o.voxel_mm = opt->voxel_mm;
    if (opt && opt->band_voxels > 0) o.band_voxels = opt->band_voxels;
    /* reach = the grid's band: boxes the model's interval decides are tiles */
    fm_field field;
    if (fm_stock_hf_field(path, o.voxel_mm, o.band_voxels * o.voxel_mm, "stock", &field, err) !=
        FM_OK)
        return NULL;
    fm_stock *stock = fm_stock_new_from_field(&field, opt, err);
    fm_field_release(&field);
    return stock;
}
