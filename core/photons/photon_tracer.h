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
#pragma once
#include "base/math.h"
#include "scene/scene.h"

#include <atomic>
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
};

struct SurfacePhoton {
    Vec3 position;
    Vec3 dirIn;   // propagation direction when landing
    Vec3 normal;  // geometric normal, facing the side the photon came from
    Color power;  // W, divided by the photon count
    double opl;   // OPL at landing (m)
};

struct PhotonMap {
    std::vector<Beam> beams;
    std::vector<SurfacePhoton> photons;
    int64_t emitted = 0;
    int64_t rejected = 0;      // non-finite photon weights discarded
    Color emittedFlux{0.0};    // W: the flux the pass's photons started with (estimates the lights' power)
    Color cutFlux{0.0};        // W: flux still carried at the end of long beams cut in an unbounded medium
    int64_t regionOverflows = 0;   // photons ended because their region stack was full (RegionStack)
};

// The arguments of one photon pass (not a settings copy: the photon-beams integrator fills them
// from RenderSettings and the pass index, integrators/photon_beams.cpp).
struct PhotonPassParams {
    uint64_t seed = 1;
    uint64_t pass = 0;
    int64_t photons = 1000;
    int maxDepth = 16;
    bool storeBeams = true;
    bool storeSurfacePhotons = true;
    BeamLength beamLength = BeamLength::Short;
    // OPL of the film's end (m): long beams in an unbounded medium reach at least that far, so the
    // frames lose nothing to their cut (photon_tracer.cpp, openBeamLength). 0 = no film yet.
    double filmEndOpl = 0.0;
    int threads = 1;
    // Memory guard: a pass whose beams and surface photons would take more than this throws
    // UserError (key render.photons_per_pass) instead of exhausting memory, e.g. an albedo-1
    // medium with a huge max_depth. 0 = no limit.
    uint64_t maxMapBytes = 0;
};

PhotonMap tracePhotons(const Scene& scene, const PhotonPassParams& s,
                       const std::atomic<bool>* abort = nullptr);

// Traces photon `index` of the pass (deterministic given seed, pass, index). Appends to `out`.
// Throws UserError if this photon alone stores more than s.maxMapBytes.
void tracePhoton(const Scene& scene, const PhotonPassParams& s, int64_t index, PhotonMap& out);

}  // namespace tpb
