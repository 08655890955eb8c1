// The Henyey-Greenstein phase function of core/scene/medium.h: HenyeyGreenstein::sample against
// its pdf, which must be HenyeyGreenstein::eval (the renderer divides by eval where it means the
// sampling pdf). Checked, for g = -0.9, -0.3, 0, 0.5, 0.95:
//   - eval equals p(mu) = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2)) written here, and integrates
//     to 1 over the sphere;
//   - a chi-square test of sample(wi, u1, u2) in (cos theta, phi) around wi against that pdf.
// A sampler with the wrong sign of g, a wrong inverse cdf or a frame not centred on wi shifts mass
// by many standard deviations per cell at 500k samples and is rejected (test_chi2 rejects HG
// sampled with g = 0.75 against g = 0.8).
#include "scene/medium.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

#include <string>

using namespace tpb;
using namespace tpb::test;

namespace {

const double kGs[] = {-0.9, -0.3, 0.0, 0.5, 0.95};
constexpr int kChi2Tests = 5;

double hgPdf(double g, double mu) { return (1.0 - g * g) / (4.0 * kPi * std::pow(1.0 + g * g - 2.0 * g * mu, 1.5)); }

}  // namespace

TEST(HenyeyGreenstein, EvalIsTheNormalisedHgPdf) {
    for (const double g : kGs) {
        const HenyeyGreenstein hg{g};
        for (int i = 0; i <= 40; ++i) {
            const double mu = -1.0 + 2.0 * i / 40.0;
            EXPECT_NEAR(hg.eval(mu), hgPdf(g, mu), 1e-12 * hgPdf(g, mu)) << "g=" << g << " mu=" << mu;
        }
        const double total = integrate1D([&](double mu) { return 2.0 * kPi * hg.eval(mu); }, -1.0, 1.0, 1e-13);
        EXPECT_NEAR(total, 1.0, 1e-9) << g;
        // Mean cosine of the scattering angle is g (the definition of the asymmetry parameter).
        const double meanCos = integrate1D([&](double mu) { return 2.0 * kPi * mu * hg.eval(mu); }, -1.0, 1.0, 1e-13);
        EXPECT_NEAR(meanCos, g, 1e-9) << g;
    }
}

// One test per g (a CTest entry each).
class HenyeyGreensteinChi2 : public ::testing::TestWithParam<int> {};

TEST_P(HenyeyGreensteinChi2, SampleFollowsEval) {
    const Vec3 wi = glm::normalize(Vec3(0.4, -0.7, 0.3));
    const double g = kGs[GetParam()];
    const HenyeyGreenstein hg{g};
    Chi2Settings s;
    s.seed = 1 + GetParam();
    s.testCount = kChi2Tests;
    s.binsX = 64;  // cos theta: the forward peak at g = 0.95 is ~0.003 wide
    const Chi2Result r = chi2TestDirections(
        [&](Rng& rng) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            return hg.sample(wi, u1, u2);
        },
        [&](const Vec3& wo) { return hg.eval(glm::dot(wi, wo)); }, wi, -1.0, s);
    EXPECT_FALSE(r.rejected) << "g=" << g << ": " << r.summary();
    EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-8) << g;
}

INSTANTIATE_TEST_SUITE_P(G, HenyeyGreensteinChi2, ::testing::Range(0, kChi2Tests),
                         [](const ::testing::TestParamInfo<int>& info) {
                             const double g = kGs[info.param];
                             std::string name = (g < 0.0 ? "minus" : "") + std::to_string(std::abs(g));
                             for (char& c : name) c = c == '.' ? 'p' : c;
                             name = name.substr(0, name.find_last_not_of('0') + 1);  // 0.500000 -> 0p5
                             if (name.back() == 'p') name.pop_back();                // 0.000000 -> 0
                             return "g_" + name;
                         });

TEST(HenyeyGreenstein, SamplesAreUnitAndForwardForLargeG) {
    const Vec3 wi = glm::normalize(Vec3(-0.1, 0.2, 1.0));
    const HenyeyGreenstein hg{0.95};
    Rng rng(7, Stream::Test, 0, 0);
    double meanCos = 0.0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        const Vec3 wo = hg.sample(wi, u1, u2);
        ASSERT_NEAR(glm::length(wo), 1.0, 1e-12);
        meanCos += glm::dot(wi, wo) / n;
    }
    // Mean cosine g; the standard deviation of the mean is below sqrt(E[mu^2] - g^2) / sqrt(n) < 0.001.
    EXPECT_NEAR(meanCos, 0.95, 0.005);
}

TEST(Medium, TransmittanceIsBeerLambertPerChannel) {
    Medium m;
    m.sigma_t = Color(0.5, 2.0, 0.0);
    const Color tr = m.transmittance(1.5);
    EXPECT_NEAR(tr.x, std::exp(-0.75), 1e-15);
    EXPECT_NEAR(tr.y, std::exp(-3.0), 1e-15);
    EXPECT_EQ(tr.z, 1.0);
    EXPECT_NEAR(m.samplingSigma(), 2.5 / 3.0, 1e-15);
}
