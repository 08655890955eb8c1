// Shared queries over a block of camera segments (estimators/segment_bundle.h, issue 15).
//
// The claim of the bundle: a segment it contains gets exactly the estimates, in exactly the order,
// of its own accelerator query. Checked here against the ordinary gather (an estimator prepared
// without slack, so with the plain support radius) on random segments in and around a cone of
// camera rays, over random beams crossing it: every value of the pixel accumulator must be equal,
// bit for bit, and enough segments must be contained and gather estimates for the check to say
// something. And the containment test itself, against the geometry it claims.
#include "estimators/segment_bundle.h"

#include "base/rng.h"
#include "estimators/beam2d.h"
#include "integrators/camera_pass.h"
#include "support/scene_builder.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

using namespace tpb;

namespace {

BundleHint coneHint(double sinHalfAngle) {
    BundleHint h;
    h.origin = Vec3(0.0, 0.0, 3.0);
    h.axis = Vec3(0.0, 0.0, -1.0);
    h.sinHalfAngle = sinHalfAngle;
    h.maxLength = 6.0;
    h.region = 0;
    return h;
}

Vec3 randomDir(Rng& rng) {
    const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * kPi * rng.uniform();
    const double s = std::sqrt(1.0 - z * z);
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
}

// A direction at angle theta from -z, azimuth phi.
Vec3 coneDir(double theta, double phi) {
    return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -std::cos(theta));
}

bool sameAccumulator(const PixelAccumulator& a, const PixelAccumulator& b, int bins) {
    if (a.steady() != b.steady()) return false;
    for (TimeAxis ax : {TimeAxis::Real, TimeAxis::Unwarped}) {
        if (a.before(ax) != b.before(ax) || a.after(ax) != b.after(ax)) return false;
        for (int k = 0; k < bins; ++k)
            for (int c = 0; c < 3; ++c)
                if (a.bin(ax, k)[c] != b.bin(ax, k)[c]) return false;
    }
    return true;
}

}  // namespace

TEST(SegmentBundle, ContainsExactlyTheSegmentsWithinSlackOfTheAxis) {
    SegmentBundle bundle;
    const double slack = 0.05;
    bundle.begin(coneHint(0.02));
    ASSERT_TRUE(bundle.active());
    EXPECT_DOUBLE_EQ(bundle.axisLength(slack), 2.5);  // slack / sin theta, below maxLength
    const Vec3 o(0.0, 0.0, 3.0);
    // Along the axis: up to the axis' end plus the slack (the capsule's cap), not beyond.
    EXPECT_TRUE(bundle.contains(o, Vec3(0, 0, -1), 2.5, 0, slack));
    EXPECT_TRUE(bundle.contains(o, Vec3(0, 0, -1), 2.549, 0, slack));
    EXPECT_FALSE(bundle.contains(o, Vec3(0, 0, -1), 2.551, 0, slack));
    // At angle theta the end point is s sin(theta) from the axis: contained while that is <= slack.
    const double theta = 0.015;
    const Vec3 w = coneDir(theta, 0.7);
    const double sEdge = slack / std::sin(theta);  // 3.33: beyond the axis' end, but its cap is round
    const Vec3 endOk = o + 2.4 * w;
    EXPECT_TRUE(bundle.contains(o, w, 2.4, 0, slack));
    EXPECT_LT(std::hypot(endOk.x, endOk.y), slack);
    EXPECT_FALSE(bundle.contains(o, w, sEdge, 0, slack));
    // Another region, an infinite segment, a segment off the axis' start: not contained.
    EXPECT_FALSE(bundle.contains(o, Vec3(0, 0, -1), 1.0, 1, slack));
    EXPECT_FALSE(bundle.contains(o, Vec3(0, 0, -1), kInf, 0, slack));
    EXPECT_FALSE(bundle.contains(o + Vec3(0.06, 0, 0), Vec3(0, 0, -1), 1.0, 0, slack));
    EXPECT_TRUE(bundle.contains(o + Vec3(0.04, 0, -0.5), Vec3(0, 0, -1), 1.0, 0, slack));
    // Ended: nothing is contained.
    bundle.end();
    EXPECT_FALSE(bundle.contains(o, Vec3(0, 0, -1), 1.0, 0, slack));
}

TEST(SegmentBundle, ContainedSegmentsGatherBitIdenticalEstimatesToTheirOwnQuery) {
    test::SceneBuilder b;
    b.camera(Vec3(0, 0, 3), Vec3(0, 0, 0), 30.0, 4, 4).film(0.0, 0.05, 160);
    b.globalMedium(b.medium(Color(0.6, 0.4, 0.2), Color(0.1, 0.3, 0.05), 0.3, 1.33));
    b.pointLight(Vec3(0, 5, 0), Color(1.0));
    const test::TestScene sc = test::prepareTestScene(b.desc());
    ASSERT_TRUE(sc);

    // Beams crossing the cone around the -z axis from (0, 0, 3): origins near the axis, random
    // directions and lengths, powers and start times.
    Rng rng(11, Stream::Photon, 1, 0);
    PhotonMap map;
    for (int i = 0; i < 3000; ++i) {
        Beam beam;
        beam.origin = Vec3(0.3 * (2.0 * rng.uniform() - 1.0), 0.3 * (2.0 * rng.uniform() - 1.0), 3.2 * rng.uniform());
        beam.dir = randomDir(rng);
        beam.length = 0.2 + 2.0 * rng.uniform();
        beam.power = Color(0.5 + rng.uniform(), 0.5 + rng.uniform(), 0.5 + rng.uniform());
        beam.opl0 = 3.0 * rng.uniform();
        beam.region = 0;
        map.beams.push_back(beam);
    }
    EstimatorPass ep;
    ep.radius = 0.03;
    ep.threads = 1;
    Beam2DEstimator plain, shared;
    plain.prepare(*sc, map, ep);
    ep.bundleSlack = 0.05;
    shared.prepare(*sc, map, ep);
    ASSERT_FALSE(plain.empty());

    const BundleHint hint = coneHint(0.02);
    EstimatorScratch sharedScratch, plainScratch;
    sharedScratch.bundle.begin(hint);
    const int bins = sc.time.bins;
    PixelAccumulator accPlain(bins), accShared(bins);
    int contained = 0, outside = 0, mismatches = 0;
    int64_t containedEstimates = 0;
    PathState path;
    path.oplCam = 0.1;
    for (int i = 0; i < 600; ++i) {
        // Inside the cone and somewhat beyond it (theta up to 1.4x), short and long segments.
        const Vec3 w = coneDir(0.028 * std::sqrt(rng.uniform()), 2.0 * kPi * rng.uniform());
        const CameraSegment seg{{hint.origin, w}, 0.3 + 3.2 * rng.uniform(), 0};
        const bool in = sharedScratch.bundle.contains(seg.ray.o, seg.ray.d, seg.sMax, seg.region, ep.bundleSlack);
        FilmTally tally;
        PixelSink sinkPlain{sc.time, accPlain, tally}, sinkShared{sc.time, accShared, tally};
        const int64_t nPlain = plain.gather(seg, path, sinkPlain, plainScratch);
        const int64_t nShared = shared.gather(seg, path, sinkShared, sharedScratch);
        if (nPlain != nShared || !sameAccumulator(accPlain, accShared, bins)) ++mismatches;
        if (in) {
            ++contained;
            containedEstimates += nShared;
        } else {
            ++outside;
        }
        accPlain.clearTouched();
        accShared.clearTouched();
    }
    EXPECT_EQ(mismatches, 0);
    EXPECT_TRUE(sharedScratch.bundle.built());
    EXPECT_GT(contained, 200);  // the check covers the shared path...
    EXPECT_GT(outside, 100);    // ...and the ordinary query of an estimator built with slack
    EXPECT_GT(containedEstimates, 2000);
}

TEST(SegmentBundle, CameraHintCoversTheBlocksRays) {
    test::SceneBuilder b;
    b.camera(Vec3(0, 1, 4), Vec3(0, 1, 0), 40.0, 64, 48).film(0.0, 0.05, 16);
    b.globalMedium(b.medium(Color(0.3), Color(0.05), 0.0, 1.0));
    b.quad(Vec3(-2, -1, -1), Vec3(4, 0, 0), Vec3(0, 4, 0), b.diffuse(Color(0.5)));
    b.pointLight(Vec3(0, 2, 0), Color(1.0));
    const test::TestScene sc = test::prepareTestScene(b.desc());
    ASSERT_TRUE(sc);
    // Every ray through the block is within the hint's angle of its axis (sampled, corners included).
    Rng rng(3, Stream::Camera, 1, 0);
    for (const auto& blk : {std::array<int, 4>{0, 0, 4, 4}, {30, 22, 4, 4}, {60, 44, 4, 4}, {62, 46, 2, 2}}) {
        const BundleHint h = bundleHint(*sc, blk[0], blk[1], blk[2], blk[3]);
        EXPECT_GT(h.sinHalfAngle, 0.0);
        for (int i = 0; i < 200; ++i) {
            const double px = blk[0] + blk[2] * (i < 4 ? (i & 1) : rng.uniform());
            const double py = blk[1] + blk[3] * (i < 4 ? (i >> 1) : rng.uniform());
            const Vec3 c = glm::cross(h.axis, sc->camera.generate(px, py).d);
            EXPECT_LE(glm::length(c), h.sinHalfAngle * (1.0 + 1e-12));
        }
    }
    // The slack contains the centre block's primary segments up to the farthest corner of the scene.
    const double slack = bundleSlack(*sc);
    const BundleHint centre = bundleHint(*sc, 30, 22, kBundleBlock, kBundleBlock);
    EXPECT_GE(slack, centre.sinHalfAngle * centre.maxLength);
    SegmentBundle bundle;
    bundle.begin(centre);
    const Ray r = sc->camera.generate(30.0, 22.0);
    EXPECT_TRUE(bundle.contains(r.o, r.d, 0.999 * centre.maxLength, centre.region, slack));
}
