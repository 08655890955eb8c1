// Viewer: the driver session and the data path from the film to the textures. The viewer never
// reads the live film: it takes a snapshot (film_snapshot.h: a pointer per tile, never waits for a
// tile being rendered) for each fetch and reads the images from it (film_view.h). The frame is read
// on the UI thread; the streak, the pixel profile and the energy per bin on helper threads, from
// a snapshot taken on the UI thread. Snapshots are dropped after the read (a held one keeps the
// tiles it shows alive while the render replaces them).
#include "viewer/app.h"

#include "base/error.h"
#include "io/folder_lock.h"

#include <chrono>
#include <filesystem>
#include <future>

#include "film/film_view.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace tpb::app {

int peakEnergyBin(const std::vector<double>& energy) {
    int best = -1;
    double peak = 0.0;
    for (size_t k = 0; k < energy.size(); ++k)
        if (std::isfinite(energy[k]) && energy[k] > peak) {
            peak = energy[k];
            best = static_cast<int>(k);
        }
    return best;
}

// The first driver: its film (hundreds of MiB on the default scene: seconds to allocate) and the
// checkpoint it resumes from are made on a helper thread while the window already shows a
// "preparing" screen (Viewer::waitForFilm); the driver only starts once it is adopted.
std::future<PreparedDriver> prepareDriver(const Scene& scene, const RenderSettings& s, const TimeBins& time,
                                          const std::string& resumePath) {
    return std::async(std::launch::async, [&scene, s, time, resumePath] {
        PreparedDriver p;
        p.driver = std::make_shared<Driver>(scene, s, time);
        if (!resumePath.empty()) {  // `tpb view --resume`: go on from the checkpoint's passes
            Checkpoint c = readCheckpoint(resumePath, &p.driver->film());  // into the driver's film: one film in memory
            p.resumedPasses = c.info.passes;
            p.driver->restore(nullptr, std::move(c.history));
        }
        return p;
    });
}

void Viewer::updatePreparingImage() {
    // While the film is allocated: the preview's steady image, fetched after each of its passes.
    if (!preview_ || preview_->completedPasses() == previewFetched_) return;
    std::shared_ptr<const FilmSnapshot> snap = preview_->snapshot();
    previewFetched_ = snap->minPasses();
    frameRgb_ = steadyImage(*snap);
    snap.reset();
    image_.upload(scene_.camera.width, scene_.camera.height, frameRgb_.data());
    const ExposureFit fit = fitExposure(frameRgb_);
    if (fit.found && st_.autoSteady) st_.evSteady = fit.ev;  // refitted to the film's picture later
    DisplayParams p = st_.display;
    p.exposureEv = st_.evSteady;
    program_.apply(image_, p);
    imageDirty_ = true;  // the film's first fetch applies the display again
}

std::shared_ptr<const FilmSnapshot> Viewer::shownSnapshot(bool steady) {
    if (preview_ && driver_->completedPasses() >= preview_->completedPasses()) preview_.reset();  // caught up
    return steady && preview_ ? preview_->snapshot() : driver_->snapshot();
}

uint64_t Viewer::shownPasses(bool steady) const {
    const uint64_t film = driver_->completedPasses();
    return steady && preview_ ? std::max(film, preview_->completedPasses()) : film;
}

void Viewer::restart(const RenderSettings& s, const std::string& why) {
    preview_.reset();  // of the old settings
    if (checkpointStage_ == CheckpointStage::Writing) {  // finish it (it holds the old driver)
        checkpointJob_.wait();
        pollCheckpoint();
    }
    checkpointStage_ = CheckpointStage::Idle;
    if (driver_) driver_->stop();  // an export or a profile read may still hold the old one
    driver_.reset();               // before the new film is allocated: one film in memory, not two
    adopt(prepareDriver(scene_, s, time_, "").get(), why);
}

void Viewer::adopt(PreparedDriver p, const std::string& why) {
    driver_ = std::move(p.driver);
    if (p.resumedPasses > 0)
        std::printf("resumed %llu passes from the checkpoint\n", static_cast<unsigned long long>(p.resumedPasses));
    ++generation_;
    edit_ = driver_->settings();
    driver_->start([](const PassStats&) { glfwPostEmptyEvent(); });  // wake the UI; no GL here
    startedAt_ = glfwGetTime();
    firstLightSec_ = -1.0;
    status_ = why;
    const RenderSettings& s = driver_->settings();
    if (!why.empty()) {
        std::printf("%s (photons/pass %lld, alpha %.4g, initial radius %.6g m, pass limit %lld)\n", why.c_str(),
                    static_cast<long long>(s.photonsPerPass), s.alpha, s.beamRadius0, static_cast<long long>(s.passes));
    }
    std::fflush(stdout);
}

namespace {

// Throws UserError when `path` is a checkpoint none of `own` names (another render's: saving would
// replace it silently).
void refuseForeignCheckpoint(const std::string& path, const std::vector<std::string>& own) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return;
    for (const std::string& o : own)
        if (std::filesystem::equivalent(o, path, ec)) return;
    std::string what = "a checkpoint that cannot be read";
    try {
        const CheckpointInfo info = readCheckpointInfo(path);
        what = "the checkpoint of another render (" + std::to_string(info.passes) + " passes of " + info.scene +
               ", written " + info.created + ")";
    } catch (const UserError&) {
    }
    throw UserError(path, 0, "",
                    "holds " + what + "; the viewer does not replace it: choose another folder in the Export "
                    "section, or continue that render with `tpb view --resume " +
                        std::filesystem::path(path).parent_path().string() + "`");
}

}  // namespace

void Viewer::requestCheckpoint() {
    if (checkpointStage_ != CheckpointStage::Idle) return;
    checkpointWasPaused_ = driver_->paused();
    driver_->pause();  // between passes: the checkpoint is written once the pass in progress ends
    checkpointStage_ = CheckpointStage::WaitingForPassEnd;
    status_ = "checkpoint: waiting for the pass in progress to end";
}

void Viewer::pollCheckpoint() {
    if (checkpointStage_ == CheckpointStage::WaitingForPassEnd) {
        const std::vector<PassStats> history = driver_->history();
        const auto snap = driver_->snapshot();
        const bool between = snap->minPasses() == snap->maxPasses() &&
                             snap->minPasses() == static_cast<int64_t>(history.size());
        if (!between) return;  // a pass is still being added (paused takes effect after it)
        const std::string path = (std::filesystem::path(st_.outDir) / kCheckpointFile).string();
        std::shared_ptr<FolderLock> lock;
        try {
            // The export folder's lock, as `tpb render` holds it on its output folder.
            lock = FolderLock::acquire(st_.outDir, "tpb view", "choose another folder in the Export section");
            refuseForeignCheckpoint(path, ownCheckpoints_);
        } catch (const std::exception& e) {
            status_ = std::string("checkpoint not written: ") + e.what();
            std::fprintf(stderr, "error: %s\n", status_.c_str());
            checkpointFailed_ = true;
            checkpointStage_ = CheckpointStage::Idle;
            if (!checkpointWasPaused_) driver_->resume();
            return;
        }
        const CheckpointInfo info = checkpointInfoFor(prepared_, driver_->settings(), opt_.flags, history.size());
        checkpointStage_ = CheckpointStage::Writing;
        status_ = "checkpoint: writing " + path;
        checkpointJob_ = std::async(std::launch::async, [d = driver_, path, info, history, lock]() -> std::string {
            try {
                writeCheckpoint(path, info, d->film(), history);
                return "";
            } catch (const std::exception& e) {
                return std::string("error: ") + e.what();
            }
        });
        return;
    }
    if (checkpointStage_ != CheckpointStage::Writing ||
        checkpointJob_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
        return;
    const std::string err = checkpointJob_.get();
    const std::string path = (std::filesystem::path(st_.outDir) / kCheckpointFile).string();
    status_ = err.empty() ? "checkpoint of " + std::to_string(driver_->history().size()) + " passes written to " + path +
                                " (tpb render --resume " + st_.outDir + ")"
                          : "checkpoint failed: " + err;
    if (err.empty()) ownCheckpoints_.push_back(path);
    else checkpointFailed_ = true;
    std::fprintf(err.empty() ? stdout : stderr, "%s\n", status_.c_str());
    std::fflush(stdout);
    checkpointStage_ = CheckpointStage::Idle;
    if (!checkpointWasPaused_) driver_->resume();
    glfwPostEmptyEvent();
}

float Viewer::binCentreOpl(int bin) const {
    return static_cast<float>(time_.startOpl + (bin + 0.5) * time_.binWidth);
}

FetchKey Viewer::frameKey() const {
    FetchKey k;
    k.generation = generation_;
    k.steady = st_.showSteady;
    k.passes = shownPasses(k.steady);
    if (!k.steady) {
        k.bin = st_.bin;
        k.axis = st_.axis;
        k.mode = st_.mode;
        k.response = st_.response;
    }
    return k;
}

FetchKey Viewer::profileKey() const {
    FetchKey k;
    k.generation = generation_;
    k.passes = driver_->completedPasses();
    k.x = st_.selX;
    k.y = st_.selY;
    k.axis = st_.axis;
    k.mode = st_.mode;
    k.response = st_.response;
    return k;
}

FetchKey Viewer::binEnergyKey() const {
    FetchKey k;
    k.generation = generation_;
    k.passes = driver_->completedPasses();
    k.axis = st_.axis;
    return k;
}

void Viewer::updateFrame() {
    const FetchKey key = frameKey();
    const double now = glfwGetTime();
    // Fetch when the film or the selection changed. An incomplete fetch (its tiles differ in passes:
    // a pass was being rendered) is repeated, and while a pass renders the tiles it finishes are
    // fetched too (the first pass can take many seconds): at most 30 (incomplete) or 4 (complete)
    // times a second, and at most a tenth of the UI thread's time (a continuous frame reads the
    // prefix sums, computed once per tile block on the first continuous read).
    const bool changed = !(key == frameKey_);
    const bool rendering = driver_->running() && !driver_->paused();
    const double gap = std::max(frameComplete_ ? 0.25 : 1.0 / 30.0, 10.0 * fetchSec_);
    if (changed || ((!frameComplete_ || rendering) && now - lastFetch_ >= gap)) {
        std::shared_ptr<const FilmSnapshot> snap = shownSnapshot(key.steady);
        frameRgb_ = key.steady ? steadyImage(*snap) : frameImage(*snap, key.bin, key.axis, key.mode, key.response);
        frameComplete_ = snap->minPasses() == snap->maxPasses();
        const int width = snap->width(), height = snap->height();
        snap.reset();  // read: let go before the upload and the exposure fit (a held tile is copied by its writer)
        frameKey_ = key;
        lastFetch_ = now;
        image_.upload(width, height, frameRgb_.data());
        imageDirty_ = true;
        fitPendingExposure(key);
        trackNoise(key);
        if (firstLightSec_ < 0.0 && std::any_of(frameRgb_.begin(), frameRgb_.end(), [](float v) { return v > 0.0f; }))
            firstLightSec_ = glfwGetTime() - startedAt_;
        fetchSec_ = glfwGetTime() - now;  // the fit included (it sorts the lit pixels)
    }
    fitHiddenFrameExposure();
    DisplayParams p = st_.display;
    p.exposureEv = st_.showSteady ? st_.evSteady : st_.evFrame;
    if (imageDirty_ || p.exposureEv != lastImageParams_.exposureEv || p.srgb != lastImageParams_.srgb ||
        p.falseColor != lastImageParams_.falseColor || p.decades != lastImageParams_.decades) {
        program_.apply(image_, p);
        lastImageParams_ = p;
        imageDirty_ = false;
    }
}

void Viewer::trackNoise(const FetchKey& key) {
    // The noise of the picture shown, from the spread between the batches of passes it was fetched
    // at (instrument.h BatchNoise): complete fetches only (every tile at the same pass). Another
    // picture (bin, axis, emission, response, steady) or a restart starts the estimate over.
    FetchKey picture = key;
    picture.passes = 0;
    if (!(picture == noiseKey_)) {
        noiseKey_ = picture;
        noise_.reset(frameRgb_.size() / 3);
    }
    if (!frameComplete_ || key.passes == 0) return;
    const RenderSettings& s = driver_->settings();
    double weight = 0.0;  // the film's divisor after key.passes passes (render_settings.h passWeight)
    for (uint64_t i = 1; i <= key.passes; ++i) weight += s.passWeight(i);
    std::vector<float> lum(frameRgb_.size() / 3);
    for (size_t i = 0; i < lum.size(); ++i)
        lum[i] = static_cast<float>(luminance(Color(frameRgb_[3 * i], frameRgb_[3 * i + 1], frameRgb_[3 * i + 2])));
    noise_.add(lum, weight);
}

void Viewer::fitHiddenFrameExposure() {
    // The steady image is shown, the frames' exposure still automatic: fit it to the frame of the
    // automatic bin once that bin is decided (a complete pass), so that the frame the user switches
    // to, the streak image and the MP4/contact sheet exports are exposed for frames.
    const uint64_t passes = driver_->completedPasses();
    if (!st_.showSteady || !st_.autoFrame || st_.autoBin || passes == 0 || passes == hiddenFitPasses_) return;
    hiddenFitPasses_ = passes;
    std::shared_ptr<const FilmSnapshot> snap = driver_->snapshot();
    const std::vector<float> rgb = frameImage(*snap, st_.bin, st_.axis, st_.mode, st_.response);
    snap.reset();
    const ExposureFit fit = fitExposure(rgb);
    if (!fit.found) return;  // a black frame: again after the next pass
    st_.evFrame = fit.ev;
    st_.autoFrame = false;
}

void Viewer::fitPendingExposure(const FetchKey& key) {
    // Auto exposure (at start, after the Auto button, after a delta <-> continuous switch): fitted
    // to the light already there - the tiles finished so far - and again on every fetch, until
    // it has seen a complete frame of at least one pass on the bin that stays.
    bool& pending = key.steady ? st_.autoSteady : st_.autoFrame;
    if (!pending) return;
    const ExposureFit fit = fitExposure(frameRgb_);
    if (!fit.found) return;
    (key.steady ? st_.evSteady : st_.evFrame) = fit.ev;
    pending = !(frameComplete_ && key.passes > 0 && (key.steady || !st_.autoBin));
    const bool news = fit.ev != lastFit_.ev || fit.litPixels != lastFit_.litPixels || !pending;
    lastFit_ = fit;
    if (!opt_.screenshot.empty() && news) {  // for the tests: when the exposure was fitted, on what
        std::printf("auto_exposure ev %.6g lit_pixels %zu passes %llu complete %d final %d bin %d steady %d\n",
                    static_cast<double>(fit.ev), fit.litPixels, static_cast<unsigned long long>(key.passes),
                    frameComplete_ ? 1 : 0, pending ? 0 : 1, key.bin, key.steady ? 1 : 0);
        std::fflush(stdout);
    }
}

void Viewer::updateBinEnergy() {
    using namespace std::chrono_literals;
    if (binEnergyJob_.valid() && binEnergyJob_.wait_for(0s) == std::future_status::ready) {
        const BinEnergyResult r = binEnergyJob_.get();
        binEnergySec_ = glfwGetTime() - binEnergyLaunched_;
        if (st_.autoBin && r.key.generation == generation_ && r.key.axis == st_.axis) {
            const int k = peakEnergyBin(r.energy);
            if (k >= 0) setAutoBin(k);
            if (r.complete && r.key.passes > 0) {  // the first pass is in: keep this bin
                st_.autoBin = false;
                if (st_.autoFrame) frameKey_ = FetchKey{};  // and fit the exposure to it for good
            } else if (!r.complete) {
                // The snapshot caught a pass in progress (its tiles differ in passes): measure
                // again, even if no pass completes any more.
                binEnergyRequested_ = FetchKey{};
            }
        }
    }
    if (!st_.autoBin || binEnergyJob_.valid()) return;
    const FetchKey key = binEnergyKey();
    // Again when a pass completes, and a few times a second during the first pass (as its tiles
    // finish), taking at most a tenth of one core (it reads every bin of the film once).
    const double now = glfwGetTime();
    const bool rendering = driver_->running() && !driver_->paused();
    const bool due = rendering && now - binEnergyLaunched_ >= std::max(0.25, 10.0 * binEnergySec_);
    if (key == binEnergyRequested_ && !due) return;
    binEnergyRequested_ = key;
    binEnergyLaunched_ = now;
    std::shared_ptr<const FilmSnapshot> snap = driver_->snapshot();
    // The job lets go of its snapshot as soon as it has read it: the callable (and what it holds)
    // lives in the future's state until the UI thread collects the result, a frame or more later,
    // and every tile a render thread finished meanwhile would be copied (tile blocks held by a
    // snapshot are copied on write: film_snapshot.h).
    binEnergyJob_ = std::async(std::launch::async, [snap = std::move(snap), key]() mutable {
        BinEnergyResult r;
        r.key = key;
        r.complete = snap->minPasses() == snap->maxPasses();
        r.energy = binEnergy(*snap, key.axis, kAutoBinStride);
        snap.reset();
        return r;
    });
}

void Viewer::updateProfile() {
    using namespace std::chrono_literals;
    if (profileJob_.valid() && profileJob_.wait_for(0s) == std::future_status::ready) {
        ProfileResult r = profileJob_.get();
        if (r.key.generation == generation_) {
            profileKey_ = r.key;
            profileRgb_ = std::move(r.profile);
            profileLum_.resize(profileRgb_.size() / 3);
            for (size_t k = 0; k < profileLum_.size(); ++k)
                profileLum_[k] = static_cast<float>(
                    luminance(Color(profileRgb_[k * 3], profileRgb_[k * 3 + 1], profileRgb_[k * 3 + 2])));
            streak_.upload(r.width, r.bins, r.streak.data());
            streakDirty_ = true;
        }
    }
    const FetchKey key = profileKey();
    if (!profileJob_.valid() && !(key == profileRequested_)) {
        profileRequested_ = key;
        std::shared_ptr<const FilmSnapshot> snap = driver_->snapshot();
        profileJob_ = std::async(std::launch::async, [snap = std::move(snap), key]() mutable {
            ProfileResult r;
            r.key = key;
            r.width = snap->width();
            r.bins = snap->bins();
            r.profile = pixelProfile(*snap, key.x, key.y, key.axis, key.mode, key.response);
            r.streak = streakImage(*snap, key.y, key.axis, key.mode, key.response);
            snap.reset();  // read: let go now, not when the UI collects the result (as above)
            return r;
        });
    }
    DisplayParams p = st_.display;
    p.exposureEv = st_.evFrame;
    if (!streak_.empty() &&
        (streakDirty_ || p.exposureEv != lastStreakParams_.exposureEv || p.srgb != lastStreakParams_.srgb ||
         p.falseColor != lastStreakParams_.falseColor || p.decades != lastStreakParams_.decades)) {
        program_.apply(streak_, p);
        lastStreakParams_ = p;
        streakDirty_ = false;
    }
}

void Viewer::startExport(const ExportRequest& req) {
    if (export_.busy()) {
        status_ = "an export is already running";
        return;
    }
    exportError_.clear();
    exportLog_.clear();
    export_.start(driver_, req);
}

void Viewer::pollExport() {
    if (!export_.collect()) return;
    exportLog_ = export_.written();
    exported_.insert(exported_.end(), exportLog_.begin(), exportLog_.end());
    exportError_ = export_.error();
    for (const std::string& w : exportLog_) std::printf("exported: %s\n", w.c_str());
    if (!exportError_.empty()) std::fprintf(stderr, "export failed: %s\n", exportError_.c_str());
    std::fflush(stdout);
}

}  // namespace tpb::app
