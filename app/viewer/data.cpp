// Viewer: the data path from the film to the textures (the render session: session.h). The viewer never
// reads the live film: it takes a snapshot (film_snapshot.h: a pointer per tile, never waits for a
// tile being rendered) for each fetch and reads the images from it (film_view.h). The frame is read
// on the UI thread; the streak, the pixel profile and the energy per bin on helper threads, from
// a snapshot taken on the UI thread. Snapshots are dropped after the read (a held one keeps the
// tiles it shows alive while the render replaces them).
#include "viewer/app.h"

#include "base/error.h"

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

void Viewer::updatePreparingImage() {
    // While the film is allocated: the preview's steady image, fetched after each of its passes.
    const Driver* preview = session_.preview();
    if (!preview || preview->completedPasses() == previewFetched_) return;
    std::shared_ptr<const FilmSnapshot> snap = preview->snapshot();
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

void Viewer::restart(const RenderSettings& s, const std::string& why) {
    session_.restart(s);
    adopted(why, 0);
}

void Viewer::adopted(const std::string& why, uint64_t resumedPasses) {
    if (resumedPasses > 0)
        std::printf("resumed %llu passes from the checkpoint\n", static_cast<unsigned long long>(resumedPasses));
    edit_ = driver().settings();
    startedAt_ = glfwGetTime();
    firstLightSec_ = -1.0;
    session_.setStatus(why);
    const RenderSettings& s = driver().settings();
    if (!why.empty()) {
        std::printf("%s (photons/pass %lld, alpha %.4g, initial radius %.6g m, pass limit %lld)\n", why.c_str(),
                    static_cast<long long>(s.photonsPerPass), s.alpha, s.beamRadius0, static_cast<long long>(s.passes));
    }
    std::fflush(stdout);
}

float Viewer::binCentreOpl(int bin) const { return static_cast<float>(time_.startOpl + (bin + 0.5) * time_.binWidth); }

FetchKey Viewer::frameKey() const {
    FetchKey k;
    k.generation = session_.generation();
    k.steady = st_.showSteady;
    k.passes = session_.shownPasses(k.steady);
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
    k.generation = session_.generation();
    k.passes = driver().completedPasses();
    k.x = st_.selX;
    k.y = st_.selY;
    k.axis = st_.axis;
    k.mode = st_.mode;
    k.response = st_.response;
    return k;
}

FetchKey Viewer::binEnergyKey() const {
    FetchKey k;
    k.generation = session_.generation();
    k.passes = driver().completedPasses();
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
    const bool rendering = driver().running() && !driver().paused();
    const double gap = std::max(frameComplete_ ? 0.25 : 1.0 / 30.0, 10.0 * fetchSec_);
    if (changed || ((!frameComplete_ || rendering) && now - lastFetch_ >= gap)) {
        std::shared_ptr<const FilmSnapshot> snap = session_.shownSnapshot(key.steady);
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
    const RenderSettings& s = driver().settings();
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
    const uint64_t passes = driver().completedPasses();
    if (!st_.showSteady || !st_.autoFrame || st_.autoBin || passes == 0 || passes == hiddenFitPasses_) return;
    hiddenFitPasses_ = passes;
    std::shared_ptr<const FilmSnapshot> snap = driver().snapshot();
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
        if (st_.autoBin && r.key.generation == session_.generation() && r.key.axis == st_.axis) {
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
    const bool rendering = driver().running() && !driver().paused();
    const bool due = rendering && now - binEnergyLaunched_ >= std::max(0.25, 10.0 * binEnergySec_);
    if (key == binEnergyRequested_ && !due) return;
    binEnergyRequested_ = key;
    binEnergyLaunched_ = now;
    std::shared_ptr<const FilmSnapshot> snap = driver().snapshot();
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
        if (r.key.generation == session_.generation()) {
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
        std::shared_ptr<const FilmSnapshot> snap = driver().snapshot();
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

}  // namespace tpb::app
