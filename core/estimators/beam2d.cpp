#include "estimators/beam2d.h"

#include "estimators/kernel_visibility.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace tpb {

bool rayBeamOverlap(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xb, const Vec3& wb, double sbLo,
                    double sbHi, double radius, RayBeamOverlap& out) {
    // Decompose the ray relative to the beam axis: parallel part (along w_b) and perpendicular part.
    const Vec3 d = xr - xb;
    const double c = glm::dot(wr, wb);
    const double sb0 = glm::dot(d, wb);
    const Vec3 w = d - sb0 * wb;  // perpendicular offset of x_r from the axis
    const Vec3 dp = wr - c * wb;  // perpendicular part of the ray direction, |dp|^2 = 1 - c^2
    const double a = glm::dot(dp, dp);
    const double r2 = radius * radius;
    const double w2 = glm::dot(w, w);

    double lo = 0.0, hi = sMax;
    // 1. Inside the infinite cylinder: a s^2 + 2 b s + (w2 - r2) <= 0.
    if (a < 1e-14) {
        // Ray parallel to the beam: inside everywhere or nowhere.
        if (w2 > r2) return false;
    } else {
        const double b = glm::dot(w, dp);
        const double disc = b * b - a * (w2 - r2);
        if (disc <= 0.0) return false;  // misses or grazes the kernel (zero-length overlap)
        const double sq = std::sqrt(disc);
        // Stable roots of a s^2 + 2 b s + cc: q = -(b + sign(b) sq); roots q/a and cc/q.
        const double q = -(b + std::copysign(sq, b));
        double s1 = q / a;
        double s2 = (q != 0.0) ? (w2 - r2) / q : s1;
        if (s1 > s2) std::swap(s1, s2);
        lo = std::max(lo, s1);
        hi = std::min(hi, s2);
    }
    // 2. Projection on the beam inside [sbLo, sbHi]: sbLo <= sb0 + c s <= sbHi.
    if (std::abs(c) < 1e-15) {
        if (sb0 < sbLo || sb0 > sbHi) return false;
    } else {
        double t1 = (sbLo - sb0) / c, t2 = (sbHi - sb0) / c;
        if (t1 > t2) std::swap(t1, t2);
        lo = std::max(lo, t1);
        hi = std::min(hi, t2);
    }
    if (!(hi > lo)) return false;
    out.sMinus = lo;
    out.sPlus = hi;
    out.sb0 = sb0;
    out.cosRB = c;
    return true;
}

bool rayBeamOverlap(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xb, const Vec3& wb, double beamLength,
                    double radius, RayBeamOverlap& out) {
    return rayBeamOverlap(xr, wr, sMax, xb, wb, 0.0, beamLength, radius, out);
}

ChannelIntegral transmittanceChannel(double sigma_t, double tau_b, const RayBeamOverlap& o) {
    const double kappa = sigma_t + tau_b * o.cosRB;
    const double len = o.sPlus - o.sMinus;
    // Optical depth E(s) = sigma_t s + tau_b s_b(s); start from the end where it is smallest.
    const double sRef = kappa >= 0.0 ? o.sMinus : o.sPlus;
    const double depth = sigma_t * sRef + tau_b * (o.sb0 + o.cosRB * sRef);
    const ExpRel g = expRelAndMass(std::abs(kappa) * len);  // its 1 - e^-x goes to the time splat
    return {std::exp(-depth) * len * g.value, g.oneMinusExp};
}

// ---- the estimator ------------------------------------------------------------------------------

void Beam2DEstimator::prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) {
    // The kernel is a cylinder of radius r around the beam: nothing beyond r from its axis.
    prepareOver(scene, map, pass, map.beams, /*bundles=*/true);
}

// Eqs. 8, 12-15 for one candidate piece of a beam: the overlap, the wall test, the closed-form
// transmittance integral and its spread in time.
bool gatherBeam2DPiece(const SegmentGather& g, const Beam& b, const BeamPiece& piece, NearShapes& near,
                       PixelSink& sink) {
    RayBeamOverlap o;
    if (!rayBeamOverlap(g.ray.o, g.ray.d, g.sMax, b.origin, b.dir, piece.sbLo, piece.sbHi, g.radius, o)) return false;
    return gatherBeam2DOverlap(g, b, o, near, sink);
}

bool gatherBeam2DOverlap(const SegmentGather& g, const Beam& b, const RayBeamOverlap& o, NearShapes& near,
                         PixelSink& sink) {
    const Medium& m = g.medium;
    const double r = g.radius;
    const double c = o.cosRB;
    // The kernel blurs the beam by r in every direction, also through a wall: a beam inside a
    // closed box would light the fog just outside it. Keep the estimate only when the beam
    // point nearest the middle of the overlap sees that point of the camera segment.
    const double sMid = 0.5 * (o.sMinus + o.sPlus);
    const double sbMid = std::clamp(o.sb0 + c * sMid, 0.0, b.length);
    const Vec3 xr = g.ray.at(sMid), xb = b.origin + sbMid * b.dir;
    if (!kernelPointVisible(g.scene, near.get(), xr, xb)) return false;
    // Eq. 8: L_b = sigma_s rho(theta) Phi_b / (pi r^2) * int T(s_r) T_b(s_b(s_r)) ds_r
    const Color& tauB = g.tauB;
    const double invArea = 1.0 / (kPi * r * r);  // 1 / Omega_R(r^2)
    const ChannelIntegral ix = transmittanceChannel(m.sigma_t.x, tauB.x, o);
    ChannelIntegral iy = ix, iz = ix;
    if (!g.grey) {
        iy = transmittanceChannel(m.sigma_t.y, tauB.y, o);
        iz = transmittanceChannel(m.sigma_t.z, tauB.z, o);
    }
    const Color integral(ix.integral, iy.integral, iz.integral);
    const double rho = m.phase.eval(-c);  // scattering from w_b into -w_r (towards the camera)
    const Color L = g.path.beta * m.sigma_s * rho * b.power * invArea * integral;
    // Eqs. 12-15: t(s_r) = t_cam + t_b0 + eta s_b(s_r) + eta s_r, linear in s_r. The exact profile's
    // kappa is the integral's (sigma_t + tau_b c per channel), so it shares the integral's expm1.
    const bool exact = g.profile == TimeProfile::Exact;
    SegmentProfile profile(exact ? m.sigma_t + tauB * c : Color(0.0), o.sMinus, o.sPlus);
    if (exact) profile.shareTotals(Color(ix.massTotal, iy.massTotal, iz.massTotal));
    const double tBeam = b.opl0 + g.eta * o.sb0;
    // No part earlier than the real path leaving the photon's path at the vertex before the beam
    // for x_r, nor (unwarped) eta r before the photon reaches the overlap's first beam point (causalFloor).
    const double sbFirst = std::max(0.0, o.sb0 + c * (c >= 0.0 ? o.sMinus : o.sPlus));
    sink.spread(L, profile, g.path.oplCam + tBeam, g.eta * (1.0 + c), tBeam, g.eta * c,
                causalFloor(g.path.oplCam, b.fromOpl, g.eta, b.from, g.ray.o, b.opl0 + g.eta * sbFirst, g.radius));
    return true;
}

namespace {
// The cylinder test as the accelerator's candidate test: the same call gatherBeam2DPiece makes, so
// the pieces it keeps are exactly those that give an estimate or fail the wall test.
struct CylinderTest {
    const Ray& ray;
    double sMax, radius;
    static bool accept(const void* context, double sbLo, double sbHi, const Vec3& origin, const Vec3& dir) {
        const auto& t = *static_cast<const CylinderTest*>(context);
        RayBeamOverlap o;
        return rayBeamOverlap(t.ray.o, t.ray.d, t.sMax, origin, dir, sbLo, sbHi, t.radius, o);
    }
};

}  // namespace

// Beam radiance estimate along the camera segment x_r + s w_r, s in [0, sMax] (eqs. 8, 10, 12-15).
int64_t Beam2DEstimator::gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                                EstimatorScratch& scratch) const {
    if (!ready_) return 0;
    const Region& region = scene_->regions[seg.region];
    const SegmentGather g{*scene_,
                          seg.ray,
                          seg.sMax,
                          region.medium,
                          region.ior,
                          pass_.radius,
                          beamAttenuation(region.medium, pass_.beamLength),
                          pass_.profile,
                          path};
    if (const std::vector<BeamPiece>* shared = sharedCylinderCandidates(seg, scratch)) {
        // The block's shared candidates (segment_bundle.h; their fat test batched too), each with the
        // exact test of the query below, in the same (beam, piece) order: the same estimates in the
        // same order. The exact test over all of them at once (overlap_batch.h: rayBeamOverlap's
        // answers bit for bit).
        NearShapes near(*scene_, seg.ray, seg.sMax, pass_.radius, scratch.shapes);
        OverlapBatch& ob = scratch.overlaps;
        rayBeamOverlaps(seg.ray.o, seg.ray.d, seg.sMax, scratch.bundle.axes, pass_.radius, ob);
        int64_t estimates = 0;
        for (const uint32_t i : ob.hits) {
            RayBeamOverlap o;
            o.sMinus = ob.sMinus[i];
            o.sPlus = ob.sPlus[i];
            o.sb0 = ob.sb0[i];
            o.cosRB = ob.cosRB[i];
            if (gatherBeam2DOverlap(g, map_->beams[(*shared)[i].beam], o, near, sink)) ++estimates;
        }
        return estimates;
    }
    scratch.pieces.clear();
    const CylinderTest test{seg.ray, seg.sMax, pass_.radius};
    accel_->candidates(seg.ray.o, seg.ray.d, seg.sMax, seg.region, scratch.pieces, {&CylinderTest::accept, &test});
    NearShapes near(*scene_, seg.ray, seg.sMax, pass_.radius, scratch.shapes);
    int64_t estimates = 0;
    for (const BeamPiece& piece : scratch.pieces)
        if (gatherBeam2DPiece(g, map_->beams[piece.beam], piece, near, sink)) ++estimates;
    return estimates;
}

}  // namespace tpb
