#include "accel/photon_grid.h"

namespace tpb {

void PhotonGrid::build(const std::vector<SurfacePhoton>& photons, double radius) {
    photons_ = &photons;
    radius_ = radius;
    invCell_ = 1.0 / radius;
    uint64_t size = 1;
    while (size < 2 * photons.size() + 1) size <<= 1;
    mask_ = size - 1;
    // Counting sort of photon indices by cell hash.
    start_.assign(size + 1, 0);
    std::vector<uint32_t> cell(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
        cell[i] = static_cast<uint32_t>(hash(cellOf(photons[i].position)));
        ++start_[cell[i] + 1];
    }
    for (uint64_t i = 0; i < size; ++i) start_[i + 1] += start_[i];
    order_.resize(photons.size());
    std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
    for (size_t i = 0; i < photons.size(); ++i) order_[fill[cell[i]]++] = static_cast<uint32_t>(i);
}

}  // namespace tpb
