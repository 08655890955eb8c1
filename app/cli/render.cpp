// `tpb render`: headless progressive render to EXR frames + steady state + JSON summary.
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/summary.h"
#include "cli/interrupt.h"
#include "cli/commands.h"
#include "cli/resume.h"
#include "base/error.h"
#include "base/text.h"
#include "film/film_export.h"
#include "io/record_json.h"
#include "film/picture_export.h"
#include "io/image_io.h"
#include "estimators/estimator.h"
#include "integrators/preview.h"
#include "io/video_encoder.h"
#include "render/nlos_capture.h"
#include "render/provenance.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <filesystem>
#include <optional>
#include <cstdio>
#include <unistd.h>

namespace tpb::app {

namespace {

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
    // Checkpoints (render/checkpoint.h, cli/resume.h).
    std::string pulse = "delta", sensor = "ideal";  // --pulse, --sensor (film/time_response.h)
    std::string counts = "off";                     // --counts (film/photon_counting.h)
    std::string resume;                             // --resume DIR
    bool outGiven = false;                          // -o given (a resume writes into the checkpoint's folder otherwise)
    bool checkpoint = false;                        // --checkpoint: one when the render ends
    double checkpointEveryMin = 0.0;                // --checkpoint-every: and every that many minutes
    bool noCheckpoint = false;                      // --no-checkpoint: none when Ctrl-C or SIGTERM stops the render
    bool overwriteCheckpoint = false;  // --overwrite-checkpoint: an earlier render's checkpoint in -o may go
    bool npy = false, mp4 = false, falseColour = false, noSrgb = false;
    // --backproject and its grid (render/nlos_backprojection.h); 0 = the default.
    bool backproject = false;
    double bpDepthMin = 0.0, bpDepthMax = 0.0;
    int bpDepths = 64;
    std::string bpFilter = "none";
    std::string bpFlagGiven;  // a --bp-* flag given (refused without --backproject)
    double fps = 24.0, videoEv = 0.0;
    int contactSheet = 0;
    bool fpsGiven = false, videoEvGiven = false;  // on the command line (a flag without its output is refused)
    bool sppGiven = false, methodGiven = false;
    std::vector<std::string> outputFlagsGiven;  // flags that shape what the render writes (refused with --preview)
};

nlohmann::json summaryJson(const PreparedRender& p, const Driver& drv, const ExportOptions& opt, double wallSec) {
    using nlohmann::json;
    const Scene& scene = *p.scene;
    const auto hist = drv.history();
    json j = summaryHeader(p, "beams", hist.size(), wallSec, drv.film(), opt);
    json stages = json::array();
    for (const auto& r : scene.stages.reasons) stages.push_back(r);
    j["stages"] = stages;
    const RenderSettings& s = drv.settings();
    j["settings"] = recordJson(settingsRecord(s));  // the one serialisation of the settings
    json per = json::array();
    int64_t beams = 0, estimates = 0, photonEst = 0;
    double passSec = 0.0;
    Color emittedFlux(0.0), cutFlux(0.0);
    int64_t regionOverflows = 0;
    for (const PassStats& p : hist) {
        per.push_back({{"pass", p.pass},
                       {"photons", p.photons},
                       {"beam_radius_m", p.beamRadius},
                       {"surface_radius_m", p.surfaceRadius},
                       {"beams", p.beams},
                       {"points", p.points},
                       {"beam_pieces", p.beamPieces},
                       {"surface_photons", p.surfacePhotons},
                       {"beam_estimates", p.camera.beamEstimates},
                       {"photon_estimates", p.camera.photonEstimates},
                       {"photon_s", p.photonSec},
                       {"build_s", p.buildSec},
                       {"camera_s", p.cameraSec},
                       {"pass_s", p.passSec},
                       {"elapsed_s", p.elapsedSec}});
        beams += p.beams;
        estimates += p.camera.beamEstimates;
        photonEst += p.camera.photonEstimates;
        passSec += p.passSec;
        emittedFlux += p.emittedFlux;
        cutFlux += p.cutFlux;
        regionOverflows += p.regionOverflows + p.camera.regionOverflows + p.paths.regionOverflows;
    }
    j["per_pass"] = per;
    const FilmStats& fs = drv.film().stats;
    const double in0 = fs.inside[0].load(), out0 = fs.outside[0].load();
    const double in1 = fs.inside[1].load(), out1 = fs.outside[1].load();
    j["totals"] = {
        {"beams", beams},
        {"beam_estimates", estimates},
        {"photon_estimates", photonEst},
        {"render_seconds", passSec},
        {"beams_per_second", passSec > 0 ? beams / passSec : 0.0},
        {"beam_estimates_per_second", passSec > 0 ? estimates / passSec : 0.0},
        {"rejected_samples", fs.rejectedSamples.load()},
        {"energy_outside_film_fraction_real", in0 + out0 > 0 ? out0 / (in0 + out0) : 0.0},
        {"energy_outside_film_fraction_unwarped", in1 + out1 > 0 ? out1 / (in1 + out1) : 0.0},
        // Long beams in an unbounded medium end past the film's end; the flux they still
        // carry there is missing from the steady image only (photon_tracer.cpp).
        {"region_stack_overflows", regionOverflows},
        {"beam_flux_cut_fraction", luminance(emittedFlux) > 0 ? luminance(cutFlux) / luminance(emittedFlux) : 0.0},
        {"peak_rss_bytes", peakRssBytes()}};
    return j;
}

// summary.json of a path-traced render (--method pt): its settings and its paths.
nlohmann::json summaryJsonPt(const PreparedRender& p, const Driver& drv, const ExportOptions& opt, double wallSec) {
    using nlohmann::json;
    const auto hist = drv.history();
    const RenderSettings& s = drv.settings();
    json j = summaryHeader(p, "pt", hist.size(), wallSec, drv.film(), opt);
    j["settings"] = recordJson(settingsRecord(s));
    json per = json::array();
    double renderSec = 0.0;
    PathTracerStats st;
    for (const PassStats& ps : hist) {
        per.push_back({{"pass", ps.pass}, {"pass_s", ps.passSec}, {"elapsed_s", ps.elapsedSec}});
        renderSec += ps.passSec;
        st += ps.paths;
    }
    j["per_pass"] = per;
    const FilmStats& fs = drv.film().stats;
    const double in0 = fs.inside[0].load(), out0 = fs.outside[0].load();
    const double in1 = fs.inside[1].load(), out1 = fs.outside[1].load();
    j["totals"] = {{"camera_paths", st.cameraPaths},
                   {"contributions", st.contributions},
                   {"shadow_rays", st.shadowRays},
                   {"laser_samples", st.laserSamples},
                   {"depth_limited", st.depthLimited},
                   {"render_seconds", renderSec},
                   {"region_stack_overflows", st.regionOverflows},
                   {"paths_per_second", renderSec > 0 ? st.cameraPaths / renderSec : 0.0},
                   {"rejected_samples", fs.rejectedSamples.load()},
                   {"energy_outside_film_fraction_real", in0 + out0 > 0 ? out0 / (in0 + out0) : 0.0},
                   {"energy_outside_film_fraction_unwarped", in1 + out1 > 0 ? out1 / (in1 + out1) : 0.0},
                   {"peak_rss_bytes", peakRssBytes()}};
    return j;
}

// What this pass's photon map holds for the chosen estimators, for the progress line: beams
// (beam2d, beam1d), photon points (point2d, point3d), surface photons (ppm); each when its stage runs.
std::string storedPhotons(const PassStats& p, const Stages& stages, const VolumeEstimator::Needs& needs) {
    std::string s;
    const auto add = [&](int64_t n, const char* what) {
        s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    if (stages.beams && needs.beams) add(p.beams, "beams");
    if (stages.beams && needs.points) add(p.points, "photon points");
    if (stages.surfacePhotons) add(p.surfacePhotons, "surface photons");
    return s.empty() ? "no photons stored" : s;
}

// Flags that contradict each other; checked before anything is loaded or written.
void checkFlagConflicts(const RenderCmd& c) {
    if (c.method != "beams") c.ov.rejectBeamsOnlyFlags(c.method);
    if (c.unwarp && c.realTime)
        throw UserError(
            "--unwarp and --real-time contradict each other: give one of them (frames are in real time "
            "unless --unwarp or the scene's render.unwarp asks for unwarped time)");
    if (c.noCheckpoint && (c.checkpoint || c.checkpointEveryMin > 0.0))
        throw UserError("--no-checkpoint contradicts --checkpoint / --checkpoint-every: give one of them");
    if (c.scene.empty() && c.resume.empty())
        throw UserError(
            "tpb render: give a scene file (tpb render SCENE), or --resume DIR to continue a render from "
            "its checkpoint");
    // A video flag without the output it shapes would be silently ignored: say which flag is missing.
    if (c.fpsGiven && !c.mp4)
        throw UserError(
            "--fps sets the frame rate of transient.mp4, which only --mp4 writes: add --mp4, or drop --fps");
    const char* look = c.videoEvGiven  ? "--video-ev"
                       : c.falseColour ? "--false-colour"
                       : c.noSrgb      ? "--no-srgb"
                                       : nullptr;
    if (look && !c.mp4 && c.contactSheet == 0)
        throw UserError(std::string(look) +
                        " shapes transient.mp4 and contact_sheet.png, and neither is written: add "
                        "--mp4 or --contact-sheet N, or drop " +
                        look);
    // --preview stops before the render: a flag for the render's outputs would be silently dropped.
    if (c.previewOnly && !c.outputFlagsGiven.empty())
        throw UserError(c.outputFlagsGiven.front() +
                        " shapes what the render writes, and --preview stops after "
                        "preview.exr/png, before any photon: drop --preview to render, or drop " +
                        c.outputFlagsGiven.front());
    if (c.sppGiven && c.method != "pt")
        throw UserError("--spp sets the path tracer's camera paths per pixel per pass; --method " + c.method +
                        " traces one camera ray per pixel per pass (its progress comes from more passes or "
                        "--photons): add --method pt, or drop --spp");
    if (!c.bpFlagGiven.empty() && !c.backproject)
        throw UserError(c.bpFlagGiven +
                        " shapes backprojection.npy, which only --backproject writes: add "
                        "--backproject, or drop " +
                        c.bpFlagGiven);
    if (c.bpDepthMin > 0.0 && c.bpDepthMax > 0.0 && c.bpDepthMax <= c.bpDepthMin)
        throw UserError("--bp-depth-max (" + shortest(c.bpDepthMax) + " m) must be beyond --bp-depth-min (" +
                        shortest(c.bpDepthMin) + " m)");
    if (c.continuous && c.delta)
        throw UserError(
            "--continuous and --delta contradict each other: give one of them (frames are for a delta "
            "pulse unless --continuous or the scene's render.emission asks for continuous emission)");
}

void run(RenderCmd& c) {
    InterruptScope interrupts;          // Ctrl-C and SIGTERM, from the start (the pilot polls them too)
    checkFlagConflicts(c);              // (each flag's range was checked when the command line was parsed)
    if (c.mp4) requireFfmpeg("--mp4");  // before hours of rendering, not after
    // Every setting is resolved and checked (prepareRender) before the first file is written (no
    // preview.exr is left behind by a bad --alpha or by photons that would not fit in memory).
    // A resume loads the checkpoint's scene with its flags (the pass count, time budget and threads
    // may change) and refuses a render that differs from it; its outputs go to the checkpoint's
    // folder unless -o says otherwise.
    std::optional<ResumeSource> resume;
    if (!c.resume.empty()) {
        resume = findCheckpoint(c.resume);
        if (!c.outGiven) c.out = std::filesystem::path(resume->path).parent_path().string();
        if (c.out.empty()) c.out = ".";
    }
    // The method is a setting like any other (one render path for every method; a checkpoint
    // records it, so a resume continues with the method it was written by).
    SettingsOverrides given = c.ov.settings();
    if (c.methodGiven) given.method = parseMethod(c.method);
    if (c.sppGiven) given.samplesPerPixel = c.spp;
    const SettingsOverrides flags = resume ? resumeOverrides(resume->info.overrides, given) : given;
    const PreparedRender prepared = resume ? prepareResume(*resume, c.scene, given, LoadOptions{c.quiet})
                                           : loadAndBuild(c.scene, given, LoadOptions{c.quiet});
    const Scene* scene = prepared.scene.get();
    const RenderSettings& ds = prepared.settings;
    const bool pt = ds.method == Method::PathTracer;

    ExportOptions opt;
    opt.axis = (ds.unwarp || c.unwarp) && !c.realTime ? TimeAxis::Unwarped : TimeAxis::Real;
    opt.mode = (ds.emission == EmissionMode::Continuous || c.continuous) && !c.delta ? EmissionMode::Continuous
                                                                                     : EmissionMode::Delta;
    opt.pixel = c.half ? ExrPixel::Half : ExrPixel::Float;
    opt.response = *parseSensor(c.sensor, *parsePulse(c.pulse));  // (each checked when parsed)
    checkTimeResponseFitsFilm(c.pulse, c.sensor, prepared.time);  // against the bins: before any pass or file
    opt.response.counting = parseCounting(c.counts);              // (checked when parsed)
    opt.step = c.frameStep;
    RenderOutputs outputs;
    outputs.out = c.out;
    outputs.opt = opt;
    outputs.noFrames = c.noFrames;
    outputs.quiet = c.quiet;
    outputs.strip = c.strip;
    outputs.stripEv = c.stripEv;
    outputs.npy = c.npy;
    outputs.mp4 = c.mp4;
    outputs.fps = c.fps;
    outputs.contactSheet = c.contactSheet;
    if (prepared.scene->camera.scan != ScanMode::None) outputs.captureScene = prepared.scene.get();
    outputs.phasor = prepared.settings.phasor.active();
    if (c.backproject) {
        if (!outputs.captureScene)
            throw UserError(
                "--backproject back-projects an NLOS capture: it needs a relay-wall camera with a "
                "\"scan\" (docs/user/nlos.md); drop --backproject for this scene");
        BackprojectionSettings bp;
        bp.depthMinM = c.bpDepthMin;
        bp.depthMaxM = c.bpDepthMax;
        bp.depths = c.bpDepths;
        bp.filter = parseBackprojectionFilter(c.bpFilter, "--bp-filter");
        bp.flag = "--backproject";
        backprojectionGrid(nlosCaptureGeometry(*prepared.scene, prepared.time), bp);  // refused before the render
        outputs.backproject = bp;
    }
    outputs.tone.exposureEv = static_cast<float>(c.videoEv);
    outputs.tone.falseColor = c.falseColour;
    outputs.tone.srgb = !c.noSrgb;

    // The folder is this render's from here on: locked, the previous render's outputs removed.
    const std::string checkpointPath = (std::filesystem::path(c.out) / kCheckpointFile).string();
    OutputFiles files = renderOutputFiles(outputs, prepared.time.bins);
    if (!(c.noCheckpoint && !resume)) files.files.push_back(kCheckpointFile);
    std::error_code ec;
    if (resume && std::filesystem::equivalent(resume->path, checkpointPath, ec)) files.keep.push_back(kCheckpointFile);
    files.replaceCheckpoint = c.overwriteCheckpoint;
    files.checkpointAdvice = "continue that render with `tpb render --resume " + c.out + "`";
    const OutputFolder folder(c.out, "render", files);
    if (!c.quiet && !folder.removed().empty())
        std::printf("removed %zu files of an earlier render in %s (listed in its manifest)\n", folder.removed().size(),
                    c.out.c_str());
    if (std::find(folder.removed().begin(), folder.removed().end(), kCheckpointFile) != folder.removed().end())
        std::fprintf(stderr, "note: removed the earlier render's %s (--overwrite-checkpoint)\n",
                     checkpointPath.c_str());

    // Geometry/camera check before any photon is traced.
    const std::vector<float> preview = renderPreview(*scene, ds.threads);
    const double tw = nowSec();
    writeExr(c.out + "/preview.exr", scene->camera.width, scene->camera.height, preview);
    const double previewExrSec = nowSec() - tw;
    outputs.previewEv =
        writeAutoExposedPng(c.out + "/preview.png", scene->camera.width, scene->camera.height, preview, ToneMap{});
    if (!c.quiet) std::printf("wrote %s/preview.exr (eye-light geometry check)\n", c.out.c_str());
    if (c.previewOnly) return;
    reportPlannedOutputs(prepared, outputs, previewExrSec);

    if (ds.passes == 0 && ds.timeBudgetSec == 0.0)
        std::fprintf(stderr, "note: no pass limit and no time budget: rendering until Ctrl-C\n");
    Driver drv(*scene, ds, prepared.time);
    uint64_t resumedPasses = 0;
    if (resume) {
        resumedPasses = restoreCheckpoint(*resume, prepared, drv);
        if (!c.quiet)
            std::printf("resumed %llu passes from %s (written %s)%s\n", static_cast<unsigned long long>(resumedPasses),
                        resume->path.c_str(), resume->info.created.c_str(),
                        ds.passes > 0 && int64_t(resumedPasses) >= ds.passes
                            ? "; the pass limit is reached already: give --passes N (the total) to render more"
                            : "");
    }
    std::string checkpointWritten, checkpointError;  // the last write's path, or why it failed
    const auto writeCheckpointNow = [&](const char* when) {
        try {
            const double t = nowSec();
            saveCheckpoint(checkpointPath, prepared, flags, drv);
            checkpointWritten = checkpointPath;
            checkpointError.clear();
            if (!c.quiet)
                std::fprintf(stderr, "%scheckpoint (%s): %llu passes written to %s in %.2f s\n",
                             isatty(STDERR_FILENO) ? "\r" : "", when,
                             static_cast<unsigned long long>(drv.history().size()), checkpointPath.c_str(),
                             nowSec() - t);
        } catch (const UserError& e) {
            // A periodic one is retried at the next period and at the end; the last one decides.
            checkpointError = e.what();
            std::fprintf(stderr, "warning: no checkpoint written (%s): %s\n", when, e.what());
        }
    };
    double lastCheckpoint = nowSec();

    const bool tty = isatty(STDERR_FILENO) && !c.quiet;
    const std::unique_ptr<VolumeEstimator> volume = makeVolumeEstimator(ds.volumeEstimator);
    const VolumeEstimator::Needs needs = volume ? volume->needs() : VolumeEstimator::Needs{};
    const double t0 = nowSec();
    drv.start([&](const PassStats& p) {
        // Between passes, on the driver's thread: no tile is being written.
        if (c.checkpointEveryMin > 0.0 && nowSec() - lastCheckpoint >= 60.0 * c.checkpointEveryMin) {
            writeCheckpointNow("periodic");
            lastCheckpoint = nowSec();
        }
        if (c.quiet) return;
        const int64_t total = ds.passes;
        if (pt) {  // no kernel, no photons: its samples per pixel
            if (tty)
                std::fprintf(stderr, "\rpass %llu  %d spp/pass  %.2f s/pass  %.1f s ",
                             static_cast<unsigned long long>(p.pass), ds.samplesPerPixel, p.passSec, p.elapsedSec);
            else if (p.pass == 1 || p.pass % 10 == 0 || (total > 0 && int64_t(p.pass) == total))
                std::fprintf(stderr, "pass %llu: %.3f s\n", static_cast<unsigned long long>(p.pass), p.passSec);
        } else if (tty) {
            const int width = 30;
            const double frac = total > 0
                                    ? double(p.pass) / total
                                    : (ds.timeBudgetSec > 0 ? std::min(1.0, p.elapsedSec / ds.timeBudgetSec) : 0.0);
            const int fill = static_cast<int>(frac * width);
            std::fprintf(stderr, "\r[%.*s%*s] pass %llu  r=%.3g m  %s  %.2f s/pass  %.1f s ", fill,
                         "##############################", width - fill, "", static_cast<unsigned long long>(p.pass),
                         p.beamRadius, storedPhotons(p, scene->stages, needs).c_str(), p.passSec, p.elapsedSec);
        } else if (p.pass == 1 || p.pass % 10 == 0 || (total > 0 && int64_t(p.pass) == total)) {
            std::fprintf(stderr, "pass %llu: r=%.4g m, %s, %.3f s\n", static_cast<unsigned long long>(p.pass),
                         p.beamRadius, storedPhotons(p, scene->stages, needs).c_str(), p.passSec);
        }
    });
    // After start() (which clears a stop request): a signal from before is passed on here, a later
    // one by the handler.
    setInterruptDriver(&drv);
    drv.wait();
    setInterruptDriver(nullptr);
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
    const bool stoppedBySignal = interrupted();
    if (stoppedBySignal && !c.quiet)
        std::fprintf(stderr, "interrupted by %s: writing the %llu finished passes\n", interruptName().c_str(),
                     static_cast<unsigned long long>(drv.completedPasses()));

    outputs.provenance = provenanceOf(drv, prepared.source.path);
    // The checkpoint first (the state a long render cannot get back), then the images.
    if (c.checkpoint || c.checkpointEveryMin > 0.0 || (stoppedBySignal && !c.noCheckpoint) ||
        (resume && c.checkpointEveryMin == 0.0 && !c.noCheckpoint))
        writeCheckpointNow(stoppedBySignal ? "interrupted" : "end of the render");
    PathTracerStats paths;
    for (const PassStats& p : drv.history()) paths += p.paths;
    if (paths.laserSamples > 0)
        std::fprintf(stderr,
                     "note: the path tracer cannot connect to lasers (%lld light samples picked one): their "
                     "light is missing from this render\n",
                     static_cast<long long>(paths.laserSamples));
    const OutputReport rep = writeRenderOutputs(drv.film(), outputs, [&] {
        nlohmann::json j = pt ? summaryJsonPt(prepared, drv, opt, wall) : summaryJson(prepared, drv, opt, wall);
        if (resume)
            j["resumed"] = {{"checkpoint", resume->path}, {"passes", resumedPasses}, {"written", resume->info.created}};
        j["checkpoint"] = checkpointWritten;
        return j;
    });
    warnFilmOverflow(prepared.source, drv.film());
    int64_t regionOverflows = 0;
    for (const PassStats& p : drv.history())
        regionOverflows += p.regionOverflows + p.camera.regionOverflows + p.paths.regionOverflows;
    if (regionOverflows > 0)
        std::fprintf(stderr,
                     "warning: %lld paths were ended because they entered more than 7 nested dielectric/null shapes "
                     "(open or overlapping shapes crossed again and again); close those shapes or make them not "
                     "overlap\n",
                     static_cast<long long>(regionOverflows));
    const double outside = checkEnergyInsideFilm(prepared, drv.film(), opt.axis);
    if (!checkpointError.empty()) {
        // The outputs are written, but the render cannot be resumed: a failure, even after a signal.
        std::fprintf(stderr,
                     "error: the checkpoint was not written: %s; the outputs are written, but this render "
                     "cannot be resumed\n",
                     checkpointError.c_str());
        exitCode() = kExitUserError;
    }
    if (stoppedBySignal && exitCode() == 0) exitCode() = exitCodeAfterInterrupt();
    if (!c.quiet) {
        const FilmStats& fs = drv.film().stats;
        std::printf("%s%llu passes in %.2f s; %s; %lld rejected samples; %s%% of the energy outside the film\n",
                    pt ? "path tracer: " : "", static_cast<unsigned long long>(drv.completedPasses()), wall,
                    writtenLine(outputs, rep).c_str(), static_cast<long long>(fs.rejectedSamples.load()),
                    percentText(outside).c_str());
    }
}

}  // namespace

void registerRender(CLI::App& app) {
    auto c = std::make_shared<RenderCmd>();
    CLI::App* cmd = app.add_subcommand("render",
                                       "Render a scene headless: preview.exr, EXR frames per time bin, "
                                       "steady.exr and summary.json");
    cmd->add_option("scene", c->scene,
                    "Scene file, JSON or Mitsuba 3 XML (with --resume: the checkpoint's scene unless given)");
    CLI::Option* out = cmd->add_option("-o,--out", c->out,
                                       "Output folder (created if needed; locked while rendering; the outputs of "
                                       "an earlier render in it are replaced, other files are kept)");
    c->ov.add(cmd);
    cmd->add_flag("--unwarp", c->unwarp, "Frames in camera-unwarped time (camera path excluded)");
    cmd->add_flag("--real-time", c->realTime, "Frames in real time (camera path included; the default)");
    cmd->add_flag("--continuous", c->continuous,
                  "Frames for continuous emission (running integral of the pulse response)");
    cmd->add_flag("--delta", c->delta, "Frames for a delta pulse (the default)");
    cmd->add_option("--pulse", c->pulse,
                    "Pulse shape the outputs are seen with: delta | gaussian:FWHM_NS | square:WIDTH_NS (a convolution "
                    "along time of the delta response: no re-render)")
        ->check(flags::pulse());
    cmd->add_option("--sensor", c->sensor,
                    "Sensor time response: ideal | gaussian:FWHM_NS (jitter) | exp:TAU_NS (decay)")
        ->check(flags::sensor());
    cmd->add_option("--counts", c->counts,
                    "Outputs as SPAD photon counts per bin (after --pulse/--sensor; no re-render): off | "
                    "photons=P,efficiency=E,dark_hz=R,ambient_hz=R,cycles=N,afterpulse=P,afterpulse_ns=T,pileup,"
                    "coates,seed=S (docs/user/photon-counting.md)")
        ->check(flags::counts());
    cmd->add_flag("--half", c->half, "Write half-float EXR frames");
    cmd->add_option("--frame-step", c->frameStep, "Write every K-th frame")
        ->transform(flags::integer(1, INT_MAX, "1 = every frame"));
    cmd->add_flag("--no-frames", c->noFrames, "Do not write per-bin frames");
    cmd->add_option("--strip", c->strip, "Frames in strip.png (PNG overview of the time axis; 0 = none)")
        ->transform(flags::integer(0, 4096, "frames side by side; 0 = no strip.png"));
    cmd->add_option("--strip-ev", c->stripEv, "Extra exposure of strip.png in EV (it is auto-exposed first)")
        ->check(flags::number(-64.0, 64.0, false, "EV"));
    cmd->add_option("--method", c->method, "Renderer: beams (progressive photon beams) | pt (unbiased path tracer)")
        ->check(CLI::IsMember({"beams", "pt"}));
    cmd->add_option("--spp", c->spp, "--method pt: camera paths per pixel per pass")
        ->transform(flags::integer(1, 1 << 20, "camera paths per pixel per pass"));
    cmd->add_flag(
        "--npy", c->npy,
        "Also write the transient volume for NumPy: transient.npy (H x W x bins x 3 float32, the frames' "
        "axis and emission), steady.npy, before.npy, after.npy and transient.json (the time axis, the render)");
    cmd->add_flag("--mp4", c->mp4, "Also write transient.mp4, the frames as a video (H.264, needs ffmpeg on PATH)");
    cmd->add_option("--fps", c->fps, "Frames per second of transient.mp4")
        ->check(flags::number(0.0, 240.0, true, "frames per second"));
    cmd->add_option("--contact-sheet", c->contactSheet,
                    "Also write contact_sheet.png: N frames in a grid, each labelled with its time (0 = none)")
        ->transform(flags::integer(0, 4096, "frames in the grid; 0 = no contact sheet"));
    cmd->add_option(
           "--video-ev", c->videoEv,
           "Extra exposure (EV) of transient.mp4 and contact_sheet.png (auto-exposed to the brightest frame first)")
        ->check(flags::number(-64.0, 64.0, false, "EV"));
    cmd->add_flag("--false-colour", c->falseColour,
                  "transient.mp4 and contact_sheet.png in false colour (log luminance)");
    cmd->add_flag("--no-srgb", c->noSrgb, "transient.mp4 and contact_sheet.png without sRGB encoding");
    cmd->add_flag("--backproject", c->backproject,
                  "Relay-wall scans: also back-project capture.h5 onto a voxel grid in front of the wall: "
                  "backprojection.npy (nx x ny x depths float32, luminance) and backprojection.json (grid, peak)");
    cmd->add_option("--bp-depth-min", c->bpDepthMin,
                    "--backproject: nearest depth from the wall, m (default: one depth step)")
        ->check(flags::number(0.0, 1e6, true, "m"));
    cmd->add_option("--bp-depth-max", c->bpDepthMax,
                    "--backproject: farthest depth, m (default: the deepest the film's last bin sees)")
        ->check(flags::number(0.0, 1e6, true, "m"));
    cmd->add_option("--bp-depths", c->bpDepths, "--backproject: voxels along the wall's normal")
        ->transform(flags::integer(1, 4096, "depths"));
    cmd->add_option("--bp-filter", c->bpFilter,
                    "--backproject: none | laplacian (minus the second difference along depth)");
    cmd->add_flag("--preview", c->previewOnly, "Only write the eye-light geometry preview, trace no photon");
    cmd->add_flag("-q,--quiet", c->quiet, "No progress output");
    cmd->add_option("--resume", c->resume,
                    "Continue the render whose checkpoint is in this folder (or this .tpbck file): same scene and "
                    "flags; --passes (the total), --time and --threads may change")
        ->type_name("DIR");
    cmd->add_flag("--checkpoint", c->checkpoint,
                  "Write a checkpoint (checkpoint.tpbck in the output folder) when the render ends, to --resume it");
    cmd->add_option("--checkpoint-every", c->checkpointEveryMin,
                    "Also write the checkpoint every MIN minutes (between passes)")
        ->check(flags::number(0.0, 1e9, true, "minutes"))
        ->type_name("MIN");
    cmd->add_flag("--overwrite-checkpoint", c->overwriteCheckpoint,
                  "Allow this render to remove or replace the checkpoint of an earlier render in the output folder "
                  "(refused otherwise: resume it with --resume, or use another -o)");
    cmd->add_flag("--no-checkpoint", c->noCheckpoint,
                  "Write no checkpoint when Ctrl-C or SIGTERM stops the render (written by default then)");
    cmd->callback([c, out, cmd] {
        c->outGiven = out->count() > 0;
        c->fpsGiven = cmd->get_option("--fps")->count() > 0;
        c->videoEvGiven = cmd->get_option("--video-ev")->count() > 0;
        c->sppGiven = cmd->get_option("--spp")->count() > 0;
        c->methodGiven = cmd->get_option("--method")->count() > 0;
        // (An output asked for: "--strip 0" and "--contact-sheet 0" ask for none.)
        for (const char* f : {"--bp-depth-min", "--bp-depth-max", "--bp-depths", "--bp-filter"})
            if (cmd->get_option(f)->count() > 0 && c->bpFlagGiven.empty()) c->bpFlagGiven = f;
        for (const char* f :
             {"--npy", "--backproject", "--mp4", "--contact-sheet", "--strip", "--checkpoint", "--checkpoint-every"})
            if (cmd->get_option(f)->count() > 0 && !(std::string(f) == "--strip" && c->strip == 0) &&
                !(std::string(f) == "--contact-sheet" && c->contactSheet == 0))
                c->outputFlagsGiven.emplace_back(f);
        run(*c);
    });
}

}  // namespace tpb::app
