#include "render/driver.h"

#include "base/parallel.h"

#include <chrono>
#include <stdexcept>
#include <cstdio>
#include <fstream>
#include <string>

namespace tpb {

double nowSec() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

Driver::Driver(const Scene& scene, const RenderSettings& settings, const TimeBins& time,
               std::unique_ptr<Integrator> integrator)
    : scene_(scene),
      settings_(settings),
      film_(std::make_unique<TransientFilm>(scene.camera.width, scene.camera.height, time, settings.phasor)),
      integrator_(integrator ? std::move(integrator) : makeIntegrator(scene, settings)) {
    settings_.threads = resolveThreads(settings_.threads);
    startTime_ = nowSec();
}

Driver::~Driver() { stop(); }

bool Driver::runPass(uint64_t pass) {
    PassStats ps;
    ps.pass = pass;
    PassContext ctx;
    ctx.pass = pass;
    ctx.time = &film_->time();
    ctx.phasor = &film_->phasor();
    ctx.threads = settings_.threads;
    ctx.tiles = film_->tileCount();
    ctx.abort = &abort_;
    const double t0 = nowSec();

    // 1. What the integrator prepares for the pass (photon beams: photons and accelerators).
    if (!integrator_->beginPass(ctx, ps) || abort_) return false;
    const double t1 = nowSec();

    // 2. Whole tiles per thread, so a pixel's time series has a single writer; each thread stages
    // its tile's pixels and adds them to the film when the tile is done (in place, transient_film.h).
    if (staging_.size() < static_cast<size_t>(ctx.threads)) staging_.resize(static_cast<size_t>(ctx.threads));
    const double weight = settings_.passWeight(ctx.pass);  // < 1 for a warm-up pass of the photon beams
    parallelFor(
        ctx.tiles, ctx.threads,
        [&](int64_t tile, int t) {
            const int i = static_cast<int>(tile);
            TransientFilm::TileWriter writer(*film_, i, &staging_[static_cast<size_t>(t)], weight);
            integrator_->renderTile(ctx, i, film_->tileRect(i), writer, t);
        },
        &abort_);
    integrator_->endPass(ctx, ps);
    ps.film.flushInto(film_->stats);
    if (abort_) return false;
    const double t2 = nowSec();
    ps.cameraSec = t2 - t1;
    ps.passSec = t2 - t0;
    ps.elapsedSec = t2 - startTime_;
    ps.peakRssBytes = peakRssBytes();
    {
        std::lock_guard<std::mutex> g(mutex_);
        history_.push_back(ps);
    }
    completed_ = pass;
    return true;
}

void Driver::restore(std::unique_ptr<TransientFilm> film, std::vector<PassStats> history) {
    if (running_) throw std::logic_error("Driver::restore while passes run");
    if (film) {
        const TimeBins &a = film->time(), &b = film_->time();
        if (film->width() != film_->width() || film->height() != film_->height() || a.bins != b.bins ||
            a.startOpl != b.startOpl || a.binWidth != b.binWidth)
            throw std::invalid_argument("Driver::restore: the film differs in size or time axis from this render's");
        film_ = std::move(film);
    }
    std::lock_guard<std::mutex> g(mutex_);
    history_ = std::move(history);
    completed_ = history_.size();
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

ProbeResult runProbe(Integrator& integrator, const Scene& scene, const ProbeRequest& request, const TimeBins& time,
                     int stepX, int stepY, int threads, const std::atomic<bool>* abort,
                     const std::function<void(double)>& progress) {
    constexpr double kPhotonShare = 0.2;  // rough share of the photon pass in the probe's time
    const auto report = [&](double f) {
        if (progress) progress(f);
    };
    const auto aborted = [&] { return abort && abort->load(); };
    ProbeResult out;
    PassContext ctx;
    ctx.pass = 0;
    ctx.time = &time;
    ctx.threads = std::max(1, threads);
    ctx.abort = abort;
    report(0.0);
    if (!integrator.beginProbe(ctx, request)) {
        out.aborted = aborted();
        return out;
    }
    if (request.photonsOnly) {
        out.ran = true;
        return out;
    }
    report(kPhotonShare);
    const int W = scene.camera.width, H = scene.camera.height;
    stepX = std::max(1, stepX);
    stepY = std::max(1, stepY);
    const int rows = (H + stepY - 1) / stepY;
    const size_t bins = static_cast<size_t>(time.bins);
    std::vector<double> perRow(static_cast<size_t>(rows) * bins, 0.0);
    std::atomic<int> rowsDone{0};
    parallelFor(
        rows, ctx.threads,
        [&](int64_t r, int thread) {
            double* row = &perRow[static_cast<size_t>(r) * bins];
            const int y = static_cast<int>(r) * stepY;
            for (int x = 0; x < W; x += stepX) {
                if (aborted()) return;  // (a row of a huge film is long too)
                const PixelAccumulator* acc = integrator.probePixel(ctx, x, y, thread);
                if (!acc) return;
                for (TimeAxis a : {TimeAxis::Real, TimeAxis::Unwarped})
                    for (int k = acc->lo(a); k <= acc->hi(a); ++k) {
                        const double* v = acc->bin(a, k);
                        row[k] += std::max(0.0, luminance(Color(v[0], v[1], v[2])));
                    }
            }
            const int done = rowsDone.fetch_add(1) + 1;
            if (thread == 0) report(kPhotonShare + (1.0 - kPhotonShare) * done / rows);
        },
        abort);
    if (aborted()) {
        out.aborted = true;
        return out;
    }
    out.luminance.assign(bins, 0.0);
    for (int r = 0; r < rows; ++r)
        for (size_t k = 0; k < bins; ++k) out.luminance[k] += perRow[static_cast<size_t>(r) * bins + k];
    report(1.0);
    out.ran = true;
    return out;
}

}  // namespace tpb
