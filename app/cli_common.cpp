#include "cli_common.h"

#include "error.h"
#include "time_range.h"

#include "commands.h"

#include <algorithm>
#include <cstdio>
#include <sys/statvfs.h>
#include <unistd.h>

namespace tpb::app {

void RenderOverrides::add(CLI::App* cmd) {
    cmd->add_option("--passes", passes, "Number of progressive passes (0 = until --time or Ctrl-C)");
    cmd->add_option("--time", timeBudget, "Time budget in seconds");
    cmd->add_option("--photons", photons, "Photons traced per pass");
    cmd->add_option("--radius", radius, "Initial beam kernel radius, m (absolute)");
    cmd->add_option("--alpha", alpha, "Progressive radius shrink parameter in (0, 1]");
    cmd->add_option("--threads", threads, "Worker threads (0 = all cores)");
    cmd->add_option("--seed", seed, "Random seed");
    cmd->add_option("--width", width, "Override the camera's horizontal resolution");
    cmd->add_option("--height", height, "Override the camera's vertical resolution");
    cmd->add_option("--bins", bins, "Override the film's number of time bins (same time range)");
    cmd->add_option("--max-depth", maxDepth, "Maximum number of scattering events per path (1 = single scattering)");
    cmd->add_option("--profile", profile, "Time profile of a ray-beam estimate: exact | uniform (paper)")
        ->check(CLI::IsMember({"exact", "uniform"}));
    cmd->add_option("--beam-length", beamLength, "Photon beams end at the next event (short) or the surface (long)")
        ->check(CLI::IsMember({"short", "long"}));
    cmd->add_flag("--pt-free-flight", ptFreeFlight,
                  "Path tracer: connect point/spot lights only from free-flight vertices, without equiangular "
                  "sampling (unbiased too, but with infinite variance next to a light in a medium)");
    cmd->add_option("--accel", accel, "Beam query backend: embree | brute")->check(CLI::IsMember({"embree", "brute"}));
}

void RenderOverrides::applyToDesc(SceneDesc& d) const {
    if (width) d.camera.width = *width;
    if (height) d.camera.height = *height;
    if (bins && *bins < 1) throw UserError("--bins must be >= 1");
    if (bins) {
        // Keep the film's time range, change its resolution.
        if (!d.film.autoRange) d.film.binWidthOpl = d.film.binWidthOpl * d.film.bins / *bins;
        d.film.bins = *bins;
    }
    if (maxDepth) {
        if (*maxDepth < 1) throw UserError("--max-depth must be >= 1");
        d.render.maxDepth = *maxDepth;
    }
    if (d.camera.width < 1 || d.camera.height < 1 || d.film.bins < 1)
        throw UserError("--width, --height and --bins must be >= 1");
    const uint64_t need = filmBytes(d.camera, d.film.bins);
    if (need > maxFilmBytes())
        throw UserError("the film would need " + humanBytes(need) + " but at most " + humanBytes(maxFilmBytes()) +
                        " is allowed; lower --width/--height/--bins");
}

void RenderOverrides::applyToSettings(DriverSettings& s) const {
    if (passes) s.passes = *passes;
    if (timeBudget) {
        s.timeBudgetSec = *timeBudget;
        if (!passes) s.passes = 0;  // a time budget alone means: as many passes as fit
    }
    if (photons) s.photonsPerPass = *photons;
    if (radius) s.beamRadius0 = *radius;
    if (alpha) s.alpha = *alpha;
    if (threads) s.threads = *threads;
    if (seed) s.seed = *seed;
    if (maxDepth) s.maxDepth = *maxDepth;
    if (profile == "exact") s.profile = TimeProfile::Exact;
    if (profile == "uniform") s.profile = TimeProfile::Uniform;
    if (beamLength == "short") s.beamLength = BeamLength::Short;
    if (beamLength == "long") s.beamLength = BeamLength::Long;
    s.accel = accel == "brute" ? BeamAccel::Kind::BruteForce : BeamAccel::Kind::Embree;
    if (s.photonsPerPass < 1) throw UserError("--photons must be >= 1");
    if (photonMapBytes(s.photonsPerPass) > maxFilmBytes())
        throw UserError("--photons " + std::to_string(s.photonsPerPass) + " needs about " +
                        humanBytes(photonMapBytes(s.photonsPerPass)) + " per pass for the photon map, more than " +
                        humanBytes(maxFilmBytes()) + "; use fewer photons per pass and more passes");
    if (!(s.alpha > 0.0 && s.alpha <= 1.0)) throw UserError("--alpha must be in (0, 1]");
    if (!(s.beamRadius0 > 0.0)) throw UserError("--radius must be > 0");
    if (s.timeBudgetSec < 0.0) throw UserError("--time must be >= 0");
}

std::unique_ptr<Scene> loadAndBuild(const std::string& path, const RenderOverrides& ov) {
    SceneDesc desc = loadScene(path);
    for (const std::string& w : desc.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    ov.applyToDesc(desc);
    std::unique_ptr<Scene> scene = Scene::build(desc);
    if (desc.film.autoRange) {
        const TimeRangeFit f = fitTimeRange(*scene, 4000, ov.threads.value_or(desc.render.threads));
        if (!f.fromPilot)
            std::fprintf(stderr, "note: the pilot pass saw no energy; the film keeps the scene-size range\n");
    }
    return scene;
}

nlohmann::json filmJson(const Scene& scene) {
    return {{"bins", scene.time.bins}, {"start_opl_m", scene.time.startOpl}, {"bin_width_opl_m", scene.time.binWidth},
            {"start_ns", scene.time.startOpl / kC_m_per_ns}, {"bin_width_ns", scene.time.binWidth / kC_m_per_ns}};
}

nlohmann::json summaryHeader(const Scene& scene, const char* method, size_t passes, double wallSec,
                             const TransientFilm& film, const ExportOptions& opt) {
    nlohmann::json j;
    j["scene"] = scene.desc.path;
    j["method"] = method;
    j["passes"] = passes;
    j["wall_seconds"] = wallSec;
    j["resolution"] = {scene.camera.width, scene.camera.height};
    j["film"] = filmJson(scene);
    j["film"]["bytes"] = film.bytes();
    j["frames"] = {{"axis", opt.axis == TimeAxis::Real ? "real" : "unwarped"},
                   {"emission", opt.mode == EmissionMode::Delta ? "delta" : "continuous"}};
    return j;
}

void warnIfOutputsMayNotFit(const Scene& scene, const RenderOutputs& r) {
    if (r.noFrames) return;
    struct statvfs fsInfo {};
    if (::statvfs(r.out.c_str(), &fsInfo) != 0) return;
    const uint64_t freeBytes = static_cast<uint64_t>(fsInfo.f_bavail) * fsInfo.f_frsize;
    const uint64_t frames = static_cast<uint64_t>(exportFrameCount(scene.time.bins, r.opt));
    const uint64_t perFrame = static_cast<uint64_t>(scene.camera.width) * scene.camera.height * 3 *
                              (r.opt.pixel == ExrPixel::Half ? 2 : 4);
    const uint64_t need = frames * perFrame;
    if (need > freeBytes)
        std::fprintf(stderr,
                     "warning: %llu frames take up to %s uncompressed and %s has only %s free; they are "
                     "compressed and may still fit, otherwise use --half, --frame-step, --no-frames or another -o\n",
                     static_cast<unsigned long long>(frames), humanBytes(need).c_str(), r.out.c_str(),
                     humanBytes(freeBytes).c_str());
}

OutputReport writeRenderOutputs(const TransientFilm& film, const RenderOutputs& r,
                                const std::function<nlohmann::json()>& summary) {
    OutputReport rep;
    const bool tty = isatty(STDERR_FILENO) && !r.quiet;
    if (!r.noFrames) rep.framesExpected = exportFrameCount(film.bins(), r.opt);
    const auto writeSummary = [&](bool final) {
        nlohmann::json j = summary();
        nlohmann::json o = {{"frames_expected", rep.framesExpected}, {"files", rep.kept}};
        if (final) o["frames_written"] = rep.framesWritten;
        else o["frames_written"] = nullptr;  // being written: the final summary replaces this one
        if (!rep.error.empty()) o["error"] = rep.error;
        j["outputs"] = o;
        writeTextFile(r.out + "/summary.json", j.dump(2) + "\n");
    };

    {
        std::vector<float> steady;  // one image for both files
        film.steadyImage(steady);
        writeExr(r.out + "/steady.exr", film.width(), film.height(), steady, r.opt.pixel);
        rep.kept.push_back("steady.exr");
        writePngPreview(r.out + "/steady.png", film.width(), film.height(), steady);
        rep.kept.push_back("steady.png");
    }
    rep.kept.push_back("summary.json");
    writeSummary(false);

    try {
        if (!r.noFrames) {
            exportFrames(film, r.out + "/frames", r.opt, [&](int done, int total) {
                rep.framesWritten = done;
                if (tty) std::fprintf(stderr, "\rwriting frames %d/%d", done, total);
            });
            if (tty) std::fprintf(stderr, "\n");
            if (rep.framesWritten > 0) rep.kept.push_back("frames/");
        }
        if (r.strip > 0) {
            exportStripPng(film, r.out + "/strip.png", r.strip, r.opt, r.stripEv);
            rep.kept.push_back("strip.png");
        }
    } catch (const UserError& e) {
        if (tty) std::fprintf(stderr, "\n");
        rep.error = e.what();
        if (rep.framesWritten > 0 && rep.framesWritten < rep.framesExpected) rep.kept.push_back("frames/ (partial)");
    }
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
        exitCode() = kExitUserError;
    }
    return rep;
}

}  // namespace tpb::app
