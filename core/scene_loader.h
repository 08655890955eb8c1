// Scene file loader: JSON (see README "Scene format") -> SceneDesc. Parse and validate only; no
// Embree or render state. Every error is a UserError "file:line: key: problem; allowed: ...".
#pragma once
#include "scene_desc.h"
#include <string>

namespace tpb {

// Reads and validates a scene file. Relative mesh paths are resolved against the file's folder.
SceneDesc loadScene(const std::string& path);
// Same, from text (for tests and tools); `virtualPath` names it in messages and sets the folder.
SceneDesc loadSceneFromString(const std::string& text, const std::string& virtualPath);

// Memory the transient film of `desc` will need, in bytes (both time axes, RGB, plus the
// steady-state images). The loader refuses films above `maxFilmBytes()`.
uint64_t filmBytes(const CameraDesc& cam, int bins);
uint64_t maxFilmBytes();  // default: 75% of physical memory; env TPB_MAX_FILM_BYTES overrides
// Rough memory of one pass's photon map (~4 beam segments per photon, as `tpb info` prints). The
// loader and --photons refuse photon counts whose map alone would exceed maxFilmBytes().
uint64_t photonMapBytes(int64_t photonsPerPass);

}  // namespace tpb
