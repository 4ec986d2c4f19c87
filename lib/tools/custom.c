/* custom.c: custom cutters given as an frep tape (HyperFun models compiled
 * by lib/hf). A spinning cutter sweeps the solid of revolution of its model:
 * at radius r and height z the maximum over the angle t of
 * f(r cos t, r sin t, z). That profile g(r, z) is tabulated once per tool on
 * a regular (r, z) grid over the declared bound, clipped to the bound, and
 * evaluated by bilinear interpolation; its intervals come from the cells'
 * corners for small boxes (exact) and a min/max pyramid for large ones, so
 * they enclose the tabulated function (lib/sweep's bounds hold for it,
 * whatever the model) and shrink with the box, as its search needs.
 *
 * How the nodes are filled (docs/tools.md, "Custom cutters"):
 *  - blocks of 8 x 8 cells are classified by the model's interval over the
 *    box of each of 32 annular sectors (r in the block's range, t in a
 *    1/32 turn, z in the block's range). Every point of the block lies in
 *    every sector's box at some angle, so a sector whose interval lies
 *    above 2 mm proves g >= its lower end on the whole block (inside), and
 *    all sectors' upper ends below -2 mm prove g <= the largest of them
 *    (outside). Such nodes hold that bound: the right sign, at least 2 mm
 *    from 0 and never farther from 0 than g. (Stocks read values near 0
 *    only: the volume, the mesh and the narrow band within a few voxels.)
 *  - all other nodes (where |g| may be under 2 mm) hold
 *    the maximum of f over 32 angles, the best two refined by golden
 *    section: an attained value, so never above g; equal to g when f is
 *    unimodal in t over each 1/32 turn near its maximum.
 *  - every node is then clipped to the declared bound cylinder:
 *    min(g, R - r, z, L - z).
 * The surface of the table lies where the bilinear interpolant of those
 * nodes vanishes: within O(h^2 curvature) of the true one where the section
 * is smooth and within a cell (h) at its corners, h = max(R, L) / 512. */
#include "tools/tools.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TABLE_CELLS 512   /* cells along the longer side of the bound */
#define BLOCK 8           /* cells per side of a classified block */
#define SECTORS 32        /* a multiple of 4: the axes are sector edges */
#define SAMPLES 32        /* angles sampled at an undecided node */
#define GOLDEN_STEPS 24   /* bracket 2 / 32 turn -> 2e-6 of a turn */
#define MAX_LEVELS 24
#define FAR_MM 2.0        /* model values beyond +-2 mm may be bounds (coarse voxels are <= 1 mm) */

typedef struct revolved_table {
    int nr, nz;            /* cells along r and z */
    double R, L, hr, hz;   /* bound and cell sizes */
    double *node;          /* (nr + 1) x (nz + 1) values, node[j * (nr + 1) + i] at (i hr, j hz) */
    int levels;
    int bw[MAX_LEVELS], bh[MAX_LEVELS]; /* blocks per row / column at each pyramid level */
    double *lo[MAX_LEVELS], *hi[MAX_LEVELS]; /* min / max of the nodes over blocks of 2^k x 2^k cells */
} revolved_table;

static void table_free(revolved_table *tb)
{
    if (!tb) return;
    free(tb->node);
    for (int k = 0; k < tb->levels; k++) {
        free(tb->lo[k]);
        free(tb->hi[k]);
    }
    free(tb);
}

static void table_release(void *ctx) { table_free((revolved_table *)ctx); }

static double node_at(const revolved_table *tb, int i, int j) { return tb->node[(size_t)j * (size_t)(tb->nr + 1) + (size_t)i]; }

/* The cell holding coordinate v (clamped to the grid), and the fraction. */
static int cell_of(double v, double h, int n, double *frac)
{
    double f = v / h;
    int c = f <= 0 ? 0 : (int)f;
    if (c > n - 1) c = n - 1;
    if (frac) *frac = f - c;
    return c;
}

static double table_eval(void *ctx, void *worker, double r, double z)
{
    (void)worker;
    const revolved_table *tb = ctx;
    double rc = r < 0 ? 0 : r > tb->R ? tb->R : r;
    double zc = z < 0 ? 0 : z > tb->L ? tb->L : z;
    double u, w;
    int i = cell_of(rc, tb->hr, tb->nr, &u), j = cell_of(zc, tb->hz, tb->nz, &w);
    if (u < 0) u = 0;
    if (u > 1) u = 1;
    if (w < 0) w = 0;
    if (w > 1) w = 1;
    double v = (1 - w) * ((1 - u) * node_at(tb, i, j) + u * node_at(tb, i + 1, j)) +
               w * ((1 - u) * node_at(tb, i, j + 1) + u * node_at(tb, i + 1, j + 1));
    /* Outside the bound: the distance to it, which the clipped nodes on
     * its surface (all <= 0) meet continuously. */
    double er = r > tb->R ? r - tb->R : 0, ez = z < 0 ? -z : z > tb->L ? z - tb->L : 0;
    if (er > 0 || ez > 0) {
        double d = -sqrt(er * er + ez * ez);
        if (d < v) v = d;
    }
    return v;
}

/* Rounding in the interpolation can step an ulp outside its corners. */
static double widen(double v) { return 1e-12 * (1 + fabs(v)); }

static fm_interval table_interval(void *ctx, void *worker, fm_interval r, fm_interval z)
{
    (void)worker;
    const revolved_table *tb = ctx;
    double ra = r.lo < 0 ? 0 : r.lo > tb->R ? tb->R : r.lo, rb = r.hi < 0 ? 0 : r.hi > tb->R ? tb->R : r.hi;
    double za = z.lo < 0 ? 0 : z.lo > tb->L ? tb->L : z.lo, zb = z.hi < 0 ? 0 : z.hi > tb->L ? tb->L : z.hi;
    /* The same cell choice as table_eval, so every point's cell is covered. */
    int i0 = cell_of(ra, tb->hr, tb->nr, NULL), i1 = cell_of(rb, tb->hr, tb->nr, NULL);
    int j0 = cell_of(za, tb->hz, tb->nz, NULL), j1 = cell_of(zb, tb->hz, tb->nz, NULL);
    fm_interval out = {DBL_MAX, -DBL_MAX};
    if ((i1 - i0 + 1) * (j1 - j0 + 1) <= 16) {
        /* Small boxes, exactly: a bilinear function is affine in each
         * variable, so over a rectangle its extremes are at the corners. In
         * each cell the box's points have the fractions between those of its
         * ends, clamped as table_eval clamps them. */
        for (int j = j0; j <= j1; j++)
            for (int i = i0; i <= i1; i++) {
                double us[2] = {ra / tb->hr - i, rb / tb->hr - i}, ws[2] = {za / tb->hz - j, zb / tb->hz - j};
                for (int e = 0; e < 2; e++) {
                    us[e] = us[e] < 0 ? 0 : us[e] > 1 ? 1 : us[e];
                    ws[e] = ws[e] < 0 ? 0 : ws[e] > 1 ? 1 : ws[e];
                }
                double v00 = node_at(tb, i, j), v10 = node_at(tb, i + 1, j);
                double v01 = node_at(tb, i, j + 1), v11 = node_at(tb, i + 1, j + 1);
                for (int a = 0; a < 2; a++)
                    for (int b = 0; b < 2; b++) {
                        double u = us[a], w = ws[b];
                        double v = (1 - w) * ((1 - u) * v00 + u * v10) + w * ((1 - u) * v01 + u * v11);
                        if (v < out.lo) out.lo = v;
                        if (v > out.hi) out.hi = v;
                    }
            }
    } else {
        int k = 0;
        while (k + 1 < tb->levels && ((i1 >> k) - (i0 >> k) > 3 || (j1 >> k) - (j0 >> k) > 3)) k++;
        for (int j = j0 >> k; j <= j1 >> k; j++)
            for (int i = i0 >> k; i <= i1 >> k; i++) {
                size_t b = (size_t)j * (size_t)tb->bw[k] + (size_t)i;
                if (tb->lo[k][b] < out.lo) out.lo = tb->lo[k][b];
                if (tb->hi[k][b] > out.hi) out.hi = tb->hi[k][b];
            }
    }
    /* Points outside the bound: min(table at the clamped point, -distance). */
    double er = r.hi > tb->R ? r.hi - tb->R : 0;
    double ez = fmax(z.lo < 0 ? -z.lo : 0, z.hi > tb->L ? z.hi - tb->L : 0);
    if (er > 0 || ez > 0) {
        double d = -sqrt(er * er + ez * ez);
        if (d < out.lo) out.lo = d;
    }
    /* A box wholly outside the bound: at most minus its distance to it. */
    double nr = r.lo > tb->R ? r.lo - tb->R : 0, nz = z.hi < 0 ? -z.hi : z.lo > tb->L ? z.lo - tb->L : 0;
    if (nr > 0 || nz > 0) {
        double d = -sqrt(nr * nr + nz * nz);
        if (d < out.hi) out.hi = d;
    }
    out.lo -= widen(out.lo);
    out.hi += widen(out.hi);
    return out;
}

/* ------------------------------------------------------------- build -- */

/* The box of the annular sector r in [r0, r1], t in [t0, t1] (a sector
 * never contains an axis direction inside it, so its corners bound it),
 * z in [z0, z1]. */
static void sector_box(double r0, double r1, double t0, double t1, double z0, double z1, fm_interval box[4])
{
    double c0 = cos(t0), c1 = cos(t1), s0 = sin(t0), s1 = sin(t1);
    double xs[4] = {r0 * c0, r0 * c1, r1 * c0, r1 * c1}, ys[4] = {r0 * s0, r0 * s1, r1 * s0, r1 * s1};
    box[0].lo = box[0].hi = xs[0];
    box[1].lo = box[1].hi = ys[0];
    for (int k = 1; k < 4; k++) {
        box[0].lo = fmin(box[0].lo, xs[k]);
        box[0].hi = fmax(box[0].hi, xs[k]);
        box[1].lo = fmin(box[1].lo, ys[k]);
        box[1].hi = fmax(box[1].hi, ys[k]);
    }
    /* cos and sin are rounded */
    double e = 1e-12 * (1 + r1);
    box[0].lo -= e;
    box[0].hi += e;
    box[1].lo -= e;
    box[1].hi += e;
    box[2].lo = z0;
    box[2].hi = z1;
    box[3].lo = box[3].hi = 0;
}

static double f_at(fm_evaluator *ev, double r, double t, double z)
{
    double p[4] = {r * cos(t), r * sin(t), z, 0};
    return fm_eval_point(ev, p);
}

/* max over t of f(r cos t, r sin t, z), as an attained value (see top). */
static double revolved_value(fm_evaluator *ev, double r, double z)
{
    if (r <= 0) {
        double p[4] = {0, 0, z, 0};
        return fm_eval_point(ev, p);
    }
    double xs[SAMPLES], ys[SAMPLES], zs[SAMPLES], out[SAMPLES];
    const double step = 2 * FM_PI / SAMPLES;
    for (int m = 0; m < SAMPLES; m++) {
        xs[m] = r * cos(m * step);
        ys[m] = r * sin(m * step);
        zs[m] = z;
    }
    fm_eval_batch(ev, SAMPLES, xs, ys, zs, NULL, out);
    int b1 = 0, b2 = -1;
    for (int m = 1; m < SAMPLES; m++) {
        if (out[m] > out[b1]) {
            b2 = b1;
            b1 = m;
        } else if (b2 < 0 || out[m] > out[b2]) {
            b2 = m;
        }
    }
    double best = out[b1];
    const int refine[2] = {b1, b2};
    const double g = 0.5 * (sqrt(5.0) - 1);
    for (int q = 0; q < 2; q++) {
        if (refine[q] < 0) continue;
        double a = (refine[q] - 1) * step, b = (refine[q] + 1) * step;
        double x1 = b - g * (b - a), x2 = a + g * (b - a);
        double f1 = f_at(ev, r, x1, z), f2 = f_at(ev, r, x2, z);
        for (int s = 0; s < GOLDEN_STEPS; s++) {
            if (f1 > best) best = f1;
            if (f2 > best) best = f2;
            if (f1 >= f2) {
                b = x2;
                x2 = x1;
                f2 = f1;
                x1 = b - g * (b - a);
                f1 = f_at(ev, r, x1, z);
            } else {
                a = x1;
                x1 = x2;
                f1 = f2;
                x2 = a + g * (b - a);
                f2 = f_at(ev, r, x2, z);
            }
        }
        if (f1 > best) best = f1;
        if (f2 > best) best = f2;
    }
    return best;
}

enum { NODE_NONE = 0, NODE_INSIDE, NODE_OUTSIDE, NODE_SAMPLE };

static fm_status table_build(const fm_tape *tape, double R, double L, revolved_table **out, fm_error *err)
{
    fm_evaluator *ev = fm_evaluator_new(tape, err);
    if (!ev) return err ? err->code : FM_ERR_LIMIT;
    revolved_table *tb = calloc(1, sizeof *tb);
    double h = fmax(R, L) / TABLE_CELLS;
    unsigned char *state = NULL;
    fm_status st = FM_OK;
    if (!tb) goto oom;
    tb->R = R;
    tb->L = L;
    tb->nr = (int)ceil(R / h - 1e-9);
    tb->nz = (int)ceil(L / h - 1e-9);
    if (tb->nr < 1) tb->nr = 1;
    if (tb->nz < 1) tb->nz = 1;
    tb->hr = R / tb->nr;
    tb->hz = L / tb->nz;
    /* Both counts are at most TABLE_CELLS: a fixed size, whatever the model. */
    size_t W = (size_t)tb->nr + 1, H = (size_t)tb->nz + 1;
    tb->node = malloc(W * H * sizeof *tb->node);
    state = calloc(W * H, 1);
    if (!tb->node || !state) goto oom;

    /* Classify blocks by the model's interval over annular sectors. */
    for (int bj = 0; bj * BLOCK < tb->nz; bj++)
        for (int bi = 0; bi * BLOCK < tb->nr; bi++) {
            int i0 = bi * BLOCK, i1 = i0 + BLOCK < tb->nr ? i0 + BLOCK : tb->nr;
            int j0 = bj * BLOCK, j1 = j0 + BLOCK < tb->nz ? j0 + BLOCK : tb->nz;
            double r0 = i0 * tb->hr, r1 = i1 == tb->nr ? R : i1 * tb->hr;
            double z0 = j0 * tb->hz, z1 = j1 == tb->nz ? L : j1 * tb->hz;
            double best_lo = -DBL_MAX, worst_hi = -DBL_MAX;
            for (int s = 0; s < SECTORS; s++) {
                fm_interval box[4];
                sector_box(r0, r1, 2 * FM_PI * s / SECTORS, 2 * FM_PI * (s + 1) / SECTORS, z0, z1, box);
                fm_interval v = fm_eval_interval(ev, box);
                if (v.lo > best_lo) best_lo = v.lo;
                if (v.hi > worst_hi) worst_hi = v.hi;
            }
            /* Far from the surface a proven bound will do; within FAR_MM
             * of it every node holds the sampled maximum. */
            int kind = best_lo >= FAR_MM ? NODE_INSIDE : worst_hi <= -FAR_MM ? NODE_OUTSIDE : NODE_SAMPLE;
            for (int j = j0; j <= j1; j++)
                for (int i = i0; i <= i1; i++) {
                    size_t n = (size_t)j * W + (size_t)i;
                    if (state[n] == NODE_SAMPLE) continue;
                    if (kind == NODE_SAMPLE || (state[n] != NODE_NONE && state[n] != kind)) {
                        state[n] = NODE_SAMPLE; /* cannot be both: keep it safe anyway */
                    } else if (kind == NODE_INSIDE) {
                        /* the largest proven lower bound */
                        tb->node[n] = state[n] == NODE_NONE || best_lo > tb->node[n] ? best_lo : tb->node[n];
                        state[n] = NODE_INSIDE;
                    } else {
                        /* the smallest proven upper bound */
                        tb->node[n] = state[n] == NODE_NONE || worst_hi < tb->node[n] ? worst_hi : tb->node[n];
                        state[n] = NODE_OUTSIDE;
                    }
                }
        }
    for (size_t j = 0; j < H; j++)
        for (size_t i = 0; i < W; i++) {
            size_t n = j * W + i;
            double r = i == W - 1 ? R : (double)i * tb->hr, z = j == H - 1 ? L : (double)j * tb->hz;
            double v = state[n] == NODE_SAMPLE ? revolved_value(ev, r, z) : tb->node[n];
            if (!isfinite(v)) {
                st = fm_error_set(err, FM_ERR_INPUT,
                                  "custom cutter: the model is not finite at r = %g, z = %g mm", r, z);
                goto done;
            }
            /* clipped to the declared bound */
            v = fmin(v, fmin(R - r, fmin(z, L - z)));
            tb->node[n] = v;
        }

    /* The min / max pyramid: level 0 is the cells, each level halves. */
    int bw = tb->nr, bh = tb->nz;
    for (int k = 0; k < MAX_LEVELS; k++) {
        tb->bw[k] = bw;
        tb->bh[k] = bh;
        tb->lo[k] = malloc((size_t)bw * (size_t)bh * sizeof(double));
        tb->hi[k] = malloc((size_t)bw * (size_t)bh * sizeof(double));
        tb->levels = k + 1;
        if (!tb->lo[k] || !tb->hi[k]) goto oom;
        for (int j = 0; j < bh; j++)
            for (int i = 0; i < bw; i++) {
                double lo = DBL_MAX, hi = -DBL_MAX;
                for (int dj = 0; dj < 2; dj++)
                    for (int di = 0; di < 2; di++) {
                        double a, b;
                        if (k == 0) {
                            a = b = node_at(tb, i + di, j + dj);
                        } else {
                            int ci = 2 * i + di, cj = 2 * j + dj;
                            if (ci >= tb->bw[k - 1] || cj >= tb->bh[k - 1]) continue;
                            size_t c = (size_t)cj * (size_t)tb->bw[k - 1] + (size_t)ci;
                            a = tb->lo[k - 1][c];
                            b = tb->hi[k - 1][c];
                        }
                        if (a < lo) lo = a;
                        if (b > hi) hi = b;
                    }
                tb->lo[k][(size_t)j * (size_t)bw + (size_t)i] = lo;
                tb->hi[k][(size_t)j * (size_t)bw + (size_t)i] = hi;
            }
        if (bw == 1 && bh == 1) break;
        bw = (bw + 1) / 2;
        bh = (bh + 1) / 2;
    }
    goto done;
oom:
    st = fm_error_set(err, FM_ERR_LIMIT, "out of memory building a custom cutter's table");
done:
    free(state);
    fm_evaluator_free(ev);
    if (st != FM_OK) {
        table_free(tb);
        return st;
    }
    *out = tb;
    return FM_OK;
}

fm_status fm_tool_custom_from_tape(const fm_tape *tape, double bound_radius, double bound_length,
                                   fm_tool_custom *custom, fm_error *err)
{
    if (!tape) return fm_error_set(err, FM_ERR_INPUT, "custom cutter: no compiled model");
    if (!(bound_radius > 0) || !(bound_length > 0) || !isfinite(bound_radius) || !isfinite(bound_length))
        return fm_error_set(err, FM_ERR_INPUT,
                            "custom cutter: bounding radius (%g) and length (%g) must be positive",
                            bound_radius, bound_length);
    revolved_table *tb = NULL;
    fm_status st = table_build(tape, bound_radius, bound_length, &tb, err);
    if (st != FM_OK) return st;
    memset(custom, 0, sizeof *custom);
    custom->ctx = tb;
    custom->eval = table_eval;
    custom->interval = table_interval;
    custom->release = table_release;
    custom->bound_radius = bound_radius;
    custom->bound_length = bound_length;
    return FM_OK;
}

void fm_tool_custom_release(fm_tool_custom *custom)
{
    if (custom && custom->release && custom->ctx) custom->release(custom->ctx);
    if (custom) custom->ctx = NULL;
}
