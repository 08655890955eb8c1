// Ray casting with Embree 3 (with accel/beam_accel.cpp, the only file that calls Embree's
// geometry API).
//
// - The device is the process-wide one of scene/embree_device.h; Embree errors are rethrown by
//   checkEmbree() as EmbreeError naming the operation.
// - Triangle meshes are Embree triangle geometry (float vertices). The positions kept here for
//   normals and the double-precision refinement of t are the float-rounded ones, so that they
//   describe exactly the triangles Embree intersects.
// - Spheres are Embree user geometry, intersected in double precision against the original
//   double ray, which the callbacks find in an extended intersection context.
// - geomID -> shape: geometries are attached with rtcAttachGeometryByID, the ID being the index
//   into Impl::geoms.
#include "scene/geometry.h"
#include "base/error.h"
#include "scene/embree_device.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace tpb {
namespace {

// ---- float conversions ---------------------------------------------------------------------------

float roundDown(double x) {
    float f = static_cast<float>(x);
    if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}
float roundUp(double x) {
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}
Vec3 toFloatPrecision(const Vec3& p) {
    return Vec3(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z));
}
double maxAbs(const Vec3& v) { return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}); }

// ---- shapes -------------------------------------------------------------------------------------

struct MeshData {
    std::vector<Vec3> positions;  // float-rounded, as given to Embree
    std::vector<Vec3> normals;    // unit, may be empty
    std::vector<glm::uvec3> triangles;
};

struct SphereData {
    Vec3 center;
    double radius;
};

enum class Kind { Mesh, Sphere };

struct GeomInfo {
    Kind kind;
    int shapeId;
    size_t index;  // into Impl::meshes or Impl::spheres
};

// Ray parameters t0 <= t1 where the line o + t d meets the sphere; false if it misses.
// Numerically stable: the discriminant is computed from the distance between the centre and the
// line (no cancellation for distant origins), and the two roots from q and c/q (no cancellation
// between -b and sqrt(disc)).
bool sphereRoots(const Vec3& o, const Vec3& d, const Vec3& c, double r, double& t0, double& t1) {
    const Vec3 f = o - c;
    const double a = glm::dot(d, d);
    if (!(a > 0.0)) return false;
    const double b = glm::dot(f, d);  // half the usual b
    const Vec3 l = f - (b / a) * d;   // centre -> closest point of the line
    const double dist = glm::length(l);
    const double disc = (r - dist) * (r + dist);  // r^2 - |l|^2
    if (!(disc >= 0.0)) return false;
    const double q = -(b + std::copysign(std::sqrt(a * disc), b));
    if (q == 0.0) {  // tangent at the origin itself
        t0 = t1 = -b / a;
        return true;
    }
    const double lenF = glm::length(f);
    const double cc = (lenF - r) * (lenF + r);  // |f|^2 - r^2
    t0 = cc / q;
    t1 = q / a;
    if (t0 > t1) std::swap(t0, t1);
    return true;
}

// Nearest root in the open interval (tmin, tmax).
bool sphereHit(const Vec3& o, const Vec3& d, const SphereData& s, double tmin, double tmax, double& t) {
    double t0, t1;
    if (!sphereRoots(o, d, s.center, s.radius, t0, t1)) return false;
    if (t0 > tmin && t0 < tmax) {
        t = t0;
        return true;
    }
    if (t1 > tmin && t1 < tmax) {
        t = t1;
        return true;
    }
    return false;
}

// The intersection context handed to Embree, extended with the double-precision ray so that the
// sphere callbacks can use it. Embree passes the RTCIntersectContext pointer back to callbacks.
struct QueryContext {
    RTCIntersectContext ctx;  // must stay the first member
    Vec3 o, d;
    double tmin = 0.0, tmax = kInf;
    // Closest hit so far in double precision. Embree only knows the float tfar; as long as tfar
    // still holds the value we wrote last (lastTfar), no triangle came closer and `closest` is
    // the exact bound. A sphere hit in (float(tmax), tmax) is thus not lost to float rounding.
    double closest = kInf;
    float lastTfar = 0.0f;
    double sphereT = kInf;  // t of the last accepted sphere hit (the closest so far)

    double bound(float tfar) const { return tfar == lastTfar ? closest : double(tfar); }
};
static_assert(std::is_standard_layout_v<QueryContext>, "QueryContext must be standard-layout");

QueryContext* queryContext(RTCIntersectContext* ctx) { return reinterpret_cast<QueryContext*>(ctx); }

void sphereBounds(const RTCBoundsFunctionArguments* args) {
    const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
    // Float bounds rounded outwards plus a small margin, so that the float ray Embree traverses
    // with cannot miss the box when the double ray grazes the sphere.
    const double pad = s->radius + 1e-6 * (s->radius + maxAbs(s->center));
    RTCBounds* b = args->bounds_o;
    b->lower_x = roundDown(s->center.x - pad);
    b->lower_y = roundDown(s->center.y - pad);
    b->lower_z = roundDown(s->center.z - pad);
    b->upper_x = roundUp(s->center.x + pad);
    b->upper_y = roundUp(s->center.y + pad);
    b->upper_z = roundUp(s->center.z + pad);
}

void sphereIntersect(const RTCIntersectFunctionNArguments* args) {
    if (args->N != 1 || !args->valid[0]) return;  // only rtcIntersect1 is used
    QueryContext* qc = queryContext(args->context);
    const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, 1);
    RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, 1);
    float& tfar = RTCRayN_tfar(ray, 1, 0);
    double t;
    if (!sphereHit(qc->o, qc->d, *s, qc->tmin, qc->bound(tfar), t)) return;
    tfar = std::min(static_cast<float>(t), tfar);
    qc->lastTfar = tfar;
    qc->closest = t;
    qc->sphereT = t;
    const Vec3 n = qc->o + t * qc->d - s->center;
    RTCHitN_Ng_x(hit, 1, 0) = static_cast<float>(n.x);
    RTCHitN_Ng_y(hit, 1, 0) = static_cast<float>(n.y);
    RTCHitN_Ng_z(hit, 1, 0) = static_cast<float>(n.z);
    RTCHitN_u(hit, 1, 0) = 0.0f;
    RTCHitN_v(hit, 1, 0) = 0.0f;
    RTCHitN_primID(hit, 1, 0) = args->primID;
    RTCHitN_geomID(hit, 1, 0) = args->geomID;
    RTCHitN_instID(hit, 1, 0, 0) = args->context->instID[0];
}

void sphereOccluded(const RTCOccludedFunctionNArguments* args) {
    if (args->N != 1 || !args->valid[0]) return;  // only rtcOccluded1 is used
    QueryContext* qc = queryContext(args->context);
    const auto* s = static_cast<const SphereData*>(args->geometryUserPtr);
    float& tfar = RTCRayN_tfar(args->ray, 1, 0);
    double t;
    if (sphereHit(qc->o, qc->d, *s, qc->tmin, qc->tmax, t)) tfar = -std::numeric_limits<float>::infinity();
}

// Embree rejects origins/directions beyond ~1.8e18 (FLT_LARGE); stay well inside.
constexpr double kMaxCoordinate = 1e18;

// Fills the Embree ray and the double ray of the context. False if the ray cannot hit anything
// (empty interval) or is unusable (non-finite, zero direction, coordinates Embree rejects).
bool setupRay(const Ray& ray, QueryContext& qc, RTCRay& r) {
    const double tmin = std::max(ray.tmin, 0.0);  // Embree segments start at t >= 0
    const double tmax = ray.tmax;
    if (!(tmin < tmax)) return false;  // also catches NaN
    if (!(maxAbs(ray.o) < kMaxCoordinate) || !(maxAbs(ray.d) < kMaxCoordinate)) return false;
    if (!(glm::dot(ray.d, ray.d) > 0.0)) return false;
    rtcInitIntersectContext(&qc.ctx);
    qc.o = ray.o;
    qc.d = ray.d;
    qc.tmin = tmin;
    qc.tmax = tmax;
    qc.sphereT = kInf;
    r.org_x = static_cast<float>(ray.o.x);
    r.org_y = static_cast<float>(ray.o.y);
    r.org_z = static_cast<float>(ray.o.z);
    r.dir_x = static_cast<float>(ray.d.x);
    r.dir_y = static_cast<float>(ray.d.y);
    r.dir_z = static_cast<float>(ray.d.z);
    if (r.dir_x == 0.0f && r.dir_y == 0.0f && r.dir_z == 0.0f) return false;  // underflow
    // Float interval inside the double one: tnear >= tmin, tfar <= tmax.
    r.tnear = roundUp(tmin);
    r.tfar = std::isinf(tmax) ? std::numeric_limits<float>::infinity() : roundDown(tmax);
    if (r.tfar < r.tnear) r.tfar = r.tnear;  // tiny interval: let double-precision spheres decide
    qc.closest = tmax;
    qc.lastTfar = r.tfar;
    r.time = 0.0f;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    return true;
}

}  // namespace

struct Geometry::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<GeomInfo> geoms;     // indexed by Embree geomID
    std::vector<int> geomOfShape;    // shape id -> geomID; -1: none, -2: more than one
    std::deque<MeshData> meshes;     // deque: stable addresses
    std::deque<SphereData> spheres;  // user data pointers of the sphere geometries
    Bounds3 bounds;
    size_t triangles = 0;
    bool committed = false;

    unsigned attach(RTCGeometry geom, const GeomInfo& info, const char* what) {
        const unsigned id = static_cast<unsigned>(geoms.size());
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene, geom, id);
        rtcReleaseGeometry(geom);  // the scene holds it now
        checkEmbree(what);
        geoms.push_back(info);
        if (info.shapeId >= 0) {
            if (geomOfShape.size() <= static_cast<size_t>(info.shapeId)) geomOfShape.resize(info.shapeId + 1, -1);
            int& g = geomOfShape[info.shapeId];
            g = g == -1 ? static_cast<int>(id) : -2;
        }
        return id;
    }
};

Geometry::Geometry() : impl_(std::make_unique<Impl>()) {
    impl_->device = embreeDevice();
    impl_->scene = rtcNewScene(impl_->device);
    checkEmbree("creating the scene");
    // Robust mode: conservative traversal and no accuracy-reducing shortcuts, so that rays through
    // shared edges of neighbouring triangles are not lost (costs ~10% on the armadillo). High
    // build quality: the scene is static and built once.
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    try {
        checkEmbree("configuring the scene");
    } catch (...) {
        rtcReleaseScene(impl_->scene);
        throw;
    }
}

Geometry::~Geometry() {
    if (impl_ && impl_->scene) rtcReleaseScene(impl_->scene);
}

void Geometry::addMesh(const TriangleMesh& mesh, int shapeId) {
    TPB_CHECK(!impl_->committed);
    if (mesh.triangles.empty()) return;
    const size_t nv = mesh.positions.size();
    TPB_CHECK(mesh.normals.empty() || mesh.normals.size() == nv);
    for (const glm::uvec3& t : mesh.triangles) TPB_CHECK(t.x < nv && t.y < nv && t.z < nv);

    MeshData data;
    data.positions.reserve(nv);
    for (const Vec3& p : mesh.positions) {
        const Vec3 q = toFloatPrecision(p);
        if (!(maxAbs(q) < kMaxCoordinate))
            throw UserError("mesh (shape " + std::to_string(shapeId) +
                            ") has non-finite or too large vertex coordinates after its transform");
        data.positions.push_back(q);
    }
    if (!mesh.normals.empty()) {
        data.normals.reserve(nv);
        for (const Vec3& n : mesh.normals) {
            const double len = glm::length(n);
            data.normals.push_back(len > 0.0 && std::isfinite(len) ? n / len : Vec3(0.0));
        }
    }
    data.triangles = mesh.triangles;

    RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    checkEmbree("creating a triangle mesh");
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), data.triangles.size()));
    if (!vb || !ib) {
        rtcReleaseGeometry(geom);
        checkEmbree("allocating triangle mesh buffers");
        throw EmbreeError(RTC_ERROR_OUT_OF_MEMORY,
                          "Embree could not allocate triangle mesh buffers; reduce the "
                          "scene's triangles or free memory");
    }
    for (size_t i = 0; i < nv; ++i) {
        vb[3 * i + 0] = static_cast<float>(data.positions[i].x);
        vb[3 * i + 1] = static_cast<float>(data.positions[i].y);
        vb[3 * i + 2] = static_cast<float>(data.positions[i].z);
    }
    for (size_t i = 0; i < data.triangles.size(); ++i) {
        ib[3 * i + 0] = data.triangles[i].x;
        ib[3 * i + 1] = data.triangles[i].y;
        ib[3 * i + 2] = data.triangles[i].z;
        for (int k = 0; k < 3; ++k) impl_->bounds.expand(data.positions[data.triangles[i][k]]);
    }

    impl_->meshes.push_back(std::move(data));
    try {
        impl_->attach(geom, GeomInfo{Kind::Mesh, shapeId, impl_->meshes.size() - 1}, "adding a triangle mesh");
    } catch (...) {
        impl_->meshes.pop_back();
        throw;
    }
    impl_->triangles += mesh.triangles.size();
}

void Geometry::addSphere(const Vec3& center, double radius, int shapeId) {
    TPB_CHECK(!impl_->committed);
    TPB_CHECK(radius > 0.0 && std::isfinite(radius));
    TPB_CHECK(std::isfinite(center.x) && std::isfinite(center.y) && std::isfinite(center.z));
    if (!(maxAbs(center) + radius < kMaxCoordinate))
        throw UserError("sphere (shape " + std::to_string(shapeId) + ") is too large or too far away");

    impl_->spheres.push_back(SphereData{center, radius});
    SphereData* s = &impl_->spheres.back();
    RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_USER);
    checkEmbree("creating a sphere");
    rtcSetGeometryUserPrimitiveCount(geom, 1);
    rtcSetGeometryUserData(geom, s);
    rtcSetGeometryBoundsFunction(geom, sphereBounds, nullptr);
    rtcSetGeometryIntersectFunction(geom, sphereIntersect);
    rtcSetGeometryOccludedFunction(geom, sphereOccluded);
    try {
        impl_->attach(geom, GeomInfo{Kind::Sphere, shapeId, impl_->spheres.size() - 1}, "adding a sphere");
    } catch (...) {
        impl_->spheres.pop_back();
        throw;
    }
    impl_->bounds.expand(center - Vec3(radius));
    impl_->bounds.expand(center + Vec3(radius));
}

void Geometry::commit() {
    TPB_CHECK(!impl_->committed);
    rtcCommitScene(impl_->scene);
    checkEmbree("building the acceleration structure");
    impl_->committed = true;
}

std::optional<SurfaceHit> Geometry::intersect(const Ray& ray) const {
    TPB_CHECK(impl_->committed);
    QueryContext qc;
    RTCRayHit rh;
    if (!setupRay(ray, qc, rh.ray)) return std::nullopt;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &qc.ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.geomID >= impl_->geoms.size()) return std::nullopt;

    const GeomInfo& info = impl_->geoms[rh.hit.geomID];
    SurfaceHit h;
    h.shape = info.shapeId;
    if (info.kind == Kind::Sphere) {
        const SphereData& s = impl_->spheres[info.index];
        if (!std::isfinite(qc.sphereT)) return std::nullopt;  // cannot happen: callback sets it
        h.t = qc.sphereT;
        h.prim = 0;
        h.p = ray.o + h.t * ray.d;
        const Vec3 n = h.p - s.center;
        const double len = glm::length(n);
        h.ng = len > 0.0 ? n / len : -glm::normalize(ray.d);
        h.ns = h.ng;
        return h;
    }

    const MeshData& m = impl_->meshes[info.index];
    const glm::uvec3 tri = m.triangles[rh.hit.primID];
    h.prim = static_cast<int>(rh.hit.primID);
    const Vec3& p0 = m.positions[tri.x];
    const Vec3& p1 = m.positions[tri.y];
    const Vec3& p2 = m.positions[tri.z];
    Vec3 n = glm::cross(p1 - p0, p2 - p0);
    double len = glm::length(n);
    if (!(len > 0.0) || !std::isfinite(len)) {
        // Needle triangle that Embree still hit: fall back to its normal (same orientation).
        n = Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
        len = glm::length(n);
        if (!(len > 0.0) || !std::isfinite(len)) {
            n = -ray.d;
            len = glm::length(n);
        }
    }
    h.ng = n / len;

    // Embree's t comes from float arithmetic on a float ray. Refine it as the intersection of the
    // double ray with the triangle's plane, unless that is ill-conditioned (grazing ray) or
    // leaves the interval (tmin, tmax).
    const double tE = rh.ray.tfar;
    const double tRef = glm::dot(p0 - ray.o, h.ng) / glm::dot(ray.d, h.ng);
    const double tol = 1e-4 * (tE + maxAbs(ray.o) + maxAbs(p0));
    h.t = (std::isfinite(tRef) && tRef > qc.tmin && tRef < qc.tmax && std::abs(tRef - tE) <= tol) ? tRef : tE;
    h.p = ray.o + h.t * ray.d;

    h.ns = h.ng;
    if (!m.normals.empty()) {
        const double u = rh.hit.u, v = rh.hit.v;
        const Vec3 s = (1.0 - u - v) * m.normals[tri.x] + u * m.normals[tri.y] + v * m.normals[tri.z];
        const double sl = glm::length(s);
        if (sl > 0.0 && std::isfinite(sl)) {
            h.ns = s / sl;
            if (glm::dot(h.ns, h.ng) < 0.0) h.ns = -h.ns;
        }
    }
    return h;
}

bool Geometry::occluded(const Ray& ray) const {
    TPB_CHECK(impl_->committed);
    QueryContext qc;
    RTCRay r;
    if (!setupRay(ray, qc, r)) return false;
    rtcOccluded1(impl_->scene, &qc.ctx, &r);
    return r.tfar == -std::numeric_limits<float>::infinity();
}

namespace {

struct PointQueryUser {
    const std::vector<GeomInfo>* geoms;
    const std::deque<MeshData>* meshes;
    const std::deque<SphereData>* spheres;
    Geometry::PrimitiveVisitor visit;
    void* user;
};

bool pointQueryPrimitive(RTCPointQueryFunctionArguments* args) {
    const auto* u = static_cast<const PointQueryUser*>(args->userPtr);
    if (args->geomID >= u->geoms->size()) return false;
    const GeomInfo& info = (*u->geoms)[args->geomID];
    Geometry::Primitive prim;
    prim.shape = info.shapeId;
    prim.prim = static_cast<int>(args->primID);
    if (info.kind == Kind::Sphere) {
        const SphereData& s = (*u->spheres)[info.index];
        prim.sphere = true;
        prim.v[0] = s.center;
        prim.radius = s.radius;
    } else {
        const MeshData& m = (*u->meshes)[info.index];
        if (args->primID >= m.triangles.size()) return false;
        const glm::uvec3 tri = m.triangles[args->primID];
        prim.v[0] = m.positions[tri.x];
        prim.v[1] = m.positions[tri.y];
        prim.v[2] = m.positions[tri.z];
    }
    u->visit(u->user, prim);
    return false;  // the query's radius is unchanged
}

}  // namespace

void Geometry::primitivesNear(const Vec3& p, double r, PrimitiveVisitor visit, void* user) const {
    TPB_CHECK(impl_->committed);
    if (!(maxAbs(p) < kMaxCoordinate) || !(r >= 0.0) || !std::isfinite(r)) return;
    RTCPointQuery q;
    q.x = static_cast<float>(p.x);
    q.y = static_cast<float>(p.y);
    q.z = static_cast<float>(p.z);
    q.time = 0.0f;
    // Float rounding of the centre and the radius: pad so that the float ball holds the double one.
    q.radius = roundUp(r + 1e-6 * (r + maxAbs(p)));
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    PointQueryUser u{&impl_->geoms, &impl_->meshes, &impl_->spheres, visit, user};
    rtcPointQuery(impl_->scene, &q, &ctx, pointQueryPrimitive, &u);
}

bool Geometry::triangle(int shape, int prim, Vec3 v[3]) const {
    if (shape < 0 || static_cast<size_t>(shape) >= impl_->geomOfShape.size()) return false;
    const int g = impl_->geomOfShape[shape];
    if (g < 0) return false;
    const GeomInfo& info = impl_->geoms[g];
    if (info.kind != Kind::Mesh) return false;
    const MeshData& m = impl_->meshes[info.index];
    if (prim < 0 || static_cast<size_t>(prim) >= m.triangles.size()) return false;
    const glm::uvec3 tri = m.triangles[prim];
    v[0] = m.positions[tri.x];
    v[1] = m.positions[tri.y];
    v[2] = m.positions[tri.z];
    return true;
}

Bounds3 Geometry::bounds() const { return impl_->bounds; }
size_t Geometry::triangleCount() const { return impl_->triangles; }
size_t Geometry::sphereCount() const { return impl_->spheres.size(); }

}  // namespace tpb
