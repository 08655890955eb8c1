// The photon-beam accelerators of accel/beam_accel.h: brute force, and Embree user geometry over the
// beam pieces (the shared device of scene/embree_device.h; Embree errors are thrown as EmbreeError).
#include "accel/beam_accel.h"

#include "accel/piece_bvh.h"

#include "base/error.h"
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
    hits.erase(std::unique(hits.begin() + static_cast<std::ptrdiff_t>(from), hits.end(),
                           [](const BeamPiece& a, const BeamPiece& b) { return a.beam == b.beam && a.piece == b.piece; }),
               hits.end());
}

namespace {

// A piece with its beam's axis and region, contiguous (one memory access per candidate).
struct Piece {
    Vec3 origin, dir;  // of the beam
    double sbLo, sbHi;
    uint32_t beam, piece;
    int region;
};

void makePieces(const std::vector<Beam>& beams, double radius, std::vector<Piece>& pieces) {
    pieces.clear();
    size_t n = 0;
    for (const Beam& b : beams) n += beamPieceCount(b.length, radius);
    pieces.reserve(n);
    for (uint32_t b = 0; b < beams.size(); ++b) {
        const uint32_t n = beamPieceCount(beams[b].length, radius);
        for (uint32_t k = 0; k < n; ++k)
            pieces.push_back({beams[b].origin, beams[b].dir, beams[b].length * k / n,
                              k + 1 == n ? beams[b].length : beams[b].length * (k + 1) / n, b, k, beams[b].region});
    }
}

// Points as zero-length pieces: the axis is the point itself (direction 0, sbLo = sbHi = 0).
void makePointPieces(const std::vector<VolumePhoton>& points, std::vector<Piece>& pieces) {
    pieces.clear();
    pieces.reserve(points.size());
    for (uint32_t k = 0; k < points.size(); ++k) pieces.push_back({points[k].position, Vec3(0.0), 0.0, 0.0, k, 0, points[k].region});
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
            if (p.region == region && test(candidate(p), p.origin, p.dir)) out.push_back(candidate(p));  // already in (beam, piece) order
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
    void build(const std::vector<Beam>& beams, const BeamSupport& support, int) final {
        radius_ = support.radius;
        makePieces(beams, support.pieceRadius, pieces_);
        buildBvh();
        setRegions();
    }
    void build(const std::vector<VolumePhoton>& points, double radius, int) final {
        radius_ = radius;
        makePointPieces(points, pieces_);
        buildBvh();
        setRegions();
    }
    size_t pieceCount() const override { return pieces_.size(); }

protected:
    // The hierarchy over pieces_ (replaces the previous one; may reorder pieces_: the regions are
    // taken after it).
    virtual void buildBvh() = 0;
    // Piece i's box padded by the support radius (plus 1e-5 of it and 1e-6 of the distance from
    // the origin, for the float boxes), rounded outward to float.
    void paddedBox(size_t i, float lo[3], float hi[3]) const {
        const Piece& p = pieces_[i];
        const Vec3 a = p.origin + p.sbLo * p.dir, e = p.origin + p.sbHi * p.dir;
        const double pad = radius_ * (1.0 + 1e-5) + 1e-6 * (1.0 + glm::length(a));
        const Vec3 l = glm::min(a, e) - pad, h = glm::max(a, e) + pad;
        for (int k = 0; k < 3; ++k) {
            lo[k] = nextFloat(static_cast<float>(l[k]), false);
            hi[k] = nextFloat(static_cast<float>(h[k]), true);
        }
    }
    // The pieces and axes of a box query's hits `ids`, appended in one loop over arrays sized once
    // (not nine push_backs per candidate inside the traversal).
    void copyHits(const std::vector<uint32_t>& ids, std::vector<BeamPiece>& out, PieceAxes& axes) const {
        const size_t base = out.size(), n = ids.size();
        out.resize(base + n);
        for (std::vector<double>* v : {&axes.ox, &axes.oy, &axes.oz, &axes.dx, &axes.dy, &axes.dz, &axes.lo, &axes.hi})
            v->resize(base + n);
        for (size_t k = 0; k < n; ++k) {
            const Piece& p = pieces_[ids[k]];
            const size_t i = base + k;
            out[i] = candidate(p);
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
    std::vector<Piece> pieces_;
    std::vector<int> regions_;  // pieces_[i].region, contiguous

private:
    void setRegions() {
        regions_.resize(pieces_.size());
        for (size_t i = 0; i < pieces_.size(); ++i) regions_[i] = pieces_[i].region;
    }
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
            const Piece& p = pieces_[i];
            const BeamPiece c = candidate(p);
            if (test(c, p.origin, p.dir)) hits.push_back(c);
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

private:
    // The hierarchy, then the pieces stored in its order: a query's hits, reported
    // by position, are then read from nearby memory (the candidates' order does not matter: they
    // are sorted by (beam, piece), and a box query's hits are sorted by their user).
    void buildBvh() override {
        boxes_.resize(pieces_.size());
        for (size_t i = 0; i < pieces_.size(); ++i) paddedBox(i, boxes_[i].lo, boxes_[i].hi);
        bvh_.build(boxes_);
        const std::vector<uint32_t>& order = bvh_.order();
        sortedPieces_.resize(pieces_.size());
        for (size_t k = 0; k < order.size(); ++k) sortedPieces_[k] = pieces_[order[k]];
        pieces_.swap(sortedPieces_);
    }
    std::vector<PieceBvh::Box> boxes_;
    std::vector<Piece> sortedPieces_;
    PieceBvh bvh_;
};

class EmbreeBeams final : public IndexedPieces {
public:
    ~EmbreeBeams() override { if (scene_) rtcReleaseScene(scene_); }

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

private:
    struct Context {
        RTCIntersectContext base;  // must be first: Embree hands this pointer back to the callbacks
        const EmbreeBeams* self;
        int region;
        std::vector<BeamPiece>* hits;
        const CandidateTest* test;  // candidates(): keep what it accepts
        std::vector<uint32_t>* ids;  // boxCandidates(): note every piece of the region
    };

    // Visits every piece whose padded box the segment crosses (intersectFn).
    void traverse(const Vec3& o, const Vec3& d, double sMax, int region, std::vector<BeamPiece>& hits,
                  const CandidateTest* test, std::vector<uint32_t>* ids) const {
        if (pieces_.empty() || !scene_) return;
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
        rh.ray.tfar = std::isfinite(sMax) ? static_cast<float>(paddedEnd(sMax)) : std::numeric_limits<float>::infinity();
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
        self->paddedBox(args->primID, lo, hi);
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
        const Piece& p = ctx->self->pieces_[args->primID];
        const BeamPiece c = candidate(p);
        if ((*ctx->test)(c, p.origin, p.dir)) ctx->hits->push_back(c);
        // No hit is reported to Embree: traversal goes on and visits every candidate piece.
    }
    static void occludedFn(const RTCOccludedFunctionNArguments*) {}

    // Embree's BVH over pieces_ (replaces the previous one).
    void buildBvh() override {
        if (scene_) rtcReleaseScene(scene_);
        scene_ = nullptr;
        try {
            RTCDevice device = embreeDevice();
            scene_ = rtcNewScene(device);
            checkEmbree("creating the photon-beam scene");
            rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
            RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
            checkEmbree("creating the photon-beam geometry");
            rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(pieces_.size()));
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

    RTCScene scene_ = nullptr;
};

}  // namespace

std::unique_ptr<BeamAccel> BeamAccel::create(AccelBackend kind) {
    if (kind == AccelBackend::BruteForce) return std::make_unique<BruteForceBeams>();
    if (kind == AccelBackend::Bvh) return std::make_unique<BvhBeams>();
    return std::make_unique<EmbreeBeams>();
}

}  // namespace tpb
