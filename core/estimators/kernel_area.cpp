#include "estimators/kernel_area.h"

#include <algorithm>
#include <cmath>

namespace tpb {

namespace {

double cross(Vec2d u, Vec2d v) { return u.x * v.y - u.y * v.x; }
double dot(Vec2d u, Vec2d v) { return u.x * v.x + u.y * v.y; }

// Signed area of the disc (origin, R) intersected with the triangle (origin, p, q): the segment
// p -> q is split where it crosses the circle; its pieces inside the disc give triangles
// (origin, u, v), those outside circular sectors of the angle they subtend.
double edgePiece(double R, Vec2d p, Vec2d q) {
    const double R2 = R * R;
    const auto sector = [R2](Vec2d u, Vec2d v) { return 0.5 * R2 * std::atan2(cross(u, v), dot(u, v)); };
    const Vec2d d{q.x - p.x, q.y - p.y};
    const double a = dot(d, d);
    if (!(a > 0.0)) return 0.0;
    const double b = dot(p, d);
    const double c = dot(p, p) - R2;
    const double disc = b * b - a * c;
    if (!(disc > 0.0)) return sector(p, q);  // the line misses the disc (or touches it)
    const double s = std::sqrt(disc);
    const double t0 = std::clamp((-b - s) / a, 0.0, 1.0);
    const double t1 = std::clamp((-b + s) / a, 0.0, 1.0);
    const Vec2d u{p.x + t0 * d.x, p.y + t0 * d.y};
    const Vec2d v{p.x + t1 * d.x, p.y + t1 * d.y};
    return sector(p, u) + 0.5 * cross(u, v) + sector(v, q);
}

}  // namespace

double discTriangleArea(double R, Vec2d a, Vec2d b, Vec2d c) {
    if (!(R > 0.0)) return 0.0;
    const double R2 = R * R;
    const double tri = 0.5 * std::abs(cross({b.x - a.x, b.y - a.y}, {c.x - a.x, c.y - a.y}));
    // The triangle inside the disc (its corners are; the disc is convex).
    if (dot(a, a) <= R2 && dot(b, b) <= R2 && dot(c, c) <= R2) return tri;
    const double s = edgePiece(R, a, b) + edgePiece(R, b, c) + edgePiece(R, c, a);
    return std::min(std::abs(s), std::min(tri, kPi * R2));
}

double ballTriangleArea(const Vec3& x, double r, const Vec3& a, const Vec3& b, const Vec3& c) {
    Vec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (!(len > 0.0) || !std::isfinite(len)) return 0.0;
    n /= len;
    const double d = glm::dot(x - a, n);
    const double R2 = r * r - d * d;
    if (!(R2 > 0.0)) return 0.0;
    // An orthonormal basis (u, v) of the plane; coordinates relative to x's projection.
    const Vec3 e = b - a;
    const Vec3 u = e / glm::length(e);
    const Vec3 v = glm::cross(n, u);
    const auto at = [&](const Vec3& p) { return Vec2d{glm::dot(p - x, u), glm::dot(p - x, v)}; };
    return discTriangleArea(std::sqrt(R2), at(a), at(b), at(c));
}

}  // namespace tpb
