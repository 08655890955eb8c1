// base/math.h: oneMinusExpNeg (1 - exp(-y), the kernels' and the time splat's exponential mass), a
// polynomial on [0, 1/32] and std::expm1 elsewhere, against long double's expm1l.
#include "base/math.h"

#include "base/rng.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include <cmath>

using namespace tpb;

namespace {
double reference(double y) { return static_cast<double>(-std::expm1l(-static_cast<long double>(y))); }
}  // namespace

TEST(OneMinusExpNeg, PolynomialRangeIsWithinTwoUlpOfLongDouble) {
    Rng rng(1, Stream::Test, 0, 0);
    double worst = 0.0;
    for (int i = 0; i < 200000; ++i) {
        // Uniform on [0, 1/32] and log-uniform down to 1e-300 (the relative error must hold for tiny y).
        const double y = i % 2 ? 0.03125 * rng.uniform() : 0.03125 * std::pow(10.0, -300.0 * rng.uniform());
        const double want = reference(y), got = oneMinusExpNeg(y);
        ASSERT_TRUE(std::isfinite(got)) << y;
        if (want > 0.0) worst = std::max(worst, std::abs(got - want) / want);
    }
    EXPECT_LT(worst, 4.5e-16);  // two ulp
    EXPECT_EQ(oneMinusExpNeg(0.0), 0.0);
    EXPECT_EQ(oneMinusExpNeg(1e-300), 1e-300);
}

TEST(OneMinusExpNeg, OutsideThePolynomialItIsExpm1AndContinuousAtTheSwitch) {
    for (double y : {0.0312500001, 0.05, 1.0, 30.0, 800.0, -1e-3, -2.0})
        EXPECT_EQ(oneMinusExpNeg(y), -std::expm1(-y)) << y;
    EXPECT_EQ(oneMinusExpNeg(kInf), 1.0);
    EXPECT_TRUE(std::isnan(oneMinusExpNeg(std::nan(""))));
    // Either side of y = 1/32: the two forms agree to an ulp.
    const double below = 0.03125, above = std::nextafter(0.03125, 1.0);
    EXPECT_NEAR(oneMinusExpNeg(below), reference(below), 1e-17);
    EXPECT_NEAR(oneMinusExpNeg(above) - oneMinusExpNeg(below), reference(above) - reference(below), 2e-17);
}

// nextFloat (by the bits) is std::nextafter towards +-inf: on zeros, denormals, the largest float,
// infinities, NaN, and a sweep of magnitudes of both signs.
TEST(Math, NextFloatIsNextafterTowardsInfinity) {
    std::vector<float> values = {0.0f,
                                 -0.0f,
                                 std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(),
                                 std::numeric_limits<float>::min(),
                                 -std::numeric_limits<float>::min(),
                                 std::numeric_limits<float>::max(),
                                 -std::numeric_limits<float>::max(),
                                 INFINITY,
                                 -INFINITY,
                                 1.0f,
                                 -1.0f};
    for (double x = 1e-40; x < 1e38; x *= 1.37) {
        values.push_back(static_cast<float>(x));
        values.push_back(static_cast<float>(-x));
    }
    for (const float f : values)
        for (const bool up : {false, true}) {
            const float want = std::nextafter(f, up ? INFINITY : -INFINITY), got = nextFloat(f, up);
            EXPECT_EQ(std::memcmp(&want, &got, sizeof want), 0) << f << (up ? " up" : " down");
        }
    EXPECT_TRUE(std::isnan(nextFloat(NAN, true)));
    EXPECT_TRUE(std::isnan(nextFloat(NAN, false)));
}
