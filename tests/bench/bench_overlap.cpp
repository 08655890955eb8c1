// The ray-beam overlap test (rayBeamOverlap, estimators/beam2d.h): the interval of a camera
// segment inside a beam's kernel cylinder. It runs on every candidate piece the accelerator
// reaches (as its CandidateTest) and again in gatherBeam2DPiece, so it is the innermost loop of the
// beam2d camera pass. Measured on a fixed pseudo-random set of ray-beam pairs, about half of which
// overlap (the rest miss the cylinder, its end caps or the segment's end), in random order so the
// branches are as unpredictable as behind a BVH traversal. items/s = overlap tests per second.
// BM_RayBeamOverlapBatch: the same test as the camera pass runs it on a block's shared pieces
// (estimators/overlap_batch.h): one segment against 512 pieces per call, vectorised (the AVX2 clone
// on CPUs that have it), the overlapping ones listed.
#include "base/rng.h"
#include "estimators/beam2d.h"
#include "estimators/overlap_batch.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

namespace tpb {
namespace {

Vec3 randomDir(Rng& rng) {
    const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * kPi * rng.uniform();
    const double s = std::sqrt(1.0 - z * z);
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
}

struct OverlapCase {
    Vec3 xr, wr, xb, wb;
    double sMax, sbLo, sbHi, radius;
};

// Beams passing within about 2 r of a point on the ray: the cylinder (radius r) catches roughly
// half of them; some of the rest are cut by the piece's range [sbLo, sbHi] or the segment's sMax.
std::vector<OverlapCase> overlapCases(size_t n) {
    Rng rng(15, Stream::Test, 0, 0);
    std::vector<OverlapCase> cases(n);
    for (OverlapCase& c : cases) {
        c.radius = 0.02 + 0.02 * rng.uniform();
        c.xr = Vec3(rng.uniform(), rng.uniform(), rng.uniform());
        c.wr = randomDir(rng);
        c.wb = randomDir(rng);
        c.sMax = 0.5 + 2.0 * rng.uniform();
        const Vec3 near = c.xr + (0.1 + 2.0 * rng.uniform()) * c.wr + 2.0 * c.radius * rng.uniform() * randomDir(rng);
        const double along = 0.5 * rng.uniform();  // the beam point nearest `near` lies this far along it
        c.xb = near - along * c.wb;
        c.sbLo = 0.0;
        c.sbHi = 0.2 + 0.6 * rng.uniform();  // a piece of a beam, as the accelerator hands them
    }
    return cases;
}

void BM_RayBeamOverlap(benchmark::State& state) {
    const std::vector<OverlapCase> cases = overlapCases(4096);
    int64_t hits = 0;
    for (auto _ : state) {
        for (const OverlapCase& c : cases) {
            RayBeamOverlap o;
            const bool hit = rayBeamOverlap(c.xr, c.wr, c.sMax, c.xb, c.wb, c.sbLo, c.sbHi, c.radius, o);
            benchmark::DoNotOptimize(o);
            hits += hit;
        }
        benchmark::DoNotOptimize(hits);
    }
    const int64_t tests = state.iterations() * static_cast<int64_t>(cases.size());
    state.SetItemsProcessed(tests);
    state.counters["hit_fraction"] = static_cast<double>(hits) / static_cast<double>(tests);
}
BENCHMARK(BM_RayBeamOverlap);

void BM_RayBeamOverlapBatch(benchmark::State& state) {
    // Eight segments of the cases above, each against 512 pieces placed around it as overlapCases
    // places a case's beam around its ray (about half overlap).
    const std::vector<OverlapCase> cases = overlapCases(8);
    constexpr size_t kPieces = 512;
    const size_t segments = cases.size();
    Rng rng(16, Stream::Test, 0, 0);
    std::vector<PieceAxes> lists(segments);
    for (size_t s = 0; s < segments; ++s) {
        const OverlapCase& r = cases[s];
        for (size_t i = 0; i < kPieces; ++i) {
            const Vec3 wb = randomDir(rng);
            const Vec3 near =
                r.xr + (0.1 + 2.0 * rng.uniform()) * r.wr + 2.0 * r.radius * rng.uniform() * randomDir(rng);
            lists[s].push(near - 0.5 * rng.uniform() * wb, wb, 0.0, 0.2 + 0.6 * rng.uniform());
        }
    }
    OverlapBatch out;
    int64_t hits = 0;
    for (auto _ : state) {
        for (size_t s = 0; s < segments; ++s) {
            const OverlapCase& r = cases[s];
            rayBeamOverlaps(r.xr, r.wr, r.sMax, lists[s], r.radius, out);
            hits += static_cast<int64_t>(out.hits.size());
        }
        benchmark::DoNotOptimize(hits);
    }
    const int64_t tests = state.iterations() * static_cast<int64_t>(segments * kPieces);
    state.SetItemsProcessed(tests);
    state.counters["hit_fraction"] = static_cast<double>(hits) / static_cast<double>(tests);
}
BENCHMARK(BM_RayBeamOverlapBatch);

}  // namespace
}  // namespace tpb
