// Camera pass of Transient Photon Beams (paper Sec. 4): camera paths through specular surfaces,
// the volume estimator (by default the 2D beam kernel, estimators/beam2d.h) on every segment inside a
// scattering medium, the surface estimator (transient progressive photon mapping,
// estimators/surface_ppm.h) on the diffuse hit, visible emitters; every estimate is spread over
// the time bins it covers (eqs. 12-15, time_splat.h) on both time axes.
#pragma once
#include "estimators/estimator.h"
#include "film/transient_film.h"
#include "photons/photon_tracer.h"
#include "scene/scene.h"

namespace tpb {

// The arguments of one camera pass (filled by the photon-beams integrator from RenderSettings and
// the pass index; the kernel radii and time profile belong to the estimators: EstimatorPass).
struct CameraPassParams {
    uint64_t seed = 1;
    uint64_t pass = 1;
    int maxDepth = 16;
    int bundleBlock = 1;       // primary segments share queries over blocks this wide (planBundles; 1: off)
    bool emittersSeen = true;  // false: the bounce filter leaves out emitters seen directly (0 events)
};

// The estimators a camera path asks (either may be null: that stage is off for the scene).
// With each its time kernel of this pass (film/time_kernel.h; None: off), which the camera
// pass puts in the PixelSink it hands that estimator.
struct CameraPassEstimators {
    const VolumeEstimator* volume = nullptr;
    const SurfaceEstimator* surface = nullptr;
    TimeKernel volumeKernel, surfaceKernel;
};

struct CameraPassStats : FilmTally {
    int64_t cameraRays = 0;
    int64_t beamEstimates = 0;
    int64_t photonEstimates = 0;
    int64_t regionOverflows = 0;  // camera paths ended because their region stack was full (RegionStack)
    CameraPassStats& operator+=(const CameraPassStats& o);
};

// Per-thread scratch space.
struct CameraPassScratch {
    PixelAccumulator acc;
    EstimatorScratch estimator;
};

// Renders one pixel's estimate for this pass into `scratch.acc` (no film access).
void renderPixel(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, const TimeBins& time,
                 int x, int y, CameraPassScratch& scratch, CameraPassStats& stats);

// Primary camera segments may be gathered in blocks of pixels that share one accelerator query
// (estimators/segment_bundle.h); the pixels and so the films are the same either way.

// What the camera pass tells the estimators about the block [x0, x0 + w) x [y0, y0 + h) of raster
// positions: the axis through its centre, the sine of the widest angle to a ray through it (its
// corners: a cone meets the image plane in an ellipse, convex), the camera's region and the
// farthest a primary segment can go (the scene's bounds seen from the camera).
BundleHint bundleHint(const Scene& scene, int x0, int y0, int w, int h);

// The slack (m) an estimator that shares queries over blocks `block` pixels wide builds its
// accelerator for: the centre block's (the widest) cone at the far end of the scene, so that every
// primary segment is contained (segment_bundle.h); 0 when the camera's region does not scatter (no
// primary segment is gathered).
double bundleSlack(const Scene& scene, int block);

// How this pass's primary segments share queries: blocks `block` pixels wide, the accelerator
// padded by `slack` (m). Block 1, slack 0: each segment takes its own query.
struct BundlePlan {
    int block = 1;
    double slack = 0.0;
};

// A shared query returns the pieces within r + slack of the block's axis, and each of the block's
// segments tests all of them: it pays while the slack is small against the radius r. Measured with
// `tpb bench scenes/cornell_medium.json --estimator beam2d --bins-list 1` over 24..512 pixels
// (docs/measurements/history.md "segment bundles"): blocks of 4 win at slack/r 1.2-2.6 (1.25-2x faster passes), lose at 4.6 and beyond
// (1.2x slower at 4.6, 2.6x at 12, 3.4x at 300).
constexpr double kMaxBundleSlackRadii = 3.0;

// The widest block (4, else 2) whose slack is at most kMaxBundleSlackRadii radii; else no bundles.
BundlePlan planBundles(const Scene& scene, double radius);

// Renders the pixels of `r` through `writer`, block by block.
void renderPixels(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, const TimeBins& time,
                  const TileRect& r, TransientFilm::TileWriter& writer, CameraPassScratch& scratch,
                  CameraPassStats& stats);

// Renders the pixels of `tile` into the film (the film's TileWriter locks that tile): for tools and
// tests; the Driver runs the photon beams integrator (integrators/photon_beams.h) instead.
void renderTile(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, TransientFilm& film,
                int tile, CameraPassScratch& scratch, CameraPassStats& stats);

}  // namespace tpb
