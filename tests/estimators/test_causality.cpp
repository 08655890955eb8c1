// Causality of every estimator (issue 33, item 9; docs/developer/adding-an-estimator.md, "Causality"): no estimate
// arrives earlier than a real path through its photon could, so the bins before the geometric
// first arrival stay exactly empty, with and without the progressive time kernel.
//
// Volume: a point-light pulse in an unbounded fog (eta = 1.2) seen by a camera 2 m away inside the
// fog. Any path light -> y -> camera has OPL >= eta (|y - L| + |y - C|) >= eta D: on the real axis
// every pixel's first arrival is eta D (scattering at the lens). The unwarped axis takes the time
// of a photon within r of the pixel's rays (up to eta r before light reaches the rays) and its
// floor allows the light another r of reach: nothing before eta (d_P - 2 r), d_P the distance
// from the light to the pixel's rays (stated and bounded: docs/developer/adding-an-estimator.md).
// Surface: a point light and a camera in vacuum in front of a wall; every path light -> wall ->
// camera is at least |C - L'| long (L' the light mirrored in the wall's plane), and reaches the
// wall no earlier than its distance from the light (1 m).
// The films' bins are fine (1 cm) and their start offset so that a first arrival lies inside a bin:
// every bin ending at or before it must hold exactly 0. Before the causal floor point3d put light
// up to eta r early (about eta r / 2 on the default kernel), ppm up to r and the box kernel its
// half-width early.
#include "render/driver.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace tpb;

namespace {

constexpr double kEta = 1.2, kDistance = 2.0, kRadius = 0.1;

// Light at the origin, camera 2 m away on +z looking at it, fog everywhere (multiple scattering).
const char* kFog = R"({
  "version": 1,
  "camera": {"position": [0, 0, 2], "look_at": [0, 0, 0], "fov": 20, "resolution": [12, 12]},
  "film": {"start_m": 0.0005, "bin_width_m": 0.01, "bins": 420},
  "media": {"m": {"sigma_s": 0.6, "sigma_a": 0.1, "g": 0.4, "ior": 1.2}},
  "global_medium": "m",
  "lights": [{"type": "point", "position": [0, 0, 0], "power": 10}],
  "render": {"photons_per_pass": 40000, "radius": 0.1, "alpha": 1, "max_depth": 4, "seed": 5}
})";

// A wall at z = -1 (the plane), the light at (0.6, 0, 0), the camera at (-0.6, 0, 0.5): the
// shortest path light -> wall -> camera is |C - L'|, L' = (0.6, 0, -2).
const char* kWall = R"({
  "version": 1,
  "camera": {"position": [-0.6, 0, 0.5], "look_at": [0.2, 0, -1], "fov": 40, "resolution": [12, 12]},
  "film": {"start_m": 0.0005, "bin_width_m": 0.01, "bins": 500},
  "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
  "shapes": [{"type": "quad", "corner": [-2, -2, -1], "edge_u": [4, 0, 0], "edge_v": [0, 4, 0], "material": "white"}],
  "lights": [{"type": "point", "position": [0.6, 0, 0], "power": 10}],
  "render": {"photons_per_pass": 40000, "surface_radius": 0.1, "alpha": 1, "max_depth": 1, "seed": 5}
})";

struct Films {
    std::vector<double> real, unwarped;             // W * H * bins * 3
    std::vector<float> beforeReal, beforeUnwarped;  // W * H * 3
};

Films render(const test::TestScene& sc, const RenderSettings& s, int passes) {
    Driver drv(*sc, s, sc.time);
    for (int p = 1; p <= passes; ++p) EXPECT_TRUE(drv.runPass(p));
    Films f;
    drv.film().volume(TimeAxis::Real, EmissionMode::Delta, f.real);
    drv.film().volume(TimeAxis::Unwarped, EmissionMode::Delta, f.unwarped);
    drv.film().beforeImage(TimeAxis::Real, f.beforeReal);
    drv.film().beforeImage(TimeAxis::Unwarped, f.beforeUnwarped);
    return f;
}

// Energy (sum over channels) of pixel `px` in the bins that end at or before `t`, plus what fell
// before the film when t is past its start; and the energy in the bins after (for non-vacuity).
struct Split {
    double early = 0.0, late = 0.0;
    int earlyBins = 0;
};
Split split(const std::vector<double>& volume, const std::vector<float>& before, const TimeBins& tb, int px, double t) {
    Split out;
    if (t >= tb.startOpl)
        for (int c = 0; c < 3; ++c) out.early += before[static_cast<size_t>(px) * 3 + c];
    for (int k = 0; k < tb.bins; ++k) {
        double e = 0.0;
        for (int c = 0; c < 3; ++c) e += volume[(static_cast<size_t>(px) * tb.bins + k) * 3 + c];
        if (tb.startOpl + (k + 1) * tb.binWidth <= t) {
            out.early += std::abs(e);
            ++out.earlyBins;
        } else {
            out.late += e;
        }
    }
    return out;
}

// A lower bound on the distance from `point` to the half-lines the camera shoots through pixel
// (x, y): the pixel's directions lie within delta (its largest corner angle) of its centre's.
double pixelRayDistanceBound(const Camera& cam, int x, int y, const Vec3& point) {
    const Vec3 centre = cam.generate(x + 0.5, y + 0.5).d;
    double delta = 0.0;
    for (int cx = 0; cx <= 1; ++cx)
        for (int cy = 0; cy <= 1; ++cy)
            delta = std::max(delta, std::acos(std::clamp(glm::dot(centre, cam.generate(x + cx, y + cy).d), -1.0, 1.0)));
    const Vec3 toPoint = point - cam.generate(x + 0.5, y + 0.5).o;
    const double D = glm::length(toPoint);
    const double theta = std::acos(std::clamp(glm::dot(centre, toPoint / D), -1.0, 1.0)) - delta - 1e-9;
    if (theta <= 0.0) return 0.0;
    return theta >= 0.5 * kPi ? D : D * std::sin(theta);
}

struct Case {
    std::string estimator;
    bool box;
};
std::string caseName(const testing::TestParamInfo<Case>& i) { return i.param.estimator + (i.param.box ? "_box" : ""); }

class VolumeCausality : public testing::TestWithParam<Case> {};

TEST_P(VolumeCausality, NothingBeforeTheFirstArrivalOnEitherAxis) {
    const test::TestScene sc = test::testSceneFrom(kFog);
    RenderSettings s = sc.settings;
    s.volumeEstimator = GetParam().estimator;
    if (s.volumeEstimator.rfind("beam", 0) == 0) s.photonsPerPass = 5000;  // long beams: fewer suffice
    if (GetParam().box) s.timeKernel = {TimeKernelKind::Box, 0.6};         // half-width 0.3 m > eta r at pass 1
    ASSERT_EQ(sc->regions[0].ior, kEta);
    const Films f = render(sc, s, 2);
    const TimeBins& tb = sc.time;
    const double firstReal = kEta * kDistance;  // 2.4 m, inside bin 239 (2.3905 .. 2.4005)
    const int W = sc->camera.width, H = sc->camera.height;
    double late = 0.0, lateUnwarped = 0.0;
    int binsChecked = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const int px = y * W + x;
            const Split real = split(f.real, f.beforeReal, tb, px, firstReal);
            EXPECT_EQ(real.early, 0.0) << "real axis, pixel " << x << "," << y;
            late += real.late;
            binsChecked += real.earlyBins;
            const double d = pixelRayDistanceBound(sc->camera, x, y, Vec3(0.0));
            const Split unw = split(f.unwarped, f.beforeUnwarped, tb, px, kEta * (d - 2.0 * kRadius));
            EXPECT_EQ(unw.early, 0.0) << "unwarped axis, pixel " << x << "," << y << ", light " << d
                                      << " m from its rays";
            lateUnwarped += unw.late;
            binsChecked += unw.earlyBins;
        }
    EXPECT_GT(late, 0.0);
    EXPECT_GT(lateUnwarped, 0.0);
    EXPECT_GT(binsChecked, W * H * 239);  // every pixel's 239 real bins, and unwarped ones
}

INSTANTIATE_TEST_SUITE_P(Estimators, VolumeCausality,
                         testing::Values(Case{"beam2d", false}, Case{"beam1d", false}, Case{"point2d", false},
                                         Case{"point3d", false}, Case{"beam2d", true}, Case{"beam1d", true},
                                         Case{"point2d", true}, Case{"point3d", true}),
                         caseName);

class SurfaceCausality : public testing::TestWithParam<bool> {};

TEST_P(SurfaceCausality, NothingBeforeTheShortestPathOverTheWall) {
    const test::TestScene sc = test::testSceneFrom(kWall);
    RenderSettings s = sc.settings;
    if (GetParam()) s.timeKernel = {TimeKernelKind::Box, 0.2};
    ASSERT_TRUE(sc->regions[0].ior == 1.0);
    const Films f = render(sc, s, 2);
    const TimeBins& tb = sc.time;
    const Vec3 C(-0.6, 0.0, 0.5), mirroredLight(0.6, 0.0, -2.0);
    // ppm takes a photon's time as the gather point's, up to r early; the floor (light from the
    // photon's vertex before straight to the gather point) keeps all of it after the shortest path.
    const double first = glm::length(C - mirroredLight);  // 2.7731 m, inside bin 277
    const double firstUnwarped = 1.0;                     // the light's distance from the wall
    const int W = sc->camera.width, H = sc->camera.height;
    double late = 0.0, lateUnwarped = 0.0;
    for (int px = 0; px < W * H; ++px) {
        const Split real = split(f.real, f.beforeReal, tb, px, first);
        EXPECT_EQ(real.early, 0.0) << "real axis, pixel " << px;
        late += real.late;
        const Split unw = split(f.unwarped, f.beforeUnwarped, tb, px, firstUnwarped);
        EXPECT_EQ(unw.early, 0.0) << "unwarped axis, pixel " << px;
        lateUnwarped += unw.late;
    }
    EXPECT_GT(late, 0.0);
    EXPECT_GT(lateUnwarped, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Ppm, SurfaceCausality, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& i) { return i.param ? "box" : "none"; });

}  // namespace
