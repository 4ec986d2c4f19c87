/* vdb_design.cpp: the grid work of the design comparison (design.c): one
 * pass over the union of the stock's and the design's trees that measures
 * the gouge and excess volumes and classifies voxels, the connected regions
 * of gouge and excess (union-find over member voxels and tiles, 26
 * neighbours), their depths at the stock's surface (exact beyond the
 * design's band from a search over the design's surface points), and the
 * rebuild of a snapshot's level set onto the stock's transform. A field's
 * design is a topology whose marked cells are evaluated as they are read
 * (field_cell), and its deviations are the field's values at the foot
 * points. C API in design_private.h; every exception stops at it. OpenVDB
 * signs throughout (phi < 0 inside). */
#include "stock/design_private.h"
#include "stock/vdb_bridge.hpp"

#include <openvdb/tools/Prune.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <unordered_map>
#include <vector>

namespace {

using namespace fm_vdb_bridge;
using Sampler = openvdb::tools::GridSampler<CAcc, openvdb::tools::BoxSampler>;

/* Below this share of a voxel, gouge or excess is the rounding between two
 * grids that describe the same surface (a plane sampled by the stock's cut
 * and by the design differs in the last bits), not a deviation. A real
 * deviation d puts at least d / (2 h) of a voxel in one of the two voxels
 * its surface crosses. */
constexpr double MIN_SHARE = 1e-4;

enum Kind : uint8_t { NONE = 0, GOUGE = 1, EXCESS = 2 };

struct CoordHash {
    size_t operator()(const Coord &c) const
    {
        uint64_t x = (uint64_t)(uint32_t)c.x() * 0x9E3779B97F4A7C15ULL;
        x ^= ((uint64_t)(uint32_t)c.y() << 21) ^ ((uint64_t)(uint32_t)c.z() << 42) ^
             (uint64_t)(uint32_t)c.z();
        x ^= x >> 33;
        x *= 0xff51afd7ed558ccdULL;
        x ^= x >> 33;
        return size_t(x);
    }
};

struct Setup {
    const Grid *stock;
    const Grid *design;
    double h, inv;
    double origin[3];
    float bgs, bgd;
    double tol;
    /* a design sample at or beyond this may interpolate clamped corners:
     * its true magnitude is at least this, maybe more */
    double clamp;
    /* a field's design: the design grid is its topology, and a marked
     * cell's values are the field's (fm_vdb_rasterize_topology) */
    const fm_field *field = nullptr;
};

/* Is the design's value at a cell a mark (a field's leaf not stored)? */
inline bool marked(const Setup &s, float design_value)
{
    return s.field && design_value == FM_VDB_LEAF_MARK;
}

inline void world_of(const Setup &s, const Coord &c, double x[3])
{
    for (int k = 0; k < 3; k++) x[k] = s.origin[k] + s.h * c[k];
}

/* The point of the stock's surface nearest voxel c: one step along the
 * normal (g: central differences of phi), q = x - phi n. Exact for planes. */
void step_to_surface(const Setup &s, const Coord &c, double phi, const double g[3], double q[3])
{
    const double n2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    world_of(s, c, q);
    if (n2 > 0) {
        const double inv = 1.0 / std::sqrt(n2);
        for (int k = 0; k < 3; k++) q[k] -= phi * g[k] * inv;
    }
}

/* step_to_surface with the differences read through the accessor. */
void foot_point(const Setup &s, CAcc &sa, const Coord &c, double phi, double q[3])
{
    double g[3];
    for (int k = 0; k < 3; k++) {
        Coord p = c, m = c;
        p[k] += 1;
        m[k] -= 1;
        g[k] = double(sa.getValue(p)) - double(sa.getValue(m));
    }
    step_to_surface(s, c, phi, g, q);
}

/* A leaf-sized cell after classification: which voxels are members of a
 * gouge or an excess region, and for each member (in the order of the
 * member bits) its share of the voxel and the deviation at its foot point
 * (NaN for a member beyond the stock's band, whose surface is elsewhere),
 * and how far it lies from the design's surface (into it for a gouge, out
 * of it for an excess: a lower bound of the region's depth; the design's
 * value at the voxel, clamped to the design's band). */
struct Cell {
    Coord origin;
    uint64_t member[8] = {};
    uint64_t gouge[8] = {};
    uint32_t prefix[8] = {};
    std::vector<float> share;
    std::vector<float> depth;
    std::vector<float> apart;
    std::vector<uint8_t> clamped;

    bool is_member(int i) const { return (member[i >> 6] >> (i & 63)) & 1; }
    Kind kind(int i) const { return ((gouge[i >> 6] >> (i & 63)) & 1) ? GOUGE : EXCESS; }
    uint32_t rank(int i) const
    {
        const uint64_t below = (i & 63) ? member[i >> 6] & ((uint64_t(1) << (i & 63)) - 1) : 0;
        return prefix[i >> 6] + uint32_t(__builtin_popcountll(below));
    }
    uint32_t count() const { return prefix[7] + uint32_t(__builtin_popcountll(member[7])); }
};

inline Coord voxel_of(const Coord &origin, int i)
{
    return origin.offsetBy(i >> 6, (i >> 3) & 7, i & 7);
}

struct TileCell {
    Coord origin;
    int size;
    Kind kind;
};

/* The values of a leaf-sized cell and P voxels around it, copied from the
 * cell's and its 26 neighbours' leaves (a cell without a leaf has one value
 * throughout), so that the voxels near a cell's surface read their
 * neighbours without an accessor: the same values, so the same results. */
template <int P>
struct Block {
    static constexpr int N = LEAF_DIM + 2 * P;
    float v[N * N * N];
    bool ready = false;

    static int at(int x, int y, int z) { return ((x + P) * N + (y + P)) * N + (z + P); }
    static bool holds(int x, int y, int z)
    {
        return x >= -P && x < LEAF_DIM + P && y >= -P && y < LEAF_DIM + P && z >= -P &&
               z < LEAF_DIM + P;
    }

    void fill(CAcc &acc, const Coord &o)
    {
        for (int dx = -1; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dz = -1; dz <= 1; dz++) {
                    const Coord n = o.offsetBy(LEAF_DIM * dx, LEAF_DIM * dy, LEAF_DIM * dz);
                    const Leaf *leaf = acc.probeConstLeaf(n);
                    const float *src = leaf ? leaf->buffer().data() : nullptr;
                    const float c = leaf ? 0.0f : acc.getValue(n);
                    /* the part of the block in this neighbour, in its own
                     * coordinates */
                    const int x0 = dx < 0 ? LEAF_DIM - P : 0, x1 = dx > 0 ? P : LEAF_DIM;
                    const int y0 = dy < 0 ? LEAF_DIM - P : 0, y1 = dy > 0 ? P : LEAF_DIM;
                    const int z0 = dz < 0 ? LEAF_DIM - P : 0, z1 = dz > 0 ? P : LEAF_DIM;
                    for (int x = x0; x < x1; x++)
                        for (int y = y0; y < y1; y++) {
                            float *dst = v + at(x + LEAF_DIM * dx, y + LEAF_DIM * dy,
                                                z0 + LEAF_DIM * dz);
                            if (src) {
                                const float *row = src + (x << 6) + (y << 3);
                                for (int z = z0; z < z1; z++) *dst++ = row[z];
                            } else {
                                for (int z = z0; z < z1; z++) *dst++ = c;
                            }
                        }
                }
        ready = true;
    }
};

/* Per thread: accessors of both grids, the design's transform, the blocks
 * of the cell at hand, and results. The stock's block reaches the six
 * neighbours of every voxel; the design's, the corners of a sample up to
 * a voxel and a half from the cell (foot points of voxels near the
 * stock's surface; farther ones read through the accessor). */
struct Worker {
    CAcc sa, da;
    const openvdb::math::Transform &dxf;
    double max_gouge = 0, max_excess = 0;
    std::vector<Cell> cells;
    Block<1> sb;
    Block<2> db;
    /* a field's design: its worker state, and the cell's values */
    const fm_field *field;
    void *fw = nullptr;
    float dvals[LEAF_SIZE];
    explicit Worker(const Setup &s)
        : sa(s.stock->constTree()), da(s.design->constTree()), dxf(s.design->transform()),
          field(s.field)
    {
        if (field && field->worker_new) {
            fw = field->worker_new(field->ctx);
            if (!fw) throw std::bad_alloc();
        }
    }
    ~Worker()
    {
        if (fw && field->worker_free) field->worker_free(field->ctx, fw);
    }
    Worker(const Worker &) = delete;
    Worker &operator=(const Worker &) = delete;
};

/* A marked cell's design values: the field's batch at its voxel centres,
 * negated and clamped to the band, the values fm_vdb_rasterize stores (the
 * same points, so the same values). */
void field_cell(const Setup &s, Worker &w, const Coord &o)
{
    double x[LEAF_SIZE], y[LEAF_SIZE], z[LEAF_SIZE], f[LEAF_SIZE];
    for (int i = 0; i < LEAF_SIZE; i++) {
        x[i] = s.origin[0] + s.h * (o.x() + (i >> 6));
        y[i] = s.origin[1] + s.h * (o.y() + ((i >> 3) & 7));
        z[i] = s.origin[2] + s.h * (o.z() + (i & 7));
    }
    s.field->batch(s.field->ctx, w.fw, LEAF_SIZE, x, y, z, f);
    for (int i = 0; i < LEAF_SIZE; i++) w.dvals[i] = -clamp_to_band(f[i], s.bgd);
}

/* foot_point for voxel i of the cell at o, reading the stock's block. */
void foot_point_in(const Setup &s, Worker &w, const Coord &o, int i, double phi, double q[3])
{
    if (!w.sb.ready) w.sb.fill(w.sa, o);
    const int x = i >> 6, y = (i >> 3) & 7, z = i & 7;
    const float *v = w.sb.v;
    const int c = Block<1>::at(x, y, z), sx = Block<1>::N * Block<1>::N, sy = Block<1>::N;
    const double g[3] = {double(v[c + sx]) - double(v[c - sx]), double(v[c + sy]) - double(v[c - sy]),
                         double(v[c + 1]) - double(v[c - 1])};
    step_to_surface(s, voxel_of(o, i), phi, g, q);
}

/* The design's trilinear sample at world point q (BoxSampler's arithmetic,
 * so the same value as its wsSample): the cell's eight corners from the
 * design's block of the cell at o when they are in it, else through the
 * accessor. */
double design_sample_in(Worker &w, const Coord &o, const double q[3])
{
    const openvdb::Vec3d u = w.dxf.worldToIndex(openvdb::Vec3d(q[0], q[1], q[2]));
    const openvdb::Vec3i b = openvdb::tools::local_util::floorVec3(u);
    const openvdb::Vec3d uvw = u - b;
    float data[2][2][2];
    const int x = b[0] - o.x(), y = b[1] - o.y(), z = b[2] - o.z();
    if (Block<2>::holds(x, y, z) && Block<2>::holds(x + 1, y + 1, z + 1)) {
        if (!w.db.ready) w.db.fill(w.da, o);
        const int N = Block<2>::N, c = Block<2>::at(x, y, z);
        for (int a = 0; a < 2; a++)
            for (int e = 0; e < 2; e++)
                for (int d = 0; d < 2; d++) data[a][e][d] = w.db.v[c + (a * N + e) * N + d];
    } else {
        openvdb::tools::BoxSampler::getValues(data, w.da, Coord(b));
    }
    return openvdb::tools::BoxSampler::trilinearInterpolation(data, uvw);
}

/* Classify the voxels of one cell; sums[0..1] get its gouge and excess
 * shares. Keeps a Cell only when it has members. The deviation at the foot
 * points is read after the shares, all at once: a field's design evaluates
 * them in one batch (its own value there, not a trilinear sample). */
void classify(const Setup &s, Worker &w, const Coord &o, double sums[2])
{
    const Leaf *sl = w.sa.probeConstLeaf(o);
    const Leaf *dl = w.da.probeConstLeaf(o);
    const float *sv = sl ? sl->buffer().data() : nullptr;
    const float *dv = dl ? dl->buffer().data() : nullptr;
    const float sc = sl ? 0.0f : w.sa.getValue(o);
    const float dc = dl ? 0.0f : w.da.getValue(o);
    if (!dl && marked(s, dc)) {
        field_cell(s, w, o);
        dv = w.dvals;
    }
    w.sb.ready = w.db.ready = false;
    Cell cell;
    cell.origin = o;
    float share[LEAF_SIZE], depth[LEAF_SIZE], apart[LEAF_SIZE];
    uint8_t clamped[LEAF_SIZE];
    /* voxels whose foot point is read: their index, foot point and sample */
    int foot_of[LEAF_SIZE];
    double fx[LEAF_SIZE], fy[LEAF_SIZE], fz[LEAF_SIZE], dev[LEAF_SIZE];
    int nfoot = 0;
    uint64_t member[8] = {}, gouge_bits[8] = {};
    double g = 0, e = 0;
    for (int i = 0; i < LEAF_SIZE; i++) {
        const double a = sv ? sv[i] : sc, b = dv ? dv[i] : dc;
        const double hm = inside_fraction(float(std::max(a, b)), s.inv);
        const double fg = inside_fraction(float(b), s.inv) - hm;
        const double fe = inside_fraction(float(a), s.inv) - hm;
        g += fg;
        e += fe;
        if (!(fg > MIN_SHARE || fe > MIN_SHARE)) continue;
        const bool gouge = fg > MIN_SHARE;
        share[i] = float(gouge ? fg : fe);
        apart[i] = float(gouge ? -b : b);
        depth[i] = std::numeric_limits<float>::quiet_NaN();
        clamped[i] = 0;
        if (gouge) gouge_bits[i >> 6] |= uint64_t(1) << (i & 63);
        if (gouge ? a >= s.bgs : a <= -s.bgs) {
            /* beyond the stock's band: air deep in the design, or stock
             * deep outside it; the region's surface is elsewhere */
            member[i >> 6] |= uint64_t(1) << (i & 63);
        } else {
            double q[3];
            foot_point_in(s, w, o, i, a, q);
            fx[nfoot] = q[0];
            fy[nfoot] = q[1];
            fz[nfoot] = q[2];
            foot_of[nfoot++] = i;
        }
    }
    sums[0] = g;
    sums[1] = e;
    if (nfoot > 0 && s.field) {
        s.field->batch(s.field->ctx, w.fw, size_t(nfoot), fx, fy, fz, dev);
        for (int k = 0; k < nfoot; k++) dev[k] = -double(clamp_to_band(dev[k], s.bgd));
    } else {
        for (int k = 0; k < nfoot; k++) {
            const double q[3] = {fx[k], fy[k], fz[k]};
            dev[k] = design_sample_in(w, o, q);
        }
    }
    for (int k = 0; k < nfoot; k++) {
        const int i = foot_of[k];
        const bool gouge = (gouge_bits[i >> 6] >> (i & 63)) & 1;
        const double d = gouge ? -dev[k] : dev[k];
        depth[i] = float(d);
        clamped[i] = std::fabs(dev[k]) >= s.clamp;
        double &mx = gouge ? w.max_gouge : w.max_excess;
        if (d > mx) mx = d;
        if (d > s.tol) member[i >> 6] |= uint64_t(1) << (i & 63);
    }
    uint32_t n = 0;
    for (int k = 0; k < 8; k++) {
        cell.member[k] = member[k];
        cell.gouge[k] = member[k] & gouge_bits[k];
        cell.prefix[k] = n;
        n += uint32_t(__builtin_popcountll(member[k]));
    }
    if (n == 0) return;
    cell.share.reserve(n);
    cell.depth.reserve(n);
    cell.apart.reserve(n);
    cell.clamped.reserve(n);
    for (int i = 0; i < LEAF_SIZE; i++) {
        if (!cell.is_member(i)) continue;
        cell.share.push_back(share[i]);
        cell.depth.push_back(depth[i]);
        cell.apart.push_back(apart[i]);
        cell.clamped.push_back(clamped[i]);
    }
    w.cells.push_back(std::move(cell));
}

/* The cells of the union of both trees: leaf-sized boxes where either grid
 * has a leaf, and tiles where both are constant (kept when they are gouge
 * or excess through and through). */
struct Walk {
    const Setup &s;
    CAcc sa, da;
    std::vector<Coord> leaves;
    std::vector<TileCell> tiles;
    double tile_gouge = 0, tile_excess = 0; /* voxels */

    explicit Walk(const Setup &st) : s(st), sa(st.stock->constTree()), da(st.design->constTree())
    {
    }

    void visit(const Coord &o, int size)
    {
        const int dsd = sa.getValueDepth(o), ddd = da.getValueDepth(o);
        const bool us = dsd < 3 && depth_extent(dsd) >= size;
        const bool ud = ddd < 3 && depth_extent(ddd) >= size && !marked(s, da.getValue(o));
        if (us && ud) {
            /* both constant: +-band, so a tile is all or nothing */
            const float a = sa.getValue(o), b = da.getValue(o);
            const double vol = double(size) * size * size;
            if (a > 0 && b < 0) {
                tiles.push_back(TileCell{o, size, GOUGE});
                tile_gouge += vol;
            } else if (a < 0 && b > 0) {
                tiles.push_back(TileCell{o, size, EXCESS});
                tile_excess += vol;
            }
            return;
        }
        if (size == LEAF_DIM) {
            leaves.push_back(o);
            return;
        }
        const int half = size / 2;
        for (int i = 0; i < 8; i++)
            visit(o.offsetBy((i & 4) ? half : 0, (i & 2) ? half : 0, (i & 1) ? half : 0), half);
    }
};

/* Union-find with path halving; the smaller index is the root. */
struct UnionFind {
    std::vector<uint32_t> parent;
    explicit UnionFind(size_t n) : parent(n)
    {
        for (size_t i = 0; i < n; i++) parent[i] = uint32_t(i);
    }
    uint32_t find(uint32_t x)
    {
        while (parent[x] != x) {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        return x;
    }
    void unite(uint32_t a, uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b)
            parent[b] = a;
        else
            parent[a] = b;
    }
};

struct TileKey {
    Coord origin;
    int size;
    bool operator==(const TileKey &o) const { return origin == o.origin && size == o.size; }
};
struct TileKeyHash {
    size_t operator()(const TileKey &k) const { return CoordHash()(k.origin) ^ size_t(k.size); }
};

/* The member elements and how to find them by coordinate. Elements are the
 * member voxels of the cells (cell base + rank) and then the member tiles. */
struct Members {
    std::vector<Cell> cells;
    std::vector<uint32_t> base;
    std::unordered_map<Coord, uint32_t, CoordHash> cell_at;
    std::vector<TileCell> tiles;
    std::unordered_map<TileKey, uint32_t, TileKeyHash> tile_at;
    uint32_t voxel_elements = 0;

    size_t elements() const { return size_t(voxel_elements) + tiles.size(); }

    /* Element of kind at voxel c, or -1. */
    int64_t element_at(const Coord &c, Kind kind) const
    {
        const Coord lo(c.x() & ~(LEAF_DIM - 1), c.y() & ~(LEAF_DIM - 1), c.z() & ~(LEAF_DIM - 1));
        auto it = cell_at.find(lo);
        if (it != cell_at.end()) {
            const Cell &cell = cells[it->second];
            const int i = ((c.x() - lo.x()) << 6) | ((c.y() - lo.y()) << 3) | (c.z() - lo.z());
            if (!cell.is_member(i) || cell.kind(i) != kind) return -1;
            return int64_t(base[it->second]) + cell.rank(i);
        }
        return tile_element_at(c, kind);
    }

    int64_t tile_element_at(const Coord &c, Kind kind) const
    {
        if (tiles.empty()) return -1;
        static const int sizes[3] = {LEAF_DIM, NODE1_DIM, NODE2_DIM};
        for (int size : sizes) {
            const Coord o(c.x() & ~(size - 1), c.y() & ~(size - 1), c.z() & ~(size - 1));
            auto it = tile_at.find(TileKey{o, size});
            if (it != tile_at.end())
                return tiles[it->second].kind == kind ? int64_t(voxel_elements) + it->second : -1;
        }
        return -1;
    }
};

void connect(const Members &m, UnionFind &uf)
{
    for (size_t ci = 0; ci < m.cells.size(); ci++) {
        const Cell &cell = m.cells[ci];
        for (int i = 0; i < LEAF_SIZE; i++) {
            if (!cell.is_member(i)) continue;
            const Kind kind = cell.kind(i);
            const uint32_t me = m.base[ci] + cell.rank(i);
            const int x = i >> 6, y = (i >> 3) & 7, z = i & 7;
            for (int d = 0; d < 27; d++) {
                if (d == 13) continue;
                const int dx = d / 9 - 1, dy = (d / 3) % 3 - 1, dz = d % 3 - 1;
                const int nx = x + dx, ny = y + dy, nz = z + dz;
                if (nx >= 0 && nx < 8 && ny >= 0 && ny < 8 && nz >= 0 && nz < 8) {
                    const int j = (nx << 6) | (ny << 3) | nz;
                    if (j > i && cell.is_member(j) && cell.kind(j) == kind)
                        uf.unite(me, m.base[ci] + cell.rank(j));
                    continue;
                }
                const int64_t other =
                    m.element_at(cell.origin.offsetBy(nx, ny, nz), kind);
                if (other >= 0) uf.unite(me, uint32_t(other));
            }
        }
    }
    /* tiles with tiles: the leaf-sized positions of the shell around each */
    for (size_t t = 0; t < m.tiles.size(); t++) {
        const TileCell &tc = m.tiles[t];
        const uint32_t me = m.voxel_elements + uint32_t(t);
        const Coord &o = tc.origin;
        for (int x = o.x() - LEAF_DIM; x <= o.x() + tc.size; x += LEAF_DIM)
            for (int y = o.y() - LEAF_DIM; y <= o.y() + tc.size; y += LEAF_DIM)
                for (int z = o.z() - LEAF_DIM; z <= o.z() + tc.size; z += LEAF_DIM) {
                    const bool inside = x >= o.x() && x < o.x() + tc.size && y >= o.y() &&
                                        y < o.y() + tc.size && z >= o.z() &&
                                        z < o.z() + tc.size;
                    if (inside) {
                        /* skip the interior column at once */
                        if (z == o.z()) z = o.z() + tc.size - LEAF_DIM;
                        continue;
                    }
                    const int64_t other = m.tile_element_at(Coord(x, y, z), tc.kind);
                    if (other >= 0) uf.unite(me, uint32_t(other));
                }
    }
}

/* The zero crossings of the design's voxel edges, bucketed by leaf: the
 * distance to the nearest is the distance to the design's surface within
 * the crossings' spacing (at most a voxel apart along the surface, so
 * within sqrt(d^2 + h^2 / 2) - d of it). Built only when a region's depth
 * is beyond the design's band, and only from the design's leaves that
 * touch roi (index space): a pass over every leaf of the design took most
 * of the comparison's time (bench/design). */
class SurfacePoints {
public:
    SurfacePoints(const Setup &s, const CoordBBox &roi) : s_(s)
    {
        CAcc acc(s.design->constTree());
        std::vector<std::pair<Coord, openvdb::Vec3f>> pts;
        for (auto leaf = s.design->constTree().cbeginLeaf(); leaf; ++leaf) {
            if (!roi.hasOverlap(leaf->getNodeBoundingBox())) continue;
            for (int i = 0; i < LEAF_SIZE; i++) {
                const float a = leaf->getValue(i);
                const Coord c = leaf->offsetToGlobalCoord(i);
                for (int k = 0; k < 3; k++) {
                    Coord n = c;
                    n[k] += 1;
                    const float b = acc.getValue(n);
                    if ((a < 0) == (b < 0)) continue;
                    const double t = double(a) / (double(a) - double(b));
                    double x[3];
                    world_of(s, c, x);
                    x[k] += t * s.h;
                    pts.emplace_back(bucket_of(x), openvdb::Vec3f(float(x[0]), float(x[1]),
                                                                   float(x[2])));
                }
            }
        }
        std::sort(pts.begin(), pts.end(), [](const auto &p, const auto &q) {
            return p.first < q.first;
        });
        points_.reserve(pts.size());
        for (size_t i = 0; i < pts.size(); i++) {
            if (i == 0 || !(pts[i].first == pts[i - 1].first))
                range_[pts[i].first] = {uint32_t(i), uint32_t(i)};
            range_[pts[i].first].second = uint32_t(i + 1);
            points_.push_back(pts[i].second);
            if (i == 0) {
                lo_ = hi_ = pts[i].first;
            } else {
                lo_ = Coord::minComponent(lo_, pts[i].first);
                hi_ = Coord::maxComponent(hi_, pts[i].first);
            }
        }
    }

    size_t bytes() const { return points_.size() * (sizeof(openvdb::Vec3f) + 12); }
    bool empty() const { return points_.empty(); }

    /* Distance from p to the nearest crossing (which goes to *at when
     * given); infinity when there is none. */
    double nearest(const double p[3], openvdb::Vec3d *at = nullptr) const
    {
        if (points_.empty()) return std::numeric_limits<double>::infinity();
        const Coord c0 = bucket_of(p);
        const double edge = s_.h * BUCKET;
        double best2 = std::numeric_limits<double>::infinity();
        int reach = 0; /* rings that can hold a point at all */
        for (int k = 0; k < 3; k++)
            reach = std::max(reach, std::max(std::abs(c0[k] - lo_[k]), std::abs(c0[k] - hi_[k])));
        for (int ring = 0; ring <= reach; ring++) {
            for (int dx = -ring; dx <= ring; dx++)
                for (int dy = -ring; dy <= ring; dy++) {
                    const bool face = std::abs(dx) == ring || std::abs(dy) == ring;
                    for (int dz = -ring; dz <= ring; dz += face ? 1 : std::max(1, 2 * ring)) {
                        const Coord b = c0.offsetBy(dx, dy, dz);
                        /* a bucket whose box is no nearer than the best
                         * point so far cannot hold a nearer one */
                        double gap2 = 0;
                        for (int k = 0; k < 3; k++) {
                            const double lo = s_.origin[k] + edge * b[k], hi = lo + edge;
                            const double g = p[k] < lo ? lo - p[k] : (p[k] > hi ? p[k] - hi : 0);
                            gap2 += g * g;
                        }
                        if (gap2 >= best2) continue;
                        auto it = range_.find(b);
                        if (it == range_.end()) continue;
                        for (uint32_t i = it->second.first; i < it->second.second; i++) {
                            const openvdb::Vec3f &q = points_[i];
                            const double ex = q[0] - p[0], ey = q[1] - p[1], ez = q[2] - p[2];
                            const double d2 = ex * ex + ey * ey + ez * ez;
                            if (d2 < best2) {
                                best2 = d2;
                                if (at) *at = openvdb::Vec3d(q[0], q[1], q[2]);
                            }
                        }
                    }
                }
            /* every point not yet seen is at least ring buckets away */
            const double bound = ring * edge;
            if (best2 <= bound * bound) break;
        }
        return std::sqrt(best2);
    }

private:
    static constexpr int BUCKET = LEAF_DIM;

    Coord bucket_of(const double x[3]) const
    {
        int c[3];
        for (int k = 0; k < 3; k++)
            c[k] = int(std::floor((x[k] - s_.origin[k]) / (s_.h * BUCKET)));
        return Coord(c[0], c[1], c[2]);
    }

    const Setup &s_;
    std::vector<openvdb::Vec3f> points_;
    std::unordered_map<Coord, std::pair<uint32_t, uint32_t>, CoordHash> range_;
    Coord lo_, hi_;
};

/* The design's distance at points (OpenVDB sign) beyond its band too: the
 * trilinear sample where it is exact (all of its cell's corners within the
 * band), else from the design's surface points around the points that need
 * them (a box about them widened by reach voxels, doubled until every point's
 * nearest crossing lies inside it: one nearer would have to be outside, and
 * the box's edge is no nearer than it). The nearest crossing c bounds the
 * distance by |p - c|; the tangent plane at c (the design's gradient there)
 * gives a second bound, |(p - c).n| + |phi(f)| at p's projection f onto the
 * plane, exact for a plane face: the smaller one is taken. A point with no
 * surface anywhere keeps the clamped sample. */
template <class T>
fm_status design_distances(const fm_vdb &v, const T *xyz, size_t n, double *out, size_t budget,
                           fm_error *err)
{
    Setup s{};
    s.stock = s.design = v.grid.get();
    s.h = v.voxel;
    s.inv = 1.0 / s.h;
    for (int k = 0; k < 3; k++) s.origin[k] = v.origin[k];
    s.bgs = s.bgd = v.grid->background();
    s.clamp = double(s.bgd) - std::sqrt(3.0) * s.h;
    CAcc acc(v.grid->constTree());
    Sampler sampler(acc, v.grid->transform());
    std::vector<size_t> far;
    for (size_t i = 0; i < n; i++) {
        const T *p = xyz + 3 * i;
        out[i] = sampler.wsSample(openvdb::Vec3d(p[0], p[1], p[2]));
        if (std::fabs(out[i]) >= s.clamp) far.push_back(i);
    }
    if (far.empty()) return FM_OK;
    CoordBBox all;
    v.grid->constTree().evalLeafBoundingBox(all);
    int reach = 2 * v.band + 2;
    while (!far.empty()) {
        CoordBBox roi;
        for (size_t i : far) {
            const T *p = xyz + 3 * i;
            Coord c;
            for (int k = 0; k < 3; k++)
                c[k] = int(std::floor((double(p[k]) - s.origin[k]) * s.inv));
            roi.expand(c);
            roi.expand(c.offsetBy(1));
        }
        roi.expand(reach);
        const bool whole = all.empty() || (roi.isInside(all));
        SurfacePoints surface(s, roi);
        if (surface.bytes() > budget)
            return fm_error_set(err, FM_ERR_LIMIT,
                                "the design's distances beyond its band: its surface points "
                                "(%.0f MB) exceed the memory budget",
                                double(surface.bytes()) / 1048576.0);
        std::vector<size_t> next;
        for (size_t i : far) {
            const T *pt = xyz + 3 * i;
            const double p[3] = {double(pt[0]), double(pt[1]), double(pt[2])};
            openvdb::Vec3d at(0.0);
            const double d = surface.nearest(p, &at);
            /* how far p is from the box's edge (the box holds voxel
             * centres roi.min()..roi.max()) */
            double room = std::numeric_limits<double>::infinity();
            for (int k = 0; k < 3; k++) {
                room = std::min(room, p[k] - (s.origin[k] + s.h * (roi.min()[k] - 0.5)));
                room = std::min(room, s.origin[k] + s.h * (roi.max()[k] + 0.5) - p[k]);
            }
            if (!whole && !(d <= room)) {
                next.push_back(i);
                continue;
            }
            if (!std::isfinite(d)) continue; /* no surface at all */
            double g[3], g2 = 0;
            for (int k = 0; k < 3; k++) {
                openvdb::Vec3d a = at, b = at;
                a[k] += 0.5 * s.h;
                b[k] -= 0.5 * s.h;
                g[k] = sampler.wsSample(a) - sampler.wsSample(b);
                g2 += g[k] * g[k];
            }
            double best = d;
            if (g2 > 0) {
                const double inv = 1.0 / std::sqrt(g2);
                double along = 0;
                for (int k = 0; k < 3; k++) along += (p[k] - at[k]) * g[k] * inv;
                openvdb::Vec3d f;
                for (int k = 0; k < 3; k++) f[k] = p[k] - along * g[k] * inv;
                const double pf = sampler.wsSample(f);
                if (std::fabs(pf) < s.clamp) best = std::min(best, std::fabs(along) + std::fabs(pf));
            }
            out[i] = out[i] < 0 ? -best : best;
        }
        far.swap(next);
        reach *= 2;
    }
    return FM_OK;
}

struct Region {
    Kind kind = NONE;
    double volume = 0; /* voxels */
    size_t voxels = 0;
    Coord lo, hi;
    double depth = -1;   /* largest foot-point deviation of its members */
    int64_t best = -1;   /* the member it belongs to */
    bool clamped = false;
    bool has_surface = false;
    double apart = 0; /* the farthest of its members from the design's surface */
    std::vector<uint32_t> clamped_cells; /* cells with clamped members (refinement) */
};

/* Position of element e: its foot point (members near the stock's
 * surface), else the centre of the voxel or tile. */
void element_position(const Setup &s, const Members &m, CAcc &sa, uint32_t e, double p[3])
{
    if (e >= m.voxel_elements) {
        const TileCell &t = m.tiles[e - m.voxel_elements];
        world_of(s, t.origin, p);
        for (int k = 0; k < 3; k++) p[k] += 0.5 * s.h * (t.size - 1);
        return;
    }
    const size_t ci = size_t(std::upper_bound(m.base.begin(), m.base.end(), e) - m.base.begin()) - 1;
    const Cell &cell = m.cells[ci];
    const uint32_t r = e - m.base[ci];
    int i = 0;
    for (; i < LEAF_SIZE; i++)
        if (cell.is_member(i) && cell.rank(i) == r) break;
    const Coord c = voxel_of(cell.origin, i);
    if (std::isnan(cell.depth[r])) {
        world_of(s, c, p);
        return;
    }
    foot_point(s, sa, c, double(sa.getValue(c)), p);
}

void fill_regions(const Setup &s, const Members &m, CAcc &sa, std::vector<Region> &regions,
                  Kind kind, size_t max_regions, fm_deviation_region **out, size_t *count,
                  size_t *total)
{
    /* a region holding less than a tolerance-thick layer over one voxel
     * face is below what the grids resolve (a design's sharp corner
     * sampled differently by two grids), not a deviation */
    const double least = s.tol / s.h;
    std::vector<const Region *> list;
    for (const Region &r : regions)
        if (r.kind == kind && r.volume >= least && r.depth > s.tol) list.push_back(&r);
    std::sort(list.begin(), list.end(), [](const Region *a, const Region *b) {
        if (a->depth != b->depth) return a->depth > b->depth;
        if (a->volume != b->volume) return a->volume > b->volume;
        return a->lo < b->lo;
    });
    *total = list.size();
    const size_t n = std::min(list.size(), max_regions);
    *count = 0;
    *out = nullptr;
    if (n == 0) return;
    *out = static_cast<fm_deviation_region *>(std::calloc(n, sizeof **out));
    if (!*out) throw std::bad_alloc();
    const double vox3 = s.h * s.h * s.h;
    for (size_t i = 0; i < n; i++) {
        const Region &r = *list[i];
        fm_deviation_region &o = (*out)[i];
        o.depth_mm = r.depth;
        o.volume_mm3 = r.volume * vox3;
        o.voxels = r.voxels;
        world_of(s, r.lo, o.lo);
        world_of(s, r.hi, o.hi);
        element_position(s, m, sa, uint32_t(r.best), o.position);
    }
    *count = n;
}

fm_status compare(const fm_vdb *sv, const fm_vdb *dv, const fm_vdb_compare_options &opt,
                  fm_deviation *out, fm_error *err)
{
    Setup s;
    s.stock = sv->grid.get();
    s.design = dv->grid.get();
    s.h = fm_vdb_voxel(sv);
    s.inv = 1.0 / s.h;
    fm_vdb_origin(sv, s.origin);
    s.bgs = s.stock->background();
    s.bgd = s.design->background();
    s.tol = opt.tolerance;
    s.clamp = double(s.bgd) - std::sqrt(3.0) * s.h;
    s.field = opt.field;

    /* 1. the cells of both trees */
    Walk walk(s);
    CoordBBox bb, db;
    s.stock->constTree().evalLeafBoundingBox(bb);
    s.design->constTree().evalLeafBoundingBox(db);
    if (bb.empty())
        bb = db;
    else if (!db.empty())
        bb.expand(db);
    if (!bb.empty()) {
        for (int x = bb.min().x() & ~(NODE2_DIM - 1); x <= bb.max().x(); x += NODE2_DIM)
            for (int y = bb.min().y() & ~(NODE2_DIM - 1); y <= bb.max().y(); y += NODE2_DIM)
                for (int z = bb.min().z() & ~(NODE2_DIM - 1); z <= bb.max().z(); z += NODE2_DIM)
                    walk.visit(Coord(x, y, z), NODE2_DIM);
    }
    if (walk.leaves.size() * sizeof(Coord) > opt.budget)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "comparing with the design: %zu cells exceed the memory budget",
                            walk.leaves.size());

    /* 2. classify the leaf-sized cells, in parallel */
    const size_t nleaves = walk.leaves.size();
    std::vector<double> sums(2 * nleaves, 0.0);
    tbb::enumerable_thread_specific<std::unique_ptr<Worker>> workers;
    std::unique_ptr<tbb::task_arena> arena = make_arena(opt.threads);
    arena->execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, nleaves, 32),
                          [&](const tbb::blocked_range<size_t> &r) {
                              auto &w = workers.local();
                              if (!w) w = std::make_unique<Worker>(s);
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  classify(s, *w, walk.leaves[i], &sums[2 * i]);
                          });
    });
    /* summed in cell order, so that the figures do not depend on threads */
    double gouge_vox = walk.tile_gouge, excess_vox = walk.tile_excess;
    for (size_t i = 0; i < nleaves; i++) {
        gouge_vox += sums[2 * i];
        excess_vox += sums[2 * i + 1];
    }
    std::vector<double>().swap(sums);
    const double vox3 = s.h * s.h * s.h;
    out->gouge_volume_mm3 = gouge_vox * vox3;
    out->excess_volume_mm3 = excess_vox * vox3;

    Members m;
    size_t mem = 0;
    for (auto &w : workers) {
        if (!w) continue;
        out->max_gouge_mm = std::max(out->max_gouge_mm, w->max_gouge);
        out->max_excess_mm = std::max(out->max_excess_mm, w->max_excess);
        for (Cell &c : w->cells) {
            mem += sizeof(Cell) + c.share.size() * 9 + 64;
            m.cells.push_back(std::move(c));
        }
        std::vector<Cell>().swap(w->cells);
    }
    std::sort(m.cells.begin(), m.cells.end(),
              [](const Cell &a, const Cell &b) { return a.origin < b.origin; });
    m.tiles = std::move(walk.tiles);
    m.base.resize(m.cells.size());
    uint64_t n = 0;
    for (size_t i = 0; i < m.cells.size(); i++) {
        m.base[i] = uint32_t(n);
        n += m.cells[i].count();
        m.cell_at[m.cells[i].origin] = uint32_t(i);
    }
    if (n + m.tiles.size() >= UINT32_MAX)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "comparing with the design: %llu deviating voxels are too many",
                            (unsigned long long)n);
    m.voxel_elements = uint32_t(n);
    for (size_t t = 0; t < m.tiles.size(); t++)
        m.tile_at[TileKey{m.tiles[t].origin, m.tiles[t].size}] = uint32_t(t);
    mem += m.elements() * 8 + m.cells.size() * 48 + m.tiles.size() * 64;
    if (mem > opt.budget)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "comparing with the design would need about %.0f MB for %zu "
                            "deviating voxels; the memory budget is %.0f MB",
                            double(mem) / 1048576.0, m.elements(), double(opt.budget) / 1048576.0);

    /* 3. connected regions */
    UnionFind uf(m.elements());
    connect(m, uf);
    std::vector<int32_t> region_of(m.elements(), -1);
    std::vector<Region> regions;
    auto region_for = [&](uint32_t e, Kind kind) -> Region & {
        const uint32_t root = uf.find(e);
        if (region_of[root] < 0) {
            region_of[root] = int32_t(regions.size());
            regions.emplace_back();
            regions.back().kind = kind;
            regions.back().best = int64_t(e);
        }
        return regions[size_t(region_of[root])];
    };
    auto grow = [](Region &r, const Coord &lo, const Coord &hi) {
        if (r.voxels == 0) {
            r.lo = lo;
            r.hi = hi;
        } else {
            r.lo = Coord::minComponent(r.lo, lo);
            r.hi = Coord::maxComponent(r.hi, hi);
        }
    };
    for (size_t ci = 0; ci < m.cells.size(); ci++) {
        const Cell &cell = m.cells[ci];
        for (int i = 0; i < LEAF_SIZE; i++) {
            if (!cell.is_member(i)) continue;
            const uint32_t r = cell.rank(i), e = m.base[ci] + r;
            Region &reg = region_for(e, cell.kind(i));
            const Coord c = voxel_of(cell.origin, i);
            grow(reg, c, c);
            reg.voxels++;
            reg.volume += cell.share[r];
            reg.apart = std::max(reg.apart, double(cell.apart[r]));
            const float d = cell.depth[r];
            if (std::isnan(d)) continue;
            reg.has_surface = true;
            if (d > reg.depth) {
                reg.depth = d;
                reg.best = e;
                reg.clamped = cell.clamped[r];
            }
            if (cell.clamped[r] &&
                (reg.clamped_cells.empty() || reg.clamped_cells.back() != ci))
                reg.clamped_cells.push_back(uint32_t(ci));
        }
    }
    for (size_t t = 0; t < m.tiles.size(); t++) {
        const TileCell &tc = m.tiles[t];
        const uint32_t e = m.voxel_elements + uint32_t(t);
        Region &reg = region_for(e, tc.kind);
        grow(reg, tc.origin, tc.origin.offsetBy(tc.size - 1));
        const double vol = double(tc.size) * tc.size * tc.size;
        reg.voxels += size_t(vol);
        reg.volume += vol;
        reg.apart = std::max(reg.apart, double(s.bgd)); /* a design tile: its band away */
    }
    for (Region &reg : regions)
        if (!reg.has_surface) {
            /* No member near the stock's surface: design material where
             * the stock never was, or the inside of a deviation whose
             * surface stays within the tolerance. Its members are as far
             * from the design's surface as they lie (up to the design's
             * band), so the deviation is at least that deep; where that is
             * within the tolerance the region is not one (fill_regions).
             * Taking the band here made phantom regions of the inside of a
             * 1 mm excess at tolerances of 1 mm and more, and raised
             * max_excess_mm to the band (cli_surface, stock_design). */
            reg.depth = reg.apart;
        }

    /* 4. depths beyond the design's band, from its surface points. The
     * nearest surface point p* of a cell's centre bounds the depth of each
     * member's foot point q by |q - p*|: cells are refined in decreasing
     * bound until none can beat the deepest found by more than a quarter
     * voxel (on a flat face every cell ties, and p* right under the centre
     * makes the bound the depth plus a hair). */
    CAcc sa(s.stock->constTree());
    /* the design with values for its surface points: a field's is made
     * here, only when a region needs it */
    Setup sd = s;
    bool need_points = false;
    for (const Region &reg : regions) need_points = need_points || (reg.has_surface && reg.clamped);
    if (need_points && s.field) {
        const fm_vdb *full = opt.full ? opt.full(opt.full_user, err) : nullptr;
        if (!full)
            return err && err->code != FM_OK
                       ? err->code
                       : fm_error_set(err, FM_ERR_INPUT, "the design's grid is not available");
        sd.design = full->grid.get();
        sd.field = nullptr;
    }
    for (Region &reg : regions) {
        if (!reg.has_surface || !reg.clamped) continue;
        /* The region (design material the stock lacks, or stock where the
         * design has none) is bounded by the stock's surface and the
         * design's, so the design's surface meets its box widened by a
         * voxel (unless it is a closed void of the stock inside the design,
         * where no crossing is found near and the whole design is read).
         * Every foot point lies within the stock's band of a member, so
         * its nearest crossing is no farther than that box's diagonal plus
         * the band: the crossings of the box widened by as much are all it
         * needs. */
        const int band = int(std::ceil(double(s.bgs) * s.inv)) + 2;
        const Coord ext = reg.hi - reg.lo;
        const int reach =
            band + 1 +
            int(std::ceil(std::sqrt(double(ext.x() + 3) * (ext.x() + 3) +
                                    double(ext.y() + 3) * (ext.y() + 3) +
                                    double(ext.z() + 3) * (ext.z() + 3)))) +
            band;
        CoordBBox roi(reg.lo, reg.hi);
        roi.expand(reach);
        std::unique_ptr<SurfacePoints> surface = std::make_unique<SurfacePoints>(sd, roi);
        if (surface->empty()) {
            CoordBBox all;
            sd.design->constTree().evalLeafBoundingBox(all);
            surface = std::make_unique<SurfacePoints>(sd, all);
        }
        if (surface->bytes() > opt.budget)
            return fm_error_set(err, FM_ERR_LIMIT,
                                "comparing with the design: its surface points (%.0f MB) "
                                "exceed the memory budget",
                                double(surface->bytes()) / 1048576.0);
        const int32_t me = int32_t(&reg - regions.data());
        /* the clamped members of reg in cell ci, with their foot points */
        auto members = [&](uint32_t ci, auto &&visit) {
            const Cell &cell = m.cells[ci];
            for (int i = 0; i < LEAF_SIZE; i++) {
                if (!cell.is_member(i)) continue;
                const uint32_t r = cell.rank(i), e = m.base[ci] + r;
                if (!cell.clamped[r] || region_of[uf.find(e)] != me) continue;
                const Coord c = voxel_of(cell.origin, i);
                double q[3];
                foot_point(s, sa, c, double(sa.getValue(c)), q);
                visit(e, q);
            }
        };
        std::vector<std::pair<double, uint32_t>> bound;
        for (uint32_t ci : reg.clamped_cells) {
            double c[3];
            world_of(s, m.cells[ci].origin, c);
            for (int k = 0; k < 3; k++) c[k] += 0.5 * s.h * (LEAF_DIM - 1);
            openvdb::Vec3d at(0.0);
            if (!std::isfinite(surface->nearest(c, &at))) continue;
            double b = 0;
            members(ci, [&](uint32_t, const double q[3]) {
                b = std::max(b, (openvdb::Vec3d(q[0], q[1], q[2]) - at).length());
            });
            bound.emplace_back(b, ci);
        }
        std::sort(bound.begin(), bound.end(),
                  [](const auto &a, const auto &b) { return a.first > b.first; });
        const double margin = 0.25 * s.h;
        for (const auto &bc : bound) {
            if (bc.first <= reg.depth + margin) break;
            /* the same bound member by member: |q - p*| of the cell's p* */
            double c[3];
            world_of(s, m.cells[bc.second].origin, c);
            for (int k = 0; k < 3; k++) c[k] += 0.5 * s.h * (LEAF_DIM - 1);
            openvdb::Vec3d at(0.0);
            surface->nearest(c, &at);
            struct Foot {
                double bound;
                uint32_t element;
                openvdb::Vec3d q;
            };
            std::vector<Foot> cand;
            members(bc.second, [&](uint32_t e, const double q[3]) {
                const openvdb::Vec3d qv(q[0], q[1], q[2]);
                cand.push_back(Foot{(qv - at).length(), e, qv});
            });
            std::sort(cand.begin(), cand.end(),
                      [](const Foot &a, const Foot &b) { return a.bound > b.bound; });
            for (const Foot &f : cand) {
                if (f.bound <= reg.depth + margin) break;
                const double q[3] = {f.q[0], f.q[1], f.q[2]};
                const double d = surface->nearest(q);
                if (d > reg.depth) {
                    reg.depth = d;
                    reg.best = f.element;
                }
            }
        }
    }

    for (const Region &reg : regions) {
        double &mx = reg.kind == GOUGE ? out->max_gouge_mm : out->max_excess_mm;
        if (reg.has_surface || reg.depth > s.tol) mx = std::max(mx, reg.depth);
    }
    fill_regions(s, m, sa, regions, GOUGE, opt.max_regions, &out->gouges, &out->gouge_count,
                 &out->gouge_total);
    fill_regions(s, m, sa, regions, EXCESS, opt.max_regions, &out->excess, &out->excess_count,
                 &out->excess_total);
    return FM_OK;
}

/* One layer of a level set's band widening, in place: the voxels next to
 * the known ones (26 neighbours) become active and get the distance that the
 * first-order upwind (Godunov) update of the Eikonal equation gives from
 * their known face neighbours - the update a fast-sweeping or fast-marching
 * step makes, exact for planes - or a known neighbour's distance plus the
 * step to it where that is less (a bound by the triangle inequality, for
 * voxels with no known face neighbour). Not yet known: +-infinity, which the
 * caller gives every voxel beyond the old band (inactive voxels, tiles and
 * the background). The layer reads a copy of the grid before it, so the
 * result does not depend on the order of the leaves. */
void widen_layer(Grid &grid, double h)
{
    const Grid::ConstPtr before = grid.deepCopy();
    openvdb::tools::dilateActiveValues(grid.tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    openvdb::tree::LeafManager<Tree> leaves(grid.tree());
    const double inf = std::numeric_limits<double>::infinity();
    leaves.foreach([&](Leaf &leaf, size_t) {
        CAcc acc(before->constTree());
        float *vals = leaf.buffer().data();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const float v0 = vals[it.pos()];
            if (!std::isinf(v0)) continue;
            const Coord c = it.getCoord();
            const bool inside = v0 < 0;
            /* distances in voxels */
            double a[3], bound = inf;
            for (int k = 0; k < 3; k++) {
                a[k] = inf;
                for (int d = -1; d <= 1; d += 2) {
                    Coord n = c;
                    n[k] += d;
                    const float u = acc.getValue(n);
                    if (std::isinf(u) || (u < 0) != inside) continue;
                    a[k] = std::min(a[k], double(std::fabs(u)) / h);
                }
            }
            for (int dx = -1; dx <= 1; dx++)
                for (int dy = -1; dy <= 1; dy++)
                    for (int dz = -1; dz <= 1; dz++) {
                        const int m = dx * dx + dy * dy + dz * dz;
                        if (m < 2) continue; /* faces: in the upwind update */
                        const float u = acc.getValue(c.offsetBy(dx, dy, dz));
                        if (std::isinf(u) || (u < 0) != inside) continue;
                        bound = std::min(bound, double(std::fabs(u)) / h + std::sqrt(double(m)));
                    }
            std::sort(a, a + 3);
            double d = inf;
            if (a[0] < inf) {
                d = a[0] + 1;
                if (d > a[1]) {
                    const double s = a[0] + a[1], q = a[0] - a[1];
                    d = 0.5 * (s + std::sqrt(2 - q * q));
                    if (d > a[2]) {
                        const double s3 = s + a[2];
                        const double sq = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
                        d = (s3 + std::sqrt(std::max(0.0, s3 * s3 - 3 * (sq - 1)))) / 3;
                    }
                }
            }
            d = std::min(d, bound);
            if (d < inf) vals[it.pos()] = float(inside ? -d * h : d * h);
        }
    });
}

} // namespace

extern "C" {

fm_status fm_vdb_compare(const fm_vdb *stock, const fm_vdb *design,
                         const fm_vdb_compare_options *opt, fm_deviation *out, fm_error *err)
{
    return guarded(err, "comparing with the design", [&] {
        return compare(stock, design, *opt, out, err);
    });
}

fm_status fm_vdb_design_distances(const fm_vdb *design, const float *xyz, size_t n, double *out,
                                  size_t budget, fm_error *err)
{
    return guarded(err, "the design's distances", [&] {
        return design_distances(*design, xyz, n, out, budget, err);
    });
}

fm_status fm_vdb_design_distance(const fm_vdb *design, const double p[3], double *out,
                                 size_t budget, fm_error *err)
{
    return guarded(err, "the design's distance", [&] {
        return design_distances(*design, p, 1, out, budget, err);
    });
}

fm_status fm_vdb_widen_band(fm_vdb *v, int band, size_t budget, fm_error *err)
{
    return guarded(err, "widening the design's band", [&]() -> fm_status {
        const int add = band - v->band;
        if (add <= 0) return FM_OK;
        /* the band's leaves grow about in proportion to its width; a layer
         * holds the old grid, the new one and the new one's copy at once */
        const double need =
            double(v->grid->memUsage()) * (1.0 + 2.0 * double(band) / double(v->band));
        if (need > double(budget))
            return fm_error_set(err, FM_ERR_LIMIT,
                                "widening the design's band to %d voxels would need about %.0f MB; "
                                "the memory budget is %.0f MB",
                                band, need / 1048576.0, double(budget) / 1048576.0);
        /* layer by layer (fast sweeping, OpenVDB's dilateSdf, took ~20 s of
         * CPU for 3D_Chips' 0.1 mm result: bench/design) */
        Grid::Ptr wide = v->grid->deepCopy();
        openvdb::tools::changeLevelSetBackground(wide->tree(),
                                                 std::numeric_limits<float>::infinity());
        auto run = [&] {
            for (int k = 0; k < add; k++) widen_layer(*wide, v->voxel);
        };
        if (v->arena)
            v->arena->execute(run);
        else
            run();
        const float bg = float(double(band) * v->voxel);
        /* what no layer reached lies beyond the new band */
        for (auto it = wide->tree().beginLeaf(); it; ++it) {
            float *vals = it->buffer().data();
            for (int i = 0; i < LEAF_SIZE; i++) {
                if (std::fabs(vals[i]) >= bg) { /* infinity too */
                    vals[i] = vals[i] < 0 ? -bg : bg;
                    it->setValueOff(i);
                }
            }
        }
        openvdb::tools::changeLevelSetBackground(wide->tree(), bg);
        openvdb::tools::pruneLevelSet(wide->tree());
        v->grid = wide;
        v->band = band;
        v->background = bg;
        v->leaves = wide->tree().leafCount();
        return FM_OK;
    });
}

fm_status fm_vdb_rebuild_onto(fm_vdb *target, const fm_vdb *source, size_t budget, fm_error *err)
{
    return guarded(err, "rebuilding the design's level set", [&]() -> fm_status {
        const Grid &src = *source->grid;
        std::vector<openvdb::Vec3s> points;
        std::vector<openvdb::Vec3I> tris;
        std::vector<openvdb::Vec4I> quads;
        openvdb::tools::volumeToMesh(src, points, tris, quads, 0.0, 0.0, true);
        std::vector<uint32_t> idx;
        idx.reserve(3 * (tris.size() + 2 * quads.size()));
        for (const auto &t : tris)
            for (int k = 0; k < 3; k++) idx.push_back(t[k]);
        for (const auto &q : quads) {
            const uint32_t a[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
            idx.insert(idx.end(), a, a + 6);
        }
        double area = 0; /* projected, as for an STL (fm_stock_estimate_bytes) */
        for (size_t i = 0; i < idx.size(); i += 3) {
            const openvdb::Vec3d p(points[idx[i]]), u = openvdb::Vec3d(points[idx[i + 1]]) - p,
                                                    v = openvdb::Vec3d(points[idx[i + 2]]) - p;
            const openvdb::Vec3d n = u.cross(v);
            area += 0.5 * (std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]));
        }
        const double need = double(fm_stock_estimate_bytes(area, fm_vdb_voxel(target),
                                                            fm_vdb_band(target))) +
                            double(points.size()) * 12 + double(idx.size()) * 4;
        if (need > double(budget))
            return fm_error_set(err, FM_ERR_LIMIT,
                                "the design would need about %.0f MB at %g mm voxels, band %d, "
                                "but the memory budget is %.0f MB",
                                need / 1048576.0, fm_vdb_voxel(target), fm_vdb_band(target),
                                double(budget) / 1048576.0);
        std::vector<float> flat(3 * points.size());
        for (size_t i = 0; i < points.size(); i++)
            for (int k = 0; k < 3; k++) flat[3 * i + k] = points[i][k];
        return fm_vdb_from_mesh(target, flat.data(), points.size(), idx.data(), idx.size() / 3,
                                err);
    });
}

} // extern "C"
