// Steady-state geometry preview ("eye light"): one ray per pixel, shaded by |cos| between the
// surface normal and the view ray times the material colour, seen through mirrors and glass.
// Lets a user check the camera and geometry before any photon is traced.
#pragma once
#include "scene/scene.h"

#include <vector>

namespace tpb {

std::vector<float> renderPreview(const Scene& scene, int threads = 0);

}  // namespace tpb
