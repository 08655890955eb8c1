// The relay-wall sensor (issue 35, its first part): a camera whose pixels are a grid on a quad
// shape, each measuring the radiance leaving its patch of the wall towards the sensor's origin.
// Checked: the loader's keys and refusals, the rays against the wall's geometry, and the time of
// flight of every pixel against geometry on both time origins, for the path tracer and the photon
// beams.
#include "film/film_view.h"
#include "render/driver.h"
#include "support/test_scene.h"
#include "render/time_range.h"
#include "scene/scene_loader.h"
#include "base/error.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

using namespace tpb;
using ::testing::HasSubstr;

namespace {

const Vec3 kSensor{-0.5, 0.0, 0.25};
const Vec3 kLight{0.3, 0.2, 0.5};

// A 1 m x 1 m diffuse wall at z = 0 facing +z, a point light in front of it, in vacuum; the sensor
// at kSensor reads a 4 x 4 grid. Film: 1 cm bins from 0 to 3 m.
std::string wallScene(const std::string& cameraExtra,
                      const std::string& wallShape =
                          R"("type": "quad", "corner": [-0.5, -0.5, 0], "edge_u": [1, 0, 0], "edge_v": [0, 1, 0])") {
    return R"({
  "version": 1,
  "camera": {"type": "relay_wall", "position": [-0.5, 0, 0.25], "wall": "relay", "resolution": [4, 4])" +
           cameraExtra + R"(},
  "film": {"start_m": 0, "bin_width_m": 0.01, "bins": 300},
  "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
  "shapes": [{"name": "relay", )" +
           wallShape + R"(, "material": "white"}],
  "lights": [{"type": "point", "position": [0.3, 0.2, 0.5], "power": 20}],
  "render": {"photons_per_pass": 20000, "surface_radius": 0.01, "radius": 0.01, "max_depth": 4, "seed": 3}
})";
}

// As the CLI prepares it, without the pilot (tests/support/test_scene.h).
test::TestScene prepare(const std::string& json, const SettingsOverrides& o = {}) {
    return test::testSceneFrom(json, "wall.json", o);
}

std::string errorOf(const std::string& json) { return test::prepareError(json, "wall.json"); }

// The arrival times over pixel (i, j)'s patch of the wall: |light - x| (+ |x - sensor| when the
// time starts at the sensor), their minimum and maximum over a fine grid of the patch.
std::pair<double, double> patchTimes(int i, int j, bool fromSensor) {
    double lo = kInf, hi = -kInf;
    for (int a = 0; a <= 40; ++a)
        for (int b = 0; b <= 40; ++b) {
            const Vec3 x{-0.5 + (i + a / 40.0) / 4.0, -0.5 + (j + b / 40.0) / 4.0, 0.0};
            const double t = glm::length(kLight - x) + (fromSensor ? glm::length(x - kSensor) : 0.0);
            lo = std::min(lo, t);
            hi = std::max(hi, t);
        }
    return {lo, hi};
}

}  // namespace

TEST(RelayWall, RaysLeaveTheSensorForTheirWallPoint) {
    const test::TestScene p = prepare(wallScene(""));
    const Camera& c = p.scene->camera;
    ASSERT_TRUE(c.relayWall);
    for (double px : {0.0, 0.5, 1.75, 4.0})
        for (double py : {0.0, 2.25, 3.5}) {
            const Ray r = c.generate(px, py);
            EXPECT_EQ(r.o, kSensor);
            const Vec3 want{-0.5 + px / 4.0, -0.5 + py / 4.0, 0.0};
            const double t = -r.o.z / r.d.z;  // where the ray meets z = 0
            const Vec3 hit = r.o + t * r.d;
            EXPECT_NEAR(glm::length(hit - want), 0.0, 1e-12) << px << " " << py;
            double qx = 0.0, qy = 0.0;
            ASSERT_TRUE(c.project(want, qx, qy));
            EXPECT_NEAR(qx, px, 1e-9);
            EXPECT_NEAR(qy, py, 1e-9);
            EXPECT_EQ(c.startOpl(r), 0.0);  // timed from the sensor
        }
    const test::TestScene w = prepare(wallScene(R"(, "time_origin": "wall")"));
    const Ray r = w.scene->camera.generate(1.0, 3.0);
    EXPECT_NEAR(w.scene->camera.startOpl(r), -glm::length(Vec3(-0.25, 0.25, 0.0) - kSensor), 1e-12);
}

// Timed from the wall, what the sensor sees before the wall (a medium) arrives up to the longest
// wall -> sensor leg early: the automatic range starts that much before the pulse.
TEST(RelayWall, AutomaticRangeStartsBeforeThePulseByTheLongestLeg) {
    const test::TestScene sensor = prepare(wallScene("")), wall = prepare(wallScene(R"(, "time_origin": "wall")"));
    EXPECT_EQ(autoTimeRange(*sensor.scene).startOpl, 0.0);
    double leg = 0.0;
    for (const Vec3& c : {Vec3(-0.5, -0.5, 0), Vec3(0.5, -0.5, 0), Vec3(-0.5, 0.5, 0), Vec3(0.5, 0.5, 0)})
        leg = std::max(leg, glm::length(c - kSensor));
    EXPECT_NEAR(autoTimeRange(*wall.scene).startOpl, -leg, 1e-12);
    EXPECT_EQ(autoTimeRange(*wall.scene).endOpl, autoTimeRange(*sensor.scene).endOpl);
}

TEST(RelayWall, BadSensorsAreRefusedNamingTheKey) {
    EXPECT_THAT(errorOf(wallScene("").replace(wallScene("").find("\"relay\","), 8, "\"other\",")),
                HasSubstr("camera.wall: no shape is named \"other\""));
    EXPECT_THAT(errorOf(wallScene("", R"("type": "sphere", "radius": 0.2)")),
                HasSubstr("camera.wall: the relay wall \"relay\" must be a quad"));
    EXPECT_THAT(errorOf(wallScene(R"(, "fov": 30)")), HasSubstr("camera.fov: fov is a pinhole camera's"));
    EXPECT_THAT(errorOf(wallScene(R"(, "time_origin": "laser")")), HasSubstr("camera.time_origin"));
    std::string inPlane = wallScene("");
    inPlane.replace(inPlane.find("[-0.5, 0, 0.25]"), 15, "[-0.5, 0, 0]");
    EXPECT_THAT(errorOf(inPlane),
                HasSubstr("camera.position: the sensor's origin lies in the plane of the relay wall"));
    std::string noWall = wallScene("");
    noWall.replace(noWall.find(", \"wall\": \"relay\""), 17, "");
    EXPECT_THAT(errorOf(noWall), HasSubstr("camera.wall: a relay-wall sensor needs \"wall\""));
}

// Light reaches each wall patch straight from the point light (vacuum, one wall: the only path),
// so every lit bin of pixel (i, j) overlaps the patch's geometric arrival times; timed from the
// wall, the wall -> sensor leg drops out of every time. The steady image does not depend on the
// time origin.
class RelayWallTimes : public ::testing::TestWithParam<const char*> {};

TEST_P(RelayWallTimes, EveryLitBinIsAGeometricArrival) {
    const std::string method = GetParam();
    SettingsOverrides o;
    o.method = method == "pt" ? Method::PathTracer : Method::Beams;
    o.passes = 4;
    if (method == "pt")
        o.samplesPerPixel = 16;
    else
        o.photons = 200000;  // every patch gathers photons in 4 passes of one camera ray
    std::vector<float> steady[2];
    for (int origin = 0; origin < 2; ++origin) {
        const bool fromSensor = origin == 0;
        const test::TestScene p = prepare(wallScene(fromSensor ? "" : R"(, "time_origin": "wall")"), o);
        Driver drv(*p.scene, p.settings, p.time);
        for (uint64_t pass = 1; pass <= 4; ++pass) ASSERT_TRUE(drv.runPass(pass));
        const auto snap = drv.snapshot();
        steady[origin] = steadyImage(*snap);
        // Photon beams gather photons within the surface radius of the pixel's point: their
        // arrival times spread by up to that radius (c = 1 in m of OPL).
        const double slack = method == "pt" ? 1e-9 : p.settings.surfaceRadius0;
        int lit[16] = {};
        for (int k = 0; k < p.time.bins; ++k) {
            const std::vector<float> img = frameImage(*snap, k, TimeAxis::Real, EmissionMode::Delta);
            const double b0 = p.time.startOpl + k * p.time.binWidth, b1 = b0 + p.time.binWidth;
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) {
                    // Film row y = j (raster y runs along edge_v from the corner).
                    const float* px = &img[(static_cast<size_t>(j) * 4 + i) * 3];
                    if (!(px[0] + px[1] + px[2] > 0.0f)) continue;
                    ++lit[j * 4 + i];
                    const auto [lo, hi] = patchTimes(i, j, fromSensor);
                    EXPECT_TRUE(b1 > lo - slack && b0 < hi + slack)
                        << method << (fromSensor ? " sensor" : " wall") << " pixel " << i << "," << j << " bin [" << b0
                        << ", " << b1 << ") outside [" << lo << ", " << hi << "]";
                }
        }
        for (int q = 0; q < 16; ++q) EXPECT_GT(lit[q], 0) << method << " pixel " << q << " never lit";
    }
    ASSERT_EQ(steady[0].size(), steady[1].size());
    for (size_t q = 0; q < steady[0].size(); ++q) EXPECT_FLOAT_EQ(steady[0][q], steady[1][q]) << q;
}

INSTANTIATE_TEST_SUITE_P(Methods, RelayWallTimes, ::testing::Values("pt", "beams"),
                         [](const auto& info) { return std::string(info.param); });
