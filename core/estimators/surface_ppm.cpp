#include "estimators/surface_ppm.h"

#include "estimators/kernel_area.h"

#include <cmath>

namespace tpb {

namespace {

// The free-space point a surface photon arrived through (Scene::bounceOrigin for its landing).
Vec3 photonAnchor(const Scene& scene, const SurfacePhoton& ph) {
    return ph.position + scene.rayEps * (ph.normal - ph.dirIn);
}

// Surfaces within this of perpendicular to the gather point's are not its surface: their photons
// are not used and their area is not counted (faces meeting at a right angle are perpendicular only
// up to float rounding when the scene is rotated).
constexpr double kPerpendicularCos = 1e-3;
// Planes whose normals are this close are parallel (1 - cos; about 0.008 degrees).
constexpr double kParallelOneMinusCos = 1e-8;

}  // namespace

void SurfacePpmEstimator::prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) {
    scene_ = &scene;
    radius_ = pass.radius;
    grid_.reset();
    photonSurface_.assign(scene.shapes.size(), 0);
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const ShapeInfo& s = scene.shapes[i];
        photonSurface_[i] = s.areaLight < 0 && s.material >= 0 &&
                            scene.materials[static_cast<size_t>(s.material)].type == MaterialType::Diffuse;
    }
    if (map.photons.empty()) return;
    grid_ = std::make_unique<PhotonGrid>();
    grid_->build(map.photons, radius_);
}

double SurfacePpmEstimator::kernelArea(const Vec3& x, const Vec3& ng, int shape, int prim) const {
    const Scene& scene = *scene_;
    const double r = radius_;
    const double disc = kPi * r * r;
    // The disc inside the triangle x lies on: all of it is surface (a tilted neighbour or a sphere
    // reaching into the ball would keep the disc too), no search needed.
    Vec3 t[3];
    if (scene.geometry.triangle(shape, prim, t)) {
        const Vec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
        const double len = glm::length(n);
        if (len > 0.0) {
            bool inside = true;
            for (int i = 0; i < 3 && inside; ++i) {
                const Vec3 e = t[(i + 1) % 3] - t[i];
                inside = glm::dot(glm::cross(e, x - t[i]), n) >= r * len * glm::length(e);
            }
            if (inside) return disc;
        }
    }
    double area = 0.0;
    bool curved = false;
    scene.geometry.forEachPrimitiveNear(x, r, [&](const Geometry::Primitive& p) {
        if (curved || p.shape < 0 || static_cast<size_t>(p.shape) >= photonSurface_.size() || !photonSurface_[p.shape])
            return;  // no photon lands there (mirror, glass, light, absorber)
        if (p.sphere) {
            // Any diffuse sphere reaching into the ball: keep the disc (exact on the sphere itself).
            if (std::abs(glm::length(x - p.v[0]) - p.radius) < r) curved = true;
            return;
        }
        Vec3 n = glm::cross(p.v[1] - p.v[0], p.v[2] - p.v[0]);
        const double len = glm::length(n);
        if (!(len > 0.0) || !std::isfinite(len)) return;
        n /= len;
        const double c = std::abs(glm::dot(n, ng));
        if (c <= kPerpendicularCos) return;
        const double d = std::abs(glm::dot(x - p.v[0], n));
        if (d >= r) return;
        if (c >= 1.0 - kParallelOneMinusCos) {
            // Coplanar: part of the gather point's surface. A parallel plane off it (the other face
            // of a thin slab, a ceiling across a narrow gap) is not in sight of it.
            if (d <= scene.rayEps) area += ballTriangleArea(x, r, p.v[0], p.v[1], p.v[2]);
            return;
        }
        // A tilted neighbour within reach: a curved or folded surface, where the disc is kept.
        if (ballTriangleArea(x, r, p.v[0], p.v[1], p.v[2]) > 0.0) curved = true;
    });
    if (curved || !(area > 0.0)) return disc;
    // A disc wholly on the surface is pi r^2 up to rounding: keep it exact (films unchanged there).
    if (std::abs(area - disc) <= 1e-12 * disc) return disc;
    return area;
}

int64_t SurfacePpmEstimator::gather(const SurfaceQuery& q, const PathState& path, PixelSink& sink) const {
    if (!grid_) return 0;
    const Scene& scene = *scene_;
    const Color fr = q.albedo * kInvPi;
    const Vec3 anchor = scene.bounceOrigin(q.ray, q.hit, q.ng);
    double invArea = 0.0;  // computed at the first photon found
    int64_t estimates = 0;
    grid_->forEachNear(q.hit.p, [&](const SurfacePhoton& ph) {
        // Same side of the same surface (at a closed box's edges the faces are perpendicular only up
        // to float rounding), and in sight over the surface (a ceiling above a closed box).
        if (glm::dot(ph.normal, q.ng) <= kPerpendicularCos) return;
        if (!scene.surfacePointsSeeEachOther(anchor, q.ng, photonAnchor(scene, ph), ph.normal)) return;
        if (invArea == 0.0) invArea = 1.0 / kernelArea(q.hit.p, q.ng, q.hit.shape, q.hit.prim);
        const Color L = path.beta * fr * ph.power * invArea;
        ++estimates;
        // The photon's time is taken as the gather point's (up to eta r early); no part earlier than
        // light from the photon's vertex before could reach the gather point (causalFloor).
        ArrivalFloor floor;
        if (ph.length > 0.0) {
            const double t = ph.opl + ph.ior * (glm::length(ph.position - ph.length * ph.dirIn - q.hit.p) - ph.length);
            floor = {path.oplCam + t, t};
        }
        sink.instant(L, path.oplCam + ph.opl, ph.opl, floor);
    });
    return estimates;
}

}  // namespace tpb
