// The render scene, built from a SceneDesc (parse -> describe -> build): geometry, materials,
// regions (volumes with an index of refraction and an optional homogeneous medium), lights,
// camera. Also decides which stages a scene needs. Built once, then used as `const Scene&`: it keeps
// no copy of its description (the render settings, the film's time axis and where a key was written
// live beside it: render_settings.h, time_range.h, prepare.h).
#pragma once
#include "scene/camera.h"
#include "scene/geometry.h"
#include "scene/light.h"
#include "scene/medium.h"
#include "scene/scene_desc.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tpb {

struct Material {
    MaterialType type = MaterialType::Diffuse;
    Color albedo{0.8};
    Color specular{1.0};
    double ior = 1.5;
};

// A region of space: the outside (index 0, the global medium or vacuum) or the interior of a
// closed dielectric / null-material shape.
struct Region {
    double ior = 1.0;
    bool hasMedium = false;  // sigma_t > 0
    Medium medium;
};

struct ShapeInfo {
    std::string name;
    int material = -1;
    int interiorRegion = 0;  // region entered when crossing the surface against its normal
    int areaLight = -1;      // visible surface of this light (front side emits)
    Bounds3 bounds;          // of its surface (float-rounded triangles and spheres included)
};

// Which parts of the algorithm a scene needs (docs/theory/how-it-works.md "A pass").
struct Stages {
    bool beams = false;            // some region scatters and photons can reach it
    bool surfacePhotons = false;   // the scene has diffuse surfaces
    bool specularChains = false;   // mirrors or dielectrics
    bool visibleEmitters = false;  // area lights
    std::vector<std::string> reasons;
};

// Region stack for nested closed shapes (entering pushes, leaving pops). Its capacity bounds the
// nesting: Scene::build refuses a scene whose dielectric/null shapes nest deeper (naming them). At
// run time a push can still find the stack full, through open or overlapping dielectric/null
// shapes (a glass quad crossed again and again the same way): push() then returns false, and the
// caller ends that path and counts it (regionOverflows in PhotonMap, CameraPassStats,
// PathTracerStats) instead of carrying on in the wrong region.
struct RegionStack {
    static constexpr int kCapacity = 8;  // the outside and up to 7 nested shapes
    int ids[kCapacity] = {0};
    int size = 1;
    int top() const { return ids[size - 1]; }
    int below() const { return size >= 2 ? ids[size - 2] : 0; }
    [[nodiscard]] bool push(int r) {
        if (size >= kCapacity) return false;
        ids[size++] = r;
        return true;
    }
    void pop() {
        if (size > 1) --size;
    }
};

// Where a light's photons start (Scene::emissionRegions): the region stack at an anchor point of
// the light, and whether that stack holds for every point the light emits from.
struct LightPlacement {
    Vec3 anchor{0.0};     // point light / spot / laser: its position; area light: a point rayEps in front
    RegionStack regions;  // region stack at the anchor
    bool uniform = true;  // no dielectric/null surface comes near the light's emitting points
};

class Scene;
// Decides which stages a built scene needs: transport/stages.h's analyzeStages (it follows camera
// rays through mirrors and glass, which the transport floor knows).
using StageAnalysis = Stages (*)(const Scene&);

class Scene {
public:
    static std::unique_ptr<const Scene> build(const SceneDesc& desc, StageAnalysis analyzeStages);

    Geometry geometry;
    std::vector<Material> materials;
    std::vector<ShapeInfo> shapes;
    std::vector<Region> regions;
    std::vector<Light> lights;
    std::vector<double> lightCdf;  // light selection proportional to luminance of power
    Camera camera;
    Bounds3 bounds;  // of geometry, lights and camera
    // Offset along the normal for rays leaving a surface: float triangles need ~1e-5 of the scene
    // size to never re-hit the surface they start on (measured in tests/scene/test_geometry.cpp).
    // The size is the larger of the geometry's diagonal and its farthest coordinate (scene.cpp).
    double rayEps = 1e-5;
    Stages stages;

    int pickLight(double u, double& pdf) const;
    // A ray leaving the surface point p in direction w, on the side of the unit normal n (dot(w, n)
    // > 0): it starts on the surface and skips it with tmin (rayEps off the surface), so free flights,
    // transmittance and OPL count from the surface itself; grazing directions start rayEps off it.
    Ray leaveSurface(const Vec3& p, const Vec3& w, const Vec3& n) const;
    // Origin for rays that continue from a surface hit of `ray` (diffuse and mirror bounces, shadow
    // rays): rayEps off the surface along ng (facing the incoming ray) and up to rayEps back along
    // the ray, into the free space it came through. ng alone is not enough near an edge: a hit
    // within rounding of it lies on the neighbouring face's plane too, and a step along ng (parallel
    // to that face at a right-angled edge) can leave the origin on or beyond it, so the next ray
    // starts outside a closed box (tests/scene/test_light_regions.cpp).
    Vec3 bounceOrigin(const Ray& ray, const SurfaceHit& hit, const Vec3& ng) const;
    // True when no surface lies on the segment from a to b.
    bool segmentClear(const Vec3& a, const Vec3& b) const;
    // Whether two points on surfaces see each other over them, so that a density estimate at one
    // may use a photon that landed at the other. a and b are their anchors (bounceOrigin: in the
    // free space in front of each), na and nb the unit normals facing that space, dot(na, nb) > 0.
    // The path between the anchors goes over the apex where the tangent planes meet above the
    // chord: on a convex surface the straight chord would dip under it (a sphere would hide its
    // own photons), while any path from inside a closed shape to outside crosses its surface.
    bool surfacePointsSeeEachOther(const Vec3& a, const Vec3& na, const Vec3& b, const Vec3& nb) const;
    // Region stack of a point: nested closed dielectric/null shapes around it, found by walking a
    // ray from the point to infinity (leaving a shape's surface = being inside it). A point nested
    // deeper than the stack holds is refused by build(); here it keeps the outermost shapes.
    RegionStack regionsAt(const Vec3& p) const;
    // Shapes (dielectric/null) around p, outermost first (the walk of regionsAt).
    std::vector<int> shapesAround(const Vec3& p) const;
    // The region stack at `to`, from the one at `from`: the dielectric/null surfaces crossed on the
    // segment between them push (entered against their normal) or pop. False if the stack overflows.
    bool walkRegions(RegionStack& stack, const Vec3& from, const Vec3& to) const;
    // Region stack where a photon of light `li` starts: at `start`, a point rayEps in front of the
    // emitting point (LightPlacement; a walk from the anchor when the light is not `uniform`).
    // Empty if the stack overflows.
    std::optional<RegionStack> emissionRegions(int li, const Vec3& start) const;
    // True when a camera ray (pixel centres, through mirrors and both ways through glass) reaches a
    // diffuse surface: only then is a surface photon map needed. (The path continuation itself,
    // interface crossings included, lives in core/transport/interaction.h.)
    RegionStack cameraRegions;                   // where the camera sits
    std::vector<LightPlacement> lightPlacement;  // where each light's photons start
};

// A scan's laser pulse instant (OPL, m) for the laser point at `target` on the relay wall: the
// light's emitOpl, minus the laser -> wall leg (eta |target - laser|) when time starts at the wall
// (the NLOS toolkit's t_accounts_first_and_last_bounces false: both legs left out).
double scanEmitOpl(const Scene& scene, const Vec3& target);

}  // namespace tpb
