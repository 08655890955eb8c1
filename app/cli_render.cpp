// `tpb render`: headless progressive render to EXR frames + steady state + JSON summary.
#include "cli_common.h"
#include "cli_converge.h"
#include "commands.h"
#include "error.h"
#include "film_export.h"
#include "image_io.h"
#include "preview.h"

#include <nlohmann/json.hpp>

#include <csignal>
#include <cstdio>
#include <unistd.h>

namespace tpb::app {

namespace {

std::atomic<Driver*> gDriver{nullptr};
std::atomic<int> gInterrupts{0};

void onSigint(int) {
    // First Ctrl-C: finish the current pass and write what has been accumulated. Second: quit now.
    if (gInterrupts.fetch_add(1) >= 1) _exit(130);
    if (Driver* d = gDriver.load()) d->requestStop();
}

struct RenderCmd {
    std::string scene, out = "out";
    RenderOverrides ov;
    bool unwarp = false, realTime = false, continuous = false, delta = false, half = false;
    bool noFrames = false, previewOnly = false, quiet = false;
    int frameStep = 1;
    int strip = 8;
    double stripEv = 0.0;
    std::string method = "beams";
    int spp = 1;
};

nlohmann::json summaryJson(const Scene& scene, const Driver& drv, const ExportOptions& opt, double wallSec) {
    using nlohmann::json;
    const auto hist = drv.history();
    json j = summaryHeader(scene, "beams", hist.size(), wallSec, drv.film(), opt);
    json stages = json::array();
    for (const auto& r : scene.stages.reasons) stages.push_back(r);
    j["stages"] = stages;
    const DriverSettings& s = drv.settings();
    j["settings"] = {{"photons_per_pass", s.photonsPerPass}, {"beam_radius0_m", s.beamRadius0},
                     {"surface_radius0_m", s.surfaceRadius0}, {"alpha", s.alpha}, {"seed", s.seed},
                     {"threads", s.threads}, {"time_profile", s.profile == TimeProfile::Exact ? "exact" : "uniform"},
                     {"beam_length", s.beamLength == BeamLength::Short ? "short" : "long"},
                     {"accel", s.accel == BeamAccel::Kind::Embree ? "embree" : "brute-force"}};
    json per = json::array();
    int64_t beams = 0, estimates = 0, photonEst = 0;
    double passSec = 0.0;
    for (const PassStats& p : hist) {
        per.push_back({{"pass", p.pass}, {"beam_radius_m", p.beamRadius}, {"surface_radius_m", p.surfaceRadius},
                       {"beams", p.beams}, {"beam_pieces", p.beamPieces}, {"surface_photons", p.surfacePhotons},
                       {"beam_estimates", p.camera.beamEstimates}, {"photon_estimates", p.camera.photonEstimates},
                       {"photon_s", p.photonSec}, {"build_s", p.buildSec}, {"camera_s", p.cameraSec},
                       {"pass_s", p.passSec}, {"elapsed_s", p.elapsedSec}});
        beams += p.beams;
        estimates += p.camera.beamEstimates;
        photonEst += p.camera.photonEstimates;
        passSec += p.passSec;
    }
    j["per_pass"] = per;
    const FilmStats& fs = drv.film().stats;
    const double in0 = fs.inside[0].load(), out0 = fs.outside[0].load();
    const double in1 = fs.inside[1].load(), out1 = fs.outside[1].load();
    j["totals"] = {{"beams", beams}, {"beam_estimates", estimates}, {"photon_estimates", photonEst},
                   {"render_seconds", passSec},
                   {"beams_per_second", passSec > 0 ? beams / passSec : 0.0},
                   {"beam_estimates_per_second", passSec > 0 ? estimates / passSec : 0.0},
                   {"rejected_samples", fs.rejectedSamples.load()},
                   {"energy_outside_film_fraction_real", in0 + out0 > 0 ? out0 / (in0 + out0) : 0.0},
                   {"energy_outside_film_fraction_unwarped", in1 + out1 > 0 ? out1 / (in1 + out1) : 0.0},
                   {"peak_rss_bytes", peakRssBytes()}};
    return j;
}

void run(RenderCmd& c) {
    std::unique_ptr<Scene> scene = loadAndBuild(c.scene, c.ov);
    ensureWritableDir(c.out);

    // Geometry/camera check before any photon is traced.
    const std::vector<float> preview = renderPreview(*scene, c.ov.threads.value_or(0));
    writeExr(c.out + "/preview.exr", scene->camera.width, scene->camera.height, preview);
    writePngPreview(c.out + "/preview.png", scene->camera.width, scene->camera.height, preview);
    if (!c.quiet) std::printf("wrote %s/preview.exr (eye-light geometry check)\n", c.out.c_str());
    if (c.previewOnly) return;

    ExportOptions opt;
    opt.axis = (scene->desc.render.unwarp || c.unwarp) && !c.realTime ? TimeAxis::Unwarped : TimeAxis::Real;
    opt.mode = (scene->desc.render.emission == EmissionMode::Continuous || c.continuous) && !c.delta
                   ? EmissionMode::Continuous : EmissionMode::Delta;
    opt.pixel = c.half ? ExrPixel::Half : ExrPixel::Float;
    opt.step = c.frameStep;
    PathTracedRenderRequest outputs;
    outputs.out = c.out;
    outputs.opt = opt;
    outputs.noFrames = c.noFrames;
    outputs.quiet = c.quiet;
    outputs.strip = c.strip;
    outputs.stripEv = c.stripEv;
    warnIfOutputsMayNotFit(*scene, outputs);
    if (c.method == "pt") {  // same outputs, rendered by the path tracer (cli_converge.cpp)
        outputs.spp = c.spp;
        renderPathTraced(*scene, c.ov, outputs);
        return;
    }

    DriverSettings ds = DriverSettings::fromScene(*scene);
    c.ov.applyToSettings(ds);
    if (ds.passes == 0 && ds.timeBudgetSec == 0.0)
        std::fprintf(stderr, "note: no pass limit and no time budget: rendering until Ctrl-C\n");
    Driver drv(*scene, ds);

    const bool tty = isatty(STDERR_FILENO) && !c.quiet;
    gDriver = &drv;
    std::signal(SIGINT, onSigint);
    const double t0 = nowSec();
    drv.start([&](const PassStats& p) {
        if (c.quiet) return;
        const int64_t total = ds.passes;
        if (tty) {
            const int width = 30;
            const double frac = total > 0 ? double(p.pass) / total
                                          : (ds.timeBudgetSec > 0 ? std::min(1.0, p.elapsedSec / ds.timeBudgetSec) : 0.0);
            const int fill = static_cast<int>(frac * width);
            std::fprintf(stderr, "\r[%.*s%*s] pass %llu  r=%.3g m  %lld beams  %.2f s/pass  %.1f s ",
                         fill, "##############################", width - fill, "",
                         static_cast<unsigned long long>(p.pass), p.beamRadius, static_cast<long long>(p.beams),
                         p.passSec, p.elapsedSec);
        } else if (p.pass == 1 || p.pass % 10 == 0 || (total > 0 && int64_t(p.pass) == total)) {
            std::fprintf(stderr, "pass %llu: r=%.4g m, %lld beams, %.3f s\n", static_cast<unsigned long long>(p.pass),
                         p.beamRadius, static_cast<long long>(p.beams), p.passSec);
        }
    });
    drv.wait();
    gDriver = nullptr;
    std::signal(SIGINT, SIG_DFL);
    if (tty) std::fprintf(stderr, "\n");
    const double wall = nowSec() - t0;
    if (drv.failure()) {
        // The passes finished before the failure are kept and written; the exit code says it failed.
        std::fprintf(stderr, "error: %s\nthe render stopped at pass %llu; writing the %llu finished passes\n",
                     drv.failureMessage().c_str(), static_cast<unsigned long long>(drv.completedPasses() + 1),
                     static_cast<unsigned long long>(drv.completedPasses()));
        try {
            std::rethrow_exception(drv.failure());
        } catch (const UserError&) {
            exitCode() = kExitUserError;
        } catch (...) {
            exitCode() = 1;
        }
    }
    if (gInterrupts > 0 && !c.quiet) std::fprintf(stderr, "interrupted: writing the %llu finished passes\n",
                                                  static_cast<unsigned long long>(drv.completedPasses()));

    const OutputReport rep =
        writeRenderOutputs(drv.film(), outputs, [&] { return summaryJson(*scene, drv, opt, wall); });
    const int frames = rep.framesWritten;
    if (!c.quiet) {
        const FilmStats& fs = drv.film().stats;
        std::printf("%llu passes in %.2f s; wrote %d frames (%s, %s) to %s/frames, steady.exr, summary.json; "
                    "%lld rejected samples\n",
                    static_cast<unsigned long long>(drv.completedPasses()), wall, frames,
                    opt.axis == TimeAxis::Real ? "real time" : "unwarped", opt.mode == EmissionMode::Delta ? "delta" : "continuous",
                    c.out.c_str(), static_cast<long long>(fs.rejectedSamples.load()));
    }
}

}  // namespace

void registerRender(CLI::App& app) {
    auto c = std::make_shared<RenderCmd>();
    CLI::App* cmd = app.add_subcommand("render", "Render a scene headless: preview.exr, EXR frames per time bin, "
                                                 "steady.exr and summary.json");
    cmd->add_option("scene", c->scene, "Scene file (JSON)")->required();
    cmd->add_option("-o,--out", c->out, "Output folder (created if needed)");
    c->ov.add(cmd);
    cmd->add_flag("--unwarp", c->unwarp, "Frames in camera-unwarped time (camera path excluded)");
    cmd->add_flag("--real-time", c->realTime, "Frames in real time (camera path included; the default)");
    cmd->add_flag("--continuous", c->continuous, "Frames for continuous emission (running integral of the pulse response)");
    cmd->add_flag("--delta", c->delta, "Frames for a delta pulse (the default)");
    cmd->add_flag("--half", c->half, "Write half-float EXR frames");
    cmd->add_option("--frame-step", c->frameStep, "Write every K-th frame")->check(CLI::PositiveNumber);
    cmd->add_flag("--no-frames", c->noFrames, "Do not write per-bin frames");
    cmd->add_option("--strip", c->strip, "Frames in strip.png (PNG overview of the time axis; 0 = none)");
    cmd->add_option("--strip-ev", c->stripEv, "Extra exposure of strip.png in EV (it is auto-exposed first)");
    cmd->add_option("--method", c->method, "Renderer: beams (progressive photon beams) | pt (unbiased path tracer)")
        ->check(CLI::IsMember({"beams", "pt"}));
    cmd->add_option("--spp", c->spp, "--method pt: camera paths per pixel per pass")->check(CLI::PositiveNumber);
    cmd->add_flag("--preview", c->previewOnly, "Only write the eye-light geometry preview, trace no photon");
    cmd->add_flag("-q,--quiet", c->quiet, "No progress output");
    cmd->callback([c] { run(*c); });
}

}  // namespace tpb::app
