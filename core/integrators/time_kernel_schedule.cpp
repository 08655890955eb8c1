#include "integrators/time_kernel_schedule.h"

#include "base/error.h"
#include "estimators/estimator.h"

#include <algorithm>

namespace tpb {

double defaultTimeKernelWidth(double radius1, double etaMax, double filmRangeOpl) {
    const double w = 2.0 * std::max(etaMax, 1.0) * radius1;
    return filmRangeOpl > 0.0 ? std::min(w, filmRangeOpl) : w;
}

double maxIndexOfRefraction(const Scene& scene, bool scatteringMediaOnly) {
    double eta = 1.0;
    for (const Region& r : scene.regions)
        if (!scatteringMediaOnly || (r.hasMedium && r.medium.scattering)) eta = std::max(eta, r.ior);
    return eta;
}

TimeKernelSchedule timeKernelSchedule(const Scene& scene, const RenderSettings& s, const TimeBins& time, int volumeDim,
                                      int surfaceDim) {
    const bool on = s.timeKernel.kind != TimeKernelKind::None;
    const double range = time.endOpl() - time.startOpl;
    const auto plan = [&](int dim, double r1, double etaMax) {
        TimeKernelPlan p;
        p.on = on;
        p.spatialDim = dim;
        p.radius1 = r1;
        p.alpha = s.alpha;
        if (on) {
            p.widthFromScene = !(s.timeKernel.width > 0.0);
            p.width1 = p.widthFromScene ? defaultTimeKernelWidth(r1, etaMax, range) : s.timeKernel.width;
        }
        return p;
    };
    TimeKernelSchedule k;
    k.volume = plan(volumeDim, s.beamRadius0, maxIndexOfRefraction(scene, true));
    k.surface = plan(surfaceDim, s.surfaceRadius0, maxIndexOfRefraction(scene, false));
    return k;
}

TimeKernelSchedule timeKernelSchedule(const Scene& scene, const RenderSettings& s, const TimeBins& time) {
    const std::unique_ptr<VolumeEstimator> v = makeVolumeEstimator(s.volumeEstimator);
    const std::unique_ptr<SurfaceEstimator> f = makeSurfaceEstimator(s.surfaceEstimator);
    if (!v) throw UserError("unknown volume estimator \"" + s.volumeEstimator + "\"");
    if (!f) throw UserError("unknown surface estimator \"" + s.surfaceEstimator + "\"");
    return timeKernelSchedule(scene, s, time, v->dim(), f->dim());
}

}  // namespace tpb
