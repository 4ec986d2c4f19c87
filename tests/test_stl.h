/* test_stl.h: a box as an ASCII STL file, for the tests that need a mesh
 * whose volume and faces they know (an STL stock, an STL fixture), and the
 * same box with one face left out (an open surface). */
#ifndef FM_TEST_STL_H
#define FM_TEST_STL_H

#include <stdio.h>

/* The faces in file order, each two triangles over its corners (corner
 * bits: x, y, z from lo (0) or hi (1)), counter-clockwise seen from
 * outside: z = lo, z = hi, y = lo, y = hi, x = lo, x = hi. Facet k (from 0)
 * starts on line 2 + 7 k. */
enum { FM_TEST_BOX_NO_FACE = -1, FM_TEST_BOX_TOP = 1 };

/* The box [lo, hi], without face skip (FM_TEST_BOX_NO_FACE: closed); 0, or
 * -1 when the file cannot be written. */
static inline int fm_test_write_box_stl(const char *path, const double lo[3], const double hi[3],
                                        int skip)
{
    static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fprintf(f, "solid box\n");
    for (int k = 0; k < 6; k++) {
        if (k == skip) continue;
        const int t[2][3] = {{q[k][0], q[k][1], q[k][2]}, {q[k][0], q[k][2], q[k][3]}};
        for (int j = 0; j < 2; j++) {
            fprintf(f, "facet normal 0 0 0\nouter loop\n");
            for (int v = 0; v < 3; v++) {
                const int c = t[j][v];
                fprintf(f, "vertex %.9g %.9g %.9g\n", c & 1 ? hi[0] : lo[0],
                        c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]);
            }
            fprintf(f, "endloop\nendfacet\n");
        }
    }
    fprintf(f, "endsolid box\n");
    return fclose(f) == 0 ? 0 : -1;
}

#endif
