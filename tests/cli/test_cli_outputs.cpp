// The machine-readable and picture outputs of the tpb binary (TPB_BINARY): `tpb render --npy
// --mp4 --contact-sheet` writes its files, lists them in the folder's manifest and summary.json,
// and refuses --mp4 before rendering when ffmpeg is missing; `tpb info --json` prints one JSON
// object with the keys docs/user/outputs.md documents.
#include "support/temp_dir.h"
#include "film/tone_map.h"
#include "io/image_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

std::string q(const fs::path& p) {
    std::string s = p.string();
    s.insert(s.begin(), '\'');
    s.push_back('\'');
    return s;
}

struct Proc {
    int code = -1;
    std::string out, err;
};

// Runs `env` `tpb args` through the shell, stdout and stderr to files in `dir`.
Proc runTpb(const std::string& args, const fs::path& dir, const std::string& env = "") {
    const std::string cmd = (env.empty() ? "" : "env " + env + " ") + q(TPB_BINARY) + " " + args + " >" +
                            q(dir / "stdout.txt") + " 2>" + q(dir / "stderr.txt") + " </dev/null";
    const int st = std::system(cmd.c_str());
    Proc p;
    p.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    p.out = slurp(dir / "stdout.txt");
    p.err = slurp(dir / "stderr.txt");
    return p;
}

// A small closed box in fog with a point light: 21x14 px (odd width), 12 bins.
const char* kScene = R"({
  "version": 1,
  "camera": {"position": [0, 0.5, 0.9], "look_at": [0, 0.5, 0], "resolution": [21, 14]},
  "film": {"bins": 12},
  "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.05}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.7}},
  "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 1, 1], "material": "white", "flip_normals": true}],
  "lights": [{"type": "point", "position": [0, 0.8, 0], "power": 5}],
  "render": {"photons_per_pass": 2000, "passes": 2, "seed": 1}
}
)";

// Width and height from a PNG's IHDR chunk.
std::pair<int, int> pngSize(const fs::path& p) {
    const std::string b = slurp(p);
    if (b.size() < 24 || b.substr(1, 3) != "PNG") return {0, 0};
    const auto be = [&](size_t i) {
        return (static_cast<unsigned char>(b[i]) << 24) | (static_cast<unsigned char>(b[i + 1]) << 16) |
               (static_cast<unsigned char>(b[i + 2]) << 8) | static_cast<unsigned char>(b[i + 3]);
    };
    return {static_cast<int>(be(16)), static_cast<int>(be(20))};
}

// An 8-bit RGB PNG's pixels (empty if unreadable).
std::vector<unsigned char> pngPixels(const fs::path& p) {
    int w = 0, h = 0, n = 0;
    unsigned char* data = stbi_load(p.string().c_str(), &w, &h, &n, 3);
    if (!data) return {};
    std::vector<unsigned char> px(data, data + static_cast<size_t>(w) * h * 3);
    stbi_image_free(data);
    return px;
}

class CliOutputs : public ::testing::Test {
protected:
    void SetUp() override {
        tmp_ = std::make_unique<tpb::test::TempDir>(
            "clio_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        dir_ = tmp_->path();
        scene_ = tmp_->write("scene.json", kScene);
    }
    std::unique_ptr<tpb::test::TempDir> tmp_;
    fs::path dir_, scene_;
};

}  // namespace

TEST_F(CliOutputs, Mp4WithoutFfmpegIsRefusedBeforeRendering) {
    const fs::path empty = dir_ / "empty_path";
    fs::create_directory(empty);
    const Proc p = runTpb("render " + q(scene_) + " -o " + q(dir_ / "out") + " --mp4", dir_, "PATH=" + empty.string());
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(p.err, "error: ffmpeg not found on PATH: install it with apt-get install ffmpeg, or drop --mp4\n");
    EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing rendered, nothing written";
}

TEST_F(CliOutputs, NpyMp4AndContactSheetAreWrittenAndListed) {
    const bool ffmpeg = std::system("command -v ffmpeg >/dev/null 2>&1") == 0;
    const fs::path out = dir_ / "out";
    const std::string flags =
        std::string(" --npy --contact-sheet 5 --unwarp --continuous -q") + (ffmpeg ? " --mp4 --fps 10" : "");
    const Proc p = runTpb("render " + q(scene_) + " -o " + q(out) + flags, dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    std::vector<std::string> want = {"transient.npy", "transient.json", "steady.npy",
                                     "before.npy",    "after.npy",      "contact_sheet.png"};
    if (ffmpeg) want.push_back("transient.mp4");
    const json manifest = json::parse(slurp(out / ".tpb-manifest.json"));
    const json summary = json::parse(slurp(out / "summary.json"));
    for (const std::string& f : want) {
        EXPECT_TRUE(fs::exists(out / f)) << f;
        EXPECT_GT(fs::file_size(out / f), 0u) << f;
        EXPECT_NE(std::find(manifest["files"].begin(), manifest["files"].end(), f), manifest["files"].end()) << f;
        EXPECT_NE(std::find(summary["outputs"]["files"].begin(), summary["outputs"]["files"].end(), f),
                  summary["outputs"]["files"].end())
            << f;
    }
    // transient.npy: header + 14 x 21 x 12 x 3 floats; the side file names the axis and the render.
    EXPECT_EQ(fs::file_size(out / "transient.npy"), 128u + 14u * 21 * 12 * 3 * 4);
    const json side = json::parse(slurp(out / "transient.json"));
    EXPECT_EQ(side["shape"], json({14, 21, 12, 3}));
    EXPECT_EQ(side["time"]["axis"], "unwarped");
    EXPECT_EQ(side["time"]["emission"], "continuous");
    EXPECT_EQ(side["time"]["bins"], 12);
    EXPECT_EQ(side["render"]["scene"], scene_.string());
    EXPECT_EQ(side["render"]["passes"], 2);
    // The settings: one serialisation, the same object in transient.json and summary.json.
    EXPECT_EQ(side["render"]["settings"], summary["settings"]);
    EXPECT_EQ(side["render"]["settings"]["seed"], 1);
    EXPECT_EQ(side["render"]["settings"]["photons_per_pass"], 2000);
    EXPECT_DOUBLE_EQ(side["time"]["start_opl_m"].get<double>(), summary["film"]["start_opl_m"].get<double>());
    EXPECT_GT(side["render"]["beam_radius_m"].get<double>(), 0.0);
    // Contact sheet: 5 frames in 3 columns x 2 rows of (21 + label) px cells.
    const auto [w, h] = pngSize(out / "contact_sheet.png");
    EXPECT_EQ(h, 2 * (14 + 9) + 3 * 2);
    EXPECT_GE(w, 3 * 21 + 4 * 2);
    if (ffmpeg && std::system("command -v ffprobe >/dev/null 2>&1") == 0) {
        const std::string cmd =
            "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
            "stream=nb_read_frames,width,height -of csv=p=0 " +
            q(out / "transient.mp4") + " > " + q(dir_ / "probe.txt");
        ASSERT_EQ(std::system(cmd.c_str()), 0);
        EXPECT_EQ(slurp(dir_ / "probe.txt"), "22,14,12\n") << "one frame per bin, the odd width padded";
    }
    // A second render into the folder without the flags removes them (they were in the manifest).
    const Proc again = runTpb("render " + q(scene_) + " -o " + q(out) + " -q --no-frames", dir_);
    ASSERT_EQ(again.code, 0) << again.err;
    for (const std::string& f : want) EXPECT_FALSE(fs::exists(out / f)) << f;
}

// --counts (film/photon_counting.h): transient.npy holds grey whole counts, the same for the same
// seed and others for another; summary.json and transient.json record the model and the units.
TEST_F(CliOutputs, CountsAreWrittenReproduciblyAndRecorded) {
    const auto counts = [&](const std::string& name, const std::string& model) {
        const fs::path out = dir_ / name;
        const Proc p =
            runTpb("render " + q(scene_) + " -o " + q(out) + " --npy --no-frames -q --counts " + model, dir_);
        EXPECT_EQ(p.code, 0) << p.err;
        const std::string bytes = slurp(out / "transient.npy");
        std::vector<float> v((bytes.size() - 128) / 4);
        std::memcpy(v.data(), bytes.data() + 128, v.size() * 4);
        return v;
    };
    const std::string model = "photons=300,dark_hz=1e6,cycles=1e5,seed=4";
    const std::vector<float> a = counts("a", model), b = counts("b", model),
                             c = counts("c", "photons=300,dark_hz=1e6,cycles=1e5,seed=5");
    ASSERT_EQ(a.size(), 14u * 21 * 12 * 3);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    double total = 0.0;
    for (size_t i = 0; i < a.size(); i += 3) {
        EXPECT_EQ(a[i], std::floor(a[i]));
        EXPECT_EQ(a[i], a[i + 2]);
        total += a[i];
    }
    EXPECT_GT(total, 0.0);
    const json summary = json::parse(slurp(dir_ / "a" / "summary.json"));
    EXPECT_EQ(
        summary["frames"]["counts"],
        "photons=300,efficiency=1,dark_hz=1000000,ambient_hz=0,cycles=100000,afterpulse=0,afterpulse_ns=10,seed=4");
    EXPECT_EQ(summary["frames"]["units"], "counts per bin");
    const json side = json::parse(slurp(dir_ / "a" / "transient.json"));
    EXPECT_EQ(side["time"]["counts"], summary["frames"]["counts"]);
    EXPECT_EQ(side["time"]["units"], "photon counts per bin (r = g = b)");
}

// Ctrl-C while ffmpeg encodes: the encoding stops, ffmpeg is killed, no transient.mp4 (nor its
// temporary file) is left, the outputs written before it stay and summary.json says why (exit
// 130). The ffmpeg here is a stand-in that writes a partial file and reads its input slowly.
TEST_F(CliOutputs, CtrlCDuringEncodingLeavesNoHalfWrittenMp4) {
    const fs::path bin = dir_ / "fakebin";
    fs::create_directory(bin);
    const fs::path marker = dir_ / "ffmpeg_started";
    std::ofstream(bin / "ffmpeg") << "#!/bin/sh\nfor a; do out=\"$a\"; done\necho partial > \"$out\"\ntouch "
                                  << q(marker)
                                  << "\nwhile dd bs=65536 count=1 of=/dev/null 2>/dev/null; do sleep 0.2; done\n";
    fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
    const fs::path out = dir_ / "out";
    const std::string script =
        "PATH=" + bin.string() + ":/usr/bin:/bin " + q(TPB_BINARY) + " render " + q(scene_) + " -o " + q(out) +
        " --width 128 --height 128 --passes 1 --no-frames --strip 0 --npy --mp4 -q >" + q(dir_ / "stdout.txt") + " 2>" +
        q(dir_ / "stderr.txt") + " & pid=$!; i=0; while [ ! -e " + q(marker) +
        " ] && [ $i -lt 1500 ]; do sleep 0.02; i=$((i+1)); done; sleep 0.3; kill -INT $pid; wait $pid; echo $? > " +
        q(dir_ / "rc.txt");
    ASSERT_EQ(std::system(("sh -c " + q(script)).c_str()), 0);
    ASSERT_TRUE(fs::exists(marker)) << slurp(dir_ / "stderr.txt");
    EXPECT_EQ(slurp(dir_ / "rc.txt"), "130\n") << slurp(dir_ / "stderr.txt");
    EXPECT_FALSE(fs::exists(out / "transient.mp4"));
    for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
    EXPECT_TRUE(fs::exists(out / "transient.npy")) << "written before the encoding: kept";
    const json summary = json::parse(slurp(out / "summary.json"));
    EXPECT_NE(summary["outputs"]["error"].get<std::string>().find("while writing transient.mp4"), std::string::npos)
        << summary["outputs"].dump();
    EXPECT_NE(slurp(dir_ / "stderr.txt").find("kept in"), std::string::npos);
}

// `tpb info --json`: one JSON object on stdout (nothing else there), with every key the table of
// docs/user/outputs.md lists, and the values the text form prints.
TEST_F(CliOutputs, InfoJsonParsesAndHasTheDocumentedKeys) {
    const Proc p = runTpb("info " + q(scene_) + " --json", dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    const json j = json::parse(p.out);  // throws (fails the test) on anything but one JSON value
    ASSERT_TRUE(j.is_object());
    const std::vector<std::string> keys = {"scene.path",
                                           "scene.version",
                                           "camera.width",
                                           "camera.height",
                                           "camera.fov_y_deg",
                                           "camera.position",
                                           "bounds.min",
                                           "bounds.max",
                                           "bounds.diagonal_m",
                                           "geometry.triangles",
                                           "geometry.spheres",
                                           "geometry.shapes",
                                           "shapes",
                                           "regions",
                                           "lights",
                                           "film.bins",
                                           "film.start_opl_m",
                                           "film.bin_width_opl_m",
                                           "film.end_opl_m",
                                           "film.start_ns",
                                           "film.bin_width_ns",
                                           "film.end_ns",
                                           "film.auto_range",
                                           "memory.film_bytes",
                                           "memory.pixel_accumulator_bytes_per_thread",
                                           "memory.photon_map_bytes_per_pass_rough",
                                           "render.method",
                                           "render.photons_per_pass",
                                           "render.radius",
                                           "render.surface_radius",
                                           "render.alpha",
                                           "render.passes",
                                           "render.time_budget_s",
                                           "render.volume_estimator",
                                           "render.surface_estimator",
                                           "render.time_kernel",
                                           "density.measured",
                                           "density.why",
                                           "density.pilot_photons",
                                           "density.scale_to_pass",
                                           "density.gathered_per_ray",
                                           "density.radius_chosen_automatically",
                                           "stages"};
    for (const std::string& k : keys) {
        std::string pointer = "/" + k;
        std::replace(pointer.begin(), pointer.end(), '.', '/');
        EXPECT_TRUE(j.contains(json::json_pointer(pointer))) << k;
    }
    EXPECT_EQ(j["camera"]["width"], 21);
    EXPECT_EQ(j["camera"]["height"], 14);
    EXPECT_EQ(j["film"]["bins"], 12);
    EXPECT_EQ(j["render"]["photons_per_pass"], 2000);
    EXPECT_EQ(j["render"]["passes"], 2);
    EXPECT_EQ(j["scene"]["path"], scene_.string());
    ASSERT_EQ(j["shapes"].size(), 1u);
    EXPECT_EQ(j["shapes"][0]["kind"], "diffuse");
    ASSERT_EQ(j["regions"].size(), 1u);
    EXPECT_EQ(j["regions"][0]["medium"]["sigma_s_per_m"], json({0.5, 0.5, 0.5}));
    ASSERT_EQ(j["lights"].size(), 1u);
    EXPECT_EQ(j["lights"][0]["type"], "point");
    EXPECT_EQ(j["lights"][0]["power_w"], json({5.0, 5.0, 5.0}));
    EXPECT_FALSE(j["stages"].empty());
    EXPECT_TRUE(j["density"]["measured"].get<bool>());
    // The text form says the same.
    const Proc t = runTpb("info " + q(scene_), dir_);
    ASSERT_EQ(t.code, 0) << t.err;
    EXPECT_NE(t.out.find("camera     21x14"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("film       12 bins"), std::string::npos) << t.out;
}

// convergence.json's "rows" is convergence.csv as JSON: the same columns as keys, the same rows.
TEST_F(CliOutputs, ConvergenceJsonRowsAreTheCsvRows) {
    const fs::path ref = dir_ / "ref.tpbref";
    const Proc r = runTpb("reference " + q(scene_) + " -o " + q(ref) + " --time 1.5 --threads 2 -q", dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path out = dir_ / "conv";
    const Proc c = runTpb("converge " + q(scene_) + " --reference " + q(ref) + " -o " + q(out) +
                              " --time 1.5 --no-plot --threads 2 --method both",
                          dir_);
    ASSERT_EQ(c.code, 0) << c.err;
    std::istringstream csv(slurp(out / "convergence.csv"));
    std::string line;
    std::getline(csv, line);
    std::vector<std::string> header;
    for (std::istringstream h(line); std::getline(h, line, ',');) header.push_back(line);
    EXPECT_EQ(header.size(), 15u);
    const json rows = json::parse(slurp(out / "convergence.json"))["rows"];
    size_t n = 0;
    for (; std::getline(csv, line); ++n) {
        ASSERT_LT(n, rows.size());
        const json& row = rows[n];
        EXPECT_EQ(row.size(), header.size());
        std::istringstream cells(line + ",");
        std::string cell;
        for (size_t i = 0; i < header.size() && std::getline(cells, cell, ','); ++i) {
            SCOPED_TRACE(header[i] + " row " + std::to_string(n));
            ASSERT_TRUE(row.contains(header[i]));
            const json& v = row[header[i]];
            if (cell.empty())
                EXPECT_TRUE(v.is_null());
            else if (v.is_string())
                EXPECT_EQ(v.get<std::string>(), cell);
            else
                EXPECT_NEAR(v.get<double>(), std::stod(cell), 1e-5 * std::abs(std::stod(cell)) + 1e-300);
        }
    }
    EXPECT_GE(n, 2u) << "both methods measured";
    EXPECT_EQ(n, rows.size());
}

// Every picture is exposed by one rule (film/picture_export.h): the automatic exposure of its
// reference image (steady.png, preview.png: itself; strip.png, contact_sheet.png: the brightest
// frame), recorded in summary.json. A 5 mW light used to give a black steady.png (written at EV 0)
// beside an auto-exposed strip.png.
TEST_F(CliOutputs, EveryPictureIsAutoExposedByOneRuleRecordedInTheSummary) {
    std::string dim = kScene;
    const std::string from = "\"power\": 5}";
    dim.replace(dim.find(from), from.size(), "\"power\": 0.005}");
    const fs::path scene = tmp_->write("dim.json", dim), out = dir_ / "out";
    const Proc p = runTpb("render " + q(scene) + " -o " + q(out) + " -q --no-frames --strip 4 --contact-sheet 4", dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    const json ev = json::parse(slurp(out / "summary.json"))["outputs"]["exposure_ev"];
    for (const char* f : {"preview.png", "steady.png", "strip.png", "contact_sheet.png"})
        ASSERT_TRUE(ev.contains(f)) << f;
    // steady.png's EV is the automatic exposure of steady.exr, and its brightest pixels are near white.
    int w = 0, h = 0;
    std::vector<float> steady;
    tpb::readExr((out / "steady.exr").string(), w, h, steady);
    const tpb::ExposureFit fit = tpb::fitExposure(steady);
    ASSERT_TRUE(fit.found);
    EXPECT_GT(fit.ev, 8.0f) << "a dim scene: EV 0 would be black";
    EXPECT_FLOAT_EQ(ev["steady.png"].get<float>(), fit.ev);
    const std::vector<unsigned char> px = pngPixels(out / "steady.png");
    ASSERT_EQ(px.size(), steady.size());
    EXPECT_GE(*std::max_element(px.begin(), px.end()), 200) << "steady.png is not black";
    // The strip and the contact sheet (no extra EV given) share the brightest frame's exposure.
    EXPECT_FLOAT_EQ(ev["strip.png"].get<float>(), ev["contact_sheet.png"].get<float>());
    EXPECT_GT(ev["strip.png"].get<float>(), 8.0f);
    const std::vector<unsigned char> strip = pngPixels(out / "strip.png");
    ASSERT_FALSE(strip.empty());
    EXPECT_GE(*std::max_element(strip.begin(), strip.end()), 200) << "strip.png is not black";
}

// The progress line names what the chosen estimator stores: photon points for point3d (it said
// "0 beams"), beams for beam2d, and surface photons where the scene has diffuse surfaces.
TEST_F(CliOutputs, ProgressLineNamesWhatTheEstimatorStores) {
    const Proc points =
        runTpb("render " + q(scene_) + " -o " + q(dir_ / "a") + " --no-frames --estimator point3d", dir_);
    ASSERT_EQ(points.code, 0) << points.err;
    EXPECT_EQ(points.err.find(" beams"), std::string::npos) << points.err;
    EXPECT_NE(points.err.find(" photon points, "), std::string::npos) << points.err;
    EXPECT_NE(points.err.find(" surface photons"), std::string::npos) << points.err;
    EXPECT_NE(points.err.find("pass 1: r="), std::string::npos) << points.err;
    EXPECT_EQ(points.err.find(" 0 photon points"), std::string::npos) << points.err;
    const Proc beams = runTpb("render " + q(scene_) + " -o " + q(dir_ / "b") + " --no-frames --estimator beam2d", dir_);
    ASSERT_EQ(beams.code, 0) << beams.err;
    EXPECT_NE(beams.err.find(" beams, "), std::string::npos) << beams.err;
    EXPECT_EQ(beams.err.find("photon points"), std::string::npos) << beams.err;
}
