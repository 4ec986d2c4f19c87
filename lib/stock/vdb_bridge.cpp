/* vdb_bridge.cpp: the only C++ in lib/stock. It owns the OpenVDB grid and
 * implements the grid work behind stock_private.h: narrow-band rasterizing
 * of an F-rep field (interval classification first, voxel batches only at
 * the boundary, in parallel), the subtraction of a swept volume restricted
 * to the leaves it can change, measures, mesh conversion and (de)serializing.
 * Every extern "C" function catches every exception and turns it into an
 * fm_error. The F-rep -> OpenVDB sign change (phi = -f) happens here. */
#include "stock/stock_private.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/Stream.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetMeasure.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <memory>
#include <mutex>
#include <new>
#include <streambuf>
#include <vector>

namespace {

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

void init_openvdb()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

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

} // namespace

struct fm_vdb {
    Grid::Ptr grid;
    double voxel = 0;
    int band = 0;
    float background = 0;
    double origin[3] = {0, 0, 0};
    std::unique_ptr<tbb::task_arena> arena;
    size_t leaves = 0; /* tracked for budgets; exact after build and load */
    bool has_bounds = false;
    Coord bounds_lo, bounds_hi; /* index box holding everything not outside */
};

namespace {

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

/* Per-thread fm_field worker states, made on first use in each thread. */
class Workers {
public:
    explicit Workers(const fm_field *f) : f_(f), ets_(nullptr) {}
    ~Workers()
    {
        if (!f_->worker_free) return;
        for (void *w : ets_)
            if (w) f_->worker_free(f_->ctx, w);
    }
    void *local()
    {
        void *&w = ets_.local();
        if (!w && f_->worker_new) w = f_->worker_new(f_->ctx);
        return w;
    }

private:
    const fm_field *f_;
    tbb::enumerable_thread_specific<void *> ets_;
};

enum class Mode { build, subtract };

/* A leaf-sized box that needs voxel work. leaf is the stock's existing leaf
 * there (subtract mode), or null where the stock is an inside tile (subtract)
 * or empty (build). */
struct LeafJob {
    Coord origin;
    Leaf *leaf;
    double field_hi; /* upper end of the field's interval over the leaf */
};

struct Box {
    Coord origin;
    int size;
};

/* Interval pass: walk aligned boxes from 4096^3 down to leaves, keeping the
 * leaves whose box can hold the field's boundary (widened by the band) and,
 * when subtracting, that meet the stock. */
struct Classifier {
    fm_vdb *v;
    const fm_field *field;
    void *worker;
    Mode mode;
    Coord clip_lo, clip_hi;
    Acc acc;
    size_t leaf_limit;
    bool over_limit = false;
    size_t intervals = 0;
    size_t new_leaves = 0;
    std::vector<LeafJob> jobs;
    std::vector<Box> inside;

    Classifier(fm_vdb *vv, const fm_field *f, void *w, Mode m, Coord lo, Coord hi, size_t limit)
        : v(vv), field(f), worker(w), mode(m), clip_lo(lo), clip_hi(hi),
          acc(vv->grid->tree()), leaf_limit(limit)
    {
    }

    void visit(const Coord &o, int s)
    {
        if (over_limit) return;
        const Coord e = o.offsetBy(s - 1);
        for (int k = 0; k < 3; k++)
            if (e[k] < clip_lo[k] || o[k] > clip_hi[k]) return;

        bool stock_tile_inside = false;
        if (mode == Mode::subtract) {
            const int depth = acc.getValueDepth(o);
            if (depth < 3 && depth_extent(depth) >= s) {
                /* One tile covers the box: outside the stock nothing can
                 * change; inside it the cut makes new leaves. */
                if (acc.getValue(o) > 0) return;
                stock_tile_inside = true;
            }
        }

        fm_interval box[3];
        for (int k = 0; k < 3; k++) {
            box[k].lo = v->origin[k] + v->voxel * o[k];
            box[k].hi = v->origin[k] + v->voxel * e[k];
        }
        const fm_interval r = field->interval(field->ctx, worker, box);
        intervals++;
        const double bg = v->background;
        if (r.hi <= -bg) return; /* outside the field by more than the band */
        if (r.lo >= bg) {        /* deep inside the field: a tile */
            inside.push_back(Box{o, s});
            return;
        }
        if (s == LEAF_DIM) {
            Leaf *leaf = nullptr;
            if (mode == Mode::subtract && !stock_tile_inside) {
                leaf = acc.probeLeaf(o);
                if (!leaf) {
                    /* A voxel-level value without a leaf cannot happen; a
                     * tile of a smaller extent than a leaf neither. */
                    const float val = acc.getValue(o);
                    if (val > 0) return;
                }
            }
            if (!leaf) {
                new_leaves++;
                if (new_leaves > leaf_limit) {
                    over_limit = true;
                    return;
                }
            }
            jobs.push_back(LeafJob{o, leaf, r.hi});
            return;
        }
        const int h = s / 2;
        for (int i = 0; i < 8; i++)
            visit(o.offsetBy((i & 4) ? h : 0, (i & 2) ? h : 0, (i & 1) ? h : 0), h);
    }
};

enum : uint8_t { ACT_NONE = 0, ACT_CHANGED, ACT_NEW_LEAF, ACT_TILE_OUT, ACT_TILE_IN };

struct JobResult {
    Leaf *created = nullptr;
    uint64_t set[LEAF_SIZE / 64] = {}; /* subtract: voxels whose value the cut set */
    size_t evaluated = 0; /* voxels the field was evaluated at */
    size_t intervals = 0; /* interval evaluations over octants of the leaf */
    double before = 0, after = 0; /* volume in voxels */
    uint8_t action = ACT_NONE;
};

/* Evaluate one leaf: build: phi = clamp(-f); subtract: phi = max(phi_stock,
 * clamp(f)) = stock \ field. Existing leaves are updated in place (each job
 * owns its leaf, so jobs run in parallel); new leaves are returned. */
void run_job(const fm_vdb *v, const fm_field *field, void *worker, Mode mode, const LeafJob &job,
             JobResult &res)
{
    const float bg = v->background;
    /* the stock's values read from the buffer once, not by getValue per
     * voxel (each call checks for out-of-core data) */
    const float *stock = mode == Mode::subtract && job.leaf ? job.leaf->buffer().data() : nullptr;
    double x[LEAF_SIZE], y[LEAF_SIZE], z[LEAF_SIZE], f[LEAF_SIZE];
    int todo[LEAF_SIZE];
    int n = 0;
    if (mode == Mode::build) {
        for (int i = 0; i < LEAF_SIZE; i++) todo[n++] = i;
    } else {
        /* phi = max(a, clamp(f)) keeps a wherever a >= the field's upper
         * bound (or the band): already cut there, or deeper in the stock
         * than the cut can reach. Those voxels need no evaluation; f = -bg
         * stands for them. Where the leaf's bound leaves some, the bounds of
         * its eight 4^3 octants, each asked for only when it has a voxel
         * the leaf's bound did not settle, settle more. The result is the
         * same as evaluating every voxel. */
        const double cap = std::min<double>(bg, job.field_hi);
        for (int oct = 0; oct < 8; oct++) {
            const int ox = (oct & 4) ? 4 : 0, oy = (oct & 2) ? 4 : 0, oz = (oct & 1) ? 4 : 0;
            int cand[64];
            int nc = 0;
            for (int k = 0; k < 64; k++) {
                const int i = ((ox + (k >> 4)) << 6) | ((oy + ((k >> 2) & 3)) << 3) | (oz + (k & 3));
                const double a = stock ? stock[i] : -bg;
                f[i] = -bg;
                if (a < cap) cand[nc++] = i;
            }
            if (nc == 0) continue;
            fm_interval box[3];
            const int o[3] = {job.origin.x() + ox, job.origin.y() + oy, job.origin.z() + oz};
            for (int k = 0; k < 3; k++) {
                box[k].lo = v->origin[k] + v->voxel * o[k];
                box[k].hi = v->origin[k] + v->voxel * (o[k] + 3);
            }
            const fm_interval r = field->interval(field->ctx, worker, box);
            res.intervals++;
            const double octcap = std::min<double>(cap, r.hi);
            for (int k = 0; k < nc; k++) {
                const int i = cand[k];
                const double a = stock ? stock[i] : -bg;
                if (a >= octcap) continue;
                if (r.lo >= bg) {
                    f[i] = bg; /* deep inside the cut: clamped to the band anyway */
                    continue;
                }
                todo[n++] = i;
            }
        }
    }
    for (int k = 0; k < n; k++) {
        const int i = todo[k];
        x[k] = v->origin[0] + v->voxel * (job.origin.x() + (i >> 6));
        y[k] = v->origin[1] + v->voxel * (job.origin.y() + ((i >> 3) & 7));
        z[k] = v->origin[2] + v->voxel * (job.origin.z() + (i & 7));
    }
    double fv[LEAF_SIZE];
    if (n > 0) field->batch(field->ctx, worker, (size_t)n, x, y, z, fv);
    for (int k = 0; k < n; k++) f[todo[k]] = fv[k];
    res.evaluated = (size_t)n;

    const double inv = 1.0 / v->voxel;
    float out[LEAF_SIZE];
    bool active[LEAF_SIZE];
    bool changed = false;
    int n_active = 0, n_neg = 0;
    double before = 0, after = 0;
    for (int i = 0; i < LEAF_SIZE; i++) {
        /* the field clamped to the band, F-rep sign; NaN counts as outside */
        double fi = f[i];
        if (!(fi == fi)) fi = -bg;
        const float fc = (float)std::min<double>(bg, std::max<double>(-bg, fi));
        float a, phi;
        if (mode == Mode::build) {
            a = bg;
            phi = -fc;
        } else {
            a = stock ? stock[i] : -bg;
            phi = std::max(a, fc);
        }
        out[i] = phi;
        active[i] = std::fabs(phi) < bg;
        n_active += active[i];
        n_neg += phi < 0;
        if (phi != a) {
            changed = true;
            res.set[i >> 6] |= uint64_t(1) << (i & 63);
        }
        before += inside_fraction(a, inv);
        after += inside_fraction(phi, inv);
    }
    res.before = before;
    res.after = after;
    if (!changed) return;

    const bool uniform = n_active == 0 && (n_neg == 0 || n_neg == LEAF_SIZE);
    if (job.leaf) {
        if (uniform) {
            /* the whole leaf is now one tile; the serial phase swaps it */
            res.action = n_neg ? ACT_TILE_IN : ACT_TILE_OUT;
            return;
        }
        float *vals = job.leaf->buffer().data();
        for (int i = 0; i < LEAF_SIZE; i++) {
            vals[i] = out[i];
            job.leaf->setActiveState(i, active[i]);
        }
        res.action = ACT_CHANGED;
        return;
    }
    if (uniform) {
        /* build: empty space stays empty, a full leaf becomes an inside
         * tile; subtract: the region was an inside tile and is now cut
         * through entirely */
        if (mode == Mode::build)
            res.action = n_neg ? ACT_TILE_IN : ACT_NONE;
        else
            res.action = n_neg ? ACT_NONE : ACT_TILE_OUT;
        return;
    }
    auto *leaf = new Leaf(job.origin, bg, false);
    for (int i = 0; i < LEAF_SIZE; i++) {
        leaf->setValueOnly(i, out[i]);
        leaf->setActiveState(i, active[i]);
    }
    res.created = leaf;
    res.action = ACT_NEW_LEAF;
}

/* Inside volume (in voxels) of the stock in an aligned box, and the number
 * of leaves there; reads tiles whole. */
double box_volume(const CAcc &acc, const Coord &o, int s, double inv,
                  size_t *leaves)
{
    const int depth = acc.getValueDepth(o);
    if (depth < 3 && depth_extent(depth) >= s)
        return acc.getValue(o) < 0 ? double(s) * s * s : 0.0;
    if (s == LEAF_DIM) {
        const Leaf *leaf = acc.probeConstLeaf(o);
        if (!leaf) return acc.getValue(o) < 0 ? double(LEAF_SIZE) : 0.0;
        (*leaves)++;
        double sum = 0;
        for (int i = 0; i < LEAF_SIZE; i++) sum += inside_fraction(leaf->getValue(i), inv);
        return sum;
    }
    const int h = s / 2;
    double sum = 0;
    for (int i = 0; i < 8; i++)
        sum += box_volume(acc, o.offsetBy((i & 4) ? h : 0, (i & 2) ? h : 0, (i & 1) ? h : 0), h,
                          inv, leaves);
    return sum;
}

/* After a cut, an internal node left with nothing but equal tiles becomes a
 * tile itself: local pruning, so that cost stays with the touched region. */
void prune_node1(Tree &tree, const Coord &ijk)
{
    const Node1 *node = tree.probeConstNode<Node1>(ijk);
    if (!node) return;
    float value;
    bool state;
    if (node->isConstant(value, state, 0.0f))
        tree.addTile(2, node->origin(), value, state);
}

fm_status run_rasterize(fm_vdb *v, const fm_field *field, Mode mode, size_t budget,
                        const fm_vdb_cut_events *ev, fm_stock_cut_stats *stats, fm_error *err)
{
    if (!field || !field->batch || !field->interval)
        return fm_error_set(err, FM_ERR_INPUT, "field has no batch or interval callback");
    for (int k = 0; k < 3; k++)
        if (!std::isfinite(field->lo[k]) || !std::isfinite(field->hi[k]) ||
            field->lo[k] > field->hi[k])
            return fm_error_set(err, FM_ERR_INPUT,
                                "field bounds are not a finite box (axis %d: %g .. %g)", k,
                                field->lo[k], field->hi[k]);

    /* Region that can change: the field's box widened by the band (outside
     * it the field is below -band), and when cutting, the stock's box. */
    const double reach = v->background + v->voxel;
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = field->lo[k] - reach;
        hi[k] = field->hi[k] + reach;
    }
    Coord clo, chi;
    for (int k = 0; k < 3; k++) {
        double a = std::floor((lo[k] - v->origin[k]) / v->voxel);
        double b = std::ceil((hi[k] - v->origin[k]) / v->voxel);
        if (mode == Mode::subtract) {
            if (!v->has_bounds) return FM_OK;
            a = std::max(a, double(v->bounds_lo[k]));
            b = std::min(b, double(v->bounds_hi[k]));
        }
        if (a > b) return FM_OK; /* the field misses the stock */
        const double lim = double(1 << 28);
        if (a < -lim || b > lim)
            return fm_error_set(err, FM_ERR_LIMIT,
                                "field bounds %g .. %g mm on axis %d are too far out for "
                                "%g mm voxels",
                                field->lo[k], field->hi[k], k, v->voxel);
        clo[k] = int(a);
        chi[k] = int(b);
    }

    const size_t leaf_bytes = fm_vdb_leaf_bytes();
    const size_t used = mode == Mode::subtract ? v->leaves * leaf_bytes : 0;
    const size_t limit = budget > used ? (budget - used) / leaf_bytes : 0;

    Workers workers(field);
    Classifier cls(v, field, workers.local(), mode, clo, chi, limit);
    for (int x = clo.x() & ~(NODE2_DIM - 1); x <= chi.x(); x += NODE2_DIM)
        for (int y = clo.y() & ~(NODE2_DIM - 1); y <= chi.y(); y += NODE2_DIM)
            for (int z = clo.z() & ~(NODE2_DIM - 1); z <= chi.z(); z += NODE2_DIM)
                cls.visit(Coord(x, y, z), NODE2_DIM);
    if (cls.over_limit) {
        const double need = double(used) + double(cls.new_leaves) * double(leaf_bytes);
        return fm_error_set(err, FM_ERR_LIMIT,
                            "the grid would need more than %.0f MB (%zu new boundary leaves "
                            "of %zu bytes found so far%s) but the memory budget is %.0f MB",
                            need / 1048576.0, cls.new_leaves, leaf_bytes,
                            mode == Mode::subtract ? " on top of the stock" : "",
                            double(budget) / 1048576.0);
    }

    const size_t njobs = cls.jobs.size();
    std::vector<JobResult> results(njobs);
    const double inv = 1.0 / v->voxel;
    std::vector<double> inside_before(cls.inside.size(), 0.0);
    std::vector<size_t> inside_leaves(cls.inside.size(), 0);
    try {
        v->arena->execute([&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, njobs, 16),
                              [&](const tbb::blocked_range<size_t> &r) {
                                  void *w = workers.local();
                                  for (size_t i = r.begin(); i != r.end(); ++i)
                                      run_job(v, field, w, mode, cls.jobs[i], results[i]);
                              });
            if (mode == Mode::subtract) {
                tbb::parallel_for(tbb::blocked_range<size_t>(0, cls.inside.size()),
                                  [&](const tbb::blocked_range<size_t> &r) {
                                      CAcc acc(v->grid->constTree());
                                      for (size_t i = r.begin(); i != r.end(); ++i)
                                          inside_before[i] =
                                              box_volume(acc, cls.inside[i].origin,
                                                         cls.inside[i].size, inv,
                                                         &inside_leaves[i]);
                                  });
            }
        });
    } catch (...) {
        /* jobs may already have built leaves; do not leak them */
        for (auto &r : results) delete r.created;
        throw;
    }

    /* Serial phase: topology changes. */
    Tree &tree = v->grid->tree();
    const float bg = v->background;
    double before = 0, after = 0;
    size_t changed = 0;
    std::vector<Coord> node1s;
    /* leaves not yet in the tree are ours to free if anything throws */
    struct FreeLeft {
        std::vector<JobResult> &r;
        ~FreeLeft()
        {
            for (auto &x : r) delete x.created;
        }
    } free_left{results};
    size_t evaluated = 0, octant_intervals = 0;
    for (size_t i = 0; i < njobs; i++) {
        JobResult &r = results[i];
        evaluated += r.evaluated;
        octant_intervals += r.intervals;
        before += r.before;
        after += r.after;
        const Coord &o = cls.jobs[i].origin;
        switch (r.action) {
        case ACT_NONE: continue;
        case ACT_CHANGED: break;
        case ACT_NEW_LEAF:
            tree.addLeaf(r.created);
            r.created = nullptr;
            v->leaves++;
            break;
        case ACT_TILE_OUT:
        case ACT_TILE_IN:
            if (cls.jobs[i].leaf) v->leaves--;
            tree.addTile(1, o, r.action == ACT_TILE_IN ? -bg : bg, false);
            node1s.push_back(o);
            break;
        }
        changed++;
        const int32_t tlo[3] = {o.x(), o.y(), o.z()};
        const int32_t thi[3] = {o.x() + LEAF_DIM - 1, o.y() + LEAF_DIM - 1,
                                o.z() + LEAF_DIM - 1};
        if (ev && ev->touch) ev->touch(ev->user, tlo, thi);
        if (ev && r.action != ACT_CHANGED && r.action != ACT_NEW_LEAF && ev->cleared)
            ev->cleared(ev->user, tlo, thi);
        else if (ev && ev->leaf_set)
            ev->leaf_set(ev->user, tlo, r.set);
    }
    for (size_t i = 0; i < cls.inside.size(); i++) {
        const Box &b = cls.inside[i];
        const CoordBBox bb(b.origin, b.origin.offsetBy(b.size - 1));
        if (mode == Mode::build) {
            tree.fill(bb, -bg, false);
            continue;
        }
        before += inside_before[i];
        if (inside_before[i] == 0 && inside_leaves[i] == 0) continue;
        tree.fill(bb, bg, false);
        v->leaves -= std::min(v->leaves, inside_leaves[i]);
        node1s.push_back(b.origin);
        const int32_t tlo[3] = {bb.min().x(), bb.min().y(), bb.min().z()};
        const int32_t thi[3] = {bb.max().x(), bb.max().y(), bb.max().z()};
        if (ev && ev->touch) ev->touch(ev->user, tlo, thi);
        if (ev && ev->cleared) ev->cleared(ev->user, tlo, thi);
    }
    if (mode == Mode::subtract) {
        for (const Coord &c : node1s) prune_node1(tree, c);
    } else {
        openvdb::tools::pruneLevelSet(tree);
        refresh_bounds(v);
    }

    if (stats) {
        const double vox3 = v->voxel * v->voxel * v->voxel;
        stats->removed_mm3 = (before - after) * vox3;
        stats->intervals = cls.intervals + octant_intervals;
        stats->leaves_evaluated = njobs;
        stats->voxels_evaluated = evaluated;
        stats->interior_boxes = cls.inside.size();
        stats->leaves_changed = changed;
    }
    return FM_OK;
}

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

size_t fm_vdb_leaf_bytes(void)
{
    /* the node, its separately allocated value buffer, and malloc's header
     * for each of the two */
    return sizeof(Leaf) + sizeof(float) * LEAF_SIZE + 32;
}

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

fm_status fm_vdb_rasterize(fm_vdb *v, const fm_field *field, size_t budget, fm_error *err)
{
    return guarded(err, "rasterizing the stock", [&] {
        return run_rasterize(v, field, Mode::build, budget, nullptr, nullptr, err);
    });
}

fm_status fm_vdb_subtract(fm_vdb *v, const fm_field *field, size_t budget,
                          const fm_vdb_cut_events *events, fm_stock_cut_stats *stats,
                          fm_error *err)
{
    if (stats) std::memset(stats, 0, sizeof *stats);
    return guarded(err, "subtracting a swept volume", [&] {
        return run_rasterize(v, field, Mode::subtract, budget, events, stats, err);
    });
}

fm_status fm_vdb_from_mesh(fm_vdb *v, const float *points, size_t npoints, const uint32_t *tris,
                           size_t ntris, fm_error *err)
{
    return guarded(err, "converting the mesh to a level set", [&]() -> fm_status {
        std::vector<openvdb::Vec3s> pts(npoints);
        for (size_t i = 0; i < npoints; i++)
            pts[i] = openvdb::Vec3s(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
        std::vector<openvdb::Vec3I> tri(ntris);
        for (size_t i = 0; i < ntris; i++)
            tri[i] = openvdb::Vec3I(tris[3 * i], tris[3 * i + 1], tris[3 * i + 2]);
        Grid::Ptr g;
        v->arena->execute([&] {
            g = openvdb::tools::meshToLevelSet<Grid>(v->grid->transform(), pts, tri,
                                                     float(v->band));
        });
        g->setGridClass(openvdb::GRID_LEVEL_SET);
        g->setName("stock");
        v->grid = g;
        v->background = g->background();
        refresh_bounds(v);
        return FM_OK;
    });
}

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

double fm_vdb_voxel(const fm_vdb *v) { return v->voxel; }
int fm_vdb_band(const fm_vdb *v) { return v->band; }
void fm_vdb_origin(const fm_vdb *v, double origin[3])
{
    for (int k = 0; k < 3; k++) origin[k] = v->origin[k];
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

void *fm_vdb_grid_ptr(fm_vdb *v) { return &v->grid; }

} // extern "C"
