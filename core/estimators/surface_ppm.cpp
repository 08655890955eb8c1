#include "estimators/surface_ppm.h"

namespace tpb {

namespace {

// The free-space point a surface photon arrived through (Scene::bounceOrigin for its landing).
Vec3 photonAnchor(const Scene& scene, const SurfacePhoton& ph) {
    return ph.position + scene.rayEps * (ph.normal - ph.dirIn);
}

}  // namespace

void SurfacePpmEstimator::prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) {
    scene_ = &scene;
    radius_ = pass.radius;
    grid_.reset();
    if (map.photons.empty()) return;
    grid_ = std::make_unique<PhotonGrid>();
    grid_->build(map.photons, radius_);
}

int64_t SurfacePpmEstimator::gather(const SurfaceQuery& q, const PathState& path, PixelSink& sink) const {
    if (!grid_) return 0;
    const Scene& scene = *scene_;
    const Color fr = q.albedo * kInvPi;
    const double invArea = 1.0 / (kPi * radius_ * radius_);
    const Vec3 anchor = scene.bounceOrigin(q.ray, q.hit, q.ng);
    int64_t estimates = 0;
    grid_->forEachNear(q.hit.p, [&](const SurfacePhoton& ph) {
        // Same side of the same surface (at a closed box's edges the faces are perpendicular only up
        // to float rounding), and in sight over the surface (a ceiling above a closed box).
        if (glm::dot(ph.normal, q.ng) <= 0.0) return;
        if (!scene.surfacePointsSeeEachOther(anchor, q.ng, photonAnchor(scene, ph), ph.normal)) return;
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
