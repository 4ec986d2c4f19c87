/* vdb_measure.cpp: what the grid measures and answers without changing
 * it: inside volume (the same smooth Heaviside the cuts use, summed
 * deterministically), surface area (OpenVDB's LevelSetMeasure), memory, the
 * active voxels' bounding box and trilinear samples. */
#include "stock/vdb_bridge.hpp"

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetMeasure.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <vector>

using namespace fm_vdb_bridge;

extern "C" {

double fm_vdb_volume(const fm_vdb *v)
{
    double result = 0;
    fm_error err;
    guarded(&err, "volume", [&]() -> fm_status {
        const Tree &tree = v->grid->constTree();
        const double inv = 1.0 / v->voxel;
        openvdb::tree::LeafManager<const Tree> leaves(tree);
        double sum = 0;
        v->arena->execute([&] {
            /* deterministic: the same grid gives the same bits whatever
             * the thread count, so volumes can be compared exactly */
            sum = tbb::parallel_deterministic_reduce(
                leaves.leafRange(64), 0.0,
                [&](const openvdb::tree::LeafManager<const Tree>::LeafRange &r, double acc) {
                    for (auto it = r.begin(); it; ++it)
                        for (int i = 0; i < LEAF_SIZE; i++)
                            acc += inside_fraction(it->getValue(i), inv);
                    return acc;
                },
                [](double a, double b) { return a + b; });
        });
        /* tiles, without visiting leaf voxels */
        Tree::ValueAllCIter it = tree.cbeginValueAll();
        it.setMaxDepth(Tree::ValueAllCIter::LEAF_DEPTH - 1);
        for (; it; ++it)
            if (*it < 0) sum += double(it.getBoundingBox().volume());
        result = sum * v->voxel * v->voxel * v->voxel;
        return FM_OK;
    });
    return result;
}

fm_status fm_vdb_area(const fm_vdb *v, double *area, fm_error *err)
{
    return guarded(err, "surface area", [&]() -> fm_status {
        double a = 0;
        v->arena->execute([&] { a = openvdb::tools::levelSetArea(*v->grid, true); });
        *area = a;
        return FM_OK;
    });
}

size_t fm_vdb_memory(const fm_vdb *v)
{
    size_t m = 0;
    fm_error err;
    guarded(&err, "memory", [&]() -> fm_status {
        m = size_t(v->grid->memUsage());
        return FM_OK;
    });
    return m;
}

void fm_vdb_memory_usage(const fm_vdb *v, fm_vdb_counts *out)
{
    std::memset(out, 0, sizeof *out);
    fm_error err;
    guarded(&err, "memory", [&]() -> fm_status {
        const Tree &tree = v->grid->constTree();
        out->memusage = size_t(tree.memUsage());
        out->leaves = size_t(tree.leafCount());
        out->active_voxels = size_t(tree.activeVoxelCount());
        std::vector<openvdb::Index32> nodes = tree.nodeCount(); /* leaves first, the root last */
        for (size_t i = 1; i + 1 < nodes.size(); i++) out->internal_nodes += nodes[i];
        return FM_OK;
    });
}

int fm_vdb_active_bounds(const fm_vdb *v, int32_t lo[3], int32_t hi[3])
{
    int found = 0;
    fm_error err;
    guarded(&err, "bounds", [&]() -> fm_status {
        const CoordBBox bb = v->grid->evalActiveVoxelBoundingBox();
        if (bb.empty()) return FM_OK;
        for (int k = 0; k < 3; k++) {
            lo[k] = bb.min()[k];
            hi[k] = bb.max()[k];
        }
        found = 1;
        return FM_OK;
    });
    return found;
}

double fm_vdb_sample(const fm_vdb *v, const double p[3])
{
    double r = v->background;
    fm_error err;
    guarded(&err, "sample", [&]() -> fm_status {
        Grid::ConstAccessor acc = v->grid->getConstAccessor();
        openvdb::tools::GridSampler<Grid::ConstAccessor, openvdb::tools::BoxSampler> s(
            acc, v->grid->transform());
        r = s.wsSample(openvdb::Vec3d(p[0], p[1], p[2]));
        return FM_OK;
    });
    return r;
}

double fm_vdb_time_bare_update(fm_vdb *v, const int32_t (*origins)[3], const uint64_t (*sets)[8],
                               size_t n, size_t *voxels)
{
    double best = 0;
    size_t count = 0;
    fm_error err;
    guarded(&err, "timing voxel updates", [&]() -> fm_status {
        Tree &tree = v->grid->tree();
        Acc acc(tree);
        const float low = -v->background;
        for (int round = 0; round < 3; round++) {
            size_t c = 0;
            const auto t0 = std::chrono::steady_clock::now();
            for (size_t j = 0; j < n; j++) {
                const Coord o(origins[j][0], origins[j][1], origins[j][2]);
                for (int w = 0; w < LEAF_SIZE / 64; w++) {
                    for (uint64_t bits = sets[j][w]; bits; bits &= bits - 1) {
                        const int i = 64 * w + __builtin_ctzll(bits);
                        const Coord ijk = o.offsetBy(i >> 6, (i >> 3) & 7, i & 7);
                        acc.setValueOnly(ijk, std::max(acc.getValue(ijk), low));
                        c++;
                    }
                }
            }
            const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            count = c;
            if (c && (round == 0 || t / double(c) < best)) best = t / double(c);
        }
        return FM_OK;
    });
    *voxels = count;
    return best;
}

} // extern "C"
