#include "render/auto_radius.h"

#include "base/error.h"
#include "estimators/estimator.h"
#include "base/parallel.h"
#include "integrators/photon_beams.h"
#include "render/driver.h"
#include "photons/photon_tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace tpb {

namespace {

double boxVolume(const Bounds3& b) {
    if (!b.valid()) return 0.0;
    const Vec3 e = b.hi - b.lo;
    return e.x * e.y * e.z;
}

double boxArea(const Bounds3& b) {
    if (!b.valid()) return 0.0;
    const Vec3 e = b.hi - b.lo;
    return 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
}

// The part [t0, t1] of the segment o + t d, t in [0, len], inside box b (slabs); false if none.
bool clipToBox(const Vec3& o, const Vec3& d, double len, const Bounds3& b, double& t0, double& t1) {
    t0 = 0.0;
    t1 = len;
    for (int k = 0; k < 3; ++k) {
        if (std::abs(d[k]) < 1e-300) {
            if (o[k] < b.lo[k] || o[k] > b.hi[k]) return false;
            continue;
        }
        double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
    }
    return t1 > t0;
}

}  // namespace

double RadiusPilot::gathered(double r) const {
    if (!(boxArea > 0.0)) return 0.0;
    if (pointKernel) return 4.0 * kPi * r * r * static_cast<double>(points) * scale / boxArea;
    return 2.0 * kPi * r * beamLength / boxArea;
}

RadiusPilot pilotRadius(const Scene& scene, const RenderSettings& settings, const std::atomic<bool>* abort) {
    RadiusPilot out;
    const std::unique_ptr<VolumeEstimator> est = makeVolumeEstimator(settings.volumeEstimator);
    out.pointKernel = est && est->needs().points && !est->needs().beams;
    out.target = out.pointKernel ? kAutoPointsPerRay : kAutoBeamsPerRay;
    if (!scene.stages.beams) {
        out.why = "no scattering medium: the volume radius is not used";
        return out;
    }
    // A probe pass of the photon-beams integrator (pass 0, not one of the render's 1, 2, ...; the
    // render's seed): its photon pass alone, storing beams and points, no surface photons.
    ProbeRequest probe;
    probe.seed = settings.seed;
    probe.photons = std::min<int64_t>(settings.photonsPerPass, kAutoPilotPhotons);
    probe.store = VolumeEstimator::Needs{true, true};
    probe.surfacePhotons = false;
    probe.photonsOnly = true;
    // At most 64 MiB (~30x a typical 4000-photon map): a medium where photons never die (albedo 1,
    // a huge max_depth) is reported as unmeasured within a second instead of filling the budget.
    probe.maxMapBytes = kAutoPilotMaxMapBytes;
    out.scale = static_cast<double>(settings.photonsPerPass) / static_cast<double>(std::max<int64_t>(probe.photons, 1));
    PhotonBeamsIntegrator beams(scene, settings);
    ProbeResult ran;
    try {
        ran = runProbe(beams, scene, probe, TimeBins{}, 1, 1, resolveThreads(settings.threads), abort);
    } catch (const UserError&) {  // the photon map over the memory budget: the render will say so
        out.why = "the pilot's photon map outgrew the memory budget";
        return out;
    }
    if (!ran.ran) {  // Ctrl-C during the pilot: the caller stops (nothing measured)
        out.why = "the pilot was interrupted";
        return out;
    }
    const PhotonMap& map = *beams.probeMap();
    out.photons = map.emitted;

    // The scattering region holding most of the beam length.
    std::vector<double> length(scene.regions.size(), 0.0);
    for (const Beam& b : map.beams)
        if (b.region >= 0 && static_cast<size_t>(b.region) < length.size() && std::isfinite(b.length))
            length[static_cast<size_t>(b.region)] += b.length;
    for (size_t r = 0; r < length.size(); ++r)
        if (length[r] > 0.0 && (out.region < 0 || length[r] > length[static_cast<size_t>(out.region)]))
            out.region = static_cast<int>(r);
    if (out.region < 0) {
        out.why = "the pilot's photons stored no beam in a scattering medium";
        return out;
    }
    // Only what lies within the scene's bounds (geometry, lights, camera): photons that escape an
    // open scene into an unbounded medium fly on far from anything the camera sees.
    // A scene with no geometry (a light in an unbounded medium) has flat bounds: each side of the
    // clip box is at least a quarter of the diagonal.
    Bounds3 clip = scene.bounds;
    const double minSide = 0.25 * std::max(scene.bounds.diagonal(), 1e-6);
    for (int k = 0; k < 3; ++k) {
        const double grow = 0.5 * std::max(0.0, minSide - (clip.hi[k] - clip.lo[k]));
        clip.lo[k] -= grow;
        clip.hi[k] += grow;
    }
    Bounds3 box;
    for (const Beam& b : map.beams) {
        double t0 = 0.0, t1 = 0.0;
        if (b.region != out.region || !std::isfinite(b.length) || !clipToBox(b.origin, b.dir, b.length, clip, t0, t1))
            continue;
        ++out.beams;
        out.beamLength += (t1 - t0) * out.scale;
        box.expand(b.origin + t0 * b.dir);
        box.expand(b.origin + t1 * b.dir);
    }
    const auto inside = [&](const Vec3& x) {
        return x.x >= clip.lo.x && x.y >= clip.lo.y && x.z >= clip.lo.z && x.x <= clip.hi.x && x.y <= clip.hi.y &&
               x.z <= clip.hi.z;
    };
    for (const VolumePhoton& p : map.points)
        if (p.region == out.region && inside(p.position)) ++out.points;
    out.boxVolume = boxVolume(box);
    out.boxArea = boxArea(box);
    if (!(out.boxVolume > 0.0) || !(out.boxArea > 0.0) || (out.pointKernel && out.points == 0)) {
        out.why = "the pilot's beams span no volume (all in a plane or a line)";
        return out;
    }
    out.meanChord = 4.0 * out.boxVolume / out.boxArea;
    out.radius = out.pointKernel
                     ? std::sqrt(out.target * out.boxArea / (4.0 * kPi * static_cast<double>(out.points) * out.scale))
                     : out.target * out.boxArea / (2.0 * kPi * out.beamLength);
    out.measured = std::isfinite(out.radius) && out.radius > 0.0;
    char buf[256];
    std::snprintf(
        buf, sizeof buf, "%lld %s in region %d over a %.3g m^3 box (mean chord %.3g m): %.3g m gathers ~%.0f per ray",
        static_cast<long long>(out.pointKernel ? out.points : out.beams), out.pointKernel ? "photon points" : "beams",
        out.region, out.boxVolume, out.meanChord, out.radius, out.target);
    out.why = buf;
    return out;
}

}  // namespace tpb
