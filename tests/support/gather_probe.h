// One volume estimate, outside the camera pass: prepare an estimator on a hand-built photon map and
// gather it along one camera segment into a pixel accumulator (tests/estimators/test_point*.cpp).
#pragma once
#include "estimators/estimator.h"

#include <vector>

namespace tpb::test {

struct GatherResult {
    int64_t estimates = 0;
    Color steady{0.0};
    std::vector<Color> bins[2];  // per axis (TimeAxis), the film's bins
    Color before[2], after[2];
    FilmTally tally;
    Color binsTotal(TimeAxis a) const {
        Color s(0.0);
        for (const Color& c : bins[static_cast<int>(a)]) s += c;
        return s;
    }
};

struct GatherSetup {
    double radius = 0.05;
    AccelBackend accel = AccelBackend::Embree;
    TimeProfile profile = TimeProfile::Exact;
    PathState path;
};

inline GatherResult gatherOnce(VolumeEstimator& est, const Scene& scene, const PhotonMap& map, const CameraSegment& seg,
                               const TimeBins& time, const GatherSetup& g) {
    EstimatorPass ep;
    ep.radius = g.radius;
    ep.accel = g.accel;
    ep.profile = g.profile;
    est.prepare(scene, map, ep);
    PixelAccumulator acc(time.bins);
    GatherResult r;
    PixelSink sink{time, acc, r.tally};
    EstimatorScratch scratch;
    if (!est.empty()) r.estimates = est.gather(seg, g.path, sink, scratch);
    r.steady = acc.steady();
    for (TimeAxis a : {TimeAxis::Real, TimeAxis::Unwarped}) {
        const int ai = static_cast<int>(a);
        r.bins[ai].assign(static_cast<size_t>(time.bins), Color(0.0));
        for (int k = 0; k < time.bins; ++k) {
            const double* b = acc.bin(a, k);
            r.bins[ai][static_cast<size_t>(k)] = Color(b[0], b[1], b[2]);
        }
        r.before[ai] = acc.before(a);
        r.after[ai] = acc.after(a);
    }
    return r;
}

}  // namespace tpb::test
