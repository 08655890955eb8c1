// The geometry preview (integrators/preview.h) as an Integrator: one pass, steady image only (the
// time bins stay empty), for checking the camera and geometry before any photon is traced.
#pragma once
#include "integrators/integrator.h"

#include <vector>

namespace tpb {

class PreviewIntegrator final : public Integrator {
public:
    PreviewIntegrator(const Scene& scene, const RenderSettings& settings);
    Method method() const override { return Method::Preview; }
    bool beginPass(const PassContext& ctx, PassStats& stats) override;
    void renderTile(const PassContext& ctx, int tile, const TileRect& rect, TransientFilm::TileWriter& writer,
                    int thread) override;
    void endPass(const PassContext&, PassStats&) override {}
    int64_t usefulPasses() const override { return 1; }

private:
    const Scene& scene_;
    RenderSettings settings_;
    std::vector<float> image_;            // W*H*3, this pass
    std::vector<PixelAccumulator> accs_;  // per thread
};

}  // namespace tpb
