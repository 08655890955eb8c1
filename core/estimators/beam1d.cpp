#include "estimators/beam1d.h"

#include "estimators/kernel_visibility.h"

#include <cmath>

namespace tpb {

std::optional<ClosestApproach> closestApproach(const Vec3& xr, const Vec3& wr, const Vec3& xb, const Vec3& wb) {
    // (1D-3), with N = w_r x w_b: |N| is sin(theta) to full relative precision even for nearly
    // parallel lines (1 - c^2 would cancel).
    const Vec3 N = glm::cross(wr, wb);
    const double n2 = glm::dot(N, N);
    if (!(n2 > 0.0)) return std::nullopt;
    const Vec3 delta = xb - xr;
    ClosestApproach ca;
    ca.sinTheta = std::sqrt(n2);
    ca.cosTheta = glm::dot(wr, wb);
    ca.sr = glm::dot(glm::cross(delta, wb), N) / n2;
    ca.sb = glm::dot(glm::cross(delta, wr), N) / n2;
    ca.distance = -glm::dot(delta, N) / ca.sinTheta;
    return ca;
}

void Beam1DEstimator::prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) {
    // Support radius r: a closest point within r of the segment lies on a piece whose box, padded
    // by r, the segment crosses (the near-parallel fallback's disc has the same radius).
    prepareOver(scene, map, pass, map.beams);
}

namespace {
// The accelerator's candidate test (accel/beam_accel.h): a superset of the pieces gather() turns
// into an estimate, decided from the piece alone (its beam's length is not at hand: a piece's
// s_b <= sbHi <= L_b bounds it). Accepted: exactly parallel lines; sin(theta) below the (1D-6)
// threshold of min(sMax, sbHi) >= the gather's min(sMax, L_b), so every pair the gather hands to
// beam2d; and a closest approach within r, on the segment and on the closed range [sbLo, sbHi] (the
// gather's half-open rule is stricter). Rejected pieces give no estimate, the accepted ones come in
// the same (beam, piece) order: the same estimates, the same sums, the same films.
struct ClosestApproachTest {
    const Ray& ray;
    double sMax, radius;
    static bool accept(const void* context, double sbLo, double sbHi, const Vec3& origin, const Vec3& dir) {
        const auto& t = *static_cast<const ClosestApproachTest*>(context);
        const std::optional<ClosestApproach> ca = closestApproach(t.ray.o, t.ray.d, origin, dir);
        if (!ca || ca->sinTheta < parallelSinThreshold(t.radius, t.sMax, sbHi)) return true;
        return std::abs(ca->distance) < t.radius && ca->sr >= 0.0 && ca->sr <= t.sMax && ca->sb >= sbLo &&
               ca->sb <= sbHi;
    }
};
}  // namespace

// The radiance the pass's beams scatter along x_r + s w_r, s in [0, sMax] ((1D-4) - (1D-6)).
int64_t Beam1DEstimator::gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                                EstimatorScratch& scratch) const {
    if (!ready_) return 0;
    const Ray& ray = seg.ray;
    const Region& region = scene_->regions[seg.region];
    const Medium& m = region.medium;
    const double r = pass_.radius;
    const SegmentGather g{*scene_,       ray, seg.sMax, m, region.ior, r, beamAttenuation(m, pass_.beamLength),
                          pass_.profile, path};
    scratch.pieces.clear();
    const ClosestApproachTest test{ray, seg.sMax, r};
    accel_->candidates(ray.o, ray.d, seg.sMax, seg.region, scratch.pieces, {&ClosestApproachTest::accept, &test});
    NearShapes near(*scene_, ray, seg.sMax, r, scratch.shapes);
    const double kernel = 1.0 / (2.0 * r);  // K1(d), |d| < r
    int64_t estimates = 0;
    for (const BeamPiece& piece : scratch.pieces) {
        const Beam& b = map_->beams[piece.beam];
        const std::optional<ClosestApproach> ca = closestApproach(ray.o, ray.d, b.origin, b.dir);
        // (1D-6): nearly parallel to the segment, the disc kernel of beam2d.
        if (!ca || ca->sinTheta < parallelSinThreshold(r, seg.sMax, b.length)) {
            if (gatherBeam2DPiece(g, b, piece, near, sink)) ++estimates;
            continue;
        }
        // (1D-4): inside the box across both lines, on the segment and on this piece of the beam.
        if (!(std::abs(ca->distance) < r)) continue;
        if (!(ca->sr >= 0.0 && ca->sr <= seg.sMax)) continue;
        if (!closestPointOnPiece(ca->sb, piece.sbLo, piece.sbHi, b.length)) continue;
        const Vec3 xr = ray.at(ca->sr), xb = b.origin + ca->sb * b.dir;
        if (!kernelPointVisible(*scene_, near.get(), xr, xb)) continue;
        const double tx = std::exp(-m.sigma_t.x * ca->sr - g.tauB.x * ca->sb);
        const Color T = g.grey ? Color(tx)
                               : Color(tx, std::exp(-m.sigma_t.y * ca->sr - g.tauB.y * ca->sb),
                                       std::exp(-m.sigma_t.z * ca->sr - g.tauB.z * ca->sb));
        const double rho = m.phase.eval(-ca->cosTheta);  // from w_b into -w_r (towards the camera)
        const Color L = path.beta * m.sigma_s * rho * b.power * T * (kernel / ca->sinTheta);
        // (1D-5): one instant on each axis.
        const double tBeam = b.opl0 + region.ior * ca->sb;
        sink.instant(
            L, path.oplCam + tBeam + region.ior * ca->sr, tBeam,
            causalFloor(path.oplCam, b.fromOpl, region.ior, b.from, ray.o, tBeam, r));  // via the vertex before
        ++estimates;
    }
    return estimates;
}

}  // namespace tpb
