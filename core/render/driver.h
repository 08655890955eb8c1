// The progressive driver: runs any Integrator (integrators/integrator.h) pass after pass into one
// transient film: beginPass on all threads, then the film's tiles spread over the worker threads
// (each tile written by one thread at a time), then endPass; the pass's counters go to the history.
// Pass i depends only on (seed, i), so results do not depend on the number of threads, and any
// list of pass indices can be run (runPass).
//
// Asynchronous API for the viewer and the CLI: start() runs passes on a background thread until
// the pass count or time budget is reached or stop() is called; pause()/resume(); snapshot() can be
// taken at any time (per-tile consistent, see film_snapshot.h) and history() returns finished passes.
#pragma once
#include "integrators/integrator.h"
#include "film/transient_film.h"
#include "base/memory.h"
#include "film/film_bytes.h"
#include "integrators/render_settings.h"
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

class Driver {
public:
    // The film gets `time` as its time axis (decided once, before the film exists: time_range.h).
    // The integrator is settings.method's (makeIntegrator) unless one is given.
    Driver(const Scene& scene, const RenderSettings& settings, const TimeBins& time,
           std::unique_ptr<Integrator> integrator = nullptr);
    ~Driver();

    // Runs one pass synchronously (all threads). Returns false if aborted midway (film untouched
    // for tiles not rendered; a partly rendered pass leaves those tiles one pass ahead).
    bool runPass(uint64_t pass);
    // Continues a render from a checkpoint (render/checkpoint.h): the film (same size and time axis
    // as this driver's, else std::invalid_argument) replaces this driver's, its finished passes and
    // their statistics become this driver's history, and the next pass start() runs is
    // history.size() + 1. Only before start() (or after the run ended).
    // A null film keeps this driver's (filled in place: readCheckpoint(path, &film())).
    void restore(std::unique_ptr<TransientFilm> film, std::vector<PassStats> history);

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
    const RenderSettings& settings() const { return settings_; }
    const Integrator& integrator() const { return *integrator_; }
    uint64_t completedPasses() const { return completed_.load(); }
    std::vector<PassStats> history() const;
    PassStats lastPass() const;

private:
    void loop(std::function<void(const PassStats&)> onPass);

    const Scene& scene_;
    RenderSettings settings_;
    std::unique_ptr<TransientFilm> film_;
    std::vector<TileStaging> staging_;  // per render thread: the tile it is writing (TransientFilm::TileWriter)
    std::thread thread_;
    std::atomic<bool> running_{false}, stopRequested_{false}, abort_{false};
    PauseGate gate_;  // pause/resume between passes (takes its lock to notify: no lost wakeup)
    std::atomic<uint64_t> completed_{0};
    mutable std::mutex mutex_;
    std::vector<PassStats> history_;
    std::exception_ptr failure_;
    std::string failureMessage_;
    std::unique_ptr<Integrator> integrator_;
    double startTime_ = 0.0;
};

double nowSec();

// A probe pass (integrators/integrator.h, ProbeRequest) run like a pass: beginProbe on `threads`
// threads, then (unless the request is photonsOnly) the pixels (x, y) with x % stepX == 0 and
// y % stepY == 0 gathered on the time axis `time`, rows spread over the threads. `luminance`: per
// bin, the luminance of every such pixel's estimate (negative parts dropped), both time axes
// summed; each row is summed on its own and the rows added in row order, so the result is the same
// for any thread count. `progress` (0..1, on the calling thread) after the photon pass and the rows.
struct ProbeResult {
    bool ran = false;               // false: the integrator has no probe, or `abort` stopped it
    bool aborted = false;           // `abort` stopped it
    std::vector<double> luminance;  // time.bins values (empty for a photonsOnly probe)
};
ProbeResult runProbe(Integrator& integrator, const Scene& scene, const ProbeRequest& request, const TimeBins& time,
                     int stepX, int stepY, int threads, const std::atomic<bool>* abort = nullptr,
                     const std::function<void(double)>& progress = {});

}  // namespace tpb
