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
#include "estimators/point3d.h"
#include "film/transient_film.h"
#include "integrators/camera_pass.h"
#include "photons/photon_tracer.h"
#include "support/scene_builder.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
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

namespace {

test::TestScene mediumScene() {
    test::SceneBuilder b;
    b.camera(Vec3(0, 0, 3), Vec3(0, 0, 0), 30.0, 4, 4).film(0.0, 0.05, 160);
    b.globalMedium(b.medium(Color(0.6, 0.4, 0.2), Color(0.1, 0.3, 0.05), 0.3, 1.33));
    b.pointLight(Vec3(0, 5, 0), Color(1.0));
    return test::prepareTestScene(b.desc());
}

// Beams or points near the -z axis from (0, 0, 3), where the cone of coneHint() runs: random
// positions, directions, lengths, powers and start times.
PhotonMap mapNearTheAxis(bool points) {
    Rng rng(11, Stream::Photon, 1, 0);
    PhotonMap map;
    for (int i = 0; i < 3000; ++i) {
        const Vec3 x(0.3 * (2.0 * rng.uniform() - 1.0), 0.3 * (2.0 * rng.uniform() - 1.0), 3.2 * rng.uniform());
        const Color power(0.5 + rng.uniform(), 0.5 + rng.uniform(), 0.5 + rng.uniform());
        if (points) {
            VolumePhoton p{};
            p.position = Vec3(0.1 * x.x, 0.1 * x.y, x.z);  // closer: the ball has no length
            p.dirIn = randomDir(rng);
            p.power = power;
            p.opl = 3.0 * rng.uniform();
            p.region = 0;
            map.points.push_back(p);
        } else {
            Beam beam;
            beam.origin = x;
            beam.dir = randomDir(rng);
            beam.length = 0.2 + 2.0 * rng.uniform();
            beam.power = power;
            beam.opl0 = 3.0 * rng.uniform();
            beam.region = 0;
            map.beams.push_back(beam);
        }
    }
    return map;
}

// Random segments from the cone's apex, inside the cone and somewhat beyond it (theta up to 1.4x),
// short and long, gathered by `shared` (prepared with slack, the block begun) and by `plain` (no
// slack): the number of mismatching accumulators, and how many segments were contained or not.
struct IdentityCheck {
    int mismatches = 0, contained = 0, outside = 0;
    int64_t containedEstimates = 0;
};

IdentityCheck compareGathers(VolumeEstimator& plain, VolumeEstimator& shared, const test::TestScene& sc,
                             const PhotonMap& map) {
    EstimatorPass ep;
    ep.radius = 0.03;
    ep.threads = 1;
    plain.prepare(*sc, map, ep);
    ep.bundleSlack = 0.05;
    shared.prepare(*sc, map, ep);
    IdentityCheck r;
    if (plain.empty() || shared.empty()) return r;
    const BundleHint hint = coneHint(0.02);
    EstimatorScratch sharedScratch, plainScratch;
    sharedScratch.bundle.begin(hint);
    const int bins = sc.time.bins;
    PixelAccumulator accPlain(bins), accShared(bins);
    PathState path;
    path.oplCam = 0.1;
    Rng rng(5, Stream::Camera, 1, 0);
    for (int i = 0; i < 600; ++i) {
        const Vec3 w = coneDir(0.028 * std::sqrt(rng.uniform()), 2.0 * kPi * rng.uniform());
        const CameraSegment seg{{hint.origin, w}, 0.3 + 3.2 * rng.uniform(), 0};
        const bool in = sharedScratch.bundle.contains(seg.ray.o, seg.ray.d, seg.sMax, seg.region, ep.bundleSlack);
        FilmTally tally;
        PixelSink sinkPlain{sc.time, accPlain, tally}, sinkShared{sc.time, accShared, tally};
        const int64_t nPlain = plain.gather(seg, path, sinkPlain, plainScratch);
        const int64_t nShared = shared.gather(seg, path, sinkShared, sharedScratch);
        if (nPlain != nShared || !sameAccumulator(accPlain, accShared, bins)) ++r.mismatches;
        if (in) {
            ++r.contained;
            r.containedEstimates += nShared;
        } else {
            ++r.outside;
        }
        accPlain.clearTouched();
        accShared.clearTouched();
    }
    EXPECT_TRUE(sharedScratch.bundle.built());
    return r;
}

// The identity check on the medium scene, with photons near the cone's axis (`points`: photon
// points for point3d, else beams), and enough segments in and out of the bundle for it to say something.
void expectSameGathers(VolumeEstimator& plain, VolumeEstimator& shared, bool points) {
    const test::TestScene sc = mediumScene();
    ASSERT_TRUE(sc);
    const IdentityCheck r = compareGathers(plain, shared, sc, mapNearTheAxis(points));
    EXPECT_EQ(r.mismatches, 0);
    EXPECT_GT(r.contained, 200);  // the check covers the shared path...
    EXPECT_GT(r.outside, 100);    // ...and the own query of an estimator built with slack
    EXPECT_GT(r.containedEstimates, 2000);
}

}  // namespace

TEST(SegmentBundle, ContainedSegmentsGatherBitIdenticalBeamEstimatesToTheirOwnQuery) {
    Beam2DEstimator plain, shared;
    expectSameGathers(plain, shared, false);
}

TEST(SegmentBundle, ContainedSegmentsGatherBitIdenticalPointEstimatesToTheirOwnQuery) {
    Point3DEstimator plain, shared;
    expectSameGathers(plain, shared, true);
}

namespace {

// A 64 x 48 camera in fog before a wall, lit by a point light (`scatters`: the fog scatters).
test::TestScene fogScene(bool scatters = true) {
    test::SceneBuilder b;
    b.camera(Vec3(0, 1, 4), Vec3(0, 1, 0), 40.0, 64, 48).film(0.0, 0.05, 16);
    b.globalMedium(b.medium(Color(scatters ? 0.3 : 0.0), Color(0.05), 0.0, 1.0));
    b.quad(Vec3(-2, -1, -1), Vec3(4, 0, 0), Vec3(0, 4, 0), b.diffuse(Color(0.5)));
    b.pointLight(Vec3(0, 2, 0), Color(1.0));
    return test::prepareTestScene(b.desc());
}

}  // namespace

TEST(SegmentBundle, CameraHintCoversTheBlocksRays) {
    const test::TestScene sc = fogScene();
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
    const double slack = bundleSlack(*sc, 4);
    const BundleHint centre = bundleHint(*sc, 30, 22, 4, 4);
    EXPECT_GE(slack, centre.sinHalfAngle * centre.maxLength);
    SegmentBundle bundle;
    bundle.begin(centre);
    const Ray r = sc->camera.generate(30.0, 22.0);
    EXPECT_TRUE(bundle.contains(r.o, r.d, 0.999 * centre.maxLength, centre.region, slack));
}

// The plan takes the widest block whose slack stays within kMaxBundleSlackRadii radii, and no
// bundles when even blocks of 2 would be too wide or the camera's region does not scatter.
TEST(SegmentBundle, PlanTakesTheWidestBlockWithinTheSlackBound) {
    const test::TestScene sc = fogScene();
    ASSERT_TRUE(sc);
    const double s4 = bundleSlack(*sc, 4), s2 = bundleSlack(*sc, 2);
    ASSERT_GT(s2, 0.0);
    EXPECT_GT(s4, 1.5 * s2);  // a block twice as wide: about twice the angle
    EXPECT_EQ(bundleSlack(*sc, 1), 0.0);
    const auto expectPlan = [&](double radius, int block, double slack) {
        SCOPED_TRACE(radius);
        const BundlePlan p = planBundles(*sc, radius);
        EXPECT_EQ(p.block, block);
        EXPECT_EQ(p.slack, slack);
        EXPECT_LE(p.slack, kMaxBundleSlackRadii * radius);
    };
    expectPlan(s4 / kMaxBundleSlackRadii * 1.001, 4, s4);
    expectPlan(s4 / kMaxBundleSlackRadii * 0.999, 2, s2);
    expectPlan(s2 / kMaxBundleSlackRadii * 1.001, 2, s2);
    expectPlan(s2 / kMaxBundleSlackRadii * 0.999, 1, 0.0);
    const test::TestScene clear = fogScene(false);
    ASSERT_TRUE(clear);
    EXPECT_EQ(bundleSlack(*clear, 4), 0.0);
    EXPECT_EQ(planBundles(*clear, 1e3).block, 1);
}

// Whole films through the camera pass: blocks of 4 and of 2, each with its slack, render the film
// of the plain pass (every segment its own query) bit for bit, for both estimators that share.
TEST(SegmentBundle, BlockedCameraPassRendersThePlainFilm) {
    const test::TestScene sc = fogScene();
    ASSERT_TRUE(sc);
    PhotonPassParams ts;
    ts.photons = 4000;
    ts.seed = 3;
    ts.threads = 1;
    ts.storePoints = true;
    const PhotonMap map = tracePhotons(*sc, ts);
    ASSERT_GT(map.beams.size(), 1000u);
    ASSERT_GT(map.points.size(), 1000u);
    const auto render = [&](VolumeEstimator& volume, int block, std::vector<double>& out) {
        EstimatorPass ep;
        ep.radius = 0.05;
        ep.threads = 1;
        ep.bundleSlack = bundleSlack(*sc, block);
        volume.prepare(*sc, map, ep);
        CameraPassEstimators est;
        est.volume = &volume;
        CameraPassParams cs;
        cs.bundleBlock = block;
        TransientFilm film(sc->camera.width, sc->camera.height, sc.time);
        CameraPassScratch scratch;
        scratch.acc.reset(film.bins());
        CameraPassStats stats;
        for (int t = 0; t < film.tileCount(); ++t) renderTile(*sc, est, cs, film, t, scratch, stats);
        stats.flushInto(film.stats);
        film.volume(TimeAxis::Real, EmissionMode::Delta, out);
        return stats.beamEstimates;
    };
    for (const bool points : {false, true}) {
        SCOPED_TRACE(points ? "point3d" : "beam2d");
        const auto make = [&]() -> std::unique_ptr<VolumeEstimator> {
            if (points) return std::make_unique<Point3DEstimator>();
            return std::make_unique<Beam2DEstimator>();
        };
        std::vector<double> plain, blocked;
        const int64_t nPlain = render(*make(), 1, plain);
        EXPECT_GT(nPlain, 3000);
        for (const int block : {4, 2}) {
            SCOPED_TRACE(block);
            EXPECT_EQ(render(*make(), block, blocked), nPlain);
            ASSERT_EQ(blocked.size(), plain.size());
            size_t differ = 0;
            for (size_t i = 0; i < plain.size(); ++i) differ += blocked[i] != plain[i];
            EXPECT_EQ(differ, 0u);
        }
    }
}
