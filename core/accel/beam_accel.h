// Finding the photon beams a camera segment may touch: the candidates of an estimator's gather.
// Long beams are split into pieces (each a sub-range [sbLo, sbHi] of s_b) so bounding boxes stay
// tight. The accelerator knows only the beams' axes and a support radius (the widest distance from
// the axis at which the estimator's kernel is non-zero, given to build()): it returns every piece
// whose box, padded by that radius, the segment may cross, and the ESTIMATOR decides the overlap
// with its own kernel (a cylinder for the 2D kernel, closest approach for a 1D kernel, ...), so a
// new kernel needs no change here. Both backends use the same pieces and return the same set once
// the estimator has tested them:
//   BruteForceBeams: every piece of the region (the test oracle).
//   EmbreeBeams:     Embree user geometry over the pieces (Embree's BVH), in beam_accel.cpp only.
// Candidates are returned sorted by (beam, piece), one per piece, so sums over them do not depend
// on traversal order. An estimator may hand candidates() its exact kernel test (CandidateTest):
// the accelerator then runs it on each piece as traversal reaches it and keeps only the pieces it
// accepts, so rejected pieces are never stored or sorted (the sort of every candidate was a quarter
// of the camera pass). The accepted pieces come back in the same order: the estimates, and the
// films, are the same with or without the test.
//
// Photon points (VolumePhoton, photon_tracer.h) are indexed the same way, as zero-length pieces: the
// build overload for points makes point k the piece (beam = k, piece = 0, sbLo = sbHi = 0) with the
// point as its "axis", padded by the support radius (the point kernels' radius), and candidates()
// returns the points whose padded box the segment may cross, sorted by index. An accelerator holds
// either beams or points, whichever it was last built over.
#pragma once
#include "accel/accel_backend.h"
#include "accel/piece_axes.h"
#include "photons/photon_tracer.h"

#include <memory>
#include <string>
#include <vector>

namespace tpb {

// A piece of beam `beam`: its parameters s_b in [sbLo, sbHi] (m along the beam from its origin).
struct BeamPiece {
    uint32_t beam;
    uint32_t piece;
    double sbLo, sbHi;
};

// Pieces of a beam of this length for kernel radius r: about 16 r long, at most 16 per beam. A
// balance between the BVH's build time (grows with pieces) and the candidates a query tests (grows
// with loose boxes); measured on point_medium / cornell_medium at 96x96 (s/pass, 8r/64: 1.56/0.86,
// 16r/16: 0.70/0.86, 32r/8: 0.64/0.92).
inline constexpr uint32_t kMaxPiecesPerBeam = 16;
inline uint32_t beamPieceCount(double length, double radius) {
    const double n = std::ceil(length / (16.0 * std::max(radius, 1e-12)));
    return static_cast<uint32_t>(std::clamp(n, 1.0, static_cast<double>(kMaxPiecesPerBeam)));
}

// Memory of an accelerator per piece (beam piece or point), an upper estimate counted against the
// photon map's memory limit before it is built (integrators/photon_beams.cpp). Our BVH: the pieces
// in its order (axis and range 64 B, beam and piece numbers 8, region 4), their boxes and the
// sorted copy (2 x 24), the sort keys and their radix scratch (2 x 8), the order (4), each piece's
// beam (4) and each beam's first piece (8 per beam, at most 8 per piece), and the nodes (128 B
// each; a node has two to four children, so there are fewer nodes than pieces: about one per three
// on the shipped scenes, the bound counted here); Embree's is smaller.
inline constexpr uint64_t kAccelBytesPerPiece = 284;

// An estimator's exact test of one candidate piece (false: its kernel cannot reach the segment).
// A plain function and a context pointer, called from inside the traversal: no allocation, no
// virtual call per candidate. A null `accept` accepts every candidate. The accelerator hands the
// piece's range [sbLo, sbHi] and axis from its own contiguous copy (`origin`, unit `dir` of the
// beam; for a point, the point, dir 0 and the range [0, 0]): the same values as the Beam's, so the
// test needs no load of the beam (a cache miss per candidate, most of which it rejects), nor of
// the piece's numbers (read only for the pieces it keeps).
struct CandidateTest {
    bool (*accept)(const void* context, double sbLo, double sbHi, const Vec3& origin, const Vec3& dir) = nullptr;
    const void* context = nullptr;
    bool operator()(double sbLo, double sbHi, const Vec3& origin, const Vec3& dir) const {
        return !accept || accept(context, sbLo, sbHi, origin, dir);
    }
};

// How far a kernel reaches from a beam's axis (m): `radius` pads the pieces' boxes (every kernel is
// zero farther away, also a shared query's slack: estimators/segment_bundle.h); `pieceRadius` sets
// the pieces' length (beamPieceCount): the kernel's own radius, so that padding more for a shared
// query cuts the beams into the same pieces and the estimates stay the same.
struct BeamSupport {
    double radius = 0.0;
    double pieceRadius = 0.0;
};

class BeamAccel {
public:
    virtual ~BeamAccel() = default;
    // `beams` must outlive the accelerator (it is referenced, not copied). supportRadius (m): the
    // estimator's kernel is zero farther than this from a beam's axis (BeamSupport).
    virtual void build(const std::vector<Beam>& beams, const BeamSupport& support, int threads) = 0;
    void build(const std::vector<Beam>& beams, double supportRadius, int threads) {
        build(beams, BeamSupport{supportRadius, supportRadius}, threads);
    }
    // Same over photon points (`points` must outlive it): the kernel is zero farther than
    // supportRadius from a point; candidate k is point k (BeamPiece::beam = k).
    virtual void build(const std::vector<VolumePhoton>& points, double supportRadius, int threads) = 0;
    // Appends the candidate pieces of beams of `region` for the segment o + s d, s in [0, sMax]
    // (d unit), sorted by (beam, piece): a superset of the pieces whose kernel the segment meets
    // (for points: of the points within supportRadius of the segment). With a test, only the
    // candidates it accepts, in the same order.
    virtual void candidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& out,
                            const CandidateTest& test) const = 0;
    void candidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& out) const {
        candidates(o, d, sMax, region, out, CandidateTest{});
    }
    // Every piece of `region` whose padded box the segment may cross, in traversal order (unsorted;
    // a piece may come twice), appended to `out` with its beam's axis and its range appended to
    // `axes` (the same values the CandidateTest is handed): for an estimator that tests the whole
    // list at once (the shared query's fat test, overlap_batch.h) and then sorts what it keeps.
    virtual void boxCandidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& out,
                               PieceAxes& axes) const = 0;
    virtual std::string name() const = 0;
    virtual size_t pieceCount() const = 0;  // beam pieces, or points

    static std::unique_ptr<BeamAccel> create(AccelBackend kind);
};

// One 64-bit key per piece: (beam, piece) in lexicographic order.
inline uint64_t beamPieceKey(const BeamPiece& p) { return (static_cast<uint64_t>(p.beam) << 32) | p.piece; }

// Sorts out[from..] by (beam, piece) and keeps one entry per piece.
void sortBeamPieces(std::vector<BeamPiece>& out, size_t from);

}  // namespace tpb
