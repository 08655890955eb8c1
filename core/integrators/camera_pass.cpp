// Camera pass of Transient Photon Beams (Marco, Jarosz, Gutierrez, Jarabo 2017).
//
// Glossary (units): beta camera-path throughput (dimensionless RGB); oplCam optical path length of
// the camera path so far (m); r beam kernel radius (m); rs surface kernel radius (m); Phi photon or
// beam power (W, already divided by the number of photons of the pass); t OPL time (m).
#include "integrators/camera_pass.h"

#include "base/rng.h"
#include "transport/free_flight.h"
#include "transport/interaction.h"

#include <algorithm>
#include <cmath>

namespace tpb {

CameraPassStats& CameraPassStats::operator+=(const CameraPassStats& o) {
    FilmTally::operator+=(o);
    cameraRays += o.cameraRays;
    beamEstimates += o.beamEstimates;
    photonEstimates += o.photonEstimates;
    regionOverflows += o.regionOverflows;
    return *this;
}

void renderPixel(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, const TimeBins& time,
                 int x, int y, CameraPassScratch& scratch, CameraPassStats& stats) {
    const uint64_t pixelIndex = static_cast<uint64_t>(y) * scene.camera.width + x;
    Rng rng(s.seed, Stream::Camera, s.pass, pixelIndex);
    Ray ray = scene.camera.generate(x + rng.uniform(), y + rng.uniform());
    PathState path;
    path.oplCam = scene.camera.startOpl(ray);  // 0 but for a relay wall timed from the wall
    PixelSink volumeSink{time, scratch.acc, stats, est.volumeKernel};
    PixelSink surfaceSink{time, scratch.acc, stats, est.surfaceKernel};
    RegionStack regions = scene.cameraRegions;
    ++stats.cameraRays;
    NullCrossingBudget nullCrossings;  // index-matched boundaries are not events: they do not use up depth

    for (int depth = 0; depth < s.maxDepth; ++depth) {
        const std::optional<SurfaceHit> hit = scene.geometry.intersect(ray);
        const double sMax = hit ? hit->t : kInf;
        const int regionId = regions.top();
        const Region& region = scene.regions[regionId];

        // Medium segment: the volume estimate along it (photon beams: eq. 10, the sum over the
        // beams crossing the ray).
        if (est.volume && region.hasMedium && region.medium.scattering)
            stats.beamEstimates += est.volume->gather({ray, sMax, regionId}, path, volumeSink, scratch.estimator);
        if (!hit) break;
        const SegmentTransport seg = crossSegment(region, ray, hit->t);
        path.beta *= seg.transmittance;
        path.oplCam += seg.opl;
        if (maxComponent(path.beta) <= 0.0) break;

        const SurfaceInteraction si = interact(scene, ray, *hit);
        const Vec3& ng = si.ng;
        if (si.kind == SurfaceKind::Emitter) {  // visible emitter, seen at its arrival time
            if (si.front && s.emittersSeen) {
                const Light& l = scene.lights[si.shape->areaLight];
                splatInstant(time, scratch.acc, stats, path.beta * l.areaRadiance(), path.oplCam + l.emitOpl,
                             l.emitOpl);
            }
            break;
        }
        if (si.kind == SurfaceKind::Absorber) break;
        const Material& mat = *si.material;
        if (si.kind == SurfaceKind::Diffuse) {
            // The surface estimate (transient progressive photon mapping) ends the path.
            if (est.surface)
                stats.photonEstimates += est.surface->gather({ray, *hit, ng, mat.albedo}, path, surfaceSink);
            break;
        }
        if (si.kind == SurfaceKind::Mirror) {
            const SpecularContinuation c = reflectMirror(scene, ray, *hit, si);
            path.beta *= c.tint;
            ray = c.ray;
        } else {
            // Dielectric or null boundary: follow reflection or refraction, chosen by Fresnel.
            const SpecularContinuation c = followInterface(scene, ray, *hit, si, regions, rng.uniform());
            if (c.regionOverflow) {
                ++stats.regionOverflows;
                break;
            }
            ray = c.ray;
            if (c.nullCrossing && nullCrossings.free()) {
                --depth;
                continue;
            }
            path.beta *= c.tint;
        }
        // A specular chain that never loses weight (a closed box of perfect mirrors) still ends
        // past kDeepRouletteDepth bounces, whatever max_depth; before that no roulette, no random
        // number (the films of max_depth < kDeepRouletteDepth stay as they were).
        if (depth + 1 >= kDeepRouletteDepth && !russianRoulette(rng, path.beta, 1.0, depth + 1)) break;
    }
}

namespace {

double farthestFromCamera(const Scene& scene) {
    const Bounds3& b = scene.bounds;
    double far2 = 0.0;
    for (int i = 0; i < 8; ++i) {
        const Vec3 c((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
        const Vec3 d = c - scene.camera.position;
        far2 = std::max(far2, glm::dot(d, d));
    }
    return std::sqrt(far2);
}

}  // namespace

BundleHint bundleHint(const Scene& scene, int x0, int y0, int w, int h) {
    const Camera& cam = scene.camera;
    BundleHint hint;
    hint.origin = cam.position;
    hint.axis = cam.generate(x0 + 0.5 * w, y0 + 0.5 * h).d;
    double sin2 = 0.0;
    for (int i = 0; i < 4; ++i) {
        const Vec3 d = cam.generate(x0 + ((i & 1) ? w : 0), y0 + ((i & 2) ? h : 0)).d;
        const Vec3 c = glm::cross(hint.axis, d);
        sin2 = std::max(sin2, glm::dot(c, c));
    }
    hint.sinHalfAngle = std::sqrt(sin2);
    hint.maxLength = farthestFromCamera(scene);
    hint.region = scene.cameraRegions.top();
    return hint;
}

double bundleSlack(const Scene& scene, int block) {
    const Region& region = scene.regions[scene.cameraRegions.top()];
    if (!region.hasMedium || !region.medium.scattering || block < 2) return 0.0;
    const Camera& cam = scene.camera;
    const int x0 = std::max(0, cam.width / 2 - block / 2), y0 = std::max(0, cam.height / 2 - block / 2);
    const BundleHint h = bundleHint(scene, x0, y0, block, block);
    // 1 % more: the segments that end on the bounds' farthest corner are contained too.
    return 1.01 * h.sinHalfAngle * h.maxLength;
}

BundlePlan planBundles(const Scene& scene, double radius) {
    for (const int block : {4, 2}) {
        const double slack = bundleSlack(scene, block);
        if (slack > 0.0 && slack <= kMaxBundleSlackRadii * radius) return {block, slack};
    }
    return {};
}

void renderPixels(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, const TimeBins& time,
                  const TileRect& r, TransientFilm::TileWriter& writer, CameraPassScratch& scratch,
                  CameraPassStats& stats) {
    const int block = std::max(1, s.bundleBlock);
    for (int by = r.y0; by < r.y0 + r.h; by += block)
        for (int bx = r.x0; bx < r.x0 + r.w; bx += block) {
            const int bw = std::min(block, r.x0 + r.w - bx), bh = std::min(block, r.y0 + r.h - by);
            if (block > 1) scratch.estimator.bundle.begin(bundleHint(scene, bx, by, bw, bh));
            for (int y = by; y < by + bh; ++y)
                for (int x = bx; x < bx + bw; ++x) {
                    renderPixel(scene, est, s, time, x, y, scratch, stats);
                    writer.addPixel(x, y, scratch.acc);
                    scratch.acc.clearTouched();
                }
            if (block > 1) scratch.estimator.bundle.end();
        }
}

void renderTile(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, TransientFilm& film,
                int tile, CameraPassScratch& scratch, CameraPassStats& stats) {
    TransientFilm::TileWriter writer(film, tile);
    renderPixels(scene, est, s, film.time(), film.tileRect(tile), writer, scratch, stats);
}

}  // namespace tpb
