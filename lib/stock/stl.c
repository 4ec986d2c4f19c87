/* stl.c: a level set from an STL file (binary or ASCII), for an STL stock
 * and for an STL design part (design.c). The file is validated before any
 * grid exists: the binary triangle count must match the file size, every
 * coordinate must be finite, and the grid the surface needs (estimated from
 * its projected area, then from the leaves its band reaches) must fit the
 * memory budget. The triangles then go to OpenVDB's meshToLevelSet through
 * the bridge. */
#include "stock/stock_impl.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Bytes held per triangle at the peak, beside the grid: our floats and an
 * ASCII facet's line, and then either our indices and the bridge's copies
 * of floats and indices (converting) or three edge records (checking that
 * the surface is closed, after the indices are freed). */
#define EDGE_RECORD_BYTES 28
#define CONVERT_BYTES (3 * 4 + 9 * 4 + 3 * 4)
#define CHECK_BYTES (3 * EDGE_RECORD_BYTES)
#define BYTES_PER_TRIANGLE                                                                       \
    (9 * 4 + 2 * 4 + (CONVERT_BYTES > CHECK_BYTES ? CONVERT_BYTES : CHECK_BYTES))

typedef struct mesh {
    float *pts;     /* 9 per triangle */
    int32_t *lines; /* an ASCII file's: each facet's line and column */
    size_t n, cap;
} mesh;

static int mesh_push(mesh *m, const float t[9], size_t max_tris, int line, int col)
{
    if (m->n == m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 1024;
        if (cap > max_tris) cap = max_tris;
        if (cap <= m->n) return -1;
        float *p = realloc(m->pts, cap * 9 * sizeof *p);
        if (!p) return -1;
        m->pts = p;
        if (line > 0) {
            int32_t *l = realloc(m->lines, cap * 2 * sizeof *l);
            if (!l) return -1;
            m->lines = l;
        }
        m->cap = cap;
    }
    memcpy(m->pts + 9 * m->n, t, 9 * sizeof *t);
    if (m->lines) {
        m->lines[2 * m->n] = line;
        m->lines[2 * m->n + 1] = col;
    }
    m->n++;
    return 0;
}

static float le_float(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
                 (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* ASCII tokenizer with line and column for messages. */
typedef struct lexer {
    const char *p, *end;
    int line, col;
    char tok[64];
    int tline, tcol;
} lexer;

static int next_token(lexer *lx)
{
    while (lx->p < lx->end && isspace((unsigned char)*lx->p)) {
        if (*lx->p == '\n') {
            lx->line++;
            lx->col = 1;
        } else {
            lx->col++;
        }
        lx->p++;
    }
    if (lx->p >= lx->end) return 0;
    lx->tline = lx->line;
    lx->tcol = lx->col;
    size_t n = 0;
    while (lx->p < lx->end && !isspace((unsigned char)*lx->p)) {
        if (n + 1 < sizeof lx->tok) lx->tok[n++] = *lx->p;
        lx->p++;
        lx->col++;
    }
    lx->tok[n] = '\0';
    return 1;
}

static int expect(lexer *lx, const char *word)
{
    return next_token(lx) && strcmp(lx->tok, word) == 0;
}

static fm_status parse_ascii(const char *path, const char *text, size_t size, size_t max_tris,
                             mesh *m, fm_error *err)
{
    lexer lx = {text, text + size, 1, 1, {0}, 1, 1};
    if (!expect(&lx, "solid"))
        return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                           "STL: expected \"solid\"");
    /* the solid's name runs to the end of the line */
    while (lx.p < lx.end && *lx.p != '\n') lx.p++;
    for (;;) {
        if (!next_token(&lx))
            return fm_error_at(err, FM_ERR_INPUT, path, lx.line, lx.col,
                               "STL: file ends before \"endsolid\"");
        if (strcmp(lx.tok, "endsolid") == 0) break;
        if (strcmp(lx.tok, "facet") != 0)
            return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                               "STL: expected \"facet\" or \"endsolid\", found \"%s\"", lx.tok);
        const int fline = lx.tline, fcol = lx.tcol;
        /* the normal is ignored: the level set's sign comes from the
         * closed surface, not from the file's normals */
        if (!expect(&lx, "normal"))
            return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                               "STL: expected \"normal\"");
        for (int i = 0; i < 3; i++) next_token(&lx);
        if (!expect(&lx, "outer") || !expect(&lx, "loop"))
            return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                               "STL: expected \"outer loop\"");
        float t[9];
        for (int v = 0; v < 3; v++) {
            if (!expect(&lx, "vertex"))
                return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                                   "STL: expected \"vertex\" (facets must be triangles)");
            for (int k = 0; k < 3; k++) {
                if (!next_token(&lx))
                    return fm_error_at(err, FM_ERR_INPUT, path, lx.line, lx.col,
                                       "STL: file ends inside a vertex");
                char *end;
                errno = 0;
                double d = strtod(lx.tok, &end);
                if (*end || end == lx.tok || !isfinite(d) || fabs(d) > 1e7)
                    return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                                       "STL: \"%s\" is not a finite coordinate", lx.tok);
                t[3 * v + k] = (float)d;
            }
        }
        if (!expect(&lx, "endloop") || !expect(&lx, "endfacet"))
            return fm_error_at(err, FM_ERR_INPUT, path, lx.tline, lx.tcol,
                               "STL: expected \"endloop endfacet\"");
        if (mesh_push(m, t, max_tris, fline, fcol))
            return fm_error_set(err, FM_ERR_LIMIT,
                                "%s: more triangles than the memory budget allows (%zu)", path,
                                max_tris);
    }
    return FM_OK;
}

/* ------------------------------------------- the grid the mesh needs -- */
/* The projected-area estimate (fm_stock_estimate_bytes) holds for a surface:
 * (2w + 7) / 8 leaves per leaf column it crosses. Slivers, zero-area
 * triangles and triangles scattered far apart make bands that are tubes
 * and blobs, far larger than their area says, with internal nodes of their
 * own (fuzz_stl: 684 bytes of STL made a 200 MB grid against a 64 MB
 * budget). So the leaves are also counted: every 8^3 leaf whose box,
 * widened by the band, meets a triangle, found by bisecting each
 * triangle's box of leaves with a separating-axis test, deduplicated in a
 * hash set, and the internal nodes above them. */

/* Voxel indices stay within +-2^30 (OpenVDB's are int32). */
#define MAX_INDEX 1073741824.0

typedef struct leaf_set {
    int32_t (*keys)[3]; /* INT32_MIN in [0]: empty */
    size_t n, size;     /* size: a power of two */
} leaf_set;

static int leaf_set_add(leaf_set *s, const int32_t k[3])
{
    if ((s->n + 1) * 2 > s->size) {
        const size_t size = s->size ? s->size * 2 : 1024;
        int32_t(*keys)[3] = malloc(size * sizeof *keys);
        if (!keys) return -1;
        for (size_t i = 0; i < size; i++) keys[i][0] = INT32_MIN;
        for (size_t i = 0; i < s->size; i++) {
            if (s->keys[i][0] == INT32_MIN) continue;
            size_t j = (size_t)fm_stock_hash3(s->keys[i]) & (size - 1);
            while (keys[j][0] != INT32_MIN) j = (j + 1) & (size - 1);
            memcpy(keys[j], s->keys[i], sizeof keys[j]);
        }
        free(s->keys);
        s->keys = keys;
        s->size = size;
    }
    size_t j = (size_t)fm_stock_hash3(k) & (s->size - 1);
    for (; s->keys[j][0] != INT32_MIN; j = (j + 1) & (s->size - 1))
        if (s->keys[j][0] == k[0] && s->keys[j][1] == k[1] && s->keys[j][2] == k[2]) return 0;
    memcpy(s->keys[j], k, sizeof s->keys[j]);
    s->n++;
    return 0;
}

/* Does the projection on axis a separate triangle v from the open box of
 * half extents e (both relative to the box's centre)? Touching separates:
 * a voxel exactly w voxels from the surface is outside the band. A zero
 * axis never separates. */
static int separates(const double a[3], const double v[3][3], const double e[3])
{
    if (a[0] == 0 && a[1] == 0 && a[2] == 0) return 0;
    double lo = INFINITY, hi = -INFINITY;
    for (int j = 0; j < 3; j++) {
        const double d = a[0] * v[j][0] + a[1] * v[j][1] + a[2] * v[j][2];
        lo = fmin(lo, d);
        hi = fmax(hi, d);
    }
    const double r = e[0] * fabs(a[0]) + e[1] * fabs(a[1]) + e[2] * fabs(a[2]);
    return lo >= r || hi <= -r;
}

/* Triangle-box overlap on the 13 separating axes (the box's 3, the
 * triangle's normal, edge x box axis); true for every box the triangle
 * enters, degenerate triangles included (their zero axes do not count). */
static int triangle_meets_box(const double v[3][3], const double e[3])
{
    double f[3][3];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) f[i][k] = v[(i + 1) % 3][k] - v[i][k];
    for (int k = 0; k < 3; k++) {
        double a[3] = {0, 0, 0};
        a[k] = 1;
        if (separates(a, v, e)) return 0;
    }
    const double n[3] = {f[0][1] * f[1][2] - f[0][2] * f[1][1],
                         f[0][2] * f[1][0] - f[0][0] * f[1][2],
                         f[0][0] * f[1][1] - f[0][1] * f[1][0]};
    if (separates(n, v, e)) return 0;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            double a[3] = {0, 0, 0}; /* unit axis k x edge i */
            a[(k + 1) % 3] = -f[i][(k + 2) % 3];
            a[(k + 2) % 3] = f[i][(k + 1) % 3];
            if (separates(a, v, e)) return 0;
        }
    return 1;
}

typedef struct leaf_count {
    leaf_set leaves;
    size_t max_leaves;        /* stop: the budget cannot hold more */
    uint64_t tests, max_tests; /* stop: triangles piled on each other */
} leaf_count;

/* Add the leaves the band (w voxels) around triangle t (mm) reaches, at
 * voxel h. 0, or -1 out of memory, 1 over max_leaves, 2 over max_tests. */
static int count_triangle(leaf_count *c, const float *t, double h, double w)
{
    double p[3][3];
    int32_t box[128][2][3], lo[3], hi[3];
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < 3; k++) p[j][k] = t[3 * j + k] / h;
    for (int k = 0; k < 3; k++) {
        const double mn = fmin(p[0][k], fmin(p[1][k], p[2][k]));
        const double mx = fmax(p[0][k], fmax(p[1][k], p[2][k]));
        /* leaf L holds the voxel centres 8L .. 8L + 7 */
        lo[k] = (int32_t)ceil((mn - w - 7) / 8);
        hi[k] = (int32_t)floor((mx + w) / 8);
    }
    int top = 0;
    memcpy(box[0][0], lo, sizeof lo);
    memcpy(box[0][1], hi, sizeof hi);
    while (top >= 0) {
        memcpy(lo, box[top][0], sizeof lo);
        memcpy(hi, box[top][1], sizeof hi);
        top--;
        if (++c->tests > c->max_tests) return 2;
        double v[3][3], e[3];
        int split = 0;
        for (int k = 0; k < 3; k++) {
            const double centre = 4.0 * ((double)lo[k] + hi[k]) + 3.5;
            e[k] = 4.0 * ((double)hi[k] - lo[k]) + 3.5 + w;
            for (int j = 0; j < 3; j++) v[j][k] = p[j][k] - centre;
            if (hi[k] - lo[k] > hi[split] - lo[split]) split = k;
        }
        if (!triangle_meets_box(v, e)) continue;
        if (hi[split] == lo[split]) { /* one leaf */
            if (leaf_set_add(&c->leaves, lo)) return -1;
            if (c->leaves.n > c->max_leaves) return 1;
            continue;
        }
        /* halves; the depth is at most 3 x 28 levels, so 128 entries hold
         * the stack */
        const int32_t mid = lo[split] + (hi[split] - lo[split]) / 2;
        top++;
        memcpy(box[top][0], lo, sizeof lo);
        memcpy(box[top][1], hi, sizeof hi);
        box[top][1][split] = mid;
        top++;
        memcpy(box[top][0], lo, sizeof lo);
        memcpy(box[top][1], hi, sizeof hi);
        box[top][0][split] = mid + 1;
    }
    return 0;
}

static int32_t floor_div(int32_t a, int32_t b)
{
    return a >= 0 ? a / b : -((-a - 1) / b) - 1;
}

/* Bytes of the grid the leaves counted need: leaves, their 128^3 and
 * 4096^3 internal nodes, and the same fixed part as the formula. */
static fm_status counted_bytes(const leaf_set *leaves, double *bytes)
{
    leaf_set n1 = {0}, n2 = {0};
    fm_status rc = FM_OK;
    for (size_t i = 0; i < leaves->size && !rc; i++) {
        const int32_t *k = leaves->keys[i];
        if (k[0] == INT32_MIN) continue;
        const int32_t a[3] = {floor_div(k[0], 16), floor_div(k[1], 16), floor_div(k[2], 16)};
        const int32_t b[3] = {floor_div(k[0], 512), floor_div(k[1], 512), floor_div(k[2], 512)};
        if (leaf_set_add(&n1, a) || leaf_set_add(&n2, b)) rc = FM_ERR_LIMIT;
    }
    *bytes = (double)leaves->n * (double)fm_vdb_leaf_bytes() +
             (double)n1.n * (double)fm_vdb_internal1_bytes() +
             (double)n2.n * (double)fm_vdb_internal2_bytes() + 65536.0;
    free(n1.keys);
    free(n2.keys);
    return rc;
}

/* -------------------------------------------- is it a closed surface? -- */
/* meshToLevelSet takes the sign from a flood fill of the outside: a hole
 * wider than a voxel lets the fill in, and the solid left is the band's
 * shell (a box without its top face at 0.5 mm: 3,920 of its 150,000 mm^3).
 * The volumes tell it: the level set's against the triangles' own
 * (divergence theorem), under half or over twice it (an open sheet
 * encloses nothing, and its shell is all it holds), or under a voxel. Only
 * then are the open edges looked for: a surface whose edges all pair up
 * passes (flipped triangles make the triangles' volume wrong, not the
 * grid's), and one with open edges is refused with the first of them. A
 * surface closed but for T-junctions or cracks narrower than a voxel
 * holds its volume and passes. */

typedef struct edge_rec {
    float a[3], b[3]; /* a before b, lexicographically */
    uint32_t tri;
} edge_rec;
_Static_assert(sizeof(edge_rec) == EDGE_RECORD_BYTES, "the budget counts edge records");

static int cmp_point(const float *p, const float *q)
{
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
    return 0;
}

static int cmp_edge_rec(const void *x, const void *y)
{
    const edge_rec *e = x, *f = y;
    const int c = cmp_point(e->a, f->a);
    return c ? c : cmp_point(e->b, f->b);
}

/* Edges used by one triangle only (endpoints matched exactly); *first
 * gets the one in the earliest triangle. (size_t)-1 when out of memory. */
static size_t open_edges(const mesh *m, edge_rec *first)
{
    edge_rec *e = malloc(3 * m->n * sizeof *e);
    if (!e) return (size_t)-1;
    for (size_t t = 0; t < m->n; t++)
        for (int k = 0; k < 3; k++) {
            const float *p = m->pts + 9 * t + 3 * k, *q = m->pts + 9 * t + 3 * ((k + 1) % 3);
            edge_rec *r = e + 3 * t + k;
            const int swap = cmp_point(p, q) > 0;
            memcpy(r->a, swap ? q : p, sizeof r->a);
            memcpy(r->b, swap ? p : q, sizeof r->b);
            r->tri = (uint32_t)t;
        }
    qsort(e, 3 * m->n, sizeof *e, cmp_edge_rec);
    size_t open = 0;
    for (size_t i = 0, j; i < 3 * m->n; i = j) {
        for (j = i + 1; j < 3 * m->n && cmp_edge_rec(e + i, e + j) == 0; j++) continue;
        if (j - i == 1 && (open++ == 0 || e[i].tri < first->tri)) *first = e[i];
    }
    free(e);
    return open;
}

static fm_status check_closed(const char *path, const char *what, const mesh *m,
                              const fm_vdb *v, fm_error *err)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < 9 * m->n; i++) {
        lo[i % 3] = fmin(lo[i % 3], m->pts[i]);
        hi[i % 3] = fmax(hi[i % 3], m->pts[i]);
    }
    double enclosed = 0;
    for (size_t t = 0; t < m->n; t++) {
        double p[3][3];
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) p[j][k] = m->pts[9 * t + 3 * j + k] - (lo[k] + hi[k]) / 2;
        const double c[3] = {p[1][1] * p[2][2] - p[1][2] * p[2][1],
                             p[1][2] * p[2][0] - p[1][0] * p[2][2],
                             p[1][0] * p[2][1] - p[1][1] * p[2][0]};
        enclosed += (p[0][0] * c[0] + p[0][1] * c[1] + p[0][2] * c[2]) / 6;
    }
    enclosed = fabs(enclosed);
    const double h = fm_vdb_voxel(v), held = fm_vdb_volume(v);
    if (held >= 0.5 * enclosed && held <= 2 * enclosed && held >= h * h * h) return FM_OK;
    edge_rec first = {{0, 0, 0}, {0, 0, 0}, 0};
    const size_t open = open_edges(m, &first);
    if (open == (size_t)-1)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory checking the STL %s %s", what,
                            path);
    if (open == 0) {
        if (held >= h * h * h) return FM_OK; /* closed: the winding is off, not the grid */
        return fm_error_set(err, FM_ERR_INPUT,
                            "the STL %s %s encloses no volume at %g mm voxels (its triangles "
                            "enclose %.3g mm^3): a %s must be a solid",
                            what, path, h, enclosed, what);
    }
    const char *fmt = "the STL %s %s is not a closed surface: %zu of its edges bound one "
                      "triangle only, the first from (%g, %g, %g) to (%g, %g, %g) in triangle "
                      "%lu; at %g mm voxels its inside holds %.1f mm^3 where its triangles "
                      "enclose %.1f mm^3 (a %s must be a solid: close the surface, or export "
                      "the part as a closed mesh)";
    const unsigned long tri = (unsigned long)first.tri + 1;
    if (m->lines)
        return fm_error_at(err, FM_ERR_INPUT, path, m->lines[2 * first.tri],
                           m->lines[2 * first.tri + 1], fmt, what, path, open, first.a[0],
                           first.a[1], first.a[2], first.b[0], first.b[1], first.b[2], tri, h,
                           held, enclosed, what);
    return fm_error_set(err, FM_ERR_INPUT, fmt, what, path, open, first.a[0], first.a[1],
                        first.a[2], first.b[0], first.b[1], first.b[2], tri, h, held, enclosed,
                        what);
}

fm_vdb *fm_stl_to_vdb(const char *path, const fm_stock_options *opt_in, const double origin[3],
                      const char *what, fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    char *text;
    size_t size;
    if (fm_file_read(path, "STL", opt.memory_budget, &text, &size, err)) return NULL;
    unsigned char *buf = (unsigned char *)text;
    mesh m = {0};
    fm_vdb *grid = NULL;
    uint32_t *tris = NULL;
    const size_t max_tris = opt.memory_budget / BYTES_PER_TRIANGLE;

    /* Binary when the size matches the count in the header exactly: many
     * binary files also begin with "solid". */
    const uint64_t count = size >= 84 ? ((uint64_t)buf[80] | (uint64_t)buf[81] << 8 |
                                         (uint64_t)buf[82] << 16 | (uint64_t)buf[83] << 24)
                                      : 0;
    if (size >= 84 && 84 + 50 * count == size) {
        if (count == 0) {
            fm_error_set(err, FM_ERR_INPUT, "STL %s has no triangles", path);
            goto out;
        }
        if (count > max_tris) {
            fm_error_set(err, FM_ERR_LIMIT,
                         "STL %s has %llu triangles, more than the memory budget allows", path,
                         (unsigned long long)count);
            goto out;
        }
        for (uint64_t i = 0; i < count; i++) {
            const unsigned char *rec = buf + 84 + 50 * i;
            float t[9];
            for (int k = 0; k < 9; k++) {
                t[k] = le_float(rec + 12 + 4 * k);
                if (!isfinite(t[k]) || fabsf(t[k]) > 1e7f) {
                    fm_error_set(err, FM_ERR_INPUT,
                                 "STL %s: triangle %llu has a coordinate that is not finite "
                                 "or beyond 1e7 mm",
                                 path, (unsigned long long)i + 1);
                    goto out;
                }
            }
            if (mesh_push(&m, t, max_tris, 0, 0)) {
                fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", path);
                goto out;
            }
        }
    } else {
        size_t i = 0;
        while (i < size && isspace(buf[i])) i++;
        if (size - i < 5 || memcmp(buf + i, "solid", 5) != 0) {
            fm_error_set(err, FM_ERR_INPUT,
                         "%s is not an STL file: %zu bytes do not match a binary STL of %llu "
                         "triangles (84 + 50 * n bytes) and it does not start with \"solid\"",
                         path, size, (unsigned long long)count);
            goto out;
        }
        if (memchr(buf, '\0', size)) {
            fm_error_set(err, FM_ERR_INPUT,
                         "%s: binary data in an ASCII STL, or a binary STL whose triangle "
                         "count (%llu) does not match its size (%zu bytes)",
                         path, (unsigned long long)count, size);
            goto out;
        }
        if (parse_ascii(path, (const char *)buf, size, max_tris, &m, err)) goto out;
        if (m.n == 0) {
            fm_error_set(err, FM_ERR_INPUT, "STL %s has no triangles", path);
            goto out;
        }
    }
    free(buf);
    buf = NULL;

    double area = 0; /* projected: sum of |cross_k| / 2 */
    for (size_t i = 0; i < m.n; i++) {
        const float *t = m.pts + 9 * i;
        const double u[3] = {t[3] - t[0], t[4] - t[1], t[5] - t[2]};
        const double v[3] = {t[6] - t[0], t[7] - t[1], t[8] - t[2]};
        area += 0.5 * (fabs(u[1] * v[2] - u[2] * v[1]) + fabs(u[2] * v[0] - u[0] * v[2]) +
                       fabs(u[0] * v[1] - u[1] * v[0]));
    }
    const size_t need = fm_stock_estimate_bytes(area, opt.voxel_mm, opt.band_voxels);
    const double mesh_bytes = (double)m.n * BYTES_PER_TRIANGLE;
    if ((double)need + mesh_bytes > (double)opt.memory_budget) {
        fm_error_set(err, FM_ERR_LIMIT,
                     "the STL %s %s would need about %.0f MB (projected surface %.0f mm^2 "
                     "at %g mm voxels, band %d, and %zu triangles) but the memory budget is "
                     "%.0f MB",
                     what, path, ((double)need + mesh_bytes) / 1048576.0, area, opt.voxel_mm,
                     opt.band_voxels, m.n, (double)opt.memory_budget / 1048576.0);
        goto out;
    }
    /* the area says it fits: count the leaves the band really reaches */
    for (size_t i = 0; i < 9 * m.n; i++)
        if (fabs((m.pts[i] - origin[i % 3]) / opt.voxel_mm) >= MAX_INDEX) {
            fm_error_set(err, FM_ERR_INPUT,
                         "STL %s: coordinate %g mm is beyond the grid's index range at %g mm "
                         "voxels (+-%.0f mm)",
                         path, m.pts[i], opt.voxel_mm, MAX_INDEX * opt.voxel_mm);
            goto out;
        }
    leaf_count lc = {{NULL, 0, 0}, opt.memory_budget / fm_vdb_leaf_bytes(), 0, 0};
    lc.max_tests = 64 * ((uint64_t)lc.max_leaves + m.n);
    int over = 0;
    for (size_t i = 0; i < m.n && !over; i++) {
        /* in index space: leaves are counted as the grid will place them */
        float t[9];
        for (int k = 0; k < 9; k++) t[k] = (float)(m.pts[9 * i + k] - origin[k % 3]);
        over = count_triangle(&lc, t, opt.voxel_mm, opt.band_voxels);
    }
    double counted = 0;
    if (!over && counted_bytes(&lc.leaves, &counted)) over = -1;
    free(lc.leaves.keys);
    if (over < 0) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory estimating the grid of %s", path);
        goto out;
    }
    if (over == 2) {
        fm_error_set(err, FM_ERR_LIMIT,
                     "the STL %s %s: its triangles lie on each other so much that the grid "
                     "they need could not be estimated within the memory budget of %.0f MB",
                     what, path, (double)opt.memory_budget / 1048576.0);
        goto out;
    }
    if (over == 1 || counted + mesh_bytes > (double)opt.memory_budget) {
        fm_error_set(err, FM_ERR_LIMIT,
                     "the STL %s %s would need %s %.0f MB (its band reaches %s%zu leaves of "
                     "8^3 voxels at %g mm voxels, band %d; projected surface %.0f mm^2, %zu "
                     "triangles) but the memory budget is %.0f MB",
                     what, path, over ? "more than" : "about",
                     (over ? (double)opt.memory_budget : counted + mesh_bytes) / 1048576.0,
                     over ? "more than " : "", lc.leaves.n, opt.voxel_mm, opt.band_voxels, area,
                     m.n, (double)opt.memory_budget / 1048576.0);
        goto out;
    }
    tris = malloc(m.n * 3 * sizeof *tris);
    if (!tris || m.n * 3 > UINT32_MAX) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory converting %s", path);
        goto out;
    }
    for (size_t i = 0; i < m.n * 3; i++) tris[i] = (uint32_t)i;
    fm_vdb *v = fm_vdb_new(opt.voxel_mm, opt.band_voxels, origin, opt.threads, err);
    if (!v) goto out;
    if (fm_vdb_from_mesh(v, m.pts, m.n * 3, tris, m.n, err)) {
        fm_vdb_free(v);
        goto out;
    }
    free(tris);
    tris = NULL;
    if (check_closed(path, what, &m, v, err)) {
        fm_vdb_free(v);
        goto out;
    }
    grid = v;
out:
    free(buf);
    free(m.pts);
    free(m.lines);
    free(tris);
    return grid;
}

fm_stock *fm_stock_new_from_stl_named(const char *path, const char *what,
                                      const fm_stock_options *opt_in, fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    const double origin[3] = {0, 0, 0};
    fm_vdb *v = fm_stl_to_vdb(path, &opt, origin, what ? what : "stock", err);
    return v ? fm_stock_wrap(v, &opt, err) : NULL;
}

fm_stock *fm_stock_new_from_stl(const char *path, const fm_stock_options *opt, fm_error *err)
{
    return fm_stock_new_from_stl_named(path, "stock", opt, err);
}
