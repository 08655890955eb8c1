#include "render/time_range.h"

#include "base/parallel.h"
#include "integrators/photon_beams.h"
#include "render/driver.h"

#include <algorithm>

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
    // A relay wall timed from the wall subtracts the wall -> sensor leg from every time: what the
    // sensor sees in a medium before the wall arrives up to the longest leg (a corner) early.
    if (s.camera.relayWall && s.camera.timeFromWall) {
        const Camera& c = s.camera;
        double leg = 0.0;
        for (const Vec3& p :
             {c.wallCorner, c.wallCorner + c.wallU, c.wallCorner + c.wallV, c.wallCorner + c.wallU + c.wallV})
            leg = std::max(leg, glm::length(p - c.position));
        w.startOpl -= c.legIor * leg;
    }
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
    // Histogram over a window 4x wider than the heuristic one.
    const TimeBins wide{t0, 4.0 * (t1 - t0) / 4096.0, 4096};
    // A probe pass of the photon-beams integrator with these settings (the render's estimators
    // when the caller keeps them: prepareRender gives the defaults, so every estimator of a
    // comparison gets one time axis), on its own seed, over about 32 x 32 pixels spread over the image.
    // Generous kernels (a low-noise pilot), never wider than kPilotMaxRadiusFraction of the diagonal:
    // the render's own radius may be huge, and the pilot only needs the arrival times.
    const double diag = std::max(scene.bounds.diagonal(), 1e-6);
    ProbeRequest probe;
    probe.seed = settings.seed ^ 0x9E3779B97F4A7C15ull;
    probe.photons = pilotPhotons;
    probe.beamRadius = std::min(std::max(settings.beamRadius0, 0.01 * diag), kPilotMaxRadiusFraction * diag);
    probe.surfaceRadius = std::min(std::max(settings.surfaceRadius0, 0.02 * diag), kPilotMaxRadiusFraction * diag);
    PhotonBeamsIntegrator beams(scene, settings);
    const int W = scene.camera.width, H = scene.camera.height;
    const ProbeResult r = runProbe(beams, scene, probe, wide, std::max(1, W / 32), std::max(1, H / 32),
                                   resolveThreads(settings.threads), control.abort, control.progress);
    if (!r.ran) {
        fit.interrupted = r.aborted;
        return fit;
    }
    const std::vector<double>& hist = r.luminance;
    double total = 0.0;
    for (double v : hist) total += v;
    if (!(total > 0.0)) return fit;
    double cum = 0.0;
    int kLo = -1, kHi = wide.bins - 1;
    for (int k = 0; k < wide.bins; ++k) {
        cum += hist[k];
        if (kLo < 0 && cum > 5e-4 * total) kLo = k;
        if (cum >= 0.98 * total) {
            kHi = k;
            break;
        }
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
