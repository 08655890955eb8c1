// The chi-square helper itself (tests/support/chi2.h): the p-value against closed forms and printed
// chi-square tables, the integration, and the test's power: a correct sampler is accepted while
// wrong ones (a uniform hemisphere against a cosine pdf, Henyey-Greenstein sampled with the wrong
// g, a sampler that leaves its domain, samples where the pdf is zero) are rejected. If the helper
// lost its power, every chi-square test of the suite would pass vacuously; these tests catch that.
#include "support/chi2.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tpb;
using namespace tpb::test;

namespace {

// Henyey-Greenstein, written here from the formula (independent of core/scene/medium.h):
// p(mu) = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2)); inverse cdf of mu for sampling.
double hgPdf(double g, double mu) { return (1.0 - g * g) / (4.0 * kPi * std::pow(1.0 + g * g - 2.0 * g * mu, 1.5)); }
double hgSampleMu(double g, double u) {
    if (g == 0.0) return 1.0 - 2.0 * u;
    const double s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u);
    return (1.0 + g * g - s * s) / (2.0 * g);
}

}  // namespace

// Q(k, x) for integer k is e^-x sum_{i<k} x^i / i! (the Poisson tail); for dof = 1 it is erfc(sqrt(x / 2)).
TEST(Chi2Helper, IncompleteGammaMatchesClosedForms) {
    for (const double x : {0.01, 0.5, 1.0, 3.0, 7.5, 20.0, 60.0}) {
        for (const int k : {1, 2, 5, 12, 40}) {
            double sum = 0.0, term = 1.0;
            for (int i = 0; i < k; ++i) {
                sum += term;
                term *= x / (i + 1);
            }
            const double q = std::exp(-x) * sum;
            EXPECT_NEAR(regularizedGammaQ(k, x), q, 1e-13 + 1e-11 * q) << "k=" << k << " x=" << x;
            EXPECT_NEAR(regularizedGammaP(k, x), 1.0 - q, 1e-12) << "k=" << k << " x=" << x;
        }
        EXPECT_NEAR(chi2PValue(x, 1), std::erfc(std::sqrt(0.5 * x)), 1e-13) << x;
        EXPECT_NEAR(chi2PValue(x, 2), std::exp(-0.5 * x), 1e-13) << x;
    }
    EXPECT_EQ(chi2PValue(0.0, 7), 1.0);
}

// Critical values of printed chi-square tables (upper-tail probability, dof, x), x given to 3 decimals.
TEST(Chi2Helper, PValueMatchesTabulatedCriticalValues) {
    struct Row {
        double p;
        int dof;
        double x;
    };
    const Row rows[] = {{0.05, 1, 3.841},     {0.01, 1, 6.635},     {0.05, 5, 11.070},  {0.01, 5, 15.086},
                        {0.99, 5, 0.554},     {0.05, 10, 18.307},   {0.01, 30, 50.892}, {0.95, 30, 18.493},
                        {0.05, 100, 124.342}, {0.01, 100, 135.807}, {0.50, 100, 99.334}};
    // The true critical value lies within the rounding (+-0.0005) of the printed one.
    for (const Row& r : rows) {
        EXPECT_GT(chi2PValue(r.x - 0.0005, r.dof), r.p) << r.dof << " " << r.x;
        EXPECT_LT(chi2PValue(r.x + 0.0005, r.dof), r.p) << r.dof << " " << r.x;
    }
}

TEST(Chi2Helper, SidakCorrection) {
    EXPECT_NEAR(sidakSignificance(0.01, 1), 0.01, 1e-15);
    const double a = sidakSignificance(0.01, 10);
    EXPECT_NEAR(1.0 - std::pow(1.0 - a, 10), 0.01, 1e-14);
    EXPECT_LT(a, 0.01 / 10 + 1e-5);
}

TEST(Chi2Helper, IntegratesPeakedFunctions) {
    EXPECT_NEAR(integrate1D([](double x) { return std::exp(-x); }, 0.0, 3.0), 1.0 - std::exp(-3.0), 1e-11);
    for (const double g : {-0.9, 0.0, 0.95, 0.99}) {
        const double total = integrate1D([&](double mu) { return 2.0 * kPi * hgPdf(g, mu); }, -1.0, 1.0);
        EXPECT_NEAR(total, 1.0, 1e-9) << g;
    }
    const double sphere = integrate2D([](double, double) { return 1.0 / (4.0 * kPi); }, sphericalDomain());
    EXPECT_NEAR(sphere, 1.0, 1e-12);
}

// A cosine-weighted hemisphere sampler (Malley, written here) passes against cos / pi ...
TEST(Chi2Helper, AcceptsACorrectSampler) {
    Chi2Settings s;
    s.testCount = 2;
    const Chi2Result r = chi2Test2D(
        [](Rng& rng) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            return Point2D{std::sqrt(1.0 - u1), 2.0 * kPi * u2};
        },
        [](double mu, double) { return mu / kPi; }, sphericalDomain(0.0), s);
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-9);
    // ... and so does Henyey-Greenstein at g = 0.8.
    const Chi2Result hg = chi2Test2D(
        [](Rng& rng) {
            return Point2D{hgSampleMu(0.8, rng.uniform()), 2.0 * kPi * rng.uniform()};
        },
        [](double mu, double) { return hgPdf(0.8, mu); }, sphericalDomain(), s);
    EXPECT_FALSE(hg.rejected) << hg.summary();
}

// ... while a uniform hemisphere sampler is rejected against the cosine pdf, HG sampled with
// g = 0.75 against g = 0.8, a sampler whose phi covers only [0, 1.9 pi), and one stepping outside.
TEST(Chi2Helper, RejectsWrongSamplers) {
    Chi2Settings s;
    s.testCount = 4;
    const Chi2Result uniform = chi2Test2D(
        [](Rng& rng) {
            return Point2D{rng.uniform(), 2.0 * kPi * rng.uniform()};
        },
        [](double mu, double) { return mu / kPi; }, sphericalDomain(0.0), s);
    EXPECT_TRUE(uniform.rejected) << uniform.summary();
    EXPECT_LT(uniform.pValue, 1e-100);
    const Chi2Result hg = chi2Test2D(
        [](Rng& rng) {
            return Point2D{hgSampleMu(0.75, rng.uniform()), 2.0 * kPi * rng.uniform()};
        },
        [](double mu, double) { return hgPdf(0.8, mu); }, sphericalDomain(), s);
    EXPECT_TRUE(hg.rejected) << hg.summary();
    EXPECT_EQ(hg.outside, 0);
    const Chi2Result phi = chi2Test2D(
        [](Rng& rng) {
            return Point2D{1.0 - 2.0 * rng.uniform(), 1.9 * kPi * rng.uniform()};
        },
        [](double, double) { return 1.0 / (4.0 * kPi); }, sphericalDomain(), s);
    EXPECT_TRUE(phi.rejected) << phi.summary();
    const Chi2Result outside = chi2Test2D(
        [](Rng& rng) {
            return Point2D{rng.uniform() * 1.01, rng.uniform()};
        },
        [](double, double) { return 1.0; }, Domain2D{}, s);
    EXPECT_TRUE(outside.rejected) << outside.summary();
    EXPECT_GT(outside.outside, 0);
}

// Samples where the pdf is zero are impossible events: rejected whatever the statistic says.
TEST(Chi2Helper, RejectsSamplesWhereThePdfIsZero) {
    Chi2Settings s;
    s.binsX = 10;
    s.binsY = 1;
    s.samples = 100000;
    const Chi2Result r = chi2Test1D([](Rng& rng) { return rng.uniform(); },
                                    [](double x) { return x < 0.9 ? 1.0 / 0.9 : 0.0; }, 0.0, 1.0, s);
    EXPECT_TRUE(r.rejected) << r.summary();
    EXPECT_GT(r.impossible, 0);
}

// Cells expecting fewer than 5 samples are pooled: a steep density with few samples still gives
// a valid test (accepted when right), and the pooled cells are counted.
TEST(Chi2Helper, PoolsCellsWithSmallExpectedCounts) {
    Chi2Settings s;
    s.binsX = 50;
    s.samples = 20000;
    const double lambda = 8.0, norm = 1.0 - std::exp(-lambda);
    const Chi2Result r = chi2Test1D([&](Rng& rng) { return -std::log(1.0 - rng.uniform() * norm) / lambda; },
                                    [&](double x) { return lambda * std::exp(-lambda * x) / norm; }, 0.0, 1.0, s);
    EXPECT_FALSE(r.rejected) << r.summary();
    EXPECT_GT(r.pooledCells, 0);
    EXPECT_LT(r.dof, 49);
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-10);
}
