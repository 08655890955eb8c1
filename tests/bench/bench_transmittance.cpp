// The transmittance integral of the 2D beam kernel (transmittanceIntegral, estimators/beam2d.h):
// Int_{s-}^{s+} exp(-sigma_t s - tau_b (sb0 + c s)) ds in closed form, one call per channel. One
// item is one ray-beam estimate's integral as gatherBeam2DPiece evaluates it: one channel in a grey
// medium (SegmentGather::grey), three in a coloured one. Args: {coloured, optical depth index};
// the optical depth sigma_t * (s+ - s-) of the overlaps runs from 1e-6 (thin: expRel's series
// branch) through 1e-3 and 1 to 50 (stiff: expm1 and a tiny exp), each within a factor 0.5-1.5.
#include "base/rng.h"
#include "estimators/beam2d.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <vector>

namespace tpb {
namespace {

constexpr double kOpticalDepths[] = {1e-6, 1e-3, 1.0, 50.0};
constexpr double kOverlapLength = 0.05;  // m, about 2 r: a kernel cylinder crossed sideways

// Overlaps of about kOverlapLength starting within a few lengths of the segment's origin, with
// random cosines: the exponent's start depth stays O(optical depth), never subnormal.
std::vector<RayBeamOverlap> overlaps(size_t n) {
    Rng rng(16, Stream::Test, 0, 0);
    std::vector<RayBeamOverlap> out(n);
    for (RayBeamOverlap& o : out) {
        o.sMinus = 4.0 * kOverlapLength * rng.uniform();
        o.sPlus = o.sMinus + kOverlapLength * (0.5 + rng.uniform());
        o.sb0 = 4.0 * kOverlapLength * rng.uniform();
        o.cosRB = 2.0 * rng.uniform() - 1.0;
    }
    return out;
}

void BM_TransmittanceIntegral(benchmark::State& state) {
    const bool coloured = state.range(0) != 0;
    const double depth = kOpticalDepths[state.range(1)];
    const double sigma = depth / kOverlapLength;
    // Short beams (the default): tau_b = sigma_t - sigma_bar, 0 in a grey medium (photon_tracer.h).
    const Color sigmaT = coloured ? sigma * Color(0.6, 1.0, 1.4) : Color(sigma);
    const Color tauB = sigmaT - Color(average(sigmaT));
    const std::vector<RayBeamOverlap> os = overlaps(1024);
    double sum = 0.0;
    for (auto _ : state) {
        for (const RayBeamOverlap& o : os) {
            const double ix = transmittanceIntegral(sigmaT.x, tauB.x, o);
            const Color integral = coloured ? Color(ix, transmittanceIntegral(sigmaT.y, tauB.y, o),
                                                    transmittanceIntegral(sigmaT.z, tauB.z, o))
                                            : Color(ix);
            benchmark::DoNotOptimize(integral);
            sum += integral.x + integral.z;
        }
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(os.size()));
    char label[64];
    std::snprintf(label, sizeof label, "%s, sigma_t*len=%g", coloured ? "coloured" : "grey", depth);
    state.SetLabel(label);
}
BENCHMARK(BM_TransmittanceIntegral)->ArgsProduct({{0, 1}, {0, 1, 2, 3}})->ArgNames({"coloured", "depth"});

}  // namespace
}  // namespace tpb
