// Options shared by the subcommands that render (render, view, converge, bench): scene loading
// and command-line overrides of the scene's render settings; flag validation; the output folder
// (lock, stale outputs); the checks and reports around a render's outputs.
#pragma once
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "render/driver.h"
#include "film/film_export.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace tpb::app {

// ---- flag validation --------------------------------------------------------------------------
// CLI11 validators whose messages name the allowed range and the meaning of special values, and
// that check finiteness ("--time nan" used to render forever). integer() and threads() rewrite the
// value (1e6 -> 1000000, a capped thread count), so they are attached with ->transform(), the
// others with ->check(). They run while the command line is
// parsed, before any subcommand starts, so a bad flag never leaves a file behind. CLI11 prefixes
// the flag: "error: --passes: must be an integer >= 0 (0 = ...); got -3".
namespace flags {
// An integer in [lo, hi]; an integral number written as 1e6 is accepted (and rewritten as digits).
CLI::Validator integer(int64_t lo, int64_t hi, const std::string& meaning = "");
// A finite number in [lo, hi] (or (lo, hi] when loOpen).
CLI::Validator number(double lo, double hi, bool loOpen, const std::string& meaning = "");
// A seed: an integer in [0, 2^64 - 1] (strtoull would wrap -1 to 2^64 - 1).
CLI::Validator seed();
// Worker threads: an integer >= 0; more than maxUsefulThreads() is capped with a warning.
CLI::Validator threads();
}  // namespace flags

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
    void applyToSettings(RenderSettings& s) const;
};

struct LoadOptions {
    bool quiet = false;  // no pilot progress
};

// Loads, validates and builds a scene, printing the loader's warnings to stderr; fits an automatic
// film range with the pilot (progress on a terminal; Ctrl-C/SIGTERM abort it: Interrupted, see
// cli_interrupt.h); refuses kernel radii that would make a pass quadratic (kMaxRadiusFraction).
std::unique_ptr<Scene> loadAndBuild(const std::string& path, const RenderOverrides& ov, const LoadOptions& lo = {});

// The film's time axis as written in summary.json and reference headers.
nlohmann::json filmJson(const Scene& scene);
// Fields every summary.json starts with (scene, method, passes, wall time, resolution, film, frames,
// film_energy: the shares of the energy before / inside / after the film per axis, rejected
// samples and overflowed pixel sums).
nlohmann::json summaryHeader(const Scene& scene, const char* method, size_t passes, double wallSec,
                             const TransientFilm& film, const ExportOptions& opt);

// Replaces every non-finite number in `j` by the string "inf", "-inf" or "nan" (JSON has no such
// numbers and nlohmann would write null, which reads as "unknown"); returns how many it replaced.
int64_t replaceNonFiniteNumbers(nlohmann::json& j);
// Warns on stderr when the film dropped pixel sums that would have overflowed its floats
// (FilmStats::overflowedPixels), naming the fix; returns that count.
int64_t warnFilmOverflow(const Scene& scene, const TransientFilm& film);

// ---- the output folder ------------------------------------------------------------------------
// A folder one tpb run writes into (render, converge). The constructor creates it if needed, takes
// an exclusive lock (flock on <dir>/.tpb.lock: the kernel releases it when the process ends, a
// crash included; a second run into the same folder is refused with a UserError naming the other
// process and the fix), then removes the outputs of the previous run into the folder: exactly the
// files its manifest (<dir>/.tpb-manifest.json) lists, or, for a folder written before manifests
// existed, what its summary.json lists. Files tpb did not write are never touched. The new run's
// files are recorded in the manifest before any of them is written, so that a run that dies while
// writing still leaves them listed for the next one.
struct OutputFiles {
    std::vector<std::string> files;  // relative to the folder
    std::string framesDir;           // "" = no frames; else frame_NNNNN.exr for bins first..last step
    int firstBin = 0, lastBin = -1, binStep = 1;
};
class OutputFolder {
public:
    OutputFolder(const std::string& dir, const std::string& command, const OutputFiles& outputs);
    ~OutputFolder();
    OutputFolder(const OutputFolder&) = delete;
    OutputFolder& operator=(const OutputFolder&) = delete;
    const std::string& dir() const { return dir_; }
    // Stale files of the previous run that the constructor removed (relative paths).
    const std::vector<std::string>& removed() const { return removed_; }

private:
    std::string dir_;
    int lockFd_ = -1;
    std::vector<std::string> removed_;
};

// What `tpb render` writes after rendering, with either method (beams or --method pt).
struct RenderOutputs {
    std::string out;
    ExportOptions opt;
    bool noFrames = false, quiet = false;
    int strip = 8;
    double stripEv = 0.0;
};
// The files RenderOutputs writes for a film of `bins` bins (preview.exr/png included).
OutputFiles renderOutputFiles(const RenderOutputs& r, int bins);

struct OutputReport {
    int framesWritten = 0, framesExpected = 0;
    std::vector<std::string> kept;  // files written completely, relative to `out`
    std::string error;              // the first write failure, or empty
    bool interrupted = false;       // a signal stopped the frame export
};

// Before rendering: the number, size and estimated write time of the frames (from the time
// `previewExrSec` that writing preview.exr, an image of the same size, took), and a warning when
// they may not fit in the free space of the output folder's file system.
void reportPlannedOutputs(const Scene& scene, const RenderOutputs& r, double previewExrSec);

// Writes steady.exr and steady.png, summary.json, frames/ and strip.png, in that order (small and
// most valuable first), then summary.json again with the final "outputs" record. `summary()` gives
// summary.json's content; "outputs" (frames expected/written, kept files, error) is added here.
// A failure writing frames or the strip (full disk...) keeps every complete file, records it in
// summary.json if it still fits, prints the error and what was kept, and sets the exit code to 2.
// A failure writing steady.exr/.png or the first summary.json is thrown as UserError. A first
// Ctrl-C/SIGTERM during the frame export stops it after the frame in progress (recorded the same
// way; exit code 128 + the signal).
OutputReport writeRenderOutputs(const TransientFilm& film, const RenderOutputs& r,
                                const std::function<nlohmann::json()>& summary);

// After the outputs are written: the share of the energy that reached the camera outside the
// film's time range, on the frames' axis. Above kOutsideWarnFraction: a warning; everything
// outside (every frame black): an error (exit code 2) that says which range would cover the
// arrivals (measured with a pilot pass) or to use "range": "auto". Returns the fraction (0 when
// no energy reached the camera at all).
inline constexpr double kOutsideWarnFraction = 0.05;
double checkEnergyInsideFilm(const Scene& scene, const TransientFilm& film, TimeAxis axis, int threads);

}  // namespace tpb::app
