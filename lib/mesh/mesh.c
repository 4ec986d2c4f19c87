/* mesh.c: the fm_mesh container: allocation under a budget, appending,
 * welding, normals, bounds, enclosed volume and the edge-topology check
 * that proves a mesh closed and consistently oriented. */
#include "mesh/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void budget_or_default(const fm_mesh_budget *in, fm_mesh_budget *out)
{
    out->max_vertices = in && in->max_vertices ? in->max_vertices : FM_MESH_DEFAULT_MAX_VERTICES;
    out->max_triangles =
        in && in->max_triangles ? in->max_triangles : FM_MESH_DEFAULT_MAX_TRIANGLES;
    /* Triangle indices are uint32: never allow more vertices than they address. */
    if (out->max_vertices > UINT32_MAX)
        out->max_vertices = UINT32_MAX;
}

fm_mesh *fm_mesh_new(size_t vertices, size_t triangles, unsigned attributes,
                     const fm_mesh_budget *budget, fm_error *err)
{
    fm_mesh *m = calloc(1, sizeof *m);
    if (!m) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory for a mesh");
        return NULL;
    }
    budget_or_default(budget, &m->budget);
    /* Allocate at least one element so that attribute presence is a
     * non-NULL pointer even for an empty mesh. */
    if (attributes & FM_MESH_NORMALS)
        m->normals = malloc(3 * sizeof(float));
    if (attributes & FM_MESH_COLORS)
        m->colors = malloc(3);
    m->positions = malloc(3 * sizeof(float));
    m->triangles = malloc(3 * sizeof(uint32_t));
    if (!m->positions || !m->triangles || ((attributes & FM_MESH_NORMALS) && !m->normals) ||
        ((attributes & FM_MESH_COLORS) && !m->colors)) {
        fm_mesh_free(m);
        fm_error_set(err, FM_ERR_LIMIT, "out of memory for a mesh");
        return NULL;
    }
    m->vertex_capacity = 1;
    m->triangle_capacity = 1;
    if (fm_mesh_reserve(m, vertices, triangles, err) != FM_OK) {
        fm_mesh_free(m);
        return NULL;
    }
    return m;
}

void fm_mesh_free(fm_mesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->colors);
    free(mesh->triangles);
    free(mesh);
}

static fm_status grow(void **p, size_t count, size_t elem, fm_error *err)
{
    size_t bytes;
    if (!fm_size_mul(count, elem, &bytes))
        return fm_error_set(err, FM_ERR_LIMIT, "mesh size overflows");
    void *q = realloc(*p, bytes ? bytes : 1);
    if (!q)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for a mesh of %zu bytes", bytes);
    *p = q;
    return FM_OK;
}

fm_status fm_mesh_reserve(fm_mesh *mesh, size_t vertices, size_t triangles, fm_error *err)
{
    if (vertices > mesh->budget.max_vertices)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "mesh needs %zu vertices, over the budget of %zu; use a coarser "
                            "voxel or a larger budget",
                            vertices, mesh->budget.max_vertices);
    if (triangles > mesh->budget.max_triangles)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "mesh needs %zu triangles, over the budget of %zu; use a coarser "
                            "voxel or a larger budget",
                            triangles, mesh->budget.max_triangles);
    if (vertices > mesh->vertex_capacity) {
        size_t cap = mesh->vertex_capacity * 2 > vertices ? mesh->vertex_capacity * 2 : vertices;
        if (cap > mesh->budget.max_vertices)
            cap = mesh->budget.max_vertices;
        if (grow((void **)&mesh->positions, cap, 3 * sizeof(float), err) != FM_OK)
            return err ? err->code : FM_ERR_LIMIT;
        if (mesh->normals && grow((void **)&mesh->normals, cap, 3 * sizeof(float), err) != FM_OK)
            return err ? err->code : FM_ERR_LIMIT;
        if (mesh->colors && grow((void **)&mesh->colors, cap, 3, err) != FM_OK)
            return err ? err->code : FM_ERR_LIMIT;
        mesh->vertex_capacity = cap;
    }
    if (triangles > mesh->triangle_capacity) {
        size_t cap =
            mesh->triangle_capacity * 2 > triangles ? mesh->triangle_capacity * 2 : triangles;
        if (cap > mesh->budget.max_triangles)
            cap = mesh->budget.max_triangles;
        if (grow((void **)&mesh->triangles, cap, 3 * sizeof(uint32_t), err) != FM_OK)
            return err ? err->code : FM_ERR_LIMIT;
        mesh->triangle_capacity = cap;
    }
    return FM_OK;
}

size_t fm_mesh_add_vertex(fm_mesh *mesh, const float p[3], const float normal[3],
                          const uint8_t rgb[3], fm_error *err)
{
    size_t i = mesh->vertex_count;
    if (fm_mesh_reserve(mesh, i + 1, mesh->triangle_count, err) != FM_OK)
        return (size_t)-1;
    memcpy(mesh->positions + 3 * i, p, 3 * sizeof(float));
    if (mesh->normals) {
        if (normal)
            memcpy(mesh->normals + 3 * i, normal, 3 * sizeof(float));
        else
            memset(mesh->normals + 3 * i, 0, 3 * sizeof(float));
    }
    if (mesh->colors) {
        if (rgb)
            memcpy(mesh->colors + 3 * i, rgb, 3);
        else
            memset(mesh->colors + 3 * i, 0, 3);
    }
    mesh->vertex_count = i + 1;
    return i;
}

size_t fm_mesh_add_triangle(fm_mesh *mesh, uint32_t a, uint32_t b, uint32_t c, fm_error *err)
{
    size_t i = mesh->triangle_count;
    if (a >= mesh->vertex_count || b >= mesh->vertex_count || c >= mesh->vertex_count) {
        fm_error_set(err, FM_ERR_INTERNAL, "triangle refers to a vertex that does not exist");
        return (size_t)-1;
    }
    if (fm_mesh_reserve(mesh, mesh->vertex_count, i + 1, err) != FM_OK)
        return (size_t)-1;
    mesh->triangles[3 * i] = a;
    mesh->triangles[3 * i + 1] = b;
    mesh->triangles[3 * i + 2] = c;
    mesh->triangle_count = i + 1;
    return i;
}

fm_status fm_mesh_append(fm_mesh *dst, const fm_mesh *src, fm_error *err)
{
    size_t nv, nt;
    if (!fm_size_add(dst->vertex_count, src->vertex_count, &nv) ||
        !fm_size_add(dst->triangle_count, src->triangle_count, &nt))
        return fm_error_set(err, FM_ERR_LIMIT, "mesh size overflows");
    fm_status st = fm_mesh_reserve(dst, nv, nt, err);
    if (st != FM_OK)
        return st;
    size_t v0 = dst->vertex_count;
    memcpy(dst->positions + 3 * v0, src->positions, 3 * sizeof(float) * src->vertex_count);
    if (dst->normals) {
        if (src->normals)
            memcpy(dst->normals + 3 * v0, src->normals, 3 * sizeof(float) * src->vertex_count);
        else
            memset(dst->normals + 3 * v0, 0, 3 * sizeof(float) * src->vertex_count);
    }
    if (dst->colors) {
        if (src->colors)
            memcpy(dst->colors + 3 * v0, src->colors, 3 * src->vertex_count);
        else
            memset(dst->colors + 3 * v0, 0, 3 * src->vertex_count);
    }
    uint32_t *t = dst->triangles + 3 * dst->triangle_count;
    for (size_t i = 0; i < 3 * src->triangle_count; i++)
        t[i] = src->triangles[i] + (uint32_t)v0;
    dst->vertex_count = nv;
    dst->triangle_count = nt;
    return FM_OK;
}

static void face_normal(const fm_mesh *m, size_t t, double n[3])
{
    const float *a = m->positions + 3 * m->triangles[3 * t];
    const float *b = m->positions + 3 * m->triangles[3 * t + 1];
    const float *c = m->positions + 3 * m->triangles[3 * t + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

fm_status fm_mesh_compute_normals(fm_mesh *mesh, fm_error *err)
{
    if (!mesh->normals) {
        mesh->normals = malloc(3 * sizeof(float) * (mesh->vertex_capacity ? mesh->vertex_capacity : 1));
        if (!mesh->normals)
            return fm_error_set(err, FM_ERR_LIMIT, "out of memory for mesh normals");
    }
    double *acc = calloc(3 * (mesh->vertex_count ? mesh->vertex_count : 1), sizeof(double));
    if (!acc)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for mesh normals");
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        double n[3];
        /* The cross product's length is twice the area: area weighting for free. */
        face_normal(mesh, t, n);
        for (int k = 0; k < 3; k++) {
            double *a = acc + 3 * mesh->triangles[3 * t + k];
            a[0] += n[0];
            a[1] += n[1];
            a[2] += n[2];
        }
    }
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        double *a = acc + 3 * i;
        double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int k = 0; k < 3; k++)
            mesh->normals[3 * i + k] = len > 0 ? (float)(a[k] / len) : 0.0f;
    }
    free(acc);
    return FM_OK;
}

/* Open-addressing hash of vertex positions by their bit patterns, so that
 * welding is exact: only vertices computed identically merge. */
static uint64_t hash_position(const float *p)
{
    uint32_t b[3];
    memcpy(b, p, sizeof b);
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    for (int k = 0; k < 3; k++) {
        h ^= b[k];
        h *= 0xff51afd7ed558ccdULL;
        h ^= h >> 33;
    }
    return h;
}

fm_status fm_mesh_weld(fm_mesh *mesh, fm_error *err)
{
    size_t n = mesh->vertex_count;
    if (n == 0)
        return FM_OK;
    size_t cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    uint32_t *table = malloc(cap * sizeof *table);
    uint32_t *remap = malloc(n * sizeof *remap);
    if (!table || !remap) {
        free(table);
        free(remap);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory welding a mesh");
    }
    memset(table, 0xff, cap * sizeof *table);
    size_t kept = 0;
    for (size_t i = 0; i < n; i++) {
        const float *p = mesh->positions + 3 * i;
        size_t slot = (size_t)hash_position(p) & (cap - 1);
        for (;;) {
            uint32_t j = table[slot];
            if (j == UINT32_MAX) {
                /* New position: compact it down to index kept. */
                table[slot] = (uint32_t)kept;
                if (kept != i) {
                    memmove(mesh->positions + 3 * kept, p, 3 * sizeof(float));
                    if (mesh->normals)
                        memmove(mesh->normals + 3 * kept, mesh->normals + 3 * i,
                                3 * sizeof(float));
                    if (mesh->colors)
                        memmove(mesh->colors + 3 * kept, mesh->colors + 3 * i, 3);
                }
                remap[i] = (uint32_t)kept++;
                break;
            }
            if (memcmp(mesh->positions + 3 * (size_t)j, p, 3 * sizeof(float)) == 0) {
                remap[i] = j;
                break;
            }
            slot = (slot + 1) & (cap - 1);
        }
    }
    size_t nt = 0;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        uint32_t a = remap[mesh->triangles[3 * t]];
        uint32_t b = remap[mesh->triangles[3 * t + 1]];
        uint32_t c = remap[mesh->triangles[3 * t + 2]];
        if (a == b || b == c || a == c)
            continue;
        mesh->triangles[3 * nt] = a;
        mesh->triangles[3 * nt + 1] = b;
        mesh->triangles[3 * nt + 2] = c;
        nt++;
    }
    mesh->vertex_count = kept;
    mesh->triangle_count = nt;
    free(table);
    free(remap);
    return FM_OK;
}

int fm_mesh_bounds(const fm_mesh *mesh, float lo[3], float hi[3])
{
    if (mesh->vertex_count == 0)
        return 0;
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = mesh->positions[k];
    for (size_t i = 1; i < mesh->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            float v = mesh->positions[3 * i + k];
            if (v < lo[k])
                lo[k] = v;
            if (v > hi[k])
                hi[k] = v;
        }
    return 1;
}

double fm_mesh_volume(const fm_mesh *mesh)
{
    /* Divergence theorem: sum of signed tetrahedra against the origin,
     * taken relative to the first vertex to keep the rounding small. */
    if (mesh->vertex_count == 0)
        return 0.0;
    const float *o = mesh->positions;
    double v = 0.0;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const float *a = mesh->positions + 3 * mesh->triangles[3 * t];
        const float *b = mesh->positions + 3 * mesh->triangles[3 * t + 1];
        const float *c = mesh->positions + 3 * mesh->triangles[3 * t + 2];
        double ax = a[0] - o[0], ay = a[1] - o[1], az = a[2] - o[2];
        double bx = b[0] - o[0], by = b[1] - o[1], bz = b[2] - o[2];
        double cx = c[0] - o[0], cy = c[1] - o[1], cz = c[2] - o[2];
        v += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    }
    return v / 6.0;
}

typedef struct edge_rec {
    uint64_t key;   /* (min << 32) | max */
    uint32_t count; /* triangles using the edge */
    int32_t dir;    /* sum of +1 for min->max, -1 for max->min */
} edge_rec;

static int cmp_edge(const void *a, const void *b)
{
    uint64_t x = ((const edge_rec *)a)->key, y = ((const edge_rec *)b)->key;
    return x < y ? -1 : x > y;
}

fm_status fm_mesh_topology_check(const fm_mesh *mesh, fm_mesh_topology *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n;
    if (!fm_size_mul(mesh->triangle_count, 3, &n))
        return fm_error_set(err, FM_ERR_LIMIT, "mesh too large to check");
    edge_rec *e = malloc((n ? n : 1) * sizeof *e);
    if (!e)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory checking a mesh");
    size_t m = 0;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->triangles + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
            out->degenerate_triangles++;
            continue;
        }
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            e[m].key = ((uint64_t)lo << 32) | hi;
            e[m].count = 1;
            e[m].dir = a < b ? 1 : -1;
            m++;
        }
    }
    qsort(e, m, sizeof *e, cmp_edge);
    for (size_t i = 0; i < m;) {
        size_t j = i;
        int dir = 0;
        while (j < m && e[j].key == e[i].key)
            dir += e[j++].dir;
        size_t count = j - i;
        out->edges++;
        if (count == 1)
            out->boundary_edges++;
        else if (count > 2)
            out->nonmanifold_edges++;
        else if (dir != 0)
            out->misoriented_edges++;
        i = j;
    }
    free(e);
    return FM_OK;
}
