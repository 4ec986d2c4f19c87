/* thin.c: material thinner than a voxel, grouped into places to report
 * (fm_stock_thin_material). vdb_thin.cpp finds the voxels; here they are
 * sorted, joined into 26-connected regions with a union-find, and the
 * largest regions described in millimetres. */
#include "stock/stock_impl.h"

#include <stdlib.h>
#include <string.h>

typedef struct thin_voxel {
    int32_t c[3];
} thin_voxel;

static int voxel_cmp(const void *a, const void *b)
{
    const int32_t *p = ((const thin_voxel *)a)->c, *q = ((const thin_voxel *)b)->c;
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
    return 0;
}

static size_t find_root(size_t *parent, size_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

typedef struct thin_acc {
    size_t voxels;
    double sum[3];
    int32_t lo[3], hi[3];
    size_t nearest;  /* voxel index nearest the centroid (second pass) */
    double best_d2;
    int wall;
} thin_acc;

/* A sheet rather than a line: see stock.h. */
static int is_wall(const thin_acc *r)
{
    int64_t side[3];
    for (int k = 0; k < 3; k++) side[k] = (int64_t)r->hi[k] - r->lo[k] + 1;
    int64_t longest = side[0], second = 0;
    for (int k = 1; k < 3; k++) {
        if (side[k] > longest) second = longest, longest = side[k];
        else if (side[k] > second) second = side[k];
    }
    return second >= 4 && (int64_t)r->voxels >= 4 * longest;
}

static int acc_cmp(const void *a, const void *b)
{
    const thin_acc *p = a, *q = b;
    if (p->wall != q->wall) return p->wall ? -1 : 1;
    if (p->voxels != q->voxels) return p->voxels > q->voxels ? -1 : 1;
    /* ties in a fixed order, whatever order the threads found them */
    for (int k = 0; k < 3; k++)
        if (p->lo[k] != q->lo[k]) return p->lo[k] < q->lo[k] ? -1 : 1;
    return 0;
}

fm_status fm_stock_thin_material(const fm_stock *s, fm_stock_thin_report *report, fm_error *err)
{
    memset(report, 0, sizeof *report);
    int32_t *ijk = NULL;
    size_t n = 0, total = 0;
    fm_status st = fm_vdb_thin_voxels(s->vdb, FM_STOCK_THIN_MAX_VOXELS, &ijk, &n, &total, err);
    if (st != FM_OK) return st;
    report->voxels = total;
    report->truncated = total > n;
    if (!n) {
        free(ijk);
        return FM_OK;
    }
    thin_voxel *v = (thin_voxel *)ijk; /* 3 int32 per voxel, the same layout */
    qsort(v, n, sizeof *v, voxel_cmp);
    size_t *parent = malloc(n * sizeof *parent);
    thin_acc *acc = calloc(n, sizeof *acc);
    if (!parent || !acc) {
        free(parent);
        free(acc);
        free(ijk);
        return fm_error_set(err, FM_ERR_LIMIT, "thin material: out of memory");
    }
    for (size_t i = 0; i < n; i++) parent[i] = i;
    /* join each voxel with its 13 neighbours that sort after it */
    for (size_t i = 0; i < n; i++)
        for (int dx = 0; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dz = -1; dz <= 1; dz++) {
                    if (dx == 0 && (dy < 0 || (dy == 0 && dz <= 0))) continue;
                    thin_voxel key = {{v[i].c[0] + dx, v[i].c[1] + dy, v[i].c[2] + dz}};
                    const thin_voxel *hit = bsearch(&key, v, n, sizeof *v, voxel_cmp);
                    if (!hit) continue;
                    size_t a = find_root(parent, i), b = find_root(parent, (size_t)(hit - v));
                    if (a != b) parent[a < b ? b : a] = a < b ? a : b;
                }
    for (size_t i = 0; i < n; i++) {
        thin_acc *r = &acc[find_root(parent, i)];
        if (!r->voxels) {
            memcpy(r->lo, v[i].c, sizeof r->lo);
            memcpy(r->hi, v[i].c, sizeof r->hi);
            r->best_d2 = -1;
        }
        r->voxels++;
        for (int k = 0; k < 3; k++) {
            r->sum[k] += v[i].c[k];
            if (v[i].c[k] < r->lo[k]) r->lo[k] = v[i].c[k];
            if (v[i].c[k] > r->hi[k]) r->hi[k] = v[i].c[k];
        }
    }
    for (size_t i = 0; i < n; i++) {
        thin_acc *r = &acc[find_root(parent, i)];
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            const double d = v[i].c[k] - r->sum[k] / (double)r->voxels;
            d2 += d * d;
        }
        if (r->best_d2 < 0 || d2 < r->best_d2) r->best_d2 = d2, r->nearest = i;
    }
    /* the roots' records first, then the largest of them */
    size_t roots = 0;
    for (size_t i = 0; i < n; i++)
        if (parent[i] == i) {
            acc[roots] = acc[i];
            acc[roots].wall = is_wall(&acc[roots]);
            report->walls += (size_t)acc[roots].wall;
            roots++;
        }
    report->regions = roots;
    qsort(acc, roots, sizeof *acc, acc_cmp);
    for (size_t r = 0; r < roots && r < FM_STOCK_THIN_MAX_REGIONS; r++) {
        fm_stock_thin_region *out = &report->region[report->count++];
        double ijk_d[3];
        out->voxels = acc[r].voxels;
        out->wall = acc[r].wall;
        for (int k = 0; k < 3; k++) ijk_d[k] = v[acc[r].nearest].c[k];
        fm_stock_index_to_world(s, ijk_d, out->position);
        for (int k = 0; k < 3; k++) ijk_d[k] = acc[r].lo[k];
        fm_stock_index_to_world(s, ijk_d, out->lo);
        for (int k = 0; k < 3; k++) ijk_d[k] = acc[r].hi[k];
        fm_stock_index_to_world(s, ijk_d, out->hi);
    }
    free(parent);
    free(acc);
    free(ijk);
    return FM_OK;
}
