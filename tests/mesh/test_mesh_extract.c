/* test_mesh_extract.c: meshes of lib/stock's level set. A box stock with a
 * cylindrical pocket cut: the whole-grid mesh is closed and outward
 * (edge check, volume against the analytic one), every vertex lies within
 * half a voxel of the exact solid's boundary (measured against a dense
 * sampling of that boundary built here), normals follow the faces; the
 * union of the per-chunk meshes, welded, is the whole-grid mesh triangle
 * for triangle, also after a cut remeshes only the dirty chunks; a sphere
 * field meshed directly sits on the sphere; chunks remeshed through their
 * cache (only the changed leaves) equal chunks meshed afresh. */
#include "fixtures.h"
#include "test.h"

#include "frep/frep.h"
#include "stock/stock.h"

#include <stdlib.h>

/* ------------------------------------------------ analytic test fields -- */

typedef struct cyl {
    double cx, cy, r, z0, z1;
} cyl;

/* Exact signed distance of a capped upright cylinder, positive inside. */
static double cyl_f(const cyl *c, double x, double y, double z)
{
    double dr = hypot(x - c->cx, y - c->cy) - c->r;
    double dz = fmax(c->z0 - z, z - c->z1);
    double out = hypot(fmax(dr, 0), fmax(dz, 0));
    double in = fmin(fmax(dr, dz), 0);
    return -(out + in);
}

typedef struct sph {
    double c[3], r;
} sph;

static double sph_f(const sph *s, double x, double y, double z)
{
    return s->r - sqrt(pow(x - s->c[0], 2) + pow(y - s->c[1], 2) + pow(z - s->c[2], 2));
}


static void cyl_batch(void *ctx, void *w, size_t n, const double *x, const double *y,
                      const double *z, double *out)
{
    (void)w;
    for (size_t i = 0; i < n; i++)
        out[i] = cyl_f(ctx, x[i], y[i], z[i]);
}

static void sph_batch(void *ctx, void *w, size_t n, const double *x, const double *y,
                      const double *z, double *out)
{
    (void)w;
    for (size_t i = 0; i < n; i++)
        out[i] = sph_f(ctx, x[i], y[i], z[i]);
}

/* Exact distances are 1-Lipschitz: centre value +- half diagonal is sound. */
static fm_interval lipschitz_interval(double v, const fm_interval box[3])
{
    double h = 0;
    for (int k = 0; k < 3; k++)
        h += pow(0.5 * (box[k].hi - box[k].lo), 2);
    h = sqrt(h);
    fm_interval r = {v - h, v + h};
    return r;
}

static fm_interval cyl_interval(void *ctx, void *w, const fm_interval box[3])
{
    (void)w;
    return lipschitz_interval(cyl_f(ctx, 0.5 * (box[0].lo + box[0].hi),
                                    0.5 * (box[1].lo + box[1].hi), 0.5 * (box[2].lo + box[2].hi)),
                              box);
}

static fm_interval sph_interval(void *ctx, void *w, const fm_interval box[3])
{
    (void)w;
    return lipschitz_interval(sph_f(ctx, 0.5 * (box[0].lo + box[0].hi),
                                    0.5 * (box[1].lo + box[1].hi), 0.5 * (box[2].lo + box[2].hi)),
                              box);
}

static fm_field cyl_field(cyl *c)
{
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = c;
    f.lo[0] = c->cx - c->r, f.lo[1] = c->cy - c->r, f.lo[2] = c->z0;
    f.hi[0] = c->cx + c->r, f.hi[1] = c->cy + c->r, f.hi[2] = c->z1;
    f.worker_new = NULL; /* no per-thread state (frep.h) */
    f.worker_free = NULL;
    f.batch = cyl_batch;
    f.interval = cyl_interval;
    return f;
}

/* ---------------------------------------- exact boundary, densely sampled -- */

/* Points on the boundary of box \ cylinder with spacing s, in a hash grid of
 * cell size g, so a vertex's distance to the nearest sample is an upper bound
 * of its distance to the true boundary plus at most s / sqrt 2. */
typedef struct samples {
    double g, lo[3];
    int n[3];
    size_t *start, *count; /* per cell, into pts */
    double *pts;
    size_t np;
} samples;

typedef struct ptlist {
    double *p;
    size_t n, cap;
} ptlist;

static void push(ptlist *l, double x, double y, double z)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 1 << 16;
        l->p = realloc(l->p, 3 * l->cap * sizeof(double));
    }
    l->p[3 * l->n] = x, l->p[3 * l->n + 1] = y, l->p[3 * l->n + 2] = z;
    l->n++;
}

static void sample_boundary(ptlist *l, const double lo[3], const double hi[3], const cyl *c,
                            double s)
{
    /* Box faces, where not inside the open cylinder. */
    for (int ax = 0; ax < 3; ax++)
        for (int side = 0; side < 2; side++) {
            int u = (ax + 1) % 3, v = (ax + 2) % 3;
            int nu = (int)ceil((hi[u] - lo[u]) / s), nv = (int)ceil((hi[v] - lo[v]) / s);
            for (int i = 0; i <= nu; i++)
                for (int j = 0; j <= nv; j++) {
                    double p[3];
                    p[ax] = side ? hi[ax] : lo[ax];
                    p[u] = lo[u] + (hi[u] - lo[u]) * i / nu;
                    p[v] = lo[v] + (hi[v] - lo[v]) * j / nv;
                    if (cyl_f(c, p[0], p[1], p[2]) <= 0)
                        push(l, p[0], p[1], p[2]);
                }
        }
    /* Cylinder wall and floor, where inside the box. */
    int na = (int)ceil(2 * FM_PI * c->r / s);
    int nz = (int)ceil((c->z1 - c->z0) / s);
    for (int a = 0; a < na; a++) {
        double t = 2 * FM_PI * a / na;
        for (int k = 0; k <= nz; k++) {
            double z = c->z0 + (c->z1 - c->z0) * k / nz;
            if (z <= hi[2])
                push(l, c->cx + c->r * cos(t), c->cy + c->r * sin(t), z);
        }
    }
    int nr = (int)ceil(c->r / s);
    for (int i = 0; i <= nr; i++) {
        double rr = c->r * i / nr;
        int m = i ? (int)ceil(2 * FM_PI * rr / s) : 1;
        for (int a = 0; a < m; a++) {
            double t = 2 * FM_PI * a / m;
            push(l, c->cx + rr * cos(t), c->cy + rr * sin(t), c->z0);
        }
    }
}

static int cell_of(const samples *S, const double *p, int k)
{
    int i = (int)floor((p[k] - S->lo[k]) / S->g);
    return i < 0 ? 0 : i >= S->n[k] ? S->n[k] - 1 : i;
}

static void samples_build(samples *S, ptlist *l, const double lo[3], const double hi[3], double g)
{
    S->g = g;
    for (int k = 0; k < 3; k++) {
        S->lo[k] = lo[k] - g;
        S->n[k] = (int)ceil((hi[k] - lo[k]) / g) + 3;
    }
    size_t cells = (size_t)S->n[0] * S->n[1] * S->n[2];
    S->start = calloc(cells + 1, sizeof(size_t));
    S->count = calloc(cells, sizeof(size_t));
    for (size_t i = 0; i < l->n; i++) {
        const double *p = l->p + 3 * i;
        S->count[((size_t)cell_of(S, p, 2) * S->n[1] + cell_of(S, p, 1)) * S->n[0] + cell_of(S, p, 0)]++;
    }
    for (size_t c = 0; c < cells; c++)
        S->start[c + 1] = S->start[c] + S->count[c];
    S->pts = malloc(3 * l->n * sizeof(double));
    memset(S->count, 0, cells * sizeof(size_t));
    for (size_t i = 0; i < l->n; i++) {
        const double *p = l->p + 3 * i;
        size_t c = ((size_t)cell_of(S, p, 2) * S->n[1] + cell_of(S, p, 1)) * S->n[0] + cell_of(S, p, 0);
        memcpy(S->pts + 3 * (S->start[c] + S->count[c]++), p, 3 * sizeof(double));
    }
    S->np = l->n;
}

/* Distance to the nearest sample within one cell ring (g must exceed the
 * distances of interest). */
static double samples_nearest(const samples *S, const double p[3])
{
    int c[3];
    for (int k = 0; k < 3; k++)
        c[k] = cell_of(S, p, k);
    double best = INFINITY;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                if (x < 0 || y < 0 || z < 0 || x >= S->n[0] || y >= S->n[1] || z >= S->n[2])
                    continue;
                size_t cell = ((size_t)z * S->n[1] + y) * S->n[0] + x;
                for (size_t i = S->start[cell]; i < S->start[cell] + S->count[cell]; i++) {
                    const double *q = S->pts + 3 * i;
                    double d = pow(q[0] - p[0], 2) + pow(q[1] - p[1], 2) + pow(q[2] - p[2], 2);
                    if (d < best)
                        best = d;
                }
            }
    return sqrt(best);
}

/* ------------------------------------------------------------- helpers -- */

static void check_closed(const fm_mesh *m, const char *what)
{
    fm_mesh_topology t;
    CHECK(fm_mesh_topology_check(m, &t, NULL) == FM_OK);
    CHECK(t.edges > 0);
    CHECK(t.boundary_edges == 0);
    CHECK(t.nonmanifold_edges == 0);
    CHECK(t.misoriented_edges == 0);
    CHECK(t.degenerate_triangles == 0);
    if (t.boundary_edges || t.nonmanifold_edges || t.misoriented_edges)
        fprintf(stderr, "%s: %zu boundary, %zu non-manifold, %zu misoriented of %zu edges\n",
                what, t.boundary_edges, t.nonmanifold_edges, t.misoriented_edges, t.edges);
}

typedef struct tri_key {
    float v[9];
} tri_key;

static int cmp_tri(const void *a, const void *b) { return memcmp(a, b, sizeof(tri_key)); }

/* The triangles as position triples, each rotated to start at its smallest
 * vertex (keeping orientation), sorted: equal lists mean equal meshes. */
static tri_key *tri_keys(const fm_mesh *m)
{
    tri_key *k = malloc((m->triangle_count + 1) * sizeof *k);
    for (size_t t = 0; t < m->triangle_count; t++) {
        const float *p[3];
        for (int i = 0; i < 3; i++)
            p[i] = m->positions + 3 * (size_t)m->triangles[3 * t + i];
        int s = 0;
        for (int i = 1; i < 3; i++)
            if (memcmp(p[i], p[s], 3 * sizeof(float)) < 0)
                s = i;
        for (int i = 0; i < 3; i++)
            memcpy(k[t].v + 3 * i, p[(s + i) % 3], 3 * sizeof(float));
    }
    qsort(k, m->triangle_count, sizeof *k, cmp_tri);
    return k;
}

/* How many triangles of a and b (the same count) differ, as sets. */
static size_t differing_triangles(const fm_mesh *a, const fm_mesh *b)
{
    tri_key *ka = tri_keys(a), *kb = tri_keys(b);
    size_t differ = 0;
    for (size_t t = 0; t < a->triangle_count; t++)
        differ += memcmp(ka + t, kb + t, sizeof *ka) != 0;
    free(ka);
    free(kb);
    return differ;
}

static void check_same_mesh(const fm_mesh *a, const fm_mesh *b)
{
    CHECK(a->triangle_count == b->triangle_count);
    CHECK(a->vertex_count == b->vertex_count);
    if (a->triangle_count != b->triangle_count) {
        fprintf(stderr, "triangles: %zu vs %zu\n", a->triangle_count, b->triangle_count);
        return;
    }
    size_t differ = differing_triangles(a, b);
    CHECK(differ == 0);
    if (differ)
        fprintf(stderr, "%zu of %zu triangles differ\n", differ, a->triangle_count);
}

/* Chunk meshes kept per chunk, as a viewer keeps them. */
typedef struct chunk_cache {
    int32_t index[64][3];
    fm_mesh *mesh[64];
    size_t n;
} chunk_cache;

static void cache_update(chunk_cache *c, fm_stock *s, uint64_t since,
                         const fm_mesh_extract_options *o, size_t *remeshed)
{
    fm_stock_chunk ch[64];
    size_t n = fm_stock_changed_chunks(s, since, ch, 64);
    CHECK(n <= 64);
    *remeshed = n;
    for (size_t i = 0; i < n && i < 64; i++) {
        fm_error err;
        fm_error_clear(&err);
        fm_mesh *m = fm_mesh_from_stock_chunk(s, ch[i].index, o, &err);
        CHECK(m != NULL);
        if (!m) {
            fprintf(stderr, "chunk: %s\n", err.message);
            continue;
        }
        size_t j = 0;
        while (j < c->n && memcmp(c->index[j], ch[i].index, sizeof ch[i].index) != 0)
            j++;
        if (j == c->n) {
            memcpy(c->index[j], ch[i].index, sizeof ch[i].index);
            c->mesh[j] = NULL;
            c->n++;
        }
        fm_mesh_free(c->mesh[j]);
        c->mesh[j] = m;
    }
}

static fm_mesh *cache_union(const chunk_cache *c)
{
    fm_mesh *u = fm_mesh_new(0, 0, FM_MESH_NORMALS, NULL, NULL);
    for (size_t j = 0; j < c->n; j++) {
        /* A chunk on its own is open at its seams (unless it holds a
         * whole closed piece), never non-manifold. */
        fm_mesh_topology t;
        fm_mesh_topology_check(c->mesh[j], &t, NULL);
        CHECK(t.nonmanifold_edges == 0 && t.misoriented_edges == 0);
        fm_mesh_append(u, c->mesh[j], NULL);
    }
    fm_mesh_weld(u, NULL);
    return u;
}

/* --------------------------------------------------------------- tests -- */

static void test_pocket(void)
{
    const double voxel = 0.2;
    const double lo[3] = {0, 0, 0}, hi[3] = {14, 13, 12};
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = voxel;
    fm_error err;
    fm_error_clear(&err);
    fm_stock *s = fm_stock_new_box(lo, hi, &so, &err);
    CHECK(s != NULL);
    if (!s) {
        fprintf(stderr, "stock: %s\n", err.message);
        return;
    }
    fm_mesh_extract_options o;
    fm_mesh_extract_default(&o);

    /* Chunks of the fresh box, kept for the incremental check below. */
    chunk_cache cache = {0};
    size_t remeshed = 0;
    cache_update(&cache, s, 0, &o, &remeshed);
    CHECK(remeshed == 8); /* 70 x 65 x 60 voxels: two chunks per axis */
    uint64_t v1 = fm_stock_version(s);

    /* A pocket of radius 3.1 through the top, floor at z = 7.3, centred off
     * the voxel lattice and across a chunk seam. */
    cyl c = {6.53, 6.71, 3.1, 7.3, 15};
    fm_field f = cyl_field(&c);
    CHECK(fm_stock_subtract(s, &f, NULL, NULL, &err) == FM_OK);

    fm_mesh *m = fm_mesh_from_stock(s, &o, &err);
    CHECK(m != NULL);
    if (!m) {
        fprintf(stderr, "mesh: %s\n", err.message);
        fm_stock_free(s);
        return;
    }
    check_closed(m, "pocket");
    double exact = 14.0 * 13 * 12 - FM_PI * c.r * c.r * (12 - c.z0);
    CHECK_NEAR(fm_mesh_volume(m), exact, 0.005 * exact);

    /* Every vertex within half a voxel of the exact boundary. */
    ptlist l = {0};
    const double spacing = voxel / 8;
    sample_boundary(&l, lo, hi, &c, spacing);
    samples S;
    samples_build(&S, &l, lo, hi, voxel);
    double worst = 0;
    for (size_t i = 0; i < m->vertex_count; i++) {
        double p[3] = {m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]};
        worst = fmax(worst, samples_nearest(&S, p));
    }
    /* The nearest sample overestimates the distance by at most
     * spacing / sqrt 2, so this bound on it is a bound on the distance. */
    CHECK(worst <= 0.5 * voxel);
    printf("pocket: %zu vertices, %zu triangles, worst distance %.4f mm (half voxel %.3f)\n",
           m->vertex_count, m->triangle_count, worst, 0.5 * voxel);

    /* Normals: flat faces away from edges point along their axis; the
     * pocket wall points to the axis (out of the solid, into the pocket). */
    size_t top = 0, wall = 0;
    for (size_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * i, *n = m->normals + 3 * i;
        double rr = hypot(p[0] - c.cx, p[1] - c.cy);
        int away = p[0] > 1 && p[0] < 13 && p[1] > 1 && p[1] < 12;
        if (away && fabs(p[2] - 12) < 0.05 && rr > c.r + 1) {
            CHECK(n[2] > 0.999f);
            top++;
        }
        if (fabs(rr - c.r) < 0.1 && p[2] > c.z0 + 1 && p[2] < 11) {
            double in = -((p[0] - c.cx) * n[0] + (p[1] - c.cy) * n[1]) / rr;
            CHECK(in > 0.99);
            wall++;
        }
    }
    CHECK(top > 100 && wall > 100);

    /* Depth colours: the top is the ramp's zero, the floor its depth. */
    fm_mesh_extract_options oc = o;
    oc.coloring = FM_MESH_COLOR_DEPTH;
    oc.top_z = 12;
    oc.depth_range = 5;
    fm_mesh *mc = fm_mesh_from_stock(s, &oc, &err);
    CHECK(mc && mc->colors);
    for (size_t i = 0; mc && i < mc->vertex_count; i++) {
        uint8_t want[3];
        fm_mesh_depth_color(12 - mc->positions[3 * i + 2], 5, want);
        CHECK(memcmp(want, mc->colors + 3 * i, 3) == 0);
    }
    uint8_t top_rgb[3], floor_rgb[3];
    fm_mesh_depth_color(0, 5, top_rgb);
    fm_mesh_depth_color(12 - c.z0, 5, floor_rgb);
    CHECK(memcmp(top_rgb, floor_rgb, 3) != 0);
    fm_mesh_free(mc);
    oc.depth_range = 0; /* the ramp needs a positive range */
    CHECK(fm_mesh_from_stock(s, &oc, &err) == NULL && err.code == FM_ERR_INPUT);

    /* Chunks: only the dirty ones are remeshed, and the union of the kept
     * chunk meshes, welded, is the whole-grid mesh. */
    cache_update(&cache, s, v1, &o, &remeshed);
    CHECK(remeshed >= 1 && remeshed < 8);
    printf("pocket cut: %zu of %zu chunks remeshed\n", remeshed, cache.n);
    fm_mesh *u = cache_union(&cache);
    check_closed(u, "chunk union");
    fm_mesh_weld(m, NULL);
    check_same_mesh(u, m);
    fm_mesh_free(u);

    /* Adaptivity reduces the whole-grid mesh and keeps it closed. */
    fm_mesh_extract_options oa = o;
    oa.adaptivity = 0.5;
    fm_mesh *ma = fm_mesh_from_stock(s, &oa, &err);
    CHECK(ma && ma->triangle_count < m->triangle_count / 2);
    if (ma) {
        fm_mesh_topology t;
        fm_mesh_topology_check(ma, &t, NULL);
        CHECK(t.misoriented_edges == 0);
        CHECK_NEAR(fm_mesh_volume(ma), exact, 0.01 * exact);
    }
    fm_mesh_free(ma);
    oa.adaptivity = 2;
    CHECK(fm_mesh_from_stock(s, &oa, &err) == NULL && err.code == FM_ERR_INPUT);

    /* A budget too small for the mesh is refused. */
    fm_mesh_extract_options ob = o;
    ob.budget.max_vertices = 1000;
    CHECK(fm_mesh_from_stock(s, &ob, &err) == NULL && err.code == FM_ERR_LIMIT);

    /* A chunk far away has no surface: an empty mesh. */
    int32_t far[3] = {50, 50, 50};
    fm_mesh *e = fm_mesh_from_stock_chunk(s, far, &o, &err);
    CHECK(e && e->triangle_count == 0);
    fm_mesh_free(e);

    for (size_t j = 0; j < cache.n; j++)
        fm_mesh_free(cache.mesh[j]);
    free(S.start);
    free(S.count);
    free(S.pts);
    free(l.p);
    fm_mesh_free(m);
    fm_stock_free(s);
}

/* A mesh's referenced vertices (position, normal, colour), sorted by
 * position, without repeats: equal lists mean equal vertex attributes. */
typedef struct vert_key {
    float p[3], n[3];
    uint8_t c[3];
} vert_key;

static int cmp_vert(const void *a, const void *b) { return memcmp(a, b, sizeof(float[3])); }

static vert_key *vert_keys(const fm_mesh *m, size_t *count)
{
    vert_key *k = calloc(3 * m->triangle_count + 1, sizeof *k);
    for (size_t t = 0; t < 3 * m->triangle_count; t++) {
        const uint32_t v = m->triangles[t];
        memcpy(k[t].p, m->positions + 3 * (size_t)v, sizeof k[t].p);
        if (m->normals)
            memcpy(k[t].n, m->normals + 3 * (size_t)v, sizeof k[t].n);
        if (m->colors)
            memcpy(k[t].c, m->colors + 3 * (size_t)v, sizeof k[t].c);
    }
    qsort(k, 3 * m->triangle_count, sizeof *k, cmp_vert);
    size_t n = 0;
    for (size_t t = 0; t < 3 * m->triangle_count; t++)
        if (n == 0 || memcmp(k[n - 1].p, k[t].p, sizeof k[t].p) != 0)
            k[n++] = k[t];
    *count = n;
    return k;
}

/* The cached chunk mesh against a fresh one: the same triangles, and each
 * vertex position the same normal and colour. */
static void check_same_chunk(const fm_mesh *cached, const fm_mesh *fresh)
{
    CHECK(cached->triangle_count == fresh->triangle_count);
    if (cached->triangle_count != fresh->triangle_count) {
        fprintf(stderr, "chunk triangles: %zu cached vs %zu fresh\n", cached->triangle_count,
                fresh->triangle_count);
        return;
    }
    size_t differ = differing_triangles(cached, fresh);
    CHECK(differ == 0);
    size_t na = 0, nb = 0;
    vert_key *va = vert_keys(cached, &na), *vb = vert_keys(fresh, &nb);
    CHECK(na == nb);
    size_t vdiffer = 0;
    for (size_t i = 0; i < na && i < nb; i++)
        vdiffer += memcmp(va[i].p, vb[i].p, sizeof va[i].p) != 0 ||
                   memcmp(va[i].n, vb[i].n, sizeof va[i].n) != 0 ||
                   memcmp(va[i].c, vb[i].c, sizeof va[i].c) != 0;
    CHECK(vdiffer == 0);
    if (differ || vdiffer)
        fprintf(stderr, "cached chunk: %zu of %zu triangles, %zu of %zu vertices differ\n", differ,
                cached->triangle_count, vdiffer, na);
    free(va);
    free(vb);
}

/* fm_mesh_from_stock_chunk_cached after each of a row of plunges (a tool
 * moving 0.5 mm at a time across chunk seams, two tools for the colours):
 * every chunk's cached mesh equals the chunk meshed afresh (triangles,
 * normals, tool colours), a cut remeshes only part of a chunk's leaves, an
 * unchanged chunk none, and the union of the cached chunks is the whole
 * grid's closed mesh. */
static void test_chunk_cache(void)
{
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = 0.1;
    fm_error err;
    fm_error_clear(&err);
    const double lo[3] = {0, 0, 0}, hi[3] = {10, 9, 4};
    fm_stock *s = fm_stock_new_box(lo, hi, &so, &err);
    CHECK(s != NULL);
    if (!s)
        return;
    fm_mesh_extract_options o;
    fm_mesh_extract_default(&o);
    o.coloring = FM_MESH_COLOR_TOOL;
    enum { N = 16 };
    fm_stock_chunk all[N];
    size_t n = fm_stock_changed_chunks(s, 0, all, N);
    CHECK(n == 4); /* 100 x 90 x 40 voxels: 2 x 2 x 1 chunks */
    if (n > N)
        n = N;
    fm_mesh_chunk_cache *cache[N];
    fm_mesh *kept[N];
    for (size_t i = 0; i < n; i++) {
        cache[i] = fm_mesh_chunk_cache_new();
        CHECK(cache[i] != NULL);
        kept[i] = fm_mesh_from_stock_chunk_cached(s, all[i].index, &o, cache[i], &err);
        CHECK(kept[i] != NULL);
        CHECK(fm_mesh_chunk_cache_last_leaves(cache[i]) == 512);
    }
    size_t partial = 0, reused = 0, calls = 0, unmarked_partial = 0;
    for (int m = 0; m < 12; m++) {
        uint64_t since = fm_stock_version(s);
        cyl c = {2.03 + 0.5 * m, 5.77, 1.5, 3.0, 6};
        fm_field f = cyl_field(&c);
        fm_stock_cut cut = {1 + m % 2, -1, m, m + 1};
        CHECK(fm_stock_subtract(s, &f, &cut, NULL, &err) == FM_OK);
        fm_stock_chunk ch[N];
        size_t nc = fm_stock_changed_chunks(s, since, ch, N);
        CHECK(nc >= 1 && nc <= n);
        /* every chunk, changed or not, through its cache */
        for (size_t i = 0; i < n; i++) {
            int changed = 0;
            for (size_t k = 0; k < nc && k < N; k++)
                changed |= !memcmp(ch[k].index, all[i].index, sizeof all[i].index);
            fm_mesh *cm = fm_mesh_from_stock_chunk_cached(s, all[i].index, &o, cache[i], &err);
            fm_mesh *fm = fm_mesh_from_stock_chunk(s, all[i].index, &o, &err);
            CHECK(cm != NULL && fm != NULL);
            const size_t leaves = fm_mesh_chunk_cache_last_leaves(cache[i]);
            calls++;
            partial += leaves > 0 && leaves < 512;
            unmarked_partial += !changed && leaves > 0;
            reused += leaves == 0;
            if (cm && fm)
                check_same_chunk(cm, fm);
            fm_mesh_free(fm);
            fm_mesh_free(kept[i]);
            kept[i] = cm;
        }
    }
    printf("chunk cache: %zu of %zu chunk meshings partial (%zu of them in chunks the stock did "
           "not mark), %zu reused whole\n",
           partial, calls, unmarked_partial, reused);
    CHECK(partial >= 12);
    CHECK(reused >= 1);
    /* A chunk whose mesh changed is one the stock marked: its own leaves or
     * a neighbour's within the two voxels its faces and normals read. */
    CHECK(unmarked_partial == 0);
    /* Nothing cut since: every chunk comes from its cache as it was. */
    for (size_t i = 0; i < n; i++) {
        fm_mesh *again = fm_mesh_from_stock_chunk_cached(s, all[i].index, &o, cache[i], &err);
        CHECK(again != NULL && fm_mesh_chunk_cache_last_leaves(cache[i]) == 0);
        if (again && kept[i])
            check_same_chunk(again, kept[i]);
        fm_mesh_free(again);
    }

    /* The union of the cached chunks is the whole grid's mesh. */
    fm_mesh *u = fm_mesh_new(0, 0, FM_MESH_NORMALS | FM_MESH_COLORS, NULL, NULL);
    for (size_t i = 0; i < n; i++)
        if (kept[i])
            fm_mesh_append(u, kept[i], NULL);
    fm_mesh_weld(u, NULL);
    check_closed(u, "cached chunk union");
    fm_mesh *w = fm_mesh_from_stock(s, &o, &err);
    CHECK(w != NULL);
    if (w) {
        fm_mesh_weld(w, NULL);
        check_same_mesh(u, w);
    }
    fm_mesh_free(w);
    fm_mesh_free(u);

    /* Other options mesh the chunk whole again. */
    fm_mesh_extract_options on = o;
    on.coloring = FM_MESH_COLOR_NONE;
    fm_mesh *cm = fm_mesh_from_stock_chunk_cached(s, all[0].index, &on, cache[0], &err);
    CHECK(cm && !cm->colors);
    CHECK(fm_mesh_chunk_cache_last_leaves(cache[0]) == 512);
    fm_mesh_free(cm);
    for (size_t i = 0; i < n; i++) {
        fm_mesh_free(kept[i]);
        fm_mesh_chunk_cache_free(cache[i]);
    }
    fm_stock_free(s);
}

static void test_field_sphere(void)
{
    sph sp = {{1.3, -2.2, 0.7}, 4.0};
    fm_field f;
    memset(&f, 0, sizeof f);
    f.ctx = &sp;
    for (int k = 0; k < 3; k++) {
        f.lo[k] = sp.c[k] - sp.r;
        f.hi[k] = sp.c[k] + sp.r;
    }
    f.worker_new = NULL; /* no per-thread state (frep.h) */
    f.worker_free = NULL;
    f.batch = sph_batch;
    f.interval = sph_interval;
    const double voxel = 0.1;
    fm_error err;
    fm_error_clear(&err);
    fm_mesh *m = fm_mesh_from_field(&f, voxel, NULL, &err);
    CHECK(m != NULL);
    if (!m) {
        fprintf(stderr, "field: %s\n", err.message);
        return;
    }
    check_closed(m, "sphere");
    CHECK_NEAR(fm_mesh_volume(m), 4.0 / 3 * FM_PI * pow(sp.r, 3), 0.005 * 4.0 / 3 * FM_PI * pow(sp.r, 3));
    double worst = 0, worst_n = 0;
    for (size_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * i, *n = m->normals + 3 * i;
        double d[3] = {p[0] - sp.c[0], p[1] - sp.c[1], p[2] - sp.c[2]};
        double r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        worst = fmax(worst, fabs(r - sp.r));
        double cosang = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / r;
        worst_n = fmax(worst_n, acos(fmin(1.0, cosang)));
    }
    CHECK(worst <= 0.5 * voxel);
    CHECK(worst_n < 3.0 * FM_PI / 180);
    printf("sphere: %zu vertices, worst radial error %.4f mm, worst normal %.2f deg\n",
           m->vertex_count, worst, worst_n * 180 / FM_PI);
    CHECK(fm_mesh_from_field(&f, 0, NULL, &err) == NULL && err.code == FM_ERR_INPUT);
    fm_mesh_free(m);
}

int main(void)
{
    test_pocket();
    test_field_sphere();
    test_chunk_cache();
    return test_summary("mesh_extract");
}
