/* mesh_write.c: the plain encoders (binary STL, binary little-endian PLY
 * with normals and colours, OBJ) into memory buffers, and writing any
 * format to a file by extension, durably (lib/core's writer). */
#include "mesh/mesh.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A growable byte buffer; on the first failure it stops growing and
 * remembers it, so encoders check once at the end. */
typedef struct bytes {
    uint8_t *data;
    size_t size, cap;
    int failed;
} bytes;

static void bytes_put(bytes *b, const void *p, size_t n)
{
    if (b->failed)
        return;
    if (b->size + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->size + n) {
            if (cap > SIZE_MAX / 2) {
                b->failed = 1;
                return;
            }
            cap *= 2;
        }
        uint8_t *q = realloc(b->data, cap);
        if (!q) {
            b->failed = 1;
            return;
        }
        b->data = q;
        b->cap = cap;
    }
    memcpy(b->data + b->size, p, n);
    b->size += n;
}

/* Little-endian stores that do not depend on the host's byte order. */
static void put_u32(bytes *b, uint32_t v)
{
    uint8_t c[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    bytes_put(b, c, 4);
}

static void put_f32(bytes *b, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put_u32(b, v);
}

static void put_str(bytes *b, const char *s) { bytes_put(b, s, strlen(s)); }

static fm_status bytes_finish(bytes *b, uint8_t **out, size_t *size, const char *what,
                              fm_error *err)
{
    if (b->failed) {
        free(b->data);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory encoding %s", what);
    }
    *out = b->data;
    *size = b->size;
    return FM_OK;
}

fm_status fm_mesh_encode_stl(const fm_mesh *mesh, uint8_t **out, size_t *size, fm_error *err)
{
    if (mesh->triangle_count > UINT32_MAX)
        return fm_error_set(err, FM_ERR_LIMIT, "STL holds at most 2^32-1 triangles");
    bytes b = {0};
    char header[80];
    memset(header, 0, sizeof header);
    /* The header must not start with "solid": readers would take it for ASCII. */
    snprintf(header, sizeof header, "frepmill binary STL, millimetres");
    bytes_put(&b, header, 80);
    put_u32(&b, (uint32_t)mesh->triangle_count);
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = mesh->positions + 3 * (size_t)mesh->triangles[3 * t + k];
        double u[3], v[3], n[3];
        for (int k = 0; k < 3; k++) {
            u[k] = (double)p[1][k] - p[0][k];
            v[k] = (double)p[2][k] - p[0][k];
        }
        n[0] = u[1] * v[2] - u[2] * v[1];
        n[1] = u[2] * v[0] - u[0] * v[2];
        n[2] = u[0] * v[1] - u[1] * v[0];
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++)
            put_f32(&b, len > 0 ? (float)(n[k] / len) : 0.0f);
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                put_f32(&b, p[k][c]);
        uint8_t attr[2] = {0, 0};
        bytes_put(&b, attr, 2);
    }
    return bytes_finish(&b, out, size, "STL", err);
}

fm_status fm_mesh_encode_ply(const fm_mesh *mesh, uint8_t **out, size_t *size, fm_error *err)
{
    if (mesh->vertex_count > UINT32_MAX || mesh->triangle_count > UINT32_MAX)
        return fm_error_set(err, FM_ERR_LIMIT, "mesh too large for PLY");
    bytes b = {0};
    char line[128];
    put_str(&b, "ply\nformat binary_little_endian 1.0\ncomment frepmill, millimetres\n");
    snprintf(line, sizeof line, "element vertex %zu\n", mesh->vertex_count);
    put_str(&b, line);
    put_str(&b, "property float x\nproperty float y\nproperty float z\n");
    if (mesh->normals)
        put_str(&b, "property float nx\nproperty float ny\nproperty float nz\n");
    if (mesh->colors)
        put_str(&b, "property uchar red\nproperty uchar green\nproperty uchar blue\n");
    snprintf(line, sizeof line, "element face %zu\n", mesh->triangle_count);
    put_str(&b, line);
    put_str(&b, "property list uchar uint vertex_indices\nend_header\n");
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        for (int k = 0; k < 3; k++)
            put_f32(&b, mesh->positions[3 * i + k]);
        if (mesh->normals)
            for (int k = 0; k < 3; k++)
                put_f32(&b, mesh->normals[3 * i + k]);
        if (mesh->colors)
            bytes_put(&b, mesh->colors + 3 * i, 3);
    }
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        uint8_t three = 3;
        bytes_put(&b, &three, 1);
        for (int k = 0; k < 3; k++)
            put_u32(&b, mesh->triangles[3 * t + k]);
    }
    return bytes_finish(&b, out, size, "PLY", err);
}

fm_status fm_mesh_encode_obj(const fm_mesh *mesh, uint8_t **out, size_t *size, fm_error *err)
{
    bytes b = {0};
    char line[160];
    put_str(&b, "# frepmill mesh, millimetres\n");
    /* %.9g round-trips every float exactly. */
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        const float *p = mesh->positions + 3 * i;
        if (mesh->colors) {
            const uint8_t *c = mesh->colors + 3 * i;
            snprintf(line, sizeof line, "v %.9g %.9g %.9g %.6g %.6g %.6g\n", p[0], p[1], p[2],
                     c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
        } else {
            snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
        }
        put_str(&b, line);
    }
    if (mesh->normals)
        for (size_t i = 0; i < mesh->vertex_count; i++) {
            const float *n = mesh->normals + 3 * i;
            snprintf(line, sizeof line, "vn %.6g %.6g %.6g\n", n[0], n[1], n[2]);
            put_str(&b, line);
        }
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->triangles + 3 * t;
        /* OBJ indices are 1-based. */
        unsigned long a = v[0] + 1ul, c = v[1] + 1ul, d = v[2] + 1ul;
        if (mesh->normals)
            snprintf(line, sizeof line, "f %lu//%lu %lu//%lu %lu//%lu\n", a, a, c, c, d, d);
        else
            snprintf(line, sizeof line, "f %lu %lu %lu\n", a, c, d);
        put_str(&b, line);
    }
    return bytes_finish(&b, out, size, "OBJ", err);
}

fm_mesh_format fm_mesh_format_from_path(const char *path)
{
    const char *dot = path ? strrchr(path, '.') : NULL;
    if (!dot || strchr(dot, '/'))
        return FM_MESH_FORMAT_UNKNOWN;
    char ext[8];
    size_t n = strlen(dot + 1);
    if (n == 0 || n >= sizeof ext)
        return FM_MESH_FORMAT_UNKNOWN;
    for (size_t i = 0; i < n && i < sizeof ext - 1; i++)
        ext[i] = (char)tolower((unsigned char)dot[1 + i]);
    ext[n] = 0;
    if (!strcmp(ext, "drc"))
        return FM_MESH_FORMAT_DRACO;
    if (!strcmp(ext, "stl"))
        return FM_MESH_FORMAT_STL;
    if (!strcmp(ext, "ply"))
        return FM_MESH_FORMAT_PLY;
    if (!strcmp(ext, "obj"))
        return FM_MESH_FORMAT_OBJ;
    return FM_MESH_FORMAT_UNKNOWN;
}

static fm_status write_encoded(const fm_mesh *mesh, const char *path, fm_mesh_format fmt,
                               const fm_mesh_draco_options *draco, fm_error *err)
{
    uint8_t *data = NULL;
    size_t size = 0;
    fm_status st;
    switch (fmt) {
    case FM_MESH_FORMAT_DRACO:
        st = fm_mesh_encode_draco(mesh, draco, &data, &size, err);
        break;
    case FM_MESH_FORMAT_STL:
        st = fm_mesh_encode_stl(mesh, &data, &size, err);
        break;
    case FM_MESH_FORMAT_PLY:
        st = fm_mesh_encode_ply(mesh, &data, &size, err);
        break;
    case FM_MESH_FORMAT_OBJ:
        st = fm_mesh_encode_obj(mesh, &data, &size, err);
        break;
    default:
        return fm_error_set(err, FM_ERR_INPUT,
                            "%s: unknown mesh format; use .drc, .stl, .ply or .obj", path);
    }
    if (st != FM_OK)
        return st;
    st = fm_file_write_durable(path, NULL, data, size, err);
    free(data);
    return st;
}

fm_status fm_mesh_write_file(const fm_mesh *mesh, const char *path,
                             const fm_mesh_draco_options *draco, fm_error *err)
{
    return write_encoded(mesh, path, fm_mesh_format_from_path(path), draco, err);
}

fm_status fm_mesh_write_stl(const fm_mesh *mesh, const char *path, fm_error *err)
{
    return write_encoded(mesh, path, FM_MESH_FORMAT_STL, NULL, err);
}

fm_status fm_mesh_write_ply(const fm_mesh *mesh, const char *path, fm_error *err)
{
    return write_encoded(mesh, path, FM_MESH_FORMAT_PLY, NULL, err);
}

fm_status fm_mesh_write_obj(const fm_mesh *mesh, const char *path, fm_error *err)
{
    return write_encoded(mesh, path, FM_MESH_FORMAT_OBJ, NULL, err);
}

fm_status fm_mesh_write_draco(const fm_mesh *mesh, const fm_mesh_draco_options *opt,
                              const char *path, fm_error *err)
{
    return write_encoded(mesh, path, FM_MESH_FORMAT_DRACO, opt, err);
}
