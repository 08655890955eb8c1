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

namespace {


// The free-space point a surface photon arrived through (Scene::bounceOrigin for its landing).
Vec3 photonAnchor(const Scene& scene, const SurfacePhoton& ph) {
    return ph.position + scene.rayEps * (ph.normal - ph.dirIn);
}

// Shapes whose bounds come within r of the camera segment [0, sMax]: only they can stand between
// a point of the segment and a beam point within r of it (the beam visibility test in gatherBeams).
void nearShapes(const Scene& scene, const Ray& ray, double sMax, double r, std::vector<int>& out) {
    out.clear();
    Bounds3 seg;
    seg.expand(ray.o);
    seg.expand(ray.at(sMax));  // an unbounded segment gives infinite bounds: every shape is near
    const Vec3 pad(r + 8.0 * scene.rayEps);
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const Bounds3& b = scene.shapes[i].bounds;
        const bool apart = glm::any(glm::lessThan(b.hi + pad, seg.lo)) || glm::any(glm::greaterThan(b.lo - pad, seg.hi));
        if (!apart || !std::isfinite(sMax)) out.push_back(static_cast<int>(i));
    }
}

// Whether one of the `near` shapes' bounds meets the segment from a to b (else nothing blocks it).
bool mayBlock(const Scene& scene, const std::vector<int>& near, const Vec3& a, const Vec3& b) {
    const Vec3 pad(8.0 * scene.rayEps);
    const Vec3 lo = glm::min(a, b) - pad, hi = glm::max(a, b) + pad;
    for (int i : near) {
        const Bounds3& sb = scene.shapes[i].bounds;
        if (!(glm::any(glm::lessThan(sb.hi, lo)) || glm::any(glm::greaterThan(sb.lo, hi)))) return true;
    }
    return false;
}

struct PathState {
    Vec3 beta{1.0};
    double oplCam = 0.0;
};

// Beam radiance estimate along the camera segment x_r + s w_r, s in [0, sMax] (eqs. 8, 10, 12-15).
void gatherBeams(const Scene& scene, const PhotonMap& map, const BeamAccel& accel, const CameraPassSettings& s,
                 const TimeBins& time, const Ray& ray, double sMax, int regionId, const PathState& path,
                 CameraPassScratch& scratch, CameraPassStats& stats) {
    const Region& region = scene.regions[regionId];
    const Medium& m = region.medium;
    const double eta = region.ior;
    scratch.hits.clear();
    accel.query(ray.o, ray.d, sMax, regionId, scratch.hits);
    if (!scratch.hits.empty()) nearShapes(scene, ray, sMax, s.beamRadius, scratch.nearShapes);
    // tau_b: attenuation along the beam inside the kernel (photon_tracer.h).
    const Color tauB = s.beamLength == BeamLength::Long ? m.sigma_t : m.sigma_t - Color(m.samplingSigma());
    const double invArea = 1.0 / (kPi * s.beamRadius * s.beamRadius);  // 1 / Omega_R(r^2)
    for (const BeamHit& h : scratch.hits) {
        const Beam& b = map.beams[h.beam];
        const RayBeamOverlap& o = h.overlap;
        const double c = o.cosRB;
        // The kernel blurs the beam by r in every direction, also through a wall: a beam inside a
        // closed box would light the fog just outside it. Keep the estimate only when the beam
        // point nearest the middle of the overlap sees that point of the camera segment.
        const double sMid = 0.5 * (o.sMinus + o.sPlus);
        const double sbMid = std::clamp(o.sb0 + c * sMid, 0.0, b.length);
        const Vec3 xr = ray.at(sMid), xb = b.origin + sbMid * b.dir;
        if (mayBlock(scene, scratch.nearShapes, xr, xb) && !scene.segmentClear(xr, xb)) continue;
        // Eq. 8: L_b = sigma_s rho(theta) Phi_b / (pi r^2) * int T(s_r) T_b(s_b(s_r)) ds_r
        const Color integral(transmittanceIntegral(m.sigma_t.x, tauB.x, o), transmittanceIntegral(m.sigma_t.y, tauB.y, o),
                             transmittanceIntegral(m.sigma_t.z, tauB.z, o));
        const double rho = m.phase.eval(-c);  // scattering from w_b into -w_r (towards the camera)
        const Color L = path.beta * m.sigma_s * rho * b.power * invArea * integral;
        ++stats.beamEstimates;
        // Eqs. 12-15: t(s_r) = t_cam + t_b0 + eta s_b(s_r) + eta s_r, linear in s_r.
        const Color kappa = s.profile == TimeProfile::Exact ? m.sigma_t + tauB * c : Color(0.0);
        const double tBeam = b.opl0 + eta * o.sb0;
        splatSpread(time, scratch.acc, stats, L, kappa, o.sMinus, o.sPlus, path.oplCam + tBeam, eta * (1.0 + c), tBeam,
                      eta * c);
    }
}

}  // namespace

CameraPassStats& CameraPassStats::operator+=(const CameraPassStats& o) {
    FilmTally::operator+=(o);
    cameraRays += o.cameraRays;
    beamEstimates += o.beamEstimates;
    photonEstimates += o.photonEstimates;
    regionOverflows += o.regionOverflows;
    return *this;
}

void renderPixel(const Scene& scene, const PhotonMap& map, const BeamAccel* beams, const PhotonGrid* grid,
                 const CameraPassSettings& s, const TimeBins& time, int x, int y, CameraPassScratch& scratch,
                 CameraPassStats& stats) {
    const uint64_t pixelIndex = static_cast<uint64_t>(y) * scene.camera.width + x;
    Rng rng(s.seed, Stream::Camera, s.pass, pixelIndex);
    Ray ray = scene.camera.generate(x + rng.uniform(), y + rng.uniform());
    PathState path;
    RegionStack regions = scene.cameraRegions;
    ++stats.cameraRays;
    NullCrossingBudget nullCrossings;  // index-matched boundaries are not events: they do not use up depth

    for (int depth = 0; depth < s.maxDepth; ++depth) {
        const std::optional<SurfaceHit> hit = scene.geometry.intersect(ray);
        const double sMax = hit ? hit->t : kInf;
        const int regionId = regions.top();
        const Region& region = scene.regions[regionId];

        // Medium segment: gather photon beams (eq. 10: sum over the beams crossing the ray).
        if (beams && region.hasMedium && region.medium.scattering)
            gatherBeams(scene, map, *beams, s, time, ray, sMax, regionId, path, scratch, stats);
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
            // Transient progressive photon mapping: L = f_r sum Phi_p / (pi rs^2), at t_p + t_cam.
            if (grid) {
                const Color fr = mat.albedo * kInvPi;
                const double invArea = 1.0 / (kPi * s.surfaceRadius * s.surfaceRadius);
                const Vec3 anchor = scene.bounceOrigin(ray, *hit, ng);
                grid->forEachNear(hit->p, [&](const SurfacePhoton& ph) {
                    // Only photons that landed on this side of this surface: not the other side of
                    // a thin wall, not the inside of a closed box seen from outside (at its edges
                    // the faces are perpendicular only up to float rounding), not a surface across
                    // a gap narrower than the radius (a ceiling above a closed box).
                    if (glm::dot(ph.normal, ng) <= 0.0) return;
                    if (!scene.surfacePointsSeeEachOther(anchor, ng, photonAnchor(scene, ph), ph.normal)) return;
                    const Color L = path.beta * fr * ph.power * invArea;
                    ++stats.photonEstimates;
                    splatInstant(time, scratch.acc, stats, L, path.oplCam + ph.opl, ph.opl);
                });
            }
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

void renderTile(const Scene& scene, const PhotonMap& map, const BeamAccel* beams, const PhotonGrid* grid,
                const CameraPassSettings& s, TransientFilm& film, int tile, CameraPassScratch& scratch,
                CameraPassStats& stats) {
    const TileRect r = film.tileRect(tile);
    TransientFilm::TileWriter writer(film, tile);
    for (int y = r.y0; y < r.y0 + r.h; ++y)
        for (int x = r.x0; x < r.x0 + r.w; ++x) {
            renderPixel(scene, map, beams, grid, s, film.time(), x, y, scratch, stats);
            writer.addPixel(x, y, scratch.acc);
            scratch.acc.clearTouched();
        }
}

}  // namespace tpb
