/* vdb_bridge.hpp: what lib/stock's C++ files (vdb_*.cpp) share and nothing
 * else sees: the OpenVDB types and tree constants frepmill assumes, the
 * definition of struct fm_vdb (the grid, its transform data, thread arena
 * and budget bookkeeping), the exception guard every extern "C" function
 * runs in, and the small helpers more than one of them needs. The C API they
 * implement is declared in stock_private.h. */
#ifndef FM_STOCK_VDB_BRIDGE_HPP
#define FM_STOCK_VDB_BRIDGE_HPP

#include "stock/stock_private.h"

#include <openvdb/openvdb.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>
#include <new>

namespace fm_vdb_bridge {

using Grid = openvdb::FloatGrid;
using Tree = Grid::TreeType;
using Leaf = Tree::LeafNodeType;
using Node1 = Tree::RootNodeType::ChildNodeType::ChildNodeType; /* 128^3 voxels */
using Coord = openvdb::Coord;
using CoordBBox = openvdb::CoordBBox;
using Acc = openvdb::tree::ValueAccessor<Tree>;
using CAcc = openvdb::tree::ValueAccessor<const Tree>;

constexpr int LEAF_DIM = 8;     /* Leaf::DIM */
constexpr int NODE1_DIM = 128;  /* Node1::DIM */
constexpr int NODE2_DIM = 4096; /* the root's children */
constexpr int LEAF_SIZE = 512;

static_assert(Leaf::DIM == LEAF_DIM, "frepmill assumes OpenVDB's 5-4-3 float tree");
static_assert(Node1::DIM == NODE1_DIM, "frepmill assumes OpenVDB's 5-4-3 float tree");

/* Run f and turn any exception into an fm_error. */
template <class F>
fm_status guarded(fm_error *err, const char *what, F &&f)
{
    try {
        return f();
    } catch (const std::bad_alloc &) {
        return fm_error_set(err, FM_ERR_LIMIT, "%s: out of memory", what);
    } catch (const openvdb::Exception &e) {
        return fm_error_set(err, FM_ERR_INTERNAL, "%s: OpenVDB: %s", what, e.what());
    } catch (const std::exception &e) {
        return fm_error_set(err, FM_ERR_INTERNAL, "%s: %s", what, e.what());
    } catch (...) {
        return fm_error_set(err, FM_ERR_INTERNAL, "%s: unknown C++ exception", what);
    }
}

/* Linear smooth Heaviside: the part of a voxel inside the surface. Exact for
 * planes through voxel faces; used for every volume so that the per-cut
 * removed volume and the whole-grid volume agree. */
inline double inside_fraction(float phi, double inv_voxel)
{
    double f = 0.5 - phi * inv_voxel;
    return f <= 0.0 ? 0.0 : (f >= 1.0 ? 1.0 : f);
}

/* A field's value clamped to the band, F-rep sign, as a grid stores it
 * (negated); NaN counts as outside. */
inline float clamp_to_band(double f, float bg)
{
    if (!(f == f)) return -bg;
    return (float)std::min<double>(bg, std::max<double>(-bg, f));
}

/* Edge, in voxels, of the region a value found at this accessor depth
 * stands for (-1: the root's background, i.e. a whole absent root child). */
inline int depth_extent(int depth)
{
    switch (depth) {
    case -1:
    case 0: return NODE2_DIM;
    case 1: return NODE1_DIM;
    case 2: return LEAF_DIM;
    default: return 1;
    }
}

/* OpenVDB's global registration, once per process. */
void init_openvdb();

/* Voxel centres at origin + voxel * index. */
openvdb::math::Transform::Ptr make_transform(double voxel, const double origin[3]);

/* threads <= 0: TBB's automatic count. */
std::unique_ptr<tbb::task_arena> make_arena(int threads);

/* Recompute v's leaf bounding box and leaf count from its tree (after a
 * build, a load or a mesh conversion). */
void refresh_bounds(fm_vdb *v);

} // namespace fm_vdb_bridge

/* The grid plus its thread arena (declared opaque in stock_private.h). */
struct fm_vdb {
    fm_vdb_bridge::Grid::Ptr grid;
    double voxel = 0;
    int band = 0;
    float background = 0;
    double origin[3] = {0, 0, 0};
    std::unique_ptr<tbb::task_arena> arena;
    size_t leaves = 0; /* tracked for budgets; exact after build and load */
    bool has_bounds = false;
    fm_vdb_bridge::Coord bounds_lo, bounds_hi; /* index box holding everything not outside */
};

#endif
