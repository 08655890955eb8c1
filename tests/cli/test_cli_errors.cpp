// Bad input and faults at the command line: the built `tpb` binary (TPB_BINARY) is run on malformed
// scene files, broken meshes, impossible film sizes and unwritable output folders. Every one must
// end with exit code 2 and a message "file:line: key: what is wrong" (never a crash, a signal or
// "internal error"). Ctrl-C during a render finishes the pass and writes the results atomically.
#include "transport/stages.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "render/time_range.h"
#include "support/temp_dir.h"
#include "support/tpb_process.h"

#include "support/checkpoint_payload.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <fstream>
#include <sstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// stderr from the first line that starts with "error: " (a slow machine, e.g. under a sanitizer, may
// print the pilot's progress line before it).
std::string fromErrorLine(const std::string& err) {
    if (err.rfind("error: ", 0) == 0) return err;
    const size_t at = err.find("\nerror: ");
    return at == std::string::npos ? err : err.substr(at + 1);
}

using tpb::test::now;
using tpb::test::Proc;
using tpb::test::runTpb;
using tpb::test::slurp;
using tpb::test::spawnTpb;
using tpb::test::tpbBinary;
using tpb::test::waitTpb;

class CliErrors : public ::testing::Test {
protected:
    void SetUp() override {
        tmp_ = std::make_unique<tpb::test::TempDir>(
            "cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        dir_ = tmp_->path();
    }
    void TearDown() override { tmp_.reset(); }

    fs::path write(const std::string& name, const std::string& text) {
        const fs::path p = dir_ / name;
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
    // `tpb render <scene>` into dir_/out with the given extra flags.
    Proc render(const fs::path& scene, const std::vector<std::string>& flags = {},
                const std::vector<std::string>& env = {}) {
        std::vector<std::string> args{"render",      scene.string(), "-o", (dir_ / "out").string(),
                                      "--no-frames", "--strip",      "0"};
        args.insert(args.end(), flags.begin(), flags.end());
        return runTpb(args, dir_, env);
    }
    // A user error: exit code 2, no signal, one "error: " line naming file:line and key.
    void expectUserError(const Proc& p, const std::string& where, const std::string& key,
                         const std::string& text = "") {
        EXPECT_FALSE(p.timedOut) << where;
        EXPECT_EQ(p.signal, 0) << where << "\n" << p.err;
        EXPECT_EQ(p.code, 2) << where << "\n" << p.err;
        EXPECT_EQ(fromErrorLine(p.err).rfind("error: ", 0), 0u) << p.err;
        EXPECT_NE(p.err.find(where + ": "), std::string::npos) << "expected \"" << where << "\" in:\n" << p.err;
        if (!key.empty()) {
            EXPECT_NE(p.err.find(": " + key + ": "), std::string::npos) << "expected key " << key << " in:\n" << p.err;
        }
        if (!text.empty()) {
            EXPECT_NE(p.err.find(text), std::string::npos) << "expected \"" << text << "\" in:\n" << p.err;
        }
        EXPECT_EQ(p.err.find("internal error"), std::string::npos) << p.err;
        EXPECT_EQ(p.err.find("Sanitizer"), std::string::npos) << p.err;
        EXPECT_EQ(p.err.find("runtime error"), std::string::npos) << p.err;
        EXPECT_FALSE(fs::exists(dir_ / "out" / "steady.exr")) << where;
    }

    // A command refused at start-up: exit code 2, stderr starting with `text`, no output folder.
    struct RefusedCommand {
        std::vector<std::string> args;
        const char* text;
    };
    void expectRefused(const std::vector<RefusedCommand>& cases) {
        for (const RefusedCommand& c : cases) {
            SCOPED_TRACE(c.args[0] + " " + c.args.back());
            const Proc p = runTpb(c.args, dir_, {}, 30.0);
            EXPECT_FALSE(p.timedOut);
            EXPECT_EQ(p.code, 2) << p.err;
            EXPECT_EQ(fromErrorLine(p.err).rfind(c.text, 0), 0u) << p.err;
            EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing may be written";
        }
    }

    std::unique_ptr<tpb::test::TempDir> tmp_;
    fs::path dir_;
};

// A valid scene, one key per line, so that each test can break line N and expect "scene.json:N".
// The camera sits inside the closed box with the light (from outside the box would be black).
const char* kLines[] = {
    "{",                                                                                                 // 1
    "  \"version\": 1,",                                                                                 // 2
    "  \"camera\": {\"position\": [0, 0.5, 0.9], \"look_at\": [0, 0.5, 0], \"resolution\": [16, 16]},",  // 3
    "  \"film\": {\"bins\": 8},",                                                                        // 4
    "  \"media\": {\"fog\": {\"sigma_s\": 0.5, \"sigma_a\": 0.05}},",                                    // 5
    "  \"global_medium\": \"fog\",",                                                                     // 6
    "  \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": 0.7}},",                           // 7
    "  \"shapes\": [{\"type\": \"box\", \"min\": [-1, 0, -1], \"max\": [1, 1, 1], \"material\": \"white\", "
    "\"flip_normals\": true}],",                                                        // 8
    "  \"lights\": [{\"type\": \"point\", \"position\": [0, 0.8, 0], \"power\": 5}],",  // 9
    "  \"render\": {\"photons_per_pass\": 2000, \"passes\": 2, \"seed\": 1}",           // 10
    "}",                                                                                // 11
};

std::string sceneWith(int line, const std::string& replacement) {
    std::string s;
    for (int i = 1; i <= 11; ++i) s += (i == line ? replacement : std::string(kLines[i - 1])) + "\n";
    return s;
}

}  // namespace

TEST_F(CliErrors, ValidSceneRenders) {  // the baseline the other tests break
    const Proc p = render(write("scene.json", sceneWith(0, "")), {"-q"});
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_TRUE(fs::exists(dir_ / "out" / "steady.exr"));
    EXPECT_TRUE(fs::exists(dir_ / "out" / "summary.json"));
}

TEST_F(CliErrors, TruncatedAndMalformedJson) {
    const fs::path f = dir_ / "scene.json";
    // Cut in the middle of line 5.
    std::string full = sceneWith(0, "");
    write("scene.json", full.substr(0, full.find("\"sigma_a\"")));
    expectUserError(render(f), f.string() + ":5", "");
    // Empty file, a lone brace, trailing garbage, a trailing comma, single quotes, comments.
    write("scene.json", "");
    expectUserError(render(f), f.string() + ":1", "");
    write("scene.json", "{");
    expectUserError(render(f), f.string() + ":1", "");
    write("scene.json", full + "\n\n{}");
    expectUserError(render(f), f.string() + ":14", "");
    write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 8,},"));
    expectUserError(render(f), f.string() + ":4", "");
    write("scene.json", sceneWith(6, "  'global_medium': 'fog',"));
    expectUserError(render(f), f.string() + ":6", "");
    write("scene.json", sceneWith(7, "  // a comment"));
    expectUserError(render(f), f.string() + ":7", "");
    // Not UTF-8, a NUL byte, a scene that is an array.
    write("scene.json", sceneWith(9, std::string("  \"lights\": [{\"type\": \"point\", \"name\": \"\xff\xfe\"}],")));
    expectUserError(render(f), f.string() + ":9", "");
    write("scene.json", sceneWith(2, std::string("  \"version\": 1,\0", 16)));
    expectUserError(render(f), f.string() + ":2", "");
    write("scene.json", "[1, 2]");
    expectUserError(render(f), f.string() + ":1", "", "JSON object");
}

TEST_F(CliErrors, WrongTypes) {
    const fs::path f = dir_ / "scene.json";
    const struct {
        int line;
        const char* text;
        const char* key;
    } cases[] = {
        {4, "  \"film\": {\"bins\": \"many\"},", "film.bins"},
        {3, "  \"camera\": {\"position\": [0, 0.5, 3], \"look_at\": [0, 0.5, 0], \"resolution\": [16, \"16\"]},",
         "camera.resolution"},
        {3, "  \"camera\": {\"position\": [0, 0.5], \"look_at\": [0, 0.5, 0]},", "camera.position"},
        {5, "  \"media\": {\"fog\": {\"sigma_s\": [0.5, 0.5], \"sigma_a\": 0.05}},", "media.fog.sigma_s"},
        {5, "  \"media\": {\"fog\": {\"sigma_s\": true}},", "media.fog.sigma_s"},
        {6, "  \"global_medium\": 3,", "global_medium"},
        {9, "  \"lights\": {\"type\": \"point\"},", "lights"},
        {9, "  \"lights\": [\"point\"],", "lights[0]"},
        {10, "  \"render\": {\"passes\": -1}", "render.passes"},
        {10, "  \"render\": {\"max_depth\": 1.5}", "render.max_depth"},
        {10, "  \"render\": {\"seed\": -3}", "render.seed"},
        {10, "  \"render\": {\"photons_per_pass\": null}", "render.photons_per_pass"},
        {8, "  \"shapes\": [{\"type\": \"box\", \"min\": [1, 1, 1], \"max\": [0, 0, 0]}],", "shapes[0].max"},
        {8, "  \"shapes\": [{\"type\": \"mesh\", \"file\": 42}],", "shapes[0].file"},
        {2, "  \"version\": 2,", "version"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.text);
        write("scene.json", sceneWith(c.line, c.text));
        expectUserError(render(f), f.string() + ":" + std::to_string(c.line), c.key);
    }
}

TEST_F(CliErrors, HugeNumbersAndNotANumber) {
    const fs::path f = dir_ / "scene.json";
    const struct {
        int line;
        const char* text;
        const char* key;
    } cases[] = {
        {5, "  \"media\": {\"fog\": {\"sigma_s\": 1e999}},", ""},  // JSON: does not fit a double
        {5, "  \"media\": {\"fog\": {\"sigma_s\": -1e999}},", ""},
        {5, "  \"media\": {\"fog\": {\"sigma_s\": NaN}},", ""},  // JSON has no NaN literal
        {5, "  \"media\": {\"fog\": {\"sigma_s\": Infinity}},", ""},
        {5, "  \"media\": {\"fog\": {\"sigma_s\": \"NaN\"}},", "media.fog.sigma_s"},
        {9, "  \"lights\": [{\"type\": \"point\", \"power\": \"inf\"}],", "lights[0].power"},
        {9, "  \"lights\": [{\"type\": \"point\", \"power\": [1, \"nan\", 1]}],", "lights[0].power"},
        {3, "  \"camera\": {\"fov\": 1e308},", "camera.fov"},
        {3, "  \"camera\": {\"resolution\": [1e300, 16]},", "camera.resolution"},
        {3, "  \"camera\": {\"resolution\": [99999999999999999999999, 16]},", "camera.resolution"},
        {4, "  \"film\": {\"bins\": 1e10},", "film.bins"},
        {4, "  \"film\": {\"bins\": 8, \"start_m\": 0, \"bin_width_m\": -1e308},", "film.bin_width_m"},
        {5, "  \"media\": {\"fog\": {\"g\": 1e300}},", "media.fog.g"},
        {10, "  \"render\": {\"seed\": 1e30}", "render.seed"},
        {10, "  \"render\": {\"max_depth\": 1e19}", "render.max_depth"},
        {10, "  \"render\": {\"photons_per_pass\": 1000000000000000000}", "render.photons_per_pass"},
        {10, "  \"render\": {\"alpha\": 1e-400}", "render.alpha"},  // underflows to 0: out of (0, 1]
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.text);
        write("scene.json", sceneWith(c.line, c.text));
        expectUserError(render(f), f.string() + ":" + std::to_string(c.line), c.key);
    }
    // Absurd counts on the command line too.
    const fs::path ok = write("ok.json", sceneWith(0, ""));
    for (const std::vector<std::string>& flags : {std::vector<std::string>{"--photons", "1000000000000000000"},
                                                  {"--photons", "0"},
                                                  {"--passes", "x"},
                                                  {"--alpha", "2"},
                                                  {"--radius", "0"},
                                                  {"--radius", "nan"},
                                                  {"--width", "0"},
                                                  {"--bins", "-5"},
                                                  {"--threads", "99999999999"},
                                                  {"--max-depth", "0"},
                                                  {"--time", "-1"}}) {
        const Proc p = render(ok, flags);
        EXPECT_EQ(p.code, 2) << flags[0] << " " << flags[1] << "\n" << p.err;
        EXPECT_EQ(p.signal, 0);
        EXPECT_EQ(p.err.find("internal error"), std::string::npos) << p.err;
    }
}

// The film's memory is checked before it is allocated: the error names the bytes needed.
TEST_F(CliErrors, FilmTooLargeIsRefusedBeforeAllocation) {
    const fs::path f = write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 256},"));
    std::string big = sceneWith(
        3, "  \"camera\": {\"position\": [0, 0.5, 3], \"look_at\": [0, 0.5, 0], \"resolution\": [256, 256]},");
    write("scene.json", big.replace(big.find("\"bins\": 8"), 9, "\"bins\": 256"));
    tpb::CameraDesc cam;
    cam.width = cam.height = 256;
    const uint64_t need = tpb::filmBytes(cam.width, cam.height, 256);
    const Proc p = render(f, {}, {"TPB_MAX_FILM_BYTES=1000000"});
    expectUserError(p, f.string() + ":4", "film.bins", std::to_string(need) + " bytes");
    EXPECT_NE(p.err.find("1000000 bytes"), std::string::npos) << p.err;  // and the limit
    // Without an override: resolution and bins far beyond any machine (exabytes; no overflow).
    write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 2147483647},"));
    big = sceneWith(
        3, "  \"camera\": {\"position\": [0, 0.5, 3], \"look_at\": [0, 0.5, 0], \"resolution\": [46000, 46000]},");
    write("scene.json", big.replace(big.find("\"bins\": 8"), 9, "\"bins\": 2147483647"));
    const Proc q = render(f);
    expectUserError(q, f.string() + ":4", "film.bins", "bytes");
    EXPECT_LT(q.seconds, 10.0);
    // The same through command-line overrides of a small scene.
    const fs::path ok = write("ok.json", sceneWith(0, ""));
    const Proc r = render(ok, {"--width", "100000", "--height", "100000", "--bins", "100000"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("would need"), std::string::npos) << r.err;
    EXPECT_LT(r.seconds, 10.0);
}

const char kBinaryObj[] =
    "\x7f"
    "ELF\x02\x01\x01\0\0\0\xff\xfe\x00\x13garbage\nf 9 9 9\n";

TEST_F(CliErrors, MissingAndCorruptMeshes) {
    const fs::path f = dir_ / "scene.json";
    const auto meshScene = [&](const std::string& file) {
        return sceneWith(8,
                         "  \"shapes\": [{\"type\": \"mesh\", \"file\": \"" + file + "\", \"material\": \"white\"}],");
    };
    write("scene.json", meshScene("nowhere.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file", "not found");
    fs::create_directories(dir_ / "folder.obj");
    write("scene.json", meshScene("folder.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file", "is a folder, not a file");
    // Corrupt files: the error names the scene's file:line and key, then the OBJ (and its line when
    // tinyobj reports one).
    const struct {
        const char* name;
        std::string text;
    } corrupt[] = {
        {"empty.obj", ""},
        {"no_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"},
        {"bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"},
        {"zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"},
        {"degenerate_only.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n"},
        {"binary.obj", std::string(kBinaryObj, sizeof kBinaryObj - 1)},
    };
    for (const auto& c : corrupt) {
        SCOPED_TRACE(c.name);
        write(c.name, c.text);
        write("scene.json", meshScene(c.name));
        const Proc p = render(f);
        expectUserError(p, f.string() + ":8", "shapes[0].file", c.name);
    }
    // Non-finite and huge vertices render or are refused, never crash.
    for (const char* text : {"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nf 4 5 6\n",
                             "v 1e300 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nf 4 5 6\n"}) {
        write("odd.obj", text);
        write("scene.json", meshScene("odd.obj"));
        const Proc p = render(f, {"-q"});
        EXPECT_TRUE(p.code == 0 || p.code == 2) << p.code << "\n" << p.err;
        EXPECT_EQ(p.signal, 0);
        EXPECT_EQ(p.err.find("internal error"), std::string::npos) << p.err;
    }
}

TEST_F(CliErrors, MissingSceneFileAndUnwritableOutput) {
    Proc p = runTpb({"render", (dir_ / "absent.json").string(), "-o", (dir_ / "out").string()}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("absent.json"), std::string::npos) << p.err;
    p = runTpb({"render", dir_.string(), "-o", (dir_ / "out").string()}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("directory"), std::string::npos) << p.err;

    const fs::path scene = write("scene.json", sceneWith(0, ""));
    write("file.txt", "not a folder");
    for (const std::string& out : {std::string("/proc/tpb_no_such_folder"), (dir_ / "file.txt" / "out").string(),
                                   (dir_ / "file.txt").string(), std::string("/dev/null")}) {
        SCOPED_TRACE(out);
        const Proc q = runTpb({"render", scene.string(), "-o", out, "--no-frames"}, dir_);
        EXPECT_EQ(q.code, 2) << q.err;
        EXPECT_EQ(q.signal, 0);
        EXPECT_EQ(fromErrorLine(q.err).rfind("error: " + out + ": ", 0), 0u) << q.err;  // names the folder first
        EXPECT_NE(q.err.find("-o"), std::string::npos) << q.err;                        // and says how to fix it
        EXPECT_EQ(q.err.find("internal error"), std::string::npos) << q.err;
    }
    EXPECT_EQ(slurp(dir_ / "file.txt"), "not a folder");
}

// Ctrl-C (SIGINT) after the first pass: the render finishes the pass in progress, writes
// steady.exr, the frames and summary.json (all through tmp + rename: no *.tmp-* file is left) and
// exits 0. A second Ctrl-C quits at once with 130.
TEST_F(CliErrors, CtrlCFinishesThePassAndWritesTheResults) {
    const fs::path scene =
        write("scene.json", sceneWith(10, "  \"render\": {\"photons_per_pass\": 60000, \"passes\": 100000}"));
    const fs::path out = dir_ / "out";
    const double t0 = now();
    const pid_t pid = spawnTpb({"render", scene.string(), "-o", out.string(), "--threads", "2"}, dir_, {});
    ASSERT_GT(pid, 0);
    bool started = false;
    while (now() - t0 < 60.0 && !started) {
        started = slurp(dir_ / "stderr.txt").find("pass 1:") != std::string::npos;
        if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_TRUE(started) << slurp(dir_ / "stderr.txt");
    kill(pid, SIGINT);
    const double tInt = now();
    const Proc p = waitTpb(pid, dir_, t0, 120.0);
    EXPECT_FALSE(p.timedOut);
    EXPECT_EQ(p.signal, 0);
    EXPECT_EQ(p.code, 0) << p.err;
    // It finishes the pass in progress, not the 100000: within about a pass of the interrupt (what a
    // pass takes, from the "pass 1: ..., 1.234 s" line, varies with the machine and the sanitizers).
    const size_t line = p.err.find("pass 1:");
    ASSERT_NE(line, std::string::npos) << p.err;
    const std::string passLine = p.err.substr(line, p.err.find('\n', line) - line);
    const size_t comma = passLine.rfind(", ");
    ASSERT_NE(comma, std::string::npos) << passLine;
    const double passSec = std::stod(passLine.substr(comma + 2));
    EXPECT_LT(p.seconds - (tInt - t0), std::max(20.0, 3.0 * passSec + 10.0)) << passLine;
    EXPECT_NE(p.err.find("interrupted"), std::string::npos) << p.err;
    ASSERT_TRUE(fs::exists(out / "summary.json")) << p.err;
    const nlohmann::json summary = nlohmann::json::parse(slurp(out / "summary.json"));
    const int passes = summary["passes"].get<int>();
    EXPECT_GE(passes, 1);
    EXPECT_LT(passes, 100000);
    EXPECT_EQ(summary["per_pass"].size(), static_cast<size_t>(passes));
    EXPECT_EQ(summary["totals"]["rejected_samples"].get<int64_t>(), 0);
    int w = 0, h = 0;
    std::vector<float> rgb;
    tpb::readExr((out / "steady.exr").string(), w, h, rgb);
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 16);
    double sum = 0.0;
    for (float v : rgb) {
        EXPECT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum, 0.0);
    int frames = 0, tmp = 0;
    for (const auto& e : fs::recursive_directory_iterator(out)) {
        const std::string name = e.path().filename().string();
        tmp += name.find(".tmp-") != std::string::npos;
        frames += name.rfind("frame_", 0) == 0;
    }
    EXPECT_EQ(tmp, 0);
    EXPECT_EQ(frames, 8);

    // Two interrupts: the second one exits immediately with 130.
    const fs::path out2 = dir_ / "out2";
    const double t1 = now();
    const pid_t pid2 = spawnTpb({"render", scene.string(), "-o", out2.string(), "--threads", "2"}, dir_, {});
    ASSERT_GT(pid2, 0);
    started = false;
    while (now() - t1 < 60.0 && !started) {
        started = slurp(dir_ / "stderr.txt").find("pass 1:") != std::string::npos;
        if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_TRUE(started);
    kill(pid2, SIGINT);
    // Two signals sent before the process takes the first merge into one (standard signals do not
    // queue): wait until the first is no longer pending (/proc ShdPnd/SigPnd), then send the second.
    const auto sigintPending = [&] {
        std::ifstream st("/proc/" + std::to_string(pid2) + "/status");
        std::string line;
        bool pending = false;
        while (std::getline(st, line))
            if (line.rfind("ShdPnd:", 0) == 0 || line.rfind("SigPnd:", 0) == 0)
                pending = pending || (std::stoull(line.substr(7), nullptr, 16) >> (SIGINT - 1)) & 1u;
        return pending;
    };
    for (int i = 0; i < 5000 && sigintPending(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    kill(pid2, SIGINT);
    const Proc q = waitTpb(pid2, dir_, t1, 60.0);
    EXPECT_EQ(q.signal, 0);
    EXPECT_EQ(q.code, 130) << q.err;
}

namespace {

// Can this process mount a tmpfs in a private mount namespace (unshare -m, the user mapped to root),
// which vanishes with the namespace? Root in a normal container can; some sandboxes cannot.
bool canMountPrivateTmpfs() {
    return std::system(
               "unshare -m -r sh -c 'd=$(mktemp -d) && mount -t tmpfs -o size=64k tmpfs \"$d\" && "
               "umount \"$d\" && rmdir \"$d\"' >/dev/null 2>&1") == 0;
}

}  // namespace

// A full disk while the frames are written: a real ENOSPC from a 96 KiB tmpfs. The render must end
// with exit 2 and an error naming the frame file and "No space left on device"; every file that is
// there must be complete (EXRs read back, summary.json parses and says how many frames were
// written), no *.tmp-* file may be left, and the frames that fitted are kept.
TEST_F(CliErrors, DiskFullDuringExportKeepsCompleteFiles) {
    if (!canMountPrivateTmpfs()) GTEST_SKIP() << "this machine does not allow `unshare -m -r` + mount tmpfs";
    const fs::path scene = write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 64},"));
    const fs::path copy = dir_ / "copy";
    // In the namespace: mount, render into the tmpfs, copy what is there out, record the exit code.
    const std::string script =
        "set -u; m=\"$1\"; mkdir -p \"$m\" && mount -t tmpfs -o size=96k tmpfs \"$m\" || exit 99; "
        "\"$2\" render \"$3\" -o \"$m/out\" --width 24 --height 24; echo $? > \"$4/code.txt\"; "
        "cp -r \"$m/out\" \"$4/copy\"; df -k \"$m\" | tail -1 > \"$4/df.txt\"";
    const std::string cmd = "unshare -m -r sh -c '" + script + "' sh '" + (dir_ / "mnt").string() + "' '" +
                            tpbBinary() + "' '" + scene.string() + "' '" + dir_.string() + "' >'" +
                            (dir_ / "stdout.txt").string() + "' 2>'" + (dir_ / "stderr.txt").string() + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir_ / "stderr.txt");
    const std::string err = slurp(dir_ / "stderr.txt");
    const int code = std::stoi(slurp(dir_ / "code.txt"));
    EXPECT_EQ(code, 2) << err;
    EXPECT_NE(err.find("No space left on device"), std::string::npos) << err;
    EXPECT_NE(err.find("/frames/frame_"), std::string::npos) << err;  // names the file that did not fit
    EXPECT_NE(err.find("kept in"), std::string::npos) << err;
    EXPECT_EQ(err.find("internal error"), std::string::npos) << err;

    // What is there is complete.
    int w = 0, h = 0;
    std::vector<float> rgb;
    tpb::readExr((copy / "steady.exr").string(), w, h, rgb);
    EXPECT_EQ(w, 24);
    const nlohmann::json summary = nlohmann::json::parse(slurp(copy / "summary.json"));
    EXPECT_EQ(summary["outputs"]["frames_expected"].get<int>(), 64);
    int frames = 0, tmp = 0;
    for (const auto& e : fs::recursive_directory_iterator(copy)) {
        const std::string name = e.path().filename().string();
        tmp += name.find(".tmp-") != std::string::npos;
        if (name.rfind("frame_", 0) == 0) {
            ++frames;
            int fw = 0, fh = 0;
            std::vector<float> f;
            EXPECT_NO_THROW(tpb::readExr(e.path().string(), fw, fh, f)) << name;
            EXPECT_EQ(fw * fh, 24 * 24) << name;
        }
    }
    EXPECT_EQ(tmp, 0);
    EXPECT_GT(frames, 0);   // the frames that fitted are kept
    EXPECT_LT(frames, 64);  // and the disk really filled up
    std::printf("tmpfs 96 KiB: %d of 64 frames fitted; summary.json frames_written = %s\n%s", frames,
                summary["outputs"]["frames_written"].dump().c_str(), err.c_str());
    // summary.json is either the final one (it fitted) with the exact count and the error, or the
    // first one, written before the frames, whose frames_written is null.
    const nlohmann::json& written = summary["outputs"]["frames_written"];
    if (!written.is_null()) {
        EXPECT_EQ(written.get<int>(), frames);
        EXPECT_NE(summary["outputs"]["error"].get<std::string>().find("No space left"), std::string::npos);
    }
}

// A pass that fails on the render thread (here: an albedo-1 box with max_depth 1e8, whose photons the
// deep roulette ends after ~83 events, ~20 MB for 2000, outgrows a 4 MB memory limit,
// TPB_MAX_FILM_BYTES) ends the render with exit 2 and the reason, not a crash; the
// outputs are still written from the passes finished before it (none here, so the images are black).
TEST_F(CliErrors, PassThatOutgrowsMemoryStopsTheRenderCleanly) {
    const fs::path scene = write("scene.json", R"({"version": 1,
      "camera": {"position": [0, 0, 0.9], "look_at": [0, 0, 0], "fov": 60, "resolution": [8, 8]},
      "film": {"start_m": 0, "bin_width_m": 0.25, "bins": 8},
      "media": {"m": {"sigma_s": 2.0}}, "global_medium": "m",
      "materials": {"wall": {"type": "diffuse", "albedo": 1}},
      "shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": "wall", "flip_normals": true}],
      "lights": [{"type": "point", "position": [0.2, 0.1, -0.3], "power": 2}],
      "render": {"photons_per_pass": 2000, "max_depth": 100000000, "passes": 3, "seed": 8}})");
    const Proc p = render(scene, {"--threads", "2"}, {"TPB_MAX_FILM_BYTES=4000000"});
    EXPECT_FALSE(p.timedOut);
    EXPECT_EQ(p.signal, 0) << p.err;
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("error: render.photons_per_pass: pass 1: "), std::string::npos) << p.err;
    EXPECT_NE(p.err.find("max_depth"), std::string::npos) << p.err;
    EXPECT_NE(p.err.find("writing the 0 finished passes"), std::string::npos) << p.err;
    EXPECT_EQ(p.err.find("internal error"), std::string::npos) << p.err;
    const nlohmann::json summary = nlohmann::json::parse(slurp(dir_ / "out" / "summary.json"));
    EXPECT_EQ(summary["passes"].get<int>(), 0);
    int w = 0, h = 0;
    std::vector<float> rgb;
    tpb::readExr((dir_ / "out" / "steady.exr").string(), w, h, rgb);
    EXPECT_EQ(w, 8);
    for (float v : rgb) EXPECT_EQ(v, 0.0f);
}

// ================================================================================================
// Issue 12, items 6-12: hangs, lost work, stale files, messages.
// ================================================================================================

namespace {

// The camera inside the lit box (the energy that reaches it does not depend on light leaking out).
std::string insideScene(const std::string& film = "{\"bins\": 8}",
                        const std::string& render = "{\"photons_per_pass\": 2000, \"passes\": 2, \"seed\": 1}") {
    return "{\"version\": 1,\n"
           " \"camera\": {\"position\": [0, 0.5, 0.9], \"look_at\": [0, 0.5, 0], \"fov\": 60, \"resolution\": [16, "
           "16]},\n"
           " \"film\": " +
           film +
           ",\n"
           " \"media\": {\"fog\": {\"sigma_s\": 0.5, \"sigma_a\": 0.05}}, \"global_medium\": \"fog\",\n"
           " \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": 0.7}},\n"
           " \"shapes\": [{\"type\": \"box\", \"min\": [-1, 0, -1], \"max\": [1, 1, 1], \"material\": \"white\", "
           "\"flip_normals\": true}],\n"
           " \"lights\": [{\"type\": \"point\", \"position\": [0, 0.8, 0], \"power\": 5}],\n"
           " \"render\": " +
           render + "}\n";
}

// Polls `file` until it contains `text` (true) or the process has ended or `timeoutSec` passed.
bool waitForText(const fs::path& file, const std::string& text, pid_t pid, double timeoutSec) {
    const double t0 = now();
    while (now() - t0 < timeoutSec) {
        if (slurp(file).find(text) != std::string::npos) return true;
        if (waitpid(pid, nullptr, WNOHANG) == pid) return false;  // (reaped: the caller must not wait again)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
}

int countFrames(const fs::path& dir) {
    int n = 0;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) n += e.path().filename().string().rfind("frame_", 0) == 0;
    return n;
}

}  // namespace

// Item 7: `--passes -3` and `--time nan` rendered forever. Every flag is checked like the scene file
// (range, finiteness), by every command, with the flag's name and range, before anything happens.
TEST_F(CliErrors, PassesAndTimeFlagsAreCheckedForRangeAndFiniteness) {
    const fs::path scene = write("scene.json", insideScene());
    const std::string out = (dir_ / "out").string();
    expectRefused({
        {{"render", scene.string(), "-o", out, "--passes", "-3"},
         "error: --passes: must be an integer >= 0 (0 = no pass limit: until --time or Ctrl-C); got -3"},
        {{"render", scene.string(), "-o", out, "--time", "nan"},
         "error: --time: must be a finite number >= 0 (seconds; 0 = no time budget); got nan"},
        {{"render", scene.string(), "-o", out, "--time", "inf"}, "error: --time: must be a finite number >= 0"},
        {{"render", scene.string(), "-o", out, "--method", "pt", "--passes", "-3"}, "error: --passes: must be"},
        {{"info", scene.string(), "--passes", "-3"}, "error: --passes: must be an integer >= 0"},
        {{"bench", scene.string(), "--time", "nan"}, "error: --time: must be a finite number >= 0"},
        {{"reference", scene.string(), "-o", out + "/r.tpbref", "--time", "nan"}, "error: --time: must be a finite"},
        {{"converge", scene.string(), "--reference", out + "/r.tpbref", "-o", out, "--time", "nan"},
         "error: --time: must be a finite"},
        {{"converge", scene.string(), "--reference", out + "/r.tpbref", "-o", out, "--time", "1", "--at", "nan"},
         "error: --at: must be a finite number > 0 (seconds); got nan"},
    });
    if (runTpb({"view", "--help"}, dir_).code == 0) {  // built with the viewer: its flags too (no window opens)
        const Proc v = runTpb({"view", scene.string(), "--passes", "-3"}, dir_, {}, 20.0);
        EXPECT_EQ(v.code, 2) << v.err;
        EXPECT_EQ(fromErrorLine(v.err).rfind("error: --passes: must be an integer >= 0", 0), 0u) << v.err;
    }
}

// Item 10: errors found after start-up (--alpha 0, --photons 0, --time -1, and those that need the
// scene: a kernel radius larger than the scene, a photon map beyond the memory limit) left
// preview.exr/png behind. Everything is checked before the first file is written.
TEST_F(CliErrors, FlagErrorsLeaveNoFileBehind) {
    const fs::path scene = write("scene.json", insideScene());
    const struct {
        std::vector<std::string> flags;
        const char* text;
    } cases[] = {
        {{"--alpha", "0"}, "error: --alpha: must be a number in (0, 1] (1 = no shrinking); got 0"},
        {{"--photons", "0"}, "error: --photons: must be an integer >= 1 (photons per pass); got 0"},
        {{"--time", "-1"}, "error: --time: must be a finite number >= 0"},
        {{"--radius", "5"}, "error: --radius 5 m is 167% of the scene's diagonal (3 m); allowed up to 25% (0.75 m)"},
        {{"--photons", "1000000000000"}, "error: --photons 1000000000000 needs about"},
        {{"--method", "pt", "--spp", "0"}, "error: --spp: must be an integer in [1, 1048576]"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.flags[0] + " " + c.flags[1]);
        const Proc p = render(scene, c.flags);
        EXPECT_EQ(p.code, 2) << p.err;
        EXPECT_EQ(fromErrorLine(p.err).rfind(c.text, 0), 0u) << p.err;
        EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing may be written, not even preview.exr";
    }
}

// Issue 33 item 4: a --pulse / --sensor spanning more than 2^20 of the film's bins was accepted,
// rendered, and failed at the first frame with "internal error" (exit 1, frames lost). It is refused
// once the time axis is known, before any pass or file, naming the flag, its span in bins, the
// limit and the fix; by --method pt and by `tpb view` (before its window opens) too.
TEST_F(CliErrors, TimeResponseWiderThanTheKernelLimitIsRefusedBeforeAnyPass) {
    const fs::path scene = write("scene.json", insideScene());
    const std::string out = (dir_ / "out").string();
    const struct {
        std::vector<std::string> args;
        const char* text;
    } cases[] = {
        {{"render", scene.string(), "-o", out, "--passes", "1", "--pulse", "square:1e9"},
         "error: --pulse square:1e9 spans "},
        {{"render", scene.string(), "-o", out, "--passes", "1", "--sensor", "exp:1e9"},
         "error: --sensor exp:1e9 spans "},
        {{"render", scene.string(), "-o", out, "--method", "pt", "--passes", "1", "--sensor", "exp:1e9"},
         "error: --sensor exp:1e9 spans "},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.args.back());
        const Proc p = runTpb(c.args, dir_, {}, 60.0);
        EXPECT_EQ(p.code, 2) << p.err;
        EXPECT_EQ(fromErrorLine(p.err).rfind(c.text, 0), 0u) << p.err;
        EXPECT_NE(p.err.find("the limit is 1048576 (2^20) bins"), std::string::npos) << p.err;
        EXPECT_NE(p.err.find("use wider bins"), std::string::npos) << p.err;
        EXPECT_NE(p.err.find("narrower than"), std::string::npos) << p.err;
        EXPECT_EQ(p.err.find("internal error"), std::string::npos) << p.err;
        EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing may be written, not even preview.exr";
    }
    if (runTpb({"view", "--help"}, dir_).code == 0) {  // built with the viewer (a screenshot run ends by itself)
        const Proc v = runTpb({"view", scene.string(), "--pulse", "square:1e9", "--screenshot",
                               (dir_ / "shot.png").string(), "--after-passes", "1"},
                              dir_, {}, 60.0);
        EXPECT_EQ(v.code, 2) << v.err;
        EXPECT_EQ(fromErrorLine(v.err).rfind("error: --pulse square:1e9 spans ", 0), 0u) << v.err;
        EXPECT_FALSE(fs::exists(dir_ / "shot.png"));
    }
}

// --counts: negative rates or budgets, unknown items and coates without pileup are refused when the
// command line is parsed, naming the item and the fix, before anything is written.
TEST_F(CliErrors, BadCountsAreRefusedNamingTheItemAndTheFix) {
    const fs::path scene = write("scene.json", insideScene());
    for (const auto& [model, text] : std::vector<std::pair<std::string, std::string>>{
             {"dark_hz=-5", "error: --counts: dark_hz=-5: dark_hz must be >= 0 (a rate in Hz; 0 for no dark counts)"},
             {"photons=-1", "error: --counts: photons=-1: photons must be > 0"},
             {"ambient_hz=-2", "error: --counts: ambient_hz=-2: ambient_hz must be >= 0"},
             {"coates", "error: --counts: coates: the Coates correction undoes pile-up; add pileup"},
             {"dark=3", "error: --counts: dark=3: unknown key; use photons=, efficiency=, dark_hz="}}) {
        const Proc p = render(scene, {"--counts", model});
        EXPECT_EQ(p.code, 2) << p.err;
        EXPECT_EQ(fromErrorLine(p.err).rfind(text, 0), 0u) << p.err;
        EXPECT_FALSE(fs::exists(dir_ / "out"));
    }
}

// Item 12: --frame-step 0 and --spp 0 said "not in range 0.000000 to 1797...(309 digits)".
TEST_F(CliErrors, FrameStepZeroSaysTheRangeInAFewWords) {
    const fs::path scene = write("scene.json", insideScene());
    for (const auto& [flag, text] :
         {std::pair<std::string, std::string>{"--frame-step",
                                              "error: --frame-step: must be an integer in [1, 2147483647] (1 = every "
                                              "frame); got 0\n"},
          {"--spp", "error: --spp: must be an integer in [1, 1048576] (camera paths per pixel per pass); got 0\n"}}) {
        const Proc p = render(scene, {"--method", "pt", flag, "0"});
        EXPECT_EQ(p.code, 2) << p.err;
        EXPECT_EQ(fromErrorLine(p.err).rfind(text, 0), 0u) << p.err;
        EXPECT_LT(p.err.size(), 200u) << p.err;
        EXPECT_EQ(p.err.find("17976931348623157"), std::string::npos) << p.err;
    }
}

// Item 12: --seed -1 wrapped to 2^64 - 1.
TEST_F(CliErrors, NegativeSeedIsRefusedNotWrapped) {
    const fs::path scene = write("scene.json", insideScene());
    const Proc p = render(scene, {"--seed", "-1"});
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind(
                  "error: --seed: must be an integer in [0, 18446744073709551615] (2^64 - 1); got -1", 0),
              0u)
        << p.err;
    const Proc q = render(scene, {"-q", "--seed", "18446744073709551615"});  // the largest seed is fine
    ASSERT_EQ(q.code, 0) << q.err;
    const nlohmann::json summary = nlohmann::json::parse(slurp(dir_ / "out" / "summary.json"));
    EXPECT_EQ(summary["settings"]["seed"].get<uint64_t>(), 18446744073709551615ull);
}

// Item 12: --unwarp --real-time and --continuous --delta were both accepted (the default won).
TEST_F(CliErrors, ContradictoryFlagsAreRefused) {
    const fs::path scene = write("scene.json", insideScene());
    Proc p = render(scene, {"--unwarp", "--real-time"});
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind("error: --unwarp and --real-time contradict each other: give one of them", 0),
              0u)
        << p.err;
    p = render(scene, {"--continuous", "--delta"});
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind("error: --continuous and --delta contradict each other: give one of them", 0),
              0u)
        << p.err;
    EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// The video flags were silently ignored without the output they shape (--fps 60 without --mp4).
TEST_F(CliErrors, VideoFlagsWithoutTheirOutputAreRefused) {
    const fs::path scene = write("scene.json", insideScene());
    Proc p = render(scene, {"--fps", "60"});
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind(
                  "error: --fps sets the frame rate of transient.mp4, which only --mp4 writes: add --mp4, or "
                  "drop --fps",
                  0),
              0u)
        << p.err;
    for (const std::vector<std::string>& flag :
         {std::vector<std::string>{"--video-ev", "1"}, {"--false-colour"}, {"--no-srgb"}}) {
        std::vector<std::string> args = flag;
        p = render(scene, args);
        EXPECT_EQ(p.code, 2) << flag[0] << ": " << p.err;
        EXPECT_EQ(fromErrorLine(p.err).rfind("error: " + flag[0] +
                                                 " shapes transient.mp4 and contact_sheet.png, and neither is "
                                                 "written: add --mp4 or --contact-sheet N, or drop " +
                                                 flag[0],
                                             0),
                  0u)
            << p.err;
    }
    EXPECT_FALSE(fs::exists(dir_ / "out"));
    // With the output they shape, they are taken.
    p = render(scene, {"-q", "--contact-sheet", "2", "--false-colour", "--video-ev", "1"});
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_TRUE(fs::exists(dir_ / "out" / "contact_sheet.png"));
}

// Item 12: --threads 1000 ran a thread per tile on 2 cores. Capped at 4 x the cores, with a warning.
TEST_F(CliErrors, ThreadsFarAboveTheCoresAreCapped) {
    const fs::path scene = write("scene.json", insideScene());
    const int cap = 4 * static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const Proc p = render(scene, {"-q", "--threads", "1000"});
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_NE(p.err.find("warning: --threads 1000 is more than 4 x the "), std::string::npos) << p.err;
    EXPECT_NE(p.err.find("using " + std::to_string(cap) + " (more threads than cores only add"), std::string::npos)
        << p.err;
    const nlohmann::json summary = nlohmann::json::parse(slurp(dir_ / "out" / "summary.json"));
    EXPECT_EQ(summary["settings"]["threads"].get<int>(), cap);
    const Proc q = render(scene, {"--threads", "-2"});
    EXPECT_EQ(q.code, 2) << q.err;
    EXPECT_EQ(fromErrorLine(q.err).rfind("error: --threads: must be an integer in [0, 2147483647] (0 = all cores", 0),
              0u)
        << q.err;
}

// Item 12: `bench --bins-list 0` blamed --bins; `bench --bench-passes 0` exited 0 with a table of zeros.
TEST_F(CliErrors, BenchBinsListZeroNamesBinsList) {
    const fs::path scene = write("scene.json", insideScene());
    const Proc p = runTpb({"bench", scene.string(), "--bins-list", "8,0"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind(
                  "error: --bins-list: must be an integer in [1, 2147483647] (each a number of time bins, "
                  "e.g. 1,256,1024); got 0",
                  0),
              0u)
        << p.err;
    EXPECT_EQ(p.out.find("ratio"), std::string::npos) << p.out;  // nothing was measured
}

TEST_F(CliErrors, BenchPassesZeroIsRefused) {
    const fs::path scene = write("scene.json", insideScene());
    const Proc p = runTpb({"bench", scene.string(), "--bins-list", "8", "--bench-passes", "0"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind(
                  "error: --bench-passes: must be an integer in [1, 100000] (passes measured per bin count); "
                  "got 0",
                  0),
              0u)
        << p.err;
    EXPECT_EQ(p.out.find("ratio"), std::string::npos) << p.out;
}

// `bench --json FILE` (issue 15, measure first): the command, and per bin count the medians, the
// stage shares, the camera-pass thread-ns per ray / estimate / splatted bin and the memory. Fails
// if: a field is missing, a count is zero although the pass did work, or the shares exceed 1.
TEST_F(CliErrors, BenchJsonRecordsTheCommandAndThePerUnitCosts) {
    const fs::path scene = write("scene.json", insideScene());
    const std::string json = (dir_ / "bench.json").string();
    const Proc p = runTpb({"bench", scene.string(), "--bins-list", "1,16", "--bench-passes", "2", "--width", "16",
                           "--height", "16", "--json", json},
                          dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    std::ifstream in(json);
    ASSERT_TRUE(in) << json;
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_NE(j.at("command").get<std::string>().find("--json"), std::string::npos);
    ASSERT_EQ(j.at("configs").size(), 2u);
    for (const auto& c : j.at("configs")) {
        EXPECT_EQ(c.at("passes").get<int>(), 2);
        EXPECT_GT(c.at("per_pass").at("camera_rays").get<double>(), 0.0);
        EXPECT_GT(c.at("per_pass").at("bins_splatted").get<double>(), 0.0);
        EXPECT_GT(c.at("camera_thread_ns").at("per_camera_ray").get<double>(), 0.0);
        EXPECT_GT(c.at("camera_thread_ns").at("per_splatted_bin").get<double>(), 0.0);
        double share = 0.0;
        for (const char* k : {"photon", "build", "camera"}) share += c.at("share_of_pass").at(k).get<double>();
        EXPECT_GT(share, 0.0);
        EXPECT_LE(share, 1.0 + 1e-9);
        EXPECT_GT(c.at("film_bytes_per_pixel_bin").get<double>(), 0.0);
        EXPECT_GT(c.at("peak_rss_bytes").get<double>(), 0.0);
    }
    // More bins: at least as many bins written per pass (an estimate covers more of them).
    EXPECT_GE(j["configs"][1]["per_pass"]["bins_splatted"].get<double>(),
              j["configs"][0]["per_pass"]["bins_splatted"].get<double>());
}

// `bench --threads-list 1,2` (issue 15: 2 threads against 1 in one run): a configuration per (bins,
// threads) in the JSON and a speed-up line per bin count; --threads with it is refused.
TEST_F(CliErrors, BenchThreadsListMeasuresEachThreadCountAndReportsTheSpeedUp) {
    const fs::path scene = write("scene.json", insideScene());
    const std::string json = (dir_ / "bench.json").string();
    const Proc p = runTpb({"bench", scene.string(), "--bins-list", "1,8", "--threads-list", "1,2", "--bench-passes",
                           "1", "--width", "8", "--height", "8", "--json", json},
                          dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    std::ifstream in(json);
    ASSERT_TRUE(in) << json;
    const nlohmann::json j = nlohmann::json::parse(in);
    ASSERT_EQ(j.at("configs").size(), 4u);
    const int expected[4][2] = {{1, 1}, {1, 2}, {8, 1}, {8, 2}};
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(j["configs"][i]["bins"].get<int>(), expected[i][0]) << i;
        EXPECT_EQ(j["configs"][i]["threads"].get<int>(), expected[i][1]) << i;
    }
    EXPECT_NE(p.out.find("speed-up 2 threads over 1 at 1 bins = "), std::string::npos) << p.out;
    EXPECT_NE(p.out.find("speed-up 2 threads over 1 at 8 bins = "), std::string::npos) << p.out;
    const Proc q = runTpb({"bench", scene.string(), "--threads-list", "1,2", "--threads", "2"}, dir_);
    EXPECT_EQ(q.code, 2) << q.err;
    EXPECT_NE(q.err.find("--threads-list and --threads both set the thread count"), std::string::npos) << q.err;
    EXPECT_EQ(q.out.find("ratio"), std::string::npos) << q.out;
}

// Item 12: a 1024x1024x512 film gave no hint of the 17 minutes its frames take to write. Before the
// render: the number of frames, their size and the write time estimated from preview.exr.
TEST_F(CliErrors, ExportSizeAndTimeAreEstimatedBeforeRendering) {
    const fs::path scene = write("scene.json", insideScene());
    const std::vector<std::string> args{"render", scene.string(), "-o", (dir_ / "out").string(), "--frame-step", "2"};
    const Proc p = runTpb(args, dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    const size_t at = p.out.find(
        "frames: 4 EXR files of 16x16 (float), up to 12.0 KiB uncompressed; writing them "
        "will take ");
    EXPECT_NE(at, std::string::npos) << p.out;
    EXPECT_NE(p.out.find("after the render (estimated from preview.exr: ", at), std::string::npos) << p.out;
    EXPECT_LT(at, p.out.find("passes in")) << "printed before the render's report";
}

// Item 12: a mesh path that is a folder said "not found" (CliErrors.MissingAndCorruptMeshes); NaN
// vertices said "degenerate" (or rendered, moved to the origin); huge ones had no scene file:line:key.
TEST_F(CliErrors, BadMeshVerticesNameTheSceneKeyAndTheObjLine) {
    const fs::path f = dir_ / "scene.json";
    const auto meshScene = [&](const std::string& file, const std::string& extra = "") {
        return sceneWith(8, "  \"shapes\": [{\"type\": \"mesh\", \"file\": \"" + file + "\", \"material\": \"white\"" +
                                extra + "}],");
    };
    write("nan.obj", "v nan nan nan\nv nan 0 0\nv 0 nan 0\nf 1 2 3\n");
    write("scene.json", meshScene("nan.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file",
                    "nan.obj:1: vertex 1 (\"v\" line 1) has a non-finite coordinate (nan)");
    write("huge.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n");
    write("scene.json", meshScene("huge.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file",
                    "huge.obj:2: vertex 2 (\"v\" line 2) coordinate 1e30 is beyond +-1e9 m");
    write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write("scene.json", meshScene("tri.obj", ", \"transform\": {\"scale\": 1e9, \"translate\": [1e9, 0, 0]}"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].transform",
                    "moves a vertex of the mesh to (2e+09, 0, 0), beyond +-1e9 m");
}

// Item 12: camera.position 1e308 was reported as "camera.up ... parallel".
TEST_F(CliErrors, HugeCameraPositionNamesThePosition) {
    const fs::path f =
        write("scene.json", sceneWith(3, "  \"camera\": {\"position\": [1e308, 0.5, 3], \"look_at\": [0, 0.5, 0]},"));
    expectUserError(render(f), f.string() + ":3", "camera.position",
                    "position is too far out: scene coordinates and sizes must be within +-1e9 m");
}

// Item 12: a UTF-16 scene file said "unexpected byte 0xFF".
TEST_F(CliErrors, Utf16SceneFileSaysToConvertIt) {
    std::string utf16 = "\xFF\xFE";
    for (char c : sceneWith(0, "")) utf16 += std::string{c, '\0'};
    const fs::path f = write("scene.json", utf16);
    expectUserError(render(f), f.string() + ":1", "",
                    "the file is UTF-16 (little-endian) text, but scene files must be UTF-8; convert it (e.g. iconv");
}

// Item 8: SIGTERM (timeout, a job scheduler) killed the render and lost every finished pass. It is
// handled like the first Ctrl-C: the pass in progress finishes, everything is written, and the exit
// code (143 = 128 + SIGTERM) says the run was cut short. Also with the path tracer.
TEST_F(CliErrors, SigtermWritesTheFinishedPassesAndExitsNonZero) {
    const fs::path scene = write("scene.json", insideScene("{\"bins\": 8}",
                                                           "{\"photons_per_pass\": 20000, "
                                                           "\"passes\": 100000, \"seed\": 1}"));
    for (const std::string method : {"beams", "pt"}) {
        SCOPED_TRACE(method);
        const fs::path out = dir_ / ("out_" + method);
        const double t0 = now();
        const pid_t pid =
            spawnTpb({"render", scene.string(), "-o", out.string(), "--threads", "2", "--method", method}, dir_, {});
        ASSERT_GT(pid, 0);
        ASSERT_TRUE(waitForText(dir_ / "stderr.txt", "pass 1:", pid, 60.0)) << slurp(dir_ / "stderr.txt");
        kill(pid, SIGTERM);
        const Proc p = waitTpb(pid, dir_, t0, 120.0);
        EXPECT_FALSE(p.timedOut);
        EXPECT_EQ(p.signal, 0) << "killed by the signal: the finished passes are lost\n" << p.err;
        EXPECT_EQ(p.code, 143) << p.err;
        EXPECT_NE(p.err.find("interrupted by SIGTERM: writing the "), std::string::npos) << p.err;
        ASSERT_TRUE(fs::exists(out / "summary.json")) << p.err;
        const nlohmann::json summary = nlohmann::json::parse(slurp(out / "summary.json"));
        EXPECT_GE(summary["passes"].get<int>(), 1);
        EXPECT_EQ(summary["outputs"]["frames_written"].get<int>(), 8);
        EXPECT_EQ(countFrames(out / "frames"), 8);
    }
}

// Item 8: SIGTERM in `tpb reference` and `tpb converge`: the finished passes are written too.
TEST_F(CliErrors, SigtermInReferenceAndConvergeWritesWhatWasDone) {
    const fs::path scene = write("scene.json", insideScene("{\"bins\": 8}",
                                                           "{\"photons_per_pass\": 20000, "
                                                           "\"passes\": 100000, \"seed\": 1}"));
    const fs::path ref = dir_ / "ref.tpbref";
    double t0 = now();
    pid_t pid =
        spawnTpb({"reference", scene.string(), "-o", ref.string(), "--time", "300", "--threads", "2"}, dir_, {});
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(waitForText(dir_ / "stderr.txt", "reference: pass 1", pid, 60.0)) << slurp(dir_ / "stderr.txt");
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    kill(pid, SIGTERM);
    Proc p = waitTpb(pid, dir_, t0, 120.0);
    EXPECT_EQ(p.signal, 0) << p.err;
    EXPECT_EQ(p.code, 143) << p.err;
    EXPECT_NE(p.err.find("interrupted by SIGTERM: writing the "), std::string::npos) << p.err;
    ASSERT_TRUE(fs::exists(ref)) << p.err;
    EXPECT_NE(p.out.find("(interrupted)"), std::string::npos) << p.out;

    const fs::path out = dir_ / "conv";
    t0 = now();
    pid = spawnTpb({"converge", scene.string(), "--reference", ref.string(), "-o", out.string(), "--time", "300",
                    "--no-plot", "--threads", "2"},
                   dir_, {});
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(waitForText(dir_ / "stdout.txt", "passes  volume", pid, 60.0)) << slurp(dir_ / "stderr.txt");
    kill(pid, SIGTERM);
    p = waitTpb(pid, dir_, t0, 120.0);
    EXPECT_EQ(p.signal, 0) << p.err;
    EXPECT_EQ(p.code, 143) << p.err;
    EXPECT_NE(p.err.find("interrupted by SIGTERM: writing what was measured"), std::string::npos) << p.err;
    EXPECT_TRUE(fs::exists(out / "convergence.csv")) << p.err;
    EXPECT_TRUE(fs::exists(out / "convergence.json")) << p.err;
}

// Item 6: the automatic-range pilot ignored Ctrl-C (and, with a huge radius, ran for minutes with no
// output). It reports its progress and a signal stops it; nothing is written.
TEST_F(CliErrors, CtrlCStopsThePilotPass) {
    // A pilot that takes seconds: an albedo-0.9 box full of dense fog, deep paths, a wide kernel.
    const fs::path scene = write("scene.json", R"({"version": 1,
      "camera": {"position": [0, 0.5, 0.9], "look_at": [0, 0.5, 0], "resolution": [64, 64]},
      "film": {"bins": 8},
      "media": {"fog": {"sigma_s": 3}}, "global_medium": "fog",
      "materials": {"white": {"type": "diffuse", "albedo": 0.9}},
      "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 1, 1], "material": "white", "flip_normals": true}],
      "lights": [{"type": "point", "position": [0, 0.8, 0], "power": 5}],
      "render": {"photons_per_pass": 2000, "passes": 2, "seed": 1, "max_depth": 400, "radius_relative": 0.2}})");
    const double t0 = now();
    const pid_t pid = spawnTpb({"render", scene.string(), "-o", (dir_ / "out").string(), "--threads", "2"}, dir_, {});
    ASSERT_GT(pid, 0);
    // Not on a terminal, the pilot's first progress line comes after 1 s. If the first pass starts
    // (or the render ends) first, this machine ran the pilot in under a second: nothing to interrupt.
    const std::string progress = "fitting the film's time range (pilot pass): ";
    bool seen = false, passed = false;
    while (now() - t0 < 30.0 && !seen && !passed) {
        const std::string err = slurp(dir_ / "stderr.txt");
        seen = err.find(progress) != std::string::npos;
        passed = err.find("pass 1:") != std::string::npos || waitpid(pid, nullptr, WNOHANG) == pid;
        if (!seen && !passed) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!seen) {
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
        if (passed) GTEST_SKIP() << "the pilot took less than 1 s on this machine:\n" << slurp(dir_ / "stderr.txt");
        FAIL() << "30 s of pilot without a progress line:\n" << slurp(dir_ / "stderr.txt");
    }
    kill(pid, SIGINT);
    const double tInt = now();
    const Proc p = waitTpb(pid, dir_, t0, 120.0);
    EXPECT_EQ(p.signal, 0) << p.err;
    EXPECT_EQ(p.code, 130) << p.err;
    EXPECT_LT(p.seconds - (tInt - t0), 20.0);
    EXPECT_NE(p.err.find("interrupted by Ctrl-C (SIGINT) while fitting the film's time range (pilot pass); nothing "
                         "was written"),
              std::string::npos)
        << p.err;
    EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// Item 6, at its root: the pilot polls the abort flag and reports its progress.
TEST_F(CliErrors, PilotPollsTheAbortFlagAndReportsProgress) {
    const tpb::SceneDesc desc = tpb::loadSceneFromString(insideScene(), "scene.json");
    const std::unique_ptr<const tpb::Scene> scene = tpb::Scene::build(desc, tpb::analyzeStages);
    tpb::RenderSettings settings = tpb::RenderSettings::fromDesc(desc.render, scene->bounds.diagonal());
    settings.threads = 2;
    std::atomic<bool> abort{true};
    tpb::PilotControl pc;
    pc.abort = &abort;
    tpb::TimeRangeFit fit = tpb::measureArrivalRange(*scene, settings, 4000, pc);
    EXPECT_TRUE(fit.interrupted);
    EXPECT_FALSE(fit.fromPilot);
    abort = false;
    std::vector<double> progress;
    pc.progress = [&](double f) { progress.push_back(f); };
    fit = tpb::measureArrivalRange(*scene, settings, 4000, pc);
    EXPECT_FALSE(fit.interrupted);
    EXPECT_TRUE(fit.fromPilot);
    ASSERT_GE(progress.size(), 3u);
    EXPECT_EQ(progress.front(), 0.0);
    EXPECT_EQ(progress.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
}

// Item 9: a render into a folder that held an earlier render left the old frames beside the new ones
// (32 frames on disk, summary.json said 16). The earlier render's outputs, and only those, are
// removed first: files the user put there stay.
TEST_F(CliErrors, StaleOutputsOfAnEarlierRenderAreRemoved) {
    const fs::path scene = write("scene.json", insideScene("{\"bins\": 16}"));
    const fs::path out = dir_ / "out";
    const std::vector<std::string> base{"render", scene.string(), "-o", out.string(), "-q"};
    auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> a = base;
        a.insert(a.end(), extra.begin(), extra.end());
        return a;
    };
    ASSERT_EQ(runTpb(base, dir_).code, 0);
    ASSERT_EQ(countFrames(out / "frames"), 16);
    write("out/notes.txt", "mine");
    write("out/frames/frame_notes.txt", "mine too");
    write("out/frames/frame_00100.exr.keep", "mine too");
    // Half the bins: 8 frames, not 8 new + 8 old.
    Proc p = runTpb(with({"--bins", "8"}), dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(countFrames(out / "frames"), 8 + 2);  // + the two files of the user named frame_*
    EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["outputs"]["frames_written"].get<int>(), 8);
    EXPECT_EQ(slurp(out / "notes.txt"), "mine");
    EXPECT_EQ(slurp(out / "frames" / "frame_notes.txt"), "mine too");
    // No frames and no strip: the earlier render's frames and strip go too.
    p = runTpb(with({"--no-frames", "--strip", "0"}), dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(countFrames(out / "frames"), 2);
    EXPECT_FALSE(fs::exists(out / "strip.png"));
    EXPECT_TRUE(fs::exists(out / "steady.exr"));
    // A folder written by a tpb without manifests: its summary.json says what it wrote.
    ASSERT_EQ(runTpb(base, dir_).code, 0);
    fs::remove(out / ".tpb-manifest.json");
    p = runTpb(with({"--bins", "4"}), dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(countFrames(out / "frames"), 4 + 2);
    EXPECT_EQ(slurp(out / "notes.txt"), "mine");
}

// Item 9: two renders into one folder mixed their files. The second is refused while the first
// runs (a lock the kernel releases when the process ends, also when it is killed).
TEST_F(CliErrors, SecondConcurrentRenderIntoTheSameFolderIsRefused) {
    const fs::path scene = write("scene.json", insideScene("{\"bins\": 8}",
                                                           "{\"photons_per_pass\": 20000, "
                                                           "\"passes\": 100000, \"seed\": 1}"));
    const fs::path out = dir_ / "out";
    const fs::path firstDir = dir_ / "first";
    fs::create_directories(firstDir);
    const double t0 = now();
    const pid_t pid = spawnTpb({"render", scene.string(), "-o", out.string(), "--threads", "2"}, firstDir, {});
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(waitForText(firstDir / "stderr.txt", "pass 1:", pid, 60.0)) << slurp(firstDir / "stderr.txt");
    const Proc second = runTpb({"render", scene.string(), "-o", out.string(), "--passes", "1"}, dir_);
    EXPECT_EQ(second.code, 2) << second.err;
    EXPECT_EQ(fromErrorLine(second.err)
                  .rfind("error: " + out.string() + ": another tpb run (tpb render, pid " + std::to_string(pid) +
                             ") is writing into this folder; two runs in one folder would mix their files: wait "
                             "for it to end, or give this one another folder with -o",
                         0),
              0u)
        << second.err;
    // Killed outright (no cleanup at all): the lock goes with the process.
    kill(pid, SIGKILL);
    const Proc first = waitTpb(pid, firstDir, t0, 60.0);
    EXPECT_EQ(first.signal, SIGKILL);
    const Proc third = runTpb({"render", scene.string(), "-o", out.string(), "--passes", "1", "-q"}, dir_);
    EXPECT_EQ(third.code, 0) << third.err;
}

// Item 11: with all the energy outside the film's time range (every frame black) nothing was said.
// Now an error (exit 2) naming the film key and the range that would cover the measured arrivals.
TEST_F(CliErrors, AllBlackFilmIsAnErrorThatSaysHowToFixTheRange) {
    const fs::path f = write("scene.json", insideScene("{\"bins\": 8,\n \"start_m\": 100, \"bin_width_m\": 0.5}"));
    for (const std::string method : {"beams", "pt"}) {
        SCOPED_TRACE(method);
        const Proc p = render(f, {"-q", "--method", method});
        EXPECT_EQ(p.code, 2) << p.err;
        const std::string head = "error: " + f.string() +
                                 ":4: film.start_m: every frame is black: all the energy that "
                                 "reached the camera arrived outside the film's time range, 100 to 104 m OPL";
        EXPECT_NE(p.err.find(head), std::string::npos) << p.err;
        EXPECT_NE(p.err.find("a pilot pass measured arrivals from "), std::string::npos) << p.err;
        EXPECT_NE(p.err.find(": set \"film\": {\"start_m\": "), std::string::npos) << p.err;
        EXPECT_NE(p.err.find("or \"range\": \"auto\""), std::string::npos) << p.err;
        EXPECT_TRUE(fs::exists(dir_ / "out" / "summary.json"));
    }
}

// Item 11: above a few percent outside the film: a warning; below: the render's last line.
TEST_F(CliErrors, EnergyOutsideTheFilmIsReported) {
    const fs::path f = write("scene.json", insideScene("{\"bins\": 8,\n \"start_m\": 0, \"bin_width_m\": 0.25}"));
    const Proc p = render(f, {});
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_NE(p.err.find("warning: " + f.string() + ":4: film.start_m: "), std::string::npos) << p.err;
    EXPECT_NE(p.err.find("% of the energy that reached the camera arrived outside the film's time range, 0 to 2 m OPL"),
              std::string::npos)
        << p.err;
    const fs::path g = write("auto.json", insideScene());
    const Proc q = render(g, {});
    EXPECT_EQ(q.code, 0) << q.err;
    EXPECT_EQ(q.err.find("warning"), std::string::npos) << q.err;
    EXPECT_NE(q.out.find("% of the energy outside the film\n"), std::string::npos) << q.out;
}

// Issue 14: the estimator and time-kernel flags and keys: a bad value names the flag or the
// file:line:key and the allowed values; nothing is written.
TEST_F(CliErrors, EstimatorAndTimeKernelErrorsNameTheAllowedValues) {
    const fs::path scene = write("scene.json", insideScene());
    const std::string out = (dir_ / "out").string();
    expectRefused({
        {{"render", scene.string(), "-o", out, "--estimator", "beam3d"},
         "error: --estimator: unknown volume estimator \"beam3d\"; allowed: beam2d"},
        {{"render", scene.string(), "-o", out, "--surface-estimator", "grid"},
         "error: --surface-estimator: unknown surface estimator \"grid\"; allowed: ppm"},
        {{"render", scene.string(), "-o", out, "--time-kernel", "gauss"},
         "error: --time-kernel: gauss: allowed none, box or box:WIDTH"},
        {{"render", scene.string(), "-o", out, "--time-kernel", "box:0"}, "error: --time-kernel: box:0: allowed"},
        {{"render", scene.string(), "-o", out, "--time-kernel", "box:1000"},
         "error: --time-kernel: the time kernel's width 1000 m (of optical path) is wider than the film's whole time "
         "range"},
        {{"render", scene.string(), "-o", out, "--method", "pt", "--time-kernel", "box"},
         "error: --time-kernel applies to the photon-beams estimators only; --method pt"},
        {{"reference", scene.string(), "-o", out + "/r.tpbref", "--passes", "1", "--estimator", "beam2d"},
         "error: --estimator applies to the photon-beams estimators only"},
        {{"info", scene.string(), "--estimator", "nope"}, "error: --estimator: unknown volume estimator \"nope\""},
    });
    // In the scene file: named by file:line:key (the render block is on line 8).
    const Proc p = render(write("bad.json", insideScene("{\"bins\": 8}", "{\"volume_estimator\": \"beam9\"}")));
    expectUserError(p, (dir_ / "bad.json").string() + ":8", "render.volume_estimator",
                    "unknown volume estimator \"beam9\"; allowed: ");
}

// tpb converge --method takes a list of estimator variants: each runs and gets its rows; a bad
// entry is refused before the output folder exists, naming the entry.
TEST_F(CliErrors, ConvergeMeasuresEstimatorVariantsAndRefusesBadOnes) {
    const fs::path scene = write("scene.json", insideScene());
    const std::string ref = (dir_ / "r.tpbref").string(), out = (dir_ / "out").string();
    const Proc r =
        runTpb({"reference", scene.string(), "-o", ref, "--passes", "2", "-q", "--width", "8", "--height", "8"}, dir_,
               {}, 60.0);
    ASSERT_EQ(r.code, 0) << r.err;
    expectRefused({
        {{"converge", scene.string(), "--reference", ref, "-o", out, "--method", "beam2d,beam9", "--passes", "1"},
         "error: --method beam9: --estimator: unknown volume estimator \"beam9\"; allowed: "},
        {{"converge", scene.string(), "--reference", ref, "-o", out, "--method", "beam2d+tent", "--passes", "1"},
         "error: --method beam2d+tent: unknown time kernel \"tent\""},
        {{"converge", scene.string(), "--reference", ref, "-o", out, "--method", "pt,pt", "--passes", "1"},
         "error: --method pt,pt: \"pt\" is listed twice"},
    });
    const Proc ok = runTpb({"converge", scene.string(), "--reference", ref, "-o", out, "--method",
                            "beams,beam2d+box:0.05", "--passes", "2", "--no-plot", "-q"},
                           dir_, {}, 120.0);
    ASSERT_EQ(ok.code, 0) << ok.err;
    std::ifstream csv(dir_ / "out" / "convergence.csv");
    std::string line;
    std::set<std::string> methods;
    std::getline(csv, line);  // header
    while (std::getline(csv, line)) methods.insert(line.substr(0, line.find(',')));
    EXPECT_EQ(methods, (std::set<std::string>{"beams", "beam2d+box:0.05"}));
}

// Issue 16, checkpoint and resume (render/checkpoint.h): SIGTERM mid-render writes a checkpoint;
// `tpb render --resume DIR` goes on to the pass limit the render had, and its film (the
// checkpoint's payload: every sum, bit for bit) and steady.exr equal those of one uninterrupted run.
using tpb::test::checkpointPayload;

TEST_F(CliErrors, SigtermWritesACheckpointAndTheResumeEqualsAnUninterruptedRun) {
    const fs::path scene = write("scene.json", insideScene("{\"bins\": 8}",
                                                           "{\"photons_per_pass\": 10000, "
                                                           "\"passes\": 16, \"seed\": 1}"));
    const fs::path out = dir_ / "out";
    const double t0 = now();
    const pid_t pid = spawnTpb(
        {"render", scene.string(), "-o", out.string(), "--threads", "2", "--strip", "0", "--radius", "0.02"}, dir_, {});
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(waitForText(dir_ / "stderr.txt", "pass 1:", pid, 60.0)) << slurp(dir_ / "stderr.txt");
    kill(pid, SIGTERM);
    const Proc p = waitTpb(pid, dir_, t0, 120.0);
    EXPECT_EQ(p.code, 143) << p.err;
    ASSERT_TRUE(fs::exists(out / "checkpoint.tpbck")) << p.err;
    EXPECT_NE(p.err.find("checkpoint (interrupted): "), std::string::npos) << p.err;
    const int done = nlohmann::json::parse(slurp(out / "summary.json"))["passes"].get<int>();
    EXPECT_GE(done, 1);

    // Resumed with another thread count; the flags (--radius) come from the checkpoint.
    const Proc r = runTpb({"render", "--resume", out.string(), "--threads", "1", "--strip", "0"}, dir_, {}, 300.0);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("resumed " + std::to_string(done) + " passes from "), std::string::npos) << r.out;
    const nlohmann::json sum = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_EQ(sum["passes"].get<int>(), 16);
    EXPECT_EQ(sum["resumed"]["passes"].get<int>(), done);
    EXPECT_EQ(sum["per_pass"].size(), 16u);

    const fs::path whole = dir_ / "whole";
    const Proc w = runTpb(
        {"render", scene.string(), "-o", whole.string(), "--strip", "0", "--radius", "0.02", "--checkpoint", "-q"},
        dir_, {}, 300.0);
    ASSERT_EQ(w.code, 0) << w.err;
    const std::string a = checkpointPayload(out / "checkpoint.tpbck"),
                      b = checkpointPayload(whole / "checkpoint.tpbck");
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << "the resumed film differs from the uninterrupted one";
    EXPECT_EQ(slurp(out / "steady.exr"), slurp(whole / "steady.exr"));
    EXPECT_EQ(slurp(out / "frames" / "frame_00004.exr"), slurp(whole / "frames" / "frame_00004.exr"));
}

// Issue 34: one render path for every method. The path tracer (--method pt) writes a checkpoint
// and resumes from it like the photon beams (refused before: "applies to the photon beams only
// so far"): 2 passes, then a resume to 4 without --method (the checkpoint records it), equal bit
// for bit to 4 passes in one go; a resume that asks for another method is refused.
TEST_F(CliErrors, PathTracerCheckpointResumesToTheFilmOfOneUninterruptedRun) {
    const fs::path scene = write("scene.json", insideScene("{\"bins\": 8}", "{\"seed\": 3}"));
    const fs::path out = dir_ / "out", whole = dir_ / "whole";
    const std::vector<std::string> pt{"--method", "pt", "--spp", "2", "--strip", "0", "-q"};
    std::vector<std::string> first{"render", scene.string(), "-o", out.string(), "--passes", "2", "--checkpoint"};
    first.insert(first.end(), pt.begin(), pt.end());
    const Proc a = runTpb(first, dir_, {}, 300.0);
    ASSERT_EQ(a.code, 0) << a.err;
    ASSERT_TRUE(fs::exists(out / "checkpoint.tpbck")) << a.err;

    const Proc r = runTpb({"render", "--resume", out.string(), "--passes", "4", "--strip", "0"}, dir_, {}, 300.0);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("resumed 2 passes from "), std::string::npos) << r.out;
    const nlohmann::json sum = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_EQ(sum["method"], "pt");
    EXPECT_EQ(sum["passes"].get<int>(), 4);
    EXPECT_EQ(sum["settings"]["samples_per_pixel"].get<int>(), 2);

    std::vector<std::string> once{"render", scene.string(), "-o", whole.string(), "--passes", "4", "--checkpoint"};
    once.insert(once.end(), pt.begin(), pt.end());
    ASSERT_EQ(runTpb(once, dir_, {}, 300.0).code, 0);
    const std::string ca = checkpointPayload(out / "checkpoint.tpbck"),
                      cb = checkpointPayload(whole / "checkpoint.tpbck");
    ASSERT_FALSE(ca.empty());
    EXPECT_TRUE(ca == cb) << "the resumed path-traced film differs from the uninterrupted one";
    EXPECT_EQ(slurp(out / "steady.exr"), slurp(whole / "steady.exr"));
    EXPECT_EQ(slurp(out / "frames" / "frame_00004.exr"), slurp(whole / "frames" / "frame_00004.exr"));

    const Proc m = runTpb({"render", "--resume", out.string(), "--method", "beams", "--passes", "6"}, dir_);
    EXPECT_EQ(m.code, 2) << m.err;
    EXPECT_NE(m.err.find("--method"), std::string::npos) << m.err;
}

TEST_F(CliErrors, ResumeRefusesAChangedSceneOrSettingAndNamesWhatChanged) {
    const fs::path scene = write("scene.json", insideScene());
    const fs::path out = dir_ / "out";
    ASSERT_EQ(
        runTpb({"render", scene.string(), "-o", out.string(), "--no-frames", "--strip", "0", "--checkpoint", "-q"},
               dir_)
            .code,
        0);
    const std::string cp = slurp(out / "checkpoint.tpbck");
    ASSERT_FALSE(cp.empty());

    std::string edited = insideScene();
    edited.replace(edited.find("\"power\": 5"), 10, "\"power\": 6");
    write("scene.json", edited);
    Proc p = runTpb({"render", "--resume", out.string(), "--passes", "4"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("lights[0].power: the checkpoint has (5, 5, 5), this run has (6, 6, 6)"), std::string::npos)
        << p.err;
    EXPECT_EQ(slurp(out / "checkpoint.tpbck"), cp) << "a refused resume must leave the checkpoint alone";

    write("scene.json", insideScene());
    p = runTpb({"render", "--resume", out.string(), "--seed", "9"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("--seed 9: the checkpoint's render ran with 1"), std::string::npos) << p.err;

    p = runTpb({"render", "--resume", (dir_ / "nowhere").string()}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("no checkpoint"), std::string::npos) << p.err;

    p = runTpb({"render", "--resume", out.string(), "--passes", "3", "-q"}, dir_);
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["passes"].get<int>(), 3);
}

// Issue 16: a Mitsuba 3 XML scene goes through every command like a JSON one; its mistakes are user
// errors (exit 2) naming the XML file, the line and the element, a broken include its own file.
TEST_F(CliErrors, MitsubaXmlScenesAreCheckedLikeJson) {
    const fs::path good = write("ok.xml",
                                "<scene version=\"3.0.0\">\n<shape type=\"cube\"/>\n"
                                "<emitter type=\"point\"><point name=\"position\" value=\"0, 0, 3\"/></emitter>\n"
                                "<sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0,0,5\" "
                                "target=\"0,0,0\"/></transform><film type=\"hdrfilm\"><integer name=\"width\" "
                                "value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor></scene>\n");
    const Proc ok = runTpb({"info", good.string()}, dir_);
    EXPECT_EQ(ok.code, 0) << ok.err;
    EXPECT_NE(ok.out.find("8x8"), std::string::npos) << ok.out;
    const fs::path bad = write("bad.xml", "<scene version=\"3.0.0\">\n\n<shape type=\"torus\"/>\n</scene>\n");
    expectUserError(render(bad), bad.string() + ":3", "<shape type=\"torus\">", "unsupported shape type \"torus\"");
    const fs::path broken = write("broken.xml", "<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>\n");
    expectUserError(runTpb({"info", broken.string()}, dir_), broken.string() + ":3", "", "XML parse error");
    const fs::path inc = write("inc.xml", "<scene version=\"3.0.0\">\n<include filename=\"broken.xml\"/>\n</scene>\n");
    expectUserError(runTpb({"info", inc.string()}, dir_), broken.string() + ":3", "", "XML parse error");
}

// Issue 33 item 8: `tpb render /dev/zero` read forever (and ignored Ctrl-C), a FIFO blocked in
// open(), and XML nested 50,000 deep crashed the loader. Each is now a user error, exit 2, at once:
// special files are refused before they are opened, nesting beyond 256 levels by file:line.
TEST_F(CliErrors, SpecialFilesAndDeepNestingAreRefusedCleanly) {
    expectUserError(render("/dev/zero"), "/dev/zero", "", "it is not a regular file but a device");
    const fs::path fifo = dir_ / "pipe.json";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    expectUserError(render(fifo), fifo.string(), "", "it is not a regular file but a FIFO (pipe)");
    std::string xml = "<scene version=\"3.0.0\">\n";
    for (int i = 0; i < 50000; ++i) xml += "<shape type=\"cube\">\n";
    for (int i = 0; i < 50000; ++i) xml += "</shape>";
    const fs::path deepXml = write("deep.xml", xml + "\n</scene>\n");
    expectUserError(render(deepXml), deepXml.string() + ":257", "", "nested deeper than 256 levels");
    const fs::path deepJson = write("deep.json", std::string(50000, '[') + std::string(50000, ']'));
    expectUserError(render(deepJson), deepJson.string() + ":1", "", "nesting deeper than 256");
}

// ---- Issue 33, item 14: messages that misled or said nothing --------------------------------------

// 100 % of the energy outside the film was printed "1e+02%" on the last line.
TEST_F(CliErrors, LastLinePrintsPercentagesWithoutExponents) {
    const fs::path f = write("scene.json", insideScene("{\"bins\": 8,\n \"start_m\": 100, \"bin_width_m\": 0.5}"));
    const Proc p = render(f);
    EXPECT_EQ(p.code, 2) << p.err;  // an all-black film (the test above)
    EXPECT_NE(p.out.find("; 100% of the energy outside the film"), std::string::npos) << p.out;
    EXPECT_EQ(p.out.find("e+0"), std::string::npos) << p.out;
}

// --no-frames ended with "wrote 0 frames (real time, delta) to out/frames": say what was written.
TEST_F(CliErrors, NoFramesLastLineSaysWhatWasWrittenInstead) {
    const fs::path f = write("scene.json", insideScene());
    const Proc p = render(f);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(p.out.find("wrote 0 frames"), std::string::npos) << p.out;
    EXPECT_NE(
        p.out.find("wrote no frames (--no-frames): steady.exr, steady.png, summary.json in " + (dir_ / "out").string()),
        std::string::npos)
        << p.out;
}

// Flags that were silently ignored: refused (exit 2, nothing written) with the reason.
TEST_F(CliErrors, FlagsThatWouldBeIgnoredAreRefused) {
    const fs::path f = write("scene.json", insideScene());
    const std::string out = (dir_ / "out").string();
    expectRefused({
        {{"render", f.string(), "-o", out, "--preview", "--npy", "--mp4"},
         "error: --npy shapes what the render writes, and --preview stops after preview.exr/png, before any photon: "
         "drop --preview to render, or drop --npy"},
        {{"render", f.string(), "-o", out, "--preview", "--contact-sheet", "4"}, "error: --contact-sheet shapes what"},
        {{"render", f.string(), "-o", out, "--preview", "--checkpoint"}, "error: --checkpoint shapes what"},
        {{"render", f.string(), "-o", out, "--spp", "4"},
         "error: --spp sets the path tracer's camera paths per pixel per pass; --method beams traces one camera ray"},
    });
    // Still accepted: --preview alone or with "no strip", --spp with the path tracer.
    EXPECT_EQ(runTpb({"render", f.string(), "-o", out, "--preview", "--strip", "0", "-q"}, dir_).code, 0);
    EXPECT_EQ(runTpb({"render", f.string(), "-o", out, "--method", "pt", "--spp", "2", "--no-frames", "-q"}, dir_).code,
              0);
}

// `view --resume DIR --passes 80 --after-passes 72` rendered 142 passes: --passes is the total (as
// in `tpb render --resume`), --after-passes the passes rendered before the screenshot; when they
// disagree the command is refused before a window opens (no display is needed to see it).
TEST_F(CliErrors, ViewRefusesPassesThatDisagreeWithAfterPasses) {
    const fs::path f = write("scene.json", insideScene());
    const fs::path out = dir_ / "out", shot = dir_ / "shot.png";
    Proc p = runTpb({"view", f.string(), "--screenshot", shot.string(), "--passes", "3", "--after-passes", "5"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_EQ(fromErrorLine(p.err).rfind("error: --passes 3 and --after-passes 5 disagree: --passes is the total", 0),
              0u)
        << p.err;
    EXPECT_NE(p.err.find("give --after-passes 3"), std::string::npos) << p.err;
    ASSERT_EQ(
        runTpb({"render", f.string(), "-o", out.string(), "--no-frames", "--strip", "0", "--checkpoint", "-q"}, dir_)
            .code,
        0);
    p = runTpb(
        {"view", "--resume", out.string(), "--screenshot", shot.string(), "--passes", "80", "--after-passes", "79"},
        dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("beyond the checkpoint's 2, so the render would go to pass 81; drop --passes, or give "
                         "--after-passes 78"),
              std::string::npos)
        << p.err;
    EXPECT_FALSE(fs::exists(shot));
}

// A megabyte-long unknown key was echoed whole.
TEST_F(CliErrors, LongUnknownKeyIsClippedInTheMessage) {
    const std::string key(1 << 20, 'k');
    const fs::path f = write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 8, \"" + key + "\": 1},"));
    const Proc p = render(f);
    expectUserError(p, f.string() + ":4", "", "unknown key for the film");
    EXPECT_NE(p.err.find("film." + key.substr(0, 60) + "... (1048576 characters): unknown key"), std::string::npos)
        << p.err.substr(0, 400);
    EXPECT_LT(p.err.size(), 1000u);
}

// An OBJ index of 2^40 was reported as "zero value"; an .stl mesh as "no triangles".
TEST_F(CliErrors, ObjIndexOverflowAndUnsupportedMeshFormatsAreNamed) {
    const fs::path f = dir_ / "scene.json";
    const auto meshScene = [&](const std::string& file) {
        return sceneWith(8,
                         "  \"shapes\": [{\"type\": \"mesh\", \"file\": \"" + file + "\", \"material\": \"white\"}],");
    };
    write("big.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1099511627776\n");
    write("scene.json", meshScene("big.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file",
                    "big.obj:4: corrupt OBJ file: face (\"f\" line 4): index 1099511627776 is beyond the largest OBJ "
                    "index tpb reads "
                    "(2147483647); the file has 3 vertices before this line");
    write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 0/1\n");
    write("scene.json", meshScene("zero.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file",
                    "zero.obj:4: corrupt OBJ file: face (\"f\" line 4): index 0; OBJ indices start at 1");
    write("m.stl", "solid m\nendsolid m\n");
    write("scene.json", meshScene("m.stl"));
    expectUserError(
        render(f), f.string() + ":8", "shapes[0].file",
        "m.stl: unsupported mesh format .stl; supported: .obj (Wavefront OBJ), .ply (PLY, ASCII or binary)");
}

// A Mitsuba XML scene named .txt was read as JSON ("unexpected '<'"): XML is told by its content.
TEST_F(CliErrors, XmlSceneUnderAnotherExtensionIsReadAsXml) {
    const fs::path f = write("scene.txt",
                             "\n  <scene version=\"3.0.0\">\n<shape type=\"cube\"/>\n"
                             "<emitter type=\"point\"><point name=\"position\" value=\"0, 0, 3\"/></emitter>\n"
                             "<sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0,0,5\" "
                             "target=\"0,0,0\"/></transform><film type=\"hdrfilm\"><integer name=\"width\" "
                             "value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor></scene>\n");
    const Proc p = runTpb({"info", f.string()}, dir_);
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_NE(p.out.find("8x8"), std::string::npos) << p.out;
}

// The resume diffs printed 0.29999999999999999 for 0.3: the shortest form that reads back the same.
TEST_F(CliErrors, ResumeDiffsPrintTheShortestNumbers) {
    std::string scene = insideScene();
    scene.replace(scene.find("\"power\": 5"), 10, "\"power\": 0.3");
    const fs::path f = write("scene.json", scene);
    const fs::path out = dir_ / "out";
    ASSERT_EQ(runTpb({"render", f.string(), "-o", out.string(), "--no-frames", "--strip", "0", "--checkpoint", "-q",
                      "--alpha", "0.7"},
                     dir_)
                  .code,
              0);
    scene.replace(scene.find("\"power\": 0.3"), 12, "\"power\": 0.1");
    write("scene.json", scene);
    Proc p = runTpb({"render", "--resume", out.string()}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("lights[0].power: the checkpoint has (0.3, 0.3, 0.3), this run has (0.1, 0.1, 0.1)"),
              std::string::npos)
        << p.err;
    EXPECT_EQ(p.err.find("0.2999"), std::string::npos) << p.err;
    scene.replace(scene.find("\"power\": 0.1"), 12, "\"power\": 0.3");
    write("scene.json", scene);
    p = runTpb({"render", "--resume", out.string(), "--alpha", "0.6"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("--alpha 0.6: the checkpoint's render ran with 0.7;"), std::string::npos) << p.err;
}

// No "did you mean" for flags; no --version.
TEST_F(CliErrors, UnknownFlagsAndCommandsSuggestTheClosestAndVersionIsPrinted) {
    const fs::path f = write("scene.json", insideScene());
    Proc p = runTpb({"render", f.string(), "-o", (dir_ / "out").string(), "--pases", "3"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("--pases: did you mean --passes?"), std::string::npos) << p.err;
    p = runTpb({"render", f.string(), "-o", (dir_ / "out").string(), "--estimater=point3d"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("--estimater: did you mean --estimator?"), std::string::npos) << p.err;
    p = runTpb({"rendr", f.string()}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("rendr: did you mean render?"), std::string::npos) << p.err;
    EXPECT_FALSE(fs::exists(dir_ / "out"));
    p = runTpb({"--version"}, dir_);
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(p.out.rfind("tpb ", 0), 0u) << p.out;
    EXPECT_NE(p.out.find(" (commit "), std::string::npos) << p.out;
    EXPECT_NE(p.out.find(std::string(", ") + TPB_BUILD_TYPE + " build)"), std::string::npos) << p.out;
}

namespace {

// insideScene() scaled by `s`: lengths x s, the fog's coefficients / s and the power x s^2 keep
// every pixel's radiance (optical depths and irradiance are scale-free).
std::string scaledInsideScene(double s) {
    const auto n = [](double v) {
        char b[40];
        std::snprintf(b, sizeof b, "%.17g", v);
        return std::string(b);
    };
    return "{\"version\": 1,\n"
           " \"camera\": {\"position\": [0, " +
           n(0.5 * s) + ", " + n(0.9 * s) + "], \"look_at\": [0, " + n(0.5 * s) +
           ", 0], \"fov\": 60, \"resolution\": [16, 16]},\n"
           " \"film\": {\"bins\": 8},\n"
           " \"media\": {\"fog\": {\"sigma_s\": " +
           n(0.5 / s) + ", \"sigma_a\": " + n(0.05 / s) +
           "}}, \"global_medium\": \"fog\",\n"
           " \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": 0.7}},\n"
           " \"shapes\": [{\"type\": \"box\", \"min\": [" +
           n(-s) + ", 0, " + n(-s) + "], \"max\": [" + n(s) + ", " + n(s) + ", " + n(s) +
           "], \"material\": \"white\", \"flip_normals\": true}],\n"
           " \"lights\": [{\"type\": \"point\", \"position\": [0, " +
           n(0.8 * s) + ", 0], \"power\": " + n(5 * s * s) +
           "}],\n"
           " \"render\": {\"photons_per_pass\": 2000, \"passes\": 2, \"seed\": 1}}\n";
}

double steadyLuminanceSum(const fs::path& exr) {
    int w = 0, h = 0;
    std::vector<float> rgb;
    tpb::readExr(exr.string(), w, h, rgb);
    double sum = 0.0;
    for (size_t i = 0; i + 2 < rgb.size(); i += 3) sum += 0.2126 * rgb[i] + 0.7152 * rgb[i + 1] + 0.0722 * rgb[i + 2];
    return sum;
}

}  // namespace

// Scenes below ~1 mm lost energy silently: the ray offsets had a floor of 1e-5 m (a tenth of a
// 0.1 mm box). They scale with the scene now: the same box at 1 m and at 0.1 mm gives the same
// steady image (same seed; up to float rounding of the geometry).
TEST_F(CliErrors, MillimetreSceneKeepsItsEnergy) {
    std::vector<double> sums;
    for (double s : {1.0, 1e-4}) {
        const fs::path f = write("scene.json", scaledInsideScene(s));
        const Proc p = render(f, {"-q"});
        ASSERT_EQ(p.code, 0) << p.err;
        sums.push_back(steadyLuminanceSum(dir_ / "out" / "steady.exr"));
    }
    ASSERT_GT(sums[0], 0.0);
    EXPECT_NEAR(sums[1] / sums[0], 1.0, 0.01) << "1 m: " << sums[0] << ", 0.1 mm: " << sums[1];
}

// One far object inflated the relative radius and the automatic time range without a word;
// --radius 1e-300, --warmup 20 --passes 1 and a laser wider than the scene ran without a warning.
TEST_F(CliErrors, ScaleMistakesAreWarnedAbout) {
    const fs::path plain = write("plain.json", insideScene());
    const Proc quiet = render(plain, {"-q"});
    ASSERT_EQ(quiet.code, 0) << quiet.err;
    EXPECT_EQ(quiet.err.find("warning"), std::string::npos) << quiet.err;

    // (A fixed film: no pilot over the 1 km range; `info` prints the warnings of a render.)
    std::string far = insideScene("{\"bins\": 8, \"start_m\": 0, \"bin_width_m\": 0.5}");
    far.replace(far.find("\"flip_normals\": true}"), 21,
                "\"flip_normals\": true},\n {\"type\": \"sphere\", \"center\": [1000, 0, 0], \"radius\": 1, "
                "\"material\": \"white\"}");
    const fs::path farScene = write("far.json", far);
    Proc p = runTpb({"info", farScene.string()}, dir_);
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_NE(p.err.find("warning: " + farScene.string() +
                         ":7: shapes[1] makes the scene 334x larger than everything "
                         "else (bounding diagonal 1002 m; 3 m without it)"),
              std::string::npos)
        << p.err;

    p = render(plain, {"-q", "--radius", "1e-300"});
    EXPECT_NE(p.err.find("warning: --radius 1e-300 m is 3.3e-301 of the scene's diagonal (3 m)"), std::string::npos)
        << p.err;
    p = render(plain, {"-q", "--warmup", "20", "--passes", "1"});
    EXPECT_NE(p.err.find("warning: --warmup 20 is as long as the render (1 passes)"), std::string::npos) << p.err;

    std::string laser = insideScene();
    laser.replace(laser.find("\"power\": 5}"), 11,
                  "\"power\": 5}, {\"type\": \"laser\", \"position\": [0, 0.5, 0], \"direction\": [1, 0, 0], "
                  "\"radius\": 10, \"power\": 1}");
    const fs::path laserScene = write("laser.json", laser);
    p = render(laserScene, {"-q"});
    EXPECT_NE(p.err.find("lights[1].radius: the laser's beam (radius 10 m) is wider than the whole scene (diagonal "
                         "3 m)"),
              std::string::npos)
        << p.err;
}

// The energy-outside warning advised "range": "auto" when the range was already automatic (a
// white closed box: long surface paths past the pilot's window).
TEST_F(CliErrors, EnergyOutsideAnAutomaticRangeIsNotToldToUseAuto) {
    std::string scene =
        insideScene("{\"bins\": 8}", "{\"photons_per_pass\": 2000, \"passes\": 2, \"seed\": 1, \"max_depth\": 200}");
    scene.replace(scene.find(" \"media\""), scene.find(" \"materials\"") - scene.find(" \"media\""), "");
    scene.replace(scene.find("\"albedo\": 0.7"), 13, "\"albedo\": 0.97");
    const fs::path f = write("scene.json", scene);
    const Proc p = render(f);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_NE(p.err.find("warning: " + f.string() + ":3: film: "), std::string::npos) << p.err;
    EXPECT_NE(p.err.find("the range is already automatic (\"range\": \"auto\" fits it to the arrivals a pilot pass "
                         "measured) and most of the rest arrived after its end: set a fixed range"),
              std::string::npos)
        << p.err;
    EXPECT_EQ(p.err.find("fit the range with"), std::string::npos) << p.err;
}
