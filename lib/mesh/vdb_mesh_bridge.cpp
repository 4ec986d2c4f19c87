// vdb_mesh_bridge.cpp: meshes from the stock's OpenVDB level set, the
// whole grid at once, and the conversion of OpenVDB's polygons to an
// fm_mesh with normals from the level-set gradient and colours by depth, by
// the tool that last cut (lib/stock's tool marks) or by the deviation from a
// design (lib/stock's fm_design), which the chunks (vdb_mesh_chunk.cpp)
// share. lib/mesh reaches the grid through lib/stock's private door
// (fm_stock_vdb_grid) and never changes it. Every exception stops at the
// extern "C" functions.
#include "mesh/vdb_mesh_private.hpp"

#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

namespace fm_vdb_mesh {

namespace {

double dist2(const openvdb::Vec3s &a, const openvdb::Vec3s &b)
{
    double dx = double(a[0]) - b[0], dy = double(a[1]) - b[1], dz = double(a[2]) - b[2];
    return dx * dx + dy * dy + dz * dz;
}

bool less(const openvdb::Vec3s &a, const openvdb::Vec3s &b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return false;
}

// Trilinear interpolation of the 3^3 voxel values v at r (index space,
// relative to v's first voxel) moved by d along axis k; every coordinate of
// the moved point lies in [0, 2].
double trilinear_offset(const float (&v)[3][3][3], const double r[3], int k, double d)
{
    int c[3];
    double t[3];
    for (int a = 0; a < 3; a++) {
        const double x = a == k ? r[a] + d : r[a];
        c[a] = std::min(1, std::max(0, int(std::floor(x))));
        t[a] = x - c[a];
    }
    double yz[2];
    for (int a = 0; a < 2; a++) {
        const float *row0 = v[c[0] + a][c[1]] + c[2], *row1 = v[c[0] + a][c[1] + 1] + c[2];
        const double z0 = row0[0] + t[2] * (double(row0[1]) - row0[0]);
        const double z1 = row1[0] + t[2] * (double(row1[1]) - row1[0]);
        yz[a] = z0 + t[1] * (z1 - z0);
    }
    return yz[0] + t[0] * (yz[1] - yz[0]);
}

} // namespace

fm_mesh *to_mesh(const fm_stock *stock, const Grid &grid, const Polygons &pg,
                 const fm_mesh_extract_options &o, fm_error *err)
{
    size_t nt = pg.triangles.size() + 2 * pg.quads.size();
    unsigned attrs = (o.normals ? FM_MESH_NORMALS : 0u) |
                     (o.coloring != FM_MESH_COLOR_NONE ? FM_MESH_COLORS : 0u);
    fm_mesh *m = fm_mesh_new(pg.points.size(), nt, attrs, &o.budget, err);
    if (!m)
        return nullptr;
    std::unique_ptr<fm_mesh, void (*)(fm_mesh *)> guard(m, fm_mesh_free);
    for (size_t i = 0; i < pg.points.size(); i++)
        for (int k = 0; k < 3; k++)
            m->positions[3 * i + k] = pg.points[i][k];
    m->vertex_count = pg.points.size();
    uint32_t *t = m->triangles;
    for (const auto &tri : pg.triangles) {
        t[0] = tri[2], t[1] = tri[1], t[2] = tri[0];
        t += 3;
    }
    for (const auto &q : pg.quads) {
        double d02 = dist2(pg.points[q[0]], pg.points[q[2]]);
        double d13 = dist2(pg.points[q[1]], pg.points[q[3]]);
        bool split02 = d02 < d13;
        if (d02 == d13) {
            // Square quads (flat faces) tie: take the diagonal through the
            // smallest vertex, which does not depend on where the quad's
            // vertex list starts.
            int smallest = 0;
            for (int k = 1; k < 4; k++)
                if (less(pg.points[q[k]], pg.points[q[smallest]]))
                    smallest = k;
            split02 = (smallest % 2) == 0;
        }
        if (split02) {
            t[0] = q[2], t[1] = q[1], t[2] = q[0];
            t[3] = q[3], t[4] = q[2], t[5] = q[0];
        } else {
            t[0] = q[3], t[1] = q[1], t[2] = q[0];
            t[3] = q[3], t[4] = q[2], t[5] = q[1];
        }
        t += 6;
    }
    m->triangle_count = nt;

    if (o.normals) {
        // Central differences of the trilinear phi half a voxel either side:
        // depends only on the vertex position and the grid, so a vertex
        // shared by two chunks gets one normal. The six samples lie in the
        // 3^3 voxels from floor(q - 0.5) (q: the vertex in index space),
        // read once per vertex.
        Grid::ConstAccessor acc = grid.getConstAccessor();
        const openvdb::math::Transform &xf = grid.transform();
        for (size_t i = 0; i < m->vertex_count; i++) {
            const float *p = m->positions + 3 * i;
            const openvdb::Vec3d q = xf.worldToIndex(openvdb::Vec3d(p[0], p[1], p[2]));
            const Coord base(int(std::floor(q[0] - 0.5)), int(std::floor(q[1] - 0.5)),
                             int(std::floor(q[2] - 0.5)));
            const double r[3] = {q[0] - base[0], q[1] - base[1], q[2] - base[2]};
            float v[3][3][3];
            const Leaf *leaf = acc.probeConstLeaf(base);
            const int lx = base[0] & int(Leaf::DIM - 1), ly = base[1] & int(Leaf::DIM - 1),
                      lz = base[2] & int(Leaf::DIM - 1);
            if (leaf && lx + 2 < int(Leaf::DIM) && ly + 2 < int(Leaf::DIM) &&
                lz + 2 < int(Leaf::DIM)) {
                // all 27 in one leaf (most vertices): read its buffer
                const float *buf = leaf->buffer().data();
                for (int a = 0; a < 3; a++)
                    for (int b = 0; b < 3; b++)
                        for (int c = 0; c < 3; c++)
                            v[a][b][c] = buf[Leaf::coordToOffset(base.offsetBy(a, b, c))];
            } else {
                for (int a = 0; a < 3; a++)
                    for (int b = 0; b < 3; b++)
                        for (int c = 0; c < 3; c++)
                            v[a][b][c] = acc.getValue(base.offsetBy(a, b, c));
            }
            double g[3];
            for (int k = 0; k < 3; k++)
                g[k] = trilinear_offset(v, r, k, 0.5) - trilinear_offset(v, r, k, -0.5);
            double len = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            for (int k = 0; k < 3; k++)
                m->normals[3 * i + k] = len > 0 ? float(g[k] / len) : 0.0f;
        }
    }
    // Colours too depend only on the vertex position: the tool recorded at
    // the voxel nearest the vertex (one of its cell's corners, whose value
    // that tool's surface set).
    const bool need_marks = o.coloring == FM_MESH_COLOR_TOOL ||
                            (o.coloring == FM_MESH_COLOR_DEPTH && o.uncut_grey);
    const double tol = o.design ? fm_design_tolerance(o.design) : 0;
    const double range = o.deviation_range > 0 ? o.deviation_range : 10 * tol;
    if (o.coloring == FM_MESH_COLOR_DEVIATION) {
        // the design's distance at each point of the stock's surface: inside
        // the design a gouge (negative deviation), outside excess; all at
        // once, so that the design's surface points beyond its band are
        // read once
        std::vector<double> dist(m->vertex_count);
        if (fm_design_sample_points(o.design, m->positions, m->vertex_count, dist.data(), err) !=
            FM_OK)
            return nullptr;
        for (size_t i = 0; i < m->vertex_count; i++)
            fm_mesh_deviation_color(-dist[i], tol, range, m->colors + 3 * i);
    }
    for (size_t i = 0; o.coloring != FM_MESH_COLOR_NONE && o.coloring != FM_MESH_COLOR_DEVIATION &&
                       i < m->vertex_count;
         i++) {
        const float *pf = m->positions + 3 * i;
        const double p[3] = {pf[0], pf[1], pf[2]};
        int tool = -1;
        const int cut = need_marks ? fm_stock_point_tool(stock, p, &tool) : 0;
        if (o.coloring == FM_MESH_COLOR_TOOL)
            fm_mesh_tool_color(cut ? tool : -1, m->colors + 3 * i);
        else if (o.uncut_grey && !cut)
            fm_mesh_tool_color(-1, m->colors + 3 * i);
        else
            fm_mesh_depth_color(o.top_z - p[2], o.depth_range, m->colors + 3 * i);
    }
    return guard.release();
}

fm_status check_options(const fm_mesh_extract_options &o, fm_error *err)
{
    if (!(o.adaptivity >= 0 && o.adaptivity <= 1))
        return fm_error_set(err, FM_ERR_INPUT, "mesh adaptivity must be in 0..1");
    if (o.coloring != FM_MESH_COLOR_NONE && o.coloring != FM_MESH_COLOR_DEPTH &&
        o.coloring != FM_MESH_COLOR_TOOL && o.coloring != FM_MESH_COLOR_DEVIATION)
        return fm_error_set(err, FM_ERR_INPUT, "unknown mesh colouring %d", int(o.coloring));
    if (o.coloring == FM_MESH_COLOR_DEVIATION && !o.design)
        return fm_error_set(err, FM_ERR_INPUT,
                            "deviation colours need a design to compare with (--design)");
    if (o.coloring == FM_MESH_COLOR_DEPTH && !(o.depth_range > 0))
        return fm_error_set(err, FM_ERR_INPUT, "depth colour range must be positive");
    return FM_OK;
}

void options_or_default(const fm_mesh_extract_options *in, fm_mesh_extract_options *out)
{
    if (in)
        *out = *in;
    else
        fm_mesh_extract_default(out);
    if (!out->budget.max_vertices)
        out->budget.max_vertices = FM_MESH_DEFAULT_MAX_VERTICES;
    if (!out->budget.max_triangles)
        out->budget.max_triangles = FM_MESH_DEFAULT_MAX_TRIANGLES;
}

namespace {

// A first budget check before OpenVDB allocates the polygons: a narrow band
// of half-width w voxels holds about 2w active voxels per surface cell, so
// active / 6 estimates the vertex count of a band of 3. fm_mesh_new checks
// the exact count afterwards.
fm_status check_budget(size_t active_voxels, const fm_mesh_budget &b, fm_error *err)
{
    size_t est = active_voxels / 6;
    if (est > b.max_vertices)
        return fm_error_set(err, FM_ERR_LIMIT,
                            "the grid's mesh would have about %zu vertices, over the budget "
                            "of %zu; use a coarser voxel or a larger budget",
                            est, b.max_vertices);
    return FM_OK;
}

fm_mesh *whole(fm_stock *stock, const fm_mesh_extract_options &o, fm_error *err)
{
    if (check_options(o, err) != FM_OK)
        return nullptr;
    const Grid &grid = stock_grid(stock);
    if (check_budget(grid.activeVoxelCount(), o.budget, err) != FM_OK)
        return nullptr;
    Polygons pg;
    openvdb::tools::volumeToMesh(grid, pg.points, pg.triangles, pg.quads, 0.0, o.adaptivity,
                                 true);
    return to_mesh(stock, grid, pg, o, err);
}

} // namespace

} // namespace fm_vdb_mesh

using namespace fm_vdb_mesh;

extern "C" {

fm_mesh *fm_mesh_from_stock(fm_stock *stock, const fm_mesh_extract_options *opt, fm_error *err)
{
    fm_mesh_extract_options o;
    options_or_default(opt, &o);
    return guarded(err, "meshing the stock", [&] { return whole(stock, o, err); });
}

} // extern "C"
