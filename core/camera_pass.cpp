// Camera pass of Transient Photon Beams (Marco, Jarosz, Gutierrez, Jarabo 2017).
//
// Glossary (units): beta camera-path throughput (dimensionless RGB); oplCam optical path length of
// the camera path so far (m); r beam kernel radius (m); rs surface kernel radius (m); Phi photon or
// beam power (W, already divided by the number of photons of the pass); t OPL time (m).
#include "camera_pass.h"

#include "bsdf.h"
#include "rng.h"

namespace tpb {

namespace {


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
    // tau_b: attenuation along the beam inside the kernel (photon_tracer.h).
    const Color tauB = s.beamLength == BeamLength::Long ? m.sigma_t : m.sigma_t - Color(m.samplingSigma());
    const double invArea = 1.0 / (kPi * s.beamRadius * s.beamRadius);  // 1 / Omega_R(r^2)
    for (const BeamHit& h : scratch.hits) {
        const Beam& b = map.beams[h.beam];
        const RayBeamOverlap& o = h.overlap;
        const double c = o.cosRB;
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
    int nullCrossings = 0;  // index-matched boundaries are not events: they do not use up depth

    for (int depth = 0; depth < s.maxDepth; ++depth) {
        const std::optional<SurfaceHit> hit = scene.geometry.intersect(ray);
        const double sMax = hit ? hit->t : kInf;
        const int regionId = regions.top();
        const Region& region = scene.regions[regionId];

        // Medium segment: gather photon beams (eq. 10: sum over the beams crossing the ray).
        if (beams && region.hasMedium && region.medium.scattering)
            gatherBeams(scene, map, *beams, s, time, ray, sMax, regionId, path, scratch, stats);
        if (!hit) break;
        if (region.hasMedium) path.beta *= region.medium.transmittance(hit->t);
        path.oplCam += region.ior * hit->t;
        if (maxComponent(path.beta) <= 0.0) break;

        const ShapeInfo& shape = scene.shapes[hit->shape];
        const bool front = glm::dot(ray.d, hit->ng) < 0.0;
        const Vec3 ng = front ? hit->ng : -hit->ng;
        Vec3 ns = front ? hit->ns : -hit->ns;
        if (glm::dot(ns, ng) <= 0.0) ns = ng;

        if (shape.areaLight >= 0) {  // visible emitter, seen at its arrival time
            if (front) {
                const Light& l = scene.lights[shape.areaLight];
                splatInstant(time, scratch.acc, stats, path.beta * l.areaRadiance(), path.oplCam + l.emitOpl, l.emitOpl);
            }
            break;
        }
        if (shape.material < 0) break;
        const Material& mat = scene.materials[shape.material];
        if (mat.type == MaterialType::Diffuse) {
            // Transient progressive photon mapping: L = f_r sum Phi_p / (pi rs^2), at t_p + t_cam.
            if (grid) {
                const Color fr = mat.albedo * kInvPi;
                const double invArea = 1.0 / (kPi * s.surfaceRadius * s.surfaceRadius);
                grid->forEachNear(hit->p, [&](const SurfacePhoton& ph) {
                    if (glm::dot(ph.normal, ng) <= 0.0) return;  // other side of a thin surface
                    const Color L = path.beta * fr * ph.power * invArea;
                    ++stats.photonEstimates;
                    splatInstant(time, scratch.acc, stats, L, path.oplCam + ph.opl, ph.opl);
                });
            }
            break;
        }
        if (mat.type == MaterialType::Mirror) {
            path.beta *= mat.specular;
            ray = {hit->p + scene.rayEps * ng, glm::normalize(reflect(ray.d, ns))};
            continue;
        }
        // Dielectric or null boundary: follow reflection or refraction, chosen by Fresnel.
        ray = scene.followInterface(shape, mat, *hit, ray.d, front, ng, ns, regions, rng.uniform());
        if (mat.type == MaterialType::Null && ++nullCrossings <= 64) --depth;
        if (mat.type == MaterialType::Dielectric) path.beta *= mat.specular;
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
