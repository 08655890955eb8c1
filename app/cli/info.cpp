// `tpb info`: what a scene contains, which stages will run and why, and the memory they need.
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/interrupt.h"
#include "cli/commands.h"
#include "cli/summary.h"
#include "base/error.h"
#include "io/record_json.h"
#include "render/auto_radius.h"

#include <nlohmann/json.hpp>

#include <array>

#include <cmath>
#include <cstdio>

namespace tpb::app {

namespace {

const char* materialName(MaterialType t) {
    return t == MaterialType::Null ? "null (index-matched boundary)" : materialTypeName(t);
}

nlohmann::json vec3(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

// Everything `tpb info` says, as the object `tpb info --json` prints (docs/user/outputs.md
// documents each key); the text form is printed from it.
nlohmann::json describe(const std::string& path, const PreparedRender& p) {
    using nlohmann::json;
    const Scene* s = p.scene.get();
    const RenderSettings& ds = p.settings;
    const Camera& cam = s->camera;
    json j;
    j["scene"] = {{"path", path}, {"version", p.source.version}};
    j["camera"] = {{"width", cam.width},
                   {"height", cam.height},
                   {"fov_y_deg", 2.0 * std::atan(cam.tanHalfFovY) * 180.0 / kPi},
                   {"position", vec3(cam.position)},
                   {"type", cam.relayWall ? "relay_wall" : "pinhole"}};
    if (cam.relayWall)
        j["camera"]["relay_wall"] = {{"corner", vec3(cam.wallCorner)},
                                     {"edge_u", vec3(cam.wallU)},
                                     {"edge_v", vec3(cam.wallV)},
                                     {"time_origin", cam.timeFromWall ? "wall" : "sensor"},
                                     {"sensor_grid", {cam.width, cam.sensorRows}},
                                     {"scan", scanModeName(cam.scan)}};
    if (cam.scan != ScanMode::None) j["camera"]["relay_wall"]["laser_points"] = cam.laserPoints();
    if (cam.scan == ScanMode::Exhaustive) j["camera"]["relay_wall"]["laser_grid"] = {cam.laserGridX, cam.laserGridY};
    j["bounds"] = {{"min", vec3(s->bounds.lo)}, {"max", vec3(s->bounds.hi)}, {"diagonal_m", s->bounds.diagonal()}};
    j["geometry"] = {{"triangles", s->geometry.triangleCount()},
                     {"spheres", s->geometry.sphereCount()},
                     {"shapes", s->shapes.size()}};
    json shapes = json::array();
    for (const ShapeInfo& sh : s->shapes)
        shapes.push_back({{"name", sh.name},
                          {"kind", sh.areaLight >= 0  ? "area light surface"
                                   : sh.material >= 0 ? materialName(s->materials[sh.material].type)
                                                      : "no material"},
                          {"interior_region", sh.interiorRegion > 0 ? json(sh.interiorRegion) : json(nullptr)}});
    j["shapes"] = shapes;
    json regions = json::array();
    for (size_t r = 0; r < s->regions.size(); ++r) {
        const Region& g = s->regions[r];
        json m = nullptr;
        if (g.hasMedium)
            m = {{"sigma_s_per_m", vec3(g.medium.sigma_s)},
                 {"sigma_a_per_m", vec3(g.medium.sigma_a)},
                 {"g", g.medium.phase.g}};
        regions.push_back(
            {{"index", r}, {"where", r == 0 ? "outside" : "inside a shape"}, {"ior", g.ior}, {"medium", m}});
    }
    j["regions"] = regions;
    json lights = json::array();
    for (const Light& l : s->lights)
        lights.push_back({{"type", lightTypeName(l.type)},
                          {"power_w", vec3(l.power)},
                          {"pulse_opl_m", l.emitOpl},
                          {"pulse_ns", l.emitOpl / kC_m_per_ns}});
    j["lights"] = lights;
    const TimeBins& t = p.time;
    j["film"] = filmJson(t);
    j["film"]["end_opl_m"] = t.endOpl();
    j["film"]["end_ns"] = t.endOpl() / kC_m_per_ns;
    j["film"]["auto_range"] = p.film.autoRange;
    j["memory"] = {
        {"film_bytes", filmBytes(cam.width, cam.height, t.bins)},
        {"pixel_accumulator_bytes_per_thread", static_cast<uint64_t>(t.bins) * 2 * 3 * sizeof(double)},
        {"photon_map_bytes_per_pass_rough", static_cast<uint64_t>(ds.photonsPerPass) * 4 * (sizeof(double) * 12 + 16)}};
    j["render"] = recordJson(settingsRecord(ds));  // the one serialisation of the settings
    j["density"] = nullptr;
    // The photon density of a pilot pass, and the radius "auto" picks from it (render/auto_radius.h).
    if (s->stages.beams && ds.method == Method::Beams) {
        // Measured once: prepareRender's when the radius is "auto", else here.
        const RadiusPilot rp = p.radiusPilot.measured ? p.radiusPilot : pilotRadius(*s, ds, &interruptFlag());
        throwIfInterrupted("while measuring the photon density (radius pilot)");
        j["density"] = {{"measured", rp.measured}, {"why", rp.why}};
        if (rp.measured) {
            j["density"]["pilot_photons"] = rp.photons;
            j["density"]["scale_to_pass"] = rp.scale;
            j["density"]["gathered_per_ray"] = rp.gathered(ds.beamRadius0);
            j["density"]["radius_chosen_automatically"] = p.radiusPilot.measured;
        }
    }
    j["stages"] = s->stages.reasons;
    return j;
}

void printText(const nlohmann::json& j) {
    const auto v3 = [](const nlohmann::json& a) {
        return std::array<double, 3>{a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
    };
    const auto& cam = j["camera"];
    const auto pos = v3(cam["position"]);
    std::printf("scene      %s (version %d)\n", j["scene"]["path"].get<std::string>().c_str(),
                j["scene"]["version"].get<int>());
    if (cam.contains("relay_wall")) {
        const auto& rw = cam["relay_wall"];
        std::printf("camera     relay wall: %dx%d grid, sensor at (%.3g, %.3g, %.3g), time from the %s\n",
                    rw["sensor_grid"][0].get<int>(), rw["sensor_grid"][1].get<int>(), pos[0], pos[1], pos[2],
                    rw["time_origin"].get<std::string>().c_str());
        if (rw.contains("laser_points"))
            std::printf("scan       %s, %lld laser point(s) per pass%s\n", rw["scan"].get<std::string>().c_str(),
                        static_cast<long long>(rw["laser_points"].get<int64_t>()),
                        rw.contains("laser_grid")
                            ? (" (" + std::to_string(rw["laser_grid"][0].get<int>()) + " x " +
                               std::to_string(rw["laser_grid"][1].get<int>()) +
                               "; the film stacks one image each: " + std::to_string(cam["width"].get<int>()) + "x" +
                               std::to_string(cam["height"].get<int>()) + ")")
                                  .c_str()
                            : "");
    } else
        std::printf("camera     %dx%d, fov %.1f deg, at (%.3g, %.3g, %.3g)\n", cam["width"].get<int>(),
                    cam["height"].get<int>(), cam["fov_y_deg"].get<double>(), pos[0], pos[1], pos[2]);
    const auto lo = v3(j["bounds"]["min"]), hi = v3(j["bounds"]["max"]);
    std::printf("bounds     (%.3g, %.3g, %.3g) - (%.3g, %.3g, %.3g), diagonal %.4g m\n", lo[0], lo[1], lo[2], hi[0],
                hi[1], hi[2], j["bounds"]["diagonal_m"].get<double>());
    std::printf("geometry   %zu triangles, %zu spheres, %zu shapes\n", j["geometry"]["triangles"].get<size_t>(),
                j["geometry"]["spheres"].get<size_t>(), j["geometry"]["shapes"].get<size_t>());
    for (const auto& sh : j["shapes"])
        std::printf("  shape %-20s %s%s\n", sh["name"].get<std::string>().c_str(),
                    sh["kind"].get<std::string>().c_str(),
                    sh["interior_region"].is_null()
                        ? ""
                        : (" -> region " + std::to_string(sh["interior_region"].get<int>())).c_str());
    for (const auto& g : j["regions"]) {
        std::printf("region %zu   %s, ior %.3g", g["index"].get<size_t>(), g["where"].get<std::string>().c_str(),
                    g["ior"].get<double>());
        if (!g["medium"].is_null()) {
            const auto ss = v3(g["medium"]["sigma_s_per_m"]), sa = v3(g["medium"]["sigma_a_per_m"]);
            std::printf(", sigma_s (%.3g %.3g %.3g) /m, sigma_a (%.3g %.3g %.3g) /m, g %.3g", ss[0], ss[1], ss[2],
                        sa[0], sa[1], sa[2], g["medium"]["g"].get<double>());
        } else {
            std::printf(", no medium");
        }
        std::printf("\n");
    }
    for (const auto& l : j["lights"]) {
        const auto pw = v3(l["power_w"]);
        std::printf("light      %s, power (%.3g %.3g %.3g) W, pulse at %.4g m OPL (%.4g ns)\n",
                    l["type"].get<std::string>().c_str(), pw[0], pw[1], pw[2], l["pulse_opl_m"].get<double>(),
                    l["pulse_ns"].get<double>());
    }
    const auto& f = j["film"];
    std::printf("film       %d bins of %.4g m OPL (%.4g ns), from %.4g to %.4g m (%.4g to %.4g ns)%s\n",
                f["bins"].get<int>(), f["bin_width_opl_m"].get<double>(), f["bin_width_ns"].get<double>(),
                f["start_opl_m"].get<double>(), f["end_opl_m"].get<double>(), f["start_ns"].get<double>(),
                f["end_ns"].get<double>(), f["auto_range"].get<bool>() ? " [auto]" : "");
    const auto& m = j["memory"];
    std::printf("memory     transient film (2 time axes, RGB float + steady double): %s\n",
                humanBytes(m["film_bytes"].get<uint64_t>()).c_str());
    std::printf("           per worker thread: pixel accumulator %s\n",
                humanBytes(m["pixel_accumulator_bytes_per_thread"].get<uint64_t>()).c_str());
    std::printf("           photon map per pass (rough, ~4 segments per photon): %s\n",
                humanBytes(m["photon_map_bytes_per_pass_rough"].get<uint64_t>()).c_str());
    const auto& r = j["render"];
    const double budget = r["time_budget_s"].get<double>();
    const std::string passes = std::to_string(r["passes"].get<long long>()) + " passes" +
                               (budget > 0 ? ", budget " + shortNumber(budget) + " s" : "");
    if (r.contains("photons_per_pass"))
        std::printf("render     %s: %lld photons/pass, beam radius %.4g m, surface radius %.4g m, alpha %.3g, %s\n",
                    r["method"].get<std::string>().c_str(), r["photons_per_pass"].get<long long>(),
                    r["radius"].get<double>(), r["surface_radius"].get<double>(), r["alpha"].get<double>(),
                    passes.c_str());
    else
        std::printf("render     %s: %s\n", r["method"].get<std::string>().c_str(), passes.c_str());
    const auto& d = j["density"];
    if (!d.is_null()) {
        if (d["measured"].get<bool>())
            std::printf(
                "density    pilot pass of %lld photons (x%.3g for the pass): %s; the radius %.4g m gathers ~%.3g per "
                "ray%s\n",
                d["pilot_photons"].get<long long>(), d["scale_to_pass"].get<double>(),
                d["why"].get<std::string>().c_str(), r["radius"].get<double>(), d["gathered_per_ray"].get<double>(),
                d["radius_chosen_automatically"].get<bool>() ? " (chosen: \"radius\": \"auto\")" : "");
        else
            std::printf("density    %s\n", d["why"].get<std::string>().c_str());
    }
    if (r.contains("volume_estimator"))
        std::printf("estimators volume %s, surface %s, time kernel %s\n",
                    r["volume_estimator"].get<std::string>().c_str(), r["surface_estimator"].get<std::string>().c_str(),
                    r["time_kernel"].get<std::string>().c_str());
    std::printf("stages\n");
    for (const auto& st : j["stages"]) std::printf("  - %s\n", st.get<std::string>().c_str());
}

void run(const std::string& path, const RenderOverrides& ov, bool asJson) {
    InterruptScope interrupts;  // the pilot of an automatic range polls Ctrl-C/SIGTERM
    const PreparedRender p = loadAndBuild(path, ov, LoadOptions{asJson});
    nlohmann::json j = describe(path, p);
    if (asJson) {
        replaceNonFiniteNumbers(j);
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        printText(j);
    }
}

}  // namespace

void registerInfo(CLI::App& app) {
    auto path = std::make_shared<std::string>();
    auto ov = std::make_shared<RenderOverrides>();
    auto asJson = std::make_shared<bool>(false);
    CLI::App* cmd =
        app.add_subcommand("info", "Print what a scene contains, the stages that will run and the memory needed");
    cmd->add_option("scene", *path, "Scene file (JSON or Mitsuba 3 XML)")->required();
    ov->add(cmd);
    cmd->add_flag("--json", *asJson,
                  "Print everything as one JSON object on stdout (docs/user/outputs.md; warnings stay on stderr)");
    cmd->callback([path, ov, asJson] { run(*path, *ov, *asJson); });
}

}  // namespace tpb::app
