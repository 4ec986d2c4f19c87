// vdb_mesh_chunk.cpp: meshes of one 64^3-voxel chunk of the stock's level
// set (the daemon publishes a job's stock chunk by chunk), made afresh or
// through fm_mesh_chunk_cache, which remeshes only the leaves a change
// reaches (live jobs). The faces are those of the whole grid's mesh whose
// grid edges start in the chunk, bit-identical; vertices, normals and
// colours through vdb_mesh_bridge.cpp's to_mesh.
#include "mesh/vdb_mesh_private.hpp"

#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

namespace fm_vdb_mesh {
namespace {

constexpr int CHUNK = FM_STOCK_CHUNK_VOXELS;

// Copy the grid's leaf at c (a leaf origin) into st, or the tile there when
// it is active or not the background; 1 when a leaf was copied.
int copy_leaf(const Grid &grid, Grid::ConstAccessor &acc, const Coord &c, Tree &st)
{
    if (const Leaf *leaf = acc.probeConstLeaf(c)) {
        st.addLeaf(new Leaf(*leaf));
        return 1;
    }
    float v = acc.getValue(c);
    bool on = acc.isValueOn(c);
    if (on || v != grid.background())
        st.addTile(1, c, v, on);
    return 0;
}

fm_mesh *chunk(fm_stock *stock, const int32_t index[3], const fm_mesh_extract_options &o,
               fm_error *err)
{
    if (check_options(o, err) != FM_OK)
        return nullptr;
    const Grid &grid = stock_grid(stock);
    Coord lo(index[0] * CHUNK, index[1] * CHUNK, index[2] * CHUNK);
    Coord hi = lo + Coord(CHUNK - 1);

    // A copy of the grid around the chunk, one leaf wider on every side:
    // the chunk's faces use cells down to lo - 1 and samples up to hi + 1,
    // and their normals sample half a voxel further. Whole leaves are shared
    // values, so the vertices come out bit-identical to the whole-grid run.
    Grid::Ptr sub = Grid::create(grid.background());
    // Share the very transform object (read only), not a copy, so that
    // indexToWorld rounds exactly as in the whole-grid run.
    sub->setTransform(std::const_pointer_cast<openvdb::math::Transform>(grid.constTransformPtr()));
    sub->setGridClass(grid.getGridClass());
    Tree &st = sub->tree();
    auto acc = grid.getConstAccessor();
    const int L = int(Leaf::DIM);
    Coord a = lo - Coord(L), b = hi + Coord(L);
    size_t leaves = 0;
    for (int x = a[0]; x <= b[0]; x += L)
        for (int y = a[1]; y <= b[1]; y += L)
            for (int z = a[2]; z <= b[2]; z += L) {
                leaves += copy_leaf(grid, acc, Coord(x, y, z), st);
            }
    fm_mesh_extract_options oc = o;
    oc.adaptivity = 0;
    if (leaves == 0)
        return fm_mesh_new(0, 0,
                           (o.normals ? FM_MESH_NORMALS : 0u) |
                               (o.coloring != FM_MESH_COLOR_NONE ? FM_MESH_COLORS : 0u),
                           &o.budget, err);

    // Faces only from the grid edges that start at the chunk's voxels.
    openvdb::BoolGrid::Ptr mask = openvdb::BoolGrid::create(false);
    mask->setTransform(grid.transform().copy());
    mask->tree().fill(CoordBBox(lo, hi), true, true);

    openvdb::tools::VolumeToMesh mesher(0.0, 0.0, true);
    mesher.setSurfaceMask(mask);
    mesher(*sub);
    Polygons pg;
    pg.points.resize(mesher.pointListSize());
    for (size_t i = 0; i < mesher.pointListSize(); i++)
        pg.points[i] = mesher.pointList()[i];
    openvdb::tools::PolygonPoolList &pools = mesher.polygonPoolList();
    for (size_t n = 0; n < mesher.polygonPoolListSize(); n++) {
        openvdb::tools::PolygonPool &pool = pools[n];
        for (size_t i = 0; i < pool.numQuads(); i++)
            pg.quads.push_back(pool.quad(i));
        for (size_t i = 0; i < pool.numTriangles(); i++)
            pg.triangles.push_back(pool.triangle(i));
    }
    fm_mesh *m = to_mesh(stock, grid, pg, oc, err);
    return m;
}

// ------------------------------------------------ incremental chunks --
//
// A live move changes a few leaves of a chunk, but remeshing the chunk
// whole redoes its unchanged faces too (most of a 64^3 chunk's triangles on
// a flat stock top). fm_mesh_chunk_cache keeps a chunk's faces as one piece
// per 8^3 leaf (the faces of the grid edges that start in that leaf) and a
// hash of every leaf's values (and active mask) in the chunk and the ring of
// leaves around it. The next call remeshes only the leaves whose hash
// changed and the neighbours such a change reaches: a leaf's faces read
// values at most one voxel outside it, their normals two, their colours
// (tool marks, which change only where a value does) one, so a neighbour
// whose values changed only further than two voxels from the leaf leaves
// its piece as a fresh run would make it. One OpenVDB run over those leaves (a copy of them
// one leaf wider, the surface mask on them) gives a polygon pool per
// sign-flag leaf; a pool's leaf is found from its vertices (every vertex of
// a face lies in a cell next to the face's edge, so within one voxel of
// the leaf) and, where that leaves two leaves possible (faces on a leaf's
// boundary plane, as a box top on a voxel plane), from the grid edges that
// can have made its faces (a sign change between the edge's two voxels).
// When a pool's leaf cannot be told, the chunk is meshed whole and cached
// anew; when even that fails, the chunk is meshed without the cache.

constexpr int LD = int(Leaf::DIM); // voxels per leaf edge
constexpr int CL = CHUNK / LD;     // leaves per chunk edge
constexpr int RL = CL + 2;         // with the ring around the chunk

int ring_slot(int x, int y, int z) { return (x * RL + y) * RL + z; } // 0..RL-1 each
int chunk_slot(int x, int y, int z) { return (x * CL + y) * CL + z; } // 0..CL-1 each

uint64_t mix(uint64_t h, uint64_t v)
{
    h ^= v + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 31);
}

// A leaf is hashed in 27 zones, by each coordinate's class: the two voxels
// at its low side (0), the four in the middle (1), the two at its high side
// (2); a neighbour's faces read values at most two voxels into the leaf, so
// only a change in the zones facing it makes the neighbour remesh. Values and
// active states both count. A tile (or nothing) hashes its value alone, the
// same in every zone.
constexpr int ZONES = 27;

int zone_class(int v) { return v < 2 ? 0 : v < LD - 2 ? 1 : 2; }

uint64_t leaf_hash(const Grid::ConstAccessor &acc, const Coord &c, uint32_t zone[ZONES])
{
    if (const Leaf *leaf = acc.probeConstLeaf(c)) {
        const float *buf = leaf->buffer().data();
        const auto &mask = leaf->getValueMask();
        uint64_t h[ZONES];
        for (int i = 0; i < ZONES; i++)
            h[i] = uint64_t(i) + 1;
        for (int x = 0; x < LD; x++) {
            const uint64_t word = mask.template getWord<openvdb::Index64>(openvdb::Index(x));
            for (int y = 0; y < LD; y++)
                for (int z = 0; z < LD; z += 2) {
                    const int off = (x * LD + y) * LD + z;
                    uint32_t a, b;
                    std::memcpy(&a, buf + off, 4);
                    std::memcpy(&b, buf + off + 1, 4);
                    const uint64_t on = (word >> (y * LD + z)) & 3u;
                    const int zn = zone_class(x) * 9 + zone_class(y) * 3 + zone_class(z);
                    h[zn] = mix(h[zn], ((uint64_t(a) << 32) | b) ^ (on * 0xD6E8FEB86659FD93ull));
                }
        }
        uint64_t whole = 1;
        for (int i = 0; i < ZONES; i++) {
            whole = mix(whole, h[i]);
            zone[i] = uint32_t(h[i] ^ (h[i] >> 32));
        }
        return whole;
    }
    uint32_t bits;
    const float v = acc.getValue(c);
    std::memcpy(&bits, &v, 4);
    const uint64_t h = mix(mix(2, bits), acc.isValueOn(c) ? 1 : 0);
    for (int i = 0; i < ZONES; i++)
        zone[i] = uint32_t(h ^ (h >> 32));
    return h;
}

// Does a change in ring slot r (at offset d from a chunk leaf, each -1..1)
// reach that leaf's faces? Only through the zones on r's side facing it.
bool change_reaches(const uint32_t *now, const uint32_t *before, const int d[3])
{
    for (int zx = 0; zx < 3; zx++) {
        if ((d[0] < 0 && zx != 2) || (d[0] > 0 && zx != 0))
            continue;
        for (int zy = 0; zy < 3; zy++) {
            if ((d[1] < 0 && zy != 2) || (d[1] > 0 && zy != 0))
                continue;
            for (int zz = 0; zz < 3; zz++) {
                if ((d[2] < 0 && zz != 2) || (d[2] > 0 && zz != 0))
                    continue;
                const int zn = zx * 9 + zy * 3 + zz;
                if (now[zn] != before[zn])
                    return true;
            }
        }
    }
    return false;
}

bool same_options(const fm_mesh_extract_options &a, const fm_mesh_extract_options &b)
{
    return a.normals == b.normals && a.coloring == b.coloring && a.top_z == b.top_z &&
           a.depth_range == b.depth_range && a.uncut_grey == b.uncut_grey &&
           a.design == b.design && a.deviation_range == b.deviation_range &&
           a.budget.max_vertices == b.budget.max_vertices &&
           a.budget.max_triangles == b.budget.max_triangles;
}

} // namespace
} // namespace fm_vdb_mesh

using namespace fm_vdb_mesh;

struct fm_mesh_chunk_cache {
    bool valid = false;
    int32_t index[3] = {0, 0, 0};
    fm_mesh_extract_options opt{};
    std::vector<uint64_t> hash = std::vector<uint64_t>(RL * RL * RL, 0);
    std::vector<uint32_t> zones = std::vector<uint32_t>(RL * RL * RL * ZONES, 0);
    std::vector<fm_mesh *> pieces = std::vector<fm_mesh *>(CL * CL * CL, nullptr);
    size_t last_leaves = 0;
    ~fm_mesh_chunk_cache()
    {
        for (fm_mesh *p : pieces)
            fm_mesh_free(p);
    }
};

namespace fm_vdb_mesh {
namespace {

// Could a face with these vertices (index space) come from a grid edge that
// starts in the leaf at o and crosses the surface?
bool face_fits_leaf(Grid::ConstAccessor &acc, const openvdb::Vec3d *q, int nq, const Coord &o)
{
    const double eps = 1e-3;
    double mn[3], mx[3];
    for (int k = 0; k < 3; k++) {
        mn[k] = mx[k] = q[0][k];
        for (int i = 1; i < nq; i++) {
            mn[k] = std::min(mn[k], q[i][k]);
            mx[k] = std::max(mx[k], q[i][k]);
        }
    }
    for (int a = 0; a < 3; a++) {
        int from[3], to[3];
        for (int k = 0; k < 3; k++) {
            // along the edge the vertices lie in [v, v + 1], across it in [v - 1, v + 1]
            from[k] = int(std::ceil(mx[k] - eps)) - 1;
            to[k] = int(std::floor(mn[k] + eps)) + (k == a ? 0 : 1);
            from[k] = std::max(from[k], o[k]);
            to[k] = std::min(to[k], o[k] + LD - 1);
        }
        for (int x = from[0]; x <= to[0]; x++)
            for (int y = from[1]; y <= to[1]; y++)
                for (int z = from[2]; z <= to[2]; z++) {
                    const Coord v(x, y, z);
                    Coord w = v;
                    w[a] += 1;
                    if ((acc.getValue(v) < 0.0f) != (acc.getValue(w) < 0.0f))
                        return true;
                }
    }
    return false;
}

// The chunk slot of each polygon pool's leaf (-1: no faces); false when a
// pool's leaf cannot be told among the slots in `meshed`.
bool attribute_pools(const Grid &grid, openvdb::tools::VolumeToMesh &mesher, const Coord &lo,
                     const std::vector<char> &meshed, std::vector<int> &pool_slot)
{
    const openvdb::math::Transform &xf = grid.transform();
    std::vector<openvdb::Vec3d> q(mesher.pointListSize());
    for (size_t i = 0; i < q.size(); i++)
        q[i] = xf.worldToIndex(openvdb::Vec3d(mesher.pointList()[i]));
    Grid::ConstAccessor acc = grid.getConstAccessor();
    openvdb::tools::PolygonPoolList &pools = mesher.polygonPoolList();
    pool_slot.assign(mesher.polygonPoolListSize(), -1);
    const double eps = 1e-3;
    for (size_t n = 0; n < mesher.polygonPoolListSize(); n++) {
        openvdb::tools::PolygonPool &pool = pools[n];
        if (pool.numQuads() == 0 && pool.numTriangles() == 0)
            continue;
        double mn[3] = {1e300, 1e300, 1e300}, mx[3] = {-1e300, -1e300, -1e300};
        auto widen = [&](uint32_t i) {
            for (int k = 0; k < 3; k++) {
                mn[k] = std::min(mn[k], q[i][k]);
                mx[k] = std::max(mx[k], q[i][k]);
            }
        };
        for (size_t i = 0; i < pool.numQuads(); i++)
            for (int k = 0; k < 4; k++)
                widen(pool.quad(i)[k]);
        for (size_t i = 0; i < pool.numTriangles(); i++)
            for (int k = 0; k < 3; k++)
                widen(pool.triangle(i)[k]);
        // the leaf's origin o: every vertex within [o - 1, o + LD] per axis
        std::vector<int> cand;
        int first[3], last[3];
        for (int k = 0; k < 3; k++) {
            const double a = mx[k] - LD - eps, b = mn[k] + 1 + eps;
            first[k] = int(std::ceil((a - lo[k]) / LD));
            last[k] = int(std::floor((b - lo[k]) / LD));
            first[k] = std::max(first[k], 0);
            last[k] = std::min(last[k], CL - 1);
        }
        for (int x = first[0]; x <= last[0]; x++)
            for (int y = first[1]; y <= last[1]; y++)
                for (int z = first[2]; z <= last[2]; z++)
                    if (meshed[chunk_slot(x, y, z)])
                        cand.push_back(chunk_slot(x, y, z));
        auto origin = [&](int s) {
            return lo + Coord(s / (CL * CL) * LD, s / CL % CL * LD, s % CL * LD);
        };
        for (size_t i = 0; cand.size() > 1 && i < pool.numQuads() + pool.numTriangles(); i++) {
            openvdb::Vec3d v[4];
            int nv = i < pool.numQuads() ? 4 : 3;
            for (int k = 0; k < nv; k++)
                v[k] = q[i < pool.numQuads() ? pool.quad(i)[k]
                                             : pool.triangle(i - pool.numQuads())[k]];
            std::vector<int> keep;
            for (int s : cand)
                if (face_fits_leaf(acc, v, nv, origin(s)))
                    keep.push_back(s);
            cand.swap(keep);
        }
        if (cand.size() != 1)
            return false;
        pool_slot[n] = cand[0];
    }
    return true;
}

// The pieces' union, one mesh, vertices shared between pieces welded.
fm_mesh *assemble(const std::vector<fm_mesh *> &pieces, unsigned attrs,
                  const fm_mesh_budget &budget, fm_error *err)
{
    size_t nv = 0, nt = 0;
    for (const fm_mesh *p : pieces)
        if (p) {
            nv += p->vertex_count;
            nt += p->triangle_count;
        }
    fm_mesh *m = fm_mesh_new(nv, nt, attrs, &budget, err);
    if (!m)
        return nullptr;
    for (const fm_mesh *p : pieces) {
        if (!p || !p->triangle_count)
            continue;
        const size_t v0 = m->vertex_count;
        std::memcpy(m->positions + 3 * v0, p->positions, 3 * p->vertex_count * sizeof(float));
        if (m->normals && p->normals)
            std::memcpy(m->normals + 3 * v0, p->normals, 3 * p->vertex_count * sizeof(float));
        if (m->colors && p->colors)
            std::memcpy(m->colors + 3 * v0, p->colors, 3 * p->vertex_count);
        uint32_t *t = m->triangles + 3 * m->triangle_count;
        for (size_t i = 0; i < 3 * p->triangle_count; i++)
            t[i] = p->triangles[i] + uint32_t(v0);
        m->vertex_count += p->vertex_count;
        m->triangle_count += p->triangle_count;
    }
    if (fm_mesh_weld(m, err) != FM_OK) {
        fm_mesh_free(m);
        return nullptr;
    }
    return m;
}

// Mesh the leaves marked in `meshed` (chunk slots) into cache pieces.
// Returns 1 on success, 0 when a pool's leaf could not be told (nothing
// changed), -1 on an error (err set).
int mesh_leaves(fm_stock *stock, const Grid &grid, const Coord &lo,
                const std::vector<char> &meshed, const fm_mesh_extract_options &oc,
                fm_mesh_chunk_cache *cc, fm_error *err)
{
    // copy the leaves one leaf around each meshed one (ring slots)
    std::vector<char> copy(RL * RL * RL, 0);
    for (int x = 0; x < CL; x++)
        for (int y = 0; y < CL; y++)
            for (int z = 0; z < CL; z++)
                if (meshed[chunk_slot(x, y, z)])
                    for (int a = 0; a < 3; a++)
                        for (int b = 0; b < 3; b++)
                            for (int c = 0; c < 3; c++)
                                copy[ring_slot(x + a, y + b, z + c)] = 1;
    Grid::Ptr sub = Grid::create(grid.background());
    sub->setTransform(std::const_pointer_cast<openvdb::math::Transform>(grid.constTransformPtr()));
    sub->setGridClass(grid.getGridClass());
    Tree &st = sub->tree();
    auto acc = grid.getConstAccessor();
    size_t leaves = 0;
    for (int x = 0; x < RL; x++)
        for (int y = 0; y < RL; y++)
            for (int z = 0; z < RL; z++) {
                if (!copy[ring_slot(x, y, z)])
                    continue;
                const Coord c = lo + Coord((x - 1) * LD, (y - 1) * LD, (z - 1) * LD);
                leaves += copy_leaf(grid, acc, c, st);
            }
    std::vector<fm_mesh *> fresh(CL * CL * CL, nullptr);
    auto drop = [&] {
        for (fm_mesh *&p : fresh) {
            fm_mesh_free(p);
            p = nullptr;
        }
    };
    if (leaves > 0) {
        openvdb::BoolGrid::Ptr mask = openvdb::BoolGrid::create(false);
        mask->setTransform(grid.transform().copy());
        for (int s = 0; s < CL * CL * CL; s++)
            if (meshed[s]) {
                const Coord o = lo + Coord(s / (CL * CL) * LD, s / CL % CL * LD, s % CL * LD);
                mask->tree().fill(CoordBBox(o, o + Coord(LD - 1)), true, true);
            }
        openvdb::tools::VolumeToMesh mesher(0.0, 0.0, true);
        mesher.setSurfaceMask(mask);
        mesher(*sub);
        std::vector<int> pool_slot;
        if (!attribute_pools(grid, mesher, lo, meshed, pool_slot))
            return 0;
        openvdb::tools::PolygonPoolList &pools = mesher.polygonPoolList();
        std::vector<uint32_t> local(mesher.pointListSize(), UINT32_MAX);
        for (int s = 0; s < CL * CL * CL; s++) {
            if (!meshed[s])
                continue;
            Polygons pg;
            auto take = [&](uint32_t i) {
                if (local[i] == UINT32_MAX) {
                    local[i] = uint32_t(pg.points.size());
                    pg.points.push_back(mesher.pointList()[i]);
                }
                return local[i];
            };
            for (size_t n = 0; n < pool_slot.size(); n++) {
                if (pool_slot[n] != s)
                    continue;
                openvdb::tools::PolygonPool &pool = pools[n];
                for (size_t i = 0; i < pool.numQuads(); i++) {
                    const openvdb::Vec4I &f = pool.quad(i);
                    pg.quads.emplace_back(take(f[0]), take(f[1]), take(f[2]), take(f[3]));
                }
                for (size_t i = 0; i < pool.numTriangles(); i++) {
                    const openvdb::Vec3I &f = pool.triangle(i);
                    pg.triangles.emplace_back(take(f[0]), take(f[1]), take(f[2]));
                }
            }
            if (pg.quads.empty() && pg.triangles.empty())
                continue;
            for (size_t n = 0; n < pool_slot.size(); n++) {
                if (pool_slot[n] != s)
                    continue;
                openvdb::tools::PolygonPool &pool = pools[n];
                for (size_t i = 0; i < pool.numQuads(); i++)
                    for (int k = 0; k < 4; k++)
                        local[pool.quad(i)[k]] = UINT32_MAX;
                for (size_t i = 0; i < pool.numTriangles(); i++)
                    for (int k = 0; k < 3; k++)
                        local[pool.triangle(i)[k]] = UINT32_MAX;
            }
            fresh[s] = to_mesh(stock, grid, pg, oc, err);
            if (!fresh[s]) {
                drop();
                return -1;
            }
        }
    }
    for (int s = 0; s < CL * CL * CL; s++)
        if (meshed[s]) {
            fm_mesh_free(cc->pieces[s]);
            cc->pieces[s] = fresh[s];
        }
    return 1;
}

fm_mesh *chunk_cached(fm_stock *stock, const int32_t index[3], const fm_mesh_extract_options &o,
                      fm_mesh_chunk_cache *cc, fm_error *err)
{
    if (check_options(o, err) != FM_OK)
        return nullptr;
    const Grid &grid = stock_grid(stock);
    const Coord lo(index[0] * CHUNK, index[1] * CHUNK, index[2] * CHUNK);
    fm_mesh_extract_options oc = o;
    oc.adaptivity = 0;
    const unsigned attrs = (o.normals ? FM_MESH_NORMALS : 0u) |
                           (o.coloring != FM_MESH_COLOR_NONE ? FM_MESH_COLORS : 0u);

    std::vector<uint64_t> hash(RL * RL * RL);
    std::vector<uint32_t> zones(RL * RL * RL * ZONES);
    {
        auto acc = grid.getConstAccessor();
        for (int x = 0; x < RL; x++)
            for (int y = 0; y < RL; y++)
                for (int z = 0; z < RL; z++) {
                    const int r = ring_slot(x, y, z);
                    hash[r] = leaf_hash(acc, lo + Coord((x - 1) * LD, (y - 1) * LD, (z - 1) * LD),
                                        &zones[size_t(r) * ZONES]);
                }
    }
    const bool reuse = cc->valid && std::memcmp(cc->index, index, sizeof cc->index) == 0 &&
                       same_options(cc->opt, o);
    std::vector<char> meshed(CL * CL * CL, reuse ? 0 : 1);
    size_t count = 0;
    if (reuse) {
        for (int x = 0; x < CL; x++)
            for (int y = 0; y < CL; y++)
                for (int z = 0; z < CL; z++) {
                    bool dirty = false;
                    for (int a = 0; a < 3 && !dirty; a++)
                        for (int b = 0; b < 3 && !dirty; b++)
                            for (int c = 0; c < 3 && !dirty; c++) {
                                const int r = ring_slot(x + a, y + b, z + c);
                                if (hash[r] == cc->hash[r])
                                    continue;
                                const int d[3] = {a - 1, b - 1, c - 1};
                                dirty = (a == 1 && b == 1 && c == 1) ||
                                        change_reaches(&zones[size_t(r) * ZONES],
                                                       &cc->zones[size_t(r) * ZONES], d);
                            }
                    meshed[chunk_slot(x, y, z)] = dirty;
                    count += dirty;
                }
    } else {
        count = meshed.size();
    }
    cc->valid = false;
    cc->last_leaves = count;
    int rc = count ? mesh_leaves(stock, grid, lo, meshed, oc, cc, err) : 1;
    if (rc == 0 && reuse) {
        std::fill(meshed.begin(), meshed.end(), 1);
        cc->last_leaves = meshed.size();
        rc = mesh_leaves(stock, grid, lo, meshed, oc, cc, err);
    }
    if (rc < 0)
        return nullptr;
    if (rc == 0)
        return chunk(stock, index, o, err); // uncached; the cache stays invalid
    cc->valid = true;
    std::memcpy(cc->index, index, sizeof cc->index);
    cc->opt = o;
    cc->hash.swap(hash);
    cc->zones.swap(zones);
    return assemble(cc->pieces, attrs, o.budget, err);
}

} // namespace
} // namespace fm_vdb_mesh

extern "C" {

fm_mesh *fm_mesh_from_stock_chunk(fm_stock *stock, const int32_t index[3],
                                  const fm_mesh_extract_options *opt, fm_error *err)
{
    fm_mesh_extract_options o;
    options_or_default(opt, &o);
    return guarded(err, "meshing a stock chunk", [&] { return chunk(stock, index, o, err); });
}

fm_mesh_chunk_cache *fm_mesh_chunk_cache_new(void)
{
    try {
        return new fm_mesh_chunk_cache();
    } catch (...) {
        return nullptr;
    }
}

void fm_mesh_chunk_cache_free(fm_mesh_chunk_cache *cache) { delete cache; }

size_t fm_mesh_chunk_cache_last_leaves(const fm_mesh_chunk_cache *cache)
{
    return cache ? cache->last_leaves : 0;
}

fm_mesh *fm_mesh_from_stock_chunk_cached(fm_stock *stock, const int32_t index[3],
                                         const fm_mesh_extract_options *opt,
                                         fm_mesh_chunk_cache *cache, fm_error *err)
{
    fm_mesh_extract_options o;
    options_or_default(opt, &o);
    if (!cache)
        return guarded(err, "meshing a stock chunk", [&] { return chunk(stock, index, o, err); });
    return guarded(err, "meshing a stock chunk",
                   [&] { return chunk_cached(stock, index, o, cache, err); });
}

} // extern "C"
