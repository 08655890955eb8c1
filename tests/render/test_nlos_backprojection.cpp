// Back-projection of NLOS captures (render/nlos_backprojection.h, issue 35). Checked: a synthetic
// capture holding one delta response per pair, at the optical length of a known point, peaks at
// that point's voxel (confocal, single and exhaustive scans, both time origins); a rendered
// confocal capture of scenes/nlos_confocal.json peaks at the T's depth (from the scene file's
// geometry) within one bin width and in front of the T; the grid's defaults and refusals; the
// images; cancelling. The agreement with tools/nlos_backproject is checked by
// tests/tools/test_backprojection_twin.py (CTest backprojection_twin).
#include "base/error.h"
#include "render/driver.h"
#include "render/nlos_backprojection.h"
#include "render/nlos_capture.h"
#include "scene/scene_loader.h"
#include "support/test_scene.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace tpb;
using ::testing::HasSubstr;

namespace {

enum class Scan { Confocal, Single, Exhaustive };

// A 2 m x 2 m wall at z = 0 seen as an 8 x 8 sensor grid (tpb's layout: index sx Sy + sy, points at
// the cell centres), normals +z, devices at (-0.5, 0, 0.25); 0.01 m bins from t_start.
NlosCapture syntheticCapture(Scan scan, bool fromDevices) {
    NlosCapture c;
    c.sensorX = c.sensorY = 8;
    c.bins = 600;
    c.deltaT = 0.01;
    c.tStart = fromDevices ? 1.0 : 0.3;
    c.tAccountsFirstAndLastBounces = fromDevices;
    c.sensorOrigin = c.laserOrigin = Vec3(-0.5, 0.0, 0.25);
    for (int sx = 0; sx < 8; ++sx)
        for (int sy = 0; sy < 8; ++sy) {
            c.sensorGrid.push_back(Vec3(-1.0 + (sx + 0.5) * 0.25, -1.0 + (sy + 0.5) * 0.25, 0.0));
            c.sensorNormals.push_back(Vec3(0.0, 0.0, 1.0));
        }
    c.confocal = scan == Scan::Confocal;
    c.exhaustive = scan == Scan::Exhaustive;
    if (scan == Scan::Single) c.laserGrid = {Vec3(0.1, -0.2, 0.0)};
    if (scan == Scan::Exhaustive) {
        c.laserX = c.laserY = 3;
        for (int lx = 0; lx < 3; ++lx)
            for (int ly = 0; ly < 3; ++ly) c.laserGrid.push_back(Vec3(-0.6 + 0.6 * lx, -0.6 + 0.6 * ly, 0.0));
    }
    c.laserNormals.assign(c.laserGrid.size(), Vec3(0.0, 0.0, 1.0));
    const size_t pairs = c.confocal ? c.sensorGrid.size() : c.laserGrid.size() * c.sensorGrid.size();
    c.H.assign(pairs * static_cast<size_t>(c.bins), 0.0f);
    return c;
}

// Adds a unit delta response of point `x` to every pair of `c`, split between the two bins whose
// centres straddle its optical length (what the back-projection's linear interpolation reads).
void addPoint(NlosCapture& c, const Vec3& x) {
    const std::vector<Vec3>& lasers = c.confocal ? c.sensorGrid : c.laserGrid;
    const size_t ns = c.sensorGrid.size(), nl = c.confocal ? 1 : lasers.size();
    for (size_t l = 0; l < nl; ++l)
        for (size_t s = 0; s < ns; ++s) {
            const Vec3& lp = c.confocal ? lasers[s] : lasers[l];
            double t = glm::length(lp - x) + glm::length(x - c.sensorGrid[s]);
            if (c.tAccountsFirstAndLastBounces)
                t += glm::length(c.laserOrigin - lp) + glm::length(c.sensorGrid[s] - c.sensorOrigin);
            const double pos = (t - c.tStart) / c.deltaT - 0.5, i0 = std::floor(pos), w = pos - i0;
            ASSERT_GE(i0, 0.0);
            ASSERT_LT(i0 + 1.0, c.bins);
            const size_t perBin = nl * ns, p = l * ns + s;
            c.H[static_cast<size_t>(i0) * perBin + p] += static_cast<float>(1.0 - w);
            c.H[static_cast<size_t>(i0 + 1.0) * perBin + p] += static_cast<float>(w);
        }
}

struct SyntheticCase {
    Scan scan;
    bool fromDevices;
    BackprojectionFilter filter;
};

class SyntheticPoint : public ::testing::TestWithParam<SyntheticCase> {};

TEST_P(SyntheticPoint, PeaksAtThePoint) {
    const SyntheticCase tc = GetParam();
    NlosCapture c = syntheticCapture(tc.scan, tc.fromDevices);
    BackprojectionSettings s;
    s.depthMinM = 0.2;
    s.depthMaxM = 1.8;
    s.depths = 17;  // 0.1 m steps
    s.filter = tc.filter;
    const BackprojectionGrid g = backprojectionGrid(c, s);
    ASSERT_EQ(g.nx(), 8);
    ASSERT_EQ(g.ny(), 8);
    // The grid lies in front of the sensor points: voxel (i, j, .) over sensor point (i, j).
    EXPECT_NEAR(glm::length(g.voxel(5, 2, 0) - Vec3(-1.0 + 5.5 * 0.25, -1.0 + 2.5 * 0.25, 0.2)), 0.0, 1e-9);
    const Vec3 x = g.voxel(5, 2, 8);  // depth 1.0 m
    addPoint(c, x);
    const BackprojectionVolume vol = backproject(c, s, 2);
    ASSERT_TRUE(vol.complete);
    EXPECT_EQ(vol.peakI, 5);
    EXPECT_EQ(vol.peakJ, 2);
    EXPECT_EQ(vol.peakK, 8);
    // Without a filter every pair reads (1 - w)^2 + w^2 >= 1/2 of its delta at the point.
    if (tc.filter == BackprojectionFilter::None) {
        EXPECT_GE(vol.peakValue, 0.5 * static_cast<double>(backprojectionPairs(c)));
    }
}

INSTANTIATE_TEST_SUITE_P(Scans, SyntheticPoint,
                         ::testing::Values(SyntheticCase{Scan::Confocal, false, BackprojectionFilter::None},
                                           SyntheticCase{Scan::Confocal, true, BackprojectionFilter::Laplacian},
                                           SyntheticCase{Scan::Single, false, BackprojectionFilter::None},
                                           SyntheticCase{Scan::Single, true, BackprojectionFilter::None},
                                           SyntheticCase{Scan::Exhaustive, false, BackprojectionFilter::Laplacian},
                                           SyntheticCase{Scan::Exhaustive, true, BackprojectionFilter::None}),
                         [](const ::testing::TestParamInfo<SyntheticCase>& info) {
                             const SyntheticCase& c = info.param;
                             const char* scan = c.scan == Scan::Confocal ? "Confocal"
                                                : c.scan == Scan::Single ? "Single"
                                                                         : "Exhaustive";
                             return std::string(scan) + (c.fromDevices ? "FromDevices" : "FromWall") +
                                    (c.filter == BackprojectionFilter::Laplacian ? "Laplacian" : "");
                         });

TEST(Backprojection, DefaultGridAndRefusals) {
    const NlosCapture c = syntheticCapture(Scan::Confocal, false);
    BackprojectionSettings s;
    const BackprojectionGrid g = backprojectionGrid(c, s);
    // Default depths: 64 from one step to (t_end - legs) / 2, legs 0 timed from the wall.
    const double tEnd = c.tStart + c.bins * c.deltaT;
    EXPECT_DOUBLE_EQ(defaultDepthMaxM(c), tEnd / 2.0);
    ASSERT_EQ(g.nz(), 64);
    EXPECT_DOUBLE_EQ(g.depthsM.back(), tEnd / 2.0);
    EXPECT_DOUBLE_EQ(g.depthsM.front(), tEnd / 2.0 / 64.0);
    EXPECT_NEAR(glm::length(g.normal - Vec3(0.0, 0.0, 1.0)), 0.0, 1e-12);

    auto error = [&](BackprojectionSettings bad) -> std::string {
        try {
            backprojectionGrid(c, bad);
        } catch (const UserError& e) {
            return e.what();
        }
        return "";
    };
    BackprojectionSettings bad = s;
    bad.depths = 0;
    EXPECT_THAT(error(bad), HasSubstr("--backproject: 0 depths; give 1 to 4096"));
    bad = s;
    bad.depthMaxM = -1.0;
    EXPECT_THAT(error(bad), HasSubstr("must be finite and > 0"));
    bad = s;
    bad.depthMinM = 2.0;
    bad.depthMaxM = 1.0;
    EXPECT_THAT(error(bad), HasSubstr("must be beyond the nearest"));
    bad = s;
    bad.lateralX = bad.lateralY = 4000;
    bad.flag = "--bp-depths";
    EXPECT_THAT(error(bad), HasSubstr("--bp-depths: 1024000000 voxels is more than"));
    NlosCapture early = c;
    early.tStart = -10.0;  // the film ends before the wall
    try {
        backprojectionGrid(early, s);
        ADD_FAILURE() << "a film ending before the wall was accepted";
    } catch (const UserError& e) {
        EXPECT_THAT(e.what(), HasSubstr("give a depth range in m"));
    }
    EXPECT_THROW(parseBackprojectionFilter("gauss", "--bp-filter"), UserError);
}

TEST(Backprojection, ImagesAndCancel) {
    NlosCapture c = syntheticCapture(Scan::Confocal, false);
    BackprojectionSettings s;
    s.depthMinM = 0.2;
    s.depthMaxM = 1.8;
    s.depths = 17;
    const BackprojectionGrid g = backprojectionGrid(c, s);
    addPoint(c, g.voxel(3, 6, 4));
    const BackprojectionVolume vol = backproject(c, s, 1);
    const BackprojectionImages im = backprojectionImages(vol);
    ASSERT_EQ(im.front.size(), 64u);
    ASSERT_EQ(im.top.size(), 17u * 8u);
    EXPECT_EQ(im.front[6 * 8 + 3], vol.peakValue);
    EXPECT_FLOAT_EQ(im.frontDepthM[6 * 8 + 3], static_cast<float>(g.depthsM[4]));
    EXPECT_EQ(im.top[4 * 8 + 3], vol.peakValue);
    // The same volume on any number of threads; a set cancel flag stops it.
    EXPECT_EQ(backproject(c, s, 3).values, vol.values);
    std::atomic<bool> cancel{true};
    EXPECT_FALSE(backproject(c, s, 2, &cancel).complete);
}

// The rendered T of scenes/nlos_confocal.json (2 passes): the filtered volume's peak lies at the T's
// depth within one bin width of round-trip time (half a bin width in depth) plus a depth step, and
// in front of the T, within one voxel pitch.
TEST(Backprojection, RenderedConfocalTarget) {
    SettingsOverrides o;
    o.passes = 2;
    const std::string path = std::string(TPB_SOURCE_DIR) + "/scenes/nlos_confocal.json";
    SceneDesc desc = loadScene(path);
    // The target's geometry from the scene file: every quad but the wall, all at one depth.
    double depthM = -1.0, xLo = 1e9, xHi = -1e9, yLo = 1e9, yHi = -1e9;
    for (const ShapeDesc& sh : desc.shapes) {
        if (sh.name == "relay") continue;
        ASSERT_EQ(sh.type, ShapeType::Quad);
        ASSERT_EQ(sh.edgeU.z, 0.0);
        ASSERT_EQ(sh.edgeV.z, 0.0);
        if (depthM >= 0.0) {
            ASSERT_EQ(depthM, sh.corner.z);
        }
        depthM = sh.corner.z;  // the wall is the plane z = 0
        const Vec3 far = sh.corner + sh.edgeU + sh.edgeV;
        xLo = std::min({xLo, sh.corner.x, far.x});
        xHi = std::max({xHi, sh.corner.x, far.x});
        yLo = std::min({yLo, sh.corner.y, far.y});
        yHi = std::max({yHi, sh.corner.y, far.y});
    }
    ASSERT_GT(depthM, 0.0);
    test::TestScene p = test::prepareTestScene(std::move(desc), o);
    Driver drv(*p.scene, p.settings, p.time);
    ASSERT_TRUE(drv.runPass(1));
    ASSERT_TRUE(drv.runPass(2));
    const NlosCapture cap = nlosCapture(*drv.snapshot(), *p.scene, path);
    BackprojectionSettings s;
    s.filter = BackprojectionFilter::Laplacian;
    s.depthMinM = 0.5;
    s.depthMaxM = 1.5;
    s.depths = 101;  // 0.01 m steps
    const BackprojectionVolume vol = backproject(cap, s);
    const Vec3 peak = vol.grid.voxel(vol.peakI, vol.peakJ, vol.peakK);
    EXPECT_NEAR(vol.grid.depthsM[static_cast<size_t>(vol.peakK)], depthM, cap.deltaT / 2.0 + 0.01);
    const double pitch = 2.0 / 16.0;
    EXPECT_GE(peak.x, xLo - pitch);
    EXPECT_LE(peak.x, xHi + pitch);
    EXPECT_GE(peak.y, yLo - pitch);
    EXPECT_LE(peak.y, yHi + pitch);
}

}  // namespace
