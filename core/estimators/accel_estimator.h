// What every kernel estimator over a BeamAccel keeps from one pass to the next (beam1d, beam2d:
// over the beams; point2d, point3d: over the photon points): the pass's scene, photon map and
// settings, and the accelerator, rebuilt each pass for the pass's radius and kept so its buffers
// are reused (re-created only when the backend changes).
#pragma once
#include "estimators/estimator.h"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

namespace tpb {

class AccelVolumeEstimator : public VolumeEstimator {
public:
    bool empty() const override { return !ready_; }
    size_t accelPrimitives() const override { return ready_ ? accel_->pieceCount() : 0; }

    // The shared query of a block of camera segments (segment_bundle.h): along the block's axis,
    // `length` long, every piece whose kernel (radius) a segment within `slack` of it can reach.
    struct BundleQuery {
        Vec3 origin, axis;
        double length, radius, slack;
    };

protected:
    // Keeps scene, map and pass; builds the accelerator over `items` (map.beams or map.points) with
    // support radius pass.radius: every kernel here is zero farther than r from its beam or point
    // (plus pass.bundleSlack for an estimator that shares queries over blocks: `bundles`).
    template <class Items>
    void prepareOver(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass, const Items& items,
                     bool bundles = false) {
        scene_ = &scene;
        map_ = &map;
        pass_ = pass;
        if (!bundles || !(pass_.bundleSlack > 0.0)) pass_.bundleSlack = 0.0;
        ready_ = !items.empty();
        if (!ready_) return;
        if (!accel_ || backend_ != pass.accel) {
            accel_ = BeamAccel::create(pass.accel);
            backend_ = pass.accel;
        }
        // (The slack's own rounding margin: segment_bundle.h's fat test uses slack (1 + 1e-6).)
        const double support = pass.radius + (pass_.bundleSlack > 0.0 ? pass_.bundleSlack * (1.0 + 2e-6) : 0.0);
        buildAccel(items, support, pass.radius, pass.threads);
    }

    // The block's shared list if it contains `seg` (null: the segment takes its own query), made on
    // first use by list(query, region, bundle), which fills bundle.pieces (and bundle.axes, if its
    // estimator reads them).
    template <class List>
    const std::vector<BeamPiece>* sharedList(const CameraSegment& seg, EstimatorScratch& scratch, List&& list) const {
        SegmentBundle& bundle = scratch.bundle;
        if (!(pass_.bundleSlack > 0.0) ||
            !bundle.contains(seg.ray.o, seg.ray.d, seg.sMax, seg.region, pass_.bundleSlack))
            return nullptr;
        if (!bundle.built()) {
            const BundleHint& h = bundle.hint();
            // The slack with a margin for rounding (the accelerator pads by slack (1 + 2e-6)).
            const BundleQuery q{h.origin, h.axis, bundle.axisLength(pass_.bundleSlack), pass_.radius,
                                pass_.bundleSlack * (1.0 + 1e-6)};
            bundle.pieces.clear();
            bundle.axes.clear();
            list(q, h.region, bundle);
            bundle.markBuilt();
        }
        return &bundle.pieces;
    }

    // The block's shared candidates (sharedList): `fat` is the estimator's test of a piece against
    // the query (its context a BundleQuery), run by the accelerator on each piece it reaches. In the
    // accelerator's (beam, piece) order, so the estimates come in the order of the own query.
    const std::vector<BeamPiece>* sharedCandidates(const CameraSegment& seg, EstimatorScratch& scratch,
                                                   decltype(CandidateTest::accept) fat) const {
        return sharedList(seg, scratch, [&](const BundleQuery& q, int region, SegmentBundle& bundle) {
            accel_->candidates(q.origin, q.axis, q.length, region, bundle.pieces, {fat, &q});
        });
    }

    // sharedCandidates() with the fat test of the beam kernels' cylinder (the block's axis against
    // the piece's cylinder of radius r + slack, caps moved out by slack) run on all of the query's
    // box candidates at once (overlap_batch.h: rayBeamOverlap's answers bit for bit) instead of one
    // callback per piece during the traversal; the kept pieces are then sorted by (beam, piece), one
    // per piece, as candidates() sorts them: the same list, in the same order, with their axes in
    // bundle.axes for the exact test, batched too.
    const std::vector<BeamPiece>* sharedCylinderCandidates(const CameraSegment& seg, EstimatorScratch& scratch) const {
        return sharedList(seg, scratch, [&](const BundleQuery& q, int region, SegmentBundle& bundle) {
            std::vector<BeamPiece>& box = scratch.pieces;
            PieceAxes& fat = scratch.boxAxes;
            box.clear();
            fat.clear();
            accel_->boxCandidates(q.origin, q.axis, q.length, region, box, fat);
            for (size_t i = 0; i < box.size(); ++i) {
                fat.lo[i] = box[i].sbLo - q.slack;
                fat.hi[i] = box[i].sbHi + q.slack;
            }
            OverlapBatch& ob = scratch.overlaps;
            rayBeamOverlaps(q.origin, q.axis, q.length, fat, q.radius + q.slack, ob);
            // Sort the kept ones by (beam, piece) and keep one per piece (sortBeamPieces' order):
            // one 64-bit key each, (beam, piece) above the index i in the box list, which orders
            // as the pair would (32 bits of beam, 4 of piece, kIndexBits of i).
            constexpr int kIndexBits = 28;
            static_assert(kMaxPiecesPerBeam <= 16, "a piece's number takes 4 bits of the sort key");
            if (box.size() >= (size_t(1) << kIndexBits))
                throw std::length_error("sharedCylinderCandidates: more box candidates than a sort key holds");
            std::vector<uint64_t>& keys = scratch.keys;
            keys.resize(ob.hits.size());
            for (size_t k = 0; k < ob.hits.size(); ++k) {
                const BeamPiece& p = box[ob.hits[k]];
                keys[k] = ((static_cast<uint64_t>(p.beam) << 4 | p.piece) << kIndexBits) | ob.hits[k];
            }
            std::sort(keys.begin(), keys.end());
            for (size_t k = 0; k < keys.size(); ++k) {
                if (k > 0 && (keys[k] >> kIndexBits) == (keys[k - 1] >> kIndexBits)) continue;
                const uint32_t i = static_cast<uint32_t>(keys[k] & ((uint64_t(1) << kIndexBits) - 1));
                bundle.pieces.push_back(box[i]);
                bundle.axes.push(Vec3(fat.ox[i], fat.oy[i], fat.oz[i]), Vec3(fat.dx[i], fat.dy[i], fat.dz[i]),
                                 box[i].sbLo, box[i].sbHi);
            }
        });
    }

    void buildAccel(const std::vector<Beam>& beams, double support, double radius, int threads) {
        accel_->build(beams, BeamSupport{support, radius}, threads);
    }
    void buildAccel(const std::vector<VolumePhoton>& points, double support, double, int threads) {
        accel_->build(points, support, threads);
    }

    const Scene* scene_ = nullptr;
    const PhotonMap* map_ = nullptr;
    EstimatorPass pass_;
    std::unique_ptr<BeamAccel> accel_;
    AccelBackend backend_ = AccelBackend::Bvh;
    bool ready_ = false;
};

}  // namespace tpb
