#include "transport/stages.h"
#include "render/prepare.h"

#include "base/error.h"
#include "base/memory.h"
#include "base/text.h"
#include "film/film_bytes.h"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <functional>

namespace tpb {

std::string SceneSource::where(const std::string& keyPath) const {
    auto it = locs.find(keyPath);
    if (it != locs.end() && it->second.line > 0) return it->second.file + ":" + std::to_string(it->second.line) + ": ";
    return path.empty() ? std::string() : path + ": ";
}

std::string SceneSource::keyWhere(const std::string& keyPath) const {
    std::string w = where(keyPath);  // "file:line: "
    if (w.size() >= 2) w.resize(w.size() - 2);
    return w + ": " + keyPath;
}

void applyFilmShape(SceneDesc& d, const SettingsOverrides& o) {
    if (o.width) d.camera.width = *o.width;
    if (o.height) d.camera.height = *o.height;
    if (o.bins && *o.bins < 1) throw UserError("--bins must be >= 1");
    if (o.bins) {
        // Keep the film's time range, change its resolution.
        if (!d.film.autoRange) d.film.binWidthOpl = d.film.binWidthOpl * d.film.bins / *o.bins;
        d.film.bins = *o.bins;
    }
    if (d.camera.width < 1 || d.camera.height < 1 || d.film.bins < 1)
        throw UserError("--width, --height and --bins must be >= 1");
    // (An exhaustive scan's film stacks one sensor image per laser point: filmHeight.)
    const uint64_t need =
        saturatingMul(filmBytes(d.camera.width, 1, d.film.bins), static_cast<uint64_t>(d.camera.filmHeight()));
    if (need > maxFilmBytes())
        throw UserError("the film would need " + humanBytes(need) + " but at most " + humanBytes(maxFilmBytes()) +
                        " is allowed; lower --width/--height/--bins");
    if (static_cast<int64_t>(d.camera.width) * d.camera.filmHeight() > INT_MAX)
        throw UserError("--width x --height is " +
                        std::to_string(static_cast<int64_t>(d.camera.width) * d.camera.filmHeight()) +
                        " pixels of film, more than " + std::to_string(INT_MAX) + "; lower --width/--height");
}

namespace {

bool contains(const Bounds3& outer, const Bounds3& inner) {
    return glm::all(glm::lessThanEqual(outer.lo, inner.lo)) && glm::all(glm::greaterThanEqual(outer.hi, inner.hi));
}

// What sets the scene's size (its bounding box's diagonal: the relative kernel radius, the
// automatic time range) and may be far from the rest: every shape, every light, the camera.
struct SizeItem {
    std::string key;  // "shapes[3]", "lights[0]", "camera.position"
    Bounds3 box;
};

std::vector<SizeItem> sizeItems(const Scene& scene) {
    std::vector<SizeItem> items;
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (scene.shapes[i].bounds.valid())
            items.push_back({"shapes[" + std::to_string(i) + "]", scene.shapes[i].bounds});
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        Bounds3 b;
        b.expand(l.position);
        if (l.type == LightType::AreaQuad) b.expand(l.corner + l.edgeU + l.edgeV);
        items.push_back({"lights[" + std::to_string(i) + "]", b});
    }
    Bounds3 cam;
    cam.expand(scene.camera.position);
    items.push_back({"camera.position", cam});
    return items;
}

// Warnings about the scene's scale, once it is built: one far object that makes the bounding box
// (and with it the relative radius and the automatic time range) more than kFarObjectRatio times
// larger than everything else, and a laser wider than the scene. An object that encloses the rest
// (a room, a medium container) is the scene's size, not a stray.
constexpr double kFarObjectRatio = 10.0;
void warnAboutScale(const Scene& scene, const SceneDesc& desc, const std::function<void(const std::string&)>& warn) {
    const std::vector<SizeItem> items = sizeItems(scene);
    const size_t n = items.size();
    std::vector<Bounds3> before(n + 1), after(n + 1);  // unions of items [0, i) and [i, n)
    for (size_t i = 0; i < n; ++i) {
        before[i + 1] = before[i];
        before[i + 1].expand(items[i].box.lo), before[i + 1].expand(items[i].box.hi);
    }
    for (size_t i = n; i-- > 0;) {
        after[i] = after[i + 1];
        after[i].expand(items[i].box.lo), after[i].expand(items[i].box.hi);
    }
    const double whole = scene.bounds.diagonal();
    const size_t shapes = static_cast<size_t>(
        std::count_if(items.begin(), items.end(), [](const SizeItem& it) { return it.key.rfind("shapes[", 0) == 0; }));
    for (size_t i = 0; i < n; ++i) {
        // The rest keeps a shape: a lone wall far from a co-located laser and camera is the scene.
        const bool isShape = items[i].key.rfind("shapes[", 0) == 0;
        if (shapes < (isShape ? 2u : 1u)) continue;
        Bounds3 rest = before[i];
        if (after[i + 1].valid()) rest.expand(after[i + 1].lo), rest.expand(after[i + 1].hi);
        const double restDiag = rest.diagonal();
        if (!(restDiag > 0.0) || whole <= kFarObjectRatio * restDiag || contains(items[i].box, rest)) continue;
        char b[640];
        std::snprintf(b, sizeof b,
                      "%s makes the scene %.0fx larger than everything else (bounding diagonal %.4g m; %.4g m "
                      "without it): the kernel radius when relative (render.radius_relative, the default) and the "
                      "automatic time range (\"range\": \"auto\") scale with the whole box, so they may be far too "
                      "large for what the camera sees; move or remove it if it is a stray, or give render.radius in "
                      "m and the film's start_m/bin_width_m",
                      items[i].key.c_str(), whole / restDiag, whole, restDiag);
        warn(desc.where(items[i].key) + b);
        break;  // one far object (with two, neither alone dominates)
    }
    const Bounds3 gb = scene.geometry.bounds();
    const double geomDiag = gb.valid() ? gb.diagonal() : 0.0;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        if (l.type != LightType::Laser || !(geomDiag > 0.0) || !(2.0 * l.laserRadius > geomDiag)) continue;
        const std::string key = "lights[" + std::to_string(i) + "].radius";
        warn(desc.where(key) + key + ": the laser's beam (radius " + shortNumber(l.laserRadius) +
             " m) is wider than the whole scene (diagonal " + shortNumber(geomDiag) +
             " m): most of its power misses the scene; a laser's radius is its beam's, typically millimetres");
    }
}

}  // namespace

PreparedRender prepareRender(SceneDesc desc, const SettingsOverrides& overrides, const PrepareOptions& options) {
    const auto warn = [&](const std::string& w) {
        if (options.warn) options.warn(w);
    };
    for (const std::string& w : desc.warnings) warn(w);
    applyFilmShape(desc, overrides);

    PreparedRender p;
    p.sceneFingerprint = sceneFingerprint(desc);
    p.scene = Scene::build(desc, analyzeStages);
    const double diag = p.scene->bounds.diagonal() > 0.0 ? p.scene->bounds.diagonal() : 1.0;
    warnAboutScale(*p.scene, desc, warn);

    // The settings: the file's, then the flags; checked once, now that the diagonal is known.
    p.settings = RenderSettings::fromDesc(desc.render, diag);
    p.settings.apply(overrides);
    for (const std::string& w : p.settings.validate({&desc, &overrides, diag})) warn(w);

    // "radius": "auto" (unless --radius overrides it) or --auto-radius: from a pilot pass's photon
    // density (auto_radius.h), capped like any radius; the surface radius, unless given, keeps the
    // default ratio to it (2x). Without a measurement the radius stays the default fraction.
    if ((desc.render.radiusAuto && !overrides.radius) || overrides.autoRadius) {
        p.radiusPilot = pilotRadius(*p.scene, p.settings, options.pilot.control.abort);
        const std::string where =
            overrides.autoRadius ? "--auto-radius: " : desc.where("render.radius") + "render.radius: auto: ";
        // The implicit default (no radius written) stays quiet when there is nothing to measure.
        const bool asked = overrides.autoRadius || desc.locs.count("render.radius");
        if (p.radiusPilot.measured) {
            double r = p.radiusPilot.radius;
            if (r > kMaxRadiusFraction * diag) {
                warn(where + "the photon density asks for " + shortNumber(r) + " m, capped at " +
                     shortNumber(kMaxRadiusFraction * diag) +
                     " m (a quarter of the scene's diagonal); use more photons");
                r = kMaxRadiusFraction * diag;
            }
            const bool surfaceGiven = desc.locs.count("render.surface_radius") ||
                                      desc.locs.count("render.surface_radius_relative") || overrides.surfaceRadius;
            if (!surfaceGiven) p.settings.surfaceRadius0 *= r / p.settings.beamRadius0;
            p.settings.beamRadius0 = r;
        } else if (asked) {
            warn(where + p.radiusPilot.why + "; the radius stays " + shortNumber(p.settings.beamRadius0) + " m");
        }
    }

    // The pilot sees the file's settings (with --max-depth and --threads), whatever the other flags.
    p.pilotSettings = RenderSettings::fromDesc(desc.render, diag);
    if (overrides.maxDepth) p.pilotSettings.maxDepth = *overrides.maxDepth;
    p.pilotSettings.threads = p.settings.threads;
    // ... with the default estimators and no time kernel, so every estimator of a comparison gets
    // the same film time axis.
    p.pilotSettings.volumeEstimator = RenderSettings{}.volumeEstimator;
    p.pilotSettings.surfaceEstimator = RenderSettings{}.surfaceEstimator;
    p.pilotSettings.timeKernel = {};

    const FilmTimeAxis axis = filmTimeAxis(*p.scene, desc.film, p.pilotSettings, options.pilot);
    p.film = desc.film;
    p.time = axis.time;
    p.fit = axis.fit;
    p.settings.validateAgainstFilm(p.time.binWidth * p.time.bins, {&desc, &overrides, diag});
    // The phasor film's frequencies (film/phasor.h): --phasor, else the film block's "phasor".
    const std::string phasorText = overrides.phasor ? *overrides.phasor : desc.film.phasor;
    if (!phasorText.empty()) {
        const std::string what = overrides.phasor ? "--phasor" : desc.where("film.phasor") + "film.phasor";
        p.settings.phasor.frequencies = parsePhasorFrequencies(phasorText, p.time.bins, p.time.binWidth, what);
        p.settings.phasor.refOpl = p.time.startOpl;
        if (p.settings.method == Method::Preview)
            throw UserError(what + ": the preview has no time; render with --method beams or pt");
        const Camera& cam = p.scene->camera;
        const uint64_t need = filmBytes(cam.width, cam.height, p.time.bins, p.settings.phasor.count());
        if (need > maxFilmBytes())
            throw UserError(what + ": the film with " + std::to_string(p.settings.phasor.count()) +
                            " phasor frequencies would need " + humanBytes(need) + " but at most " +
                            humanBytes(maxFilmBytes()) + " is allowed; ask for fewer frequencies or a smaller film");
    }
    p.source.path = desc.path;
    p.source.version = desc.version;
    p.source.locs = std::move(desc.locs);
    return p;
}

Fingerprint renderFingerprint(const PreparedRender& p) {
    Fingerprint f = p.sceneFingerprint;
    for (auto& kv : settingsFingerprint(p.settings)) f.push_back(std::move(kv));
    for (auto& kv : timeFingerprint(p.time)) f.push_back(std::move(kv));
    for (auto& kv : phasorFingerprint(p.settings.phasor)) f.push_back(std::move(kv));
    return f;
}

}  // namespace tpb
