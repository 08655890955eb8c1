// Unbiased transient volumetric path tracer (see path_tracer.h for the algorithm and the time axes).
//
// Glossary (units): beta camera-path throughput (dimensionless RGB, 1 at the sensor); oplCam OPL
// of the camera path from the sensor to the current vertex (m); oplUnw OPL of the camera path from
// its first non-specular vertex to the current vertex (m, 0 while there is none: the unwarped time
// of a contribution is emitOpl + connection + oplUnw, a sum of positive terms, so it never suffers
// the cancellation of "total - camera prefix"); Li light term of a connection (incident radiance
// times solid angle over the sampling pdfs, W / (m^2 sr)).
#include "integrators/path_tracer.h"

#include "base/error.h"
#include "base/parallel.h"
#include "base/rng.h"
#include "base/sampling.h"
#include "transport/free_flight.h"
#include "transport/interaction.h"

#include <climits>
#include <vector>

namespace tpb {

namespace {

constexpr int kMaxShadowCrossings = 64;
constexpr int kRussianRouletteDepth = 3;

struct PathContext {
    const Scene& scene;
    const TimeBins& time;
    PixelAccumulator& acc;
    PathTracerStats& stats;
    double sampleWeight;  // 1 / samplesPerPixel
    // A scan (scene/camera.h): the pixel's laser point; the scan's laser aims there, pulsing at
    // aimEmitOpl (scanEmitOpl). Null: every laser keeps its own direction.
    const Vec3* aim = nullptr;
    double aimEmitOpl = 0.0;
    // The bounce filter (RenderSettings::bounceMin/bounceMax) and the scattering vertices of the
    // camera path up to the one connecting now (a laser's spot adds one event).
    int bounceMin = 0, bounceMax = INT_MAX;
    int vertices = 0;
    bool keeps(int events) const { return events >= bounceMin && events <= bounceMax; }
};

// Where equiangular sampling stops on a segment: transmittance e^-30 in the clearest channel.
// Beyond it, free-flight vertices alone connect to delta lights, so an unbounded segment (an open
// medium) neither wastes samples at negligible transmittance nor puts them at absurd times.
double equiangularReach(const Medium& m) {
    const double sigmaMin = std::min(m.sigma_t.x, std::min(m.sigma_t.y, m.sigma_t.z));
    return sigmaMin > 0.0 ? 30.0 / sigmaMin : kInf;
}

// A laser's leg: its beam (from disc point (u1, u2), aimed at the pixel's laser point for a scan)
// up to the first surface, inside the region the laser sits in. Two ways to connect a vertex x to it:
//  - the spot, where the beam meets a diffuse surface: it re-emits the flux the leg transmits as a
//    Lambertian point, of radiant intensity Phi T_leg (rho / pi) cos(n, w) towards w (W / sr);
//  - the beam itself when the region scatters: a line light whose point y(s) sends
//    Phi T(s) sigma_s p(cos(d, w)) ds towards w; s is sampled equiangularly about x
//    (base/sampling.h), which keeps the 1 / |x - y|^2 bounded next to the beam.
// The laser's delta direction is carried by the leg in both. Not connected: a beam that meets glass,
// a mirror or a null boundary first (no spot), and light scattered beyond the laser's own region.
struct LaserLeg {
    Ray ray;
    double length = kInf;  // to the first surface
    const Region* region = nullptr;
    double emitOpl = 0.0;                   // pulse instant (a scan's: scanEmitOpl)
    bool spot = false;                      // the leg ends on a diffuse surface
    Vec3 spotAnchor{0.0}, spotNormal{0.0};  // rayEps in front of the spot; its normal, facing the laser
    Color spotIntensityCos{0.0};            // Phi T_leg rho / pi (W / sr per unit cosine)
    double spotOpl = 0.0;                   // pulse instant + the leg's OPL
    bool scattering() const { return region->hasMedium && region->medium.scattering; }
};

LaserLeg laserLeg(const PathContext& ctx, int li, double u1, double u2) {
    const Scene& scene = ctx.scene;
    const Light& light = scene.lights[li];
    const bool aimed = ctx.aim && li == scene.camera.scanLaser;
    LaserLeg leg;
    const Vec3 dir = aimed ? glm::normalize(*ctx.aim - light.position) : light.direction;
    leg.ray = {light.laserOrigin(u1, u2, dir), dir};
    leg.region = &scene.regions[static_cast<size_t>(scene.lightPlacement[static_cast<size_t>(li)].regions.top())];
    leg.emitOpl = aimed ? ctx.aimEmitOpl : light.emitOpl;
    const std::optional<SurfaceHit> hit = scene.geometry.intersect(leg.ray);
    if (!hit) return leg;
    leg.length = hit->t;
    const SurfaceInteraction si = interact(scene, leg.ray, *hit);
    if (si.kind != SurfaceKind::Diffuse) return leg;
    const SegmentTransport seg = crossSegment(*leg.region, leg.ray, hit->t);
    leg.spot = true;
    leg.spotAnchor = scene.bounceOrigin(leg.ray, *hit, si.ng);
    leg.spotNormal = si.ng;
    leg.spotIntensityCos = light.power * seg.transmittance * si.material->albedo * kInvPi;
    leg.spotOpl = leg.emitOpl + seg.opl;
    return leg;
}

// One contribution at real time tReal and unwarped time tUnw.
void splat(PathContext& ctx, const Color& L, double tReal, double tUnw) {
    const int64_t rejectedBefore = ctx.stats.rejected;
    splatInstant(ctx.time, ctx.acc, ctx.stats, L * ctx.sampleWeight, tReal, tUnw);
    if (ctx.stats.rejected == rejectedBefore && !isBlack(L)) ++ctx.stats.contributions;
}

// Shadow ray from `from` (in the region on top of `stack`) to `to`. Null boundaries are crossed
// (push on entering, pop on leaving), any other surface blocks. On success returns the product of
// the regions' transmittances and the OPL of the connection.
bool traceShadow(const Scene& scene, Vec3 from, const Vec3& to, RegionStack stack, Color& tr, double& opl,
                 PathTracerStats& stats) {
    tr = Color(1.0);
    opl = 0.0;
    for (int i = 0; i < kMaxShadowCrossings; ++i) {
        const Vec3 v = to - from;
        const double dist = glm::length(v);
        if (!(dist > 0.0)) return true;
        const Ray ray{from, v / dist, 0.0, dist};
        const std::optional<SurfaceHit> hit = scene.geometry.intersect(ray);
        const SegmentTransport seg = crossSegment(scene.regions[stack.top()], ray, hit ? hit->t : dist);
        opl += seg.opl;
        tr *= seg.transmittance;
        if (!hit) return true;
        const SurfaceInteraction si = interact(scene, ray, *hit);
        if (si.kind != SurfaceKind::Null) return false;  // every other surface blocks
        const SpecularContinuation c = crossNull(scene, ray, *hit, si, stack);
        if (c.regionOverflow) {
            ++stats.regionOverflows;
            return false;
        }
        from = c.ray.o;
    }
    return false;
}

bool isDeltaPositionLight(const Light& l) { return l.type == LightType::Point || l.type == LightType::Spot; }

// The connection of vertex x to light `li` (picked with probability `pick`; u1, u2 place the point
// on an area light): light term, shadow ray from x + offset, splat at the connection's times.
// `scatter(w)` is the vertex's phase function or BSDF-times-cosine for the direction w to the light.
template <class Scatter>
void connectLight(PathContext& ctx, int li, double pick, double u1, double u2, double u3, double u4, const Vec3& x,
                  const Vec3& offset, const RegionStack& regions, const Color& beta, double oplCam, double oplUnw,
                  Scatter&& scatter) {
    const Scene& scene = ctx.scene;
    const Light& light = scene.lights[li];
    Vec3 y;
    Color Li(0.0);
    double emitOpl = light.emitOpl;
    switch (light.type) {
        case LightType::Point:
        case LightType::Spot: {
            y = light.position;
            const Vec3 v = y - x;
            const double d2 = glm::dot(v, v);
            if (!(d2 > 0.0)) return;
            double intensity = 1.0 / (4.0 * kPi);  // per watt, point light
            if (light.type == LightType::Spot) {
                const double cosL = glm::dot(light.direction, -v / std::sqrt(d2));
                intensity = light.spotIntegral > 0.0 ? light.spotProfile(cosL) / light.spotIntegral : 0.0;
            }
            Li = light.power * (intensity / d2);
            break;
        }
        case LightType::AreaQuad: {
            // pdf 1 / area. The shadow ray ends where the light's photons start (rayEps in front of
            // the quad and in from its edges): a light filling a closed box's ceiling is then out
            // of reach from outside, also through the box's edges.
            y = light.offsetAreaPoint(u1, u2, scene.rayEps);
            const Vec3 v = y - x;
            const double d2 = glm::dot(v, v);
            if (!(d2 > 0.0)) return;
            const double cosL = -glm::dot(light.normal, v) / std::sqrt(d2);
            if (cosL <= 0.0) return;  // one-sided: emits along its normal only
            Li = light.areaRadiance() * (cosL * light.area / d2);
            break;
        }
        case LightType::Laser: {
            const LaserLeg leg = laserLeg(ctx, li, u1, u2);
            const bool beam = leg.scattering() && leg.length > 0.0;
            if (!leg.spot && !beam) {
                ++ctx.stats.laserSamples;
                return;
            }
            // The spot or the beam, with probability 1/2 each when both can be connected.
            const bool both = leg.spot && beam;
            const bool useSpot = leg.spot && (!both || u3 < 0.5);
            const double choice = both ? 0.5 : 1.0;
            if (useSpot) {
                y = leg.spotAnchor;
                const Vec3 v = y - x;
                const double d2 = glm::dot(v, v);
                if (!(d2 > 0.0)) return;
                const double cosOut = -glm::dot(leg.spotNormal, v) / std::sqrt(d2);
                if (cosOut <= 0.0) return;  // behind the spot's surface (or along it: the wall itself)
                Li = leg.spotIntensityCos * (cosOut / (d2 * choice));
                emitOpl = leg.spotOpl;
            } else {
                const Medium& m = leg.region->medium;
                const double reach = std::min(leg.length, equiangularReach(m));
                const EquiangularFrame f(leg.ray.o, leg.ray.d, reach, x);
                if (!f.valid) return;
                const EquiangularSample eq = f.sample(u4);
                if (!(eq.t >= 0.0 && eq.t < reach) || !(eq.pdf > 0.0) || !std::isfinite(eq.pdf)) return;
                y = leg.ray.at(eq.t);
                const Vec3 v = x - y;
                const double d2 = glm::dot(v, v);
                if (!(d2 > 0.0)) return;
                const double phase = m.phase.eval(glm::dot(leg.ray.d, v / std::sqrt(d2)));
                Li = light.power * m.transmittance(eq.t) * m.sigma_s * (phase / (d2 * eq.pdf * choice));
                emitOpl = leg.emitOpl + leg.region->ior * eq.t;
                ++ctx.stats.equiangularSamples;
            }
            break;
        }
    }
    if (isBlack(Li) || !ctx.keeps(ctx.vertices + (light.type == LightType::Laser ? 1 : 0))) return;
    const Vec3 w = glm::normalize(y - x);
    const Color f = scatter(w);
    if (isBlack(f)) return;
    ++ctx.stats.shadowRays;
    Color tr;
    double oplShadow;
    if (!traceShadow(scene, x + offset, y, regions, tr, oplShadow, ctx.stats)) return;
    const Color L = beta * f * Li * tr / pick;
    splat(ctx, L, emitOpl + oplShadow + oplCam, emitOpl + oplShadow + oplUnw);
}

// The two techniques that place a scattering point on a medium segment and connect it to a point
// or spot light: free flight (pdf sigma_bar exp(-sigma_bar t), the vertex the path continues
// from) and equiangular (EquiangularFrame, base/sampling.h, on [0, reach)). Each takes one
// sample; the balance heuristic weights them, so the sum stays unbiased while each covers where
// the other is poor: equiangular next to the light (where free flight has infinite variance: the
// integral of 1/d^4 over a ball around the light diverges), free flight far from it, where the
// transmittance dominates.
struct SegmentMis {
    Ray ray;
    double reach = 0.0, sigmaBar = 0.0;
    double freeFlightPdf(double t) const { return sigmaBar * std::exp(-sigmaBar * t); }
};

// Next-event estimation at vertex x: one light picked with Scene::pickLight, then connectLight.
// At a free-flight medium vertex (distance t along `mis->ray`) a delta light's connection carries
// the free-flight technique's MIS weight.
template <class Scatter>
void nextEvent(PathContext& ctx, Rng& rng, const Vec3& x, const Vec3& offset, const RegionStack& regions, Color beta,
               double oplCam, double oplUnw, const SegmentMis* mis, double t, Scatter&& scatter) {
    // Always draw the same count of numbers, so later decisions do not depend on the light type.
    const double uLight = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    double pick = 0.0;
    const int li = ctx.scene.pickLight(uLight, pick);
    if (li < 0 || !(pick > 0.0)) return;
    const Light& light = ctx.scene.lights[li];
    if (mis && isDeltaPositionLight(light) && t < mis->reach) {
        const EquiangularFrame f(mis->ray.o, mis->ray.d, mis->reach, light.position);
        if (f.valid) {
            const double pff = mis->freeFlightPdf(t), peq = f.pdf(t);
            beta *= pff / (pff + peq);
        }
    }
    // A laser takes two more numbers (spot or beam, the point on the beam): drawn only for lasers,
    // so the paths of scenes without one are what they were.
    double u3 = 0.0, u4 = 0.0;
    if (light.type == LightType::Laser) u3 = rng.uniform(), u4 = rng.uniform();
    connectLight(ctx, li, pick, u1, u2, u3, u4, x, offset, regions, beta, oplCam, oplUnw, scatter);
}

// The equiangular technique on one medium segment (see SegmentMis): a light picked with
// Scene::pickLight; a point or spot light gets an equiangular point t on [0, reach) and the
// estimate  beta sigma_s(t) T(t) / pdf_eq(t) * w_eq(t) * connection.
void equiangularSegment(PathContext& ctx, Rng& rng, const SegmentMis& mis, const Region& region,
                        const RegionStack& regions, const Color& beta, double oplCam, double oplUnw, bool nonSpecular) {
    const double uLight = rng.uniform(), uT = rng.uniform();  // always two numbers
    double pick = 0.0;
    const int li = ctx.scene.pickLight(uLight, pick);
    if (li < 0 || !(pick > 0.0)) return;
    const Light& light = ctx.scene.lights[li];
    if (!isDeltaPositionLight(light)) return;
    const EquiangularFrame f(mis.ray.o, mis.ray.d, mis.reach, light.position);
    if (!f.valid) return;
    const EquiangularSample eq = f.sample(uT);  // base/sampling.h
    const double t = eq.t;
    if (!(t >= 0.0 && t < mis.reach)) return;  // rounding at the ends
    const double peq = eq.pdf, pff = mis.freeFlightPdf(t);
    if (!(peq > 0.0) || !std::isfinite(peq)) return;
    const Medium& m = region.medium;
    // sigma_s T / pdf_eq * w_eq = sigma_s T / pdf_eq * pdf_eq / (pdf_eq + pdf_ff) = sigma_s T / (pdf_eq + pdf_ff)
    const Color weight = beta * m.sigma_s * m.transmittance(t) / (peq + pff);
    const double dOpl = region.ior * t;
    ++ctx.stats.equiangularSamples;
    connectLight(ctx, li, pick, 0.0, 0.0, 0.0, 0.0, mis.ray.at(t), Vec3(0.0), regions, weight, oplCam + dOpl,
                 nonSpecular ? oplUnw + dOpl : 0.0,
                 [&](const Vec3& w) { return Color(m.phase.eval(glm::dot(mis.ray.d, w))); });
}

// Russian roulette on the throughput from the kRussianRouletteDepth-th vertex on, ending even
// full-throughput paths past kDeepRouletteDepth vertices (russianRoulette); false if the path dies.
bool roulette(Rng& rng, Color& beta, int depth) {
    if (depth < kRussianRouletteDepth) return true;
    return russianRoulette(rng, beta, 1.0, depth);
}

void tracePath(PathContext& ctx, const RenderSettings& s, Ray ray, Rng& rng) {
    const Scene& scene = ctx.scene;
    Color beta(1.0);
    double oplCam = scene.camera.startOpl(ray), oplUnw = 0.0;  // 0 but for a relay wall timed from the wall
    bool nonSpecular = false;                                  // the path has reached its first non-specular vertex
    bool emitterVisible = true;                 // previous vertex is the sensor or specular: emitter hits count
    RegionStack regions = scene.cameraRegions;  // where the camera sits (usually the outside)
    int depth = 0;
    ++ctx.stats.cameraPaths;
    // Null crossings do not count as depth; this bounds the loop in degenerate geometry.
    const int maxIterations = 4 * std::max(s.maxDepth, 1) + 256;

    for (int it = 0; it < maxIterations; ++it) {
        const std::optional<SurfaceHit> hit = scene.geometry.intersect(ray);
        const double dSurf = hit ? hit->t : kInf;
        const Region& region = scene.regions[regions.top()];

        if (region.hasMedium) {
            const Medium& m = region.medium;
            if (m.scattering) {
                // A scattering vertex on this segment would be at depth + 1 <= maxDepth.
                const double sigmaBar = m.samplingSigma();
                const SegmentMis mis{ray, s.equiangular ? std::min(dSurf, equiangularReach(m)) : 0.0, sigmaBar};
                if (s.equiangular) {
                    ctx.vertices = depth + 1;  // the equiangular point is this segment's scattering vertex
                    equiangularSegment(ctx, rng, mis, region, regions, beta, oplCam, oplUnw, nonSpecular);
                }
                const FreeFlight ff = sampleFreeFlight(region, ray, dSurf, rng);
                if (ff.scattered) {
                    // Medium scattering vertex.
                    const double d = ff.distance;
                    beta *= ff.weight;
                    oplCam += ff.opl;
                    if (nonSpecular) oplUnw += ff.opl;
                    nonSpecular = true;
                    if (!isFinite(beta)) {
                        ++ctx.stats.rejected;
                        return;
                    }
                    const Vec3 x = ray.at(d);
                    ++depth;
                    const Vec3 wi = ray.d;
                    ctx.vertices = depth;
                    nextEvent(ctx, rng, x, Vec3(0.0), regions, beta, oplCam, oplUnw, s.equiangular ? &mis : nullptr, d,
                              [&](const Vec3& w) { return Color(m.phase.eval(glm::dot(wi, w))); });
                    if (depth >= s.maxDepth) {
                        ++ctx.stats.depthLimited;
                        return;
                    }
                    if (!roulette(rng, beta, depth)) return;
                    const double v1 = rng.uniform(), v2 = rng.uniform();
                    ray = {x, m.phase.sample(wi, v1, v2)};
                    emitterVisible = false;
                    continue;
                }
                if (hit) beta *= ff.weight;
            } else if (hit) {
                beta *= crossSegment(region, ray, dSurf).transmittance;
            }
        }
        if (!hit) return;  // escaped
        oplCam += region.ior * hit->t;
        if (nonSpecular) oplUnw += region.ior * hit->t;
        if (!isFinite(beta)) {
            ++ctx.stats.rejected;
            return;
        }
        if (isBlack(beta)) return;

        const SurfaceInteraction si = interact(scene, ray, *hit);
        const Vec3& ng = si.ng;  // facing the incoming ray
        const Vec3& ns = si.ns;

        if (si.kind == SurfaceKind::Emitter) {  // emitter: visible from its front side, absorbs
            if (si.front && emitterVisible) {
                const Light& l = scene.lights[si.shape->areaLight];
                if (ctx.keeps(depth)) splat(ctx, beta * l.areaRadiance(), l.emitOpl + oplCam, l.emitOpl + oplUnw);
            }
            return;
        }
        if (si.kind == SurfaceKind::Absorber) return;
        const Material& mat = *si.material;

        if (si.kind == SurfaceKind::Null) {
            // Index-matched boundary (as in the beam core): no bending, no reflection, no depth.
            const SpecularContinuation c = crossNull(scene, ray, *hit, si, regions);
            if (c.regionOverflow) {
                ++ctx.stats.regionOverflows;
                return;
            }
            ray = c.ray;
            continue;
        }

        ++depth;
        if (si.kind == SurfaceKind::Diffuse) {
            nonSpecular = true;
            const Color fr = mat.albedo * kInvPi;
            const Vec3 origin = scene.bounceOrigin(ray, *hit, ng);
            ctx.vertices = depth;
            nextEvent(ctx, rng, hit->p, origin - hit->p, regions, beta, oplCam, oplUnw, nullptr, 0.0,
                      [&](const Vec3& w) {
                          if (glm::dot(w, ng) <= 0.0) return Color(0.0);  // light behind the surface
                          return fr * std::max(0.0, glm::dot(w, ns));
                      });
            if (depth >= s.maxDepth) {
                ++ctx.stats.depthLimited;
                return;
            }
            const double v1 = rng.uniform(), v2 = rng.uniform();
            const Vec3 wo = glm::normalize(toWorld(sampleCosineHemisphere(v1, v2), ns));
            if (glm::dot(wo, ng) <= 0.0) return;
            beta *= mat.albedo;  // f cos / pdf
            ray = {origin, wo};
            emitterVisible = false;
        } else if (si.kind == SurfaceKind::Mirror) {
            if (depth >= s.maxDepth) {
                ++ctx.stats.depthLimited;
                return;
            }
            const SpecularContinuation c = reflectMirror(scene, ray, *hit, si);
            beta *= c.tint;
            ray = c.ray;
            emitterVisible = true;
        } else {  // dielectric: reflection or refraction chosen by Fresnel
            if (depth >= s.maxDepth) {
                ++ctx.stats.depthLimited;
                return;
            }
            const SpecularContinuation c = followInterface(scene, ray, *hit, si, regions, rng.uniform());
            if (c.regionOverflow) {
                ++ctx.stats.regionOverflows;
                return;
            }
            ray = c.ray;
            beta *= c.tint;
            emitterVisible = true;
        }
        if (!roulette(rng, beta, depth)) return;
    }
    ++ctx.stats.depthLimited;
}

}  // namespace

PathTracerStats& PathTracerStats::operator+=(const PathTracerStats& o) {
    FilmTally::operator+=(o);
    cameraPaths += o.cameraPaths;
    contributions += o.contributions;
    shadowRays += o.shadowRays;
    laserSamples += o.laserSamples;
    equiangularSamples += o.equiangularSamples;
    depthLimited += o.depthLimited;
    regionOverflows += o.regionOverflows;
    return *this;
}

void pathTracePixel(const Scene& scene, const RenderSettings& s, uint64_t pass, const TimeBins& time, int x, int y,
                    PixelAccumulator& acc, PathTracerStats& stats) {
    const int spp = std::max(1, s.samplesPerPixel);
    const uint64_t pixelIndex = static_cast<uint64_t>(y) * static_cast<uint64_t>(scene.camera.width) + x;
    Rng rng(s.seed, Stream::PathTracer, pass, pixelIndex);
    PathContext ctx{scene, time, acc, stats, 1.0 / spp};
    ctx.bounceMin = s.bounceMin;
    ctx.bounceMax = s.bounceMax;
    Vec3 aim;
    if (scene.camera.scan != ScanMode::None) {
        aim = scene.camera.laserTarget(scene.camera.laserPointOf(x, y));
        ctx.aim = &aim;
        ctx.aimEmitOpl = scanEmitOpl(scene, aim);
    }
    for (int i = 0; i < spp; ++i) {
        const double jx = rng.uniform(), jy = rng.uniform();
        tracePath(ctx, s, scene.camera.generate(x + jx, y + jy), rng);
    }
}

}  // namespace tpb
