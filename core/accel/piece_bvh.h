// A bounding volume hierarchy over axis-aligned boxes, for queries that want EVERY box a segment
// crosses (the beam pieces' padded boxes, accel/beam_accel.h), not the nearest hit: no ordering,
// no early exit, so the build favours speed over tree quality.
//
// Build (a linear BVH, Lauterbach et al. 2009 "Fast BVH construction on GPUs"): the boxes' centres
// get 33-bit Morton codes (11 bits per axis over the centres' bounds) and are sorted by them (three
// passes of an 11-bit radix sort); a range of the sorted boxes is split where the highest bit in
// which its first and last codes differ changes (the middle when they are equal), two levels at a
// time, so that a node has up to four children (their boxes side by side, tested at once), down to
// single boxes. O(n) after the sort; 128-byte nodes (two cache lines) in depth-first order, with a
// mask per kind of child (interior, one box, several) so that a query branches per child it meets,
// not per slot. Issue 15: Embree's user-geometry build took 22 ms for the default scene's 99k
// pieces (57 % of a 32x32 beam2d pass), and its traversal ~57 ns per box reached, in calls through
// its callback.
//
// Query: a node's four child boxes are slab-tested at once in float; those boxes are padded by
// 1e-6 of their coordinates (+1e-6), far more than the float test's rounding, so a box that meets
// the segment in exact arithmetic is never rejected. A child that is one box is reported when its
// padded box passes; a leaf of several (only at the depth cap) tests each of its boxes in double
// against the stored float values. The caller pads the boxes themselves (outward float rounding
// included) for its own exact test. The nodes to visit are queued first in first out, each
// prefetched when queued: breadth-first, a query has many node fetches in flight instead of
// waiting on one after another (BM_BeamAccelCandidates 5-10 % faster than depth-first).
#pragma once
#include "base/math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

namespace tpb {

class PieceBvh {
public:
    // The binary splits' depth cap (33 Morton bits, then halving runs of equal codes: enough for
    // 2^27 boxes with one centre): a range that deep becomes one leaf, however many boxes it has.
    static constexpr int kMaxDepth = 60;
    struct Box {
        float lo[3], hi[3];
    };
    // Replaces the hierarchy by one over `boxes`. Queries report a box by its position in the
    // hierarchy's order, order()[position] being its index in `boxes`: a caller that stores its
    // items in that order reads the items of a query's neighbouring hits from neighbouring memory.
    // `threads`: the per-box loops and the root's subtrees are shared among that many threads
    // (the same hierarchy, answering the same queries, for any number).
    void build(const std::vector<Box>& boxes, int threads = 1);
    const std::vector<uint32_t>& order() const { return order_; }
    size_t size() const { return order_.size(); }
    size_t nodeCount() const { return nodeCount_; }

    // Calls visit(k) once for each box (at position k of order()) that the segment o + s d,
    // s in [0, sMax], meets (and possibly for boxes it passes within rounding of), in an
    // unspecified order. sMax may be inf.
    template <class Visit>
    void forEachCrossed(const Vec3& o, const Vec3& d, double sMax, Visit&& visit) const {
        if (nodeCount_ == 0) return;
        // A zero (or tiny) direction component: the slab holds the whole segment or none of it; a
        // huge finite inverse gives that answer without a branch per node ((lo - o) * big is
        // +-huge, or 0 when o lies on the plane, which counts as inside).
        const auto inverse = [](double x) { return std::abs(x) > 1e-30 ? std::clamp(1.0 / x, -1e30, 1e30) : 1e30; };
        const double invD[3] = {inverse(d.x), inverse(d.y), inverse(d.z)};
        const double org[3] = {o.x, o.y, o.z};
        // Float copies for the nodes (whose boxes are padded for float rounding, build()).
        V4 o4[3], i4[3];
        for (int a = 0; a < 3; ++a) {
            o4[a] = V4{} + static_cast<float>(org[a]);
            i4[a] = V4{} + static_cast<float>(invD[a]);
        }
        const V4 tMax4 = V4{} + static_cast<float>(std::min(sMax, 3e38));
        // A leaf's own boxes: the slab test in double on the stored (exact) float values.
        const auto crosses = [&](const Box& b) {
            double tNear = 0.0, tFar = sMax;
            for (int a = 0; a < 3; ++a) {
                const double t0 = (static_cast<double>(b.lo[a]) - org[a]) * invD[a];
                const double t1 = (static_cast<double>(b.hi[a]) - org[a]) * invD[a];
                tNear = std::max(tNear, std::min(t0, t1));
                tFar = std::min(tFar, std::max(t0, t1));
            }
            return tNear <= tFar;
        };
        // The nodes still to visit, first in first out: a node is fetched ahead when it is queued
        // and visited only after the ones queued before it, so that the traversal does not wait on
        // one node's fetch after another (the order of the reported boxes does not matter).
        // (The thread's queue, or one of this call's own when a visit queries again.)
        thread_local std::vector<uint32_t> threadQueue;
        thread_local bool threadQueueInUse = false;
        std::vector<uint32_t> ownQueue;
        const bool nested = threadQueueInUse;
        std::vector<uint32_t>& queue = nested ? ownQueue : threadQueue;
        struct Release {
            bool nested;
            ~Release() {
                if (!nested) threadQueueInUse = false;
            }
        } release{nested};
        threadQueueInUse = true;
        queue.clear();
        size_t head = 0;
        uint32_t n = 0;
        while (true) {
            const Node4& node = nodes_[n];
            V4 tNear = V4{}, tFar = tMax4;
            for (int a = 0; a < 3; ++a) {
                V4 lo, hi;
                std::memcpy(&lo, node.lo[a], sizeof lo);
                std::memcpy(&hi, node.hi[a], sizeof hi);
                const V4 t0 = (lo - o4[a]) * i4[a], t1 = (hi - o4[a]) * i4[a];
                tNear = vmax(tNear, vmin(t0, t1));
                tFar = vmin(tFar, vmax(t0, t1));
            }
            // The slots whose box the segment meets (an unused slot never does). Compared lane by
            // lane: the mask built from the vector comparison's lanes was miscompiled by GCC 12
            // under -O1 with UBSan (children lost; tests/accel/test_piece_bvh.cpp caught it).
            unsigned met = 0;
            for (int j = 0; j < 4; ++j) met |= (tNear[j] <= tFar[j] ? 1u : 0u) << j;
            // Interior children: queued, and fetched ahead.
            for (unsigned m = met & node.interior; m; m &= m - 1) {
                const uint32_t c = node.child[__builtin_ctz(m)];
                const char* line = reinterpret_cast<const char*>(&nodes_[c]);
                __builtin_prefetch(line);
                __builtin_prefetch(line + 64);
                queue.push_back(c);
            }
            // One-box leaves: the slot's (padded) box was the box's test.
            for (unsigned m = met & node.single; m; m &= m - 1) visit(node.child[__builtin_ctz(m)]);
            // Leaves of several boxes (only at the depth cap): each box in double.
            for (unsigned m = met & node.several; m; m &= m - 1) {
                const Leaf& leaf = leaves_[node.child[__builtin_ctz(m)]];
                for (uint32_t k = leaf.first; k < leaf.first + leaf.count; ++k)
                    if (crosses(sorted_[k])) visit(k);
            }
            if (head == queue.size()) return;
            n = queue[head++];
        }
    }

private:
    using V4 = float __attribute__((vector_size(16)));
    static V4 vmin(V4 a, V4 b) { return a < b ? a : b; }
    static V4 vmax(V4 a, V4 b) { return a > b ? a : b; }
    // A node: up to four children, their boxes side by side (one vector per axis and side: the
    // four slab tests at once).
    // Two cache lines.
    struct alignas(64) Node4 {
        float lo[3][4];
        float hi[3][4];
        // Per slot: an interior child's node, a one-box leaf's box (its position in order_), or a
        // leaf of several boxes' entry in leaves_.
        uint32_t child[4];
        // Slot masks (bit j: slot j): interior children, leaves of one box, leaves of several; an
        // unused slot is in none.
        uint8_t interior, single, several;
    };
    static Box emptyBox() { return {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}}; }
    static void grow(Box& into, const Box& b) {
        for (int a = 0; a < 3; ++a) {
            into.lo[a] = std::min(into.lo[a], b.lo[a]);
            into.hi[a] = std::max(into.hi[a], b.hi[a]);
        }
    }
    // Child slot j of `node`: its box padded for the float test, or (`box` null) an unused slot.
    static void setSlot(Node4& node, int j, const Box* box);
    uint32_t splitOf(uint32_t begin, uint32_t end) const;
    struct Split {
        int ranges = 0;
        uint32_t r[4][2];  // [begin, end) of each child's range
    };
    struct Leaf;
    // Where a (sub)tree's build writes: its next node, and the leaves of several boxes.
    struct Builder {
        uint32_t next;
        std::vector<Leaf>* leaves;
    };
    Split splitRange(uint32_t begin, uint32_t end, int depth) const;
    static bool isLeaf(const Split& s, int j, int depth);
    static void beginNode(Node4& node);
    void finishNode(Node4& node, const Split& s, int depth, const Box (&childBox)[4], Builder& builder,
                    Box& bounds) const;
    uint32_t buildNode(uint32_t begin, uint32_t end, int depth, Box& bounds, Builder& builder);

    // A sort key: the Morton code (33 bits) above the box's index (kIndexBits).
    static constexpr int kIndexBits = 31;
    static constexpr uint64_t kIndexMask = (uint64_t(1) << kIndexBits) - 1;

    std::unique_ptr<Node4[]> nodes_;  // depth-first, the root first; kept (and grown) across builds
    size_t nodeCount_ = 0, nodeCapacity_ = 0;
    std::vector<uint32_t> order_;  // box indices in Morton order (the positions queries report)
    std::vector<Box> sorted_;      // the boxes in that order (a leaf's boxes are contiguous)
    struct Leaf {
        uint32_t first, count;  // positions [first, first + count) in order_
    };
    std::vector<Leaf> leaves_;                  // the leaves of several boxes (at the depth cap)
    std::vector<uint64_t> keys_, scratchKeys_;  // sort keys, sorted after build()
};

}  // namespace tpb
