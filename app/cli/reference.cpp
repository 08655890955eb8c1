// `tpb reference`: render (or reuse) a reference transient volume, core/eval/reference.h.
#include "cli/reference.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/interrupt.h"
#include "base/error.h"
#include "eval/reference.h"
#include "film/picture_export.h"
#include "io/image_io.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace tpb::app {

namespace {

namespace fs = std::filesystem;

struct ReferenceCmd {
    std::string scene, out, method = "pt";
    RenderOverrides ov;
    int spp = 4;
    int subpixels = 4;
    bool analytic = false, force = false, quiet = false;
};

std::string defaultReferencePath(const PreparedRender& p, const std::string& method) {
    const Scene& scene = *p.scene;
    const std::string stem = fs::path(p.source.path).stem().string();
    const std::string m = method == "analytic-single-scattering" ? "ss" : method;
    return "ref/" + stem + "-" + m + "-" + std::to_string(scene.camera.width) + "x" +
           std::to_string(scene.camera.height) + "x" + std::to_string(p.time.bins) + "-d" +
           std::to_string(p.settings.maxDepth) + ".tpbref";
}

void runReference(ReferenceCmd& c) {
    InterruptScope interrupts;  // Ctrl-C and SIGTERM: the finished passes are written (marked interrupted)
    if (c.analytic || c.method != "beams")
        c.ov.rejectBeamsOnlyFlags(c.analytic ? "analytic-single-scattering" : c.method);
    const PreparedRender prepared = loadAndBuild(c.scene, c.ov, LoadOptions{c.quiet});
    const Scene* scene = prepared.scene.get();
    const std::string method = c.analytic ? "analytic-single-scattering" : c.method;
    ReferenceInfo want = describeScene(*scene, prepared.time, prepared.source.path, prepared.settings);
    want.method = method;
    ReferenceJob job;
    job.method = method;
    if (c.analytic) {
        want.maxDepth = 1;
        if (prepared.settings.maxDepth != 1 && c.ov.maxDepth)
            throw UserError("--analytic-single-scattering is single scattering: --max-depth must be 1 (or left out)");
    } else {
        if (!c.ov.passes && !c.ov.timeBudget) throw UserError("a reference needs --passes N or --time SECONDS");
        job.passes = c.ov.passes.value_or(0);
        job.timeBudgetSec = c.ov.timeBudget.value_or(0.0);  // (both validated: prepareRender)
        want.requestedPasses = job.passes;
        want.requestedTimeSec = job.timeBudgetSec;
        if (method == "pt") {
            job.pt = prepared.settings;
            job.pt.samplesPerPixel = c.spp;
            job.pt.method = Method::PathTracer;
            setSettings(want, job.pt);
        } else {
            job.beams = prepared.settings;
            setSettings(want, job.beams);
        }
    }
    const std::string out = c.out.empty() ? defaultReferencePath(prepared, method) : c.out;
    if (!c.force && fileExists(out)) {
        try {
            const ReferenceInfo have = readReferenceInfo(out);
            const std::vector<std::string> diff = cacheMismatches(have, want);
            if (diff.empty()) {
                std::printf("reusing the cached reference (same settings; --force to re-render)\n");
                printReference(out, have);
                return;
            }
            std::printf("%s exists but was rendered with other settings; re-rendering it:\n", out.c_str());
            for (const std::string& d : diff) std::printf("  - %s\n", d.c_str());
        } catch (const UserError& e) {
            std::printf("%s is not a usable reference (%s); re-rendering it\n", out.c_str(), e.what());
        }
    }
    // Fail on an unwritable destination before spending the time budget.
    const fs::path parent = fs::path(out).parent_path();
    if (!parent.empty()) ensureWritableDir(parent.string());

    ReferenceVolume ref;
    if (c.analytic) {
        if (!c.quiet)
            std::fprintf(stderr, "single-scattering quadrature, %d x %d rays per pixel...\n", c.subpixels, c.subpixels);
        ref = singleScatteringReference(*scene, prepared.time, prepared.source.path, prepared.settings, c.subpixels,
                                        c.ov.threads.value_or(0));
        throwIfInterrupted("during the single-scattering quadrature");
    } else {
        double lastPrint = 0.0;
        const bool tty = isatty(STDERR_FILENO) && !c.quiet;
        ref = renderReference(
            *scene, prepared.time, prepared.source.path, job, &interruptFlag(), [&](int64_t passes, double elapsed) {
                if (c.quiet) return;
                if (tty) {
                    std::fprintf(stderr, "\rreference: pass %lld, %.1f s ", static_cast<long long>(passes), elapsed);
                } else if (elapsed - lastPrint >= 30.0 || passes == 1) {
                    std::fprintf(stderr, "reference: pass %lld, %.1f s\n", static_cast<long long>(passes), elapsed);
                    lastPrint = elapsed;
                }
            });
        if (tty) std::fprintf(stderr, "\n");
        if (interrupted())
            std::fprintf(stderr, "interrupted by %s: writing the %lld finished passes (marked interrupted)\n",
                         interruptName().c_str(), static_cast<long long>(ref.info.passes));
        if (interrupted() && ref.info.passes == 0) throwIfInterrupted("before the first pass finished");
    }
    writeReference(out, ref);
    writeAutoExposedPng(out + ".steady.png", ref.info.width, ref.info.height, ref.steady, ToneMap{});
    std::printf("wrote ");
    printReference(out, ref.info);
    if (interrupted()) exitCode() = exitCodeAfterInterrupt();
}

}  // namespace

void printReference(const std::string& path, const ReferenceInfo& i) {
    std::printf("%s: %s, %dx%d, %d bins [%.4g, %.4g] m OPL, max depth %d", path.c_str(), i.method.c_str(), i.width,
                i.height, i.bins, i.startOpl, i.startOpl + i.bins * i.binWidth, i.maxDepth);
    if (i.method == "pt")
        std::printf(", %lld passes x %d spp, seed %llu", static_cast<long long>(i.passes), i.samplesPerPixel,
                    static_cast<unsigned long long>(i.seed));
    if (i.method == "beams") std::printf(", %lld passes", static_cast<long long>(i.passes));
    std::printf(", %.1f s%s\n", i.wallSeconds, i.interrupted ? " (interrupted)" : "");
    if (i.selfErrorReal >= 0.0)
        std::printf("  its own relative RMSE (%s): volume real %.4g, unwarped %.4g, steady %.4g\n",
                    i.selfErrorEstimate.c_str(), i.selfErrorReal, i.selfErrorUnwarped, i.selfErrorSteady);
    else
        std::printf("  its own error: %s\n", i.selfErrorEstimate.c_str());
}

void registerReference(CLI::App& app) {
    auto c = std::make_shared<ReferenceCmd>();
    CLI::App* cmd =
        app.add_subcommand("reference",
                           "Render a reference transient volume (path tracer by default, or the single-scattering "
                           "quadrature) into a .tpbref file; reused when it exists with the same settings");
    cmd->add_option("scene", c->scene, "Scene file (JSON or Mitsuba 3 XML)")->required();
    cmd->add_option("-o,--out", c->out,
                    "Reference file (default: ref/<scene>-<method>-<W>x<H>x<bins>-d<depth>.tpbref)");
    cmd->add_option("--method", c->method, "Renderer: pt (unbiased path tracer) | beams")
        ->check(CLI::IsMember({"pt", "beams"}));
    cmd->add_option("--spp", c->spp, "Path tracer: camera paths per pixel per pass")
        ->transform(flags::integer(1, 1 << 20, "camera paths per pixel per pass"));
    cmd->add_flag("--analytic-single-scattering", c->analytic,
                  "Quadrature of single scattering (one point light in an infinite medium, no shapes)");
    cmd->add_option("--subpixels", c->subpixels, "Quadrature: N x N rays per pixel")
        ->transform(flags::integer(1, 64, "N x N rays per pixel"));
    cmd->add_flag("--force", c->force, "Re-render even if the file exists with the same settings");
    cmd->add_flag("-q,--quiet", c->quiet, "No progress output");
    c->ov.add(cmd);
    cmd->callback([c] { runReference(*c); });
}

}  // namespace tpb::app
