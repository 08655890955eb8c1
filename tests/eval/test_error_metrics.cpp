// Error metrics and reference volumes (core/eval/error_metrics.h, core/eval/reference.h), and the statistical
// agreement of the two renderers:
//  1. metric definitions on synthetic data (exact values): relative RMSE, per frame, totals,
//     half-split self-error, noise correction, power-law fit, log-log interpolation, checkpoints;
//  2. reference files: round trip (bit-identical), mismatch and corruption errors naming the file,
//     film-vs-reference layout;
//  3. the single-scattering quadrature reference against the path tracer (max depth 1), and the
//     path tracer's half-split self-error against its actual error;
//  4. path tracer vs photon beams on a small fog box lit from outside the fog: steady image and
//     transient volume agree within error bars estimated from independent passes / runs;
//  5. the CLI: `tpb reference` (cache reuse), `tpb converge --method both` outputs, mismatch errors.
#include "render/driver.h"
#include "base/error.h"
#include "eval/error_metrics.h"
#include "base/parallel.h"
#include "integrators/path_tracer.h"
#include "eval/reference.h"
#include "base/rng.h"
#include "scene/scene_loader.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unistd.h>

using namespace tpb;
namespace fs = std::filesystem;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

fs::path tempRoot() { return fs::temp_directory_path() / ("tpb_test_error_metrics_" + std::to_string(::getpid())); }

std::string tempDir(const std::string& name) {
    const fs::path p = tempRoot() / name;
    fs::create_directories(p);
    return p.string();
}

// Removes this process's temporary folder at exit.
struct TempCleanup {
    ~TempCleanup() {
        std::error_code ec;
        fs::remove_all(tempRoot(), ec);
    }
} gTempCleanup;

test::TestScene sceneFrom(const std::string& json, const std::string& path = "test.json") {
    return test::testSceneFrom(json, path);
}

std::string readText(const std::string& path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

}  // namespace

// ---- 1. metric definitions ----------------------------------------------------------------------

TEST(ErrorMetrics, RelativeRmseExactValues) {
    const std::vector<double> ref = {1, 2, 3, 4};
    std::vector<double> x;
    for (double r : ref) x.push_back(1.1 * r);
    EXPECT_NEAR(relativeRmse(x, ref), 0.1, 1e-12);                                              // a uniform 10% error
    EXPECT_DOUBLE_EQ(relativeRmse(std::vector<double>{0, 0}, std::vector<double>{3, 4}), 1.0);  // black image
    EXPECT_DOUBLE_EQ(relativeRmse(ref, ref), 0.0);
    // sqrt((1 + 1) / 4)
    EXPECT_NEAR(relativeRmse(std::vector<double>{2, 0, 1, 1}, std::vector<double>{1, 1, 1, 1}), std::sqrt(0.5), 1e-15);
    EXPECT_TRUE(std::isnan(relativeRmse(std::vector<double>{1, 1}, std::vector<double>{0, 0})));
    EXPECT_NEAR(relativeRmse(std::vector<float>{1.5f, 0.5f}, std::vector<float>{1.0f, 1.0f}), 0.5, 1e-7);
    EXPECT_NEAR(relativeRmse(std::vector<double>{1.5, 0.5}, std::vector<float>{1.0f, 1.0f}), 0.5, 1e-15);
    EXPECT_NEAR(relativeTotalDifference(std::vector<double>{1.5, 0.6}, std::vector<double>{1.0, 1.0}), 0.05, 1e-15);

    AbsoluteError a;
    a.add(2.0, 1.0);
    a.add(0.0, 3.0);
    EXPECT_DOUBLE_EQ(a.relative(), 1.0);  // (1 + 3) / (1 + 3)
}

TEST(ErrorMetrics, PerFrameErrorsAddUpToTheVolumeError) {
    // 2 pixels x 3 bins x RGB; bin 0 exact, bin 1 +10%, bin 2 empty in the reference.
    const int bins = 3;
    std::vector<float> ref(2 * bins * 3, 0.0f);
    std::vector<double> x(ref.size(), 0.0);
    for (int p = 0; p < 2; ++p)
        for (int c = 0; c < 3; ++c) {
            ref[(p * bins + 0) * 3 + c] = 1.0f + p + c;
            ref[(p * bins + 1) * 3 + c] = 2.0f * (1 + c);
            x[(p * bins + 0) * 3 + c] = 1.0 + p + c;
            x[(p * bins + 1) * 3 + c] = 1.1 * 2.0 * (1 + c);
        }
    x[(1 * bins + 2) * 3 + 1] = 0.5;  // energy where the reference has none
    const std::vector<double> f = perFrameRelativeRmse(x, ref, bins);
    ASSERT_EQ(f.size(), 3u);
    EXPECT_DOUBLE_EQ(f[0], 0.0);
    EXPECT_NEAR(f[1], 0.1, 1e-12);
    EXPECT_TRUE(std::isnan(f[2]));
    // The volume error pools the sums: sqrt(sum_k diff2_k / sum_k ref2_k).
    double diff2 = 0.0, ref2 = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
        diff2 += (x[i] - ref[i]) * (x[i] - ref[i]);
        ref2 += double(ref[i]) * ref[i];
    }
    EXPECT_NEAR(relativeRmse(x, ref), std::sqrt(diff2 / ref2), 1e-15);
}

TEST(ErrorMetrics, HalfSplitSelfErrorAndNoiseCorrection) {
    EXPECT_DOUBLE_EQ(halfSplitRelativeError(4.0, 1.0, 1, 1), 1.0);  // sqrt(1/4 * 4)
    EXPECT_DOUBLE_EQ(halfSplitRelativeError(4.0, 1.0, 3, 1), std::sqrt(3.0 / 16.0 * 4.0));
    EXPECT_TRUE(std::isnan(halfSplitRelativeError(4.0, 1.0, 3, 0)));
    EXPECT_DOUBLE_EQ(noiseCorrected(0.5, 0.3), 0.4);
    EXPECT_DOUBLE_EQ(noiseCorrected(0.2, 0.3), 0.0);
    EXPECT_TRUE(std::isnan(noiseCorrected(0.5, -1.0)));

    // Statistically: N passes of truth + Gaussian noise; the half-split estimate of the mean's
    // relative RMSE matches its actual relative RMSE (pooled over many entries: within 10%).
    const int n = 4000, passes = 20;
    std::vector<double> truth(n), a(n, 0.0), b(n, 0.0);
    Rng rng(11, Stream::Test, 0, 0);
    for (int i = 0; i < n; ++i) truth[i] = 1.0 + (i % 7);
    for (int p = 0; p < passes; ++p)
        for (int i = 0; i < n; ++i) {
            const double g = std::sqrt(-2.0 * std::log(1.0 - rng.uniform())) * std::cos(2.0 * kPi * rng.uniform());
            (p % 2 ? b : a)[i] += (truth[i] + 0.5 * truth[i] * g) / (passes / 2);
        }
    SquaredError halves, actual;
    std::vector<double> full(n);
    for (int i = 0; i < n; ++i) {
        full[i] = 0.5 * (a[i] + b[i]);
        halves.diff2 += (a[i] - b[i]) * (a[i] - b[i]);
        halves.ref2 += full[i] * full[i];
        actual.add(full[i], truth[i]);
    }
    const double est = halfSplitRelativeError(halves.diff2, halves.ref2, passes / 2, passes / 2);
    EXPECT_NEAR(est / actual.relative(), 1.0, 0.1) << est << " vs " << actual.relative();
}

TEST(ErrorMetrics, PowerLawFitInterpolationAndTimeToReach) {
    std::vector<double> t, e;
    for (int i = 0; i < 8; ++i) {
        t.push_back(std::pow(2.0, i));
        e.push_back(2.0 * std::pow(t.back(), -0.5));
    }
    const PowerLawFit f = fitPowerLaw(t, e);
    EXPECT_NEAR(f.slope, -0.5, 1e-12);
    EXPECT_NEAR(f.intercept, std::log(2.0), 1e-12);
    EXPECT_EQ(f.points, 8);
    EXPECT_NEAR(f.at(16.0), 0.5, 1e-12);
    EXPECT_NEAR(f.timeFor(0.25), 64.0, 1e-9);
    // Second half only: a different early slope does not matter.
    std::vector<double> e2 = e;
    for (int i = 0; i < 4; ++i) e2[i] = 10.0 * std::pow(t[i], -1.0);
    const PowerLawFit h = fitPowerLawSecondHalf(t, e2);
    EXPECT_NEAR(h.slope, -0.5, 1e-12);
    EXPECT_EQ(h.points, 4);
    EXPECT_EQ(fitPowerLawSecondHalf({1, 2, 4}, {1, 0.5, 0.25}).points, 2);
    EXPECT_TRUE(std::isnan(fitPowerLaw({1.0}, {1.0}).slope));
    EXPECT_EQ(fitPowerLaw({1, 2, -1, 4}, {1, 0.5, 3, 0}).points, 2);  // non-positive values skipped

    // Log-log interpolation is exact on a power law; time to reach inverts it.
    EXPECT_NEAR(interpolateLogLog(t, e, 10.0), 2.0 / std::sqrt(10.0), 1e-12);
    EXPECT_NEAR(interpolateLogLog(t, e, 1.0), 2.0, 1e-12);
    EXPECT_TRUE(std::isnan(interpolateLogLog(t, e, 0.5)));
    EXPECT_TRUE(std::isnan(interpolateLogLog(t, e, 1000.0)));
    EXPECT_NEAR(timeToReach(t, e, 0.4), 25.0, 1e-9);
    EXPECT_DOUBLE_EQ(timeToReach(t, e, 5.0), 1.0);                        // already there at the first point
    EXPECT_TRUE(std::isnan(timeToReach(t, e, 0.01)));                     // never reached
    EXPECT_NEAR(timeToReach({1, 2, 4}, {1, 0.6, 0.7}, 0.6), 2.0, 1e-12);  // first crossing
}

TEST(ErrorMetrics, GeometricCheckpoints) {
    const std::vector<double> c = geometricCheckpoints(1.0, 256.0, 9);
    ASSERT_EQ(c.size(), 9u);
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(c[i], std::pow(2.0, i), 1e-9 * std::pow(2.0, i));
    EXPECT_EQ(c.back(), 256.0);
    const std::vector<double> d = geometricCheckpoints(1.0, 256.0, 9, {10.0, 4.0, 300.0, -1.0});
    ASSERT_EQ(d.size(), 10u);  // 10 added, 4 duplicate, 300 and -1 out of range
    EXPECT_TRUE(std::is_sorted(d.begin(), d.end()));
    EXPECT_EQ(geometricCheckpoints(5.0, 2.0, 4), std::vector<double>{2.0});
}

// ---- 2. reference files -------------------------------------------------------------------------

namespace {

ReferenceVolume syntheticReference(int W, int H, int B) {
    ReferenceVolume r;
    ReferenceInfo& i = r.info;
    i.scene = "scenes/x.json";
    i.sceneHash = "fnv1a64:0123456789abcdef";
    i.method = "pt";
    i.passes = 7;
    RenderSettings pt;
    pt.method = Method::PathTracer;
    pt.samplesPerPixel = 3;
    pt.seed = 42;
    pt.maxDepth = 5;
    setSettings(i, pt);
    i.width = W;
    i.height = H;
    i.bins = B;
    i.startOpl = 1.25;
    i.binWidth = 0.05;
    i.requestedPasses = 7;
    i.wallSeconds = 1.5;
    i.halfA = 4;
    i.halfB = 3;
    i.selfErrorReal = 0.1;
    i.selfErrorUnwarped = 0.2;
    i.selfErrorSteady = 0.05;
    i.selfErrorEstimate = "half-split: odd vs even passes";
    for (size_t k = 0; k < i.volumeSize(); ++k) {
        r.real.push_back(std::sin(0.37f * k) + 1.5f);
        r.unwarped.push_back(1.0f / (1.0f + k));
    }
    for (size_t k = 0; k < i.pixels() * 3; ++k) {
        r.steady.push_back(0.5f * k);
        r.selfDiff2.push_back(1e-3f * k);
    }
    return r;
}

void expectUserErrorMentioning(const std::function<void()>& f, const std::vector<std::string>& words) {
    try {
        f();
        ADD_FAILURE() << "no UserError";
    } catch (const UserError& e) {
        const std::string msg = e.what();
        for (const std::string& w : words) EXPECT_NE(msg.find(w), std::string::npos) << "'" << w << "' not in: " << msg;
    }
}

}  // namespace

// A version-1 file (before the settings had one object: seed, max_depth, samples_per_pixel at the
// top of the header; no hash after the arrays) still reads, with the same fields.
TEST(Reference, VersionOneHeadersStillRead) {
    const std::string dir = tempDir("version1");
    const std::string path = dir + "/v1.tpbref";
    const ReferenceVolume r = syntheticReference(4, 2, 3);
    writeReference(path, r);
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    uint64_t n = 0;
    std::memcpy(&n, bytes.data() + 8, 8);
    nlohmann::json h = nlohmann::json::parse(bytes.substr(16, n));
    ASSERT_EQ(h["version"], 2);
    h["version"] = 1;
    h["seed"] = h["settings"]["seed"];
    h["max_depth"] = h["settings"]["max_depth"];
    h["samples_per_pixel"] = h["settings"]["samples_per_pixel"];
    h.erase("settings");
    h.erase("sealed");  // version 1 had no hash after the arrays
    const std::string text = h.dump(2) + "\n";
    const uint64_t m = text.size();
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), 8);
        out.write(reinterpret_cast<const char*>(&m), 8);
        out << text;
        out.write(bytes.data() + 16 + n, static_cast<std::streamsize>(bytes.size() - 16 - n - 8));
    }
    const ReferenceVolume q = readReference(path);
    EXPECT_EQ(q.info.seed, 42u);
    EXPECT_EQ(q.info.maxDepth, 5);
    EXPECT_EQ(q.info.samplesPerPixel, 3);
    EXPECT_EQ(q.real, r.real);
    EXPECT_TRUE(cacheMismatches(q.info, r.info).empty());
}

TEST(Reference, FileRoundTripIsBitIdentical) {
    const std::string dir = tempDir("roundtrip");
    const std::string path = dir + "/a.tpbref";
    const ReferenceVolume r = syntheticReference(5, 3, 4);
    writeReference(path, r);
    const ReferenceVolume q = readReference(path);
    EXPECT_EQ(q.real, r.real);
    EXPECT_EQ(q.unwarped, r.unwarped);
    EXPECT_EQ(q.steady, r.steady);
    EXPECT_EQ(q.selfDiff2, r.selfDiff2);
    const ReferenceInfo& a = r.info;
    const ReferenceInfo& b = q.info;
    EXPECT_EQ(b.scene, a.scene);
    EXPECT_EQ(b.sceneHash, a.sceneHash);
    EXPECT_EQ(b.method, a.method);
    EXPECT_EQ(b.passes, a.passes);
    EXPECT_EQ(b.samplesPerPixel, a.samplesPerPixel);
    EXPECT_EQ(b.seed, a.seed);
    EXPECT_EQ(b.maxDepth, a.maxDepth);
    EXPECT_EQ(b.width, 5);
    EXPECT_EQ(b.height, 3);
    EXPECT_EQ(b.bins, 4);
    EXPECT_EQ(b.startOpl, a.startOpl);
    EXPECT_EQ(b.binWidth, a.binWidth);
    EXPECT_EQ(b.halfA, 4);
    EXPECT_EQ(b.halfB, 3);
    EXPECT_EQ(b.selfErrorReal, 0.1);
    EXPECT_EQ(b.selfErrorEstimate, a.selfErrorEstimate);
    EXPECT_TRUE(referenceMismatches(b, a).empty());
    EXPECT_TRUE(cacheMismatches(b, a).empty());
    EXPECT_EQ(readReferenceInfo(path).bins, 4);
    // The settings (the header's one "settings" object) read back value for value.
    ASSERT_FALSE(a.settings.empty());
    EXPECT_EQ(b.settings.size(), a.settings.size());
    for (const RecordEntry& e : a.settings) {
        const RecordValue* v = recordFind(b.settings, e.key);
        ASSERT_NE(v, nullptr) << e.key;
        EXPECT_EQ(recordText(*v), recordText(e.value)) << e.key;
    }
    // No temporary file left behind, and the layout is the documented one.
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
    EXPECT_EQ(files, 1);
    std::ifstream f(path, std::ios::binary);
    char magic[8];
    uint64_t n = 0;
    f.read(magic, 8);
    f.read(reinterpret_cast<char*>(&n), 8);
    EXPECT_EQ(std::string(magic, 8), "TPBREF1\n");
    // magic, length, header, the arrays, and the 8-byte hash that seals them (version 2).
    EXPECT_EQ(fs::file_size(path), 16 + n + 4 * (2 * 5 * 3 * 4 * 3 + 2 * 5 * 3 * 3) + 8);
    // Without the optional self_diff2 array.
    ReferenceVolume s = r;
    s.selfDiff2.clear();
    writeReference(dir + "/b.tpbref", s);
    EXPECT_TRUE(readReference(dir + "/b.tpbref").selfDiff2.empty());
}

TEST(Reference, MismatchesAndCorruptFilesAreClearErrorsNamingTheFile) {
    const std::string dir = tempDir("mismatch");
    const std::string path = dir + "/ref.tpbref";
    const ReferenceVolume r = syntheticReference(4, 4, 6);
    writeReference(path, r);
    const ReferenceInfo have = readReferenceInfo(path);

    ReferenceInfo want = have;
    want.bins = 8;
    expectUserErrorMentioning([&] { requireCompatible(path, have, want); }, {path, "bins", "6", "8"});
    want = have;
    want.width = 8;
    expectUserErrorMentioning([&] { requireCompatible(path, have, want); }, {path, "resolution", "4x4", "8x4"});
    want = have;
    want.maxDepth = 1;
    expectUserErrorMentioning([&] { requireCompatible(path, have, want); }, {path, "max depth", "--max-depth 5"});
    want = have;
    want.startOpl += 0.01;
    expectUserErrorMentioning([&] { requireCompatible(path, have, want); }, {path, "time range"});
    want = have;
    want.sceneHash = "fnv1a64:ffffffffffffffff";
    expectUserErrorMentioning([&] { requireCompatible(path, have, want); }, {path, "scene file contents"});
    want = have;
    want.startOpl += 1e-9;  // within tolerance
    EXPECT_NO_THROW(requireCompatible(path, have, want));
    // A cached reference is reused only with the same method, seed, spp and budget.
    want = have;
    want.seed = 43;
    EXPECT_FALSE(cacheMismatches(have, want).empty());
    want = have;
    want.requestedPasses = 8;
    EXPECT_FALSE(cacheMismatches(have, want).empty());
    EXPECT_TRUE(referenceMismatches(have, want).empty());  // but it is still a usable reference

    // Corrupt or missing files.
    const std::string missing = dir + "/nope.tpbref";
    expectUserErrorMentioning([&] { readReference(missing); }, {missing});
    const std::string truncated = dir + "/truncated.tpbref";
    fs::copy_file(path, truncated);
    fs::resize_file(truncated, fs::file_size(path) - 4);
    expectUserErrorMentioning([&] { readReference(truncated); }, {truncated, "truncated"});
    // One flipped bit in an array: the hash that seals the arrays refuses it.
    const std::string flipped = dir + "/flipped.tpbref";
    fs::copy_file(path, flipped);
    {
        std::fstream f(flipped, std::ios::binary | std::ios::in | std::ios::out);
        f.seekg(-20, std::ios::end);
        char c = 0;
        f.read(&c, 1);
        c = static_cast<char>(c ^ 0x10);
        f.seekp(-20, std::ios::end);
        f.write(&c, 1);
    }
    expectUserErrorMentioning([&] { readReference(flipped); }, {flipped, "corrupted"});
    const std::string bad = dir + "/bad.tpbref";
    {
        std::ofstream f(bad, std::ios::binary);
        f << "not a reference at all";
    }
    expectUserErrorMentioning([&] { readReference(bad); }, {bad, "magic"});
    const std::string badHeader = dir + "/badheader.tpbref";
    {
        std::ofstream f(badHeader, std::ios::binary);
        const std::string h = "{\"format\": \"tpb-reference\", \"version\": 9}";
        const uint64_t n = h.size();
        f.write("TPBREF1\n", 8);
        f.write(reinterpret_cast<const char*>(&n), 8);
        f << h;
    }
    expectUserErrorMentioning([&] { readReference(badHeader); }, {badHeader, "version 9"});
}

TEST(Reference, FilmComparisonUsesTheVolumeLayout) {
    // A film with one pass of known values (18x5 pixels: two tiles across), a reference 1/1.25 of it
    // on the real axis and equal on the unwarped axis and steady image.
    const int W = 18, H = 5, B = 3;
    TimeBins tb{0.0, 1.0, B};
    TransientFilm film(W, H, tb);
    ReferenceVolume ref = syntheticReference(W, H, B);
    ref.info.startOpl = 0.0;
    ref.info.binWidth = 1.0;
    PixelAccumulator acc(B);
    for (int t = 0; t < film.tileCount(); ++t) {
        const TileRect r = film.tileRect(t);
        TransientFilm::TileWriter w(film, t);
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                const size_t p = static_cast<size_t>(y) * W + x;
                for (int k = 0; k < B; ++k) {
                    const Color v(1.0 + p + k, 2.0 + k, 0.5 + 0.1 * p);
                    acc.add(TimeAxis::Real, k, v);
                    acc.add(TimeAxis::Unwarped, k, v);
                    for (int c = 0; c < 3; ++c) {
                        ref.real[(p * B + k) * 3 + c] = static_cast<float>(v[c] / 1.25);
                        ref.unwarped[(p * B + k) * 3 + c] = static_cast<float>(v[c]);
                    }
                }
                const Color s(3.0 + p, 1.0, 2.0);
                acc.addSteady(s);
                for (int c = 0; c < 3; ++c) ref.steady[p * 3 + c] = static_cast<float>(s[c]);
                w.addPixel(x, y, acc);
                acc.clearTouched();
            }
    }
    const FilmError real = compareWithReference(film, ref, TimeAxis::Real, true);
    EXPECT_NEAR(real.volume, 0.25, 1e-6);
    for (double e : real.perFrame) EXPECT_NEAR(e, 0.25, 1e-6);
    EXPECT_NEAR(real.volumeL1, 0.25, 1e-6);
    EXPECT_NEAR(real.steady, 0.0, 1e-7);
    EXPECT_NEAR(real.steadyTotalDiff, 0.0, 1e-7);
    EXPECT_NEAR(compareWithReference(film, ref, TimeAxis::Unwarped, false).volume, 0.0, 1e-7);
    // Masked pixels leave the sums.
    std::vector<uint8_t> mask(static_cast<size_t>(W) * H, 0);
    for (size_t p = 0; p < mask.size(); p += 2) {
        mask[p] = 1;
        for (int k = 0; k < B; ++k)
            for (int c = 0; c < 3; ++c) ref.unwarped[(p * B + k) * 3 + c] = 1e6f;
    }
    EXPECT_NEAR(compareWithReference(film, ref, TimeAxis::Unwarped, false, &mask).volume, 0.0, 1e-7);
    EXPECT_GT(compareWithReference(film, ref, TimeAxis::Unwarped, false).volume, 0.5);
}

// ---- 3. single-scattering quadrature vs the path tracer --------------------------------------

namespace {

// A point light pulse (emitted at 1 ns) in an infinite coloured medium with an index of refraction.
const char* kPointMedium = R"({
  "version": 1,
  "camera": {"position": [0.2, 0.1, 3], "look_at": [0, 0, 0], "fov": 40, "resolution": [14, 14]},
  "film": {"start_m": 0.965, "bin_width_m": 0.3325, "bins": 18},
  "media": {"m": {"sigma_s": [0.3, 0.4, 0.5], "sigma_a": [0.1, 0.05, 0.2], "g": 0.4, "ior": 1.33}},
  "global_medium": "m",
  "lights": [{"type": "point", "position": [0, 0, 0], "power": [10, 8, 6], "emit_time_ns": 1}],
  "render": {"max_depth": 1, "seed": 5}
})";

// Relative RMSE of two arrays over the unmasked pixels (`per` values per pixel).
double maskedRmse(const std::vector<float>& x, const std::vector<float>& ref, const std::vector<uint8_t>& mask,
                  size_t per) {
    SquaredError e;
    for (size_t p = 0; p < mask.size(); ++p)
        if (!mask[p])
            for (size_t j = 0; j < per; ++j) e.add(x[p * per + j], ref[p * per + j]);
    return e.relative();
}

}  // namespace

TEST(Reference, SingleScatteringQuadratureAgreesWithThePathTracer) {
    auto scene = sceneFrom(kPointMedium);
    const ReferenceVolume exact =
        singleScatteringReference(*scene, scene.time, scene.source.path, scene.settings, 4, 2);
    EXPECT_EQ(exact.info.method, "analytic-single-scattering");
    EXPECT_EQ(exact.info.maxDepth, 1);
    // Energy bookkeeping: the bins hold what arrives inside the film, the steady image everything.
    double steady = 0.0, real = 0.0, unw = 0.0;
    for (float v : exact.steady) steady += v;
    for (float v : exact.real) real += v;
    for (float v : exact.unwarped) unw += v;
    EXPECT_GT(real, 0.5 * steady);
    EXPECT_LE(real, steady * (1 + 1e-6));
    EXPECT_LE(unw, steady * (1 + 1e-6));

    ReferenceJob job;
    job.method = "pt";
    job.pt.seed = 9;
    job.pt.samplesPerPixel = 16;
    job.pt.maxDepth = 1;
    job.pt.threads = 2;
    job.passes = 160;
    const ReferenceVolume pt = renderReference(*scene, scene.time, scene.source.path, job);
    EXPECT_EQ(pt.info.passes, 160);
    EXPECT_EQ(pt.info.halfA, 80);
    EXPECT_GT(pt.info.selfErrorReal, 0.0);

    // The pixels next to the light's image are left out: there the path tracer's next-event
    // estimate has a 1 / h singularity (heavy tails) and the quadrature is least accurate.
    const std::vector<uint8_t> mask = lightPixelMask(*scene, 2.5);
    ASSERT_GT(std::count(mask.begin(), mask.end(), uint8_t(0)), 150);
    const size_t B3 = static_cast<size_t>(scene.time.bins) * 3;
    const double eSteady = maskedRmse(pt.steady, exact.steady, mask, 3);
    const double eReal = maskedRmse(pt.real, exact.real, mask, B3);
    const double eUnw = maskedRmse(pt.unwarped, exact.unwarped, mask, B3);
    const double sSteady = referenceSelfError(pt, TimeAxis::Real, true, &mask);
    const double sReal = referenceSelfError(pt, TimeAxis::Real, false, &mask);
    const double sUnw = referenceSelfError(pt, TimeAxis::Unwarped, false, &mask);
    std::printf(
        "path tracer (2560 spp) vs quadrature: steady %.4f (own estimate %.4f), real %.4f (%.4f), "
        "unwarped %.4f (%.4f)\n",
        eSteady, sSteady, eReal, sReal, eUnw, sUnw);
    // Unbiased: the actual error is the path tracer's noise, which the half-split estimates (the
    // pooled estimate itself fluctuates by ~10-20% here). With 40x the samples the error keeps
    // falling as t^-0.5 to ~0.25% (checked with `tpb converge --mask-lights 2.5`): no bias.
    EXPECT_LT(eSteady, 0.05);
    EXPECT_LT(eReal, 0.08);
    EXPECT_LT(eUnw, 0.15);
    EXPECT_NEAR(eSteady / sSteady, 1.0, 0.4);
    EXPECT_NEAR(eReal / sReal, 1.0, 0.4);
    EXPECT_NEAR(eUnw / sUnw, 1.0, 0.4);
    double ts = 0.0, te = 0.0;
    for (size_t p = 0; p < mask.size(); ++p)
        if (!mask[p])
            for (int c = 0; c < 3; ++c) {
                ts += pt.steady[p * 3 + c];
                te += exact.steady[p * 3 + c];
            }
    EXPECT_NEAR(ts / te, 1.0, 0.01);
}

TEST(Reference, SingleScatteringRefusesOtherScenes) {
    std::string withShape = kPointMedium;
    withShape.replace(withShape.find("\"lights\""), 0,
                      "\"materials\": {\"w\": {\"type\": \"diffuse\"}}, \"shapes\": [{\"type\": \"quad\", \"corner\": "
                      "[-1, -1, -1], \"edge_u\": [2, 0, 0], \"edge_v\": [0, 0, 2], \"material\": \"w\"}],\n  ");
    auto s1 = sceneFrom(withShape, "with_shape.json");
    expectUserErrorMentioning([&] { singleScatteringReference(*s1, s1.time, s1.source.path, s1.settings); },
                              {"with_shape.json", "1 shapes"});
    std::string twoLights = kPointMedium;
    twoLights.replace(twoLights.find("1}],"), 4, "1}, {\"type\": \"point\", \"position\": [1, 0, 0], \"power\": 1}],");
    auto s2 = sceneFrom(twoLights, "two_lights.json");
    expectUserErrorMentioning([&] { singleScatteringReference(*s2, s2.time, s2.source.path, s2.settings); },
                              {"two_lights.json", "2 lights"});
}

// ---- 4. path tracer vs photon beams ------------------------------------------------------------

namespace {

// A fog-filled box (null boundary) over a floor, in front of a red wall, lit by a point light
// pulse outside the fog: every path vertex stays >= 0.6 m from the light, so the path tracer's
// next-event estimates are bounded and its error bars from the spread of passes are reliable.
// (With the light inside the fog, a vertex near it makes 1 / d^2 unbounded: infinite variance.)
// max_depth 64: the two renderers count depth differently across null boundaries (the photon
// tracer and the camera pass count a crossing as a bounce, the path tracer does not), so a low
// limit cuts different paths (max_depth 8 here: beams 3% darker, 25% in the late bins).
// Small kernels: the kernel bias at the fog box's faces and the floor's edges is ~1.7% of the
// image total at 0.004 / 0.012 and ~0.6% at 0.002 / 0.006 (relative radii).
const char* kFogBox = R"({
  "version": 1,
  "camera": {"position": [0, 1.0, 4.0], "look_at": [0, 0.8, 0], "fov": 40, "resolution": [24, 24]},
  "film": {"bins": 32, "range": "auto"},
  "media": {"fog": {"sigma_s": 0.8, "sigma_a": 0.1, "g": 0.3}},
  "materials": {"white": {"type": "diffuse", "albedo": 0.7}, "red": {"type": "diffuse", "albedo": [0.7, 0.2, 0.15]},
                "fogbox": {"type": "null"}},
  "shapes": [
    {"name": "floor", "type": "quad", "corner": [-1.5, 0, -1.5], "edge_u": [0, 0, 3], "edge_v": [3, 0, 0], "material": "white"},
    {"name": "back", "type": "quad", "corner": [-1.5, 0, -1.5], "edge_u": [3, 0, 0], "edge_v": [0, 2.5, 0], "material": "red"},
    {"name": "fog", "type": "box", "min": [-0.8, 0.2, -0.8], "max": [0.8, 1.4, 0.8], "material": "fogbox", "interior_medium": "fog"}
  ],
  "lights": [{"type": "point", "position": [0.2, 2.0, 0.3], "power": 20, "emit_time_ns": 0}],
  "render": {"photons_per_pass": 20000, "radius_relative": 0.002, "surface_radius_relative": 0.006, "alpha": 0.7,
             "max_depth": 64, "seed": 1}
})";

// Mean and standard error per entry from independent samples (sums of x and x^2).
struct Moments {
    std::vector<double> sum, sum2;
    int n = 0;
    explicit Moments(size_t size) : sum(size, 0.0), sum2(size, 0.0) {}
    void add(const std::vector<double>& x) {
        for (size_t i = 0; i < x.size(); ++i) {
            sum[i] += x[i];
            sum2[i] += x[i] * x[i];
        }
        ++n;
    }
    double mean(size_t i) const { return sum[i] / n; }
    double se2(size_t i) const {  // squared standard error of the mean
        const double m = mean(i);
        return std::max(0.0, (sum2[i] - n * m * m) / (n - 1.0)) / n;
    }
};

// Layout of one estimate: per pixel, [real bins | unwarped bins | steady] x RGB.
size_t slot(int bins, size_t pixel, int s, int c) { return (pixel * (2 * bins + 1) + s) * 3 + c; }

struct Comparison {
    double within4 = 0.0;  // fraction of compared entries with |z| < 4
    double chi2 = 0.0;     // sum d^2 / sum (se_a^2 + se_b^2): ~1 when both agree within noise
    int entries = 0;
};

Comparison compare(const Moments& a, const Moments& b, const std::vector<size_t>& idx) {
    Comparison r;
    double d2 = 0.0, s2 = 0.0;
    int ok = 0;
    for (size_t i : idx) {
        const double d = a.mean(i) - b.mean(i), s = a.se2(i) + b.se2(i);
        if (!(s > 0.0)) continue;
        d2 += d * d;
        s2 += s;
        ok += std::abs(d) < 4.0 * std::sqrt(s);
        ++r.entries;
    }
    r.within4 = r.entries ? double(ok) / r.entries : 0.0;
    r.chi2 = s2 > 0.0 ? d2 / s2 : 0.0;
    return r;
}

}  // namespace

TEST(Consistency, PathTracerAndPhotonBeamsAgreeWithinErrorBars) {
    auto scene = sceneFrom(kFogBox, "fog_box.json");
    const int W = scene->camera.width, H = scene->camera.height, B = scene.time.bins;
    const size_t P = static_cast<size_t>(W) * H, size = P * (2 * B + 1) * 3;
    ASSERT_TRUE(scene->stages.beams && scene->stages.surfacePhotons);

    // Path tracer: every pass is an independent estimate of every pixel.
    RenderSettings ps;
    ps.maxDepth = 64;  // the path tracer's depth unless set below
    ps.seed = 3;
    ps.samplesPerPixel = 16;
    ps.maxDepth = scene.settings.maxDepth;
    const int ptPasses = 40;
    Moments pt(size);
    std::vector<double> est(size);
    const int threads = 2;
    std::vector<PixelAccumulator> accs(threads, PixelAccumulator(B));
    std::vector<PathTracerStats> stats(threads);
    for (int pass = 1; pass <= ptPasses; ++pass) {
        std::fill(est.begin(), est.end(), 0.0);
        parallelFor(static_cast<int64_t>(P), threads, [&](int64_t p, int t) {
            PixelAccumulator& acc = accs[t];
            pathTracePixel(*scene, ps, pass, scene.time, static_cast<int>(p % W), static_cast<int>(p / W), acc,
                           stats[t]);
            for (int a = 0; a < 2; ++a)
                for (int k = 0; k < B; ++k)
                    for (int c = 0; c < 3; ++c) est[slot(B, p, a * B + k, c)] = acc.bin(static_cast<TimeAxis>(a), k)[c];
            for (int c = 0; c < 3; ++c) est[slot(B, p, 2 * B, c)] = acc.steady()[c];
            acc.clearTouched();
        });
        pt.add(est);
    }
    for (const PathTracerStats& s : stats) EXPECT_EQ(s.rejected, 0);

    // Photon beams: independent progressive runs (different seeds), the spread across runs.
    const int runs = 8, passes = 12;
    Moments beams(size);
    std::vector<double> vol[2];
    std::vector<float> steady;
    for (int run = 0; run < runs; ++run) {
        RenderSettings ds = scene.settings;
        ds.seed = 100 + run;
        ds.threads = threads;
        Driver drv(*scene, ds, scene.time);
        for (int p = 1; p <= passes; ++p) ASSERT_TRUE(drv.runPass(p));
        EXPECT_EQ(drv.film().stats.rejectedSamples.load(), 0);
        drv.film().volume(TimeAxis::Real, EmissionMode::Delta, vol[0]);
        drv.film().volume(TimeAxis::Unwarped, EmissionMode::Delta, vol[1]);
        drv.film().steadyImage(steady);
        for (size_t p = 0; p < P; ++p) {
            for (int a = 0; a < 2; ++a)
                for (int k = 0; k < B; ++k)
                    for (int c = 0; c < 3; ++c) est[slot(B, p, a * B + k, c)] = vol[a][(p * B + k) * 3 + c];
            for (int c = 0; c < 3; ++c) est[slot(B, p, 2 * B, c)] = steady[p * 3 + c];
        }
        beams.add(est);
    }

    // Totals of the steady image per channel: within 3%.
    for (int c = 0; c < 3; ++c) {
        double tp = 0.0, tb = 0.0;
        for (size_t p = 0; p < P; ++p) {
            tp += pt.mean(slot(B, p, 2 * B, c));
            tb += beams.mean(slot(B, p, 2 * B, c));
        }
        std::printf("steady total, channel %d: beams / path tracer = %.4f\n", c, tb / tp);
        EXPECT_NEAR(tb / tp, 1.0, 0.03) << "channel " << c << ": beams " << tb << ", path tracer " << tp;
    }

    // Per pixel: steady image (each channel), and the transient volume (every pixel, bin, channel
    // holding some light) on both axes.
    std::vector<size_t> steadyIdx, volIdx[2];
    double peak = 0.0;
    for (size_t p = 0; p < P; ++p)
        for (int k = 0; k < 2 * B; ++k)
            for (int c = 0; c < 3; ++c) peak = std::max(peak, pt.mean(slot(B, p, k, c)));
    for (size_t p = 0; p < P; ++p)
        for (int c = 0; c < 3; ++c) {
            steadyIdx.push_back(slot(B, p, 2 * B, c));
            for (int a = 0; a < 2; ++a)
                for (int k = 0; k < B; ++k) {
                    const size_t i = slot(B, p, a * B + k, c);
                    if (std::max(pt.mean(i), beams.mean(i)) > 1e-3 * peak) volIdx[a].push_back(i);
                }
        }
    const Comparison cs = compare(pt, beams, steadyIdx), cr = compare(pt, beams, volIdx[0]),
                     cu = compare(pt, beams, volIdx[1]);
    std::printf(
        "beams vs path tracer: steady %d entries, %.1f%% within 4 sigma, chi2/n %.2f; volume real %d entries, "
        "%.1f%%, %.2f; unwarped %d entries, %.1f%%, %.2f\n",
        cs.entries, 100 * cs.within4, cs.chi2, cr.entries, 100 * cr.within4, cr.chi2, cu.entries, 100 * cu.within4,
        cu.chi2);
    EXPECT_GT(cs.entries, 1000);
    EXPECT_GT(cs.within4, 0.92);
    EXPECT_GT(cr.within4, 0.92);
    EXPECT_GT(cu.within4, 0.92);
    // Pooled: the squared differences are what the error bars predict (kernel bias would add).
    EXPECT_LT(cs.chi2, 2.0);
    EXPECT_LT(cr.chi2, 2.0);
    EXPECT_LT(cu.chi2, 2.0);

    // Whole-image time profile: per bin, the sum over pixels (high signal: bias would show).
    for (int a = 0; a < 2; ++a) {
        double maxBin = 0.0;
        std::vector<double> tp(B, 0.0), tb(B, 0.0), s2(B, 0.0);
        for (int k = 0; k < B; ++k) {
            for (size_t p = 0; p < P; ++p)
                for (int c = 0; c < 3; ++c) {
                    const size_t i = slot(B, p, a * B + k, c);
                    tp[k] += pt.mean(i);
                    tb[k] += beams.mean(i);
                }
            maxBin = std::max(maxBin, tp[k]);
        }
        for (int k = 0; k < B; ++k) {
            if (tp[k] < 0.02 * maxBin) continue;
            EXPECT_NEAR(tb[k] / tp[k], 1.0, 0.06)
                << "axis " << a << " bin " << k << ": beams " << tb[k] << ", pt " << tp[k];
        }
    }
}

// ---- 5. the CLI ---------------------------------------------------------------------------------

namespace {

int runTpb(const std::string& args, std::string& output) {
    const std::string log = tempDir("cli") + "/log.txt";
    const std::string cmd = std::string(TPB_BINARY) + " " + args + " > " + log + " 2>&1";
    const int rc = std::system(cmd.c_str());
    output = readText(log);
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace

TEST(Cli, ReferenceCacheAndConvergeOutputs) {
    const std::string dir = tempDir("cli_run");
    const std::string scene = std::string(TPB_SOURCE_DIR) + "/scenes/point_medium.json";
    const std::string small = " --width 16 --height 16 --bins 24 --threads 2";
    const std::string ref = dir + "/ref/ss.tpbref";
    std::string out;
    ASSERT_EQ(runTpb("reference " + scene + small + " --analytic-single-scattering -o " + ref, out), 0) << out;
    ASSERT_TRUE(fs::exists(ref));

    // A path-traced reference is reused when asked again with the same settings.
    const std::string ptRef = dir + "/ref/pt.tpbref";
    ASSERT_EQ(runTpb("reference " + scene + small + " --max-depth 1 --passes 2 --spp 2 -o " + ptRef, out), 0) << out;
    EXPECT_EQ(out.find("reusing"), std::string::npos);
    ASSERT_EQ(runTpb("reference " + scene + small + " --max-depth 1 --passes 2 --spp 2 -o " + ptRef, out), 0) << out;
    EXPECT_NE(out.find("reusing"), std::string::npos) << out;
    ASSERT_EQ(runTpb("reference " + scene + small + " --max-depth 1 --passes 3 --spp 2 -o " + ptRef, out), 0) << out;
    EXPECT_NE(out.find("re-rendering"), std::string::npos) << out;

    // Converge against the quadrature: both methods, equal-time strip, plot.
    const std::string cv = dir + "/cv";
    ASSERT_EQ(
        runTpb("converge " + scene + small + " --max-depth 1 --reference " + ref +
                   " --method both --time 0.6 --first-checkpoint 0.05 --checkpoints 4 --frames 3 --at 0.3 -o " + cv,
               out),
        0)
        << out;
    EXPECT_NE(out.find("fitted convergence slope"), std::string::npos) << out;
    const std::string csv = readText(cv + "/convergence.csv");
    EXPECT_EQ(csv.rfind("method,checkpoint,elapsed_s,passes,", 0), 0u);
    EXPECT_NE(csv.find("\nbeams,"), std::string::npos);
    EXPECT_NE(csv.find("\npt,"), std::string::npos);
    for (const char* f : {"convergence.json", "convergence.gp", "equal_time.png", "equal_time.csv"})
        EXPECT_TRUE(fs::exists(cv + "/" + f)) << f;
    // (the SVG/PNG need gnuplot; converge only warns without it)

    // A run that does not match the reference: exit code 2 and a message naming the file.
    EXPECT_EQ(runTpb("converge " + scene + " --width 16 --height 16 --bins 20 --threads 2 --max-depth 1 --reference " +
                         ref + " --time 0.1 -o " + dir + "/cv2",
                     out),
              2);
    EXPECT_NE(out.find(ref), std::string::npos) << out;
    EXPECT_NE(out.find("bins"), std::string::npos) << out;
    EXPECT_EQ(
        runTpb("converge " + scene + small + " --max-depth 3 --reference " + ref + " --time 0.1 -o " + dir + "/cv3",
               out),
        2);
    EXPECT_NE(out.find("--max-depth 1"), std::string::npos) << out;
    // Without overrides the run takes the reference's resolution, bins and depth.
    ASSERT_EQ(
        runTpb("converge " + scene + " --threads 2 --reference " + ref + " --time 0.2 --no-plot -o " + dir + "/cv4",
               out),
        0)
        << out;
    EXPECT_NE(out.find("--width 16 --height 16 --bins 24 --max-depth 1"), std::string::npos) << out;

    // render --method pt writes the same outputs as the beam renderer.
    const std::string rd = dir + "/render_pt";
    ASSERT_EQ(runTpb("render " + scene + small + " --method pt --spp 2 --passes 2 --frame-step 8 -q -o " + rd, out), 0)
        << out;
    for (const char* f : {"steady.exr", "steady.png", "summary.json", "strip.png", "frames/frame_00000.exr"})
        EXPECT_TRUE(fs::exists(rd + "/" + f)) << f;
    EXPECT_NE(readText(rd + "/summary.json").find("\"method\": \"pt\""), std::string::npos);
}
