// Options shared by the subcommands that render (render, view, converge, bench): scene loading
// and command-line overrides of the scene's render settings.
#pragma once
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "driver.h"
#include "film_export.h"
#include "scene.h"
#include "scene_loader.h"

#include <memory>
#include <optional>
#include <string>

namespace tpb::app {

struct RenderOverrides {
    std::optional<int64_t> passes, photons;
    std::optional<double> timeBudget, radius, alpha;
    std::optional<int> threads, width, height, bins, maxDepth;
    std::optional<uint64_t> seed;
    std::string profile, beamLength, accel = "embree";

    void add(CLI::App* cmd);
    // Applies the overrides that change the scene description (resolution, bins).
    void applyToDesc(SceneDesc& desc) const;
    // Applies the rest to the driver settings.
    void applyToSettings(DriverSettings& s) const;
};

// Loads, validates and builds a scene, printing the loader's warnings to stderr.
std::unique_ptr<Scene> loadAndBuild(const std::string& path, const RenderOverrides& ov);

std::string humanBytes(uint64_t bytes);

// The film's time axis as written in summary.json and reference headers.
nlohmann::json filmJson(const Scene& scene);
// Fields every summary.json starts with (scene, method, passes, wall time, resolution, film, frames).
nlohmann::json summaryHeader(const Scene& scene, const char* method, size_t passes, double wallSec,
                             const TransientFilm& film, const ExportOptions& opt);

}  // namespace tpb::app
