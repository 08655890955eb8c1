// The viewer's render session, without a window (no GLFW, GL or ImGui): the Driver that renders
// in the background and its film, the steady preview run while the first film is allocated, the
// checkpoints "Save checkpoint" writes and the exports running on their own threads. The UI
// (app.h, Viewer) reads the film through it; `wake` is called from other threads when there is
// something new to show (a pass finished), so a window can sleep until then.
#pragma once
#include "render/checkpoint.h"
#include "render/driver.h"
#include "render/prepare.h"
#include "viewer/export.h"

#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

namespace tpb::app {

// A driver made off the UI thread (its film allocated, a checkpoint read into it), not started yet.
struct PreparedDriver {
    std::shared_ptr<Driver> driver;
    uint64_t resumedPasses = 0;  // from the checkpoint of `tpb view --resume` (0: none)
};
std::future<PreparedDriver> prepareDriver(const Scene& scene, const RenderSettings& s, const TimeBins& time,
                                          const std::string& resumePath);

class ViewerSession {
public:
    using Wake = std::function<void()>;
    // Starts preparing the first driver (its film is allocated on a helper thread: filmReady()),
    // and, with `preview`, the steady preview (preview_ below). `flags`: the overrides the render
    // runs with, recorded in the checkpoints it writes. `resumePath`: a checkpoint to go on from.
    ViewerSession(const PreparedRender& prepared, const RenderSettings& settings, const SettingsOverrides& flags,
                  const std::string& resumePath, bool preview, Wake wake);
    ~ViewerSession();  // finishes a checkpoint being written, cancels an export, stops the render
    ViewerSession(const ViewerSession&) = delete;
    ViewerSession& operator=(const ViewerSession&) = delete;

    const PreparedRender& prepared() const { return prepared_; }
    const Scene& scene() const { return *prepared_.scene; }
    const TimeBins& time() const { return time_; }

    // ---- the driver ----
    bool filmReady() const;  // the first driver is prepared (or adopted)
    // Waits for the first driver and starts it (the preview stops after its pass in progress);
    // returns the passes it resumed from a checkpoint.
    uint64_t adoptFirst();
    bool hasDriver() const { return static_cast<bool>(driver_); }
    Driver& driver() { return *driver_; }
    const Driver& driver() const { return *driver_; }
    const std::shared_ptr<Driver>& sharedDriver() const { return driver_; }
    // Counts the drivers: a restart makes a new one (its film starts empty).
    uint64_t generation() const { return generation_; }
    // A new driver with settings `s` (a checkpoint being written is finished first).
    void restart(const RenderSettings& s);

    // ---- the steady preview (issue 33 item 11) ----
    // The same passes into a one-bin film, run while the first film is allocated: its steady image
    // is the film's after as many passes (TransientBeams.SteadyImageDoesNotDependOnTheBins). Shown
    // until the film has caught up, then dropped. Null when there is none (any more).
    const Driver* preview() const { return preview_.get(); }
    // The snapshot a picture is read from: the preview's for the steady image while it is ahead.
    std::shared_ptr<const FilmSnapshot> shownSnapshot(bool steady);
    uint64_t shownPasses(bool steady) const;

    // ---- checkpoints ("Save checkpoint") ----
    enum class CheckpointStage { Idle, WaitingForPassEnd, Writing };
    // Pauses between passes, then writes <folder>/checkpoint.tpbck on a helper thread (pollCheckpoint).
    void requestCheckpoint(const std::string& folder);
    void pollCheckpoint();  // advances the stages; call often
    CheckpointStage checkpointStage() const { return checkpointStage_; }
    bool checkpointFailed() const { return checkpointFailed_; }  // one was refused or failed
    // Closing: the render stopped inside the pass the checkpoint waited for (it cannot be written).
    void abandonCheckpointWait();

    // ---- exports (their files, progress and errors) ----
    void startExport(const ExportRequest& req);
    void pollExport();  // collects a finished export (printed on stdout/stderr)
    ExportJob& exportJob() { return export_; }
    const std::vector<std::string>& exportLog() const { return exportLog_; }  // the last export's files
    const std::vector<std::string>& exported() const { return exported_; }    // every file of the session
    const std::string& exportError() const { return exportError_; }

    // The last thing the session has to say (a checkpoint written, a restart's reason...).
    const std::string& status() const { return status_; }
    void setStatus(std::string s) { status_ = std::move(s); }

private:
    void adopt(PreparedDriver p);

    const PreparedRender& prepared_;
    TimeBins time_;
    SettingsOverrides flags_;
    Wake wake_;
    std::shared_ptr<Driver> driver_;          // null until the first one is adopted
    std::future<PreparedDriver> prepareJob_;  // the first driver, made while the window shows
    std::shared_ptr<Driver> preview_;
    uint64_t generation_ = 0;
    std::string status_;

    // The checkpoints this session resumed from or wrote: the only ones "Save checkpoint"
    // overwrites (another render's checkpoint in the folder is refused, never replaced silently).
    std::vector<std::string> ownCheckpoints_;
    CheckpointStage checkpointStage_ = CheckpointStage::Idle;
    std::string checkpointFolder_;
    bool checkpointWasPaused_ = false;
    bool checkpointFailed_ = false;
    std::future<std::string> checkpointJob_;  // "" or the error

    ExportJob export_;
    std::vector<std::string> exportLog_, exported_;
    std::string exportError_;
};

}  // namespace tpb::app
