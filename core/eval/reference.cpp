// Reference volumes (see reference.h for the file format and what each field means).
#include "eval/reference.h"

#include "io/film_container.h"
#include "base/error.h"
#include "base/parallel.h"
#include "film/film_view.h"

#include "io/record_json.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace tpb {

static_assert(std::endian::native == std::endian::little, "the reference format is little-endian");

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr char kMagic[9] = "TPBREF1\n";
constexpr const char* kFormat = "tpb-reference";
// 2: the settings in one object, "settings" (settingsRecord); 1 wrote seed, max_depth,
// samples_per_pixel, photons_per_pass and beam_radius0_m at the top (still read).
constexpr int kVersion = 2;

json infoToJson(const ReferenceInfo& i) {
    json j;
    j["format"] = kFormat;
    j["version"] = kVersion;
    j["scene"] = i.scene;
    j["scene_hash"] = i.sceneHash;
    j["method"] = i.method;
    j["passes"] = i.passes;
    j["settings"] = recordJson(i.settings);
    j["resolution"] = {i.width, i.height};
    j["bins"] = i.bins;
    j["start_opl_m"] = i.startOpl;
    j["bin_width_opl_m"] = i.binWidth;
    j["emission"] = "delta";
    j["requested_passes"] = i.requestedPasses;
    j["requested_time_s"] = i.requestedTimeSec;
    j["wall_seconds"] = i.wallSeconds;
    j["interrupted"] = i.interrupted;
    j["halves"] = {i.halfA, i.halfB};
    j["self_error"] = {{"real", i.selfErrorReal},
                       {"unwarped", i.selfErrorUnwarped},
                       {"steady", i.selfErrorSteady},
                       {"estimate", i.selfErrorEstimate}};
    return j;
}

ReferenceInfo infoFromJson(const json& j) {
    ReferenceInfo i;
    if (j.value("format", std::string()) != kFormat) throw std::runtime_error("not a tpb reference header");
    const int version = j.value("version", 0);
    if (version != 1 && version != kVersion)
        throw std::runtime_error("unsupported version " + std::to_string(version) + " (this tpb reads 1 and 2)");
    i.scene = j.at("scene").get<std::string>();
    i.sceneHash = j.value("scene_hash", std::string());
    i.method = j.at("method").get<std::string>();
    i.passes = j.at("passes").get<int64_t>();
    const json& s = version == 1 ? j : j.at("settings");
    i.settings = recordFromJson(s);
    i.samplesPerPixel = s.value("samples_per_pixel", 1);
    i.seed = s.at("seed").get<uint64_t>();
    i.maxDepth = s.at("max_depth").get<int>();
    i.photonsPerPass = s.value("photons_per_pass", int64_t(0));
    i.beamRadius0 = s.value(version == 1 ? "beam_radius0_m" : "radius", 0.0);
    i.width = j.at("resolution").at(0).get<int>();
    i.height = j.at("resolution").at(1).get<int>();
    i.bins = j.at("bins").get<int>();
    i.startOpl = j.at("start_opl_m").get<double>();
    i.binWidth = j.at("bin_width_opl_m").get<double>();
    if (j.value("emission", std::string("delta")) != "delta") throw std::runtime_error("emission must be \"delta\"");
    i.requestedPasses = j.value("requested_passes", int64_t(0));
    i.requestedTimeSec = j.value("requested_time_s", 0.0);
    i.wallSeconds = j.value("wall_seconds", 0.0);
    i.interrupted = j.value("interrupted", false);
    if (j.contains("halves")) {
        i.halfA = j["halves"].at(0).get<int64_t>();
        i.halfB = j["halves"].at(1).get<int64_t>();
    }
    if (j.contains("self_error")) {
        const json& s = j["self_error"];
        i.selfErrorReal = s.value("real", -1.0);
        i.selfErrorUnwarped = s.value("unwarped", -1.0);
        i.selfErrorSteady = s.value("steady", -1.0);
        i.selfErrorEstimate = s.value("estimate", std::string("unknown"));
    }
    if (i.width < 1 || i.height < 1 || i.bins < 1 || !(i.binWidth > 0.0))
        throw std::runtime_error("bad resolution, bins or bin width");
    return i;
}

struct ArraySpec {
    std::string name;
    std::vector<int64_t> shape;
    size_t count() const {
        size_t n = 1;
        for (int64_t s : shape) n *= static_cast<size_t>(s);
        return n;
    }
};

std::vector<ArraySpec> arraySpecs(const ReferenceInfo& i, bool withSelf) {
    std::vector<ArraySpec> a = {{"real", {i.height, i.width, i.bins, 3}},
                                {"unwarped", {i.height, i.width, i.bins, 3}},
                                {"steady", {i.height, i.width, 3}}};
    if (withSelf) a.push_back({"self_diff2", {i.height, i.width, 3}});
    return a;
}

std::vector<float>* arrayByName(ReferenceVolume& r, const std::string& name) {
    if (name == "real") return &r.real;
    if (name == "unwarped") return &r.unwarped;
    if (name == "steady") return &r.steady;
    if (name == "self_diff2") return &r.selfDiff2;
    return nullptr;
}

[[noreturn]] void corrupt(const std::string& path, const std::string& why) {
    throw UserError(path, 0, "", "not a valid tpb reference file (" + why + "); re-create it with `tpb reference`");
}

// Opens the container (film_container.h) and parses its header.
json readHeader(FilmContainerReader& f, const std::string& path) {
    if (!f.opened())
        throw UserError(path, 0, "",
                        "cannot open the reference file (missing or unreadable); create it with `tpb reference`");
    try {
        return json::parse(f.header());
    } catch (const std::exception& e) {
        corrupt(path, std::string("header is not JSON: ") + e.what());
    }
}

FilmContainerReader openReference(const std::string& path) {
    return FilmContainerReader(path, std::string_view(kMagic, 8),
                               [path](const std::string& why) { corrupt(path, why); });
}

std::string fmtDouble(double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%.9g", v);
    return b;
}

// ---- single-scattering quadrature ----------------------------------------------------------------

// 4-point Gauss-Legendre on [0, 1].
constexpr double kGLx[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
constexpr double kGLw[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};

// Radiance single-scattered towards the camera along the ray o + s dir (s > 0), from a point light
// in an infinite homogeneous medium. With h the distance from the light to the ray's line and sc
// the ray parameter of the closest point, s = sc + h tan(phi) turns ds / d^2 into dphi / h:
//   L = int_{phi0}^{pi/2} sigma_s e^{-sigma_t (s + d)} p(cos theta) Phi / (4 pi h) dphi,
// d = h / cos(phi), cos theta = -sin(phi) (light -> x -> camera). The phi range is cut at every
// time-bin edge of both axes (real: ior (s + d) + emit is increasing in phi; unwarped: ior d + emit
// is decreasing then increasing), so each piece lies in one bin of each axis, and at 128 uniform
// steps; each piece gets 4-point Gauss-Legendre.
void singleScatterRay(const Medium& m, double ior, const Light& light, const Vec3& o, const Vec3& dir,
                      const TimeBins& tb, double weight, double* real, double* unw, Color& steady,
                      std::vector<double>& cuts) {
    const Vec3 toL = light.position - o;
    const double sc = glm::dot(toL, dir);
    const double h = glm::length(toL - sc * dir);
    if (!(h > 1e-12)) return;  // the ray goes through the light (a set of measure zero)
    const double phi0 = std::atan2(-sc, h), phi1 = 0.5 * kPi;
    cuts.clear();
    cuts.push_back(phi0);
    cuts.push_back(phi1);
    auto add = [&](double phi) {
        if (phi > phi0 && phi < phi1) cuts.push_back(phi);
    };
    add(0.0);
    for (int k = 0; k <= tb.bins; ++k) {
        const double tau = (tb.startOpl + k * tb.binWidth - light.emitOpl) / ior;  // geometric length
        const double q = (tau - sc) / h;  // real: tan(phi) + sec(phi) = q  <=>  phi = 2 atan(q) - pi/2
        if (q > 0.0) add(2.0 * std::atan(q) - 0.5 * kPi);
        if (tau > h) {  // unwarped: h sec(phi) = tau
            const double a = std::acos(h / tau);
            add(a);
            add(-a);
        }
    }
    constexpr int kUniform = 128;
    for (int i = 1; i < kUniform; ++i) add(-0.5 * kPi + kPi * i / kUniform);
    std::sort(cuts.begin(), cuts.end());
    const Color base = m.sigma_s * light.power / (4.0 * kPi * h);
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        const double a = cuts[i], b = cuts[i + 1];
        if (!(b > a)) continue;
        const double pm = 0.5 * (a + b);
        const double sm = sc + h * std::tan(pm), dm = h / std::cos(pm);
        const int kr = tb.binOf(light.emitOpl + ior * (sm + dm));
        const int ku = tb.binOf(light.emitOpl + ior * dm);
        Color sum(0.0);
        for (int g = 0; g < 4; ++g) {
            const double phi = a + (b - a) * kGLx[g];
            const double s = sc + h * std::tan(phi), d = h / std::cos(phi);
            const double p = m.phase.eval(-std::sin(phi));
            sum += m.transmittance(s + d) * (p * (b - a) * kGLw[g]);
        }
        const Color c = base * sum * weight;
        steady += c;
        if (kr >= 0 && kr < tb.bins)
            for (int ch = 0; ch < 3; ++ch) real[kr * 3 + ch] += c[ch];
        if (ku >= 0 && ku < tb.bins)
            for (int ch = 0; ch < 3; ++ch) unw[ku * 3 + ch] += c[ch];
    }
}

}  // namespace

// ---- file I/O ------------------------------------------------------------------------------------

bool fileExists(const std::string& path) {
    std::error_code ec;
    return fs::is_regular_file(path, ec);
}

std::string hashFile(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return "";
    uint64_t h = 1469598103934665603ull;
    char buf[65536];
    while (f.read(buf, sizeof buf) || f.gcount() > 0) {
        const std::streamsize n = f.gcount();
        for (std::streamsize i = 0; i < n; ++i) {
            h ^= static_cast<unsigned char>(buf[i]);
            h *= 1099511628211ull;
        }
        if (!f) break;
    }
    char out[40];
    std::snprintf(out, sizeof out, "fnv1a64:%016" PRIx64, h);
    return out;
}

void writeReference(const std::string& path, const ReferenceVolume& ref) {
    const ReferenceInfo& i = ref.info;
    const bool withSelf = !ref.selfDiff2.empty();
    const std::vector<ArraySpec> specs = arraySpecs(i, withSelf);
    json header = infoToJson(i);
    json arrays = json::array();
    for (const ArraySpec& s : specs) {
        const std::vector<float>* a = arrayByName(const_cast<ReferenceVolume&>(ref), s.name);
        TPB_CHECK(a && a->size() == s.count());
        arrays.push_back({{"name", s.name}, {"shape", s.shape}, {"dtype", "float32"}});
    }
    header["arrays"] = arrays;
    header["sealed"] = true;  // a hash of the arrays follows them (version 2)
    const std::string text = header.dump(2) + "\n";
    const fs::path target(path);
    if (target.has_parent_path()) {
        std::error_code ec;
        fs::create_directories(target.parent_path(), ec);
        if (ec) throw UserError(path, 0, "", "cannot create its folder: " + ec.message());
    }
    FilmContainerWriter f(path, std::string_view(kMagic, 8), text);
    for (const ArraySpec& s : specs) {
        const std::vector<float>* a = arrayByName(const_cast<ReferenceVolume&>(ref), s.name);
        f.write(a->data(), a->size() * sizeof(float));
    }
    f.commit(/*seal=*/true);
}

ReferenceInfo readReferenceInfo(const std::string& path) {
    FilmContainerReader f = openReference(path);
    const json header = readHeader(f, path);
    try {
        return infoFromJson(header);
    } catch (const std::exception& e) {
        corrupt(path, std::string("header: ") + e.what());
    }
}

ReferenceVolume readReference(const std::string& path) {
    FilmContainerReader f = openReference(path);
    const json header = readHeader(f, path);
    ReferenceVolume r;
    try {
        r.info = infoFromJson(header);
    } catch (const std::exception& e) {
        corrupt(path, std::string("header: ") + e.what());
    }
    if (!header.contains("arrays") || !header["arrays"].is_array()) corrupt(path, "header has no \"arrays\"");
    const std::vector<ArraySpec> known = arraySpecs(r.info, true);
    size_t expectBytes = 0;
    std::vector<ArraySpec> listed;
    for (const json& a : header["arrays"]) {
        ArraySpec s;
        s.name = a.value("name", std::string());
        if (a.value("dtype", std::string("float32")) != "float32") corrupt(path, "array " + s.name + " is not float32");
        const auto it = std::find_if(known.begin(), known.end(), [&](const ArraySpec& k) { return k.name == s.name; });
        if (it == known.end()) corrupt(path, "unknown array \"" + s.name + "\"");
        s.shape = a.value("shape", std::vector<int64_t>());
        if (s.shape != it->shape) corrupt(path, "array " + s.name + " has a shape that does not match resolution/bins");
        listed.push_back(s);
        expectBytes += s.count() * sizeof(float);
    }
    for (const char* need : {"real", "unwarped", "steady"})
        if (std::none_of(listed.begin(), listed.end(), [&](const ArraySpec& s) { return s.name == need; }))
            corrupt(path, std::string("array \"") + need + "\" missing");
    const bool sealed = header.value("sealed", false);
    const uint64_t expect = f.payloadOffset() + expectBytes + (sealed ? 8 : 0);
    if (f.fileBytes() != expect)
        corrupt(path, "file size " + std::to_string(f.fileBytes()) + " bytes, expected " + std::to_string(expect) +
                          " (truncated?)");
    for (const ArraySpec& s : listed) {
        std::vector<float>* a = arrayByName(r, s.name);
        a->resize(s.count());
        f.read(a->data(), s.count() * sizeof(float), ("array " + s.name).c_str());
    }
    if (sealed) f.readSeal();
    return r;
}

// ---- compatibility -------------------------------------------------------------------------------

std::vector<std::string> referenceMismatches(const ReferenceInfo& ref, const ReferenceInfo& want) {
    std::vector<std::string> m;
    if (!ref.sceneHash.empty() && !want.sceneHash.empty() && ref.sceneHash != want.sceneHash)
        m.push_back("scene file contents: reference was rendered from " + ref.scene + " (" + ref.sceneHash +
                    "), this run uses " + want.scene + " (" + want.sceneHash + ")");
    if (ref.width != want.width || ref.height != want.height)
        m.push_back("resolution: reference has " + std::to_string(ref.width) + "x" + std::to_string(ref.height) +
                    ", this run has " + std::to_string(want.width) + "x" + std::to_string(want.height));
    if (ref.bins != want.bins)
        m.push_back("bins: reference has " + std::to_string(ref.bins) + ", this run has " + std::to_string(want.bins));
    const double tol = 1e-6 * std::max(ref.binWidth, want.binWidth);
    if (std::abs(ref.startOpl - want.startOpl) > tol || std::abs(ref.binWidth - want.binWidth) * want.bins > tol)
        m.push_back("time range: reference has start " + fmtDouble(ref.startOpl) + " m, bin width " +
                    fmtDouble(ref.binWidth) + " m; this run has start " + fmtDouble(want.startOpl) + " m, bin width " +
                    fmtDouble(want.binWidth) + " m");
    if (ref.maxDepth != want.maxDepth)
        m.push_back("max depth: reference has " + std::to_string(ref.maxDepth) + ", this run has " +
                    std::to_string(want.maxDepth) + " (use --max-depth " + std::to_string(ref.maxDepth) + ")");
    return m;
}

std::vector<std::string> cacheMismatches(const ReferenceInfo& ref, const ReferenceInfo& want) {
    std::vector<std::string> m = referenceMismatches(ref, want);
    if (ref.sceneHash != want.sceneHash && (ref.sceneHash.empty() || want.sceneHash.empty()))
        m.push_back("scene hash: unknown on one side");
    if (ref.method != want.method) m.push_back("method: " + ref.method + " vs " + want.method);
    if (want.method != "analytic-single-scattering") {
        if (ref.seed != want.seed)
            m.push_back("seed: " + std::to_string(ref.seed) + " vs " + std::to_string(want.seed));
        if (ref.samplesPerPixel != want.samplesPerPixel)
            m.push_back("samples per pixel: " + std::to_string(ref.samplesPerPixel) + " vs " +
                        std::to_string(want.samplesPerPixel));
        if (ref.photonsPerPass != want.photonsPerPass || std::abs(ref.beamRadius0 - want.beamRadius0) > 1e-12)
            m.push_back("photons per pass / initial radius differ");
        if (ref.requestedPasses != want.requestedPasses ||
            std::abs(ref.requestedTimeSec - want.requestedTimeSec) > 1e-9)
            m.push_back("budget: reference was asked for " + std::to_string(ref.requestedPasses) + " passes / " +
                        fmtDouble(ref.requestedTimeSec) + " s, now " + std::to_string(want.requestedPasses) +
                        " passes / " + fmtDouble(want.requestedTimeSec) + " s");
        if (ref.interrupted) m.push_back("the cached reference was interrupted before its budget");
    }
    return m;
}

void requireCompatible(const std::string& path, const ReferenceInfo& ref, const ReferenceInfo& want) {
    const std::vector<std::string> m = referenceMismatches(ref, want);
    if (m.empty()) return;
    std::string msg = "the reference does not match this run:";
    for (const std::string& s : m) msg += "\n  - " + s;
    msg += "\n  (re-create it with `tpb reference` and the same scene and overrides, or change the overrides)";
    throw UserError(path, 0, "", msg);
}

void setSettings(ReferenceInfo& i, const RenderSettings& s) {
    i.settings = settingsRecord(s);
    i.seed = s.seed;
    i.maxDepth = s.maxDepth;
    i.samplesPerPixel = s.method == Method::PathTracer ? std::max(1, s.samplesPerPixel) : 1;
    i.photonsPerPass = s.method == Method::Beams ? s.photonsPerPass : 0;
    i.beamRadius0 = s.method == Method::Beams ? s.beamRadius0 : 0.0;
}

ReferenceInfo describeScene(const Scene& scene, const TimeBins& time, const std::string& scenePath,
                            const RenderSettings& settings) {
    ReferenceInfo i;
    i.scene = scenePath;
    i.sceneHash = hashFile(scenePath);
    i.width = scene.camera.width;
    i.height = scene.camera.height;
    i.bins = time.bins;
    i.startOpl = time.startOpl;
    i.binWidth = time.binWidth;
    setSettings(i, settings);
    return i;
}

// ---- rendering -----------------------------------------------------------------------------------

ReferenceVolume renderReference(const Scene& scene, const TimeBins& time, const std::string& scenePath,
                                const ReferenceJob& job, const std::atomic<bool>* abort,
                                const std::function<void(int64_t, double)>& progress) {
    if (job.method != "pt" && job.method != "beams") throw UserError("reference method must be pt or beams");
    if (job.passes <= 0 && !(job.timeBudgetSec > 0.0)) throw UserError("a reference needs --passes or --time");
    ReferenceVolume r;
    ReferenceInfo& info = r.info;
    info = describeScene(scene, time, scenePath, job.method == "pt" ? job.pt : job.beams);
    info.method = job.method;
    info.requestedPasses = job.passes;
    info.requestedTimeSec = job.timeBudgetSec;
    const int B = time.bins;
    const size_t P = info.pixels();
    const double t0 = nowSec();
    auto budgetLeft = [&](int64_t done) {
        if (abort && abort->load()) return false;
        if (job.passes > 0 && done >= job.passes) return false;
        // A time budget stops the run, but never before 2 passes (the self-error needs both halves).
        return !(job.timeBudgetSec > 0.0 && nowSec() - t0 >= job.timeBudgetSec && done >= 2);
    };
    r.real.assign(info.volumeSize(), 0.0f);
    r.unwarped.assign(info.volumeSize(), 0.0f);
    r.steady.assign(P * 3, 0.0f);

    if (job.method == "beams") {
        RenderSettings ds = job.beams;
        ds.passes = 0;
        ds.timeBudgetSec = 0.0;
        setSettings(info, ds);
        Driver drv(scene, ds, time);
        int64_t done = 0;
        while (budgetLeft(done)) {
            if (!drv.runPass(static_cast<uint64_t>(done + 1))) break;
            ++done;
            if (progress) progress(done, nowSec() - t0);
        }
        info.passes = done;
        info.interrupted = abort && abort->load();
        const std::shared_ptr<const FilmSnapshot> snap = drv.snapshot();
        for (int a = 0; a < 2; ++a) {
            std::vector<float>& dst = a == 0 ? r.real : r.unwarped;
            for (int k = 0; k < B; ++k) {
                const std::vector<float> img = frameImage(*snap, k, static_cast<TimeAxis>(a), EmissionMode::Delta);
                for (size_t p = 0; p < P; ++p)
                    for (int c = 0; c < 3; ++c) dst[(p * B + k) * 3 + c] = img[p * 3 + c];
            }
        }
        r.steady = steadyImage(*snap);
        info.selfErrorEstimate = "unknown (photon beams: the error is mostly kernel bias)";
    } else {
        RenderSettings ps = job.pt;
        ps.method = Method::PathTracer;
        setSettings(info, ps);
        // Two films of the same passes split by parity (odd / even), each run by a Driver: pass i
        // depends only on (seed, i), so together they are the film of passes 1..done.
        Driver da(scene, ps, time), db(scene, ps, time);
        int64_t done = 0;
        while (budgetLeft(done)) {
            const uint64_t pass = static_cast<uint64_t>(done + 1);
            if (!(pass % 2 == 1 ? da : db).runPass(pass)) break;
            if (abort && abort->load()) break;  // checked between passes: every finished pass is whole
            ++done;
            if (progress) progress(done, nowSec() - t0);
        }
        const TransientFilm& fa = da.film();
        const TransientFilm& fb = db.film();
        info.passes = done;
        info.interrupted = abort && abort->load();
        const double na = static_cast<double>((done + 1) / 2), nb = static_cast<double>(done / 2);
        info.halfA = (done + 1) / 2;
        info.halfB = done / 2;
        const double wa = done > 0 ? na / (na + nb) : 0.0, wb = done > 0 ? nb / (na + nb) : 0.0;
        r.selfDiff2.assign(P * 3, 0.0f);
        std::vector<double> diff2(P * 3, 0.0);
        SquaredError sums[3];  // ref2 per quantity (diff2 kept per pixel)
        const std::shared_ptr<const FilmSnapshot> sa = fa.snapshot(), sb = fb.snapshot();
        std::vector<float> ia, ib;
        for (int a = 0; a < 2; ++a) {
            std::vector<float>& dst = a == 0 ? r.real : r.unwarped;
            for (int k = 0; k < B; ++k) {
                ia = frameImage(*sa, k, static_cast<TimeAxis>(a), EmissionMode::Delta);
                ib = frameImage(*sb, k, static_cast<TimeAxis>(a), EmissionMode::Delta);
                for (size_t p = 0; p < P; ++p)
                    for (int c = 0; c < 3; ++c) {
                        const double x = ia[p * 3 + c], y = ib[p * 3 + c];
                        const double full = wa * x + wb * y;
                        dst[(p * B + k) * 3 + c] = static_cast<float>(full);
                        diff2[p * 3 + a] += (x - y) * (x - y);
                        sums[a].ref2 += full * full;
                    }
            }
        }
        ia = steadyImage(*sa);
        ib = steadyImage(*sb);
        for (size_t p = 0; p < P; ++p)
            for (int c = 0; c < 3; ++c) {
                const double x = ia[p * 3 + c], y = ib[p * 3 + c];
                const double full = wa * x + wb * y;
                r.steady[p * 3 + c] = static_cast<float>(full);
                diff2[p * 3 + 2] += (x - y) * (x - y);
                sums[2].ref2 += full * full;
            }
        for (size_t i = 0; i < diff2.size(); ++i) {
            r.selfDiff2[i] = static_cast<float>(diff2[i]);
            sums[i % 3].diff2 += diff2[i];
        }
        if (nb > 0) {
            info.selfErrorReal = halfSplitRelativeError(sums[0].diff2, sums[0].ref2, na, nb);
            info.selfErrorUnwarped = halfSplitRelativeError(sums[1].diff2, sums[1].ref2, na, nb);
            info.selfErrorSteady = halfSplitRelativeError(sums[2].diff2, sums[2].ref2, na, nb);
            info.selfErrorEstimate = "half-split: odd vs even passes";
        } else {
            r.selfDiff2.clear();
            info.selfErrorEstimate = "unknown (fewer than 2 passes)";
        }
    }
    info.wallSeconds = nowSec() - t0;
    return r;
}

ReferenceVolume singleScatteringReference(const Scene& scene, const TimeBins& time, const std::string& scenePath,
                                          const RenderSettings& settings, int subpixels, int threads) {
    const std::string where = scenePath.empty() ? std::string("scene") : scenePath;
    auto refuse = [&](const std::string& why) {
        throw UserError(where, 0, "",
                        "the analytic single-scattering reference needs exactly one point light in an "
                        "infinite homogeneous scattering medium and no shapes: " +
                            why);
    };
    if (scene.lights.size() != 1) refuse(std::to_string(scene.lights.size()) + " lights");
    const Light& light = scene.lights[0];
    if (light.type != LightType::Point) refuse("the light is not a point light");
    if (!scene.shapes.empty()) refuse(std::to_string(scene.shapes.size()) + " shapes");
    if (scene.regions.empty() || !scene.regions[0].hasMedium) refuse("no global medium");
    const Region& region = scene.regions[0];
    if (!region.medium.scattering) refuse("the global medium does not scatter");
    subpixels = std::max(1, subpixels);

    ReferenceVolume r;
    ReferenceInfo& info = r.info;
    RenderSettings single = settings;
    single.maxDepth = 1;
    info = describeScene(scene, time, scenePath, single);
    info.method = "analytic-single-scattering";
    info.passes = 0;
    info.selfErrorReal = info.selfErrorUnwarped = info.selfErrorSteady = 0.0;
    info.selfErrorEstimate = "quadrature (4-point Gauss-Legendre per piece, pieces cut at every bin edge)";
    const int W = scene.camera.width, H = scene.camera.height, B = time.bins;
    r.real.assign(info.volumeSize(), 0.0f);
    r.unwarped.assign(info.volumeSize(), 0.0f);
    r.steady.assign(info.pixels() * 3, 0.0f);
    r.selfDiff2.assign(info.pixels() * 3, 0.0f);
    double lx = -1e9, ly = -1e9;
    if (!scene.camera.project(light.position, lx, ly)) lx = ly = -1e9;
    const double t0 = nowSec();
    parallelFor(H, resolveThreads(threads), [&](int64_t y, int) {
        std::vector<double> cuts, real(static_cast<size_t>(B) * 3), unw(static_cast<size_t>(B) * 3);
        for (int x = 0; x < W; ++x) {
            std::fill(real.begin(), real.end(), 0.0);
            std::fill(unw.begin(), unw.end(), 0.0);
            Color steady(0.0);
            const bool nearLight = std::abs(lx - (x + 0.5)) < 1.5 && std::abs(ly - (y + 0.5)) < 1.5;
            const int n = nearLight ? 8 * subpixels : subpixels;
            const double w = 1.0 / (double(n) * n);
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const Ray ray = scene.camera.generate(x + (i + 0.5) / n, static_cast<double>(y) + (j + 0.5) / n);
                    singleScatterRay(region.medium, region.ior, light, ray.o, ray.d, time, w, real.data(), unw.data(),
                                     steady, cuts);
                }
            const size_t p = static_cast<size_t>(y) * W + x;
            for (int k = 0; k < B; ++k)
                for (int c = 0; c < 3; ++c) {
                    r.real[(p * B + k) * 3 + c] = static_cast<float>(real[k * 3 + c]);
                    r.unwarped[(p * B + k) * 3 + c] = static_cast<float>(unw[k * 3 + c]);
                }
            for (int c = 0; c < 3; ++c) r.steady[p * 3 + c] = static_cast<float>(steady[c]);
        }
    });
    info.wallSeconds = nowSec() - t0;
    return r;
}

// ---- measuring -----------------------------------------------------------------------------------

FilmError compareWithReference(const TransientFilm& film, const ReferenceVolume& ref, TimeAxis axis, bool perFrame,
                               const std::vector<uint8_t>* mask) {
    const ReferenceInfo& i = ref.info;
    TPB_CHECK(film.width() == i.width && film.height() == i.height && film.bins() == i.bins);
    const size_t P = i.pixels();
    const int B = i.bins;
    const bool useMask = mask && mask->size() == P;
    const std::vector<float>& rv = ref.volume(axis);
    const std::shared_ptr<const FilmSnapshot> snap = film.snapshot();  // one state of the film for every frame
    FilmError out;
    SquaredError total;
    AbsoluteError totalL1, steadyL1;
    if (perFrame) out.perFrame.assign(static_cast<size_t>(B), 0.0);
    std::vector<float> img;
    for (int k = 0; k < B; ++k) {
        img = frameImage(*snap, k, axis, EmissionMode::Delta);
        SquaredError e;
        for (size_t p = 0; p < P; ++p) {
            if (useMask && (*mask)[p]) continue;
            const float* r = &rv[(p * B + k) * 3];
            for (int c = 0; c < 3; ++c) {
                e.add(img[p * 3 + c], r[c]);
                totalL1.add(img[p * 3 + c], r[c]);
            }
        }
        total.add(e);
        if (perFrame) out.perFrame[k] = e.relative();
    }
    out.volume = total.relative();
    out.volumeL1 = totalL1.relative();
    img = steadyImage(*snap);
    SquaredError s;
    double sx = 0.0, sr = 0.0;
    for (size_t p = 0; p < P; ++p) {
        if (useMask && (*mask)[p]) continue;
        for (int c = 0; c < 3; ++c) {
            s.add(img[p * 3 + c], ref.steady[p * 3 + c]);
            steadyL1.add(img[p * 3 + c], ref.steady[p * 3 + c]);
            sx += img[p * 3 + c];
            sr += ref.steady[p * 3 + c];
        }
    }
    out.steady = s.relative();
    out.steadyL1 = steadyL1.relative();
    out.steadyTotalDiff = sr != 0.0 ? (sx - sr) / sr : std::numeric_limits<double>::quiet_NaN();
    return out;
}

double referenceSelfError(const ReferenceVolume& ref, TimeAxis axis, bool steady, const std::vector<uint8_t>* mask) {
    const ReferenceInfo& i = ref.info;
    const size_t P = i.pixels();
    const bool useMask = mask && mask->size() == P;
    if (!useMask) {
        const double e = steady ? i.selfErrorSteady : i.selfError(axis);
        return std::isfinite(e) ? e : -1.0;
    }
    if (i.method == "analytic-single-scattering") return 0.0;
    if (ref.selfDiff2.size() != P * 3 || i.halfB <= 0) return -1.0;
    const int slot = steady ? 2 : static_cast<int>(axis);
    const std::vector<float>& v = steady ? ref.steady : ref.volume(axis);
    const size_t per = steady ? 3 : static_cast<size_t>(i.bins) * 3;
    double diff2 = 0.0, ref2 = 0.0;
    for (size_t p = 0; p < P; ++p) {
        if ((*mask)[p]) continue;
        diff2 += ref.selfDiff2[p * 3 + slot];
        for (size_t j = 0; j < per; ++j) ref2 += double(v[p * per + j]) * v[p * per + j];
    }
    const double e = halfSplitRelativeError(diff2, ref2, double(i.halfA), double(i.halfB));
    return std::isfinite(e) ? e : -1.0;
}

std::vector<uint8_t> lightPixelMask(const Scene& scene, double radius) {
    std::vector<uint8_t> mask;
    if (!(radius > 0.0)) return mask;
    const int W = scene.camera.width, H = scene.camera.height;
    mask.assign(static_cast<size_t>(W) * H, 0);
    for (const Light& l : scene.lights) {
        if (l.type != LightType::Point && l.type != LightType::Spot) continue;
        double lx, ly;
        if (!scene.camera.project(l.position, lx, ly)) continue;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                if (std::hypot(x + 0.5 - lx, y + 0.5 - ly) <= radius) mask[static_cast<size_t>(y) * W + x] = 1;
    }
    return mask;
}

}  // namespace tpb
