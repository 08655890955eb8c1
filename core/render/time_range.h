// The film's time axis, decided once before the film exists (filmTimeAxis): the explicit range of
// the scene's "film" block, or for "range": "auto" a heuristic window from the scene's size,
// refined by a pilot pass.
//
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
#include "film/time_splat.h"
#include "integrators/render_settings.h"
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
    const std::atomic<bool>* abort = nullptr;       // stops the pilot at its next check
    std::function<void(double fraction)> progress;  // 0..1, called on the calling thread only
};

// A window of optical path lengths (m).
struct OplRange {
    double startOpl = 0.0, endOpl = 0.0;
};

// Earliest/latest useful OPL from the scene's size alone: the lights' pulse to the scene and back
// to the camera, with a few bounces (the window "range": "auto" starts from).
OplRange autoTimeRange(const Scene& scene);

// Measures the arrival-time range of the energy reaching the camera with a pilot pass (also for
// scenes with an explicit range: what range would cover them). It reads the seed, max depth, beam
// length, radii and threads of `settings`.
TimeRangeFit measureArrivalRange(const Scene& scene, const RenderSettings& settings, int64_t pilotPhotons,
                                 const PilotControl& control = {});

struct PilotOptions {
    bool run = true;         // false: "range": "auto" keeps the heuristic window (tests, tools)
    int64_t photons = 4000;  // photons of the pilot pass
    PilotControl control;
};

struct FilmTimeAxis {
    TimeBins time;     // the film's axis (film.bins bins)
    TimeRangeFit fit;  // what the pilot measured (the heuristic window when it did not run)
};

// The film's time axis: the explicit range of `film`, or for film.autoRange the heuristic window
// refined by the pilot (when pilot.run; the pilot's settings are `pilotSettings`). An interrupted
// pilot leaves the heuristic window (fit.interrupted is set: the caller decides).
FilmTimeAxis filmTimeAxis(const Scene& scene, const FilmDesc& film, const RenderSettings& pilotSettings,
                          const PilotOptions& pilot = {});

}  // namespace tpb
