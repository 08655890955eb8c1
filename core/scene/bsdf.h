// Surface scattering: Lambertian, perfect mirror, smooth dielectric (Fresnel, total internal
// reflection). Directions are propagation directions; n is the geometric/shading normal.
#pragma once
#include "base/math.h"

namespace tpb {

inline Vec3 reflect(const Vec3& d, const Vec3& n) { return d - 2.0 * glm::dot(d, n) * n; }

// Unpolarised Fresnel reflectance for a smooth interface. cosI = |cos| of the incident angle,
// etaI/etaT the indices on the incident/transmitted side. Returns 1 on total internal reflection.
inline double fresnelDielectric(double cosI, double etaI, double etaT) {
    cosI = std::clamp(cosI, 0.0, 1.0);
    const double sinI2 = std::max(0.0, 1.0 - cosI * cosI);
    const double sinT2 = (etaI / etaT) * (etaI / etaT) * sinI2;
    if (sinT2 >= 1.0) return 1.0;
    const double cosT = std::sqrt(1.0 - sinT2);
    const double rs = (etaI * cosI - etaT * cosT) / (etaI * cosI + etaT * cosT);
    const double rp = (etaT * cosI - etaI * cosT) / (etaT * cosI + etaI * cosT);
    return 0.5 * (rs * rs + rp * rp);
}

// Refracts propagation direction d through a surface with normal n facing the incident side
// (dot(d, n) < 0), eta = etaI / etaT. Returns false on total internal reflection.
inline bool refract(const Vec3& d, const Vec3& n, double eta, Vec3& out) {
    const double cosI = -glm::dot(d, n);
    const double sinT2 = eta * eta * std::max(0.0, 1.0 - cosI * cosI);
    if (sinT2 >= 1.0) return false;
    const double cosT = std::sqrt(1.0 - sinT2);
    out = glm::normalize(eta * d + (eta * cosI - cosT) * n);
    return true;
}

}  // namespace tpb
