// The batched ray-beam overlap (estimators/overlap_batch.h) against the scalar rayBeamOverlap
// (beam2d.h) it must reproduce bit for bit: which pieces overlap, and for those the interval, the
// projection sb0 and the cosine. On random segments and pieces around a kernel's scale, and on the
// degenerate cases the scalar code branches on (parallel and perpendicular axes, a segment ending
// inside the kernel, a piece ending inside it, grazing). The loader runs the AVX-512 or AVX2 clone
// of the kernel on CPUs that have them and the SSE2 one elsewhere; this test checks whichever one
// this CPU runs.
#include "estimators/overlap_batch.h"

#include "base/rng.h"
#include "estimators/beam2d.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

using namespace tpb;

namespace {

struct PieceCase {
    Vec3 origin, dir;
    double lo, hi;
};

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

Vec3 randomDir(Rng& rng) {
    const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * kPi * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
}

// Compares the batch with the scalar test on every piece; returns the number of overlaps.
int compareWithScalar(const Vec3& xr, const Vec3& wr, double sMax, const std::vector<PieceCase>& cases, double radius) {
    PieceAxes axes;
    for (const PieceCase& c : cases) axes.push(c.origin, c.dir, c.lo, c.hi);
    OverlapBatch batch;
    rayBeamOverlaps(xr, wr, sMax, axes, radius, batch);
    size_t next = 0;
    int overlaps = 0;
    for (size_t i = 0; i < cases.size(); ++i) {
        RayBeamOverlap o;
        const bool hit =
            rayBeamOverlap(xr, wr, sMax, cases[i].origin, cases[i].dir, cases[i].lo, cases[i].hi, radius, o);
        const bool listed = next < batch.hits.size() && batch.hits[next] == i;
        EXPECT_EQ(hit, listed) << "piece " << i;
        if (!listed) continue;
        ++next;
        ++overlaps;
        EXPECT_TRUE(sameBits(o.sMinus, batch.sMinus[i])) << i << ": " << o.sMinus << " vs " << batch.sMinus[i];
        EXPECT_TRUE(sameBits(o.sPlus, batch.sPlus[i])) << i << ": " << o.sPlus << " vs " << batch.sPlus[i];
        EXPECT_TRUE(sameBits(o.sb0, batch.sb0[i])) << i;
        EXPECT_TRUE(sameBits(o.cosRB, batch.cosRB[i])) << i;
    }
    EXPECT_EQ(next, batch.hits.size()) << "the batch lists overlaps the scalar test does not find";
    return overlaps;
}

}  // namespace

TEST(OverlapBatch, RandomPiecesMatchTheScalarTestBitForBit) {
    Rng rng(11, Stream::Test, 1, 0);
    int overlaps = 0, pieces = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Vec3 xr(rng.uniform() - 0.5, rng.uniform() - 0.5, 2.0 + rng.uniform());
        const Vec3 wr = randomDir(rng);
        const double sMax = trial % 3 == 0 ? kInf : 0.2 + 3.0 * rng.uniform();
        const double radius = 0.01 + 0.2 * rng.uniform();
        std::vector<PieceCase> cases;
        // Pieces whose axes pass near the segment (within a few radii) in random directions, and
        // some far away; odd counts so the vector loop's remainder runs too.
        const int n = 37 + trial % 7;
        for (int i = 0; i < n; ++i) {
            const double s = (std::isfinite(sMax) ? sMax : 3.0) * (1.2 * rng.uniform() - 0.1);
            const Vec3 near = xr + s * wr + (3.0 * radius * rng.uniform()) * randomDir(rng);
            const Vec3 dir = randomDir(rng);
            const double len = 0.05 + rng.uniform();
            const double back = len * rng.uniform();
            const double lo = len * 0.5 * rng.uniform();
            cases.push_back({near - back * dir, dir, lo, lo + len * rng.uniform()});
        }
        pieces += n;
        overlaps += compareWithScalar(xr, wr, sMax, cases, radius);
    }
    // The comparison says something only if both answers occur often.
    EXPECT_GT(overlaps, pieces / 10);
    EXPECT_LT(overlaps, pieces * 9 / 10);
}

TEST(OverlapBatch, DegenerateConfigurationsMatchTheScalarTest) {
    const Vec3 xr(0.0, 0.0, 0.0), wr(0.0, 0.0, -1.0);
    const double r = 0.05;
    std::vector<PieceCase> cases = {
        {Vec3(0.01, 0.0, -0.5), Vec3(0.0, 0.0, -1.0), 0.0, 1.0},  // parallel, inside the kernel
        {Vec3(0.2, 0.0, -0.5), Vec3(0.0, 0.0, -1.0), 0.0, 1.0},   // parallel, outside
        {Vec3(0.01, 0.0, -0.5), Vec3(0.0, 0.0, 1.0), 0.0, 1.0},   // antiparallel, inside
        {Vec3(-1.0, 0.0, -0.5), Vec3(1.0, 0.0, 0.0), 0.0, 2.0},   // perpendicular, crossing
        {Vec3(-1.0, 0.0, -0.5), Vec3(1.0, 0.0, 0.0), 0.0, 0.5},   // perpendicular, piece ends before
        {Vec3(-1.0, 0.0, -0.5), Vec3(1.0, 0.0, 0.0), 0.98, 2.0},  // perpendicular, piece ends inside the kernel
        {Vec3(-1.0, r, -0.5), Vec3(1.0, 0.0, 0.0), 0.0, 2.0},     // grazing the kernel (disc 0)
        {Vec3(-1.0, 0.0, -0.99), Vec3(1.0, 0.0, 0.0), 0.0, 2.0},  // the segment ends inside the kernel
        {Vec3(-1.0, 0.0, 0.02), Vec3(1.0, 0.0, 0.0), 0.0, 2.0},   // the kernel around the segment's start
        {Vec3(-1.0, 0.0, -0.5), Vec3(0.6, 0.0, -0.8), 0.0, 3.0},  // oblique
        {Vec3(0.0, 0.0, -0.5), Vec3(0.0, 0.0, 0.0), 0.0, 0.0},    // a point (zero direction)
        {Vec3(0.0, 0.0, -0.5), Vec3(1.0, 0.0, 0.0), 0.0, 0.0},    // a zero-length piece on the segment
        {Vec3(0.0, 0.0, 3.0), Vec3(0.0, 0.0, -1.0), 0.0, 1.0},    // parallel, ends before the segment starts
    };
    const int overlaps = compareWithScalar(xr, wr, 1.0, cases, r);
    EXPECT_GE(overlaps, 5);
    compareWithScalar(xr, wr, kInf, cases, r);
    compareWithScalar(xr, wr, 0.0, cases, r);  // an empty segment: nothing overlaps
}
