/* stl.c: stock from an STL file (binary or ASCII). The file is validated
 * before any grid exists: the binary triangle count must match the file
 * size, every coordinate must be finite, and the grid the surface needs
 * (estimated from its projected area) must fit the memory budget. The
 * triangles then go to OpenVDB's meshToLevelSet through the bridge. */
#include "stock/stock_impl.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Bytes held per triangle while converting: our floats and indices, and
 * the bridge's copies of both. */
#define BYTES_PER_TRIANGLE (9 * 4 + 3 * 4 + 9 * 4 + 3 * 4)

typedef struct mesh {
    float *pts; /* 9 per triangle */
    size_t n, cap;
} mesh;

static int mesh_push(mesh *m, const float t[9], size_t max_tris)
{
    if (m->n == m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 1024;
        if (cap > max_tris) cap = max_tris;
        if (cap <= m->n) return -1;
        float *p = realloc(m->pts, cap * 9 * sizeof *p);
        if (!p) return -1;
        m->pts = p;
        m->cap = cap;
    }
    memcpy(m->pts + 9 * m->n, t, 9 * sizeof *t);
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
        if (mesh_push(m, t, max_tris))
            return fm_error_set(err, FM_ERR_LIMIT,
                                "%s: more triangles than the memory budget allows (%zu)", path,
                                max_tris);
    }
    return FM_OK;
}

fm_stock *fm_stock_new_from_stl(const char *path, const fm_stock_options *opt_in, fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    FILE *fp = path ? fopen(path, "rb") : NULL;
    if (!fp) {
        fm_error_set(err, FM_ERR_IO, "cannot open STL %s: %s", path ? path : "(null)",
                     strerror(errno));
        return NULL;
    }
    struct stat st;
    if (fstat(fileno(fp), &st) != 0 || !S_ISREG(st.st_mode)) {
        fm_error_set(err, FM_ERR_IO, "STL %s is not a regular file", path);
        fclose(fp);
        return NULL;
    }
    const size_t size = (size_t)st.st_size;
    if ((uint64_t)st.st_size > opt.memory_budget) {
        fm_error_set(err, FM_ERR_LIMIT, "STL %s (%.0f MB) is larger than the memory budget",
                     path, (double)st.st_size / 1048576.0);
        fclose(fp);
        return NULL;
    }
    unsigned char *buf = malloc(size + 1);
    if (!buf) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", path);
        fclose(fp);
        return NULL;
    }
    const size_t got = fread(buf, 1, size, fp);
    fclose(fp);
    buf[got] = '\0';
    mesh m = {0};
    fm_stock *stock = NULL;
    uint32_t *tris = NULL;
    const size_t max_tris = opt.memory_budget / BYTES_PER_TRIANGLE;
    if (got != size) {
        fm_error_set(err, FM_ERR_IO, "cannot read %s", path);
        goto out;
    }

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
            if (mesh_push(&m, t, max_tris)) {
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
                     "the STL stock %s would need about %.0f MB (projected surface %.0f mm^2 "
                     "at %g mm voxels, band %d, and %zu triangles) but the memory budget is "
                     "%.0f MB",
                     path, ((double)need + mesh_bytes) / 1048576.0, area, opt.voxel_mm,
                     opt.band_voxels, m.n, (double)opt.memory_budget / 1048576.0);
        goto out;
    }
    tris = malloc(m.n * 3 * sizeof *tris);
    if (!tris || m.n * 3 > UINT32_MAX) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory converting %s", path);
        goto out;
    }
    for (size_t i = 0; i < m.n * 3; i++) tris[i] = (uint32_t)i;
    const double origin[3] = {0, 0, 0};
    fm_vdb *v = fm_vdb_new(opt.voxel_mm, opt.band_voxels, origin, opt.threads, err);
    if (!v) goto out;
    if (fm_vdb_from_mesh(v, m.pts, m.n * 3, tris, m.n, err)) {
        fm_vdb_free(v);
        goto out;
    }
    stock = fm_stock_wrap(v, &opt, err);
out:
    free(buf);
    free(m.pts);
    free(tris);
    return stock;
}
