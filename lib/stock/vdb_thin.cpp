/* vdb_thin.cpp: the voxels next to material thinner than a voxel, which the
 * volume measure counts and the mesh cannot show (fm_vdb_thin_voxels, used
 * by thin.c's fm_stock_thin_regions). A voxel centre outside the stock with
 * the surface within half a voxel of it, none of whose 26 neighbours is
 * inside: the marching cubes that touch it have no inside corner, so no
 * face stands for that material. Leaves are scanned in parallel in the
 * stock's arena. Signs here are OpenVDB's: negative inside. */
#include "stock/vdb_bridge.hpp"

#include <openvdb/tree/LeafManager.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <vector>

using namespace fm_vdb_bridge;

namespace {

/* Is the voxel at c (value phi, outside) beside material no neighbour
 * holds? */
bool thin_at(CAcc &acc, const Coord &c)
{
    for (int dx = -1; dx <= 1; dx++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dz = -1; dz <= 1; dz++) {
                if (!dx && !dy && !dz) continue;
                if (acc.getValue(c.offsetBy(dx, dy, dz)) <= 0.0f) return false;
            }
    return true;
}

} // namespace

extern "C" fm_status fm_vdb_thin_voxels(const fm_vdb *v, size_t cap, int32_t **ijk, size_t *count,
                                        size_t *total, fm_error *err)
{
    *ijk = nullptr;
    *count = *total = 0;
    return guarded(err, "thin material", [&]() -> fm_status {
        const Tree &tree = v->grid->tree();
        openvdb::tree::LeafManager<const Tree> leaves(tree);
        const float half_voxel = float(0.5 * v->voxel);
        /* each thread keeps at most cap voxels (memory stays bounded) and
         * counts them all */
        struct Found {
            std::vector<Coord> kept;
            size_t seen = 0;
        };
        tbb::enumerable_thread_specific<Found> found;
        v->arena->execute([&] {
            tbb::parallel_for(leaves.leafRange(), [&](const openvdb::tree::LeafManager<const Tree>::LeafRange &r) {
                CAcc acc(tree);
                Found &mine = found.local();
                for (auto leaf = r.begin(); leaf; ++leaf) {
                    const float *buf = leaf->buffer().data();
                    for (int i = 0; i < LEAF_SIZE; i++) {
                        const float phi = buf[i];
                        if (!(phi > 0.0f && phi <= half_voxel)) continue;
                        const Coord c = leaf->offsetToGlobalCoord(openvdb::Index(i));
                        if (!thin_at(acc, c)) continue;
                        if (mine.kept.size() < cap) mine.kept.push_back(c);
                        mine.seen++;
                    }
                }
            });
        });
        size_t n = 0;
        for (const Found &f : found) n += f.seen;
        *total = n;
        const size_t keep = std::min(n, cap);
        if (!keep) return FM_OK;
        int32_t *out = static_cast<int32_t *>(std::malloc(3 * keep * sizeof *out));
        if (!out) return fm_error_set(err, FM_ERR_LIMIT, "thin material: out of memory");
        size_t k = 0;
        for (const Found &f : found)
            for (const Coord &c : f.kept) {
                if (k == keep) break;
                out[3 * k] = c.x(), out[3 * k + 1] = c.y(), out[3 * k + 2] = c.z();
                k++;
            }
        *ijk = out;
        *count = keep;
        return FM_OK;
    });
}
