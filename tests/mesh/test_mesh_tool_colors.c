/* test_mesh_tool_colors.c: meshes coloured by the tool that last cut.
 * A box stock gets a flat pocket from tool 3, then a deeper round pocket
 * from tool 7 that cuts into the first one's wall and floor. Each vertex
 * of the mesh lies on one of three known surfaces (the box's, the first
 * pocket's, the second's); which one is decided here from the closed-form
 * distances to the three, and the colour must be that surface's: grey for
 * the box, tool 3's and tool 7's hues for the pockets. Vertices within a
 * few voxels of two surfaces (the edges) are left out, since the voxel
 * nearest the vertex may belong to either. The per-chunk meshes carry the
 * same colours as the whole-grid mesh, a snapshot keeps them, depth
 * colouring with uncut_grey greys exactly the box's faces, and a cut
 * that removes a whole region forgets its marks. */
#include "stock/fields.h"
#include "test.h"

#include "mesh/mesh.h"
#include "stock/stock.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const double VOXEL = 0.2;

/* 0: the box's own faces, 1: pocket of tool 3, 2: pocket of tool 7, -1: too
 * near two of them to say. */
static int owner(const shape *box, const shape *p1, const shape *p2, const float *v)
{
    const double d[3] = {fabs(shape_eval(box, v[0], v[1], v[2])),
                         fabs(shape_eval(p1, v[0], v[1], v[2])),
                         fabs(shape_eval(p2, v[0], v[1], v[2]))};
    int best = 0;
    for (int k = 1; k < 3; k++)
        if (d[k] < d[best]) best = k;
    for (int k = 0; k < 3; k++)
        if (k != best && d[k] - d[best] < 2.5 * VOXEL) return -1;
    return best;
}

typedef struct vkey {
    float p[3];
    uint8_t rgb[3];
} vkey;

static int cmp_vkey(const void *a, const void *b) { return memcmp(a, b, sizeof(vkey)); }

/* Vertices (position and colour) sorted, so that two meshes' vertex sets
 * compare with one memcmp. */
static vkey *sorted_vertices(const fm_mesh *m)
{
    vkey *k = calloc(m->vertex_count ? m->vertex_count : 1, sizeof *k);
    for (size_t i = 0; k && i < m->vertex_count; i++) {
        memcpy(k[i].p, m->positions + 3 * i, sizeof k[i].p);
        memcpy(k[i].rgb, m->colors + 3 * i, 3);
    }
    if (k) qsort(k, m->vertex_count, sizeof *k, cmp_vkey);
    return k;
}

static void check_same_colours(const fm_mesh *a, const fm_mesh *b, const char *what)
{
    CHECK(a->vertex_count == b->vertex_count);
    if (a->vertex_count != b->vertex_count) return;
    vkey *ka = sorted_vertices(a), *kb = sorted_vertices(b);
    CHECK(ka && kb);
    if (ka && kb) {
        int same = memcmp(ka, kb, a->vertex_count * sizeof *ka) == 0;
        if (!same) fprintf(stderr, "%s: vertex colours differ\n", what);
        CHECK(same);
    }
    free(ka);
    free(kb);
}

static fm_mesh *chunk_union(fm_stock *s, const fm_mesh_extract_options *o)
{
    fm_stock_chunk chunks[256];
    size_t n = fm_stock_changed_chunks(s, 0, chunks, 256);
    CHECK(n > 0 && n <= 256);
    fm_mesh *u = fm_mesh_new(0, 0, FM_MESH_NORMALS | FM_MESH_COLORS, NULL, NULL);
    for (size_t i = 0; u && i < n && i < 256; i++) {
        fm_error err;
        fm_mesh *c = fm_mesh_from_stock_chunk(s, chunks[i].index, o, &err);
        CHECK(c != NULL);
        if (c) CHECK(fm_mesh_append(u, c, &err) == FM_OK);
        fm_mesh_free(c);
    }
    if (u) CHECK(fm_mesh_weld(u, NULL) == FM_OK);
    return u;
}

static void test_two_tools(void)
{
    fm_error err;
    shape box = {.kind = SHAPE_BOX, .a = {0, 0, 0}, .b = {30, 24, 16}};
    /* tool 3: flat pocket 6..20 x 4..20, floor at z 10, open to the top */
    shape p1 = {.kind = SHAPE_BOX, .a = {6, 4, 10}, .b = {20, 20, 20}};
    /* tool 7: round pocket r 5 around (20, 12), floor at z 6, open to the
     * top: cuts into the first pocket's right wall and floor */
    shape p2 = {.kind = SHAPE_CYLINDER, .a = {20, 12, 6}, .b = {20}, .r = 5};
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = VOXEL;
    fm_stock *s = fm_stock_new_box(box.a, box.b, &so, &err);
    CHECK(s != NULL);
    if (!s) return;
    fm_field f1 = shape_field(&p1), f2 = shape_field(&p2);
    fm_stock_cut c1 = {3, 1, 0, 1}, c2 = {7, 2, 1, 2};
    CHECK(fm_stock_subtract(s, &f1, &c1, NULL, &err) == FM_OK);
    CHECK(fm_stock_subtract(s, &f2, &c2, NULL, &err) == FM_OK);

    fm_mesh_extract_options o;
    fm_mesh_extract_default(&o);
    o.coloring = FM_MESH_COLOR_TOOL;
    fm_mesh *m = fm_mesh_from_stock(s, &o, &err);
    CHECK(m && m->colors);
    if (!m || !m->colors) {
        fm_mesh_free(m);
        fm_stock_free(s);
        return;
    }
    uint8_t want[3][3];
    fm_mesh_tool_color(-1, want[0]);
    fm_mesh_tool_color(3, want[1]);
    fm_mesh_tool_color(7, want[2]);
    CHECK(memcmp(want[0], want[1], 3) && memcmp(want[1], want[2], 3) &&
          memcmp(want[0], want[2], 3));
    size_t count[3] = {0}, wrong = 0, skipped = 0;
    for (size_t i = 0; i < m->vertex_count; i++) {
        const int k = owner(&box, &p1, &p2, m->positions + 3 * i);
        if (k < 0) {
            skipped++;
            continue;
        }
        count[k]++;
        if (memcmp(m->colors + 3 * i, want[k], 3)) {
            if (wrong < 5)
                fprintf(stderr, "vertex %.3f %.3f %.3f: colour %d %d %d, surface %d\n",
                        m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2],
                        m->colors[3 * i], m->colors[3 * i + 1], m->colors[3 * i + 2], k);
            wrong++;
        }
    }
    printf("two tools: %zu vertices: %zu box, %zu tool 3, %zu tool 7, %zu near edges, %zu "
           "wrong\n",
           m->vertex_count, count[0], count[1], count[2], skipped, wrong);
    CHECK(wrong == 0);
    CHECK(count[0] > 10000 && count[1] > 3000 && count[2] > 3000);

    /* chunks: same vertices, same colours */
    fm_mesh *u = chunk_union(s, &o);
    CHECK(u != NULL);
    if (u) check_same_colours(u, m, "chunk union");
    fm_mesh_free(u);

    /* depth colouring with uncut_grey: grey exactly where tool colouring
     * is grey */
    fm_mesh_extract_options od = o;
    od.coloring = FM_MESH_COLOR_DEPTH;
    od.top_z = 16;
    od.uncut_grey = 1;
    fm_mesh *md = fm_mesh_from_stock(s, &od, &err);
    CHECK(md && md->vertex_count == m->vertex_count);
    size_t mismatch = 0;
    for (size_t i = 0; md && i < md->vertex_count; i++) {
        const int grey_t = !memcmp(m->colors + 3 * i, want[0], 3);
        const int grey_d = !memcmp(md->colors + 3 * i, want[0], 3);
        if (grey_t != grey_d) mismatch++;
    }
    CHECK(mismatch == 0);
    fm_mesh_free(md);

    /* a snapshot keeps the marks */
    char path[] = "/tmp/fm_tool_colors_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0);
    if (fd >= 0) close(fd);
    CHECK(fm_stock_save(s, path, NULL, &err) == FM_OK);
    fm_stock *r = fm_stock_load_vdb(path, NULL, &err);
    CHECK(r != NULL);
    if (r) {
        fm_mesh *mr = fm_mesh_from_stock(r, &o, &err);
        CHECK(mr != NULL);
        if (mr) check_same_colours(mr, m, "after a snapshot");
        fm_mesh_free(mr);
        fm_stock_free(r);
    }
    unlink(path);
    char prev[64];
    snprintf(prev, sizeof prev, "%s.prev", path);
    unlink(prev);

    /* a third cut by tool 3 removes the whole top 10 mm: every mark above
     * it goes with it, the new floor is tool 3's, tool 7's round pocket
     * below z 10 stays tool 7's */
    const size_t before = fm_stock_memory_bytes(s);
    int tool = -1;
    const double wall3[3] = {6, 12, 14}, wall7[3] = {25, 12, 13};
    CHECK(fm_stock_point_tool(s, wall3, &tool) && tool == 3);
    CHECK(fm_stock_point_tool(s, wall7, &tool) && tool == 7);
    shape top = {.kind = SHAPE_BOX, .a = {-1, -1, 10}, .b = {31, 25, 20}};
    fm_field ft = shape_field(&top);
    CHECK(fm_stock_subtract(s, &ft, &c1, NULL, &err) == FM_OK);
    CHECK(fm_stock_memory_bytes(s) < before);
    const double floor_pt[3] = {3, 3, 10}, hole_floor[3] = {20, 12, 6};
    CHECK(fm_stock_point_tool(s, floor_pt, &tool) && tool == 3);
    CHECK(fm_stock_point_tool(s, hole_floor, &tool) && tool == 7);
    CHECK(!fm_stock_point_tool(s, wall3, &tool));
    CHECK(!fm_stock_point_tool(s, wall7, &tool));
    const double side[3] = {0, 12, 3};
    CHECK(!fm_stock_point_tool(s, side, &tool));

    fm_mesh_free(m);
    fm_stock_free(s);
}

int main(void)
{
    test_two_tools();
    return test_summary("mesh_tool_colors");
}
