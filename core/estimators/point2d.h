// The point x beam 2D estimator ("point2d"): the beam radiance estimate (Jarosz, Zwicker, Jensen
// 2008, "The beam radiance estimate for volumetric photon mapping"; "Point x Beam (2D)" in Jarosz
// et al. 2011), made transient as the paper does for beams (Marco et al. 2017, Sec. 4: "analogous
// concepts apply for extending 3D and 1D kernels to transient state"; time as in eqs. 11-15).
// Photon POINTS (photon_tracer.h, VolumePhoton) are gathered along the camera segment with a 2D
// kernel perpendicular to the ray: each point is blurred into a disc of radius r across the ray.
//
// Glossary (units):
//   x_r, w_r   camera segment origin and unit direction; s in [0, S] distance along it (m)
//   x_p, w_p   photon point and its propagation direction before scattering (VolumePhoton::dirIn)
//   Phi_p      point power (W m): Phi T(s) / (sigma_bar Tbar(s)), see photon_tracer.h
//   t_p        OPL of the photon at x_p (m), emission time included
//   s_p        projection of x_p on the ray: s_p = (x_p - x_r) . w_r (m)
//   u_p        distance of x_p from the ray's line: |x_p - x_r - s_p w_r| (m)
//   r          kernel radius (m); sigma_t, sigma_s (1/m, RGB); eta index of refraction; rho the phase
//              function at the scattering cosine w_p . (-w_r)
//
// Derivation. The points' expected measure sum_p Phi_p delta(x - x_p) delta(w - w_p) is the
// radiance L(x, w) of the photon paths (photon_tracer.h: the weight makes it the beams' measure).
// The radiance scattered once more towards the camera along the segment is
//   L = Int_0^S T_r(s) sigma_s Int rho(w . -w_r) L(x_r + s w_r, w) dw ds
//     = E[ sum_p sigma_s rho(w_p . -w_r) Phi_p Int_0^S T_r(s) delta^3(x_r + s w_r - x_p) ds ],
// and the line integral of the 3D delta is a 2D delta across the ray at s = s_p:
//   Int_0^S T_r(s) delta^3(...) ds = T_r(s_p) delta^2(u_p) 1(0 <= s_p <= S).
// Blurring the 2D delta with the disc kernel K_2(u) = 1 / (pi r^2) for u < r gives the estimate
//   L = sum_{p: u_p < r, 0 <= s_p <= S} sigma_s rho(w_p . -w_r) Phi_p T_r(s_p) / (pi r^2),
// T_r(s) = exp(-sigma_t s) per channel (chromatic media: per channel). Units: 1/m * 1/sr * W m *
// 1/m^2 = W/(m^2 sr). Kernel dimension 2 (the disc's area pi r^2 shrinks by (i + alpha)/(i + 1)).
//
// Time (as eqs. 12-14 for beams). The light of point p scatters at x_p at OPL t_p; the kernel
// places it at the ray point s_p (the disc is a projection along the ray's cross-section, no
// length along the ray), from where it travels eta s_p of OPL to the segment's start and then the
// camera path's OPL t_cam. One contribution arrives at one instant on each axis:
//   real:      t = t_cam + t_p + eta s_p          unwarped:  t = t_p
// (the unwarped time is that of the scattering event, as t_b0 + eta s_b is the beam point's: the
// camera part is dropped), written with PixelSink::instant. As r -> 0 it is the exact arrival time
// of the path through x_p; the photon point, unlike a beam, carries one time only, so the estimate
// has no spread along the ray (the paper's remark on photon points, Sec. 4).
//
// Walls: as beam2d, a point is kept only when it sees the camera-segment point x_r + s_p w_r it is
// blurred onto (estimators/kernel_visibility.h).
#pragma once
#include "base/math.h"
#include "estimators/accel_estimator.h"

#include <memory>
#include <optional>

namespace tpb {

// The 2D kernel's geometry: the projection of a point on the camera segment, and its distance from
// the ray's line. Empty when the point is farther than r from the line (u_p >= r) or its
// projection falls outside [0, sMax] (the kernel's support).
struct RayPointDisc {
    double s = 0.0;      // s_p (m)
    double dist2 = 0.0;  // u_p^2 (m^2)
};
std::optional<RayPointDisc> rayPointDisc(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xp, double radius);

class Point2DEstimator final : public AccelVolumeEstimator {
public:
    static constexpr int kDim = 2;
    std::string name() const override { return "point2d"; }
    int dim() const override { return kDim; }
    Needs needs() const override { return {false, true}; }
    void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) override;
    int64_t gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                   EstimatorScratch& scratch) const override;
};

}  // namespace tpb
