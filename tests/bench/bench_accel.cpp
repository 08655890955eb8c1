// The accelerators and the estimators' gathers on the beams and volume photons of one photon pass
// of the default scene (pass 1 of scenes/cornell_medium.json, 4000 photons, bench_scene.h), with
// pass 1's kernel radius:
//   BM_BeamAccelBuild:      BeamAccel::build over the beams (accel/beam_accel.h), the accelerator
//                           kept across iterations as the estimators keep it (buffers reused);
//                           Args: backend (0 Embree, 1 brute force, 2 our BVH), threads (our BVH's
//                           build shares its per-piece loops). items/s = beams indexed.
//   BM_EstimatorPrepare:    VolumeEstimator::prepare (the accelerator build over its input);
//                           Arg: 0 beam2d (beams), 1 point3d (volume photons).
//   BM_BeamAccelCandidates: Embree candidates() for the first segment of camera rays (the camera
//                           ray up to its first surface), without a test (every piece whose padded
//                           box the ray crosses) and with the cylinder test (Arg 1, the test beam2d
//                           hands the traversal: rayBeamOverlap); Arg backend 0 Embree, 2 our BVH.
//                           ns_per_ray: per query ray.
//   BM_EstimatorGather:     VolumeEstimator::gather along those segments into a pixel accumulator
//                           over the film's time axis (the scene's 256 bins), the estimates'
//                           wall tests and time splats included; Arg: 0 beam2d, 1 point3d.
// Camera rays: a jittered 32 x 32 grid over the 256 x 256 image, fixed seed. Embree builds its BVH
// on its own thread pool (every core, whatever `threads` says), so the builds are timed in wall
// time (UseRealTime); the queries run on the calling thread.
#include "bench_scene.h"
#include "estimators/beam2d.h"
#include "estimators/estimator.h"

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

namespace tpb {
namespace {

// Arg backend: 0 Embree, 1 brute force, 2 our BVH (accel/piece_bvh.h).
AccelBackend backendOf(int64_t arg) {
    return arg == 0 ? AccelBackend::Embree : arg == 1 ? AccelBackend::BruteForce : AccelBackend::Bvh;
}

// The volume kernel's radius of pass 1 (the progressive schedule starts at the scene's radius).
double passOneRadius() { return bench::defaultScene().settings.beamRadius0; }

const std::vector<CameraSegment>& cameraSegments() {
    static const std::vector<CameraSegment> segs = [] {
        const Scene& scene = *bench::defaultScene().scene;
        Rng rng(18, Stream::Test, 0, 0);
        std::vector<CameraSegment> out;
        const int n = 32;
        const double cellX = static_cast<double>(scene.camera.width) / n,
                     cellY = static_cast<double>(scene.camera.height) / n;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                CameraSegment seg;
                seg.ray = scene.camera.generate((x + rng.uniform()) * cellX, (y + rng.uniform()) * cellY);
                const std::optional<SurfaceHit> hit = scene.geometry.intersect(seg.ray);
                seg.sMax = hit ? hit->t : kInf;
                seg.region = scene.cameraRegions.top();
                out.push_back(seg);
            }
        return out;
    }();
    return segs;
}

// Reports time per query ray in ns (a rate of rays / 1e9, inverted).
void perRay(benchmark::State& state, size_t rays) {
    const double n = static_cast<double>(state.iterations()) * static_cast<double>(rays);
    state.SetItemsProcessed(static_cast<int64_t>(n));
    state.counters["ns_per_ray"] =
        benchmark::Counter(n * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

const char* estimatorName(int64_t arg) { return arg == 0 ? "beam2d" : "point3d"; }

EstimatorPass estimatorPass() {
    EstimatorPass ep;
    const RenderSettings& s = bench::defaultScene().settings;
    ep.radius = passOneRadius();
    ep.profile = s.profile;
    ep.beamLength = s.beamLength;
    ep.accel = AccelBackend::Embree;
    ep.threads = 1;
    return ep;
}

void BM_BeamAccelBuild(benchmark::State& state) {
    const PhotonMap& map = bench::defaultPhotonMap();
    const AccelBackend kind = backendOf(state.range(0));
    const std::unique_ptr<BeamAccel> accel = BeamAccel::create(kind);
    for (auto _ : state) {
        accel->build(map.beams, passOneRadius(), static_cast<int>(state.range(1)));
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(map.beams.size()));
    state.counters["beams"] = static_cast<double>(map.beams.size());
    state.counters["pieces"] = static_cast<double>(accel->pieceCount());
    state.SetLabel(accel->name());
}
BENCHMARK(BM_BeamAccelBuild)
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Args({2, 2})
    ->ArgNames({"backend", "threads"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

void BM_EstimatorPrepare(benchmark::State& state) {
    const PreparedRender& p = bench::defaultScene();
    const PhotonMap& map = bench::defaultPhotonMap();
    const std::unique_ptr<VolumeEstimator> est = makeVolumeEstimator(estimatorName(state.range(0)));
    const EstimatorPass ep = estimatorPass();
    for (auto _ : state) {
        est->prepare(*p.scene, map, ep);
        benchmark::ClobberMemory();
    }
    const size_t items = est->needs().beams ? map.beams.size() : map.points.size();
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(items));
    state.counters["primitives"] = static_cast<double>(est->accelPrimitives());
    state.SetLabel(est->name());
}
BENCHMARK(BM_EstimatorPrepare)->Arg(0)->Arg(1)->ArgName("estimator")->Unit(benchmark::kMicrosecond)->UseRealTime();

// The 2D kernel's candidate test (what Beam2DEstimator::gather hands the traversal).
struct CylinderTest {
    const CameraSegment& seg;
    double radius;
    static bool accept(const void* context, double sbLo, double sbHi, const Vec3& origin, const Vec3& dir) {
        const auto& t = *static_cast<const CylinderTest*>(context);
        RayBeamOverlap o;
        return rayBeamOverlap(t.seg.ray.o, t.seg.ray.d, t.seg.sMax, origin, dir, sbLo, sbHi, t.radius, o);
    }
};

void BM_BeamAccelCandidates(benchmark::State& state) {
    const PhotonMap& map = bench::defaultPhotonMap();
    const std::vector<CameraSegment>& segs = cameraSegments();
    const bool withTest = state.range(0) != 0;
    const std::unique_ptr<BeamAccel> accel = BeamAccel::create(backendOf(state.range(1)));
    accel->build(map.beams, passOneRadius(), 1);
    std::vector<BeamPiece> pieces;
    int64_t found = 0;
    for (auto _ : state) {
        for (const CameraSegment& seg : segs) {
            pieces.clear();
            const CylinderTest test{seg, passOneRadius()};
            accel->candidates(seg.ray.o, seg.ray.d, seg.sMax, seg.region, pieces,
                              withTest ? CandidateTest{&CylinderTest::accept, &test} : CandidateTest{});
            benchmark::DoNotOptimize(pieces.data());
            found += static_cast<int64_t>(pieces.size());
        }
    }
    perRay(state, segs.size());
    state.counters["pieces_per_ray"] =
        static_cast<double>(found) / (static_cast<double>(state.iterations()) * static_cast<double>(segs.size()));
    state.SetLabel(std::string(withTest ? "cylinder test, " : "boxes only, ") + accel->name());
}
BENCHMARK(BM_BeamAccelCandidates)
    ->ArgsProduct({{0, 1}, {0, 2}})
    ->ArgNames({"test", "backend"})
    ->Unit(benchmark::kMicrosecond);

void BM_EstimatorGather(benchmark::State& state) {
    const PreparedRender& p = bench::defaultScene();
    const PhotonMap& map = bench::defaultPhotonMap();
    const std::vector<CameraSegment>& segs = cameraSegments();
    const std::unique_ptr<VolumeEstimator> est = makeVolumeEstimator(estimatorName(state.range(0)));
    est->prepare(*p.scene, map, estimatorPass());
    PixelAccumulator acc(p.time.bins);
    FilmTally tally;
    PixelSink sink{p.time, acc, tally};
    EstimatorScratch scratch;
    const PathState path;
    int64_t estimates = 0;
    for (auto _ : state) {
        for (const CameraSegment& seg : segs) {
            estimates += est->gather(seg, path, sink, scratch);
            benchmark::DoNotOptimize(acc.steady());
            acc.clearTouched();
        }
    }
    perRay(state, segs.size());
    state.counters["estimates_per_ray"] =
        static_cast<double>(estimates) / (static_cast<double>(state.iterations()) * static_cast<double>(segs.size()));
    state.SetLabel(est->name());
}
BENCHMARK(BM_EstimatorGather)->Arg(0)->Arg(1)->ArgName("estimator")->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace tpb
