// Surface interactions (core/transport/interaction.h), checked against formulas written here:
//  - interact(): the kind of each surface and the normals turned to the incoming side;
//  - a glass sphere (n = 1.5): the frequency of the Fresnel choice against the unpolarised Fresnel
//    reflectance (binomial z-test, fixed seed) at several angles, the refracted direction against
//    Snell's law, total internal reflection beyond the critical angle from inside (every u);
//  - the region stack: pushed on entering, popped on leaving, a push onto a full stack reported as
//    regionOverflow (stack untouched, nothing thrown); null boundaries never bend or reflect;
//  - the mirror bounce, Russian roulette's survival frequency and weight (also the deep rule that
//    ends full-weight paths), the null-crossing budget.
// The Fresnel reflectance and Snell's law are this file's own code, not scene/bsdf.h.
#include "transport/stages.h"
#include "transport/interaction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

using namespace tpb;

namespace {

constexpr double kIor = 1.5;

SceneDesc baseDesc() {
    SceneDesc d;
    d.camera.position = Vec3(0.0, 0.0, -5.0);
    d.camera.lookAt = Vec3(0.0);
    d.camera.up = Vec3(0.0, 1.0, 0.0);
    d.camera.width = 4;
    d.camera.height = 4;
    d.render.radiusRelative = false;
    return d;
}
int addMaterial(SceneDesc& d, MaterialType t, const Color& spec = Color(1.0)) {
    MaterialDesc m;
    m.type = t;
    m.specular = spec;
    m.ior = kIor;
    d.materials.push_back(m);
    return static_cast<int>(d.materials.size()) - 1;
}
void addSphere(SceneDesc& d, const Vec3& c, double r, int mat, int interior = -1) {
    ShapeDesc s;
    s.type = ShapeType::Sphere;
    s.center = c;
    s.radius = r;
    s.material = mat;
    s.interiorMedium = interior;
    d.shapes.push_back(s);
}
void addQuad(SceneDesc& d, const Vec3& corner, const Vec3& u, const Vec3& v, int mat) {
    ShapeDesc s;
    s.type = ShapeType::Quad;
    s.corner = corner;
    s.edgeU = u;
    s.edgeV = v;
    s.material = mat;
    d.shapes.push_back(s);
}

// A unit sphere of the given material at the origin.
std::unique_ptr<const Scene> sphereScene(MaterialType t, const Color& spec = Color(1.0)) {
    SceneDesc d = baseDesc();
    addSphere(d, Vec3(0.0), 1.0, addMaterial(d, t, spec));
    return Scene::build(d, analyzeStages);
}

// Unpolarised Fresnel reflectance from the incident and transmitted cosines (Hecht).
double fresnelRef(double cosI, double n1, double n2) {
    const double sinT = n1 / n2 * std::sqrt(1.0 - cosI * cosI);
    if (sinT >= 1.0) return 1.0;
    const double cosT = std::sqrt(1.0 - sinT * sinT);
    const double rs = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    const double rp = (n1 * cosT - n2 * cosI) / (n1 * cosT + n2 * cosI);
    return 0.5 * (rs * rs + rp * rp);
}

// A ray along +z at height b (in x) from z = -5, and its hit on the unit sphere.
struct Shot {
    Ray ray;
    SurfaceHit hit;
};
Shot shoot(const Scene& scene, double b) {
    Shot s;
    s.ray = Ray{Vec3(b, 0.0, -5.0), Vec3(0.0, 0.0, 1.0)};
    const auto hit = scene.geometry.intersect(s.ray);
    EXPECT_TRUE(hit.has_value());
    if (hit) s.hit = *hit;
    return s;
}

}  // namespace

TEST(Interaction, KindsAndFacingNormals) {
    SceneDesc d = baseDesc();
    addQuad(d, Vec3(-1.0, -1.0, 0.0), Vec3(2.0, 0.0, 0.0), Vec3(0.0, 2.0, 0.0), addMaterial(d, MaterialType::Diffuse));
    addQuad(d, Vec3(-1.0, -1.0, 1.0), Vec3(2.0, 0.0, 0.0), Vec3(0.0, 2.0, 0.0), -1);
    LightDesc l;
    l.type = LightType::AreaQuad;
    l.corner = Vec3(-1.0, -1.0, 2.0);
    l.edgeU = Vec3(2.0, 0.0, 0.0);
    l.edgeV = Vec3(0.0, 2.0, 0.0);
    d.lights.push_back(l);
    const auto scene = Scene::build(d, analyzeStages);
    const Vec3 geomNormal = glm::normalize(glm::cross(Vec3(2.0, 0.0, 0.0), Vec3(0.0, 2.0, 0.0)));  // +z
    const SurfaceKind expected[] = {SurfaceKind::Diffuse, SurfaceKind::Absorber, SurfaceKind::Emitter};
    for (int k = 0; k < 3; ++k) {
        for (const double dir : {1.0, -1.0}) {
            const double z = k + (dir > 0.0 ? -0.5 : 0.5);
            const Ray ray{Vec3(0.1, 0.2, z), Vec3(0.0, 0.0, dir)};
            const auto hit = scene->geometry.intersect(ray);
            ASSERT_TRUE(hit);
            ASSERT_NEAR(hit->p.z, k, 1e-6);
            const SurfaceInteraction si = interact(*scene, ray, *hit);
            EXPECT_EQ(si.kind, expected[k]) << k;
            // The quads' normal is +z: a ray along +z arrives from the back.
            EXPECT_EQ(si.front, dir < 0.0);
            EXPECT_NEAR(glm::dot(si.ng, geomNormal), -dir, 1e-12);
            EXPECT_GT(glm::dot(si.ns, si.ng), 0.0);
            EXPECT_LT(glm::dot(ray.d, si.ng), 0.0);  // facing the incoming ray
            EXPECT_EQ(si.material != nullptr, expected[k] == SurfaceKind::Diffuse);
        }
    }
}

TEST(Interaction, FresnelChoiceFrequencyMatchesFresnel) {
    const auto scene = sphereScene(MaterialType::Dielectric);
    Rng rng(7, Stream::Test, 0, 1);
    for (const double b : {0.0, 0.5, 0.8, 0.95, 0.995}) {
        const Shot s = shoot(*scene, b);
        const SurfaceInteraction si = interact(*scene, s.ray, s.hit);
        ASSERT_EQ(si.kind, SurfaceKind::Dielectric);
        ASSERT_TRUE(si.front);
        const double cosI = std::sqrt(1.0 - b * b);
        const double F = fresnelRef(cosI, 1.0, kIor);
        const int n = 200000;
        int reflected = 0;
        for (int i = 0; i < n; ++i) {
            RegionStack regions = scene->cameraRegions;
            const SpecularContinuation c = followInterface(*scene, s.ray, s.hit, si, regions, rng.uniform());
            ASSERT_FALSE(c.regionOverflow);
            EXPECT_FALSE(c.nullCrossing);
            if (c.transmitted) {
                EXPECT_EQ(regions.size, 2);
                // Snell: sin(theta_t) = sin(theta_i) / n, in the plane of incidence, into the sphere.
                const Vec3 nrm = glm::normalize(s.hit.p);
                const double cosT = -glm::dot(c.ray.d, nrm);
                EXPECT_NEAR(std::sqrt(std::max(0.0, 1.0 - cosT * cosT)), b / kIor, 1e-9);
                EXPECT_GT(cosT, 0.0);
                EXPECT_NEAR(c.ray.d.y, 0.0, 1e-12);
            } else {
                ++reflected;
                EXPECT_EQ(regions.size, 1);
                const Vec3 nrm = glm::normalize(s.hit.p);
                const Vec3 mirror = s.ray.d - 2.0 * glm::dot(s.ray.d, nrm) * nrm;
                EXPECT_NEAR(glm::length(c.ray.d - mirror), 0.0, 1e-9);
            }
        }
        const double z = (reflected - n * F) / std::sqrt(n * F * (1.0 - F));
        EXPECT_LT(std::abs(z), 4.0) << "b " << b << " F " << F << " measured " << double(reflected) / n;
    }
}

TEST(Interaction, TotalInternalReflectionBeyondTheCriticalAngle) {
    const auto scene = sphereScene(MaterialType::Dielectric);
    const double critical = std::asin(1.0 / kIor);
    // From inside: rays along +z at height b hit the sphere at the angle asin(b) to its normal.
    for (const double b : {0.7, 0.8, 0.95}) {
        ASSERT_GT(std::asin(b), critical);
        const Ray ray{Vec3(b, 0.0, 0.0), Vec3(0.0, 0.0, 1.0)};
        const auto hit = scene->geometry.intersect(ray);
        ASSERT_TRUE(hit);
        const SurfaceInteraction si = interact(*scene, ray, *hit);
        ASSERT_FALSE(si.front);
        for (const double u : {0.0, 0.5, 0.999999}) {
            RegionStack regions;
            ASSERT_TRUE(regions.push(scene->shapes[0].interiorRegion));
            const SpecularContinuation c = followInterface(*scene, ray, *hit, si, regions, u);
            EXPECT_FALSE(c.transmitted) << b << " " << u;
            EXPECT_EQ(regions.size, 2);
            EXPECT_LT(glm::dot(c.ray.d, glm::normalize(hit->p)), 0.0);  // back into the sphere
        }
    }
    // Just inside the critical angle some light leaves (F < 1).
    const double b = 0.98 * std::sin(critical);
    const Ray ray{Vec3(b, 0.0, 0.0), Vec3(0.0, 0.0, 1.0)};
    const auto hit = scene->geometry.intersect(ray);
    ASSERT_TRUE(hit);
    RegionStack regions;
    ASSERT_TRUE(regions.push(scene->shapes[0].interiorRegion));
    const SpecularContinuation c = followInterface(*scene, ray, *hit, interact(*scene, ray, *hit), regions, 0.9999);
    EXPECT_TRUE(c.transmitted);
    EXPECT_EQ(regions.size, 1);
}

TEST(Interaction, RegionStackPushedEnteringAndPoppedLeavingAGlassSphere) {
    const auto scene = sphereScene(MaterialType::Dielectric, Color(0.9, 0.8, 0.7));
    const int inside = scene->shapes[0].interiorRegion;
    ASSERT_GT(inside, 0);
    RegionStack regions = scene->cameraRegions;
    ASSERT_EQ(regions.size, 1);
    Shot s = shoot(*scene, 0.3);
    const SpecularContinuation in =
        followInterface(*scene, s.ray, s.hit, interact(*scene, s.ray, s.hit), regions, 0.99);
    ASSERT_TRUE(in.transmitted);
    EXPECT_EQ(regions.size, 2);
    EXPECT_EQ(regions.top(), inside);
    EXPECT_EQ(in.tint, Color(0.9, 0.8, 0.7));
    // The continued ray starts on the surface and skips it with tmin (Scene::leaveSurface).
    EXPECT_EQ(in.ray.o, s.hit.p);
    EXPECT_GT(in.ray.tmin, 0.0);
    const auto exitHit = scene->geometry.intersect(in.ray);
    ASSERT_TRUE(exitHit);
    EXPECT_NEAR(glm::length(exitHit->p), 1.0, 1e-9);
    EXPECT_GT(exitHit->t, 0.5);  // the far side, not the entry point again
    const SpecularContinuation out =
        followInterface(*scene, in.ray, *exitHit, interact(*scene, in.ray, *exitHit), regions, 0.99);
    ASSERT_TRUE(out.transmitted);
    EXPECT_EQ(regions.size, 1);
    EXPECT_EQ(regions.top(), 0);
    // Through a slab-like pair of refractions of a sphere the ray leaves deviated but outwards.
    EXPECT_GT(glm::dot(out.ray.d, glm::normalize(exitHit->p)), 0.0);
}

TEST(Interaction, FullRegionStackIsReportedNotThrown) {
    const auto scene = sphereScene(MaterialType::Dielectric);
    RegionStack regions;
    while (regions.size < RegionStack::kCapacity) ASSERT_TRUE(regions.push(0));
    const Shot s = shoot(*scene, 0.1);
    const SurfaceInteraction si = interact(*scene, s.ray, s.hit);
    SpecularContinuation c;
    EXPECT_NO_THROW(c = followInterface(*scene, s.ray, s.hit, si, regions, 0.99));
    EXPECT_TRUE(c.regionOverflow);
    EXPECT_FALSE(c.transmitted);
    EXPECT_EQ(regions.size, RegionStack::kCapacity);
    // A reflection needs no push: a full stack is no obstacle then.
    const SpecularContinuation r = followInterface(*scene, s.ray, s.hit, si, regions, 0.0);
    EXPECT_FALSE(r.regionOverflow);
    EXPECT_FALSE(r.transmitted);

    // The straight null crossing reports it the same way.
    const auto nullScene = sphereScene(MaterialType::Null);
    const Shot ns = shoot(*nullScene, 0.1);
    const SpecularContinuation cn =
        crossNull(*nullScene, ns.ray, ns.hit, interact(*nullScene, ns.ray, ns.hit), regions);
    EXPECT_TRUE(cn.regionOverflow);
    EXPECT_EQ(regions.size, RegionStack::kCapacity);
}

TEST(Interaction, NullBoundaryNeverBendsNorReflects) {
    const auto scene = sphereScene(MaterialType::Null);
    for (const double b : {0.0, 0.6, 0.99}) {
        const Shot s = shoot(*scene, b);
        const SurfaceInteraction si = interact(*scene, s.ray, s.hit);
        ASSERT_EQ(si.kind, SurfaceKind::Null);
        // Not u = 0 (probability 2^-53): F is rounding-level above 0 there (cosT is computed from
        // cosI), so u = 0 alone would reflect.
        for (const double u : {1e-12, 0.5, 0.999999}) {
            RegionStack regions;
            const SpecularContinuation c = followInterface(*scene, s.ray, s.hit, si, regions, u);
            EXPECT_TRUE(c.transmitted);
            EXPECT_TRUE(c.nullCrossing);
            EXPECT_EQ(c.tint, Color(1.0));
            EXPECT_NEAR(glm::length(c.ray.d - s.ray.d), 0.0, 1e-12);
            EXPECT_EQ(regions.top(), scene->shapes[0].interiorRegion);
        }
        RegionStack regions;
        const SpecularContinuation c = crossNull(*scene, s.ray, s.hit, si, regions);
        EXPECT_TRUE(c.transmitted);
        EXPECT_EQ(c.ray.d, s.ray.d);
        EXPECT_LT(glm::dot(c.ray.o - s.hit.p, si.ng), 0.0);  // behind the surface
        EXPECT_EQ(regions.top(), scene->shapes[0].interiorRegion);
    }
}

TEST(Interaction, MirrorReflectsAboutTheNormalWithItsTint) {
    const auto scene = sphereScene(MaterialType::Mirror, Color(0.5, 0.6, 0.7));
    const Shot s = shoot(*scene, 0.6);
    const SurfaceInteraction si = interact(*scene, s.ray, s.hit);
    ASSERT_EQ(si.kind, SurfaceKind::Mirror);
    const SpecularContinuation c = reflectMirror(*scene, s.ray, s.hit, si);
    const Vec3 n = glm::normalize(s.hit.p);
    const Vec3 mirror = s.ray.d - 2.0 * glm::dot(s.ray.d, n) * n;
    EXPECT_NEAR(glm::length(c.ray.d - mirror), 0.0, 1e-9);
    EXPECT_EQ(c.tint, Color(0.5, 0.6, 0.7));
    EXPECT_GT(glm::length(c.ray.o), 1.0);  // off the surface, outside
    EXPECT_FALSE(scene->geometry.intersect(c.ray).has_value());
}

TEST(Interaction, RussianRouletteSurvivalFrequencyAndWeight) {
    Rng rng(11, Stream::Test, 0, 2);
    const int n = 100000;
    const double q = 0.3;
    int survived = 0;
    for (int i = 0; i < n; ++i) {
        Color w(0.3, 0.1, 0.2);
        if (russianRoulette(rng, w, 1.0, 1)) {
            ++survived;
            EXPECT_NEAR(w.x, 1.0, 1e-12);
            EXPECT_NEAR(w.y, 0.1 / 0.3, 1e-12);
        }
    }
    EXPECT_LT(std::abs((survived - n * q) / std::sqrt(n * q * (1.0 - q))), 4.0);
    // Relative to a reference; q >= 1 survives without drawing a number.
    Rng a(3, Stream::Test, 0, 3), b(3, Stream::Test, 0, 3);
    Color w(2.0);
    EXPECT_TRUE(russianRoulette(a, w, 1.5, 1));
    EXPECT_EQ(w, Color(2.0));
    EXPECT_EQ(a.uniform(), b.uniform());
    Color zero(0.0);
    EXPECT_FALSE(russianRoulette(a, zero, 1.0, 1));
}

// Issue 33 item 5: from kDeepRouletteDepth events on, a full-weight path (albedo 1 everywhere, where
// the throughput rule never fires) survives with kDeepRouletteSurvival and is divided by it, so it
// ends; before that depth it draws nothing, as before (the films of max_depth < 64 are unchanged).
// A lower throughput survival is kept (q = min(weight / reference, 0.95)).
TEST(Interaction, DeepRussianRouletteEndsFullWeightPathsWithoutBias) {
    // Below the deep depth: a full weight survives without drawing.
    Rng a(5, Stream::Test, 0, 4), b(5, Stream::Test, 0, 4);
    Color w(1.0);
    EXPECT_TRUE(russianRoulette(a, w, 1.0, kDeepRouletteDepth - 1));
    EXPECT_EQ(w, Color(1.0));
    EXPECT_EQ(a.uniform(), b.uniform());
    // From the deep depth on: survival frequency 0.95 and weight 1 / 0.95, mean weight kept.
    Rng rng(11, Stream::Test, 0, 5);
    const int n = 100000;
    const double q = kDeepRouletteSurvival;
    int survived = 0;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        Color v(1.0, 0.5, 0.25);
        if (russianRoulette(rng, v, 1.0, kDeepRouletteDepth)) {
            ++survived;
            ASSERT_EQ(v, Color(1.0 / q, 0.5 / q, 0.25 / q));
            sum += v.x;
        }
    }
    EXPECT_LT(std::abs((survived - n * q) / std::sqrt(n * q * (1.0 - q))), 4.0);
    EXPECT_NEAR(sum / n, 1.0, 4.0 * std::sqrt((1.0 - q) / q / n));
    // A weight below the cap keeps the throughput rule: q = 0.3, weight brought back to the reference.
    Color low(0.3);
    Rng c(7, Stream::Test, 0, 6);
    for (int i = 0; i < 100 && !russianRoulette(c, low, 1.0, 10 * kDeepRouletteDepth); ++i) low = Color(0.3);
    EXPECT_NEAR(low.x, 1.0, 1e-12);
    // The depth is a parameter: a caller may start the deep rule earlier.
    Rng d(9, Stream::Test, 0, 7), e(9, Stream::Test, 0, 7);
    Color x(1.0);
    (void)russianRoulette(d, x, 1.0, 3, 3);
    EXPECT_NE(d.uniform(), e.uniform());  // it drew
}

TEST(Interaction, NullCrossingBudgetGivesTheFirstCrossingsFree) {
    NullCrossingBudget budget;
    for (int i = 0; i < NullCrossingBudget::kFreeCrossings; ++i) EXPECT_TRUE(budget.free());
    EXPECT_FALSE(budget.free());
    EXPECT_FALSE(budget.free());
}
