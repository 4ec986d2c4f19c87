// vdb_mesh_private.hpp: what lib/mesh's two OpenVDB files share (private
// to lib/mesh): the grid types, the stock's grid, OpenVDB's polygons and
// their conversion to an fm_mesh (vdb_mesh_bridge.cpp), the options' checks
// and the exception guard every extern "C" entry goes through.
#ifndef FM_MESH_VDB_MESH_PRIVATE_HPP
#define FM_MESH_VDB_MESH_PRIVATE_HPP

#include "mesh/mesh.h"
#include "stock/stock_private.h"

#include <openvdb/openvdb.h>

#include <exception>
#include <mutex>
#include <new>
#include <vector>

namespace fm_vdb_mesh {

using Grid = openvdb::FloatGrid;
using Tree = Grid::TreeType;
using Leaf = Tree::LeafNodeType;
using Coord = openvdb::Coord;
using CoordBBox = openvdb::CoordBBox;

inline void init_openvdb()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

inline const Grid &stock_grid(fm_stock *stock)
{
    auto *ptr = static_cast<Grid::Ptr *>(fm_stock_vdb_grid(stock));
    return **ptr;
}

struct Polygons {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
};

// Turn OpenVDB's output into an fm_mesh: quads split along their shorter
// diagonal (a choice made from the quad's positions alone, so a chunk and the whole grid
// split a face alike), faces reversed to fm_mesh's outward counter-clockwise
// order (OpenVDB's polygons wind the other way for phi < 0 inside), then
// normals and colours per vertex.
fm_mesh *to_mesh(const fm_stock *stock, const Grid &grid, const Polygons &pg,
                 const fm_mesh_extract_options &o, fm_error *err);

// The extraction options' checks (colouring, adaptivity, depth range).
fm_status check_options(const fm_mesh_extract_options &o, fm_error *err);

// Options with the default budget filled in.
void options_or_default(const fm_mesh_extract_options *in, fm_mesh_extract_options *out);

// Runs f with OpenVDB initialised; every exception becomes err (nullptr).
template <class F>
fm_mesh *guarded(fm_error *err, const char *what, F &&f)
{
    try {
        init_openvdb();
        return f();
    } catch (const std::bad_alloc &) {
        fm_error_set(err, FM_ERR_LIMIT, "%s: out of memory", what);
    } catch (const openvdb::Exception &e) {
        fm_error_set(err, FM_ERR_INTERNAL, "%s: OpenVDB: %s", what, e.what());
    } catch (const std::exception &e) {
        fm_error_set(err, FM_ERR_INTERNAL, "%s: %s", what, e.what());
    } catch (...) {
        fm_error_set(err, FM_ERR_INTERNAL, "%s: unknown C++ exception", what);
    }
    return nullptr;
}

} // namespace fm_vdb_mesh

#endif
