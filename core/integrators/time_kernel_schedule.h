// The schedule of the progressive time kernel of the photon-beams estimators (issue 14; Marco et
// al. 2019; the derivation: docs/theory/derivations.md "Progressive time kernel"). Per estimator (the
// volume and the surface estimator have their own radius, dimension and so schedule):
//   off:  r_i = progressiveRadius(r_1, alpha, i, d)                       (d = the estimator's dim())
//   on:   r_i = progressiveRadius(r_1, alpha, i, D), tau_i = progressiveRadius(tau_1, alpha, i, D),
//         D = d + 1: the space-time kernel's measure r^d tau shrinks by (i + alpha) / (i + 1).
// tau_1 = width / 2 with width = RenderSettings::timeKernel.width, or when that is 0 the scene's
// default (defaultTimeKernelWidth): the OPL light takes to cross the pass-1 kernel, 2 eta_max r_1.
#pragma once
#include "base/progressive.h"
#include "film/time_kernel.h"
#include "integrators/render_settings.h"
#include "scene/scene.h"

namespace tpb {

// The default full width (m of OPL) of an estimator's time kernel at pass 1: 2 eta_max r_1, the
// optical path light takes to cross the pass-1 spatial kernel (diameter 2 r_1 in a medium of index
// eta_max), at most the film's time range. Rationale (docs/theory/derivations.md): photons that the spatial kernel
// gathers at x arrived from points within r of x, so their arrival times already scatter by up to
// +-eta r around x's; a time kernel of that half-width balances the time blur with the spatial blur
// (bias r^2 ~ tau^2 with tau = eta r) and does not tie the kernel to the film's bins (where the bins
// are wider than this the kernel barely matters, which is right: there the bins do the smoothing).
double defaultTimeKernelWidth(double radius1, double etaMax, double filmRangeOpl);

// The largest index of refraction of the regions an estimator's light crosses: the scattering
// media (volume estimator) or every region (surface estimator: a diffuse surface may sit in glass).
double maxIndexOfRefraction(const Scene& scene, bool scatteringMediaOnly);

// One estimator's schedule.
struct TimeKernelPlan {
    bool on = false;
    int spatialDim = 2;
    double radius1 = 0.0;         // m, the spatial kernel of pass 1
    double width1 = 0.0;          // m of OPL, full width of the time kernel at pass 1 (0 when off)
    bool widthFromScene = false;  // width1 is defaultTimeKernelWidth (RenderSettings width 0)
    double alpha = 0.7;
    int dim() const { return scheduleDimension(spatialDim, on); }  // D of the schedule
    double radius(uint64_t pass) const { return progressiveRadius(radius1, alpha, pass, dim()); }
    TimeKernel kernel(uint64_t pass) const {
        if (!on) return {};
        return {TimeKernelKind::Box, progressiveTimeHalfWidth(0.5 * width1, alpha, pass, dim())};
    }
};

struct TimeKernelSchedule {
    TimeKernelPlan volume, surface;
};

// The schedules of the two estimators of `settings` (by their names; a name the registry does not
// know throws UserError), for the film's time axis.
TimeKernelSchedule timeKernelSchedule(const Scene& scene, const RenderSettings& settings, const TimeBins& time);
// Same, with the estimators' spatial dimensions given.
TimeKernelSchedule timeKernelSchedule(const Scene& scene, const RenderSettings& settings, const TimeBins& time,
                                      int volumeDim, int surfaceDim);

}  // namespace tpb
