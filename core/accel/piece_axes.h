// Beam pieces as plain arrays (a structure of arrays): what a batched kernel test reads
// (estimators/overlap_batch.h) and what the accelerator can hand out with its raw candidates
// (BeamAccel::boxCandidates).
#pragma once
#include "base/math.h"

#include <cstddef>
#include <vector>

namespace tpb {

// Beam pieces as a structure of arrays: the beam's origin and unit direction, and the piece's
// range [lo, hi] of beam parameters (m).
struct PieceAxes {
    std::vector<double> ox, oy, oz, dx, dy, dz, lo, hi;
    size_t size() const { return ox.size(); }
    void clear() {
        for (std::vector<double>* v : {&ox, &oy, &oz, &dx, &dy, &dz, &lo, &hi}) v->clear();
    }
    void reserve(size_t n) {
        for (std::vector<double>* v : {&ox, &oy, &oz, &dx, &dy, &dz, &lo, &hi}) v->reserve(n);
    }
    void push(const Vec3& origin, const Vec3& dir, double sbLo, double sbHi) {
        ox.push_back(origin.x);
        oy.push_back(origin.y);
        oz.push_back(origin.z);
        dx.push_back(dir.x);
        dy.push_back(dir.y);
        dz.push_back(dir.z);
        lo.push_back(sbLo);
        hi.push_back(sbHi);
    }
};

}  // namespace tpb
