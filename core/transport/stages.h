// Which stages a scene needs (Scene::stages): photon beams where a region scatters, the surface
// photon map where the camera sees a diffuse surface (directly or through mirrors and glass),
// specular chains, visible emitters. Passed to Scene::build (scene.h), which cannot trace
// through surfaces itself (the transport floor is above it).
#pragma once
#include "scene/scene.h"

namespace tpb {

Stages analyzeStages(const Scene& s);

}  // namespace tpb
