// Bad input and faults at the command line: the built `tpb` binary (TPB_BINARY) is run on malformed
// scene files, broken meshes, impossible film sizes and unwritable output folders. Every one must
// end with exit code 2 and a message "file:line: key: what is wrong" (never a crash, a signal or
// "internal error"). Ctrl-C during a render finishes the pass and writes the results atomically.
#include "image_io.h"
#include "scene_loader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace fs = std::filesystem;

namespace {

struct Proc {
    int code = -1;    // exit code, -1 when killed by a signal
    int signal = 0;   // terminating signal, 0 when it exited
    bool timedOut = false;
    std::string out, err;
    double seconds = 0.0;
};

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// Starts TPB_BINARY with `args` (stdout, stderr to files in `dir`), extra "NAME=value" environment.
pid_t spawnTpb(const std::vector<std::string>& args, const fs::path& dir, const std::vector<std::string>& env) {
    std::vector<std::string> argv{TPB_BINARY};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> cargv;
    for (std::string& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    std::vector<std::string> envs;
    for (char** e = environ; *e; ++e) {
        const std::string kv(*e);
        bool overridden = false;
        for (const std::string& x : env) overridden |= kv.compare(0, x.find('=') + 1, x, 0, x.find('=') + 1) == 0;
        if (!overridden) envs.push_back(kv);
    }
    envs.insert(envs.end(), env.begin(), env.end());
    std::vector<char*> cenv;
    for (std::string& e : envs) cenv.push_back(e.data());
    cenv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, (dir / "stdout.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, (dir / "stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, cargv[0], &fa, nullptr, cargv.data(), cenv.data());
    posix_spawn_file_actions_destroy(&fa);
    EXPECT_EQ(rc, 0) << std::strerror(rc);
    return rc == 0 ? pid : -1;
}

Proc waitTpb(pid_t pid, const fs::path& dir, double t0, double timeoutSec) {
    Proc p;
    int status = 0;
    for (;;) {
        const pid_t r = waitpid(pid, &status, WNOHANG);
        if (r == pid) break;
        if (now() - t0 > timeoutSec) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            p.timedOut = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    p.seconds = now() - t0;
    if (WIFEXITED(status)) p.code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) p.signal = WTERMSIG(status);
    p.out = slurp(dir / "stdout.txt");
    p.err = slurp(dir / "stderr.txt");
    return p;
}

Proc runTpb(const std::vector<std::string>& args, const fs::path& dir, const std::vector<std::string>& env = {},
            double timeoutSec = 60.0) {
    const double t0 = now();
    const pid_t pid = spawnTpb(args, dir, env);
    if (pid < 0) return {};
    return waitTpb(pid, dir, t0, timeoutSec);
}

class CliErrors : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("tpb_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
                std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }

    fs::path write(const std::string& name, const std::string& text) {
        const fs::path p = dir_ / name;
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
    // `tpb render <scene>` into dir_/out with the given extra flags.
    Proc render(const fs::path& scene, const std::vector<std::string>& flags = {}, const std::vector<std::string>& env = {}) {
        std::vector<std::string> args{"render", scene.string(), "-o", (dir_ / "out").string(), "--no-frames", "--strip", "0"};
        args.insert(args.end(), flags.begin(), flags.end());
        return runTpb(args, dir_, env);
    }
    // A user error: exit code 2, no signal, one "error: " line naming file:line and key.
    void expectUserError(const Proc& p, const std::string& where, const std::string& key, const std::string& text = "") {
        EXPECT_FALSE(p.timedOut) << where;
        EXPECT_EQ(p.signal, 0) << where << "\n" << p.err;
        EXPECT_EQ(p.code, 2) << where << "\n" << p.err;
        EXPECT_EQ(p.err.rfind("error: ", 0), 0u) << p.err;
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

    fs::path dir_;
};

// A valid scene, one key per line, so that each test can break line N and expect "scene.json:N".
// The camera sits inside the closed box with the light (from outside the box would be black).
const char* kLines[] = {
    "{",                                                                                        // 1
    "  \"version\": 1,",                                                                        // 2
    "  \"camera\": {\"position\": [0, 0.5, 0.9], \"look_at\": [0, 0.5, 0], \"resolution\": [16, 16]},",  // 3
    "  \"film\": {\"bins\": 8},",                                                               // 4
    "  \"media\": {\"fog\": {\"sigma_s\": 0.5, \"sigma_a\": 0.05}},",                           // 5
    "  \"global_medium\": \"fog\",",                                                            // 6
    "  \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": 0.7}},",                  // 7
    "  \"shapes\": [{\"type\": \"box\", \"min\": [-1, 0, -1], \"max\": [1, 1, 1], \"material\": \"white\", "
    "\"flip_normals\": true}],",                                                                // 8
    "  \"lights\": [{\"type\": \"point\", \"position\": [0, 0.8, 0], \"power\": 5}],",           // 9
    "  \"render\": {\"photons_per_pass\": 2000, \"passes\": 2, \"seed\": 1}",                   // 10
    "}",                                                                                        // 11
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
    const struct { int line; const char* text; const char* key; } cases[] = {
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
    const struct { int line; const char* text; const char* key; } cases[] = {
        {5, "  \"media\": {\"fog\": {\"sigma_s\": 1e999}},", ""},    // JSON: does not fit a double
        {5, "  \"media\": {\"fog\": {\"sigma_s\": -1e999}},", ""},
        {5, "  \"media\": {\"fog\": {\"sigma_s\": NaN}},", ""},      // JSON has no NaN literal
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
    for (const std::vector<std::string>& flags :
         {std::vector<std::string>{"--photons", "1000000000000000000"}, {"--photons", "0"}, {"--passes", "x"},
          {"--alpha", "2"}, {"--radius", "0"}, {"--radius", "nan"}, {"--width", "0"}, {"--bins", "-5"},
          {"--threads", "99999999999"}, {"--max-depth", "0"}, {"--time", "-1"}}) {
        const Proc p = render(ok, flags);
        EXPECT_EQ(p.code, 2) << flags[0] << " " << flags[1] << "\n" << p.err;
        EXPECT_EQ(p.signal, 0);
        EXPECT_EQ(p.err.find("internal error"), std::string::npos) << p.err;
    }
}

// The film's memory is checked before it is allocated: the error names the bytes needed.
TEST_F(CliErrors, FilmTooLargeIsRefusedBeforeAllocation) {
    const fs::path f = write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 256},"));
    std::string big = sceneWith(3, "  \"camera\": {\"position\": [0, 0.5, 3], \"look_at\": [0, 0.5, 0], \"resolution\": [256, 256]},");
    write("scene.json", big.replace(big.find("\"bins\": 8"), 9, "\"bins\": 256"));
    tpb::CameraDesc cam;
    cam.width = cam.height = 256;
    const uint64_t need = tpb::filmBytes(cam, 256);
    const Proc p = render(f, {}, {"TPB_MAX_FILM_BYTES=1000000"});
    expectUserError(p, f.string() + ":4", "film.bins", std::to_string(need) + " bytes");
    EXPECT_NE(p.err.find("1000000 bytes"), std::string::npos) << p.err;  // and the limit
    // Without an override: resolution and bins far beyond any machine (exabytes; no overflow).
    write("scene.json", sceneWith(4, "  \"film\": {\"bins\": 2147483647},"));
    big = sceneWith(3, "  \"camera\": {\"position\": [0, 0.5, 3], \"look_at\": [0, 0.5, 0], \"resolution\": [46000, 46000]},");
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

const char kBinaryObj[] = "\x7f" "ELF\x02\x01\x01\0\0\0\xff\xfe\x00\x13garbage\nf 9 9 9\n";

TEST_F(CliErrors, MissingAndCorruptMeshes) {
    const fs::path f = dir_ / "scene.json";
    const auto meshScene = [&](const std::string& file) {
        return sceneWith(8, "  \"shapes\": [{\"type\": \"mesh\", \"file\": \"" + file + "\", \"material\": \"white\"}],");
    };
    write("scene.json", meshScene("nowhere.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file", "not found");
    fs::create_directories(dir_ / "folder.obj");
    write("scene.json", meshScene("folder.obj"));
    expectUserError(render(f), f.string() + ":8", "shapes[0].file", "not found");
    // Corrupt files: the error names the scene's file:line and key, then the OBJ (and its line when
    // tinyobj reports one).
    const struct { const char* name; std::string text; } corrupt[] = {
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
        EXPECT_EQ(q.err.rfind("error: " + out + ": ", 0), 0u) << q.err;  // names the folder first
        EXPECT_NE(q.err.find("-o"), std::string::npos) << q.err;         // and says how to fix it
        EXPECT_EQ(q.err.find("internal error"), std::string::npos) << q.err;
    }
    EXPECT_EQ(slurp(dir_ / "file.txt"), "not a folder");
}

// Ctrl-C (SIGINT) after the first pass: the render finishes the pass in progress, writes
// steady.exr, the frames and summary.json (all through tmp + rename: no *.tmp-* file is left) and
// exits 0. A second Ctrl-C quits at once with 130.
TEST_F(CliErrors, CtrlCFinishesThePassAndWritesTheResults) {
    const fs::path scene = write("scene.json", sceneWith(10, "  \"render\": {\"photons_per_pass\": 60000, \"passes\": 100000}"));
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
    EXPECT_LT(p.seconds - (tInt - t0), 20.0);
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
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    kill(pid2, SIGINT);
    const Proc q = waitTpb(pid2, dir_, t1, 60.0);
    EXPECT_EQ(q.signal, 0);
    EXPECT_EQ(q.code, 130) << q.err;
}

namespace {

// Can this process mount a tmpfs in a private mount namespace (unshare -m, the user mapped to root),
// which vanishes with the namespace? Root in a normal container can; some sandboxes cannot.
bool canMountPrivateTmpfs() {
    return std::system("unshare -m -r sh -c 'd=$(mktemp -d) && mount -t tmpfs -o size=64k tmpfs \"$d\" && "
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
    const std::string cmd = "unshare -m -r sh -c '" + script + "' sh '" + (dir_ / "mnt").string() + "' '" + TPB_BINARY +
                            "' '" + scene.string() + "' '" + dir_.string() + "' >'" + (dir_ / "stdout.txt").string() +
                            "' 2>'" + (dir_ / "stderr.txt").string() + "'";
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

// A pass that fails on the render thread (here: an albedo-1 box with max_depth 1e8 outgrows the
// memory limit, TPB_MAX_FILM_BYTES) ends the render with exit 2 and the reason, not a crash; the
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
