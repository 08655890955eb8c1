// Sampling routines for directions and shapes. Each returns the sample and its pdf where useful.
#pragma once
#include "base/math.h"

namespace tpb {

inline Vec3 sampleUniformSphere(double u1, double u2) {
    const double z = 1.0 - 2.0 * u1;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = 2.0 * kPi * u2;
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}
inline constexpr double kUniformSpherePdf = 1.0 / (4.0 * kPi);

// Cosine-weighted direction around +z; pdfW = cos(theta) / pi.
inline Vec3 sampleCosineHemisphere(double u1, double u2) {
    const double r = std::sqrt(u1);
    const double phi = 2.0 * kPi * u2;
    return Vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u1)));
}

// Uniform direction in the cone cos(theta) >= cosMax around +z; pdfW = 1 / (2 pi (1 - cosMax)).
inline Vec3 sampleUniformCone(double u1, double u2, double cosMax) {
    const double cosT = 1.0 - u1 * (1.0 - cosMax);
    const double sinT = std::sqrt(std::max(0.0, 1.0 - cosT * cosT));
    const double phi = 2.0 * kPi * u2;
    return Vec3(sinT * std::cos(phi), sinT * std::sin(phi), cosT);
}

// Local (x, y, z) around n -> world.
inline Vec3 toWorld(const Vec3& local, const Vec3& n) {
    Vec3 t, b;
    coordinateSystem(n, t, b);
    return local.x * t + local.y * b + local.z * n;
}

}  // namespace tpb
