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
};

// The estimators a camera path asks (either may be null: that stage is off for the scene).
// With each its time kernel of this pass (estimators/time_kernel.h; None: off), which the camera
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

// Renders the pixels of `tile` into the film (the film's TileWriter locks that tile): for tools and
// tests; the Driver runs the photon beams integrator (integrators/photon_beams.h) instead.
void renderTile(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, TransientFilm& film,
                int tile, CameraPassScratch& scratch, CameraPassStats& stats);

}  // namespace tpb
