// Pulse shapes and sensor responses (film/time_response.h): the kernel's G against closed forms;
// the bin weights against an independent Monte Carlo histogram of (arrival in the bin + pulse
// delay + sensor delay); a blurred single-scattering film against quadrature renders of the
// emission times the pulse spreads over (transport is time-invariant: a pulse is a weighted sum of
// delta pulses emitted at other instants); the film readers (frame, profile, streak, volume,
// continuous emission) through the kernel.
#include "film/film_export.h"
#include "film/film_view.h"
#include "film/time_response.h"
#include "film/transient_film.h"
#include "eval/reference.h"
#include "base/rng.h"
#include "support/quadrature.h"
#include "support/temp_dir.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

namespace tpb {
namespace {

TimeResponse pulse(const char* s) { return *parsePulse(s); }
TimeResponse sensor(const char* s) { return *parseSensor(s); }
TimeResponse both(const char* p, const char* s) { return *parseSensor(s, *parsePulse(p)); }
TimeResponse make(PulseShape p, double pw, SensorShape s = SensorShape::Ideal, double sw = 0.0) {
    TimeResponse r;
    r.pulse = p;
    r.pulseWidth = pw;
    r.sensor = s;
    r.sensorWidth = sw;
    return r;
}

TEST(TimeResponse, ParsesAndNamesShapesInNanoseconds) {
    EXPECT_TRUE(pulse("delta").identity());
    EXPECT_TRUE(sensor("ideal").identity());
    const TimeResponse g = pulse("gaussian:0.5");
    EXPECT_EQ(g.pulse, PulseShape::Gaussian);
    EXPECT_DOUBLE_EQ(g.pulseWidth, 0.5 * kC_m_per_ns);
    EXPECT_EQ(pulseName(g), "gaussian:0.5");
    EXPECT_EQ(sensorName(sensor("exp:0.02")), "exp:0.02");
    EXPECT_EQ(describe(both("square:1", "gaussian:0.1")), "square pulse, 1 ns; gaussian sensor jitter, FWHM 0.1 ns");
    for (const char* bad : {"gaussian", "gaussian:0", "gaussian:-1", "gaussian:x", "square:inf", "box:1", ""})
        EXPECT_FALSE(parsePulse(bad)) << bad;
    for (const char* bad : {"exp", "exp:0", "delta", "gaussian:nan"}) EXPECT_FALSE(parseSensor(bad)) << bad;
}

// G (the second antiderivative of h) against closed forms: the pulse is integrated numerically,
// the sensor is not, so a Gaussian pulse must equal a Gaussian sensor of the same FWHM; a square
// pulse with an ideal sensor is t^2 / (2w) on [0, w] and t - w/2 after.
TEST(TimeResponse, NumericalPulseMatchesClosedForms) {
    const double w = 0.3;
    TimeResponse gp, gs, sq;
    gp.pulse = PulseShape::Gaussian;
    gp.pulseWidth = w;
    gs.sensor = SensorShape::Gaussian;
    gs.sensorWidth = w;
    sq.pulse = PulseShape::Square;
    sq.pulseWidth = w;
    for (double t = -0.5; t <= 0.8; t += 0.01) {
        EXPECT_NEAR(responseG(gp, t), responseG(gs, t), 1e-12 + 1e-10 * std::abs(t)) << t;
        const double want = t < 0 ? 0.0 : t <= w ? t * t / (2 * w) : t - w / 2;
        EXPECT_NEAR(responseG(sq, t), want, 1e-12 + 1e-10 * std::abs(t)) << t;
    }
    // Exponential sensor: G(t) = t - tau (1 - e^{-t/tau}); with a square pulse, quadrature of it.
    TimeResponse ex;
    ex.sensor = SensorShape::Exponential;
    ex.sensorWidth = 0.1;
    TimeResponse sqex = ex;
    sqex.pulse = PulseShape::Square;
    sqex.pulseWidth = w;
    for (double t = -0.2; t <= 1.0; t += 0.013) {
        EXPECT_NEAR(responseG(ex, t), t <= 0 ? 0.0 : t - 0.1 * (1 - std::exp(-t / 0.1)), 1e-14) << t;
        const double q = test::gaussLegendre5([&](double u) { return responseG(ex, t - u) / w; }, 0.0, w, 4000);
        EXPECT_NEAR(responseG(sqex, t), q, 1e-9) << t;
    }
}

// W_m is the probability that light arriving uniformly within a bin, delayed by the pulse and the
// sensor, is counted m bins later: a histogram of 4 million such samples, within 4.5 standard
// errors per bin, for every shape and a combination, at widths below and above a bin.
TEST(TimeResponse, BinWeightsAreTheHistogramOfTheDelays) {
    const double D = 0.05;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::normal_distribution<double> N(0.0, 1.0);
    const double toSigma = 1.0 / 2.3548200450309493;
    for (const TimeResponse& r :
         {pulse("gaussian:0.05"), pulse("gaussian:1"), pulse("square:0.1"), pulse("square:0.9"), sensor("gaussian:0.4"),
          sensor("exp:0.03"), sensor("exp:0.6"), both("gaussian:0.5", "exp:0.2"), both("square:0.4", "gaussian:0.2")}) {
        SCOPED_TRACE(describe(r));
        const BinKernel k = binKernel(r, D);
        double sum = 0.0;
        for (double w : k.w) sum += w;
        EXPECT_NEAR(sum, 1.0, 1e-9);
        const int n = 4000000;
        std::vector<double> hist(k.w.size(), 0.0);
        int outside = 0;
        for (int i = 0; i < n; ++i) {
            double t = U(rng) * D;
            if (r.pulse == PulseShape::Gaussian) t += N(rng) * r.pulseWidth * toSigma;
            if (r.pulse == PulseShape::Square) t += U(rng) * r.pulseWidth;
            if (r.sensor == SensorShape::Gaussian) t += N(rng) * r.sensorWidth * toSigma;
            if (r.sensor == SensorShape::Exponential) t += -std::log(1.0 - U(rng)) * r.sensorWidth;
            const int m = static_cast<int>(std::floor(t / D)) - k.lo;
            if (m < 0 || m >= static_cast<int>(hist.size()))
                ++outside;
            else
                hist[static_cast<size_t>(m)] += 1.0;
        }
        EXPECT_LE(outside, 2) << "the kernel's support misses delays";
        for (size_t m = 0; m < hist.size(); ++m) {
            const double p = k.w[m], se = std::sqrt(std::max(p * (1 - p), 1.0 / n) / n);
            EXPECT_NEAR(hist[m] / n, p, 4.5 * se) << "m = " << static_cast<int>(m) + k.lo;
        }
    }
    EXPECT_TRUE(binKernel(TimeResponse{}, D).identity());
}

// A point light in fog seen through single scattering (eval/reference.h's quadrature). Emitting
// with pulse p is the sum over emission instants t0 of p(t0) times the delta response emitted at
// t0: quadrature renders at the Gauss-Legendre nodes of t0 make the reference. The blurred
// delta film must match it within 0.6 % of the profile's peak per bin (the within-bin uniformity
// is the only approximation, O(D^2 x'')), where the unblurred film is off by 15 % or more.
const char* kFog = R"({
  "version": 1,
  "camera": {"position": [0, 0, 3], "look_at": [0.6, 0, 0], "fov": 10, "resolution": [4, 4]},
  "film": {"start_m": 3.5, "bin_width_m": 0.05, "bins": 120},
  "media": {"m": {"sigma_s": 0.4, "sigma_a": 0.1}},
  "global_medium": "m",
  "lights": [{"type": "point", "position": [0, 0, 0], "power": 10, "emit_time_m": 1.5}],
  "render": {"photons_per_pass": 1000, "radius": 0.06, "passes": 1, "max_depth": 1, "seed": 3}
})";

std::vector<double> fogVolume(double emitOpl) {
    SceneDesc d = loadSceneFromString(kFog, "fog.json");
    d.lights[0].emitOpl = emitOpl;
    const test::TestScene s = test::prepareTestScene(d);
    const ReferenceVolume ref = singleScatteringReference(*s, s.time, "fog.json", s.settings, 2, 2);
    return std::vector<double>(ref.real.begin(), ref.real.end());
}

TEST(TimeResponse, BlurredSingleScatteringFilmMatchesRendersOfTheSpreadEmission) {
    const double t0 = 1.5, D = 0.05;
    const int bins = 120, pixels = 16;
    const std::vector<double> delta = fogVolume(t0);
    struct Case {
        TimeResponse r;
        double a, b;                            // emission offsets the reference integrates over
        std::function<double(double)> density;  // of the offset
    };
    const double sg = 0.3 / 2.3548200450309493, tau = 0.12;
    const std::vector<Case> cases = {
        {make(PulseShape::Gaussian, 0.3), -6 * sg, 6 * sg,
         [&](double u) { return std::exp(-0.5 * u * u / (sg * sg)) / (sg * 2.5066282746310002); }},
        {make(PulseShape::Square, 0.3), 0.0, 0.3, [](double) { return 1.0 / 0.3; }},
        {make(PulseShape::Delta, 0.0, SensorShape::Exponential, tau), 0.0, 12 * tau,
         [&](double u) { return std::exp(-u / tau) / tau; }},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(describe(c.r));
        // Reference: 5-point Gauss-Legendre over the offsets on panels of a quarter bin (a bin's
        // integral changes on the scale of a bin as the emission moves: coarser nodes miss that).
        std::vector<double> ref(delta.size(), 0.0);
        static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                                    0.9061798459386640};
        static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                    0.2369268850561891};
        const int panels = static_cast<int>(std::ceil((c.b - c.a) / (0.25 * D)));
        const double h = (c.b - c.a) / panels;
        for (int i = 0; i < panels; ++i)
            for (int j = 0; j < 5; ++j) {
                const double u = c.a + (i + 0.5) * h + 0.5 * h * x[j];
                const std::vector<double> v = fogVolume(t0 + u);
                const double weight = 0.5 * h * w[j] * c.density(u);
                for (size_t q = 0; q < v.size(); ++q) ref[q] += weight * v[q];
            }
        const BinKernel k = binKernel(c.r, D);
        double worst = 0.0, worstRaw = 0.0;
        for (int p = 0; p < pixels; ++p) {
            const double* series = &delta[static_cast<size_t>(p) * bins * 3];
            std::vector<double> out(static_cast<size_t>(bins) * 3);
            const double zero[3] = {0, 0, 0};
            applyKernel(k, series, bins, zero, zero, out.data());
            double peak = 0.0;
            for (int q = 0; q < bins * 3; ++q) peak = std::max(peak, ref[static_cast<size_t>(p) * bins * 3 + q]);
            ASSERT_GT(peak, 0.0);
            for (int q = 0; q < bins * 3; ++q) {
                const double want = ref[static_cast<size_t>(p) * bins * 3 + q];
                worst = std::max(worst, std::abs(out[q] - want) / peak);
                worstRaw = std::max(worstRaw, std::abs(series[q] - want) / peak);
            }
        }
        std::printf("%s: worst bin error %.4f of the peak (unblurred %.3f)\n", describe(c.r).c_str(), worst, worstRaw);
        EXPECT_LT(worst, 0.006);
        EXPECT_GT(worstRaw, 10 * worst) << "the case does not tell a blurred film from a sharp one";
    }
}

// The film readers through a kernel: frame k, the profile, the streak and the volume are the same
// numbers, each the kernel applied to the pixel's series; continuous emission is the running sum
// of the blurred delta response (plus what came before the film).
TEST(TimeResponse, FilmReadersApplyTheKernelAlongEachPixelsSeries) {
    const TimeBins time{1.0, 0.1, 24};
    TransientFilm film(20, 18, time);
    Rng rng(5, Stream::Test, 0, 0);
    for (int tile = 0; tile < film.tileCount(); ++tile) {
        TransientFilm::TileWriter w(film, tile);
        const TileRect r = film.tileRect(tile);
        PixelAccumulator acc(time.bins);
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                acc.reset(time.bins);
                for (int k = 0; k < time.bins; ++k)
                    if (rng.uniform() < 0.3)
                        acc.add(TimeAxis::Real, k, Color(rng.uniform(), rng.uniform(), 2 * rng.uniform()));
                OutsideFilm o;
                o.before = Color(0.5);
                acc.addOutside(TimeAxis::Real, o);
                w.addPixel(x, y, acc);
            }
    }
    const auto snap = film.snapshot();
    const TimeResponse resp = both("gaussian:0.6", "exp:0.3");
    const BinKernel k = binKernel(resp, time.binWidth);
    ASSERT_GT(k.w.size(), 4u);
    const std::vector<double> vol = volume(*snap, TimeAxis::Real, EmissionMode::Delta, resp);
    const std::vector<double> volC = volume(*snap, TimeAxis::Real, EmissionMode::Continuous, resp);
    const std::vector<double> raw = volume(*snap, TimeAxis::Real, EmissionMode::Delta);
    const int W = 20, H = 18, B = time.bins;
    for (int y = 0; y < H; y += 5)
        for (int x = 0; x < W; x += 3) {
            const size_t base = (static_cast<size_t>(y) * W + x) * B * 3;
            std::vector<double> want(static_cast<size_t>(B) * 3);
            const double zero[3] = {0, 0, 0};
            applyKernel(k, &raw[base], B, zero, zero, want.data());
            double run[3] = {0.5, 0.5, 0.5};  // before the film
            const std::vector<float> prof = pixelProfile(*snap, x, y, TimeAxis::Real, EmissionMode::Delta, resp);
            const std::vector<float> streak = streakImage(*snap, y, TimeAxis::Real, EmissionMode::Delta, resp);
            for (int b = 0; b < B; ++b)
                for (int c = 0; c < 3; ++c) {
                    const double v = want[static_cast<size_t>(b) * 3 + c];
                    EXPECT_NEAR(vol[base + b * 3 + c], v, 1e-12);
                    EXPECT_FLOAT_EQ(prof[static_cast<size_t>(b) * 3 + c], static_cast<float>(v));
                    EXPECT_FLOAT_EQ(streak[(static_cast<size_t>(b) * W + x) * 3 + c], static_cast<float>(v));
                }
            for (int b = 0; b < B; ++b)
                for (int c = 0; c < 3; ++c) {
                    // The running sum of the blurred response: the kernel sums to 1, so the light
                    // before the film contributes 0.5 once its blur is complete; close enough after
                    // the first few bins, exact in the differences.
                    run[c] += want[static_cast<size_t>(b) * 3 + c];
                    if (b >= 8) {
                        const double d = volC[base + b * 3 + c] - volC[base + (b - 1) * 3 + c];
                        EXPECT_NEAR(d, want[static_cast<size_t>(b) * 3 + c], 1e-9) << x << " " << y << " " << b;
                    }
                }
        }
    for (int bin : {0, 5, 13, 23}) {
        const std::vector<float> f = frameImage(*snap, bin, TimeAxis::Real, EmissionMode::Delta, resp);
        const std::vector<float> fc = frameImage(*snap, bin, TimeAxis::Real, EmissionMode::Continuous, resp);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c) {
                    const size_t v = (static_cast<size_t>(y) * W + x) * B * 3 + static_cast<size_t>(bin) * 3 + c;
                    EXPECT_FLOAT_EQ(f[(static_cast<size_t>(y) * W + x) * 3 + c], static_cast<float>(vol[v]));
                    EXPECT_NEAR(fc[(static_cast<size_t>(y) * W + x) * 3 + c], volC[v], 1e-5 * (1 + std::abs(volC[v])));
                }
    }
    // The identity reads the sums as before, bit for bit.
    EXPECT_EQ(frameImage(*snap, 7, TimeAxis::Real, EmissionMode::Delta, TimeResponse{}),
              frameImage(*snap, 7, TimeAxis::Real, EmissionMode::Delta));
}

// A kernel cut to the film (|m| < bins, the rest summed into before/after) reads a series as the
// whole kernel does, for responses far longer than the film on both sides, in delta (extensions 0)
// and continuous emission (extensions: what came before, the last value); a response shorter than
// the film gives the same kernel, weight for weight.
TEST(TimeResponse, KernelCutToTheFilmReadsItAsTheWholeKernelDoes) {
    const double D = 0.1;
    const int B = 24;
    Rng rng(11, Stream::Test, 0, 0);
    std::vector<double> x(static_cast<size_t>(B) * 3);
    for (double& v : x) v = rng.uniform();
    const double left[3] = {0.7, 0.2, 1.3}, right[3] = {2.0, 0.4, 0.9}, zero[3] = {0.0, 0.0, 0.0};
    for (const TimeResponse& r :
         {both("gaussian:3", "exp:2"), both("square:20", "gaussian:1"), sensor("exp:40"), pulse("gaussian:30")}) {
        SCOPED_TRACE(describe(r));
        const BinKernel whole = binKernel(r, D), cut = binKernel(r, D, B);
        ASSERT_GT(whole.w.size(), static_cast<size_t>(2 * B)) << "the response must be longer than the film";
        EXPECT_GE(cut.lo, 1 - B);
        EXPECT_LE(cut.lo + static_cast<int>(cut.w.size()), B);
        EXPECT_GT(cut.before + cut.after, 0.0);
        // The cut kernel's tails are telescoped sums (exact to rounding); the whole kernel's are sums
        // of thousands of second differences, each off by G's rounding: it misses 1 by up to 5e-10
        // (exp:40), and the two readings agree within that.
        const double wholeSum = std::accumulate(whole.w.begin(), whole.w.end(), 0.0);
        EXPECT_NEAR(std::accumulate(cut.w.begin(), cut.w.end(), 0.0) + cut.before + cut.after, 1.0, 1e-14);
        const double tol = 1e-12 + 2.0 * std::abs(wholeSum - 1.0);
        for (const double* ext : {zero, left}) {
            const double* rightExt = ext == zero ? zero : right;
            std::vector<double> a(x.size()), b(x.size());
            applyKernel(whole, x.data(), B, ext, rightExt, a.data());
            applyKernel(cut, x.data(), B, ext, rightExt, b.data());
            for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(b[i], a[i], tol * (1.0 + std::abs(a[i]))) << i;
        }
    }
    const BinKernel narrow = binKernel(both("gaussian:0.6", "exp:0.1"), D),
                    narrowCut = binKernel(both("gaussian:0.6", "exp:0.1"), D, B);
    EXPECT_EQ(narrowCut.lo, narrow.lo);
    EXPECT_EQ(narrowCut.w, narrow.w);
    EXPECT_EQ(narrowCut.before, 0.0);
    EXPECT_EQ(narrowCut.after, 0.0);
}

// Issue 33 item 6: the kernel was computed for every frame (a wide response took seconds per frame:
// 64 frames of 64x64 in minutes; the viewer froze on every step). It is computed once per
// (response, bin width, film bins): an export of all frames, the strip, a profile, a streak, the
// volume and continuous frames compute it once; another response once more; the first again not
// at all. The shared kernel is the computed one, weight for weight, and a frame read through it
// twice is the same image.
TEST(TimeResponse, KernelIsComputedOncePerResponseAndBinWidth) {
    const TimeBins time{1.0, 0.1, 24};
    TransientFilm film(12, 10, time);
    Rng rng(7, Stream::Test, 0, 0);
    for (int tile = 0; tile < film.tileCount(); ++tile) {
        TransientFilm::TileWriter w(film, tile);
        const TileRect r = film.tileRect(tile);
        PixelAccumulator acc(time.bins);
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                acc.reset(time.bins);
                for (int k = 0; k < time.bins; ++k) acc.add(TimeAxis::Real, k, Color(rng.uniform()));
                w.addPixel(x, y, acc);
            }
    }
    const auto snap = film.snapshot();
    test::TempDir tmp("time_response_cache");
    ExportOptions opt;
    opt.response = both("gaussian:0.613", "exp:0.417");  // widths no other test uses (the cache is per process)
    const uint64_t n0 = binKernelComputations();
    const std::vector<float> first = frameImage(*snap, 9, TimeAxis::Real, EmissionMode::Delta, opt.response);
    EXPECT_EQ(exportFrames(*snap, tmp.path().string() + "/frames", opt), time.bins);
    exportStripPng(*snap, tmp.path().string() + "/strip.png", 8, opt, ToneMap{});
    pixelProfile(*snap, 3, 4, TimeAxis::Real, EmissionMode::Delta, opt.response);
    streakImage(*snap, 5, TimeAxis::Real, EmissionMode::Continuous, opt.response);
    volume(*snap, TimeAxis::Real, EmissionMode::Delta, opt.response);
    for (int k = 0; k < time.bins; ++k) frameImage(*snap, k, TimeAxis::Real, EmissionMode::Continuous, opt.response);
    EXPECT_EQ(binKernelComputations() - n0, 1u) << "the kernel must be computed once for every read of one response";
    const TimeResponse other = both("gaussian:0.613", "exp:0.2");
    frameImage(*snap, 3, TimeAxis::Real, EmissionMode::Delta, other);
    frameImage(*snap, 4, TimeAxis::Real, EmissionMode::Delta, other);
    EXPECT_EQ(binKernelComputations() - n0, 2u);
    EXPECT_EQ(frameImage(*snap, 9, TimeAxis::Real, EmissionMode::Delta, opt.response), first);
    EXPECT_EQ(binKernelComputations() - n0, 2u);
    const std::shared_ptr<const BinKernel> shared = sharedBinKernel(opt.response, time.binWidth, time.bins);
    const BinKernel computed = binKernel(opt.response, time.binWidth, time.bins);
    EXPECT_EQ(shared->lo, computed.lo);
    EXPECT_EQ(shared->w, computed.w);
    EXPECT_EQ(shared->before, computed.before);
    EXPECT_EQ(shared->after, computed.after);
}

}  // namespace
}  // namespace tpb
