// Photon pass: traces photons from the lights and stores every path segment inside a scattering
// medium as a photon beam (paper Sec. 4, Fig. 2a) and every landing on a diffuse surface as a
// surface photon, each with its start time as optical path length (eq. 11: t_b0 = sum eta_j s_j).
//
// Beams are "short" by default: a beam ends at the next scattering event or surface, and its
// energy along s_b is Phi * T(s_b) / P(survive to s_b); with free-flight sampling at the average
// extinction sigma_bar this leaves exp(-(sigma_t - sigma_bar) s_b) inside the kernel (tau_b, see
// beam2d.h), which is 1 for grey media. "Long" beams extend to the surface and keep the full
// transmittance exp(-sigma_t s_b) (the form of the paper's eq. 8); the photon still scatters at the
// sampled distance.
//
// Volume photons ("points", PhotonPassParams::storePoints, for point estimators such as point2d /
// point3d): one at every scattering event the free flight samples inside a scattering medium, at
// the end of the segment whose beam has the same depth. Its weight makes the points estimate what
// the beams estimate. A segment entered with flux Phi (per channel, W) stands for the photon flux
// along it, Phi T(s) delta(x - x(s)) ds integrated over s in [0, d_surf) (T(s) = exp(-sigma_t s)):
// the beam's integrand. The event is sampled with pdf p(s) = sigma_bar exp(-sigma_bar s) =
// sigma_bar Tbar(s) for s < d_surf (transport/free_flight.h), so the one-sample estimator of that
// integral is
//   E[ Phi T(s) / p(s) delta(x - x(s)) 1(s < d_surf) ] = Int_0^{d_surf} Phi T(s) delta(x - x(s)) ds,
// i.e. the point carries
//   power = Phi T(s) / (sigma_bar Tbar(s)) = Phi exp(-(sigma_t - sigma_bar) s) / sigma_bar   (W m),
// the short beam's power at its end divided by sigma_bar (Phi / sigma_bar in a grey medium). It is
// the scattering photon's weight before the albedo: the point estimators multiply by sigma_s (as
// the beam estimators do), so a point's contribution has the units of a beam's times a length, which
// the point kernels' extra 1/m (1/(pi r^2) across the ray instead of along a beam's length, or
// 1/(4/3 pi r^3) integrated along the ray) take away. Storing points draws no random number: the
// photon paths, hence the beams and surface photons, are the same with or without them.
#pragma once
#include "base/memory.h"
#include "base/math.h"
#include "scene/scene.h"
#include "transport/interaction.h"

#include <atomic>
#include <climits>
#include <cstdint>
#include <vector>

namespace tpb {

struct Beam {
    Vec3 origin;
    Vec3 dir;        // unit, propagation direction
    double length;   // m
    Color power;     // flux at the beam origin (W), already divided by the photon count
    double opl0;     // OPL at the origin (m), emission time included
    int region;      // region whose medium the beam lives in
    uint32_t depth;  // number of scattering/reflection events before this segment
    // The photon's vertex before the origin and its OPL: the causal floor's start (estimators/
    // estimator.h, causalFloor). The origin itself for a beam leaving a light or refracted into a
    // medium of higher index. fromOpl -inf: unknown (a beam built by hand), no floor on the real axis.
    Vec3 from{0.0};
    double fromOpl = -kInf;
};

// A photon at a scattering event inside a scattering medium (see the header: weight and depth).
struct VolumePhoton {
    Vec3 position;        // m, the scattering point x(s)
    Vec3 dirIn;           // unit, propagation direction of the segment that ends here (before scattering)
    Color power;          // W m: Phi T(s) / (sigma_bar Tbar(s)), already divided by the photon count
    double opl;           // OPL at the scattering point (m), emission time included
    int region;           // region whose medium it scatters in
    uint32_t depth;       // that of the segment (beam) it ends: scattering/reflection events before it
    double length = 0.0;  // m, from the segment's start (the event before, OPL opl - ior length) to here
};

struct SurfacePhoton {
    Vec3 position;
    Vec3 dirIn;   // propagation direction when landing
    Vec3 normal;  // geometric normal, facing the side the photon came from
    Color power;  // W, divided by the photon count
    double opl;   // OPL at landing (m)
    // m, from the segment's start (the event before: the causal floor's start) to here, and the
    // index of the region it crossed. length 0: unknown (a photon built by hand), no floor.
    double length = 0.0;
    double ior = 1.0;
};

struct PhotonMap {
    std::vector<Beam> beams;
    std::vector<SurfacePhoton> photons;
    std::vector<VolumePhoton> points;  // only when PhotonPassParams::storePoints
    int64_t emitted = 0;
    int64_t rejected = 0;         // non-finite photon weights discarded
    Color emittedFlux{0.0};       // W: the flux the pass's photons started with (estimates the lights' power)
    Color cutFlux{0.0};           // W: flux still carried at the end of long beams cut in an unbounded medium
    int64_t regionOverflows = 0;  // photons ended because their region stack was full (RegionStack)
    bool aborted = false;         // the abort flag stopped the pass: the map is partial, discard it
    // Empty, keeping the arrays' capacity (PhotonTracer reuses its batches' maps).
    void clear() {
        beams.clear();
        photons.clear();
        points.clear();
        emitted = rejected = regionOverflows = 0;
        aborted = false;
        emittedFlux = cutFlux = Color(0.0);
    }
};

// The arguments of one photon pass (not a settings copy: the photon-beams integrator fills them
// from RenderSettings and the pass index, integrators/photon_beams.cpp).
struct PhotonPassParams {
    uint64_t seed = 1;
    uint64_t pass = 0;
    int64_t photons = 1000;
    // The count the photons' power is divided by (0: `photons`). A warm-up pass traces fewer
    // photons with a full pass's power each (render_settings.h, passWeight): its estimate is
    // photons / powerPhotons of a full pass's.
    int64_t powerPhotons = 0;
    int maxDepth = 16;
    // Events from which Russian roulette also ends full-weight photons (russianRoulette,
    // transport/interaction.h): what bounds a pass whose photons never lose weight. Tests lower it
    // to compare the deep rule with none (INT_MAX turns it off).
    int rouletteDepth = kDeepRouletteDepth;
    bool storeBeams = true;
    bool storeSurfacePhotons = true;
    bool storePoints = false;  // volume photons at scattering events (the point estimators)
    BeamLength beamLength = BeamLength::Short;
    // OPL of the film's end (m): long beams in an unbounded medium reach at least that far, so the
    // frames lose nothing to their cut (photon_tracer.cpp, openBeamLength). 0 = no film yet.
    double filmEndOpl = 0.0;
    int threads = 1;
    // A scan's laser point (scene/camera.h laserTarget): light `aimLight` (a laser) is aimed at
    // `aimTarget` instead of its own direction, and the photons' random numbers are keyed by
    // `laserPoint` too, so every laser point of a pass has its own photons. -1: no aim.
    // The bounce filter (RenderSettings::bounceMin/bounceMax): only photons whose light path has
    // minEvents..maxEvents events where a camera path gathers them are stored (a beam or point of
    // depth d: d + 1, the camera's scattering point included; a surface photon landing after d
    // events: d + 1, its landing included). The photons themselves go on: same paths either way.
    int minEvents = 0, maxEvents = INT_MAX;
    bool keeps(uint32_t depth) const {
        const int64_t n = static_cast<int64_t>(depth) + 1;
        return n >= minEvents && n <= maxEvents;
    }
    int aimLight = -1;
    Vec3 aimTarget{0.0};
    double aimEmitOpl =
        0.0;  // the aimed laser's pulse instant (OPL, m): a wall time origin starts its clock at the wall
    int64_t laserPoint = 0;
    // Memory guard: a pass whose beams, surface photons and points would take more than this throws
    // UserError (key render.photons_per_pass) instead of exhausting memory, e.g. an albedo-1
    // medium with a huge max_depth. 0 = no limit.
    uint64_t maxMapBytes = 0;
};

// Traces passes of photons in fixed batches (the map's order does not depend on the number of
// threads), keeping the batches' buffers from one pass to the next: a renderer's passes trace the
// same count, and growing fresh buffers every pass was ~3 % of a small point3d pass (issue 15).
// `abort` is read before every photon and every 4096 events of one photon: a pass stops within
// milliseconds of Ctrl-C (PhotonMap::aborted), however long its photons are.
class PhotonTracer {
public:
    PhotonMap trace(const Scene& scene, const PhotonPassParams& s, const std::atomic<bool>* abort = nullptr);

private:
    std::vector<PhotonMap> parts_;
};

// One pass with buffers of its own (PhotonTracer::trace).
PhotonMap tracePhotons(const Scene& scene, const PhotonPassParams& s, const std::atomic<bool>* abort = nullptr);

// Bytes the map's beams, surface photons and points take (what maxMapBytes limits).
uint64_t storedMapBytes(const PhotonMap& m);
// Rough memory of one pass's photon map before it is traced (~4 beam segments per photon, as
// `tpb info` prints): what validate() checks against the limit (base/memory.h).
inline uint64_t photonMapBytes(int64_t photonsPerPass) {
    return saturatingMul(static_cast<uint64_t>(std::max<int64_t>(photonsPerPass, 0)), 4 * (sizeof(double) * 12 + 16));
}

// Traces photon `index` of the pass (deterministic given seed, pass, index). Appends to `out`.
// Throws UserError if this photon alone stores more than s.maxMapBytes. Returns false, the photon
// cut short, when `abort` is set.
bool tracePhoton(const Scene& scene, const PhotonPassParams& s, int64_t index, PhotonMap& out,
                 const std::atomic<bool>* abort = nullptr);

}  // namespace tpb
