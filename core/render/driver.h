// The progressive driver: pass i = trace photons (seeded by (pass, photon)), build the beam BVH
// and the surface-photon grid, camera pass over tiles (seeded by (pass, pixel)), shrink the radii.
// Passes are independent given their index, so results do not depend on the number of threads.
//
// Asynchronous API for the viewer and the CLI: start() runs passes on a background thread until
// the pass count or time budget is reached or stop() is called; pause()/resume(); the film can be
// read at any time (per-tile consistent, see film.h) and history() returns finished passes.
#pragma once
#include "accel/beam_accel.h"
#include "integrators/camera_pass.h"
#include "film/film.h"
#include "render/memory_budget.h"
#include "render/render_settings.h"
#include "base/pause_gate.h"
#include "scene/scene.h"

#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace tpb {

struct PassStats {
    uint64_t pass = 0;  // 1-based
    double beamRadius = 0.0, surfaceRadius = 0.0;
    int64_t photons = 0, beams = 0, beamPieces = 0, surfacePhotons = 0;
    // Flux the photons started with, and the part still carried at the end of long beams cut in an
    // unbounded medium (missing from the steady image only: see photon_tracer.cpp, openBeamLength).
    Color emittedFlux{0.0}, cutFlux{0.0};
    int64_t regionOverflows = 0;  // photons ended by a full region stack (camera paths: camera.regionOverflows)
    CameraPassStats camera;
    double photonSec = 0.0, buildSec = 0.0, cameraSec = 0.0, passSec = 0.0;
    double elapsedSec = 0.0;  // since start()
    uint64_t peakRssBytes = 0;
};

class Driver {
public:
    // The film gets `time` as its time axis (decided once, before the film exists: time_range.h).
    Driver(const Scene& scene, const RenderSettings& settings, const TimeBins& time);
    ~Driver();

    // Runs one pass synchronously (all threads). Returns false if aborted midway (film untouched
    // for tiles not rendered; a partly rendered pass leaves those tiles one pass ahead).
    bool runPass(uint64_t pass);

    void start(std::function<void(const PassStats&)> onPass = {});
    void pause();
    void resume();
    void stop();  // finishes the tile in progress, then returns; safe to call twice
    void wait();  // until the background run ends by itself (passes or budget)
    bool running() const { return running_.load(); }
    // Why the background run stopped early, if a pass threw (e.g. the photon map outgrew the memory
    // budget, or out of memory): the exception, and its message. The passes finished before it stay
    // in the film; the failed pass may have added some tiles (as an aborted one does).
    std::exception_ptr failure() const;
    std::string failureMessage() const;
    bool paused() const { return gate_.paused(); }
    // Stops the background run after the pass in progress (a paused run sees it within 20 ms).
    // Only stores an atomic: safe to call from a signal handler (the CLI's Ctrl-C/SIGTERM).
    void requestStop() { stopRequested_ = true; }

    const TransientFilm& film() const { return *film_; }
    TransientFilm& film() { return *film_; }
    const Scene& scene() const { return scene_; }
    const RenderSettings& settings() const { return settings_; }
    uint64_t completedPasses() const { return completed_.load(); }
    std::vector<PassStats> history() const;
    PassStats lastPass() const;

private:
    void loop(std::function<void(const PassStats&)> onPass);

    const Scene& scene_;
    RenderSettings settings_;
    std::unique_ptr<TransientFilm> film_;
    std::thread thread_;
    std::atomic<bool> running_{false}, stopRequested_{false}, abort_{false};
    PauseGate gate_;  // pause/resume between passes (takes its lock to notify: no lost wakeup)
    std::atomic<uint64_t> completed_{0};
    mutable std::mutex mutex_;
    std::vector<PassStats> history_;
    std::exception_ptr failure_;
    std::string failureMessage_;
    std::unique_ptr<BeamAccel> accel_;  // kept across passes so its buffers are reused
    double startTime_ = 0.0;
};

double nowSec();

}  // namespace tpb
