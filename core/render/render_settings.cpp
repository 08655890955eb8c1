#include "render/render_settings.h"

#include "scene/scene.h"

namespace tpb {

const char* methodName(Method m) {
    switch (m) {
        case Method::Beams: return "beams";
        case Method::PathTracer: return "pt";
        case Method::Preview: return "preview";
    }
    return "?";
}

std::optional<Method> parseMethod(std::string_view s) {
    if (s == "beams") return Method::Beams;
    if (s == "pt") return Method::PathTracer;
    if (s == "preview") return Method::Preview;
    return std::nullopt;
}

RenderSettings RenderSettings::fromDesc(const RenderDesc& r, double sceneDiagonal) {
    const double diag = sceneDiagonal > 0.0 ? sceneDiagonal : 1.0;
    RenderSettings s;
    s.photonsPerPass = r.photonsPerPass;
    s.beamRadius0 = r.radiusRelative ? r.radius * diag : r.radius;
    s.surfaceRadius0 = r.radiusRelative ? r.surfaceRadius * diag : r.surfaceRadius;
    s.alpha = r.alpha;
    s.passes = r.passes;
    s.timeBudgetSec = r.timeBudgetSec;
    s.maxDepth = r.maxDepth;
    s.seed = r.seed;
    s.threads = r.threads;
    s.profile = r.timeProfile;
    s.beamLength = r.beamLength;
    s.emission = r.emission;
    s.unwarp = r.unwarp;
    return s;
}

RenderSettings RenderSettings::fromScene(const Scene& scene) {
    RenderSettings s = fromDesc(scene.desc.render, scene.bounds.diagonal());
    s.beamRadius0 = scene.beamRadius0;
    s.surfaceRadius0 = scene.surfaceRadius0;
    return s;
}

}  // namespace tpb
