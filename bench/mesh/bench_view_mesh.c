/* bench_view_mesh.c: the finished stock's whole mesh for the viewer (not a
 * test). Loads a stock snapshot (a job's stock.vdb) and meshes it whole at
 * each adaptivity given, printing the triangles, the Draco bytes, the time,
 * and how far the mesh strays from the stock's surface: the largest
 * |signed distance| of the grid (trilinear, lib/stock) at each vertex, edge
 * midpoint and centroid of every triangle. That is how the daemon's
 * FM_PUBLISH_VIEW_ADAPTIVITY was chosen (docs/daemon.md).
 * Usage: bench_view_mesh stock.vdb [adaptivity...] (default 0 0.1 0.2 0.3 0.5). */
#include "mesh/mesh.h"
#include "stock/stock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "bench_clock.h"

/* Largest |distance| of the surface sampled on the mesh's triangles, mm. */
static double max_deviation(const fm_stock *stock, const fm_mesh *mesh)
{
    double worst = 0;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const float *v[3];
        for (int k = 0; k < 3; k++) v[k] = mesh->positions + 3 * (size_t)mesh->triangles[3 * t + k];
        /* barycentric weights: the corners, the edge midpoints, the centroid */
        static const double w[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {.5, .5, 0}, {0, .5, .5},
                                       {.5, 0, .5}, {1 / 3., 1 / 3., 1 / 3.}};
        for (int s = 0; s < 7; s++) {
            double p[3];
            for (int c = 0; c < 3; c++) p[c] = w[s][0] * v[0][c] + w[s][1] * v[1][c] + w[s][2] * v[2][c];
            double d = fabs(fm_stock_sample(stock, p));
            if (d > worst) worst = d;
        }
    }
    return worst;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_view_mesh stock.vdb [adaptivity...]\n");
        return 2;
    }
    fm_error err;
    fm_error_clear(&err);
    fm_stock_options sopt;
    fm_stock_options_default(&sopt);
    fm_stock *stock = fm_stock_load_vdb(argv[1], &sopt, &err);
    if (!stock) {
        fprintf(stderr, "bench_view_mesh: %s: %s\n", argv[1], err.message);
        return 1;
    }
    static const char *defaults[] = {"0", "0.1", "0.2", "0.3", "0.5"};
    int count = argc > 2 ? argc - 2 : 5;
    printf("%s: voxel %.3f mm\n", argv[1], fm_stock_voxel_size(stock));
    printf("adaptivity  triangles  draco_bytes  mesh_s  encode_s  max_deviation_mm\n");
    int rc = 0;
    for (int i = 0; i < count; i++) {
        fm_mesh_extract_options opt;
        fm_mesh_extract_default(&opt);
        opt.adaptivity = atof(argc > 2 ? argv[i + 2] : defaults[i]);
        opt.coloring = FM_MESH_COLOR_TOOL;
        double t0 = bench_wall_s();
        fm_mesh *mesh = fm_mesh_from_stock(stock, &opt, &err);
        double t1 = bench_wall_s();
        uint8_t *drc = NULL;
        size_t size = 0;
        if (!mesh || fm_mesh_encode_draco(mesh, NULL, &drc, &size, &err) != FM_OK) {
            fprintf(stderr, "bench_view_mesh: adaptivity %g: %s\n", opt.adaptivity, err.message);
            fm_mesh_free(mesh);
            rc = 1;
            continue;
        }
        double t2 = bench_wall_s();
        printf("%10.2f  %9zu  %11zu  %6.2f  %8.2f  %16.4f\n", opt.adaptivity, mesh->triangle_count, size,
               t1 - t0, t2 - t1, max_deviation(stock, mesh));
        free(drc);
        fm_mesh_free(mesh);
    }
    fm_stock_free(stock);
    return rc;
}
