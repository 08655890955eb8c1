// The viewer's measuring aids (app/viewer/instrument.h): ticks, the profile's log scale, and the
// noise estimate from the spread between passes.
#include "viewer/instrument.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace tpb::app;

TEST(Instrument, TicksAreRoundStepsInsideTheRange) {
    const std::vector<AxisTick> t = niceTicks(0.0, 36.9, 8);
    ASSERT_GE(t.size(), 4u);
    EXPECT_LE(t.size(), 8u);
    EXPECT_EQ(t.front().label, "0");
    EXPECT_DOUBLE_EQ(t[1].value - t[0].value, 5.0);
    EXPECT_EQ(t[1].label, "5");
    EXPECT_LE(t.back().value, 36.9);
    const std::vector<AxisTick> f = niceTicks(1.23, 1.31, 5);  // 0.02 steps
    ASSERT_FALSE(f.empty());
    EXPECT_EQ(f.front().label, "1.24");
    for (const AxisTick& k : f) EXPECT_TRUE(k.value >= 1.23 - 1e-12 && k.value <= 1.31 + 1e-12) << k.value;
    EXPECT_TRUE(niceTicks(2.0, 2.0, 5).empty());
    EXPECT_TRUE(niceTicks(0.0, INFINITY, 5).empty());
}

TEST(Instrument, LogScaleMapsDecadesBelowThePeak) {
    const std::vector<float> v = logScale({1.0f, 0.1f, 1e-3f, 1e-9f, 0.0f}, 6.0f);
    EXPECT_FLOAT_EQ(v[0], 1.0f);
    EXPECT_NEAR(v[1], 1.0f - 1.0f / 6.0f, 1e-6);
    EXPECT_NEAR(v[2], 0.5f, 1e-6);
    EXPECT_FLOAT_EQ(v[3], 0.0f);  // below the floor
    EXPECT_FLOAT_EQ(v[4], 0.0f);  // no light
    EXPECT_EQ(logScale({0.0f, 0.0f}, 6.0f), (std::vector<float>{0.0f, 0.0f}));
}

// Batches of passes with known noise: the estimate matches the standard error of the mean, also
// with unequal batch weights (warm-up passes, several passes completing between two reads).
TEST(Instrument, NoiseIsTheStandardErrorOfTheMeanFromTheBatches) {
    std::mt19937 rng(5);
    const size_t pixels = 4000;
    const double level = 2.0, sigma = 0.5;  // one unit-weight pass: mean 2, standard deviation 0.5
    BatchNoise noise;
    noise.reset(pixels);
    std::vector<double> sum(pixels, 0.0);
    std::vector<float> mean(pixels);
    double weight = 0.0;
    const double weights[] = {0.125, 0.25, 0.5, 1, 1, 2, 1, 3, 1, 1, 1, 2, 1, 1, 1, 1};
    for (double w : weights) {
        std::normal_distribution<double> batch(level, sigma / std::sqrt(w));  // a batch of weight w
        for (size_t i = 0; i < pixels; ++i) {
            sum[i] += w * batch(rng);
            mean[i] = static_cast<float>(sum[i] / (weight + w));
        }
        weight += w;
        noise.add(mean, weight);
        if (noise.batches() == 1) {
            EXPECT_LT(noise.relativeError(), 0.0);  // one batch: no spread yet
        }
    }
    EXPECT_EQ(noise.batches(), 16);
    const double expected = sigma / std::sqrt(weight) / level;
    EXPECT_NEAR(noise.relativeError(), expected, 0.05 * expected);
    noise.add(mean, weight);  // nothing new: ignored
    EXPECT_EQ(noise.batches(), 16);
    // Halving the noise of every pass halves the estimate (it measures, it is not a schedule).
    BatchNoise quiet;
    quiet.reset(pixels);
    std::fill(sum.begin(), sum.end(), 0.0);
    weight = 0.0;
    for (double w : weights) {
        std::normal_distribution<double> batch(level, 0.5 * sigma / std::sqrt(w));
        for (size_t i = 0; i < pixels; ++i) {
            sum[i] += w * batch(rng);
            mean[i] = static_cast<float>(sum[i] / (weight + w));
        }
        weight += w;
        quiet.add(mean, weight);
    }
    EXPECT_NEAR(quiet.relativeError(), 0.5 * expected, 0.05 * expected);
}
