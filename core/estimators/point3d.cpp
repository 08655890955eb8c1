#include "estimators/point3d.h"

#include "estimators/beam2d.h"  // expRel
#include "estimators/kernel_visibility.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace tpb {

std::optional<RayPointChord> rayPointChord(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xp, double radius) {
    const Vec3 d = xp - xr;
    const double sP = glm::dot(d, wr);
    const Vec3 perp = d - sP * wr;  // offset across the ray (no cancellation in |d|^2 - s_p^2)
    const double h2 = radius * radius - glm::dot(perp, perp);
    if (!(h2 > 0.0)) return std::nullopt;
    const double h = std::sqrt(h2);
    const double lo = std::max(0.0, sP - h), hi = std::min(sMax, sP + h);
    if (!(hi > lo)) return std::nullopt;
    return RayPointChord{lo, hi, sP};
}

double chordTransmittance(double sigma_t, double sMinus, double sPlus) {
    const double len = sPlus - sMinus;
    return std::exp(-sigma_t * sMinus) * len * expRel(sigma_t * len);
}

void Point3DEstimator::prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) {
    // The ball kernel is zero farther than r from the point.
    prepareOver(scene, map, pass, map.points, /*bundles=*/true);
}

namespace {
// The kernel test as the accelerator's candidate test: the same call gather() makes per candidate.
struct PointKernelTest {
    const Ray& ray;
    double sMax, radius;
    static bool accept(const void* context, double, double, const Vec3& point, const Vec3&) {
        const auto& t = *static_cast<const PointKernelTest*>(context);
        return rayPointChord(t.ray.o, t.ray.d, t.sMax, point, t.radius).has_value();
    }
};

// The fat test of segment_bundle.h: is the point within r + slack of the block's axis (a segment
// within slack of the axis can then pass within r of it)?
bool acceptFatBall(const void* context, double, double, const Vec3& point, const Vec3&) {
    const auto& q = *static_cast<const AccelVolumeEstimator::BundleQuery*>(context);
    return rayPointChord(q.origin, q.axis, q.length, point, q.radius + q.slack).has_value();
}
}  // namespace

// L = sum_p sigma_s rho Phi_p (3 / (4 pi r^3)) Int_{s-}^{s+} T_r(s) ds, spread over the chord (header).
int64_t Point3DEstimator::gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                                 EstimatorScratch& scratch) const {
    if (!ready_) return 0;
    const Scene& scene = *scene_;
    const Ray& ray = seg.ray;
    const Region& region = scene.regions[seg.region];
    const Medium& m = region.medium;
    const double eta = region.ior, r = pass_.radius;
    bool haveNear = false;
    const double invVolume = 3.0 / (4.0 * kPi * r * r * r);  // K_3
    const Color kappa = pass_.profile == TimeProfile::Exact ? m.sigma_t : Color(0.0);
    const bool grey = isGrey(m.sigma_t);
    int64_t estimates = 0;
    const auto estimate = [&](uint32_t index) {
        const VolumePhoton& p = map_->points[index];
        const std::optional<RayPointChord> chord = rayPointChord(ray.o, ray.d, seg.sMax, p.position, r);
        if (!chord) return;
        if (!haveNear) {
            nearShapes(scene, ray, seg.sMax, r, scratch.shapes);
            haveNear = true;
        }
        if (!kernelPointVisible(scene, scratch.shapes, ray.at(0.5 * (chord->sMinus + chord->sPlus)), p.position))
            return;
        const double ix = chordTransmittance(m.sigma_t.x, chord->sMinus, chord->sPlus);
        const Color integral = grey ? Color(ix)
                                    : Color(ix, chordTransmittance(m.sigma_t.y, chord->sMinus, chord->sPlus),
                                            chordTransmittance(m.sigma_t.z, chord->sMinus, chord->sPlus));
        const double rho = m.phase.eval(-glm::dot(p.dirIn, ray.d));  // scattering from w_p into -w_r
        const Color L = path.beta * m.sigma_s * rho * p.power * invVolume * integral;
        // t(s) = t_cam + t_p + eta s (real), t_p (unwarped); energy density exp(-sigma_t s) on the chord.
        // No part earlier than the real path leaving the point's flight at its start for x_r
        // (causalFloor): near the camera or the light's line of sight the chord's near part would be.
        sink.spread(
            L, kappa, chord->sMinus, chord->sPlus, path.oplCam + p.opl, eta, p.opl, 0.0,
            causalFloor(path.oplCam, p.opl - eta * p.length, eta, p.position - p.length * p.dirIn, ray.o, p.opl, r));
        ++estimates;
    };
    if (const std::vector<BeamPiece>* shared = sharedCandidates(seg, scratch, &acceptFatBall)) {
        // The block's shared candidates (segment_bundle.h), in the order of the query below.
        for (const BeamPiece& c : *shared) estimate(c.beam);
        return estimates;
    }
    scratch.pieces.clear();
    const PointKernelTest test{ray, seg.sMax, r};
    accel_->candidates(ray.o, ray.d, seg.sMax, seg.region, scratch.pieces, {&PointKernelTest::accept, &test});
    for (const BeamPiece& candidate : scratch.pieces) estimate(candidate.beam);
    return estimates;
}

}  // namespace tpb
