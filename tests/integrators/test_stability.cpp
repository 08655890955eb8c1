// Numerical stability on stiff and extreme cases, and degenerate input (issue 6).
//
// Every case pins an expected value (analytic limit, quadrature or an independent estimate) and
// checks that no NaN/Inf reaches the film (FilmStats::rejectedSamples and a scan of the volume on
// both time axes and of the steady-state image).
//
// Most estimator-level cases use one construction: a laser inside a box of homogeneous medium
// (null boundary), seen from a camera outside it, single scattering only (max_depth 1). The
// expected image, integrated over solid angle, has an exact form for the 2D kernel of
// beam2d.h: for a camera ray of direction w and the kernel cylinder C of radius r around the
// beam, d(omega) ds = d^3x / |x - cam|^2, so
//   E[ sum_pixels L_px Omega_px ] = int_C sigma_s p(-c(x)) Phi / (pi r^2) T_cam(x) T_b(s_b(x)) / |x - cam|^2 d^3x,
// with c(x) = dot(w(x), w_b), s_b(x) the projection of x on the beam axis, T_cam the transmittance
// from x back to the box entry and T_b = exp(-sigma_t s_b) (the expectation of short beams). The
// reference is a 3D quadrature of that over the cylinder (restricted to the box and the field of
// view), binned at the estimator's times t_real = entry OPL + eta (s_r + s_b) + t_emit and
// t_unwarped = t_emit + eta s_b, except that a real time before the causal floor t_f = t_emit +
// entry OPL + eta |laser - entry point| (no light reaches the camera segment earlier; docs/
// estimators.md, "Causality") is mirrored to 2 t_f - t_real, as the estimator does. It is
// independent of the renderer's code paths (no overlap interval, no closed-form transmittance
// integral, no time splat).
#include "accel/beam_accel.h"
#include "scene/bsdf.h"
#include "estimators/beam2d.h"
#include "integrators/camera_pass.h"
#include "render/driver.h"
#include "film/film_view.h"
#include "base/error.h"
#include "base/parallel.h"
#include "photons/photon_tracer.h"
#include "base/progressive.h"
#include "scene/scene_loader.h"
#include "support/temp_dir.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numeric>
#include <sstream>
#include <thread>
#include <tuple>
#include <unistd.h>

using namespace tpb;
namespace fs = std::filesystem;

namespace {

test::TestScene sceneFrom(const std::string& json, const std::string& path = "stability.json") {
    return test::testSceneFrom(json, path);
}

std::string num(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}
std::string vec(const Vec3& v) {
    std::ostringstream s;  // (a stream: GCC 12 warns falsely on chained string operator+)
    s << '[' << num(v.x) << ", " << num(v.y) << ", " << num(v.z) << ']';
    return s.str();
}

// No NaN/Inf (and no negative energy) anywhere in the film; no rejected estimate.
void expectFiniteFilm(const TransientFilm& film, const char* what) {
    EXPECT_EQ(film.stats.rejectedSamples.load(), 0) << what;
    for (int a = 0; a < 2; ++a) {
        EXPECT_TRUE(std::isfinite(film.stats.inside[a].load())) << what;
        EXPECT_TRUE(std::isfinite(film.stats.outside[a].load())) << what;
        std::vector<double> vol;
        film.volume(static_cast<TimeAxis>(a), EmissionMode::Delta, vol);
        size_t bad = 0;
        for (double v : vol) bad += !(std::isfinite(v) && v >= 0.0);
        EXPECT_EQ(bad, 0u) << what << " axis " << a;
    }
    std::vector<float> steady;
    film.steadyImage(steady);
    size_t bad = 0;
    for (float v : steady) bad += !(std::isfinite(v) && v >= 0.0f);
    EXPECT_EQ(bad, 0u) << what << " steady";
}

// Solid angle of every pixel of the pinhole camera (4x4 midpoint rule over the image plane).
std::vector<double> pixelSolidAngles(const Camera& cam) {
    std::vector<double> om(static_cast<size_t>(cam.width) * cam.height);
    const double aspect = static_cast<double>(cam.width) / cam.height;
    const double du = 2.0 * cam.tanHalfFovY * aspect / cam.width, dv = 2.0 * cam.tanHalfFovY / cam.height;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            double o = 0.0;
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) {
                    const double sx = (2.0 * (x + (i + 0.5) / 4) / cam.width - 1.0) * cam.tanHalfFovY * aspect;
                    const double sy = (1.0 - 2.0 * (y + (j + 0.5) / 4) / cam.height) * cam.tanHalfFovY;
                    o += du * dv / 16.0 / std::pow(1.0 + sx * sx + sy * sy, 1.5);
                }
            om[static_cast<size_t>(y) * cam.width + x] = o;
        }
    return om;
}

// Segment [t0, t1] of the ray o + t d inside the axis-aligned box (slab method).
bool boxInterval(const Vec3& o, const Vec3& d, const Vec3& lo, const Vec3& hi, double& t0, double& t1) {
    t0 = -kInf;
    t1 = kInf;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0) {
            if (o[a] < lo[a] || o[a] > hi[a]) return false;
            continue;
        }
        double u = (lo[a] - o[a]) / d[a], v = (hi[a] - o[a]) / d[a];
        if (u > v) std::swap(u, v);
        t0 = std::max(t0, u);
        t1 = std::min(t1, v);
    }
    return t1 > t0;
}

// ---- the laser-in-a-medium-box construction ------------------------------------------------------

struct LaserBox {
    Vec3 boxLo{-0.6, -0.6, -3.6}, boxHi{0.6, 0.6, -1.0};
    double sigmaS = 0.5, sigmaA = 0.1, g = 0.3, ior = 1.0;
    Vec3 laser{0.0, 0.0, -3.4}, dir{0.0, 0.0, 1.0};
    double power = 2.0, emit = 0.5;
    double fov = 3.0;  // degrees; camera at the origin looking down -z
    int res = 48;
    double radius = 0.01;
    double filmStart = 0.475, binWidth = 0.05;
    int bins = 80;
    // Long beams end at the box wall: every beam of the laser is the same segment, so one photon
    // per pass gives the exact expectation and the only noise left is the pixels' jitter.
    BeamLength beamLength = BeamLength::Long;
    int photons = 1, passes = 32;
    uint64_t seed = 7;

    std::string json() const {
        return R"({"version": 1,
          "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov": )" +
               num(fov) + R"(, "resolution": [)" + std::to_string(res) + ", " + std::to_string(res) + R"(]},
          "film": {"start_m": )" +
               num(filmStart) + R"(, "bin_width_m": )" + num(binWidth) + R"(, "bins": )" + std::to_string(bins) + R"(},
          "media": {"m": {"sigma_s": )" +
               num(sigmaS) + R"(, "sigma_a": )" + num(sigmaA) + R"(, "g": )" + num(g) + R"(, "ior": )" + num(ior) +
               R"(}},
          "materials": {"boundary": {"type": "null"}},
          "shapes": [{"type": "box", "min": )" +
               vec(boxLo) + R"(, "max": )" + vec(boxHi) +
               R"(, "material": "boundary", "interior_medium": "m"}],
          "lights": [{"type": "laser", "position": )" +
               vec(laser) + R"(, "direction": )" + vec(dir) + R"(, "power": )" + num(power) + R"(, "emit_time_m": )" +
               num(emit) + R"(}],
          "render": {"photons_per_pass": )" +
               std::to_string(photons) + R"(, "radius": )" + num(radius) +
               R"(, "surface_radius": 0.02, "alpha": 1.0, "max_depth": 1, "seed": )" + std::to_string(seed) + "}}";
    }
};

struct ImageIntegral {
    double steady = 0.0;
    std::vector<double> bins[2];  // per time axis
};

// The reference of the file comment: 3D midpoint quadrature over the kernel cylinder.
// sigmaT < 0: the box's sigma_s + sigma_a; 0 gives the sigma_t -> 0 limit (per unit sigma_s when
// c.sigmaS = 1).
ImageIntegral cylinderReference(const LaserBox& c, const test::TestScene& t, int nz = 1200, int nr = 12, int nphi = 24,
                                double sigmaT = -1.0) {
    const Scene& sc = *t;
    const TimeBins& time = t.time;
    ImageIntegral ref;
    ref.bins[0].assign(time.bins, 0.0);
    ref.bins[1].assign(time.bins, 0.0);
    const Vec3 wb = glm::normalize(c.dir);
    double t0, t1;
    EXPECT_TRUE(boxInterval(c.laser, wb, c.boxLo, c.boxHi, t0, t1));
    const double len = t1;  // the beam ends where it leaves the box
    Vec3 e1, e2;
    coordinateSystem(wb, e1, e2);
    const double st = sigmaT >= 0.0 ? sigmaT : c.sigmaS + c.sigmaA, r = c.radius;
    const HenyeyGreenstein hg{c.g};
    const Vec3 cam = sc.camera.position;
    const double dz = len / nz, dr = r / nr, dphi = 2.0 * kPi / nphi;
    for (int iz = 0; iz < nz; ++iz) {
        const double z = (iz + 0.5) * dz;
        for (int ir = 0; ir < nr; ++ir) {
            const double rho = (ir + 0.5) * dr;
            for (int ip = 0; ip < nphi; ++ip) {
                const double phi = (ip + 0.5) * dphi;
                const Vec3 x = c.laser + z * wb + rho * (std::cos(phi) * e1 + std::sin(phi) * e2);
                if (glm::any(glm::lessThan(x, c.boxLo)) || glm::any(glm::greaterThan(x, c.boxHi))) continue;
                double px, py;
                if (!sc.camera.project(x, px, py) || px < 0 || py < 0 || px >= sc.camera.width ||
                    py >= sc.camera.height)
                    continue;
                const Vec3 v = x - cam;
                const double dist = glm::length(v);
                const Vec3 w = v / dist;
                double a0, a1;
                if (!boxInterval(cam, w, c.boxLo, c.boxHi, a0, a1)) continue;
                const double entry = std::max(a0, 0.0);
                const double sr = dist - entry;  // camera segment inside the medium
                const double sb = glm::dot(x - c.laser, wb);
                const double f = c.sigmaS * hg.eval(-glm::dot(w, wb)) * c.power / (kPi * r * r) *
                                 std::exp(-st * (sr + sb)) / (dist * dist) * rho * dr * dphi * dz;
                ref.steady += f;
                const double tReal = c.emit + entry + c.ior * (sr + sb);
                const double tFloor = c.emit + entry + c.ior * glm::length(cam + entry * w - c.laser);
                const int kr = time.binOf(tReal < tFloor ? 2.0 * tFloor - tReal : tReal);
                const int ku = time.binOf(c.emit + c.ior * sb);
                if (kr >= 0 && kr < time.bins) ref.bins[0][kr] += f;
                if (ku >= 0 && ku < time.bins) ref.bins[1][ku] += f;
            }
        }
    }
    return ref;
}

// The rendered image integrated over solid angle: steady state and per bin on both axes.
ImageIntegral imageIntegral(const TransientFilm& film, const Camera& cam) {
    const std::vector<double> om = pixelSolidAngles(cam);
    ImageIntegral out;
    std::vector<float> steady;
    film.steadyImage(steady);
    for (size_t p = 0; p < om.size(); ++p) out.steady += steady[p * 3] * om[p];
    const int B = film.bins();
    for (int a = 0; a < 2; ++a) {
        std::vector<double> vol;
        film.volume(static_cast<TimeAxis>(a), EmissionMode::Delta, vol);
        out.bins[a].assign(B, 0.0);
        for (size_t p = 0; p < om.size(); ++p)
            for (int k = 0; k < B; ++k) out.bins[a][k] += vol[(p * B + k) * 3] * om[p];
    }
    return out;
}

struct Rendered {
    test::TestScene scene;
    std::unique_ptr<Driver> driver;
    std::vector<PassStats> passes;
};

Rendered renderScene(const std::string& json, int passes, int threads = 2,
                     const std::function<void(RenderSettings&)>& tweak = {}) {
    Rendered r;
    r.scene = sceneFrom(json);
    RenderSettings ds = r.scene.settings;
    ds.threads = threads;
    if (tweak) tweak(ds);
    r.driver = std::make_unique<Driver>(*r.scene, ds, r.scene.time);
    for (int p = 1; p <= passes; ++p) EXPECT_TRUE(r.driver->runPass(p));
    r.passes = r.driver->history();
    return r;
}

// One pass like Driver::runPass (beams only, Embree queries), with separate depth limits for the
// photons (1 = single scattering) and the camera paths (through mirrors and glass).
struct PassRunner {
    const Scene& scene;
    TransientFilm film;
    int64_t photons = 4000;
    double radius = 0.01;
    int photonDepth = 1, cameraDepth = 4, threads = 2;
    uint64_t seed = 1;
    BeamLength beamLength = BeamLength::Short;
    int64_t beams = 0;

    explicit PassRunner(const test::TestScene& s) : scene(*s), film(s->camera.width, s->camera.height, s.time) {}
    void run(uint64_t pass) {
        PhotonPassParams pt;
        pt.seed = seed;
        pt.pass = pass;
        pt.photons = photons;
        pt.maxDepth = photonDepth;
        pt.beamLength = beamLength;
        pt.threads = threads;
        const PhotonMap map = tracePhotons(scene, pt);
        beams += static_cast<int64_t>(map.beams.size());
        Beam2DEstimator beam2d;
        EstimatorPass ep;
        ep.radius = radius;
        ep.beamLength = beamLength;
        ep.threads = threads;
        beam2d.prepare(scene, map, ep);
        CameraPassEstimators est;
        if (!beam2d.empty()) est.volume = &beam2d;
        CameraPassParams cs;
        cs.seed = seed;
        cs.pass = pass;
        cs.maxDepth = cameraDepth;
        std::vector<CameraPassScratch> scratch(threads);
        std::vector<CameraPassStats> stats(threads);
        for (auto& sc : scratch) sc.acc.reset(film.bins());
        parallelFor(film.tileCount(), threads, [&](int64_t tile, int t) {
            renderTile(scene, est, cs, film, static_cast<int>(tile), scratch[t], stats[t]);
        });
        for (const auto& st : stats) st.flushInto(film.stats);
    }
};

// Renders the laser box and compares the image integral with the cylinder quadrature: steady state
// within `tolSteady` (relative), every bin on both axes within tolBin of the total.
ImageIntegral checkLaserBox(const LaserBox& c, const char* what, double tolSteady, double tolBin,
                            double sigmaScale = 1.0, int radialSteps = 12) {
    auto sc = sceneFrom(c.json());
    PassRunner run(sc);
    run.photons = c.photons;
    run.radius = c.radius;
    run.seed = c.seed;
    run.beamLength = c.beamLength;
    for (int p = 1; p <= c.passes; ++p) run.run(p);
    expectFiniteFilm(run.film, what);
    // sigmaScale != 1: radiance per unit sigma_s against the sigma_t -> 0 limit (no attenuation).
    LaserBox unit = c;
    unit.sigmaS = c.sigmaS / sigmaScale;
    const ImageIntegral ref = cylinderReference(unit, sc, 1200, radialSteps, 24, sigmaScale != 1.0 ? 0.0 : -1.0);
    ImageIntegral got = imageIntegral(run.film, sc->camera);
    got.steady /= sigmaScale;
    for (auto& b : got.bins)
        for (double& v : b) v /= sigmaScale;
    std::printf("%-28s image integral %.6g vs quadrature %.6g (%+.2f%%)\n", what, got.steady, ref.steady,
                100.0 * (got.steady / ref.steady - 1.0));
    EXPECT_GT(ref.steady, 0.0) << what;
    EXPECT_NEAR(got.steady, ref.steady, tolSteady * ref.steady) << what;
    for (int a = 0; a < 2; ++a) {
        double worst = 0.0;
        int worstK = -1;
        for (int k = 0; k < sc.time.bins; ++k) {
            const double e = std::abs(got.bins[a][k] - ref.bins[a][k]);
            if (e > worst) {
                worst = e;
                worstK = k;
            }
        }
        EXPECT_LT(worst, tolBin * ref.steady)
            << what << " axis " << a << " bin " << worstK << ": " << got.bins[a][std::max(worstK, 0)] << " vs "
            << ref.bins[a][std::max(worstK, 0)];
    }
    return got;
}

}  // namespace

// ---- 3. beam orientation at the estimator level ----------------------------------------------------

// A laser pointing straight at the camera: every camera ray is (anti)parallel to the beam up to the
// pixel's angle, so the real-time slope eta (1 + c) vanishes and all of a pixel's energy lands in a
// single bin, at the geometric time t_emit + |laser - camera| (3.4 m of vacuum-equivalent path).
TEST(StabilityOrientation, LaserPointingAtTheCameraFillsOneBinPerPixel) {
    LaserBox c;  // laser at z = -3.4 towards the camera at the origin
    auto sc = sceneFrom(c.json());
    PassRunner run(sc);
    run.photons = c.photons;
    run.radius = c.radius;
    for (int p = 1; p <= c.passes; ++p) run.run(p);
    const TransientFilm& film = run.film;
    expectFiniteFilm(film, "toward");
    const int B = film.bins(), kGeo = sc.time.binOf(c.emit + 3.4);
    ASSERT_EQ(kGeo, 68);
    std::vector<double> vol;
    film.volume(TimeAxis::Real, EmissionMode::Delta, vol);
    int lit = 0;
    for (int p = 0; p < c.res * c.res; ++p) {
        double in = 0.0, other = 0.0;
        for (int k = 0; k < B; ++k) (k == kGeo ? in : other) += vol[(static_cast<size_t>(p) * B + k) * 3];
        EXPECT_EQ(other, 0.0) << "pixel " << p;
        lit += in > 0.0;
    }
    EXPECT_GT(lit, 100);  // the beam's footprint: a disc of ~10 pixels radius
    // Its energy and the unwarped profile (spread over [t_emit, t_emit + 2.4]) against quadrature.
    const ImageIntegral got = checkLaserBox(c, "toward", 0.02, 0.004);
    // The Driver with the scene's own max_depth 1: crossing the null boundary is not an event, so
    // the camera still sees single scattering in the box (same camera samples: same image).
    Rendered d = renderScene(c.json(), c.passes, 2, [&](RenderSettings& ds) { ds.beamLength = c.beamLength; });
    expectFiniteFilm(d.driver->film(), "toward, driver");
    EXPECT_NEAR(imageIntegral(d.driver->film(), d.scene->camera).steady, got.steady, 1e-6 * got.steady);
}

TEST(StabilityOrientation, TowardAwayPerpendicularObliqueAndNearlyParallelMatchQuadrature) {
    {
        LaserBox c;  // tilted by 1e-7 rad: c = -1 + 5e-15, the collapsed-interval branch's edge
        c.dir = glm::normalize(Vec3(1e-7, 0.0, 1.0));
        checkLaserBox(c, "toward, tilted 1e-7", 0.02, 0.004);
    }
    {
        LaserBox c;  // pointing away: back-scattering, t_real = t_emit + 2|z| - 1.2 spread over 4.8 m
        c.laser = Vec3(0.0, 0.0, -1.2);
        c.dir = Vec3(0.0, 0.0, -1.0);
        c.bins = 128;
        checkLaserBox(c, "away", 0.02, 0.004);
    }
    {
        LaserBox c;  // perpendicular to the view direction
        c.laser = Vec3(-0.5, 0.0, -2.5);
        c.dir = Vec3(1.0, 0.0, 0.0);
        c.fov = 32.0;
        c.res = 96;
        c.radius = 0.02;
        checkLaserBox(c, "perpendicular", 0.02, 0.004);
    }
    {
        LaserBox c;  // perpendicular, short beams (random lengths, tau_b = 0): noisier, same expectation
        c.laser = Vec3(-0.5, 0.0, -2.5);
        c.dir = Vec3(1.0, 0.0, 0.0);
        c.fov = 32.0;
        c.res = 96;
        c.radius = 0.02;
        c.beamLength = BeamLength::Short;
        c.photons = 400;
        c.passes = 8;
        checkLaserBox(c, "perpendicular, short beams", 0.03, 0.008);
    }
    {
        LaserBox c;  // parallel to the view direction but 5 cm off axis: long, grazing overlaps
        c.laser = Vec3(0.05, 0.0, -3.4);
        c.fov = 6.0;
        checkLaserBox(c, "parallel, offset", 0.02, 0.004);
    }
}

// ---- 7. Henyey-Greenstein g = -0.999, 0, 0.999 ------------------------------------------------------

TEST(StabilityPhase, ExtremeAnisotropyMatchesQuadrature) {
    for (double g : {-0.999, 0.0, 0.999}) {
        LaserBox c;  // oblique beam: scattering angles 8..31 degrees towards the camera
        c.laser = Vec3(-0.4, 0.1, -3.2);
        c.dir = glm::normalize(Vec3(0.3, 0.0, 1.0));
        c.fov = 24.0;
        c.res = 96;
        c.radius = 0.015;
        c.g = g;
        const std::string what = "oblique, g = " + num(g);
        checkLaserBox(c, what.c_str(), 0.02, 0.004);
    }
    // Straight at the camera with g = 0.999: the phase peak (width ~1e-3 rad) is narrower than the
    // kernel's angular footprint; the quadrature resolves it across the cylinder's cross-section.
    LaserBox c;
    c.g = 0.999;
    c.fov = 1.0;
    c.res = 64;
    checkLaserBox(c, "toward, g = 0.999", 0.01, 0.01, 1.0, 64);
    c.g = -0.999;
    checkLaserBox(c, "toward, g = -0.999", 0.01, 0.01);
}

// ---- 1. nearly empty media: sigma_t -> 0 ------------------------------------------------------------

// sigma_s = 1e-12 and 1e-6 /m, no absorption: the radiance divided by sigma_s must match the
// sigma_t -> 0 limit of the single-scattering integral (the cylinder quadrature with T = 1).
TEST(StabilityEmptyMedium, RadiancePerSigmaTendsToTheVacuumLimit) {
    for (double sigma : {1e-12, 1e-6}) {
        LaserBox c;
        c.laser = Vec3(-0.4, 0.1, -3.2);
        c.dir = glm::normalize(Vec3(0.3, 0.0, 1.0));
        c.fov = 24.0;
        c.res = 96;
        c.radius = 0.015;
        c.sigmaS = sigma;
        c.sigmaA = 0.0;
        c.beamLength = BeamLength::Short;  // free flights of ~1/sigma: every beam reaches the wall
        c.photons = 2;
        c.passes = 16;
        const std::string what = "empty, sigma_s = " + num(sigma);
        checkLaserBox(c, what.c_str(), 0.01, 0.004, sigma);
    }
}

// A point light in an unbounded medium with sigma_s = 1e-12: photon beams ~1e12 m long (Embree
// boxes of 1.5e10 m), against the closed form of the sigma -> 0 limit of single scattering (g = 0):
// along a ray o + s w passing at distance h from the light (closest at s*),
//   L = sigma_s Phi / (16 pi^2) int_0^inf ds / (h^2 + (s - s*)^2),  t(s) = s + d(s) monotone, and
// the mass arriving before OPL t is  atan(u(t) / h) / h  with  u(t) = ((t - s*)^2 - h^2) / (2 (t - s*)).
TEST(StabilityEmptyMedium, UnboundedBeamsOfAPointLightMatchTheClosedForm) {
    const double sigma = 1e-12, power = 10.0;
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0.6, 0, 0], "fov": 10, "resolution": [8, 8]},
      "film": {"start_m": 2.8, "bin_width_m": 0.1, "bins": 40},
      "media": {"m": {"sigma_s": 1e-12, "sigma_a": 0}}, "global_medium": "m",
      "lights": [{"type": "point", "position": [0, 0, 0], "power": 10}],
      "render": {"photons_per_pass": 3000, "radius": 0.03, "alpha": 1, "max_depth": 1, "seed": 5}})";
    Rendered r = renderScene(json, 32);
    const Scene& sc = *r.scene;
    const TimeBins& time = r.scene.time;
    expectFiniteFilm(r.driver->film(), "point light, sigma 1e-12");
    EXPECT_GT(r.passes[0].beams, 2900);
    EXPECT_EQ(r.passes[0].beamPieces, r.passes[0].beams * static_cast<int64_t>(beamPieceCount(1e11, 0.03)));
    std::vector<double> vol;
    r.driver->film().volume(TimeAxis::Real, EmissionMode::Delta, vol);
    std::vector<float> steady;
    r.driver->film().steadyImage(steady);
    const int W = 8, B = time.bins;
    double errSteady = 0.0, refSteady = 0.0, totalGot = 0.0, totalRef = 0.0, errBins = 0.0, refBins = 0.0;
    for (int y = 0; y < W; ++y)
        for (int x = 0; x < W; ++x) {
            double ref = 0.0;
            std::vector<double> bins(B, 0.0);
            const int g = 6;
            for (int j = 0; j < g; ++j)
                for (int i = 0; i < g; ++i) {
                    const Ray ray = sc.camera.generate(x + (i + 0.5) / g, y + (j + 0.5) / g);
                    const double sStar = glm::dot(-ray.o, ray.d), h = glm::length(ray.o + sStar * ray.d);
                    const double k = sigma * power / (16.0 * kPi * kPi) / (g * g);
                    const double tFirst = glm::length(ray.o);  // s = 0: straight from the light
                    const auto mass = [&](double t) {          // int_0^{s(t)} ds / (h^2 + (s - s*)^2)
                        if (t <= tFirst) return 0.0;
                        const double tp = t - sStar, u = (tp * tp - h * h) / (2.0 * tp);
                        return std::max(0.0, (std::atan(u / h) - std::atan(-sStar / h)) / h);
                    };
                    ref += k * (kPi / 2.0 + std::atan(sStar / h)) / h;
                    for (int b = 0; b < B; ++b) {
                        const double t0 = time.startOpl + b * time.binWidth;
                        bins[b] += k * (mass(t0 + time.binWidth) - mass(t0));
                    }
                }
            const size_t p = static_cast<size_t>(y) * W + x;
            errSteady += (steady[p * 3] - ref) * (steady[p * 3] - ref);
            refSteady += ref * ref;
            totalGot += steady[p * 3];
            totalRef += ref;
            for (int b = 0; b < B; ++b) {
                const double e = vol[(p * B + b) * 3] - bins[b];
                errBins += e * e;
                refBins += bins[b] * bins[b];
            }
        }
    std::printf("point light, sigma 1e-12: image %.5g vs %.5g; relative RMSE steady %.4f, per bin %.4f\n", totalGot,
                totalRef, std::sqrt(errSteady / refSteady), std::sqrt(errBins / refBins));
    EXPECT_NEAR(totalGot, totalRef, 0.02 * totalRef);
    EXPECT_LT(std::sqrt(errSteady / refSteady), 0.06);
    EXPECT_LT(std::sqrt(errBins / refBins), 0.15);  // measured 0.10 (a wrong time axis gives ~1)
}

// ---- 2. optically very thick media --------------------------------------------------------------

// A laser (radius 0.2 m, vertical) through a purely absorbing slab (null box, thickness 0.1 m) onto
// a diffuse floor seen directly by the camera: the floor's radiance is exactly exp(-sigma_a d) times the one without
// the slab, and exactly 0 once exp underflows (sigma_a = 1e6: exp(-1e5)).
TEST(StabilityThickMedium, AbsorbingSlabTransmitsExactlyExpOfMinusTau) {
    const auto scene = [](double sigmaA) {
        return R"({"version": 1,
          "camera": {"position": [0, 0.3, 1.5], "look_at": [0, 0, 0], "fov": 30, "resolution": [16, 16]},
          "film": {"start_m": 1.5, "bin_width_m": 0.05, "bins": 40},
          "media": {"slab": {"sigma_a": )" +
               num(sigmaA) + R"(}},
          "materials": {"white": {"type": "diffuse", "albedo": 0.5}, "boundary": {"type": "null"}},
          "shapes": [{"type": "quad", "corner": [-2, 0, -2], "edge_u": [0, 0, 4], "edge_v": [4, 0, 0], "material": "white"},
                     {"type": "box", "min": [-0.5, 0.4, -0.5], "max": [0.5, 0.5, 0.5], "material": "boundary",
                      "interior_medium": "slab"}],
          "lights": [{"type": "laser", "position": [0, 1, 0], "direction": [0, -1, 0], "radius": 0.2, "power": 3}],
          "render": {"photons_per_pass": 2000, "radius": 0.01, "surface_radius": 0.05, "max_depth": 4, "seed": 3}})";
    };
    const auto image = [](const std::string& json, const char* what) {
        Rendered r = renderScene(json, 2);
        expectFiniteFilm(r.driver->film(), what);
        EXPECT_EQ(r.passes[0].beams, 0);  // absorbing only: no beams
        std::vector<double> vol;
        r.driver->film().volume(TimeAxis::Real, EmissionMode::Delta, vol);
        std::vector<float> steady;
        r.driver->film().steadyImage(steady);
        double total = 0.0;
        for (size_t i = 0; i < steady.size(); i += 3) total += steady[i];
        return total;
    };
    const double clear = image(scene(0.0), "no slab medium");
    ASSERT_GT(clear, 0.0);
    for (double sigma : {5.0, 50.0}) {
        const double got = image(scene(sigma), "absorbing slab");
        EXPECT_NEAR(got / clear, std::exp(-0.1 * sigma), 1e-6 * std::exp(-0.1 * sigma)) << sigma;
    }
    EXPECT_EQ(image(scene(1e6), "sigma_a 1e6"), 0.0);
}

namespace {

// Chandrasekhar's H function of isotropic scattering with albedo omega, by fixed-point iteration of
// H(mu) = 1 / (1 - omega/2 mu int_0^1 H(mu') / (mu + mu') dmu') on a midpoint grid in mu'.
double chandrasekharH(double omega, double mu, double* zerothMoment = nullptr) {
    const int n = 800;
    std::vector<double> x(n), h(n, 1.0), next(n);
    for (int i = 0; i < n; ++i) x[i] = (i + 0.5) / n;
    const auto apply = [&](double m) {
        double s = 0.0;
        for (int i = 0; i < n; ++i) s += h[i] / (m + x[i]);
        return 1.0 / (1.0 - 0.5 * omega * m * s / n);
    };
    for (int it = 0; it < 2000; ++it) {
        double change = 0.0;
        for (int i = 0; i < n; ++i) {
            next[i] = apply(x[i]);
            change = std::max(change, std::abs(next[i] - h[i]));
        }
        h.swap(next);
        if (change < 1e-13) break;
    }
    if (zerothMoment) {
        double m0 = 0.0;
        for (double v : h) m0 += v / n;
        *zerothMoment = m0;
    }
    return apply(mu);
}

}  // namespace

// sigma_t = 1e6 /m, albedo 0.5, a laser at normal incidence onto a 1 m thick slab inside a black
// catcher box: every photon dies within microns (a few events each), nothing reaches the far side,
// and the energy leaving the lit face is the plane albedo of a semi-infinite isotropic medium,
// r(mu0 = 1) = 1 - H(1) sqrt(1 - omega) (Chandrasekhar), measured by the catcher's surface photons.
TEST(StabilityThickMedium, SemiInfiniteSlabReflectsThePlaneAlbedoAndNothingPasses) {
    double m0 = 0.0;
    const double H1 = chandrasekharH(0.5, 1.0, &m0);
    ASSERT_NEAR(m0, (2.0 / 0.5) * (1.0 - std::sqrt(0.5)), 1e-3);  // exact zeroth moment of H
    const double albedoRef = 1.0 - H1 * std::sqrt(0.5);
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 1.5, 2], "look_at": [0, 0, 0], "fov": 40, "resolution": [16, 16]},
      "film": {"start_m": 0, "bin_width_m": 0.1, "bins": 60},
      "media": {"thick": {"sigma_s": 5e5, "sigma_a": 5e5}},
      "materials": {"black": {"type": "diffuse", "albedo": 0}, "boundary": {"type": "null"}},
      "shapes": [{"type": "box", "min": [-3, -3, -3], "max": [3, 3, 3], "material": "black", "flip_normals": true},
                 {"type": "box", "min": [-2.5, -1, -2.5], "max": [2.5, 0, 2.5], "material": "boundary",
                  "interior_medium": "thick"}],
      "lights": [{"type": "laser", "position": [0, 1, 0], "direction": [0, -1, 0], "power": 1}],
      "render": {"photons_per_pass": 20000, "radius": 0.01, "surface_radius": 0.05, "max_depth": 200, "seed": 9}})";
    auto sc = sceneFrom(json);
    PhotonPassParams pt;
    pt.photons = 200000;
    pt.maxDepth = 200;
    pt.threads = 2;
    const double t0 = nowSec();
    const PhotonMap map = tracePhotons(*sc, pt);
    const double sec = nowSec() - t0;
    double reflected = 0.0, below = 0.0;
    for (const SurfacePhoton& ph : map.photons) {
        EXPECT_TRUE(isFinite(ph.power));
        (ph.position.y > 0.0 ? reflected : below) += ph.power.x;
    }
    double deepest = 0.0;
    for (const Beam& b : map.beams) {
        EXPECT_TRUE(isFinite(b.power) && std::isfinite(b.length));
        deepest = std::max(deepest, -std::min(b.origin.y, b.origin.y + b.length * b.dir.y));
    }
    const double sigmaR = std::sqrt(albedoRef * (1.0 - albedoRef) / pt.photons);
    std::printf(
        "thick slab: reflected %.4f vs plane albedo %.4f (H(1) = %.5f); %.2f beams/photon, deepest %.3g m, "
        "%.3f s\n",
        reflected, albedoRef, H1, double(map.beams.size()) / pt.photons, deepest, sec);
    EXPECT_EQ(map.rejected, 0);
    EXPECT_EQ(below, 0.0);
    EXPECT_NEAR(reflected, albedoRef, 5.0 * sigmaR + 0.003);
    EXPECT_LT(double(map.beams.size()) / pt.photons, 4.0);  // Russian roulette on albedo 0.5
    EXPECT_LT(deepest, 1e-3);                               // a thousand mean free paths
    // The full render: finite, and quick since photons die fast.
    const double r0 = nowSec();
    Rendered r = renderScene(json, 2);
    expectFiniteFilm(r.driver->film(), "thick slab render");
    EXPECT_LT(nowSec() - r0, 10.0);
}

// Chromatic extinction spanning 12 orders of magnitude (1e6, 1, 1e-6 /m): free-flight sampling at
// the average sigma gives per-channel weights up to ~2^53 and the thin channels cannot be sampled
// through the slab at all, but nothing may turn into NaN/Inf on the film.
TEST(StabilityThickMedium, ChromaticExtinctionOverTwelveDecadesStaysFinite) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 1.5, 2], "look_at": [0, 0, 0], "fov": 50, "resolution": [16, 16]},
      "film": {"bins": 16},
      "media": {"thick": {"sigma_s": [5e5, 0.5, 5e-7], "sigma_a": [5e5, 0.5, 5e-7]}},
      "materials": {"white": {"type": "diffuse", "albedo": 0.7}, "boundary": {"type": "null"}},
      "shapes": [{"type": "box", "min": [-3, -3, -3], "max": [3, 3, 3], "material": "white", "flip_normals": true},
                 {"type": "box", "min": [-1, -1, -1], "max": [1, 0, 1], "material": "boundary", "interior_medium": "thick"}],
      "lights": [{"type": "point", "position": [0, 1, 0], "power": 5}],
      "render": {"photons_per_pass": 5000, "radius": 0.02, "surface_radius": 0.05, "max_depth": 32, "seed": 4}})";
    Rendered r = renderScene(json, 2);
    expectFiniteFilm(r.driver->film(), "chromatic thick");
}

// ---- 4. time resolution ---------------------------------------------------------------------------

// The beam pointing away from the camera (times spread over 4.8 m of real time) on films whose bins
// are far finer than an estimate's interval (1e-4 m), far wider than everything (one bin of 100 m)
// and covering only part of the arrivals (the rest must be in film.stats.outside).
TEST(StabilityTimeBins, FineCoarseAndPartialFilmsConserveEnergy) {
    LaserBox c;
    c.laser = Vec3(0.0, 0.0, -1.2);
    c.dir = Vec3(0.0, 0.0, -1.0);
    c.passes = 8;
    c.bins = 128;  // [0.475, 6.875): everything
    auto full = sceneFrom(c.json());
    const ImageIntegral ref = cylinderReference(c, full);
    // Reference mass arriving in [lo, hi) of real time (linear within the 0.05 m reference bins).
    const auto frac = [&](double lo, double hi) {
        double m = 0.0;
        for (int k = 0; k < c.bins; ++k) {
            const double t0 = c.filmStart + k * c.binWidth, t1 = t0 + c.binWidth;
            const double a = std::max(lo, t0), b = std::min(hi, t1);
            if (b > a) m += ref.bins[0][k] * (b - a) / c.binWidth;
        }
        return m;
    };
    const auto render = [&](const LaserBox& cc) {
        auto sc = sceneFrom(cc.json());
        auto run = std::make_unique<PassRunner>(sc);
        run->photons = cc.photons;
        run->radius = cc.radius;
        run->seed = cc.seed;
        run->beamLength = cc.beamLength;
        for (int p = 1; p <= cc.passes; ++p) run->run(p);
        expectFiniteFilm(run->film, "time bins");
        ImageIntegral got = imageIntegral(run->film, sc->camera);
        const double in = run->film.stats.inside[0].load(), out = run->film.stats.outside[0].load();
        return std::make_tuple(got, out / (in + out), run->film.stats.outside[1].load() / (in + out));
    };
    // Fine: 2000 bins of 1e-4 m over [3.0, 3.2) of real time. Each estimate covers up to ~1000 bins.
    {
        LaserBox f = c;
        f.filmStart = 3.0;
        f.binWidth = 1e-4;
        f.bins = 2000;
        const auto [got, outFrac, outFracUnw] = render(f);
        double inside = 0.0;
        for (double v : got.bins[0]) inside += v;
        const double refInside = frac(3.0, 3.2);
        std::printf("fine bins: inside %.5g vs %.5g; outside fraction %.4f vs %.4f\n", inside, refInside, outFrac,
                    1.0 - refInside / ref.steady);
        EXPECT_NEAR(inside, refInside, 0.02 * refInside);
        EXPECT_NEAR(outFrac, 1.0 - refInside / ref.steady, 0.01);
        EXPECT_NEAR(outFracUnw, 1.0, 1e-12);  // unwarped arrivals are all before 3.0
        // Groups of 100 fine bins against linear interpolation of the reference's mass.
        for (int gI = 0; gI < 20; ++gI) {
            double v = 0.0;
            for (int k = gI * 100; k < gI * 100 + 100; ++k) v += got.bins[0][k];
            const double lo = 3.0 + gI * 0.01;
            EXPECT_NEAR(v, frac(lo, lo + 0.01), 0.1 * frac(lo, lo + 0.01) + 1e-3 * ref.steady) << gI;
        }
    }
    // Coarse: one bin of 100 m: every estimate is far narrower than the bin.
    {
        LaserBox f = c;
        f.filmStart = 0.0;
        f.binWidth = 100.0;
        f.bins = 1;
        const auto [got, outFrac, outFracUnw] = render(f);
        EXPECT_NEAR(got.bins[0][0], got.steady, 1e-6 * got.steady);
        EXPECT_NEAR(got.bins[1][0], got.steady, 1e-6 * got.steady);
        EXPECT_NEAR(outFrac, 0.0, 1e-12);
        EXPECT_NEAR(outFracUnw, 0.0, 1e-12);
        EXPECT_NEAR(got.steady, ref.steady, 0.01 * ref.steady);
    }
    // Partial: the film covers [2.5, 4.5) of real time; before and after go to `outside`.
    {
        LaserBox f = c;
        f.filmStart = 2.5;
        f.binWidth = 0.05;
        f.bins = 40;
        const auto [got, outFrac, outFracUnw] = render(f);
        EXPECT_NEAR(outFrac, 1.0 - frac(2.5, 4.5) / ref.steady, 0.01);
        double inside = 0.0;
        for (double v : got.bins[0]) inside += v;
        EXPECT_NEAR(inside + outFrac * got.steady, got.steady, 1e-4 * got.steady);
    }
}

// ---- 5. long times ----------------------------------------------------------------------------------

// Pulse emitted at 1e4 m of OPL, bins of 1e-4 m: the laser pointing at the camera arrives at
// exactly 1e4 + 3.4 m; the film starts 50.5 bins earlier, so the first-arrival bin is 50 on the
// axis. A pixel off the axis at angle theta can get light no earlier than a path laser -> its
// ray's box entry x_e (1 m away) -> camera, 1e4 + |x_e| + |laser - x_e| ~ 1e4 + 3.4 + 0.71 theta^2
// (the causal floor, docs/developer/adding-an-estimator.md "Causality"): up to 7e-5 m later at the kernel's edge
// (theta = 0.01), past bin 50's end for the outer pixels, where its light lies at that floor. So
// each lit pixel's first bin is that of its rays' earliest arrival, exactly, 10 km into the pulse.
TEST(StabilityLongTimes, FirstArrivalBinAfterTenKilometresOfPath) {
    LaserBox c;
    c.emit = 1e4;
    c.filmStart = 1e4 + 3.4 - 50.5e-4;
    c.binWidth = 1e-4;
    c.bins = 200;
    c.passes = 4;
    auto sc = sceneFrom(c.json());
    PassRunner run(sc);
    run.photons = c.photons;
    run.radius = c.radius;
    run.beamLength = c.beamLength;
    for (int p = 1; p <= c.passes; ++p) run.run(p);
    expectFiniteFilm(run.film, "long times");
    std::vector<double> vol;
    run.film.volume(TimeAxis::Real, EmissionMode::Delta, vol);
    const Camera& cam = sc->camera;
    const TimeBins& tb = sc.time;
    // The earliest arrival through the ray at image point (u, v), via its entry into the box at z = -1.
    const auto arrival = [&](double u, double v) {
        const Ray ray = cam.generate(u, v);
        const Vec3 xe = ray.o + (-1.0 - ray.o.z) / ray.d.z * ray.d;
        return c.emit + glm::length(xe - ray.o) + glm::length(c.laser - xe);
    };
    const int B = c.bins;
    int lit = 0, onAxisBin = 0;
    for (int y = 0; y < c.res; ++y)
        for (int x = 0; x < c.res; ++x) {
            const int p = y * c.res + x;
            int first = -1, last = -1;
            for (int k = 0; k < B; ++k)
                if (vol[(static_cast<size_t>(p) * B + k) * 3] > 0.0) {
                    if (first < 0) first = k;
                    last = k;
                }
            if (first < 0) continue;
            ++lit;
            // The pixel's point nearest the image centre (the axis) and its farthest corner.
            const double h = 0.5 * c.res;
            const double tMin = arrival(std::clamp(h, double(x), x + 1.0), std::clamp(h, double(y), y + 1.0));
            const double tMax = arrival(x + 0.5 < h ? x : x + 1.0, y + 0.5 < h ? y : y + 1.0);
            EXPECT_GE(first, tb.binOf(tMin)) << "pixel " << x << "," << y;
            EXPECT_LE(first, tb.binOf(tMax)) << "pixel " << x << "," << y;
            EXPECT_LE(last, 51) << "pixel " << x << "," << y;
            if (tb.binOf(tMax) == 50) {
                EXPECT_EQ(first, 50) << "pixel " << x << "," << y;
                ++onAxisBin;
            }
        }
    std::printf("long times: %d lit pixels, %d wholly in bin 50\n", lit, onAxisBin);
    EXPECT_GT(lit, 100);
    EXPECT_GT(onAxisBin, 50);
    // Energy outside this 2 cm window: the unwarped axis (t_emit + s_b) is entirely before it.
    EXPECT_NEAR(run.film.stats.outside[0].load() / run.film.stats.inside[0].load(), 0.0, 1e-12);
}

// ---- 6. many passes -----------------------------------------------------------------------------------

// Driver::runPass(1000000) directly after a few passes: the radius follows the lgamma schedule
// (no underflow even for alpha = 0.01, r ~ 1e-3 r1), the film stays finite and its per-tile
// normalisation counts the passes; with alpha = 0.7 the image stays an unbiased estimate.
TEST(StabilityManyPasses, PassOneMillionKeepsTheFilmFiniteAndNormalised) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0.6, 0, 0], "fov": 10, "resolution": [8, 8]},
      "film": {"start_m": 2.8, "bin_width_m": 0.1, "bins": 40},
      "media": {"m": {"sigma_s": 0.4, "sigma_a": 0.1, "g": 0.3}}, "global_medium": "m",
      "materials": {"white": {"type": "diffuse", "albedo": 0.6}},
      "shapes": [{"type": "quad", "corner": [-3, -1, -3], "edge_u": [0, 0, 6], "edge_v": [6, 0, 0], "material": "white"}],
      "lights": [{"type": "point", "position": [0, 0, 0], "power": 10}],
      "render": {"photons_per_pass": 6000, "radius": 0.06, "surface_radius": 0.1, "max_depth": 4, "seed": 3}})";
    for (double alpha : {0.7, 0.01}) {
        Rendered r = renderScene(json, 0, 2, [&](RenderSettings& ds) { ds.alpha = alpha; });
        Driver& drv = *r.driver;
        for (uint64_t p : {1ull, 2ull, 3ull, 4ull}) ASSERT_TRUE(drv.runPass(p));
        std::vector<float> before;
        drv.film().steadyImage(before);
        ASSERT_TRUE(drv.runPass(1000000));
        const PassStats last = drv.lastPass();
        EXPECT_EQ(last.pass, 1000000u);
        EXPECT_DOUBLE_EQ(last.beamRadius, progressiveRadius(0.06, alpha, 1000000, 2));
        EXPECT_GT(last.beamRadius, 0.0);
        EXPECT_TRUE(std::isfinite(1.0 / (kPi * last.beamRadius * last.beamRadius)));
        if (alpha == 0.01) {
            EXPECT_LT(last.beamRadius, 2e-3 * 0.06);
        }
        EXPECT_EQ(drv.film().minPasses(), 5);
        EXPECT_EQ(drv.completedPasses(), 1000000u);
        expectFiniteFilm(drv.film(), "pass 1e6");
        std::vector<float> after;
        drv.film().steadyImage(after);
        double a = 0.0, b = 0.0;
        for (size_t i = 0; i < after.size(); i += 3) {
            a += after[i];
            b += before[i];
        }
        EXPECT_GT(a, 0.0);
        if (alpha == 0.7) {
            EXPECT_NEAR(a, b, 0.1 * b);  // mean of 5 passes vs mean of 4
        }
    }
}

// ---- 8. index of refraction ---------------------------------------------------------------------------

// A laser crosses a glass slab (thickness 0.1 m, ior 1, 1.5, 2.4, 3.5) at normal incidence, then
// a gap, then a box of fog seen by the camera (long beams: every transmitted photon stores the same
// fog beam). Light is slowed in glass: every pixel's time profile is the ior-1 profile shifted by
// (ior - 1) * 0.1 m = 0, 5, 14, 25 bins of 0.01 m, scaled by the fraction of photons transmitted
// straight through, (1 - F)^2 with F = ((n - 1) / (n + 1))^2 (internal reflections arrive too late
// for the depth limit).
TEST(StabilityIor, GlassSlabDelaysArrivalsByEtaMinusOneTimesThickness) {
    const auto json = [](double n) {
        return R"({"version": 1,
          "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov": 30, "resolution": [32, 32]},
          "film": {"start_m": 2.0, "bin_width_m": 0.01, "bins": 400},
          "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.1, "g": 0.2}},
          "materials": {"glass": {"type": "dielectric", "ior": )" +
               num(n) + R"(}, "boundary": {"type": "null"}},
          "shapes": [{"type": "box", "min": [-1.0, -0.3, -2.3], "max": [-0.9, 0.3, -1.7], "material": "glass"},
                     {"type": "box", "min": [-0.6, -0.4, -2.4], "max": [0.6, 0.4, -1.6], "material": "boundary",
                      "interior_medium": "fog"}],
          "lights": [{"type": "laser", "position": [-1.5, 0, -2.0], "direction": [1, 0, 0], "power": 1}],
          "render": {"photons_per_pass": 4000, "radius": 0.015, "alpha": 1, "seed": 2}})";
    };
    const auto render = [&](double n, std::vector<double>& vol) {
        auto sc = sceneFrom(json(n));
        PassRunner run(sc);
        run.photons = 4000;
        run.radius = 0.015;
        run.photonDepth = 3;  // glass entry, glass exit, then the fog beam (null boundaries use no depth)
        run.cameraDepth = 2;
        run.beamLength = BeamLength::Long;
        run.run(1);
        expectFiniteFilm(run.film, "glass slab");
        run.film.volume(TimeAxis::Real, EmissionMode::Delta, vol);
        return run.beams;
    };
    std::vector<double> base;
    const int64_t beams1 = render(1.0, base);
    ASSERT_EQ(beams1, 4000);  // index-matched glass: every photon goes straight through
    const int B = 400, P = 32 * 32;
    for (double n : {1.5, 2.4, 3.5}) {
        std::vector<double> vol;
        const int64_t beams = render(n, vol);
        const int shift = static_cast<int>(std::lround((n - 1.0) * 0.1 / 0.01));
        const double F = (n - 1) * (n - 1) / ((n + 1) * (n + 1));
        const double frac = double(beams) / beams1, expect = (1 - F) * (1 - F);
        EXPECT_NEAR(frac, expect, 5.0 * std::sqrt(expect * (1 - expect) / beams1)) << n;
        int lit = 0;
        for (int p = 0; p < P; ++p) {
            const double* a = &base[static_cast<size_t>(p) * B * 3];
            const double* b = &vol[static_cast<size_t>(p) * B * 3];
            int firstA = -1, firstB = -1;
            double peak = 0.0;
            for (int k = 0; k < B; ++k) {
                if (firstA < 0 && a[k * 3] > 0.0) firstA = k;
                if (firstB < 0 && b[k * 3] > 0.0) firstB = k;
                peak = std::max(peak, a[k * 3]);
            }
            if (firstA < 0) {
                EXPECT_LT(firstB, 0);
                continue;
            }
            ++lit;
            EXPECT_EQ(firstB, firstA + shift) << "ior " << n << " pixel " << p;
            for (int k = 0; k + shift < B; ++k)
                EXPECT_NEAR(b[(k + shift) * 3], frac * a[k * 3], 1e-3 * frac * peak)
                    << "ior " << n << " pixel " << p << " bin " << k;
        }
        EXPECT_GT(lit, 20);  // the fog beam's row across the image
    }
}

// Total internal reflection: a laser inside a glass block (n = 1.5, critical angle 41.8 deg) meets
// the top face at 60 deg: no photon may reach the fog above it. At 30 deg, 1 - F(30 deg) leaves.
TEST(StabilityIor, TotalInternalReflectionKeepsLightInside) {
    const auto beamsAbove = [](double angleDeg, int64_t& total) {
        const double a = angleDeg * kPi / 180.0;
        const std::string json = R"({"version": 1,
          "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "resolution": [8, 8]},
          "film": {"bins": 8},
          "media": {"fog": {"sigma_s": 1.0}},
          "materials": {"glass": {"type": "dielectric", "ior": 1.5}, "boundary": {"type": "null"}},
          "shapes": [{"type": "box", "min": [-5, -1, -5], "max": [5, 0, 5], "material": "glass"},
                     {"type": "box", "min": [-5, 0.01, -5], "max": [5, 2, 5], "material": "boundary", "interior_medium": "fog"}],
          "lights": [{"type": "laser", "position": [0, -0.5, 0], "direction": )" +
                                 vec(Vec3(std::sin(a), std::cos(a), 0.0)) + R"(, "power": 1}]})";
        auto sc = sceneFrom(json);
        EXPECT_EQ(sc->lightPlacement[0].regions.top(), 1);  // the laser sits inside the glass
        PhotonPassParams pt;
        pt.photons = 20000;
        pt.maxDepth = 2;  // glass -> top face -> gap (-> null boundary, no depth) -> fog
        const PhotonMap map = tracePhotons(*sc, pt);
        total = pt.photons;
        int64_t n = 0;
        for (const Beam& b : map.beams) n += b.region == 2;
        return n;
    };
    int64_t total = 0;
    EXPECT_EQ(beamsAbove(60.0, total), 0);
    const int64_t through = beamsAbove(30.0, total);
    const double cosT = std::sqrt(1.0 - 1.5 * 1.5 * 0.25);
    const double F = fresnelDielectric(std::cos(30.0 * kPi / 180.0), 1.5, 1.0);
    EXPECT_GT(cosT, 0.0);
    EXPECT_NEAR(double(through) / total, 1.0 - F, 5.0 * std::sqrt(F * (1 - F) / total));
}

// Light slowed in a medium: a null box whose medium has ior 1.33. The laser inside it pointing at
// the camera: every photon path is 2.4 m inside the medium and 1 m outside, so all energy of every
// pixel arrives in the one bin of t_emit + 1 + 1.33 * 2.4.
TEST(StabilityIor, SlowMediumTimeIsEtaTimesDistance) {
    for (double n : {1.0, 1.33, 2.4}) {
        LaserBox c;
        c.ior = n;
        c.bins = 200;
        c.passes = 2;
        auto sc = sceneFrom(c.json());
        PassRunner run(sc);
        run.photons = 1;
        run.radius = c.radius;
        run.beamLength = BeamLength::Long;
        for (int p = 1; p <= c.passes; ++p) run.run(p);
        expectFiniteFilm(run.film, "slow medium");
        const int k = sc.time.binOf(c.emit + 1.0 + n * 2.4);
        std::vector<double> vol;
        run.film.volume(TimeAxis::Real, EmissionMode::Delta, vol);
        double in = 0.0, other = 0.0;
        for (int p = 0; p < c.res * c.res; ++p)
            for (int b = 0; b < c.bins; ++b) (b == k ? in : other) += vol[(static_cast<size_t>(p) * c.bins + b) * 3];
        EXPECT_GT(in, 0.0) << n;
        EXPECT_EQ(other, 0.0) << n;
    }
}

// ---- 9. albedo 1 and many bounces -------------------------------------------------------------------

// In an unbounded albedo-1 medium Russian roulette never fires (the weight stays exactly Phi/N), so
// every photon runs to max_depth: exactly max_depth beams each, and the total track length
// sum(P_b len_b) = Phi max_depth / sigma_s (each free flight is exponential with mean 1/sigma_s).
TEST(StabilityAlbedoOne, InfiniteConservativeMediumRunsToMaxDepthWithConstantWeights) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [8, 8]},
      "film": {"bins": 8},
      "media": {"m": {"sigma_s": 2.0, "g": 0.5}}, "global_medium": "m",
      "lights": [{"type": "point", "position": [0, 0, 0], "power": 4}]})";
    auto sc = sceneFrom(json);
    PhotonPassParams pt;
    pt.photons = 20000;
    pt.maxDepth = 24;
    pt.threads = 2;
    const PhotonMap map = tracePhotons(*sc, pt);
    EXPECT_EQ(map.beams.size(), static_cast<size_t>(pt.photons * pt.maxDepth));
    double track = 0.0;
    for (const Beam& b : map.beams) {
        ASSERT_EQ(b.power.x, 4.0 / pt.photons);
        track += b.power.x * b.length;
    }
    const double expect = 4.0 * pt.maxDepth / 2.0;
    EXPECT_NEAR(track, expect, 5.0 * expect / std::sqrt(double(pt.photons) * pt.maxDepth));
}

// A closed diffuse box (albedo rho = 0.5) filled with an albedo-1 medium: the medium only redirects,
// so the power landing on the walls (surface photons store it at every landing) sums to
// Phi (1 + rho + rho^2 + ...) = 2 Phi, and every stored weight stays Phi/N (roulette at the walls).
// With white walls (albedo 1) too, nothing is ever absorbed: every photon runs to max_depth, the
// weights stay exactly Phi/N and the stored energy per photon is bounded by 2 max_depth Phi/N.
TEST(StabilityAlbedoOne, ClosedBoxFurnace) {
    const auto json = [](double albedo) {
        return R"({"version": 1,
          "camera": {"position": [0, 0, 0.9], "look_at": [0, 0, 0], "fov": 60, "resolution": [16, 16]},
          "film": {"start_m": 0, "bin_width_m": 0.25, "bins": 32},
          "media": {"m": {"sigma_s": 2.0}}, "global_medium": "m",
          "materials": {"wall": {"type": "diffuse", "albedo": )" +
               num(albedo) + R"(}},
          "shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": "wall", "flip_normals": true}],
          "lights": [{"type": "point", "position": [0.2, 0.1, -0.3], "power": 2}],
          "render": {"photons_per_pass": 4000, "radius": 0.03, "surface_radius": 0.08, "max_depth": 48, "seed": 8}})";
    };
    {
        auto sc = sceneFrom(json(0.5));
        PhotonPassParams pt;
        pt.photons = 50000;
        pt.maxDepth = 1000;
        // The throughput roulette alone: the deep rule (from 64 events on, which a few of these
        // photons reach) divides by 0.95 and is tested in test_photon_tracer.
        pt.rouletteDepth = std::numeric_limits<int>::max();
        pt.threads = 2;
        const PhotonMap map = tracePhotons(*sc, pt);
        double landed = 0.0;
        for (const SurfacePhoton& ph : map.photons) {
            ASSERT_DOUBLE_EQ(ph.power.x, 2.0 / pt.photons);
            landed += ph.power.x;
        }
        std::printf("furnace: landed %.4f Phi (expect 2), %.2f events/photon\n", landed / 2.0,
                    double(map.beams.size() + map.photons.size()) / pt.photons);
        EXPECT_NEAR(landed / 2.0, 2.0, 5.0 * std::sqrt(2.0 / pt.photons));
    }
    {
        auto sc = sceneFrom(json(1.0));
        PhotonPassParams pt;
        pt.photons = 4000;
        pt.maxDepth = 48;
        pt.threads = 2;
        const PhotonMap map = tracePhotons(*sc, pt);
        const size_t events = map.beams.size() + map.photons.size();
        EXPECT_GE(events, static_cast<size_t>(pt.photons * pt.maxDepth));      // one beam or landing per level
        EXPECT_LE(events, static_cast<size_t>(2 * pt.photons * pt.maxDepth));  // at most both
        for (const Beam& b : map.beams) ASSERT_EQ(b.power.x, 2.0 / pt.photons);
        for (const SurfacePhoton& ph : map.photons) ASSERT_EQ(ph.power.x, 2.0 / pt.photons);
        const double t0 = nowSec();
        Rendered r = renderScene(json(1.0), 2);
        expectFiniteFilm(r.driver->film(), "white furnace");
        EXPECT_LT(nowSec() - t0, 15.0);
        EXPECT_LE(r.passes[0].beams, 4000 * 48);
    }
}

namespace {

// Renders with `ds` and expects the pass to stop with a UserError that names render.photons_per_pass,
// the memory limit of 4 MiB and `what`, before any pass completed; returns its message.
std::string expectMemoryStop(const test::TestScene& sc, const RenderSettings& ds, const std::string& what) {
    Driver drv(*sc, ds, sc.time);
    drv.start();
    drv.wait();
    EXPECT_TRUE(drv.failure());
    if (!drv.failure()) return "";
    EXPECT_THROW(std::rethrow_exception(drv.failure()), UserError);
    const std::string msg = drv.failureMessage();
    for (const std::string& part : {std::string("render.photons_per_pass"), std::string("4.00 MiB"), what})
        EXPECT_NE(msg.find(part), std::string::npos) << msg;
    EXPECT_EQ(drv.completedPasses(), 0u);
    EXPECT_FALSE(drv.running());
    std::vector<float> img;
    drv.film().steadyImage(img);
    for (float v : img) EXPECT_EQ(v, 0.0f);
    return msg;
}

// Renders with `ds` and expects every pass to complete, with a finite film; returns the last pass's stats.
PassStats expectRenders(const test::TestScene& sc, const RenderSettings& ds, uint64_t passes) {
    Driver ok(*sc, ds, sc.time);
    ok.start();
    ok.wait();
    EXPECT_FALSE(ok.failure()) << ok.failureMessage();
    EXPECT_EQ(ok.completedPasses(), passes);
    expectFiniteFilm(ok.film(), "within the memory budget");
    return ok.lastPass();
}

}  // namespace

// A pass that cannot be done (the photon map of an albedo-1 box with a huge max_depth outgrows the
// memory budget) must not take the process down: the photon tracer throws UserError on a worker
// thread, parallelFor carries it to the driver thread, the driver records it and stops, and the
// film keeps what the finished passes gave (here: none, so it stays exactly zero).
TEST(StabilityAlbedoOne, PhotonMapOverTheMemoryBudgetStopsTheRenderWithAMessage) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 0.9], "look_at": [0, 0, 0], "fov": 60, "resolution": [8, 8]},
      "film": {"start_m": 0, "bin_width_m": 0.25, "bins": 8},
      "media": {"m": {"sigma_s": 2.0}}, "global_medium": "m",
      "materials": {"wall": {"type": "diffuse", "albedo": 1}},
      "shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": "wall", "flip_normals": true}],
      "lights": [{"type": "point", "position": [0.2, 0.1, -0.3], "power": 2}],
      "render": {"photons_per_pass": 2000, "max_depth": 100000000, "passes": 3, "seed": 8}})";
    auto sc = sceneFrom(json);
    RenderSettings ds = sc.settings;
    ds.threads = 2;
    // 4 MiB: about 40k beams, while the pass stores ~2000 x 105 (the deep roulette ends each photon
    // after 83 events on average, transport/interaction.h; before it, one photon alone stored 1e8).
    ds.maxPhotonMapBytes = 4u << 20;
    const double t0 = nowSec();
    expectMemoryStop(sc, ds, "max_depth");
    EXPECT_LT(nowSec() - t0, 30.0);

    // Within the budget the same scene renders: max_depth 48 stores at most 2 x 48 events per photon
    // (2000 x 96 x ~100 B = 19 MB). A fixed radius: the automatic one, measured now that the pilot's
    // photons end (it used to outgrow its 64 MiB and fall back to 1 % of the diagonal), cuts the
    // beams into pieces whose accelerator would pass the limit.
    ds.maxDepth = 48;
    ds.maxPhotonMapBytes = 64u << 20;
    ds.beamRadius0 = 0.035;
    ds.surfaceRadius0 = 0.07;
    expectRenders(sc, ds, 3);
}

// The accelerator counts against the same memory limit as the photon map, before it is built: long
// beams and a tiny kernel radius cut every beam into 16 pieces, whose index would take far more
// than the beams themselves (kAccelBytesPerPiece). The pass stops with a message naming the
// accelerator and the limit; with the limit raised the same scene renders.
TEST(StabilityAlbedoOne, AcceleratorOverTheMemoryBudgetStopsTheRenderWithAMessage) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 4.5], "look_at": [0, 0, 0], "fov": 60, "resolution": [8, 8]},
      "film": {"start_m": 0, "bin_width_m": 1, "bins": 8},
      "media": {"m": {"sigma_s": 0.05}}, "global_medium": "m",
      "materials": {"wall": {"type": "diffuse", "albedo": 0.5}},
      "shapes": [{"type": "box", "min": [-5, -5, -5], "max": [5, 5, 5], "material": "wall", "flip_normals": true}],
      "lights": [{"type": "point", "position": [0.2, 0.1, -0.3], "power": 2}],
      "render": {"photons_per_pass": 2000, "max_depth": 4, "passes": 2, "seed": 8}})";
    auto sc = sceneFrom(json);
    RenderSettings ds = sc.settings;
    ds.threads = 2;
    ds.volumeEstimator = "beam2d";
    ds.beamRadius0 = 0.001;           // pieces of 16 mm: beams of metres are cut in 16
    ds.maxPhotonMapBytes = 4u << 20;  // the beams (~2000 x 4 x ~100 B) fit; 16 pieces each do not
    expectMemoryStop(sc, ds, "accelerator");

    ds.maxPhotonMapBytes = 256u << 20;
    const PassStats last = expectRenders(sc, ds, 2);
    EXPECT_GT(last.beamPieces, 8 * last.beams);  // the case is what it says: many pieces per beam
}

// parallelFor rethrows a worker's exception on the calling thread after joining every worker, and
// stops handing out work: it must never reach std::terminate.
TEST(StabilityFaults, ParallelForRethrowsAWorkersExceptionOnTheCallingThread) {
    for (int threads : {1, 2, 4}) {
        SCOPED_TRACE(threads);
        std::atomic<int64_t> ran{0};
        EXPECT_THROW(parallelFor(100000, threads,
                                 [&](int64_t i, int) {
                                     ++ran;
                                     if (i == 37) throw std::runtime_error("item 37");
                                 }),
                     std::runtime_error);
        EXPECT_GE(ran.load(), 38);
        EXPECT_LT(ran.load(), 100000);  // the other items were not all run after the failure
    }
}

// ---- 10. degenerate input -------------------------------------------------------------------------

// An OBJ floor with zero-area triangles (repeated vertex, collinear vertices, a needle of 1e-300
// height) renders exactly like the clean floor: the degenerate triangles are dropped.
TEST(StabilityDegenerate, ZeroAreaTrianglesAreHarmless) {
    const test::TempDir tmp("stability_degenerate");
    const fs::path& dir = tmp.path();
    std::ofstream(dir / "clean.obj") << "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\nf 1 4 3\n";
    std::ofstream(dir / "dirty.obj") << "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nv 0 0 0\nv 1 0 1\nv 0.5 1e-300 0.5\n"
                                        "f 1 3 2\nf 5 5 6\nf 1 4 3\nf 5 6 1\nf 1 3 5\nf 5 6 7\nf 2 2 2\n";
    const auto json = [&](const std::string& obj) {
        return R"({"version": 1,
          "camera": {"position": [0, 1, 2], "look_at": [0, 0, 0], "fov": 50, "resolution": [16, 16]},
          "film": {"start_m": 1.5, "bin_width_m": 0.1, "bins": 30},
          "media": {"fog": {"sigma_s": 0.2}}, "global_medium": "fog",
          "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
          "shapes": [{"type": "mesh", "file": ")" +
               (dir / obj).string() + R"(", "material": "white"}],
          "lights": [{"type": "point", "position": [0.3, 0.8, 0.2], "power": 10}],
          "render": {"photons_per_pass": 3000, "radius": 0.03, "surface_radius": 0.05, "max_depth": 4, "seed": 5}})";
    };
    Rendered a = renderScene(json("clean.obj"), 2), b = renderScene(json("dirty.obj"), 2);
    expectFiniteFilm(b.driver->film(), "degenerate triangles");
    std::vector<double> va, vb;
    a.driver->film().volume(TimeAxis::Real, EmissionMode::Delta, va);
    b.driver->film().volume(TimeAxis::Real, EmissionMode::Delta, vb);
    EXPECT_EQ(va, vb);
    EXPECT_GT(std::accumulate(va.begin(), va.end(), 0.0), 0.0);
}

// A point light at the centre of a glass sphere (n = 1.5, R = 0.5) in fog: the light's region is
// the sphere's inside, so no beam is stored inside the sphere, every photon leaves radially
// (normal incidence) and its first fog beam starts on the sphere at OPL t_emit + n R.
TEST(StabilityDegenerate, LightInsideAGlassSphere) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 50, "resolution": [16, 16]},
      "film": {"start_m": 2.5, "bin_width_m": 0.1, "bins": 40},
      "media": {"fog": {"sigma_s": 0.3, "sigma_a": 0.05}}, "global_medium": "fog",
      "materials": {"glass": {"type": "dielectric", "ior": 1.5}},
      "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "glass"}],
      "lights": [{"type": "point", "position": [0, 0, 0], "power": 10, "emit_time_m": 1.0}],
      "render": {"photons_per_pass": 4000, "radius": 0.03, "max_depth": 6, "seed": 5}})";
    auto sc = sceneFrom(json);
    ASSERT_EQ(sc->lightPlacement.size(), 1u);
    EXPECT_EQ(sc->lightPlacement[0].regions.size, 2);
    EXPECT_EQ(sc->lightPlacement[0].regions.top(), 1);
    EXPECT_EQ(sc->cameraRegions.top(), 0);
    PhotonPassParams pt;
    pt.photons = 20000;
    pt.maxDepth = 2;
    const PhotonMap map = tracePhotons(*sc, pt);
    const double F0 = 0.04;  // ((1.5 - 1) / (1.5 + 1))^2
    int64_t first = 0;
    for (const Beam& b : map.beams) {
        EXPECT_EQ(b.region, 0);
        EXPECT_EQ(b.depth, 1u);  // depth 0 is the glass interior: never a beam
        EXPECT_NEAR(glm::length(b.origin), 0.5, 1e-4);
        EXPECT_NEAR(glm::dot(b.dir, glm::normalize(b.origin)), 1.0, 1e-9);
        EXPECT_NEAR(b.opl0, 1.0 + 1.5 * 0.5, 2e-4);
        ++first;
    }
    EXPECT_NEAR(double(first) / pt.photons, 1.0 - F0, 5.0 * std::sqrt(F0 * (1 - F0) / pt.photons));
    Rendered r = renderScene(json, 2);
    expectFiniteFilm(r.driver->film(), "light in glass");
    std::vector<float> steady;
    r.driver->film().steadyImage(steady);
    EXPECT_GT(std::accumulate(steady.begin(), steady.end(), 0.0), 0.0);
}

// No lights: black, no crash. No medium: no beams at all.
TEST(StabilityDegenerate, NoLightsAndNoMedia) {
    const std::string noLights = R"({"version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [16, 16]},
      "film": {"bins": 8},
      "media": {"fog": {"sigma_s": 0.3}}, "global_medium": "fog",
      "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
      "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "white"}],
      "render": {"photons_per_pass": 1000}})";
    Rendered a = renderScene(noLights, 2);
    expectFiniteFilm(a.driver->film(), "no lights");
    EXPECT_EQ(a.passes[0].beams, 0);
    EXPECT_EQ(a.passes[0].surfacePhotons, 0);
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped}) {
        std::vector<double> vol;
        a.driver->film().volume(axis, EmissionMode::Delta, vol);
        EXPECT_EQ(std::count(vol.begin(), vol.end(), 0.0), static_cast<std::ptrdiff_t>(vol.size()));
    }
    // A light of zero power is never picked: same as no light.
    std::string zero = noLights;
    zero.replace(zero.find("\"render\""), 0, R"("lights": [{"type": "point", "position": [0, 1, 0], "power": 0}], )");
    Rendered z = renderScene(zero, 1);
    EXPECT_EQ(z.passes[0].beams, 0);
    expectFiniteFilm(z.driver->film(), "zero-power light");

    const std::string noMedia = R"({"version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [16, 16]},
      "film": {"bins": 8},
      "materials": {"white": {"type": "diffuse", "albedo": 0.8}, "glass": {"type": "dielectric"}},
      "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "white"},
                 {"type": "sphere", "center": [0.8, 0, 0], "radius": 0.3, "material": "glass"},
                 {"type": "quad", "corner": [-2, -0.5, -2], "edge_u": [0, 0, 4], "edge_v": [4, 0, 0], "material": "white"}],
      "lights": [{"type": "point", "position": [0, 1.5, 1], "power": 10}],
      "render": {"photons_per_pass": 2000}})";
    Rendered b = renderScene(noMedia, 2);
    EXPECT_FALSE(b.scene->stages.beams);
    for (const PassStats& p : b.passes) {
        EXPECT_EQ(p.beams, 0);
        EXPECT_EQ(p.beamPieces, 0);
        EXPECT_EQ(p.camera.beamEstimates, 0);
        EXPECT_GT(p.surfacePhotons, 0);
    }
    expectFiniteFilm(b.driver->film(), "no media");
}

// The camera inside a medium box (null boundary) with a point light: camera rays start in the
// medium (scene.cameraRegions) and gather from their origin. Reference: single scattering along
// each ray up to the box wall,
//   L = int_0^{s_exit} sigma_s e^{-sigma_t s} p(cos) Phi / (4 pi d^2) e^{-sigma_t d} ds.
TEST(StabilityDegenerate, CameraInsideAMediumBox) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 1.5], "look_at": [0.4, 0, 0], "fov": 12, "resolution": [6, 6]},
      "film": {"start_m": 1.0, "bin_width_m": 0.1, "bins": 40},
      "media": {"m": {"sigma_s": 0.4, "sigma_a": 0.1, "g": 0.3}},
      "materials": {"boundary": {"type": "null"}},
      "shapes": [{"type": "box", "min": [-2, -2, -2], "max": [2, 2, 2], "material": "boundary", "interior_medium": "m"}],
      "lights": [{"type": "point", "position": [0, 0, 0], "power": 10}]})";
    auto sc = sceneFrom(json);
    EXPECT_EQ(sc->cameraRegions.top(), 1);
    EXPECT_EQ(sc->lightPlacement[0].regions.top(), 1);
    PassRunner run(sc);
    run.photons = 4000;
    run.radius = 0.06;
    run.photonDepth = 1;
    run.cameraDepth = 1;  // no boundary to cross: the gather happens at depth 0
    for (int p = 1; p <= 24; ++p) run.run(p);
    expectFiniteFilm(run.film, "camera in medium");
    std::vector<float> steady;
    run.film.steadyImage(steady);
    const Medium& m = sc->regions[1].medium;
    double err = 0.0, norm = 0.0;
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 6; ++x) {
            double ref = 0.0;
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) {
                    const Ray ray = sc->camera.generate(x + (i + 0.5) / 4, y + (j + 0.5) / 4);
                    double a0, a1;
                    boxInterval(ray.o, ray.d, Vec3(-2.0), Vec3(2.0), a0, a1);
                    const int n = 20000;
                    const double h = a1 / n;
                    for (int k = 0; k < n; ++k) {
                        const double s = (k + 0.5) * h;
                        const Vec3 v = ray.at(s);
                        const double d = glm::length(v);
                        ref += m.sigma_s.x * std::exp(-m.sigma_t.x * (s + d)) * m.phase.eval(glm::dot(v / d, -ray.d)) *
                               10.0 / (4.0 * kPi * d * d) * h / 16.0;
                    }
                }
            const double got = steady[(y * 6 + x) * 3];
            err += (got - ref) * (got - ref);
            norm += ref * ref;
        }
    std::printf("camera inside medium box: relative RMSE %.4f\n", std::sqrt(err / norm));
    EXPECT_LT(std::sqrt(err / norm), 0.05);
}

// Hand-made beams of zero length, zero power, 1e-300 m, 1e12 m and pointing exactly at the camera
// through the Embree and brute-force queries: finite, and the degenerate ones add exactly nothing.
TEST(StabilityDegenerate, ZeroLengthAndZeroPowerBeams) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov": 10, "resolution": [16, 16]},
      "film": {"start_m": 0, "bin_width_m": 0.1, "bins": 60},
      "media": {"m": {"sigma_s": 0.5, "sigma_a": 0.1}}, "global_medium": "m",
      "lights": [{"type": "point", "position": [0, 0, -2], "power": 1}]})";
    auto sc = sceneFrom(json);
    const auto render = [&](const std::vector<Beam>& beams, AccelBackend kind, std::vector<double>& vol) {
        PhotonMap map;
        map.beams = beams;
        Beam2DEstimator beam2d;
        EstimatorPass ep;
        ep.radius = 0.02;
        ep.accel = kind;
        beam2d.prepare(*sc, map, ep);
        CameraPassEstimators est;
        if (!beam2d.empty()) est.volume = &beam2d;
        TransientFilm film(16, 16, sc.time);
        CameraPassParams cs;
        CameraPassScratch scratch;
        scratch.acc.reset(film.bins());
        CameraPassStats stats;
        for (int t = 0; t < film.tileCount(); ++t) renderTile(*sc, est, cs, film, t, scratch, stats);
        stats.flushInto(film.stats);
        expectFiniteFilm(film, "hand-made beams");
        film.volume(TimeAxis::Real, EmissionMode::Delta, vol);
    };
    const Color P(0.01);
    const std::vector<Beam> good = {
        {Vec3(-0.3, 0.05, -2.0), Vec3(1, 0, 0), 0.6, P, 0.0, 0, 1},                      // perpendicular
        {Vec3(0.0, 0.0, -3.0), Vec3(0, 0, 1), 2.0, P, 0.0, 0, 1},                        // at the camera
        {Vec3(0.02, -0.3, -2.5), glm::normalize(Vec3(0, 1, 1e-9)), 1e12, P, 0.0, 0, 1},  // 1e12 m
    };
    std::vector<Beam> all = good;
    all.push_back({Vec3(0.0, 0.0, -2.0), Vec3(1, 0, 0), 0.0, P, 0.0, 0, 1});               // zero length
    all.push_back({Vec3(0.0, 0.0, -2.0), Vec3(0, 0, 1), 1e-300, P, 0.0, 0, 1});            // 1e-300 m
    all.push_back({Vec3(0.0, 0.0, -2.5), Vec3(0, 1, 0), 1.0, Color(0.0), 0.0, 0, 1});      // zero power
    all.push_back({Vec3(0.0, -0.5, -2.5), Vec3(0, 1, 0), 1.0, Color(1e-300), 0.0, 0, 1});  // denormal result
    for (AccelBackend kind : {AccelBackend::Embree, AccelBackend::BruteForce, AccelBackend::Bvh}) {
        std::vector<double> a, b;
        render(good, kind, a);
        render(all, kind, b);
        EXPECT_GT(std::accumulate(a.begin(), a.end(), 0.0), 0.0);
        ASSERT_EQ(a.size(), b.size());
        for (size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i], b[i], 1e-12 * (1.0 + a[i])) << i;
    }
}

// ---- the viewer's access pattern while the driver runs -----------------------------------------

// One thread reads the film the way the viewer does (snapshots: frame, steady image, and
// pixelProfile/streak on a helper thread, history(), lastPass(), completedPasses()) while
// Driver::start renders, pauses, resumes and stops. Everything read must be finite, per-tile pass
// counts never go backwards, and history() is consistent with completedPasses(). Run under
// ThreadSanitizer by tools/sanitize thread.
TEST(StabilityConcurrent, ViewerReadsWhileTheDriverRenders) {
    const std::string json = R"({"version": 1,
      "camera": {"position": [0, 1, 3.5], "look_at": [0, 1, 0], "fov": 40, "resolution": [40, 24]},
      "film": {"start_m": 2, "bin_width_m": 0.1, "bins": 24},
      "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.05, "g": 0.2}}, "global_medium": "fog",
      "materials": {"white": {"type": "diffuse", "albedo": 0.7}, "glass": {"type": "dielectric", "ior": 1.5}},
      "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true},
                 {"type": "sphere", "center": [-0.4, 0.5, 0], "radius": 0.35, "material": "glass"}],
      "lights": [{"type": "point", "position": [0, 1.8, 0], "power": 20}],
      "render": {"photons_per_pass": 1500, "radius_relative": 0.01, "surface_radius_relative": 0.03, "seed": 9}})";
    auto sc = sceneFrom(json);
    RenderSettings ds = sc.settings;
    ds.threads = 2;
    ds.passes = 0;  // until stopped
    Driver drv(*sc, ds, sc.time);
    std::atomic<int> callbacks{0};
    std::atomic<bool> done{false};
    std::atomic<int64_t> badValues{0}, reads{0};
    const auto finite = [&](const std::vector<float>& v) {
        for (float x : v)
            if (!(std::isfinite(x) && x >= 0.0f)) {
                ++badValues;
                return;
            }
    };
    drv.start([&](const PassStats& p) {
        EXPECT_GT(p.pass, 0u);
        ++callbacks;
    });
    std::thread helper([&] {  // the viewer's helper thread: profile and streak of a pixel
        std::vector<float> prof, streak;
        while (!done) {
            const auto snap = drv.snapshot();
            prof = pixelProfile(*snap, 7, 5, TimeAxis::Real, EmissionMode::Continuous);
            streak = streakImage(*snap, 5, TimeAxis::Unwarped, EmissionMode::Delta);
            finite(prof);
            finite(streak);
            ++reads;
        }
    });
    std::vector<float> frame;
    uint64_t lastCompleted = 0;
    int iter = 0;
    while (drv.completedPasses() < 8 || iter < 50) {
        const int k = iter % 24;
        const auto snap = drv.snapshot();
        frame = frameImage(*snap, k, iter % 2 ? TimeAxis::Real : TimeAxis::Unwarped,
                           iter % 3 ? EmissionMode::Delta : EmissionMode::Continuous);
        finite(frame);
        frame = steadyImage(*snap);
        finite(frame);
        const uint64_t completed = drv.completedPasses();
        EXPECT_GE(completed, lastCompleted);
        lastCompleted = completed;
        const std::vector<PassStats> hist = drv.history();  // pushed before completedPasses() moves on
        EXPECT_GE(hist.size(), completed);
        for (size_t i = 0; i < hist.size(); ++i) EXPECT_EQ(hist[i].pass, i + 1);
        (void)drv.lastPass();
        if (iter == 20) drv.pause();
        if (iter == 30) drv.resume();
        ++iter;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        ASSERT_LT(iter, 200000) << "the driver made no progress";
    }
    drv.stop();
    done = true;
    helper.join();
    EXPECT_FALSE(drv.running());
    EXPECT_GE(callbacks.load(), 8);
    EXPECT_EQ(badValues.load(), 0);
    EXPECT_GT(reads.load(), 0);
    EXPECT_EQ(drv.history().size(), drv.completedPasses());
    expectFiniteFilm(drv.film(), "after concurrent reads");
    // stop() finishes the tile in progress: every tile holds the completed passes (the tiles of an
    // aborted pass may hold one more).
    EXPECT_GE(drv.film().minPasses(), static_cast<int64_t>(drv.completedPasses()));
}
