// The photon-beam accelerators of accel/beam_accel.h: brute force, and Embree user geometry over the
// beam pieces (the shared device of scene/embree_device.h; Embree errors are thrown as EmbreeError).
#include "accel/beam_accel.h"

#include "accel/piece_bvh.h"

#include "base/error.h"
#include "base/parallel.h"
#include "scene/embree_device.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tpb {

void sortBeamPieces(std::vector<BeamPiece>& hits, size_t from) {
    std::sort(hits.begin() + static_cast<std::ptrdiff_t>(from), hits.end(),
              [](const BeamPiece& a, const BeamPiece& b) { return beamPieceKey(a) < beamPieceKey(b); });
    // Embree may visit a primitive twice (spatial splits); keep one hit per (beam, piece).
    hits.erase(
        std::unique(hits.begin() + static_cast<std::ptrdiff_t>(from), hits.end(),
                    [](const BeamPiece& a, const BeamPiece& b) { return a.beam == b.beam && a.piece == b.piece; }),
        hits.end());
}

namespace {

// A piece with its beam's axis and region, as made from its beam or point.
struct Piece {
    Vec3 origin, dir;  // of the beam
    double sbLo, sbHi;
    uint32_t beam, piece;
    int region;
};

// Piece k of the n of beam `b` (every backend cuts the beams with these expressions: the same pieces).
Piece beamPiece(const Beam& beam, uint32_t b, uint32_t k, uint32_t n) {
    return {beam.origin, beam.dir, beam.length * k / n, k + 1 == n ? beam.length : beam.length * (k + 1) / n,
            b,           k,        beam.region};
}

void makePieces(const std::vector<Beam>& beams, double radius, std::vector<Piece>& pieces) {
    pieces.clear();
    size_t n = 0;
    for (const Beam& b : beams) n += beamPieceCount(b.length, radius);
    pieces.reserve(n);
    for (uint32_t b = 0; b < beams.size(); ++b) {
        const uint32_t n = beamPieceCount(beams[b].length, radius);
        for (uint32_t k = 0; k < n; ++k) pieces.push_back(beamPiece(beams[b], b, k, n));
    }
}

// Points as zero-length pieces: the axis is the point itself (direction 0, sbLo = sbHi = 0).
Piece pointPiece(const VolumePhoton& point, uint32_t k) {
    return {point.position, Vec3(0.0), 0.0, 0.0, k, 0, point.region};
}

void makePointPieces(const std::vector<VolumePhoton>& points, std::vector<Piece>& pieces) {
    pieces.clear();
    pieces.reserve(points.size());
    for (uint32_t k = 0; k < points.size(); ++k) pieces.push_back(pointPiece(points[k], k));
}

// What a hierarchy keeps of a piece, in three arrays: its axis and range in one cache line (what
// the box and the candidate test read; an 80-byte Piece straddled two), its (beam, piece) (read for
// the candidates kept) and its region (read for every box a query reaches).
struct alignas(64) PieceAxis {
    Vec3 origin, dir;
    double sbLo, sbHi;
};
struct PieceId {
    uint32_t beam, piece;
};
static_assert(sizeof(PieceAxis) == 64 && sizeof(PieceId) == 8,
              "kAccelBytesPerPiece (beam_accel.h) counts 64 + 8 bytes per stored piece");

PieceAxis axisOf(const Piece& p) { return {p.origin, p.dir, p.sbLo, p.sbHi}; }

// The box of piece axis p padded by the support radius (plus 1e-5 of it and 1e-6 of the distance
// from the origin, for the float boxes), rounded outward to float.
TPB_HOT_INLINE void paddedBox(const PieceAxis& p, double radius, float lo[3], float hi[3]) {
    const Vec3 a = p.origin + p.sbLo * p.dir, e = p.origin + p.sbHi * p.dir;
    const double pad = radius * (1.0 + 1e-5) + 1e-6 * (1.0 + glm::length(a));
    const Vec3 l = glm::min(a, e) - pad, h = glm::max(a, e) + pad;
    for (int k = 0; k < 3; ++k) {
        lo[k] = nextFloat(static_cast<float>(l[k]), false);
        hi[k] = nextFloat(static_cast<float>(h[k]), true);
    }
}

// The per-piece loops of a build, shared among the pass's threads.
template <class F>
void forChunks(size_t n, int threads, const F& f) {
    parallelChunks(n, threads, size_t(1) << 14, f);
}

BeamPiece candidate(const Piece& p) { return {p.beam, p.piece, p.sbLo, p.sbHi}; }

class BruteForceBeams final : public BeamAccel {
public:
    using BeamAccel::build;
    void build(const std::vector<Beam>& beams, const BeamSupport& support, int) override {
        radius_ = support.radius;
        makePieces(beams, support.pieceRadius, pieces_);
    }
    void build(const std::vector<VolumePhoton>& points, double radius, int) override {
        radius_ = radius;
        makePointPieces(points, pieces_);
    }
    using BeamAccel::candidates;
    void candidates(const Vec3&, const Vec3&, double, int region, std::vector<BeamPiece>& out,
                    const CandidateTest& test) const override {
        for (const Piece& p : pieces_)
            if (p.region == region && test(p.sbLo, p.sbHi, p.origin, p.dir))
                out.push_back(candidate(p));  // already in (beam, piece) order
    }
    void boxCandidates(const Vec3&, const Vec3&, double, int region, std::vector<BeamPiece>& out,
                       PieceAxes& axes) const override {
        for (const Piece& p : pieces_)
            if (p.region == region) {
                out.push_back(candidate(p));
                axes.push(p.origin, p.dir, p.sbLo, p.sbHi);
            }
    }
    std::string name() const override { return "brute-force"; }
    size_t pieceCount() const override { return pieces_.size(); }

private:
    double radius_ = 0.0;
    std::vector<Piece> pieces_;
};

// What the two hierarchies share: the pieces (their regions also in an array of their own, which
// a traversal reads for every box it reaches, the pieces only for those of the query's region),
// each piece's padded box, and the copy of a box query's hits into the caller's arrays.
class IndexedPieces : public BeamAccel {
public:
    using BeamAccel::build;
    size_t pieceCount() const override { return axes_.size(); }

protected:
    void resizeStorage(size_t n) {
        axes_.resize(n);
        ids_.resize(n);
        regions_.resize(n);
    }
    void store(size_t k, const Piece& p) {
        axes_[k] = axisOf(p);
        ids_[k] = {p.beam, p.piece};
        regions_[k] = p.region;
    }
    BeamPiece candidate(size_t k) const { return {ids_[k].beam, ids_[k].piece, axes_[k].sbLo, axes_[k].sbHi}; }
    // The pieces and axes of a box query's hits `ids`, appended in one loop over arrays sized once
    // (not nine push_backs per candidate inside the traversal).
    void copyHits(const std::vector<uint32_t>& ids, std::vector<BeamPiece>& out, PieceAxes& axes) const {
        const size_t base = out.size(), n = ids.size();
        out.resize(base + n);
        for (std::vector<double>* v : {&axes.ox, &axes.oy, &axes.oz, &axes.dx, &axes.dy, &axes.dz, &axes.lo, &axes.hi})
            v->resize(base + n);
        for (size_t k = 0; k < n; ++k) {
            const PieceAxis& p = axes_[ids[k]];
            const size_t i = base + k;
            out[i] = candidate(ids[k]);
            axes.ox[i] = p.origin.x;
            axes.oy[i] = p.origin.y;
            axes.oz[i] = p.origin.z;
            axes.dx[i] = p.dir.x;
            axes.dy[i] = p.dir.y;
            axes.dz[i] = p.dir.z;
            axes.lo[i] = p.sbLo;
            axes.hi[i] = p.sbHi;
        }
    }
    // The segment's far end as the traversals take it: a little beyond sMax, so that rounding
    // never drops a piece the estimator's double test would accept.
    static double paddedEnd(double sMax) { return std::isfinite(sMax) ? sMax * (1.0 + 1e-5) + 1e-5 : sMax; }

    double radius_ = 0.0;
    std::vector<PieceAxis> axes_;
    std::vector<PieceId> ids_;
    std::vector<int> regions_;
};

// Our own hierarchy (accel/piece_bvh.h): built in a few ms, traversed without a callback per box.
class BvhBeams final : public IndexedPieces {
public:
    using BeamAccel::candidates;
    void candidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& hits,
                    const CandidateTest& test) const override {
        const size_t from = hits.size();
        bvh_.forEachCrossed(o, d, paddedEnd(sMax), [&](uint32_t i) TPB_HOT_LAMBDA {
            if (regions_[i] != region) return;
            const PieceAxis& p = axes_[i];
            if (test(p.sbLo, p.sbHi, p.origin, p.dir)) hits.push_back(candidate(i));
        });
        sortBeamPieces(hits, from);
    }
    void boxCandidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& out,
                       PieceAxes& axes) const override {
        thread_local std::vector<uint32_t> ids;
        ids.clear();
        bvh_.forEachCrossed(o, d, paddedEnd(sMax), [&](uint32_t i) TPB_HOT_LAMBDA {
            if (regions_[i] == region) ids.push_back(i);
        });
        copyHits(ids, out, axes);
    }
    std::string name() const override { return "bvh"; }

    void build(const std::vector<Beam>& beams, const BeamSupport& support, int threads) override {
        radius_ = support.radius;
        const size_t nb = beams.size();
        first_.resize(nb + 1);
        first_[0] = 0;
        for (size_t b = 0; b < nb; ++b)
            first_[b + 1] = first_[b] + beamPieceCount(beams[b].length, support.pieceRadius);
        const size_t n = first_[nb];
        boxes_.resize(n);
        beamOf_.resize(n);
        forChunks(nb, threads, [&](size_t b0, size_t b1) {
            for (size_t b = b0; b < b1; ++b) {
                const uint32_t count = static_cast<uint32_t>(first_[b + 1] - first_[b]);
                for (uint32_t k = 0; k < count; ++k) {
                    const size_t i = first_[b] + k;
                    paddedBox(axisOf(beamPiece(beams[b], static_cast<uint32_t>(b), k, count)), radius_, boxes_[i].lo,
                              boxes_[i].hi);
                    beamOf_[i] = static_cast<uint32_t>(b);
                }
            }
        });
        storeInOrder(n, threads, [&](uint32_t i) {
            const uint32_t b = beamOf_[i];
            return beamPiece(beams[b], b, static_cast<uint32_t>(i - first_[b]),
                             static_cast<uint32_t>(first_[b + 1] - first_[b]));
        });
    }
    void build(const std::vector<VolumePhoton>& points, double radius, int threads) override {
        radius_ = radius;
        const size_t n = points.size();
        boxes_.resize(n);
        forChunks(n, threads, [&](size_t i0, size_t i1) {
            for (size_t i = i0; i < i1; ++i)
                paddedBox(axisOf(pointPiece(points[i], static_cast<uint32_t>(i))), radius_, boxes_[i].lo, boxes_[i].hi);
        });
        storeInOrder(n, threads, [&](uint32_t i) { return pointPiece(points[i], i); });
    }

private:
    // The hierarchy over boxes_ (piece i's padded box, in the input's order), then the pieces
    // stored in its order, each made again from its beam or point by pieceOf(i) (cheaper than
    // moving 80-byte pieces): a query's hits, reported by position, are then read from nearby
    // memory (the candidates' order does not matter: they are sorted by (beam, piece), and a box
    // query's hits by their user).
    template <class PieceOf>
    void storeInOrder(size_t n, int threads, const PieceOf& pieceOf) {
        bvh_.build(boxes_, threads);
        const std::vector<uint32_t>& order = bvh_.order();
        resizeStorage(n);
        forChunks(n, threads, [&](size_t k0, size_t k1) {
            for (size_t k = k0; k < k1; ++k) store(k, pieceOf(order[k]));
        });
    }

    std::vector<PieceBvh::Box> boxes_;  // in the input's order
    std::vector<size_t> first_;         // beam b's pieces are [first_[b], first_[b + 1]) in the input's order
    std::vector<uint32_t> beamOf_;      // the beam of piece i (input order)
    PieceBvh bvh_;
};

class EmbreeBeams final : public IndexedPieces {
public:
    ~EmbreeBeams() override {
        if (scene_) rtcReleaseScene(scene_);
    }

    using BeamAccel::candidates;
    void candidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& hits,
                    const CandidateTest& test) const override {
        const size_t from = hits.size();
        traverse(o, d, sMax, region, hits, &test, nullptr);
        sortBeamPieces(hits, from);
    }
    void boxCandidates(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& out,
                       PieceAxes& axes) const override {
        // The callback only notes the piece's index; the pieces and their axes are copied after the
        // traversal (copyHits).
        thread_local std::vector<uint32_t> ids;
        ids.clear();
        traverse(o, d, sMax, region, out, nullptr, &ids);
        copyHits(ids, out, axes);
    }
    std::string name() const override { return "embree"; }
    void build(const std::vector<Beam>& beams, const BeamSupport& support, int) override {
        radius_ = support.radius;
        std::vector<Piece> made;
        makePieces(beams, support.pieceRadius, made);
        storeMade(made);
    }
    void build(const std::vector<VolumePhoton>& points, double radius, int) override {
        radius_ = radius;
        std::vector<Piece> made;
        makePointPieces(points, made);
        storeMade(made);
    }

private:
    struct Context {
        RTCIntersectContext base;  // must be first: Embree hands this pointer back to the callbacks
        const EmbreeBeams* self;
        int region;
        std::vector<BeamPiece>* hits;
        const CandidateTest* test;   // candidates(): keep what it accepts
        std::vector<uint32_t>* ids;  // boxCandidates(): note every piece of the region
    };

    // Visits every piece whose padded box the segment crosses (intersectFn).
    void traverse(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& hits,
                  const CandidateTest* test, std::vector<uint32_t>* ids) const {
        if (axes_.empty() || !scene_) return;
        Context ctx;
        rtcInitIntersectContext(&ctx.base);
        ctx.self = this;
        ctx.region = region;
        ctx.hits = &hits;
        ctx.test = test;
        ctx.ids = ids;
        RTCRayHit rh;
        rh.ray.org_x = static_cast<float>(o.x);
        rh.ray.org_y = static_cast<float>(o.y);
        rh.ray.org_z = static_cast<float>(o.z);
        rh.ray.dir_x = static_cast<float>(d.x);
        rh.ray.dir_y = static_cast<float>(d.y);
        rh.ray.dir_z = static_cast<float>(d.z);
        rh.ray.tnear = 0.0f;
        // Pad the float ray so Embree's culling never drops a piece the double test would accept.
        rh.ray.tfar =
            std::isfinite(sMax) ? static_cast<float>(paddedEnd(sMax)) : std::numeric_limits<float>::infinity();
        rh.ray.mask = 0xFFFFFFFFu;
        rh.ray.flags = 0;
        rh.ray.time = 0.0f;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &ctx.base, &rh);
    }

    static void boundsFn(const RTCBoundsFunctionArguments* args) {
        const auto* self = static_cast<const EmbreeBeams*>(args->geometryUserPtr);
        float lo[3], hi[3];
        paddedBox(self->axes_[args->primID], self->radius_, lo, hi);
        RTCBounds* out = args->bounds_o;
        out->lower_x = lo[0];
        out->lower_y = lo[1];
        out->lower_z = lo[2];
        out->upper_x = hi[0];
        out->upper_y = hi[1];
        out->upper_z = hi[2];
    }

    static void intersectFn(const RTCIntersectFunctionNArguments* args) {
        if (!args->valid[0]) return;
        auto* ctx = reinterpret_cast<Context*>(args->context);
        // Embree reached this piece's padded box: a candidate, kept if the estimator's test accepts it.
        // The region is read from its own small array: a box query touches the pieces themselves
        // only after the traversal, in a loop whose loads overlap (boxCandidates).
        if (ctx->self->regions_[args->primID] != ctx->region) return;
        if (ctx->ids) {
            ctx->ids->push_back(args->primID);
            return;
        }
        const PieceAxis& p = ctx->self->axes_[args->primID];
        if ((*ctx->test)(p.sbLo, p.sbHi, p.origin, p.dir)) ctx->hits->push_back(ctx->self->candidate(args->primID));
        // No hit is reported to Embree: traversal goes on and visits every candidate piece.
    }
    static void occludedFn(const RTCOccludedFunctionNArguments*) {}

    // Embree's BVH over pieces_ (replaces the previous one).
    void buildScene() {
        if (scene_) rtcReleaseScene(scene_);
        scene_ = nullptr;
        try {
            RTCDevice device = embreeDevice();
            scene_ = rtcNewScene(device);
            checkEmbree("creating the photon-beam scene");
            rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
            RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
            checkEmbree("creating the photon-beam geometry");
            rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(axes_.size()));
            rtcSetGeometryUserData(g, this);
            rtcSetGeometryBoundsFunction(g, &EmbreeBeams::boundsFn, this);
            rtcSetGeometryIntersectFunction(g, &EmbreeBeams::intersectFn);
            rtcSetGeometryOccludedFunction(g, &EmbreeBeams::occludedFn);
            rtcCommitGeometry(g);
            rtcAttachGeometry(scene_, g);
            rtcReleaseGeometry(g);
            rtcCommitScene(scene_);
            checkEmbree("building the photon-beam BVH");
        } catch (...) {
            if (scene_) rtcReleaseScene(scene_);
            scene_ = nullptr;  // candidates() then finds nothing rather than query a broken scene
            throw;
        }
    }

    // The pieces in the input's (beam, piece) order, stored, then Embree's BVH over them.
    void storeMade(const std::vector<Piece>& made) {
        resizeStorage(made.size());
        for (size_t k = 0; k < made.size(); ++k) store(k, made[k]);
        buildScene();
    }

    RTCScene scene_ = nullptr;
};

}  // namespace

std::unique_ptr<BeamAccel> BeamAccel::create(AccelBackend kind) {
    if (kind == AccelBackend::BruteForce) return std::make_unique<BruteForceBeams>();
    if (kind == AccelBackend::Bvh) return std::make_unique<BvhBeams>();
    return std::make_unique<EmbreeBeams>();
}

}  // namespace tpb
