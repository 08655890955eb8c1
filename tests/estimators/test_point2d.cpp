// Tests of the point x beam 2D estimator ("point2d", estimators/point2d.h):
//  - exact: the disc geometry (projection, distance, support), one point's estimate against the
//    formula written out (chromatic medium, eta != 1, camera throughput and OPL), its instant on
//    both time axes, both accelerator backends; the kernel integrates to one across the ray (a grid
//    of points filling space gives sigma_s rho Phi Int_0^S T(s) ds); a wall between the point and
//    the ray blocks it;
//  - statistical: single scattering from a point-light pulse in an infinite chromatic medium
//    (max depth 1) against the quadrature oracle (singleScatteringReference) per pixel, bin and
//    channel on both time axes, delta and continuous emission, z-tests with the per-pass variance;
//    the same statistics reject a film 3% too bright and a time axis 3% too slow;
//  - consistency: Embree and brute-force candidates, 1 and 2 threads give identical films.
#include "estimators/point2d.h"
#include "estimators/estimator.h"
#include "support/gather_probe.h"
#include "support/point_scenes.h"
#include "support/single_scattering_check.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace tpb;
using tpb::test::kBox;
using tpb::test::kSingleScatter;
using tpb::test::point;
using tpb::test::renderVolume;

namespace {

// An infinite chromatic medium with eta = 1.3; `shapes` is a JSON array.
std::string mediumScene(const std::string& shapes = "[]") {
    return R"({
      "version": 1,
      "camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov": 20, "resolution": [4, 4]},
      "film": {"start_m": 0, "bin_width_m": 0.1, "bins": 64},
      "media": {"m": {"sigma_s": [0.3, 0.5, 0.9], "sigma_a": [0.1, 0.05, 0.2], "g": 0.4, "ior": 1.3}},
      "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
      "global_medium": "m",
      "shapes": )" +
           shapes + R"(,
      "lights": [{"type": "point", "position": [0, 3, 0], "power": 1}],
      "render": {"photons_per_pass": 100, "radius": 0.05, "seed": 1}
    })";
}

}  // namespace

TEST(Point2D, RegisteredWithItsDimensionAndNeeds) {
    const auto est = makeVolumeEstimator("point2d");
    ASSERT_TRUE(est);
    EXPECT_EQ(est->name(), "point2d");
    EXPECT_EQ(est->dim(), 2);
    EXPECT_FALSE(est->needs().beams);
    EXPECT_TRUE(est->needs().points);
    const std::vector<std::string> names = volumeEstimatorNames();
    EXPECT_NE(std::find(names.begin(), names.end(), "point2d"), names.end());
    EXPECT_TRUE(makeVolumeEstimator("beam2d")->needs().beams);  // the default still reads beams only
    EXPECT_FALSE(makeVolumeEstimator("beam2d")->needs().points);
}

TEST(Point2D, DiscGeometryProjectionDistanceAndSupport) {
    const Vec3 xr(0.1, -0.2, 0.3), wr = glm::normalize(Vec3(1.0, 2.0, -0.5));
    const Vec3 side = glm::normalize(glm::cross(wr, Vec3(0.0, 0.0, 1.0)));
    const double r = 0.05;
    for (double s : {1e-9, 0.4, 1.999999}) {
        for (double u : {0.0, 0.01, 0.049999}) {
            const auto d = rayPointDisc(xr, wr, 2.0, xr + s * wr + u * side, r);
            ASSERT_TRUE(d) << s << " " << u;
            EXPECT_NEAR(d->s, s, 1e-12);
            EXPECT_NEAR(d->dist2, u * u, 1e-13);
        }
    }
    EXPECT_FALSE(rayPointDisc(xr, wr, 2.0, xr - 1e-9 * wr, r));               // behind the segment's start
    EXPECT_FALSE(rayPointDisc(xr, wr, 2.0, xr + 2.000001 * wr, r));           // past its end
    EXPECT_FALSE(rayPointDisc(xr, wr, 2.0, xr + 1.0 * wr + 0.05 * side, r));  // on the disc's rim: outside
    EXPECT_FALSE(rayPointDisc(xr, wr, 2.0, xr + 1.0 * wr + 0.0500001 * side, r));
    EXPECT_TRUE(rayPointDisc(xr, wr, kInf, xr + 1e6 * wr + 0.01 * side, r));  // unbounded segment
}

// One point: L = beta sigma_s rho(w_p . -w_r) Phi_p T_r(s_p) / (pi r^2), arriving at
// t_cam + t_p + eta s_p (real) and t_p (unwarped), through both backends.
TEST(Point2D, OnePointMatchesTheFormulaAtItsInstantOnBothAxes) {
    const test::TestScene sc = test::testSceneFrom(mediumScene());
    const Medium& m = sc->regions[0].medium;
    const double eta = sc->regions[0].ior, r = 0.05, sP = 1.5, opl = 2.03;
    ASSERT_EQ(eta, 1.3);
    PhotonMap map;
    const Vec3 dirIn(0.3, -1.0, 0.2);
    map.points.push_back(point(Vec3(0.02, -0.01, sP), dirIn, Color(1.0, 2.0, 3.0), opl));
    const CameraSegment seg{Ray{Vec3(0.0), Vec3(0.0, 0.0, 1.0)}, 4.0, 0};
    test::GatherSetup g;
    g.radius = r;
    g.path.beta = Color(0.9, 0.8, 0.7);
    g.path.oplCam = 0.5;
    const double rho = m.phase.eval(-glm::dot(glm::normalize(dirIn), seg.ray.d));
    const Color expected = g.path.beta * m.sigma_s * rho * Color(1.0, 2.0, 3.0) * m.transmittance(sP) / (kPi * r * r);
    const int kReal = sc.time.binOf(0.5 + opl + eta * sP), kUnwarped = sc.time.binOf(opl);
    ASSERT_EQ(kReal, 44);
    ASSERT_EQ(kUnwarped, 20);
    for (AccelBackend backend : {AccelBackend::Embree, AccelBackend::BruteForce}) {
        g.accel = backend;
        Point2DEstimator est;
        const test::GatherResult res = test::gatherOnce(est, *sc, map, seg, sc.time, g);
        EXPECT_EQ(res.estimates, 1);
        EXPECT_EQ(est.accelPrimitives(), 1u);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(res.steady[c], expected[c], 1e-14 * expected[c]);
            EXPECT_NEAR(res.bins[0][kReal][c], expected[c], 1e-14 * expected[c]);
            EXPECT_NEAR(res.bins[1][kUnwarped][c], expected[c], 1e-14 * expected[c]);
            EXPECT_NEAR(res.binsTotal(TimeAxis::Real)[c], expected[c], 1e-14 * expected[c]);  // one instant
            EXPECT_NEAR(res.binsTotal(TimeAxis::Unwarped)[c], expected[c], 1e-14 * expected[c]);
        }
        // Outside the support: past the segment's end, behind its start, farther than r.
        for (const CameraSegment& s :
             {CameraSegment{seg.ray, 1.49, 0}, CameraSegment{Ray{Vec3(0, 0, 1.6), seg.ray.d}, 4.0, 0}}) {
            Point2DEstimator e;
            EXPECT_EQ(test::gatherOnce(e, *sc, map, s, sc.time, g).estimates, 0);
        }
        g.radius = 0.02;
        Point2DEstimator small;
        EXPECT_EQ(test::gatherOnce(small, *sc, map, seg, sc.time, g).estimates, 0);
        g.radius = r;
    }
}

// Filling space with points of power Phi dV (a cylindrical grid around the ray, reaching past the
// kernel and past both ends of the segment) turns the estimate into the integral of the kernel:
//   Int d^3x_p T_r(s_p) K_2(u_p) 1(0 <= s_p <= S) = Int_0^S T_r(s) ds,
// i.e. sigma_s rho Phi (1 - e^{-sigma_t S}) / sigma_t: pins the disc's normalisation 1 / (pi r^2).
TEST(Point2D, KernelIntegratesToOneAcrossTheRay) {
    const test::TestScene sc = test::testSceneFrom(mediumScene());
    const Medium& m = sc->regions[0].medium;
    const double r = 0.08, S = 2.0;
    const Vec3 xr(0.0), wr(0.0, 0.0, 1.0), dirIn(0.0, 1.0, 0.0);
    const int nU = 24, nPhi = 6;             // rings of width r/16: 16 inside the disc, 8 outside it
    const double du = r / 16.0, ds = 0.002;  // midpoint rule along s
    PhotonMap map;
    for (double s = -0.2 + 0.5 * ds; s < S + 0.2; s += ds)
        for (int i = 0; i < nU; ++i)
            for (int j = 0; j < nPhi; ++j) {
                const double u = (i + 0.5) * du, phi = 2.0 * kPi * (j + 0.5 + 0.3 * i) / nPhi;
                const double dV =
                    kPi * ((i + 1.0) * (i + 1.0) - double(i) * i) * du * du / nPhi * ds;  // exact ring area
                map.points.push_back(point(Vec3(u * std::cos(phi), u * std::sin(phi), s), dirIn, Color(dV), 1.0));
            }
    const CameraSegment seg{Ray{xr, wr}, S, 0};
    test::GatherSetup g;
    g.radius = r;
    Point2DEstimator est;
    const test::GatherResult res = test::gatherOnce(est, *sc, map, seg, sc.time, g);
    EXPECT_EQ(res.estimates, static_cast<int64_t>(std::lround(S / ds)) * 16 * nPhi);
    const double rho = m.phase.eval(0.0);
    for (int c = 0; c < 3; ++c) {
        const double st = m.sigma_t[c];
        const double exact = m.sigma_s[c] * rho * (1.0 - std::exp(-st * S)) / st;
        EXPECT_NEAR(res.steady[c], exact, 1e-6 * exact) << "channel " << c;  // midpoint rule in s only
    }
}

// A wall between the point and the camera segment (the kernel reaches through it) blocks the
// estimate; the same point on the segment's side of the wall, or without the wall, counts.
TEST(Point2D, AWallBetweenThePointAndTheRayBlocksIt) {
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
        Point2DEstimator a, b, c;
        EXPECT_EQ(test::gatherOnce(a, *walled, behind, seg, walled.time, g).estimates, 0);
        EXPECT_EQ(test::gatherOnce(b, *open, behind, seg, open.time, g).estimates, 1);
        EXPECT_EQ(test::gatherOnce(c, *walled, before, seg, walled.time, g).estimates, 1);
    }
}

// The estimator's film against the single-scattering quadrature, per pixel, bin and channel (see
// tests/support/single_scattering_check.h). A fixed radius r = 5 cm (alpha = 1), whose kernel bias
// (~(r / 0.6 m)^2 / 2) is below the tests' resolution. Statistics, per (axis, emission): the mean
// z^2 of the cells (time profile and shape) and the z of each channel's total (normalisation: its
// standard error is ~0.7%, set mostly by the photon points within a few r of the camera, which all
// pixels' rays share). The same thresholds must reject the film 4% too bright and a reference whose
// time runs 3% slower (eta 1.236 instead of 1.2).
TEST(Point2D, SingleScatteringMatchesQuadraturePerPixelAndBinOnBothAxes) {
    test::expectSingleScatteringMatches(kSingleScatter, "point2d", 300);
}

TEST(Point2D, BruteForceAndEmbreeGiveIdenticalFilms) {
    const test::TestScene sc = test::testSceneFrom(kBox);
    RenderSettings s = sc.settings;
    s.volumeEstimator = "point2d";
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

TEST(Point2D, OneAndTwoThreadsGiveIdenticalFilms) {
    const test::TestScene sc = test::testSceneFrom(kBox);
    RenderSettings s = sc.settings;
    s.volumeEstimator = "point2d";
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
