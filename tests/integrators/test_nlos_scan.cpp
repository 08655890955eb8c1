// Relay-wall scans (issue 35): a laser aimed at one wall point (single), at every sensor point
// (confocal) or at every point of a grid (exhaustive, one sensor image per laser point stacked in
// the film). Checked: the loader's keys and refusals, the laser points against the wall's
// geometry, the time of flight of the hidden target's response against geometry on both time
// origins, and that a scan's film does not depend on the number of threads.
#include "film/film_view.h"
#include "render/driver.h"
#include "render/fingerprint.h"
#include "scene/scene_loader.h"
#include "support/test_scene.h"
#include "base/error.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <string>

using namespace tpb;
using ::testing::HasSubstr;

namespace {

const Vec3 kSensor{-0.5, 0.0, 0.25};
// The hidden target: a 0.5 m square at z = 1 facing the wall, centred on the wall's axis.
constexpr double kTargetZ = 1.0, kTargetHalf = 0.25;

// A 2 m x 2 m relay wall at z = 0 facing +z (the NLOS toolkit's default wall), the sensor and the
// laser at kSensor, the target 1 m away; the sensor reads an 8 x 8 grid; 4 cm bins over 6 m.
std::string scanScene(const std::string& scan, const std::string& cameraExtra = "",
                      const std::string& laser = R"("name": "laser", "type": "laser", "position": [-0.5, 0, 0.25])") {
    return R"({
  "version": 1,
  "camera": {"type": "relay_wall", "position": [-0.5, 0, 0.25], "wall": "relay", "resolution": [8, 8],
             "scan": )" +
           scan + cameraExtra + R"(},
  "film": {"start_m": 0, "bin_width_m": 0.04, "bins": 150},
  "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
  "shapes": [{"name": "relay", "type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0],
              "material": "white"},
             {"name": "target", "type": "quad", "corner": [-0.25, -0.25, 1], "edge_u": [0, 0.5, 0],
              "edge_v": [0.5, 0, 0], "material": "white"}],
  "lights": [{)" +
           laser + R"(, "power": 1}],
  "render": {"photons_per_pass": 20000, "surface_radius": 0.08, "radius": 0.01, "max_depth": 4, "seed": 5}
})";
}

test::TestScene prepare(const std::string& json, const SettingsOverrides& o = {}) {
    return test::testSceneFrom(json, "scan.json", o);
}

std::string errorOf(const std::string& json) { return test::prepareError(json, "scan.json"); }

// The earliest time light from laser point `l` reaches the target and comes back to wall point
// `w`: min over the target of |l - p| + |p - w| (a fine grid of the target), plus the legs laser ->
// l and w -> sensor when time starts at the sensor.
double firstArrival(const Vec3& l, const Vec3& w, bool fromSensor) {
    double best = kInf;
    for (int a = 0; a <= 100; ++a)
        for (int b = 0; b <= 100; ++b) {
            const Vec3 p{-kTargetHalf + 2 * kTargetHalf * a / 100.0, -kTargetHalf + 2 * kTargetHalf * b / 100.0,
                         kTargetZ};
            best = std::min(best, glm::length(l - p) + glm::length(p - w));
        }
    return best + (fromSensor ? glm::length(l - kSensor) + glm::length(w - kSensor) : 0.0);
}

// The film's first bin (after the wall's own response near t = 0) holding light at pixel (x, y).
int firstLitBin(const FilmSnapshot& snap, int x, int y, int fromBin) {
    const std::vector<float> p = pixelProfile(snap, x, y, TimeAxis::Real, EmissionMode::Delta);  // bins x RGB
    for (int k = std::max(fromBin, 0); k < snap.bins(); ++k)
        if (p[3 * k] + p[3 * k + 1] + p[3 * k + 2] > 0.0f) return k;
    return -1;
}

}  // namespace

TEST(NlosScan, LaserPointsLieOnTheWallGrid) {
    const test::TestScene c = prepare(scanScene(R"({"mode": "confocal", "laser": "laser"})"));
    const Camera& cam = c->camera;
    ASSERT_EQ(cam.laserPoints(), 64);
    EXPECT_EQ(cam.height, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const int64_t l = cam.laserPointOf(x, y);
            EXPECT_EQ(l, y * 8 + x);
            EXPECT_NEAR(glm::length(cam.laserTarget(l) - Vec3(-1 + (x + 0.5) / 4, -1 + (y + 0.5) / 4, 0)), 0.0, 1e-12);
        }
    const test::TestScene e = prepare(scanScene(R"({"mode": "exhaustive", "laser": "laser", "grid": [3, 2]})"));
    ASSERT_EQ(e->camera.laserPoints(), 6);
    EXPECT_EQ(e->camera.height, 8 * 6);  // one 8 x 8 sensor image per laser point
    EXPECT_EQ(e->camera.laserPointOf(2, 8 * 5 + 3), 5);
    EXPECT_NEAR(glm::length(e->camera.laserTarget(5) - Vec3(-1 + 2.5 * 2 / 3, -1 + 1.5, 0)), 0.0, 1e-12);
    // Raster row 8 l + j reads sensor row j of every layer.
    for (int l = 0; l < 6; ++l)
        EXPECT_NEAR(glm::length(e->camera.wallPoint(1.5, 8.0 * l + 2.5) - Vec3(-0.625, -0.375, 0)), 0.0, 1e-12);
    const test::TestScene s = prepare(scanScene(R"({"mode": "single", "laser": "laser", "point": [0.25, 0.75]})"));
    EXPECT_EQ(s->camera.laserPoints(), 1);
    EXPECT_NEAR(glm::length(s->camera.laserTarget(0) - Vec3(-0.5, 0.5, 0)), 0.0, 1e-12);
}

TEST(NlosScan, BadScansAreRefusedNamingTheKey) {
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "confocal", "laser": "other"})")),
                HasSubstr("camera.scan.laser: no light is named \"other\""));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "confocal", "laser": "laser"})", "",
                                  R"("name": "laser", "type": "point", "position": [-0.5, 0, 0.25])")),
                HasSubstr("is a point light; a scan needs a \"laser\""));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "sideways", "laser": "laser"})")), HasSubstr("camera.scan.mode"));
    EXPECT_THAT(errorOf(scanScene(R"({"laser": "laser"})")), HasSubstr("camera.scan.mode"));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "exhaustive", "laser": "laser"})")), HasSubstr("camera.scan.grid"));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "exhaustive", "laser": "laser", "grid": [0, 2]})")),
                HasSubstr("camera.scan.grid"));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "confocal", "laser": "laser", "grid": [2, 2]})")),
                HasSubstr("camera.scan.grid: grid is the exhaustive scan's"));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "single", "laser": "laser", "point": [1.5, 0]})")),
                HasSubstr("camera.scan.point"));
    // An exhaustive scan whose film cannot fit: refused before anything is built.
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "exhaustive", "laser": "laser", "grid": [30000, 30000]})")),
                HasSubstr("camera.scan.grid"));
    // A laser behind the wall, and one whose ray meets the target first.
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "confocal", "laser": "laser"})", "",
                                  R"("name": "laser", "type": "laser", "position": [0, 0, -0.5])")),
                HasSubstr("camera.scan.laser: the laser \"laser\" is not on the sensor's side"));
    EXPECT_THAT(errorOf(scanScene(R"({"mode": "confocal", "laser": "laser"})", "",
                                  R"("name": "laser", "type": "laser", "position": [0, 0, 1.5])")),
                HasSubstr("shape \"target\" is in the way"));
}

// A checkpoint of one scan does not resume another: the scan enters the scene's fingerprint.
TEST(NlosScan, TheScanIsPartOfTheFingerprint) {
    const auto fp = [](const std::string& scan) {
        return sceneFingerprint(loadSceneFromString(scanScene(scan), "scan.json"));
    };
    const Fingerprint confocal = fp(R"({"mode": "confocal", "laser": "laser"})");
    EXPECT_THAT(fingerprintChanges(confocal, fp(R"({"mode": "single", "laser": "laser"})")),
                ::testing::Contains(HasSubstr("camera.scan.mode")));
    EXPECT_THAT(fingerprintChanges(fp(R"({"mode": "exhaustive", "laser": "laser", "grid": [2, 2]})"),
                                   fp(R"({"mode": "exhaustive", "laser": "laser", "grid": [2, 3]})")),
                ::testing::Contains(HasSubstr("camera.scan.grid_y")));
    EXPECT_THAT(fingerprintChanges(fp(R"({"mode": "single", "laser": "laser", "point": [0.5, 0.5]})"),
                                   fp(R"({"mode": "single", "laser": "laser", "point": [0.25, 0.5]})")),
                ::testing::Contains(HasSubstr("camera.scan.point_u")));
    EXPECT_TRUE(fingerprintChanges(confocal, fp(R"({"mode": "confocal", "laser": "laser"})")).empty());
}

// The target's response at every wall point starts at the geometric first arrival (laser ->
// laser point -> target -> wall point, and the sensor's legs when time starts at the sensor), to
// within a bin and the surface kernel's spread; nothing of the target arrives earlier.
class NlosScanTimes : public ::testing::TestWithParam<std::tuple<const char*, const char*>> {};

TEST_P(NlosScanTimes, TargetResponseStartsAtTheGeometricArrival) {
    const std::string mode = std::get<0>(GetParam()), origin = std::get<1>(GetParam());
    const bool fromSensor = origin == std::string("sensor");
    const std::string scan = mode == "confocal" ? R"({"mode": "confocal", "laser": "laser"})"
                                                : R"({"mode": "exhaustive", "laser": "laser", "grid": [2, 1]})";
    SettingsOverrides o;
    o.passes = 4;
    const test::TestScene p = prepare(scanScene(scan, fromSensor ? "" : R"(, "time_origin": "wall")"), o);
    Driver drv(*p.scene, p.settings, p.time);
    for (uint64_t pass = 1; pass <= 4; ++pass) ASSERT_TRUE(drv.runPass(pass));
    const auto snap = drv.snapshot();
    const Camera& cam = p->camera;
    const double r = p.settings.surfaceRadius0, bin = p.time.binWidth;
    int checked = 0, onTime = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const Vec3 w = cam.wallPoint(x + 0.5, y + 0.5), l = cam.laserTarget(cam.laserPointOf(x, y));
            const double t0 = firstArrival(l, w, fromSensor);
            // The gathered photons lie within r of the pixel's point, itself within half a pixel of
            // its centre: each leg may be that much shorter (2 legs on the wall: 2 (r + pixel/2)).
            const double spread = 2.0 * (r + 0.5 * glm::length(cam.wallU) / cam.width * std::sqrt(2.0));
            // The wall's own response (the laser spot, seen where the kernel reaches it) arrives at
            // the legs' time, at least 2 m (twice the target's distance) before the target's light:
            // look after it.
            const double direct = fromSensor ? glm::length(l - kSensor) + glm::length(w - kSensor) : 0.0;
            const int k = firstLitBin(*snap, x, y, static_cast<int>((direct + spread + bin - p.time.startOpl) / bin));
            if (k < 0) continue;  // no photon of this wall point reached the target and came back
            ++checked;
            const double b0 = p.time.startOpl + k * bin;
            EXPECT_GE(b0 + bin, t0 - spread) << mode << " " << origin << " pixel " << x << "," << y;
            // Where few photons come back (the grid's edges), the first one may come a little later.
            if (b0 <= t0 + spread + bin) ++onTime;
        }
    EXPECT_GE(checked, cam.width * cam.height / 2) << "too few wall points saw the target";
    EXPECT_GE(onTime, 0.9 * checked) << "the target's response starts late at " << checked - onTime << " of " << checked
                                     << " wall points";
}

INSTANTIATE_TEST_SUITE_P(ModesAndOrigins, NlosScanTimes,
                         ::testing::Combine(::testing::Values("confocal", "exhaustive"),
                                            ::testing::Values("sensor", "wall")),
                         [](const auto& info) {
                             return std::string(std::get<0>(info.param)) + "_" + std::get<1>(info.param);
                         });

// The same capture by the photon beams and by the path tracer (next-event estimation to the laser's
// spot and beam, path_tracer.cpp): in vacuum; with fog between the wall and the target (a null box:
// the laser and sensor legs stay clear); and with fog everywhere, the laser's leg included (its
// scattered light reaches the path tracer through the beam technique; with --bounces 2: so that the
// single scattering off the laser's beam seen by the sensor, a delta the path tracer cannot see, is
// left out of both). Every wall point's energy, each quarter of the wall's time profile in 0.6 m
// blocks and the total agree within noise (z-scores from independent passes of each method). The beams' surface kernel (0.1 m on a
// response that varies over the 0.5 m target) is allowed a bias of 5 % of each value.
enum class NlosMedium { Vacuum, FogBox, FogEverywhere };
class NlosScanMethods : public ::testing::TestWithParam<NlosMedium> {};

TEST_P(NlosScanMethods, PhotonBeamsMatchThePathTracer) {
    const NlosMedium medium = GetParam();
    const bool fog = medium != NlosMedium::Vacuum;
    const char* label = medium == NlosMedium::Vacuum ? "vacuum" : medium == NlosMedium::FogBox ? "fog box" : "fog";
    std::string json = scanScene(R"({"mode": "confocal", "laser": "laser"})", R"(, "time_origin": "wall")");
    json.replace(json.find(R"("resolution": [8, 8])"), 20, R"("resolution": [4, 4])");
    json.replace(json.find(R"("start_m": 0, "bin_width_m": 0.04, "bins": 150)"), 46,
                 R"("start_m": 0.5, "bin_width_m": 0.1, "bins": 30)");
    json.replace(json.find(R"("surface_radius": 0.08)"), 22, R"("surface_radius": 0.1)");
    if (medium == NlosMedium::FogEverywhere) {
        json.replace(json.find(R"("materials": {)"), 14,
                     R"("media": {"fog": {"sigma_s": 0.3, "sigma_a": 0.05}}, "global_medium": "fog",
  "materials": {)");
    } else if (fog) {
        json.replace(json.find(R"("materials": {)"), 14,
                     R"("media": {"fog": {"sigma_s": 0.6, "sigma_a": 0.1}},
  "materials": {"box": {"type": "null"}, )");
        json.replace(json.find(R"("shapes": [)"), 11,
                     R"("shapes": [{"name": "fog", "type": "box", "min": [-1, -1, 0.3], "max": [1, 1, 0.9],
              "material": "box", "interior_medium": "fog"},
             )");
    }
    struct Series {
        std::vector<std::vector<double>> perPass;  // per pass: pixel totals, pixel x block values, the total
    };
    const auto run = [&](Method m, int passes) {
        SettingsOverrides o;
        o.method = m;
        o.maxDepth = 8;  // neither method's depth limit cuts the tails the other keeps
        if (medium == NlosMedium::FogEverywhere) {
            o.bounces = std::pair<int, int>{2, INT_MAX};
            o.photons = 5000;  // (camera rays gather beams all the way: a costlier pass)
        }
        if (m == Method::PathTracer) o.samplesPerPixel = 32;
        const test::TestScene p = prepare(json, o);
        Series s;
        for (int pass = 1; pass <= passes; ++pass) {
            Driver drv(*p.scene, p.settings, p.time);
            EXPECT_TRUE(drv.runPass(static_cast<uint64_t>(pass)));
            const auto snap = drv.snapshot();
            // Per wall point: the energy inside the film (the laser spot's own response, which the
            // path tracer cannot see, arrives before it); per quarter of the wall (2 x 2 points: a
            // single point's bins gather too few photons per pass for a normal mean), 5 blocks of
            // 6 bins (0.6 m).
            std::vector<double> v(16 + 4 * 5, 0.0);
            for (int y = 0; y < 4; ++y)
                for (int x = 0; x < 4; ++x) {
                    const std::vector<float> prof = pixelProfile(*snap, x, y, TimeAxis::Real, EmissionMode::Delta);
                    const size_t q = static_cast<size_t>(y * 4 + x), quarter = static_cast<size_t>((y / 2) * 2 + x / 2);
                    for (int k = 0; k < p.time.bins; ++k) {
                        v[q] += prof[3 * k];
                        v[16 + quarter * 5 + static_cast<size_t>(k / 6)] += prof[3 * k];
                    }
                }
            double total = 0.0;  // and the capture's energy inside the film (the last value)
            for (size_t q = 0; q < 16; ++q) total += v[q];
            v.push_back(total);
            s.perPass.push_back(std::move(v));
        }
        return s;
    };
    const Series beams = run(Method::Beams, 16), pt = run(Method::PathTracer, 32);
    const auto meanSe = [](const Series& s, size_t i) {
        const double n = static_cast<double>(s.perPass.size());
        double mean = 0.0, ss = 0.0;
        for (const auto& v : s.perPass) mean += v[i] / n;
        for (const auto& v : s.perPass) ss += (v[i] - mean) * (v[i] - mean);
        return std::pair<double, double>{mean, std::sqrt(ss / (n - 1.0) / n)};
    };
    int compared = 0, over3 = 0;
    double worst = 0.0, sumBeams = 0.0, sumPt = 0.0;
    for (size_t i = 0; i < beams.perPass[0].size(); ++i) {
        const auto [mb, sb] = meanSe(beams, i);
        const auto [mp, sp] = meanSe(pt, i);
        if (i < 16) sumBeams += mb, sumPt += mp;
        if (!(mb > 0.0 || mp > 0.0)) continue;
        const double bias = 0.05 * std::max(mb, mp);
        const double z = (mb - mp) / std::sqrt(sb * sb + sp * sp + bias * bias);
        ++compared;
        worst = std::max(worst, std::abs(z));
        if (std::abs(z) > 3.0) ++over3;
        EXPECT_LT(std::abs(z), 5.0) << label << " value " << i << ": beams " << mb << " +- " << sb << ", path tracer "
                                    << mp << " +- " << sp;
    }
    EXPECT_GT(compared, 16);
    EXPECT_LE(over3, std::max(1, compared / 100)) << "worst |z| " << worst;
    std::printf("%s: %d values compared, worst |z| %.2f, energy beams / path tracer %.4f\n", label, compared, worst,
                sumBeams / sumPt);
}

INSTANTIATE_TEST_SUITE_P(Media, NlosScanMethods,
                         ::testing::Values(NlosMedium::Vacuum, NlosMedium::FogBox, NlosMedium::FogEverywhere),
                         [](const auto& info) {
                             return std::string(info.param == NlosMedium::Vacuum   ? "vacuum"
                                                : info.param == NlosMedium::FogBox ? "fog"
                                                                                   : "fog_everywhere");
                         });

// The bounce filter partitions the light: the films of bounces 0..1, 2..3 and 4.. add up to the
// unfiltered film (the photons and paths are the same whatever the filter; only what is stored or
// connected changes), for both methods; the laser spot's own response is 1 bounce and the target's
// first response 3, so 2..3 holds the target and nothing before it.
class NlosBounceFilter : public ::testing::TestWithParam<Method> {};

TEST_P(NlosBounceFilter, FiltersPartitionTheFilm) {
    const Method method = GetParam();
    const auto render = [&](int lo, int hi) {
        SettingsOverrides o;
        o.method = method;
        o.maxDepth = 8;
        o.photons = 5000;
        o.samplesPerPixel = 256;
        if (lo > 0 || hi < INT_MAX) o.bounces = std::pair<int, int>{lo, hi};
        const test::TestScene p =
            prepare(scanScene(R"({"mode": "confocal", "laser": "laser"})", R"(, "time_origin": "wall")"), o);
        Driver drv(*p.scene, p.settings, p.time);
        EXPECT_TRUE(drv.runPass(1));
        const auto snap = drv.snapshot();
        std::vector<double> v;
        const std::vector<float> steady = steadyImage(*snap);
        v.assign(steady.begin(), steady.end());
        for (int k = 0; k < p.time.bins; ++k) {
            const std::vector<float> img = frameImage(*snap, k, TimeAxis::Real, EmissionMode::Delta);
            v.insert(v.end(), img.begin(), img.end());
        }
        return v;
    };
    const std::vector<double> all = render(0, INT_MAX), direct = render(0, 1), third = render(2, 3),
                              later = render(4, INT_MAX);
    ASSERT_EQ(all.size(), third.size());
    double total = 0.0, worst = 0.0, sumThird = 0.0, sumLater = 0.0, sumDirect = 0.0;
    for (size_t i = 0; i < all.size(); ++i) {
        total += all[i];
        worst = std::max(worst, std::abs(direct[i] + third[i] + later[i] - all[i]));
        sumDirect += direct[i], sumThird += third[i], sumLater += later[i];
    }
    EXPECT_LE(worst, 1e-5 * total / 1000.0 + 1e-12) << "the filtered films do not add up to the film";
    EXPECT_GT(sumThird, 0.0);
    if (method == Method::Beams) {
        EXPECT_GT(sumDirect, 100.0 * sumThird);  // the laser spot, seen through the surface kernel
    } else {
        EXPECT_EQ(sumDirect, 0.0);  // a delta on the wall: the path tracer never sees it
        EXPECT_GT(sumLater, 0.0);   // (5 bounces: too rare for one pass of the beams)
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, NlosBounceFilter, ::testing::Values(Method::Beams, Method::PathTracer),
                         [](const auto& info) { return std::string(info.param == Method::Beams ? "beams" : "pt"); });

// Bounce filters are refused with the key when they cannot be honoured.
TEST(NlosScan, BadBounceFiltersAreRefused) {
    std::string json = scanScene(R"({"mode": "confocal", "laser": "laser"})");
    const std::string withFilter = [&] {
        std::string j = json;
        j.replace(j.find(R"("max_depth": 4)"), 14, R"("max_depth": 4, "bounces": [3, 2])");
        return j;
    }();
    EXPECT_THAT(errorOf(withFilter), HasSubstr("render.bounces"));
    std::string mirror = json;
    mirror.replace(mirror.find(R"("max_depth": 4)"), 14, R"("max_depth": 4, "bounces": 3)");
    mirror.replace(mirror.find(R"("materials": {)"), 14, R"("materials": {"m": {"type": "mirror"}, )");
    EXPECT_THAT(errorOf(mirror), HasSubstr("does not count a camera path's mirror and glass bounces"));
}

// Laser points are rendered one after the other and their pixels gathered on any thread: the
// film is the same for 1 and 2 threads.
TEST(NlosScan, OneAndTwoThreadsGiveIdenticalFilms) {
    std::vector<float> vol[2];
    for (int t = 0; t < 2; ++t) {
        SettingsOverrides o;
        o.threads = t + 1;
        o.photons = 5000;
        const test::TestScene p = prepare(scanScene(R"({"mode": "exhaustive", "laser": "laser", "grid": [2, 2]})"), o);
        Driver drv(*p.scene, p.settings, p.time);
        ASSERT_TRUE(drv.runPass(1));
        ASSERT_TRUE(drv.runPass(2));
        const auto snap = drv.snapshot();
        for (int k = 0; k < p.time.bins; ++k) {
            const std::vector<float> img = frameImage(*snap, k, TimeAxis::Real, EmissionMode::Delta);
            vol[t].insert(vol[t].end(), img.begin(), img.end());
        }
    }
    ASSERT_EQ(vol[0].size(), vol[1].size());
    EXPECT_TRUE(vol[0] == vol[1]);
    EXPECT_GT(*std::max_element(vol[0].begin(), vol[0].end()), 0.0f);
}
