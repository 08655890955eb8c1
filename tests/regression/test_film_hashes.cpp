// Regression guard for refactors: every shipped scene rendered small, with a fixed seed, hashed.
//
// Each scene of scenes/ is rendered by the photon beams and by the path tracer (+ the geometry
// preview; entries "pt:<scene>") at 32x32 px, 24 bins, 1500 photons per pass, 2 passes, 2
// threads, seed 7 (the automatic time range runs its pilot as `tpb render` does). The film (both
// axes, delta emission, the steady image and what fell before/after the film) is hashed (FNV-1a 64
// over the float bits) and summarised by sums that a refactor must keep. tests/data/film_hashes.txt
// holds, per scene: the hash, then the sums.
//   - The film depends on the build (optimisation level, sanitizers and compiler change the last
//     bits, which can turn a path at a grazing hit): a build other than the one recorded (build
//     type, compiler, sanitizer) skips the test, saying so. tools/test's Release build checks it.
//   - Embree picks its SIMD kernels by the CPU's instruction sets, which can turn a path at a
//     grazing hit, so the file holds one block per CPU ("cpu <model> [<isa>]", the model name plus
//     the SIMD sets Embree dispatches on; a block without "[...]" was recorded before the sets were
//     part of the key and stands for its model). Same build, a block recorded on this CPU: the hash
//     must equal that block's exactly (and the sums to 1e-5).
//   - Same build, no block of this CPU: the sums must match to 1e-3 and a hash mismatch is a note.
//     TPB_EXACT_HASHES=1 makes it exact everywhere.
// A change that alters films on purpose re-records the file with TPB_UPDATE_HASHES=1 (this CPU's
// block only: the other blocks are stale then) and says in its commit message which scenes changed
// and why. TPB_UPDATE_HASHES=add adds this CPU's block and keeps the others: for a new machine when
// nothing changed on purpose.
#include "support/path_tracer_passes.h"
#include "integrators/path_tracer.h"
#include "integrators/preview.h"
#include "render/driver.h"
#include "scene/scene_loader.h"
#include "render/prepare.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <iomanip>
#include <sstream>

using namespace tpb;
namespace fs = std::filesystem;

namespace {

const std::string kDataFile = std::string(TPB_SOURCE_DIR) + "/tests/data/film_hashes.txt";

struct Signature {
    std::string hash;
    double sums[6] = {0, 0, 0, 0, 0, 0};  // real, unwarped, steady, before real, before unwarped, sum of squares (real)
};

std::string buildFingerprint() {
    std::string b = std::string(TPB_BUILD_TYPE) + " " + __VERSION__;
#if defined(__SANITIZE_ADDRESS__)
    b += " asan";
#endif
#if defined(__SANITIZE_THREAD__)
    b += " tsan";
#endif
    return b;
}

std::string cpuModel() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown";
}

// The CPU's key in the hash file: its model name and the SIMD instruction sets Embree chooses its
// kernels by (a machine with AVX-512 runs other kernels than one with AVX2 only).
std::string cpuKey() {
    std::ifstream in("/proc/cpuinfo");
    std::string line, flags;
    while (std::getline(in, line))
        if (line.rfind("flags", 0) == 0) {
            flags = " " + line.substr(line.find(':') + 1) + " ";
            break;
        }
    std::string isa;
    for (const char* f : {"sse4_2", "avx", "avx2", "avx512f", "avx512vl", "avx512bw", "avx512dq"})
        if (flags.find(std::string(" ") + f + " ") != std::string::npos)
            isa += (isa.empty() ? "" : " ") + std::string(f);
    return cpuModel() + " [" + isa + "]";
}

// A block of the hash file: the CPU it was recorded on, the build, the signatures by scene.
struct HashBlock {
    std::string cpu, build;
    std::map<std::string, Signature> scenes;
    // Recorded on this machine: the same key, or a legacy block (no "[...]") of the same model.
    bool ofThisCpu() const { return cpu == cpuKey() || (cpu.find('[') == std::string::npos && cpu == cpuModel()); }
};

std::vector<HashBlock> readHashFile(const std::string& path) {
    std::ifstream in(path);
    std::vector<HashBlock> blocks;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        if (line.rfind("cpu ", 0) == 0) {
            blocks.push_back({line.substr(4), "", {}});
            continue;
        }
        if (blocks.empty()) blocks.push_back({"unknown", "", {}});
        if (line.rfind("build ", 0) == 0) {
            blocks.back().build = line.substr(6);
            continue;
        }
        std::istringstream ss(line);
        std::string name;
        Signature s;
        ss >> name >> s.hash;
        for (double& v : s.sums) ss >> v;
        blocks.back().scenes[name] = s;
    }
    return blocks;
}

struct Fnv {
    uint64_t h = 1469598103934665603ull;
    void add(const std::vector<float>& v) {
        for (float f : v) {
            uint32_t bits;
            std::memcpy(&bits, &f, 4);
            for (int i = 0; i < 4; ++i) {
                h ^= (bits >> (8 * i)) & 0xffu;
                h *= 1099511628211ull;
            }
        }
    }
};

Signature filmSignature(const TransientFilm& film);

// The scene as the CLI prepares it, the pilot (for "range": "auto") with 1500 photons on 2 threads.
PreparedRender prepareFixed(const SceneDesc& d) {
    SettingsOverrides o;
    o.threads = 2;
    PrepareOptions opt;
    opt.pilot.photons = 1500;
    return prepareRender(d, o, opt);
}

Signature renderSignature(const std::string& scenePath) {
    SceneDesc d = loadScene(scenePath);
    d.camera.width = d.camera.height = 32;
    d.film.bins = 24;
    d.render.photonsPerPass = 1500;
    d.render.seed = 7;
    const PreparedRender p = prepareFixed(d);
    const Scene* scene = p.scene.get();
    RenderSettings ds = p.settings;
    ds.threads = 2;
    Driver drv(*scene, ds, p.time);
    for (int p = 1; p <= 2; ++p) EXPECT_TRUE(drv.runPass(p)) << scenePath;
    return filmSignature(drv.film());
}

// The path tracer on the same scene and film (1 sample per pixel, 2 passes, max depth 8), and the
// geometry preview (steady only): every renderer is guarded, not only the photon beams.
Signature pathTracerSignature(const std::string& scenePath) {
    SceneDesc d = loadScene(scenePath);
    d.camera.width = d.camera.height = 32;
    d.film.bins = 24;
    d.render.seed = 7;
    const PreparedRender p = prepareFixed(d);
    const Scene* scene = p.scene.get();
    RenderSettings ps;
    ps.maxDepth = 64;  // the path tracer's depth unless set below
    ps.seed = 7;
    ps.samplesPerPixel = 1;
    ps.maxDepth = 8;
    ps.threads = 2;
    TransientFilm film(scene->camera.width, scene->camera.height, p.time);
    EXPECT_EQ(test::renderPathTracer(*scene, ps, 1, 2, film), 2) << scenePath;
    Signature sig = filmSignature(film);
    Fnv fnv;
    fnv.h = std::stoull(sig.hash, nullptr, 16);
    fnv.add(renderPreview(*scene, 2));
    char buf[32];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv.h));
    sig.hash = buf;
    return sig;
}

Signature filmSignature(const TransientFilm& film) {
    Fnv fnv;
    Signature sig;
    std::vector<float> img;
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped}) {
        for (int k = 0; k < film.bins(); ++k) {
            film.frame(k, axis, EmissionMode::Delta, img);
            fnv.add(img);
            for (float v : img) {
                sig.sums[static_cast<int>(axis)] += v;
                if (axis == TimeAxis::Real) sig.sums[5] += static_cast<double>(v) * v;
            }
        }
        film.beforeImage(axis, img);
        fnv.add(img);
        for (float v : img) sig.sums[3 + static_cast<int>(axis)] += v;
        film.afterImage(axis, img);
        fnv.add(img);
    }
    film.steadyImage(img);
    fnv.add(img);
    for (float v : img) sig.sums[2] += v;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv.h));
    sig.hash = buf;
    return sig;
}

std::vector<std::string> sceneFiles() {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(std::string(TPB_SOURCE_DIR) + "/scenes"))
        if (e.path().extension() == ".json") out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

TEST(FilmHashes, EveryShippedSceneRendersAsRecorded) {
    std::map<std::string, Signature> got;
    for (const std::string& name : sceneFiles()) {
        got[name] = renderSignature(std::string(TPB_SOURCE_DIR) + "/scenes/" + name);
        got["pt:" + name] = pathTracerSignature(std::string(TPB_SOURCE_DIR) + "/scenes/" + name);
    }

    std::vector<HashBlock> blocks = readHashFile(kDataFile);
    if (const char* u = std::getenv("TPB_UPDATE_HASHES"); u && (std::string(u) == "1" || std::string(u) == "add")) {
        std::vector<HashBlock> keep;
        if (std::string(u) == "add")
            for (const HashBlock& b : blocks)
                if (b.cpu != cpuKey()) keep.push_back(b);
        keep.push_back({cpuKey(), buildFingerprint(), got});
        std::ofstream out(kDataFile);
        out << "# tests/regression/test_film_hashes.cpp: scene hash sum_real sum_unwarped sum_steady before_real "
               "before_unwarped sumsq_real\n";
        for (const HashBlock& b : keep) {
            out << "cpu " << b.cpu << "\n";
            out << "build " << b.build << "\n";
            for (const auto& [name, s] : b.scenes) {
                out << name << " " << s.hash;
                for (double v : s.sums) out << " " << std::setprecision(17) << v;
                out << "\n";
            }
        }
        GTEST_SKIP() << "recorded " << got.size() << " scenes into " << kDataFile << " (cpu " << cpuKey() << ", "
                     << keep.size() << " block(s))";
    }

    ASSERT_FALSE(blocks.empty()) << kDataFile << " is missing or empty: record it with TPB_UPDATE_HASHES=1";
    std::vector<const HashBlock*> mine, sameBuild;
    for (const HashBlock& b : blocks) {
        if (b.build != buildFingerprint()) continue;
        sameBuild.push_back(&b);
        if (b.ofThisCpu()) mine.push_back(&b);
    }
    if (sameBuild.empty())
        GTEST_SKIP() << "the hashes were recorded with the build \"" << blocks.front().build << "\"; this is \""
                     << buildFingerprint() << "\" (the Release build of tools/test checks them)";
    const char* exactEnv = std::getenv("TPB_EXACT_HASHES");
    const bool exact = (exactEnv && std::string(exactEnv) == "1") || !mine.empty();
    const std::vector<const HashBlock*>& candidates = mine.empty() ? sameBuild : mine;
    const std::map<std::string, Signature>& want = candidates.front()->scenes;
    for (const auto& [name, s] : got) {
        ASSERT_TRUE(want.count(name)) << name << " has no recorded signature: re-record with TPB_UPDATE_HASHES=1";
        // The block whose hash this film has, if any (several blocks may stand for this CPU).
        const Signature* w = &want.at(name);
        for (const HashBlock* b : candidates)
            if (b->scenes.count(name) && b->scenes.at(name).hash == s.hash) w = &b->scenes.at(name);
        const double tol = exact ? 1e-5 : 1e-3;
        for (int i = 0; i < 6; ++i)
            EXPECT_NEAR(s.sums[i], w->sums[i], tol * std::abs(w->sums[i]) + 1e-30) << name << " sum " << i;
        if (exact)
            EXPECT_EQ(s.hash, w->hash) << name << ": the film changed (a block of this CPU, " << cpuKey()
                                       << ", holds another hash)";
        else if (s.hash != w->hash)
            std::printf("note: %s hash %s differs from the recorded %s (recorded on another CPU: %s; this is %s)\n",
                        name.c_str(), s.hash.c_str(), w->hash.c_str(), candidates.front()->cpu.c_str(),
                        cpuKey().c_str());
    }
    EXPECT_EQ(got.size(), want.size()) << "scenes were added or removed: re-record with TPB_UPDATE_HASHES=1";
}
