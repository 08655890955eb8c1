// The volume export (core/film/volume_export.h) read back by NumPy: /usr/bin/python3 loads
// transient.npy, steady/before/after.npy with numpy.load as they are, and transient.json with
// json; the test compares shape, dtype, C order and every value with the film's views
// (film_view.h) in both axes and emission modes, and the side file's fields with the film.
// Skipped (with the reason) when /usr/bin/python3 has no numpy (apt-get install python3-numpy).
#include "film/film_view.h"
#include "film/volume_export.h"
#include "film_test_passes.h"
#include "io/npy.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace tpb;
namespace fs = std::filesystem;

namespace {

const char* kPython = "/usr/bin/python3";

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

// Runs a shell command, returns its exit code and stdout.
int run(const std::string& cmd, std::string& out) {
    out.clear();
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return -1;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    const int st = ::pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string numpyMissing() {
    std::string out;
    if (!fs::exists(kPython)) return std::string(kPython) + " is missing (apt-get install python3 python3-numpy)";
    if (run(std::string(kPython) + " -c 'import numpy' 2>&1", out) != 0)
        return std::string(kPython) + " cannot import numpy (apt-get install python3-numpy): " + out;
    return "";
}

// 37x21 pixels (tiles full and partial), 9 bins, 3 passes of synthetic estimates.
std::shared_ptr<const FilmSnapshot> snapshot() {
    static const std::unique_ptr<TransientFilm> film = [] {
        auto f = std::make_unique<TransientFilm>(37, 21, TimeBins{2.0, 0.25, 9});
        for (uint64_t p = 1; p <= 3; ++p) test::addRandomPass(*f, 5, p);
        return f;
    }();
    return film->snapshot();
}

VolumeProvenance provenance() {
    VolumeProvenance v;
    v.scene = "scenes/x.json";
    v.settings = {{"method", std::string("beams")},
                  {"seed", uint64_t(42)},
                  {"photons_per_pass", int64_t(12345)},
                  {"volume_estimator", std::string("beam2d")},
                  {"alpha", 0.75},
                  {"radius", 0.05}};
    v.beamRadius = 0.04;
    return v;
}

// Loads the files with numpy and writes them back as raw float32 (C order, what numpy holds),
// plus a JSON line with what numpy says about them.
const char* kReadBack = R"PY(
import json, sys, numpy as np
d = sys.argv[1]
info = {}
for name in ["transient", "steady", "before", "after"]:
    a = np.load(d + "/" + name + ".npy")
    info[name] = {"shape": list(a.shape), "dtype": str(a.dtype), "fortran": bool(np.isfortran(a)),
                  "c_contiguous": bool(a.flags["C_CONTIGUOUS"])}
    np.ascontiguousarray(a, dtype="<f4").tofile(d + "/" + name + ".raw")
v = np.load(d + "/transient.npy")
info["probe"] = float(v[3, 30, 5, 1])  # [y, x, k, c]
print(json.dumps(info))
)PY";

std::vector<float> rawFloats(const fs::path& p) {
    const std::string b = slurp(p);
    std::vector<float> v(b.size() / 4);
    std::memcpy(v.data(), b.data(), v.size() * 4);
    return v;
}

}  // namespace

TEST(NpyVolumeExport, NumpyLoadsTheFilmValueForValueWithItsTimeAxis) {
    const std::string missing = numpyMissing();
    if (!missing.empty()) GTEST_SKIP() << missing;
    const auto s = snapshot();
    const int W = s->width(), H = s->height(), B = s->bins();
    test::TempDir tmp("npy_volume");
    tmp.write("read_back.py", kReadBack);
    for (int a = 0; a < 2; ++a)
        for (EmissionMode mode : {EmissionMode::Delta, EmissionMode::Continuous}) {
            const TimeAxis axis = static_cast<TimeAxis>(a);
            SCOPED_TRACE(std::string(a == 0 ? "real" : "unwarped") +
                         (mode == EmissionMode::Delta ? " delta" : " continuous"));
            ExportOptions opt;
            opt.axis = axis;
            opt.mode = mode;
            const fs::path dir = tmp / ("v" + std::to_string(a) + std::to_string(static_cast<int>(mode)));
            int lastRow = 0;
            const std::vector<std::string> names =
                exportVolumeNpy(*s, dir.string(), opt, provenance(), [&](int rows, int total) {
                    EXPECT_EQ(rows, lastRow + 1);
                    EXPECT_EQ(total, H);
                    lastRow = rows;
                });
            EXPECT_EQ(names, volumeFileNames());
            EXPECT_EQ(lastRow, H);
            std::string out;
            ASSERT_EQ(
                run(std::string(kPython) + " " + (tmp / "read_back.py").string() + " " + dir.string() + " 2>&1", out),
                0)
                << out;
            const nlohmann::json info = nlohmann::json::parse(out);
            EXPECT_EQ(info["transient"]["shape"], nlohmann::json({H, W, B, 3}));
            for (const char* n : {"steady", "before", "after"})
                EXPECT_EQ(info[n]["shape"], nlohmann::json({H, W, 3})) << n;
            for (const char* n : {"transient", "steady", "before", "after"}) {
                EXPECT_EQ(info[n]["dtype"], "float32") << n;
                EXPECT_FALSE(info[n]["fortran"].get<bool>()) << n;
                EXPECT_TRUE(info[n]["c_contiguous"].get<bool>()) << n;
            }
            // Every value, against the pixel profiles (volume[y, x, k, c]).
            const std::vector<float> vol = rawFloats(dir / "transient.raw");
            ASSERT_EQ(vol.size(), static_cast<size_t>(H) * W * B * 3);
            size_t mismatches = 0, nonZero = 0;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const std::vector<float> prof = pixelProfile(*s, x, y, axis, mode);
                    for (int k = 0; k < B; ++k)
                        for (int c = 0; c < 3; ++c) {
                            const float want = prof[static_cast<size_t>(k) * 3 + c];
                            const float got = vol[((static_cast<size_t>(y) * W + x) * B + k) * 3 + c];
                            mismatches += got != want;
                            nonZero += want != 0.0f;
                        }
                }
            EXPECT_EQ(mismatches, 0u);
            EXPECT_GT(nonZero, vol.size() / 4) << "the synthetic film must not be mostly black";
            EXPECT_EQ(info["probe"].get<float>(), pixelProfile(*s, 30, 3, axis, mode)[5 * 3 + 1]);
            // The continuous volume's bin k equals frameImage's continuous frame k (its prefix sums).
            const std::vector<float> f4 = frameImage(*s, 4, axis, mode);
            EXPECT_EQ(vol[((static_cast<size_t>(7) * W + 11) * B + 4) * 3 + 2],
                      f4[(static_cast<size_t>(7) * W + 11) * 3 + 2]);
            EXPECT_EQ(rawFloats(dir / "steady.raw"), steadyImage(*s));
            EXPECT_EQ(rawFloats(dir / "before.raw"), beforeImage(*s, axis));
            EXPECT_EQ(rawFloats(dir / "after.raw"), afterImage(*s, axis));

            // The side file.
            const nlohmann::json j = nlohmann::json::parse(slurp(dir / "transient.json"));
            EXPECT_EQ(j["shape"], nlohmann::json({H, W, B, 3}));
            EXPECT_EQ(j["time"]["axis"], a == 0 ? "real" : "unwarped");
            EXPECT_EQ(j["time"]["emission"], mode == EmissionMode::Delta ? "delta" : "continuous");
            EXPECT_EQ(j["time"]["bins"], B);
            EXPECT_DOUBLE_EQ(j["time"]["start_opl_m"].get<double>(), 2.0);
            EXPECT_DOUBLE_EQ(j["time"]["bin_width_opl_m"].get<double>(), 0.25);
            EXPECT_NEAR(j["time"]["start_ns"].get<double>(), 2.0 / 0.299792458, 1e-12);
            EXPECT_NEAR(j["time"]["bin_width_ns"].get<double>(), 0.25 / 0.299792458, 1e-12);
            EXPECT_EQ(j["render"]["passes"], 3);
            EXPECT_EQ(j["render"]["settings"]["seed"], 42);
            EXPECT_EQ(j["render"]["settings"]["photons_per_pass"], 12345);
            EXPECT_EQ(j["render"]["scene"], "scenes/x.json");
            EXPECT_EQ(j["render"]["settings"]["volume_estimator"], "beam2d");
            EXPECT_DOUBLE_EQ(j["render"]["beam_radius_m"].get<double>(), 0.04);
            double before = 0.0, after = 0.0;
            for (float v : beforeImage(*s, axis)) before += v;
            for (float v : afterImage(*s, axis)) after += v;
            const auto& e = j["energy"];
            EXPECT_NEAR(
                e["before_rgb"][0].get<double>() + e["before_rgb"][1].get<double>() + e["before_rgb"][2].get<double>(),
                before, 1e-9 * before);
            EXPECT_NEAR(
                e["after_rgb"][0].get<double>() + e["after_rgb"][1].get<double>() + e["after_rgb"][2].get<double>(),
                after, 1e-9 * after);
            EXPECT_GT(e["before_fraction"].get<double>(), 0.0);  // the synthetic passes put light before and after
            EXPECT_GT(e["after_fraction"].get<double>(), 0.0);
            EXPECT_NEAR(e["before_fraction"].get<double>() + e["inside_fraction"].get<double>() +
                            e["after_fraction"].get<double>(),
                        1.0, 1e-9);
        }
}

TEST(NpyVolumeExport, CancelLeavesNoVolumeAndNoSideFile) {
    const auto s = snapshot();
    test::TempDir tmp("npy_cancel");
    std::atomic<bool> cancel{false};
    const std::vector<std::string> names = exportVolumeNpy(
        *s, tmp.path().string(), ExportOptions{}, provenance(),
        [&](int rows, int) {
            if (rows == 5) cancel = true;
        },
        &cancel);
    EXPECT_EQ(names, (std::vector<std::string>{"steady.npy", "before.npy", "after.npy"}));
    EXPECT_FALSE(fs::exists(tmp / "transient.npy"));
    EXPECT_FALSE(fs::exists(tmp / "transient.json"));
    for (const auto& e : fs::directory_iterator(tmp.path()))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}
