#include "estimators/point2d.h"

#include "estimators/kernel_visibility.h"

#include <cmath>

namespace tpb {

std::optional<RayPointDisc> rayPointDisc(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xp, double radius) {
    const Vec3 d = xp - xr;
    const double s = glm::dot(d, wr);
    if (!(s >= 0.0 && s <= sMax)) return std::nullopt;
    const Vec3 perp = d - s * wr;  // the offset across the ray (not |d|^2 - s^2: no cancellation)
    const double dist2 = glm::dot(perp, perp);
    if (!(dist2 < radius * radius)) return std::nullopt;
    return RayPointDisc{s, dist2};
}

void Point2DEstimator::prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) {
    // The disc kernel is zero farther than r from the ray's line, hence from the segment.
    prepareOver(scene, map, pass, map.points);
}

namespace {
// The kernel test as the accelerator's candidate test: the same call gather() makes per candidate.
struct PointKernelTest {
    const Ray& ray;
    double sMax, radius;
    static bool accept(const void* context, double, double, const Vec3& point, const Vec3&) {
        const auto& t = *static_cast<const PointKernelTest*>(context);
        return rayPointDisc(t.ray.o, t.ray.d, t.sMax, point, t.radius).has_value();
    }
};
}  // namespace

// L = sum_p sigma_s rho(w_p . -w_r) Phi_p T_r(s_p) / (pi r^2), one instant per point (header).
int64_t Point2DEstimator::gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                                 EstimatorScratch& scratch) const {
    if (!ready_) return 0;
    const Scene& scene = *scene_;
    const Ray& ray = seg.ray;
    const Region& region = scene.regions[seg.region];
    const Medium& m = region.medium;
    const double eta = region.ior, r = pass_.radius;
    scratch.pieces.clear();
    const PointKernelTest test{ray, seg.sMax, r};
    accel_->candidates(ray.o, ray.d, seg.sMax, seg.region, scratch.pieces, {&PointKernelTest::accept, &test});
    bool haveNear = false;
    const double invArea = 1.0 / (kPi * r * r);  // K_2 = 1 / (pi r^2)
    int64_t estimates = 0;
    for (const BeamPiece& candidate : scratch.pieces) {
        const VolumePhoton& p = map_->points[candidate.beam];
        const std::optional<RayPointDisc> disc = rayPointDisc(ray.o, ray.d, seg.sMax, p.position, r);
        if (!disc) continue;
        if (!haveNear) {
            nearShapes(scene, ray, seg.sMax, r, scratch.shapes);
            haveNear = true;
        }
        if (!kernelPointVisible(scene, scratch.shapes, ray.at(disc->s), p.position)) continue;
        const double rho = m.phase.eval(-glm::dot(p.dirIn, ray.d));  // scattering from w_p into -w_r
        const Color L = path.beta * m.sigma_s * rho * p.power * m.transmittance(disc->s) * invArea;
        // No earlier than the real path leaving the point's flight at its start for x_r (causalFloor).
        sink.instant(
            L, path.oplCam + p.opl + eta * disc->s, p.opl,
            causalFloor(path.oplCam, p.opl - eta * p.length, eta, p.position - p.length * p.dirIn, ray.o, p.opl, r));
        ++estimates;
    }
    return estimates;
}

}  // namespace tpb
