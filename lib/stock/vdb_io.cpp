/* vdb_io.cpp: the grid to and from bytes (an OpenVDB stream, Blosc or zip
 * compressed) for snapshots; the snapshot wrapper in snapshot.c checks the
 * bytes before they reach the reader here. */
#include "stock/vdb_bridge.hpp"

#include <openvdb/io/Stream.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <streambuf>

using namespace fm_vdb_bridge;

namespace {

/* An std::streambuf over bytes already in memory, so that OpenVDB reads the
 * verified snapshot without another copy. */
class MemoryBuf : public std::streambuf {
public:
    MemoryBuf(const unsigned char *p, size_t n)
    {
        char *b = reinterpret_cast<char *>(const_cast<unsigned char *>(p));
        setg(b, b, b + n);
    }
};

/* An std::streambuf that grows a malloc'd buffer handed to C afterwards. */
class MallocBuf : public std::streambuf {
public:
    ~MallocBuf() override { std::free(buf_); }
    unsigned char *release(size_t *len)
    {
        *len = len_;
        unsigned char *b = buf_;
        buf_ = nullptr;
        len_ = cap_ = 0;
        return b;
    }

protected:
    std::streamsize xsputn(const char *s, std::streamsize n) override
    {
        if (n <= 0) return 0;
        if (!reserve(len_ + size_t(n))) return 0;
        std::memcpy(buf_ + len_, s, size_t(n));
        len_ += size_t(n);
        return n;
    }
    int_type overflow(int_type c) override
    {
        if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
        const char ch = traits_type::to_char_type(c);
        return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
    }

private:
    bool reserve(size_t need)
    {
        if (need <= cap_) return true;
        size_t cap = cap_ ? cap_ : 1 << 16;
        while (cap < need) cap *= 2;
        void *p = std::realloc(buf_, cap);
        if (!p) return false;
        buf_ = static_cast<unsigned char *>(p);
        cap_ = cap;
        return true;
    }
    unsigned char *buf_ = nullptr;
    size_t len_ = 0, cap_ = 0;
};

} // namespace

extern "C" {

fm_status fm_vdb_write(const fm_vdb *v, unsigned char **buf, size_t *len, fm_error *err)
{
    *buf = nullptr;
    *len = 0;
    return guarded(err, "writing the stock grid", [&]() -> fm_status {
        MallocBuf mb;
        std::ostream os(&mb);
        openvdb::io::Stream out(os);
        uint32_t comp = openvdb::io::COMPRESS_ACTIVE_MASK;
        comp |= openvdb::io::Archive::hasBloscCompression() ? openvdb::io::COMPRESS_BLOSC
                                                            : openvdb::io::COMPRESS_ZIP;
        out.setCompression(comp);
        openvdb::GridCPtrVec grids;
        grids.push_back(v->grid);
        out.write(grids);
        os.flush();
        if (!os) return fm_error_set(err, FM_ERR_LIMIT, "writing the stock grid: out of memory");
        *buf = mb.release(len);
        return FM_OK;
    });
}

fm_vdb *fm_vdb_read(const unsigned char *buf, size_t len, int threads, fm_error *err)
{
    fm_vdb *out = nullptr;
    guarded(err, "reading the stock grid", [&]() -> fm_status {
        init_openvdb();
        MemoryBuf mb(buf, len);
        std::istream is(&mb);
        openvdb::io::Stream in(is, false);
        openvdb::GridPtrVecPtr grids = in.getGrids();
        if (!grids || grids->size() != 1)
            return fm_error_set(err, FM_ERR_INPUT, "snapshot holds %zu grids, expected one",
                                grids ? grids->size() : size_t(0));
        Grid::Ptr g = openvdb::gridPtrCast<Grid>((*grids)[0]);
        if (!g || g->getGridClass() != openvdb::GRID_LEVEL_SET)
            return fm_error_set(err, FM_ERR_INPUT,
                                "snapshot grid is not a float level set");
        const openvdb::math::Transform &xf = g->transform();
        if (!xf.isLinear() || !xf.hasUniformScale())
            return fm_error_set(err, FM_ERR_INPUT, "snapshot grid has a non-uniform transform");
        const double voxel = xf.voxelSize()[0];
        const float bg = g->background();
        if (!(voxel > 0) || !(bg > 0))
            return fm_error_set(err, FM_ERR_INPUT, "snapshot grid has voxel %g, background %g",
                                voxel, double(bg));
        auto v = std::make_unique<fm_vdb>();
        v->grid = g;
        v->voxel = voxel;
        v->background = bg;
        v->band = int(std::lround(bg / voxel));
        const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
        for (int k = 0; k < 3; k++) v->origin[k] = o[k];
        v->arena = make_arena(threads);
        refresh_bounds(v.get());
        out = v.release();
        return FM_OK;
    });
    return out;
}

} // extern "C"
