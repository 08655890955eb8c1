#include "render/driver.h"

#include "base/parallel.h"
#include "accel/photon_grid.h"
#include "base/progressive.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

namespace tpb {

double nowSec() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

Driver::Driver(const Scene& scene, const RenderSettings& settings, const TimeBins& time)
    : scene_(scene), settings_(settings),
      film_(std::make_unique<TransientFilm>(scene.camera.width, scene.camera.height, time)) {
    settings_.threads = resolveThreads(settings_.threads);
    startTime_ = nowSec();
}

Driver::~Driver() { stop(); }

bool Driver::runPass(uint64_t pass) {
    PassStats ps;
    ps.pass = pass;
    // Radius schedule: both kernels are 2D (area shrinks by (i + alpha) / (i + 1) per pass).
    ps.beamRadius = progressiveRadius(settings_.beamRadius0, settings_.alpha, pass, 2);
    ps.surfaceRadius = progressiveRadius(settings_.surfaceRadius0, settings_.alpha, pass, 2);
    const double t0 = nowSec();

    // 1. Photon pass (only the stages the scene needs).
    PhotonTraceSettings pt;
    pt.seed = settings_.seed;
    pt.pass = pass;
    pt.photons = settings_.photonsPerPass;
    pt.maxDepth = settings_.maxDepth;
    pt.storeBeams = scene_.stages.beams;
    pt.storeSurfacePhotons = scene_.stages.surfacePhotons;
    pt.beamLength = settings_.beamLength;
    pt.filmEndOpl = film_->time().endOpl();
    pt.threads = settings_.threads;
    pt.maxMapBytes = settings_.maxPhotonMapBytes > 0 ? settings_.maxPhotonMapBytes : maxFilmBytes();
    PhotonMap map = tracePhotons(scene_, pt, &abort_);
    if (abort_) return false;
    ps.photons = map.emitted;
    ps.beams = static_cast<int64_t>(map.beams.size());
    ps.surfacePhotons = static_cast<int64_t>(map.photons.size());
    ps.emittedFlux = map.emittedFlux;
    ps.cutFlux = map.cutFlux;
    ps.regionOverflows = map.regionOverflows;
    const double t1 = nowSec();

    // 2. Acceleration structures.
    BeamAccel* accel = nullptr;
    if (scene_.stages.beams && !map.beams.empty()) {
        if (!accel_) accel_ = BeamAccel::create(settings_.accel);
        accel_->build(map.beams, ps.beamRadius, settings_.threads);
        accel = accel_.get();
        ps.beamPieces = static_cast<int64_t>(accel->pieceCount());
    }
    std::unique_ptr<PhotonGrid> grid;
    if (scene_.stages.surfacePhotons && !map.photons.empty()) {
        grid = std::make_unique<PhotonGrid>();
        grid->build(map.photons, ps.surfaceRadius);
    }
    const double t2 = nowSec();

    // 3. Camera pass: whole tiles per thread, so a pixel's time series has a single writer.
    CameraPassSettings cs;
    cs.seed = settings_.seed;
    cs.pass = pass;
    cs.beamRadius = ps.beamRadius;
    cs.surfaceRadius = ps.surfaceRadius;
    cs.profile = settings_.profile;
    cs.beamLength = settings_.beamLength;
    cs.maxDepth = settings_.maxDepth;
    const int threads = settings_.threads;
    std::vector<CameraPassScratch> scratch(static_cast<size_t>(threads));
    for (auto& sc : scratch) sc.acc.reset(film_->bins());
    std::vector<CameraPassStats> stats(static_cast<size_t>(threads));
    parallelFor(film_->tileCount(), threads, [&](int64_t tile, int t) {
        renderTile(scene_, map, accel, grid.get(), cs, *film_, static_cast<int>(tile), scratch[t], stats[t]);
    }, &abort_);
    for (const CameraPassStats& st : stats) {
        ps.camera += st;
        st.flushInto(film_->stats);
    }
    if (abort_) return false;
    const double t3 = nowSec();
    ps.photonSec = t1 - t0;
    ps.buildSec = t2 - t1;
    ps.cameraSec = t3 - t2;
    ps.passSec = t3 - t0;
    ps.elapsedSec = t3 - startTime_;
    ps.peakRssBytes = peakRssBytes();
    {
        std::lock_guard<std::mutex> g(mutex_);
        history_.push_back(ps);
    }
    completed_ = pass;
    return true;
}

void Driver::start(std::function<void(const PassStats&)> onPass) {
    stop();
    {
        std::lock_guard<std::mutex> g(mutex_);
        failure_ = nullptr;
        failureMessage_.clear();
    }
    stopRequested_ = false;
    abort_ = false;
    gate_.rearm();
    running_ = true;
    startTime_ = nowSec();
    thread_ = std::thread([this, onPass] { loop(onPass); });
}

void Driver::loop(std::function<void(const PassStats&)> onPass) {
    const double t0 = nowSec();
    for (uint64_t pass = completed_ + 1;; ++pass) {
        if (!gate_.waitUntilOpen(&stopRequested_) || stopRequested_ || abort_) break;
        if (settings_.passes > 0 && static_cast<int64_t>(pass) > settings_.passes) break;
        if (settings_.timeBudgetSec > 0.0 && nowSec() - t0 >= settings_.timeBudgetSec) break;
        try {
            if (!runPass(pass)) break;
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> g(mutex_);
            failure_ = std::current_exception();
            failureMessage_ = e.what();
            break;
        } catch (...) {
            std::lock_guard<std::mutex> g(mutex_);
            failure_ = std::current_exception();
            failureMessage_ = "unknown exception";
            break;
        }
        if (onPass) onPass(lastPass());
    }
    running_ = false;
}

void Driver::pause() { gate_.pause(); }
void Driver::resume() { gate_.resume(); }

void Driver::stop() {
    abort_ = true;
    stopRequested_ = true;
    gate_.stop();
    if (thread_.joinable()) thread_.join();
    running_ = false;
}

void Driver::wait() {
    if (thread_.joinable()) thread_.join();
}

std::vector<PassStats> Driver::history() const {
    std::lock_guard<std::mutex> g(mutex_);
    return history_;
}

std::exception_ptr Driver::failure() const {
    std::lock_guard<std::mutex> g(mutex_);
    return failure_;
}

std::string Driver::failureMessage() const {
    std::lock_guard<std::mutex> g(mutex_);
    return failureMessage_;
}

PassStats Driver::lastPass() const {
    std::lock_guard<std::mutex> g(mutex_);
    return history_.empty() ? PassStats{} : history_.back();
}

}  // namespace tpb
