// Automatic film time range ("film": {"range": "auto"}): a pilot pass (photons of pass 0 and a
// sparse grid of camera pixels, rendered into a wide, fine histogram) measures when energy arrives,
// and the film is fitted from the earliest to the latest arrival that carries energy: the
// [0.05%, 98%] quantiles of the arrival-time distribution of the real and unwarped axes, padded.
//
// The pilot's kernels are generous (low noise) but capped at kPilotMaxRadiusFraction of the scene's
// diagonal, whatever the render's radius: its cost stays that of an ordinary pass (a radius of the
// order of the diagonal made it rays x beams, minutes without output). It polls an abort flag
// (Ctrl-C, SIGTERM) and reports its progress.
#pragma once
#include "scene/scene.h"

#include <atomic>
#include <functional>

namespace tpb {

inline constexpr double kPilotMaxRadiusFraction = 0.05;

struct TimeRangeFit {
    double startOpl = 0.0, endOpl = 0.0;
    double heuristicStart = 0.0, heuristicEnd = 0.0;  // the scene-size bound it started from
    bool fromPilot = false;                           // false: no energy seen, heuristic kept
    bool interrupted = false;                         // the abort flag stopped the pilot: nothing fitted
};

struct PilotControl {
    const std::atomic<bool>* abort = nullptr;          // stops the pilot at its next check
    std::function<void(double fraction)> progress;     // 0..1, called on the calling thread only
};

// Measures the arrival-time range of the energy reaching the camera with a pilot pass, without
// changing the scene (also for scenes with an explicit range: what range would cover them).
TimeRangeFit measureArrivalRange(const Scene& scene, int64_t pilotPhotons, int threads,
                                 const PilotControl& control = {});

// Fits scene.time (keeping its number of bins) when the scene asks for an automatic range.
TimeRangeFit fitTimeRange(Scene& scene, int64_t pilotPhotons, int threads, const PilotControl& control = {});

}  // namespace tpb
