// The time splat (splatTime, film/time_splat.h): one estimate's energy spread over the film's
// time bins it covers, exponential profile in closed form. Two entry points:
//   BM_SplatTimeProfile: the SegmentProfile signature with the profile built beforehand, as the
//     gather builds one per estimate and splats it on both time axes (the cost per axis);
//   BM_SplatTimeKappa:   the older (kappa, s0, s1) signature, which builds the profile per call.
// Args: {bins, span, coloured}. The film is 10.24 m of OPL in 1, 256 or 1024 bins; span 0 is an
// estimate inside one bin (0.4 of a bin: no transcendental call), span 16 one covering 16 bin
// widths (17 bins, 18 boundaries; 256 and 1024 bins only: in a one-bin film an estimate 16 bins
// long would be 164 m of OPL, mostly before and after the film).
// coloured 0 is a grey kappa (one channel evaluated, the default scene's fog), 1 three kappas.
// items/s = estimates splatted per second; bins_per_estimate counts the sink's calls.
#include "base/rng.h"
#include "film/time_splat.h"

#include <benchmark/benchmark.h>

#include <utility>
#include <vector>

namespace tpb {
namespace {

constexpr double kFilmStart = 1.0, kFilmRange = 10.24;  // m of OPL

struct SplatCase {
    double s0, s1;  // m along the camera segment
    double a, b;    // t(s) = a + b s (m of OPL)
};

TimeBins filmBins(int bins) {
    TimeBins tb;
    tb.startOpl = kFilmStart;
    tb.binWidth = kFilmRange / bins;
    tb.bins = bins;
    return tb;
}

// Estimates at random places in the film whose time interval [tA, tB] covers `span` bin widths
// (0: 0.4 of one bin, starting 0.3 into it), with slopes of either sign (the unwarped axis's
// eta c is negative for beams coming towards the camera).
std::vector<SplatCase> splatCases(const TimeBins& tb, int span, size_t n) {
    Rng rng(17, Stream::Test, static_cast<uint64_t>(tb.bins), static_cast<uint64_t>(span));
    std::vector<SplatCase> cases(n);
    const double widthT = (span == 0 ? 0.4 : span) * tb.binWidth;
    for (SplatCase& c : cases) {
        const int k = tb.bins > span ? static_cast<int>(rng.uniform() * (tb.bins - span)) : -(span - tb.bins) / 2;
        const double tA = tb.startOpl + (k + 0.3) * tb.binWidth;
        const double slope = 0.2 + 1.8 * rng.uniform();  // |eta (1 + c)|
        c.b = rng.uniform() < 0.5 ? slope : -slope;
        c.s0 = rng.uniform();
        c.s1 = c.s0 + widthT / slope;
        c.a = tA - c.b * (c.b > 0.0 ? c.s0 : c.s1);  // the early end of the interval at tA
    }
    return cases;
}

Color benchKappa(bool coloured) { return coloured ? Color(0.2, 0.5, 1.2) : Color(0.27); }

// Adds into per-bin sums as a PixelAccumulator would; counts the calls.
struct BinSums {
    std::vector<Color> bins;
    int64_t calls = 0;
    void operator()(int k, const Color& c) {
        bins[static_cast<size_t>(k)] += c;
        ++calls;
    }
};

void finish(benchmark::State& state, const BinSums& sums, size_t estimates, bool coloured) {
    const int64_t n = state.iterations() * static_cast<int64_t>(estimates);
    state.SetItemsProcessed(n);
    state.counters["bins_per_estimate"] = static_cast<double>(sums.calls) / static_cast<double>(n);
    state.SetLabel(coloured ? "coloured" : "grey");
}

void BM_SplatTimeProfile(benchmark::State& state) {
    const TimeBins tb = filmBins(static_cast<int>(state.range(0)));
    const bool coloured = state.range(2) != 0;
    const std::vector<SplatCase> cases = splatCases(tb, static_cast<int>(state.range(1)), 256);
    std::vector<SegmentProfile> profiles;
    profiles.reserve(cases.size());
    for (const SplatCase& c : cases) profiles.emplace_back(benchKappa(coloured), c.s0, c.s1);
    BinSums sums{std::vector<Color>(static_cast<size_t>(tb.bins), Color(0.0))};
    const Color energy(1.0, 0.8, 0.6);
    OutsideFilm outside;
    for (auto _ : state) {
        for (size_t i = 0; i < cases.size(); ++i) {
            const OutsideFilm o = splatTime(tb, energy, profiles[i], cases[i].a, cases[i].b, sums);
            outside.before += o.before;
            outside.after += o.after;
        }
        benchmark::DoNotOptimize(outside);
        benchmark::DoNotOptimize(sums.bins.data());
        benchmark::ClobberMemory();
    }
    finish(state, sums, cases.size(), coloured);
}

void BM_SplatTimeKappa(benchmark::State& state) {
    const TimeBins tb = filmBins(static_cast<int>(state.range(0)));
    const bool coloured = state.range(2) != 0;
    const std::vector<SplatCase> cases = splatCases(tb, static_cast<int>(state.range(1)), 256);
    const Color kappa = benchKappa(coloured);
    BinSums sums{std::vector<Color>(static_cast<size_t>(tb.bins), Color(0.0))};
    const Color energy(1.0, 0.8, 0.6);
    OutsideFilm outside;
    for (auto _ : state) {
        for (const SplatCase& c : cases) {
            const OutsideFilm o = splatTime(tb, energy, kappa, c.s0, c.s1, c.a, c.b, sums);
            outside.before += o.before;
            outside.after += o.after;
        }
        benchmark::DoNotOptimize(outside);
        benchmark::DoNotOptimize(sums.bins.data());
        benchmark::ClobberMemory();
    }
    finish(state, sums, cases.size(), coloured);
}

// {bins, span}: one bin's estimate in every film; many bins' in the films that have them.
void splatArgs(benchmark::internal::Benchmark* b) {
    b->ArgNames({"bins", "span", "coloured"});
    const std::pair<int64_t, int64_t> shapes[] = {{1, 0}, {256, 0}, {1024, 0}, {256, 16}, {1024, 16}};
    for (int64_t coloured : {0, 1})
        for (const auto& [bins, span] : shapes) b->Args({bins, span, coloured});
}
BENCHMARK(BM_SplatTimeProfile)->Apply(splatArgs);
BENCHMARK(BM_SplatTimeKappa)->Apply(splatArgs);

}  // namespace
}  // namespace tpb
