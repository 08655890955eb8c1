// Exact and analytic tests of the ray-beam kernel, the time splat, the progressive schedule and the
// phase function / Fresnel helpers: closed forms against numerical quadrature and limits.
#include "estimators/beam2d.h"
#include "scene/bsdf.h"
#include "scene/medium.h"
#include "base/progressive.h"
#include "base/rng.h"
#include "film/time_splat.h"

#include "support/quadrature.h"

#include <gtest/gtest.h>

#include <functional>

using namespace tpb;

namespace {

// Composite Gauss-Legendre (5 points) on n panels: accurate for smooth integrands.
double quad(const std::function<double(double)>& f, double a, double b, int n = 2000) {
    return test::gaussLegendre5(f, a, b, n);
}

bool insideKernel(const Vec3& p, const Vec3& xb, const Vec3& wb, double L, double r) {
    const double sb = glm::dot(p - xb, wb);
    if (sb < 0.0 || sb > L) return false;
    const Vec3 perp = p - xb - sb * wb;
    return glm::dot(perp, perp) <= r * r;
}

Vec3 randomDir(Rng& rng) {
    const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * kPi * rng.uniform();
    const double s = std::sqrt(1.0 - z * z);
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
}

}  // namespace

TEST(BeamKernel, ExpRelLimits) {
    EXPECT_DOUBLE_EQ(expRel(0.0), 1.0);
    EXPECT_NEAR(expRel(1e-8), 1.0 - 0.5e-8, 1e-15);
    EXPECT_NEAR(expRel(1.0), 1.0 - std::exp(-1.0), 1e-15);
    EXPECT_NEAR(expRel(800.0), 1.0 / 800.0, 1e-15);
    EXPECT_TRUE(std::isfinite(expRel(-700.0)));
    // Both branches against a long-double reference around the series/expm1 switch.
    for (double x : {1e-7, 0.99e-5, 1.01e-5, 1e-3, -1e-3, 0.5}) {
        const long double lx = x;
        const double ref = static_cast<double>(-std::expm1(-lx) / lx);
        EXPECT_NEAR(expRel(x), ref, 1e-15) << x;
    }
}

TEST(BeamKernel, OverlapIntervalMatchesPointSampling) {
    Rng rng(7, Stream::Test, 0, 0);
    int nonEmpty = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Vec3 xr(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
        const Vec3 wr = randomDir(rng), wb = randomDir(rng);
        const Vec3 xb = xr + 0.6 * wr + 0.2 * randomDir(rng) - 0.3 * wb;
        const double L = 0.2 + rng.uniform(), r = 0.05 + 0.1 * rng.uniform(), sMax = 0.3 + 1.5 * rng.uniform();
        RayBeamOverlap o;
        const bool hit = rayBeamOverlap(xr, wr, sMax, xb, wb, L, r, o);
        // Brute force: sample the segment finely.
        const int n = 20000;
        double lo = kInf, hi = -kInf;
        for (int i = 0; i <= n; ++i) {
            const double s = sMax * i / n;
            if (insideKernel(xr + s * wr, xb, wb, L, r)) {
                lo = std::min(lo, s);
                hi = std::max(hi, s);
            }
        }
        const double step = sMax / n;
        if (!hit) {
            EXPECT_TRUE(!(hi >= lo) || hi - lo <= 2 * step) << "trial " << trial;
            continue;
        }
        ++nonEmpty;
        ASSERT_LE(lo, hi) << "trial " << trial;
        EXPECT_NEAR(o.sMinus, lo, 1.01 * step) << "trial " << trial;
        EXPECT_NEAR(o.sPlus, hi, 1.01 * step) << "trial " << trial;
        EXPECT_NEAR(o.cosRB, glm::dot(wr, wb), 1e-15);
    }
    EXPECT_GT(nonEmpty, 60);
}

TEST(BeamKernel, TransmittanceIntegralMatchesQuadrature) {
    Rng rng(11, Stream::Test, 0, 0);
    const double sigmas[] = {1e-12, 1e-3, 0.5, 3.0, 40.0};
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Vec3 xr(0.0), wr = randomDir(rng), wb = randomDir(rng);
        const Vec3 xb = xr + 0.5 * wr + 0.05 * randomDir(rng) - 0.4 * wb;
        RayBeamOverlap o;
        if (!rayBeamOverlap(xr, wr, 2.0, xb, wb, 1.0, 0.1, o)) continue;
        for (double st : sigmas)
            for (double tauFactor : {1.0, 0.0, -0.3}) {  // long beam, grey short beam, chromatic short beam
                const double tau = tauFactor * st;
                const double closed = transmittanceIntegral(st, tau, o);
                const double ref = quad([&](double s) { return std::exp(-st * s - tau * (o.sb0 + o.cosRB * s)); },
                                        o.sMinus, o.sPlus, 200);
                EXPECT_NEAR(closed, ref, 1e-11 * std::max(1.0, ref) + 1e-12 * ref)
                    << "sigma " << st << " trial " << trial;
                ++checked;
            }
    }
    EXPECT_GT(checked, 200);
}

TEST(BeamKernel, LimitsBeamTowardCameraPerpendicularParallelGrazing) {
    const Vec3 xr(0.0), wr(0.0, 0.0, 1.0);
    const double st = 0.7, r = 0.05;
    RayBeamOverlap o;
    // Beam pointing straight at the camera: kappa = sigma_t (1 + c) = 0 for long beams; the
    // integrand is constant: exp(-sigma_t (s + s_b(s))) with s + s_b(s) fixed.
    ASSERT_TRUE(rayBeamOverlap(xr, wr, 10.0, Vec3(0, 0, 2.0), -wr, 1.0, r, o));
    EXPECT_NEAR(o.sMinus, 1.0, 1e-12);
    EXPECT_NEAR(o.sPlus, 2.0, 1e-12);
    const double towards = transmittanceIntegral(st, st, o);
    EXPECT_NEAR(towards, std::exp(-st * 2.0) * 1.0, 1e-14);
    // Beam going away along the ray: kappa = 2 sigma_t.
    ASSERT_TRUE(rayBeamOverlap(xr, wr, 10.0, Vec3(0, 0, 1.0), wr, 1.0, r, o));
    EXPECT_NEAR(transmittanceIntegral(st, st, o),
                quad([&](double s) { return std::exp(-st * (s + s - 1.0)); }, 1.0, 2.0), 1e-12);
    // Perpendicular beam: chord of length 2r at s = 1 (c = 0, s_b constant).
    ASSERT_TRUE(rayBeamOverlap(xr, wr, 10.0, Vec3(-0.5, 0, 1.0), Vec3(1, 0, 0), 1.0, r, o));
    EXPECT_NEAR(o.sPlus - o.sMinus, 2 * r, 1e-12);
    EXPECT_NEAR(transmittanceIntegral(st, st, o),
                std::exp(-st * 0.5) * quad([&](double s) { return std::exp(-st * s); }, 1.0 - r, 1.0 + r), 1e-13);
    // Parallel and offset inside / outside the radius.
    EXPECT_TRUE(rayBeamOverlap(xr, wr, 10.0, Vec3(0.5 * r, 0, 1.0), wr, 1.0, r, o));
    EXPECT_FALSE(rayBeamOverlap(xr, wr, 10.0, Vec3(1.5 * r, 0, 1.0), wr, 1.0, r, o));
    // Grazing: the ray passes at distance r (1 - eps) from the axis: tiny, finite, shrinking chord.
    double prev = kInf;
    for (double eps : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10}) {
        if (rayBeamOverlap(xr, wr, 10.0, Vec3(r * (1 - eps), -0.5, 1.0), Vec3(0, 1, 0), 1.0, r, o)) {
            const double len = o.sPlus - o.sMinus;
            EXPECT_TRUE(std::isfinite(len));
            EXPECT_LT(len, prev);
            EXPECT_NEAR(len, 2 * r * std::sqrt(1 - (1 - eps) * (1 - eps)), 1e-9);
            prev = len;
            EXPECT_TRUE(std::isfinite(transmittanceIntegral(st, st, o)));
        }
    }
    EXPECT_FALSE(rayBeamOverlap(xr, wr, 10.0, Vec3(r * (1 + 1e-9), -0.5, 1.0), Vec3(0, 1, 0), 1.0, r, o));
}

TEST(BeamKernel, ExtremeExtinctionStaysFinite) {
    RayBeamOverlap o;
    ASSERT_TRUE(rayBeamOverlap(Vec3(0.0), Vec3(0, 0, 1), 10.0, Vec3(-0.5, 0, 1.0), Vec3(1, 0, 0), 1.0, 0.05, o));
    for (double st : {1e-12, 1e-6, 1.0, 1e3, 1e6}) {
        const double v = transmittanceIntegral(st, st, o);
        EXPECT_TRUE(std::isfinite(v)) << st;
        EXPECT_GE(v, 0.0);
    }
    // sigma_t -> 0: tends to the chord length.
    EXPECT_NEAR(transmittanceIntegral(1e-12, 1e-12, o), 0.1, 1e-12);
    // Huge extinction underflows to exactly 0, never NaN.
    EXPECT_EQ(transmittanceIntegral(1e6, 1e6, o), 0.0);
}

TEST(TimeSplat, MassConservedAndMatchesQuadrature) {
    TimeBins tb{1.0, 0.01, 100};
    Rng rng(3, Stream::Test, 0, 0);
    for (int trial = 0; trial < 200; ++trial) {
        const double s0 = rng.uniform(), s1 = s0 + 0.001 + 0.3 * rng.uniform();
        const double kappa = (rng.uniform() - 0.3) * 30.0;
        const double a = 1.0 + rng.uniform() * 0.8, b = (rng.uniform() - 0.5) * 4.0;
        std::vector<double> bins(100, 0.0);
        const OutsideFilm out =
            splatTime(tb, Color(1.0), Color(kappa), s0, s1, a, b, [&](int k, const Color& c) { bins[k] += c.x; });
        double total = out.before.x + out.after.x;
        for (double v : bins) total += v;
        EXPECT_NEAR(total, 1.0, 1e-12) << trial;
        // Each bin vs quadrature of the normalised density over the s-range mapped to the bin.
        const double norm = quad([&](double s) { return std::exp(-kappa * s); }, s0, s1, 400);
        // What falls before t = start and after t = end: quadrature of the density over the s-range
        // whose time a + b s lies there (the crossing s_c = (t_c - a) / b; which side depends on sign(b)).
        const auto massBeyond = [&](double tCross, bool below) {
            const double sc = (tCross - a) / b;
            const bool lowerSide = (b > 0.0) == below;  // s < sc maps to t < tCross when b > 0
            const double u = lowerSide ? s0 : std::max(s0, sc), v = lowerSide ? std::min(s1, sc) : s1;
            return v > u ? quad([&](double s) { return std::exp(-kappa * s); }, u, v, 200) / norm : 0.0;
        };
        EXPECT_NEAR(out.before.x, massBeyond(tb.startOpl, true), 1e-10) << trial;
        EXPECT_NEAR(out.after.x, massBeyond(tb.endOpl(), false), 1e-10) << trial;
        for (int k = 0; k < 100; ++k) {
            const double tLo = tb.startOpl + k * tb.binWidth;
            double u = (tLo - a) / b, v = (tLo + tb.binWidth - a) / b;
            if (u > v) std::swap(u, v);
            u = std::max(u, s0);
            v = std::min(v, s1);
            const double ref = v > u ? quad([&](double s) { return std::exp(-kappa * s); }, u, v, 50) / norm : 0.0;
            EXPECT_NEAR(bins[k], ref, 1e-10) << "trial " << trial << " bin " << k;
        }
    }
}

// Estimates that cross four or more bin boundaries take their masses by recurrence (time_splat.h,
// splat_detail::splatPieces: E_{i+1} = E_i exp(-kappa dx)); each bin is checked against the closed
// form in long double, over spans of 4 to 3000 bins, both directions of time along s, decaying and
// reflected profiles, uniform ones, and stiff ones (kappa len up to ~9000, where all but the first
// bins underflow). The bound per bin is the conditioning of the inputs, which the recurrence does
// not worsen: a bin boundary's s = (T_j - a) / b carries rounding ds ~ 8 eps (|T_j| + |a|) / |b|, and
// moves the bin's mass by up to the peak density times ds (kappa / (1 - e^{-kappa len}), or 1/len
// when uniform); 1e-13 on top for the masses' own rounding. (The per-boundary expm1 code this
// replaced had the same worst errors on these cases: 1.5e-13 uniform, 1.1e-12 at kappa 3000.)
// Energy conserved to 1e-12, never negative or NaN.
TEST(TimeSplat, ManyBinsByRecurrenceMatchTheClosedFormInLongDouble) {
    const TimeBins tb{2.0, 1e-3, 4000};
    Rng rng(5, Stream::Test, 0, 0);
    const double kappas[] = {0.0, 1e-14, 0.27, -0.27, 30.0, -30.0, 3000.0, -3000.0};
    int checkedBins = 0;
    for (int trial = 0; trial < 160; ++trial) {
        const double kappa = kappas[trial % 8];
        const int span = trial < 80 ? 4 + trial % 13 : 40 + static_cast<int>(2960 * rng.uniform());
        const double slope = (trial / 8) % 2 ? 0.3 + rng.uniform() : -(0.3 + 1.4 * rng.uniform());
        const double s0 = rng.uniform(), len = (span + rng.uniform()) * tb.binWidth / std::abs(slope);
        const double s1 = s0 + len;
        // Starts anywhere from a bin before the film to inside it; some run past its end.
        const double tStart = tb.startOpl + (-1.0 + (tb.bins - span * 0.5) * rng.uniform()) * tb.binWidth;
        const double a = slope > 0.0 ? tStart - slope * s0 : tStart - slope * s1, b = slope;
        std::vector<double> bins(tb.bins, 0.0);
        const OutsideFilm out = splatTime(tb, Color(1.0), Color(kappa), s0, s1, a, b, [&](int k, const Color& c) {
            ASSERT_TRUE(std::isfinite(c.x) && c.x >= 0.0) << trial << " bin " << k;
            bins[k] += c.x;
        });
        // Closed form: the mass of s in [u, v], with x measured from the decaying end.
        const long double kq = std::abs(kappa), L = len;
        const bool uniform = !(kq * L > 1e-12L);
        const auto massOf = [&](long double u, long double v) {  // s0 <= u <= v <= s1
            const long double xu = kappa >= 0.0 ? u - s0 : s1 - v, xv = kappa >= 0.0 ? v - s0 : s1 - u;
            if (uniform) return (xv - xu) / L;
            return std::exp(-kq * xu) * -std::expm1(-kq * (xv - xu)) / -std::expm1(-kq * L);
        };
        const double peakDensity = uniform ? 1.0 / len : std::abs(kappa) / -std::expm1(-std::abs(kappa) * len);
        const double ds = 8.0 * 2.2e-16 * (tb.endOpl() + std::abs(a)) / std::abs(b);
        const double tol = 1e-13 + peakDensity * ds;
        double total = out.before.x + out.after.x;
        for (int k = 0; k < tb.bins; ++k) {
            total += bins[k];
            const long double tLo = tb.startOpl + static_cast<long double>(k) * tb.binWidth, tHi = tLo + tb.binWidth;
            long double u = (tLo - a) / b, v = (tHi - a) / b;
            if (u > v) std::swap(u, v);
            u = std::max<long double>(u, s0);
            v = std::min<long double>(v, s1);
            const long double ref = v > u ? massOf(u, v) : 0.0L;
            if (ref == 0.0L && bins[k] == 0.0) continue;
            ++checkedBins;
            EXPECT_NEAR(bins[k], static_cast<double>(ref), tol) << "trial " << trial << " bin " << k;
        }
        EXPECT_NEAR(total, 1.0, 1e-12) << trial;
    }
    EXPECT_GT(checkedBins, 20000);
}

// The one-bin shortcut (no transcendental call) gives the bin all of the energy, exactly; a
// coloured kappa splats each channel as the grey splat with that channel's kappa would (the shared
// SegmentProfile evaluates channels independently, the grey path one channel for all three).
TEST(TimeSplat, OneBinIsExactAndChannelsMatchGreySplats) {
    const TimeBins tb{0.0, 1.0, 4};
    int calls = 0;
    Color got(0.0);
    const OutsideFilm out =
        splatTime(tb, Color(2.0, 3.0, 5.0), Color(1.0, 40.0, -7.0), 0.2, 0.3, 1.1, 1.0, [&](int k, const Color& c) {
            ++calls;
            EXPECT_EQ(k, 1);
            got = c;
        });
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(got.x, 2.0);
    EXPECT_EQ(got.y, 3.0);
    EXPECT_EQ(got.z, 5.0);
    EXPECT_TRUE(isBlack(out.before) && isBlack(out.after));

    const TimeBins fine{0.5, 0.01, 60};
    const Color kappa(2.0, 35.0, -12.0);
    const double s0 = 0.1, s1 = 0.6, a = 0.6, b = -0.7;  // time runs backwards along s and crosses the film start
    std::vector<Color> colour(60, Color(0.0));
    const OutsideFilm oc =
        splatTime(fine, Color(1.0), kappa, s0, s1, a, b, [&](int k, const Color& c) { colour[k] += c; });
    for (int ch = 0; ch < 3; ++ch) {
        std::vector<double> grey(60, 0.0);
        const OutsideFilm og =
            splatTime(fine, Color(1.0), Color(kappa[ch]), s0, s1, a, b, [&](int k, const Color& c) { grey[k] += c.x; });
        EXPECT_EQ(oc.before[ch], og.before.x) << ch;
        EXPECT_EQ(oc.after[ch], og.after.x) << ch;
        double total = oc.before[ch] + oc.after[ch];
        for (int k = 0; k < 60; ++k) {
            EXPECT_EQ(colour[k][ch], grey[k]) << "channel " << ch << " bin " << k;
            total += colour[k][ch];
        }
        EXPECT_NEAR(total, 1.0, 1e-12) << ch;
    }
}

// binOf(t, 1 / binWidth), which multiplies, gives binOf(t)'s bin (which divides) for every t: on
// and within a few ulp of the boundaries of films with awkward widths (0.1, 1/3, 0.3, 1e-3 ...),
// far before and after them, at +-inf and NaN, and at random times.
TEST(TimeSplat, BinByReciprocalIsTheBinByDivision) {
    const TimeBins films[] = {{0.0, 0.1, 10},         {0.5, 0.3, 9}, {1.0, 1.0 / 3.0, 1024}, {-2.7, 1e-3, 4096},
                              {123.456, 0.0123, 256}, {0.0, 7.0, 1}, {1e-9, 3e-5, 100000}};
    Rng rng(99, Stream::Test, 0, 0);
    int64_t checked = 0, nearBoundary = 0;
    for (const TimeBins& tb : films) {
        const double inv = 1.0 / tb.binWidth;
        const auto same = [&](double t) {
            ASSERT_EQ(tb.binOf(t, inv), tb.binOf(t))
                << "t = " << t << " start " << tb.startOpl << " width " << tb.binWidth;
            ++checked;
        };
        for (int j = -3; j <= tb.bins + 3; j += (tb.bins > 5000 ? 97 : 1)) {
            double t = tb.startOpl + j * tb.binWidth;
            for (int u = 0; u < 4; ++u) t = std::nextafter(t, -kInf);
            for (int u = 0; u < 9; ++u, t = std::nextafter(t, kInf)) {
                same(t);
                ++nearBoundary;
            }
        }
        for (const double t : {kInf, -kInf, std::nan(""), 1e300, -1e300, 1e18, -1e18, 0.0, -0.0}) same(t);
        for (int i = 0; i < 20000; ++i) same(tb.startOpl + (rng.uniform() * 1.4 - 0.2) * tb.bins * tb.binWidth);
    }
    EXPECT_GT(nearBoundary, 10000);
    EXPECT_GT(checked, 150000);
}

TEST(TimeSplat, CollapsedIntervalGoesToOneBin) {
    TimeBins tb{0.0, 0.1, 10};
    std::vector<double> bins(10, 0.0);
    // b = 0: beam pointing straight at the camera, all energy at one instant.
    OutsideFilm out =
        splatTime(tb, Color(2.0), Color(1.0), 0.0, 0.5, 0.55, 0.0, [&](int k, const Color& c) { bins[k] += c.x; });
    EXPECT_DOUBLE_EQ(bins[5], 2.0);
    EXPECT_EQ(out.before.x + out.after.x, 0.0);
    // The same instant before the film and after it goes to the matching side.
    out = splatTime(tb, Color(2.0), Color(1.0), 0.0, 0.5, -0.5, 0.0, [&](int, const Color&) { ADD_FAILURE(); });
    EXPECT_EQ(out.before.x, 2.0);
    EXPECT_EQ(out.after.x, 0.0);
    out = splatTime(tb, Color(2.0), Color(1.0), 0.0, 0.5, 1.0, 0.0, [&](int, const Color&) { ADD_FAILURE(); });
    EXPECT_EQ(out.before.x, 0.0);
    EXPECT_EQ(out.after.x, 2.0);
}

TEST(TimeSplat, PartlyOutsideAndNarrowerThanABin) {
    TimeBins tb{1.0, 0.5, 4};  // [1, 3)
    std::vector<double> bins(4, 0.0);
    const auto sink = [&](int k, const Color& c) { bins[k] += c.x; };
    // Uniform over t in [0.5, 1.5]: half before the film.
    OutsideFilm out = splatTime(tb, Color(1.0), Color(0.0), 0.0, 1.0, 0.5, 1.0, sink);
    EXPECT_NEAR(bins[0], 0.5, 1e-15);
    EXPECT_NEAR(out.before.x, 0.5, 1e-15);
    EXPECT_EQ(out.after.x, 0.0);
    // The same with time running backwards along s (b < 0): t in [0.5, 1.5] again.
    std::fill(bins.begin(), bins.end(), 0.0);
    out = splatTime(tb, Color(1.0), Color(0.0), 0.0, 1.0, 1.5, -1.0, sink);
    EXPECT_NEAR(bins[0], 0.5, 1e-15);
    EXPECT_NEAR(out.before.x, 0.5, 1e-15);
    EXPECT_EQ(out.after.x, 0.0);
    // Interval far narrower than a bin.
    std::fill(bins.begin(), bins.end(), 0.0);
    out = splatTime(tb, Color(1.0), Color(5.0), 0.0, 1e-6, 2.2, 1.0, sink);
    EXPECT_NEAR(bins[2], 1.0, 1e-15);
    // Wider than the film on both sides: t in [-2, 8], film [1, 3): 0.3 before, 0.5 after.
    std::fill(bins.begin(), bins.end(), 0.0);
    out = splatTime(tb, Color(1.0), Color(0.0), 0.0, 10.0, -2.0, 1.0, sink);
    for (double v : bins) EXPECT_NEAR(v, 0.05, 1e-14);
    EXPECT_NEAR(out.before.x, 0.3, 1e-14);
    EXPECT_NEAR(out.after.x, 0.5, 1e-14);
    // Per channel: the exponential profile differs by channel, and so do the two sides.
    std::fill(bins.begin(), bins.end(), 0.0);
    out = splatTime(tb, Color(1.0), Color(0.0, 1.0, -1.0), 0.0, 10.0, -2.0, 1.0, [](int, const Color&) {});
    EXPECT_NEAR(out.before.y, -std::expm1(-3.0) / -std::expm1(-10.0), 1e-12);  // s in [0, 3] of exp(-s) on [0, 10]
    EXPECT_NEAR(out.after.y, (std::exp(-5.0) - std::exp(-10.0)) / -std::expm1(-10.0), 1e-12);
    EXPECT_NEAR(out.before.z, (std::exp(3.0) - 1.0) / (std::exp(10.0) - 1.0), 1e-12);
    // Far in time with very fine bins (1e4 m of OPL, bins of 1e-4 m): still exact.
    TimeBins fine{1e4, 1e-4, 100};
    std::vector<double> fb(100, 0.0);
    out = splatTime(fine, Color(1.0), Color(0.0), 0.0, 1e-3, 1e4 + 2e-3, 2.0,
                    [&](int k, const Color& c) { fb[k] += c.x; });
    for (int k = 20; k < 40; ++k) EXPECT_NEAR(fb[k], 0.05, 1e-9) << k;
    EXPECT_NEAR(fb[19] + fb[40], 0.0, 1e-9);
}

TEST(Progressive, RadiusScheduleMatchesRecurrenceAndStaysFinite) {
    for (int dim : {1, 2, 3})
        for (double alpha : {0.3, 0.7, 1.0}) {
            double r = 0.1;
            for (uint64_t i = 1; i < 2000; ++i) {
                // lgamma of arguments ~1e3 carries ~1e-13 absolute error in the log: 1e-11 relative.
                EXPECT_NEAR(progressiveRadius(0.1, alpha, i, dim), r, 1e-11 * r) << dim << " " << alpha << " " << i;
                r *= std::pow((i + alpha) / (i + 1.0), 1.0 / dim);
            }
        }
    // alpha = 1: no shrinking.
    EXPECT_NEAR(progressiveRadius(0.1, 1.0, 1000000, 2), 0.1, 1e-12);
    // After 1e6 passes r^2 ~ r1^2 i^(alpha - 1) / Gamma(1 + alpha): finite, positive, no underflow.
    const double r6 = progressiveRadius(0.1, 0.7, 1000000, 2);
    EXPECT_GT(r6, 0.0);
    EXPECT_NEAR(r6 * r6, 0.01 * std::pow(1e6, -0.3) / std::tgamma(1.7), 1e-3 * r6 * r6);
    EXPECT_TRUE(std::isfinite(1.0 / (kPi * r6 * r6)));
    EXPECT_GT(progressiveRadius(1e-3, 0.01, 1000000000ull, 3), 0.0);
}

TEST(PhaseFunction, HenyeyGreensteinNormalisedAndSamplingConsistent) {
    for (double g : {-0.999, -0.5, 0.0, 0.3, 0.999}) {
        HenyeyGreenstein hg{g};
        // int p dw = 2 pi int_{-1}^{1} p(mu) dmu. For |g| -> 1 the peak is ~(1-|g|)^2 wide in mu, so
        // integrate in y = log(distance to the peak): mu = peak - sign * e^y.
        const double peak = g >= 0.0 ? 1.0 : -1.0;
        auto integral = [&](double lo, double hi) {  // int_lo^hi p(mu) dmu, lo < hi
            const double dLo = std::abs(peak - lo), dHi = std::abs(peak - hi);
            const double yA = std::log(std::max(std::min(dLo, dHi), 1e-30)), yB = std::log(std::max(dLo, dHi));
            const auto f = [&](double y) {
                const double e = std::exp(y);
                return hg.eval(peak - (peak > 0 ? e : -e)) * e;
            };
            return quad(f, yA, yB, 4000);
        };
        const double norm = 2.0 * kPi * integral(-1.0, 1.0);
        EXPECT_NEAR(norm, 1.0, 1e-6) << g;
        // Sampling: mean cosine equals g, and a histogram in mu matches the pdf.
        Rng rng(5, Stream::Test, 0, static_cast<uint64_t>((g + 2) * 1000));
        const Vec3 wi(0, 0, 1);
        const int n = 200000, nb = 20;
        std::vector<double> hist(nb, 0.0);
        double mean = 0.0;
        for (int i = 0; i < n; ++i) {
            const Vec3 wo = hg.sample(wi, rng.uniform(), rng.uniform());
            EXPECT_NEAR(glm::length(wo), 1.0, 1e-12);
            const double mu = glm::dot(wi, wo);
            mean += mu;
            hist[std::min(nb - 1, static_cast<int>((mu + 1.0) * 0.5 * nb))] += 1.0;
        }
        EXPECT_NEAR(mean / n, g, 5e-3) << g;
        for (int b = 0; b < nb; ++b) {
            const double lo = -1.0 + 2.0 * b / nb, hi = lo + 2.0 / nb;
            const double p = 2.0 * kPi * integral(lo, hi);
            const double sigma = std::sqrt(n * p * (1 - p)) + 1.0;
            EXPECT_NEAR(hist[b], n * p, 5.0 * sigma) << "g " << g << " bin " << b;
        }
    }
}

TEST(Fresnel, LimitsAndTotalInternalReflection) {
    for (double n : {1.0, 1.5, 2.4, 3.5}) {
        const double f0 = (n - 1) / (n + 1);
        EXPECT_NEAR(fresnelDielectric(1.0, 1.0, n), f0 * f0, 1e-14);
        EXPECT_NEAR(fresnelDielectric(1.0, n, 1.0), f0 * f0, 1e-14);
        EXPECT_NEAR(fresnelDielectric(1e-9, 1.0, n), 1.0, 1e-6);  // grazing
    }
    EXPECT_EQ(fresnelDielectric(0.5, 1.0, 1.0), 0.0);  // index-matched
    // TIR beyond the critical angle from glass to air.
    const double critCos = std::sqrt(1.0 - 1.0 / (1.5 * 1.5));
    EXPECT_EQ(fresnelDielectric(critCos * 0.99, 1.5, 1.0), 1.0);
    Vec3 out;
    EXPECT_FALSE(refract(glm::normalize(Vec3(1.0, 0.0, -critCos * 0.99)), Vec3(0, 0, 1), 1.5, out));
    // Snell's law.
    const Vec3 d = glm::normalize(Vec3(0.6, 0.0, -0.8));
    ASSERT_TRUE(refract(d, Vec3(0, 0, 1), 1.0 / 1.5, out));
    EXPECT_NEAR(out.x, 0.6 / 1.5, 1e-14);
    EXPECT_NEAR(glm::length(out), 1.0, 1e-14);
}
