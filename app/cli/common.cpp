#include "base/parallel.h"
#include "cli/common.h"
#include "film/output_names.h"

#include "cli/flags.h"
#include "cli/summary.h"

#include "cli/interrupt.h"
#include "base/error.h"
#include "estimators/estimator_names.h"
#include "film/film_view.h"
#include "film/picture_export.h"
#include "io/folder_lock.h"
#include "io/npy.h"
#include "render/nlos_capture.h"
#include "render/checkpoint.h"
#include "render/time_range.h"

#include "cli/commands.h"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <sys/statvfs.h>
#include <unistd.h>

namespace tpb::app {

namespace fs = std::filesystem;

namespace {

// "0.4 s", "12 s", "17 min", "2.3 h".
std::string humanSeconds(double s) {
    char b[32];
    if (s < 10.0)
        std::snprintf(b, sizeof b, "%.1f s", s);
    else if (s < 120.0)
        std::snprintf(b, sizeof b, "%.0f s", s);
    else if (s < 7200.0)
        std::snprintf(b, sizeof b, "%.0f min", s / 60.0);
    else
        std::snprintf(b, sizeof b, "%.1f h", s / 3600.0);
    return b;
}

std::string withMeaning(const std::string& rule, const std::string& meaning) {
    return meaning.empty() ? rule : rule + " (" + meaning + ")";
}

}  // namespace

// ---- flag validation ----------------------------------------------------------------------------

namespace flags {

CLI::Validator integer(int64_t lo, int64_t hi, const std::string& meaning) {
    const std::string rule = hi == INT64_MAX ? "an integer >= " + std::to_string(lo)
                                             : "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    return CLI::Validator(
        [=](std::string& s) -> std::string {
            const std::string fail = "must be " + withMeaning(rule, meaning) + "; got " + s;
            int64_t v = 0;
            const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
            if (ec == std::errc::result_out_of_range) return fail;
            if (ec != std::errc() || ptr != s.data() + s.size()) {
                // 1e6: an integral number in another notation is fine; rewrite it as digits for CLI11.
                char* end = nullptr;
                const double d = std::strtod(s.c_str(), &end);
                if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(d) || d != std::floor(d) ||
                    std::fabs(d) >= 9.2e18)
                    return fail;
                v = static_cast<int64_t>(d);
                if (v >= lo && v <= hi) s = std::to_string(v);
            }
            return v >= lo && v <= hi ? std::string() : fail;
        },
        rule);
}

CLI::Validator number(double lo, double hi, bool loOpen, const std::string& meaning) {
    const bool noHi = hi == std::numeric_limits<double>::infinity();
    const std::string rule =
        noHi ? std::string("a finite number ") + (loOpen ? "> " : ">= ") + shortNumber(lo)
             : std::string("a number in ") + (loOpen ? "(" : "[") + shortNumber(lo) + ", " + shortNumber(hi) + "]";
    return CLI::Validator(
        [=](std::string& s) -> std::string {
            char* end = nullptr;
            errno = 0;
            const double v = std::strtod(s.c_str(), &end);
            const bool parsed = !s.empty() && end == s.c_str() + s.size();
            const bool ok = parsed && std::isfinite(v) && (loOpen ? v > lo : v >= lo) && v <= hi;
            return ok ? std::string() : "must be " + withMeaning(rule, meaning) + "; got " + s;
        },
        rule);
}

CLI::Validator seed() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            uint64_t v = 0;
            const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
            if (s.empty() || ec != std::errc() || ptr != s.data() + s.size())
                return "must be an integer in [0, 18446744073709551615] (2^64 - 1); got " + s;
            return std::string();
        },
        "an integer in [0, 2^64 - 1]");
}

CLI::Validator pulse() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            return parsePulse(s) ? std::string()
                                 : "must be delta, gaussian:FWHM_NS or square:WIDTH_NS (a width in ns, > 0); got " + s;
        },
        "delta|gaussian:NS|square:NS");
}

CLI::Validator sensor() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            return parseSensor(s) ? std::string()
                                  : "must be ideal, gaussian:FWHM_NS or exp:TAU_NS (a width in ns, > 0); got " + s;
        },
        "ideal|gaussian:NS|exp:NS");
}

CLI::Validator counts() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            try {
                parseCounting(s, "");  // CLI11 names the flag
                return std::string();
            } catch (const UserError& e) {
                return e.what();
            }
        },
        "off|photons=P,dark_hz=R,...");
}

CLI::Validator threads() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            int64_t v = 0;
            const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
            if (s.empty() || ptr != s.data() + s.size() || ec != std::errc() || v < 0 || v > INT_MAX)
                return "must be an integer in [0, " + std::to_string(INT_MAX) + "] (0 = all cores; more than " +
                       std::to_string(maxUsefulThreads()) + " is capped); got " + s;
            const int cap = maxUsefulThreads();
            if (v > cap) {
                std::fprintf(stderr,
                             "warning: --threads %s is more than %d x the %d cores of this machine: using %d (more "
                             "threads than cores only add memory and contention; 0 = all cores)\n",
                             s.c_str(), kThreadsPerCoreCap, cap / kThreadsPerCoreCap, cap);
                s = std::to_string(cap);
            }
            return std::string();
        },
        "an integer >= 0");
}

}  // namespace flags

void RenderOverrides::add(CLI::App* cmd) {
    using flags::integer;
    using flags::number;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    cmd->add_option("--passes", passes, "Number of progressive passes (0 = until --time or Ctrl-C)")
        ->transform(integer(0, INT64_MAX, "0 = no pass limit: until --time or Ctrl-C"));
    cmd->add_option("--time", timeBudget, "Time budget in seconds")
        ->check(number(0.0, kInf, false, "seconds; 0 = no time budget"));
    cmd->add_option("--photons", photons, "Photons traced per pass")
        ->transform(integer(1, INT64_MAX, "photons per pass"));
    cmd->add_option("--warmup", warmup,
                    "Warm-up passes: the first W passes trace photons/2^W, ..., photons/2 (a first picture sooner; "
                    "default 0, the viewer 3)")
        ->transform(integer(0, kMaxWarmupPasses, "0 = no warm-up"));
    cmd->add_option("--radius", radius, "Initial beam kernel radius, m (absolute)")
        ->check(number(0.0, kMaxSceneCoordinateM, true, "meters"));
    cmd->add_flag(
           "--auto-radius", autoRadius,
           "Initial radius from the photon density of a pilot pass (as \"radius\": \"auto\"; `tpb info` shows it)")
        ->excludes(cmd->get_option("--radius"));
    cmd->add_option("--alpha", alpha, "Progressive radius shrink parameter in (0, 1]")
        ->check(number(0.0, 1.0, true, "1 = no shrinking"));
    cmd->add_option("--threads", threads, "Worker threads (0 = all cores)")->transform(flags::threads());
    cmd->add_option("--seed", seed, "Random seed")->check(flags::seed());
    cmd->add_option("--width", width, "Override the camera's horizontal resolution")
        ->transform(integer(1, INT_MAX, "pixels"));
    cmd->add_option("--height", height, "Override the camera's vertical resolution")
        ->transform(integer(1, INT_MAX, "pixels"));
    cmd->add_option("--bins", bins, "Override the film's number of time bins (same time range)")
        ->transform(integer(1, INT_MAX, "time bins of the film"));
    cmd->add_option("--max-depth", maxDepth, "Maximum number of scattering events per path (1 = single scattering)")
        ->transform(integer(1, INT_MAX, "1 = single scattering"));
    cmd->add_option("--bounces", bounces,
                    "Bounce filter: only light with N scattering events (surface or medium; a laser's spot "
                    "counts one), or MIN:MAX, or MIN: (no upper limit); e.g. 3 = an NLOS relay wall's third "
                    "bounce, 2: = without the wall's direct response")
        ->check(CLI::Validator(
            [](std::string& v) -> std::string {
                int a = 0, b = 0;
                char colon = 0, extra = 0;
                if (std::sscanf(v.c_str(), "%d%c%d%c", &a, &colon, &b, &extra) == 3 && colon == ':' && a >= 0 && a <= b)
                    return "";
                if (std::sscanf(v.c_str(), "%d%c%c", &a, &colon, &extra) == 2 && colon == ':' && a >= 0) return "";
                if (std::sscanf(v.c_str(), "%d%c", &a, &extra) == 1 && a >= 0) return "";
                return "expected N, MIN:MAX or MIN: with 0 <= MIN <= MAX (scattering events), got \"" + v + "\"";
            },
            "N|MIN:MAX|MIN:", "bounces"));
    cmd->add_option("--profile", profile, "Time profile of a ray-beam estimate: exact | uniform (paper)")
        ->check(CLI::IsMember({"exact", "uniform"}));
    cmd->add_option("--beam-length", beamLength, "Photon beams end at the next event (short) or the surface (long)")
        ->check(CLI::IsMember({"short", "long"}));
    cmd->add_flag("--pt-free-flight", ptFreeFlight,
                  "Path tracer: connect point/spot lights only from free-flight vertices, without equiangular "
                  "sampling (unbiased too, but with infinite variance next to a light in a medium)");
    std::string volumeNames, surfaceNames;
    for (const std::string& n : volumeEstimatorNames()) volumeNames += (volumeNames.empty() ? "" : " | ") + n;
    for (const std::string& n : surfaceEstimatorNames()) surfaceNames += (surfaceNames.empty() ? "" : " | ") + n;
    cmd->add_option(
        "--estimator", estimator,
        "Volume density estimator of the photon-beams method: " + volumeNames + " (docs/user/estimators.md)");
    cmd->add_option("--surface-estimator", surfaceEstimator, "Surface density estimator: " + surfaceNames);
    cmd->add_option("--time-kernel", timeKernel,
                    "Progressive time kernel of the estimators: none | box (width chosen from the scene) | box:WIDTH "
                    "(m of optical path, full width at pass 1; it shrinks with the radius)")
        ->check(CLI::Validator(
            [](std::string& s) {
                if (parseTimeKernel(s)) return std::string();
                return s +
                       ": allowed none, box or box:WIDTH with WIDTH > 0 in m of optical path "
                       "(e.g. box:0.05)";
            },
            "none|box|box:WIDTH"));
    cmd->add_option("--phasor", phasor,
                    "Exact phasor film beside the bins (docs/user/phasor.md): F1,F2,... (cycles per m of optical "
                    "path) | wl:WL1,WL2,... (wavelengths, m) | band:MEAN:SIGMA (mitransient's phasor film band, m)");
    cmd->add_option("--accel", accel, "Beam query backend: bvh | embree | brute")
        ->check(CLI::IsMember({"bvh", "embree", "brute"}));
}

SettingsOverrides RenderOverrides::settings() const {
    SettingsOverrides o;
    o.passes = passes;
    o.photons = photons;
    o.warmup = warmup;
    o.timeBudget = timeBudget;
    o.radius = radius;
    o.autoRadius = autoRadius;
    o.alpha = alpha;
    o.threads = threads;
    o.maxDepth = maxDepth;
    if (bounces) {
        int a = 0, b = INT_MAX;
        char colon = 0;
        const int n = std::sscanf(bounces->c_str(), "%d%c%d", &a, &colon, &b);
        o.bounces = {a, n == 1 ? a : b};  // "N" = N:N; "MIN:" keeps b = INT_MAX
    }
    o.seed = seed;
    o.width = width;
    o.height = height;
    o.bins = bins;
    if (profile == "exact") o.profile = TimeProfile::Exact;
    if (profile == "uniform") o.profile = TimeProfile::Uniform;
    if (beamLength == "short") o.beamLength = BeamLength::Short;
    if (beamLength == "long") o.beamLength = BeamLength::Long;
    if (accel) o.accel = *parseAccelBackend(*accel);
    if (ptFreeFlight) o.equiangular = false;
    o.volumeEstimator = estimator;
    o.surfaceEstimator = surfaceEstimator;
    if (timeKernel) o.timeKernel = parseTimeKernel(*timeKernel);
    o.phasor = phasor;
    return o;
}

void RenderOverrides::rejectBeamsOnlyFlags(const std::string& method) const {
    const char* flag = estimator          ? "--estimator"
                       : surfaceEstimator ? "--surface-estimator"
                       : timeKernel       ? "--time-kernel"
                                          : nullptr;
    if (!flag) return;
    throw UserError(std::string(flag) + " applies to the photon-beams estimators only; --method " + method +
                    (method == "pt" ? " is the unbiased path tracer, which has no kernel" : " has no kernel") +
                    ": drop " + flag + " or use --method beams");
}

PreparedRender loadAndBuild(const std::string& path, const RenderOverrides& ov, const LoadOptions& lo) {
    return loadAndBuild(path, ov.settings(), lo);
}

PreparedRender loadAndBuild(const std::string& path, const SettingsOverrides& ov, const LoadOptions& lo) {
    const bool tty = isatty(STDERR_FILENO) && !lo.quiet;
    const double t0 = nowSec();
    double lastPrint = t0 - 9.0;  // not on a terminal: a first line after 1 s, then one every 10 s
    PrepareOptions po;
    po.warn = [](const std::string& w) { std::fprintf(stderr, "warning: %s\n", w.c_str()); };
    po.pilot.photons = 4000;
    po.pilot.control.abort = &interruptFlag();
    po.pilot.control.progress = [&](double f) {
        if (lo.quiet) return;
        const double now = nowSec();
        if (tty) {
            std::fprintf(stderr, "\rfitting the film's time range (pilot pass): %3.0f%%", 100.0 * f);
        } else if (now - lastPrint >= 10.0) {  // a log: lines only when it takes that long
            std::fprintf(stderr, "fitting the film's time range (pilot pass): %.0f%% after %.0f s\n", 100.0 * f,
                         now - t0);
            lastPrint = now;
        }
    };
    PreparedRender p = prepareRender(loadScene(path), ov, po);
    if (p.film.autoRange) {
        if (tty) std::fprintf(stderr, "\r%60s\r", "");
        throwIfInterrupted("while fitting the film's time range (pilot pass)");
        if (!p.fit.fromPilot)
            std::fprintf(stderr, "note: the pilot pass saw no energy; the film keeps the scene-size range\n");
    }
    throwIfInterrupted("while loading the scene");
    return p;
}

nlohmann::json filmJson(const TimeBins& time) {
    return {{"bins", time.bins},
            {"start_opl_m", time.startOpl},
            {"bin_width_opl_m", time.binWidth},
            {"start_ns", time.startOpl / kC_m_per_ns},
            {"bin_width_ns", time.binWidth / kC_m_per_ns}};
}

nlohmann::json summaryHeader(const PreparedRender& p, const char* method, size_t passes, double wallSec,
                             const TransientFilm& film, const ExportOptions& opt) {
    nlohmann::json j;
    j["scene"] = p.source.path;
    j["method"] = method;
    j["passes"] = passes;
    j["wall_seconds"] = wallSec;
    j["resolution"] = {p.scene->camera.width, p.scene->camera.height};
    j["film"] = filmJson(film.time());
    j["film"]["bytes"] = film.bytes();
    j["frames"] = {{"axis", opt.axis == TimeAxis::Real ? "real" : "unwarped"},
                   {"emission", opt.mode == EmissionMode::Delta ? "delta" : "continuous"},
                   {"pulse", pulseName(opt.response)},
                   {"sensor", sensorName(opt.response)},
                   {"time_response", describe(opt.response)},
                   {"counts", countingName(opt.response.counting)},  // film/photon_counting.h
                   {"units", opt.response.counting.enabled ? "counts per bin" : "radiance"},
                   {"step", opt.step}};
    const FilmStats& fs = film.stats;
    nlohmann::json energy = {{"rejected_samples", fs.rejectedSamples.load()},
                             {"overflowed_pixel_sums", fs.overflowedPixels.load()}};
    for (int a = 0; a < 2; ++a) {
        // Luminance shares; continuous frames include `before` (a step response), the last
        // continuous frame is the steady image minus `after`.
        const double in = fs.inside[a].load(), out = fs.outside[a].load(), before = fs.before[a].load();
        const double total = in + out;
        energy[a == 0 ? "real" : "unwarped"] = {{"before_film_fraction", total > 0 ? before / total : 0.0},
                                                {"inside_film_fraction", total > 0 ? in / total : 0.0},
                                                {"after_film_fraction", total > 0 ? (out - before) / total : 0.0}};
    }
    j["film_energy"] = energy;
    return j;
}

int64_t replaceNonFiniteNumbers(nlohmann::json& j) {
    int64_t n = 0;
    if (j.is_number_float() && !std::isfinite(j.get<double>())) {
        const double v = j.get<double>();
        j = std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf";
        return 1;
    }
    if (j.is_structured())
        for (auto& e : j) n += replaceNonFiniteNumbers(e);
    return n;
}

void checkTimeResponseFitsFilm(const std::string& pulse, const std::string& sensor, const TimeBins& time) {
    const TimeResponse p = *parsePulse(pulse), s = *parseSensor(sensor), both = *parseSensor(sensor, p);
    const double span = responseSpanBins(both, time.binWidth);
    if (span <= kMaxResponseBins) return;
    // The spans add (time_response.cpp, support()) and grow linearly with each width, and inversely
    // with the bin width: the widest pulse (sensor) that fits beside the other, the most bins that fit.
    const double pulseSpan = responseSpanBins(p, time.binWidth), sensorSpan = responseSpanBins(s, time.binWidth);
    const auto ns = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%.3g", v);
        return std::string(b);
    };
    std::string what, narrower;
    if (pulseSpan > kMaxResponseBins || sensorSpan <= 0.0) {
        what = "--pulse " + pulse;
        if (sensorSpan < kMaxResponseBins)
            narrower = "a --pulse narrower than " +
                       ns(p.pulseWidth / kC_m_per_ns * (kMaxResponseBins - sensorSpan) / pulseSpan) + " ns";
    } else if (sensorSpan > kMaxResponseBins || pulseSpan <= 0.0) {
        what = "--sensor " + sensor;
        if (pulseSpan < kMaxResponseBins)
            narrower = "a --sensor narrower than " +
                       ns(s.sensorWidth / kC_m_per_ns * (kMaxResponseBins - pulseSpan) / sensorSpan) + " ns";
    } else {
        what = "--pulse " + pulse + " with --sensor " + sensor;
        narrower = "a narrower --pulse or --sensor";
    }
    const double fewerBins = std::floor(time.bins * (kMaxResponseBins / span));
    const std::string wider = fewerBins >= 1.0
                                  ? "wider bins (--bins " + std::to_string(static_cast<long long>(fewerBins)) +
                                        " or fewer, or a longer film time range)"
                                  : "wider bins (a longer film time range with fewer --bins)";
    throw UserError(what + " spans " + ns(span) + " bins of this film (bins of " + ns(time.binWidth / kC_m_per_ns) +
                    " ns); the limit is 1048576 (2^20) bins, beyond which the response's weights are rounding "
                    "noise: use " +
                    wider + (narrower.empty() ? "" : ", or " + narrower));
}

int64_t warnFilmOverflow(const SceneSource& source, const TransientFilm& film) {
    const int64_t n = film.stats.overflowedPixels.load();
    if (n > 0)
        std::fprintf(stderr,
                     "warning: %s: %lld pixel sums would have exceeded the film's float images (max 3.4e38) and "
                     "were dropped from those passes (the film holds no Inf, but those pixels are too dark): lower "
                     "the lights' power (transport is linear: scaling every light by s scales the film by s)\n",
                     source.keyWhere(source.wrote("lights[0]") ? "lights[0].power" : "lights").c_str(),
                     static_cast<long long>(n));
    return n;
}

// ---- the output folder ----------------------------------------------------------------------------

namespace {

constexpr const char* kManifestName = ".tpb-manifest.json";

// A path the manifest may name: relative, inside the folder (no "..", not absolute).
bool safeRelative(const std::string& p) {
    if (p.empty() || p[0] == '/') return false;
    for (const auto& part : fs::path(p))
        if (part == "..") return false;
    return true;
}

// frame_NNNNN.exr -> NNNNN, or -1.
int frameIndex(const std::string& name) {
    if (name.size() < 15 || name.rfind("frame_", 0) != 0 || name.compare(name.size() - 4, 4, ".exr") != 0) return -1;
    int k = 0;
    const auto [ptr, ec] = std::from_chars(name.data() + 6, name.data() + name.size() - 4, k);
    return ec == std::errc() && ptr == name.data() + name.size() - 4 && k >= 0 ? k : -1;
}

// "name" and the temporary files of an interrupted atomic write of it ("name.tmp-<pid>").
std::string baseOfTemporary(const std::string& name) {
    const size_t at = name.rfind(".tmp-");
    return at == std::string::npos ? name : name.substr(0, at);
}

struct PreviousOutputs {
    std::set<std::string> files;  // relative to the folder, no frames
    std::string framesDir;
    int first = 0, last = -1, step = 1;
    bool any() const { return !files.empty() || !framesDir.empty(); }
};

nlohmann::json readJsonFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return nlohmann::json::parse(s.str(), nullptr, /*allow_exceptions=*/false);
}

// What the previous run listed: its manifest, or (a folder written before manifests existed) the
// outputs of a `tpb render` summary.json: its files, the previews and every frame name of its film.
PreviousOutputs previousOutputs(const fs::path& dir) {
    PreviousOutputs prev;
    std::error_code ec;
    if (fs::exists(dir / kManifestName, ec)) {
        const nlohmann::json m = readJsonFile(dir / kManifestName);
        if (!m.is_object()) {
            std::fprintf(stderr, "warning: %s is not readable JSON: ignored (no stale output is removed)\n",
                         (dir / kManifestName).c_str());
            return prev;
        }
        if (m.contains("files") && m["files"].is_array())
            for (const auto& f : m["files"])
                if (f.is_string() && safeRelative(f.get<std::string>())) prev.files.insert(f.get<std::string>());
        if (m.contains("frames") && m["frames"].is_object()) {
            const auto& fr = m["frames"];
            if (fr.value("folder", "").size() && safeRelative(fr.value("folder", "")) && fr.value("step", 1) >= 1) {
                prev.framesDir = fr.value("folder", "");
                prev.first = fr.value("first", 0);
                prev.last = fr.value("last", -1);
                prev.step = fr.value("step", 1);
            }
        }
        return prev;
    }
    if (!fs::exists(dir / kSummaryName, ec)) return prev;
    const nlohmann::json s = readJsonFile(dir / kSummaryName);
    const bool render = s.is_object() && s.contains("outputs") && s["outputs"].is_object() && s.contains("film") &&
                        s["film"].is_object() && s["film"].value("bins", 0) > 0 && s.contains("method");
    if (!render) return prev;
    const auto& files = s["outputs"].value("files", nlohmann::json::array());
    bool frames = false;
    for (const auto& f : files) {
        if (!f.is_string()) continue;
        const std::string name = f.get<std::string>();
        if (name.rfind("frames/", 0) == 0)
            frames = true;
        else if (safeRelative(name) && name.find('/') == std::string::npos)
            prev.files.insert(name);
    }
    prev.files.insert(kPreviewExrName);
    prev.files.insert(kPreviewPngName);
    prev.files.insert(kSummaryName);
    if (frames) {
        prev.framesDir = "frames";
        prev.first = 0;
        prev.last = s["film"].value("bins", 0) - 1;
        prev.step = 1;
    }
    return prev;
}

// Removes the previous run's files (and their leftover temporaries); returns what was removed.
std::vector<std::string> removeOutputs(const fs::path& dir, const PreviousOutputs& prev) {
    std::vector<std::string> removed;
    std::error_code ec;
    const auto removeIf = [&](const fs::path& folder, const std::string& rel, const std::string& name, bool listed) {
        if (!listed) return;
        const fs::path p = folder / name;
        const fs::file_status st = fs::symlink_status(p, ec);
        if (ec || !(fs::is_regular_file(st) || fs::is_symlink(st))) return;  // never a folder
        if (fs::remove(p, ec)) removed.push_back(rel);
    };
    // Top-level files, and files in subfolders the manifest names (none today but frames).
    std::set<fs::path> folders{fs::path()};
    for (const std::string& f : prev.files) folders.insert(fs::path(f).parent_path());
    for (const fs::path& sub : folders) {
        const fs::path folder = dir / sub;
        if (!fs::is_directory(folder, ec)) continue;
        std::vector<std::string> names;
        for (const fs::directory_entry& e : fs::directory_iterator(folder, ec))
            names.push_back(e.path().filename().string());
        for (const std::string& name : names) {
            const std::string rel = (sub / baseOfTemporary(name)).generic_string();
            removeIf(folder, (sub / name).generic_string(), name, prev.files.count(rel) > 0);
        }
    }
    if (!prev.framesDir.empty()) {
        const fs::path folder = dir / prev.framesDir;
        if (fs::is_directory(folder, ec)) {
            std::vector<std::string> names;
            for (const fs::directory_entry& e : fs::directory_iterator(folder, ec))
                names.push_back(e.path().filename().string());
            for (const std::string& name : names) {
                const int k = frameIndex(baseOfTemporary(name));
                const bool listed = k >= prev.first && k <= prev.last && (k - prev.first) % prev.step == 0;
                removeIf(folder, prev.framesDir + "/" + name, name, listed);
            }
            if (fs::is_empty(folder, ec)) fs::remove(folder, ec);  // only when nothing else is in it
        }
    }
    return removed;
}

bool listed(const std::vector<std::string>& names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
}

// Throws a UserError when the folder holds a checkpoint that this run would remove (the previous
// run's manifest lists it) or could overwrite (this run lists it), unless kept or replaced on request.
void refuseToLoseCheckpoint(const std::string& dir, const std::string& command, const OutputFiles& outputs,
                            const PreviousOutputs& prev) {
    const fs::path path = fs::path(dir) / kCheckpointFile;
    std::error_code ec;
    if (outputs.replaceCheckpoint || listed(outputs.keep, kCheckpointFile) || !fs::is_regular_file(path, ec)) return;
    const bool removes = prev.files.count(kCheckpointFile) > 0, overwrites = listed(outputs.files, kCheckpointFile);
    if (!removes && !overwrites) return;
    std::string what;
    try {
        const CheckpointInfo info = readCheckpointInfo(path.string());
        what = "holds the checkpoint of an earlier render (" + std::to_string(info.passes) + " passes of " +
               info.scene + ", written " + info.created + ")";
    } catch (const UserError& e) {
        what = "holds a checkpoint that cannot be read (" + std::string(e.what()) + ")";
    }
    throw UserError(path.string(), 0, "",
                    what + ", which this tpb " + command + " would " + (removes ? "remove" : "overwrite") +
                        "; a checkpoint is never discarded silently: " +
                        (outputs.checkpointAdvice.empty() ? "" : outputs.checkpointAdvice + ", ") +
                        "give this run another folder with -o" +
                        (command == "render" ? ", or add --overwrite-checkpoint to discard it"
                                             : ", or move the checkpoint out of the folder"));
}

}  // namespace

OutputFolder::OutputFolder(const std::string& dir, const std::string& command, const OutputFiles& outputs)
    : dir_(dir), lock_(FolderLock::acquire(dir, "tpb " + command)) {
    PreviousOutputs prev = previousOutputs(dir);
    for (const std::string& k : outputs.keep) prev.files.erase(k);  // a resume's checkpoint (cli/resume.h)
    refuseToLoseCheckpoint(dir, command, outputs, prev);
    removed_ = removeOutputs(dir, prev);

    nlohmann::json m;
    m["written_by"] = "tpb " + command;
    m["pid"] = ::getpid();
    m["files"] = outputs.files;
    if (!outputs.framesDir.empty())
        m["frames"] = {{"folder", outputs.framesDir},
                       {"first", outputs.firstBin},
                       {"last", outputs.lastBin},
                       {"step", outputs.binStep}};
    m["note"] = "the files the last tpb run wrote into this folder; the next run removes them first";
    writeTextFile((fs::path(dir) / kManifestName).string(), m.dump(2) + "\n");
}

OutputFolder::~OutputFolder() = default;  // releases the lock (lock_)

namespace {

// backprojection.npy (nx, ny, nz float32) and backprojection.json (its grid, its peak, its cost).
void writeBackprojection(const std::string& out, const NlosCapture& cap, const BackprojectionSettings& s, bool quiet) {
    const double t0 = nowSec();
    const BackprojectionVolume vol = backproject(cap, s);
    const double sec = nowSec() - t0;
    const BackprojectionGrid& g = vol.grid;
    writeNpy(out + "/" + kBackprojectionNpyName, {g.nx(), g.ny(), g.nz()}, vol.values);
    using nlohmann::json;
    auto vec = [](const Vec3& v) { return json::array({v.x, v.y, v.z}); };
    json j;
    j["about"] =
        "backprojection.npy: (nx, ny, nz) float32, the sum over (laser, sensor) pairs of the capture's H "
        "(luminance) at t(x) = |l - x| + |x - s| (+ the first and last legs when the capture's time counts "
        "them), then the filter; voxel (i, j, k) = origin + a[i] u + b[j] v + depths_m[k] normal";
    j["filter"] = backprojectionFilterName(vol.filter);
    j["origin"] = vec(g.origin);
    j["u"] = vec(g.u);
    j["v"] = vec(g.v);
    j["normal"] = vec(g.normal);
    j["a_m"] = g.a;
    j["b_m"] = g.b;
    j["depths_m"] = g.depthsM;
    j["peak"] = {{"voxel", {vol.peakI, vol.peakJ, vol.peakK}},
                 {"position_m", vec(g.voxel(vol.peakI, vol.peakJ, vol.peakK))},
                 {"depth_m", g.depthsM[static_cast<size_t>(vol.peakK)]},
                 {"value", vol.peakValue}};
    j["voxels"] = g.voxels();
    j["pairs"] = backprojectionPairs(cap);
    j["seconds"] = sec;
    writeTextFile(out + "/" + kBackprojectionJsonName, j.dump(2) + "\n");
    if (!quiet)
        std::printf("back-projected %lld voxels x %lld pairs in %.3f s: peak at depth %.3f m\n",
                    static_cast<long long>(g.voxels()), static_cast<long long>(backprojectionPairs(cap)), sec,
                    g.depthsM[static_cast<size_t>(vol.peakK)]);
}

}  // namespace

OutputFiles renderOutputFiles(const RenderOutputs& r, int bins) {
    OutputFiles f;
    f.files = {kPreviewExrName, kPreviewPngName, kSteadyExrName, kSteadyPngName, kSummaryName};
    if (r.strip > 0) f.files.push_back(kStripName);
    if (r.captureScene) f.files.push_back(kCaptureH5Name);
    if (r.phasor)
        for (const std::string& n : phasorFileNames()) f.files.push_back(n);
    if (r.captureScene && r.backproject) {
        f.files.push_back(kBackprojectionNpyName);
        f.files.push_back(kBackprojectionJsonName);
    }
    if (r.npy)
        for (const std::string& n : volumeFileNames()) f.files.push_back(n);
    if (r.contactSheet > 0) f.files.push_back(contactSheetName());
    if (r.mp4) f.files.push_back(mp4Name());
    const int frames = exportFrameCount(bins, r.opt);
    if (!r.noFrames && frames > 0) {
        f.framesDir = "frames";
        f.firstBin = r.opt.firstBin;
        f.binStep = std::max(1, r.opt.step);
        f.lastBin = r.opt.firstBin + (frames - 1) * f.binStep;
    }
    return f;
}

std::string writtenLine(const RenderOutputs& r, const OutputReport& rep) {
    const char* axis = r.opt.axis == TimeAxis::Real ? "real time" : "unwarped";
    const char* mode = r.opt.mode == EmissionMode::Delta ? "delta" : "continuous";
    if (!r.noFrames)
        return "wrote " + std::to_string(rep.framesWritten) + " frames (" + axis + ", " + mode + ") to " + r.out +
               "/frames, steady.exr, summary.json";
    std::string files;
    for (const std::string& f : rep.kept) files += (files.empty() ? "" : ", ") + f;
    return "wrote no frames (--no-frames): " + files + " in " + r.out;
}

std::string percentText(double fraction) {
    const double p = 100.0 * fraction;
    char b[32];
    std::snprintf(b, sizeof b, p >= 9.95 ? "%.0f" : "%.2g", p);
    return b;
}

void reportPlannedOutputs(const PreparedRender& p, const RenderOutputs& r, double previewExrSec) {
    if (r.noFrames) return;
    const Scene& scene = *p.scene;
    const uint64_t frames = static_cast<uint64_t>(exportFrameCount(p.time.bins, r.opt));
    const uint64_t perFrame =
        static_cast<uint64_t>(scene.camera.width) * scene.camera.height * 3 * (r.opt.pixel == ExrPixel::Half ? 2 : 4);
    const uint64_t need = frames * perFrame;
    const double writeSec = static_cast<double>(frames) * previewExrSec;
    if (!r.quiet) {
        const bool large = writeSec > 60.0 || need > (uint64_t(1) << 30);
        const auto about = [](double sec) {
            return sec < 0.1 ? std::string("under 0.1 s") : "about " + humanSeconds(sec);
        };
        std::printf(
            "frames: %llu EXR files of %dx%d (%s), up to %s uncompressed; writing them will take %s after "
            "the render (estimated from preview.exr: %s)%s\n",
            static_cast<unsigned long long>(frames), scene.camera.width, scene.camera.height,
            r.opt.pixel == ExrPixel::Half ? "half" : "float", humanBytes(need).c_str(), about(writeSec).c_str(),
            previewExrSec < 0.1 ? "under 0.1 s" : humanSeconds(previewExrSec).c_str(),
            large ? "; --frame-step K, --half or --no-frames write less" : "");
        std::fflush(stdout);
    }
    struct statvfs fsInfo {};
    if (::statvfs(r.out.c_str(), &fsInfo) != 0) return;
    const uint64_t freeBytes = static_cast<uint64_t>(fsInfo.f_bavail) * fsInfo.f_frsize;
    if (need > freeBytes)
        std::fprintf(stderr,
                     "warning: %llu frames take up to %s uncompressed and %s has only %s free; they are "
                     "compressed and may still fit, otherwise use --half, --frame-step, --no-frames or another -o\n",
                     static_cast<unsigned long long>(frames), humanBytes(need).c_str(), r.out.c_str(),
                     humanBytes(freeBytes).c_str());
}

namespace {

// A progress bar on a terminal, a line every 10 s in a log.
class ExportProgress {
public:
    ExportProgress(const char* what, bool tty, bool quiet)
        : what_(what), tty_(tty), quiet_(quiet), t0_(nowSec()), last_(t0_) {}
    ~ExportProgress() {
        if (tty_ && shown_) std::fprintf(stderr, "\n");
    }
    void operator()(int done, int total) {
        if (tty_) {
            const int width = 30, fill = total > 0 ? static_cast<int>(30.0 * done / total) : 0;
            std::fprintf(stderr, "\r%s [%.*s%*s] %d/%d", what_, fill, "##############################", width - fill,
                         "", done, total);
            shown_ = true;
        } else if (!quiet_ && nowSec() - last_ >= 10.0) {
            last_ = nowSec();
            std::fprintf(stderr, "%s: %d/%d after %.0f s\n", what_, done, total, last_ - t0_);
        }
    }

private:
    const char* what_;
    bool tty_, quiet_, shown_ = false;
    double t0_, last_;
};

// transient.npy & co, contact_sheet.png, transient.mp4, after the frames and the strip. A first
// signal stops the one being written (it leaves no file) and the ones after it.
void writePictureOutputs(const FilmSnapshot& snap, const RenderOutputs& r, OutputReport& rep,
                         const std::atomic<bool>* cancel, bool tty) {
    const auto stopped = [&](const std::string& what) {
        if (!(cancel && cancel->load())) return false;
        rep.interrupted = true;
        if (rep.error.empty()) rep.error = "interrupted by " + interruptName() + " while writing " + what;
        return true;
    };
    if (r.npy && !rep.interrupted) {
        std::vector<std::string> names;
        {
            ExportProgress bar("writing transient.npy (rows)", tty, r.quiet);
            names = exportVolumeNpy(snap, r.out, r.opt, r.provenance, std::ref(bar), cancel);
        }
        rep.kept.insert(rep.kept.end(), names.begin(), names.end());
        stopped("transient.npy");
    }
    const bool needTone = (r.contactSheet > 0 || r.mp4) && !rep.interrupted;
    const ToneMap tone = needTone ? autoExposedToneMap(snap, r.opt, r.tone) : r.tone;
    if (r.contactSheet > 0 && !rep.interrupted) {
        exportContactSheet(snap, r.out + "/" + contactSheetName(), r.contactSheet, r.opt, tone);
        rep.kept.push_back(contactSheetName());
        rep.exposureEv.emplace_back(contactSheetName(), tone.exposureEv);
    }
    if (r.mp4 && !rep.interrupted) {
        int n = 0;
        {
            ExportProgress bar("encoding transient.mp4", tty, r.quiet);
            n = exportMp4(snap, r.out + "/" + mp4Name(), r.opt, tone, r.fps, std::ref(bar), cancel);
        }
        if (!stopped(mp4Name()) && n > 0) {
            rep.kept.push_back(mp4Name());
            rep.exposureEv.emplace_back(mp4Name(), tone.exposureEv);
        }
    }
}

}  // namespace

OutputReport writeRenderOutputs(const TransientFilm& film, const RenderOutputs& r,
                                const std::function<nlohmann::json()>& summary) {
    // Every output from one snapshot: the same passes in each file.
    const std::shared_ptr<const FilmSnapshot> snap = film.snapshot();
    OutputReport rep;
    const bool tty = isatty(STDERR_FILENO) && !r.quiet;
    if (!r.noFrames) rep.framesExpected = exportFrameCount(film.bins(), r.opt);
    const auto writeSummary = [&](bool final) {
        nlohmann::json j = summary();
        replaceNonFiniteNumbers(j);
        nlohmann::json o = {{"frames_expected", rep.framesExpected}, {"files", rep.kept}};
        nlohmann::json ev = nlohmann::json::object();
        if (r.previewEv) ev["preview.png"] = *r.previewEv;
        for (const auto& [name, e] : rep.exposureEv) ev[name] = e;
        o["exposure_ev"] = ev;
        if (final)
            o["frames_written"] = rep.framesWritten;
        else
            o["frames_written"] = nullptr;  // being written: the final summary replaces this one
        if (!rep.error.empty()) o["error"] = rep.error;
        j["outputs"] = o;
        writeTextFile(r.out + "/summary.json", j.dump(2) + "\n");
    };

    {
        const std::vector<float> steady = steadyImage(*snap);  // one image for both files
        writeExr(r.out + "/" + kSteadyExrName, film.width(), film.height(), steady, r.opt.pixel);
        rep.kept.push_back(kSteadyExrName);
        const float ev =
            writeAutoExposedPng(r.out + "/" + kSteadyPngName, film.width(), film.height(), steady, ToneMap{});
        rep.kept.push_back(kSteadyPngName);
        rep.exposureEv.emplace_back(kSteadyPngName, ev);
    }
    if (r.captureScene) {
        const NlosCapture cap = nlosCapture(*snap, *r.captureScene, r.provenance.scene, r.opt.response);
        writeNlosHdf5(r.out + "/" + kCaptureH5Name, cap);
        rep.kept.push_back(kCaptureH5Name);
        if (r.backproject) {
            writeBackprojection(r.out, cap, *r.backproject, r.quiet);
            rep.kept.push_back(kBackprojectionNpyName);
            rep.kept.push_back(kBackprojectionJsonName);
        }
    }
    rep.kept.push_back(kSummaryName);
    writeSummary(false);

    // A first signal during the export stops it after the frame in progress. If the render was
    // already interrupted, the flag is set: the export runs to the end, and a second signal quits.
    const std::atomic<bool>* cancel = interrupted() ? nullptr : &interruptFlag();
    bool internal = false;  // the export failed on a bug (exit code 1), not on the user's input or disk
    try {
        // The phasor film first (small): a failure is recorded in the summary like a frame's.
        if (r.phasor)
            for (const std::string& n : exportPhasorNpy(*snap, r.out, r.opt, r.provenance)) rep.kept.push_back(n);
        if (!r.noFrames) {
            const double t0 = nowSec();
            double lastPrint = t0;
            exportFrames(
                *snap, r.out + "/frames", r.opt,
                [&](int done, int total) {
                    rep.framesWritten = done;
                    if (tty) {
                        std::fprintf(stderr, "\rwriting frames %d/%d", done, total);
                    } else if (!r.quiet && nowSec() - lastPrint >= 10.0) {
                        lastPrint = nowSec();
                        std::fprintf(stderr, "writing frames: %d/%d after %.0f s\n", done, total, lastPrint - t0);
                    }
                },
                cancel);
            if (tty) std::fprintf(stderr, "\n");
            if (rep.framesWritten > 0) rep.kept.push_back("frames/");
            if (cancel && cancel->load() && rep.framesWritten < rep.framesExpected) {
                rep.interrupted = true;
                rep.error = "interrupted by " + interruptName() + " while writing the frames";
            }
        }
        if (r.strip > 0 && !rep.interrupted) {
            ToneMap stripTone;  // the frames' exposure rule (picture_export.h), sRGB, --strip-ev more
            stripTone.exposureEv = static_cast<float>(r.stripEv);
            stripTone = autoExposedToneMap(*snap, r.opt, stripTone);
            exportStripPng(*snap, r.out + "/strip.png", r.strip, r.opt, stripTone);
            rep.kept.push_back(kStripName);
            rep.exposureEv.emplace_back(kStripName, stripTone.exposureEv);
        }
        writePictureOutputs(*snap, r, rep, cancel, tty);
    } catch (const std::exception& e) {
        // A user error (a full disk, ...) or a bug: either way the finished film's steady image and
        // summary stay, with the frames written so far, and the summary says what failed.
        if (tty) std::fprintf(stderr, "\n");
        const bool user = dynamic_cast<const UserError*>(&e) != nullptr;
        rep.error = user ? e.what() : std::string("internal error while writing the outputs: ") + e.what();
        internal = !user;
        if (rep.framesWritten > 0 && rep.framesWritten < rep.framesExpected) rep.kept.push_back("frames/ (partial)");
    }
    if (rep.interrupted && rep.framesWritten > 0 && rep.framesWritten < rep.framesExpected)
        std::replace(rep.kept.begin(), rep.kept.end(), std::string("frames/"), std::string("frames/ (partial)"));
    try {
        writeSummary(true);
    } catch (const UserError&) {
        if (rep.error.empty()) throw;
        // The first summary.json stays (its frames_written is null: frames were being written).
    }
    if (!rep.error.empty()) {
        std::string kept;
        for (const std::string& k : rep.kept) kept += (kept.empty() ? "" : ", ") + k;
        std::fprintf(stderr, "error: %s\nkept in %s (complete files only): %s; %d of %d frames\n", rep.error.c_str(),
                     r.out.c_str(), kept.c_str(), rep.framesWritten, rep.framesExpected);
        exitCode() = rep.interrupted ? 128 + interruptSignal() : internal ? 1 : kExitUserError;
    }
    return rep;
}

double checkEnergyInsideFilm(const PreparedRender& p, const TransientFilm& film, TimeAxis axis) {
    const int a = axis == TimeAxis::Real ? 0 : 1;
    const double in = film.stats.inside[a].load(), out = film.stats.outside[a].load();
    if (!(in + out > 0.0)) return 0.0;
    const double fraction = out / (in + out);
    const TimeBins& t = film.time();
    const char* axisName = axis == TimeAxis::Real ? "real-time" : "unwarped";
    const SceneSource& d = p.source;
    const std::string key = d.wrote("film.start_m")        ? "film.start_m"
                            : d.wrote("film.start_ns")     ? "film.start_ns"
                            : d.wrote("film.bin_width_m")  ? "film.bin_width_m"
                            : d.wrote("film.bin_width_ns") ? "film.bin_width_ns"
                                                           : "film";
    char range[160];
    std::snprintf(range, sizeof range, "%.4g to %.4g m OPL (%.4g to %.4g ns)", t.startOpl, t.endOpl(),
                  t.startOpl / kC_m_per_ns, t.endOpl() / kC_m_per_ns);
    if (in > 0.0 && fraction <= kOutsideWarnFraction) return fraction;
    if (in > 0.0) {
        // The advice depends on who chose the range: the file's keys, or the pilot ("range": "auto",
        // which keeps 98% of the arrivals it measured, so more missing means a tail it did not see).
        const double before = film.stats.before[a].load();
        const char* side = before > 0.5 * out ? "before its start" : "after its end";
        const std::string fixIt =
            p.film.autoRange
                ? std::string(
                      "the range is already automatic (\"range\": \"auto\" fits it to the arrivals a pilot "
                      "pass measured) and most of the rest arrived ") +
                      side + ": set a fixed range that covers it with film.start_m and film.bin_width_m (and bins)"
                : std::string("most of it arrived ") + side +
                      ": fit the range with \"film\": {\"range\": \"auto\"} or widen start_m/bin_width_m (or bins)";
        std::fprintf(stderr,
                     "warning: %s: %.1f%% of the energy that reached the camera arrived outside the film's time range, "
                     "%s on the %s axis: the frames miss it; %s\n",
                     d.keyWhere(key).c_str(), 100.0 * fraction, range, axisName, fixIt.c_str());
        return fraction;
    }
    // Every frame is black. Measure where the energy arrives, to say which range would hold it.
    std::string fix = p.film.autoRange ? "the range is already automatic and its pilot saw no light: set a fixed "
                                         "range with film.start_m and film.bin_width_m"
                                       : "use \"film\": {\"range\": \"auto\"} to fit it to the scene";
    PilotControl pc;
    pc.abort = &interruptFlag();
    const TimeRangeFit fit = measureArrivalRange(*p.scene, p.pilotSettings, 4000, pc);
    if (fit.fromPilot) {
        char b[400];
        std::snprintf(b, sizeof b,
                      "a pilot pass measured arrivals from %.4g to %.4g m OPL: set \"film\": {\"start_m\": %.4g, "
                      "\"bin_width_m\": %.4g} to cover them with the same %d bins%s",
                      fit.startOpl, fit.endOpl, fit.startOpl, (fit.endOpl - fit.startOpl) / t.bins, t.bins,
                      p.film.autoRange ? "" : ", or \"range\": \"auto\" to fit the range automatically");
        fix = b;
    }
    std::fprintf(stderr,
                 "error: %s: every frame is black: all the energy that reached the camera arrived outside the film's "
                 "time range, %s on the %s axis; %s (the outputs were written)\n",
                 d.keyWhere(key).c_str(), range, axisName, fix.c_str());
    if (exitCode() == 0) exitCode() = kExitUserError;
    return fraction;
}

}  // namespace tpb::app
