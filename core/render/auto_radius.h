// The initial kernel radius from the scene's own photon density ("radius": "auto", --radius auto;
// issue 15): a pilot photon pass with the render's photons per pass measures how densely the
// photons fill the medium, and the radius is chosen so that a camera ray crossing the medium
// gathers about a fixed number of beams (or photon points) per pass, whatever the scene's size,
// medium or light. A fixed fraction of the scene diagonal gathers 100x more in a small dense
// medium than in a large thin one.
//
// Derivation (docs/theory/derivations.md, checked in tests/render/test_auto_radius.cpp). The photons of
// one pass, in the scattering medium that holds most of their beam length, clipped to the scene's
// bounds (an open scene in an unbounded medium loses photons to infinity), fill a box B (the bounds
// of the clipped beams) of volume V and surface area A:
//   beams: total length L, length density rho_L = L / V. For isotropic lines of length density
//     rho_L, the mean number that pass through a convex body K is rho_L * area(K) / 4 (Cauchy-Crofton:
//     the mean projected area of a convex body is a quarter of its surface). The kernel region of a
//     camera chord of length S is a cylinder of radius r around it, area ~ 2 pi r S, so a chord meets
//       N_beams = rho_L * pi r S / 2
//     beams. The mean chord of a convex body is S = 4 V / A (Cauchy), so N_beams = 2 pi r L / A and
//       r = N_target * A / (2 pi L).
//   points: n points in V; a cylinder of radius r around the chord holds N = (n / V) pi r^2 S =
//     4 pi r^2 n / A of them, so r = sqrt(N_target * A / (4 pi n)).
// The targets (kAutoBeamsPerRay, kAutoPointsPerRay) are quality knobs, not fitted to a scene: they
// sit in the middle of what the shipped scenes' hand-set radii gather (`tpb info` on scenes/*.json:
// 35-163 beams per ray for the beam2d scenes, 0.12-2.0 photon points for the point3d ones).
// No scattering medium, or photons that never enter one: no measurement, the default fraction of
// the diagonal stays (RadiusPilot::measured false, with the reason).
#pragma once
#include "integrators/render_settings.h"
#include "scene/scene.h"

#include <atomic>
#include <string>

namespace tpb {

inline constexpr double kAutoBeamsPerRay = 64.0;  // beams a camera chord through the medium gathers per pass
inline constexpr double kAutoPointsPerRay = 2.0;  // photon points (point2d, point3d)
// The pilot traces at most this many photons and scales what it measures to the render's photons
// per pass (lengths and counts grow linearly with the photons): the pilot stays cheap.
inline constexpr int64_t kAutoPilotPhotons = 4000;
inline constexpr uint64_t kAutoPilotMaxMapBytes = 64ull << 20;

struct RadiusPilot {
    bool measured = false;          // false: no beams in a scattering medium (why says so)
    std::string why;                // what was measured, or why nothing was
    int region = -1;                // the medium region measured
    int64_t photons = 0;            // traced by the pilot
    double scale = 1.0;             // the render's photons per pass / the pilot's
    int64_t beams = 0, points = 0;  // the pilot's, in that region
    double beamLength = 0.0;        // m, total, in that region, scaled to the render's photons per pass
    double boxVolume = 0.0;         // m^3 of the box bounding those beams
    double boxArea = 0.0;           // m^2
    double meanChord = 0.0;         // m, 4 V / A
    bool pointKernel = false;       // the estimator gathers photon points
    double target = 0.0;            // beams or points per camera chord
    double radius = 0.0;            // m, the chosen initial volume radius
    // What the given radius would gather per chord (N as above), for `tpb info`.
    double gathered(double r) const;
};

// Traces the pilot photon pass (pass 0 of the render's seed, min(settings.photonsPerPass,
// kAutoPilotPhotons) photons) and chooses the radius for settings.volumeEstimator. Polls `abort`.
// A pilot whose photon map outgrows the memory budget measures nothing (why says so).
RadiusPilot pilotRadius(const Scene& scene, const RenderSettings& settings, const std::atomic<bool>* abort = nullptr);

}  // namespace tpb
