// Scene file loader: JSON (see docs/user/scenes.md "Scene format") -> SceneDesc. Parse and validate only; no
// Embree or render state. Every error is a UserError "file:line: key: problem; allowed: ...".
#pragma once
#include "base/memory.h"
#include "film/film_bytes.h"
#include "scene/scene_desc.h"
#include <cstdint>
#include <string>

namespace tpb {

// Reads and validates a scene file. Relative mesh paths are resolved against the file's folder.
// A ".xml" file, or a file whose first non-blank character is "<" (XML under another name), is read
// as a Mitsuba 3 scene (scene/mitsuba_loader.h), anything else as JSON.
SceneDesc loadScene(const std::string& path);
// Same, from text (for tests and tools); `virtualPath` names it in messages and sets the folder.
SceneDesc loadSceneFromString(const std::string& text, const std::string& virtualPath);
// The loader refuses films and photon counts above the memory limit (base/memory.h).

// The whole text of a scene file (JSON, Mitsuba XML and its includes), read only if it is a
// regular file of at most kMaxSceneFileBytes: a device (/dev/zero), a FIFO or a folder would be
// read forever or not at all, and a huge file would fill memory before any check. UserError
// (file `path`, line 0) naming what it is, its size, and the fix. `what`: "scene file", ...
inline constexpr uint64_t kMaxSceneFileBytes = uint64_t(256) << 20;
std::string readSceneFile(const std::string& path, const std::string& what = "scene file");

}  // namespace tpb
