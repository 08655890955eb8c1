#include "integrators/render_settings.h"

#include <climits>
#include <tuple>

#include "base/error.h"
#include "estimators/estimator_names.h"
#include "base/memory.h"
#include "film/film_bytes.h"
#include "photons/photon_tracer.h"
#include "base/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>

namespace tpb {

const char* methodName(Method m) {
    switch (m) {
        case Method::Beams: return "beams";
        case Method::PathTracer: return "pt";
        case Method::Preview: return "preview";
    }
    return "?";
}

std::optional<Method> parseMethod(std::string_view s) {
    if (s == "beams") return Method::Beams;
    if (s == "pt") return Method::PathTracer;
    if (s == "preview") return Method::Preview;
    return std::nullopt;
}

int64_t RenderSettings::photonsForPass(uint64_t pass) const {
    if (warmupPasses <= 0 || pass > static_cast<uint64_t>(warmupPasses)) return photonsPerPass;
    const int shift = warmupPasses + 1 - static_cast<int>(pass);  // 1 .. warmupPasses
    return std::max<int64_t>(1, photonsPerPass >> shift);
}

double RenderSettings::passWeight(uint64_t pass) const {
    if (method != Method::Beams || photonsPerPass <= 0) return 1.0;
    return static_cast<double>(photonsForPass(pass)) / static_cast<double>(photonsPerPass);
}

RenderSettings RenderSettings::fromDesc(const RenderDesc& r, double sceneDiagonal) {
    const double diag = sceneDiagonal > 0.0 ? sceneDiagonal : 1.0;
    RenderSettings s;
    s.photonsPerPass = r.photonsPerPass;
    s.warmupPasses = r.warmup;
    s.beamRadius0 = r.radiusRelative ? r.radius * diag : r.radius;
    s.surfaceRadius0 = r.radiusRelative ? r.surfaceRadius * diag : r.surfaceRadius;
    s.alpha = r.alpha;
    s.passes = r.passes;
    s.timeBudgetSec = r.timeBudgetSec;
    s.maxDepth = r.maxDepth;
    s.bounceMin = r.bounceMin;
    s.bounceMax = r.bounceMax;
    s.seed = r.seed;
    s.threads = r.threads;
    s.profile = r.timeProfile;
    s.beamLength = r.beamLength;
    s.emission = r.emission;
    s.unwarp = r.unwarp;
    s.volumeEstimator = r.volumeEstimator;
    s.surfaceEstimator = r.surfaceEstimator;
    s.timeKernel = r.timeKernel;
    return s;
}

void RenderSettings::apply(const SettingsOverrides& o) {
    if (o.method) method = *o.method;
    if (o.passes) passes = *o.passes;
    if (o.timeBudget) {
        timeBudgetSec = *o.timeBudget;
        if (!o.passes) passes = 0;  // a time budget alone means: as many passes as fit
    }
    if (o.photons) photonsPerPass = *o.photons;
    if (o.warmup) warmupPasses = *o.warmup;
    if (o.radius) beamRadius0 = *o.radius;
    if (o.surfaceRadius) surfaceRadius0 = *o.surfaceRadius;
    if (o.alpha) alpha = *o.alpha;
    if (o.threads) threads = *o.threads;
    if (o.maxDepth) maxDepth = *o.maxDepth;
    if (o.bounces) std::tie(bounceMin, bounceMax) = *o.bounces;
    if (o.seed) seed = *o.seed;
    if (o.samplesPerPixel) samplesPerPixel = *o.samplesPerPixel;
    if (o.profile) profile = *o.profile;
    if (o.beamLength) beamLength = *o.beamLength;
    if (o.accel) accel = *o.accel;
    if (o.equiangular) equiangular = *o.equiangular;
    if (o.volumeEstimator) volumeEstimator = *o.volumeEstimator;
    if (o.surfaceEstimator) surfaceEstimator = *o.surfaceEstimator;
    if (o.timeKernel) timeKernel = *o.timeKernel;
}

namespace {

// One setting as validate() names it: by its flag when an override set it, else by its key in the
// scene file's render block ("render.<key>", at the file and line where it was written).
struct Field {
    std::string key;   // in the render block: "alpha"
    std::string flag;  // "--alpha"
    bool overridden = false;
};

class Checker {
public:
    explicit Checker(const SettingsSource& src) : src_(src) {}

    Field field(const std::string& key, const std::string& flag, bool overridden) const {
        return {key, flag, overridden};
    }
    std::string name(const Field& f) const { return f.overridden ? f.flag : f.key; }
    // Whether the value was given at all (a flag, or a key written in the file).
    bool given(const Field& f) const { return f.overridden || (src_.desc && src_.desc->locs.count("render." + f.key)); }
    [[noreturn]] void fail(const Field& f, const std::string& message) const {
        if (f.overridden) throw UserError(message);
        const std::string key = "render." + f.key;
        if (!src_.desc) throw UserError("", 0, key, message);
        const auto it = src_.desc->locs.find(key);
        if (it == src_.desc->locs.end()) throw UserError(src_.desc->path, 0, key, message);
        throw UserError(it->second.file, it->second.line, key, message);
    }
    // "<name> <rule> (got <value>)" unless ok.
    void check(bool ok, const Field& f, const std::string& rule, const std::string& got) const {
        if (!ok) fail(f, name(f) + " " + rule + " (got " + got + ")");
    }
    void warn(const Field& f, const std::string& message) {
        if (f.overridden || !src_.desc)
            warnings.push_back(f.overridden ? message : "render." + f.key + ": " + message);
        else
            warnings.push_back(src_.desc->where("render." + f.key) + "render." + f.key + ": " + message);
    }

    std::vector<std::string> warnings;

private:
    const SettingsSource& src_;
};

}  // namespace

std::vector<std::string> RenderSettings::validate(const SettingsSource& src) {
    const SettingsOverrides none;
    const SettingsOverrides& ov = src.overrides ? *src.overrides : none;
    Checker c(src);

    // ---- photons per pass, and the photon map they need ----
    const Field photons = c.field("photons_per_pass", "--photons", ov.photons.has_value());
    c.check(photonsPerPass >= 1, photons, "must be >= 1", std::to_string(photonsPerPass));
    if (photonMapBytes(photonsPerPass) > maxFilmBytes())
        c.fail(photons, c.name(photons) + " " + std::to_string(photonsPerPass) + " needs about " +
                            humanBytes(photonMapBytes(photonsPerPass)) + " per pass for the photon map, more than " +
                            humanBytes(maxFilmBytes()) + "; use fewer photons per pass and more passes");

    // ---- kernel radii of pass 1, against the scene's diagonal ----
    const bool fileRelative = src.desc && src.desc->render.radiusRelative;
    const auto checkRadius = [&](double radiusM, const std::string& key, bool overridden, double fileValue) {
        const bool relative = fileRelative && !overridden;
        const Field f = c.field(relative ? key + "_relative" : key, "--radius", overridden);
        const double shown = relative ? fileValue : radiusM;
        c.check(radiusM > 0.0 && std::isfinite(radiusM), f, "must be > 0", shortNumber(shown));
        if (!c.given(f)) return;
        if (relative) {  // a fraction of the diagonal, known without the scene
            if (fileValue > kMaxRadiusFraction)
                c.fail(f, f.key + " " + shortNumber(fileValue) + " is too large: allowed (0, " +
                              shortNumber(kMaxRadiusFraction) +
                              "] (a fraction of the scene's diagonal). A kernel "
                              "that wide makes every camera ray gather every beam or photon, so a pass costs rays x "
                              "beams (minutes, with no better image); typical values are 0.001 to 0.02");
            if (fileValue > kSlowRadiusFraction)
                c.warn(f, f.key + " " + shortNumber(fileValue) + " is large (above " +
                              shortNumber(kSlowRadiusFraction) +
                              " of the scene's diagonal): passes get much slower "
                              "as the kernel grows; typical values are 0.001 to 0.02");
            if (fileValue < kTinyRadiusFraction)
                c.warn(f, f.key + " " + shortNumber(fileValue) + " is tiny (below " + shortNumber(kTinyRadiusFraction) +
                              " of the scene's diagonal): the kernel almost never meets a photon, so the image stays "
                              "black or spiky; typical values are 0.001 to 0.02");
            return;
        }
        if (!(src.sceneDiagonal > 0.0)) return;  // absolute: checked once the scene is built
        const double diag = src.sceneDiagonal, fraction = radiusM / diag;
        char b[512];
        if (fraction > kMaxRadiusFraction) {
            std::snprintf(b, sizeof b,
                          "%s %g m is %.0f%% of the scene's diagonal (%.4g m); allowed up to %.0f%% (%.4g m). A "
                          "kernel that wide makes every camera ray gather every beam or photon, so a pass costs "
                          "rays x beams (minutes, with no better image); typical radii are 0.1%% to 2%% of the "
                          "diagonal (%.3g to %.3g m)",
                          c.name(f).c_str(), radiusM, 100.0 * fraction, diag, 100.0 * kMaxRadiusFraction,
                          kMaxRadiusFraction * diag, 0.001 * diag, 0.02 * diag);
            c.fail(f, b);
        }
        if (fraction < kTinyRadiusFraction) {
            std::snprintf(b, sizeof b,
                          "%s %g m is %.2g of the scene's diagonal (%.4g m), below %g: the kernel almost never meets "
                          "a photon, so the image stays black or spiky; typical radii are 0.1%% to 2%% of the "
                          "diagonal (%.3g to %.3g m)",
                          c.name(f).c_str(), radiusM, fraction, diag, kTinyRadiusFraction, 0.001 * diag, 0.02 * diag);
            c.warn(f, b);
        }
        if (fraction > kSlowRadiusFraction) {
            std::snprintf(b, sizeof b,
                          "%s %g m is %.0f%% of the scene's diagonal (%.4g m): passes get much slower as the kernel "
                          "grows; typical radii are 0.1%% to 2%% of the diagonal (%.3g to %.3g m)",
                          c.name(f).c_str(), radiusM, 100.0 * fraction, diag, 0.001 * diag, 0.02 * diag);
            c.warn(f, b);
        }
    };
    checkRadius(beamRadius0, "radius", ov.radius.has_value(), src.desc ? src.desc->render.radius : 0.0);
    checkRadius(surfaceRadius0, "surface_radius", false, src.desc ? src.desc->render.surfaceRadius : 0.0);

    // ---- the rest ----
    c.check(alpha > 0.0 && alpha <= 1.0, c.field("alpha", "--alpha", ov.alpha.has_value()), "must be in (0, 1]",
            shortNumber(alpha));
    c.check(passes >= 0, c.field("passes", "--passes", ov.passes.has_value()),
            "must be >= 0 (0 = until the time budget or Ctrl-C)", std::to_string(passes));
    c.check(timeBudgetSec >= 0.0 && std::isfinite(timeBudgetSec),
            c.field("time_budget_s", "--time", ov.timeBudget.has_value()),
            "must be a finite number of seconds >= 0 (0 = no time budget)", shortNumber(timeBudgetSec));
    c.check(maxDepth >= 1, c.field("max_depth", "--max-depth", ov.maxDepth.has_value()),
            "must be >= 1 (1 = single scattering)", std::to_string(maxDepth));
    const Field bounces = c.field("bounces", "--bounces", ov.bounces.has_value());
    c.check(bounceMin >= 0 && bounceMin <= bounceMax, bounces, "must be MIN:MAX with 0 <= MIN <= MAX",
            std::to_string(bounceMin) + ":" + std::to_string(bounceMax));
    // Photon beams filter where photons are stored, counting the camera path's gathering event
    // only: exact unless a camera path bounces off a mirror or glass before it gathers.
    if (bounceFilter() && method == Method::Beams && src.desc)
        for (const MaterialDesc& m : src.desc->materials)
            if (m.type == MaterialType::Mirror || m.type == MaterialType::Dielectric)
                c.fail(bounces, c.name(bounces) +
                                    ": the photon beams' bounce filter does not count a camera path's mirror and "
                                    "glass bounces yet, and the scene has a " +
                                    materialTypeName(m.type) + " material (\"" + m.name +
                                    "\"); use the path tracer (--method pt) or drop the filter");
    c.check(warmupPasses >= 0 && warmupPasses <= kMaxWarmupPasses, c.field("warmup", "--warmup", ov.warmup.has_value()),
            "must be an integer from 0 (no warm-up) to " + std::to_string(kMaxWarmupPasses) +
                " (warm-up passes with fewer photons)",
            std::to_string(warmupPasses));
    // A warm-up as long as the render: pass 1 traces 1/2^W of the photons, and no pass a full load.
    const Field warm = c.field("warmup", "--warmup", ov.warmup.has_value());
    if (passes > 0 && warmupPasses > 0 && warmupPasses >= passes && c.given(warm))
        c.warn(warm, c.name(warm) + " " + std::to_string(warmupPasses) + " is as long as the render (" +
                         std::to_string(passes) +
                         " passes): every pass is a warm-up pass with fewer photons (pass 1 "
                         "traces 1/2^" +
                         std::to_string(warmupPasses) +
                         " of photons_per_pass); use fewer warm-up "
                         "passes than passes, or 0");
    c.check(samplesPerPixel >= 1, c.field("samples_per_pixel", "--spp", ov.samplesPerPixel.has_value()), "must be >= 1",
            std::to_string(samplesPerPixel));
    // ---- the estimators and the time kernel (photon beams only) ----
    const auto checkName = [&](const std::string& name, const std::vector<std::string>& known, const Field& f,
                               const char* what) {
        if (std::find(known.begin(), known.end(), name) != known.end()) return;
        std::string list;
        for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
        c.fail(f,
               c.name(f) + ": unknown " + what + " \"" + name + "\"; allowed: " + list + " (docs/user/estimators.md)");
    };
    const Field volEst = c.field("volume_estimator", "--estimator", ov.volumeEstimator.has_value());
    const Field surfEst = c.field("surface_estimator", "--surface-estimator", ov.surfaceEstimator.has_value());
    const Field tk = c.field("time_kernel", "--time-kernel", ov.timeKernel.has_value());
    checkName(volumeEstimator, volumeEstimatorNames(), volEst, "volume estimator");
    checkName(surfaceEstimator, surfaceEstimatorNames(), surfEst, "surface estimator");
    c.check(timeKernel.width >= 0.0 && std::isfinite(timeKernel.width), tk,
            "width must be a finite length > 0 in m of optical path (or 0 / absent: chosen from the scene)",
            shortNumber(timeKernel.width));
    if (method != Method::Beams) {
        // A flag that only the photon-beams integrator reads makes no sense with another method
        // (values from the scene file are the file's settings for photon beams: no complaint).
        for (const Field* f : {&volEst, &surfEst, &tk})
            if (f->overridden)
                c.fail(*f, c.name(*f) + " applies to the photon-beams estimators only (--method beams); the " +
                               std::string(methodName(method) == std::string("pt")
                                               ? "path tracer is unbiased and has no kernel"
                                               : "geometry preview has no light transport") +
                               ": drop " + c.name(*f) + " or use --method beams");
    }

    const Field thr = c.field("threads", "--threads", ov.threads.has_value());
    c.check(threads >= 0, thr, "must be >= 0 (0 = all cores)", std::to_string(threads));
    if (threads > maxUsefulThreads()) {
        c.warn(thr, c.name(thr) + " " + std::to_string(threads) + " is more than " +
                        std::to_string(kThreadsPerCoreCap) + " x the " +
                        std::to_string(maxUsefulThreads() / kThreadsPerCoreCap) + " cores of this machine: using " +
                        std::to_string(maxUsefulThreads()) + " (0 = all cores)");
        threads = maxUsefulThreads();
    }
    return c.warnings;
}

void RenderSettings::validateAgainstFilm(double filmRangeOpl, const SettingsSource& src) const {
    const SettingsOverrides none;
    const SettingsOverrides& ov = src.overrides ? *src.overrides : none;
    Checker c(src);
    const Field tk = c.field("time_kernel", "--time-kernel", ov.timeKernel.has_value());
    if (method == Method::Beams && timeKernel.kind != TimeKernelKind::None && timeKernel.width > filmRangeOpl)
        c.fail(tk, c.name(tk) + ": the time kernel's width " + shortNumber(timeKernel.width) +
                       " m (of optical path) is wider than the film's whole time range " + shortNumber(filmRangeOpl) +
                       " m: every frame would show the same blur; give a width below the range (a few bin widths, "
                       "e.g. " +
                       shortNumber(4.0 * filmRangeOpl / 100.0) + " m), or \"box\" to let the renderer choose");
}

Record settingsRecord(const RenderSettings& s) {
    Record r;
    const auto put = [&](const char* key, RecordValue v) { r.push_back({key, std::move(v)}); };
    put("method", std::string(methodName(s.method)));
    put("passes", static_cast<int64_t>(s.passes));
    put("time_budget_s", s.timeBudgetSec);
    put("max_depth", static_cast<int64_t>(s.maxDepth));
    if (s.bounceFilter())
        put("bounces", std::to_string(s.bounceMin) + ":" +
                           (s.bounceMax == INT_MAX ? std::string("") : std::to_string(s.bounceMax)));
    put("seed", s.seed);
    put("threads", static_cast<int64_t>(s.threads));
    if (s.method == Method::Beams) {
        put("photons_per_pass", static_cast<int64_t>(s.photonsPerPass));
        put("warmup", static_cast<int64_t>(s.warmupPasses));
        put("radius", s.beamRadius0);
        put("surface_radius", s.surfaceRadius0);
        put("alpha", s.alpha);
        put("time_profile", std::string(s.profile == TimeProfile::Exact ? "exact" : "uniform"));
        put("beam_length", std::string(s.beamLength == BeamLength::Short ? "short" : "long"));
        put("accel", std::string(accelBackendName(s.accel)));
        put("volume_estimator", s.volumeEstimator);
        put("surface_estimator", s.surfaceEstimator);
        put("time_kernel", timeKernelName(s.timeKernel));
    } else if (s.method == Method::PathTracer) {
        put("samples_per_pixel", static_cast<int64_t>(s.samplesPerPixel));
        put("equiangular", s.equiangular);
    }
    put("emission", std::string(s.emission == EmissionMode::Delta ? "delta" : "continuous"));
    put("unwarp", s.unwarp);
    return r;
}

}  // namespace tpb
