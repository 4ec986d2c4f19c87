/* vdb_validate.cpp: the level-set invariants checked over the whole grid,
 * for tests: values within the band, activity matching |phi| < band, tiles
 * inactive at +-band, and no hole in the band between opposite signs. */
#include "stock/vdb_bridge.hpp"

#include <cmath>

using namespace fm_vdb_bridge;

extern "C" {

fm_status fm_vdb_validate(const fm_vdb *v, fm_error *err)
{
    return guarded(err, "validating the stock grid", [&]() -> fm_status {
        const Tree &tree = v->grid->constTree();
        const float bg = v->background;
        CAcc acc(tree);
        auto opposite = [bg](float a, float b) {
            return (a >= bg && b <= -bg) || (a <= -bg && b >= bg);
        };
        static const int nb[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
            for (int i = 0; i < LEAF_SIZE; i++) {
                const float a = leaf->getValue(i);
                const Coord c = leaf->offsetToGlobalCoord(i);
                if (!(std::fabs(a) <= bg))
                    return fm_error_set(err, FM_ERR_INTERNAL,
                                        "voxel (%d,%d,%d) = %g is outside +-%g", c.x(), c.y(),
                                        c.z(), double(a), double(bg));
                if (leaf->isValueOn(i) != (std::fabs(a) < bg))
                    return fm_error_set(err, FM_ERR_INTERNAL,
                                        "voxel (%d,%d,%d) = %g is %s", c.x(), c.y(), c.z(),
                                        double(a), leaf->isValueOn(i) ? "active" : "inactive");
                for (const auto &d : nb) {
                    const Coord n = c.offsetBy(d[0], d[1], d[2]);
                    if (opposite(a, acc.getValue(n)))
                        return fm_error_set(err, FM_ERR_INTERNAL,
                                            "hole in the band between (%d,%d,%d) and (%d,%d,%d)",
                                            c.x(), c.y(), c.z(), n.x(), n.y(), n.z());
                }
            }
        }
        Tree::ValueAllCIter it = tree.cbeginValueAll();
        it.setMaxDepth(Tree::ValueAllCIter::LEAF_DEPTH - 1);
        for (; it; ++it) {
            const float a = *it;
            const CoordBBox bb = it.getBoundingBox();
            if (it.isValueOn() || std::fabs(a) != bg)
                return fm_error_set(err, FM_ERR_INTERNAL,
                                    "tile at (%d,%d,%d) is %s with value %g",
                                    bb.min().x(), bb.min().y(), bb.min().z(),
                                    it.isValueOn() ? "active" : "inactive", double(a));
            /* leaf-sized cells just outside each face of the tile */
            const int s = bb.dim().x();
            for (int f = 0; f < 6; f++) {
                const int ax = f / 2, u = (ax + 1) % 3, w = (ax + 2) % 3;
                for (int p = 0; p < s; p += LEAF_DIM)
                    for (int q = 0; q < s; q += LEAF_DIM) {
                        Coord c = bb.min();
                        c[ax] = (f % 2) ? bb.min()[ax] - 1 : bb.max()[ax] + 1;
                        c[u] += p;
                        c[w] += q;
                        const int depth = acc.getValueDepth(c);
                        if (depth < 3 && opposite(a, acc.getValue(c)))
                            return fm_error_set(err, FM_ERR_INTERNAL,
                                                "tiles of opposite sign meet at (%d,%d,%d)",
                                                c.x(), c.y(), c.z());
                    }
            }
        }
        return FM_OK;
    });
}

} // extern "C"
