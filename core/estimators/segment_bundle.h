// One accelerator query shared by the camera segments of a block of pixels (issue 15).
//
// The primary segments of a block of B x B pixels of a pinhole camera all start at the camera and
// leave it inside a narrow cone (half-angle theta: the block's corner rays). A camera segment S
// that lies within `slack` of one axis segment C = [o, o + L a] (both of its end points do; the
// capsule of radius slack around C is convex, so all of S does) can only meet a beam piece's kernel
// cylinder (radius r, flat caps at sbLo, sbHi) if C meets the piece's FAT cylinder: radius
// r + slack, caps moved out by slack (a point q of C within slack of a point p of S in the kernel
// has a perpendicular distance <= r + slack and a projection within slack of [sbLo, sbHi]). And
// C then crosses the piece's box padded by r + slack (the box padded by r holds p; |q - p| <= slack
// in every coordinate), so the accelerator must be built with support radius r + slack.
//
// So: one query along C with the fat test gives a candidate list, sorted by (beam, piece), that
// holds every piece any contained segment can meet; each segment then runs the EXACT test of its
// own gather on that list, in order. The accepted pieces, their order and so the estimates and the
// films are the same as with one query per segment (tests/estimators/test_segment_bundle.cpp),
// at a fraction of the traversals: ~300 fat candidates tested per segment instead of a traversal
// through ~670 boxes with a callback each.
//
// Nothing here depends on who made the hint: containment is checked per segment, geometrically,
// and a segment that is not contained (a secondary segment, one longer than L, another region)
// takes the ordinary query. The list is built lazily, by the first contained segment.
#pragma once
#include "accel/beam_accel.h"
#include "base/math.h"
#include "estimators/overlap_batch.h"

#include <algorithm>
#include <vector>

namespace tpb {

// What the camera pass knows about a block before tracing it.
struct BundleHint {
    Vec3 origin{0.0};           // the camera's pinhole
    Vec3 axis{0.0};             // unit, through the block's centre
    double sinHalfAngle = 0.0;  // sin of the largest angle between `axis` and a ray of the block
    double maxLength = 0.0;     // m: no primary segment is longer (the scene's extent seen from origin)
    int region = 0;             // the camera's region
};

class SegmentBundle {
public:
    // Starts a block: `slack` (m) is the estimator's (the accelerator's extra support radius);
    // the axis C is as long as the slack allows (slack / sin theta) and no longer than maxLength.
    void begin(const BundleHint& h) {
        hint_ = h;
        active_ = h.sinHalfAngle >= 0.0 && h.maxLength > 0.0 && glm::dot(h.axis, h.axis) > 0.5;
        built_ = false;
        pieces.clear();
        axes.clear();
    }
    void end() {
        active_ = false;
        built_ = false;
    }
    bool active() const { return active_; }
    bool built() const { return built_; }
    void markBuilt() { built_ = true; }

    // The axis length for a given slack.
    double axisLength(double slack) const {
        const double l = hint_.sinHalfAngle > 0.0 ? slack / hint_.sinHalfAngle : hint_.maxLength;
        return std::min(l, hint_.maxLength);
    }
    // Does the segment x + s w, s in [0, sMax], of `region` lie within `slack` of the axis?
    bool contains(const Vec3& x, const Vec3& w, double sMax, int region, double slack) const {
        if (!active_ || region != hint_.region || !std::isfinite(sMax)) return false;
        const double len = axisLength(slack);
        return distance2ToAxis(x, len) <= slack * slack && distance2ToAxis(x + sMax * w, len) <= slack * slack;
    }
    const BundleHint& hint() const { return hint_; }

    std::vector<BeamPiece> pieces;  // the shared candidates, sorted by (beam, piece)
    PieceAxes axes;  // their axes, as arrays, for an estimator that tests them in a batch (overlap_batch.h)

private:
    double distance2ToAxis(const Vec3& p, double len) const {
        const Vec3 d = p - hint_.origin;
        const double t = std::clamp(glm::dot(d, hint_.axis), 0.0, len);
        const Vec3 e = d - t * hint_.axis;
        return glm::dot(e, e);
    }
    BundleHint hint_;
    bool active_ = false, built_ = false;
};

}  // namespace tpb
