// An integrator: one progressive pass of some estimator of the transient film, as the Driver runs
// it (render/driver.h). Every method — photon beams (the paper), the path tracer (the unbiased
// reference), the geometry preview — is one, so the CLI's render/reference/converge commands, the
// automatic-range pilot and the viewer run any of them the same way, with the same threads, tiles,
// pause/resume/abort, history and film snapshots.
//
// A pass has three steps, called by the Driver in this order:
//   beginPass(ctx)        once, may use every thread (photon beams trace photons and build their
//                         accelerators here; the path tracer does nothing);
//   renderTile(ctx, ...)  for every tile of the film, concurrently, each tile by one thread: the
//                         integrator adds its pixels' estimates for this pass to the TileWriter;
//   endPass(ctx, stats)   once: the pass's counters (PassStats), summed in tile order so that they,
//                         like the film, do not depend on the number of threads.
// Pass i depends only on (settings.seed, i): passes can run in any order, be skipped (another
// machine renders them) or be repeated, and two films of disjoint passes merge into the film of all.
//
// Writing a new integrator: implement the three calls, give it a Method (render_settings.h) and a
// case in makeIntegrator() (integrators/integrator.cpp), and add it to the parameterised test
// tests/integrators/test_integrators.cpp that runs every integrator on the analytic scenes.
#pragma once
#include "film/transient_film.h"
#include "integrators/camera_pass.h"
#include "integrators/path_tracer.h"
#include "integrators/render_settings.h"
#include "estimators/estimator.h"
#include "photons/photon_tracer.h"
#include "scene/scene.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

namespace tpb {

struct PassContext {
    uint64_t pass = 1;                         // 1-based; keys every random number of the pass
    const TimeBins* time = nullptr;            // the film's time axis
    const PhasorSpec* phasor = nullptr;        // the film's phasor frequencies (film/phasor.h), or none
    int threads = 1;                           // worker threads of the Driver (thread ids 0..threads-1)
    int tiles = 0;                             // tiles of the film (tile ids 0..tiles-1)
    const std::atomic<bool>* abort = nullptr;  // set: stop as soon as possible (the pass is dropped)
};

// What a pass did: the Driver's history, the CLI's summaries and the viewer's stats panel.
struct PassStats {
    uint64_t pass = 0;  // 1-based
    // Photon beams: kernel radii of this pass, photons traced and what they stored (points: photons
    // at scattering events, for the point estimators); beamPieces: what the volume estimator indexed
    // (beam pieces, or points).
    double beamRadius = 0.0, surfaceRadius = 0.0;
    // and half-widths of their time kernels (m of OPL; 0 = off: film/time_kernel.h).
    double volumeTimeHalfWidth = 0.0, surfaceTimeHalfWidth = 0.0;
    int64_t photons = 0, beams = 0, beamPieces = 0, surfacePhotons = 0, points = 0;
    // Flux the photons started with, and the part still carried at the end of long beams cut in an
    // unbounded medium (missing from the steady image only: see photon_tracer.cpp, openBeamLength).
    Color emittedFlux{0.0}, cutFlux{0.0};
    int64_t regionOverflows = 0;  // photons ended by a full region stack (camera paths: camera.regionOverflows)
    CameraPassStats camera;       // photon beams' camera pass: rays, estimates, film tallies
    PathTracerStats paths;        // path tracer: paths, connections, film tallies
    FilmTally film;               // what the pass added to the film's counters (rejected, outside, inside)
    // Wall-clock seconds of its steps (photon tracing, accelerator build, camera pass).
    double photonSec = 0.0, buildSec = 0.0, cameraSec = 0.0, passSec = 0.0;
    double elapsedSec = 0.0;  // since the Driver's start()
    uint64_t peakRssBytes = 0;
};

// A probe pass measures the scene before the render: the pilots of render/time_range.h (the film's
// time range, from the arrival times) and render/auto_radius.h (the kernel radius, from the photon
// density). It is not one of the render's passes (pass 0, keyed by its own seed), writes no film and
// scales no power. The Driver's runProbe (render/driver.h) runs it like a pass.
struct ProbeRequest {
    uint64_t seed = 1;
    int64_t photons = 0;
    // What the photon map stores: the volume estimator's needs unless set; surface photons when the
    // scene has a diffuse surface, unless `surfacePhotons` is false.
    std::optional<VolumeEstimator::Needs> store;
    bool surfacePhotons = true;
    uint64_t maxMapBytes = 0;                      // bytes of photon map; 0 = the settings' limit
    bool photonsOnly = false;                      // the photon pass alone (probeMap()), no camera probe
    double beamRadius = 0.0, surfaceRadius = 0.0;  // m, the kernels the camera probe gathers with
};

class Integrator {
public:
    virtual ~Integrator() = default;
    virtual Method method() const = 0;
    // False when ctx.abort stopped it (the Driver then drops the pass).
    virtual bool beginPass(const PassContext& ctx, PassStats& stats) = 0;
    // Adds this pass's estimate of every pixel of `rect` (tile `tile`) to `writer`. Called by thread
    // `thread` only for that tile; different tiles run concurrently.
    virtual void renderTile(const PassContext& ctx, int tile, const TileRect& rect, TransientFilm::TileWriter& writer,
                            int thread) = 0;
    virtual void endPass(const PassContext& ctx, PassStats& stats) = 0;
    // A probe pass (ProbeRequest) with ctx.pass 0: false when the method has none, or ctx.abort
    // stopped it. Then probePixel for the pixels the caller chooses, from any threads (each thread
    // `thread` its own pixels at a time).
    virtual bool beginProbe(const PassContext& /*ctx*/, const ProbeRequest& /*request*/) { return false; }
    // The probe's estimate of pixel (x, y) on ctx.time's bins, in thread `thread`'s accumulator
    // (valid until that thread's next call).
    virtual const PixelAccumulator* probePixel(const PassContext& /*ctx*/, int /*x*/, int /*y*/, int /*thread*/) {
        return nullptr;
    }
    // The photon map of the probe (photon beams), else null.
    virtual const PhotonMap* probeMap() const { return nullptr; }
    // Passes that improve the estimate: 0 = unlimited (progressive), 1 = the first pass is the answer
    // (the preview).
    virtual int64_t usefulPasses() const { return 0; }
};

// The integrator of settings.method for this scene.
std::unique_ptr<Integrator> makeIntegrator(const Scene& scene, const RenderSettings& settings);

}  // namespace tpb
