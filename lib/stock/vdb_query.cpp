/* vdb_query.cpp: read-only walks over the stock's OpenVDB grid for the
 * collision check and for grids made from fields that are not distances:
 * the region visitor behind fm_stock_visit (aligned blocks from the root's
 * 4096^3 children down to 8^3 leaves, tiles reported whole, the caller
 * pruning blocks before they are opened) and the triangle mesh of a grid's
 * zero set (to rebuild true distances from it). Every extern "C" function
 * catches every exception; signs here are OpenVDB's until the values are
 * handed to C, where they are F-rep's (phi = -f). */
#include "stock/vdb_bridge.hpp"

#include <openvdb/tools/VolumeToMesh.h>

#include <cstdlib>
#include <cstring>
#include <vector>

using namespace fm_vdb_bridge;

namespace {

struct Visitor {
    CAcc acc;
    Coord clip_lo, clip_hi;
    int (*prune)(void *, const int32_t *, const int32_t *);
    int (*visit)(void *, const fm_stock_region *);
    void *user;
    bool stopped = false;
    float values[LEAF_SIZE];

    explicit Visitor(const Tree &tree) : acc(tree) {}

    void walk(const Coord &o, int s)
    {
        if (stopped) return;
        const Coord e = o.offsetBy(s - 1);
        for (int k = 0; k < 3; k++)
            if (e[k] < clip_lo[k] || o[k] > clip_hi[k]) return;
        const int32_t lo[3] = {o.x(), o.y(), o.z()}, hi[3] = {e.x(), e.y(), e.z()};
        /* a uniform block is reported whole, unasked: cheaper than the
         * caller's question */
        const int depth = acc.getValueDepth(o);
        if (depth < 3 && depth_extent(depth) >= s) {
            fm_stock_region r;
            std::memcpy(r.lo, lo, sizeof r.lo);
            std::memcpy(r.hi, hi, sizeof r.hi);
            r.values = nullptr;
            r.value = -acc.getValue(o);
            if (visit(user, &r)) stopped = true;
            return;
        }
        if (prune && prune(user, lo, hi)) return;
        if (s == LEAF_DIM) {
            const Leaf *leaf = acc.probeConstLeaf(o);
            fm_stock_region r;
            std::memcpy(r.lo, lo, sizeof r.lo);
            std::memcpy(r.hi, hi, sizeof r.hi);
            if (leaf) {
                const float *buf = leaf->buffer().data();
                for (int i = 0; i < LEAF_SIZE; i++) values[i] = -buf[i];
                r.values = values;
                r.value = 0;
            } else {
                r.values = nullptr;
                r.value = -acc.getValue(o);
            }
            if (visit(user, &r)) stopped = true;
            return;
        }
        const int h = s / 2;
        for (int i = 0; i < 8 && !stopped; i++)
            walk(o.offsetBy((i & 4) ? h : 0, (i & 2) ? h : 0, (i & 1) ? h : 0), h);
    }
};

} // namespace

extern "C" {

fm_status fm_vdb_visit(const fm_vdb *v, const int32_t lo[3], const int32_t hi[3],
                       int (*prune)(void *user, const int32_t lo[3], const int32_t hi[3]),
                       int (*visit)(void *user, const fm_stock_region *region), void *user,
                       fm_error *err)
{
    return guarded(err, "walking the stock grid", [&]() -> fm_status {
        for (int k = 0; k < 3; k++)
            if (lo[k] > hi[k]) return FM_OK;
        Visitor w(v->grid->constTree());
        w.clip_lo = Coord(lo[0], lo[1], lo[2]);
        w.clip_hi = Coord(hi[0], hi[1], hi[2]);
        w.prune = prune;
        w.visit = visit;
        w.user = user;
        const int mask = ~(NODE2_DIM - 1);
        for (int64_t x = lo[0] & mask; x <= hi[0] && !w.stopped; x += NODE2_DIM)
            for (int64_t y = lo[1] & mask; y <= hi[1] && !w.stopped; y += NODE2_DIM)
                for (int64_t z = lo[2] & mask; z <= hi[2] && !w.stopped; z += NODE2_DIM)
                    w.walk(Coord(int(x), int(y), int(z)), NODE2_DIM);
        return FM_OK;
    });
}

fm_status fm_vdb_zero_set_mesh(const fm_vdb *v, float **points, size_t *npoints, uint32_t **tris,
                               size_t *ntris, fm_error *err)
{
    *points = nullptr;
    *tris = nullptr;
    *npoints = *ntris = 0;
    return guarded(err, "meshing the zero set", [&]() -> fm_status {
        std::vector<openvdb::Vec3s> pts;
        std::vector<openvdb::Vec3I> tri;
        std::vector<openvdb::Vec4I> quad;
        openvdb::tools::volumeToMesh(*v->grid, pts, tri, quad, 0.0, 0.0);
        const size_t nt = tri.size() + 2 * quad.size();
        if (pts.empty() || nt == 0) return fm_error_set(err, FM_ERR_INPUT, "the field has no surface");
        float *p = static_cast<float *>(std::malloc(pts.size() * 3 * sizeof(float)));
        uint32_t *t = static_cast<uint32_t *>(std::malloc(nt * 3 * sizeof(uint32_t)));
        if (!p || !t) {
            std::free(p);
            std::free(t);
            return fm_error_set(err, FM_ERR_LIMIT, "meshing the zero set: out of memory");
        }
        for (size_t i = 0; i < pts.size(); i++)
            for (int k = 0; k < 3; k++) p[3 * i + k] = pts[i][k];
        size_t n = 0;
        for (const auto &a : tri)
            for (int k = 0; k < 3; k++) t[n++] = a[k];
        for (const auto &q : quad) {
            const uint32_t c[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
            for (uint32_t x : c) t[n++] = x;
        }
        *points = p;
        *npoints = pts.size();
        *tris = t;
        *ntris = nt;
        return FM_OK;
    });
}

} // extern "C"
