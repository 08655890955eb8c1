// Viewer (`tpb view`) tests: the binary runs headless under xvfb-run (Mesa llvmpipe) on a tiny
// scene with --screenshot, and the tests check the PNG it saves against the film (read back from
// the EXRs that --export writes through the Export buttons' code path), against an independent
// `tpb render` of the same scene, seed, passes and threads, and across the time-axis and emission
// toggles. Skipped only when xvfb-run is missing or cannot start an X server.
#include "film/tone_map.h"
#include "io/image_io.h"
#include "integrators/render_settings.h"

#include "support/checkpoint_payload.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>
#pragma GCC diagnostic pop

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// A small Cornell-like box filled with fog, lit by a point light pulse: 64x64, 32 bins.
const char* kScene = R"({
  "version": 1,
  "camera": {"position": [0, 1, 3.9], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov": 38, "resolution": [64, 64]},
  "film": {"bins": 32, "range": "auto"},
  "media": {"fog": {"sigma_s": 0.3, "sigma_a": 0.02, "g": 0.3}},
  "global_medium": "fog",
  "materials": {
    "white": {"type": "diffuse", "albedo": 0.75},
    "red":   {"type": "diffuse", "albedo": [0.63, 0.065, 0.05]},
    "green": {"type": "diffuse", "albedo": [0.14, 0.45, 0.091]}
  },
  "shapes": [
    {"name": "floor",   "type": "quad", "corner": [-1, 0, -1], "edge_u": [0, 0, 2], "edge_v": [2, 0, 0], "material": "white"},
    {"name": "ceiling", "type": "quad", "corner": [-1, 2, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "white"},
    {"name": "back",    "type": "quad", "corner": [-1, 0, -1], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "white"},
    {"name": "left",    "type": "quad", "corner": [-1, 0, -1], "edge_u": [0, 2, 0], "edge_v": [0, 0, 2], "material": "red"},
    {"name": "right",   "type": "quad", "corner": [1, 0, -1],  "edge_u": [0, 0, 2], "edge_v": [0, 2, 0], "material": "green"}
  ],
  "lights": [{"type": "point", "position": [0, 1.6, 0], "power": 50, "emit_time_ns": 0}],
  "render": {"photons_per_pass": 2000, "radius_relative": 0.01, "surface_radius_relative": 0.02, "alpha": 0.7, "passes": 2}
})";

constexpr int kFilm = 64, kBins = 32;
constexpr int kWinW = 1280, kWinH = 800;
const std::string kRenderArgs = " --passes 2 --seed 7 --threads 2";
const std::string kXvfb = "env LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s '-screen 0 1280x900x24' ";

struct Proc {
    int code = -1;
    std::string out, err;
};

std::string slurp(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

std::string q(const fs::path& p) {
    std::string s = "'";  // appended, not "'" + string: GCC 12's -Wrestrict misfires on that insert
    s += p.string();
    s += '\'';
    return s;
}

Proc runShell(const std::string& cmd, const fs::path& logBase) {
    const fs::path out = logBase.string() + ".out", err = logBase.string() + ".err";
    const int st = std::system((cmd + " >" + q(out) + " 2>" + q(err)).c_str());
    Proc r;
    r.code = (st != -1 && WIFEXITED(st)) ? WEXITSTATUS(st) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

struct Image8 {
    int w = 0, h = 0;
    std::vector<unsigned char> px;  // RGB
    const unsigned char* at(int x, int y) const { return &px[(static_cast<size_t>(y) * w + x) * 3]; }
};

Image8 readPng(const fs::path& p) {
    Image8 img;
    int n = 0;
    unsigned char* data = stbi_load(p.string().c_str(), &img.w, &img.h, &n, 3);
    if (!data) return Image8{};
    img.px.assign(data, data + static_cast<size_t>(img.w) * img.h * 3);
    stbi_image_free(data);
    return img;
}

struct Exr {
    int w = 0, h = 0;
    std::vector<float> rgb;
    float lum(int x, int y) const {
        const float* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
        return 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
    }
};

Exr readExrFile(const fs::path& p) {
    Exr e;
    tpb::readExr(p.string(), e.w, e.h, e.rgb);
    return e;
}

// The viewer's machine-readable report line.
struct Area {
    bool ok = false;
    double x = 0, y = 0, w = 0, h = 0, zoom = 0, ev = 0;
    int bin = -1, steady = -1;
};

Area parseArea(const std::string& out) {
    Area a;
    const size_t pos = out.find("image_area ");
    if (pos == std::string::npos) return a;
    a.ok = std::sscanf(out.c_str() + pos, "image_area %lf %lf %lf %lf zoom %lf exposure_ev %lf bin %d steady %d", &a.x,
                       &a.y, &a.w, &a.h, &a.zoom, &a.ev, &a.bin, &a.steady) == 8;
    return a;
}

// The viewer's controls as reported with the screenshot: "<tag> x y w h Section/label" lines
// (tag "control": the last frame, "control_first": the first frame, drawn while pass 1 rendered).
struct Rect {
    double x = 0, y = 0, w = 0, h = 0;
    bool operator==(const Rect&) const = default;
};

std::map<std::string, Rect> parseControls(const std::string& out, const std::string& tag) {
    std::map<std::string, Rect> m;
    std::istringstream in(out);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind(tag + " ", 0) != 0) continue;
        Rect r;
        int used = 0;
        if (std::sscanf(line.c_str() + tag.size(), " %lf %lf %lf %lf %n", &r.x, &r.y, &r.w, &r.h, &used) == 4)
            m[line.substr(tag.size() + static_cast<size_t>(used))] = r;
    }
    return m;
}

// What the CPU tone map (core/film/tone_map.h, used by every exported picture) makes of a film
// pixel: the screen (shaders/display.frag on the GPU) must show the same bytes within rounding.
std::array<int, 3> cpuToneMap(const float* rgb, double ev, bool falseColor) {
    tpb::ToneMap tm;
    tm.exposureEv = static_cast<float>(ev);
    tm.falseColor = falseColor;
    unsigned char out[3];
    tpb::toneMapPixel(rgb, tm, out);
    return {out[0], out[1], out[2]};
}

// Screenshot pixel at the centre of film pixel (x, y).
const unsigned char* cell(const Image8& shot, const Area& a, int x, int y) {
    const int sx = static_cast<int>(std::floor(a.x + (x + 0.5) * a.zoom));
    const int sy = static_cast<int>(std::floor(a.y + (y + 0.5) * a.zoom));
    return shot.at(std::clamp(sx, 0, shot.w - 1), std::clamp(sy, 0, shot.h - 1));
}

// How many film pixels the screenshot shows as the CPU tone map says (each channel within 3 of 255:
// 8-bit rounding and the GPU's float), and how many distinct colours the CPU map gives them.
struct ToneMatch {
    int close = 0, total = 0, distinct = 0;
};

ToneMatch matchToneMap(const Image8& shot, const Area& a, const Exr& film, bool falseColor) {
    ToneMatch m;
    std::set<std::array<int, 3>> colours;
    for (int y = 0; y < kFilm; ++y)
        for (int x = 0; x < kFilm; ++x) {
            if (std::abs(x - kFilm / 2) <= 1 && std::abs(y - kFilm / 2) <= 1) continue;  // selection marker
            const unsigned char* p = cell(shot, a, x, y);
            const std::array<int, 3> want =
                cpuToneMap(&film.rgb[(static_cast<size_t>(y) * kFilm + x) * 3], a.ev, falseColor);
            colours.insert(want);
            bool ok = true;
            for (int c = 0; c < 3; ++c) ok &= std::abs(static_cast<int>(p[c]) - want[c]) <= 3;
            m.close += ok;
            ++m.total;
        }
    m.distinct = static_cast<int>(colours.size());
    return m;
}

// Max relative difference between two images of the same size (scaled by the larger magnitude,
// with a floor of 1e-6 of the image's peak for pixels that are ~0 in both).
double maxRelDiff(const Exr& a, const Exr& b) {
    float peak = 0.0f;
    for (float v : b.rgb) peak = std::max(peak, std::fabs(v));
    double worst = 0.0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        const double d = std::fabs(static_cast<double>(a.rgb[i]) - b.rgb[i]);
        const double s = std::max({std::fabs(static_cast<double>(a.rgb[i])), std::fabs(static_cast<double>(b.rgb[i])),
                                   1e-6 * static_cast<double>(peak), 1e-30});
        worst = std::max(worst, d / s);
    }
    return worst;
}

// How much of the image area is black (no light shown) or clipped to white (blown out).
// An exposure fitted to the picture also uses the range: its brightest pixels come near white.
struct Tones {
    double black = 0.0, white = 0.0;  // fractions of the film's pixels
    int bright = 0;                   // 98th percentile of the pixels' largest 8-bit channel
};

Tones tones(const Image8& shot, const Area& a) {
    int black = 0, white = 0;
    std::vector<int> peaks;
    for (int y = 0; y < kFilm; ++y)
        for (int x = 0; x < kFilm; ++x) {
            if (std::abs(x - kFilm / 2) <= 1 && std::abs(y - kFilm / 2) <= 1) continue;  // selection marker
            const unsigned char* p = cell(shot, a, x, y);
            black += std::max({p[0], p[1], p[2]}) <= 8;
            white += std::min({p[0], p[1], p[2]}) >= 250;
            peaks.push_back(std::max({p[0], p[1], p[2]}));
        }
    const size_t k = peaks.size() * 98 / 100;
    std::nth_element(peaks.begin(), peaks.begin() + static_cast<std::ptrdiff_t>(k), peaks.end());
    const double n = static_cast<double>(peaks.size());
    return {black / n, white / n, peaks[k]};
}

std::string frameName(int bin) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "frame_%05d.exr", bin);
    return buf;
}

std::string viewerFrameName(int bin, const std::string& tag) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "frame_%05d_%s.exr", bin, tag.c_str());
    return buf;
}

fs::path makeTempDir(const std::string& what) {
    const fs::path d = fs::temp_directory_path() / ("tpb_test_viewer_" + what + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// One viewer run per mode (real/delta, unwarped, continuous), each with --export, shared by the tests.
struct Mode {
    std::string name, flags, tag;
};
const std::vector<Mode> kModes = {{"real_delta", "", "real_delta"},
                                  {"unwarped", " --unwarp", "unwarped_delta"},
                                  {"continuous", " --continuous", "real_continuous"}};

// Runs a command under xvfb-run, again if the X server failed to start (two `xvfb-run -a` started
// at once, e.g. under `ctest -j`, can pick the same display number).
// The command's own exit code is written to a file: xvfb-run exits 5 when it cannot remove its
// temporary folder after the command ended (seen once under load in CI), which says nothing about
// the command.
Proc runXvfb(const std::string& cmd, const fs::path& logBase) {
    const fs::path script = logBase.string() + ".xvfb.sh", code = logBase.string() + ".code";
    std::ofstream(script) << cmd << "\necho $? > " << q(code) << "\n";
    Proc r;
    for (int attempt = 0; attempt < 4; ++attempt) {
        fs::remove(code);
        r = runShell(kXvfb + "sh " + q(script), logBase);
        if (r.err.find("Xvfb failed to start") == std::string::npos) break;
        ::usleep(300000u * (attempt + 1) + 1000u * static_cast<unsigned>(::getpid() % 300));
    }
    if (const std::string c = slurp(code); !c.empty()) r.code = std::stoi(c);
    return r;
}

// Each test process (CTest runs each test on its own) renders only what its test needs, once.
class ViewerTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) {
            skip_ = "xvfb-run is not installed (apt-get install xvfb xauth): cannot run the viewer headless";
            return;
        }
        dir_ = makeTempDir("xvfb");
        std::ofstream(dir_ / "scene.json") << kScene;
        const Proc probe = runXvfb("true", dir_ / "probe");
        if (probe.code != 0) skip_ = "xvfb-run cannot start an X server: " + probe.err;
    }
    static void TearDownTestSuite() {
        if (!dir_.empty() && !std::getenv("TPB_KEEP_TEST_FILES")) fs::remove_all(dir_);
    }
    void SetUp() override {
        if (!skip_.empty()) GTEST_SKIP() << skip_;
    }

    // Independent reference render (no GL involved) in a mode; its folder.
    static fs::path reference(const Mode& m) {
        const fs::path out = dir_ / ("ref_" + m.name);
        if (!refs_.count(m.name)) {
            // With the viewer's warm-up (render_settings.h kViewerWarmupPasses): the same passes.
            refs_[m.name] =
                runShell(std::string(TPB_BINARY) + " render " + q(dir_ / "scene.json") + kRenderArgs + m.flags +
                             " --warmup " + std::to_string(tpb::kViewerWarmupPasses) + " -q -o " + q(out),
                         out);
        }
        EXPECT_EQ(refs_[m.name].code, 0) << "tpb render failed: " << refs_[m.name].err;
        return out;
    }

    // The bin shown: much energy, some bins after the first light reaches the camera (so that
    // continuous emission, the running sum, differs from the delta pulse response).
    static int bin() {
        if (bin_ >= 0) return bin_;
        const std::vector<double> energy = binEnergy();
        const double peak = *std::max_element(energy.begin(), energy.end());
        int first = 0;
        while (first < kBins - 1 && energy[first] <= 0.01 * peak) ++first;
        bin_ = static_cast<int>(std::max_element(energy.begin() + std::min(first + 2, kBins - 1), energy.end()) -
                                energy.begin());
        return bin_;
    }

    // The viewer with --screenshot view_<mode>.png and --export view_<mode>/.
    static const Proc& view(const Mode& m) {
        if (!views_.count(m.name)) {
            const fs::path base = dir_ / ("view_" + m.name);
            views_[m.name] =
                runXvfb(std::string(TPB_BINARY) + " view " + q(dir_ / "scene.json") + kRenderArgs + m.flags +
                            " --bin " + std::to_string(bin()) + " --after-passes 2 --window-size 1280 800" +
                            " --screenshot " + q(base.string() + ".png") + " --export " + q(base),
                        base);
        }
        return views_[m.name];
    }
    static Image8 shot(const Mode& m) { return readPng(dir_ / ("view_" + m.name + ".png")); }

    // A viewer run of its own: `tpb view scene.json <args> --screenshot <name>.png`.
    static Proc viewRun(const std::string& name, const std::string& args) {
        const fs::path base = dir_ / name;
        return runXvfb(std::string(TPB_BINARY) + " view " + q(dir_ / "scene.json") + " " + args +
                           " --window-size 1280 800 --screenshot " + q(base.string() + ".png"),
                       base);
    }
    static Image8 shotOf(const std::string& name) { return readPng(dir_ / (name + ".png")); }

    // Energy (luminance summed over the image) of each bin of the independent real/delta render.
    static std::vector<double> binEnergy() {
        const fs::path ref = reference(kModes[0]);
        std::vector<double> energy(kBins, 0.0);
        for (int k = 0; k < kBins; ++k) {
            const Exr f = readExrFile(ref / "frames" / frameName(k));
            for (int y = 0; y < f.h; ++y)
                for (int x = 0; x < f.w; ++x) energy[k] += f.lum(x, y);
        }
        return energy;
    }

    static inline std::string skip_;
    static inline fs::path dir_;
    static inline int bin_ = -1;
    static inline std::map<std::string, Proc> refs_, views_;
};

// The viewer exits 0 after N passes with a PNG of the whole window, and its image area shows the
// frame: where the independent render's frame has energy the screenshot is not black, and every
// film pixel is shown as the CPU tone map (exposure + sRGB) makes it, within 8-bit rounding, so the display
// chain (upload, shader, FBO, ImGui) neither moves, flips nor distorts pixels.
TEST_F(ViewerTest, ScreenshotShowsTheRenderedFrame) {
    const Mode& m = kModes[0];
    const Proc& r = view(m);
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const Image8 img = shot(m);
    ASSERT_EQ(img.w, kWinW);
    ASSERT_EQ(img.h, kWinH);
    const Area a = parseArea(r.out);
    ASSERT_TRUE(a.ok) << r.out;
    EXPECT_EQ(a.bin, bin());
    EXPECT_EQ(a.steady, 0);
    ASSERT_GE(a.zoom, 1.0);
    EXPECT_NEAR(a.w, kFilm * a.zoom, 1e-3);
    EXPECT_NEAR(a.h, kFilm * a.zoom, 1e-3);
    ASSERT_GE(a.x, 0.0);
    ASSERT_GE(a.y, 0.0);
    ASSERT_LE(a.x + a.w, kWinW);
    ASSERT_LE(a.y + a.h, kWinH);

    const Exr ref = readExrFile(reference(m) / "frames" / frameName(bin()));
    ASSERT_EQ(ref.w, kFilm);
    float peak = 0.0f;
    for (int y = 0; y < kFilm; ++y)
        for (int x = 0; x < kFilm; ++x) peak = std::max(peak, ref.lum(x, y));
    ASSERT_GT(peak, 0.0f) << "the reference frame is black: bad test scene";

    int lit = 0, litBlack = 0;
    for (int y = 0; y < kFilm; ++y)
        for (int x = 0; x < kFilm; ++x) {
            if (std::abs(x - kFilm / 2) <= 1 && std::abs(y - kFilm / 2) <= 1) continue;  // selection marker
            const unsigned char* p = cell(img, a, x, y);
            if (ref.lum(x, y) > 0.02f * peak) {
                ++lit;
                if (std::max({p[0], p[1], p[2]}) <= 8) ++litBlack;
            }
        }
    EXPECT_GT(lit, kFilm * kFilm / 10) << "too few lit pixels to judge";
    EXPECT_EQ(litBlack, 0) << "pixels with energy shown black";
    const ToneMatch t = matchToneMap(img, a, ref, false);
    EXPECT_GE(t.close, t.total * 99 / 100) << t.close << " of " << t.total << " pixels match the CPU tone map (sRGB)";
}

// The screen in false colour shows what the exports' CPU false-colour map makes of the film (the
// shader and core/film/tone_map.cpp are two codes of one mapping). Not vacuous: the frame's pixels
// span several colours of the ramp (a one-colour picture could match a wrong ramp by chance).
TEST_F(ViewerTest, FalseColourScreenMatchesTheCpuToneMap) {
    const Mode& m = kModes[0];
    const Proc r = viewRun("false_colour", kRenderArgs + m.flags + " --bin " + std::to_string(bin()) +
                                               " --after-passes 2 --click 'Display/False colour'");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const Area a = parseArea(r.out);
    ASSERT_TRUE(a.ok) << r.out;
    ASSERT_EQ(a.bin, bin());
    const Exr ref = readExrFile(reference(m) / "frames" / frameName(bin()));
    ASSERT_EQ(ref.w, kFilm);
    const ToneMatch t = matchToneMap(shotOf("false_colour"), a, ref, true);
    EXPECT_GE(t.distinct, 20) << "too few distinct false colours to judge";
    EXPECT_GE(t.close, t.total * 99 / 100) << t.close << " of " << t.total << " pixels match the CPU false-colour map";
}

// --export goes through the Export buttons' code path; the EXRs must hold exactly the film that an
// independent `tpb render` (same seed, passes, threads) produces, in each axis/emission mode.
TEST_F(ViewerTest, ExportEqualsIndependentRender) {
    for (const Mode& m : kModes) {
        SCOPED_TRACE(m.name);
        const Proc& r = view(m);
        ASSERT_EQ(r.code, 0) << r.out << r.err;
        const fs::path exp = dir_ / ("view_" + m.name);
        const fs::path frame = exp / viewerFrameName(bin(), m.tag);
        ASSERT_TRUE(fs::exists(frame)) << r.out;
        EXPECT_NE(r.out.find("exported: " + frame.string()), std::string::npos) << r.out;
        const fs::path ref = reference(m);
        const Exr got = readExrFile(frame);
        const Exr want = readExrFile(ref / "frames" / frameName(bin()));
        ASSERT_EQ(got.w, want.w);
        ASSERT_EQ(got.h, want.h);
        EXPECT_LE(maxRelDiff(got, want), 1e-6);

        const Exr steady = readExrFile(exp / "steady.exr");
        const Exr steadyRef = readExrFile(ref / "steady.exr");
        ASSERT_EQ(steady.rgb.size(), steadyRef.rgb.size());
        EXPECT_LE(maxRelDiff(steady, steadyRef), 1e-6);
    }
}

// `tpb view --method pt` runs the path tracer in the viewer's Driver: its export of the shown bin
// and its steady image equal `tpb render --method pt` with the same seed and passes (the same
// integrator through the same Driver), and the picture is not black. Would fail if the viewer
// ignored --method (the beams' film differs) or the path tracer's passes differed between the two.
TEST_F(ViewerTest, PathTracerRunsLiveInTheViewer) {
    const fs::path out = dir_ / "ref_pt";
    const Proc ref = runShell(
        std::string(TPB_BINARY) + " render " + q(dir_ / "scene.json") + kRenderArgs + " --method pt -q -o " + q(out),
        out);
    ASSERT_EQ(ref.code, 0) << ref.err;
    const fs::path base = dir_ / "view_pt";
    const Proc r = runXvfb(std::string(TPB_BINARY) + " view " + q(dir_ / "scene.json") + kRenderArgs + " --method pt" +
                               " --bin " + std::to_string(bin()) + " --after-passes 2 --window-size 1280 800" +
                               " --screenshot " + q(base.string() + ".png") + " --export " + q(base),
                           base);
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const Exr got = readExrFile(base / viewerFrameName(bin(), "real_delta"));
    const Exr want = readExrFile(out / "frames" / frameName(bin()));
    ASSERT_EQ(got.w, want.w);
    EXPECT_LE(maxRelDiff(got, want), 1e-6);
    EXPECT_LE(maxRelDiff(readExrFile(base / "steady.exr"), readExrFile(out / "steady.exr")), 1e-6);
    double sum = 0.0;
    for (float v : got.rgb) sum += v;
    EXPECT_GT(sum, 0.0) << "the path tracer's frame is black";
    const Exr beams = readExrFile(reference(kModes[0]) / "frames" / frameName(bin()));
    EXPECT_GT(maxRelDiff(got, beams), 1e-3) << "the viewer showed the photon beams' film, not the path tracer's";
}

// The unwarping and emission toggles change the picture (same film, another view of it).
TEST_F(ViewerTest, TogglesChangeThePicture) {
    const Proc& r0 = view(kModes[0]);
    ASSERT_EQ(r0.code, 0) << r0.err;
    const Area a = parseArea(r0.out);
    ASSERT_TRUE(a.ok);
    const Image8 base = shot(kModes[0]);
    ASSERT_EQ(base.w, kWinW);
    for (size_t i = 1; i < kModes.size(); ++i) {
        SCOPED_TRACE(kModes[i].name);
        const Proc& r = view(kModes[i]);
        ASSERT_EQ(r.code, 0) << r.err;
        const Area b = parseArea(r.out);
        ASSERT_TRUE(b.ok);
        EXPECT_DOUBLE_EQ(b.x, a.x);  // same layout, so the areas compare pixel for pixel
        EXPECT_DOUBLE_EQ(b.zoom, a.zoom);
        const Image8 img = shot(kModes[i]);
        ASSERT_EQ(img.w, base.w);
        double diff = 0.0;
        int changed = 0;
        for (int y = 0; y < kFilm; ++y)
            for (int x = 0; x < kFilm; ++x) {
                const unsigned char* p = cell(base, a, x, y);
                const unsigned char* o = cell(img, b, x, y);
                int d = 0;
                for (int c = 0; c < 3; ++c) d += std::abs(static_cast<int>(p[c]) - static_cast<int>(o[c]));
                diff += d / 3.0;
                changed += d > 6;
            }
        EXPECT_GT(diff / (kFilm * kFilm), 5.0) << "mean 8-bit difference of the image area";
        EXPECT_GT(changed, kFilm * kFilm / 4);
    }
}

// Closing while a pass is in progress (Ctrl-C, same path as the close button) stops the driver,
// tears down GL/ImGui/GLFW and exits 0 without waiting for the render to finish.
TEST_F(ViewerTest, ClosingDuringRenderExitsZero) {
    const fs::path script = dir_ / "close.sh";
    // Ctrl-C once the window is up (the viewer says so; a background job of `sh` ignores SIGINT
    // until the viewer installs its handler, so a signal during the scene load would be lost).
    const fs::path log = dir_ / "close.log";
    std::ofstream(script) << std::string(TPB_BINARY) << " view " << q(dir_ / "scene.json")
                          << " --passes 0 --photons 20000 --threads 2 > " << q(log) << " 2>&1 &\n"
                          << "pid=$!\ni=0\nwhile ! grep -q 'window open' " << q(log)
                          << " && [ $i -lt 500 ]; do sleep 0.1; i=$((i+1)); done\n"
                          << "sleep 1\nkill -INT $pid\nwait $pid\necho \"viewer_exit=$?\"\ncat " << q(log) << "\n";
    const Proc r = runXvfb("timeout 60 sh " + q(script), dir_ / "close");
    EXPECT_NE(r.out.find("viewer_exit=0"), std::string::npos) << r.out << r.err;
}

// The "Steady state" export button writes steady.exr. It shared its label, and so its ImGui ID, with
// the "Steady state" view radio button drawn above it, which took the click: nothing was written.
// The click goes through ImGui's hit test and IDs like a user's (--click).
TEST_F(ViewerTest, SteadyStateExportButtonWritesSteadyExr) {
    const fs::path out = dir_ / "steady_button";
    const Proc r = viewRun("steady_button", kRenderArgs + " --after-passes 2 --export-folder " + q(out) +
                                                " --click 'Export/Steady state'");
    EXPECT_NE(r.out.find("click: Export/Steady state"), std::string::npos) << r.out;
    ASSERT_TRUE(fs::exists(out / "steady.exr")) << r.out << r.err;
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("exported: " + (out / "steady.exr").string()), std::string::npos) << r.out;
    const Exr steady = readExrFile(out / "steady.exr");
    const Exr steadyRef = readExrFile(reference(kModes[0]) / "steady.exr");
    ASSERT_EQ(steady.rgb.size(), steadyRef.rgb.size());
    EXPECT_LE(maxRelDiff(steady, steadyRef), 1e-6);
    // That button only: no frame, streak or profile (and the folder's lock file, .tpb.lock).
    int files = 0;
    for (const auto& e : fs::directory_iterator(out))
        files += e.is_regular_file() && e.path().filename() != ".tpb.lock";
    EXPECT_EQ(files, 1);
}

// Audit of the ImGui IDs: the viewer checks every control it draws against the others of the frame
// and reports a clash on stderr (exit 1 in screenshot mode). With every optional control shown -
// render settings open, false colour on, playback running (its button then reads "Pause", as the
// render's Pause button does) - no two controls share an ID.
TEST_F(ViewerTest, NoTwoControlsShareAnImGuiId) {
    const Proc r = viewRun("ids", kRenderArgs +
                                      " --after-passes 1 --bin 3 --click 'Render settings' --click "
                                      "'Display/False colour' --click 'Time/Play'");
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_EQ(r.err.find("share an ImGui ID"), std::string::npos) << r.err;
    const std::map<std::string, Rect> controls = parseControls(r.out, "control");
    for (const char* name : {"Time/Pause", "Progress/Pause", "View/Steady state", "Export/Steady state",
                             "Render settings/alpha", "Display/decades"})
        EXPECT_TRUE(controls.count(name)) << name << " not drawn:\n" << r.out;
}

// The first frame shows light: with --frame and without --bin the viewer shows the bin of peak
// energy (not bin 0, before any light arrives) with the exposure fitted to it, in both emission modes.
TEST_F(ViewerTest, FirstPictureShowsLightInBothEmissionModes) {
    const std::vector<double> energy = binEnergy();
    const double peak = *std::max_element(energy.begin(), energy.end());
    for (const Mode& m : {kModes[0], kModes[2]}) {
        SCOPED_TRACE(m.name);
        const Proc r = viewRun("first_" + m.name, kRenderArgs + m.flags + " --frame --after-passes 1");
        ASSERT_EQ(r.code, 0) << r.out << r.err;
        const Area a = parseArea(r.out);
        ASSERT_TRUE(a.ok) << r.out;
        ASSERT_GE(a.bin, 0);
        ASSERT_LT(a.bin, kBins);
        EXPECT_GE(energy[a.bin], 0.5 * peak) << "bin " << a.bin << " holds little light";
        const Tones t = tones(shotOf("first_" + m.name), a);
        std::printf("%s: bin %d, %.3g EV: black %.3f, white %.3f, bright %d\n", m.name.c_str(), a.bin, a.ev, t.black,
                    t.white, t.bright);
        EXPECT_LT(t.black, 0.5) << "black: " << t.black << ", exposure " << a.ev << " EV, bin " << a.bin;
        EXPECT_LT(t.white, 0.05) << "blown out: " << t.white << ", exposure " << a.ev << " EV, bin " << a.bin;
        EXPECT_GE(t.bright, 180) << "too dark: exposure " << a.ev << " EV, bin " << a.bin;
    }
}

// Switching delta <-> continuous fits the exposure again (a running sum is orders of magnitude
// brighter than the pulse response: continuous was shown blown out to white, delta then black).
TEST_F(ViewerTest, SwitchingEmissionModeRefitsTheExposure) {
    for (const Mode& m : {kModes[0], kModes[2]}) {
        SCOPED_TRACE("starting in " + m.name);
        const std::string name = "switch_" + m.name;
        const Proc r = viewRun(name, kRenderArgs + m.flags + " --after-passes 1 --bin " + std::to_string(bin()) +
                                         " --click 'View/Continuous emission'");
        ASSERT_EQ(r.code, 0) << r.out << r.err;
        const Area a = parseArea(r.out);
        ASSERT_TRUE(a.ok) << r.out;
        EXPECT_NE(r.out.find(m.flags.empty() ? "mode continuous" : "mode delta"), std::string::npos) << r.out;
        const Tones t = tones(shotOf(name), a);
        std::printf("%s, then switched: %.3g EV: black %.3f, white %.3f, bright %d\n", m.name.c_str(), a.ev, t.black,
                    t.white, t.bright);
        EXPECT_LT(t.black, 0.5) << "black: " << t.black << ", exposure " << a.ev << " EV";
        EXPECT_LT(t.white, 0.05) << "blown out: " << t.white << ", exposure " << a.ev << " EV";
        EXPECT_GE(t.bright, 180) << "too dark: exposure " << a.ev << " EV";
    }
}

// Auto exposure is fitted to the tiles already finished, during the first pass, not after it (a
// first pass can take many seconds). The first pass here gathers for a few seconds (more photons);
// the viewer reports each fit with the passes completed at that moment.
TEST_F(ViewerTest, AutoExposureFitsTheTilesFinishedDuringTheFirstPass) {
    // No warm-up: the test needs a first pass long enough to see its tiles arrive.
    const Proc r = viewRun("midpass", "--seed 7 --threads 2 --photons 40000 --warmup 0 --passes 1 --after-passes 1");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    std::istringstream in(r.out);
    std::string line;
    int during = 0, final = 0;
    while (std::getline(in, line)) {
        double ev = 0;
        size_t lit = 0;
        unsigned long long passes = 0;
        int complete = 0, fin = 0, bin = 0, steady = 0;
        if (std::sscanf(line.c_str(),
                        "auto_exposure ev %lf lit_pixels %zu passes %llu complete %d final %d bin %d steady %d", &ev,
                        &lit, &passes, &complete, &fin, &bin, &steady) != 7)
            continue;
        EXPECT_GT(lit, 0u);
        during += passes == 0;
        final += fin;
    }
    EXPECT_GT(during, 0) << "no exposure fitted before the first pass ended:\n" << r.out;
    EXPECT_EQ(final, 1) << r.out;
}

// The controls keep their place when the render finishes (and when the first pass completes): a
// click aimed while it renders lands on the same control after. (The Pause row went away at the
// end and the statistics rows came in after pass 1, moving the Export buttons by rows.)
TEST_F(ViewerTest, ControlsKeepTheirPlaceWhenTheRenderFinishes) {
    // No warm-up and many photons: the first frame is drawn while pass 1 renders.
    const Proc r = viewRun("layout", "--seed 7 --threads 2 --photons 40000 --warmup 0 --passes 2 --after-passes 2");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("layout_first passes 0 running 1"), std::string::npos) << r.out;
    const std::map<std::string, Rect> first = parseControls(r.out, "control_first");
    const std::map<std::string, Rect> last = parseControls(r.out, "control");
    int exportButtons = 0;
    for (const auto& [name, rect] : last) {
        if (name.rfind("Export", 0) == 0) ++exportButtons;
        if (name.rfind("Messages/", 0) == 0) continue;  // below every control, free to grow
        const auto f = first.find(name);
        ASSERT_NE(f, first.end()) << name << " was not there while rendering";
        EXPECT_EQ(f->second, rect) << name << " moved from y " << f->second.y << " to y " << rect.y;
    }
    EXPECT_GE(exportButtons, 8);  // the section, folder, 6 buttons, Cancel
}

// A long status line wraps inside the controls panel (it was cut off at the panel's edge).
TEST_F(ViewerTest, LongStatusLinesWrap) {
    const fs::path out = dir_ / ("a_folder_with_a_long_name_so_that_the_status_line_is_longer_than_the_panel_"
                                 "is_wide_" +
                                 std::string(40, 'x'));
    const Proc r = viewRun("status", kRenderArgs + " --after-passes 1 --export-folder " + q(out) +
                                         " --click 'Export/Window screenshot (F12)'");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_TRUE(fs::exists(out / "window_001.png")) << r.out;
    const std::map<std::string, Rect> controls = parseControls(r.out, "control");
    ASSERT_TRUE(controls.count("Messages/status")) << r.out;
    const Rect st = controls.at("Messages/status");
    double left = 0, right = 0;
    const size_t pos = r.out.find("messages_area ");
    ASSERT_NE(pos, std::string::npos);
    ASSERT_EQ(std::sscanf(r.out.c_str() + pos, "messages_area %lf %lf", &left, &right), 2);
    EXPECT_LE(st.x + st.w, right + 1.0) << "the status line runs past the panel";
    EXPECT_GE(st.h, 3 * 13.0) << "a " << ("saved " + out.string()).size() << "-character status line on " << st.h / 13.0
                              << " lines";
}

// Issue 33 item 11: the first picture of the default scene (the one tools/run opens) shows the
// scene - most of its pixels lit - after the warm-up's passes (3, 7/8 of one full pass's photons:
// the first ~0.15 s of a desktop's render), not a few grey discs of one time bin (5 % lit: what the
// peak bin showed, and what --frame still shows). 128x128 keeps the film small; the photons' discs
// cover the same share of the walls at any resolution. And the image is fitted to its panel.
TEST_F(ViewerTest, FirstPictureOfTheDefaultSceneLightsMostOfIt) {
    const std::string scene = q(fs::path(TPB_SOURCE_DIR) / "scenes" / "cornell_medium.json");
    const auto litShare = [](const Image8& shot, const Area& a, int film) {
        int lit = 0;
        for (int y = 0; y < film; ++y)
            for (int x = 0; x < film; ++x) {
                const int sx = static_cast<int>(std::floor(a.x + (x + 0.5) * a.zoom));
                const int sy = static_cast<int>(std::floor(a.y + (y + 0.5) * a.zoom));
                const unsigned char* p = shot.at(std::clamp(sx, 0, shot.w - 1), std::clamp(sy, 0, shot.h - 1));
                lit += std::max({p[0], p[1], p[2]}) > 8;
            }
        return static_cast<double>(lit) / (film * film);
    };
    const std::string args = " --width 128 --height 128 --seed 3 --threads 2 --after-passes " +
                             std::to_string(tpb::kViewerWarmupPasses) + " --window-size 1280 800 --screenshot ";
    const fs::path shot = dir_ / "default_first.png";
    const Proc r = runXvfb(std::string(TPB_BINARY) + " view " + scene + args + q(shot), dir_ / "default_first");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const Area a = parseArea(r.out);
    ASSERT_TRUE(a.ok) << r.out;
    const double lit = litShare(readPng(shot), a, 128);
    std::printf("default scene after %d passes: %.3f of the pixels lit (steady %d)\n", tpb::kViewerWarmupPasses, lit,
                a.steady);
    EXPECT_GT(lit, 0.8) << r.out;

    // Fitted: the image fills the panel's height or width (the old integer zoom left a 256-pixel
    // image at 1:1 in an 880 x 430 panel).
    double px = 0, py = 0, pw = 0, ph = 0;
    int fit = 0;
    const size_t at = r.out.find("image_panel ");
    ASSERT_NE(at, std::string::npos) << r.out;
    ASSERT_EQ(std::sscanf(r.out.c_str() + at, "image_panel %lf %lf %lf %lf fit %d", &px, &py, &pw, &ph, &fit), 5);
    EXPECT_EQ(fit, 1);
    EXPECT_TRUE(a.h >= ph - 2.0 || a.w >= pw - 2.0 * 12.0 - 2.0)
        << "image " << a.w << " x " << a.h << " in a panel of " << pw << " x " << ph;
    EXPECT_GE(a.x, px);
    EXPECT_LE(a.x + a.w, px + pw + 1e-3);

    // The frame of the peak bin, as the viewer opened before (and opens with --frame): discs.
    const fs::path frame = dir_ / "default_frame.png";
    const Proc f =
        runXvfb(std::string(TPB_BINARY) + " view " + scene + " --frame" + args + q(frame), dir_ / "default_frame");
    ASSERT_EQ(f.code, 0) << f.out << f.err;
    const Area fa = parseArea(f.out);
    ASSERT_TRUE(fa.ok) << f.out;
    const double frameLit = litShare(readPng(frame), fa, 128);
    std::printf("its peak bin %d: %.3f lit\n", fa.bin, frameLit);
    EXPECT_LT(frameLit, 0.5) << "the peak bin is a picture already: this test no longer shows what the default avoids";
}

namespace {

// The words after `tag` on its report line ("ticks streak_ns 0 5 10" -> {"0", "5", "10"}).
std::vector<std::string> reportWords(const std::string& out, const std::string& tag) {
    std::vector<std::string> words;
    const size_t at = out.find("\n" + tag + " ");
    if (at == std::string::npos) return words;
    std::istringstream line(out.substr(at + tag.size() + 2, out.find('\n', at + 1) - at - tag.size() - 2));
    for (std::string w; line >> w;) words.push_back(w);
    return words;
}

}  // namespace

// Issue 33 item 12: the streak and the profile have time ticks in ns (the streak also in m), the
// profile a log scale, false colour a colour bar whose labels are the film luminance of each
// decade below the white point (2^-EV), as drawn.
TEST_F(ViewerTest, TimeTicksLogScaleAndColourBarAreDrawn) {
    const Proc r = viewRun("instrument", kRenderArgs + " --after-passes 2 --false-color --bin " +
                                             std::to_string(bin()) + " --click 'Streak and pixel profile/log scale'");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const Area a = parseArea(r.out);
    ASSERT_TRUE(a.ok) << r.out;
    for (const char* axis : {"ticks streak_ns", "ticks profile_ns"}) {
        const std::vector<std::string> t = reportWords(r.out, axis);
        EXPECT_GE(t.size(), 3u) << axis << "\n" << r.out;
        double last = -1.0;
        for (const std::string& w : t) {  // increasing numbers
            const double v = std::stod(w);
            EXPECT_GT(v, last) << axis;
            last = v;
        }
    }
    EXPECT_NE(r.out.find("\nprofile_log 1"), std::string::npos) << r.out;
    const std::vector<std::string> bar = reportWords(r.out, "colour_bar");
    ASSERT_EQ(bar.size(), 5u) << r.out;  // white, then 4 decades below it (the default decades)
    const double white = std::exp2(-a.ev);
    EXPECT_NEAR(std::stod(bar[0]), white, 0.05 * white) << r.out;
    EXPECT_NEAR(std::stod(bar[4]), 1e-4 * white, 0.05e-4 * white) << r.out;
}

// Item 12: a settings change that would discard the accumulation asks first (a popup); "Keep the
// accumulation" keeps the passes, "Restart" restarts. Sections are folded so that the Render
// settings' "auto radius" button is in view of an 800-pixel window.
TEST_F(ViewerTest, SettingsThatDiscardTheAccumulationAskFirst) {
    const std::string fold = kRenderArgs +
                             " --after-passes 2 --bin 3 --click Time --click View --click Display "
                             "--click 'Render settings' --click 'Render settings/auto radius'";
    const Proc asked = viewRun("ask_restart", fold);
    ASSERT_EQ(asked.code, 0) << asked.out << asked.err;
    const std::map<std::string, Rect> controls = parseControls(asked.out, "control");
    EXPECT_TRUE(controls.count("Restart the accumulation?/Restart")) << asked.out;
    EXPECT_TRUE(controls.count("Restart the accumulation?/Keep the accumulation")) << asked.out;
    EXPECT_EQ(asked.out.find("accumulation restarted"), std::string::npos) << asked.out;

    const Proc kept = viewRun("keep_restart", fold + " --click 'Restart the accumulation?/Keep the accumulation'");
    ASSERT_EQ(kept.code, 0) << kept.out << kept.err;
    EXPECT_EQ(kept.out.find("accumulation restarted"), std::string::npos) << kept.out;
    EXPECT_FALSE(parseControls(kept.out, "control").count("Restart the accumulation?/Restart")) << kept.out;

    const Proc restarted = viewRun("do_restart", fold + " --click 'Restart the accumulation?/Restart'");
    ASSERT_EQ(restarted.code, 0) << restarted.out << restarted.err;
    EXPECT_NE(restarted.out.find("accumulation restarted"), std::string::npos) << restarted.out;
}

// Item 12: Q (or Esc) quits at once, but asks first while an export runs (the MP4 here).
TEST_F(ViewerTest, KeyboardQuitAsksWhileAnExportRuns) {
    const fs::path out = dir_ / "quit_export";
    const Proc asked = viewRun("quit_export", kRenderArgs + " --after-passes 1 --bin 3 --export-folder " + q(out) +
                                                  " --click Export/MP4 --click key:Q");
    EXPECT_EQ(asked.code, 0) << asked.out << asked.err;  // still open: the screenshot was taken
    EXPECT_NE(asked.out.find("quit: asked first, an export is running"), std::string::npos) << asked.out;
    const Proc quit = viewRun("quit_now", kRenderArgs + " --after-passes 1 --bin 3 --click key:Q");
    EXPECT_NE(quit.out.find("quit: by the keyboard"), std::string::npos) << quit.out;
    EXPECT_NE(quit.err.find("closed before the screenshot"), std::string::npos) << quit.err;
}

// Item 12: the noise indicator (the spread between the batches of passes, instrument.h) is known
// after two batches and falls as the passes accumulate (about as 1/sqrt of the photons).
TEST_F(ViewerTest, NoiseIndicatorFallsAsPassesAccumulate) {
    const auto noise = [](const Proc& r) {
        const std::vector<std::string> w = reportWords(r.out, "noise");
        return w.size() >= 2 ? std::stod(w[1]) : -2.0;
    };
    const Proc few = viewRun("noise_few", "--seed 7 --threads 2 --steady --after-passes 4");
    const Proc many = viewRun("noise_many", "--seed 7 --threads 2 --steady --after-passes 16");
    ASSERT_EQ(few.code, 0) << few.err;
    ASSERT_EQ(many.code, 0) << many.err;
    std::printf("steady image noise after 4 passes %.4f, after 16 %.4f\n", noise(few), noise(many));
    EXPECT_GT(noise(few), 0.0) << few.out;
    EXPECT_GT(noise(many), 0.0) << many.out;
    EXPECT_LT(noise(many), 0.7 * noise(few));
}

// Without a display: a clear message and exit code 2 (needs no X server).
TEST(ViewerCli, NoDisplayExitsWithCode2) {
    const fs::path dir = makeTempDir("nodisplay");
    std::ofstream(dir / "scene.json") << kScene;
    const Proc r = runShell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(TPB_BINARY) + " view " +
                                q(dir / "scene.json") + " --screenshot " + q(dir / "x.png"),
                            dir / "run");
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("cannot open a window"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("xvfb-run"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "x.png"));

    // Flag mistakes are user errors too.
    const Proc bad1 =
        runShell(std::string(TPB_BINARY) + " view " + q(dir / "scene.json") + " --export out", dir / "bad1");
    EXPECT_EQ(bad1.code, 2) << bad1.err;
    const Proc bad2 =
        runShell(std::string(TPB_BINARY) + " view " + q(dir / "scene.json") + " --bin 3 --time 2", dir / "bad2");
    EXPECT_EQ(bad2.code, 2) << bad2.err;
    fs::remove_all(dir);
}

// --bin and --time outside the film are refused alike (--bin 999 was silently clamped while --time
// 1e9 warned), naming the flag and the film's range, before a window opens (so with no display).
TEST(ViewerCli, BinOrTimeOutsideTheFilmIsRefusedWithTheRange) {
    const fs::path dir = makeTempDir("range");
    std::ofstream(dir / "scene.json") << kScene;
    struct Case {
        std::string flags, says;
    };
    const std::vector<Case> cases = {{"--bin 999", "--bin 999 is outside the film: its bins are 0 to 31"},
                                     {"--bin -1", "--bin -1 is outside the film: its bins are 0 to 31"},
                                     {"--time 1e9", "--time 1e+09 ns is outside the film (0 to "},
                                     {"--time -2", "--time -2 ns is outside the film (0 to "},
                                     {"--time nan", "--time must be a time in ns within the film: 0 to "},
                                     {"--exposure nan", "--exposure: must be a number in [-40, 40] (EV"},
                                     {"--unwarp --real-time", "excludes"},
                                     {"--continuous --delta", "excludes"}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.flags);
        const Proc r = runShell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(TPB_BINARY) + " view " +
                                    q(dir / "scene.json") + " " + c.flags + " --screenshot " + q(dir / "x.png"),
                                dir / "run");
        EXPECT_EQ(r.code, 2) << r.out << r.err;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("cannot open a window"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "x.png"));
    }
    fs::remove_all(dir);
}

// Every `view` flag is checked like `tpb render`'s, while parsing: a bad value is refused with exit
// code 2 and a short message naming the flag and its range, before any window (so with no
// display). --after-passes printed a 309-digit range (CLI::PositiveNumber) and --time-budget took
// NaN, negatives and inf (NaN was then blamed on --time, a flag view does not have).
TEST(ViewerCli, BadFlagValuesAreRefusedNamingTheFlag) {
    const fs::path dir = makeTempDir("flags");
    std::ofstream(dir / "scene.json") << kScene;
    struct Case {
        std::string flags, says;
    };
    const std::vector<Case> cases = {
        {"--after-passes 0", "--after-passes: must be an integer >= 1 (passes rendered before the screenshot); got 0"},
        {"--after-passes -3", "--after-passes: must be an integer >= 1"},
        {"--after-passes 1e400", "--after-passes: must be an integer >= 1"},
        {"--time-budget nan", "--time-budget: must be a finite number >= 0 (seconds; 0 = no time budget); got nan"},
        {"--time-budget -1", "--time-budget: must be a finite number >= 0"},
        {"--time-budget inf", "--time-budget: must be a finite number >= 0"},
        {"--exposure 1e300", "--exposure: must be a number in [-40, 40]"},
        {"--window-size 10 800", "--window-size: must be an integer in [64, 16384]"}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.flags);
        const Proc r = runShell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(TPB_BINARY) + " view " +
                                    q(dir / "scene.json") + " --screenshot " + q(dir / "x.png") + " " + c.flags,
                                dir / "run");
        EXPECT_EQ(r.code, 2) << r.out << r.err;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
        EXPECT_LT(r.err.size(), 300u) << "a short message: " << r.err;
        EXPECT_EQ(r.err.find("cannot open a window"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir / "x.png"));
    }
    fs::remove_all(dir);
}

}  // namespace

// The viewer warms up by default (render_settings.h kViewerWarmupPasses) and reports its timeline:
// when light was first on screen and when each pass ended (seconds from the start, increasing).
// --warmup 0 turns the warm-up off. (No timing is asserted: the machines are shared.)
TEST_F(ViewerTest, TimelineReportsFirstLightAndTheWarmup) {
    const auto timeline = [](const std::string& out, int& warmup, std::vector<double>& ends) {
        const size_t at = out.find("timeline first_light_s ");
        if (at == std::string::npos) return -2.0;
        double first = -2.0;
        int used = 0;
        if (std::sscanf(out.c_str() + at, "timeline first_light_s %lf warmup %d pass_end_s%n", &first, &warmup, &used) <
            2)
            return -2.0;
        std::istringstream rest(out.substr(at + static_cast<size_t>(used), out.find('\n', at) - at - used));
        for (double t; rest >> t;) ends.push_back(t);
        return first;
    };
    const Proc& r = view(kModes[0]);
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    int warmup = -1;
    std::vector<double> ends;
    const double first = timeline(r.out, warmup, ends);
    EXPECT_GE(first, 0.0) << r.out;  // the film has light: it was shown
    EXPECT_EQ(warmup, tpb::kViewerWarmupPasses);
    ASSERT_EQ(ends.size(), 2u) << r.out;
    EXPECT_GT(ends[0], 0.0);
    EXPECT_GT(ends[1], ends[0]);
    const Proc off = viewRun("nowarmup", kRenderArgs + " --warmup 0 --after-passes 1");
    ASSERT_EQ(off.code, 0) << off.out << off.err;
    ends.clear();
    timeline(off.out, warmup, ends);
    EXPECT_EQ(warmup, 0) << off.out;
}

using tpb::test::checkpointPayload;

// Issue 16: "Save checkpoint" writes the viewer's film between passes; `tpb render --resume` goes on
// from it to a film bit-identical to one `tpb render` of all the passes (with the viewer's warm-up),
// and `tpb view --resume` opens it and refines it further.
TEST_F(ViewerTest, SavedCheckpointResumesToTheFilmOfOneUninterruptedRender) {
    const fs::path out = dir_ / "ckpt";
    const Proc r = viewRun(
        "ckpt", kRenderArgs + " --after-passes 2 --export-folder " + q(out) + " --click 'Progress/Save checkpoint'");
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    ASSERT_TRUE(fs::exists(out / "checkpoint.tpbck")) << r.out << r.err;
    EXPECT_NE(r.out.find("checkpoint of 2 passes written to "), std::string::npos) << r.out;

    const Proc resumed =
        runShell(std::string(TPB_BINARY) + " render --resume " + q(out) + " --passes 4 --no-frames --strip 0 -q",
                 out / "resume");
    ASSERT_EQ(resumed.code, 0) << resumed.err;
    const fs::path whole = dir_ / "ckpt_whole";
    const Proc w = runShell(std::string(TPB_BINARY) + " render " + q(dir_ / "scene.json") +
                                " --seed 7 --threads 2 --warmup " + std::to_string(tpb::kViewerWarmupPasses) +
                                " --passes 4 --checkpoint --no-frames --strip 0 -q -o " + q(whole),
                            whole);
    ASSERT_EQ(w.code, 0) << w.err;
    const std::string a = checkpointPayload(out / "checkpoint.tpbck");
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == checkpointPayload(whole / "checkpoint.tpbck"))
        << "resumed film differs from the uninterrupted one";

    const Proc v = runXvfb(std::string(TPB_BINARY) + " view --resume " + q(out) +
                               " --after-passes 1 --window-size 1280 800 --screenshot " + q(dir_ / "ckpt_view.png"),
                           dir_ / "ckpt_view");
    EXPECT_EQ(v.code, 0) << v.out << v.err;
    EXPECT_NE(v.out.find("resumed 4 passes from the checkpoint"), std::string::npos) << v.out;
    EXPECT_NE(v.out.find("after 5 passes"), std::string::npos) << v.out;
}

// Photon counts in the viewer (film/photon_counting.h): started with --counts, the Volume export
// holds grey whole counts under a "_counts" name; the View section's "counts" box turns them off
// at once, and the export is the noise-free film again.
TEST_F(ViewerTest, CountsRowTogglesTheCountedFilmAndItsExports) {
    const auto npy = [](const fs::path& file) {
        std::ifstream f(file, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        const size_t header =
            bytes.size() < 10
                ? 0
                : 10 + (static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8));
        std::vector<float> v(bytes.size() > header ? (bytes.size() - header) / 4 : 0);
        if (!v.empty()) std::memcpy(v.data(), bytes.data() + header, v.size() * 4);
        return v;
    };
    const std::string counts = " --counts photons=300,dark_hz=1e6,seed=2 --after-passes 1 --export-folder ";
    const fs::path on = dir_ / "counts_on", off = dir_ / "counts_off";
    const Proc a = viewRun("counts_on", kRenderArgs + counts + q(on) + " --click 'Export/Volume (.npy)'");
    ASSERT_EQ(a.code, 0) << a.out << a.err;
    const std::vector<float> c = npy(on / "volume_real_delta_counts" / "transient.npy");
    ASSERT_EQ(c.size(), static_cast<size_t>(kFilm) * kFilm * kBins * 3) << a.out << a.err;
    double total = 0.0;
    for (size_t i = 0; i < c.size(); i += 3) {
        ASSERT_EQ(c[i], std::floor(c[i]));
        ASSERT_EQ(c[i], c[i + 1]);
        total += c[i];
    }
    EXPECT_GT(total, 0.5 * 300 * kFilm * kFilm) << "about 300 counts per mean pixel, most inside the film";
    const Proc b =
        viewRun("counts_off", kRenderArgs + counts + q(off) + " --click View/counts --click 'Export/Volume (.npy)'");
    ASSERT_EQ(b.code, 0) << b.out << b.err;
    EXPECT_FALSE(fs::exists(off / "volume_real_delta_counts"));
    const std::vector<float> f = npy(off / "volume_real_delta" / "transient.npy");
    ASSERT_EQ(f.size(), c.size()) << b.out << b.err;
    size_t fractional = 0;
    for (float v : f) fractional += v != std::floor(v);
    EXPECT_GT(fractional, f.size() / 100) << "the noise-free film is radiance, not counts";
}

// The Export section's Volume (.npy), MP4 and Contact sheet buttons (issue 16), clicked like a
// user in camera-unwarped time: the volume holds the independent render's frames value for value
// (transient.npy's bin k = frames/frame_k.exr), its side file names the axis and the passes, the
// contact sheet is a PNG, and the MP4 has one frame per bin (when ffmpeg/ffprobe are installed).
TEST_F(ViewerTest, ExportButtonsWriteTheVolumeTheMp4AndTheContactSheet) {
    const bool ffmpeg = std::system("command -v ffmpeg >/dev/null 2>&1 && command -v ffprobe >/dev/null 2>&1") == 0;
    const fs::path out = dir_ / "issue16_buttons";
    const Proc r = viewRun("issue16_buttons", kRenderArgs + " --unwarp --after-passes 2 --export-folder " + q(out) +
                                                  " --click 'Export/Volume (.npy)' --click 'Export/Contact sheet'" +
                                                  (ffmpeg ? " --click 'Export/MP4'" : ""));
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const fs::path vol = out / "volume_unwarped_delta";
    ASSERT_TRUE(fs::exists(vol / "transient.npy")) << r.out << r.err;
    for (const char* f : {"transient.json", "steady.npy", "before.npy", "after.npy"})
        EXPECT_TRUE(fs::exists(vol / f)) << f;
    std::ifstream f(vol / "transient.npy", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 10u);
    const size_t header = 10 + (static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8));
    ASSERT_EQ(bytes.size(), header + static_cast<size_t>(kFilm) * kFilm * kBins * 3 * 4);
    EXPECT_NE(bytes.find("'shape': (64, 64, 32, 3)"), std::string::npos);
    const fs::path ref = reference(kModes[1]);  // the independent render, unwarped delta
    double worst = 0.0;
    for (int k : {bin(), kBins / 2}) {
        const Exr frame = readExrFile(ref / "frames" / frameName(k));
        for (int y = 0; y < kFilm; ++y)
            for (int x = 0; x < kFilm; ++x)
                for (int c = 0; c < 3; ++c) {
                    float v = 0.0f;
                    std::memcpy(
                        &v, bytes.data() + header + ((static_cast<size_t>(y) * kFilm + x) * kBins + k) * 12 + c * 4, 4);
                    const float want = frame.rgb[(static_cast<size_t>(y) * kFilm + x) * 3 + c];
                    worst = std::max(worst, std::abs(double(v) - want) / std::max(1e-20, std::abs(double(want))));
                }
    }
    EXPECT_LE(worst, 1e-6);
    std::ifstream js(vol / "transient.json");
    const std::string side((std::istreambuf_iterator<char>(js)), std::istreambuf_iterator<char>());
    EXPECT_NE(side.find("\"axis\": \"unwarped\""), std::string::npos) << side;
    EXPECT_NE(side.find("\"passes\": 2"), std::string::npos) << side;
    const Image8 sheet = readPng(out / "contact_sheet_unwarped_delta.png");
    EXPECT_GT(sheet.w, 4 * kFilm);  // 16 frames: 4 x 4
    EXPECT_GT(sheet.h, 4 * kFilm);
    if (ffmpeg) {
        const fs::path mp4 = out / "transient_unwarped_delta.mp4";
        ASSERT_TRUE(fs::exists(mp4)) << r.out << r.err;
        const std::string cmd =
            "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames "
            "-of csv=p=0 " +
            q(mp4) + " > " + q(out / "probe.txt");
        ASSERT_EQ(std::system(cmd.c_str()), 0);
        std::ifstream p(out / "probe.txt");
        int frames = 0;
        p >> frames;
        EXPECT_EQ(frames, kBins);
    }
}

// Issue 16: the View section's pulse shape and sensor response (--pulse / --sensor set them at
// start) change what is read from the film, not the film: the exported frame equals `tpb render`'s
// with the same flags (a convolution of the same sums), in delta and continuous emission, and it
// differs from the delta-pulse frame.
TEST_F(ViewerTest, PulseShapeAndSensorResponseAreAppliedToTheShownAndExportedFrames) {
    for (const Mode& m : {kModes[0], kModes[2]}) {
        SCOPED_TRACE(m.name);
        const std::string resp = " --pulse gaussian:0.4 --sensor exp:0.3";
        const fs::path out = dir_ / ("pulse_" + m.name);
        const Proc r = viewRun("pulse_" + m.name, kRenderArgs + m.flags + resp + " --bin " + std::to_string(bin()) +
                                                      " --after-passes 2 --export " + q(out));
        ASSERT_EQ(r.code, 0) << r.out << r.err;
        const fs::path frame = out / viewerFrameName(bin(), m.tag + "_pulse-gaussian0.4_sensor-exp0.3");
        ASSERT_TRUE(fs::exists(frame)) << r.out;
        const fs::path ref = dir_ / ("pulse_ref_" + m.name);
        const Proc w =
            runShell(std::string(TPB_BINARY) + " render " + q(dir_ / "scene.json") + kRenderArgs + m.flags + resp +
                         " --warmup " + std::to_string(tpb::kViewerWarmupPasses) + " --strip 0 -q -o " + q(ref),
                     ref);
        ASSERT_EQ(w.code, 0) << w.err;
        const Exr got = readExrFile(frame), want = readExrFile(ref / "frames" / frameName(bin()));
        ASSERT_EQ(got.rgb.size(), want.rgb.size());
        EXPECT_LE(maxRelDiff(got, want), 1e-6);
        const Exr sharp = readExrFile(reference(m) / "frames" / frameName(bin()));
        EXPECT_GT(maxRelDiff(got, sharp), 0.05) << "the pulse shape changed nothing";
        const nlohmann::json summary = nlohmann::json::parse(slurp(ref / "summary.json"));
        EXPECT_EQ(summary["frames"]["time_response"], "gaussian pulse, FWHM 0.4 ns; exponential sensor decay, 0.3 ns");
    }
}

// Issue 33, item 7: closing the viewer during "All frames" cancelled the export and left part of
// the frames with no note. The export in progress is finished now (the window closes first): Ctrl-C
// once the export has started, and every frame is there, with no INCOMPLETE.txt. 4096 small bins
// keep the export busy for much longer than the frame loop takes to see the signal. Item 2: a
// closed terminal (SIGHUP) closes the window the same way, where it killed the viewer (exit 129
// after the export is finished).
TEST_F(ViewerTest, ClosingDuringAllFramesFinishesTheExport) {
    for (const std::string sig : {"INT", "HUP"}) {
        SCOPED_TRACE(sig);
        const std::string name = "close_frames_" + sig;
        const fs::path out = dir_ / name, log = dir_ / (name + ".log"), script = dir_ / (name + ".sh");
        std::ofstream(script) << std::string(TPB_BINARY) << " view " << q(dir_ / "scene.json") << kRenderArgs
                              << " --width 16 --height 16 --bins 4096 --after-passes 1 --window-size 1280 800"
                              << " --screenshot " << q(dir_ / (name + ".png")) << " --export-folder " << q(out)
                              << " --click 'Export/All frames' > " << q(log) << " 2>&1 &\n"
                              << "pid=$!\ni=0\nwhile [ ! -d " << q(out / "frames_real_delta")
                              << " ] && [ $i -lt 6000 ]; do sleep 0.01; i=$((i+1)); done\n"
                              << "kill -" << sig << " $pid\nwait $pid\necho viewer_exit=$?\ncat " << q(log) << "\n";
        const Proc r = runXvfb("timeout 120 sh " + q(script), dir_ / name);
        int frames = 0;
        std::error_code ec;
        for (const auto& e : fs::directory_iterator(out / "frames_real_delta", ec))
            frames += e.path().filename().string().rfind("frame_", 0) == 0;
        EXPECT_EQ(frames, 4096) << r.out << r.err;
        EXPECT_FALSE(fs::exists(out / "frames_real_delta" / "INCOMPLETE.txt"));
        EXPECT_NE(r.out.find("closing: finishing the export (all frames "), std::string::npos) << r.out;
        EXPECT_NE(r.out.find("exported: "), std::string::npos) << r.out;
        // 128 + the signal: the screenshot the script asked for was not taken. (A viewer killed by
        // the signal, as before, gives the same code through the shell: the frames tell them apart.)
        EXPECT_NE(r.out.find(sig == "HUP" ? "viewer_exit=129" : "viewer_exit=130"), std::string::npos) << r.out;
    }
}

// Item 7: an MP4 cut short by closing the viewer was dropped without a word. A second Ctrl-C while
// the viewer finishes the export cancels it, and says what was not written. The fake ffmpeg on PATH
// reads nothing for 3 s (the frames fill its pipe), so the export is still running.
TEST_F(ViewerTest, SecondCtrlCWhileClosingCancelsTheMp4AndSaysSo) {
    const fs::path out = dir_ / "close_mp4", log = dir_ / "close_mp4.log", script = dir_ / "close_mp4.sh";
    const fs::path bin = dir_ / "fakebin", started = dir_ / "close_mp4.started";
    fs::create_directories(bin);
    std::ofstream(bin / "ffmpeg") << "#!/bin/sh\ntouch " << q(started) << "\nsleep 3\ncat >/dev/null\nexit 1\n";
    fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
    std::ofstream(script) << "PATH=" << q(bin) << ":$PATH " << std::string(TPB_BINARY) << " view "
                          << q(dir_ / "scene.json") << kRenderArgs << " --after-passes 1 --window-size 1280 800"
                          << " --screenshot " << q(dir_ / "close_mp4.png") << " --export-folder " << q(out)
                          << " --click 'Export/MP4' > " << q(log) << " 2>&1 &\n"
                          << "pid=$!\ni=0\nwhile [ ! -e " << q(started) << " ] && [ $i -lt 6000 ]; do sleep 0.01; "
                          << "i=$((i+1)); done\nkill -INT $pid\ni=0\nwhile ! grep -q 'closing: finishing' " << q(log)
                          << " && [ $i -lt 500 ]; do sleep 0.01; i=$((i+1)); done\n"
                          << "kill -INT $pid\nwait $pid\ncat " << q(log) << "\n";
    const Proc r = runXvfb("timeout 120 sh " + q(script), dir_ / "close_mp4");
    EXPECT_NE(r.out.find("closing: finishing the export (MP4 "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("export failed: export cancelled; not written: transient_real_delta.mp4"), std::string::npos)
        << r.out;
    EXPECT_FALSE(fs::exists(out / "transient_real_delta.mp4"));
}

// Item 7: the viewer's exports and "Save checkpoint" ignored the lock `tpb render` holds on its
// output folder, and "Save checkpoint" replaced another render's checkpoint. Both are refused now,
// with the holder or the checkpoint named, and nothing is written (screenshot mode: exit 2).
TEST_F(ViewerTest, ExportsAndSaveCheckpointRespectTheFolderLockAndOtherCheckpoints) {
    // A render holds the folder.
    const fs::path out = dir_ / "locked", log = dir_ / "locked_render.log";
    const std::string render = std::string(TPB_BINARY) + " render " + q(dir_ / "scene.json") +
                               " --width 16 --height 16 --passes 100000 --threads 1 --no-frames -o " + q(out);
    const fs::path script = dir_ / "locked.sh";
    std::ofstream(script) << render << " > " << q(log) << " 2>&1 &\n"
                          << "rpid=$!\ni=0\nwhile ! grep -q 'pass 1:' " << q(log)
                          << " && [ $i -lt 3000 ]; do sleep 0.02; i=$((i+1)); done\necho render_pid=$rpid\n"
                          << std::string(TPB_BINARY) << " view " << q(dir_ / "scene.json") << kRenderArgs
                          << " --after-passes 1 --window-size 1280 800 --screenshot " << q(dir_ / "locked.png")
                          << " --export-folder " << q(out)
                          << " --click 'Export/Steady state' --click 'Progress/Save checkpoint'\n"
                          << "echo viewer_exit=$?\nkill -KILL $rpid\nwait $rpid\n";
    Proc r = runXvfb("timeout 120 sh " + q(script), dir_ / "locked");
    EXPECT_NE(r.out.find("viewer_exit=2"), std::string::npos) << r.out << r.err;
    const size_t at = r.out.find("render_pid=");
    ASSERT_NE(at, std::string::npos) << r.out;
    const std::string pid = r.out.substr(at + 11, r.out.find('\n', at) - at - 11);
    const std::string held = out.string() + ": another tpb run (tpb render, pid " + pid +
                             ") is writing into this folder; two runs in one folder would mix their files: wait for "
                             "it to end, or choose another folder in the Export section";
    EXPECT_NE(r.err.find("export failed: " + held), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("error: checkpoint not written: " + held), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "steady.exr"));
    EXPECT_FALSE(fs::exists(out / "checkpoint.tpbck"));

    // Another render's checkpoint in the export folder (no render runs now): kept, not replaced.
    const fs::path other = dir_ / "other_ckpt";
    const Proc w =
        runShell(std::string(TPB_BINARY) + " render " + q(dir_ / "scene.json") +
                     " --width 16 --height 16 --passes 1 --checkpoint --no-frames --strip 0 -q -o " + q(other),
                 dir_ / "other_ckpt");
    ASSERT_EQ(w.code, 0) << w.err;
    const std::string before = slurp(other / "checkpoint.tpbck");
    r = viewRun("other_ckpt_view",
                kRenderArgs + " --after-passes 1 --export-folder " + q(other) + " --click 'Progress/Save checkpoint'");
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("error: checkpoint not written: " + (other / "checkpoint.tpbck").string() +
                         ": holds the checkpoint of another render (1 passes of "),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(slurp(other / "checkpoint.tpbck") == before) << "the other render's checkpoint was replaced";
}

namespace {

// The hidden target of scenes/nlos_confocal.json as the scene file gives it: every quad but the
// relay wall (z = 0), all at one depth; their extent in x and y.
struct HiddenTarget {
    double depthM = -1.0, xLo = 1e9, xHi = -1e9, yLo = 1e9, yHi = -1e9;
};

HiddenTarget hiddenTarget(const fs::path& scene) {
    const nlohmann::json j = nlohmann::json::parse(slurp(scene));
    HiddenTarget t;
    for (const auto& s : j["shapes"]) {
        if (s["name"] == "relay") continue;
        const auto c = s["corner"].get<std::vector<double>>(), u = s["edge_u"].get<std::vector<double>>(),
                   v = s["edge_v"].get<std::vector<double>>();
        EXPECT_EQ(u[2], 0.0);
        EXPECT_EQ(v[2], 0.0);
        t.depthM = c[2];
        t.xLo = std::min({t.xLo, c[0], c[0] + u[0] + v[0]});
        t.xHi = std::max({t.xHi, c[0], c[0] + u[0] + v[0]});
        t.yLo = std::min({t.yLo, c[1], c[1] + u[1] + v[1]});
        t.yHi = std::max({t.yHi, c[1], c[1] + u[1] + v[1]});
    }
    return t;
}

}  // namespace

// The Back-projection view on the shipped confocal scan (2 full passes, no warm-up): the report's peak voxel is at
// the T's depth within one bin width of round-trip time plus a depth step, in front of the T within
// one voxel pitch, and the panel's front image is drawn (not black).
TEST(ViewerBackprojection, PeakIsAtTheHiddenTarget) {
    if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is missing";
    const fs::path dir = makeTempDir("backprojection");
    const fs::path scene = fs::path(TPB_SOURCE_DIR) / "scenes" / "nlos_confocal.json";
    const Proc r =
        runXvfb(std::string(TPB_BINARY) + " view " + q(scene) +
                    " --passes 2 --warmup 0 --seed 1 --after-passes 2 --window-size 1280 800 --screenshot " +
                    q(dir / "bp.png") + " --click Back-projection --click 'Back-projection/Show back-projection'",
                dir / "bp");
    if (r.err.find("Xvfb failed to start") != std::string::npos) GTEST_SKIP() << "no X server: " << r.err;
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const size_t at = r.out.find("backprojection passes ");
    ASSERT_NE(at, std::string::npos) << r.out;
    int passes = 0, nx = 0, ny = 0, nz = 0, i = 0, j = 0, k = 0;
    long long pairs = 0;
    double ms = 0, depth = 0, x = 0, y = 0, z = 0, fx = 0, fy = 0, fw = 0, fh = 0;
    ASSERT_EQ(std::sscanf(r.out.c_str() + at,
                          "backprojection passes %d voxels %d %d %d pairs %lld ms %lf peak_voxel %d %d %d depth_m %lf "
                          "position_m %lf %lf %lf front_area %lf %lf %lf %lf",
                          &passes, &nx, &ny, &nz, &pairs, &ms, &i, &j, &k, &depth, &x, &y, &z, &fx, &fy, &fw, &fh),
              17)
        << r.out;
    EXPECT_EQ(passes, 2);
    EXPECT_EQ(nx, 16);
    EXPECT_EQ(ny, 16);
    EXPECT_EQ(pairs, 256);
    const nlohmann::json sc = nlohmann::json::parse(slurp(scene));
    const double binM = sc["film"]["bin_width_m"].get<double>();
    const double stepM = (sc["film"]["start_m"].get<double>() + binM * sc["film"]["bins"].get<int>()) / 2.0 / nz;
    const HiddenTarget t = hiddenTarget(scene);
    ASSERT_GT(t.depthM, 0.0);
    EXPECT_NEAR(depth, t.depthM, binM / 2.0 + stepM);
    const double pitch = 2.0 / 16.0;  // the 2 m wall over 16 sensor points
    EXPECT_GE(x, t.xLo - pitch);
    EXPECT_LE(x, t.xHi + pitch);
    EXPECT_GE(y, t.yLo - pitch);
    EXPECT_LE(y, t.yHi + pitch);
    // The front image is on screen and shows the peak (some pixel near white-yellow).
    const Image8 shot = readPng(dir / "bp.png");
    ASSERT_GT(fw, 10.0);
    ASSERT_LE(fx + fw, shot.w);
    ASSERT_LE(fy + fh, shot.h);
    int bright = 0;
    for (int py = static_cast<int>(fy); py < static_cast<int>(fy + fh); ++py)
        for (int px = static_cast<int>(fx); px < static_cast<int>(fx + fw); ++px)
            bright += shot.at(px, py)[0] > 240 && shot.at(px, py)[1] > 200;
    EXPECT_GT(bright, 0) << "no bright voxel in the front image";
    fs::remove_all(dir);
}
