#include "photons/photon_tracer.h"

#include <optional>

#include "base/error.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "base/rng.h"
#include "base/sampling.h"
#include "transport/free_flight.h"
#include "transport/interaction.h"

namespace tpb {

namespace {

// Length of a long beam that never reaches a surface (an unbounded medium). A contribution from
// the point s along the beam arrives at OPL >= opl0 + eta s on both time axes (the unwarped time is
// that of the scattering point, the real one adds the camera path), so a beam that reaches the
// film's end loses nothing the frames show: only the steady image and the energy counted after the
// film miss the flux the beam still carries at its end, which is counted (PhotonMap::cutFlux).
// At least 10 scene diagonals (the steady image near the scene), and never past the distance where
// the transmittance of every scattering channel is below 1e-7 (exp(-16.2)).
double openBeamLength(const Scene& scene, const Medium& m, double eta, double opl0, double filmEndOpl) {
    double sigmaScatter = kInf;  // smallest extinction among the channels that scatter
    for (int c = 0; c < 3; ++c)
        if (m.sigma_s[c] > 0.0) sigmaScatter = std::min(sigmaScatter, m.sigma_t[c]);
    const double diag = std::max(scene.bounds.diagonal(), 1e-3);
    const double toFilmEnd = filmEndOpl > opl0 ? (filmEndOpl - opl0) / eta : 0.0;
    const double wanted = std::max(10.0 * diag, toFilmEnd);
    return std::isfinite(sigmaScatter) ? std::min(wanted, 16.2 / sigmaScatter) : 10.0 * diag;
}

[[noreturn]] void mapTooLarge(const PhotonPassParams& s, const std::string& who) {
    throw UserError("", 0, "render.photons_per_pass",
                    "pass " + std::to_string(s.pass) + ": " + who + " stored more than " + humanBytes(s.maxMapBytes) +
                        " of photon beams, surface photons and points, the memory limit (TPB_MAX_FILM_BYTES); lower "
                        "photons_per_pass or render.max_depth (a medium or walls with albedo near 1 keep photons "
                        "alive for up to max_depth bounces)");
}

uint64_t mapBytes(size_t beams, size_t photons, size_t points) {
    return beams * sizeof(Beam) + photons * sizeof(SurfacePhoton) + points * sizeof(VolumePhoton);
}

}  // namespace

uint64_t storedMapBytes(const PhotonMap& m) { return mapBytes(m.beams.size(), m.photons.size(), m.points.size()); }

bool tracePhoton(const Scene& scene, const PhotonPassParams& s, int64_t index, PhotonMap& out,
                 const std::atomic<bool>* abort) {
    // Laser point l > 0 of a scan keys its photons above every photon index a pass can have.
    Rng rng(s.seed, Stream::Photon, s.pass, static_cast<uint64_t>(index) + (static_cast<uint64_t>(s.laserPoint) << 40));
    double lightPdf;
    const int li = scene.pickLight(rng.uniform(), lightPdf);
    if (li < 0 || lightPdf <= 0.0) return true;
    std::optional<Light> aimed;  // a scan's laser, aimed at this laser point (built only then)
    if (li == s.aimLight) {
        aimed = scene.lights[li];
        aimed->direction = glm::normalize(s.aimTarget - aimed->position);
        aimed->emitOpl = s.aimEmitOpl;
    }
    const Light& light = aimed ? *aimed : scene.lights[li];
    EmissionSample em = light.sampleEmission(rng, scene.rayEps);
    Color power = em.power / (lightPdf * static_cast<double>(s.powerPhotons > 0 ? s.powerPhotons : s.photons));
    const double power0 = maxComponent(power);
    if (!(power0 > 0.0)) return true;
    out.emittedFlux += power;
    Ray ray = em.ray;
    // The photon starts in the region where it leaves the light: a light inside a fog container
    // or a closed box emits into it (an area light may straddle a boundary: per point).
    const std::optional<RegionStack> startRegions = scene.emissionRegions(li, ray.o);
    if (!startRegions) {
        ++out.regionOverflows;
        return true;
    }
    RegionStack regions = *startRegions;
    double opl = light.emitOpl;        // eq. 11: the photon's clock starts at the pulse instant
    NullCrossingBudget nullCrossings;  // index-matched boundaries are not events: they do not use up depth
    const size_t beams0 = out.beams.size(), photons0 = out.photons.size(), points0 = out.points.size();

    // The start of the previous segment (the emission point at first) and its region's index: a
    // beam's `from` (photon_tracer.h).
    Vec3 prevStart = ray.o;
    double prevStartOpl = opl, prevIor = kInf;
    for (int depth = 0; depth < s.maxDepth; ++depth) {
        Vec3 from = prevStart;
        double fromOpl = prevStartOpl;
        const double fromIor = prevIor;
        prevStart = ray.o;
        prevStartOpl = opl;
        if ((depth & 4095) == 4095) {  // a long photon: the memory guard and the abort flag
            const uint64_t mine =
                mapBytes(out.beams.size() - beams0, out.photons.size() - photons0, out.points.size() - points0);
            if (s.maxMapBytes > 0 && mine > s.maxMapBytes) mapTooLarge(s, "photon " + std::to_string(index) + " alone");
            if (abort && abort->load(std::memory_order_relaxed)) return false;
        }
        const std::optional<SurfaceHit> hit = scene.geometry.intersect(ray);
        const double dSurf = hit ? hit->t : kInf;
        const Region& region = scene.regions[regions.top()];
        prevIor = region.ior;
        // Refracted into a denser medium: the straight path from the vertex before could be faster
        // than its length times this region's index, so the beam's own origin is its `from`.
        if (fromIor < region.ior) {
            from = ray.o;
            fromOpl = opl;
        }

        if (region.hasMedium && !region.medium.scattering) {
            // Absorbing only: no scattering event to sample, just attenuate up to the surface.
            if (!hit) break;
            power *= crossSegment(region, ray, hit->t).transmittance;
        } else if (region.hasMedium) {
            const Medium& m = region.medium;
            // Free-flight sampling with pdf sigma_bar exp(-sigma_bar d) (transport/free_flight.h).
            const FreeFlight ff = sampleFreeFlight(region, ray, dSurf, rng);
            if (s.storeBeams) {
                double len = s.beamLength == BeamLength::Short ? ff.distance : dSurf;
                if (!std::isfinite(len)) {
                    len = openBeamLength(scene, m, region.ior, opl, s.filmEndOpl);
                    out.cutFlux += power * m.transmittance(len);  // what flows on past the beam's end
                }
                if (len > 0.0 && std::isfinite(len) && s.keeps(static_cast<uint32_t>(depth)))
                    out.beams.push_back(
                        {ray.o, ray.d, len, power, opl, regions.top(), static_cast<uint32_t>(depth), from, fromOpl});
            }
            if (s.storePoints && ff.scattered && s.keeps(static_cast<uint32_t>(depth))) {
                // The point at the end of this segment (header): Phi T(d) / (sigma_bar Tbar(d)) per
                // channel, as one exponent so that neither transmittance underflows on its own.
                const double sigmaBar = m.samplingSigma(), d = ff.distance;
                const Color w(std::exp((sigmaBar - m.sigma_t.x) * d), std::exp((sigmaBar - m.sigma_t.y) * d),
                              std::exp((sigmaBar - m.sigma_t.z) * d));
                out.points.push_back({ray.at(d), ray.d, power * w / sigmaBar, opl + ff.opl, regions.top(),
                                      static_cast<uint32_t>(depth), d});
            }
            if (!std::isfinite(ff.distance)) break;
            // Weight: T(d) sigma_s / (sigma_bar T_bar(d)) at a scattering event, T / T_bar at a surface.
            power *= ff.weight;
            if (ff.scattered) {
                opl += ff.opl;
                ray = {ray.at(ff.distance), m.phase.sample(ray.d, rng.uniform(), rng.uniform())};
            }
            if (!isFinite(power)) {
                ++out.rejected;
                return true;
            }
            if (ff.scattered) {
                // Russian roulette on the throughput relative to the emitted power.
                if (!russianRoulette(rng, power, power0, depth + 1, s.rouletteDepth)) return true;
                continue;
            }
        }
        if (!hit) break;
        opl += region.ior * hit->t;

        const SurfaceInteraction si = interact(scene, ray, *hit);
        switch (si.kind) {
            case SurfaceKind::Emitter:
            case SurfaceKind::Absorber: return true;  // emitters and unassigned shapes absorb
            case SurfaceKind::Diffuse: {
                if (s.storeSurfacePhotons && s.keeps(static_cast<uint32_t>(depth)))
                    out.photons.push_back({hit->p, ray.d, si.ng, power, opl, hit->t, region.ior});
                const Vec3 newDir =
                    glm::normalize(toWorld(sampleCosineHemisphere(rng.uniform(), rng.uniform()), si.ns));
                if (glm::dot(newDir, si.ng) <= 0.0) return true;
                power *= si.material->albedo;
                ray = {scene.bounceOrigin(ray, *hit, si.ng), newDir};
                break;
            }
            case SurfaceKind::Mirror: {
                const SpecularContinuation c = reflectMirror(scene, ray, *hit, si);
                power *= c.tint;
                ray = c.ray;
                break;
            }
            case SurfaceKind::Dielectric:
            case SurfaceKind::Null: {
                const SpecularContinuation c = followInterface(scene, ray, *hit, si, regions, rng.uniform());
                if (c.regionOverflow) {
                    ++out.regionOverflows;
                    return true;
                }
                ray = c.ray;
                if (c.nullCrossing && nullCrossings.free()) {
                    --depth;
                    continue;
                }
                power *= c.tint;
                break;
            }
        }
        if (!russianRoulette(rng, power, power0, depth + 1, s.rouletteDepth)) return true;
    }
    return true;
}

PhotonMap PhotonTracer::trace(const Scene& scene, const PhotonPassParams& s, const std::atomic<bool>* abort) {
    constexpr int64_t kBatch = 1024;
    // The memory guard's running total is shared by the threads: each batch adds its bytes every
    // kGuardEvery photons (and at its end), not per photon, and checks the total with its own
    // unreported bytes at every photon.
    constexpr int64_t kGuardEvery = 64;
    const int64_t batches = (s.photons + kBatch - 1) / kBatch;
    parts_.resize(static_cast<size_t>(batches));
    for (PhotonMap& p : parts_) p.clear();
    std::atomic<uint64_t> stored{0};  // bytes of all batches so far, for the memory guard
    parallelFor(
        batches, s.threads,
        [&](int64_t b, int) {
            PhotonMap& part = parts_[static_cast<size_t>(b)];
            const int64_t end = std::min(s.photons, (b + 1) * kBatch);
            uint64_t reported = 0;  // of this batch's bytes, those added to `stored`
            int64_t i = b * kBatch;
            for (; i < end; ++i) {
                if (abort && abort->load(std::memory_order_relaxed)) break;
                if (!tracePhoton(scene, s, i, part, abort)) break;
                if (s.maxMapBytes > 0) {
                    const uint64_t mine = storedMapBytes(part);
                    uint64_t total = stored.load(std::memory_order_relaxed) + (mine - reported);
                    if ((i - b * kBatch) % kGuardEvery == kGuardEvery - 1 || i + 1 == end) {
                        total = stored.fetch_add(mine - reported) + (mine - reported);
                        reported = mine;
                    }
                    if (total > s.maxMapBytes) mapTooLarge(s, "the photons traced so far");
                }
            }
            part.emitted = i - b * kBatch;
            part.aborted = i < end;
        },
        abort);
    PhotonMap all;
    size_t nb = 0, np = 0, nv = 0;
    for (const PhotonMap& p : parts_) {
        nb += p.beams.size();
        np += p.photons.size();
        nv += p.points.size();
    }
    all.beams.reserve(nb);
    all.photons.reserve(np);
    all.points.reserve(nv);
    for (PhotonMap& p : parts_) {
        all.beams.insert(all.beams.end(), p.beams.begin(), p.beams.end());
        all.photons.insert(all.photons.end(), p.photons.begin(), p.photons.end());
        all.points.insert(all.points.end(), p.points.begin(), p.points.end());
        all.emitted += p.emitted;
        all.rejected += p.rejected;
        all.emittedFlux += p.emittedFlux;
        all.cutFlux += p.cutFlux;
        all.regionOverflows += p.regionOverflows;
        all.aborted = all.aborted || p.aborted;
    }
    // Batches never handed out (parallelFor stops at the abort flag) leave the map short too.
    if (abort && abort->load() && all.emitted < s.photons) all.aborted = true;
    return all;
}

PhotonMap tracePhotons(const Scene& scene, const PhotonPassParams& s, const std::atomic<bool>* abort) {
    return PhotonTracer().trace(scene, s, abort);
}

}  // namespace tpb
