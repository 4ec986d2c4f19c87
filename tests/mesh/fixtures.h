/* fixtures.h: meshes built by hand for the lib/mesh tests, whose geometry is
 * known independently of lib/mesh (a box, a UV sphere). */
#ifndef FM_TESTS_MESH_FIXTURES_H
#define FM_TESTS_MESH_FIXTURES_H

#include "mesh/mesh.h"

#include <math.h>

/* Corner i of the box has x from bit 0, y from bit 1, z from bit 2. The six
 * quads are listed counter-clockwise seen from outside. */
static const int fixture_box_quads[6][4] = {
    {0, 2, 3, 1}, /* -z */
    {4, 5, 7, 6}, /* +z */
    {0, 1, 5, 4}, /* -y */
    {2, 6, 7, 3}, /* +y */
    {0, 4, 6, 2}, /* -x */
    {1, 3, 7, 5}, /* +x */
};
static const float fixture_box_normals[6][3] = {
    {0, 0, -1}, {0, 0, 1}, {0, -1, 0}, {0, 1, 0}, {-1, 0, 0}, {1, 0, 0}};

static inline fm_mesh *fixture_box(const float lo[3], const float hi[3])
{
    fm_mesh *m = fm_mesh_new(8, 12, 0, NULL, NULL);
    if (!m)
        return NULL;
    for (int i = 0; i < 8; i++) {
        float p[3] = {(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]};
        fm_mesh_add_vertex(m, p, NULL, NULL, NULL);
    }
    for (int f = 0; f < 6; f++) {
        const int *q = fixture_box_quads[f];
        fm_mesh_add_triangle(m, (uint32_t)q[0], (uint32_t)q[1], (uint32_t)q[2], NULL);
        fm_mesh_add_triangle(m, (uint32_t)q[0], (uint32_t)q[2], (uint32_t)q[3], NULL);
    }
    return m;
}

/* A closed UV sphere of radius r about c: rings latitude bands, segs
 * longitudes, poles as single vertices. Normals are the exact radial
 * directions; colours encode the octant so a test can check them. */
static inline fm_mesh *fixture_sphere(const double c[3], double r, int rings, int segs)
{
    size_t nv = 2 + (size_t)(rings - 1) * segs;
    fm_mesh *m = fm_mesh_new(nv, 2 * (size_t)segs * (rings - 1), FM_MESH_NORMALS | FM_MESH_COLORS,
                             NULL, NULL);
    if (!m)
        return NULL;
    for (int i = 0; i <= rings; i++) {
        double th = FM_PI * i / rings;
        int count = (i == 0 || i == rings) ? 1 : segs;
        for (int j = 0; j < count; j++) {
            double ph = 2 * FM_PI * j / segs;
            double n[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
            float p[3], nf[3];
            uint8_t rgb[3];
            for (int k = 0; k < 3; k++) {
                p[k] = (float)(c[k] + r * n[k]);
                nf[k] = (float)n[k];
                rgb[k] = n[k] > 0 ? 200 : 40;
            }
            fm_mesh_add_vertex(m, p, nf, rgb, NULL);
        }
    }
    /* Vertex index of ring i (1..rings-1), segment j. */
#define FIX_V(i, j) ((uint32_t)(1 + ((i) - 1) * segs + ((j) % segs)))
    uint32_t south = (uint32_t)(nv - 1);
    for (int j = 0; j < segs; j++) {
        /* North cap: normal points up and out when seen from outside. */
        fm_mesh_add_triangle(m, 0, FIX_V(1, j), FIX_V(1, j + 1), NULL);
        for (int i = 1; i < rings - 1; i++) {
            fm_mesh_add_triangle(m, FIX_V(i, j), FIX_V(i + 1, j), FIX_V(i + 1, j + 1), NULL);
            fm_mesh_add_triangle(m, FIX_V(i, j), FIX_V(i + 1, j + 1), FIX_V(i, j + 1), NULL);
        }
        fm_mesh_add_triangle(m, FIX_V(rings - 1, j), south, FIX_V(rings - 1, j + 1), NULL);
    }
#undef FIX_V
    return m;
}

#endif
