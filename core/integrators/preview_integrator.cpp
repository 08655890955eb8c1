#include "integrators/preview_integrator.h"

#include "integrators/preview.h"

namespace tpb {

// ---- the geometry preview ---------------------------------------------------------------------

PreviewIntegrator::PreviewIntegrator(const Scene& scene, const RenderSettings& settings)
    : scene_(scene), settings_(settings) {}

bool PreviewIntegrator::beginPass(const PassContext& ctx, PassStats&) {
    image_ = renderPreview(scene_, ctx.threads);
    accs_.assign(static_cast<size_t>(ctx.threads), PixelAccumulator(ctx.time->bins));
    return true;
}

void PreviewIntegrator::renderTile(const PassContext&, int, const TileRect& r, TransientFilm::TileWriter& writer,
                                   int thread) {
    PixelAccumulator& acc = accs_[static_cast<size_t>(thread)];
    for (int y = r.y0; y < r.y0 + r.h; ++y)
        for (int x = r.x0; x < r.x0 + r.w; ++x) {
            const float* p = &image_[(static_cast<size_t>(y) * scene_.camera.width + x) * 3];
            acc.addSteady(Color(p[0], p[1], p[2]));
            writer.addPixel(x, y, acc);
            acc.clearTouched();
        }
}

}  // namespace tpb
