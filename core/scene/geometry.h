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
#include <type_traits>

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

    // A primitive reported by forEachPrimitiveNear: a triangle (its float-rounded vertices, as
    // intersected) or a sphere (centre v[0], radius).
    struct Primitive {
        int shape = -1;
        int prim = -1;  // triangle index within the shape (0 for spheres)
        bool sphere = false;
        Vec3 v[3];
        double radius = 0.0;
    };
    using PrimitiveVisitor = void (*)(void* user, const Primitive& prim);
    // Calls visit(user, prim) for every primitive whose bounding box meets the ball of radius r
    // around p (a superset of the primitives within r: the caller tests the exact distance).
    // Thread-safe after commit().
    void primitivesNear(const Vec3& p, double r, PrimitiveVisitor visit, void* user) const;
    template <class Fn>
    void forEachPrimitiveNear(const Vec3& p, double r, Fn&& fn) const {
        primitivesNear(
            p, r, [](void* u, const Primitive& prim) { (*static_cast<std::remove_reference_t<Fn>*>(u))(prim); }, &fn);
    }

    // The float-rounded vertices of triangle `prim` of shape `shape` (a SurfaceHit's shape and prim),
    // false for a sphere or a shape made of more than one geometry.
    bool triangle(int shape, int prim, Vec3 v[3]) const;

    Bounds3 bounds() const;
    size_t triangleCount() const;
    size_t sphereCount() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace tpb
