// The surface kernel's area (estimators/kernel_area.h, and SurfacePpmEstimator::kernelArea):
//  - discTriangleArea against Monte Carlo quadrature on random discs and triangles of every
//    relative size and position (5e5 points each: a standard error under 0.1 % of the disc), and
//    its limits exactly: the disc inside the triangle (pi R^2), the triangle inside the disc (its
//    area), the disc centred on an edge (half), on a square's corner (a quarter, over its two
//    triangles), outside (0), either orientation;
//  - ballTriangleArea: the disc of radius sqrt(r^2 - d^2) at distance d from the plane;
//  - Geometry::forEachPrimitiveNear reports the triangles and spheres within reach;
//  - the estimator's kernel area in a scene: pi r^2 inside a floor, half at a wall's foot, a quarter
//    in a room's corner, the floor's part beside a mirror tile, a thin slab's back face ignored,
//    pi r^2 on a sphere and where a tilted (curved) neighbour is in reach.
#include "estimators/kernel_area.h"
#include "estimators/surface_ppm.h"
#include "scene/scene.h"
#include "support/scene_builder.h"
#include "transport/stages.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace tpb;
using tpb::test::SceneBuilder;

namespace {

bool insideTriangle(Vec2d p, Vec2d a, Vec2d b, Vec2d c) {
    const auto side = [](Vec2d u, Vec2d v, Vec2d w) { return (v.x - u.x) * (w.y - u.y) - (v.y - u.y) * (w.x - u.x); };
    const double s0 = side(a, b, p), s1 = side(b, c, p), s2 = side(c, a, p);
    return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

// Monte Carlo estimate of the area of disc(0, R) n triangle and its standard error.
std::pair<double, double> monteCarlo(double R, Vec2d a, Vec2d b, Vec2d c, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int n = 500'000;
    int hits = 0;
    for (int i = 0; i < n; ++i) {
        const double rho = R * std::sqrt(u(rng)), phi = 2.0 * kPi * u(rng);
        hits += insideTriangle({rho * std::cos(phi), rho * std::sin(phi)}, a, b, c);
    }
    const double p = static_cast<double>(hits) / n;
    return {kPi * R * R * p, kPi * R * R * std::sqrt(p * (1.0 - p) / n)};
}

}  // namespace

TEST(KernelArea, DiscTriangleMatchesMonteCarlo) {
    std::mt19937_64 rng(33);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    double worstZ = 0.0;
    for (int k = 0; k < 24; ++k) {
        const double R = 0.1 + 0.9 * (u(rng) + 1.0);  // 0.1 .. 1.9: triangles inside, around, across
        const Vec2d a{u(rng), u(rng)}, b{u(rng), u(rng)}, c{u(rng), u(rng)};
        const double exact = discTriangleArea(R, a, b, c);
        const auto [mc, se] = monteCarlo(R, a, b, c, rng);
        const double z = (exact - mc) / std::max(se, 1e-12);
        worstZ = std::max(worstZ, std::abs(z));
        EXPECT_LT(std::abs(z), 5.0) << "case " << k << ": " << exact << " vs " << mc << " +- " << se;
        EXPECT_NEAR(discTriangleArea(R, a, c, b), exact, 1e-12);  // either orientation
        EXPECT_NEAR(discTriangleArea(R, b, c, a), exact, 1e-12);
    }
    std::printf("disc n triangle vs Monte Carlo: worst |z| %.2f over 24 cases\n", worstZ);
}

TEST(KernelArea, DiscTriangleLimits) {
    const double R = 0.3, disc = kPi * R * R;
    // The disc inside a large triangle, centred anywhere at least R from its edges.
    EXPECT_NEAR(discTriangleArea(R, {-10, -10}, {10, -10}, {0, 10}), disc, 1e-14);
    EXPECT_NEAR(discTriangleArea(R, {-1, -0.3 - 1e-12}, {10, -0.3 - 1e-12}, {-1, 10}), disc, 1e-12);
    // The triangle inside the disc: its area, 0.5 |(-0.1, 0.1) x (-0.2, -0.1)| = 0.015.
    EXPECT_NEAR(discTriangleArea(R, {0.1, 0}, {0, 0.1}, {-0.1, -0.1}), 0.015, 1e-15);
    // Centred on an edge: half (the other side of the edge is off the triangle).
    EXPECT_NEAR(discTriangleArea(R, {-10, 0}, {10, 0}, {0, 10}), 0.5 * disc, 1e-13);
    // A square's corner, over its two triangles: a quarter.
    const Vec2d o{0, 0}, p{5, 0}, q{5, 5}, s{0, 5};
    EXPECT_NEAR(discTriangleArea(R, o, p, q) + discTriangleArea(R, o, q, s), 0.25 * disc, 1e-13);
    // A square's corner off the diagonal's end: the two triangles split the quarter unequally.
    EXPECT_NEAR(discTriangleArea(R, o, p, s) + discTriangleArea(R, p, q, s), 0.25 * disc, 1e-13);
    // Past an edge at distance h: the circular segment R^2 acos(h/R) - h sqrt(R^2 - h^2) is missing.
    const double h = 0.1;
    const double segment = R * R * std::acos(h / R) - h * std::sqrt(R * R - h * h);
    EXPECT_NEAR(discTriangleArea(R, {-10, -h}, {10, -h}, {0, 10}), disc - segment, 1e-13);
    // Outside, and degenerate.
    EXPECT_EQ(discTriangleArea(R, {1, 1}, {2, 1}, {1, 2}), 0.0);
    EXPECT_EQ(discTriangleArea(R, {-1, 0}, {0, 0}, {1, 0}), 0.0);
    EXPECT_EQ(discTriangleArea(0.0, {-1, -1}, {1, -1}, {0, 1}), 0.0);
}

TEST(KernelArea, BallTriangleIsTheDiscCutByThePlane) {
    const Vec3 a(-5, 2, -5), b(-5, 2, 5), c(5, 2, 0);  // the plane y = 2
    const double r = 0.5;
    EXPECT_NEAR(ballTriangleArea(Vec3(0, 2, 0), r, a, b, c), kPi * r * r, 1e-13);
    EXPECT_NEAR(ballTriangleArea(Vec3(0, 2.3, 0), r, a, b, c), kPi * (r * r - 0.09), 1e-13);
    EXPECT_NEAR(ballTriangleArea(Vec3(0, 1.7, 0), r, a, b, c), kPi * (r * r - 0.09), 1e-13);
    EXPECT_EQ(ballTriangleArea(Vec3(0, 2.5, 0), r, a, b, c), 0.0);
    EXPECT_NEAR(ballTriangleArea(Vec3(-5, 2, 0), r, a, b, c), 0.5 * kPi * r * r, 1e-13);  // on the edge x = -5
    EXPECT_EQ(ballTriangleArea(Vec3(0, 2, 0), r, a, a, c), 0.0);                          // degenerate
}

namespace {

// A room's floor (y = 0, 2 m x 2 m, two triangles) and back wall (z = -1), a mirror tile in the
// floor, a thin slab lying on the floor (its bottom face 1 mm under its top), a sphere, and a ramp.
struct KernelScene {
    std::unique_ptr<const Scene> scene;
    SurfacePpmEstimator est;
    double r = 0.05;

    KernelScene() {
        SceneBuilder b;
        b.camera(Vec3(0, 1, 3), Vec3(0, 0, 0), 40.0, 4, 4).film(0.0, 0.1, 10);
        const int white = b.diffuse(Color(0.5));
        b.quad(Vec3(-1, 0, -1), Vec3(0, 0, 2), Vec3(2, 0, 0), white);                   // floor, normal +y
        b.quad(Vec3(-1, 0, -1), Vec3(2, 0, 0), Vec3(0, 2, 0), white);                   // back wall z = -1, normal +z
        b.quad(Vec3(1, 0, 0.5), Vec3(0, 0, 0.5), Vec3(1, 0, 0), b.mirror(Color(0.9)));  // mirror tile x in [1, 2]
        b.quad(Vec3(-3, 0, -1), Vec3(0, 0, 1), Vec3(1, 0, 0), white);                   // floor x in [-3, -2] ...
        b.quad(Vec3(-3, -0.001, -1), Vec3(1, 0, 0), Vec3(0, 0, 1), white);              // ... a slab 1 mm thick
        b.sphere(Vec3(0, 0.5, 5), 0.3, white);
        b.quad(Vec3(-1, 0, 2), Vec3(0, 0, 1), Vec3(2, 0, 0), white);    // floor z in [2, 3] ...
        b.quad(Vec3(-1, 0, 3), Vec3(0, 0.2, 1), Vec3(2, 0, 0), white);  // ... then a ramp
        b.pointLight(Vec3(0, 1, 0), Color(1.0));
        scene = Scene::build(b.desc(), analyzeStages);
        PhotonMap map;
        EstimatorPass pass;
        pass.radius = r;
        est.prepare(*scene, map, pass);
    }
    double area(const Vec3& x, const Vec3& n = Vec3(0, 1, 0)) const { return est.kernelArea(x, n); }
};

}  // namespace

TEST(KernelArea, GeometryReportsPrimitivesWithinReach) {
    KernelScene k;
    int triangles = 0, spheres = 0;
    k.scene->geometry.forEachPrimitiveNear(Vec3(0, 0.5, 4.75), 0.1, [&](const Geometry::Primitive& p) {
        triangles += !p.sphere;
        spheres += p.sphere;
        if (p.sphere) {
            EXPECT_EQ(p.v[0], Vec3(0, 0.5, 5));
            EXPECT_EQ(p.radius, 0.3);
        }
    });
    EXPECT_EQ(spheres, 1);
    EXPECT_EQ(triangles, 0);
    std::vector<int> shapes;
    k.scene->geometry.forEachPrimitiveNear(Vec3(0.3, 0.0, -0.98), 0.05,
                                           [&](const Geometry::Primitive& p) { shapes.push_back(p.shape); });
    EXPECT_GE(std::count(shapes.begin(), shapes.end(), 0), 1);  // the floor
    EXPECT_GE(std::count(shapes.begin(), shapes.end(), 1), 1);  // the wall
}

TEST(KernelArea, EstimatorCountsTheSurfaceTheDiscCovers) {
    KernelScene k;
    const double disc = kPi * k.r * k.r;
    EXPECT_EQ(k.area(Vec3(0.3, 0, 0.2)), disc);                       // inside the floor, across its diagonal: exactly
    EXPECT_NEAR(k.area(Vec3(0.3, 0, -1)), 0.5 * disc, 1e-12 * disc);  // at the wall's foot
    EXPECT_NEAR(k.area(Vec3(0.3, 0, 1)), 0.5 * disc, 1e-12 * disc);   // at the floor's open edge
    EXPECT_NEAR(k.area(Vec3(-1, 0, -1)), 0.25 * disc, 1e-12 * disc);  // in the room's corner
    const double h = 0.02;                                            // 2 cm from the wall
    const double segment = k.r * k.r * std::acos(h / k.r) - h * std::sqrt(k.r * k.r - h * h);
    EXPECT_NEAR(k.area(Vec3(0.3, 0, -1 + h)), disc - segment, 1e-12 * disc);
    // The wall's own disc at its foot: half (the floor is perpendicular to it).
    EXPECT_NEAR(k.area(Vec3(0.3, 0, -1), Vec3(0, 0, 1)), 0.5 * disc, 1e-12 * disc);
    // Beside the mirror tile (x = 1): only the floor's half counts (no photon lands on a mirror).
    EXPECT_NEAR(k.area(Vec3(1, 0, 0.7)), 0.5 * disc, 1e-12 * disc);
    // The slab's top at its middle: its bottom face 1 mm below is not its surface.
    EXPECT_EQ(k.area(Vec3(-2.5, 0, -0.5)), disc);
    // On the sphere, and next to the ramp (a tilted neighbour): the disc.
    EXPECT_EQ(k.area(Vec3(0, 0.8, 5)), disc);
    EXPECT_EQ(k.area(Vec3(0, 0, 2.98)), disc);
    EXPECT_NEAR(k.area(Vec3(0, 0, 2.0)), 0.5 * disc, 1e-12 * disc);  // the same floor's other edge
}

TEST(KernelArea, HitTriangleShortcutGivesTheSameArea) {
    KernelScene k;
    int shortcuts = 0;
    for (double x = -0.99; x < 1.0; x += 0.0173)
        for (double z = -0.99; z < 1.0; z += 0.0191) {
            const auto hit = k.scene->geometry.intersect(Ray{Vec3(x, 1.5, z), Vec3(0, -1, 0)});
            ASSERT_TRUE(hit);
            ASSERT_EQ(hit->shape, 0);  // the floor
            const double withHit = k.est.kernelArea(hit->p, Vec3(0, 1, 0), hit->shape, hit->prim);
            const double searched = k.area(hit->p);
            ASSERT_NEAR(withHit, searched, 1e-12 * searched) << x << ", " << z;
            Vec3 t[3];
            ASSERT_TRUE(k.scene->geometry.triangle(hit->shape, hit->prim, t));
            shortcuts += withHit == kPi * k.r * k.r;
        }
    EXPECT_GT(shortcuts, 8000);  // most of the floor is more than r from its edges and diagonal
    Vec3 t[3];
    EXPECT_FALSE(k.scene->geometry.triangle(5, 0, t));  // the sphere
}
