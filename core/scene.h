// The render scene, built from a SceneDesc (parse -> describe -> build): geometry, materials,
// regions (volumes with an index of refraction and an optional homogeneous medium), lights,
// camera, the film's time axis and the kernel radii. Also decides which stages a scene needs.
#pragma once
#include "camera.h"
#include "geometry.h"
#include "light.h"
#include "medium.h"
#include "scene_desc.h"
#include "time_splat.h"

#include <memory>
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
};

// Which parts of the algorithm a scene needs (README "Stages").
struct Stages {
    bool beams = false;            // some region scatters and photons can reach it
    bool surfacePhotons = false;   // the scene has diffuse surfaces
    bool specularChains = false;   // mirrors or dielectrics
    bool visibleEmitters = false;  // area lights
    std::vector<std::string> reasons;
};

// Region stack for nested closed shapes (entering pushes, leaving pops).
struct RegionStack {
    int ids[8] = {0};
    int size = 1;
    int top() const { return ids[size - 1]; }
    int below() const { return size >= 2 ? ids[size - 2] : 0; }
    void push(int r) { if (size < 8) ids[size++] = r; }
    void pop() { if (size > 1) --size; }
};

class Scene {
public:
    static std::unique_ptr<Scene> build(const SceneDesc& desc);

    SceneDesc desc;
    Geometry geometry;
    std::vector<Material> materials;
    std::vector<ShapeInfo> shapes;
    std::vector<Region> regions;
    std::vector<Light> lights;
    std::vector<double> lightCdf;  // light selection proportional to luminance of power
    Camera camera;
    TimeBins time;
    Bounds3 bounds;        // of geometry, lights and camera
    double beamRadius0 = 0.01;     // m, pass 1
    double surfaceRadius0 = 0.02;  // m, pass 1
    // Offset along the normal for rays leaving a surface: float triangles need ~1e-5 of the scene
    // size to never re-hit the surface they start on (measured in tests/test_geometry.cpp).
    double rayEps = 1e-5;
    Stages stages;

    int pickLight(double u, double& pdf) const;
    // Continues a path (propagation direction d) through a dielectric or null boundary: reflection
    // or refraction chosen by Fresnel with the random number u (total internal reflection included),
    // pushing/popping the region stack on transmission. ng/ns face the incoming side.
    Ray followInterface(const ShapeInfo& shape, const Material& mat, const SurfaceHit& hit, const Vec3& d, bool front,
                        const Vec3& ng, const Vec3& ns, RegionStack& regions, double u) const;
    // Region stack of a point: nested closed dielectric/null shapes around it, found by walking a
    // ray from the point to infinity (leaving a shape's surface = being inside it).
    RegionStack regionsAt(const Vec3& p) const;
    // True when a camera ray (pixel centres, through mirrors and both ways through glass) reaches a
    // diffuse surface: only then is a surface photon map needed.
    bool cameraSeesDiffuse() const;
    RegionStack cameraRegions;               // where the camera sits
    std::vector<RegionStack> lightRegions;   // where each light sits
    // Indices on both sides of a dielectric/null surface crossed `entering` (against its normal)
    // or leaving. On transmission the caller pushes shape.interiorRegion or pops the stack.
    void interfaceEtas(const ShapeInfo& shape, bool entering, const RegionStack& stack, double& etaI,
                       double& etaT) const {
        etaI = regions[stack.top()].ior;
        etaT = entering ? regions[shape.interiorRegion].ior : regions[stack.below()].ior;
    }
};

// Earliest/latest useful OPL for the automatic film range.
void autoTimeRange(const Scene& scene, double& startOpl, double& endOpl);

}  // namespace tpb
