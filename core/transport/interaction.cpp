// Surface interactions along a path (see interaction.h).
#include "transport/interaction.h"

#include "scene/bsdf.h"

namespace tpb {

namespace {

// The region stack on transmission through a dielectric/null surface: entering (against its
// normal) pushes the shape's interior, leaving pops. False, stack untouched, when the push finds
// the stack full (RegionStack).
[[nodiscard]] bool crossRegions(const SurfaceInteraction& si, RegionStack& regions) {
    if (!si.front) {
        regions.pop();
        return true;
    }
    return regions.push(si.shape->interiorRegion);
}

}  // namespace

SurfaceInteraction interact(const Scene& scene, const Ray& ray, const SurfaceHit& hit) {
    SurfaceInteraction si;
    si.shape = &scene.shapes[hit.shape];
    si.front = glm::dot(ray.d, hit.ng) < 0.0;
    si.ng = si.front ? hit.ng : -hit.ng;
    si.ns = si.front ? hit.ns : -hit.ns;
    if (glm::dot(si.ns, si.ng) <= 0.0) si.ns = si.ng;
    if (si.shape->areaLight >= 0) {
        si.kind = SurfaceKind::Emitter;  // visible from its front side; absorbs
        return si;
    }
    if (si.shape->material < 0) {
        si.kind = SurfaceKind::Absorber;  // unassigned shapes absorb
        return si;
    }
    si.material = &scene.materials[si.shape->material];
    switch (si.material->type) {
        case MaterialType::Diffuse: si.kind = SurfaceKind::Diffuse; break;
        case MaterialType::Mirror: si.kind = SurfaceKind::Mirror; break;
        case MaterialType::Dielectric: si.kind = SurfaceKind::Dielectric; break;
        case MaterialType::Null: si.kind = SurfaceKind::Null; break;
    }
    return si;
}

InterfaceEtas interfaceEtas(const Scene& scene, const ShapeInfo& shape, bool entering, const RegionStack& stack) {
    InterfaceEtas e;
    e.etaI = scene.regions[stack.top()].ior;
    e.etaT = entering ? scene.regions[shape.interiorRegion].ior : scene.regions[stack.below()].ior;
    return e;
}

SpecularContinuation reflectMirror(const Scene& scene, const Ray& ray, const SurfaceHit& hit,
                                   const SurfaceInteraction& si) {
    SpecularContinuation c;
    c.ray = {scene.bounceOrigin(ray, hit, si.ng), glm::normalize(reflect(ray.d, si.ns))};
    c.tint = si.material->specular;
    return c;
}

SpecularContinuation followInterface(const Scene& scene, const Ray& ray, const SurfaceHit& hit,
                                     const SurfaceInteraction& si, RegionStack& regions, double u) {
    SpecularContinuation c;
    c.nullCrossing = si.kind == SurfaceKind::Null;
    c.tint = c.nullCrossing ? Color(1.0) : si.material->specular;
    const Vec3& d = ray.d;
    InterfaceEtas eta = interfaceEtas(scene, *si.shape, si.front, regions);
    if (c.nullCrossing) eta.etaT = eta.etaI;  // index-matched: never bends, never reflects
    const double F = fresnelDielectric(-glm::dot(d, si.ns), eta.etaI, eta.etaT);
    // The continued ray starts on the surface and skips it with tmin (leaveSurface): moving the
    // origin by rayEps would skip that much medium - 100 mean free paths at 1e6 /m - and that much
    // optical path at every crossing.
    Vec3 refr;
    if (u < F || !refract(d, si.ns, eta.etaI / eta.etaT, refr)) {
        c.ray = scene.leaveSurface(hit.p, glm::normalize(reflect(d, si.ns)), si.ng);
        return c;
    }
    if (!crossRegions(si, regions)) {
        c.regionOverflow = true;
        return c;
    }
    c.transmitted = true;
    c.ray = scene.leaveSurface(hit.p, refr, -si.ng);
    return c;
}

SpecularContinuation crossNull(const Scene& scene, const Ray& ray, const SurfaceHit& hit, const SurfaceInteraction& si,
                               RegionStack& regions) {
    SpecularContinuation c;
    c.nullCrossing = true;
    c.ray = {hit.p - scene.rayEps * si.ng, ray.d};
    if (!crossRegions(si, regions)) {
        c.regionOverflow = true;
        return c;
    }
    c.transmitted = true;
    return c;
}

Ray offsetReflection(const Scene& scene, const Ray& ray, const SurfaceHit& hit, const Vec3& n) {
    return {hit.p + scene.rayEps * n, glm::normalize(reflect(ray.d, n))};
}

Ray offsetStraightThrough(const Scene& scene, const Ray& ray, const SurfaceHit& hit, const Vec3& n) {
    return {hit.p - scene.rayEps * n, ray.d};
}

bool russianRoulette(Rng& rng, Color& weight, double reference, int events, int deepDepth) {
    double q = std::min(1.0, maxComponent(weight) / reference);
    if (events >= deepDepth) q = std::min(q, kDeepRouletteSurvival);
    if (!(q > 0.0)) return false;
    if (q < 1.0) {
        if (rng.uniform() >= q) return false;
        weight /= q;
    }
    return true;
}

}  // namespace tpb
