#include "render/time_range.h"

#include "base/memory.h"
#include "film/film_bytes.h"

#include "accel/beam_accel.h"
#include "integrators/camera_pass.h"
#include "integrators/photon_beams.h"
#include "base/parallel.h"
#include "accel/photon_grid.h"
#include "photons/photon_tracer.h"

#include <mutex>

namespace tpb {

OplRange autoTimeRange(const Scene& s) {
    double emit = kInf;
    for (const Light& l : s.lights) emit = std::min(emit, l.emitOpl);
    if (!std::isfinite(emit)) emit = 0.0;
    double maxIor = 1.0;
    for (const Region& r : s.regions) maxIor = std::max(maxIor, r.ior);
    const Bounds3 g = s.geometry.bounds();
    double diag = g.valid() ? g.diagonal() : s.bounds.diagonal();
    if (!(diag > 0.0)) diag = 1.0;
    // Lights to the scene and back to the camera, with a few bounces: a generous window.
    const double camDist = g.valid() ? glm::length(s.camera.position - g.center()) : 0.0;
    OplRange w;
    w.startOpl = emit;
    w.endOpl = emit + maxIor * (2.5 * diag) + camDist;
    return w;
}

TimeRangeFit measureArrivalRange(const Scene& scene, const RenderSettings& settings, int64_t pilotPhotons,
                                 const PilotControl& control) {
    TimeRangeFit fit;
    const OplRange window = autoTimeRange(scene);
    const double t0 = window.startOpl, t1 = window.endOpl;
    fit.heuristicStart = t0;
    fit.heuristicEnd = t1;
    fit.startOpl = t0;
    fit.endOpl = t1;
    const auto aborted = [&] { return control.abort && control.abort->load(); };
    const auto progress = [&](double f) {
        if (control.progress) control.progress(f);
    };
    // Rough shares of the pilot's time, for the progress report: photons, then camera rows.
    constexpr double kPhotonShare = 0.2;

    // Histogram over a window 4x wider than the heuristic one.
    TimeBins wide{t0, 4.0 * (t1 - t0) / 4096.0, 4096};
    const int threads = resolveThreads(settings.threads);
    // A probe pass of the beam2d estimator (beams, no points), its own seed, pass 0, no power
    // scaling and no film yet.
    PhotonPassParams pt = photonPassFor(scene, settings, makeVolumeEstimator("beam2d")->needs(), 0, threads);
    pt.seed = settings.seed ^ 0x9E3779B97F4A7C15ull;
    pt.photons = pilotPhotons;
    pt.powerPhotons = 0;
    progress(0.0);
    const PhotonMap map = tracePhotons(scene, pt, control.abort);
    if (aborted()) {
        fit.interrupted = true;
        return fit;
    }
    progress(kPhotonShare);
    const double diag = std::max(scene.bounds.diagonal(), 1e-6);
    CameraPassParams cs;
    cs.seed = pt.seed;
    cs.pass = 0;
    // Generous kernels (a low-noise pilot), never wider than kPilotMaxRadiusFraction of the diagonal:
    // the render's own radius may be huge, and the pilot only needs the arrival times.
    const double beamRadius = std::min(std::max(settings.beamRadius0, 0.01 * diag), kPilotMaxRadiusFraction * diag);
    const double surfaceRadius = std::min(std::max(settings.surfaceRadius0, 0.02 * diag), kPilotMaxRadiusFraction * diag);
    cs.maxDepth = settings.maxDepth;
    EstimatorPass ep;
    ep.threads = threads;
    std::unique_ptr<VolumeEstimator> volume = makeVolumeEstimator("beam2d");
    std::unique_ptr<SurfaceEstimator> surface = makeSurfaceEstimator("ppm");
    CameraPassEstimators est;
    if (scene.stages.beams && !map.beams.empty()) {
        ep.radius = beamRadius;
        volume->prepare(scene, map, ep);
        est.volume = volume.get();
    }
    if (scene.stages.surfacePhotons && !map.photons.empty()) {
        ep.radius = surfaceRadius;
        surface->prepare(scene, map, ep);
        est.surface = surface.get();
    }
    if (aborted()) {
        fit.interrupted = true;
        return fit;
    }
    // Every 8th pixel in each direction (at least an 8x8 grid).
    const int W = scene.camera.width, H = scene.camera.height;
    const int sx = std::max(1, W / 32), sy = std::max(1, H / 32);
    const int rows = (H + sy - 1) / sy;
    std::vector<double> hist(wide.bins, 0.0);
    std::mutex m;
    std::atomic<int> rowsDone{0};
    parallelFor(rows, threads, [&](int64_t r, int worker) {
        CameraPassScratch scratch;
        scratch.acc.reset(wide.bins);
        CameraPassStats stats;
        std::vector<double> local(wide.bins, 0.0);
        const int y = static_cast<int>(r) * sy;
        for (int x = 0; x < W; x += sx) {
            if (aborted()) return;  // (a row of a huge film is long too)
            renderPixel(scene, est, cs, wide, x, y, scratch, stats);
            for (TimeAxis a : {TimeAxis::Real, TimeAxis::Unwarped})
                for (int k = scratch.acc.lo(a); k <= scratch.acc.hi(a); ++k) {
                    const double* v = scratch.acc.bin(a, k);
                    local[k] += std::max(0.0, luminance(Color(v[0], v[1], v[2])));
                }
            scratch.acc.clearTouched();
        }
        {
            std::lock_guard<std::mutex> g(m);
            for (int k = 0; k < wide.bins; ++k) hist[k] += local[k];
        }
        const int done = rowsDone.fetch_add(1) + 1;
        if (worker == 0) progress(kPhotonShare + (1.0 - kPhotonShare) * done / rows);
    }, control.abort);
    if (aborted()) {
        fit.interrupted = true;
        return fit;
    }
    progress(1.0);
    double total = 0.0;
    for (double v : hist) total += v;
    if (!(total > 0.0)) return fit;
    double cum = 0.0;
    int kLo = -1, kHi = wide.bins - 1;
    for (int k = 0; k < wide.bins; ++k) {
        cum += hist[k];
        if (kLo < 0 && cum > 5e-4 * total) kLo = k;
        if (cum >= 0.98 * total) { kHi = k; break; }
    }
    kLo = std::max(kLo, 0);
    const double lo = wide.startOpl + kLo * wide.binWidth, hi = wide.startOpl + (kHi + 1) * wide.binWidth;
    const double pad = 0.05 * (hi - lo);
    fit.startOpl = std::max(t0, lo - pad);
    fit.endOpl = hi + pad;
    fit.fromPilot = true;
    return fit;
}

FilmTimeAxis filmTimeAxis(const Scene& scene, const FilmDesc& film, const RenderSettings& pilotSettings,
                          const PilotOptions& pilot) {
    FilmTimeAxis axis;
    const OplRange window = autoTimeRange(scene);
    axis.fit.startOpl = axis.fit.heuristicStart = window.startOpl;
    axis.fit.endOpl = axis.fit.heuristicEnd = window.endOpl;
    axis.time.bins = film.bins;
    if (!film.autoRange) {
        axis.time.startOpl = film.startOpl;
        axis.time.binWidth = film.binWidthOpl;
        return axis;
    }
    axis.time.startOpl = window.startOpl;
    axis.time.binWidth = (window.endOpl - window.startOpl) / film.bins;
    if (!pilot.run) return axis;
    axis.fit = measureArrivalRange(scene, pilotSettings, pilot.photons, pilot.control);
    if (axis.fit.fromPilot) {
        axis.time.startOpl = axis.fit.startOpl;
        axis.time.binWidth = (axis.fit.endOpl - axis.fit.startOpl) / film.bins;
    }
    return axis;
}

}  // namespace tpb
