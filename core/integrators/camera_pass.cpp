// Camera pass of Transient Photon Beams (Marco, Jarosz, Gutierrez, Jarabo 2017).
//
// Glossary (units): beta camera-path throughput (dimensionless RGB); oplCam optical path length of
// the camera path so far (m); r beam kernel radius (m); rs surface kernel radius (m); Phi photon or
// beam power (W, already divided by the number of photons of the pass); t OPL time (m).
#include "integrators/camera_pass.h"

#include "base/rng.h"
#include "transport/free_flight.h"
#include "transport/interaction.h"

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
            if (si.front) {
                const Light& l = scene.lights[si.shape->areaLight];
                splatInstant(time, scratch.acc, stats, path.beta * l.areaRadiance(), path.oplCam + l.emitOpl, l.emitOpl);
            }
            break;
        }
        if (si.kind == SurfaceKind::Absorber) break;
        const Material& mat = *si.material;
        if (si.kind == SurfaceKind::Diffuse) {
            // The surface estimate (transient progressive photon mapping) ends the path.
            if (est.surface) stats.photonEstimates += est.surface->gather({ray, *hit, ng, mat.albedo}, path, surfaceSink);
            break;
        }
        if (si.kind == SurfaceKind::Mirror) {
            const SpecularContinuation c = reflectMirror(scene, ray, *hit, si);
            path.beta *= c.tint;
            ray = c.ray;
            continue;
        }
        // Dielectric or null boundary: follow reflection or refraction, chosen by Fresnel.
        const SpecularContinuation c = followInterface(scene, ray, *hit, si, regions, rng.uniform());
        if (c.regionOverflow) { ++stats.regionOverflows; break; }
        ray = c.ray;
        if (c.nullCrossing && nullCrossings.free()) --depth;
        path.beta *= c.tint;
    }
}

void renderTile(const Scene& scene, const CameraPassEstimators& est, const CameraPassParams& s, TransientFilm& film,
                int tile, CameraPassScratch& scratch, CameraPassStats& stats) {
    const TileRect r = film.tileRect(tile);
    TransientFilm::TileWriter writer(film, tile);
    for (int y = r.y0; y < r.y0 + r.h; ++y)
        for (int x = r.x0; x < r.x0 + r.w; ++x) {
            renderPixel(scene, est, s, film.time(), x, y, scratch, stats);
            writer.addPixel(x, y, scratch.acc);
            scratch.acc.clearTouched();
        }
}

}  // namespace tpb
