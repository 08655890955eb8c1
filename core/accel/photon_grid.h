// Hashed uniform grid over surface photons for fixed-radius range queries (cell size = radius).
#pragma once
#include "photons/photon_tracer.h"

#include <vector>

namespace tpb {

class PhotonGrid {
public:
    void build(const std::vector<SurfacePhoton>& photons, double radius);
    // Calls fn(const SurfacePhoton&) for every photon within `radius` of p.
    template <class Fn>
    void forEachNear(const Vec3& p, Fn&& fn) const {
        if (photons_ == nullptr || photons_->empty()) return;
        const glm::i64vec3 c = cellOf(p);
        const double r2 = radius_ * radius_;
        // Distinct buckets of the 27 neighbouring cells (two cells may share a bucket).
        uint64_t buckets[27];
        int n = 0;
        for (int64_t dz = -1; dz <= 1; ++dz)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    const uint64_t h = hash(c + glm::i64vec3(dx, dy, dz));
                    bool seen = false;
                    for (int j = 0; j < n && !seen; ++j) seen = buckets[j] == h;
                    if (!seen) buckets[n++] = h;
                }
        for (int j = 0; j < n; ++j)
            for (uint32_t i = start_[buckets[j]]; i < start_[buckets[j] + 1]; ++i) {
                const SurfacePhoton& ph = (*photons_)[order_[i]];
                const Vec3 v = ph.position - p;
                if (glm::dot(v, v) <= r2) fn(ph);
            }
    }

private:
    glm::i64vec3 cellOf(const Vec3& p) const {
        return glm::i64vec3(static_cast<int64_t>(std::floor(p.x * invCell_)),
                            static_cast<int64_t>(std::floor(p.y * invCell_)),
                            static_cast<int64_t>(std::floor(p.z * invCell_)));
    }
    uint64_t hash(const glm::i64vec3& c) const {
        const uint64_t h = static_cast<uint64_t>(c.x) * 73856093ull ^ static_cast<uint64_t>(c.y) * 19349663ull ^
                           static_cast<uint64_t>(c.z) * 83492791ull;
        return h & mask_;
    }
    const std::vector<SurfacePhoton>* photons_ = nullptr;
    double radius_ = 0.0, invCell_ = 1.0;
    uint64_t mask_ = 0;
    std::vector<uint32_t> start_, order_;
};

}  // namespace tpb
