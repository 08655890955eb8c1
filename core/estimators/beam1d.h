// The 1D beam kernel estimator ("beam1d"): the "Beam x Beam 1D" estimate of Jarosz et al. 2011
// (A comprehensive theory of volumetric radiance estimation using photon points and beams; used
// progressively in Progressive Photon Beams, Jarosz et al. 2011), made transient. Each beam is
// taken at its closest approach to the camera segment with a 1D box kernel across both.
//
// Glossary (units): as in beam2d.h. x_r + s_r w_r, s_r in [0, S], the camera segment; x_b + s_b w_b,
// s_b in [0, L_b], the beam (power Phi_b, start OPL t_b0); c = dot(w_r, w_b); sin(theta) =
// |w_r x w_b|; n = w_r x w_b / sin(theta), the direction across both; r the kernel radius (m);
// sigma_s, sigma_t (1/m); tau_b the beam attenuation inside the kernel (beamAttenuation(), beam2d.h:
// sigma_t for long beams, sigma_t - sigma_sampling for short ones); eta the index of refraction.
//
// (1D-1) What is estimated. A beam is a line of flux: its radiance is Phi_b T_b(s_b) times a delta
// across the beam, so the radiance it scatters towards the camera along the segment is
//   L_b = sigma_s rho(-c) Phi_b Int_0^S ds_r Int_0^{L_b} ds_b T_r(s_r) T_b(s_b) delta3(v),
//   v = x_r(s_r) - x_b(s_b),  T_r(s) = exp(-sigma_t s),  T_b(s) = exp(-tau_b s),
// (the s_b integral of delta3 is the 2D delta across the beam, since |dv/ds_b| = 1).
// (1D-2) Kernels. A density estimate replaces delta3 by a normalised kernel K(v). beam2d's is
// delta(v.w_b) K2(v_perp) with a disc K2 = 1/(pi r^2) (paper eq. 8); the 1D one is
//   K(v) = K1(v.n) delta2(P v),   K1(d) = 1/(2r) for |d| < r, 0 otherwise (a box, Int K1 = 1),
// with P the projection onto the plane spanned by w_r and w_b. Written in beam2d's form it is
// delta(v.w_b) times the "strip" kernel K1(u_n) delta(u_m) on the beam's cross-section (u_n along
// n, u_m along m = w_b x n): a normalised 2D kernel supported inside beam2d's disc of radius r.
// (1D-3) Closest approach. P v = (s_r - s_r*) w_r - (s_b - s_b*) w_b, with (Delta = x_b - x_r,
// N = w_r x w_b, |N| = sin(theta))
//   s_r* = (Delta x w_b).N / |N|^2,   s_b* = (Delta x w_r).N / |N|^2,   d = v.n = -Delta.N / |N|,
// the closest points of the two lines and their (signed) distance, the same for every (s_r, s_b).
// The map (s_r, s_b) -> P v has Jacobian |w_r x w_b| = sin(theta), so the double integral of
// f delta2(P v) is f(s_r*, s_b*) / sin(theta):
// (1D-4) the estimate
//   L_b ~ sigma_s rho(-c) Phi_b T_r(s_r*) T_b(s_b*) K1(d) / sin(theta),
// counted when 0 <= s_r* <= S and 0 <= s_b* <= L_b (sharp: the kernel does not blur along the
// plane). The accelerator splits beams into pieces [sbLo, sbHi]; a piece counts s_b* in
// [sbLo, sbHi), the last one [sbLo, L_b], so a closest point on a piece boundary counts once
// (adjacent pieces share the same double, beam_accel.cpp). Kernel dimension 1: its measure 2r
// shrinks by (i + alpha) / (i + 1) per pass. Its expectation over a beam offset u n uniform over a
// range wider than 2r is Int K1 = 1 times the rest: the exact line integral of the spread beams
// (tests/estimators/test_beam1d.cpp checks this by Monte Carlo against quadrature).
//
// (1D-5) Time. The kernel (1D-2) is a delta in the plane of w_r and w_b, so exactly one pair
// (s_r*, s_b*) contributes, and its extent along n moves neither s_r nor s_b: the estimate has no
// time extent of its own (beam2d's disc does: its extent along m maps onto an s_r interval of
// length ~2r / sin(theta), over which eqs. 12-15 spread the energy). Its light arrives at
//   real:      t = t_cam + t_b0 + eta s_b* + eta s_r*        unwarped:  t = t_b0 + eta s_b*,
// the limit of beam2d's t(s_r) = t_cam + t_b0 + eta s_b(s_r) + eta s_r at s_r = s_r* (n is
// perpendicular to w_b, so s_b* is the projection s_b(s_r*) of x_r(s_r*) on the beam). As for
// beam2d, the blur across the kernel itself takes no time (an O(r) error that vanishes with r).
//
// (1D-6) Near-parallel ray and beam. As sin(theta) -> 0, (1D-4) is unbounded and exactly parallel
// lines have no closest point. Take beams leaving a point at distance h < r from the camera line
// isotropically (a light, a scattering vertex): a direction at angle theta << 1 from +-w_r passes
// within r for every azimuth, its closest point on the beam stays at s_b* ~ h / theta inside the
// beam, and with F = sigma_s rho Phi_b T its estimate is F / (2 r theta). Over dOmega / (4 pi) =
// theta dtheta dphi / (4 pi) the mean Int theta dtheta F / (4 r theta) is finite, but
//   E[L_b^2] ~ 2 Int_{h/l} theta dtheta / 2 * F^2 / (4 r^2 theta^2) = F^2 log(l / h) / (4 r^2):
// a log divergence, infinite for a ray through the point (h = 0). (For h > r the azimuths within
// the kernel shrink to ~4 r / h: F^2 log(l / h) / (4 pi r h). For beam origins spread over a volume
// the measure is dd sin(theta) ds_r* ds_b* dOmega and the second moment stays finite; the third
// diverges logarithmically. Either way the tail is heavy.)
// Rule: per (segment, beam), with l = min(S, L_b),
//   sin(theta) <  eps = clamp(pi r / (2 l), 1e-4, 1):  beam2d's estimate (eq. 8, 12-15; the disc),
//   sin(theta) >= eps:                                 (1D-4) with (1D-5).
// Both are estimates with normalised kernels supported within r of the beam (1D-2), chosen by the
// directions alone (not by position), so the mixture is a kernel estimate whose bias vanishes as
// r -> 0 like each one's (and eps -> 1e-4: the disc's share of pairs becomes negligible). eps
// equalises the two bounds: (1D-4) <= sigma_s rho Phi_b T / (2 r eps) = sigma_s rho Phi_b T l /
// (pi r^2), and eq. 8 is at most that times max(1, 1/|c|) (its overlap is at most S and L_b / |c|
// long), so no pair's estimate exceeds ~ l / (pi r^2), and the log divergence is cut at eps:
// E[L_b^2] ~ F^2 log(1 / eps) / r^2 for a point on the camera line.
// The floor 1e-4 keeps (1D-3) well conditioned: rounding a direction by delta ~ 1e-16 moves the
// closest points by ~ |Delta| delta / sin^2(theta), below 1e-8 |Delta| above the floor. (A fixed
// floor costs nothing in consistency: the disc is a valid kernel for any share of the pairs.)
//
// Homogeneous media only (it reads the region's sigma_t and sigma_s). Same wall test as beam2d
// (kernel_visibility.h): the beam point x_b(s_b*) must see the camera-segment point x_r(s_r*).
#pragma once
#include "base/math.h"
#include "estimators/beam2d.h"
#include "estimators/accel_estimator.h"

#include <memory>
#include <optional>

namespace tpb {

// (1D-3): the closest points of the lines x_r + s_r w_r and x_b + s_b w_b (unit directions).
struct ClosestApproach {
    double sr = 0.0, sb = 0.0;  // m, along the camera ray / the beam
    double distance = 0.0;      // m, d = v.n (signed; the kernel uses |d|)
    double cosTheta = 0.0;      // c = dot(w_r, w_b)
    double sinTheta = 0.0;      // |w_r x w_b| > 0
};
// nullopt when the lines are exactly parallel (w_r x w_b == 0).
std::optional<ClosestApproach> closestApproach(const Vec3& xr, const Vec3& wr, const Vec3& xb, const Vec3& wb);

// The half-open piece rule of (1D-4): s_b in [sbLo, sbHi), or [sbLo, L_b] for the beam's last piece.
inline bool closestPointOnPiece(double sb, double sbLo, double sbHi, double beamLength) {
    return sb >= sbLo && (sb < sbHi || (sbHi >= beamLength && sb <= beamLength));
}

// (1D-6): below this sin(theta) a (segment, beam) pair takes beam2d's estimate. sMax may be infinite.
inline double parallelSinThreshold(double radius, double sMax, double beamLength) {
    const double l = std::min(sMax, beamLength);
    return std::clamp(kPi * radius / (2.0 * l), 1e-4, 1.0);
}

class Beam1DEstimator final : public AccelVolumeEstimator {
public:
    static constexpr int kDim = 1;
    std::string name() const override { return "beam1d"; }
    int dim() const override { return kDim; }
    Needs needs() const override { return {true, false}; }  // beams only
    void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) override;
    int64_t gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                   EstimatorScratch& scratch) const override;
};

}  // namespace tpb
