// Scene file loader: JSON (see README "Scene format") -> SceneDesc. Parse and validate only; no
// Embree or render state. Every error is a UserError "file:line: key: problem; allowed: ...".
#pragma once
#include "memory_budget.h"
#include "scene_desc.h"
#include <string>

namespace tpb {

// Reads and validates a scene file. Relative mesh paths are resolved against the file's folder.
SceneDesc loadScene(const std::string& path);
// Same, from text (for tests and tools); `virtualPath` names it in messages and sets the folder.
SceneDesc loadSceneFromString(const std::string& text, const std::string& virtualPath);
// The loader refuses films and photon counts above the memory budget (memory_budget.h).

}  // namespace tpb
