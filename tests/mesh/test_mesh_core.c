/* test_mesh_core.c: the fm_mesh container (budgets, append, weld, volume,
 * topology check) and the plain encoders (STL, PLY, OBJ), checked against
 * geometry built by hand and bytes parsed here independently. */
#include "fixtures.h"
#include "test.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static uint32_t rd_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float rd_f32(const uint8_t *p)
{
    uint32_t v = rd_u32(p);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

static void test_box_topology_and_volume(void)
{
    const float lo[3] = {-1, 2, 0.5f}, hi[3] = {3, 4, 2};
    fm_mesh *m = fixture_box(lo, hi);
    CHECK(m && m->vertex_count == 8 && m->triangle_count == 12);
    fm_mesh_topology t;
    CHECK(fm_mesh_topology_check(m, &t, NULL) == FM_OK);
    CHECK(t.edges == 18); /* 12 box edges + 6 quad diagonals */
    CHECK(t.boundary_edges == 0 && t.nonmanifold_edges == 0 && t.misoriented_edges == 0);
    CHECK_NEAR(fm_mesh_volume(m), 4.0 * 2.0 * 1.5, 1e-5);
    float blo[3], bhi[3];
    CHECK(fm_mesh_bounds(m, blo, bhi));
    for (int k = 0; k < 3; k++) {
        CHECK(blo[k] == lo[k]);
        CHECK(bhi[k] == hi[k]);
    }

    /* Flipping one triangle makes its three edges run the same way as
     * their neighbours'. */
    uint32_t tmp = m->triangles[0];
    m->triangles[0] = m->triangles[1];
    m->triangles[1] = tmp;
    CHECK(fm_mesh_topology_check(m, &t, NULL) == FM_OK);
    CHECK(t.misoriented_edges == 3);
    /* Dropping a triangle opens three edges. */
    m->triangle_count--;
    CHECK(fm_mesh_topology_check(m, &t, NULL) == FM_OK);
    CHECK(t.boundary_edges == 3);
    fm_mesh_free(m);
}

static void test_weld_and_append(void)
{
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    fm_mesh *box = fixture_box(lo, hi);
    /* A triangle soup: every triangle gets its own three vertices. */
    fm_mesh *soup = fm_mesh_new(0, 0, FM_MESH_COLORS, NULL, NULL);
    for (size_t t = 0; t < box->triangle_count; t++) {
        uint32_t v[3];
        for (int k = 0; k < 3; k++) {
            uint8_t rgb[3] = {(uint8_t)t, 1, 2};
            v[k] = (uint32_t)fm_mesh_add_vertex(soup, box->positions + 3 * box->triangles[3 * t + k],
                                                NULL, rgb, NULL);
        }
        fm_mesh_add_triangle(soup, v[0], v[1], v[2], NULL);
    }
    CHECK(soup->vertex_count == 36);
    fm_mesh_topology t;
    fm_mesh_topology_check(soup, &t, NULL);
    CHECK(t.boundary_edges == 36);
    CHECK(fm_mesh_weld(soup, NULL) == FM_OK);
    CHECK(soup->vertex_count == 8 && soup->triangle_count == 12);
    fm_mesh_topology_check(soup, &t, NULL);
    CHECK(t.boundary_edges == 0 && t.misoriented_edges == 0 && t.nonmanifold_edges == 0);
    CHECK_NEAR(fm_mesh_volume(soup), 1.0, 1e-6);

    /* Two boxes side by side: append keeps both closed and adds volumes. */
    const float lo2[3] = {5, 0, 0}, hi2[3] = {7, 1, 1};
    fm_mesh *b2 = fixture_box(lo2, hi2);
    CHECK(fm_mesh_append(soup, b2, NULL) == FM_OK);
    CHECK(soup->vertex_count == 16 && soup->triangle_count == 24);
    CHECK(soup->colors[3 * 8] == 0); /* attributes the source lacks are zero */
    CHECK_NEAR(fm_mesh_volume(soup), 3.0, 1e-5);
    fm_mesh_topology_check(soup, &t, NULL);
    CHECK(t.boundary_edges == 0 && t.misoriented_edges == 0);

    /* Normals of a box corner: the mean of three axis normals. */
    CHECK(fm_mesh_compute_normals(box, NULL) == FM_OK);
    for (int i = 0; i < 8; i++) {
        float *n = box->normals + 3 * i;
        CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5);
        for (int k = 0; k < 3; k++)
            CHECK(((i >> k) & 1) ? n[k] > 0.3f : n[k] < -0.3f);
    }
    fm_mesh_free(b2);
    fm_mesh_free(soup);
    fm_mesh_free(box);
}

static void test_budget(void)
{
    fm_mesh_budget b = {4, 4};
    fm_error err;
    fm_error_clear(&err);
    fm_mesh *m = fm_mesh_new(8, 2, 0, &b, &err);
    CHECK(m == NULL && err.code == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "budget");
    m = fm_mesh_new(4, 4, 0, &b, &err);
    CHECK(m != NULL);
    float p[3] = {0, 0, 0};
    for (int i = 0; i < 4; i++)
        CHECK(fm_mesh_add_vertex(m, p, NULL, NULL, &err) == (size_t)i);
    CHECK(fm_mesh_add_vertex(m, p, NULL, NULL, &err) == (size_t)-1);
    CHECK(err.code == FM_ERR_LIMIT);
    CHECK(fm_mesh_add_triangle(m, 0, 1, 9, &err) == (size_t)-1);
    fm_mesh_free(m);
}

static void test_stl(void)
{
    const float lo[3] = {0, 0, 0}, hi[3] = {2, 3, 4};
    fm_mesh *m = fixture_box(lo, hi);
    uint8_t *buf = NULL;
    size_t size = 0;
    CHECK(fm_mesh_encode_stl(m, &buf, &size, NULL) == FM_OK);
    CHECK(size == 84 + 50 * 12);
    CHECK(strncmp((const char *)buf, "solid", 5) != 0);
    CHECK(rd_u32(buf + 80) == 12);
    for (int t = 0; t < 12; t++) {
        const uint8_t *r = buf + 84 + 50 * t;
        const float *want = fixture_box_normals[t / 2];
        for (int k = 0; k < 3; k++)
            CHECK_NEAR(rd_f32(r + 4 * k), want[k], 1e-6);
        const int *q = fixture_box_quads[t / 2];
        int corner[3] = {q[0], q[(t & 1) ? 2 : 1], q[(t & 1) ? 3 : 2]};
        for (int v = 0; v < 3; v++)
            for (int k = 0; k < 3; k++)
                CHECK(rd_f32(r + 12 + 12 * v + 4 * k) == ((corner[v] >> k) & 1 ? hi[k] : lo[k]));
    }
    free(buf);
    fm_mesh_free(m);
}

static void test_ply(void)
{
    const double c[3] = {1, 2, 3};
    fm_mesh *m = fixture_sphere(c, 5, 6, 8);
    uint8_t *buf = NULL;
    size_t size = 0;
    CHECK(fm_mesh_encode_ply(m, &buf, &size, NULL) == FM_OK);
    const char *end = strstr((const char *)buf, "end_header\n");
    CHECK(end != NULL);
    if (!end) {
        free(buf);
        fm_mesh_free(m);
        return;
    }
    size_t header = (size_t)(end - (const char *)buf) + 11;
    char text[1024];
    memcpy(text, buf, header < sizeof text - 1 ? header : sizeof text - 1);
    text[header < sizeof text - 1 ? header : sizeof text - 1] = 0;
    CHECK_STR_CONTAINS(text, "format binary_little_endian 1.0");
    char want[64];
    snprintf(want, sizeof want, "element vertex %zu\n", m->vertex_count);
    CHECK_STR_CONTAINS(text, want);
    snprintf(want, sizeof want, "element face %zu\n", m->triangle_count);
    CHECK_STR_CONTAINS(text, want);
    CHECK_STR_CONTAINS(text, "property uchar red");
    CHECK_STR_CONTAINS(text, "property float nz");
    /* Vertex: 6 floats + 3 bytes; face: count byte + 3 uint32. */
    CHECK(size == header + m->vertex_count * 27 + m->triangle_count * 13);
    const uint8_t *v = buf + header;
    for (size_t i = 0; i < m->vertex_count; i++, v += 27) {
        for (int k = 0; k < 3; k++) {
            CHECK(rd_f32(v + 4 * k) == m->positions[3 * i + k]);
            CHECK(rd_f32(v + 12 + 4 * k) == m->normals[3 * i + k]);
            /* The fixture colours each channel by the normal's sign. */
            CHECK(v[24 + k] == (m->normals[3 * i + k] > 0 ? 200 : 40));
        }
    }
    const uint8_t *f = v;
    for (size_t t = 0; t < m->triangle_count; t++, f += 13) {
        CHECK(f[0] == 3);
        for (int k = 0; k < 3; k++)
            CHECK(rd_u32(f + 1 + 4 * k) == m->triangles[3 * t + k]);
    }
    free(buf);
    fm_mesh_free(m);
}

static void test_obj_and_files(void)
{
    const float lo[3] = {-0.125f, 0, 0}, hi[3] = {1, 1.0f / 3.0f, 7};
    fm_mesh *m = fixture_box(lo, hi);
    uint8_t *buf = NULL;
    size_t size = 0;
    CHECK(fm_mesh_encode_obj(m, &buf, &size, NULL) == FM_OK);
    char *text = malloc(size + 1);
    memcpy(text, buf, size);
    text[size] = 0;
    size_t nv = 0, nf = 0;
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        float x, y, z;
        unsigned a, b, c;
        if (sscanf(line, "v %f %f %f", &x, &y, &z) == 3) {
            /* %.9g must bring back the very same floats. */
            CHECK(x == m->positions[3 * nv] && y == m->positions[3 * nv + 1] &&
                  z == m->positions[3 * nv + 2]);
            nv++;
        } else if (sscanf(line, "f %u %u %u", &a, &b, &c) == 3) {
            CHECK(a == m->triangles[3 * nf] + 1 && b == m->triangles[3 * nf + 1] + 1 &&
                  c == m->triangles[3 * nf + 2] + 1);
            nf++;
        }
    }
    CHECK(nv == 8 && nf == 12);
    free(text);
    free(buf);

    CHECK(fm_mesh_format_from_path("a/b.STL") == FM_MESH_FORMAT_STL);
    CHECK(fm_mesh_format_from_path("x.drc") == FM_MESH_FORMAT_DRACO);
    CHECK(fm_mesh_format_from_path("x.ply") == FM_MESH_FORMAT_PLY);
    CHECK(fm_mesh_format_from_path("x.Obj") == FM_MESH_FORMAT_OBJ);
    CHECK(fm_mesh_format_from_path("x.d/stl") == FM_MESH_FORMAT_UNKNOWN);
    CHECK(fm_mesh_format_from_path("stl") == FM_MESH_FORMAT_UNKNOWN);

    char path[64];
    snprintf(path, sizeof path, "/tmp/fm_test_mesh_%d.stl", (int)getpid());
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_mesh_write_file(m, path, NULL, &err) == FM_OK);
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL);
    if (f) {
        fseek(f, 0, SEEK_END);
        CHECK(ftell(f) == 84 + 50 * 12);
        fclose(f);
    }
    remove(path);
    CHECK(fm_mesh_write_file(m, "/tmp/x.xyz", NULL, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, ".drc");
    CHECK(fm_mesh_write_file(m, "/nonexistent-dir/x.stl", NULL, &err) == FM_ERR_IO);
    fm_mesh_free(m);
}

int main(void)
{
    test_box_topology_and_volume();
    test_weld_and_append();
    test_budget();
    test_stl();
    test_ply();
    test_obj_and_files();
    return test_summary("mesh_core");
}
