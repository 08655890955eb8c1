// Chi-square tests of the sampling routines of core/base/sampling.h, each against its pdf:
//   sampleUniformSphere      pdfW = 1 / (4 pi) over the sphere            (cos theta, phi) cells
//   sampleCosineHemisphere   pdfW = cos(theta) / pi over the hemisphere   (cos theta, phi) cells
//   sampleUniformCone        pdfW = 1 / (2 pi (1 - cosMax)) in the cone    (cos theta, phi) cells
//   EquiangularFrame         pdf(t) = h / ((theta_b - theta_a) (h^2 + (t - D)^2)) on [0, tMax)
// A wrong sampler (a lost square root, phi over half the circle, a cone a little too wide, a wrong
// angle range in the equiangular map) moves mass between cells by many standard deviations at
// these sample counts, or puts samples where the pdf is zero, and is rejected (test_chi2 shows
// the helper rejects such samplers). The pdfs are written here from their formulas; the
// equiangular pdf is also checked against its defining property, pdf(t) |x(t) - y|^2 = constant.
#include "base/rng.h"
#include "base/sampling.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

using namespace tpb;
using namespace tpb::test;

namespace {

// All chi-square tests of this file share the overall significance 1% (Sidak).
constexpr int kChi2Tests = 10;

Chi2Settings settings(uint64_t seed) {
    Chi2Settings s;
    s.seed = seed;
    s.testCount = kChi2Tests;
    return s;
}

void expectUnit(const Vec3& w) { EXPECT_NEAR(glm::length(w), 1.0, 1e-12); }

}  // namespace

TEST(Sampling, UniformSphereChi2) {
    const Chi2Result r = chi2TestDirections(
        [](Rng& rng) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            return sampleUniformSphere(u1, u2);
        },
        [](const Vec3&) { return 1.0 / (4.0 * kPi); }, Vec3(0.0, 0.0, 1.0), -1.0, settings(1));
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
    EXPECT_DOUBLE_EQ(kUniformSpherePdf, 1.0 / (4.0 * kPi));
    for (int i = 0; i < 100; ++i) expectUnit(sampleUniformSphere(i / 100.0, (i * 37 % 100) / 100.0));
}

TEST(Sampling, CosineHemisphereChi2) {
    const Chi2Result r = chi2TestDirections(
        [](Rng& rng) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            return sampleCosineHemisphere(u1, u2);
        },
        [](const Vec3& w) { return std::max(w.z, 0.0) / kPi; }, Vec3(0.0, 0.0, 1.0), 0.0, settings(2));
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
    for (int i = 0; i < 100; ++i) expectUnit(sampleCosineHemisphere(i / 100.0, (i * 37 % 100) / 100.0));
}

// Around a tilted axis through toWorld, as the lights and the phase function use it: the frame is
// the renderer's, the test's cells are in the test's own frame around the same axis.
TEST(Sampling, CosineHemisphereAroundATiltedNormalChi2) {
    const Vec3 n = glm::normalize(Vec3(0.3, -0.8, 0.52));
    const Chi2Result r = chi2TestDirections(
        [&](Rng& rng) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            return toWorld(sampleCosineHemisphere(u1, u2), n);
        },
        [&](const Vec3& w) { return std::max(glm::dot(w, n), 0.0) / kPi; }, n, 0.0, settings(3));
    EXPECT_FALSE(r.rejected) << r.summary();
}

TEST(Sampling, UniformConeChi2) {
    uint64_t seed = 10;
    for (const double cosMax : {0.95, 0.5, -0.4}) {
        const Chi2Result r = chi2TestDirections(
            [&](Rng& rng) {
                const double u1 = rng.uniform(), u2 = rng.uniform();
                return sampleUniformCone(u1, u2, cosMax);
            },
            [&](const Vec3&) { return 1.0 / (2.0 * kPi * (1.0 - cosMax)); }, Vec3(0.0, 0.0, 1.0), cosMax,
            settings(seed++));
        EXPECT_FALSE(r.rejected) << "cosMax " << cosMax << ": " << r.summary();
        EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
    }
}

TEST(Sampling, ToWorldIsARotationTakingZToTheNormal) {
    for (const Vec3& n : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), glm::normalize(Vec3(-0.2, 0.9, 0.1))}) {
        EXPECT_LT(glm::length(toWorld(Vec3(0, 0, 1), n) - n), 1e-12);
        const Vec3 x = toWorld(Vec3(1, 0, 0), n), y = toWorld(Vec3(0, 1, 0), n);
        expectUnit(x);
        expectUnit(y);
        EXPECT_NEAR(glm::dot(x, y), 0.0, 1e-12);
        EXPECT_NEAR(glm::dot(x, n), 0.0, 1e-12);
        EXPECT_GT(glm::dot(glm::cross(x, y), n), 0.999);  // right-handed: no mirror image
    }
}

// ---- equiangular sampling -------------------------------------------------------------------------

namespace {

struct EquiangularCase {
    Vec3 o, w, y;
    double tMax;
};

// Light beside the middle of the segment, beyond its end, behind its origin, and very close to it
// (a sharp peak: the case equiangular sampling exists for).
const EquiangularCase kEquiangularCases[] = {
    {Vec3(0.0), Vec3(1, 0, 0), Vec3(1.0, 0.5, 0.0), 2.0},
    {Vec3(0.1, -0.2, 0.3), glm::normalize(Vec3(1, 1, 0)), Vec3(3.0, 2.0, 0.5), 1.5},
    {Vec3(0.0), Vec3(0, 0, 1), Vec3(0.2, 0.0, -1.0), 4.0},
    {Vec3(0.0), Vec3(0, 1, 0), Vec3(0.0, 0.7, 0.01), 1.0},
};

}  // namespace

// The pdf written from the geometry: pdf(t) = c / |x(t) - y|^2, c making it integrate to 1.
TEST(Sampling, EquiangularPdfIsInverseSquareDistanceAndNormalised) {
    for (const EquiangularCase& c : kEquiangularCases) {
        const EquiangularFrame f(c.o, c.w, c.tMax, c.y);
        ASSERT_TRUE(f.valid);
        const auto dist2 = [&](double t) {
            const Vec3 x = c.o + t * c.w;
            return glm::dot(x - c.y, x - c.y);
        };
        const double norm = integrate1D([&](double t) { return 1.0 / dist2(t); }, 0.0, c.tMax, 1e-13);
        for (int i = 0; i <= 20; ++i) {
            const double t = c.tMax * i / 20.0;
            EXPECT_NEAR(f.pdf(t), 1.0 / (norm * dist2(t)), 1e-9 * f.pdf(t)) << t;
        }
        EXPECT_NEAR(integrate1D([&](double t) { return f.pdf(t); }, 0.0, c.tMax, 1e-13), 1.0, 1e-9);
        for (const double u : {0.0, 0.1, 0.5, 0.9, 0.999999}) {
            const EquiangularSample s = f.sample(u);
            EXPECT_GE(s.t, -1e-12);
            EXPECT_LE(s.t, c.tMax * (1.0 + 1e-12));
            EXPECT_EQ(s.pdf, f.pdf(s.t));
        }
    }
    // An unbounded segment (an open medium): theta runs up to pi / 2, the pdf still integrates to 1
    // (the tail beyond t = 1e6 m holds ~ h / (1e6 (theta_b - theta_a)) of it).
    const EquiangularFrame open(Vec3(0.0), Vec3(1, 0, 0), kInf, Vec3(0.5, 0.3, 0.0));
    ASSERT_TRUE(open.valid);
    EXPECT_NEAR(integrate1D([&](double t) { return open.pdf(t); }, 0.0, 1e3, 1e-12) +
                    integrate1D([&](double t) { return open.pdf(t); }, 1e3, 1e6, 1e-12),
                1.0, 1e-6);
    // The light on the segment's line, or an empty segment: no sampling.
    EXPECT_FALSE(EquiangularFrame(Vec3(0.0), Vec3(1, 0, 0), 1.0, Vec3(2.0, 0.0, 0.0)).valid);
    EXPECT_FALSE(EquiangularFrame(Vec3(0.0), Vec3(1, 0, 0), 0.0, Vec3(0.5, 1.0, 0.0)).valid);
}

TEST(Sampling, EquiangularChi2) {
    uint64_t seed = 20;
    for (const EquiangularCase& c : kEquiangularCases) {
        const EquiangularFrame f(c.o, c.w, c.tMax, c.y);
        const auto dist2 = [&](double t) {
            const Vec3 x = c.o + t * c.w;
            return glm::dot(x - c.y, x - c.y);
        };
        const double norm = integrate1D([&](double t) { return 1.0 / dist2(t); }, 0.0, c.tMax, 1e-13);
        Chi2Settings s = settings(seed++);
        s.binsX = 100;
        s.samples = 200000;
        const Chi2Result r = chi2Test1D([&](Rng& rng) { return f.sample(rng.uniform()).t; },
                                        [&](double t) { return 1.0 / (norm * dist2(t)); }, 0.0, c.tMax, s);
        EXPECT_FALSE(r.rejected) << r.summary();
    }
}
