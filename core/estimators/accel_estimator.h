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
    // support radius pass.radius: every kernel here is zero farther than r from its beam or point
    // (plus pass.bundleSlack for an estimator that shares queries over blocks: `bundles`).
    template <class Items>
    void prepareOver(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass, const Items& items,
                     bool bundles = false) {
        scene_ = &scene;
        map_ = &map;
        pass_ = pass;
        if (!bundles || !(pass_.bundleSlack > 0.0)) pass_.bundleSlack = 0.0;
        ready_ = !items.empty();
        if (!ready_) return;
        if (!accel_ || backend_ != pass.accel) {
            accel_ = BeamAccel::create(pass.accel);
            backend_ = pass.accel;
        }
        // (The slack's own rounding margin: segment_bundle.h's fat test uses slack (1 + 1e-6).)
        const double support = pass.radius + (pass_.bundleSlack > 0.0 ? pass_.bundleSlack * (1.0 + 2e-6) : 0.0);
        buildAccel(items, support, pass.radius, pass.threads);
    }

    void buildAccel(const std::vector<Beam>& beams, double support, double radius, int threads) {
        accel_->build(beams, BeamSupport{support, radius}, threads);
    }
    void buildAccel(const std::vector<VolumePhoton>& points, double support, double, int threads) {
        accel_->build(points, support, threads);
    }

    const Scene* scene_ = nullptr;
    const PhotonMap* map_ = nullptr;
    EstimatorPass pass_;
    std::unique_ptr<BeamAccel> accel_;
    AccelBackend backend_ = AccelBackend::Embree;
    bool ready_ = false;
};

}  // namespace tpb
