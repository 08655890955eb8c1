// The 2D beam kernel estimator ("beam2d"): ray-beam density estimation with the 2D kernel of
// Transient Photon Beams (Marco et al. 2017), building on Jarosz et al. 2011 ("Beam x Beam 2D"):
// the overlap of a camera segment with a beam's kernel cylinder, the closed form of eq. 8, the
// time profile of the estimate (eqs. 11-15), and Beam2DEstimator, which gathers every beam of a
// pass along a camera segment (eq. 10: the sum over the beams crossing the ray).
//
// Glossary (units):
//   x_r, w_r   camera segment origin and unit direction; s_r in [0, S] distance along it (m)
//   x_b, w_b   beam origin and unit direction; s_b in [0, L_b] distance along it (m)
//   c          cos between w_r and w_b (dot(w_r, w_b)); the scattering cosine is -c
//   r          kernel radius (m): the beam is blurred into a cylinder of radius r around its axis
//   sigma_t    extinction of the medium (1/m, RGB); tau_b the beam attenuation used inside the kernel
//              (sigma_t for long beams; sigma_t - sigma_sampling for short beams, see photon_tracer.h)
//   eta        index of refraction of the medium: OPL = eta * distance
//
// Eq. 8 of the paper (with Omega_R(r^2) = pi r^2, the kernel's cross-section perpendicular to the beam):
//   L_b = sigma_s rho(-c) Phi_b / (pi r^2) * Int_{s-}^{s+} T(s_r) T_b(s_b(s_r)) ds_r,
// where s_b(s_r) = s_b0 + c s_r is the projection of the ray point on the beam axis.
// The closed form of the integral (derived in docs/theory/derivations.md, checked against quadrature in
// tests/estimators/test_beam2d.cpp) is, with kappa = sigma_t + tau_b c and E(s) = sigma_t s + tau_b s_b(s):
//   Int = exp(-E(s-)) * (s+ - s-) * g(kappa (s+ - s-)),   g(x) = (1 - e^{-x}) / x,
// evaluated from the end with the larger transmittance so g's argument is >= 0 (no overflow, no 0/0;
// g(0) = 1 gives the beam-pointing-at-the-camera limit kappa -> 0 and the sigma_t -> 0 limit).
// (The paper's eq. 9 divides by mu_t cos(theta_b); with our convention the factor is sigma_t (1 + c)
//  for long beams. Our tests pin the correct form.)
//
// Time (eqs. 11-15): the optical path length of the light reaching the camera through the kernel
// point at s_r is linear in s_r:
//   real:      t(s_r) = t_cam + t_b0 + eta (s_b0 + c s_r) + eta s_r     (slope eta (1 + c) >= 0)
//   unwarped:  t(s_r) = t_b0 + eta (s_b0 + c s_r)                        (slope eta c)
// and the energy density along s_r is proportional to exp(-kappa s_r): exponential in time too.
#pragma once
#include "base/math.h"
#include "estimators/accel_estimator.h"
#include "estimators/kernel_visibility.h"

namespace tpb {

// g(x) = (1 - exp(-x)) / x, with g(0) = 1. Stable for all x >= -700. Also 1 - exp(-x) itself when it
// was computed on the way (|x| >= 1e-5; else -1): the time profile of the same estimate needs it.
struct ExpRel {
    double value;
    double oneMinusExp;
};
inline ExpRel expRelAndMass(double x) {
    if (std::abs(x) < 1e-5) return {1.0 - 0.5 * x + x * x / 6.0, -1.0};
    const double m = oneMinusExpNeg(x);
    return {m / x, m};
}
inline double expRel(double x) { return expRelAndMass(x).value; }

// Interval of the camera segment inside the beam's kernel cylinder (radius r, axis = the beam's
// segment, flat end caps), intersected with the segment [0, sMax]. Returns false when empty.
struct RayBeamOverlap {
    double sMinus = 0.0, sPlus = 0.0;  // s_r interval (m)
    double sb0 = 0.0;                  // projection of x_r on the beam axis: s_b(s_r) = sb0 + c s_r
    double cosRB = 0.0;                // c = dot(w_r, w_b)
};
bool rayBeamOverlap(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xb, const Vec3& wb, double beamLength,
                    double radius, RayBeamOverlap& out);
// Same, restricted to beam parameters [sbLo, sbHi] (the BVH splits long beams into pieces).
bool rayBeamOverlap(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xb, const Vec3& wb, double sbLo,
                    double sbHi, double radius, RayBeamOverlap& out);

// Int_{s-}^{s+} exp(-sigma_t s - tau_b (sb0 + c s)) ds for one channel (closed form above), and the
// unnormalised mass of its time profile, oneMinusExpNeg(|kappa| (s+ - s-)), when the closed form computed it
// (|kappa| len >= 1e-5; else -1): the time splat (time_splat.h) needs the same value.
struct ChannelIntegral {
    double integral = 0.0;
    double massTotal = -1.0;
};
ChannelIntegral transmittanceChannel(double sigma_t, double tau_b, const RayBeamOverlap& o);
inline double transmittanceIntegral(double sigma_t, double tau_b, const RayBeamOverlap& o) {
    return transmittanceChannel(sigma_t, tau_b, o).integral;
}

// tau_b (1/m): the attenuation along a beam inside the kernel (photon_tracer.h): sigma_t for long
// beams, sigma_t - sigma_sampling for short ones (1 for grey media).
inline Color beamAttenuation(const Medium& m, BeamLength length) {
    return length == BeamLength::Long ? m.sigma_t : m.sigma_t - Color(m.samplingSigma());
}

// What the per-beam estimates along one camera segment share (also used by beam1d.h).
struct SegmentGather {
    const Scene& scene;
    const Ray& ray;        // x_r, w_r
    double sMax;           // m, the segment's length (may be infinite)
    const Medium& medium;  // of the segment's region
    double eta;            // its index of refraction
    double radius;         // m, this pass's kernel radius r
    Color tauB;            // beamAttenuation()
    TimeProfile profile;
    const PathState& path;
    // Grey medium and beam attenuation: one channel of the transmittance stands for all three.
    bool grey = isGrey(medium.sigma_t) && isGrey(tauB);
};

// Eqs. 8, 12-15 for one candidate piece [sbLo, sbHi] of beam b: adds its estimate (times the
// path's throughput) to sink when the segment meets the piece's kernel cylinder and the wall test
// (kernel_visibility.h) passes; returns whether it did.
bool gatherBeam2DPiece(const SegmentGather& g, const Beam& b, const BeamPiece& piece, NearShapes& near,
                       PixelSink& sink);
// The same with the overlap already found (rayBeamOverlap of the segment and the piece, true).
bool gatherBeam2DOverlap(const SegmentGather& g, const Beam& b, const RayBeamOverlap& o, NearShapes& near,
                         PixelSink& sink);

// The estimator (eqs. 8, 10, 12-15). Kernel dimension 2 (a disc across the beam): the kernel's
// area pi r^2 shrinks by (i + alpha) / (i + 1) per pass. Homogeneous media only (it reads the
// region's sigma_t and sigma_s): a heterogeneous medium needs its own estimator (transmittance
// integrals by ray marching or tracking).
class Beam2DEstimator final : public AccelVolumeEstimator {
public:
    static constexpr int kDim = 2;
    std::string name() const override { return "beam2d"; }
    int dim() const override { return kDim; }
    void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) override;
    int64_t gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                   EstimatorScratch& scratch) const override;
};

}  // namespace tpb
