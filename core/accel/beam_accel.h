// Finding every photon beam whose kernel cylinder overlaps a camera segment.
// Long beams are split into pieces (each a sub-range of s_b) so bounding boxes stay tight; both
// backends use the same pieces, so they return exactly the same hits:
//   BruteForceBeams: tests every piece (the test oracle).
//   EmbreeBeams:     Embree user geometry over the pieces (Embree's BVH), in beam_accel.cpp only.
// Hits are returned sorted by (beam, piece), so sums over hits do not depend on traversal order.
#pragma once
#include "accel/accel_backend.h"
#include "estimators/beam_kernel.h"
#include "photons/photon_tracer.h"

#include <memory>
#include <string>
#include <vector>

namespace tpb {

struct BeamHit {
    uint32_t beam;
    uint32_t piece;
    RayBeamOverlap overlap;
};

// Pieces of a beam of this length for kernel radius r: about 16 r long, at most 16 per beam. A
// balance between the BVH's build time (grows with pieces) and the candidates a query tests (grows
// with loose boxes); measured on point_medium / cornell_medium at 96x96 (s/pass, 8r/64: 1.56/0.86,
// 16r/16: 0.70/0.86, 32r/8: 0.64/0.92).
inline uint32_t beamPieceCount(double length, double radius) {
    const double n = std::ceil(length / (16.0 * std::max(radius, 1e-12)));
    return static_cast<uint32_t>(std::clamp(n, 1.0, 16.0));
}

class BeamAccel {
public:
    virtual ~BeamAccel() = default;
    // `beams` must outlive the accelerator (it is referenced, not copied).
    virtual void build(const std::vector<Beam>& beams, double radius, int threads) = 0;
    // Appends the hits of segment o + s d, s in [0, sMax], with beams of `region`, then sorts them.
    virtual void query(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamHit>& hits) const = 0;
    virtual std::string name() const = 0;
    virtual size_t pieceCount() const = 0;

    static std::unique_ptr<BeamAccel> create(AccelBackend kind);
};

void sortBeamHits(std::vector<BeamHit>& hits, size_t from);

}  // namespace tpb
