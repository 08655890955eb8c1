// Camera pass of Transient Photon Beams (paper Sec. 4): camera paths through specular surfaces,
// the 2D-kernel beam estimate (eq. 8, closed form in beam_kernel.h) on every medium segment,
// transient progressive photon mapping on the diffuse hit, visible emitters; every estimate is
// spread over the time bins it covers (eqs. 12-15, time_splat.h) on both time axes.
#pragma once
#include "accel/beam_accel.h"
#include "film/transient_film.h"
#include "accel/photon_grid.h"
#include "photons/photon_tracer.h"
#include "scene/scene.h"

namespace tpb {

struct CameraPassSettings {
    uint64_t seed = 1;
    uint64_t pass = 1;
    double beamRadius = 0.01;     // m, this pass
    double surfaceRadius = 0.02;  // m, this pass
    TimeProfile profile = TimeProfile::Exact;
    BeamLength beamLength = BeamLength::Short;
    int maxDepth = 16;
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
    std::vector<BeamHit> hits;
    std::vector<int> nearShapes;  // shapes near the current camera segment (beam visibility)
};

// Renders the pixels of `tile` into the film (the film's TileWriter locks that tile).
void renderTile(const Scene& scene, const PhotonMap& map, const BeamAccel* beams, const PhotonGrid* grid,
                const CameraPassSettings& s, TransientFilm& film, int tile, CameraPassScratch& scratch,
                CameraPassStats& stats);

// Renders one pixel's estimate for this pass into `acc` (no film access; used by tests too).
void renderPixel(const Scene& scene, const PhotonMap& map, const BeamAccel* beams, const PhotonGrid* grid,
                 const CameraPassSettings& s, const TimeBins& time, int x, int y, CameraPassScratch& scratch,
                 CameraPassStats& stats);

}  // namespace tpb
