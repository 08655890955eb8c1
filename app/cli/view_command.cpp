// `tpb view`: the viewer's flags (CLI11). Prepares the render as `tpb render` does (loadAndBuild)
// and hands it, with the plain ViewOptions, to the viewer (app/viewer, its own target).
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/resume.h"
#include "base/error.h"
#include "viewer/app.h"

#include <filesystem>
#include <limits>
#include <memory>
#include <string>

namespace tpb::app {

static_assert(kViewerExitUserError == kExitUserError, "the viewer's exit code for a user error is the CLI's");

namespace {

struct ViewCmd {
    std::string scene;
    RenderOverrides ov;
    ViewOptions view;
    std::string method = "beams";
    int spp = 1;
    std::string resume;  // --resume DIR
};

// --passes is the total pass count, as in `tpb render --resume` (docs/user/commands.md "Checkpoints and resume");
// --after-passes counts the passes this run renders before the screenshot (beyond a resumed
// checkpoint's). A screenshot after more passes than the total would never come: refused, instead
// of one flag silently winning.
void checkScreenshotPasses(const ViewCmd& c, uint64_t resumedPasses) {
    if (c.view.screenshot.empty() || !c.ov.passes) return;
    const int64_t total = c.view.afterPasses + static_cast<int64_t>(resumedPasses);
    if (total <= *c.ov.passes) return;
    const std::string after = std::to_string(c.view.afterPasses), passes = std::to_string(*c.ov.passes);
    std::string msg = "--passes " + passes + " and --after-passes " + after +
                      " disagree: --passes is the total (as in "
                      "tpb render --resume) and --after-passes the passes rendered before the screenshot";
    if (resumedPasses > 0)
        msg += " beyond the checkpoint's " + std::to_string(resumedPasses) + ", so the render would go to pass " +
               std::to_string(total);
    const int64_t fit = *c.ov.passes - static_cast<int64_t>(resumedPasses);
    msg += "; drop --passes" + (fit >= 1 ? ", or give --after-passes " + std::to_string(fit) : std::string());
    throw UserError(msg);
}

void run(const ViewCmd& c) {
    if (c.scene.empty() && c.resume.empty())
        throw UserError("tpb view: give a scene file (tpb view SCENE), or --resume DIR to go on refining a checkpoint");
    if (c.resume.empty()) checkScreenshotPasses(c, 0);
    ViewOptions view = c.view;
    view.launchedAt = nowSec();  // the viewer's timeline counts from here (the scene's loading included)
    view.flags = c.ov.settings();
    if (!c.resume.empty()) {  // the checkpoint's scene and settings (cli/resume.h), refined further
        if (c.method != "beams")
            throw UserError("--resume: checkpoints are of the photon beams; drop --method " + c.method);
        const ResumeSource src = findCheckpoint(c.resume);
        checkScreenshotPasses(c, src.info.passes);
        view.flags = resumeOverrides(src.info.overrides, c.ov.settings());
        PreparedRender prepared = prepareResume(src, c.scene, c.ov.settings());
        checkTimeResponseFitsFilm(view.pulse, view.sensor, prepared.time);
        if (view.exportFolder.empty()) view.exportFolder = std::filesystem::path(src.path).parent_path().string();
        if (const int code = runViewer(prepared, view, src.path)) exitCode() = code;
        return;
    }
    PreparedRender prepared = loadAndBuild(c.scene, c.ov);
    checkTimeResponseFitsFilm(view.pulse, view.sensor, prepared.time);  // before the window opens
    // The integrator the viewer's Driver runs (checked by the flag's IsMember when parsed).
    prepared.settings.method = *parseMethod(c.method);
    prepared.settings.samplesPerPixel = c.spp;
    // The viewer warms up (a first picture sooner, render_settings.h) unless told otherwise.
    if (!c.ov.warmup && !prepared.source.wrote("render.warmup")) prepared.settings.warmupPasses = kViewerWarmupPasses;
    if (const int code = runViewer(prepared, view)) exitCode() = code;
}

}  // namespace

void registerView(CLI::App& app) {
    auto c = std::make_shared<ViewCmd>();
    ViewOptions* o = &c->view;
    CLI::App* cmd = app.add_subcommand(
        "view", "Interactive viewer: the render refines in the background while you scrub through time");
    cmd->add_option("scene", c->scene,
                    "Scene file, JSON or Mitsuba 3 XML (with --resume: the checkpoint's scene unless given)");
    cmd->add_option("--resume", c->resume,
                    "Go on refining the checkpoint in this folder (or this .tpbck file): same scene and settings; "
                    "\"Save checkpoint\" writes it back there")
        ->type_name("DIR");
    c->ov.add(cmd);
    cmd->add_option("--method", c->method,
                    "Renderer shown live: beams (progressive photon beams) | pt (unbiased path tracer) | preview "
                    "(geometry, steady only)")
        ->check(CLI::IsMember({"beams", "pt", "preview"}));
    cmd->add_option("--spp", c->spp, "--method pt: camera paths per pixel per pass")
        ->transform(flags::integer(1, 1 << 20, "camera paths per pixel per pass"));
    // In the viewer --time is the time shown (ns); the render's time budget is --time-budget.
    cmd->remove_option(cmd->get_option("--time"));
    // Every flag is checked while parsing (cli_common.h flags::), as for `tpb render`: a bad value is
    // refused with its range and exit code 2 before the scene loads or a window opens.
    cmd->add_option("--time-budget", c->ov.timeBudget, "Render time budget in seconds")
        ->check(flags::number(0.0, std::numeric_limits<double>::infinity(), false, "seconds; 0 = no time budget"));
    CLI::Option* shot = cmd->add_option("--screenshot", o->screenshot,
                                        "Save a PNG of the window after --after-passes passes, then exit");
    cmd->add_option("--after-passes", o->afterPasses, "Passes to render before the screenshot (default 1)")
        ->needs(shot)
        ->transform(flags::integer(1, INT64_MAX, "passes rendered before the screenshot"));
    cmd->add_option("--export", o->exportDir,
                    "With --screenshot: once the passes are done, export the current frame and the steady "
                    "state to this folder by clicking the Export buttons")
        ->needs(shot);
    cmd->add_option("--export-folder", o->exportFolder, "The Export section's folder (default out/view)");
    cmd->add_option("--click", o->clicks,
                    "With --screenshot: once the passes are done, click this control before the screenshot, "
                    "as 'Section/label' (e.g. 'View/Continuous emission', 'Export/Steady state'), or press a key as "
                    "'key:NAME' (Escape, Q, F, 1, Left, Right, Space; on the frame after the previous click); "
                    "repeatable, in order")
        ->needs(shot)
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    CLI::Option* t =
        cmd->add_option("--time", o->timeNs,
                        "Time shown, in ns, within the film (the bin containing it; default: the bin of peak energy)");
    cmd->add_option("--bin", o->bin, "Time bin shown, 0 to bins - 1 (default: the bin of peak energy)")->excludes(t);
    CLI::Option* unwarp = cmd->add_flag("--unwarp", o->unwarp, "Start in camera-unwarped time");
    cmd->add_flag("--real-time", o->realTime, "Start in real time (the default)")->excludes(unwarp);
    CLI::Option* continuous = cmd->add_flag("--continuous", o->continuous, "Start with continuous emission");
    cmd->add_flag("--delta", o->delta, "Start with a delta pulse (the default)")->excludes(continuous);
    // The exposure slider's range; leaving the flag out means automatic exposure.
    cmd->add_option("--exposure", o->exposure, "Exposure in EV (default: automatic)")
        ->check(flags::number(-kMaxExposureEv, kMaxExposureEv, false, "EV; leave it out for automatic exposure"));
    cmd->add_option("--pulse", o->pulse, "Start with this pulse shape: delta | gaussian:FWHM_NS | square:WIDTH_NS")
        ->check(flags::pulse());
    cmd->add_option("--sensor", o->sensor, "Start with this sensor response: ideal | gaussian:FWHM_NS | exp:TAU_NS")
        ->check(flags::sensor());
    cmd->add_option("--counts", o->counts,
                    "Start with the film read as SPAD photon counts: off | photons=P,efficiency=E,dark_hz=R,"
                    "ambient_hz=R,cycles=N,afterpulse=P,afterpulse_ns=T,pileup,coates,seed=S")
        ->check(flags::counts());
    cmd->add_flag("--false-color", o->falseColor, "Start with the false-colour intensity map");
    cmd->add_flag("--no-srgb", o->noSrgb, "Show linear values (no sRGB encoding)");
    CLI::Option* steady =
        cmd->add_flag("--steady", o->steady,
                      "Start on the steady-state image (the default without --bin/--time, until a time is picked)");
    cmd->add_flag("--frame", o->frame, "Start on a time frame (the bin of peak energy without --bin/--time)")
        ->excludes(steady);
    cmd->add_option("--pixel", o->pixel, "Selected pixel: X Y (time profile; Y is the streak row)")->expected(2);
    cmd->add_option("--window-size", o->windowSize, "Window size: W H (default 1280 800)")
        ->expected(2)
        ->transform(flags::integer(64, kMaxWindowPx, "window pixels, width and height"));
    cmd->callback([c] { run(*c); });
}

}  // namespace tpb::app
