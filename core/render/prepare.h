// The one preparation step of a render, shared by the CLI, the viewer and the tests:
// scene description (+ overrides) -> film shape -> Scene (immutable) -> RenderSettings (validated)
// -> the film's time axis (the pilot, for "range": "auto"). What later messages need from the
// description (the scene path, where each key was written) is kept beside the scene in a
// SceneSource; nothing reads the description after this step.
#pragma once
#include "render/auto_radius.h"
#include "render/fingerprint.h"
#include "integrators/render_settings.h"
#include "render/time_range.h"
#include "scene/scene.h"
#include "scene/scene_desc.h"

#include <functional>
#include <map>
#include <memory>
#include <string>

namespace tpb {

// Where a scene came from, for messages after the build.
struct SceneSource {
    std::string path;                       // the scene file ("" or a virtual name for text)
    int version = 1;                        // of the scene format
    std::map<std::string, SourceLoc> locs;  // key path -> where it was written
    // "file:line: " for a key path, or "file: " when the key was not written (SceneDesc::where).
    std::string where(const std::string& keyPath) const;
    // "file:line: key" (no trailing ": "), for messages that go on with ": ...".
    std::string keyWhere(const std::string& keyPath) const;
    bool wrote(const std::string& keyPath) const { return locs.count(keyPath) > 0; }
};

struct PreparedRender {
    std::unique_ptr<const Scene> scene;
    RenderSettings settings;       // the file's render block + the overrides, validated
    RenderSettings pilotSettings;  // what the pilot ran with: the file's values, --max-depth, --threads
    FilmDesc film;                 // the film as described (autoRange: whether the pilot fits it)
    TimeBins time;                 // the film's time axis
    TimeRangeFit fit;              // what the pilot measured (heuristic window when it did not run)
    RadiusPilot radiusPilot;       // "radius": "auto" / --auto-radius: what chose the radius (else not measured)
    SceneSource source;
    Fingerprint sceneFingerprint;  // the description after the film-shape overrides (fingerprint.h)
};

// Everything that decides the passes of this render: scene, settings, time axis (fingerprint.h).
Fingerprint renderFingerprint(const PreparedRender& p);

struct PrepareOptions {
    PilotOptions pilot;  // run (default), photons, abort flag and progress
    // Each warning (the loader's, then validate()'s) as soon as it is known; none when empty.
    std::function<void(const std::string&)> warn;
};

// Applies the film-shape overrides (width, height, bins: the bins keep the film's time range) to
// the description, refusing a film beyond the memory limit (base/memory.h).
void applyFilmShape(SceneDesc& desc, const SettingsOverrides& overrides);

// Loads nothing: takes the description (loadScene), applies the overrides, builds the scene,
// validates the settings against its diagonal and decides the film's time axis (running the pilot
// for "range": "auto" when options.pilot.run). Throws UserError for a bad value; an interrupted
// pilot returns with fit.interrupted set (the caller decides what to do).
PreparedRender prepareRender(SceneDesc desc, const SettingsOverrides& overrides = {},
                             const PrepareOptions& options = {});

}  // namespace tpb
