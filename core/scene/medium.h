// Homogeneous participating media and the Henyey-Greenstein phase function.
// Units: sigma_* in 1/m; ior dimensionless (OPL = ior * distance).
#pragma once
#include "base/math.h"
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

struct Medium {
    Color sigma_s{0.0};
    Color sigma_a{0.0};
    Color sigma_t{0.0};  // sigma_s + sigma_a
    double ior = 1.0;
    HenyeyGreenstein phase;
    bool scattering = false;  // any sigma_s > 0: beams are stored only in scattering media

    // Single scalar used for free-flight sampling (average of sigma_t).
    double samplingSigma() const { return average(sigma_t); }
    Color transmittance(double d) const {
        return Color(std::exp(-sigma_t.x * d), std::exp(-sigma_t.y * d), std::exp(-sigma_t.z * d));
    }
};

}  // namespace tpb
