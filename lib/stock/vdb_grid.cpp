/* vdb_grid.cpp: the stock grid's life: creating an empty level set with
 * its transform and thread arena, freeing it, the per-node byte costs the
 * budget formulas use, plain accessors, the leaf walk for initial chunk
 * marking, and the private door lib/mesh reads the grid through. */
#include "stock/vdb_bridge.hpp"

#include <mutex>

using namespace fm_vdb_bridge;

namespace fm_vdb_bridge {

void init_openvdb()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr make_transform(double voxel, const double origin[3])
{
    auto xf = openvdb::math::Transform::createLinearTransform(voxel);
    xf->postTranslate(openvdb::Vec3d(origin[0], origin[1], origin[2]));
    return xf;
}

std::unique_ptr<tbb::task_arena> make_arena(int threads)
{
    /* copied to a local: make_unique would odr-use the static member */
    int n = tbb::task_arena::automatic;
    if (threads > 0) n = threads;
    return std::make_unique<tbb::task_arena>(n);
}

void refresh_bounds(fm_vdb *v)
{
    CoordBBox bb;
    v->grid->tree().evalLeafBoundingBox(bb);
    v->has_bounds = !bb.empty();
    if (v->has_bounds) {
        v->bounds_lo = bb.min();
        v->bounds_hi = bb.max();
    }
    v->leaves = v->grid->tree().leafCount();
}

} // namespace fm_vdb_bridge

extern "C" {

size_t fm_vdb_leaf_bytes(void)
{
    /* the node, its separately allocated value buffer, and malloc's header
     * for each of the two */
    return sizeof(Leaf) + sizeof(float) * LEAF_SIZE + 32;
}

size_t fm_vdb_leaf_memusage(void) { return sizeof(Leaf) + sizeof(float) * LEAF_SIZE; }

size_t fm_vdb_internal1_bytes(void) { return sizeof(Node1) + 16; }

size_t fm_vdb_internal2_bytes(void) { return sizeof(Tree::RootNodeType::ChildNodeType) + 16; }

fm_vdb *fm_vdb_new(double voxel, int band, const double origin[3], int threads, fm_error *err)
{
    fm_vdb *out = nullptr;
    guarded(err, "creating the stock grid", [&]() -> fm_status {
        init_openvdb();
        auto v = std::make_unique<fm_vdb>();
        v->voxel = voxel;
        v->band = band;
        v->background = float(band * voxel);
        for (int k = 0; k < 3; k++) v->origin[k] = origin[k];
        v->grid = Grid::create(v->background);
        v->grid->setTransform(make_transform(voxel, origin));
        v->grid->setGridClass(openvdb::GRID_LEVEL_SET);
        v->grid->setName("stock");
        v->arena = make_arena(threads);
        out = v.release();
        return FM_OK;
    });
    return out;
}

void fm_vdb_free(fm_vdb *v)
{
    try {
        delete v;
    } catch (...) {
        /* destructors do not throw; nothing to report to */
    }
}

double fm_vdb_voxel(const fm_vdb *v) { return v->voxel; }
int fm_vdb_band(const fm_vdb *v) { return v->band; }
void fm_vdb_origin(const fm_vdb *v, double origin[3])
{
    for (int k = 0; k < 3; k++) origin[k] = v->origin[k];
}

void fm_vdb_for_each_leaf(const fm_vdb *v, fm_vdb_touch_fn touch, void *user)
{
    fm_error err;
    guarded(&err, "leaves", [&]() -> fm_status {
        for (auto it = v->grid->constTree().cbeginLeaf(); it; ++it) {
            const Coord o = it->origin();
            const int32_t lo[3] = {o.x(), o.y(), o.z()};
            const int32_t hi[3] = {o.x() + LEAF_DIM - 1, o.y() + LEAF_DIM - 1,
                                   o.z() + LEAF_DIM - 1};
            touch(user, lo, hi);
        }
        return FM_OK;
    });
}

void *fm_vdb_grid_ptr(fm_vdb *v) { return &v->grid; }

} // extern "C"
