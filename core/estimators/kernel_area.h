// Areas of a kernel's support on a surface: the disc (or ball) of radius r around a gather point
// cut by triangles, in closed form. Used by the surface estimator to normalise its kernel over the
// surface it actually covers (docs/developer/adding-an-estimator.md, "The surface kernel at
// edges").
#pragma once
#include "base/math.h"

namespace tpb {

struct Vec2d {
    double x = 0.0, y = 0.0;
};

// Area of the disc of radius R centred at the origin intersected with the triangle (a, b, c),
// either orientation: exact (a sum over the triangle's edges of signed circle-triangle pieces).
double discTriangleArea(double R, Vec2d a, Vec2d b, Vec2d c);

// Area of the part of triangle (a, b, c) within distance r of x (the ball of radius r cut by the
// triangle's plane is a disc of radius sqrt(r^2 - d^2), d the distance from x to the plane).
// 0 for a degenerate triangle.
double ballTriangleArea(const Vec3& x, double r, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace tpb
