// Automatic film time range ("film": {"range": "auto"}): a pilot pass (photons of pass 0 and a
// sparse grid of camera pixels, rendered into a wide, fine histogram) measures when energy arrives,
// and the film is fitted from the earliest to the latest arrival that carries energy: the
// [0.05%, 98%] quantiles of the arrival-time distribution of the real and unwarped axes, padded.
#pragma once
#include "scene.h"

namespace tpb {

struct TimeRangeFit {
    double startOpl = 0.0, endOpl = 0.0;
    double heuristicStart = 0.0, heuristicEnd = 0.0;  // the scene-size bound it started from
    bool fromPilot = false;                           // false: no energy seen, heuristic kept
};

// Fits scene.time (keeping its number of bins) when the scene asks for an automatic range.
TimeRangeFit fitTimeRange(Scene& scene, int64_t pilotPhotons, int threads);

}  // namespace tpb
