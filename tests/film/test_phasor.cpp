// The exact phasor film (film/phasor.h): each closed form against quadrature of its definition,
// at the limits the derivation (docs/theory/phasor.md) must survive, and the film's bookkeeping.
#include "film/phasor.h"

#include "base/error.h"
#include "film/film_view.h"
#include "film/transient_film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using namespace tpb;

namespace {

// Int_lo^hi g(t) dt by composite Gauss-Legendre (5 points on each of n panels).
Complex quad(const std::function<Complex(double)>& g, double lo, double hi, int n = 4000) {
    static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                0.2369268850561891};
    Complex s(0.0, 0.0);
    const double h = (hi - lo) / n;
    for (int i = 0; i < n; ++i) {
        const double m = lo + (i + 0.5) * h;
        for (int j = 0; j < 5; ++j) s += w[j] * 0.5 * h * g(m + 0.5 * h * x[j]);
    }
    return s;
}

// The definition: the unit-mass density exp(-kappa s) on [s0, s1] (kappa signed), arriving at
// a + b s, weighted by exp(-i 2 pi f (t - tRef)), integrated along s.
Complex phasorByQuadrature(double kappa, double s0, double s1, double a, double b, double f, double tRef) {
    // Normalised on its decaying end so that exp never overflows.
    const double ref = kappa >= 0.0 ? s0 : s1;
    const auto density = [&](double s) { return std::exp(-kappa * (s - ref)); };
    const double mass = quad([&](double s) { return Complex(density(s), 0.0); }, s0, s1).real();
    const Complex p = quad(
        [&](double s) {
            const double t = a + b * s;
            return density(s) * std::exp(Complex(0.0, -2.0 * kPi * f * (t - tRef)));
        },
        s0, s1);
    return p / mass;
}

}  // namespace

TEST(PhasorPhi, MatchesItsSeriesNearZeroAndTheDirectFormAwayFromIt) {
    // phi(w) = (1 - e^{-w}) / w = 1 - w/2 + w^2/6 - w^3/24 + ...
    for (double x : {0.0, 1e-12, 1e-7, 1e-4}) {
        for (double y : {0.0, 1e-12, 1e-7, 1e-4}) {
            if (x == 0.0 && y == 0.0) continue;
            const Complex w(x, y);
            const Complex series = 1.0 - w / 2.0 + w * w / 6.0 - w * w * w / 24.0;
            const Complex got = phasorPhi(x, y);
            EXPECT_NEAR(got.real(), series.real(), 1e-15) << x << " " << y;
            EXPECT_NEAR(got.imag(), series.imag(), 1e-15) << x << " " << y;
        }
    }
    for (double x : {0.3, 2.0, 40.0, 800.0})
        for (double y : {-50.0, -1.0, 0.5, 7.0, 3000.0}) {
            const Complex w(x, y);
            const Complex direct = (1.0 - std::exp(-w)) / w;
            const Complex got = phasorPhi(x, y);
            EXPECT_NEAR(std::abs(got - direct), 0.0, 1e-14 * std::abs(direct) + 1e-300) << x << " " << y;
        }
    EXPECT_EQ(phasorPhi(0.0, 0.0), Complex(1.0, 0.0));
}

TEST(PhasorProfile, ExponentialSegmentsMatchQuadratureAcrossTheirLimits) {
    struct Case {
        double kappa, s0, s1, a, b;
    };
    const Case cases[] = {
        {0.0, 0.0, 1.0, 2.0, 1.0},         // uniform, time grows along s
        {1.5, 0.2, 1.7, 3.0, 1.33},        // moderate decay
        {-1.5, 0.2, 1.7, 3.0, 1.33},       // growing along s (reflected)
        {2.0, 0.0, 2.0, 4.0, -0.5},        // time falls along s (a ray towards the camera)
        {-2.0, 0.0, 2.0, 4.0, -0.5},       // both
        {60.0, 0.0, 3.0, 1.0, 1.0},        // stiff: the mass sits at the start
        {1e-9, 0.0, 5.0, 1.0, 2.0},        // kappa at the uniform threshold's edge
        {3.0, 1.0, 1.0 + 1e-7, 2.5, 1.0},  // a very short interval (an instant)
        {0.7, 0.0, 40.0, 0.0, 1.0},        // a long interval (many periods)
        {0.9, 0.0, 1.0, 2.0, 0.0},         // no spread in time (b = 0)
    };
    for (const Case& c : cases)
        for (double f : {0.0, 1e-6, 0.3, 2.0, 17.0}) {
            const ExpProfile e(c.kappa, c.s0, c.s1);
            const double tRef = 0.75;
            const Complex got = profilePhasor(e, c.a, c.b, f, tRef);
            const Complex want = phasorByQuadrature(c.kappa, c.s0, c.s1, c.a, c.b, f, tRef);
            EXPECT_NEAR(std::abs(got - want), 0.0, 1e-10)
                << "kappa " << c.kappa << " [" << c.s0 << ", " << c.s1 << "] a " << c.a << " b " << c.b << " f " << f
                << ": got " << got << " want " << want;
            if (f == 0.0) {
                EXPECT_EQ(got, Complex(1.0, 0.0));  // the steady image, exactly
            }
            EXPECT_LE(std::abs(got), 1.0 + 1e-15);  // |P| <= the energy
        }
}

TEST(PhasorProfile, AnInstantIsAPurePhase) {
    const ExpProfile e(0.0, 0.0, 0.0);
    for (double t : {0.0, 0.37, 12.5, 1e4 + 0.25})
        for (double f : {0.5, 3.0, 100.0}) {
            const Complex got = profilePhasor(e, t, 0.0, f, 0.0);
            const double th = -2.0 * kPi * std::fmod(f * t, 1.0);
            EXPECT_NEAR(got.real(), std::cos(th), 1e-9) << t << " " << f;
            EXPECT_NEAR(got.imag(), std::sin(th), 1e-9) << t << " " << f;
        }
}

TEST(PhasorEstimate, TheFloorsMirroredPartMatchesQuadratureOfTheMirroredDensity) {
    // A grey segment on [0, 2] with time a + b s and a floor inside its time range: the part
    // earlier than the floor arrives at 2 floor - t instead (time_splat.h splatTimeFloored).
    for (double b : {1.2, -0.8})
        for (double kappa : {0.0, 0.9, -1.3}) {
            const double a = 3.0, s0 = 0.0, s1 = 2.0;
            const double tA = std::min(a + b * s0, a + b * s1), tB = std::max(a + b * s0, a + b * s1);
            const double floor = tA + 0.37 * (tB - tA);
            PhasorSpec spec;
            spec.frequencies = {0.0, 0.4, 2.5};
            spec.refOpl = 1.0;
            std::vector<double> out(spec.frequencies.size() * 6, 0.0);
            const SegmentProfile p(Color(kappa), s0, s1);
            addEstimatePhasor(spec, Color(2.0), p, a, b, floor, out.data());
            const double ref = kappa >= 0.0 ? s0 : s1;
            const auto density = [&](double s) { return std::exp(-kappa * (s - ref)); };
            const double mass = quad([&](double s) { return Complex(density(s), 0.0); }, s0, s1).real();
            for (size_t i = 0; i < spec.frequencies.size(); ++i) {
                const double f = spec.frequencies[i];
                const Complex want = 2.0 / mass *
                                     quad(
                                         [&](double s) {
                                             double t = a + b * s;
                                             if (t < floor) t = 2.0 * floor - t;
                                             return density(s) * std::exp(Complex(0.0, -2.0 * kPi * f * (t - 1.0)));
                                         },
                                         s0, s1, 20000);
                const Complex got(out[i * 6], out[i * 6 + 3]);
                EXPECT_NEAR(std::abs(got - want), 0.0, 1e-8) << "b " << b << " kappa " << kappa << " f " << f;
                EXPECT_EQ(out[i * 6], out[i * 6 + 1]);  // grey: the channels agree
            }
        }
}

TEST(PhasorEstimate, ColourProfilesAreEachChannelsGreyProfile) {
    PhasorSpec spec;
    spec.frequencies = {0.7, 3.1};
    const Color kappa(0.5, -2.0, 4.0);
    std::vector<double> rgb(12, 0.0);
    addEstimatePhasor(spec, Color(1.0, 2.0, 3.0), SegmentProfile(kappa, 0.1, 1.4), 2.0, 0.9, -kInf, rgb.data());
    const double ks[3] = {kappa.x, kappa.y, kappa.z};
    for (int c = 0; c < 3; ++c) {
        std::vector<double> grey(12, 0.0);
        addEstimatePhasor(spec, Color(c + 1.0), SegmentProfile(Color(ks[c]), 0.1, 1.4), 2.0, 0.9, -kInf, grey.data());
        for (int i = 0; i < 2; ++i) {
            EXPECT_DOUBLE_EQ(rgb[i * 6 + c], grey[i * 6 + c]);
            EXPECT_DOUBLE_EQ(rgb[i * 6 + 3 + c], grey[i * 6 + 3 + c]);
        }
    }
}

TEST(PhasorResponse, TransformsMatchQuadratureOfTheResponses) {
    const double fwhmToSigma = 1.0 / (2.0 * std::sqrt(2.0 * std::log(2.0)));
    for (double f : {0.0, 0.8, 5.0}) {
        TimeResponse g;
        g.pulse = PulseShape::Gaussian;
        g.pulseWidth = 0.3;
        const double sg = 0.3 * fwhmToSigma;
        const Complex wantG = quad(
            [&](double t) {
                return std::exp(-0.5 * t * t / (sg * sg)) / (sg * std::sqrt(2.0 * kPi)) *
                       std::exp(Complex(0.0, -2.0 * kPi * f * t));
            },
            -12.0 * sg, 12.0 * sg);
        EXPECT_NEAR(std::abs(responseTransform(g, f) - wantG), 0.0, 1e-12) << f;

        TimeResponse sq;
        sq.pulse = PulseShape::Square;
        sq.pulseWidth = 0.45;
        const Complex wantS =
            quad([&](double t) { return std::exp(Complex(0.0, -2.0 * kPi * f * t)) / 0.45; }, 0.0, 0.45);
        EXPECT_NEAR(std::abs(responseTransform(sq, f) - wantS), 0.0, 1e-12) << f;

        TimeResponse ex;
        ex.sensor = SensorShape::Exponential;
        ex.sensorWidth = 0.2;
        const Complex wantE =
            quad([&](double t) { return std::exp(-t / 0.2) / 0.2 * std::exp(Complex(0.0, -2.0 * kPi * f * t)); }, 0.0,
                 0.2 * 60.0, 20000);
        EXPECT_NEAR(std::abs(responseTransform(ex, f) - wantE), 0.0, 1e-10) << f;

        TimeResponse both = g;  // a convolution is a product of transforms
        both.sensor = SensorShape::Exponential;
        both.sensorWidth = 0.2;
        EXPECT_NEAR(std::abs(responseTransform(both, f) - wantG * wantE), 0.0, 1e-10) << f;
    }
}

TEST(PhasorFilm, SumsMergeAndReadBackAsTheAverageOfTheEstimates) {
    const TimeBins tb{1.0, 0.05, 40};
    PhasorSpec spec;
    spec.frequencies = {0.0, 1.5, 9.0};
    spec.refOpl = tb.startOpl;
    TransientFilm a(20, 18, tb, spec), b(20, 18, tb, spec);
    PixelAccumulator acc(tb.bins, &spec);
    FilmTally tally;
    // Pixel (17, 3) in tile (1, 0): one instant and one segment per pass; two passes in `a`, one in `b`.
    const auto pass = [&](TransientFilm& film, double scale) {
        for (int t = 0; t < film.tileCount(); ++t) {
            TransientFilm::TileWriter w(film, t);
            const TileRect r = film.tileRect(t);
            if (17 >= r.x0 && 17 < r.x0 + r.w && 3 >= r.y0 && 3 < r.y0 + r.h) {
                splatInstant(tb, acc, tally, Color(scale), 1.3, 1.1);
                splatSpread(tb, acc, tally, Color(2.0 * scale, scale, 0.5), Color(0.4), 0.0, 1.0, 1.2, 0.8, 1.0, 0.8);
                w.addPixel(17, 3, acc);
                acc.clearTouched();
            }
        }
    };
    pass(a, 1.0);
    pass(a, 3.0);
    pass(b, 2.0);
    a.merge(b);
    const std::shared_ptr<const FilmSnapshot> snap = a.snapshot();
    const std::vector<double> v = phasorVolume(*snap, TimeAxis::Real);
    ASSERT_EQ(v.size(), 20u * 18u * 3u * 6u);
    // The average of scales 1, 3, 2 is 2: one estimate pair at scale 2, computed directly.
    std::vector<double> want(18, 0.0);
    addEstimatePhasor(spec, Color(2.0), SegmentProfile(Color(0.0), 0.0, 0.0), 1.3, 0.0, -kInf, want.data());
    addEstimatePhasor(spec, Color(4.0, 2.0, 0.5), SegmentProfile(Color(0.4), 0.0, 1.0), 1.2, 0.8, -kInf, want.data());
    const double* got = &v[(3u * 20u + 17u) * 18u];
    for (int i = 0; i < 18; ++i) EXPECT_NEAR(got[i], want[static_cast<size_t>(i)], 1e-14) << i;
    // P(0) is the steady image.
    const std::vector<float> steady = steadyImage(*snap);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], steady[(3u * 20u + 17u) * 3u + c], 1e-6);
    // Every other pixel is zero, and a film without a phasor spec has none.
    double rest = 0.0;
    for (size_t i = 0; i < v.size(); ++i)
        if (i / 18 != 3u * 20u + 17u) rest += std::abs(v[i]);
    EXPECT_EQ(rest, 0.0);
    TransientFilm plain(20, 18, tb);
    EXPECT_TRUE(phasorVolume(*plain.snapshot(), TimeAxis::Real).empty());
    EXPECT_THROW(plain.merge(a), std::invalid_argument);  // different phasor frequencies
}

TEST(PhasorFrequencies, ParsesListsWavelengthsAndMitransientsBand) {
    EXPECT_EQ(parsePhasorFrequencies("2,0.5,2", 100, 0.01, "--phasor"), (std::vector<double>{0.5, 2.0}));
    const std::vector<double> wl = parsePhasorFrequencies("wl:0.25,2", 100, 0.01, "--phasor");
    ASSERT_EQ(wl.size(), 2u);
    EXPECT_DOUBLE_EQ(wl[0], 0.5);
    EXPECT_DOUBLE_EQ(wl[1], 4.0);
    // mitransient: N = 200 bins of 0.01 m (range 2 m), MEAN 0.1 m, SIGMA 0.12 m: mean index 20,
    // sigma index 2 / 0.72 = 2.78, indices floor(20 - 8.33) = 11 .. ceil(20 + 8.33) = 29, f = k / 2 m.
    const std::vector<double> band = parsePhasorFrequencies("band:0.1:0.12", 200, 0.01, "--phasor");
    ASSERT_EQ(band.size(), 19u);
    EXPECT_DOUBLE_EQ(band.front(), 5.5);
    EXPECT_DOUBLE_EQ(band.back(), 14.5);
    for (const char* bad : {"", "x", "1,,2", "-1", "wl:0", "wl:-2", "band:0.1", "band:0:0.1", "2e7", "nan"}) {
        try {
            parsePhasorFrequencies(bad, 100, 0.01, "--phasor");
            ADD_FAILURE() << "accepted \"" << bad << "\"";
        } catch (const UserError& e) {
            EXPECT_NE(std::string(e.what()).find("--phasor"), std::string::npos) << e.what();
        }
    }
    // A band above the film's Nyquist frequency (50 cycles/m at 0.01 m bins) has no FFT index.
    try {
        parsePhasorFrequencies("band:0.005:0.05", 100, 0.01, "film.phasor");
        ADD_FAILURE() << "accepted a band above the Nyquist frequency";
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find("Nyquist"), std::string::npos) << e.what();
    }
}
