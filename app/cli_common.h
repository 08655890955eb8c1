// Options shared by the subcommands that render (render, view, converge, bench): scene loading
// and command-line overrides of the scene's render settings.
#pragma once
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "driver.h"
#include "film_export.h"
#include "scene.h"
#include "scene_loader.h"

#include <functional>
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
    bool ptFreeFlight = false;  // path tracer: no equiangular sampling (for comparisons)

    void add(CLI::App* cmd);
    // Applies the overrides that change the scene description (resolution, bins).
    void applyToDesc(SceneDesc& desc) const;
    // Applies the rest to the driver settings.
    void applyToSettings(DriverSettings& s) const;
};

// Loads, validates and builds a scene, printing the loader's warnings to stderr.
std::unique_ptr<Scene> loadAndBuild(const std::string& path, const RenderOverrides& ov);

// The film's time axis as written in summary.json and reference headers.
nlohmann::json filmJson(const Scene& scene);
// Fields every summary.json starts with (scene, method, passes, wall time, resolution, film, frames).
nlohmann::json summaryHeader(const Scene& scene, const char* method, size_t passes, double wallSec,
                             const TransientFilm& film, const ExportOptions& opt);

// What `tpb render` writes after rendering, with either method (beams or --method pt).
struct RenderOutputs {
    std::string out;
    ExportOptions opt;
    bool noFrames = false, quiet = false;
    int strip = 8;
    double stripEv = 0.0;
};

struct OutputReport {
    int framesWritten = 0, framesExpected = 0;
    std::vector<std::string> kept;  // files written completely, relative to `out`
    std::string error;              // the first write failure, or empty
};

// Before rendering: warns when the frames, uncompressed, would not fit in the free space of the
// output folder's file system (they are ZIP-compressed, so they often fit anyway).
void warnIfOutputsMayNotFit(const Scene& scene, const RenderOutputs& r);

// Writes steady.exr and steady.png, summary.json, frames/ and strip.png, in that order (small and
// most valuable first), then summary.json again with the final "outputs" record. `summary()` gives
// summary.json's content; "outputs" (frames expected/written, kept files, error) is added here.
// A failure writing frames or the strip (full disk...) keeps every complete file, records it in
// summary.json if it still fits, prints the error and what was kept, and sets the exit code to 2.
// A failure writing steady.exr/.png or the first summary.json is thrown as UserError.
OutputReport writeRenderOutputs(const TransientFilm& film, const RenderOutputs& r,
                                const std::function<nlohmann::json()>& summary);

}  // namespace tpb::app
