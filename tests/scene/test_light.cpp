// Photon emission of core/scene/light.{h,cpp} (Light::sampleEmission), each light type against the
// distribution it must emit:
//   point   direction uniform over the sphere, pdfW = 1 / (4 pi); origin the light's position
//   spot    direction uniform in the cutoff cone, pdfW = 1 / (2 pi (1 - cos cutoff)), weighted by
//           Phi f(cos) / (int f dw pdfW) with the smoothstep falloff f, so that the emitted
//           intensity is Phi f / int f dw (int f dw in closed form here)
//   area    origin uniform over the quad (pdfA = 1 / area), direction cosine-weighted around its
//           normal (pdfW = cos / pi): Lambertian emission; weight Phi
//   laser   delta: exactly the beam direction; origin the position, or uniform over the beam's disc
// Chi-square tests (tests/support/chi2.h) put the samples in cells and compare with the pdfs written
// here: a spot that emits outside its cone or with the wrong falloff weight, an area light biased
// towards a corner or emitting uniformly instead of by cosine, a laser disc sampled with r ~ u
// instead of sqrt(u) are all rejected.
#include "scene/light.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

using namespace tpb;
using namespace tpb::test;

namespace {

constexpr int kChi2Tests = 6;

Chi2Settings settings(uint64_t seed) {
    Chi2Settings s;
    s.seed = seed;
    s.testCount = kChi2Tests;
    return s;
}

// smoothstep between the cutoff and the falloff cone, as the scene format defines the spot profile.
double spotProfile(double cosTheta, double cosCutoff, double cosFalloff) {
    if (cosTheta >= cosFalloff) return 1.0;
    if (cosTheta <= cosCutoff) return 0.0;
    const double x = (cosTheta - cosCutoff) / (cosFalloff - cosCutoff);
    return 3.0 * x * x - 2.0 * x * x * x;
}
// int f dw = 2 pi [(1 - cosFalloff) + (cosFalloff - cosCutoff) int_0^1 (3x^2 - 2x^3) dx], the
// integral being 1/2.
double spotIntegral(double cosCutoff, double cosFalloff) {
    return 2.0 * kPi * ((1.0 - cosFalloff) + 0.5 * (cosFalloff - cosCutoff));
}
double cosDeg(double deg) { return std::cos(deg * kPi / 180.0); }

}  // namespace

TEST(LightEmission, PointLightIsUniformOverTheSphere) {
    LightDesc d;
    d.type = LightType::Point;
    d.position = Vec3(0.3, 1.2, -0.4);
    d.power = Color(2.0, 3.0, 4.0);
    const Light light = Light::fromDesc(d);
    const Chi2Result r = chi2TestDirections(
        [&](Rng& rng) {
            const EmissionSample e = light.sampleEmission(rng, 1e-5);
            EXPECT_EQ(e.ray.o, d.position);
            EXPECT_EQ(e.power, d.power);
            return e.ray.d;
        },
        [](const Vec3&) { return 1.0 / (4.0 * kPi); }, Vec3(0.0, 1.0, 0.0), -1.0, settings(1));
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
}

TEST(LightEmission, SpotLightIsUniformInItsConeWithTheFalloffInTheWeight) {
    uint64_t seed = 2;
    for (const auto& [cutoffDeg, falloffDeg] : {std::pair{30.0, 25.0}, std::pair{70.0, 10.0}}) {
        LightDesc d;
        d.type = LightType::Spot;
        d.position = Vec3(-0.5, 2.0, 0.1);
        d.direction = Vec3(0.2, -1.0, 0.3);  // not unit in the description: fromDesc normalises
        d.spotCutoffDeg = cutoffDeg;
        d.spotFalloffDeg = falloffDeg;
        d.power = Color(5.0);
        const Light light = Light::fromDesc(d);
        const Vec3 axis = glm::normalize(d.direction);
        const double cosC = cosDeg(cutoffDeg), cosF = cosDeg(falloffDeg);
        const double pdfW = 1.0 / (2.0 * kPi * (1.0 - cosC));
        EXPECT_NEAR(light.spotIntegral, spotIntegral(cosC, cosF), 1e-6 * spotIntegral(cosC, cosF));

        double weightSum = 0.0, weightSq = 0.0;
        int64_t n = 0;
        const Chi2Result r = chi2TestDirections(
            [&](Rng& rng) {
                const EmissionSample e = light.sampleEmission(rng, 1e-5);
                EXPECT_EQ(e.ray.o, d.position);
                // The weight makes the emitted intensity Phi f / int f dw: checked per sample.
                const double cosT = glm::dot(e.ray.d, axis);
                const double w = 5.0 * spotProfile(cosT, cosC, cosF) / (spotIntegral(cosC, cosF) * pdfW);
                EXPECT_NEAR(e.power.x, w, 1e-5 * 5.0 / (spotIntegral(cosC, cosF) * pdfW) + 1e-9);
                EXPECT_EQ(e.power.x, e.power.y);
                weightSum += e.power.x;
                weightSq += e.power.x * e.power.x;
                ++n;
                return e.ray.d;
            },
            [&](const Vec3&) { return pdfW; }, axis, cosC, settings(seed++));
        EXPECT_FALSE(r.rejected) << cutoffDeg << "/" << falloffDeg << ": " << r.summary();
        EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
        // The mean weight is the power (all of it leaves the light): a z-test at 5 sigma.
        const double mean = weightSum / n, sd = std::sqrt(std::max(weightSq / n - mean * mean, 0.0) / n);
        EXPECT_NEAR(mean, 5.0, 5.0 * sd) << cutoffDeg;
    }
}

namespace {

LightDesc areaDesc() {
    LightDesc d;
    d.type = LightType::AreaQuad;
    d.corner = Vec3(-0.3, 1.9, -0.2);
    d.edgeU = Vec3(0.8, 0.0, 0.0);
    d.edgeV = Vec3(0.0, 0.3, 0.4);  // a 0.8 x 0.5 rectangle, tilted; normal cross(U, V) = (0, -0.32, 0.24) / 0.4
    d.power = Color(7.0);
    return d;
}

}  // namespace

// With no offset, the origin lies on the quad: (u, v) = its coordinates along the edges, uniform in [0, 1]^2.
TEST(LightEmission, AreaLightPositionIsUniformOverTheQuad) {
    const LightDesc d = areaDesc();
    const Light light = Light::fromDesc(d);
    EXPECT_NEAR(light.area, 0.4, 1e-15);
    const Vec3 n = glm::normalize(glm::cross(d.edgeU, d.edgeV));
    const Chi2Result r = chi2Test2D(
        [&](Rng& rng) {
            const EmissionSample e = light.sampleEmission(rng, 0.0);
            EXPECT_EQ(e.power, d.power);
            const Vec3 q = e.ray.o - d.corner;
            EXPECT_NEAR(glm::dot(q, n), 0.0, 1e-14);
            return Point2D{glm::dot(q, d.edgeU) / glm::dot(d.edgeU, d.edgeU),
                           glm::dot(q, d.edgeV) / glm::dot(d.edgeV, d.edgeV)};
        },
        [](double, double) { return 1.0; }, Domain2D{}, settings(4));
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
}

TEST(LightEmission, AreaLightDirectionIsCosineAroundItsNormal) {
    const LightDesc d = areaDesc();
    const Light light = Light::fromDesc(d);
    const Vec3 n = glm::normalize(glm::cross(d.edgeU, d.edgeV));
    const Chi2Result r =
        chi2TestDirections([&](Rng& rng) { return light.sampleEmission(rng, 1e-5).ray.d; },
                           [&](const Vec3& w) { return std::max(glm::dot(w, n), 0.0) / kPi; }, n, 0.0, settings(5));
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
}

// With an offset, the origin is that far in front of the quad and inside it.
TEST(LightEmission, AreaLightOffsetStartsInFrontOfTheQuad) {
    const LightDesc d = areaDesc();
    const Light light = Light::fromDesc(d);
    const Vec3 n = glm::normalize(glm::cross(d.edgeU, d.edgeV));
    const double offset = 1e-3;
    Rng rng(6, Stream::Test, 0, 0);
    for (int i = 0; i < 10000; ++i) {
        const Vec3 q = light.sampleEmission(rng, offset).ray.o - d.corner;
        EXPECT_NEAR(glm::dot(q, n), offset, 1e-12);
        const double u = glm::dot(q, d.edgeU) / glm::dot(d.edgeU, d.edgeU);
        const double v = glm::dot(q, d.edgeV) / glm::dot(d.edgeV, d.edgeV);
        EXPECT_GT(u, 0.0);
        EXPECT_LT(u, 1.0);
        EXPECT_GT(v, 0.0);
        EXPECT_LT(v, 1.0);
    }
}

TEST(LightEmission, ThinLaserIsExactlyItsBeam) {
    LightDesc d;
    d.type = LightType::Laser;
    d.position = Vec3(0.1, 0.2, 0.3);
    d.direction = Vec3(1.0, 0.0, 0.0);
    d.power = Color(3.0);
    const Light light = Light::fromDesc(d);
    Rng rng(7, Stream::Test, 0, 0);
    for (int i = 0; i < 1000; ++i) {
        const EmissionSample e = light.sampleEmission(rng, 1e-5);
        EXPECT_EQ(e.ray.o, d.position);
        EXPECT_EQ(e.ray.d, d.direction);
        EXPECT_EQ(e.power, d.power);
    }
}

// A laser with a radius: the direction stays the beam's; the origin is uniform over the disc of
// that radius normal to the beam: (r^2 / R^2, phi) uniform in [0, 1] x [0, 2 pi).
TEST(LightEmission, WideLaserIsUniformOverItsDisc) {
    LightDesc d;
    d.type = LightType::Laser;
    d.position = Vec3(0.1, 0.2, 0.3);
    d.direction = Vec3(0.0, 0.6, 0.8);
    d.laserRadius = 0.05;
    const Light light = Light::fromDesc(d);
    const DirectionFrame frame(d.direction);
    const Chi2Result r = chi2Test2D(
        [&](Rng& rng) {
            const EmissionSample e = light.sampleEmission(rng, 1e-5);
            EXPECT_LT(glm::length(e.ray.d - d.direction), 1e-15);
            const Vec3 q = e.ray.o - d.position;
            EXPECT_NEAR(glm::dot(q, frame.n), 0.0, 1e-15);
            double phi = std::atan2(glm::dot(q, frame.b), glm::dot(q, frame.t));
            if (phi < 0.0) phi += 2.0 * kPi;
            return Point2D{glm::dot(q, q) / (d.laserRadius * d.laserRadius), phi};
        },
        [](double, double) { return 1.0 / (2.0 * kPi); }, Domain2D{0.0, 1.0, 0.0, 2.0 * kPi}, settings(8));
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
}
