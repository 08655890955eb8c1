// Exact tests of the progressive time kernel's splat (film/time_kernel.h, K1-K4): the share of
// each bin of (profile * box) against an independent quadrature of the convolution, for an instant
// and for the exponential segment (kappa > 0, < 0, ~0; b > 0, < 0, ~0; chromatic), energy
// conservation with what falls before and after the film, the tau -> 0 limit, the bit-identical
// kernel-free path, the first moment, and the phi-functions against long double.
#include "film/time_kernel.h"
#include "film/transient_film.h"
#include "base/rng.h"

#include "support/quadrature.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

using namespace tpb;

namespace {

// ---- the oracle: quadrature of the convolution, nothing from time_kernel.h --------------------

// Composite 5-point Gauss-Legendre on n panels.
double quad(const std::function<double(double)>& f, double a, double b, int n) {
    return test::gaussLegendre5(f, a, b, n);
}

// The share of the time interval [lo, hi] (lo may be -inf, hi +inf) of the profile "density
// exp(-kappa s) on [s0, s1], arriving at a + b s" (an instant when s1 == s0) convolved with the box of
// half-width tau: Int p(s) |[lo, hi] n [t(s) - tau, t(s) + tau]| / (2 tau) ds, split where the
// overlap's slope changes (t(s) = lo +- tau, hi +- tau) so every piece is smooth (exp x linear).
double oracleShare(double kappa, double s0, double s1, double a, double b, double tau, double lo, double hi) {
    const auto weight = [&](double t) {
        const double l = std::max(lo, t - tau), h = std::min(hi, t + tau);
        return std::max(0.0, h - l) / (2.0 * tau);
    };
    if (!(s1 > s0)) return weight(a + b * s0);
    std::vector<double> cuts = {s0, s1};
    if (b != 0.0)
        for (double e : {lo - tau, lo + tau, hi - tau, hi + tau}) {
            const double s = (e - a) / b;
            if (std::isfinite(s) && s > s0 && s < s1) cuts.push_back(s);
        }
    std::sort(cuts.begin(), cuts.end());
    const auto density = [&](double s) { return std::exp(-kappa * (s - s0)); };
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        if (!(cuts[i + 1] > cuts[i])) continue;
        num += quad([&](double s) { return density(s) * weight(a + b * s); }, cuts[i], cuts[i + 1], 200);
        den += quad(density, cuts[i], cuts[i + 1], 200);
    }
    return num / den;
}

struct Splat {
    std::vector<Color> bins;
    OutsideFilm out;
};

Splat smoothed(const TimeBins& tb, const Color& E, const Color& kappa, double s0, double s1, double a, double b,
               const TimeKernel& k) {
    Splat r;
    r.bins.assign(static_cast<size_t>(tb.bins), Color(0.0));
    r.out = splatTimeSmoothed(tb, E, kappa, s0, s1, a, b, k, [&](int bin, const Color& c) {
        ASSERT_GE(bin, 0);
        ASSERT_LT(bin, tb.bins);
        r.bins[static_cast<size_t>(bin)] += c;
    });
    return r;
}

Splat plain(const TimeBins& tb, const Color& E, const Color& kappa, double s0, double s1, double a, double b) {
    Splat r;
    r.bins.assign(static_cast<size_t>(tb.bins), Color(0.0));
    r.out =
        splatTime(tb, E, kappa, s0, s1, a, b, [&](int bin, const Color& c) { r.bins[static_cast<size_t>(bin)] += c; });
    return r;
}

TimeKernel box(double tau) { return {TimeKernelKind::Box, tau}; }

struct Case {
    double kappa, s0, s1, a, b;
    const char* what;
};

// Film [2, 6] m in 40 bins of 0.1 m.
const TimeBins kFilm{2.0, 0.1, 40};

const Case kCases[] = {
    {3.0, 0.2, 1.4, 2.5, 1.7, "kappa > 0, b > 0"},
    {-3.0, 0.2, 1.4, 2.5, 1.7, "kappa < 0, b > 0"},
    {3.0, 0.2, 1.4, 5.0, -1.3, "kappa > 0, b < 0"},
    {-3.0, 0.2, 1.4, 5.0, -1.3, "kappa < 0, b < 0"},
    {1e-9, 0.2, 1.4, 2.5, 1.7, "kappa ~ 0"},
    {0.0, 0.2, 1.4, 2.5, 1.7, "kappa = 0 (uniform)"},
    {-2e-10, 0.2, 1.4, 5.0, -1.3, "kappa ~ 0-, b < 0"},
    {40.0, 0.2, 1.4, 2.5, 1.7, "steep decay (mu = 48)"},
    {-40.0, 0.2, 1.4, 5.0, -1.3, "steep growth, b < 0"},
    {3.0, 0.2, 1.4, 3.7, 1e-5, "b ~ 0 (T = 1.2e-5 m, above the instant rule)"},
    {3.0, 0.2, 1.4, 3.7, -1e-5, "b ~ 0-"},
    {3.0, 0.0, 1.2, 1.6, 1.0, "straddles the film's start"},
    {-2.0, 0.0, 1.6, 4.9, 1.0, "straddles the film's end"},
    {1.0, 0.0, 12.0, 0.5, 0.6, "covers the whole film and beyond"},
    {0.0, 0.7, 0.7, 3.33, 1.0, "an instant (s0 == s1)"},
    {0.0, 0.0, 0.0, 2.03, 0.0, "an instant near the film's start"},
    {0.0, 0.0, 0.0, 5.97, 0.0, "an instant near the film's end"},
};

// Returns the largest difference seen.
double expectMatchesOracle(const Case& c, double tau, const Color& kappa, double tol) {
    double worst = 0.0;
    const Splat s = smoothed(kFilm, Color(1.0), kappa, c.s0, c.s1, c.a, c.b, box(tau));
    for (int ch = 0; ch < 3; ++ch) {
        const double k = kappa[ch];
        for (int bin = 0; bin < kFilm.bins; ++bin) {
            const double lo = kFilm.startOpl + bin * kFilm.binWidth;
            const double ref = oracleShare(k, c.s0, c.s1, c.a, c.b, tau, lo, lo + kFilm.binWidth);
            worst = std::max(worst, std::abs(s.bins[static_cast<size_t>(bin)][ch] - ref));
            EXPECT_NEAR(s.bins[static_cast<size_t>(bin)][ch], ref, tol)
                << c.what << ", tau " << tau << ", channel " << ch << ", bin " << bin;
        }
        EXPECT_NEAR(s.out.before[ch], oracleShare(k, c.s0, c.s1, c.a, c.b, tau, -kInf, kFilm.startOpl), tol)
            << c.what << ", tau " << tau << " (before)";
        EXPECT_NEAR(s.out.after[ch], oracleShare(k, c.s0, c.s1, c.a, c.b, tau, kFilm.endOpl(), kInf), tol)
            << c.what << ", tau " << tau << " (after)";
    }
    return worst;
}

}  // namespace

TEST(TimeKernelMath, PhiFunctionsMatchLongDouble) {
    EXPECT_EQ(expPhi1(0.0), 1.0);
    EXPECT_EQ(expPhi2(0.0), 0.5);
    for (double z : {-1e-9, -0.99e-5, -1.01e-5, -1e-3, -0.1, -0.49, -0.51, -1.0, -7.0, -60.0, -700.0, 1e-4, 0.3}) {
        const long double lz = z;
        const long double e = std::expm1(lz);
        // Series in long double where the direct form would cancel.
        long double p2 = 0.0L, term = 0.5L;
        for (int k = 0; k < 40; ++k) {
            p2 += term;
            term *= lz / (k + 3);
        }
        if (std::abs(z) > 1.0) p2 = (e - lz) / (lz * lz);
        EXPECT_NEAR(expPhi1(z), static_cast<double>(e / lz), 2e-16 * std::abs(static_cast<double>(e / lz))) << z;
        EXPECT_NEAR(expPhi2(z), static_cast<double>(p2), 1e-15 * static_cast<double>(p2)) << z;
    }
}

TEST(TimeKernelMath, SharesMatchQuadratureOfTheConvolution) {
    double worst = 0.0;
    for (const Case& c : kCases)
        for (double tau : {0.003, 0.07, 0.5, 3.0})
            worst = std::max(worst, expectMatchesOracle(c, tau, Color(c.kappa), 2e-13));
    std::printf("convolved shares vs quadrature: worst |difference| %.3g (E = 1)\n", worst);
}

// With a causal floor F (time_splat.h, ArrivalFloor) the smoothed profile's part before F is
// mirrored about it: bin [lo, hi] gets the unfloored share of [max(lo, F), hi] plus that of its
// mirror image [2F - hi, 2F - max(lo, F)]; nothing before F (docs/developer/adding-an-estimator.md, "Causality").
TEST(TimeKernelMath, AFloorMirrorsTheSmoothedProfilesEarlyPart) {
    double worst = 0.0;
    for (const Case& c : kCases)
        for (double tau : {0.07, 0.5})
            for (double lag : {0.05, 0.3, 1.0}) {  // the floor this far after the smoothed support's start
                const double tA = std::min(c.a + c.b * c.s0, c.a + c.b * c.s1);
                const double F = tA - tau + lag;
                Splat r;
                r.bins.assign(static_cast<size_t>(kFilm.bins), Color(0.0));
                r.out = splatTimeSmoothed(
                    kFilm, Color(1.0), Color(c.kappa), c.s0, c.s1, c.a, c.b, box(tau),
                    [&](int bin, const Color& e) { r.bins[static_cast<size_t>(bin)] += e; }, F);
                const auto share = [&](double lo, double hi) {
                    if (!(hi > F)) return 0.0;
                    const double l = std::max(lo, F);
                    return oracleShare(c.kappa, c.s0, c.s1, c.a, c.b, tau, l, hi) +
                           oracleShare(c.kappa, c.s0, c.s1, c.a, c.b, tau, 2.0 * F - hi, 2.0 * F - l);
                };
                double total = r.out.before.x + r.out.after.x;
                for (int bin = 0; bin < kFilm.bins; ++bin) {
                    const double lo = kFilm.startOpl + bin * kFilm.binWidth, got = r.bins[static_cast<size_t>(bin)].x;
                    worst = std::max(worst, std::abs(got - share(lo, lo + kFilm.binWidth)));
                    EXPECT_NEAR(got, share(lo, lo + kFilm.binWidth), 1e-12)
                        << c.what << ", tau " << tau << ", lag " << lag << ", bin " << bin;
                    if (lo + kFilm.binWidth <= F) {
                        EXPECT_EQ(got, 0.0) << c.what << ", bin " << bin;
                    }
                    total += got;
                }
                EXPECT_NEAR(r.out.before.x, share(-kInf, kFilm.startOpl), 1e-12) << c.what;
                EXPECT_NEAR(total, 1.0, 1e-12) << c.what;  // energy kept
            }
    std::printf("floored (mirrored) shares vs quadrature: worst |difference| %.3g (E = 1)\n", worst);
}

TEST(TimeKernelMath, ChromaticChannelsEachMatchQuadrature) {
    for (const Case& c : kCases) {
        if (!(c.s1 > c.s0)) continue;
        for (double tau : {0.02, 0.4}) expectMatchesOracle(c, tau, Color(2.0, -1.0, 1e-8), 2e-13);
    }
}

TEST(TimeKernelMath, AnIntervalBelowTheInstantRuleIsSmoothedAsAnInstant) {
    // T = 1.2e-13 m < 1e-9 bin: the same instant rule as splatTime; the true convolution differs by O(T / tau).
    const Case c{3.0, 0.2, 1.4, 3.7, 1e-13, "b ~ 0, instant rule"};
    expectMatchesOracle(c, 0.05, Color(3.0), 1e-11);
}

TEST(TimeKernelMath, EnergyIsConservedWithBeforeAndAfter) {
    Rng rng(7, Stream::Camera, 1, 2);
    double worst = 0.0;
    for (int i = 0; i < 3000; ++i) {
        const double s0 = rng.uniform(), len = i % 7 == 0 ? 0.0 : 3.0 * rng.uniform();
        const double a = 0.5 + 6.0 * rng.uniform(), b = (rng.uniform() - 0.5) * (i % 5 == 0 ? 1e-6 : 4.0);
        const Color kappa = i % 3 == 0
                                ? Color(20.0 * (rng.uniform() - 0.5))
                                : Color(20.0 * (rng.uniform() - 0.5), 1e-9 * rng.uniform(), -3.0 * rng.uniform());
        const double tau = std::pow(10.0, -4.0 + 5.0 * rng.uniform());  // 1e-4 .. 10 m
        const Color E(1.0, 2.5, 0.25);
        const Splat s = smoothed(kFilm, E, kappa, s0, s0 + len, a, b, box(tau));
        Color sum = s.out.before + s.out.after;
        for (const Color& v : s.bins) {
            ASSERT_GE(v.x, 0.0);
            ASSERT_GE(v.y, 0.0);
            ASSERT_GE(v.z, 0.0);
            sum += v;
        }
        ASSERT_GE(std::min({s.out.before.x, s.out.after.x, s.out.before.z, s.out.after.z}), 0.0);
        for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, std::abs(sum[ch] - E[ch]) / E[ch]);
    }
    std::printf("energy conservation: worst |sum(bins) + before + after - E| / E = %.3g over 3000 splats\n", worst);
    EXPECT_LT(worst, 1e-13);
}

TEST(TimeKernelMath, TauToZeroGivesTheKernelFreeSplat) {
    for (const Case& c : kCases) {
        const Color kappa = c.s1 > c.s0 ? Color(c.kappa, -1.5, 0.0) : Color(0.0);
        const Splat ref = plain(kFilm, Color(1.0), kappa, c.s0, c.s1, c.a, c.b);
        for (double tau : {1e-8, 1e-11, 1e-14}) {
            const Splat s = smoothed(kFilm, Color(1.0), kappa, c.s0, c.s1, c.a, c.b, box(tau));
            // The kernel moves at most the mass within tau of a bin edge: density x tau.
            const double tol = std::max(1e-12, 30.0 * tau);
            for (int bin = 0; bin < kFilm.bins; ++bin)
                for (int ch = 0; ch < 3; ++ch)
                    EXPECT_NEAR(s.bins[static_cast<size_t>(bin)][ch], ref.bins[static_cast<size_t>(bin)][ch], tol)
                        << c.what << ", tau " << tau << ", bin " << bin;
            for (int ch = 0; ch < 3; ++ch) {
                EXPECT_NEAR(s.out.before[ch], ref.out.before[ch], tol) << c.what;
                EXPECT_NEAR(s.out.after[ch], ref.out.after[ch], tol) << c.what;
            }
        }
    }
}

TEST(TimeKernelMath, AnInactiveKernelIsTheKernelFreeCodeBitForBit) {
    for (const Case& c : kCases) {
        const Color kappa = c.s1 > c.s0 ? Color(c.kappa, -1.5, 0.0) : Color(0.0);
        const Splat ref = plain(kFilm, Color(0.3, 1.0, 7.0), kappa, c.s0, c.s1, c.a, c.b);
        for (const TimeKernel k :
             {TimeKernel{}, TimeKernel{TimeKernelKind::Box, 0.0}, TimeKernel{TimeKernelKind::None, 0.4}}) {
            const Splat s = smoothed(kFilm, Color(0.3, 1.0, 7.0), kappa, c.s0, c.s1, c.a, c.b, k);
            for (int bin = 0; bin < kFilm.bins; ++bin)
                ASSERT_EQ(s.bins[static_cast<size_t>(bin)], ref.bins[static_cast<size_t>(bin)]);
            ASSERT_EQ(s.out.before, ref.out.before);
            ASSERT_EQ(s.out.after, ref.out.after);
        }
    }
    // The film's entry points: splatSpread / splatInstant with an inactive kernel equal the old ones.
    PixelAccumulator a(kFilm.bins), b(kFilm.bins);
    FilmTally ta, tb;
    for (const Case& c : kCases) {
        const Color kappa = c.s1 > c.s0 ? Color(c.kappa, -1.5, 0.0) : Color(0.0);
        splatSpread(kFilm, a, ta, Color(1.0, 2.0, 3.0), kappa, c.s0, c.s1, c.a, c.b, c.a - 1.0, 0.5 * c.b);
        splatSpread(kFilm, b, tb, Color(1.0, 2.0, 3.0), kappa, c.s0, c.s1, c.a, c.b, c.a - 1.0, 0.5 * c.b,
                    TimeKernel{});
        splatInstant(kFilm, a, ta, Color(0.5), c.a, c.a - 0.7);
        splatInstant(kFilm, b, tb, Color(0.5), c.a, c.a - 0.7, TimeKernel{TimeKernelKind::Box, 0.0});
    }
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped}) {
        for (int k = 0; k < kFilm.bins; ++k)
            for (int ch = 0; ch < 3; ++ch) ASSERT_EQ(a.bin(axis, k)[ch], b.bin(axis, k)[ch]);
        EXPECT_EQ(a.before(axis), b.before(axis));
        EXPECT_EQ(a.after(axis), b.after(axis));
    }
    EXPECT_EQ(a.steady(), b.steady());
    for (int ax = 0; ax < 2; ++ax) {
        EXPECT_EQ(ta.inside[ax], tb.inside[ax]);
        EXPECT_EQ(ta.outside[ax], tb.outside[ax]);
        EXPECT_EQ(ta.before[ax], tb.before[ax]);
    }
}

TEST(TimeKernelMath, TheFilmKeepsTheSteadyStateAndSmoothsBothAxes) {
    PixelAccumulator a(kFilm.bins);
    FilmTally t;
    const Color L(1.0, 0.5, 0.25);
    splatSpread(kFilm, a, t, L, Color(2.0), 0.0, 1.0, 3.0, 1.5, 2.5, -0.5, box(0.3));
    EXPECT_EQ(a.steady(), L);
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped}) {
        Color sum = a.before(axis) + a.after(axis);
        int touched = 0;
        for (int k = 0; k < kFilm.bins; ++k) {
            sum += Color(a.bin(axis, k)[0], a.bin(axis, k)[1], a.bin(axis, k)[2]);
            touched += a.bin(axis, k)[0] > 0.0;
        }
        EXPECT_NEAR(sum.x, L.x, 1e-14);
        EXPECT_NEAR(sum.z, L.z, 1e-14);
        // Support of the real axis: [3 - 0.3, 4.5 + 0.3] = 21 bins; unwarped: [2 - 0.3, 2.5 + 0.3] from the film's start.
        EXPECT_EQ(touched, axis == TimeAxis::Real ? 21 : 8);
    }
}

TEST(TimeKernelMath, TheSymmetricKernelKeepsTheMeanArrivalTime) {
    // Bins 1 mm, kernel half-width ~5 cm (50 bins): the binned mean of a smoothed instant is t0 up to
    // the two partly covered end bins, |error| <= bw^2 / (8 tau); exactly t0 when t0 is a bin centre
    // or edge (the bins are then symmetric about t0).
    const TimeBins fine{2.0, 0.001, 4000};
    const double tau = 0.05037;  // 2 tau not a whole number of bins: the end bins do not mirror each other
    const auto binnedMean = [&](const Splat& s) {
        double m = 0.0, w = 0.0;
        for (int k = 0; k < fine.bins; ++k) {
            const double c = fine.startOpl + (k + 0.5) * fine.binWidth;
            m += c * s.bins[static_cast<size_t>(k)].x;
            w += s.bins[static_cast<size_t>(k)].x;
        }
        return m / w;
    };
    Rng rng(11, Stream::Camera, 3, 4);
    double worst = 0.0;
    for (int i = 0; i < 50; ++i) {
        const double t0 = 3.0 + 2.0 * rng.uniform();
        const double mean = binnedMean(smoothed(fine, Color(1.0), Color(0.0), 0.0, 0.0, t0, 0.0, box(tau)));
        worst = std::max(worst, std::abs(mean - t0));
        EXPECT_LE(std::abs(mean - t0), fine.binWidth * fine.binWidth / (8.0 * tau) + 1e-12) << t0;
    }
    std::printf("instant: worst |binned mean - t0| = %.3g m (bound %.3g m)\n", worst,
                fine.binWidth * fine.binWidth / (8.0 * tau));
    for (double t0 : {3.0 + 0.0005, 3.1234 + 0.0005 - 0.0004, 4.0}) {  // bin centres and an edge
        const double mean = binnedMean(smoothed(fine, Color(1.0), Color(0.0), 0.0, 0.0, t0, 0.0, box(0.0437)));
        EXPECT_NEAR(mean, t0, 1e-12) << t0;
    }
    // The exponential segment: the convolution keeps the profile's mean (mean of the box is 0).
    // Analytic mean of exp(-mu x) on [0, 1]: 1/mu - 1/(e^mu - 1); here t = 3 + 0.8 s, s in [0, 1.5].
    const double kappa = 2.0, len = 1.5, mu = kappa * len;
    const double meanT = 3.0 + 0.8 * len * (1.0 / mu - 1.0 / std::expm1(mu));
    const double smooth = binnedMean(smoothed(fine, Color(1.0), Color(kappa), 0.0, len, 3.0, 0.8, box(0.2)));
    const double raw = binnedMean(plain(fine, Color(1.0), Color(kappa), 0.0, len, 3.0, 0.8));
    EXPECT_NEAR(smooth, meanT, 1e-6);
    EXPECT_NEAR(raw, meanT, 1e-6);
    // A one-sided kernel would move it by tau / 2 = 0.1 m: far outside these tolerances.
}
