// Participating media and the Henyey-Greenstein phase function.
// Units: sigma_* in 1/m; ior dimensionless (OPL = ior * distance).
//
// A medium answers two questions about a ray segment [0, tMax): sampleFreeFlight (where the
// next scattering event is, with its per-channel weight) and transmittance. Tracers ask these
// through core/transport/free_flight.h. The set of media is closed (MediumKind): homogeneous is
// the only kind today; a heterogeneous medium adds a kind and a case in these two functions
// (delta/ratio tracking against a majorant; the Rng is passed for that), and nothing else in the
// tracers changes. The camera pass's 2D beam kernel (estimators/beam_kernel.h, eq. 8 in closed
// form) reads sigma_t / sigma_s directly: it needs a homogeneous medium, so a heterogeneous one
// will need its own estimator there (or a quadrature of the kernel).
#pragma once
#include "base/math.h"
#include "base/rng.h"
#include "base/sampling.h"

namespace tpb {

// Henyey-Greenstein phase function p(cos) with cos = dot(wi_propagation, wo_propagation), i.e. the
// cosine of the scattering angle (0 = forward). Normalised over the sphere: int p dw = 1.
struct HenyeyGreenstein {
    double g = 0.0;

    double eval(double cosTheta) const {
        const double denom = 1.0 + g * g - 2.0 * g * cosTheta;
        // denom >= (1-|g|)^2 > 0 for |g| < 1
        return (1.0 - g * g) / (4.0 * kPi * denom * std::sqrt(denom));
    }
    // Samples an outgoing propagation direction given the incoming propagation direction `wi`.
    // The pdf equals eval(dot(wi, wo)).
    Vec3 sample(const Vec3& wi, double u1, double u2) const {
        double cosTheta;
        if (std::abs(g) < 1e-3) {
            cosTheta = 1.0 - 2.0 * u1;
        } else {
            const double sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u1);
            cosTheta = (1.0 + g * g - sq * sq) / (2.0 * g);
        }
        cosTheta = std::clamp(cosTheta, -1.0, 1.0);
        const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        const double phi = 2.0 * kPi * u2;
        return glm::normalize(toWorld(Vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta), wi));
    }
};

// A free flight sampled along a ray segment [0, tMax).
struct MediumSample {
    double distance = kInf;  // m, to the scattering event, or tMax when the segment is crossed
    bool scattered = false;  // distance < tMax: a scattering event inside the medium
    // Per channel, what the path's weight is multiplied by: sigma_s T(d) / (sigma_bar T_bar(d)) at
    // a scattering event, T(tMax) / T_bar(tMax) when the segment is crossed. 0 (not computed) when
    // distance is infinite: an unbounded segment crossed, the path leaves the scene.
    Color weight{0.0};
};

enum class MediumKind { Homogeneous };  // the closed set of media (see the file header)

struct Medium {
    MediumKind kind = MediumKind::Homogeneous;
    Color sigma_s{0.0};
    Color sigma_a{0.0};
    Color sigma_t{0.0};  // sigma_s + sigma_a
    double ior = 1.0;
    HenyeyGreenstein phase;
    bool scattering = false;  // any sigma_s > 0: beams are stored only in scattering media

    // Single scalar used for free-flight sampling (average of sigma_t): sigma_bar.
    double samplingSigma() const { return average(sigma_t); }
    // Homogeneous transmittance over a distance d: exp(-sigma_t d) per channel.
    Color transmittance(double d) const {
        return Color(std::exp(-sigma_t.x * d), std::exp(-sigma_t.y * d), std::exp(-sigma_t.z * d));
    }
    // Transmittance of the segment [0, tMax) of `ray` (a heterogeneous medium needs where it is).
    Color transmittance(const Ray& /*ray*/, double tMax) const { return transmittance(tMax); }

    // Free-flight sampling with pdf sigma_bar exp(-sigma_bar d) (one random number from rng) on the
    // segment [0, tMax) of `ray`; tMax may be infinite (no surface ahead). With one scalar
    // sigma_bar for all channels the weight is sigma_s T(d) / (sigma_bar T_bar(d)) at a
    // scattering event and T / T_bar at the segment's end (photon_tracer.h, path_tracer.h).
    MediumSample sampleFreeFlight(const Ray& /*ray*/, double tMax, Rng& rng) const {
        const double sigmaBar = samplingSigma();
        MediumSample ms;
        const double d = -std::log(1.0 - rng.uniform()) / sigmaBar;
        ms.scattered = d < tMax;
        ms.distance = ms.scattered ? d : tMax;
        if (!std::isfinite(ms.distance)) return ms;
        const Color tr = transmittance(ms.distance);
        const double trBar = std::exp(-sigmaBar * ms.distance);
        ms.weight = ms.scattered ? sigma_s * tr / (sigmaBar * trBar) : tr / trBar;
        return ms;
    }
};

}  // namespace tpb
