#include "viewer/export.h"

#include "base/error.h"
#include "io/atomic_file.h"
#include "io/folder_lock.h"
#include "film/picture_export.h"
#include "film/volume_export.h"
#include "render/provenance.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace tpb::app {

void markFramesComplete(const std::string& dir, int written, int total) {
    const std::string marker = dir + "/" + kIncompleteName;
    if (written >= total) {
        std::error_code ec;
        std::filesystem::remove(marker, ec);  // an earlier cancelled export's note: this one is complete
        return;
    }
    writeFileAtomic(marker, "this export was cancelled after " + std::to_string(written) + " of " +
                                std::to_string(total) + " frames: the frames from frame " + std::to_string(written) +
                                " on are missing, or left from an earlier export; export all frames again\n");
}

bool ExportJob::start(std::shared_ptr<const Driver> driver, const ExportRequest& req) {
    if (running_.load()) return false;
    if (thread_.joinable()) thread_.join();
    {
        std::lock_guard<std::mutex> g(mutex_);
        error_.clear();
        written_.clear();
        stage_ = "starting";
    }
    cancel_ = false;
    done_ = 0;
    total_ = 0;
    running_ = true;
    thread_ = std::thread([this, driver = std::move(driver), req] { run(driver, req); });
    return true;
}

void ExportJob::run(std::shared_ptr<const Driver> driver, ExportRequest req) {
    // One snapshot for the whole export (the files show the same passes); held until it ends.
    const std::shared_ptr<const FilmSnapshot> snap = driver->snapshot();
    const FilmSnapshot& film = *snap;
    ExportOptions opt;
    opt.axis = req.axis;
    opt.mode = req.mode;
    opt.response = req.response;
    const int frames = req.allFrames ? film.bins() : 0;
    // Progress units: a file, a frame, a row of the volume, a frame of the video.
    total_ = (req.frame ? 1 : 0) + frames + (req.steady ? 1 : 0) + (req.streak ? 1 : 0) + (req.profile ? 1 : 0) +
             (req.volume ? film.height() : 0) + (req.mp4 ? film.bins() : 0) + (req.contactSheet ? 1 : 0);
    auto step = [&](const std::string& stage) {
        std::lock_guard<std::mutex> g(mutex_);
        stage_ = stage;
    };
    auto wrote = [&](const std::string& path) {
        std::lock_guard<std::mutex> g(mutex_);
        written_.push_back(path);
    };
    std::vector<std::string> notWritten;  // what a cancel left out, for the message
    try {
        // The folder is locked for the export, as `tpb render` locks its output folder: a render
        // writing into it refuses this export (and the other way round).
        const std::shared_ptr<FolderLock> lock =
            FolderLock::acquire(req.dir, "tpb view", "choose another folder in the Export section");
        if (req.frame && !cancel_) {
            step("current frame");
            const std::string path = req.dir + "/" + frameName(req.bin, outputTag(req.axis, req.mode, req.response));
            exportFrame(film, req.bin, path, opt);
            wrote(path);
            ++done_;
        }
        if (req.steady && !cancel_) {
            step("steady state");
            const std::string path = req.dir + "/" + kSteadyExrName;
            exportSteady(film, path);
            wrote(path);
            ++done_;
        }
        if (req.streak && !cancel_) {
            step("streak image");
            const std::string path = req.dir + "/" + streakName(req.row, outputTag(req.axis, req.mode, req.response));
            exportStreak(film, req.row, path, opt);
            wrote(path);
            ++done_;
        }
        if (req.profile && !cancel_) {
            step("pixel profile");
            const std::string path =
                req.dir + "/" + profileName(req.x, req.y, outputTag(req.axis, req.mode, req.response));
            exportProfileCsv(film, req.x, req.y, path, opt);
            wrote(path);
            ++done_;
        }
        if (frames > 0 && !cancel_) {
            step("all frames");
            const std::string dir = req.dir + "/" + framesDirName(outputTag(req.axis, req.mode, req.response));
            const int base = done_.load();
            int n = 0;
            try {
                n = exportFrames(
                    film, dir, opt, [&](int d, int) { done_ = base + (n = d); }, &cancel_);
            } catch (...) {  // a full disk: the frames written are marked as a partial set, if it can be
                try {
                    markFramesComplete(dir, n, frames);
                } catch (const std::exception&) {}
                throw;
            }
            markFramesComplete(dir, n, frames);
            if (n < frames) {
                wrote(dir + "/ (" + std::to_string(n) + " of " + std::to_string(frames) + " frames: incomplete, see " +
                      kIncompleteName + ")");
                notWritten.push_back(std::to_string(frames - n) + " of the frames");
            } else {
                wrote(dir + "/ (" + std::to_string(n) + " frames)");
            }
        }
        if (req.volume && !cancel_) {
            step("volume (.npy rows)");
            const std::string dir = req.dir + "/" + volumeDirName(outputTag(req.axis, req.mode, req.response));
            const int base = done_.load();
            const std::vector<std::string> names = exportVolumeNpy(
                film, dir, opt, provenanceOf(*driver, req.scenePath), [&](int d, int) { done_ = base + d; }, &cancel_);
            if (!cancel_) wrote(dir + "/ (transient.npy, transient.json, steady/before/after.npy)");
            // A film with phasor frequencies (--phasor): its exact phasors beside the volume.
            if (!cancel_ && film.phasor().active()) {
                exportPhasorNpy(film, dir, opt, provenanceOf(*driver, req.scenePath));
                wrote(dir + "/ (phasor.npy, phasor_rgb.npy, phasor.json)");
            }
        }
        if (req.contactSheet && !cancel_) {
            step("contact sheet");
            const std::string path = req.dir + "/" + contactSheetName(outputTag(req.axis, req.mode, req.response));
            exportContactSheet(film, path, req.sheetFrames, opt, req.tone);
            wrote(path);
            ++done_;
        }
        if (req.mp4 && !cancel_) {
            step("MP4");
            const std::string path = req.dir + "/" + mp4Name(outputTag(req.axis, req.mode, req.response));
            const int base = done_.load();
            if (exportMp4(
                    film, path, opt, req.tone, req.fps, [&](int d, int) { done_ = base + d; }, &cancel_) > 0)
                wrote(path);
        }
        if (cancel_) {
            // Everything asked for and not finished is named (a cancelled volume or MP4 leaves no file).
            const auto skipped = [&](bool asked, const std::string& name) {
                if (asked && std::find_if(written_.begin(), written_.end(), [&](const std::string& w) {
                                 return w.find(name) != std::string::npos;
                             }) == written_.end())
                    notWritten.push_back(name);
            };
            std::lock_guard<std::mutex> g(mutex_);
            skipped(req.volume, volumeDirName(outputTag(req.axis, req.mode, req.response)) + "/");
            skipped(req.contactSheet, contactSheetName(outputTag(req.axis, req.mode, req.response)));
            skipped(req.mp4, mp4Name(outputTag(req.axis, req.mode, req.response)));
            error_ = "export cancelled";
            for (size_t i = 0; i < notWritten.size(); ++i) error_ += (i ? ", " : "; not written: ") + notWritten[i];
        }
    } catch (const std::exception& e) {
        std::lock_guard<std::mutex> g(mutex_);
        error_ = e.what();
    }
    step("done");
    running_ = false;
}

bool ExportJob::collect() {
    if (running_.load() || !thread_.joinable()) return false;
    thread_.join();
    return true;
}

float ExportJob::progress() const {
    const int t = total_.load();
    return t > 0 ? static_cast<float>(done_.load()) / static_cast<float>(t) : 0.0f;
}

std::string ExportJob::progressLabel() const {
    std::lock_guard<std::mutex> g(mutex_);
    return stage_ + " " + std::to_string(done_.load()) + "/" + std::to_string(total_.load());
}

std::vector<std::string> ExportJob::written() const {
    std::lock_guard<std::mutex> g(mutex_);
    return written_;
}

std::string ExportJob::error() const {
    std::lock_guard<std::mutex> g(mutex_);
    return error_;
}

void ExportJob::cancelAndJoin() {
    cancel_ = true;
    if (thread_.joinable()) thread_.join();
}

}  // namespace tpb::app
