// The one settings type of a render: what every integrator (photon beams, the path tracer, the
// geometry preview), the driver, the pilot, the CLI and the viewer read. It is built once from the
// scene description's "render" block plus command-line overrides (SettingsOverrides) and checked by
// one validate(); nothing downstream copies it field by field.
//
// Units: radii in meters (absolute: a relative radius in the scene file is resolved against the
// built scene's bounding diagonal), times in seconds of wall clock, depths in scattering vertices.
#pragma once
#include "accel/accel_backend.h"
#include "scene/scene_desc.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace tpb {

// The integrator a render runs (README "Methods").
enum class Method {
    Beams,       // progressive transient photon beams (the paper)
    PathTracer,  // unbiased transient volumetric path tracer (the reference)
    Preview,     // steady geometry preview ("eye light"), no light transport
};
const char* methodName(Method m);                       // "beams" | "pt" | "preview"
std::optional<Method> parseMethod(std::string_view s);  // accepts the names above

class Scene;

struct RenderSettings {
    Method method = Method::Beams;

    // ---- every method ----
    int64_t passes = 16;         // 0 = until the time budget (or an interrupt)
    double timeBudgetSec = 0.0;  // 0 = no budget
    int maxDepth = 16;           // scattering vertices of a path (null crossings do not count)
    uint64_t seed = 1;           // pass i depends only on (seed, i)
    int threads = 0;             // 0 = all cores

    // ---- photon beams (paper Sec. 4) ----
    int64_t photonsPerPass = 20000;
    double beamRadius0 = 0.01;     // m, kernel radius of pass 1 (volume)
    double surfaceRadius0 = 0.02;  // m, kernel radius of pass 1 (surface photons)
    double alpha = 0.7;            // progressive shrink, (0, 1]
    TimeProfile profile = TimeProfile::Exact;
    BeamLength beamLength = BeamLength::Short;
    AccelBackend accel = AccelBackend::Embree;
    // The density estimators, by name (estimators/registry.cpp, docs/estimators.md).
    std::string volumeEstimator = "beam2d";  // along camera segments in media
    std::string surfaceEstimator = "ppm";    // at diffuse camera-path vertices
    uint64_t maxPhotonMapBytes = 0;  // per pass; 0 = maxFilmBytes() (memory_budget.h)

    // ---- path tracer ----
    int samplesPerPixel = 1;
    // Point and spot lights seen from media: equiangular sampling along each medium segment
    // (path_tracer.cpp) instead of next-event estimation at free-flight vertices (infinite
    // variance next to the light). Both are unbiased.
    bool equiangular = true;

    // ---- how the film is first shown (viewer, exported frames) ----
    EmissionMode emission = EmissionMode::Delta;
    bool unwarp = false;

    // The scene description's "render" block, radii resolved against the scene's bounding
    // diagonal (m) when they are relative.
    static RenderSettings fromDesc(const RenderDesc& r, double sceneDiagonal);
    // Transitional: from a built scene that still carries its description.
    static RenderSettings fromScene(const Scene& scene);
};

}  // namespace tpb
