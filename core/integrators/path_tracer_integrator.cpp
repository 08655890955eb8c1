#include "integrators/path_tracer_integrator.h"

namespace tpb {

// ---- the path tracer --------------------------------------------------------------------------

PathTracerIntegrator::PathTracerIntegrator(const Scene& scene, const RenderSettings& settings)
    : scene_(scene), settings_(settings) {}

bool PathTracerIntegrator::beginPass(const PassContext& ctx, PassStats&) {
    accs_.assign(static_cast<size_t>(ctx.threads), PixelAccumulator(ctx.time->bins, ctx.phasor));
    tileStats_.assign(static_cast<size_t>(ctx.tiles), PathTracerStats{});
    return true;
}

void PathTracerIntegrator::renderTile(const PassContext& ctx, int tile, const TileRect& r,
                                      TransientFilm::TileWriter& writer, int thread) {
    PixelAccumulator& acc = accs_[static_cast<size_t>(thread)];
    PathTracerStats& st = tileStats_[static_cast<size_t>(tile)];
    for (int y = r.y0; y < r.y0 + r.h; ++y)
        for (int x = r.x0; x < r.x0 + r.w; ++x) {
            pathTracePixel(scene_, settings_, ctx.pass, *ctx.time, x, y, acc, st);
            writer.addPixel(x, y, acc);
            acc.clearTouched();
        }
}

void PathTracerIntegrator::endPass(const PassContext&, PassStats& ps) {
    for (const PathTracerStats& st : tileStats_) ps.paths += st;
    ps.film = static_cast<const FilmTally&>(ps.paths);
}

}  // namespace tpb
