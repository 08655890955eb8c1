// Tests of the point x beam 3D estimator ("point3d", estimators/point3d.h):
//  - exact: the chord of the ball on the segment against dense sampling (clipped at both ends,
//    grazing, unbounded segments); the chord's transmittance integral against quadrature, with its
//    sigma_t -> 0 limit (the chord's length) and large sigma_t (e^{-sigma_t s-} / sigma_t); one
//    point's estimate against the formula written out (chromatic medium, eta != 1), its time profile
//    per bin against quadrature (real axis: density e^{-sigma_t s} per channel over t = a + eta s;
//    unwarped: one instant), the uniform profile, both accelerator backends; the kernel integrates
//    to one (a grid of points filling space gives sigma_s rho Phi Int_0^S T(s) ds); a wall between the
//    point and the ray blocks it;
//  - statistical: single scattering from a point-light pulse in an infinite chromatic medium against
//    the quadrature oracle, per pixel, bin and channel, both axes, delta and continuous emission
//    (tests/support/single_scattering_check.h), with the check that a 4% brighter film and a 3%
//    slower time axis are rejected;
//  - consistency: Embree and brute-force candidates, 1 and 2 threads give identical films.
#include "estimators/beam2d.h"
#include "estimators/point3d.h"
#include "support/gather_probe.h"
#include "support/point_scenes.h"
#include "support/single_scattering_check.h"
#include "support/test_scene.h"

#include "support/quadrature.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

using namespace tpb;
using tpb::test::kBox;
using tpb::test::kSingleScatter;
using tpb::test::point;
using tpb::test::renderVolume;

namespace {

// Composite Gauss-Legendre (5 points) on n panels.
double quad(const std::function<double(double)>& f, double a, double b, int n = 400) {
    return test::gaussLegendre5(f, a, b, n);
}

// An infinite chromatic medium with eta = 1.3; `shapes` is a JSON array.
std::string mediumScene(const std::string& shapes = "[]") {
    return R"({
      "version": 1,
      "camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov": 20, "resolution": [4, 4]},
      "film": {"start_m": 0, "bin_width_m": 0.02, "bins": 300},
      "media": {"m": {"sigma_s": [0.3, 0.5, 0.9], "sigma_a": [0.1, 0.05, 2.2], "g": 0.4, "ior": 1.3}},
      "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
      "global_medium": "m",
      "shapes": )" +
           shapes + R"(,
      "lights": [{"type": "point", "position": [0, 3, 0], "power": 1}],
      "render": {"photons_per_pass": 100, "radius": 0.05, "seed": 1}
    })";
}

}  // namespace

TEST(Point3D, RegisteredWithItsDimensionAndNeeds) {
    const auto est = makeVolumeEstimator("point3d");
    ASSERT_TRUE(est);
    EXPECT_EQ(est->name(), "point3d");
    EXPECT_EQ(est->dim(), 3);
    EXPECT_FALSE(est->needs().beams);
    EXPECT_TRUE(est->needs().points);
    const std::vector<std::string> names = volumeEstimatorNames();
    EXPECT_NE(std::find(names.begin(), names.end(), "point3d"), names.end());
}

// The chord [s-, s+] against dense sampling of |x_r + s w_r - x_p| < r on [0, sMax].
TEST(Point3D, ChordMatchesDenseSamplingClippedAndGrazing) {
    Rng rng(21, Stream::Test, 0, 0);
    int nonEmpty = 0, clipped = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * kPi * rng.uniform();
        const Vec3 wr(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z);
        const Vec3 xr(rng.uniform(), rng.uniform(), rng.uniform());
        const double r = 0.05 + 0.1 * rng.uniform(), sMax = 0.2 + rng.uniform();
        const Vec3 xp = xr + (1.4 * rng.uniform() - 0.2) * wr +
                        Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * (2.5 * r);
        const auto chord = rayPointChord(xr, wr, sMax, xp, r);
        const int n = 20000;
        double lo = kInf, hi = -kInf;
        for (int i = 0; i <= n; ++i) {
            const double s = sMax * i / n;
            if (glm::length(xr + s * wr - xp) < r) {
                lo = std::min(lo, s);
                hi = std::max(hi, s);
            }
        }
        const double step = sMax / n;
        if (!chord) {
            EXPECT_TRUE(!(hi >= lo) || hi - lo <= 2 * step) << trial;
            continue;
        }
        ++nonEmpty;
        clipped += chord->sMinus == 0.0 || chord->sPlus == sMax;
        EXPECT_NEAR(chord->sMinus, lo, 1.01 * step) << trial;
        EXPECT_NEAR(chord->sPlus, hi, 1.01 * step) << trial;
        EXPECT_NEAR(chord->sP, glm::dot(xp - xr, wr), 1e-15);
    }
    EXPECT_GT(nonEmpty, 80);
    EXPECT_GT(clipped, 10);
    // Grazing: a chord that shrinks to zero as the point moves out to distance r.
    const Vec3 xr(0.0), wr(0.0, 0.0, 1.0);
    double prev = kInf;
    for (double eps : {1e-2, 1e-4, 1e-6, 1e-8}) {
        const auto c = rayPointChord(xr, wr, 2.0, Vec3(0.1 * (1.0 - eps), 0.0, 1.0), 0.1);
        ASSERT_TRUE(c);
        const double len = c->sPlus - c->sMinus;
        EXPECT_NEAR(len, 2.0 * 0.1 * std::sqrt(1.0 - (1.0 - eps) * (1.0 - eps)), 1e-9);
        EXPECT_LT(len, prev);
        prev = len;
    }
    EXPECT_FALSE(rayPointChord(xr, wr, 2.0, Vec3(0.1, 0.0, 1.0), 0.1));       // touching: empty
    EXPECT_FALSE(rayPointChord(xr, wr, 2.0, Vec3(0.0, 0.0, -0.1), 0.1));      // touching the start
    const auto open = rayPointChord(xr, wr, kInf, Vec3(0.0, 0.0, 1e5), 0.1);  // unbounded segment
    ASSERT_TRUE(open);
    EXPECT_NEAR(open->sPlus - open->sMinus, 0.2, 1e-9);
}

// Int_{s-}^{s+} e^{-sigma_t s} ds: closed form = quadrature; sigma_t -> 0 gives the chord length,
// large sigma_t gives e^{-sigma_t s-} / sigma_t.
TEST(Point3D, ChordTransmittanceMatchesQuadratureAndLimits) {
    for (double st : {1e-12, 1e-6, 1e-3, 0.5, 3.0, 40.0, 1e3}) {
        for (auto [a, b] :
             {std::pair{0.0, 0.1}, std::pair{0.7, 0.8}, std::pair{2.0, 2.0 + 1e-7}, std::pair{0.0, 3.0}}) {
            const double closed = chordTransmittance(st, a, b);
            const double ref = quad([&](double s) { return std::exp(-st * s); }, a, b, 20000);
            EXPECT_NEAR(closed, ref, 1e-10 * ref) << st << " [" << a << ", " << b << "]";
        }
    }
    EXPECT_NEAR(chordTransmittance(1e-14, 0.3, 0.5), 0.2, 1e-14);  // sigma_t -> 0: the chord length
    EXPECT_DOUBLE_EQ(chordTransmittance(0.0, 0.3, 0.5), 0.2 * 1.0);
    const double big = 1e4;
    EXPECT_NEAR(chordTransmittance(big, 0.001, 0.1), std::exp(-big * 0.001) / big,
                1e-12 * std::exp(-big * 0.001) / big);
    EXPECT_EQ(chordTransmittance(1e6, 10.0, 11.0), 0.0);  // underflows to 0, no NaN
    EXPECT_TRUE(std::isfinite(chordTransmittance(1e300, 0.0, 1.0)));
}

// One point: L = beta sigma_s rho Phi (3 / (4 pi r^3)) Int_{s-}^{s+} T(s) ds; on the real axis spread
// over t = t_cam + t_p + eta s with density e^{-sigma_t s} per channel, on the unwarped axis at t_p.
TEST(Point3D, OnePointMatchesTheFormulaAndItsTimeProfilePerBin) {
    const test::TestScene sc = test::testSceneFrom(mediumScene());
    const Medium& m = sc->regions[0].medium;
    const double eta = sc->regions[0].ior, r = 0.3, opl = 2.013;
    ASSERT_EQ(eta, 1.3);
    ASSERT_GT(m.sigma_t.z, 2.0);  // a thick channel: its profile is far from even
    const Vec3 xp(0.1, -0.05, 1.5), dirIn(0.3, -1.0, 0.2);
    PhotonMap map;
    map.points.push_back(point(xp, dirIn, Color(1.0, 2.0, 3.0), opl));
    // Its flight started 1 m back: the causal floor (light leaving there for the camera) lies
    // 0.6 eta before the chord's start, so it changes nothing here (CausalFloorBinsTheChordsEarlyPart).
    map.points.back().length = 1.0;
    const CameraSegment seg{Ray{Vec3(0.0), Vec3(0.0, 0.0, 1.0)}, 4.0, 0};
    test::GatherSetup g;
    g.radius = r;
    g.path.beta = Color(0.9, 0.8, 0.7);
    g.path.oplCam = 0.5;
    const auto chord = rayPointChord(seg.ray.o, seg.ray.d, seg.sMax, xp, r);
    ASSERT_TRUE(chord);
    const double rho = m.phase.eval(-glm::dot(glm::normalize(dirIn), seg.ray.d));
    const double K3 = 3.0 / (4.0 * kPi * r * r * r);
    Color expected;
    for (int c = 0; c < 3; ++c)
        expected[c] = g.path.beta[c] * m.sigma_s[c] * rho * (c + 1.0) * K3 *
                      quad([&](double s) { return std::exp(-m.sigma_t[c] * s); }, chord->sMinus, chord->sPlus);
    const TimeBins& tb = sc.time;
    const int kUnwarped = tb.binOf(opl);
    for (AccelBackend backend : {AccelBackend::Embree, AccelBackend::BruteForce}) {
        g.accel = backend;
        g.profile = TimeProfile::Exact;
        Point3DEstimator est;
        const test::GatherResult res = test::gatherOnce(est, *sc, map, seg, tb, g);
        ASSERT_EQ(res.estimates, 1);
        int binsChecked = 0;
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(res.steady[c], expected[c], 1e-12 * expected[c]) << c;
            EXPECT_NEAR(res.bins[1][kUnwarped][c], expected[c], 1e-12 * expected[c]) << c;  // one instant
            // Real axis: bin k holds the energy of s with t_cam + t_p + eta s in the bin.
            const double a = g.path.oplCam + opl, total = quad([&](double s) { return std::exp(-m.sigma_t[c] * s); },
                                                               chord->sMinus, chord->sPlus);
            for (int k = 0; k < tb.bins; ++k) {
                const double sLo = std::max(chord->sMinus, (tb.startOpl + k * tb.binWidth - a) / eta);
                const double sHi = std::min(chord->sPlus, (tb.startOpl + (k + 1) * tb.binWidth - a) / eta);
                const double share =
                    sHi > sLo ? quad([&](double s) { return std::exp(-m.sigma_t[c] * s); }, sLo, sHi, 20) / total : 0.0;
                EXPECT_NEAR(res.bins[0][k][c], expected[c] * share, 1e-10 * expected[c])
                    << "channel " << c << " bin " << k;
                binsChecked += share > 0.0;
            }
        }
        EXPECT_GE(binsChecked, 3 * 30);  // the chord 2 h ~ 0.57 m spreads over ~37 bins of 0.02 m / eta
        // The uniform profile (the paper's even spread): the same energy, shares proportional to time.
        g.profile = TimeProfile::Uniform;
        Point3DEstimator uni;
        const test::GatherResult u = test::gatherOnce(uni, *sc, map, seg, tb, g);
        const double tLo = g.path.oplCam + opl + eta * chord->sMinus, tHi = g.path.oplCam + opl + eta * chord->sPlus;
        const int kMid = tb.binOf(0.5 * (tLo + tHi));
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(u.steady[c], expected[c], 1e-12 * expected[c]);
            EXPECT_NEAR(u.bins[0][kMid][c], expected[c] * tb.binWidth / (tHi - tLo), 1e-10 * expected[c]);
        }
    }
}

// A point whose flight starts at itself (length 0): no light earlier than the real path x_p -> x_r,
// t_cam + t_p + eta |x_p - x_r|. The chord's part with eta s below eta |x_p - x_r| is mirrored about
// that floor (s -> 2 s_f - s), the rest lands as before, the total unchanged (docs/developer/adding-an-estimator.md,
// "Causality"): every bin against quadrature of the mirrored profile.
TEST(Point3D, CausalFloorMirrorsTheChordsEarlyPart) {
    const test::TestScene sc = test::testSceneFrom(mediumScene());
    const Medium& m = sc->regions[0].medium;
    const double eta = sc->regions[0].ior, r = 0.3, opl = 2.013;
    const Vec3 xp(0.1, -0.05, 1.5), dirIn(0.3, -1.0, 0.2);
    PhotonMap map;
    map.points.push_back(point(xp, dirIn, Color(1.0), opl));
    const CameraSegment seg{Ray{Vec3(0.0), Vec3(0.0, 0.0, 1.0)}, 4.0, 0};
    test::GatherSetup g;
    g.radius = r;
    g.path.oplCam = 0.5;
    const auto chord = rayPointChord(seg.ray.o, seg.ray.d, seg.sMax, xp, r);
    ASSERT_TRUE(chord);
    const double a = g.path.oplCam + opl, floorReal = a + eta * glm::length(xp);
    const double sFloor = glm::length(xp);  // eta s = eta |x_p - x_r|: the chord's share below it moves
    ASSERT_GT(sFloor, chord->sMinus + 0.2);
    Point3DEstimator est;
    const test::GatherResult res = test::gatherOnce(est, *sc, map, seg, sc.time, g);
    ASSERT_EQ(res.estimates, 1);
    const TimeBins& tb = sc.time;
    const int kFloor = tb.binOf(floorReal);
    const auto T = [&](double lo, double hi) {
        return hi > lo ? quad([&](double s) { return std::exp(-m.sigma_t.x * s); }, lo, hi) : 0.0;
    };
    const double total = T(chord->sMinus, chord->sPlus);
    for (int k = 0; k < kFloor; ++k) EXPECT_EQ(res.bins[0][k].x, 0.0) << k;  // nothing before the floor
    for (int k = kFloor; k < tb.bins; ++k) {
        const double lo = (tb.startOpl + k * tb.binWidth - a) / eta, hi = lo + tb.binWidth / eta;  // bin k in s
        const double direct = T(std::max(sFloor, lo), std::min(chord->sPlus, hi));
        const double mirrored = T(std::max(chord->sMinus, 2.0 * sFloor - hi), std::min(sFloor, 2.0 * sFloor - lo));
        EXPECT_NEAR(res.bins[0][k].x, res.steady.x * (direct + mirrored) / total, 1e-10 * res.steady.x) << k;
    }
    EXPECT_NEAR(res.binsTotal(TimeAxis::Real).x, res.steady.x, 1e-12 * res.steady.x);  // energy kept
    EXPECT_GT(T(chord->sMinus, sFloor) / total, 0.3);
}

// Filling space with points of power Phi dV turns the estimate into the kernel's integral:
//   Int d^3x_p K_3 Int_0^S T(s) 1(|x(s) - x_p| < r) ds = Int_0^S T(s) ds.
// Cylindrical grid around the ray: u = r sin(theta) with Gauss-Legendre in theta (the integrand
// 2 pi u 2 h(u), h = sqrt(r^2 - u^2), is smooth in theta), a fine midpoint rule in s_p reaching r past
// both ends of the segment. Pins the ball's normalisation 3 / (4 pi r^3) and the chord's clipping.
TEST(Point3D, KernelIntegratesToOneAlongTheRay) {
    const test::TestScene sc = test::testSceneFrom(mediumScene());
    const Medium& m = sc->regions[0].medium;
    const double r = 0.08, S = 2.0, ds = r / 40.0;
    static const double gx[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double gw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                 0.2369268850561891};
    const int nPhi = 5;
    PhotonMap map;
    for (double s = -1.5 * r + 0.5 * ds; s < S + 1.5 * r; s += ds)
        for (int j = 0; j < 5; ++j) {
            const double theta = 0.25 * kPi * (1.0 + gx[j]), wTheta = 0.25 * kPi * gw[j];  // theta in [0, pi/2]
            const double u = r * std::sin(theta);
            const double dA = 2.0 * kPi * u * r * std::cos(theta) * wTheta;  // 2 pi u du
            for (int k = 0; k < nPhi; ++k) {
                const double phi = 2.0 * kPi * (k + 0.37 * j) / nPhi;
                map.points.push_back(
                    point(Vec3(u * std::cos(phi), u * std::sin(phi), s), Vec3(0, 1, 0), Color(dA * ds / nPhi), 1.0));
            }
        }
    const CameraSegment seg{Ray{Vec3(0.0), Vec3(0.0, 0.0, 1.0)}, S, 0};
    test::GatherSetup g;
    g.radius = r;
    Point3DEstimator est;
    const test::GatherResult res = test::gatherOnce(est, *sc, map, seg, sc.time, g);
    const double rho = m.phase.eval(0.0);
    for (int c = 0; c < 3; ++c) {
        const double st = m.sigma_t[c];
        const double exact = m.sigma_s[c] * rho * (1.0 - std::exp(-st * S)) / st;
        EXPECT_NEAR(res.steady[c], exact, 2e-4 * exact) << "channel " << c;
    }
}

TEST(Point3D, AWallBetweenThePointAndTheRayBlocksIt) {
    const std::string wall =
        R"([{"type": "quad", "corner": [-1, -1, 1], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "white"}])";
    const test::TestScene walled = test::testSceneFrom(mediumScene(wall)), open = test::testSceneFrom(mediumScene());
    const CameraSegment seg{Ray{Vec3(-0.5, 0.0, 0.98), Vec3(1.0, 0.0, 0.0)}, 1.0, 0};
    test::GatherSetup g;
    g.radius = 0.05;
    PhotonMap behind, before;
    behind.points.push_back(point(Vec3(0.0, 0.0, 1.02), Vec3(0, -1, 0), Color(1.0), 1.0));
    before.points.push_back(point(Vec3(0.0, 0.0, 0.94), Vec3(0, -1, 0), Color(1.0), 1.0));
    for (AccelBackend backend : {AccelBackend::Embree, AccelBackend::BruteForce}) {
        g.accel = backend;
        Point3DEstimator a, b, c;
        EXPECT_EQ(test::gatherOnce(a, *walled, behind, seg, walled.time, g).estimates, 0);
        EXPECT_EQ(test::gatherOnce(b, *open, behind, seg, open.time, g).estimates, 1);
        EXPECT_EQ(test::gatherOnce(c, *walled, before, seg, walled.time, g).estimates, 1);
    }
}

// See tests/estimators/test_point2d.cpp (same scene, radius and thresholds): per-cell mean z^2 and
// per-channel totals against singleScatteringReference, both axes, delta and continuous.
TEST(Point3D, SingleScatteringMatchesQuadraturePerPixelAndBinOnBothAxes) {
    test::expectSingleScatteringMatches(kSingleScatter, "point3d", 300);
}

TEST(Point3D, BruteForceAndEmbreeGiveIdenticalFilms) {
    const test::TestScene sc = test::testSceneFrom(kBox);
    RenderSettings s = sc.settings;
    s.volumeEstimator = "point3d";
    s.threads = 2;
    s.accel = AccelBackend::Embree;
    const std::vector<double> a = renderVolume(sc, s, 2);
    s.accel = AccelBackend::BruteForce;
    const std::vector<double> b = renderVolume(sc, s, 2);
    ASSERT_EQ(a.size(), b.size());
    double total = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i], b[i]) << i;
        total += a[i];
    }
    EXPECT_GT(total, 0.0);
}

TEST(Point3D, OneAndTwoThreadsGiveIdenticalFilms) {
    const test::TestScene sc = test::testSceneFrom(kBox);
    RenderSettings s = sc.settings;
    s.volumeEstimator = "point3d";
    s.threads = 1;
    const std::vector<double> a = renderVolume(sc, s, 2);
    s.threads = 2;
    const std::vector<double> b = renderVolume(sc, s, 2);
    ASSERT_EQ(a.size(), b.size());
    double total = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i], b[i]) << i;
        total += a[i];
    }
    EXPECT_GT(total, 0.0);
}
