// Basic types and constants shared by the whole core.
// Positions and directions are double precision (glm::dvec3); time is optical path length (OPL)
// in meters, also double. Colours are linear RGB triples.
#pragma once
#include <glm/glm.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

// For the small helpers of the per-estimate path (the time splat, the exponential masses): GCC
// stops inlining them once their callers grow, and a call per bin costs more than the helper.
// TPB_HOT_LAMBDA goes after a lambda's parameter list, for the same reason.
#if defined(__GNUC__)
#define TPB_HOT_INLINE inline __attribute__((always_inline))
#define TPB_HOT_LAMBDA __attribute__((always_inline))
#else
#define TPB_HOT_INLINE inline
#define TPB_HOT_LAMBDA
#endif

namespace tpb {

using Vec3 = glm::dvec3;
using Color = glm::dvec3;
using Mat4 = glm::dmat4;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInvPi = 1.0 / kPi;
inline constexpr double kInf = std::numeric_limits<double>::infinity();
// Speed of light in vacuum, meters per nanosecond: OPL[m] = kC_m_per_ns * t[ns].
inline constexpr double kC_m_per_ns = 0.299792458;

inline double luminance(const Color& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }
inline double maxComponent(const Color& c) { return std::max(c.x, std::max(c.y, c.z)); }
inline double average(const Color& c) { return (c.x + c.y + c.z) / 3.0; }
inline bool isFinite(const Color& c) { return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z); }
inline bool isBlack(const Color& c) { return c.x == 0.0 && c.y == 0.0 && c.z == 0.0; }
inline bool isGrey(const Color& c) { return c.x == c.y && c.y == c.z; }  // one channel stands for all three

// 1 - exp(-y) = -expm1(-y), the mass of [0, y] of a decaying exponential: the kernels' transmittance
// integrals and the time splat evaluate it once or more per estimate. For 0 <= y <= 1/32 (thin media
// over a kernel's width: kappa ~ 0.3/m over a few cm) the Taylor series to y^9, in Estrin's form
// (the truncation, y^10 / 10!, is below 3e-22 of y there); else std::expm1. Within 1e-15 relative of
// the exact value on [0, 1/32] (tests/base/test_math.cpp, against long double; glibc's expm1 is
// ~4 ns, this ~1 ns, measured in a tight loop).
TPB_HOT_INLINE double oneMinusExpNeg(double y) {
    if (!(y >= 0.0 && y <= 0.03125)) return -std::expm1(-y);
    constexpr double c2 = -1.0 / 2.0, c3 = 1.0 / 6.0, c4 = -1.0 / 24.0, c5 = 1.0 / 120.0, c6 = -1.0 / 720.0,
                     c7 = 1.0 / 5040.0, c8 = -1.0 / 40320.0, c9 = 1.0 / 362880.0;
    const double y2 = y * y, y4 = y2 * y2;
    const double lo = (1.0 + c2 * y) + (c3 + c4 * y) * y2;
    const double hi = (c5 + c6 * y) + (c7 + c8 * y) * y2;
    return y * (lo + (hi + c9 * y * y4) * y4);
}

// std::nextafter(f, up ? +inf : -inf), from the float's bits (the libm call was 9 % of building
// the beam pieces' BVH, which rounds every box outward to float): tests/base/test_math.cpp.
inline float nextFloat(float f, bool up) {
    if (std::isnan(f) || f == (up ? INFINITY : -INFINITY)) return f;
    if (f == 0.0f) return up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    bits = ((f > 0.0f) == up) ? bits + 1 : bits - 1;  // away from zero, or towards it
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

// Orthonormal basis around a unit vector n (Duff et al. 2017, branchless).
inline void coordinateSystem(const Vec3& n, Vec3& t, Vec3& b) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double bb = n.x * n.y * a;
    t = Vec3(1.0 + sign * n.x * n.x * a, sign * bb, -sign * n.x);
    b = Vec3(bb, sign + n.y * n.y * a, -n.y);
}

struct Bounds3 {
    Vec3 lo{kInf, kInf, kInf};
    Vec3 hi{-kInf, -kInf, -kInf};
    void expand(const Vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void expand(const Bounds3& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    bool valid() const { return lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z; }
    double diagonal() const { return valid() ? glm::length(hi - lo) : 0.0; }
    Vec3 center() const { return 0.5 * (lo + hi); }
};

struct Ray {
    Vec3 o;
    Vec3 d;  // unit direction
    double tmin = 0.0;
    double tmax = kInf;
    Vec3 at(double t) const { return o + t * d; }
};

}  // namespace tpb
