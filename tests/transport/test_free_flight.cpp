// Free flight and segment transport (core/transport/free_flight.h, Medium in scene/medium.h),
// checked against the exponential law written here:
//  - the probability of reaching the surface at distance D is exp(-sigma_bar D) (binomial z-test),
//    the mean distance of the scattering events is that of the truncated exponential (z-test);
//  - the weights are unbiased per channel: E[weight 1{surface}] = exp(-sigma_t D) and
//    E[weight 1{event before x}] = sigma_s (1 - exp(-sigma_t x)) / sigma_t for a chromatic
//    medium (z-tests), and exactly sigma_s / sigma_bar, 1 for a grey one;
//  - transmittance and OPL of a segment: exp(-sigma_t d), ior * d, exactly 1 in vacuum (also for
//    an unbounded segment).
#include "transport/free_flight.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tpb;

namespace {

Region makeRegion(const Color& sigma_s, const Color& sigma_a, double ior) {
    Region r;
    r.ior = ior;
    r.medium.sigma_s = sigma_s;
    r.medium.sigma_a = sigma_a;
    r.medium.sigma_t = sigma_s + sigma_a;
    r.medium.ior = ior;
    r.medium.scattering = true;
    r.hasMedium = true;
    return r;
}

const Ray kRay{Vec3(0.0), Vec3(0.0, 0.0, 1.0)};

// Mean and standard error of a running sample.
struct Moments {
    double n = 0, sum = 0, sum2 = 0;
    void add(double x) {
        n += 1;
        sum += x;
        sum2 += x * x;
    }
    double mean() const { return sum / n; }
    double stderrOfMean() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean()) / n); }
};

}  // namespace

TEST(FreeFlight, SurfaceReachedWithProbabilityExpMinusSigmaBarD) {
    const Region region = makeRegion(Color(1.5), Color(0.5), 1.33);  // sigma_bar = 2 /m
    const double tMax = 0.8;
    Rng rng(5, Stream::Test, 0, 10);
    const int n = 200000;
    int reached = 0;
    Moments dist;
    for (int i = 0; i < n; ++i) {
        const FreeFlight ff = sampleFreeFlight(region, kRay, tMax, rng);
        EXPECT_DOUBLE_EQ(ff.opl, 1.33 * ff.distance);
        if (ff.scattered) {
            ASSERT_LT(ff.distance, tMax);
            ASSERT_GE(ff.distance, 0.0);
            EXPECT_NEAR(ff.weight.x, 1.5 / 2.0, 1e-12);  // grey: sigma_s / sigma_bar
            dist.add(ff.distance);
        } else {
            ++reached;
            EXPECT_EQ(ff.distance, tMax);
            EXPECT_NEAR(ff.weight.y, 1.0, 1e-12);  // grey: T / T_bar = 1
        }
    }
    const double sigma = 2.0, p = std::exp(-sigma * tMax);
    EXPECT_LT(std::abs((reached - n * p) / std::sqrt(n * p * (1.0 - p))), 4.0) << double(reached) / n << " vs " << p;
    // Truncated exponential: E[d | d < D] = 1/sigma - D e^{-sigma D} / (1 - e^{-sigma D}).
    const double meanRef = 1.0 / sigma - tMax * p / (1.0 - p);
    EXPECT_LT(std::abs(dist.mean() - meanRef) / dist.stderrOfMean(), 4.0) << dist.mean() << " vs " << meanRef;
}

TEST(FreeFlight, UnboundedSegmentAlwaysScattersWithMeanFreePath) {
    const Region region = makeRegion(Color(0.2, 0.4, 0.6), Color(0.2), 1.0);  // sigma_bar = 0.6 /m
    Rng rng(6, Stream::Test, 0, 11);
    Moments dist;
    for (int i = 0; i < 100000; ++i) {
        const FreeFlight ff = sampleFreeFlight(region, kRay, kInf, rng);
        ASSERT_TRUE(ff.scattered);
        ASSERT_TRUE(std::isfinite(ff.distance));
        dist.add(ff.distance);
    }
    EXPECT_LT(std::abs(dist.mean() - 1.0 / 0.6) / dist.stderrOfMean(), 4.0) << dist.mean();
}

TEST(FreeFlight, ChromaticWeightsAreUnbiasedPerChannel) {
    const Color sigma_s(0.5, 1.0, 2.0), sigma_a(0.5, 0.2, 1.0);
    const Color sigma_t = sigma_s + sigma_a;  // (1, 1.2, 3): sigma_bar = 1.7333
    const Region region = makeRegion(sigma_s, sigma_a, 1.0);
    const double tMax = 0.7;
    Rng rng(8, Stream::Test, 0, 12);
    Moments surf[3], vol[3];
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
        const FreeFlight ff = sampleFreeFlight(region, kRay, tMax, rng);
        for (int c = 0; c < 3; ++c) {
            surf[c].add(ff.scattered ? 0.0 : ff.weight[c]);
            vol[c].add(ff.scattered ? ff.weight[c] : 0.0);
        }
    }
    for (int c = 0; c < 3; ++c) {
        // Surface: the transmittance; volume: the scattered fraction int_0^D sigma_s e^{-sigma_t s} ds.
        const double surfRef = std::exp(-sigma_t[c] * tMax);
        const double volRef = sigma_s[c] * (1.0 - std::exp(-sigma_t[c] * tMax)) / sigma_t[c];
        EXPECT_LT(std::abs(surf[c].mean() - surfRef) / surf[c].stderrOfMean(), 4.0)
            << c << " " << surf[c].mean() << " vs " << surfRef;
        EXPECT_LT(std::abs(vol[c].mean() - volRef) / vol[c].stderrOfMean(), 4.0)
            << c << " " << vol[c].mean() << " vs " << volRef;
    }
}

TEST(FreeFlight, SegmentTransmittanceAndOpl) {
    const Region region = makeRegion(Color(0.3, 0.6, 0.9), Color(0.1), 1.5);
    for (const double d : {0.0, 0.25, 2.0, 10.0}) {
        const SegmentTransport st = crossSegment(region, kRay, d);
        EXPECT_NEAR(st.transmittance.x, std::exp(-0.4 * d), 1e-15);
        EXPECT_NEAR(st.transmittance.y, std::exp(-0.7 * d), 1e-15);
        EXPECT_NEAR(st.transmittance.z, std::exp(-1.0 * d), 1e-15);
        EXPECT_DOUBLE_EQ(st.opl, 1.5 * d);
        EXPECT_EQ(region.medium.transmittance(kRay, d), region.medium.transmittance(d));
    }
    Region vacuum;
    vacuum.ior = 1.0;
    for (const double d : {0.5, kInf}) {
        const SegmentTransport st = crossSegment(vacuum, kRay, d);
        EXPECT_EQ(st.transmittance, Color(1.0));  // exactly: no 0 * inf
        EXPECT_EQ(st.opl, d);
    }
}
