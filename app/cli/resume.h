// Checkpoints from the command line (render/checkpoint.h has the file and its guarantees):
// `tpb render --resume DIR` and `tpb view --resume DIR` find DIR's checkpoint, load the scene it
// was rendered from with the flags it was rendered with (resumeOverrides: the resuming command may
// change the pass count, time budget and threads, nothing else), refuse a render that differs from
// the checkpoint's, naming each change, and hand the restored film to the Driver.
#pragma once
#include "cli/common.h"
#include "render/checkpoint.h"

#include <string>

namespace tpb::app {

struct ResumeSource {
    std::string path;  // the checkpoint file
    CheckpointInfo info;
};
// DIR/checkpoint.tpbck, or DIR itself when it is a file. UserError naming the path and the fix.
ResumeSource findCheckpoint(const std::string& dirOrFile);

// Loads and prepares the render a checkpoint continues: `scene` ("" = the checkpoint's), the
// checkpoint's flags with `given` on top (resumeOverrides). Throws UserError listing every
// difference between this render and the checkpoint's (fingerprint.h).
PreparedRender prepareResume(const ResumeSource& src, const std::string& scene, const SettingsOverrides& given,
                             const LoadOptions& lo = {});

// Reads the whole checkpoint and restores it into `drv` (which runs the prepared render).
// Returns the passes restored.
uint64_t restoreCheckpoint(const ResumeSource& src, const PreparedRender& p, Driver& drv);

// Writes `drv`'s finished passes to `path` (only between passes, or after the run: the film's
// tiles must agree). UserError on failure (the previous checkpoint is kept).
void saveCheckpoint(const std::string& path, const PreparedRender& p, const SettingsOverrides& flags,
                    const Driver& drv);

}  // namespace tpb::app
