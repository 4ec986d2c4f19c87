/* vdb_rasterize.cpp: F-rep fields into the grid, in the narrow band only
 * (as OpenVDB's tools/ rasterizers do for their inputs). An interval pass
 * classifies aligned boxes from 4096^3 down to leaves (outside / inside
 * tile / maybe boundary); only boundary leaves get voxel batches, in
 * parallel; then a serial phase changes the topology. Building writes
 * phi = -f into an empty grid; subtracting a swept volume writes
 * phi = max(phi_stock, f) restricted to the leaves it can change, and
 * reports what changed (chunks, tool marks, removed volume). A topology
 * pass (a design's) stops after the interval pass and marks the leaves. */
#include "stock/vdb_bridge.hpp"

#include <openvdb/tools/Prune.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

using namespace fm_vdb_bridge;

namespace {

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
        if (!w && f_->worker_new) {
            /* worker_new returns NULL only when it cannot allocate (frep.h;
             * a stateless field has no worker_new): the callbacks need
             * their state (tests/alloc found the crash). */
            w = f_->worker_new(f_->ctx);
            if (!w) throw std::bad_alloc();
        }
        return w;
    }

private:
    const fm_field *f_;
    tbb::enumerable_thread_specific<void *> ets_;
};

/* topology: build's interval pass only; the leaves it would evaluate become
 * marks (fm_vdb_rasterize_topology) */
enum class Mode { build, subtract, topology };

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

/* Interval pass: aligned boxes from 4096^3 down to leaves, one level at a
 * time, each level's boxes in parallel; it keeps the leaves whose box can
 * hold the field's boundary (widened by the band) and, when subtracting,
 * that meet the stock. Children are listed in the order of their parents,
 * so jobs come out in the same order whatever the thread count. */
class Classifier {
public:
    Classifier(fm_vdb *vv, const fm_field *f, Workers &w, Mode m, Coord lo, Coord hi, size_t limit)
        : v_(vv), field_(f), workers_(w), mode_(m), clip_lo_(lo), clip_hi_(hi), leaf_limit_(limit)
    {
    }

    /* Classify everything under the given root-level boxes. */
    void run(std::vector<Box> level)
    {
        while (!level.empty() && !over_limit()) {
            /* Breadth first, a fine level of a large field holds millions
             * of boxes before a single leaf is counted against the budget:
             * past a size, the level is finished piece by piece, so that
             * the lists stay bounded and the leaf limit stops the pass. */
            if (level.size() > max_level_boxes) {
                for (size_t i = 0; i < level.size() && !over_limit(); i += max_level_boxes) {
                    const size_t end = std::min(level.size(), i + max_level_boxes);
                    run(std::vector<Box>(level.begin() + long(i), level.begin() + long(end)));
                }
                return;
            }
            /* Chunks of boxes, each classified by one task into its own
             * output; the outputs are joined in chunk order. */
            const size_t chunk = 32, nchunks = (level.size() + chunk - 1) / chunk;
            std::vector<Out> outs(nchunks);
            auto work = [&](size_t c) {
                Acc acc(v_->grid->tree());
                void *w = workers_.local();
                const size_t end = std::min(level.size(), (c + 1) * chunk);
                for (size_t i = c * chunk; i < end && !over_limit(); i++) classify(acc, w, level[i], outs[c]);
            };
            if (nchunks == 1) {
                work(0);
            } else {
                v_->arena->execute([&] {
                    tbb::parallel_for(tbb::blocked_range<size_t>(0, nchunks, 1),
                                      [&](const tbb::blocked_range<size_t> &r) {
                                          for (size_t c = r.begin(); c != r.end(); ++c) work(c);
                                      },
                                      tbb::simple_partitioner());
                });
            }
            std::vector<Box> next;
            for (Out &o : outs) {
                intervals += o.intervals;
                jobs.insert(jobs.end(), o.jobs.begin(), o.jobs.end());
                inside.insert(inside.end(), o.inside.begin(), o.inside.end());
                next.insert(next.end(), o.split.begin(), o.split.end());
            }
            level.swap(next);
        }
    }

    static constexpr size_t max_level_boxes = size_t(1) << 16;

    bool over_limit() const { return new_leaves_.load(std::memory_order_relaxed) > leaf_limit_; }
    size_t new_leaves() const { return new_leaves_.load(); }

    size_t intervals = 0;
    std::vector<LeafJob> jobs;
    std::vector<Box> inside;

private:
    struct Out {
        size_t intervals = 0;
        std::vector<LeafJob> jobs;
        std::vector<Box> inside, split;
    };

    void classify(Acc &acc, void *worker, const Box &b, Out &out)
    {
        const Coord &o = b.origin;
        const int s = b.size;
        const Coord e = o.offsetBy(s - 1);
        for (int k = 0; k < 3; k++)
            if (e[k] < clip_lo_[k] || o[k] > clip_hi_[k]) return;

        bool stock_tile_inside = false;
        if (mode_ == Mode::subtract) {
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
            box[k].lo = v_->origin[k] + v_->voxel * o[k];
            box[k].hi = v_->origin[k] + v_->voxel * e[k];
        }
        const fm_interval r = field_->interval(field_->ctx, worker, box);
        out.intervals++;
        const double bg = v_->background;
        if (r.hi <= -bg) return; /* outside the field by more than the band */
        if (r.lo >= bg) {        /* deep inside the field: a tile */
            out.inside.push_back(b);
            return;
        }
        if (s == LEAF_DIM) {
            Leaf *leaf = nullptr;
            if (mode_ == Mode::subtract && !stock_tile_inside) {
                leaf = acc.probeLeaf(o);
                /* A voxel-level value without a leaf cannot happen; a tile
                 * of a smaller extent than a leaf neither. */
                if (!leaf && acc.getValue(o) > 0) return;
            }
            if (!leaf && new_leaves_.fetch_add(1, std::memory_order_relaxed) + 1 > leaf_limit_) return;
            out.jobs.push_back(LeafJob{o, leaf, r.hi});
            return;
        }
        const int h = s / 2;
        for (int i = 0; i < 8; i++)
            out.split.push_back(Box{o.offsetBy((i & 4) ? h : 0, (i & 2) ? h : 0, (i & 1) ? h : 0), h});
    }

    fm_vdb *v_;
    const fm_field *field_;
    Workers &workers_;
    Mode mode_;
    Coord clip_lo_, clip_hi_;
    size_t leaf_limit_;
    std::atomic<size_t> new_leaves_{0};
};

/* One leaf job in this many is timed for the statistics. */
constexpr size_t JOB_SAMPLE = 8;

enum : uint8_t { ACT_NONE = 0, ACT_CHANGED, ACT_NEW_LEAF, ACT_TILE_OUT, ACT_TILE_IN };

struct JobResult {
    Leaf *created = nullptr;
    uint64_t set[LEAF_SIZE / 64] = {}; /* subtract: voxels whose value the cut set */
    size_t evaluated = 0; /* voxels the field was evaluated at */
    size_t intervals = 0; /* interval evaluations over octants of the leaf */
    size_t changed_voxels = 0; /* voxels whose value changed */
    size_t uncertain = 0; /* voxels a field evaluation that ran out of budget may have left low */
    double uncertain_mm = 0; /* by how much at most */
    double removed = 0; /* subtract: inside volume before - after, in voxels */
    double job_s = 0, field_s = 0; /* timed jobs only: the whole job, the field calls in it */
    uint8_t action = ACT_NONE;
};

inline double seconds_now()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/* Is the leaf (values and activity) now one uniform tile: no active voxel
 * and every value on one side? Returns 0 (no), -1 (inside), +1 (outside). */
int uniform_sign(const float *vals, const Leaf::NodeMaskType &mask)
{
    if (!mask.isOff()) return 0;
    int neg = 0;
    for (int i = 0; i < LEAF_SIZE; i++) neg += vals[i] < 0;
    return neg == LEAF_SIZE ? -1 : neg == 0 ? 1 : 0;
}

/* The least float at or above x: a float a is below x exactly when it is
 * below this, so the leaf's floats compare in float. */
inline float float_at_least(double x)
{
    float f = float(x);
    if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

/* Bits 0-3: which of q[0..4) are below cap. */
inline uint64_t below4(const float *q, float cap)
{
#if defined(__SSE2__)
    return uint64_t(_mm_movemask_ps(_mm_cmplt_ps(_mm_loadu_ps(q), _mm_set1_ps(cap))));
#else
    return uint64_t(q[0] < cap) | uint64_t(q[1] < cap) << 1 | uint64_t(q[2] < cap) << 2 | uint64_t(q[3] < cap) << 3;
#endif
}

/* Evaluate one leaf: build: phi = clamp(-f); subtract: phi = max(phi_stock,
 * clamp(f)) = stock \ field. Existing leaves are updated in place (each job
 * owns its leaf, so jobs run in parallel); new leaves are returned. When
 * timed, how long the job and its field calls took is recorded (the
 * benchmark's breakdown samples jobs; clock reads cost too much for all). */
void run_job(const fm_vdb *v, const fm_field *field, void *worker, Mode mode, const LeafJob &job,
             JobResult &res, bool timed)
{
    const double t_start = timed ? seconds_now() : 0;
    double t_field = 0;
    const float bg = v->background;
    /* the stock's values read and written in the buffer, not by getValue
     * per voxel (each call checks for out-of-core data) */
    float *stock = mode == Mode::subtract && job.leaf ? job.leaf->buffer().data() : nullptr;
    double x[LEAF_SIZE], y[LEAF_SIZE], z[LEAF_SIZE], fv[LEAF_SIZE], sf[LEAF_SIZE];
    const bool shortfall = mode == Mode::subtract && field->batch_shortfall;
    int todo[LEAF_SIZE], full[LEAF_SIZE];
    int n = 0, nfull = 0;
    if (mode == Mode::build) {
        for (int i = 0; i < LEAF_SIZE; i++) todo[n++] = i;
    } else {
        /* phi = max(a, clamp(f)) keeps a wherever a >= the field's upper
         * bound (or the band): already cut there, or deeper in the stock
         * than the cut can reach. Those voxels need no evaluation and are
         * not touched. Where the leaf's bound leaves some, the bounds of
         * its eight 4^3 octants, each asked for only when it has a voxel
         * the leaf's bound did not settle, settle more. The result is the
         * same as evaluating every voxel. */
        const double cap = std::min<double>(bg, job.field_hi);
        /* A field within its box (frep.h) is at most the voxel's signed
         * distance to that box: where the stock already holds that much, a
         * previous cut took the voxel as far as this one can (the floor or
         * wall of a pocket retraced by the next pass, which the octant's
         * interval cannot see). The margin covers the field's own rounding. */
        const bool boxed = field->within_box != 0;
        /* The box distance is separable: per axis, the 8 coordinates of
         * the leaf are inside [lo, hi] (their distance to its nearer face)
         * or outside (the square of their distance to it). */
        double face[3][8], out2[3][8];
        if (boxed)
            for (int k = 0; k < 3; k++)
                for (int j = 0; j < 8; j++) {
                    const double p = v->origin[k] + v->voxel * (job.origin[k] + j);
                    const double below = field->lo[k] - p, above = p - field->hi[k];
                    face[k][j] = below > 0 || above > 0 ? bg : std::min(-below, -above);
                    out2[k][j] = below > 0 ? below * below : above > 0 ? above * above : 0;
                }
        /* Does the box bound settle voxel i, whose stock value is a? Outside
         * the box S <= -distance < 0, so the stock's air side, or a voxel
         * farther out than the band, is settled without the square root. */
        auto box_settles = [&](int i, double a) {
            const int ix = i >> 6, iy = (i >> 3) & 7, iz = i & 7;
            const double o2 = out2[0][ix] + out2[1][iy] + out2[2][iz];
            if (o2 > 1e-20 && (a >= 0 || o2 >= double(bg) * bg)) return true;
            const double in = std::min<double>(bg, std::min(face[0][ix], std::min(face[1][iy], face[2][iz])));
            return a >= clamp_to_band((o2 > 0 ? -std::sqrt(o2) : in) + 1e-11, bg);
        };
        /* Which voxels are below the cap: bit y * 8 + z of word x. An
         * octant's voxels are four words' bits under one of four masks. */
        uint64_t below[8];
        const float capf = float_at_least(cap);
        for (int ix = 0; ix < 8; ix++) {
            uint64_t w = 0;
            if (stock)
                for (int b = 0; b < 64; b += 4) w |= below4(stock + ix * 64 + b, capf) << b;
            else
                w = -bg < cap ? ~uint64_t(0) : 0;
            below[ix] = w;
        }
        for (int oct = 0; oct < 8; oct++) {
            const int ox = (oct & 4) ? 4 : 0, oy = (oct & 2) ? 4 : 0, oz = (oct & 1) ? 4 : 0;
            const uint64_t rows = uint64_t(0xF) << oz; /* z in [oz, oz + 4) of one y */
            const uint64_t octmask = (rows | rows << 8 | rows << 16 | rows << 24) << (8 * oy);
            uint64_t any = 0;
            for (int ix = ox; ix < ox + 4; ix++) any |= below[ix] & octmask;
            if (!any) continue;
            fm_interval box[3];
            const int o[3] = {job.origin.x() + ox, job.origin.y() + oy, job.origin.z() + oz};
            for (int k = 0; k < 3; k++) {
                box[k].lo = v->origin[k] + v->voxel * o[k];
                box[k].hi = v->origin[k] + v->voxel * (o[k] + 3);
            }
            const double t0 = timed ? seconds_now() : 0;
            const fm_interval r = field->interval(field->ctx, worker, box);
            if (timed) t_field += seconds_now() - t0;
            res.intervals++;
            const double octcap = std::min<double>(cap, r.hi);
            /* Deeper inside the field's box than the band, the box bound is
             * the band and skips nothing: only octants near a face or
             * outside ask it (most of a ball's, none of a floor's). */
            bool deep = true;
            for (int k = 0; k < 3; k++) deep = deep && box[k].lo - bg > field->lo[k] && box[k].hi + bg < field->hi[k];
            const bool near_face = boxed && !deep;
            /* the octant's voxels below its own cap, as a mask like below's */
            const float octcapf = float_at_least(octcap);
            for (int ix = ox; ix < ox + 4; ix++) {
                uint64_t open = 0;
                if (stock)
                    for (int iy = oy; iy < oy + 4; iy++)
                        open |= below4(stock + (ix << 6) + (iy << 3) + oz, octcapf) << ((iy << 3) + oz);
                else
                    open = -bg < octcap ? octmask : 0;
                for (uint64_t m = below[ix] & octmask & open; m; m &= m - 1) {
                    const int i = (ix << 6) | __builtin_ctzll(m);
                    const double a = stock ? stock[i] : -bg;
                    if (near_face && box_settles(i, a)) continue;
                    if (r.lo >= bg)
                        full[nfull++] = i; /* deep inside the cut: clamped to the band anyway */
                    else
                        todo[n++] = i;
                }
            }
        }
    }
    for (int k = 0; k < n; k++) {
        const int i = todo[k];
        x[k] = v->origin[0] + v->voxel * (job.origin.x() + (i >> 6));
        y[k] = v->origin[1] + v->voxel * (job.origin.y() + ((i >> 3) & 7));
        z[k] = v->origin[2] + v->voxel * (job.origin.z() + (i & 7));
    }
    if (n > 0) {
        const double t0 = timed ? seconds_now() : 0;
        if (shortfall)
            field->batch_shortfall(field->ctx, worker, (size_t)n, x, y, z, fv, sf);
        else
            field->batch(field->ctx, worker, (size_t)n, x, y, z, fv);
        if (timed) t_field += seconds_now() - t0;
    }
    res.evaluated = (size_t)n;

    if (mode == Mode::build) {
        float out[LEAF_SIZE];
        Leaf::NodeMaskType mask;
        bool changed = false;
        for (int i = 0; i < LEAF_SIZE; i++) {
            out[i] = -clamp_to_band(fv[i], bg);
            if (std::fabs(out[i]) < bg) mask.setOn(i);
            changed |= out[i] != bg;
        }
        if (changed) {
            const int u = uniform_sign(out, mask);
            if (u) {
                /* empty space stays empty, a full leaf becomes an inside tile */
                res.action = u < 0 ? ACT_TILE_IN : ACT_NONE;
            } else {
                auto *leaf = new Leaf(job.origin, bg, false);
                std::memcpy(leaf->buffer().data(), out, sizeof out);
                leaf->setValueMask(mask);
                res.created = leaf;
                res.action = ACT_NEW_LEAF;
            }
        }
    } else {
        /* Only the evaluated voxels and those deep inside the cut can
         * change: update them in place (in a scratch leaf where the stock
         * is an inside tile), counting what changed and the volume it
         * took. */
        float scratch[LEAF_SIZE];
        Leaf::NodeMaskType scratch_mask;
        float *vals = stock;
        Leaf::NodeMaskType *mask = job.leaf ? &job.leaf->getValueMask() : &scratch_mask;
        if (!vals) {
            std::fill(scratch, scratch + LEAF_SIZE, -bg);
            vals = scratch;
        }
        const double inv = 1.0 / v->voxel;
        double removed = 0;
        size_t nchanged = 0;
        auto apply = [&](int i, float fc) {
            const float a = vals[i];
            if (!(fc > a)) return; /* max(a, fc) = a */
            vals[i] = fc;
            mask->set(i, std::fabs(fc) < bg);
            res.set[i >> 6] |= uint64_t(1) << (i & 63);
            nchanged++;
            removed += inside_fraction(a, inv) - inside_fraction(fc, inv);
        };
        for (int k = 0; k < n; k++) {
            const int i = todo[k];
            if (shortfall && sf[k] > 0) {
                /* the true value lies in [fv, fv + sf]: the voxel is
                 * uncertain when the top of that range would store more */
                const float hi = clamp_to_band(fv[k] + sf[k], bg);
                const float stored = std::max(vals[i], clamp_to_band(fv[k], bg));
                if (hi > stored) {
                    res.uncertain++;
                    res.uncertain_mm = std::max(res.uncertain_mm, double(hi) - double(stored));
                }
            }
            apply(i, clamp_to_band(fv[k], bg));
        }
        for (int k = 0; k < nfull; k++) apply(full[k], bg);
        res.changed_voxels = nchanged;
        res.removed = removed;
        if (nchanged > 0) {
            const int u = uniform_sign(vals, *mask);
            if (job.leaf) {
                /* a leaf now uniform becomes one tile; the serial phase swaps it */
                res.action = u < 0 ? ACT_TILE_IN : u > 0 ? ACT_TILE_OUT : ACT_CHANGED;
            } else if (u) {
                /* the region was an inside tile and is now cut through entirely */
                res.action = u < 0 ? ACT_NONE : ACT_TILE_OUT;
            } else {
                auto *leaf = new Leaf(job.origin, bg, false);
                std::memcpy(leaf->buffer().data(), scratch, sizeof scratch);
                leaf->setValueMask(scratch_mask);
                res.created = leaf;
                res.action = ACT_NEW_LEAF;
            }
        }
    }
    if (timed) {
        res.job_s = seconds_now() - t_start;
        res.field_s = t_field;
    }
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

    const double t_classify = seconds_now();
    Workers workers(field);
    Classifier cls(v, field, workers, mode, clo, chi, limit);
    /* The roots go to the classifier in bounded batches: a large box at a
     * fine voxel has a billion of them (4 m at 1 um), more than the budget
     * allows to list. */
    std::vector<Box> roots;
    for (int x = clo.x() & ~(NODE2_DIM - 1); x <= chi.x() && !cls.over_limit(); x += NODE2_DIM)
        for (int y = clo.y() & ~(NODE2_DIM - 1); y <= chi.y() && !cls.over_limit(); y += NODE2_DIM)
            for (int z = clo.z() & ~(NODE2_DIM - 1); z <= chi.z(); z += NODE2_DIM) {
                roots.push_back(Box{Coord(x, y, z), NODE2_DIM});
                if (roots.size() == Classifier::max_level_boxes) {
                    cls.run(std::move(roots));
                    roots = std::vector<Box>();
                }
            }
    if (!roots.empty() && !cls.over_limit()) cls.run(std::move(roots));
    if (cls.over_limit()) {
        const double need = double(used) + double(cls.new_leaves()) * double(leaf_bytes);
        return fm_error_set(err, FM_ERR_LIMIT,
                            "the grid would need more than %.0f MB (%zu new boundary leaves "
                            "of %zu bytes found so far%s) but the memory budget is %.0f MB",
                            need / 1048576.0, cls.new_leaves(), leaf_bytes,
                            mode == Mode::subtract ? " on top of the stock" : "",
                            double(budget) / 1048576.0);
    }

    if (mode == Mode::topology) {
        Tree &tree = v->grid->tree();
        for (const Box &b : cls.inside)
            tree.fill(CoordBBox(b.origin, b.origin.offsetBy(b.size - 1)), -v->background, false);
        for (const LeafJob &j : cls.jobs) tree.addTile(1, j.origin, FM_VDB_LEAF_MARK, true);
        refresh_bounds(v);
        return FM_OK;
    }

    const double t_voxels = seconds_now();
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
                                      run_job(v, field, w, mode, cls.jobs[i], results[i],
                                              i % JOB_SAMPLE == 0);
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
    const double t_apply = seconds_now();
    Tree &tree = v->grid->tree();
    const float bg = v->background;
    double removed = 0, job_s = 0, field_s = 0;
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
    size_t evaluated = 0, octant_intervals = 0, changed_voxels = 0, uncertain = 0;
    double uncertain_mm = 0;
    for (size_t i = 0; i < njobs; i++) {
        JobResult &r = results[i];
        evaluated += r.evaluated;
        octant_intervals += r.intervals;
        changed_voxels += r.changed_voxels;
        uncertain += r.uncertain;
        uncertain_mm = std::max(uncertain_mm, r.uncertain_mm);
        removed += r.removed;
        job_s += r.job_s;
        field_s += r.field_s;
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
        removed += inside_before[i];
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
        stats->removed_mm3 = removed * vox3;
        stats->intervals = cls.intervals + octant_intervals;
        stats->leaves_evaluated = njobs;
        stats->voxels_evaluated = evaluated;
        stats->interior_boxes = cls.inside.size();
        stats->leaves_changed = changed;
        stats->voxels_changed = changed_voxels;
        stats->voxels_uncertain = uncertain;
        stats->uncertain_max_mm = uncertain_mm;
        stats->time_classify_s = t_voxels - t_classify;
        stats->time_voxels_s = t_apply - t_voxels;
        stats->time_apply_s = seconds_now() - t_apply;
        stats->time_leaves_cpu_s = job_s * JOB_SAMPLE;
        stats->time_field_cpu_s = field_s * JOB_SAMPLE;
    }
    return FM_OK;
}

} // namespace

extern "C" {

fm_status fm_vdb_rasterize(fm_vdb *v, const fm_field *field, size_t budget, fm_error *err)
{
    return guarded(err, "rasterizing the stock", [&] {
        return run_rasterize(v, field, Mode::build, budget, nullptr, nullptr, err);
    });
}

fm_status fm_vdb_rasterize_topology(fm_vdb *v, const fm_field *field, size_t budget,
                                    fm_error *err)
{
    return guarded(err, "classifying the field", [&] {
        return run_rasterize(v, field, Mode::topology, budget, nullptr, nullptr, err);
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

} // extern "C"
