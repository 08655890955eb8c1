// The default scene and one photon pass of it, as the benchmarks of the photon pass and of the
// accelerators use them: scenes/cornell_medium.json prepared as the CLI prepares it (loadScene +
// prepareRender, the pilot fitting the film's time range with 4000 photons, app/cli/common.cpp),
// and the photon pass the photon-beams integrator would run for pass 1 (integrators/photon_beams.cpp),
// storing beams, volume photons and surface photons so both beam2d and point3d have their input.
// Everything is built once per process, on first use (never at static initialisation, so a
// --benchmark_filter that skips these benchmarks costs nothing).
#pragma once
#include "photons/photon_tracer.h"
#include "base/memory.h"
#include "film/film_bytes.h"
#include "render/prepare.h"
#include "scene/scene_loader.h"

#include <string>

namespace tpb::bench {

inline const PreparedRender& defaultScene() {
    static const PreparedRender p = [] {
        PrepareOptions po;
        po.pilot.photons = 4000;  // as the CLI's pilot
        return prepareRender(loadScene(std::string(TPB_SOURCE_DIR) + "/scenes/cornell_medium.json"), {}, po);
    }();
    return p;
}

// The photon pass of pass `pass` with the scene's settings (photons per pass, depth, beam length,
// seed); `beams` / `points` choose what the volume estimator would need stored.
inline PhotonPassParams photonPassParams(const PreparedRender& p, bool beams, bool points, uint64_t pass = 1) {
    PhotonPassParams pt;
    pt.seed = p.settings.seed;
    pt.pass = pass;
    pt.photons = p.settings.photonsPerPass;
    pt.maxDepth = p.settings.maxDepth;
    pt.storeBeams = p.scene->stages.beams && beams;
    pt.storePoints = p.scene->stages.beams && points;
    pt.storeSurfacePhotons = p.scene->stages.surfacePhotons;
    pt.beamLength = p.settings.beamLength;
    pt.filmEndOpl = p.time.endOpl();
    pt.threads = 1;  // one thread: the benchmarks measure per-core throughput
    pt.maxMapBytes = maxFilmBytes();
    return pt;
}

// Pass 1's photon map with beams and points (single-threaded, deterministic).
inline const PhotonMap& defaultPhotonMap() {
    static const PhotonMap map = tracePhotons(*defaultScene().scene, photonPassParams(defaultScene(), true, true));
    return map;
}

}  // namespace tpb::bench
