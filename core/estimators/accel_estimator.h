// What every kernel estimator over a BeamAccel keeps from one pass to the next (beam1d, beam2d:
// over the beams; point2d, point3d: over the photon points): the pass's scene, photon map and
// settings, and the accelerator, rebuilt each pass for the pass's radius and kept so its buffers
// are reused (re-created only when the backend changes).
#pragma once
#include "estimators/estimator.h"

#include <memory>

namespace tpb {

class AccelVolumeEstimator : public VolumeEstimator {
public:
    bool empty() const override { return !ready_; }
    size_t accelPrimitives() const override { return ready_ ? accel_->pieceCount() : 0; }

protected:
    // Keeps scene, map and pass; builds the accelerator over `items` (map.beams or map.points) with
    // support radius pass.radius: every kernel here is zero farther than r from its beam or point.
    template <class Items>
    void prepareOver(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass, const Items& items) {
        scene_ = &scene;
        map_ = &map;
        pass_ = pass;
        ready_ = !items.empty();
        if (!ready_) return;
        if (!accel_ || backend_ != pass.accel) {
            accel_ = BeamAccel::create(pass.accel);
            backend_ = pass.accel;
        }
        accel_->build(items, pass.radius, pass.threads);
    }

    const Scene* scene_ = nullptr;
    const PhotonMap* map_ = nullptr;
    EstimatorPass pass_;
    std::unique_ptr<BeamAccel> accel_;
    AccelBackend backend_ = AccelBackend::Embree;
    bool ready_ = false;
};

}  // namespace tpb
