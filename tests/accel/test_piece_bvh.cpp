// PieceBvh (core/accel/piece_bvh.h): every box a segment meets is reported, once, and nothing far
// from the segment is, against a brute-force slab test in long double; on random boxes, flat and
// point-like ones, many identical ones (equal Morton codes: the depth cap), axis-parallel segments
// (zero direction components), segments that start on a box's face, and unbounded ones.
#include <algorithm>
#include "accel/piece_bvh.h"
#include "base/rng.h"

#include <gtest/gtest.h>

#include <set>
#include <vector>

using namespace tpb;

namespace {

// Does o + s d, s in [0, sMax], meet the box enlarged by `grow` on every side? (long double)
bool meets(const PieceBvh::Box& b, const Vec3& o, const Vec3& d, double sMax, long double grow) {
    long double lo = 0.0L, hi = sMax;
    const double org[3] = {o.x, o.y, o.z}, dir[3] = {d.x, d.y, d.z};
    for (int a = 0; a < 3; ++a) {
        const long double l = static_cast<long double>(b.lo[a]) - grow, h = static_cast<long double>(b.hi[a]) + grow;
        if (dir[a] == 0.0) {
            if (org[a] < l || org[a] > h) return false;
            continue;
        }
        long double t0 = (l - org[a]) / dir[a], t1 = (h - org[a]) / dir[a];
        if (t0 > t1) std::swap(t0, t1);
        lo = std::max(lo, t0);
        hi = std::min(hi, t1);
    }
    return lo <= hi;
}

Vec3 randomUnit(Rng& rng) {
    const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * kPi * rng.uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

struct Stats {
    size_t queries = 0, reported = 0, exact = 0;
};

// Every box the segment meets is reported exactly once; every reported box lies within `slack`
// (relative to the scene's size) of the segment.
// `reuse`: a hierarchy built before (over other boxes) to rebuild, instead of a new one.
Stats check(const std::vector<PieceBvh::Box>& boxes, Rng& rng, int queries, PieceBvh* reuse = nullptr,
            int threads = 1) {
    PieceBvh fresh;
    PieceBvh& bvh = reuse ? *reuse : fresh;
    bvh.build(boxes, threads);
    EXPECT_EQ(bvh.size(), boxes.size());
    // The memory estimate (kAccelBytesPerPiece, accel/beam_accel.h) counts a node per box.
    EXPECT_LE(bvh.nodeCount(), std::max<size_t>(boxes.size(), 1));
    Stats st;
    for (int q = 0; q < queries; ++q) {
        Vec3 o(4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0);
        Vec3 d = randomUnit(rng);
        if (q % 5 == 0) d = Vec3(q % 3 == 0, q % 3 == 1, q % 3 == 2);  // axis-parallel
        if (q % 7 == 0 && !boxes.empty()) {                            // starting on a face of some box
            const PieceBvh::Box& b = boxes[rng.uniform() * boxes.size()];
            o = Vec3(b.lo[0], 0.5 * (b.lo[1] + b.hi[1]), 0.5 * (b.lo[2] + b.hi[2]));
        }
        const double sMax = q % 4 == 0 ? kInf : 3.0 * rng.uniform();
        std::vector<int> seen(boxes.size(), 0);
        bvh.forEachCrossed(o, d, sMax, [&](uint32_t k) { ++seen[bvh.order()[k]]; });
        for (size_t i = 0; i < boxes.size(); ++i) {
            const bool in = meets(boxes[i], o, d, sMax, 0.0L);
            if (in) {
                EXPECT_EQ(seen[i], 1) << "box " << i << " query " << q;
                ++st.exact;
            } else {
                EXPECT_LE(seen[i], 1) << "box " << i << " query " << q;
            }
            if (seen[i]) {
                EXPECT_TRUE(meets(boxes[i], o, d, sMax, 1e-5L)) << "box " << i << " reported far from query " << q;
                ++st.reported;
            }
        }
        ++st.queries;
        if (::testing::Test::HasFailure()) break;
    }
    return st;
}

PieceBvh::Box box(const Vec3& c, const Vec3& half) {
    PieceBvh::Box b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = static_cast<float>(c[a] - half[a]);
        b.hi[a] = static_cast<float>(c[a] + half[a]);
    }
    return b;
}

// n boxes, centres uniform in [-1, 1]^3, half-sizes uniform in [0, maxHalf] per axis.
std::vector<PieceBvh::Box> randomCloud(Rng& rng, int n, double maxHalf) {
    std::vector<PieceBvh::Box> boxes;
    for (int i = 0; i < n; ++i) {
        const Vec3 c(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0);
        const Vec3 half(maxHalf * rng.uniform(), maxHalf * rng.uniform(), maxHalf * rng.uniform());
        boxes.push_back(box(c, half));
    }
    return boxes;
}

}  // namespace

TEST(PieceBvh, ReportsEveryBoxTheSegmentMeetsOnceAndNoneFarFromIt) {
    Rng rng(41, Stream::Test, 0, 0);
    std::vector<PieceBvh::Box> boxes;
    for (int i = 0; i < 3000; ++i) {
        const Vec3 c(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0);
        Vec3 half(0.25 * rng.uniform(), 0.25 * rng.uniform(), 0.25 * rng.uniform());
        if (i % 10 == 0) half.y = 0.0;      // flat
        if (i % 17 == 0) half = Vec3(0.0);  // a point
        boxes.push_back(box(c, half));
    }
    const Stats st = check(boxes, rng, 400);
    EXPECT_EQ(st.queries, 400u);
    EXPECT_GT(st.exact, 2000u);                        // not vacuous
    EXPECT_LT(st.reported, st.exact + st.exact / 20);  // and not much more than the exact set
}

// Equal centres give equal Morton codes (split at the middle, then the depth cap: a leaf of many);
// a flat cloud (all centres on one plane) has one axis without extent.
TEST(PieceBvh, IdenticalAndCoplanarBoxes) {
    Rng rng(43, Stream::Test, 0, 0);
    std::vector<PieceBvh::Box> same(5000, box(Vec3(0.25, -0.5, 0.75), Vec3(0.2, 0.1, 0.3)));
    Stats st = check(same, rng, 60);
    EXPECT_EQ(st.queries, 60u);
    EXPECT_GT(st.exact, 5000u);
    std::vector<PieceBvh::Box> flat;
    for (int i = 0; i < 2000; ++i)
        flat.push_back(box(Vec3(2.0 * rng.uniform() - 1.0, 0.3, 2.0 * rng.uniform() - 1.0), Vec3(0.05, 0.0, 0.05)));
    st = check(flat, rng, 300);
    EXPECT_EQ(st.queries, 300u);
    EXPECT_GT(st.exact, 100u);
}

TEST(PieceBvh, EmptyAndSingleBox) {
    Rng rng(47, Stream::Test, 0, 0);
    PieceBvh bvh;
    bvh.build({});
    int calls = 0;
    bvh.forEachCrossed(Vec3(0.0), Vec3(1.0, 0.0, 0.0), kInf, [&](uint32_t) { ++calls; });
    EXPECT_EQ(calls, 0);
    const std::vector<PieceBvh::Box> one = {box(Vec3(1.0, 0.0, 0.0), Vec3(0.1))};
    bvh.build(one);
    bvh.forEachCrossed(Vec3(0.0), Vec3(1.0, 0.0, 0.0), kInf, [&](uint32_t k) { calls += 1 + static_cast<int>(k); });
    EXPECT_EQ(calls, 1);
    bvh.forEachCrossed(Vec3(0.0), Vec3(1.0, 0.0, 0.0), 0.85, [&](uint32_t) { ++calls; });
    EXPECT_EQ(calls, 1);  // ends before the box
    const Stats st = check(one, rng, 200);
    EXPECT_EQ(st.queries, 200u);
}

// A hierarchy is rebuilt every pass over the same storage (grown, never shrunk): a smaller set
// after a larger one, then none, then a larger one again, each answered as if built fresh.
TEST(PieceBvh, RebuiltOverDifferentSetsAnswersForTheLastOne) {
    Rng rng(53, Stream::Test, 0, 0);
    PieceBvh bvh;
    for (const int n : {2000, 300, 0, 1, 4000}) {
        const std::vector<PieceBvh::Box> boxes = randomCloud(rng, n, 0.2);
        const Stats st = check(boxes, rng, 80, &bvh);
        EXPECT_EQ(st.queries, 80u) << n << " boxes";
        if (n >= 2000) {
            EXPECT_GT(st.exact, 2 * st.queries) << n << " boxes";  // not vacuous: boxes met per query
        }
    }
}

// Large sets are built with the root's subtrees on several threads, each in its own stretch of the
// node array: the same hierarchy order and the same answers as one thread's build.
TEST(PieceBvh, BuiltOnTwoThreadsAnswersTheSame) {
    Rng rng(59, Stream::Test, 0, 0);
    std::vector<PieceBvh::Box> boxes = randomCloud(rng, 40000, 0.02);
    // and a clump of equal centres (split at the middle once their codes are exhausted)
    for (int i = 0; i < 3000; ++i) boxes.push_back(box(Vec3(0.3, 0.3, 0.3), Vec3(0.01)));
    PieceBvh one, two;
    one.build(boxes, 1);
    two.build(boxes, 2);
    EXPECT_EQ(one.order(), two.order());
    for (int q = 0; q < 200; ++q) {
        const Vec3 o(4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0);
        const Vec3 d = q % 10 == 0 ? glm::normalize(Vec3(0.3) - o) : randomUnit(rng);  // some through the clump
        std::vector<uint32_t> a, b;
        one.forEachCrossed(o, d, kInf, [&](uint32_t k) { a.push_back(k); });
        two.forEachCrossed(o, d, kInf, [&](uint32_t k) { b.push_back(k); });
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        ASSERT_EQ(a, b) << "query " << q;
    }
    const Stats st = check(boxes, rng, 60, nullptr, 2);  // and against the exact slab test
    EXPECT_EQ(st.queries, 60u);
    EXPECT_GT(st.exact, 3000u);
}

// A visit may query the hierarchy again (the traversal's queue is then the nested call's own):
// the outer query still reports each of its boxes once.
TEST(PieceBvh, AVisitThatQueriesAgainLeavesTheOuterQueryWhole) {
    Rng rng(61, Stream::Test, 0, 0);
    const std::vector<PieceBvh::Box> boxes = randomCloud(rng, 2000, 0.2);
    PieceBvh bvh;
    bvh.build(boxes);
    const Vec3 o(-2.0, 0.1, 0.2), d = glm::normalize(Vec3(1.0, 0.05, -0.1));
    std::vector<uint32_t> plain, outer;
    bvh.forEachCrossed(o, d, kInf, [&](uint32_t k) { plain.push_back(k); });
    size_t inner = 0;
    bvh.forEachCrossed(o, d, kInf, [&](uint32_t k) {
        outer.push_back(k);
        bvh.forEachCrossed(Vec3(0.0, -2.0, 0.0), Vec3(0.0, 1.0, 0.0), kInf, [&](uint32_t) { ++inner; });
    });
    std::sort(plain.begin(), plain.end());
    std::sort(outer.begin(), outer.end());
    EXPECT_GT(plain.size(), 5u);
    EXPECT_EQ(plain, outer);
    EXPECT_GT(inner, 0u);
}
