// The reflect/refract choice at a dielectric interface, followInterface (core/transport/interaction.cpp):
// with the uniform number u it reflects when u < F, F the unpolarised Fresnel reflectance, and
// refracts (pushing / popping the region stack) otherwise; beyond the critical angle it always
// reflects (total internal reflection). Checked here, entering a glass sphere (1 -> 1.5) and leaving
// it (1.5 -> 1) at several angles:
//   - the frequency of reflection over N random u against F written here from the Fresnel equations
//     in angle form (Rs = sin^2(i - t) / sin^2(i + t), Rp = tan^2(i - t) / tan^2(i + t)): a binomial
//     z-test per angle, Sidak-corrected over the angles;
//   - the threshold itself: u just below F reflects, just above refracts;
//   - the directions: mirror reflection, Snell's law for the refracted ray, and the region stack;
//   - total internal reflection for every u beyond asin(1 / 1.5).
// A choice with the probabilities swapped, F of the wrong side's indices, or Schlick's
// approximation instead of the exact F would fail the z-tests (N = 40000 resolves F to ~0.002).
// Everything goes through `cross` below: when the choice moves (core/transport), retarget it there.
#include "transport/stages.h"
#include "scene/scene.h"
#include "support/chi2.h"
#include "support/scene_builder.h"

#include "transport/interaction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iterator>

using namespace tpb;
using namespace tpb::test;

namespace {

constexpr double kGlassIor = 1.5;

// F from the Fresnel equations in angle form, etaI sin(i) = etaT sin(t).
double fresnelReference(double cosI, double etaI, double etaT) {
    const double i = std::acos(cosI);
    const double sinT = etaI / etaT * std::sin(i);
    if (sinT >= 1.0) return 1.0;
    const double t = std::asin(sinT);
    if (i < 1e-6) return std::pow((etaI - etaT) / (etaI + etaT), 2);
    const double rs = std::pow(std::sin(i - t) / std::sin(i + t), 2);
    const double rp = std::pow(std::tan(i - t) / std::tan(i + t), 2);
    return 0.5 * (rs + rp);
}

// A scene with one glass sphere of radius 1 at the origin (region 1 inside, index 1.5).
struct GlassSphere {
    std::unique_ptr<const Scene> scene;
    int shape = -1;
    GlassSphere() {
        SceneBuilder b;
        b.sphere(Vec3(0.0), 1.0, b.dielectric(kGlassIor)).pointLight(Vec3(0.0, 3.0, 0.0), Color(1.0));
        scene = Scene::build(b.desc(), analyzeStages);
        for (size_t i = 0; i < scene->shapes.size(); ++i)
            if (scene->shapes[i].interiorRegion != 0) shape = static_cast<int>(i);
    }
};

struct Crossing {
    bool reflected = false;
    Ray ray;
    RegionStack regions;
};

// A path at the sphere's top (normal +y) arriving at angle theta (radians) from the normal, from
// outside (entering) or from inside (leaving), continued with the uniform number u.
Crossing cross(const GlassSphere& g, double theta, bool entering, double u) {
    const Vec3 nOut(0.0, 1.0, 0.0);
    SurfaceHit hit;
    hit.p = nOut;
    hit.ng = hit.ns = nOut;
    hit.shape = g.shape;
    hit.t = 1.0;
    const double s = std::sin(theta), c = std::cos(theta);
    // Propagation direction against the normal facing the incoming side.
    const Vec3 nIn = entering ? nOut : -nOut;
    const Vec3 d = glm::normalize(Vec3(s, 0.0, 0.0) - c * nIn);
    Crossing x;
    if (!entering) {
        EXPECT_TRUE(x.regions.push(g.scene->shapes[g.shape].interiorRegion));
    }
    const ShapeInfo& shape = g.scene->shapes[g.shape];
    const Ray incoming{hit.p - d, d};
    const SurfaceInteraction si = interact(*g.scene, incoming, hit);
    EXPECT_EQ(si.front, entering);
    const SpecularContinuation next = followInterface(*g.scene, incoming, hit, si, x.regions, u);
    EXPECT_FALSE(next.regionOverflow);
    if (next.regionOverflow) return x;
    const Ray* r = &next.ray;
    x.ray = *r;
    x.reflected = glm::dot(r->d, nIn) > 0.0;
    // Reflection is the mirror direction, the stack unchanged; refraction obeys Snell's law.
    const double etaI = entering ? 1.0 : kGlassIor, etaT = entering ? kGlassIor : 1.0;
    if (x.reflected) {
        EXPECT_LT(glm::length(r->d - (d - 2.0 * glm::dot(d, nIn) * nIn)), 1e-12);
        EXPECT_EQ(x.regions.size, entering ? 1 : 2);
    } else {
        const double sinT = glm::length(glm::cross(r->d, nIn));
        EXPECT_NEAR(etaT * sinT, etaI * s, 1e-12);
        EXPECT_GT(r->d.x * d.x, -1e-15);  // on along the same tangential direction
        EXPECT_EQ(x.regions.size, entering ? 2 : 1);
        if (entering) {
            EXPECT_EQ(x.regions.top(), shape.interiorRegion);
        }
    }
    return x;
}

double deg(double d) { return d * kPi / 180.0; }

struct Case {
    double thetaDeg;
    bool entering;
};
// Below the critical angle asin(1 / 1.5) = 41.81 deg when leaving.
const Case kCases[] = {{1.0, true},  {30.0, true},  {60.0, true},  {80.0, true},  {89.0, true},
                       {5.0, false}, {25.0, false}, {38.0, false}, {41.0, false}, {41.7, false}};

}  // namespace

TEST(FresnelChoice, ReflectionFrequencyIsTheFresnelReflectance) {
    const GlassSphere g;
    ASSERT_GE(g.shape, 0);
    const double alpha = sidakSignificance(0.01, static_cast<int>(std::size(kCases)));
    const int n = 40000;
    uint64_t index = 0;
    for (const Case& c : kCases) {
        const double cosI = std::cos(deg(c.thetaDeg));
        const double F = c.entering ? fresnelReference(cosI, 1.0, kGlassIor) : fresnelReference(cosI, kGlassIor, 1.0);
        Rng rng(1, Stream::Test, 0, index++);
        int reflected = 0;
        for (int i = 0; i < n; ++i) reflected += cross(g, deg(c.thetaDeg), c.entering, rng.uniform()).reflected;
        // Two-sided binomial z-test (normal approximation; n F (1 - F) >= 40000 * 0.04 * 0.96 here).
        const double z = (reflected - n * F) / std::sqrt(n * F * (1.0 - F));
        const double p = std::erfc(std::abs(z) / std::sqrt(2.0));
        EXPECT_GE(p, alpha) << (c.entering ? "entering" : "leaving") << " at " << c.thetaDeg << " deg: " << reflected
                            << " of " << n << " reflected, F = " << F << ", z = " << z;
    }
}

TEST(FresnelChoice, ReflectsExactlyBelowTheFresnelThreshold) {
    const GlassSphere g;
    for (const Case& c : kCases) {
        const double cosI = std::cos(deg(c.thetaDeg));
        const double F = c.entering ? fresnelReference(cosI, 1.0, kGlassIor) : fresnelReference(cosI, kGlassIor, 1.0);
        EXPECT_TRUE(cross(g, deg(c.thetaDeg), c.entering, F * (1.0 - 1e-9)).reflected) << c.thetaDeg;
        EXPECT_FALSE(cross(g, deg(c.thetaDeg), c.entering, F * (1.0 + 1e-9)).reflected) << c.thetaDeg;
        EXPECT_TRUE(cross(g, deg(c.thetaDeg), c.entering, 0.0).reflected) << c.thetaDeg;
        EXPECT_FALSE(cross(g, deg(c.thetaDeg), c.entering, 1.0 - 1e-12).reflected) << c.thetaDeg;
    }
}

TEST(FresnelChoice, TotalInternalReflectionBeyondTheCriticalAngle) {
    const GlassSphere g;
    Rng rng(2, Stream::Test, 0, 0);
    for (const double thetaDeg : {41.9, 45.0, 60.0, 89.0}) {
        for (int i = 0; i < 1000; ++i) EXPECT_TRUE(cross(g, deg(thetaDeg), false, rng.uniform()).reflected) << thetaDeg;
        EXPECT_TRUE(cross(g, deg(thetaDeg), false, 1.0 - 1e-12).reflected) << thetaDeg;
    }
}
