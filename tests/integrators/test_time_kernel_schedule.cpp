// The progressive time kernel's schedule (integrators/time_kernel_schedule.h, photon_beams.cpp):
// radius and half-width follow i^{-(1 - alpha) / D} with D = dim + 1 when the kernel is on (dim when
// off, unchanged), the default width 2 eta_max r_1 (capped at the film's range), the passes' stats,
// and that the film check (RenderSettings::validateAgainstFilm) never refuses the default width.
#include "base/error.h"
#include "integrators/photon_beams.h"
#include "integrators/time_kernel_schedule.h"
#include "render/driver.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tpb;

namespace {

// A foggy box with a glass sphere: a scattering medium of index 1.33, glass 1.5.
const char* kScene = R"({
  "version": 1,
  "camera": {"position": [0, 1, 3.5], "look_at": [0, 1, 0], "fov": 40, "resolution": [16, 16]},
  "film": {"start_m": 2.0, "bin_width_m": 0.05, "bins": 100},
  "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.05, "g": 0.2, "ior": 1.33}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.7}, "glass": {"type": "dielectric", "ior": 1.5}},
  "shapes": [
    {"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true},
    {"type": "sphere", "center": [-0.4, 0.5, 0], "radius": 0.35, "material": "glass"}
  ],
  "lights": [{"type": "point", "position": [0, 1.8, 0], "power": 20}],
  "render": {"photons_per_pass": 500, "radius": 0.03, "surface_radius": 0.05, "alpha": 0.7, "seed": 2}
})";

double logSlope(double f1, double f2, double i1, double i2) { return std::log(f2 / f1) / std::log(i2 / i1); }

}  // namespace

TEST(TimeKernelSchedule, OffLeavesTheRadiusScheduleUnchanged) {
    auto sc = test::testSceneFrom(kScene);
    const PhotonBeamsIntegrator pb(*sc, sc.settings);
    const TimeKernelSchedule k = pb.timeKernels(sc.time);
    EXPECT_FALSE(k.volume.on);
    EXPECT_FALSE(k.surface.on);
    for (uint64_t i : {1ull, 2ull, 17ull, 1000ull, 1000000ull}) {
        EXPECT_EQ(pb.beamRadius(i), progressiveRadius(0.03, 0.7, i, 2));
        EXPECT_EQ(pb.surfaceRadius(i), progressiveRadius(0.05, 0.7, i, 2));
        EXPECT_FALSE(k.volume.kernel(i).active());
        EXPECT_FALSE(k.surface.kernel(i).active());
    }
}

TEST(TimeKernelSchedule, RadiusAndHalfWidthShrinkAsIToTheMinusOneMinusAlphaOverD) {
    auto sc = test::testSceneFrom(kScene);
    for (double alpha : {0.5, 0.7, 4.0 / 7.0}) {
        RenderSettings s = sc.settings;
        s.alpha = alpha;
        s.timeKernel = {TimeKernelKind::Box, 0.0};
        const PhotonBeamsIntegrator pb(*sc, s);
        const TimeKernelSchedule k = pb.timeKernels(sc.time);
        ASSERT_TRUE(k.volume.on);
        EXPECT_EQ(k.volume.dim(), 3);   // beam2d: 2 + 1
        EXPECT_EQ(k.surface.dim(), 3);  // ppm: 2 + 1
        const double tau1 = k.volume.kernel(1).halfWidth, r1 = pb.beamRadius(1);
        EXPECT_EQ(r1, 0.03);
        for (uint64_t i : {2ull, 10ull, 1000ull, 100000ull}) {
            // r and tau at the same rate; r^d tau shrinks by (i + alpha) / (i + 1) per pass.
            EXPECT_NEAR(k.volume.kernel(i).halfWidth / tau1, pb.beamRadius(i) / r1, 1e-14);
            const double measure = std::pow(pb.beamRadius(i), 2) * k.volume.kernel(i).halfWidth;
            const double next = std::pow(pb.beamRadius(i + 1), 2) * k.volume.kernel(i + 1).halfWidth;
            // (lgamma's rounding: ~1e-16 of lgamma(i) ~ i log i, in the exponent)
            const double tol = 1e-13 + 1e-15 * i * std::log(static_cast<double>(i));
            EXPECT_NEAR(next / measure, (i + alpha) / (i + 1.0), tol) << i;
            EXPECT_EQ(k.volume.radius(i), pb.beamRadius(i));
            EXPECT_EQ(k.surface.radius(i), pb.surfaceRadius(i));
        }
        // Asymptotically i^{-(1 - alpha) / D}: the log-slope between 1e5 and 1e7 passes.
        const double expected = -(1.0 - alpha) / 3.0;
        EXPECT_NEAR(logSlope(pb.beamRadius(100000), pb.beamRadius(10000000), 1e5, 1e7), expected, 1e-5);
        EXPECT_NEAR(logSlope(k.surface.kernel(100000).halfWidth, k.surface.kernel(10000000).halfWidth, 1e5, 1e7),
                    expected, 1e-5);
        // Off: D = 2, the faster shrink.
        EXPECT_NEAR(
            logSlope(progressiveRadius(0.03, alpha, 100000, 2), progressiveRadius(0.03, alpha, 10000000, 2), 1e5, 1e7),
            -(1.0 - alpha) / 2.0, 1e-5);
    }
}

TEST(TimeKernelSchedule, DefaultWidthIsTheTimeToCrossThePassOneKernel) {
    auto sc = test::testSceneFrom(kScene);
    EXPECT_DOUBLE_EQ(maxIndexOfRefraction(*sc, true), 1.33);  // the fog
    EXPECT_DOUBLE_EQ(maxIndexOfRefraction(*sc, false), 1.5);  // the glass too
    RenderSettings s = sc.settings;
    s.timeKernel = {TimeKernelKind::Box, 0.0};
    const TimeKernelSchedule k = timeKernelSchedule(*sc, s, sc.time);
    EXPECT_TRUE(k.volume.widthFromScene);
    EXPECT_DOUBLE_EQ(k.volume.width1, 2.0 * 1.33 * 0.03);
    EXPECT_DOUBLE_EQ(k.surface.width1, 2.0 * 1.5 * 0.05);
    EXPECT_DOUBLE_EQ(k.volume.kernel(1).halfWidth, 1.33 * 0.03);
    // At most the film's time range; eta below 1 counts as 1.
    EXPECT_DOUBLE_EQ(defaultTimeKernelWidth(0.5, 1.2, 0.7), 0.7);
    EXPECT_DOUBLE_EQ(defaultTimeKernelWidth(0.01, 1.0, 0.0), 0.02);
    // An explicit width is used as given, for both estimators.
    s.timeKernel.width = 0.08;
    const TimeKernelSchedule e = timeKernelSchedule(*sc, s, sc.time);
    EXPECT_FALSE(e.volume.widthFromScene);
    EXPECT_EQ(e.volume.width1, 0.08);
    EXPECT_EQ(e.surface.width1, 0.08);
}

TEST(TimeKernelSchedule, PassStatsReportEachEstimatorsHalfWidth) {
    auto sc = test::testSceneFrom(kScene);
    RenderSettings s = sc.settings;
    s.threads = 2;
    s.timeKernel = {TimeKernelKind::Box, 0.0};
    Driver drv(*sc, s, sc.time);
    for (int p = 1; p <= 3; ++p) ASSERT_TRUE(drv.runPass(p));
    const TimeKernelSchedule k = timeKernelSchedule(*sc, s, sc.time);
    const std::vector<PassStats> h = drv.history();
    ASSERT_EQ(h.size(), 3u);
    for (const PassStats& ps : h) {
        EXPECT_EQ(ps.volumeTimeHalfWidth, k.volume.kernel(ps.pass).halfWidth);
        EXPECT_EQ(ps.surfaceTimeHalfWidth, k.surface.kernel(ps.pass).halfWidth);
        EXPECT_EQ(ps.beamRadius, k.volume.radius(ps.pass));
        EXPECT_GT(ps.volumeTimeHalfWidth, 0.0);
    }
    EXPECT_LT(h[2].volumeTimeHalfWidth, h[0].volumeTimeHalfWidth);
}

TEST(TimeKernelSchedule, TheDefaultWidthIsNeverRefusedByTheFilmCheck) {
    // validateAgainstFilm (render_settings.h) refuses an explicit width above the film's range; the
    // default is capped at the range, so "box" alone always passes, even with a huge radius.
    auto sc = test::testSceneFrom(kScene);  // range 5 m
    const double range = sc.time.binWidth * sc.time.bins;
    RenderSettings s = sc.settings;
    s.timeKernel = {TimeKernelKind::Box, 0.0};
    s.surfaceRadius0 = 4.0;  // 2 eta r_1 = 12 m > 5 m
    EXPECT_NO_THROW(s.validateAgainstFilm(range, {}));
    const TimeKernelSchedule k = timeKernelSchedule(*sc, s, sc.time);
    EXPECT_DOUBLE_EQ(k.surface.width1, range);
    s.timeKernel = {TimeKernelKind::Box, 4.9};
    EXPECT_NO_THROW(s.validateAgainstFilm(range, {}));
    s.timeKernel = {TimeKernelKind::Box, 5.5};
    EXPECT_THROW(s.validateAgainstFilm(range, {}), UserError);
}
