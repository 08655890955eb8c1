// The one settings type of a render: what every integrator (photon beams, the path tracer, the
// geometry preview), the driver, the pilot, the CLI and the viewer read. It is built once from the
// scene description's "render" block plus command-line overrides (SettingsOverrides) and checked by
// one validate(); nothing downstream copies it field by field.
//
// Units: radii in meters (absolute: a relative radius in the scene file is resolved against the
// built scene's bounding diagonal), times in seconds of wall clock, depths in scattering vertices.
#pragma once
#include "accel/accel_backend.h"
#include "film/phasor.h"
#include "io/record.h"
#include "scene/scene_desc.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tpb {

// The integrator a render runs (docs/user/commands.md).
enum class Method {
    Beams,       // progressive transient photon beams (the paper)
    PathTracer,  // unbiased transient volumetric path tracer (the reference)
    Preview,     // steady geometry preview ("eye light"), no light transport
};
const char* methodName(Method m);                       // "beams" | "pt" | "preview"
std::optional<Method> parseMethod(std::string_view s);  // accepts the names above

// Command-line (or viewer) overrides of the scene file's render block: what is set replaces the
// file's value. width/height/bins change the film's shape: they are applied to the description
// before the scene is built (applyFilmShape, prepare.h); the rest to RenderSettings (apply()).
struct SettingsOverrides {
    std::optional<Method> method;
    std::optional<int64_t> passes, photons;
    std::optional<int> warmup;         // --warmup
    std::optional<double> timeBudget;  // s; given without passes it means "as many passes as fit"
    std::optional<double> radius;      // m, absolute: the volume kernel of pass 1 (--radius)
    std::optional<double>
        surfaceRadius;        // m, absolute: the surface kernel of pass 1 (checkpoints, render/checkpoint.h)
    bool autoRadius = false;  // --auto-radius: the radius from a pilot pass (auto_radius.h)
    std::optional<double> alpha;
    std::optional<int> threads, maxDepth, samplesPerPixel;
    std::optional<std::pair<int, int>> bounces;  // --bounces
    std::optional<uint64_t> seed;
    std::optional<TimeProfile> profile;
    std::optional<BeamLength> beamLength;
    std::optional<AccelBackend> accel;
    std::optional<bool> equiangular;
    std::optional<std::string> volumeEstimator, surfaceEstimator;  // --estimator, --surface-estimator
    std::optional<TimeKernelSettings> timeKernel;                  // --time-kernel
    std::optional<std::string> phasor;                             // --phasor (film/phasor.h)
    // ---- the film's shape ----
    std::optional<int> width, height, bins;
};

// Where the values of a RenderSettings came from, for validate()'s messages: a value the
// overrides set is named by its flag ("--alpha ..."), one written in the scene file by its file,
// line and key ("scene.json:12: render.alpha: ...").
struct SettingsSource {
    const SceneDesc* desc = nullptr;               // the file's render block and its locs
    const SettingsOverrides* overrides = nullptr;  // flags
    // The built scene's bounding diagonal (m); 0 = not known yet (the loader): absolute radii are
    // then only checked to be > 0, relative ones against their fraction of the diagonal.
    double sceneDiagonal = 0.0;
};

// The viewer's default warm-up: pass 1 at 1/8 of the photons. (W = 5 gives beam2d four refinements
// within 3 s on the default scene instead of three, but its first picture, 1/32 of the photons,
// leaves most pixels black on a 2000-photon scene: docs/measurements/history.md.)
inline constexpr int kViewerWarmupPasses = 3;
inline constexpr int kMaxWarmupPasses = 20;

struct RenderSettings {
    Method method = Method::Beams;

    // ---- every method ----
    int64_t passes = 16;         // 0 = until the time budget (or an interrupt)
    double timeBudgetSec = 0.0;  // 0 = no budget
    int maxDepth = 16;           // scattering vertices of a path (null crossings do not count)
    // Bounce filter: only light whose path from the light to the sensor has bounceMin..bounceMax
    // scattering events (surface or medium; a laser's spot counts as one) reaches the film. E.g.
    // NLOS: 3..3 is the relay wall's third bounce alone, 2..INT_MAX leaves out the wall's direct
    // response. Default: everything.
    int bounceMin = 0, bounceMax = INT_MAX;  // (0: an emitter seen directly)
    bool bounceFilter() const { return bounceMin > 0 || bounceMax < INT_MAX; }
    uint64_t seed = 1;  // pass i depends only on (seed, i)
    int threads = 0;    // 0 = all cores

    // ---- photon beams (paper Sec. 4) ----
    int64_t photonsPerPass = 20000;
    // Warm-up (issue 15: a first picture fast, refinements often): the first W passes trace fewer
    // photons, photonsPerPass / 2^(W + 1 - i) for pass i <= W (at least 1), so pass 1 costs about
    // 1/2^W of a full one; every later pass is the one a render without warm-up runs (pass i depends
    // only on (seed, i)). The film is the photon-weighted average of its passes: a warm-up pass's
    // photons carry the power of a full pass's (divided by photonsPerPass, not by their own count),
    // so the pass adds w_i L_i with w_i = passWeight(i), and the film divides by the sum of the
    // weights (TileSums::weight). A pass with half the photons counts half, so after n passes the
    // film has the noise of n - W + 1 - 2^-W full passes: the warm-up costs the photons it did not
    // trace and nothing more (equal weights carried (2^(W+1) - W - 2) / n of extra relative
    // variance; docs/theory/how-it-works.md "Warm-up").
    // 0 = off (`tpb render`); `tpb view` uses kViewerWarmupPasses unless the scene or --warmup sets it.
    int warmupPasses = 0;
    // The photons traced in pass `pass` (1-based): photonsPerPass after the warm-up.
    int64_t photonsForPass(uint64_t pass) const;
    // The weight of pass `pass` in the film's average: photonsForPass / photonsPerPass for the photon
    // beams (1 after the warm-up), 1 for the path tracer and the preview (no photons).
    double passWeight(uint64_t pass) const;
    double beamRadius0 = 0.01;     // m, kernel radius of pass 1 (volume)
    double surfaceRadius0 = 0.02;  // m, kernel radius of pass 1 (surface photons)
    double alpha = 0.7;            // progressive shrink, (0, 1]
    TimeProfile profile = TimeProfile::Exact;
    BeamLength beamLength = BeamLength::Short;
    AccelBackend accel = AccelBackend::Bvh;
    // The density estimators, by name (estimators/registry.cpp, docs/developer/adding-an-estimator.md).
    std::string volumeEstimator = "beam2d";  // along camera segments in media
    std::string surfaceEstimator = "ppm";    // at diffuse camera-path vertices
    TimeKernelSettings timeKernel;           // off by default
    uint64_t maxPhotonMapBytes = 0;          // per pass; 0 = maxFilmBytes() (base/memory.h)

    // ---- path tracer ----
    int samplesPerPixel = 1;
    // Point and spot lights seen from media: equiangular sampling along each medium segment
    // (path_tracer.cpp) instead of next-event estimation at free-flight vertices (infinite
    // variance next to the light). Both are unbiased.
    bool equiangular = true;

    // ---- the film's phasor frequencies (film/phasor.h; resolved by render/prepare.cpp once the
    // time axis is known; none by default) ----
    PhasorSpec phasor;

    // ---- how the film is first shown (viewer, exported frames) ----
    EmissionMode emission = EmissionMode::Delta;
    bool unwarp = false;

    // The scene description's "render" block, radii resolved against the scene's bounding
    // diagonal (m) when they are relative.
    static RenderSettings fromDesc(const RenderDesc& r, double sceneDiagonal);
    // Applies the overrides that are set (not the film's shape).
    void apply(const SettingsOverrides& o);
    // The one range check of the render settings: photons >= 1 and within the photon-map memory
    // budget, kernel radii > 0 and at most kMaxRadiusFraction of the scene's diagonal (warned about
    // above kSlowRadiusFraction), alpha in (0, 1], passes >= 0, a finite time budget >= 0, max
    // depth >= 1, samples per pixel >= 1, threads >= 0 (capped at maxUsefulThreads(), with a
    // warning). Throws UserError naming where the bad value came from (SettingsSource); returns
    // the warnings, each "file:line: render.key: ..." or "--flag ...".
    std::vector<std::string> validate(const SettingsSource& source);
    // The checks that need the film's time axis (decided after validate(), render/prepare.cpp): a
    // time kernel no wider than the film's range (filmRangeOpl, m). Throws UserError like validate().
    void validateAgainstFilm(double filmRangeOpl, const SettingsSource& source) const;
};

// The one serialisation of the settings (summary.json "settings", `tpb info` "render",
// transient.json "render", the reference header, the checkpoint's fingerprint). Keys are the scene
// file's render keys where the file has one (photons_per_pass, warmup, radius and surface_radius in
// m, alpha, passes, time_budget_s, max_depth, seed, threads, time_profile, beam_length,
// volume_estimator, surface_estimator, emission, unwarp), else the flag's name (method, accel,
// samples_per_pixel, equiangular); time_kernel as the flag writes it ("none", "box", "box:0.05").
// Only the keys the method reads: the photon-beam keys for beams, the path tracer's for pt.
Record settingsRecord(const RenderSettings& s);

}  // namespace tpb
