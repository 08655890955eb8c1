// Progressive transient photon beams (Marco, Jarosz, Gutierrez, Jarabo 2017), as an Integrator.
// Pass i (paper Sec. 4, Fig. 2):
//   beginPass  photon pass: photons traced from the lights, keyed by (seed, i, photon); every path
//              segment inside a scattering medium stored as a beam with its start time (OPL, eq. 11),
//              every diffuse landing as a surface photon (photons/photon_tracer.h); then the beam
//              accelerator and the surface-photon grid built for this pass's kernel radii;
//   renderTile camera pass (integrators/camera_pass.h): camera paths through specular surfaces, the
//              2D-kernel beam estimate on every medium segment (eq. 8), the surface photon estimate
//              on the diffuse hit, each spread over the time bins it covers (eqs. 12-15);
//   endPass    the counters.
// The kernel radii shrink pass after pass (Knaus & Zwicker 2011; base/progressive.h): each
// estimator (estimators/estimator.h, chosen by name in the settings) gives the dimension of its
// kernel to the schedule (the 2D beam kernel and the surface kernel are both 2D: their area shrinks
// by (i + alpha) / (i + 1) per pass).
// With the optional progressive time kernel (RenderSettings::timeKernel, film/time_kernel.h)
// each estimator's estimates are also smoothed along time by a box whose half-width shrinks with its
// radius, and both follow the schedule of dimension dim() + 1 (integrators/time_kernel_schedule.h).
// Only the stages the scene needs run (Scene::stages: no beams without a scattering medium that
// photons reach, no surface photons without a diffuse surface).
#pragma once
#include "estimators/estimator.h"
#include "integrators/camera_pass.h"
#include "integrators/integrator.h"
#include "integrators/time_kernel_schedule.h"
#include "photons/photon_tracer.h"

#include <memory>
#include <vector>

namespace tpb {

// The photon pass of pass `pass` (1-based; the pilots' probe passes are pass 0) for these settings
// and a volume estimator that reads `needs`: the one place its parameters are filled. `threads`:
// the workers that trace; `filmEndOpl`: the film's end (0 before the film exists).
PhotonPassParams photonPassFor(const Scene& scene, const RenderSettings& s, const VolumeEstimator::Needs& needs,
                               uint64_t pass, int threads, double filmEndOpl = 0.0);

class PhotonBeamsIntegrator final : public Integrator {
public:
    PhotonBeamsIntegrator(const Scene& scene, const RenderSettings& settings);
    Method method() const override { return Method::Beams; }
    bool beginPass(const PassContext& ctx, PassStats& stats) override;
    void renderTile(const PassContext& ctx, int tile, const TileRect& rect, TransientFilm::TileWriter& writer,
                    int thread) override;
    void endPass(const PassContext& ctx, PassStats& stats) override;
    bool beginProbe(const PassContext& ctx, const ProbeRequest& request) override;
    const PixelAccumulator* probePixel(const PassContext& ctx, int x, int y, int thread) override;
    const PhotonMap* probeMap() const override { return &map_; }

    // Kernel radii of pass `pass` (m), from the estimators' kernel dimensions.
    double beamRadius(uint64_t pass) const;
    double surfaceRadius(uint64_t pass) const;
    // The estimators' time-kernel schedules on the film's time axis (off unless settings.timeKernel).
    TimeKernelSchedule timeKernels(const TimeBins& time) const;
    bool timeKernelOn() const { return settings_.timeKernel.kind != TimeKernelKind::None; }
    // The photon map of the pass in progress (for tools and tests).
    const PhotonMap& photonMap() const { return map_; }

private:
    // The photon pass `pt` into map_, its counts added to `ps`; false when aborted.
    bool photonPass(const PassContext& ctx, const PhotonPassParams& pt, PassStats& ps);
    // The estimators' accelerators over map_ for this pass's kernels.
    void prepareEstimators(const PassContext& ctx, const PhotonPassParams& pt, const TimeKernel& volumeKernel,
                           const TimeKernel& surfaceKernel, PassStats& ps);
    // A relay wall's scan: every laser point's photon pass and pixels, staged in scanTiles_.
    bool scanPass(const PassContext& ctx, PhotonPassParams pt, const TimeKernel& volumeKernel,
                  const TimeKernel& surfaceKernel, PassStats& ps);

    const Scene& scene_;
    RenderSettings settings_;
    PhotonMap map_;
    PhotonTracer tracer_;                        // its batch buffers kept from pass to pass
    std::unique_ptr<VolumeEstimator> volume_;    // settings.volumeEstimator, kept across passes
    std::unique_ptr<SurfaceEstimator> surface_;  // settings.surfaceEstimator
    CameraPassEstimators estimators_;            // this pass's (null: stage off or nothing to gather)
    CameraPassParams camera_;
    std::vector<CameraPassScratch> scratch_;  // per thread
    std::vector<CameraPassStats> tileStats_;  // per tile, summed in tile order
    std::vector<TileStaging> scanTiles_;      // a scan's pass, per tile, until the tiles run
};

}  // namespace tpb
