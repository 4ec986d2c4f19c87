/* vdb_mesh_to_volume.cpp: a closed triangle soup (an STL stock) to the
 * stock's level set with OpenVDB's tools::meshToLevelSet, on the stock's
 * transform and band. */
#include "stock/vdb_bridge.hpp"

#include <openvdb/tools/MeshToVolume.h>

#include <vector>

using namespace fm_vdb_bridge;

extern "C" {

fm_status fm_vdb_from_mesh(fm_vdb *v, const float *points, size_t npoints, const uint32_t *tris,
                           size_t ntris, fm_error *err)
{
    return guarded(err, "converting the mesh to a level set", [&]() -> fm_status {
        std::vector<openvdb::Vec3s> pts(npoints);
        for (size_t i = 0; i < npoints; i++)
            pts[i] = openvdb::Vec3s(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
        std::vector<openvdb::Vec3I> tri(ntris);
        for (size_t i = 0; i < ntris; i++)
            tri[i] = openvdb::Vec3I(tris[3 * i], tris[3 * i + 1], tris[3 * i + 2]);
        Grid::Ptr g;
        v->arena->execute([&] {
            g = openvdb::tools::meshToLevelSet<Grid>(v->grid->transform(), pts, tri,
                                                     float(v->band));
        });
        g->setGridClass(openvdb::GRID_LEVEL_SET);
        g->setName("stock");
        v->grid = g;
        v->background = g->background();
        refresh_bounds(v);
        return FM_OK;
    });
}

} // extern "C"
