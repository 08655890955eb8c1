// The ray-beam overlap of beam2d.h (rayBeamOverlap: a camera segment against a beam piece's kernel
// cylinder) run over a whole list of candidate pieces at once: the pieces a block of pixels shares
// (segment_bundle.h) are stored as a structure of arrays, and one camera segment is tested against
// all of them in a loop the compiler vectorises (two doubles per SSE2 instruction, four in the AVX2
// clone, eight in the AVX-512 one, the loader picking the widest the CPU has: GCC target_clones).
//
// The batch computes, lane by lane, exactly the operations of the scalar rayBeamOverlap in the same
// order (no FMA contraction, no reassociation: the file is built with -ffp-contract=off and
// without -ffast-math, so no clone fuses a multiply and an add), with every branch replaced by a select, so
// its answers - which pieces overlap and their intervals - are the scalar test's bit for bit
// (tests/estimators/test_overlap_batch.cpp checks that on random and degenerate configurations).
#pragma once
#include "accel/piece_axes.h"
#include "base/math.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tpb {

// The overlaps of one camera segment with a list of pieces: for every piece i, whether it overlaps
// (`hits` lists those i in increasing order) and, for those, the fields of RayBeamOverlap
// (s_r interval, sb0, cos) at index i.
struct OverlapBatch {
    std::vector<double> sMinus, sPlus, sb0, cosRB;
    std::vector<uint32_t> hits;
};

// rayBeamOverlap(xr, wr, sMax, origin_i, dir_i, lo_i, hi_i, radius) for every piece i of `pieces`.
void rayBeamOverlaps(const Vec3& xr, const Vec3& wr, double sMax, const PieceAxes& pieces, double radius,
                     OverlapBatch& out);

}  // namespace tpb
