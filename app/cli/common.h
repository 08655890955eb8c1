// Options shared by the subcommands that render (render, view, converge, bench): scene loading
// and command-line overrides of the scene's render settings; the output folder (lock, stale
// outputs); the checks and reports around a render's outputs. No third-party header: the flag
// validators are in cli/flags.h (CLI11), summary.json in cli/summary.h (nlohmann).
#pragma once
#include "render/driver.h"
#include "film/film_export.h"
#include "film/tone_map.h"
#include "film/volume_export.h"
#include "render/nlos_backprojection.h"
#include "render/prepare.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace CLI {
class App;
}
namespace tpb {
class FolderLock;
}

namespace tpb::app {

struct RenderOverrides {
    std::optional<int64_t> passes, photons;
    std::optional<int> warmup;
    std::optional<double> timeBudget, radius, alpha;
    bool autoRadius = false;
    std::optional<int> threads, width, height, bins, maxDepth;
    std::optional<uint64_t> seed;
    std::string profile, beamLength;
    std::optional<std::string> accel;    // "bvh" | "embree" | "brute"; unset = the default
    std::optional<std::string> bounces;  // "N", "MIN:MAX" or "MIN:" (the bounce filter)
    std::optional<std::string> estimator, surfaceEstimator, timeKernel;  // names checked by validate()
    std::optional<std::string> phasor;  // --phasor, read by prepareRender (film/phasor.h)
    bool ptFreeFlight = false;          // path tracer: no equiangular sampling (for comparisons)

    void add(CLI::App* cmd);
    // The overrides the flags give (prepareRender applies and validates them).
    SettingsOverrides settings() const;
    // Throws UserError when a flag of the photon-beams estimators (--estimator, --surface-estimator,
    // --time-kernel) is given to a command that runs `method` ("pt", "analytic-single-scattering").
    void rejectBeamsOnlyFlags(const std::string& method) const;
};

struct LoadOptions {
    bool quiet = false;  // no pilot progress
};

// Loads a scene and prepares its render (prepareRender: overrides, build, one validate() of the
// settings, the film's time axis), printing the warnings to stderr; fits an automatic film range
// with the pilot (progress on a terminal; Ctrl-C/SIGTERM abort it: Interrupted, see interrupt.h).
PreparedRender loadAndBuild(const std::string& path, const RenderOverrides& ov, const LoadOptions& lo = {});
// The same with the overrides as values (a resume: the checkpoint's flags, cli/resume.h).
PreparedRender loadAndBuild(const std::string& path, const SettingsOverrides& ov, const LoadOptions& lo = {});

// Refuses (UserError) a --pulse / --sensor whose kernel spans more than kMaxResponseBins of the
// film's bins (film/time_response.h), naming the flag and the fix; called once the time axis is
// known (after the pilot), before any pass or file.
void checkTimeResponseFitsFilm(const std::string& pulse, const std::string& sensor, const TimeBins& time);

// Warns on stderr when the film dropped pixel sums that would have overflowed its floats
// (FilmStats::overflowedPixels), naming the fix; returns that count.
int64_t warnFilmOverflow(const SceneSource& source, const TransientFilm& film);

// ---- the output folder ------------------------------------------------------------------------
// A folder one tpb run writes into (render, converge). The constructor creates it if needed, takes
// an exclusive lock (io/folder_lock.h: flock on <dir>/.tpb.lock, released by the kernel when the
// process ends, a crash included; a second run into the same folder, or the viewer exporting into
// it, is refused with a UserError naming the other process and the fix), then removes the outputs of the previous run into the folder: exactly the
// files its manifest (<dir>/.tpb-manifest.json) lists, or, for a folder written before manifests
// existed, what its summary.json lists. Files tpb did not write are never touched. The new run's
// files are recorded in the manifest before any of them is written, so that a run that dies while
// writing still leaves them listed for the next one. A checkpoint (checkpoint.tpbck: hours of
// render) that the run would remove or overwrite is never touched silently: the constructor refuses
// with a UserError naming it, its passes and the ways forward, unless it is in `keep` or
// `replaceCheckpoint` is set.
struct OutputFiles {
    std::vector<std::string> files;  // relative to the folder
    std::string framesDir;           // "" = no frames; else frame_NNNNN.exr for bins first..last step
    int firstBin = 0, lastBin = -1, binStep = 1;
    // Files of the previous run that stay even when its manifest lists them (the checkpoint a
    // resume reads, until the resumed render replaces it).
    std::vector<std::string> keep;
    bool replaceCheckpoint = false;  // the user said so (tpb render --overwrite-checkpoint)
    // The ways forward the refusal names after "another folder with -o" (e.g. "continue it with
    // `tpb render --resume DIR`"), or "".
    std::string checkpointAdvice;
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
    std::shared_ptr<FolderLock> lock_;  // io/folder_lock.h
    std::vector<std::string> removed_;
};

// What `tpb render` writes after rendering, with either method (beams or --method pt).
struct RenderOutputs {
    std::string out;
    ExportOptions opt;
    bool noFrames = false, quiet = false;
    int strip = 8;
    double stripEv = 0.0;
    bool npy = false;      // --npy: transient.npy, steady/before/after.npy, transient.json (volume_export.h)
    bool mp4 = false;      // --mp4: transient.mp4 (picture_export.h, ffmpeg)
    double fps = 24.0;     // --fps
    int contactSheet = 0;  // --contact-sheet N: contact_sheet.png of N frames (0 = none)
    ToneMap tone;          // the MP4's and contact sheet's mapping; its exposure is added to the automatic one
    std::optional<float> previewEv;  // the EV preview.png was written with (for summary.json), if it was
    VolumeProvenance provenance;     // for transient.json; filled after the render (provenanceOf)
    // A relay-wall scan: capture.h5 in the NLOS toolkit's layout (render/nlos_capture.h), written
    // with the steady image.
    const Scene* captureScene = nullptr;
    bool phasor = false;  // the film has a phasor film: phasor.npy & co (volume_export.h)
    // --backproject: backprojection.npy and .json from the capture (render/nlos_backprojection.h).
    std::optional<BackprojectionSettings> backproject;
};
// The files RenderOutputs writes for a film of `bins` bins (preview.exr/png included).
OutputFiles renderOutputFiles(const RenderOutputs& r, int bins);

struct OutputReport {
    int framesWritten = 0, framesExpected = 0;
    std::vector<std::string> kept;  // files written completely, relative to `out`
    std::string error;              // the first write failure, or empty
    bool interrupted = false;       // a signal stopped the frame export
    // The EV each picture was written with (picture_export.h's exposure rule), by file name.
    std::vector<std::pair<std::string, float>> exposureEv;
};

// The last line's account of the outputs: "wrote 12 frames (real time, delta) to out/frames,
// steady.exr, summary.json", or without frames what was written instead ("wrote no frames
// (--no-frames): steady.exr, steady.png, strip.png, summary.json in out").
std::string writtenLine(const RenderOutputs& r, const OutputReport& rep);
// A share in percent for people: "100", "12", "3.4", "0.052" (never "1e+02").
std::string percentText(double fraction);

// Before rendering: the number, size and estimated write time of the frames (from the time
// `previewExrSec` that writing preview.exr, an image of the same size, took), and a warning when
// they may not fit in the free space of the output folder's file system.
void reportPlannedOutputs(const PreparedRender& p, const RenderOutputs& r, double previewExrSec);

// After the outputs are written: the share of the energy that reached the camera outside the
// film's time range, on the frames' axis. Above kOutsideWarnFraction: a warning; everything
// outside (every frame black): an error (exit code 2) that says which range would cover the
// arrivals (measured with a pilot pass) or to use "range": "auto". Returns the fraction (0 when
// no energy reached the camera at all).
inline constexpr double kOutsideWarnFraction = 0.05;
// The pilot runs with p.pilotSettings.
double checkEnergyInsideFilm(const PreparedRender& p, const TransientFilm& film, TimeAxis axis);

}  // namespace tpb::app
