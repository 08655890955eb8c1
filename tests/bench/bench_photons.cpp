// Photon tracing (PhotonTracer, photons/photon_tracer.h) on the default scene
// (scenes/cornell_medium.json as the CLI loads it, bench_scene.h): one photon pass with the scene's
// photons per pass, pass 1, one thread, the tracer kept across iterations as the renderer keeps it. Arg: what the pass stores besides the surface photons,
//   0: beams (beam1d / beam2d, the default estimator),
//   1: volume photons (point2d / point3d, the scene's estimator),
//   2: both.
// The photon paths are the same in all three (storing draws no random number). items/s = photons
// emitted per second; the counters are what one pass stores.
#include "bench_scene.h"

#include <benchmark/benchmark.h>

namespace tpb {
namespace {

void BM_TracePhotons(benchmark::State& state) {
    const PreparedRender& p = bench::defaultScene();
    const int mode = static_cast<int>(state.range(0));
    const PhotonPassParams pt = bench::photonPassParams(p, mode != 1, mode != 0);
    PhotonMap map;
    PhotonTracer tracer;
    int64_t emitted = 0;
    for (auto _ : state) {
        map = tracer.trace(*p.scene, pt);
        emitted += map.emitted;
        benchmark::DoNotOptimize(map.beams.data());
        benchmark::DoNotOptimize(map.points.data());
        benchmark::DoNotOptimize(map.photons.data());
    }
    state.SetItemsProcessed(emitted);
    state.counters["beams"] = static_cast<double>(map.beams.size());
    state.counters["points"] = static_cast<double>(map.points.size());
    state.counters["surface_photons"] = static_cast<double>(map.photons.size());
    static const char* const kLabels[] = {"beams", "points", "beams+points"};
    state.SetLabel(kLabels[mode]);
}
BENCHMARK(BM_TracePhotons)->Arg(0)->Arg(1)->Arg(2)->ArgName("store")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tpb
