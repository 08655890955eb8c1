// RenderSettings: the one validate() (a bad value named by file:line:key when it came from the
// scene file, by its flag when an override set it), the overrides, relative radii against the
// scene's diagonal, and prepareRender (render/prepare.h) deciding the film's time axis once.
#include "base/parallel.h"
#include "render/prepare.h"
#include "integrators/render_settings.h"
#include "base/memory.h"
#include "film/film_bytes.h"
#include "scene/scene_loader.h"
#include "base/error.h"
#include "estimators/estimator_names.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

using namespace tpb;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

namespace {

// The message of the UserError `f` throws ("" if it throws none).
std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const UserError& e) {
        return e.what();
    }
    return "";
}

// A description whose render keys were "written" in scene.json at the given lines.
SceneDesc fileWith(const std::map<std::string, int>& lines) {
    SceneDesc d;
    d.path = "scene.json";
    for (const auto& [key, line] : lines) d.locs[key] = SourceLoc{"scene.json", line};
    return d;
}

std::string validateFile(const SceneDesc& d, double diag = 3.0) {
    return errorOf([&] {
        RenderSettings s = RenderSettings::fromDesc(d.render, diag);
        s.validate({&d, nullptr, diag});
    });
}

std::string validateFlags(const SettingsOverrides& o, double diag = 3.0) {
    return errorOf([&] {
        const SceneDesc d = fileWith({});
        RenderSettings s = RenderSettings::fromDesc(d.render, diag);
        s.apply(o);
        s.validate({&d, &o, diag});
    });
}

}  // namespace

TEST(RenderSettingsValidate, FileValuesAreNamedByFileLineAndKey) {
    SceneDesc d = fileWith({{"render.alpha", 12}});
    d.render.alpha = 1.5;
    EXPECT_EQ(validateFile(d), "scene.json:12: render.alpha: alpha must be in (0, 1] (got 1.5)");

    d = fileWith({{"render.photons_per_pass", 4}});
    d.render.photonsPerPass = 0;
    EXPECT_EQ(validateFile(d), "scene.json:4: render.photons_per_pass: photons_per_pass must be >= 1 (got 0)");

    d = fileWith({{"render.passes", 5}});
    d.render.passes = -2;
    EXPECT_THAT(validateFile(d), StartsWith("scene.json:5: render.passes: passes must be >= 0"));

    d = fileWith({{"render.time_budget_s", 6}});
    d.render.timeBudgetSec = std::numeric_limits<double>::infinity();
    EXPECT_THAT(validateFile(d), StartsWith("scene.json:6: render.time_budget_s: time_budget_s must be a finite"));

    d = fileWith({{"render.max_depth", 7}});
    d.render.maxDepth = 0;
    EXPECT_THAT(validateFile(d), StartsWith("scene.json:7: render.max_depth: max_depth must be >= 1"));

    d = fileWith({{"render.threads", 8}});
    d.render.threads = -1;
    EXPECT_THAT(validateFile(d), StartsWith("scene.json:8: render.threads: threads must be >= 0"));
}

TEST(RenderSettingsValidate, FileRadii) {
    // Relative: a fraction of the diagonal, checked without knowing it.
    SceneDesc d = fileWith({{"render.radius_relative", 9}});
    d.render.radius = 0.3;
    EXPECT_THAT(validateFile(d, 0.0), StartsWith("scene.json:9: render.radius_relative: radius_relative 0.3 is too "
                                                 "large: allowed (0, 0.25]"));
    d.render.radius = -0.1;
    EXPECT_THAT(validateFile(d, 0.0), StartsWith("scene.json:9: render.radius_relative: radius_relative must be > 0"));
    // Absolute: against the diagonal once it is known, not before.
    d = fileWith({{"render.surface_radius", 10}});
    d.render.radiusRelative = false;
    d.render.surfaceRadius = 1.0;
    EXPECT_EQ(validateFile(d, 0.0), "");
    EXPECT_THAT(validateFile(d, 3.0), StartsWith("scene.json:10: render.surface_radius: surface_radius 1 m is 33% of "
                                                 "the scene's diagonal (3 m); allowed up to 25% (0.75 m)"));
}

TEST(RenderSettingsValidate, OverridesAreNamedByTheirFlag) {
    SettingsOverrides o;
    o.alpha = 0.0;
    EXPECT_EQ(validateFlags(o), "--alpha must be in (0, 1] (got 0)");
    o = {};
    o.photons = 0;
    EXPECT_EQ(validateFlags(o), "--photons must be >= 1 (got 0)");
    o = {};
    o.photons = int64_t(1) << 62;
    EXPECT_THAT(validateFlags(o), HasSubstr("per pass for the photon map, more than"));
    EXPECT_THAT(validateFlags(o), StartsWith("--photons "));
    o = {};
    o.passes = -1;
    EXPECT_THAT(validateFlags(o), StartsWith("--passes must be >= 0"));
    o = {};
    o.timeBudget = std::nan("");
    EXPECT_THAT(validateFlags(o), StartsWith("--time must be a finite number of seconds >= 0"));
    o = {};
    o.maxDepth = 0;
    EXPECT_THAT(validateFlags(o), StartsWith("--max-depth must be >= 1"));
    o = {};
    o.samplesPerPixel = 0;
    EXPECT_THAT(validateFlags(o), StartsWith("--spp must be >= 1"));
    o = {};
    o.radius = 5.0;
    EXPECT_THAT(validateFlags(o), StartsWith("--radius 5 m is 167% of the scene's diagonal (3 m); allowed up to 25%"));
    o.radius = -1.0;
    EXPECT_THAT(validateFlags(o), StartsWith("--radius must be > 0"));
    // A flag overrides a bad file value: the file's value is not used, so not refused.
    SceneDesc d = fileWith({{"render.alpha", 3}});
    d.render.alpha = 2.0;
    o = {};
    o.alpha = 0.5;
    RenderSettings s = RenderSettings::fromDesc(d.render, 3.0);
    s.apply(o);
    EXPECT_NO_THROW(s.validate({&d, &o, 3.0}));
}

TEST(RenderSettingsValidate, WarningsAndThreadCap) {
    SettingsOverrides o;
    o.radius = 0.3;  // 10% of the diagonal: allowed, slow
    const SceneDesc d = fileWith({});
    RenderSettings s = RenderSettings::fromDesc(d.render, 3.0);
    s.apply(o);
    std::vector<std::string> w = s.validate({&d, &o, 3.0});
    ASSERT_EQ(w.size(), 1u);
    EXPECT_THAT(w[0], StartsWith("--radius 0.3 m is 10% of the scene's diagonal (3 m): passes get much slower"));

    SceneDesc f = fileWith({{"render.threads", 2}});
    f.render.threads = maxUsefulThreads() + 5;
    s = RenderSettings::fromDesc(f.render, 3.0);
    w = s.validate({&f, nullptr, 3.0});
    ASSERT_EQ(w.size(), 1u);
    EXPECT_THAT(w[0], StartsWith("scene.json:2: render.threads: threads " + std::to_string(maxUsefulThreads() + 5)));
    EXPECT_EQ(s.threads, maxUsefulThreads());
}

TEST(RenderSettings, OverridesApply) {
    RenderDesc r;
    r.passes = 40;
    r.seed = 3;
    RenderSettings s = RenderSettings::fromDesc(r, 1.0);
    SettingsOverrides o;
    o.timeBudget = 2.5;  // alone: as many passes as fit in it
    o.seed = 99;
    o.maxDepth = 1;
    o.profile = TimeProfile::Uniform;
    o.beamLength = BeamLength::Long;
    o.accel = AccelBackend::BruteForce;
    o.equiangular = false;
    o.samplesPerPixel = 4;
    o.method = Method::PathTracer;
    s.apply(o);
    EXPECT_EQ(s.passes, 0);
    EXPECT_EQ(s.timeBudgetSec, 2.5);
    EXPECT_EQ(s.seed, 99u);
    EXPECT_EQ(s.maxDepth, 1);
    EXPECT_EQ(s.profile, TimeProfile::Uniform);
    EXPECT_EQ(s.beamLength, BeamLength::Long);
    EXPECT_EQ(s.accel, AccelBackend::BruteForce);
    EXPECT_FALSE(s.equiangular);
    EXPECT_EQ(s.samplesPerPixel, 4);
    EXPECT_EQ(s.method, Method::PathTracer);
    o.passes = 7;  // with passes, the budget does not clear them
    s.apply(o);
    EXPECT_EQ(s.passes, 7);
}

TEST(RenderSettings, RelativeRadiiResolveAgainstTheDiagonal) {
    RenderDesc r;
    r.radiusRelative = true;
    r.radius = 0.01;
    r.surfaceRadius = 0.02;
    const RenderSettings rel = RenderSettings::fromDesc(r, 4.0);
    EXPECT_DOUBLE_EQ(rel.beamRadius0, 0.04);
    EXPECT_DOUBLE_EQ(rel.surfaceRadius0, 0.08);
    r.radiusRelative = false;
    const RenderSettings abs = RenderSettings::fromDesc(r, 4.0);
    EXPECT_EQ(abs.beamRadius0, 0.01);
    EXPECT_EQ(abs.surfaceRadius0, 0.02);
}

// ---- prepareRender --------------------------------------------------------------------------

namespace {
// A point light in a box of medium, camera 3 m away: diagonal well above 1 m.
std::string sceneJson(const std::string& film, const std::string& render) {
    return R"({"version": 1,
"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [8, 6]},
"film": )" +
           film + R"(,
"media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.1}},
"global_medium": "fog",
"lights": [{"type": "point", "position": [0, 0, 0], "power": 1}],
"render": )" +
           render + "}";
}
}  // namespace

TEST(PrepareRender, ExplicitRangeAndBinsOverride) {
    const std::string json = sceneJson(R"({"start_m": 1.0, "bin_width_m": 0.02, "bins": 50})", R"({"alpha": 0.6})");
    SettingsOverrides o;
    o.bins = 100;  // same range, finer bins
    const PreparedRender p = prepareRender(loadSceneFromString(json, "p.json"), o);
    EXPECT_EQ(p.time.bins, 100);
    EXPECT_EQ(p.time.startOpl, 1.0);
    EXPECT_DOUBLE_EQ(p.time.binWidth, 0.01);
    EXPECT_FALSE(p.fit.fromPilot);  // an explicit range runs no pilot
    EXPECT_EQ(p.settings.alpha, 0.6);
    EXPECT_EQ(p.scene->camera.width, 8);
    EXPECT_EQ(p.source.path, "p.json");
    EXPECT_EQ(p.source.where("render.alpha"), "p.json:7: ");
}

TEST(PrepareRender, AutoRangeWithoutThePilotKeepsTheHeuristicWindow) {
    PrepareOptions opt;
    opt.pilot.run = false;
    const PreparedRender p = prepareRender(loadSceneFromString(sceneJson(R"({"bins": 64})", "{}"), "a.json"), {}, opt);
    const OplRange w = autoTimeRange(*p.scene);
    EXPECT_EQ(p.time.bins, 64);
    EXPECT_EQ(p.time.startOpl, w.startOpl);
    EXPECT_EQ(p.time.binWidth, (w.endOpl - w.startOpl) / 64);
    EXPECT_FALSE(p.fit.fromPilot);
}

TEST(PrepareRender, RefusesBadOverridesAndRadiiBeforeThePilot) {
    const std::string json = sceneJson(R"({"bins": 16})", R"({"radius": 2.0, "surface_radius": 0.01})");
    PrepareOptions opt;
    opt.pilot.run = false;
    const std::string e = errorOf([&] { prepareRender(loadSceneFromString(json, "r.json"), {}, opt); });
    EXPECT_THAT(e, StartsWith("r.json:7: render.radius: radius 2 m is "));
    EXPECT_THAT(e, HasSubstr("allowed up to 25%"));
    SettingsOverrides o;
    o.radius = 0.01;  // replaces the file's radius: accepted
    EXPECT_EQ(errorOf([&] { prepareRender(loadSceneFromString(json, "r.json"), o, opt); }), "");
    o.alpha = 3.0;
    EXPECT_EQ(errorOf([&] { prepareRender(loadSceneFromString(json, "r.json"), o, opt); }),
              "--alpha must be in (0, 1] (got 3)");
}

// ---- the estimators and the time kernel (issue 14) ----------------------------------------------

TEST(RenderSettings, TimeKernelNamesRoundTrip) {
    EXPECT_EQ(parseTimeKernel("none"), TimeKernelSettings{});
    EXPECT_EQ(parseTimeKernel("box"), (TimeKernelSettings{TimeKernelKind::Box, 0.0}));
    EXPECT_EQ(parseTimeKernel("box:0.05"), (TimeKernelSettings{TimeKernelKind::Box, 0.05}));
    for (const char* bad : {"", "box:", "box:0", "box:-1", "box:x", "box:1e999", "gauss", "Box", "box:0.1m"})
        EXPECT_FALSE(parseTimeKernel(bad).has_value()) << bad;
    for (const char* s : {"none", "box", "box:0.05"}) EXPECT_EQ(timeKernelName(*parseTimeKernel(s)), s);
}

TEST(RenderSettingsValidate, UnknownEstimatorIsNamedWithTheAllowedValues) {
    SceneDesc d = fileWith({{"render.volume_estimator", 9}});
    d.render.volumeEstimator = "beam3d";
    EXPECT_THAT(validateFile(d), StartsWith("scene.json:9: render.volume_estimator: "));
    EXPECT_THAT(validateFile(d), HasSubstr("unknown volume estimator \"beam3d\"; allowed: beam2d"));
    SettingsOverrides o;
    o.volumeEstimator = "nope";
    EXPECT_THAT(validateFlags(o), StartsWith("--estimator: unknown volume estimator \"nope\"; allowed: "));
    o = {};
    o.surfaceEstimator = "ppm2";
    EXPECT_THAT(validateFlags(o), StartsWith("--surface-estimator: unknown surface estimator \"ppm2\"; allowed: ppm"));
    o = {};
    o.volumeEstimator = volumeEstimatorNames().back();
    EXPECT_EQ(validateFlags(o), "");
}

TEST(RenderSettingsValidate, EstimatorFlagsNeedThePhotonBeamsMethod) {
    SettingsOverrides o;
    o.method = Method::PathTracer;
    o.timeKernel = TimeKernelSettings{TimeKernelKind::Box, 0.1};
    EXPECT_THAT(validateFlags(o), HasSubstr("--time-kernel applies to the photon-beams estimators only"));
    o.timeKernel.reset();
    o.volumeEstimator = "beam2d";
    EXPECT_THAT(validateFlags(o), HasSubstr("--estimator applies to the photon-beams estimators only"));
    // The file's estimator is the file's photon-beams setting: no complaint when another method runs.
    SceneDesc d = fileWith({{"render.time_kernel", 4}});
    d.render.timeKernel = {TimeKernelKind::Box, 0.1};
    RenderSettings s = RenderSettings::fromDesc(d.render, 3.0);
    SettingsOverrides pt;
    pt.method = Method::PathTracer;
    s.apply(pt);
    EXPECT_EQ(errorOf([&] { s.validate({&d, &pt, 3.0}); }), "");
}

TEST(PrepareRender, TimeKernelWiderThanTheFilmIsRefused) {
    PrepareOptions opt;
    opt.pilot.run = false;
    // The film covers 16 x 0.05 = 0.8 m of OPL.
    const std::string film = R"({"start_m": 1.0, "bin_width_m": 0.05, "bins": 16})";
    const std::string wide = sceneJson(film, R"({"time_kernel": {"type": "box", "width": 2.0}})");
    const std::string e = errorOf([&] { prepareRender(loadSceneFromString(wide, "k.json"), {}, opt); });
    EXPECT_THAT(e, StartsWith("k.json:7: render.time_kernel: "));
    EXPECT_THAT(e, HasSubstr("width 2 m (of optical path) is wider than the film's whole time range 0.8 m"));
    SettingsOverrides o;
    o.timeKernel = TimeKernelSettings{TimeKernelKind::Box, 0.9};
    EXPECT_THAT(errorOf([&] { prepareRender(loadSceneFromString(sceneJson(film, "{}"), "k.json"), o, opt); }),
                StartsWith("--time-kernel: the time kernel's width 0.9 m"));
    o.timeKernel = TimeKernelSettings{TimeKernelKind::Box, 0.1};
    const PreparedRender p = prepareRender(loadSceneFromString(sceneJson(film, "{}"), "k.json"), o, opt);
    EXPECT_EQ(p.settings.timeKernel, (TimeKernelSettings{TimeKernelKind::Box, 0.1}));
    // The pilot fits the time axis with the default estimators and no kernel, whatever is chosen.
    EXPECT_EQ(p.pilotSettings.timeKernel, TimeKernelSettings{});
    EXPECT_EQ(p.pilotSettings.volumeEstimator, RenderSettings{}.volumeEstimator);
}

TEST(SceneLoaderRender, EstimatorAndTimeKernelKeys) {
    PrepareOptions opt;
    opt.pilot.run = false;
    const std::string film = R"({"start_m": 1.0, "bin_width_m": 0.05, "bins": 16})";
    const auto load = [&](const std::string& render) { return loadSceneFromString(sceneJson(film, render), "t.json"); };
    EXPECT_EQ(load(R"({"time_kernel": "box"})").render.timeKernel, (TimeKernelSettings{TimeKernelKind::Box, 0.0}));
    EXPECT_EQ(load(R"({"time_kernel": "none"})").render.timeKernel, TimeKernelSettings{});
    EXPECT_EQ(load(R"({"time_kernel": {"width": 0.2}})").render.timeKernel,
              (TimeKernelSettings{TimeKernelKind::Box, 0.2}));
    EXPECT_EQ(load(R"({"volume_estimator": "beam2d", "surface_estimator": "ppm"})").render.volumeEstimator, "beam2d");
    EXPECT_THAT(errorOf([&] { load(R"({"time_kernel": "gauss"})"); }),
                AllOf(StartsWith("t.json:7: render.time_kernel: "), HasSubstr("allowed: none, box")));
    EXPECT_THAT(errorOf([&] { load(R"({"time_kernel": {"type": "tent"}})"); }),
                StartsWith("t.json:7: render.time_kernel.type: unknown time kernel \"tent\""));
    EXPECT_THAT(errorOf([&] { load(R"({"time_kernel": {"type": "box", "width": -1}})"); }),
                StartsWith("t.json:7: render.time_kernel.width: width must be > 0"));
    EXPECT_THAT(errorOf([&] { load(R"({"time_kernel": {"type": "box", "widht": 1}})"); }), HasSubstr("widht"));
    EXPECT_THAT(errorOf([&] { load(R"({"time_kernel": 3})"); }), HasSubstr("expected \"none\", \"box\" or an object"));
    // The name is checked by validate(), in prepareRender, at the file's line.
    EXPECT_THAT(errorOf([&] { prepareRender(load(R"({"volume_estimator": "beams"})"), {}, opt); }),
                AllOf(StartsWith("t.json:7: render.volume_estimator: "), HasSubstr("allowed: ")));
    EXPECT_THAT(errorOf([&] { load(R"({"volume_estimator": 2})"); }), HasSubstr("expected a string"));
}

TEST(RenderSettings, WarmupHalvesThePhotonsOfTheFirstPasses) {
    RenderDesc r;
    r.photonsPerPass = 4000;
    r.warmup = 3;
    RenderSettings s = RenderSettings::fromDesc(r, 1.0);
    EXPECT_EQ(s.warmupPasses, 3);
    const int64_t want[] = {500, 1000, 2000, 4000, 4000, 4000};
    for (uint64_t p = 1; p <= 6; ++p) EXPECT_EQ(s.photonsForPass(p), want[p - 1]) << "pass " << p;
    s.warmupPasses = 0;  // off: every pass traces them all
    for (uint64_t p = 1; p <= 4; ++p) EXPECT_EQ(s.photonsForPass(p), 4000);
    s.photonsPerPass = 5;  // never fewer than one photon
    s.warmupPasses = 4;
    EXPECT_EQ(s.photonsForPass(1), 1);
    EXPECT_EQ(s.photonsForPass(3), 1);
    EXPECT_EQ(s.photonsForPass(4), 2);
    EXPECT_EQ(s.photonsForPass(5), 5);
    SettingsOverrides o;
    o.warmup = 1;
    s.apply(o);
    EXPECT_EQ(s.warmupPasses, 1);
}

TEST(RenderSettingsValidate, WarmupOutOfRangeIsNamedByFileLineOrFlag) {
    SceneDesc d = fileWith({{"render.warmup", 14}});
    d.render.warmup = kMaxWarmupPasses + 1;
    EXPECT_THAT(validateFile(d), StartsWith("scene.json:14: render.warmup: warmup must be an integer from 0"));
    d.render.warmup = -1;
    EXPECT_THAT(validateFile(d), HasSubstr("(got -1)"));
    d.render.warmup = kMaxWarmupPasses;
    EXPECT_EQ(validateFile(d), "");
    SettingsOverrides o;
    o.warmup = 99;
    EXPECT_THAT(validateFlags(o), StartsWith("--warmup must be an integer from 0"));
}
