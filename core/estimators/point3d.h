// The point x beam 3D estimator ("point3d"): photon points gathered along the camera segment with a
// 3D kernel integrated along the ray ("Point x Beam (3D)" in Jarosz et al. 2011; the volumetric
// photon-mapping kernel of Jensen & Christensen 1998 taken along the ray instead of at ray-marching
// steps), made transient as the paper does for beams (Marco et al. 2017, Sec. 4: "analogous
// concepts apply for extending 3D and 1D kernels to transient state"; time as in eqs. 11-15).
//
// Glossary (units): as point2d.h — camera segment x_r + s w_r, s in [0, S]; photon point x_p,
// direction w_p, power Phi_p (W m, photon_tracer.h), OPL t_p; s_p = (x_p - x_r) . w_r and u_p the
// point's distance from the ray's line; r kernel radius; sigma_t, sigma_s (1/m, RGB); eta index.
//
// Derivation. With the points' measure as in point2d.h,
//   L = E[ sum_p sigma_s rho(w_p . -w_r) Phi_p Int_0^S T_r(s) delta^3(x_r + s w_r - x_p) ds ].
// Blurring the 3D delta with the ball kernel K_3(y) = 3 / (4 pi r^3) for |y| < r:
//   L = sum_p sigma_s rho(w_p . -w_r) Phi_p (3 / (4 pi r^3)) Int_{s-}^{s+} T_r(s) ds,
// where [s-, s+] is the chord of the ball around x_p on the segment:
//   |x_r + s w_r - x_p|^2 < r^2  <=>  |s - s_p| < h,  h = sqrt(r^2 - u_p^2),
//   s- = max(0, s_p - h),  s+ = min(S, s_p + h).
// Closed form per channel (T_r(s) = exp(-sigma_t s)):
//   Int_{s-}^{s+} exp(-sigma_t s) ds = exp(-sigma_t s-) (s+ - s-) g(sigma_t (s+ - s-)),
//   g(x) = (1 - e^{-x}) / x (expRel, beam2d.h), g(0) = 1: the sigma_t -> 0 limit is the chord
// length, a large sigma_t gives exp(-sigma_t s-) / sigma_t. Units: 1/m * 1/sr * W m * 1/m^3 * m =
// W/(m^2 sr). Kernel dimension 3 (the ball's volume 4/3 pi r^3 shrinks by (i + alpha)/(i + 1)).
//
// Time (as eqs. 12-15 for beams). The point carries one time t_p; the kernel spreads its light over
// the chord, and the part scattered at the ray point s travels eta s of OPL to the segment's start
// (and then t_cam to the sensor). The estimate's energy along s has density proportional to
// T_r(s) = exp(-sigma_t s) on [s-, s+] (kappa = sigma_t per channel), and its arrival time is
// linear in s:
//   real:      t(s) = t_cam + t_p + eta s     (slope eta)
//   unwarped:  t(s) = t_p                     (slope 0: one instant)
// written with PixelSink::spread (the uniform profile, the paper's even spread, is kappa = 0). As
// r -> 0 the chord shrinks to s_p and both reduce to point2d's instants. No part is binned before
// the causal floor (estimator.h, causalFloor; derived in docs/developer/adding-an-estimator.md, "Causality"): the
// chord's near part could otherwise arrive up to eta r before any real path through the point.
//
// Walls: as beam2d, a point is kept only when it sees the middle of its chord on the camera
// segment (estimators/kernel_visibility.h).
#pragma once
#include "base/math.h"
#include "estimators/accel_estimator.h"

#include <memory>
#include <optional>

namespace tpb {

// The chord of the camera segment [0, sMax] inside the ball of radius r around x_p; empty when the
// segment misses the ball or only touches it (zero length).
struct RayPointChord {
    double sMinus = 0.0, sPlus = 0.0;  // s interval (m)
    double sP = 0.0;                   // s_p, the projection of x_p (m)
};
std::optional<RayPointChord> rayPointChord(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xp, double radius);

// Int_{s-}^{s+} exp(-sigma_t s) ds for one channel (closed form above).
double chordTransmittance(double sigma_t, double sMinus, double sPlus);

class Point3DEstimator final : public AccelVolumeEstimator {
public:
    static constexpr int kDim = 3;
    std::string name() const override { return "point3d"; }
    int dim() const override { return kDim; }
    Needs needs() const override { return {false, true}; }
    void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) override;
    int64_t gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                   EstimatorScratch& scratch) const override;
};

}  // namespace tpb
