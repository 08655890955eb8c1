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

// Equiangular sampling (Kulla and Fajardo 2012) of a point on the segment x(t) = o + t w,
// 0 <= t < tMax (w unit), towards a point y (a light). With D = (y - o).w and h the distance from y
// to the line, |x(t) - y|^2 = h^2 + (t - D)^2; the angle theta(t) = atan((t - D) / h) has
// d theta / dt = h / (h^2 + (t - D)^2), so theta uniform in [theta(0), theta(tMax)] gives
//     pdf(t) = h / ((theta_b - theta_a) (h^2 + (t - D)^2)),     t = D + h tan(theta),
// whose 1/|x - y|^2 cancels the light's. tMax may be infinite. (Chi-square test against pdf(t) in
// tests/base/test_sampling.cpp; checked against free-flight NEE in test_path_tracer.)
struct EquiangularSample {
    double t = 0.0;    // distance along the segment (m)
    double pdf = 0.0;  // pdf(t) (1/m)
};
struct EquiangularFrame {
    double D = 0.0, h = 0.0, thetaA = 0.0, thetaB = 0.0;
    bool valid = false;  // false when y lies on the line or the segment is empty: do not sample

    EquiangularFrame(const Vec3& o, const Vec3& w, double tMax, const Vec3& y) {
        const Vec3 oy = y - o;
        D = glm::dot(oy, w);
        h = glm::length(oy - D * w);
        if (!(h > 0.0) || !(tMax > 0.0)) return;  // y on the segment's line: a set of measure zero
        thetaA = std::atan2(-D, h);
        thetaB = std::isfinite(tMax) ? std::atan2(tMax - D, h) : 0.5 * kPi;
        valid = thetaB > thetaA;
    }
    // The point for the uniform number u in [0, 1); rounding can put t just outside [0, tMax).
    EquiangularSample sample(double u) const {
        const double t = D + h * std::tan(thetaA + u * (thetaB - thetaA));
        return {t, pdf(t)};
    }
    double pdf(double t) const { return h / ((thetaB - thetaA) * (h * h + (t - D) * (t - D))); }
};

// Local (x, y, z) around n -> world.
inline Vec3 toWorld(const Vec3& local, const Vec3& n) {
    Vec3 t, b;
    coordinateSystem(n, t, b);
    return local.x * t + local.y * b + local.z * n;
}

}  // namespace tpb
