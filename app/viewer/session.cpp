// The viewer's render session (session.h): drivers, the steady preview, checkpoints, exports.
#include "viewer/session.h"

#include "base/error.h"
#include "io/folder_lock.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

namespace tpb::app {

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

ViewerSession::ViewerSession(const PreparedRender& prepared, const RenderSettings& settings,
                             const SettingsOverrides& flags, const std::string& resumePath, bool preview, Wake wake)
    : prepared_(prepared), time_(prepared.time), flags_(flags), wake_(std::move(wake)) {
    if (!resumePath.empty()) ownCheckpoints_.push_back(resumePath);  // "Save checkpoint" may replace it
    prepareJob_ = prepareDriver(scene(), settings, time_, resumePath);
    if (preview) {
        RenderSettings ps = settings;
        const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
        ps.threads = std::max(1, (settings.threads > 0 ? settings.threads : cores) - 1);  // a core for the allocation
        TimeBins one = time_;
        one.binWidth = time_.binWidth * time_.bins;
        one.bins = 1;
        preview_ = std::make_shared<Driver>(scene(), ps, one);
        preview_->start([w = wake_](const PassStats&) { w(); });
    }
}

ViewerSession::~ViewerSession() {
    export_.cancelAndJoin();
    if (checkpointJob_.valid()) checkpointJob_.wait();  // a checkpoint being written is finished, not cut
    if (preview_) preview_->stop();
    if (prepareJob_.valid()) prepareJob_.wait();  // closed while preparing: the film is dropped once made
    if (driver_) driver_->stop();
}

bool ViewerSession::filmReady() const {
    using namespace std::chrono_literals;
    return driver_ || (prepareJob_.valid() && prepareJob_.wait_for(0s) == std::future_status::ready);
}

uint64_t ViewerSession::adoptFirst() {
    if (preview_) preview_->requestStop();  // after its pass in progress: a complete picture
    PreparedDriver p = prepareJob_.get();
    const uint64_t resumed = p.resumedPasses;
    adopt(std::move(p));
    return resumed;
}

void ViewerSession::adopt(PreparedDriver p) {
    driver_ = std::move(p.driver);
    ++generation_;
    driver_->start([w = wake_](const PassStats&) { w(); });
}

void ViewerSession::restart(const RenderSettings& s) {
    if (checkpointStage_ == CheckpointStage::Writing) {  // finish it (it holds the old driver)
        checkpointJob_.wait();
        pollCheckpoint();
    }
    checkpointStage_ = CheckpointStage::Idle;
    preview_.reset();              // of the old settings
    if (driver_) driver_->stop();  // an export or a profile read may still hold the old one
    driver_.reset();               // before the new film is allocated: one film in memory, not two
    adopt(prepareDriver(scene(), s, time_, "").get());
}

std::shared_ptr<const FilmSnapshot> ViewerSession::shownSnapshot(bool steady) {
    if (preview_ && driver_->completedPasses() >= preview_->completedPasses()) preview_.reset();  // caught up
    return steady && preview_ ? preview_->snapshot() : driver_->snapshot();
}

uint64_t ViewerSession::shownPasses(bool steady) const {
    const uint64_t film = driver_->completedPasses();
    return steady && preview_ ? std::max(film, preview_->completedPasses()) : film;
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
    } catch (const UserError&) {}
    throw UserError(path, 0, "",
                    "holds " + what +
                        "; the viewer does not replace it: choose another folder in the Export "
                        "section, or continue that render with `tpb view --resume " +
                        std::filesystem::path(path).parent_path().string() + "`");
}

}  // namespace

void ViewerSession::requestCheckpoint(const std::string& folder) {
    if (checkpointStage_ != CheckpointStage::Idle) return;
    checkpointFolder_ = folder;
    checkpointWasPaused_ = driver_->paused();
    driver_->pause();  // between passes: the checkpoint is written once the pass in progress ends
    checkpointStage_ = CheckpointStage::WaitingForPassEnd;
    status_ = "checkpoint: waiting for the pass in progress to end";
}

void ViewerSession::abandonCheckpointWait() {
    if (checkpointStage_ != CheckpointStage::WaitingForPassEnd) return;
    std::fprintf(stderr, "error: checkpoint not written: the render stopped inside a pass\n");
    checkpointStage_ = CheckpointStage::Idle;
}

void ViewerSession::pollCheckpoint() {
    if (checkpointStage_ == CheckpointStage::WaitingForPassEnd) {
        const std::vector<PassStats> history = driver_->history();
        const auto snap = driver_->snapshot();
        const bool between =
            snap->minPasses() == snap->maxPasses() && snap->minPasses() == static_cast<int64_t>(history.size());
        if (!between) return;  // a pass is still being added (paused takes effect after it)
        const std::string path = (std::filesystem::path(checkpointFolder_) / kCheckpointFile).string();
        std::shared_ptr<FolderLock> lock;
        try {
            // The export folder's lock, as `tpb render` holds it on its output folder.
            lock = FolderLock::acquire(checkpointFolder_, "tpb view", "choose another folder in the Export section");
            refuseForeignCheckpoint(path, ownCheckpoints_);
        } catch (const std::exception& e) {
            status_ = std::string("checkpoint not written: ") + e.what();
            std::fprintf(stderr, "error: %s\n", status_.c_str());
            checkpointFailed_ = true;
            checkpointStage_ = CheckpointStage::Idle;
            if (!checkpointWasPaused_) driver_->resume();
            return;
        }
        const CheckpointInfo info = checkpointInfoFor(prepared_, driver_->settings(), flags_, history.size());
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
    const std::string path = (std::filesystem::path(checkpointFolder_) / kCheckpointFile).string();
    status_ = err.empty() ? "checkpoint of " + std::to_string(driver_->history().size()) + " passes written to " +
                                path + " (tpb render --resume " + checkpointFolder_ + ")"
                          : "checkpoint failed: " + err;
    if (err.empty())
        ownCheckpoints_.push_back(path);
    else
        checkpointFailed_ = true;
    std::fprintf(err.empty() ? stdout : stderr, "%s\n", status_.c_str());
    std::fflush(stdout);
    checkpointStage_ = CheckpointStage::Idle;
    if (!checkpointWasPaused_) driver_->resume();
    wake_();
}

void ViewerSession::startExport(const ExportRequest& req) {
    if (export_.busy()) {
        status_ = "an export is already running";
        return;
    }
    exportError_.clear();
    exportLog_.clear();
    export_.start(driver_, req);
}

void ViewerSession::pollExport() {
    if (!export_.collect()) return;
    exportLog_ = export_.written();
    exported_.insert(exported_.end(), exportLog_.begin(), exportLog_.end());
    exportError_ = export_.error();
    for (const std::string& w : exportLog_) std::printf("exported: %s\n", w.c_str());
    if (!exportError_.empty()) std::fprintf(stderr, "export failed: %s\n", exportError_.c_str());
    std::fflush(stdout);
}

}  // namespace tpb::app
