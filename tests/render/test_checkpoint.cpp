// Checkpoints (render/checkpoint.h, render/fingerprint.h): a film written and read back is the same
// bits; a render resumed from a checkpoint of n passes and run on to N gives the film of one run of
// N passes, bit for bit, whatever the thread counts; corrupted, truncated and inconsistent files are
// refused; the fingerprint names what changed; a resume keeps the checkpoint's flags.
#include "render/checkpoint.h"
#include "render/driver.h"
#include "base/error.h"
#include "support/temp_dir.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace tpb {
namespace {

namespace fs = std::filesystem;

// A small fog box with a diffuse floor: volume (beams) and surface (photons) estimates, 24x20 (edge
// tiles of 8 and 4 pixels), 12 bins.
const char* kScene = R"({
  "version": 1,
  "camera": {"position": [0, 0.5, 0.9], "look_at": [0, 0.5, 0], "resolution": [24, 20]},
  "film": {"bins": 12},
  "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.05}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.7}},
  "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 1, 1], "material": "white", "flip_normals": true}],
  "lights": [{"type": "point", "position": [0, 0.8, 0], "power": 5}],
  "render": {"photons_per_pass": 1500, "passes": 6, "seed": 3, "radius": 0.05, "surface_radius": 0.08}
})";

// Every value of every tile, bit for bit, and the pass counts.
void expectSameFilm(const TransientFilm& a, const TransientFilm& b) {
    const auto sa = a.snapshot(), sb = b.snapshot();
    ASSERT_EQ(sa->tileCount(), sb->tileCount());
    for (int t = 0; t < sa->tileCount(); ++t) {
        const TileSums &x = sa->block(t).sums, &y = sb->block(t).sums;
        ASSERT_EQ(x.passes, y.passes) << "tile " << t;
        ASSERT_EQ(x.weight, y.weight) << "tile " << t << ": the passes' summed weight (the film's divisor)";
        const auto same = [&](const auto& u, const auto& v, const char* what) {
            ASSERT_EQ(u.size(), v.size()) << what;
            EXPECT_EQ(std::memcmp(u.data(), v.data(), u.size() * sizeof(u[0])), 0) << what << " of tile " << t;
        };
        same(x.steady, y.steady, "steady");
        for (int ax = 0; ax < 2; ++ax) {
            same(x.bins[ax], y.bins[ax], "bins");
            same(x.before[ax], y.before[ax], "before");
            same(x.after[ax], y.after[ax], "after");
        }
        EXPECT_EQ(x.absBound, y.absBound);
    }
}

double filmSum(const TransientFilm& f) {
    double s = 0.0;
    const auto snap = f.snapshot();
    for (int t = 0; t < snap->tileCount(); ++t)
        for (double v : snap->block(t).sums.bins[0]) s += v;
    return s;
}

CheckpointInfo infoOf(const test::TestScene& ts, const RenderSettings& s, uint64_t passes) {
    CheckpointInfo i;
    i.scene = "test.json";
    i.passes = passes;
    i.width = ts->camera.width;
    i.height = ts->camera.height;
    i.time = ts.time;
    i.fingerprint = settingsFingerprint(s);
    i.overrides = checkpointOverrides(s, {});
    return i;
}

class CheckpointTest : public ::testing::Test {
protected:
    test::TempDir tmp{"checkpoint"};
    std::string path() const { return (tmp.path() / kCheckpointFile).string(); }
};

TEST_F(CheckpointTest, WrittenAndReadBackIsTheSameFilm) {
    const test::TestScene ts = test::testSceneFrom(kScene);
    RenderSettings s = ts.settings;
    s.threads = 2;
    Driver d(*ts, s, ts.time);
    ASSERT_TRUE(d.runPass(1));
    ASSERT_TRUE(d.runPass(2));
    ASSERT_GT(filmSum(d.film()), 0.0) << "the scene must put light on the film, or the test shows nothing";
    writeCheckpoint(path(), infoOf(ts, s, 2), d.film(), d.history());
    const Checkpoint c = readCheckpoint(path());
    expectSameFilm(d.film(), *c.film);
    EXPECT_EQ(c.info.passes, 2u);
    EXPECT_EQ(c.info.time.startOpl, ts.time.startOpl);
    EXPECT_EQ(c.info.time.binWidth, ts.time.binWidth);
    ASSERT_EQ(c.history.size(), 2u);
    EXPECT_EQ(c.history[1].pass, 2u);
    EXPECT_EQ(c.history[1].beams, d.history()[1].beams);
    EXPECT_EQ(c.history[1].beamRadius, d.history()[1].beamRadius);
    EXPECT_EQ(c.history[1].camera.beamEstimates, d.history()[1].camera.beamEstimates);
    EXPECT_EQ(c.film->stats.inside[0].load(), d.film().stats.inside[0].load());
    EXPECT_EQ(c.film->stats.rejectedSamples.load(), d.film().stats.rejectedSamples.load());
    EXPECT_EQ(fingerprintChanges(c.info.fingerprint, settingsFingerprint(s)), std::vector<std::string>{});
}

// Also with a warm-up that the checkpoint cuts in two (passes 1-2 of W = 3 weigh about 1/8 + 1/4): the
// summed weight, the film's divisor, comes back from the file.
TEST_F(CheckpointTest, ResumedRenderIsBitIdenticalToOneUninterruptedRun) {
    for (const int warmup : {0, 3}) {
        SCOPED_TRACE("warm-up " + std::to_string(warmup));
        const test::TestScene ts = test::testSceneFrom(kScene);
        RenderSettings s = ts.settings;  // 6 passes
        s.threads = 2;
        s.warmupPasses = warmup;
        Driver whole(*ts, s, ts.time);
        whole.start();
        whole.wait();
        ASSERT_EQ(whole.completedPasses(), 6u);

        RenderSettings first = s;
        first.passes = 2;
        first.threads = 1;
        Driver part(*ts, first, ts.time);
        part.start();
        part.wait();
        writeCheckpoint(path(), infoOf(ts, s, 2), part.film(), part.history());

        Checkpoint c = readCheckpoint(path());
        RenderSettings rest = s;
        rest.threads = 2;
        Driver resumed(*ts, rest, ts.time);
        resumed.restore(std::move(c.film), std::move(c.history));
        EXPECT_EQ(resumed.completedPasses(), 2u);
        resumed.start();
        resumed.wait();
        ASSERT_EQ(resumed.completedPasses(), 6u);
        ASSERT_EQ(resumed.history().size(), 6u);
        EXPECT_EQ(resumed.history()[2].pass, 3u) << "the resumed run goes on with pass 3, not pass 1 again";
        expectSameFilm(whole.film(), resumed.film());
        EXPECT_EQ(resumed.film().stats.inside[0].load(), whole.film().stats.inside[0].load());

        EXPECT_EQ(resumed.history()[2].beamRadius, whole.history()[2].beamRadius);
        const double weight = resumed.film().snapshot()->block(0).sums.weight;
        double expected = 0.0;
        for (uint64_t i = 1; i <= 6; ++i) expected += s.passWeight(i);
        EXPECT_EQ(weight, expected);
        if (warmup == 0)
            EXPECT_EQ(weight, 6.0);
        else
            EXPECT_NEAR(weight, 0.125 + 0.25 + 0.5 + 3.0, 3.0 / static_cast<double>(s.photonsPerPass));
    }
}

// Read into the driver's own film (a resume holds one film, not two): the same sums; a film of
// another shape is refused.
TEST_F(CheckpointTest, ReadIntoAnExistingFilmFillsItInPlace) {
    const test::TestScene ts = test::testSceneFrom(kScene);
    RenderSettings s = ts.settings;
    Driver d(*ts, s, ts.time);
    ASSERT_TRUE(d.runPass(1));
    ASSERT_TRUE(d.runPass(2));
    writeCheckpoint(path(), infoOf(ts, s, 2), d.film(), d.history());
    Driver resumed(*ts, s, ts.time);
    Checkpoint c = readCheckpoint(path(), &resumed.film());
    EXPECT_EQ(c.film, nullptr);
    resumed.restore(nullptr, std::move(c.history));
    EXPECT_EQ(resumed.completedPasses(), 2u);
    expectSameFilm(d.film(), resumed.film());
    EXPECT_EQ(resumed.film().stats.inside[0].load(), d.film().stats.inside[0].load());
    TimeBins other = ts.time;
    other.bins += 1;
    TransientFilm wrong(ts->camera.width, ts->camera.height, other);
    EXPECT_THROW(readCheckpoint(path(), &wrong), UserError);
}

TEST_F(CheckpointTest, CorruptTruncatedAndForeignFilesAreRefusedByName) {
    const test::TestScene ts = test::testSceneFrom(kScene);
    RenderSettings s = ts.settings;
    Driver d(*ts, s, ts.time);
    ASSERT_TRUE(d.runPass(1));
    writeCheckpoint(path(), infoOf(ts, s, 1), d.film(), d.history());
    std::string bytes;
    {
        std::ifstream in(path(), std::ios::binary);
        std::ostringstream ss;
        ss << in.rdbuf();
        bytes = ss.str();
    }
    const auto refused = [&](const std::string& content, const std::string& why) {
        const std::string p = (tmp.path() / "bad.tpbck").string();
        std::ofstream(p, std::ios::binary | std::ios::trunc) << content;
        try {
            readCheckpoint(p);
            ADD_FAILURE() << "accepted: " << why;
        } catch (const UserError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find(p), std::string::npos) << m;
            EXPECT_NE(m.find(why), std::string::npos) << "expected \"" << why << "\" in " << m;
        }
    };
    std::string flipped = bytes;
    flipped[flipped.size() - 100] ^= 0x10;  // one bit of the film
    refused(flipped, "corrupted");
    refused(bytes.substr(0, bytes.size() - 9), "truncated");
    refused(bytes.substr(0, 12), "truncated");
    refused(std::string("TPBREF1\n") + bytes.substr(8), "wrong magic");
    refused(bytes + "x", "announces");
    EXPECT_NO_THROW(readCheckpoint(path()));
}

TEST_F(CheckpointTest, FilmCaughtMidPassIsNotWrittenAndThePreviousCheckpointStays) {
    const test::TestScene ts = test::testSceneFrom(kScene);
    RenderSettings s = ts.settings;
    Driver d(*ts, s, ts.time);
    ASSERT_TRUE(d.runPass(1));
    writeCheckpoint(path(), infoOf(ts, s, 1), d.film(), d.history());
    const auto before = fs::last_write_time(path());
    const uintmax_t size = fs::file_size(path());
    {  // one tile one pass ahead, as a pass cut short leaves it
        PixelAccumulator acc(d.film().bins());
        TransientFilm::TileWriter w(d.film(), 0);
        w.addPixel(0, 0, acc);
    }
    try {
        writeCheckpoint(path(), infoOf(ts, s, 1), d.film(), d.history());
        ADD_FAILURE() << "a film whose tiles disagree was written";
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find("cut short"), std::string::npos) << e.what();
    }
    EXPECT_EQ(fs::last_write_time(path()), before);
    EXPECT_EQ(fs::file_size(path()), size);
    EXPECT_NO_THROW(readCheckpoint(path()));
}

TEST(Fingerprint, NamesEachChangedKeyAndIgnoresWhatAResumeMayChange) {
    SceneDesc a = loadSceneFromString(kScene, "a.json");
    SceneDesc b = a;
    b.lights[0].power = Color(6.0);
    b.shapes[0].boxMax.y = 1.5;
    const std::vector<std::string> ch = fingerprintChanges(sceneFingerprint(a), sceneFingerprint(b));
    ASSERT_EQ(ch.size(), 2u);
    EXPECT_EQ(ch[0], "shapes[0].max: the checkpoint has (1, 1, 1), this run has (1, 1.5, 1)");
    EXPECT_EQ(ch[1], "lights[0].power: the checkpoint has (5, 5, 5), this run has (6, 6, 6)");

    RenderSettings s, t;
    t.passes = 99;
    t.threads = 7;
    t.timeBudgetSec = 5.0;
    t.emission = EmissionMode::Continuous;
    t.accel = AccelBackend::Embree;  // every backend gives the same films
    EXPECT_TRUE(fingerprintChanges(settingsFingerprint(s), settingsFingerprint(t)).empty());
    // A checkpoint written when the accelerator was in the fingerprint still resumes.
    Fingerprint older = settingsFingerprint(s);
    older.push_back({"render.accel", "embree"});
    EXPECT_TRUE(fingerprintChanges(older, settingsFingerprint(t)).empty());
    t.seed = 2;
    t.alpha = 0.5;
    EXPECT_EQ(fingerprintChanges(settingsFingerprint(s), settingsFingerprint(t)).size(), 2u);
    TimeBins u{0.0, 0.01, 10}, v = u;
    v.binWidth = 0.010000000000000002;  // one ulp: bins would land elsewhere
    EXPECT_EQ(fingerprintChanges(timeFingerprint(u), timeFingerprint(v)).size(), 1u);
}

// Checkpoints written before the settings had one serialisation named five keys differently; the
// values were written the same way (%.17g), so such a checkpoint still resumes, and a changed value
// is named by its current key.
TEST(Fingerprint, OlderKeyNamesStillResume) {
    RenderSettings s;
    s.photonsPerPass = 1234;
    s.beamRadius0 = 0.0125;
    s.surfaceRadius0 = 0.03;
    s.volumeEstimator = "point3d";
    Fingerprint older;
    for (const auto& [k, v] : settingsFingerprint(s)) {
        std::string key = k;
        if (k == "render.photons_per_pass") key = "render.photons";
        if (k == "render.radius") key = "render.radius_m";
        if (k == "render.surface_radius") key = "render.surface_radius_m";
        if (k == "render.volume_estimator") key = "render.estimator";
        older.emplace_back(key, v);
    }
    ASSERT_NE(older, settingsFingerprint(s));
    EXPECT_TRUE(fingerprintChanges(older, settingsFingerprint(s)).empty());
    RenderSettings t = s;
    t.beamRadius0 = 0.02;
    const std::vector<std::string> ch = fingerprintChanges(older, settingsFingerprint(t));
    ASSERT_EQ(ch.size(), 1u);
    EXPECT_EQ(ch[0], "render.radius: the checkpoint has 0.0125, this run has 0.02");
    RenderSettings pt;
    pt.method = Method::PathTracer;
    pt.samplesPerPixel = 4;
    Fingerprint olderPt;
    for (const auto& [k, v] : settingsFingerprint(pt))
        olderPt.emplace_back(k == "render.samples_per_pixel" ? "render.spp" : k, v);
    EXPECT_TRUE(fingerprintChanges(olderPt, settingsFingerprint(pt)).empty());
}

TEST(ResumeOverrides, AdoptTheCheckpointsFlagsAndRefuseOtherValues) {
    RenderSettings s;
    s.seed = 4;
    s.photonsPerPass = 777;
    s.beamRadius0 = 0.03;
    s.surfaceRadius0 = 0.05;
    s.passes = 10;
    SettingsOverrides flags;
    flags.width = 32;
    const SettingsOverrides cp = checkpointOverrides(s, flags);
    SettingsOverrides given;
    given.passes = 40;
    given.threads = 1;
    given.seed = 4;  // the same value: allowed
    const SettingsOverrides r = resumeOverrides(cp, given);
    EXPECT_EQ(r.passes, 40);
    EXPECT_EQ(r.threads, 1);
    EXPECT_EQ(r.seed, 4u);
    EXPECT_EQ(r.photons, 777);
    EXPECT_EQ(r.radius, 0.03);
    EXPECT_EQ(r.surfaceRadius, 0.05);
    EXPECT_EQ(r.width, 32);
    EXPECT_FALSE(r.autoRadius) << "the radius the pilot chose is written out: no pilot on resume";
    RenderSettings back;
    back.apply(r);
    EXPECT_TRUE(fingerprintChanges(settingsFingerprint(s), settingsFingerprint(back)).empty());

    given.seed = 5;
    try {
        resumeOverrides(cp, given);
        ADD_FAILURE() << "a different seed was accepted";
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find("--seed 5: the checkpoint's render ran with 4"), std::string::npos)
            << e.what();
    }
    SettingsOverrides wider;
    wider.width = 64;
    EXPECT_THROW(resumeOverrides(cp, wider), UserError);
    SettingsOverrides keepPasses;
    EXPECT_EQ(resumeOverrides(cp, keepPasses).passes, 10) << "no --passes: the checkpoint's pass limit";
}

}  // namespace
}  // namespace tpb
