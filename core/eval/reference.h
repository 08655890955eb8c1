// Reference transient volumes for convergence measurements: rendering them (path tracer, photon
// beams, or the single-scattering quadrature), saving/loading them, and measuring a film against
// one (relative RMSE, error_metrics.h).
//
// ---- File format (".tpbref", version 2; tpb's film container, io/film_container.h) ---------------
//   bytes 0..7    magic "TPBREF1\n"
//   bytes 8..15   N: length of the JSON header in bytes, unsigned 64-bit little-endian
//   bytes 16..    the JSON header (N bytes, UTF-8)
//   then          the arrays listed in header["arrays"], in that order, back to back, each
//                 float32 little-endian, count = product of its "shape"
//   then          when header["sealed"] (every version-2 file): the 64-bit hash of the arrays
//                 (WordHash, array by array); nothing after it.
// Arrays (row-major, top image row first):
//   "real"       [H, W, bins, 3]  delta-emission transient volume on the real time axis
//   "unwarped"   [H, W, bins, 3]  the same on the camera-unwarped axis
//   "steady"     [H, W, 3]        steady-state image (all energy, also what fell outside the bins)
//   "self_diff2" [H, W, 3]        per pixel, sum over bins and RGB of (a - b)^2 between the two
//                                 independent halves of the passes (odd / even passes) for the
//                                 real axis, the unwarped axis and the steady image; all zero for
//                                 a quadrature reference; absent when unknown (beams)
// Bin k covers OPL [start_opl_m + k bin_width_opl_m, + bin_width_opl_m) (m; ns = m / 0.299792458).
// Header keys: format ("tpb-reference"), version (2; 1 is read too), scene (path as given),
// scene_hash (FNV-1a 64 of the scene file's bytes; meshes it references are not hashed), method
// ("pt", "beams" or "analytic-single-scattering"), passes, settings (settingsRecord: seed,
// max_depth, samples_per_pixel, photons_per_pass, radius...; version 1 wrote seed, max_depth,
// samples_per_pixel, photons_per_pass and beam_radius0_m at the top), resolution [W, H], bins, start_opl_m, bin_width_opl_m, emission ("delta"),
// requested_passes, requested_time_s (the budget it was asked for; 0 = not given), wall_seconds,
// interrupted, halves [na, nb] (passes in each half), self_error {real, unwarped, steady, estimate}
// (the reference's own relative RMSE, error_metrics.h; -1 = unknown), arrays [{name, shape}],
// sealed (true: the hash follows the arrays).
#pragma once
#include "render/driver.h"
#include "eval/error_metrics.h"
#include "film/transient_film.h"
#include "integrators/path_tracer.h"
#include "scene/scene.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace tpb {

struct ReferenceInfo {
    std::string scene, sceneHash;
    std::string method = "pt";  // "pt" | "beams" | "analytic-single-scattering"
    int64_t passes = 0;
    // The settings that rendered it (settingsRecord: the one serialisation of the settings), the
    // header's "settings"; the fields below are read from it (setSettings, and when the file is
    // read back) and compared by the compatibility checks.
    Record settings;
    int samplesPerPixel = 1;
    uint64_t seed = 0;
    int maxDepth = 0;
    int64_t photonsPerPass = 0;  // beams only
    double beamRadius0 = 0.0;    // beams only
    int width = 0, height = 0, bins = 0;
    double startOpl = 0.0, binWidth = 0.0;
    int64_t requestedPasses = 0;
    double requestedTimeSec = 0.0;
    double wallSeconds = 0.0;
    bool interrupted = false;
    int64_t halfA = 0, halfB = 0;  // passes in each half (self_diff2)
    double selfErrorReal = -1.0, selfErrorUnwarped = -1.0, selfErrorSteady = -1.0;
    std::string selfErrorEstimate = "unknown";

    size_t pixels() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
    size_t volumeSize() const { return pixels() * static_cast<size_t>(bins) * 3u; }
    double selfError(TimeAxis a) const { return a == TimeAxis::Real ? selfErrorReal : selfErrorUnwarped; }
};

// Sets info.settings and the fields read from them (seed, max depth, samples per pixel, photons
// per pass and pass 1's radius for the photon beams).
void setSettings(ReferenceInfo& info, const RenderSettings& settings);

struct ReferenceVolume {
    ReferenceInfo info;
    std::vector<float> real, unwarped;  // volumeSize() each
    std::vector<float> steady;          // pixels() * 3
    std::vector<float> selfDiff2;       // pixels() * 3 (real, unwarped, steady), or empty (unknown)
    const std::vector<float>& volume(TimeAxis a) const { return a == TimeAxis::Real ? real : unwarped; }
};

// Atomic write (tmp file + rename). Throws UserError naming the path on failure.
void writeReference(const std::string& path, const ReferenceVolume& ref);
// Throws UserError naming the path: missing file, bad magic, bad header, wrong size.
ReferenceVolume readReference(const std::string& path);
ReferenceInfo readReferenceInfo(const std::string& path);  // header only
bool fileExists(const std::string& path);

// FNV-1a 64 of a file's bytes as "fnv1a64:<16 hex digits>", or "" if it cannot be read.
std::string hashFile(const std::string& path);

// Differences that make a reference unusable for a run described by `want`: scene hash (when
// both are known), resolution, bins, time range (within 1e-6 of a bin), max depth. Each entry
// reads "<what>: reference has X, this run has Y". Empty = compatible.
std::vector<std::string> referenceMismatches(const ReferenceInfo& ref, const ReferenceInfo& want);
// Same plus what a cached reference must also share to be reused instead of re-rendered:
// method, seed, samples per pixel, photons and radius (beams), the requested budget, and that it
// was not interrupted.
std::vector<std::string> cacheMismatches(const ReferenceInfo& ref, const ReferenceInfo& want);
// Throws UserError "<path>: the reference does not match this run: ..." when mismatched.
void requireCompatible(const std::string& path, const ReferenceInfo& ref, const ReferenceInfo& want);

// Fills the film-related fields of an info from a built scene and its film's time axis
// (resolution, bins, time range), the scene path and its hash, and the seed and max depth.
ReferenceInfo describeScene(const Scene& scene, const TimeBins& time, const std::string& scenePath,
                            const RenderSettings& settings);

// ---- Rendering references --------------------------------------------------------------------

struct ReferenceJob {
    std::string method = "pt";   // "pt" or "beams"
    RenderSettings pt;           // method pt
    RenderSettings beams;        // method beams (its passes/time budget are ignored: see below)
    int64_t passes = 0;          // 0 = until timeBudgetSec
    double timeBudgetSec = 0.0;  // 0 = until passes
};

// Renders the reference: method pt alternates its passes between two films (odd / even passes)
// to estimate its own error (self_diff2, self_error); method beams is one progressive run
// (self-error unknown: its error is mostly kernel bias, which the spread does not show).
// `progress(passes, elapsedSec)` after each pass. A set `abort` stops after the current pass
// (info.interrupted). Does not set the scene hash unless scenePath names a readable file.
ReferenceVolume renderReference(const Scene& scene, const TimeBins& time, const std::string& scenePath,
                                const ReferenceJob& job, const std::atomic<bool>* abort = nullptr,
                                const std::function<void(int64_t, double)>& progress = {});

// Single scattering from a point light in an infinite homogeneous medium, by quadrature along
// every camera ray (averaged over `subpixels` x `subpixels` rays per pixel, 8x more in each
// direction for the pixels next to the light's image). Both time axes, delta emission, and the
// steady image. Throws UserError naming the scene file unless the scene is exactly that: one point
// light, a scattering global medium, no shapes.
ReferenceVolume singleScatteringReference(const Scene& scene, const TimeBins& time, const std::string& scenePath,
                                          const RenderSettings& settings, int subpixels = 4, int threads = 0);

// ---- Measuring a film against a reference ----------------------------------------------------

struct FilmError {
    double volume = std::numeric_limits<double>::quiet_NaN();           // relative RMSE, one axis, all bins
    double steady = std::numeric_limits<double>::quiet_NaN();           // relative RMSE, steady image
    double steadyTotalDiff = std::numeric_limits<double>::quiet_NaN();  // (sum - sum ref) / sum ref
    std::vector<double> perFrame;                                       // relative RMSE per bin (when asked)
    double volumeL1 = std::numeric_limits<double>::quiet_NaN();         // sum |x - ref| / sum |ref| (AbsoluteError)
    double steadyL1 = std::numeric_limits<double>::quiet_NaN();
};

// `mask` (optional, pixels() entries): pixels with a non-zero entry are left out of every sum.
FilmError compareWithReference(const TransientFilm& film, const ReferenceVolume& ref, TimeAxis axis, bool perFrame,
                               const std::vector<uint8_t>* mask = nullptr);

// The reference's own relative RMSE (half-split estimate) over the unmasked pixels, for the
// volume on `axis` (steady = false) or the steady image (steady = true); -1 when unknown.
double referenceSelfError(const ReferenceVolume& ref, TimeAxis axis, bool steady,
                          const std::vector<uint8_t>* mask = nullptr);

// Pixels within `radius` pixels of the image of a point or spot light (1 = masked), for metrics
// that leave out the singular neighbourhood of a point light. Empty mask when radius <= 0.
std::vector<uint8_t> lightPixelMask(const Scene& scene, double radius);

}  // namespace tpb
