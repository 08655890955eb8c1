// The progressive driver: pass i = trace photons (seeded by (pass, photon)), build the beam BVH
// and the surface-photon grid, camera pass over tiles (seeded by (pass, pixel)), shrink the radii.
// Passes are independent given their index, so results do not depend on the number of threads.
//
// Asynchronous API for the viewer and the CLI: start() runs passes on a background thread until
// the pass count or time budget is reached or stop() is called; pause()/resume(); snapshot() can be
// taken at any time (per-tile consistent, see film_snapshot.h) and history() returns finished passes.
#pragma once
#include "accel/beam_accel.h"
#include "integrators/camera_pass.h"
#include "film/transient_film.h"
#include "render/memory_budget.h"
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

struct DriverSettings {
    int64_t photonsPerPass = 20000;
    double beamRadius0 = 0.01;     // m
    double surfaceRadius0 = 0.02;  // m
    double alpha = 0.7;
    int64_t passes = 16;           // 0 = unlimited
    double timeBudgetSec = 0.0;    // 0 = unlimited
    int maxDepth = 16;
    uint64_t seed = 1;
    int threads = 0;
    TimeProfile profile = TimeProfile::Exact;
    BeamLength beamLength = BeamLength::Short;
    BeamAccel::Kind accel = BeamAccel::Kind::Embree;
    uint64_t maxPhotonMapBytes = 0;  // per pass; 0 = maxFilmBytes() (memory_budget.h)

    static DriverSettings fromScene(const Scene& scene);
};

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
    Driver(const Scene& scene, const DriverSettings& settings);
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

    // The film as its tiles have published it: after runPass() returns (or onPass is called), every
    // tile holds that pass; during a pass, tiles may differ by one. Cheap (a pointer per tile): take
    // one when showing or exporting and drop it after, since a snapshot held while passes go on keeps
    // the tile blocks it shows alive (film_snapshot.h). Not cached here for that reason: a snapshot
    // the driver kept from one pass to the next would double the film's memory during every pass.
    std::shared_ptr<const FilmSnapshot> snapshot() const { return film_->snapshot(); }
    const TransientFilm& film() const { return *film_; }
    TransientFilm& film() { return *film_; }
    const Scene& scene() const { return scene_; }
    const DriverSettings& settings() const { return settings_; }
    uint64_t completedPasses() const { return completed_.load(); }
    std::vector<PassStats> history() const;
    PassStats lastPass() const;

private:
    void loop(std::function<void(const PassStats&)> onPass);

    const Scene& scene_;
    DriverSettings settings_;
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
