// `tpb info`: what a scene contains, which stages will run and why, and the memory they need.
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/interrupt.h"
#include "cli/commands.h"
#include "render/auto_radius.h"

#include <cmath>
#include <cstdio>

namespace tpb::app {

namespace {

const char* materialName(MaterialType t) {
    switch (t) {
        case MaterialType::Diffuse: return "diffuse";
        case MaterialType::Mirror: return "mirror";
        case MaterialType::Dielectric: return "dielectric";
        case MaterialType::Null: return "null (index-matched boundary)";
    }
    return "?";
}
const char* lightName(LightType t) {
    switch (t) {
        case LightType::Point: return "point";
        case LightType::Spot: return "spot";
        case LightType::AreaQuad: return "area";
        case LightType::Laser: return "laser";
    }
    return "?";
}

void run(const std::string& path, const RenderOverrides& ov) {
    InterruptScope interrupts;  // the pilot of an automatic range polls Ctrl-C/SIGTERM
    const PreparedRender p = loadAndBuild(path, ov);
    const Scene* s = p.scene.get();
    const RenderSettings& ds = p.settings;
    const Camera& cam = s->camera;
    const double fovYDeg = 2.0 * std::atan(cam.tanHalfFovY) * 180.0 / kPi;
    std::printf("scene      %s (version %d)\n", path.c_str(), p.source.version);
    std::printf("camera     %dx%d, fov %.1f deg, at (%.3g, %.3g, %.3g)\n", cam.width, cam.height, fovYDeg,
                cam.position.x, cam.position.y, cam.position.z);
    std::printf("bounds     (%.3g, %.3g, %.3g) - (%.3g, %.3g, %.3g), diagonal %.4g m\n", s->bounds.lo.x, s->bounds.lo.y,
                s->bounds.lo.z, s->bounds.hi.x, s->bounds.hi.y, s->bounds.hi.z, s->bounds.diagonal());
    std::printf("geometry   %zu triangles, %zu spheres, %zu shapes\n", s->geometry.triangleCount(),
                s->geometry.sphereCount(), s->shapes.size());
    for (size_t i = 0; i < s->shapes.size(); ++i) {
        const ShapeInfo& sh = s->shapes[i];
        std::printf("  shape %-20s %s%s\n", sh.name.c_str(),
                    sh.areaLight >= 0 ? "area light surface" : sh.material >= 0 ? materialName(s->materials[sh.material].type) : "no material",
                    sh.interiorRegion > 0 ? (" -> region " + std::to_string(sh.interiorRegion)).c_str() : "");
    }
    for (size_t r = 0; r < s->regions.size(); ++r) {
        const Region& g = s->regions[r];
        const Medium& m = g.medium;
        std::printf("region %zu   %s, ior %.3g", r, r == 0 ? "outside" : "inside a shape", g.ior);
        if (g.hasMedium)
            std::printf(", sigma_s (%.3g %.3g %.3g) /m, sigma_a (%.3g %.3g %.3g) /m, g %.3g", m.sigma_s.x, m.sigma_s.y,
                        m.sigma_s.z, m.sigma_a.x, m.sigma_a.y, m.sigma_a.z, m.phase.g);
        else
            std::printf(", no medium");
        std::printf("\n");
    }
    for (const Light& l : s->lights)
        std::printf("light      %s, power (%.3g %.3g %.3g) W, pulse at %.4g m OPL (%.4g ns)\n", lightName(l.type), l.power.x,
                    l.power.y, l.power.z, l.emitOpl, l.emitOpl / kC_m_per_ns);
    const TimeBins& t = p.time;
    std::printf("film       %d bins of %.4g m OPL (%.4g ns), from %.4g to %.4g m (%.4g to %.4g ns)%s\n", t.bins, t.binWidth,
                t.binWidth / kC_m_per_ns, t.startOpl, t.endOpl(), t.startOpl / kC_m_per_ns, t.endOpl() / kC_m_per_ns,
                p.film.autoRange ? " [auto]" : "");
    std::printf("memory     transient film (2 time axes, RGB float + steady double): %s\n",
                humanBytes(filmBytes(cam.width, cam.height, t.bins)).c_str());
    std::printf("           per worker thread: pixel accumulator %s\n",
                humanBytes(static_cast<uint64_t>(t.bins) * 2 * 3 * sizeof(double)).c_str());
    const uint64_t beamBytes = static_cast<uint64_t>(ds.photonsPerPass) * 4 * (sizeof(double) * 12 + 16);
    std::printf("           photon map per pass (rough, ~4 segments per photon): %s\n", humanBytes(beamBytes).c_str());
    std::printf("render     %lld photons/pass, beam radius %.4g m, surface radius %.4g m, alpha %.3g, %lld passes%s\n",
                static_cast<long long>(ds.photonsPerPass), ds.beamRadius0, ds.surfaceRadius0, ds.alpha,
                static_cast<long long>(ds.passes), ds.timeBudgetSec > 0 ? (", budget " + std::to_string(ds.timeBudgetSec) + " s").c_str() : "");
    // The photon density of a pilot pass, and the radius "auto" picks from it (render/auto_radius.h).
    if (s->stages.beams && ds.method == Method::Beams) {
        // Measured once: prepareRender's when the radius is "auto", else here.
        const RadiusPilot rp = p.radiusPilot.measured ? p.radiusPilot : pilotRadius(*s, ds, &interruptFlag());
        throwIfInterrupted("while measuring the photon density (radius pilot)");
        if (rp.measured)
            std::printf("density    pilot pass of %lld photons (x%.3g for the pass): %s; the radius %.4g m gathers ~%.3g per ray%s\n",
                        static_cast<long long>(rp.photons), rp.scale, rp.why.c_str(), ds.beamRadius0, rp.gathered(ds.beamRadius0),
                        p.radiusPilot.measured ? " (chosen: \"radius\": \"auto\")" : "");
        else
            std::printf("density    %s\n", rp.why.c_str());
    }
    std::printf("estimators volume %s, surface %s, time kernel %s\n", ds.volumeEstimator.c_str(), ds.surfaceEstimator.c_str(),
                timeKernelName(ds.timeKernel).c_str());
    std::printf("stages\n");
    for (const std::string& r : s->stages.reasons) std::printf("  - %s\n", r.c_str());
}

}  // namespace

void registerInfo(CLI::App& app) {
    auto path = std::make_shared<std::string>();
    auto ov = std::make_shared<RenderOverrides>();
    CLI::App* cmd = app.add_subcommand("info", "Print what a scene contains, the stages that will run and the memory needed");
    cmd->add_option("scene", *path, "Scene file (JSON)")->required();
    ov->add(cmd);
    cmd->callback([path, ov] { run(*path, *ov); });
}

}  // namespace tpb::app
