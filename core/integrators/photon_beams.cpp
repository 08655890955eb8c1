#include "integrators/photon_beams.h"

#include "accel/beam_accel.h"
#include "base/error.h"
#include "base/progressive.h"
#include "integrators/time_kernel_schedule.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "film/film_snapshot.h"
#include "film/film_bytes.h"

#include <chrono>

namespace tpb {

namespace {

double wallSec() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

}  // namespace

PhotonPassParams photonPassFor(const Scene& scene, const RenderSettings& s, const VolumeEstimator::Needs& needs,
                               uint64_t pass, int threads, double filmEndOpl) {
    PhotonPassParams pt;
    pt.seed = s.seed;
    pt.pass = pass;
    pt.photons = s.photonsForPass(pass);  // fewer during the warm-up,
    pt.powerPhotons = s.photonsPerPass;   // each with a full pass's power (passWeight)
    pt.maxDepth = s.maxDepth;
    // Only what the volume estimator reads (beams, points at scattering events, or both).
    pt.storeBeams = scene.stages.beams && needs.beams;
    pt.storePoints = scene.stages.beams && needs.points;
    pt.storeSurfacePhotons = scene.stages.surfacePhotons;
    pt.beamLength = s.beamLength;
    pt.filmEndOpl = filmEndOpl;
    pt.threads = threads;
    pt.maxMapBytes = s.maxPhotonMapBytes > 0 ? s.maxPhotonMapBytes : maxFilmBytes();
    pt.minEvents = s.bounceMin;
    pt.maxEvents = s.bounceMax;
    return pt;
}

PhotonBeamsIntegrator::PhotonBeamsIntegrator(const Scene& scene, const RenderSettings& settings)
    : scene_(scene),
      settings_(settings),
      volume_(makeVolumeEstimator(settings.volumeEstimator)),
      surface_(makeSurfaceEstimator(settings.surfaceEstimator)) {
    if (!volume_) throw UserError("unknown volume estimator \"" + settings.volumeEstimator + "\"");
    if (!surface_) throw UserError("unknown surface estimator \"" + settings.surfaceEstimator + "\"");
}

// With the time kernel on, the schedule runs over space and time: D = dim() + 1 (progressive.h).
double PhotonBeamsIntegrator::beamRadius(uint64_t pass) const {
    return progressiveRadius(settings_.beamRadius0, settings_.alpha, pass,
                             scheduleDimension(volume_->dim(), timeKernelOn()));
}

double PhotonBeamsIntegrator::surfaceRadius(uint64_t pass) const {
    return progressiveRadius(settings_.surfaceRadius0, settings_.alpha, pass,
                             scheduleDimension(surface_->dim(), timeKernelOn()));
}

TimeKernelSchedule PhotonBeamsIntegrator::timeKernels(const TimeBins& time) const {
    return timeKernelSchedule(scene_, settings_, time, volume_->dim(), surface_->dim());
}

bool PhotonBeamsIntegrator::beginPass(const PassContext& ctx, PassStats& ps) {
    ps.beamRadius = beamRadius(ctx.pass);
    ps.surfaceRadius = surfaceRadius(ctx.pass);
    const TimeKernelSchedule kernels = timeKernels(*ctx.time);
    const TimeKernel volumeKernel = kernels.volume.kernel(ctx.pass), surfaceKernel = kernels.surface.kernel(ctx.pass);
    ps.volumeTimeHalfWidth = volumeKernel.halfWidth;
    ps.surfaceTimeHalfWidth = surfaceKernel.halfWidth;

    // Camera pass settings and scratch for the tiles.
    camera_.seed = settings_.seed;
    camera_.pass = ctx.pass;
    camera_.maxDepth = settings_.maxDepth;
    camera_.emittersSeen = settings_.bounceMin == 0;
    scratch_.resize(static_cast<size_t>(ctx.threads));
    for (auto& sc : scratch_) sc.acc.reset(ctx.time->bins, ctx.phasor);
    tileStats_.assign(static_cast<size_t>(ctx.tiles), CameraPassStats{});

    const PhotonPassParams pt =
        photonPassFor(scene_, settings_, volume_->needs(), ctx.pass, ctx.threads, ctx.time->endOpl());
    if (scene_.camera.scan == ScanMode::None) {
        // 1. Photon pass (only the stages the scene needs); 2. the estimators' accelerators.
        if (!photonPass(ctx, pt, ps)) return false;
        prepareEstimators(ctx, pt, volumeKernel, surfaceKernel, ps);
        return true;
    }
    return scanPass(ctx, pt, volumeKernel, surfaceKernel, ps);
}

bool PhotonBeamsIntegrator::photonPass(const PassContext& ctx, const PhotonPassParams& pt, PassStats& ps) {
    const double t0 = wallSec();
    map_ = tracer_.trace(scene_, pt, ctx.abort);
    if (map_.aborted || (ctx.abort && ctx.abort->load())) return false;
    ps.photons += map_.emitted;
    ps.beams += static_cast<int64_t>(map_.beams.size());
    ps.points += static_cast<int64_t>(map_.points.size());
    ps.surfacePhotons += static_cast<int64_t>(map_.photons.size());
    ps.emittedFlux += map_.emittedFlux;
    ps.cutFlux += map_.cutFlux;
    ps.regionOverflows += map_.regionOverflows;
    ps.photonSec += wallSec() - t0;
    return true;
}

void PhotonBeamsIntegrator::prepareEstimators(const PassContext& ctx, const PhotonPassParams& pt,
                                              const TimeKernel& volumeKernel, const TimeKernel& surfaceKernel,
                                              PassStats& ps) {
    const double t1 = wallSec();
    const VolumeEstimator::Needs needs = volume_->needs();
    EstimatorPass ep;
    ep.profile = settings_.profile;
    ep.beamLength = settings_.beamLength;
    ep.accel = settings_.accel;
    ep.threads = ctx.threads;
    estimators_ = {};
    estimators_.volumeKernel = volumeKernel;
    estimators_.surfaceKernel = surfaceKernel;
    BundlePlan bundles;
    const bool volumeInput = (needs.beams && !map_.beams.empty()) || (needs.points && !map_.points.empty());
    if (scene_.stages.beams && volumeInput) {
        // The accelerator over the beams' pieces (or the points) counts against the same memory
        // limit as the map itself, checked before it is built: a beam is up to 16 pieces.
        uint64_t pieces = 0;
        if (needs.beams)
            for (const Beam& b : map_.beams) pieces += beamPieceCount(b.length, ps.beamRadius);
        if (needs.points) pieces += map_.points.size();
        const uint64_t need = storedMapBytes(map_) + pieces * kAccelBytesPerPiece;
        if (pt.maxMapBytes > 0 && need > pt.maxMapBytes)
            throw UserError("", 0, "render.photons_per_pass",
                            "pass " + std::to_string(ctx.pass) + ": the photon map and its accelerator (" +
                                std::to_string(pieces) + " beam pieces or points) would take " + humanBytes(need) +
                                ", more than " + humanBytes(pt.maxMapBytes) +
                                ", the memory limit (TPB_MAX_FILM_BYTES); lower photons_per_pass or "
                                "render.max_depth, or raise the kernel radius (a beam is cut in pieces about 16 "
                                "radii long)");
        ep.radius = ps.beamRadius;
        ep.timeKernel = volumeKernel;
        bundles = planBundles(scene_, ps.beamRadius);  // primary segments share queries (segment_bundle.h)
        ep.bundleSlack = bundles.slack;
        volume_->prepare(scene_, map_, ep);
        if (!volume_->empty()) estimators_.volume = volume_.get();
        ps.beamPieces += static_cast<int64_t>(volume_->accelPrimitives());
    }
    if (scene_.stages.surfacePhotons && !map_.photons.empty()) {
        ep.radius = ps.surfaceRadius;
        ep.timeKernel = surfaceKernel;
        ep.bundleSlack = 0.0;
        surface_->prepare(scene_, map_, ep);
        if (!surface_->empty()) estimators_.surface = surface_.get();
    }
    camera_.bundleBlock = bundles.block;
    ps.buildSec += wallSec() - t1;
}

// A scan (scene/camera.h): laser point after laser point, the photon pass of that point, then its
// pixels gathered and staged per tile (the tiles replay them: renderTile). The pixels of one laser
// point are gathered in parallel, tile by tile (one thread per tile: no lock).
bool PhotonBeamsIntegrator::scanPass(const PassContext& ctx, PhotonPassParams pt, const TimeKernel& volumeKernel,
                                     const TimeKernel& surfaceKernel, PassStats& ps) {
    const Camera& cam = scene_.camera;
    const FilmLayout layout(cam.width, cam.height, *ctx.time);
    scanTiles_.resize(layout.tiles.size());
    for (TileStaging& t : scanTiles_) t.clear();
    pt.aimLight = cam.scanLaser;
    const int64_t points = cam.laserPoints();
    for (int64_t l = 0; l < points; ++l) {
        pt.aimTarget = cam.laserTarget(l);
        pt.aimEmitOpl = scanEmitOpl(scene_, pt.aimTarget);
        pt.laserPoint = l;
        if (!photonPass(ctx, pt, ps)) return false;
        prepareEstimators(ctx, pt, volumeKernel, surfaceKernel, ps);
        const double t0 = wallSec();
        // The film rows this laser point lights (confocal: one pixel).
        int x0 = 0, x1 = cam.width, y0 = 0, y1 = cam.height;
        if (cam.scan == ScanMode::Confocal) {
            x0 = static_cast<int>(l % cam.width), x1 = x0 + 1;
            y0 = static_cast<int>(l / cam.width), y1 = y0 + 1;
        } else if (cam.scan == ScanMode::Exhaustive) {
            y0 = static_cast<int>(l) * cam.sensorRows, y1 = y0 + cam.sensorRows;
        }
        std::vector<int> tiles;
        for (int ty = y0 / FilmLayout::kTile; ty <= (y1 - 1) / FilmLayout::kTile; ++ty)
            for (int tx = x0 / FilmLayout::kTile; tx <= (x1 - 1) / FilmLayout::kTile; ++tx)
                tiles.push_back(ty * layout.tilesX + tx);
        parallelFor(
            static_cast<int64_t>(tiles.size()), ctx.threads,
            [&](int64_t i, int thread) {
                const int tile = tiles[static_cast<size_t>(i)];
                const TileRect& r = layout.tiles[static_cast<size_t>(tile)];
                CameraPassScratch& scratch = scratch_[static_cast<size_t>(thread)];
                CameraPassStats& stats = tileStats_[static_cast<size_t>(tile)];
                for (int y = std::max(y0, r.y0); y < std::min(y1, r.y0 + r.h); ++y)
                    for (int x = std::max(x0, r.x0); x < std::min(x1, r.x0 + r.w); ++x) {
                        renderPixel(scene_, estimators_, camera_, *ctx.time, x, y, scratch, stats);
                        stagePixel(scanTiles_[static_cast<size_t>(tile)],
                                   static_cast<uint32_t>((y - r.y0) * r.w + (x - r.x0)), scratch.acc);
                    }
            },
            ctx.abort);
        if (ctx.abort && ctx.abort->load()) return false;
        ps.cameraSec += wallSec() - t0;
    }
    return true;
}

void PhotonBeamsIntegrator::renderTile(const PassContext& ctx, int tile, const TileRect& r,
                                       TransientFilm::TileWriter& writer, int thread) {
    if (scene_.camera.scan != ScanMode::None) {  // gathered by scanPass
        writer.addStaged(scanTiles_[static_cast<size_t>(tile)]);
        return;
    }
    CameraPassScratch& scratch = scratch_[static_cast<size_t>(thread)];
    CameraPassStats& stats = tileStats_[static_cast<size_t>(tile)];
    renderPixels(scene_, estimators_, camera_, *ctx.time, r, writer, scratch, stats);
}

void PhotonBeamsIntegrator::endPass(const PassContext&, PassStats& ps) {
    for (const CameraPassStats& st : tileStats_) ps.camera += st;
    ps.film = static_cast<const FilmTally&>(ps.camera);
}

// The pilots' probe: the photon pass of the request, then (unless photonsOnly) the estimators
// prepared for its kernels with the pass's defaults otherwise (no time kernel, no shared queries).
bool PhotonBeamsIntegrator::beginProbe(const PassContext& ctx, const ProbeRequest& req) {
    PhotonPassParams pt = photonPassFor(scene_, settings_, req.store.value_or(volume_->needs()), 0, ctx.threads);
    pt.seed = req.seed;
    pt.photons = req.photons;
    pt.powerPhotons = 0;
    pt.storeSurfacePhotons = pt.storeSurfacePhotons && req.surfacePhotons;
    if (req.maxMapBytes > 0) pt.maxMapBytes = std::min(pt.maxMapBytes, req.maxMapBytes);
    if (scene_.camera.scan != ScanMode::None) {  // a scan's pilot: the laser at its middle point
        pt.aimLight = scene_.camera.scanLaser;
        pt.aimTarget = scene_.camera.laserTarget(scene_.camera.laserPoints() / 2);
        pt.aimEmitOpl = scanEmitOpl(scene_, pt.aimTarget);
    }
    map_ = tracer_.trace(scene_, pt, ctx.abort);
    if (map_.aborted || (ctx.abort && ctx.abort->load())) return false;
    estimators_ = {};
    if (req.photonsOnly) return true;
    EstimatorPass ep;
    ep.threads = ctx.threads;
    if (scene_.stages.beams && (!map_.beams.empty() || !map_.points.empty())) {
        ep.radius = req.beamRadius;
        volume_->prepare(scene_, map_, ep);
        if (!volume_->empty()) estimators_.volume = volume_.get();
    }
    if (scene_.stages.surfacePhotons && !map_.photons.empty()) {
        ep.radius = req.surfaceRadius;
        surface_->prepare(scene_, map_, ep);
        if (!surface_->empty()) estimators_.surface = surface_.get();
    }
    camera_ = {};
    camera_.seed = req.seed;
    camera_.pass = 0;
    camera_.maxDepth = settings_.maxDepth;
    scratch_.resize(static_cast<size_t>(ctx.threads));
    for (auto& sc : scratch_) sc.acc.reset(ctx.time->bins, ctx.phasor);
    return !(ctx.abort && ctx.abort->load());
}

const PixelAccumulator* PhotonBeamsIntegrator::probePixel(const PassContext& ctx, int x, int y, int thread) {
    CameraPassScratch& scratch = scratch_[static_cast<size_t>(thread)];
    scratch.acc.clearTouched();
    CameraPassStats stats;
    renderPixel(scene_, estimators_, camera_, *ctx.time, x, y, scratch, stats);
    return &scratch.acc;
}

}  // namespace tpb
