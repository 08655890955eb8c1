#include "cli/resume.h"

#include "base/error.h"

#include <filesystem>

namespace tpb::app {

namespace fs = std::filesystem;

ResumeSource findCheckpoint(const std::string& dirOrFile) {
    ResumeSource s;
    std::error_code ec;
    s.path = fs::is_directory(dirOrFile, ec) ? (fs::path(dirOrFile) / kCheckpointFile).string() : dirOrFile;
    if (!fs::exists(s.path, ec))
        throw UserError("--resume " + dirOrFile + ": no checkpoint " + s.path +
                        " (a render writes one with --checkpoint or --checkpoint-every, and when Ctrl-C or SIGTERM "
                        "stops it); give the output folder of such a render");
    s.info = readCheckpointInfo(s.path);
    return s;
}

PreparedRender prepareResume(const ResumeSource& src, const std::string& scene, const SettingsOverrides& given,
                             const LoadOptions& lo) {
    const std::string path = scene.empty() ? src.info.scene : scene;
    std::error_code ec;
    if (!fs::exists(path, ec))
        throw UserError(src.path + ": the scene it was rendered from, " + path +
                        ", is not there any more: give its new path (tpb render SCENE --resume DIR)");
    PreparedRender p = loadAndBuild(path, resumeOverrides(src.info.overrides, given), lo);
    const std::vector<std::string> changes = fingerprintChanges(src.info.fingerprint, renderFingerprint(p));
    if (!changes.empty()) {
        std::string msg = "cannot resume " + src.path + " (" + std::to_string(src.info.passes) + " passes of " +
                          src.info.scene + "): this render differs from the checkpoint's:";
        const size_t shown = std::min<size_t>(changes.size(), 12);
        for (size_t i = 0; i < shown; ++i) msg += "\n  " + changes[i];
        if (shown < changes.size()) msg += "\n  ... and " + std::to_string(changes.size() - shown) + " more";
        msg += "\nundo the change to resume, or render the changed scene anew (without --resume)";
        throw UserError(msg);
    }
    return p;
}

uint64_t restoreCheckpoint(const ResumeSource& src, const PreparedRender& p, Driver& drv) {
    Checkpoint c = readCheckpoint(src.path, &drv.film());  // into the driver's film: one film in memory
    // The file may have been replaced since its header was read (a render still writing into the
    // folder cannot: the folder is locked): check again.
    const std::vector<std::string> changes = fingerprintChanges(c.info.fingerprint, renderFingerprint(p));
    if (!changes.empty()) throw UserError(src.path + ": changed while being resumed (" + changes.front() + ")");
    if (c.history.size() != c.info.passes)
        throw UserError(src.path + ": not a usable tpb checkpoint: " + std::to_string(c.history.size()) +
                        " passes in its history, " + std::to_string(c.info.passes) + " in its film");
    const uint64_t passes = c.info.passes;
    drv.restore(nullptr, std::move(c.history));
    return passes;
}

void saveCheckpoint(const std::string& path, const PreparedRender& p, const SettingsOverrides& flags,
                    const Driver& drv) {
    const std::vector<PassStats> history = drv.history();
    writeCheckpoint(path, checkpointInfoFor(p, drv.settings(), flags, history.size()), drv.film(), history);
}

}  // namespace tpb::app
