// What makes two renders the same progressive sequence: a flat, ordered list of (key, value)
// strings describing everything that decides pass i's estimate (the scene as built, the settings
// that enter a pass, the film's shape and time axis). A checkpoint (checkpoint.h) stores it; a
// resume compares the stored list with the one of the run that wants to go on, and every key whose
// value differs is named in the refusal ("lights[0].power: the checkpoint has (1, 1, 1), this run
// (2, 2, 2)").
//
// Not in it, on purpose: the pass count and time budget (a resume renders more passes), threads
// (pass i does not depend on them: driver.h), the beam accelerator (every backend gives the same
// candidates once tested, hence the same films: accel/beam_accel.h), how the film is shown (emission mode, time axis
// shown, unwarping) and the photon-map memory cap (it refuses a pass, never changes one). Mesh
// files are in it by the FNV-1a 64 of their bytes, so an edited OBJ is seen; the scene file's own
// bytes are not (comments, key order and the render block's pass count may change).
#pragma once
#include "film/time_splat.h"
#include "integrators/render_settings.h"
#include "scene/scene_desc.h"

#include <string>
#include <utility>
#include <vector>

namespace tpb {

using Fingerprint = std::vector<std::pair<std::string, std::string>>;

// The scene as described (camera, film shape, media, materials, shapes, lights); the render block
// is left to settingsFingerprint (its values after the overrides are what count).
Fingerprint sceneFingerprint(const SceneDesc& desc);
// The settings that enter a pass (method, seed, photons, warm-up, radii, alpha, estimators, time
// kernel, max depth, time profile, beam length, path tracer's spp and sampling): those keys of
// settingsRecord (integrators/render_settings.h), each as "render.<key>".
Fingerprint settingsFingerprint(const RenderSettings& s);
// The film's time axis (bins, start, width: bit-exact, as %.17g).
Fingerprint timeFingerprint(const TimeBins& t);
// The phasor film's frequencies (film/phasor.h), as the list phasorListText writes; nothing without
// one. A checkpoint holds the phasor sums, so a resume must have the same.
Fingerprint phasorFingerprint(const PhasorSpec& p);
// "f1,f2,..." (cycles per m, shortest decimals): what --phasor reads back as the same list.
std::string phasorListText(const PhasorSpec& p);

// The current name of a fingerprint key: checkpoints written before the settings had one
// serialisation name some keys differently (render.photons, render.radius_m,
// render.surface_radius_m, render.estimator, render.spp); they still resume.
std::string currentFingerprintKey(const std::string& key);

// "key: the checkpoint has A, this run has B" for every key whose value differs, "key: only in the
// checkpoint (A)" / "key: only in this run (B)" for keys on one side. Empty = the same sequence.
std::vector<std::string> fingerprintChanges(const Fingerprint& checkpoint, const Fingerprint& now);

// FNV-1a 64 of a file's bytes as 16 hex digits, or "unreadable" when it cannot be read.
std::string fileFingerprint(const std::string& path);

}  // namespace tpb
