// Checkpoints (see checkpoint.h for the format and the guarantees).
#include "render/checkpoint.h"

#include "base/text.h"

#include "base/error.h"
#include "io/film_container.h"

#include <nlohmann/json.hpp>

#include <bit>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>

namespace tpb {

static_assert(std::endian::native == std::endian::little, "the checkpoint format is little-endian");

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr char kMagic[9] = "TPBCKPT\n";
constexpr const char* kFormat = "tpb-checkpoint";
constexpr int kVersion = 1;

// A 64-bit hash of a byte stream taken 8 bytes at a time (FNV-1a's step on words): fast enough
// for a 12 GiB film (one multiply per 8 bytes), and any flipped or lost word changes it.
json colorJson(const Color& c) { return {c.x, c.y, c.z}; }
Color colorFrom(const json& j) { return Color(j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()); }

json tallyJson(const FilmTally& t) {
    return {{"rejected", t.rejected},
            {"outside", {t.outside[0], t.outside[1]}},
            {"before", {t.before[0], t.before[1]}},
            {"inside", {t.inside[0], t.inside[1]}},
            {"bins_splatted", t.binsSplatted}};
}
void tallyFrom(const json& j, FilmTally& t) {
    t.rejected = j.at("rejected").get<int64_t>();
    for (int a = 0; a < 2; ++a) {
        t.outside[a] = j.at("outside").at(a).get<double>();
        t.before[a] = j.at("before").at(a).get<double>();
        t.inside[a] = j.at("inside").at(a).get<double>();
    }
    t.binsSplatted = j.at("bins_splatted").get<int64_t>();
}

json passJson(const PassStats& p) {
    json c = tallyJson(p.camera);
    c["camera_rays"] = p.camera.cameraRays;
    c["beam_estimates"] = p.camera.beamEstimates;
    c["photon_estimates"] = p.camera.photonEstimates;
    c["region_overflows"] = p.camera.regionOverflows;
    json t = tallyJson(p.paths);
    t["camera_paths"] = p.paths.cameraPaths;
    t["contributions"] = p.paths.contributions;
    t["shadow_rays"] = p.paths.shadowRays;
    t["laser_samples"] = p.paths.laserSamples;
    t["equiangular_samples"] = p.paths.equiangularSamples;
    t["depth_limited"] = p.paths.depthLimited;
    t["region_overflows"] = p.paths.regionOverflows;
    return {{"pass", p.pass},
            {"beam_radius_m", p.beamRadius},
            {"surface_radius_m", p.surfaceRadius},
            {"volume_time_half_width_m", p.volumeTimeHalfWidth},
            {"surface_time_half_width_m", p.surfaceTimeHalfWidth},
            {"photons", p.photons},
            {"beams", p.beams},
            {"beam_pieces", p.beamPieces},
            {"surface_photons", p.surfacePhotons},
            {"points", p.points},
            {"emitted_flux", colorJson(p.emittedFlux)},
            {"cut_flux", colorJson(p.cutFlux)},
            {"region_overflows", p.regionOverflows},
            {"camera", c},
            {"paths", t},
            {"film", tallyJson(p.film)},
            {"photon_s", p.photonSec},
            {"build_s", p.buildSec},
            {"camera_s", p.cameraSec},
            {"pass_s", p.passSec},
            {"elapsed_s", p.elapsedSec},
            {"peak_rss_bytes", p.peakRssBytes}};
}
PassStats passFrom(const json& j) {
    PassStats p;
    p.pass = j.at("pass").get<uint64_t>();
    p.beamRadius = j.at("beam_radius_m").get<double>();
    p.surfaceRadius = j.at("surface_radius_m").get<double>();
    p.volumeTimeHalfWidth = j.at("volume_time_half_width_m").get<double>();
    p.surfaceTimeHalfWidth = j.at("surface_time_half_width_m").get<double>();
    p.photons = j.at("photons").get<int64_t>();
    p.beams = j.at("beams").get<int64_t>();
    p.beamPieces = j.at("beam_pieces").get<int64_t>();
    p.surfacePhotons = j.at("surface_photons").get<int64_t>();
    p.points = j.at("points").get<int64_t>();
    p.emittedFlux = colorFrom(j.at("emitted_flux"));
    p.cutFlux = colorFrom(j.at("cut_flux"));
    p.regionOverflows = j.at("region_overflows").get<int64_t>();
    const json& c = j.at("camera");
    tallyFrom(c, p.camera);
    p.camera.cameraRays = c.at("camera_rays").get<int64_t>();
    p.camera.beamEstimates = c.at("beam_estimates").get<int64_t>();
    p.camera.photonEstimates = c.at("photon_estimates").get<int64_t>();
    p.camera.regionOverflows = c.at("region_overflows").get<int64_t>();
    const json& t = j.at("paths");
    tallyFrom(t, p.paths);
    p.paths.cameraPaths = t.at("camera_paths").get<int64_t>();
    p.paths.contributions = t.at("contributions").get<int64_t>();
    p.paths.shadowRays = t.at("shadow_rays").get<int64_t>();
    p.paths.laserSamples = t.at("laser_samples").get<int64_t>();
    p.paths.equiangularSamples = t.at("equiangular_samples").get<int64_t>();
    p.paths.depthLimited = t.at("depth_limited").get<int64_t>();
    p.paths.regionOverflows = t.at("region_overflows").get<int64_t>();
    tallyFrom(j.at("film"), p.film);
    p.photonSec = j.at("photon_s").get<double>();
    p.buildSec = j.at("build_s").get<double>();
    p.cameraSec = j.at("camera_s").get<double>();
    p.passSec = j.at("pass_s").get<double>();
    p.elapsedSec = j.at("elapsed_s").get<double>();
    p.peakRssBytes = j.at("peak_rss_bytes").get<uint64_t>();
    return p;
}

// ---- the command-line overrides ------------------------------------------------------------------
const char* profileName(TimeProfile p) { return p == TimeProfile::Exact ? "exact" : "uniform"; }
const char* lengthName(BeamLength b) { return b == BeamLength::Short ? "short" : "long"; }
const char* accelName(AccelBackend a) { return a == AccelBackend::BruteForce ? "brute" : accelBackendName(a); }

json overridesJson(const SettingsOverrides& o) {
    json j = json::object();
    auto put = [&](const char* k, const auto& v) {
        if (v) j[k] = *v;
    };
    if (o.method) j["method"] = methodName(*o.method);
    put("passes", o.passes);
    put("photons", o.photons);
    put("warmup", o.warmup);
    put("time", o.timeBudget);
    put("radius", o.radius);
    put("surface_radius", o.surfaceRadius);
    if (o.autoRadius) j["auto_radius"] = true;
    put("alpha", o.alpha);
    put("threads", o.threads);
    put("max_depth", o.maxDepth);
    put("spp", o.samplesPerPixel);
    put("seed", o.seed);
    if (o.profile) j["profile"] = profileName(*o.profile);
    if (o.beamLength) j["beam_length"] = lengthName(*o.beamLength);
    if (o.accel) j["accel"] = accelName(*o.accel);
    put("equiangular", o.equiangular);
    put("estimator", o.volumeEstimator);
    put("surface_estimator", o.surfaceEstimator);
    if (o.timeKernel) j["time_kernel"] = timeKernelName(*o.timeKernel);
    put("phasor", o.phasor);
    put("width", o.width);
    put("height", o.height);
    put("bins", o.bins);
    return j;
}
SettingsOverrides overridesFrom(const json& j) {
    SettingsOverrides o;
    auto get = [&](const char* k, auto& v) {
        if (j.contains(k)) v = j.at(k).get<typename std::remove_reference_t<decltype(v)>::value_type>();
    };
    if (j.contains("method")) o.method = parseMethod(j.at("method").get<std::string>());
    get("passes", o.passes);
    get("photons", o.photons);
    get("warmup", o.warmup);
    get("time", o.timeBudget);
    get("radius", o.radius);
    get("surface_radius", o.surfaceRadius);
    o.autoRadius = j.value("auto_radius", false);
    get("alpha", o.alpha);
    get("threads", o.threads);
    get("max_depth", o.maxDepth);
    get("spp", o.samplesPerPixel);
    get("seed", o.seed);
    if (j.contains("profile")) o.profile = j.at("profile") == "exact" ? TimeProfile::Exact : TimeProfile::Uniform;
    if (j.contains("beam_length")) o.beamLength = j.at("beam_length") == "short" ? BeamLength::Short : BeamLength::Long;
    if (j.contains("accel")) o.accel = parseAccelBackend(j.at("accel").get<std::string>()).value_or(AccelBackend::Bvh);
    get("equiangular", o.equiangular);
    get("estimator", o.volumeEstimator);
    get("surface_estimator", o.surfaceEstimator);
    if (j.contains("time_kernel")) o.timeKernel = parseTimeKernel(j.at("time_kernel").get<std::string>());
    get("phasor", o.phasor);
    get("width", o.width);
    get("height", o.height);
    get("bins", o.bins);
    return o;
}

std::string utcNow() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char b[32];
    std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return b;
}

uint64_t payloadBytes(const FilmLayout& layout) {
    uint64_t n = 0;
    for (size_t t = 0; t < layout.tiles.size(); ++t) {
        const uint64_t px = layout.pixels(static_cast<int>(t));
        n += 16 + 8 * (px * 3 * 5 + 2 * px * static_cast<uint64_t>(layout.time.bins) * 3 +
                       2 * px * static_cast<uint64_t>(layout.phasor.count()) * 6);
    }
    return n;
}

[[noreturn]] void bad(const std::string& path, const std::string& why) {
    throw UserError(path + ": not a usable tpb checkpoint: " + why +
                    " (write a new one with tpb render --checkpoint, or render without --resume)");
}

struct Opened {
    std::unique_ptr<FilmContainerReader> in;
    json header;
};

Opened openCheckpoint(const std::string& path) {
    Opened o;
    o.in = std::make_unique<FilmContainerReader>(path, std::string_view(kMagic, 8),
                                                 [path](const std::string& why) { bad(path, why); });
    if (!o.in->opened())
        throw UserError(path + ": cannot open the checkpoint: " + std::strerror(errno) +
                        " (resume from the folder of a render that wrote " + kCheckpointFile + ")");
    try {
        o.header = json::parse(o.in->header());
    } catch (const std::exception& e) {
        bad(path, std::string("header is not JSON (") + e.what() + ")");
    }
    if (o.header.value("format", "") != kFormat) bad(path, "format is not \"tpb-checkpoint\"");
    if (o.header.value("version", 0) != kVersion)
        bad(path, "version " + std::to_string(o.header.value("version", 0)) + ", this tpb reads version 1");
    if (o.header.value("byte_order", "") != "little") bad(path, "byte order is not little-endian");
    const uint64_t payload = o.header.value("payload_bytes", uint64_t(0));
    const uint64_t size = o.in->fileBytes();
    if (size != o.in->payloadOffset() + payload + 8)
        bad(path, "the file has " + std::to_string(size) + " bytes, its header announces " +
                      std::to_string(o.in->payloadOffset() + payload + 8) + " (truncated or cut while copying)");
    return o;
}

CheckpointInfo infoFrom(const std::string& path, const json& h) {
    CheckpointInfo i;
    try {
        i.scene = h.at("scene").get<std::string>();
        i.created = h.at("created").get<std::string>();
        i.passes = h.at("passes").get<uint64_t>();
        i.width = h.at("width").get<int>();
        i.height = h.at("height").get<int>();
        i.time.bins = h.at("time").at("bins").get<int>();
        i.time.startOpl = h.at("time").at("start_opl_m").get<double>();
        i.time.binWidth = h.at("time").at("bin_width_opl_m").get<double>();
        if (h.contains("phasor")) {
            i.phasor.frequencies = h.at("phasor").at("frequencies_per_m").get<std::vector<double>>();
            i.phasor.refOpl = h.at("phasor").at("reference_opl_m").get<double>();
        }
        for (const json& kv : h.at("fingerprint"))
            i.fingerprint.emplace_back(kv.at(0).get<std::string>(), kv.at(1).get<std::string>());
        i.overrides = overridesFrom(h.at("overrides"));
    } catch (const std::exception& e) {
        bad(path, std::string("header field missing or of the wrong type (") + e.what() + ")");
    }
    if (i.width < 1 || i.height < 1 || i.time.bins < 1 || !(i.time.binWidth > 0.0))
        bad(path, "film size or time axis out of range");
    for (double f : i.phasor.frequencies)
        if (!(f >= 0.0 && f <= 1e6)) bad(path, "phasor frequency out of range");
    const FilmLayout layout(i.width, i.height, i.time, i.phasor);
    if (h.value("payload_bytes", uint64_t(0)) != payloadBytes(layout))
        bad(path, "payload size does not match its " + std::to_string(i.width) + "x" + std::to_string(i.height) + "x" +
                      std::to_string(i.time.bins) + " film");
    return i;
}

}  // namespace

void writeCheckpoint(const std::string& path, const CheckpointInfo& info, const TransientFilm& film,
                     const std::vector<PassStats>& history) {
    const std::shared_ptr<const FilmSnapshot> snap = film.snapshot();
    if (snap->minPasses() != static_cast<int64_t>(info.passes) ||
        snap->maxPasses() != static_cast<int64_t>(info.passes))
        throw UserError(path + ": no checkpoint written: the film's tiles hold " + std::to_string(snap->minPasses()) +
                        " to " + std::to_string(snap->maxPasses()) + " passes, not " + std::to_string(info.passes) +
                        " each (a pass was cut short); the last checkpoint, if any, is kept");
    const FilmLayout layout(film.width(), film.height(), film.time(), film.phasor());
    json h;
    h["format"] = kFormat;
    h["version"] = kVersion;
    h["byte_order"] = "little";
    h["scene"] = info.scene;
    h["created"] = info.created.empty() ? utcNow() : info.created;
    h["passes"] = info.passes;
    // The passes' summed weight (TileSums::weight; below `passes` after a warm-up), the same in
    // every tile. Written since the photon-weighted average; a checkpoint without it weighs every
    // pass 1, as the renders that wrote such files did.
    h["weight"] = film.tileCount() > 0 ? snap->block(0).sums.weight : static_cast<double>(info.passes);
    h["width"] = film.width();
    h["height"] = film.height();
    h["time"] = {
        {"bins", film.time().bins}, {"start_opl_m", film.time().startOpl}, {"bin_width_opl_m", film.time().binWidth}};
    h["tiles"] = film.tileCount();
    // The phasor film's sums follow each tile's after[1] (film/phasor.h); absent: none.
    if (film.phasor().active())
        h["phasor"] = {{"frequencies_per_m", film.phasor().frequencies}, {"reference_opl_m", film.phasor().refOpl}};
    h["payload_bytes"] = payloadBytes(layout);
    json fp = json::array();
    for (const auto& [k, v] : info.fingerprint) fp.push_back({k, v});
    h["fingerprint"] = fp;
    h["overrides"] = overridesJson(info.overrides);
    const FilmStats& st = film.stats;
    h["stats"] = {{"rejected_samples", st.rejectedSamples.load()},
                  {"overflowed_pixels", st.overflowedPixels.load()},
                  {"outside", {st.outside[0].load(), st.outside[1].load()}},
                  {"before", {st.before[0].load(), st.before[1].load()}},
                  {"inside", {st.inside[0].load(), st.inside[1].load()}}};
    json hist = json::array();
    for (const PassStats& p : history) hist.push_back(passJson(p));
    h["history"] = hist;
    const std::string text = h.dump();

    FilmContainerWriter f(path, std::string_view(kMagic, 8), text);
    for (int t = 0; t < snap->tileCount(); ++t) {
        const TileSums& s = snap->block(t).sums;
        f.write(&s.passes, 8);
        f.write(&s.absBound, 8);
        f.write(s.steady.data(), s.steady.size() * 8);
        f.write(s.bins[0].data(), s.bins[0].size() * 8);
        f.write(s.bins[1].data(), s.bins[1].size() * 8);
        f.write(s.before[0].data(), s.before[0].size() * 8);
        f.write(s.before[1].data(), s.before[1].size() * 8);
        f.write(s.after[0].data(), s.after[0].size() * 8);
        f.write(s.after[1].data(), s.after[1].size() * 8);
        f.write(s.phasor[0].data(), s.phasor[0].size() * 8);
        f.write(s.phasor[1].data(), s.phasor[1].size() * 8);
    }
    f.commit(/*seal=*/true);
}

CheckpointInfo readCheckpointInfo(const std::string& path) {
    Opened o = openCheckpoint(path);
    return infoFrom(path, o.header);
}

Checkpoint readCheckpoint(const std::string& path, TransientFilm* into) {
    Opened o = openCheckpoint(path);
    Checkpoint c;
    c.info = infoFrom(path, o.header);
    if (into && (into->width() != c.info.width || into->height() != c.info.height || into->bins() != c.info.time.bins ||
                 into->time().startOpl != c.info.time.startOpl || into->time().binWidth != c.info.time.binWidth))
        throw UserError(path + ": the checkpoint's film (" + std::to_string(c.info.width) + "x" +
                        std::to_string(c.info.height) + "x" + std::to_string(c.info.time.bins) +
                        ") differs from this render's: render anew without --resume");
    try {
        for (const json& p : o.header.at("history")) c.history.push_back(passFrom(p));
    } catch (const std::exception& e) {
        bad(path, std::string("history of the passes unreadable (") + e.what() + ")");
    }
    const PhasorSpec& phasor = c.info.phasor;
    if (into && !(into->phasor() == phasor))
        throw UserError(path + ": the checkpoint's phasor film (" + std::to_string(phasor.count()) +
                        " frequencies) differs from this render's (" + std::to_string(into->phasor().count()) +
                        "): resume with the same --phasor, or render anew without --resume");
    if (!into) c.film = std::make_unique<TransientFilm>(c.info.width, c.info.height, c.info.time, phasor);
    TransientFilm& film = into ? *into : *c.film;
    auto get = [&](void* data, size_t bytes) { o.in->read(data, bytes, "film"); };
    // Each pass weighs at most 1 (render_settings.h passWeight), a pass at least 1 photon's share.
    double weight = static_cast<double>(c.info.passes);
    try {
        weight = o.header.value("weight", weight);
    } catch (const std::exception&) {
        bad(path, "header field \"weight\" is not a number");
    }
    if (!(weight >= 0.0) || weight > static_cast<double>(c.info.passes) * (1.0 + 1e-12) ||
        (c.info.passes > 0 && !(weight > 0.0)))
        bad(path, "header weight " + std::to_string(weight) + " is out of range for " + std::to_string(c.info.passes) +
                      " passes");
    for (int t = 0; t < film.tileCount(); ++t) {
        TileSums s;
        s.zero(static_cast<size_t>(film.tileRect(t).w) * film.tileRect(t).h, film.bins(), film.phasor().count());
        get(&s.passes, 8);
        get(&s.absBound, 8);
        get(s.steady.data(), s.steady.size() * 8);
        get(s.bins[0].data(), s.bins[0].size() * 8);
        get(s.bins[1].data(), s.bins[1].size() * 8);
        get(s.before[0].data(), s.before[0].size() * 8);
        get(s.before[1].data(), s.before[1].size() * 8);
        get(s.after[0].data(), s.after[0].size() * 8);
        get(s.after[1].data(), s.after[1].size() * 8);
        get(s.phasor[0].data(), s.phasor[0].size() * 8);
        get(s.phasor[1].data(), s.phasor[1].size() * 8);
        if (s.passes != static_cast<int64_t>(c.info.passes))
            bad(path, "tile " + std::to_string(t) + " holds " + std::to_string(s.passes) + " passes, the header " +
                          std::to_string(c.info.passes));
        s.weight = weight;
        film.restoreTile(t, std::move(s));
    }
    o.in->readSeal();
    try {
        const json& st = o.header.at("stats");
        film.stats.rejectedSamples = st.at("rejected_samples").get<int64_t>();
        film.stats.overflowedPixels = st.at("overflowed_pixels").get<int64_t>();
        for (int a = 0; a < 2; ++a) {
            film.stats.outside[a] = st.at("outside").at(a).get<double>();
            film.stats.before[a] = st.at("before").at(a).get<double>();
            film.stats.inside[a] = st.at("inside").at(a).get<double>();
        }
    } catch (const std::exception& e) {
        bad(path, std::string("film counters unreadable (") + e.what() + ")");
    }
    return c;
}

SettingsOverrides checkpointOverrides(const RenderSettings& s, const SettingsOverrides& flags) {
    SettingsOverrides o = flags;
    o.method = s.method;
    o.passes = s.passes;
    o.seed = s.seed;
    o.maxDepth = s.maxDepth;
    o.autoRadius = false;  // the radius it chose is written out below
    if (s.method == Method::Beams) {
        o.photons = s.photonsPerPass;
        o.warmup = s.warmupPasses;
        o.radius = s.beamRadius0;
        o.surfaceRadius = s.surfaceRadius0;
        o.alpha = s.alpha;
        o.profile = s.profile;
        o.beamLength = s.beamLength;
        o.accel = s.accel;
        o.volumeEstimator = s.volumeEstimator;
        o.surfaceEstimator = s.surfaceEstimator;
        o.timeKernel = s.timeKernel;
    } else if (s.method == Method::PathTracer) {
        o.samplesPerPixel = s.samplesPerPixel;
        o.equiangular = s.equiangular;
    }
    // The resolved list (a band's frequencies depend on the bins): the resume's film gets the same.
    if (s.phasor.active()) o.phasor = phasorListText(s.phasor);
    return o;
}

CheckpointInfo checkpointInfoFor(const PreparedRender& p, const RenderSettings& running, const SettingsOverrides& flags,
                                 uint64_t passes) {
    CheckpointInfo i;
    std::error_code ec;
    const fs::path abs = fs::absolute(p.source.path, ec);
    i.scene = ec ? p.source.path : abs.lexically_normal().string();
    i.passes = passes;
    i.width = p.scene->camera.width;
    i.height = p.scene->camera.height;
    i.time = p.time;
    i.fingerprint = p.sceneFingerprint;
    for (auto& kv : settingsFingerprint(running)) i.fingerprint.push_back(std::move(kv));
    for (auto& kv : timeFingerprint(p.time)) i.fingerprint.push_back(std::move(kv));
    for (auto& kv : phasorFingerprint(running.phasor)) i.fingerprint.push_back(std::move(kv));
    i.phasor = running.phasor;
    i.overrides = checkpointOverrides(running, flags);
    return i;
}

SettingsOverrides resumeOverrides(const SettingsOverrides& cp, const SettingsOverrides& given) {
    SettingsOverrides o = cp;
    // What a resume may change: how many passes, how long, on how many threads.
    if (given.passes) o.passes = given.passes;
    if (given.timeBudget)
        o.timeBudget = given.timeBudget;
    else
        o.timeBudget.reset();  // a budget counts from the start of a run: the earlier run's is spent
    o.threads = given.threads;
    auto same = [&](const char* flag, const auto& mine, const auto& theirs, auto show) {
        if (!mine) return;
        if (!theirs || !(*mine == *theirs))
            throw UserError(std::string(flag) + " " + show(*mine) + ": the checkpoint's render ran with " +
                            (theirs ? show(*theirs) : std::string("no ") + flag) +
                            "; a resumed render continues the same sequence: drop " + flag +
                            " (the checkpoint's value is used) or render anew without --resume");
    };
    auto str = [](const auto& v) {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::string>)
            return v;
        else if constexpr (std::is_floating_point_v<std::decay_t<decltype(v)>>)
            return shortest(v);
        else
            return std::to_string(v);
    };
    same("--photons", given.photons, cp.photons, str);
    same("--warmup", given.warmup, cp.warmup, str);
    same("--radius", given.radius, cp.radius, str);
    same("--alpha", given.alpha, cp.alpha, str);
    same("--max-depth", given.maxDepth, cp.maxDepth, str);
    same("--spp", given.samplesPerPixel, cp.samplesPerPixel, str);
    same("--seed", given.seed, cp.seed, str);
    same("--estimator", given.volumeEstimator, cp.volumeEstimator, str);
    same("--surface-estimator", given.surfaceEstimator, cp.surfaceEstimator, str);
    same("--width", given.width, cp.width, str);
    same("--height", given.height, cp.height, str);
    same("--bins", given.bins, cp.bins, str);
    same("--method", given.method, cp.method, [](Method m) { return std::string(methodName(m)); });
    same("--profile", given.profile, cp.profile, [](TimeProfile p) { return std::string(profileName(p)); });
    same("--beam-length", given.beamLength, cp.beamLength, [](BeamLength b) { return std::string(lengthName(b)); });
    same("--accel", given.accel, cp.accel, [](AccelBackend a) { return std::string(accelName(a)); });
    same("--phasor", given.phasor, cp.phasor, str);
    same("--time-kernel", given.timeKernel, cp.timeKernel,
         [](const TimeKernelSettings& k) { return timeKernelName(k); });
    same("--pt-free-flight", given.equiangular, cp.equiangular, [](bool e) { return std::string(e ? "off" : "on"); });
    if (given.autoRadius && !cp.autoRadius)
        throw UserError(
            "--auto-radius: the checkpoint was rendered without it; a resumed render continues the same "
            "sequence: drop --auto-radius or render anew without --resume");
    return o;
}

}  // namespace tpb
