// The wall test of the volume kernels (beam1d, beam2d, point2d, point3d): a kernel blurs a beam or a photon
// point by r in every direction, also through a wall, so a beam or point inside a closed box would
// light the fog just outside it. An estimate is kept only when the beam or point sees the point of
// the camera segment it is blurred onto; these two helpers make that test cheap (most segments have
// no shape near them, and then nothing can block).
#pragma once
#include "scene/scene.h"

#include <cmath>
#include <vector>

namespace tpb {

// Shapes whose bounds come within r of the camera segment [0, sMax]: only they can stand between
// a point of the segment and a beam or photon point within r of it.
inline void nearShapes(const Scene& scene, const Ray& ray, double sMax, double r, std::vector<int>& out) {
    out.clear();
    Bounds3 seg;
    seg.expand(ray.o);
    seg.expand(ray.at(sMax));  // an unbounded segment gives infinite bounds: every shape is near
    const Vec3 pad(r + 8.0 * scene.rayEps);
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const Bounds3& b = scene.shapes[i].bounds;
        const bool apart =
            glm::any(glm::lessThan(b.hi + pad, seg.lo)) || glm::any(glm::greaterThan(b.lo - pad, seg.hi));
        if (!apart || !std::isfinite(sMax)) out.push_back(static_cast<int>(i));
    }
}

// Whether one of the `near` shapes' bounds meets the segment from a to b (else nothing blocks it).
inline bool mayBlock(const Scene& scene, const std::vector<int>& near, const Vec3& a, const Vec3& b) {
    const Vec3 pad(8.0 * scene.rayEps);
    const Vec3 lo = glm::min(a, b) - pad, hi = glm::max(a, b) + pad;
    for (int i : near) {
        const Bounds3& sb = scene.shapes[i].bounds;
        if (!(glm::any(glm::lessThan(sb.hi, lo)) || glm::any(glm::greaterThan(sb.lo, hi)))) return true;
    }
    return false;
}

// The wall test itself: whether the kernel point `from` (on the beam, or the photon point) sees the
// camera-segment point `to`. `near` is nearShapes() of the segment.
inline bool kernelPointVisible(const Scene& scene, const std::vector<int>& near, const Vec3& to, const Vec3& from) {
    return !mayBlock(scene, near, to, from) || scene.segmentClear(to, from);
}

// nearShapes() of one camera segment, computed on first use (most segments meet no beam near a wall).
class NearShapes {
public:
    NearShapes(const Scene& scene, const Ray& ray, double sMax, double r, std::vector<int>& storage)
        : scene_(scene), ray_(ray), sMax_(sMax), r_(r), shapes_(storage) {}
    const std::vector<int>& get() {
        if (!have_) {
            nearShapes(scene_, ray_, sMax_, r_, shapes_);
            have_ = true;
        }
        return shapes_;
    }

private:
    const Scene& scene_;
    const Ray& ray_;
    double sMax_, r_;
    std::vector<int>& shapes_;
    bool have_ = false;
};

}  // namespace tpb
