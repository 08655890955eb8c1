// The unbiased transient volumetric path tracer (integrators/path_tracer.h: algorithm, time axes)
// as an Integrator: each pass traces settings.samplesPerPixel camera paths per pixel, keyed by
// (seed, pass, pixel); nothing to prepare before the tiles.
#pragma once
#include "integrators/integrator.h"
#include "integrators/path_tracer.h"

#include <vector>

namespace tpb {

class PathTracerIntegrator final : public Integrator {
public:
    PathTracerIntegrator(const Scene& scene, const RenderSettings& settings);
    Method method() const override { return Method::PathTracer; }
    bool beginPass(const PassContext& ctx, PassStats& stats) override;
    void renderTile(const PassContext& ctx, int tile, const TileRect& rect, TransientFilm::TileWriter& writer,
                    int thread) override;
    void endPass(const PassContext& ctx, PassStats& stats) override;

private:
    const Scene& scene_;
    RenderSettings settings_;
    std::vector<PixelAccumulator> accs_;      // per thread
    std::vector<PathTracerStats> tileStats_;  // per tile, summed in tile order
};

}  // namespace tpb
