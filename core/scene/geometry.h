// Ray casting against the scene's surfaces: the surfaces' only interface to Embree (no Embree type
// appears in this header; the other Embree user is the beam accelerator, accel/beam_accel.cpp).
// Triangle meshes go to Embree triangle geometry, their hit distance refined in double precision
// against the triangle's plane; spheres are Embree user geometry intersected analytically in double
// precision. A shape too large or too far away for Embree's float rays is refused (UserError).
#pragma once
#include "base/math.h"
#include "scene/mesh.h"
#include <memory>
#include <optional>

namespace tpb {

struct SurfaceHit {
    double t = kInf;  // ray parameter (distance, since directions are unit)
    Vec3 p;           // hit point
    Vec3 ng;          // geometric normal, unit, on the side the shape defines as outside
    Vec3 ns;          // shading normal, unit, same hemisphere as ng
    int shape = -1;   // user shape id given when the geometry was added
    int prim = -1;    // triangle index within the shape (0 for spheres)
};

class Geometry {
public:
    Geometry();
    ~Geometry();
    Geometry(const Geometry&) = delete;
    Geometry& operator=(const Geometry&) = delete;

    // Adds geometry tagged with `shapeId` (reported back in SurfaceHit::shape).
    void addMesh(const TriangleMesh& mesh, int shapeId);
    void addSphere(const Vec3& center, double radius, int shapeId);
    // Must be called once after adding everything and before any query.
    void commit();

    // Closest hit with ray.tmin < t < ray.tmax. Thread-safe after commit().
    std::optional<SurfaceHit> intersect(const Ray& ray) const;
    // Any hit with ray.tmin < t < ray.tmax. Thread-safe after commit().
    bool occluded(const Ray& ray) const;

    Bounds3 bounds() const;
    size_t triangleCount() const;
    size_t sphereCount() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace tpb
