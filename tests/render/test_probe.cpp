// Probe passes (integrators/integrator.h ProbeRequest, render/driver.h runProbe): the pilots'
// measurements run by the photon-beams integrator, the same for any thread count, with the
// estimators the settings name, and refused by the methods that have none.
#include "integrators/photon_beams.h"
#include "render/driver.h"
#include "render/prepare.h"
#include "render/time_range.h"
#include "scene/scene_loader.h"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <vector>

using namespace tpb;

namespace {

// Fog in a closed diffuse box, a point light: beams and surface photons both gathered.
const char* kScene = R"({
  "version": 1,
  "camera": {"position": [0, 1, 0.9], "look_at": [0, 1, 0], "fov": 60, "resolution": [24, 20]},
  "film": {"bins": 32},
  "media": {"fog": {"sigma_s": 0.6, "sigma_a": 0.1, "g": 0.2}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
  "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true}],
  "lights": [{"type": "point", "position": [0.2, 1.5, -0.3], "power": 10}],
  "render": {"photons_per_pass": 2000, "max_depth": 8, "seed": 9}
})";

PreparedRender prepare(const SettingsOverrides& o = {}) {
    PrepareOptions opt;
    opt.pilot.run = false;
    return prepareRender(loadSceneFromString(kScene, "probe.json"), o, opt);
}

ProbeRequest request() {
    ProbeRequest r;
    r.seed = 77;
    r.photons = 1500;
    r.beamRadius = 0.05;
    r.surfaceRadius = 0.08;
    return r;
}

const TimeBins kWide{0.0, 0.05, 200};

}  // namespace

TEST(Probe, SameHistogramForAnyThreadCount) {
    const PreparedRender p = prepare();
    std::vector<double> first;
    for (int threads : {1, 2, 3, 7}) {
        PhotonBeamsIntegrator beams(*p.scene, p.settings);
        const ProbeResult r = runProbe(beams, *p.scene, request(), kWide, 3, 2, threads);
        ASSERT_TRUE(r.ran);
        ASSERT_EQ(r.luminance.size(), 200u);
        if (first.empty()) {
            first = r.luminance;
            double total = 0.0;
            for (double v : first) total += v;
            EXPECT_GT(total, 0.0);  // something was gathered (a zero histogram would pass trivially)
        } else {
            EXPECT_EQ(r.luminance, first) << threads << " threads";
        }
    }
}

// The probe gathers with the estimators of the settings: point3d's histogram is not beam2d's.
TEST(Probe, GathersWithTheChosenEstimator) {
    SettingsOverrides o;
    o.volumeEstimator = "point3d";
    const PreparedRender beam2d = prepare(), point3d = prepare(o);
    PhotonBeamsIntegrator a(*beam2d.scene, beam2d.settings), b(*point3d.scene, point3d.settings);
    const ProbeResult ra = runProbe(a, *beam2d.scene, request(), kWide, 2, 2, 2);
    const ProbeResult rb = runProbe(b, *point3d.scene, request(), kWide, 2, 2, 2);
    ASSERT_TRUE(ra.ran && rb.ran);
    EXPECT_NE(ra.luminance, rb.luminance);
    // A photons-only probe stores what was asked: points and beams, no surface photons.
    ProbeRequest only = request();
    only.photonsOnly = true;
    only.store = VolumeEstimator::Needs{true, true};
    only.surfacePhotons = false;
    const ProbeResult rp = runProbe(a, *beam2d.scene, only, kWide, 1, 1, 2);
    ASSERT_TRUE(rp.ran);
    EXPECT_TRUE(rp.luminance.empty());
    ASSERT_NE(a.probeMap(), nullptr);
    EXPECT_GT(a.probeMap()->beams.size(), 0u);
    EXPECT_GT(a.probeMap()->points.size(), 0u);
    EXPECT_EQ(a.probeMap()->photons.size(), 0u);
}

TEST(Probe, AbortAndMethodsWithoutAProbe) {
    const PreparedRender p = prepare();
    std::atomic<bool> abort{true};
    PhotonBeamsIntegrator beams(*p.scene, p.settings);
    const ProbeResult r = runProbe(beams, *p.scene, request(), kWide, 1, 1, 2, &abort);
    EXPECT_FALSE(r.ran);
    EXPECT_TRUE(r.aborted);
    RenderSettings pt = p.settings;
    pt.method = Method::PathTracer;
    const std::unique_ptr<Integrator> tracer = makeIntegrator(*p.scene, pt);
    const ProbeResult none = runProbe(*tracer, *p.scene, request(), kWide, 1, 1, 2);
    EXPECT_FALSE(none.ran);
    EXPECT_FALSE(none.aborted);
}

// The time-range pilot is such a probe: its fit does not depend on the thread count either.
TEST(Probe, TimeRangePilotIsTheSameForAnyThreadCount) {
    PreparedRender p = prepare();
    p.pilotSettings.threads = 1;
    const TimeRangeFit one = measureArrivalRange(*p.scene, p.pilotSettings, 3000);
    p.pilotSettings.threads = 3;
    const TimeRangeFit three = measureArrivalRange(*p.scene, p.pilotSettings, 3000);
    ASSERT_TRUE(one.fromPilot);
    EXPECT_EQ(one.startOpl, three.startOpl);
    EXPECT_EQ(one.endOpl, three.endOpl);
}
