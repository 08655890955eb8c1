#include "integrators/photon_beams.h"

#include "base/progressive.h"
#include "render/memory_budget.h"

#include <chrono>

namespace tpb {

namespace {

double wallSec() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

// Kernel dimensions of the two estimators, for the radius schedule (base/progressive.h).
constexpr int kBeamKernelDim = 2;     // the 2D beam kernel: a disc across the beam (eq. 8)
constexpr int kSurfaceKernelDim = 2;  // surface photon mapping: a disc on the surface

}  // namespace

PhotonBeamsIntegrator::PhotonBeamsIntegrator(const Scene& scene, const RenderSettings& settings)
    : scene_(scene), settings_(settings) {}

double PhotonBeamsIntegrator::beamRadius(uint64_t pass) const {
    return progressiveRadius(settings_.beamRadius0, settings_.alpha, pass, kBeamKernelDim);
}

double PhotonBeamsIntegrator::surfaceRadius(uint64_t pass) const {
    return progressiveRadius(settings_.surfaceRadius0, settings_.alpha, pass, kSurfaceKernelDim);
}

bool PhotonBeamsIntegrator::beginPass(const PassContext& ctx, PassStats& ps) {
    ps.beamRadius = beamRadius(ctx.pass);
    ps.surfaceRadius = surfaceRadius(ctx.pass);
    const double t0 = wallSec();

    // 1. Photon pass (only the stages the scene needs).
    PhotonTraceSettings pt;
    pt.seed = settings_.seed;
    pt.pass = ctx.pass;
    pt.photons = settings_.photonsPerPass;
    pt.maxDepth = settings_.maxDepth;
    pt.storeBeams = scene_.stages.beams;
    pt.storeSurfacePhotons = scene_.stages.surfacePhotons;
    pt.beamLength = settings_.beamLength;
    pt.filmEndOpl = ctx.time->endOpl();
    pt.threads = ctx.threads;
    pt.maxMapBytes = settings_.maxPhotonMapBytes > 0 ? settings_.maxPhotonMapBytes : maxFilmBytes();
    map_ = tracePhotons(scene_, pt, ctx.abort);
    if (ctx.abort && ctx.abort->load()) return false;
    ps.photons = map_.emitted;
    ps.beams = static_cast<int64_t>(map_.beams.size());
    ps.surfacePhotons = static_cast<int64_t>(map_.photons.size());
    ps.emittedFlux = map_.emittedFlux;
    ps.cutFlux = map_.cutFlux;
    ps.regionOverflows = map_.regionOverflows;
    const double t1 = wallSec();

    // 2. Acceleration structures.
    haveBeams_ = scene_.stages.beams && !map_.beams.empty();
    if (haveBeams_) {
        if (!accel_) accel_ = BeamAccel::create(settings_.accel);
        accel_->build(map_.beams, ps.beamRadius, ctx.threads);
        ps.beamPieces = static_cast<int64_t>(accel_->pieceCount());
    }
    grid_.reset();
    if (scene_.stages.surfacePhotons && !map_.photons.empty()) {
        grid_ = std::make_unique<PhotonGrid>();
        grid_->build(map_.photons, ps.surfaceRadius);
    }
    const double t2 = wallSec();
    ps.photonSec = t1 - t0;
    ps.buildSec = t2 - t1;

    // 3. Camera pass settings and scratch for the tiles.
    camera_.seed = settings_.seed;
    camera_.pass = ctx.pass;
    camera_.beamRadius = ps.beamRadius;
    camera_.surfaceRadius = ps.surfaceRadius;
    camera_.profile = settings_.profile;
    camera_.beamLength = settings_.beamLength;
    camera_.maxDepth = settings_.maxDepth;
    scratch_.resize(static_cast<size_t>(ctx.threads));
    for (auto& sc : scratch_) sc.acc.reset(ctx.time->bins);
    tileStats_.assign(static_cast<size_t>(ctx.tiles), CameraPassStats{});
    return true;
}

void PhotonBeamsIntegrator::renderTile(const PassContext& ctx, int tile, const TileRect& r,
                                       TransientFilm::TileWriter& writer, int thread) {
    CameraPassScratch& scratch = scratch_[static_cast<size_t>(thread)];
    CameraPassStats& stats = tileStats_[static_cast<size_t>(tile)];
    const BeamAccel* beams = haveBeams_ ? accel_.get() : nullptr;
    for (int y = r.y0; y < r.y0 + r.h; ++y)
        for (int x = r.x0; x < r.x0 + r.w; ++x) {
            renderPixel(scene_, map_, beams, grid_.get(), camera_, *ctx.time, x, y, scratch, stats);
            writer.addPixel(x, y, scratch.acc);
            scratch.acc.clearTouched();
        }
}

void PhotonBeamsIntegrator::endPass(const PassContext&, PassStats& ps) {
    for (const CameraPassStats& st : tileStats_) ps.camera += st;
    ps.film = static_cast<const FilmTally&>(ps.camera);
}

}  // namespace tpb
