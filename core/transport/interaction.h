// Surface interactions along a path: the one place the tracers (photon tracer, camera pass, path
// tracer, preview, the stage analysis in scene.cpp) read what a surface hit is and continue a path
// through it specularly.
//  - interact(): the facing geometry (front, ng and ns turned towards the incoming side) and the
//    kind of surface: Emitter (an area light's quad: it absorbs), Absorber (no material), Diffuse,
//    Mirror, Dielectric, Null (an index-matched boundary of a medium container).
//  - the specular continuations, as value structs (SpecularContinuation): the mirror bounce, the
//    Fresnel choice at a dielectric/null interface with the caller's random number (total internal
//    reflection included) pushing/popping the region stack, and the straight null crossing of the
//    path tracer and its shadow rays. A full region stack is reported (regionOverflow), never
//    thrown: the caller ends the path and counts it (RegionStack).
//  - the null-crossing depth rule of the beam core and Russian roulette.
// What each tracer does at a diffuse surface (store photons, gather, next-event estimation,
// shading) stays in that tracer.
//
// Two null crossings exist, kept apart so that every film stays bit-identical: followInterface
// (photon tracer, camera pass) draws the caller's Fresnel number (F = 0: always transmitted) and
// starts the continued ray on the surface (Scene::leaveSurface); crossNull (path tracer, shadow
// rays) draws nothing and starts rayEps behind the surface. Making them one changes the films.
#pragma once
#include "base/rng.h"
#include "scene/scene.h"

namespace tpb {

enum class SurfaceKind { Emitter, Absorber, Diffuse, Mirror, Dielectric, Null };

struct SurfaceInteraction {
    SurfaceKind kind = SurfaceKind::Absorber;
    const ShapeInfo* shape = nullptr;
    const Material* material = nullptr;  // null for Emitter and Absorber
    bool front = false;                  // the ray arrives against hit.ng (from the shape's outside)
    Vec3 ng{0.0};                        // geometric normal facing the incoming ray
    Vec3 ns{0.0};                        // shading normal facing the incoming ray (ng if it faces away)
};

// What the surface hit `hit` of `ray` is, seen from the side the ray comes from.
SurfaceInteraction interact(const Scene& scene, const Ray& ray, const SurfaceHit& hit);

// A path continued through a specular surface.
struct SpecularContinuation {
    Ray ray;                      // the continued ray (undefined when regionOverflow)
    Color tint{1.0};              // multiplies the path weight: mirror/dielectric specular, 1 across null
    bool regionOverflow = false;  // the crossing needed a push onto a full region stack: end the path
    bool nullCrossing = false;    // the surface was a null boundary
    bool transmitted = false;     // crossed the surface (the region stack was pushed or popped)
};

// Indices of refraction on both sides of a dielectric/null surface crossed `entering` (against
// its normal) or leaving. On transmission the region shape.interiorRegion is pushed, or the stack
// popped.
struct InterfaceEtas {
    double etaI = 1.0;  // incident side: the region on top of the stack
    double etaT = 1.0;  // transmitted side
};
InterfaceEtas interfaceEtas(const Scene& scene, const ShapeInfo& shape, bool entering, const RegionStack& stack);

// Perfect mirror (si.kind == Mirror): reflection about ns from Scene::bounceOrigin.
SpecularContinuation reflectMirror(const Scene& scene, const Ray& ray, const SurfaceHit& hit,
                                   const SurfaceInteraction& si);

// A dielectric or null boundary (si.kind Dielectric or Null): reflection or refraction chosen by
// Fresnel with the random number u (total internal reflection included), pushing/popping the
// region stack on transmission. A null boundary is index-matched: F = 0, no bending.
SpecularContinuation followInterface(const Scene& scene, const Ray& ray, const SurfaceHit& hit,
                                     const SurfaceInteraction& si, RegionStack& regions, double u);

// A null boundary crossed straight on without a random number (path tracer, shadow rays): the ray
// goes on rayEps behind the surface, the region stack pushed (entering) or popped (leaving).
SpecularContinuation crossNull(const Scene& scene, const Ray& ray, const SurfaceHit& hit, const SurfaceInteraction& si,
                               RegionStack& regions);

// Rays for previews and the stage analysis (no Fresnel, no region stack): the reflection of `ray`
// about the unit normal n (facing the ray) from rayEps in front of the surface, and `ray` going on
// straight from rayEps behind it.
Ray offsetReflection(const Scene& scene, const Ray& ray, const SurfaceHit& hit, const Vec3& n);
Ray offsetStraightThrough(const Scene& scene, const Ray& ray, const SurfaceHit& hit, const Vec3& n);

// The beam core's null-crossing depth rule (photon tracer, camera pass): index-matched boundaries
// are not events and do not use up depth, for the first kFreeCrossings of a path; after that they
// count, so a path caught between null surfaces still ends.
struct NullCrossingBudget {
    static constexpr int kFreeCrossings = 64;
    int crossings = 0;
    // Counts one null crossing; true while it is free (the caller gives the depth back).
    bool free() { return ++crossings <= kFreeCrossings; }
};

// Russian roulette on a path weight after `events` scattering/reflection events: it survives with
// q = min(1, max_c weight / reference) and is divided by q. reference: the photon's emitted power
// (photon tracer), 1 (camera paths). From `deepDepth` events on, q is also at most
// kDeepRouletteSurvival, so a path whose weight never drops (albedo 1 everywhere: a lossless
// medium, white walls, perfect mirrors) still ends: on average 1 / (1 - 0.95) = 20 events past
// deepDepth, whatever max_depth says (1e6 for a Mitsuba user's "unbounded"). Unbiased: a survivor
// is divided by q. Draws a random number only when q < 1, so a path with fewer than deepDepth
// events draws exactly what it did without the deep rule: no render with max_depth < deepDepth
// changes (the default max_depth is 16; every shipped scene renders with at most 16). False: the
// path dies.
inline constexpr int kDeepRouletteDepth = 64;
inline constexpr double kDeepRouletteSurvival = 0.95;
[[nodiscard]] bool russianRoulette(Rng& rng, Color& weight, double reference, int events,
                                   int deepDepth = kDeepRouletteDepth);

}  // namespace tpb
