// Geometry (Embree) and mesh tests: ray casts against analytic references, OBJ loading.
#include "base/error.h"
#include "scene/geometry.h"
#include "scene/mesh.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

using namespace tpb;

namespace {

// ---- helpers ------------------------------------------------------------------------------------

struct Rng {
    std::mt19937_64 gen;
    explicit Rng(uint64_t seed) : gen(seed) {}
    double uniform(double a = 0.0, double b = 1.0) { return std::uniform_real_distribution<double>(a, b)(gen); }
    Vec3 unitVector() {
        for (;;) {
            const Vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
            const double l2 = glm::dot(v, v);
            if (l2 > 1e-4 && l2 <= 1.0) return v / std::sqrt(l2);
        }
    }
    Vec3 inBall(double r) {
        for (;;) {
            const Vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
            if (glm::dot(v, v) <= 1.0) return r * v;
        }
    }
};

double relErr(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

// Independent reference for ray-sphere: geometric construction in long double (projection of
// the centre on the ray, then half chord). Returns roots t0 <= t1 and the "margin"
// r^2 - h^2 (h = distance centre-line) relative to r^2, to tell clear hits/misses from tangents.
struct SphereRef {
    bool hit = false;
    long double t0 = 0, t1 = 0;
    long double margin = 0;
};
SphereRef sphereReference(const Vec3& o, const Vec3& d, const Vec3& c, double r) {
    using L = long double;
    const L ox = o.x, oy = o.y, oz = o.z, dx = d.x, dy = d.y, dz = d.z;
    const L cx = L(c.x) - ox, cy = L(c.y) - oy, cz = L(c.z) - oz;  // centre relative to origin
    const L dd = dx * dx + dy * dy + dz * dz;
    const L tc = (cx * dx + cy * dy + cz * dz) / dd;
    const L hx = cx - tc * dx, hy = cy - tc * dy, hz = cz - tc * dz;
    const L h2 = hx * hx + hy * hy + hz * hz;
    const L r2 = L(r) * L(r);
    SphereRef ref;
    ref.margin = (r2 - h2) / r2;
    if (h2 > r2) return ref;
    const L half = std::sqrt((r2 - h2) / dd);
    ref.hit = true;
    ref.t0 = tc - half;
    ref.t1 = tc + half;
    return ref;
}
// Expected hit in (tmin, tmax), or -1 for none.
double sphereExpected(const SphereRef& ref, double tmin, double tmax) {
    if (!ref.hit) return -1.0;
    if (ref.t0 > tmin && ref.t0 < tmax) return double(ref.t0);
    if (ref.t1 > tmin && ref.t1 < tmax) return double(ref.t1);
    return -1.0;
}

Ray makeRay(const Vec3& o, const Vec3& d, double tmin = 0.0, double tmax = kInf) {
    Ray r;
    r.o = o;
    r.d = glm::normalize(d);
    r.tmin = tmin;
    r.tmax = tmax;
    return r;
}

void expectUnit(const Vec3& v, double tol = 1e-12) { EXPECT_NEAR(glm::length(v), 1.0, tol); }

// Checks one sphere query against the reference; `skipNearTangent` ignores rays whose margin is
// so small that double precision itself cannot decide.
void checkSphereRay(const Geometry& g, const Ray& ray, const Vec3& c, double r, int shapeId, int& hits, int& misses) {
    const SphereRef ref = sphereReference(ray.o, ray.d, c, r);
    if (ref.hit && std::abs(double(ref.margin)) < 1e-10) return;  // numerically tangent
    if (!ref.hit && std::abs(double(ref.margin)) < 1e-10) return;
    const double expected = sphereExpected(ref, ray.tmin, ray.tmax);
    // Roots within rounding of tmin: either answer is right.
    if (ref.hit && (std::abs(double(ref.t0) - ray.tmin) < 1e-9 * r || std::abs(double(ref.t1) - ray.tmin) < 1e-9 * r))
        return;
    const auto h = g.intersect(ray);
    EXPECT_EQ(g.occluded(ray), h.has_value());
    if (expected < 0.0) {
        EXPECT_FALSE(h.has_value()) << "unexpected hit at t=" << h->t;
        ++misses;
        return;
    }
    ++hits;
    ASSERT_TRUE(h.has_value()) << "missed, expected t=" << expected;
    EXPECT_LT(relErr(h->t, expected), 1e-9) << h->t << " vs " << expected;
    EXPECT_GT(h->t, ray.tmin);
    EXPECT_LT(h->t, ray.tmax);
    EXPECT_EQ(h->shape, shapeId);
    EXPECT_EQ(h->prim, 0);
    const Vec3 p = ray.o + h->t * ray.d;
    EXPECT_LT(glm::length(h->p - p), 1e-12 * (1.0 + glm::length(p)));
    expectUnit(h->ng);
    EXPECT_LT(glm::length(h->ng - (h->p - c) / r), 1e-8);
    EXPECT_EQ(h->ns, h->ng);
}

std::filesystem::path tempDir() {
    const auto dir = std::filesystem::temp_directory_path() / ("tpb_test_geometry_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir;
}

// Removes the temporary folder after all tests.
struct TempDirCleanup : ::testing::Environment {
    void TearDown() override {
        std::error_code ec;
        std::filesystem::remove_all(tempDir(), ec);
    }
};
[[maybe_unused]] ::testing::Environment* const kTempDirCleanup =
    ::testing::AddGlobalTestEnvironment(new TempDirCleanup);

std::string writeFile(const std::string& name, const std::string& text) {
    const auto path = tempDir() / name;
    std::ofstream(path) << text;
    return path.string();
}

}  // namespace

// ---- spheres ---------------------------------------------------------------------------------

TEST(GeometrySphere, RaysFromOutsideMatchClosedForm) {
    const Vec3 c(0.3, -0.2, 0.5);
    const double r = 1.7;
    Geometry g;
    g.addSphere(c, r, 7);
    g.commit();
    EXPECT_EQ(g.sphereCount(), 1u);
    EXPECT_EQ(g.triangleCount(), 0u);

    Rng rng(12345);
    int hits = 0, misses = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 o = c + rng.uniform(1.05, 20.0) * r * rng.unitVector();
        // Aim at a random point of a slightly bigger ball: most rays hit, some miss.
        const Vec3 target = c + rng.inBall(1.3 * r);
        checkSphereRay(g, makeRay(o, target - o), c, r, 7, hits, misses);
    }
    EXPECT_GT(hits, 8000);
    EXPECT_GT(misses, 2000);
}

TEST(GeometrySphere, RaysFromInsideHitFarSide) {
    const Vec3 c(-2.0, 1.0, 3.0);
    const double r = 0.8;
    Geometry g;
    g.addSphere(c, r, 3);
    g.commit();
    Rng rng(777);
    int hits = 0, misses = 0;
    for (int i = 0; i < 20000; ++i) {
        const Ray ray = makeRay(c + rng.inBall(0.999 * r), rng.unitVector());
        checkSphereRay(g, ray, c, r, 3, hits, misses);
        const auto h = g.intersect(ray);
        ASSERT_TRUE(h.has_value());
        EXPECT_GT(glm::dot(h->ng, ray.d), 0.0);  // leaving: outward normal along the ray
    }
    EXPECT_EQ(misses, 0);
}

TEST(GeometrySphere, RaysStartingOnSurfaceWithTmin) {
    const Vec3 c(1.0, 2.0, -1.0);
    const double r = 2.5;
    Geometry g;
    g.addSphere(c, r, 0);
    g.commit();
    Rng rng(4242);
    int hits = 0, misses = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 n = rng.unitVector();
        const Vec3 o = c + r * n;
        Vec3 d = rng.unitVector();
        const double cosTheta = glm::dot(d, n);
        if (std::abs(cosTheta) < 1e-3) continue;  // chord shorter than a few tmin
        const Ray ray = makeRay(o, d, 1e-6 * r);
        checkSphereRay(g, ray, c, r, 0, hits, misses);
        const auto h = g.intersect(ray);
        if (cosTheta > 0.0) {
            EXPECT_FALSE(h.has_value()) << "ray leaving the surface must not hit itself";
        } else {
            ASSERT_TRUE(h.has_value());
            EXPECT_LT(relErr(h->t, -2.0 * r * cosTheta), 1e-9);
        }
    }
    EXPECT_GT(hits, 9000);
    EXPECT_GT(misses, 9000);
}

TEST(GeometrySphere, MissesAndTangentRays) {
    const Vec3 c(0.0, 0.0, 0.0);
    const double r = 1.0;
    Geometry g;
    g.addSphere(c, r, 1);
    g.commit();
    Rng rng(99);
    for (int i = 0; i < 5000; ++i) {
        // A line at distance b from the centre, along direction d, starting far before it.
        const Vec3 d = rng.unitVector();
        Vec3 u, v;
        coordinateSystem(d, u, v);
        const double delta = std::pow(10.0, rng.uniform(-6.0, -2.0));
        const double phi = rng.uniform(0.0, 2.0 * kPi);
        const Vec3 side = std::cos(phi) * u + std::sin(phi) * v;
        const double back = rng.uniform(2.0, 50.0);
        // Just inside: hits, twice, close to each other.
        const Ray in = makeRay(c + (1.0 - delta) * r * side - back * d, d);
        int hits = 0, misses = 0;
        checkSphereRay(g, in, c, r, 1, hits, misses);
        EXPECT_EQ(hits, 1);
        // Just outside: misses.
        const Ray out = makeRay(c + (1.0 + delta) * r * side - back * d, d);
        EXPECT_FALSE(g.intersect(out).has_value());
        EXPECT_FALSE(g.occluded(out));
        // Pointing away from the sphere from outside: misses.
        const Ray away = makeRay(c + back * d, d);
        EXPECT_FALSE(g.intersect(away).has_value());
        EXPECT_FALSE(g.occluded(away));
    }
}

TEST(GeometrySphere, BigSphereAndDistantOrigins) {
    // A planet-sized ground sphere: rays from just above its top, and from very far away.
    const Vec3 c(0.0, -1e4, 0.0);
    const double r = 1e4;
    Geometry g;
    g.addSphere(c, r, 5);
    g.commit();
    Rng rng(2024);
    int hits = 0, misses = 0;
    for (int i = 0; i < 10000; ++i) {
        const Vec3 o(rng.uniform(-10, 10), rng.uniform(0.01, 10.0), rng.uniform(-10, 10));
        const Vec3 d = Vec3(rng.uniform(-1, 1), rng.uniform(-1, -0.01), rng.uniform(-1, 1));
        checkSphereRay(g, makeRay(o, d), c, r, 5, hits, misses);
    }
    EXPECT_GT(hits, 9000);
    // Small sphere seen from 1e5 away.
    Geometry g2;
    const Vec3 c2(1.0, 2.0, 3.0);
    g2.addSphere(c2, 0.5, 2);
    g2.commit();
    for (int i = 0; i < 2000; ++i) {
        const Vec3 o = c2 + 1e5 * rng.unitVector();
        checkSphereRay(g2, makeRay(o, c2 + rng.inBall(0.6) - o), c2, 0.5, 2, hits, misses);
    }
}

TEST(GeometrySphere, TmaxAndTminAreRespected) {
    const Vec3 c(0.0, 0.0, 5.0);
    Geometry g;
    g.addSphere(c, 1.0, 0);
    g.commit();
    const Vec3 o(0.1, -0.2, 0.0), d = glm::normalize(Vec3(0.0, 0.0, 1.0));
    const SphereRef ref = sphereReference(o, d, c, 1.0);
    ASSERT_TRUE(ref.hit);
    const double t0 = double(ref.t0), t1 = double(ref.t1);
    EXPECT_FALSE(g.intersect(makeRay(o, d, 0.0, t0 * (1 - 1e-12))).has_value());
    EXPECT_FALSE(g.occluded(makeRay(o, d, 0.0, t0 * (1 - 1e-12))));
    auto h = g.intersect(makeRay(o, d, 0.0, t0 * (1 + 1e-12)));
    ASSERT_TRUE(h.has_value());
    EXPECT_LT(relErr(h->t, t0), 1e-12);
    EXPECT_TRUE(g.occluded(makeRay(o, d, 0.0, t0 * (1 + 1e-12))));
    // tmin past the near root: the far root.
    h = g.intersect(makeRay(o, d, t0 * (1 + 1e-9)));
    ASSERT_TRUE(h.has_value());
    EXPECT_LT(relErr(h->t, t1), 1e-12);
    EXPECT_GT(glm::dot(h->ng, d), 0.0);
    // Interval strictly between the roots: nothing.
    EXPECT_FALSE(g.intersect(makeRay(o, d, t0 * 1.001, t1 * 0.999)).has_value());
    EXPECT_FALSE(g.occluded(makeRay(o, d, t0 * 1.001, t1 * 0.999)));
    // Both past.
    EXPECT_FALSE(g.intersect(makeRay(o, d, t1 * 1.001)).has_value());
}

// ---- quads ------------------------------------------------------------------------------------

namespace {
struct QuadRef {
    bool hit = false;
    double t = 0, s = 0, u = 0;  // ray parameter and (s, u) coordinates along edgeU, edgeV
};
// Ray-plane intersection and parallelogram coordinates, in long double.
QuadRef quadReference(const Vec3& corner, const Vec3& U, const Vec3& V, const Ray& ray) {
    using L = long double;
    auto dot = [](const Vec3& a, const Vec3& b) { return L(a.x) * L(b.x) + L(a.y) * L(b.y) + L(a.z) * L(b.z); };
    const Vec3 n = glm::cross(U, V);
    QuadRef q;
    const L denom = dot(ray.d, n);
    if (denom == 0) return q;
    const L t = (dot(corner, n) - dot(ray.o, n)) / denom;
    // Point relative to the corner, then solve [U V] (s u)^T = w by the 2x2 Gram system.
    const L wx = L(ray.o.x) + t * L(ray.d.x) - L(corner.x);
    const L wy = L(ray.o.y) + t * L(ray.d.y) - L(corner.y);
    const L wz = L(ray.o.z) + t * L(ray.d.z) - L(corner.z);
    const L wu = wx * U.x + wy * U.y + wz * U.z, wv = wx * V.x + wy * V.y + wz * V.z;
    const L uu = dot(U, U), uv = dot(U, V), vv = dot(V, V);
    const L det = uu * vv - uv * uv;
    q.s = double((wu * vv - wv * uv) / det);
    q.u = double((wv * uu - wu * uv) / det);
    q.t = double(t);
    q.hit = t > ray.tmin && t < ray.tmax && q.s >= 0 && q.s <= 1 && q.u >= 0 && q.u <= 1;
    return q;
}
}  // namespace

TEST(GeometryQuad, RandomRaysMatchRayPlaneReference) {
    Rng rng(31337);
    for (int quad = 0; quad < 5; ++quad) {
        const Vec3 corner(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3));
        const Vec3 U = rng.uniform(0.5, 3.0) * rng.unitVector();
        Vec3 V = rng.uniform(0.5, 3.0) * rng.unitVector();
        if (glm::length(glm::cross(glm::normalize(U), glm::normalize(V))) < 0.3) V = glm::cross(U, V);
        const TriangleMesh mesh = makeQuad(corner, U, V);
        ASSERT_EQ(mesh.triangles.size(), 2u);
        Geometry g;
        g.addMesh(mesh, 10 + quad);
        g.commit();
        EXPECT_EQ(g.triangleCount(), 2u);
        const Vec3 n = glm::normalize(glm::cross(U, V));
        const Vec3 center = corner + 0.5 * (U + V);
        int hits = 0, misses = 0;
        for (int i = 0; i < 10000; ++i) {
            const Vec3 o = center + rng.uniform(0.2, 8.0) * rng.unitVector();
            const Vec3 target = corner + rng.uniform(-0.2, 1.2) * U + rng.uniform(-0.2, 1.2) * V;
            const Ray ray = makeRay(o, target - o);
            const QuadRef ref = quadReference(corner, U, V, ray);
            const auto h = g.intersect(ray);
            EXPECT_EQ(g.occluded(ray), h.has_value());
            // Skip rays within float rounding of an edge, or nearly parallel to the plane.
            const double edge = std::min({std::abs(ref.s), std::abs(ref.s - 1), std::abs(ref.u), std::abs(ref.u - 1)});
            if (edge < 1e-4 || std::abs(glm::dot(ray.d, n)) < 1e-3) continue;
            if (!ref.hit) {
                EXPECT_FALSE(h.has_value()) << "s=" << ref.s << " u=" << ref.u << " t=" << ref.t;
                ++misses;
                continue;
            }
            ++hits;
            ASSERT_TRUE(h.has_value()) << "s=" << ref.s << " u=" << ref.u;
            // The float vertices move the plane by ~1e-7: t error grows as the ray grazes.
            const double cosTheta = std::abs(glm::dot(ray.d, n));
            EXPECT_LT(relErr(h->t, ref.t), 1e-5 * std::max(1.0, 0.1 / cosTheta)) << cosTheta;
            EXPECT_EQ(h->shape, 10 + quad);
            // Triangle 0 is (c, c+U, c+U+V): s >= u; triangle 1 is (c, c+U+V, c+V).
            if (std::abs(ref.s - ref.u) > 1e-4) {
                EXPECT_EQ(h->prim, ref.s > ref.u ? 0 : 1);
            }
            expectUnit(h->ng);
            EXPECT_LT(glm::length(h->ng - n), 1e-6);
            EXPECT_EQ(h->ns, h->ng);
            EXPECT_LT(glm::length(h->p - (ray.o + h->t * ray.d)), 1e-12 * (1 + glm::length(h->p)));
            // The hit point lies on the plane far more precisely than float t would give.
            EXPECT_LT(std::abs(glm::dot(h->p - corner, n)), 1e-6);
        }
        EXPECT_GT(hits, 3000);
        EXPECT_GT(misses, 500);
    }
}

TEST(GeometryQuad, HitsOnTheSharedDiagonalAreNotMissed) {
    Rng rng(5150);
    // Axis-aligned quad where diagonal points are exactly representable: rays straight down.
    {
        Geometry g;
        g.addMesh(makeQuad(Vec3(0.0), Vec3(1, 0, 0), Vec3(0, 1, 0)), 0);
        g.commit();
        int missed = 0;
        for (int k = 1; k < 1024; ++k) {
            const double lambda = k / 1024.0;
            const Ray down = makeRay(Vec3(lambda, lambda, 1.0), Vec3(0, 0, -1));
            const Ray up = makeRay(Vec3(lambda, lambda, -1.0), Vec3(0, 0, 1));
            for (const Ray& ray : {down, up}) {
                const auto h = g.intersect(ray);
                if (!h) {
                    ++missed;
                    continue;
                }
                EXPECT_NEAR(h->t, 1.0, 1e-12);
                EXPECT_LT(glm::length(h->ng - Vec3(0, 0, 1)), 1e-15);
                EXPECT_TRUE(g.occluded(ray));
            }
        }
        EXPECT_EQ(missed, 0);
    }
    // General quads: random origins aimed at points of the diagonal.
    for (int quad = 0; quad < 5; ++quad) {
        const Vec3 corner(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2));
        const Vec3 U = rng.uniform(0.5, 2.0) * rng.unitVector();
        const Vec3 V = glm::cross(U, rng.unitVector());
        if (glm::length(V) < 0.3) continue;
        Geometry g;
        g.addMesh(makeQuad(corner, U, V), 0);
        g.commit();
        const Vec3 n = glm::normalize(glm::cross(U, V));
        int missed = 0, tested = 0;
        for (int i = 0; i < 20000; ++i) {
            const Vec3 p = corner + rng.uniform(0.01, 0.99) * (U + V);
            const Vec3 o = p + rng.uniform(0.5, 5.0) * rng.unitVector();
            const Ray ray = makeRay(o, p - o);
            if (std::abs(glm::dot(ray.d, n)) < 1e-2) continue;
            ++tested;
            const auto h = g.intersect(ray);
            if (!h) {
                ++missed;
                continue;
            }
            EXPECT_LT(glm::length(h->p - p), 1e-5 * (1 + glm::length(o - p)));
            EXPECT_TRUE(g.occluded(ray));
        }
        EXPECT_GT(tested, 15000);
        EXPECT_EQ(missed, 0) << "rays through the shared diagonal went through the quad";
    }
}

TEST(GeometryQuad, TmaxTminAndOccludedAgree) {
    Geometry g;
    g.addMesh(makeQuad(Vec3(-1, -1, 2), Vec3(2, 0, 0), Vec3(0, 2, 0)), 4);
    g.commit();
    Rng rng(8);
    for (int i = 0; i < 2000; ++i) {
        const Vec3 o(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-1, 1));
        const Vec3 target(rng.uniform(-0.9, 0.9), rng.uniform(-0.9, 0.9), 2.0);
        const Ray ray = makeRay(o, target - o);
        const auto h = g.intersect(ray);
        ASSERT_TRUE(h.has_value());
        const double t = glm::length(target - o);
        EXPECT_LT(relErr(h->t, t), 1e-5);
        EXPECT_EQ(h->shape, 4);
        // Shortened / started past the hit: no hit, also for occluded.
        for (const Ray& r : {makeRay(o, target - o, 0.0, t * 0.999), makeRay(o, target - o, t * 1.001)}) {
            EXPECT_FALSE(g.intersect(r).has_value());
            EXPECT_FALSE(g.occluded(r));
        }
        const Ray longer = makeRay(o, target - o, t * 0.999, t * 1.001);
        EXPECT_TRUE(g.intersect(longer).has_value());
        EXPECT_TRUE(g.occluded(longer));
    }
}

// ---- boxes -------------------------------------------------------------------------------------

TEST(GeometryBox, MeshHasOutwardFacingTriangles) {
    const Vec3 lo(-1, -2, -3), hi(2, 1, 0.5);
    const TriangleMesh box = makeBox(lo, hi);
    ASSERT_EQ(box.triangles.size(), 12u);
    EXPECT_TRUE(box.normals.empty());
    const Vec3 center = 0.5 * (lo + hi);
    double area = 0;
    for (const auto& t : box.triangles) {
        const Vec3 a = box.positions[t.x], b = box.positions[t.y], c = box.positions[t.z];
        const Vec3 n = glm::cross(b - a, c - a);
        area += 0.5 * glm::length(n);
        EXPECT_GT(glm::dot(n, (a + b + c) / 3.0 - center), 0.0);
    }
    const Vec3 e = hi - lo;
    EXPECT_NEAR(area, 2 * (e.x * e.y + e.y * e.z + e.z * e.x), 1e-12);
    const Bounds3 b = box.bounds();
    EXPECT_EQ(b.lo, lo);
    EXPECT_EQ(b.hi, hi);
}

TEST(GeometryBox, RaysFromInsideHitTheWallWithOutwardNormal) {
    const Vec3 lo(-1, -0.5, 0), hi(1.5, 2, 1);
    Geometry g;
    g.addMesh(makeBox(lo, hi), 9);
    g.commit();
    EXPECT_EQ(g.triangleCount(), 12u);
    const Bounds3 b = g.bounds();
    EXPECT_LT(glm::length(b.lo - lo), 1e-7);
    EXPECT_LT(glm::length(b.hi - hi), 1e-7);
    Rng rng(6);
    int missed = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 o(rng.uniform(lo.x, hi.x), rng.uniform(lo.y, hi.y), rng.uniform(lo.z, hi.z));
        const Ray ray = makeRay(o, rng.unitVector());
        // Slab exit distance and axis.
        double tExit = kInf;
        int axis = -1;
        for (int k = 0; k < 3; ++k) {
            if (ray.d[k] == 0.0) continue;
            const double tk = ((ray.d[k] > 0 ? hi[k] : lo[k]) - o[k]) / ray.d[k];
            if (tk < tExit) {
                tExit = tk;
                axis = k;
            }
        }
        const auto h = g.intersect(ray);
        if (!h) {
            ++missed;
            continue;
        }
        EXPECT_EQ(h->shape, 9);
        EXPECT_LT(relErr(h->t, tExit), 1e-5);
        EXPECT_GT(glm::dot(h->ng, ray.d), 0.0);
        // Normal along the exit axis, unless the exit is within rounding of a box edge.
        Vec3 expected(0.0);
        expected[axis] = ray.d[axis] > 0 ? 1.0 : -1.0;
        const Vec3 p = o + tExit * ray.d;
        double toEdge = kInf;
        for (int k = 0; k < 3; ++k)
            if (k != axis) toEdge = std::min({toEdge, std::abs(p[k] - lo[k]), std::abs(p[k] - hi[k])});
        if (toEdge > 1e-5) {
            EXPECT_LT(glm::length(h->ng - expected), 1e-12);
        }
        EXPECT_TRUE(g.occluded(ray));
    }
    EXPECT_EQ(missed, 0);
}

// ---- mixed scenes, robustness, threads -----------------------------------------------------

TEST(Geometry, ShapeIdsAndClosestHitAcrossShapes) {
    Geometry g;
    g.addMesh(makeQuad(Vec3(-5, -5, 10), Vec3(10, 0, 0), Vec3(0, 10, 0)), 100);  // faces +z
    g.addSphere(Vec3(0, 0, 5), 1.0, 200);
    g.addMesh(makeBox(Vec3(2, -1, 4), Vec3(4, 1, 6)), 300);
    g.addSphere(Vec3(-3, 0, 5), 0.5, 400);
    g.commit();
    EXPECT_EQ(g.sphereCount(), 2u);
    EXPECT_EQ(g.triangleCount(), 14u);
    const Bounds3 b = g.bounds();
    EXPECT_LT(glm::length(b.lo - Vec3(-5, -5, 4)), 1e-9);
    EXPECT_LT(glm::length(b.hi - Vec3(5, 5, 10)), 1e-9);

    auto hitShape = [&](const Vec3& o, const Vec3& d) {
        const auto h = g.intersect(makeRay(o, d));
        return h ? h->shape : -1;
    };
    EXPECT_EQ(hitShape(Vec3(0, 0, 0), Vec3(0, 0, 1)), 200);    // sphere before the quad
    EXPECT_EQ(hitShape(Vec3(0, 3, 0), Vec3(0, 0, 1)), 100);    // beside the sphere: quad
    EXPECT_EQ(hitShape(Vec3(3, 0, 0), Vec3(0, 0, 1)), 300);    // box before the quad
    EXPECT_EQ(hitShape(Vec3(-3, 0, 0), Vec3(0, 0, 1)), 400);   // second sphere
    EXPECT_EQ(hitShape(Vec3(0, 0, 20), Vec3(0, 0, 1)), -1);    // beyond everything
    EXPECT_EQ(hitShape(Vec3(-10, 0, 5), Vec3(1, 0, 0)), 400);  // through both spheres and box
    EXPECT_EQ(hitShape(Vec3(10, 0, 5), Vec3(-1, 0, 0)), 300);

    // Back face of the quad: ng still along cross(edgeU, edgeV) (+z), the ray arrives from +z.
    const auto h = g.intersect(makeRay(Vec3(0, 3, 20), Vec3(0, 0, -1)));
    ASSERT_TRUE(h.has_value());
    EXPECT_EQ(h->shape, 100);
    EXPECT_LT(glm::length(h->ng - Vec3(0, 0, 1)), 1e-12);
    EXPECT_NEAR(h->t, 10.0, 1e-9);
}

TEST(Geometry, DegenerateRaysDoNotCrash) {
    Geometry g;
    g.addSphere(Vec3(0, 0, 5), 1.0, 0);
    g.addMesh(makeQuad(Vec3(-1, -1, 3), Vec3(2, 0, 0), Vec3(0, 2, 0)), 1);
    g.commit();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<Ray> rays;
    Ray r;
    r.o = Vec3(0, 0, 0);
    r.d = Vec3(0, 0, 0);
    rays.push_back(r);  // zero direction
    r.d = Vec3(nan, 0, 1);
    rays.push_back(r);  // NaN direction
    r.d = Vec3(0, 0, 1);
    r.o = Vec3(nan, 0, 0);
    rays.push_back(r);  // NaN origin
    r.o = Vec3(kInf, 0, 0);
    rays.push_back(r);  // infinite origin
    r.o = Vec3(0, 0, 0);
    r.tmin = 2.0;
    r.tmax = 1.0;
    rays.push_back(r);  // empty interval
    r.tmin = nan;
    r.tmax = kInf;
    rays.push_back(r);  // NaN tmin
    r.tmin = 0.0;
    r.tmax = nan;
    rays.push_back(r);  // NaN tmax
    r.tmax = 0.0;
    rays.push_back(r);  // zero-length segment
    r.d = Vec3(1e-200, 0, 0);
    r.tmax = kInf;
    rays.push_back(r);  // direction underflows in float
    for (const Ray& ray : rays) {
        EXPECT_FALSE(g.intersect(ray).has_value());
        EXPECT_FALSE(g.occluded(ray));
    }
    // A non-unit direction is still handled (t in units of |d|).
    r = Ray{};
    r.d = Vec3(0, 0, 2);
    const auto h = g.intersect(r);
    ASSERT_TRUE(h.has_value());
    EXPECT_NEAR(h->t, 1.5, 1e-6);
    // Negative tmin is treated as 0.
    r.d = Vec3(0, 0, 1);
    r.o = Vec3(0, 0, 5);
    r.tmin = -10;
    const auto h2 = g.intersect(r);
    ASSERT_TRUE(h2.has_value());
    EXPECT_NEAR(h2->t, 1.0, 1e-12);
    EXPECT_EQ(h2->shape, 0);
}

TEST(Geometry, EmptySceneMissesEverything) {
    Geometry g;
    g.commit();
    EXPECT_FALSE(g.intersect(makeRay(Vec3(0.0), Vec3(0, 0, 1))).has_value());
    EXPECT_FALSE(g.occluded(makeRay(Vec3(0.0), Vec3(0, 0, 1))));
    EXPECT_FALSE(g.bounds().valid());
}

TEST(Geometry, ConcurrentQueriesMatchSerialOnes) {
    Geometry g;
    g.addSphere(Vec3(0, 0, 0), 1.0, 0);
    g.addMesh(makeBox(Vec3(-3), Vec3(3)), 1);
    g.addMesh(makeQuad(Vec3(-0.5, -2, -0.5), Vec3(1, 0, 0), Vec3(0, 0, 1)), 2);
    g.commit();
    Rng rng(1);
    std::vector<Ray> rays;
    for (int i = 0; i < 20000; ++i) rays.push_back(makeRay(rng.inBall(2.5), rng.unitVector()));
    std::vector<double> serialT(rays.size());
    std::vector<int> serialShape(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        const auto h = g.intersect(rays[i]);
        serialT[i] = h ? h->t : -1.0;
        serialShape[i] = h ? h->shape : -1;
    }
    std::atomic<int> mismatches{0};
    std::vector<std::thread> threads;
    for (int w = 0; w < 4; ++w)
        threads.emplace_back([&, w] {
            for (size_t i = w; i < rays.size(); i += 2) {  // overlapping ranges on purpose
                const auto h = g.intersect(rays[i]);
                if ((h ? h->t : -1.0) != serialT[i] || (h ? h->shape : -1) != serialShape[i] ||
                    g.occluded(rays[i]) != h.has_value())
                    ++mismatches;
            }
        });
    for (auto& t : threads) t.join();
    EXPECT_EQ(mismatches.load(), 0);
}

// ---- mesh operations -----------------------------------------------------------------------

TEST(Mesh, QuadOrientationAndShadingNormals) {
    TriangleMesh q = makeQuad(Vec3(0.0), Vec3(1, 0, 0), Vec3(0, 1, 0));
    ASSERT_EQ(q.positions.size(), 4u);
    for (const auto& t : q.triangles) {
        const Vec3 n = glm::cross(q.positions[t.y] - q.positions[t.x], q.positions[t.z] - q.positions[t.x]);
        EXPECT_GT(n.z, 0.0);
    }
    // Vertex normals tilted in x, and pointing to the back side: ns is interpolated, then put on
    // the ng side.
    q.normals = {Vec3(-1, 0, -1), Vec3(1, 0, -1), Vec3(1, 0, -1), Vec3(-1, 0, -1)};
    Geometry g;
    g.addMesh(q, 0);
    g.commit();
    const auto h = g.intersect(makeRay(Vec3(0.25, 0.75, 1), Vec3(0, 0, -1)));
    ASSERT_TRUE(h.has_value());
    EXPECT_LT(glm::length(h->ng - Vec3(0, 0, 1)), 1e-15);
    expectUnit(h->ns);
    EXPECT_GT(glm::dot(h->ns, h->ng), 0.0);
    // Interpolated normal at x=0.25 is (-0.5, 0, -1) normalized, flipped to (0.5, 0, 1).
    EXPECT_LT(glm::length(h->ns - glm::normalize(Vec3(0.5, 0, 1))), 1e-6);
}

TEST(Mesh, TransformAndFlip) {
    TriangleMesh box = makeBox(Vec3(0), Vec3(1));
    box.normals.assign(box.positions.size(), Vec3(0, 0, 1));
    Mat4 m(1.0);
    m = glm::translate(m, Vec3(1, 2, 3));
    m = glm::scale(m, Vec3(2, 1, 4));
    box.transform(m);
    Bounds3 b = box.bounds();
    EXPECT_EQ(b.lo, Vec3(1, 2, 3));
    EXPECT_EQ(b.hi, Vec3(3, 3, 7));
    for (const Vec3& n : box.normals) EXPECT_LT(glm::length(n - Vec3(0, 0, 1)), 1e-15);

    auto allOutward = [](const TriangleMesh& mesh) {
        const Vec3 c = mesh.bounds().center();
        for (const auto& t : mesh.triangles) {
            const Vec3 a = mesh.positions[t.x], bb = mesh.positions[t.y], cc = mesh.positions[t.z];
            if (glm::dot(glm::cross(bb - a, cc - a), (a + bb + cc) / 3.0 - c) <= 0) return false;
        }
        return true;
    };
    EXPECT_TRUE(allOutward(box));
    // Mirror: the winding is swapped so that faces stay outward.
    TriangleMesh mirrored = box;
    mirrored.transform(glm::scale(Mat4(1.0), Vec3(-1, 1, 1)));
    EXPECT_TRUE(allOutward(mirrored));
    // Normal transform: inverse transpose (shear).
    TriangleMesh quad = makeQuad(Vec3(0), Vec3(1, 0, 0), Vec3(0, 1, 0));
    quad.normals.assign(4, Vec3(0, 0, 1));
    Mat4 shear(1.0);
    shear[1][2] = 1.0;  // z += y
    quad.transform(shear);
    const auto& t = quad.triangles[0];
    const Vec3 ng = glm::normalize(
        glm::cross(quad.positions[t.y] - quad.positions[t.x], quad.positions[t.z] - quad.positions[t.x]));
    for (const Vec3& n : quad.normals) EXPECT_LT(glm::length(n - ng), 1e-12);
    // Flip reverses winding and normals.
    TriangleMesh flipped = box;
    flipped.flip();
    EXPECT_FALSE(allOutward(flipped));
    for (const Vec3& n : flipped.normals) EXPECT_EQ(n, Vec3(0, 0, -1));
    flipped.flip();
    EXPECT_EQ(flipped.triangles, box.triangles);
}

// ---- OBJ loading ------------------------------------------------------------------------------

TEST(ObjLoader, TriangulatesAndDropsDegenerateTriangles) {
    const std::string path = writeFile("small.obj",
                                       "# quad, degenerate triangle, triangle\n"
                                       "mtllib missing.mtl\n"
                                       "o thing\n"
                                       "v 0 0 0\n"
                                       "v 1 0 0\n"
                                       "v 1 1 0\n"
                                       "v 0 1 0\n"
                                       "v 2 0 0\n"
                                       "v 0 0 1\n"
                                       "v 9 9 9\n"  // unused
                                       "usemtl whatever\n"
                                       "f 1 2 3 4\n"
                                       "f 1 2 5\n"  // collinear
                                       "f 1 6 2\n"
                                       "f 3 3 4\n");  // repeated vertex
    size_t dropped = 99;
    const TriangleMesh m = loadObj(path, &dropped);
    EXPECT_EQ(dropped, 2u);
    EXPECT_EQ(m.triangles.size(), 3u);
    EXPECT_EQ(m.positions.size(), 5u);  // vertices 5 and 7 unreferenced after dropping
    EXPECT_TRUE(m.normals.empty());
    // The quad keeps the file's counter-clockwise orientation (+z).
    for (int i = 0; i < 2; ++i) {
        const auto& t = m.triangles[i];
        const Vec3 n = glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
        EXPECT_GT(n.z, 0.0);
        EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
    }
    const Bounds3 b = m.bounds();
    EXPECT_EQ(b.lo, Vec3(0, 0, 0));
    EXPECT_EQ(b.hi, Vec3(1, 1, 1));
    EXPECT_NO_THROW(loadObj(path));  // null counter is fine
}

TEST(ObjLoader, VertexNormalsOnlyWhenConsistent) {
    const std::string smooth = writeFile("smooth.obj",
                                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                         "vn 0 0 2\nvn 0 0.6 0.8\nvn 0 0 1\n"
                                         "f 1//1 2//2 3//1\n"
                                         "f 1//3 3//1 4//3\n");  // 1//3 has the same value as 1//1
    const TriangleMesh m = loadObj(smooth);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    EXPECT_LT(glm::length(m.normals[0] - Vec3(0, 0, 1)), 1e-7);  // normalised (tinyobj parses to ~1e-8)
    EXPECT_LT(glm::length(m.normals[1] - Vec3(0, 0.6, 0.8)), 1e-7);

    // Per-face normals (a position with two different normals): dropped.
    const std::string faceted = writeFile("faceted.obj",
                                          "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 1\n"
                                          "vn 0 0 1\nvn 0 1 0\n"
                                          "f 1//1 2//1 3//1\nf 1//2 3//2 4//2\n");
    EXPECT_TRUE(loadObj(faceted).normals.empty());
    // Normals on only some corners: dropped.
    const std::string partial = writeFile("partial.obj",
                                          "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
                                          "f 1//1 2//1 3//1\nf 1 3 4\n");
    EXPECT_TRUE(loadObj(partial).normals.empty());
}

TEST(ObjLoader, ErrorsNameTheFile) {
    const std::string missing = (tempDir() / "does_not_exist.obj").string();
    try {
        loadObj(missing);
        FAIL() << "expected UserError";
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
        EXPECT_EQ(e.file(), missing);
    }

    struct Case {
        const char* name;
        const char* text;
        const char* expect;  // part of the message
    };
    const Case cases[] = {
        {"zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "corrupt"},
        {"out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "out of range"},
        {"out_of_range_quad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 7\n", "out of range"},
        {"negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -9\n", "out of range"},
        {"normal_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//4\n", "out of range"},
        {"nonfinite.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
        {"empty.obj", "# nothing\n", "no triangles"},
        {"points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n", "no triangles"},
        {"all_degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "degenerate"},
        {"binary.obj",
         "\x7f"
         "ELF\x01\x02\x03\n\xff\xfe garbage\n",
         "no triangles"},
    };
    for (const Case& c : cases) {
        const std::string path = writeFile(c.name, c.text);
        try {
            loadObj(path);
            ADD_FAILURE() << c.name << ": expected UserError";
        } catch (const UserError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(path), std::string::npos) << c.name << ": " << msg;
            EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
        }
    }
    // tinyobj's line number is carried into the error position.
    const std::string bad = writeFile("bad_line.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 0 2\n");
    try {
        loadObj(bad);
        FAIL() << "expected UserError";
    } catch (const UserError& e) {
        EXPECT_EQ(e.line(), 5) << e.what();
    }
    // A folder is not a file.
    EXPECT_THROW(loadObj(tempDir().string()), UserError);
}

TEST(ObjLoader, Armadillo) {
    const std::string path = std::string(TPB_SOURCE_DIR) + "/scenes/armadillo.obj";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
    size_t dropped = 0;
    const TriangleMesh m = loadObj(path, &dropped);
    EXPECT_EQ(m.triangles.size() + dropped, 52000u);
    EXPECT_LT(dropped, 100u);
    EXPECT_LE(m.positions.size(), 26002u);
    EXPECT_GT(m.positions.size(), 25000u);
    EXPECT_TRUE(m.normals.empty() || m.normals.size() == m.positions.size());
    const Bounds3 b = m.bounds();
    ASSERT_TRUE(b.valid());

    Geometry g;
    g.addMesh(m, 42);
    g.commit();
    EXPECT_EQ(g.triangleCount(), m.triangles.size());
    EXPECT_LT(glm::length(g.bounds().lo - b.lo), 1e-6);
    EXPECT_LT(glm::length(g.bounds().hi - b.hi), 1e-6);

    // Rays from a surrounding sphere toward points near the centre: hits come in front-facing
    // (outward winding) and leave the mesh an even number of times (closed surface).
    Rng rng(52000);
    const Vec3 c = b.center();
    const double radius = b.diagonal();
    int hits = 0, frontFacing = 0, evenCrossings = 0;
    for (int i = 0; i < 2000; ++i) {
        const Vec3 o = c + radius * rng.unitVector();
        const Vec3 target = c + rng.inBall(0.1 * radius);
        Ray ray = makeRay(o, target - o);
        const auto h = g.intersect(ray);
        EXPECT_EQ(g.occluded(ray), h.has_value());
        if (!h) continue;
        ++hits;
        EXPECT_EQ(h->shape, 42);
        ASSERT_GE(h->prim, 0);
        ASSERT_LT(size_t(h->prim), m.triangles.size());
        expectUnit(h->ng);
        expectUnit(h->ns);
        EXPECT_GE(glm::dot(h->ns, h->ng), 0.0);
        if (glm::dot(h->ng, ray.d) < 0) ++frontFacing;
        int crossings = 0;
        std::optional<SurfaceHit> next = h;
        while (next && crossings < 1000) {
            ++crossings;
            // Triangles are float: step past the hit by more than float rounding of t.
            ray.tmin = next->t + 1e-5 * radius;
            next = g.intersect(ray);
        }
        if (crossings % 2 == 0) ++evenCrossings;
    }
    EXPECT_GT(hits, 1000);
    EXPECT_GT(frontFacing, hits * 99 / 100);
    EXPECT_GT(evenCrossings, hits * 99 / 100);
}
