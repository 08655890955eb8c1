// Basic types and constants shared by the whole core.
// Positions and directions are double precision (glm::dvec3); time is optical path length (OPL)
// in meters, also double. Colours are linear RGB triples.
#pragma once
#include <glm/glm.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

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
    void expand(const Vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void expand(const Bounds3& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
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
