// Consistency tests of the photon-beam accelerators (accel/beam_accel.h): the brute-force list of
// every piece is the oracle for Embree's BVH. With random beams (lengths from far below to far above
// the kernel radius, several regions) and random camera segments (finite and infinite sMax;
// directions parallel, anti-parallel and grazing to a beam; ends just past a kernel), fixed seeds:
//   (a) Embree's candidates contain every piece whose kernel cylinder the segment overlaps
//       (rayBeamOverlap with the accelerator's radius, applied to the brute-force list);
//   (b) both backends return candidates sorted by (beam, piece), without duplicates, only of the
//       queried region, with the same piece ranges;
//   (c) after the overlap test both backends give exactly the same pieces;
//   (d) beamPieceCount stays in 1..16 and a beam's pieces tile [0, length] exactly.
// Photon points (zero-length pieces, the point estimators): Embree's candidates contain every point
// within the radius of the segment and both backends agree after that test, also after a rebuild
// from beams to points and back.
// Also: a rebuild replaces the beams; the shared Embree device (scene/embree_device.h) turns an Embree error into an EmbreeError.
#include "accel/beam_accel.h"
#include "base/rng.h"
#include "estimators/beam2d.h"
#include "estimators/point3d.h"
#include "scene/embree_device.h"

#include <embree3/rtcore.h>  // only to provoke an Embree error in the device test

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

using namespace tpb;

namespace {

constexpr int kRegions = 3;

Vec3 randomDir(Rng& rng) {
    const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * kPi * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
}

Vec3 randomPoint(Rng& rng, double halfSize) {
    return Vec3((2.0 * rng.uniform() - 1.0) * halfSize, (2.0 * rng.uniform() - 1.0) * halfSize,
                (2.0 * rng.uniform() - 1.0) * halfSize);
}

// A unit vector perpendicular to unit w.
Vec3 perpendicular(const Vec3& w, Rng& rng) {
    Vec3 p;
    do p = glm::cross(w, randomDir(rng));
    while (glm::length(p) < 1e-3);
    return glm::normalize(p);
}

// Random or axis-aligned directions, lengths from 1e-4 r to 1e4 r (1 to 16 pieces), regions 0..kRegions-1 (region 2 rarer).
std::vector<Beam> randomBeams(Rng& rng, size_t count, double radius) {
    std::vector<Beam> beams;
    for (size_t i = 0; i < count; ++i) {
        Beam b{};
        b.origin = randomPoint(rng, 2.0);
        b.dir = randomDir(rng);
        if (rng.uniform() < 0.15) {  // along an axis: the kernel cylinder touches its box's faces
            b.dir = Vec3(0.0);
            b.dir[static_cast<int>(rng.uniform() * 3)] = rng.uniform() < 0.5 ? 1.0 : -1.0;
        }
        b.length = radius * std::pow(10.0, -4.0 + 8.0 * rng.uniform());
        b.power = Color(1.0);
        b.opl0 = 0.0;
        const double u = rng.uniform();
        b.region = u < 0.5 ? 0 : (u < 0.9 ? 1 : 2);
        b.depth = 0;
        beams.push_back(b);
    }
    return beams;
}

struct Segment {
    Vec3 o, d;
    double sMax;
    int region;
};

// Camera segments, many of them placed against one beam to reach the kernel's edges.
Segment randomSegment(Rng& rng, const std::vector<Beam>& beams, double radius) {
    const Beam& b = beams[static_cast<size_t>(rng.uniform() * beams.size())];
    Segment s;
    s.region = rng.uniform() < 0.8 ? b.region : static_cast<int>(rng.uniform() * kRegions);
    const double sb = rng.uniform() * b.length;  // a point of the beam's axis
    const Vec3 side = perpendicular(b.dir, rng);
    const int kind = static_cast<int>(rng.uniform() * 6);
    switch (kind) {
        case 0:  // anywhere
            s.o = randomPoint(rng, 3.0);
            s.d = randomDir(rng);
            break;
        case 1:  // parallel or anti-parallel, inside the cylinder or just outside it
        case 2: {
            const double dist = radius * (rng.uniform() < 0.5 ? rng.uniform() : 1.0 + (rng.uniform() - 0.5) * 1e-6);
            s.d = kind == 1 ? b.dir : -b.dir;
            s.o = b.origin + (3.0 * rng.uniform() - 1.0) * b.length * b.dir + dist * side;  // before, on or after it
            break;
        }
        case 3: {  // grazing: crosses the axis' perpendicular plane at a distance within 1e-6 r of r
            const Vec3 across = glm::normalize(glm::cross(b.dir, side));
            const double mix = rng.uniform() * 0.2;  // mostly perpendicular to the beam, slightly tilted
            s.d = glm::normalize(across + mix * b.dir);
            const Vec3 touch = b.origin + sb * b.dir + radius * (1.0 + (rng.uniform() - 0.5) * 2e-6) * side;
            s.o = touch - (0.5 + 2.0 * rng.uniform()) * s.d;
            break;
        }
        case 4: {  // through the kernel, from far away
            const Vec3 target = b.origin + sb * b.dir + radius * rng.uniform() * side;
            s.d = randomDir(rng);
            s.o = target - (0.01 + 5.0 * rng.uniform()) * s.d;
            break;
        }
        default: {  // nearly along the beam (small angles)
            s.d = glm::normalize(b.dir + 1e-4 * std::pow(10.0, 3.0 * rng.uniform()) * side);
            if (rng.uniform() < 0.5) s.d = -s.d;
            s.o = b.origin + sb * b.dir - rng.uniform() * 3.0 * s.d + radius * rng.uniform() * side;
            break;
        }
    }
    // sMax: infinite, random, or ending just past where the segment enters the beam's kernel.
    const double u = rng.uniform();
    if (u < 0.3) {
        s.sMax = kInf;
    } else if (u < 0.7) {
        s.sMax = 6.0 * rng.uniform();
    } else {
        RayBeamOverlap ov;
        s.sMax = rayBeamOverlap(s.o, s.d, kInf, b.origin, b.dir, b.length, radius, ov)
                     ? ov.sMinus + radius * std::pow(10.0, -9.0 + 8.0 * rng.uniform())
                     : 6.0 * rng.uniform();
    }
    return s;
}

using Key = std::tuple<uint32_t, uint32_t, double, double>;
Key key(const BeamPiece& p) { return {p.beam, p.piece, p.sbLo, p.sbHi}; }

void expectSortedUniqueOfRegion(const std::vector<BeamPiece>& c, const std::vector<Beam>& beams, int region,
                                const char* backend) {
    for (size_t i = 0; i < c.size(); ++i) {
        ASSERT_LT(c[i].beam, beams.size()) << backend;
        EXPECT_EQ(beams[c[i].beam].region, region) << backend;
        if (i > 0) {
            const bool increasing =
                c[i - 1].beam < c[i].beam || (c[i - 1].beam == c[i].beam && c[i - 1].piece < c[i].piece);
            EXPECT_TRUE(increasing) << backend << ": candidates " << i - 1 << ", " << i
                                    << " out of (beam, piece) order";
        }
    }
}

std::vector<Key> overlapping(const std::vector<BeamPiece>& c, const std::vector<Beam>& beams, const Segment& s,
                             double radius) {
    std::vector<Key> out;
    for (const BeamPiece& p : c) {
        const Beam& b = beams[p.beam];
        RayBeamOverlap ov;
        if (rayBeamOverlap(s.o, s.d, s.sMax, b.origin, b.dir, p.sbLo, p.sbHi, radius, ov)) out.push_back(key(p));
    }
    return out;
}

struct Counts {
    size_t queries = 0, overlaps = 0, candidatesEmbree = 0, candidatesBrute = 0;
};

// `rebuild`: both accelerators are first built over other beams (the estimator keeps one accelerator
// across passes), so the comparison also checks that a build replaces the previous one.
// `indexed`: the backend compared with brute force (Embree's BVH or ours).
Counts compareBackends(AccelBackend indexed, uint64_t seed, size_t beamCount, double radius, size_t queries,
                       bool rebuild = false) {
    Rng rng(seed, Stream::Test, 0, 0);
    auto brute = BeamAccel::create(AccelBackend::BruteForce);
    auto embree = BeamAccel::create(indexed);
    const std::vector<Beam> previous = rebuild ? randomBeams(rng, beamCount, 2.0 * radius) : std::vector<Beam>{};
    if (rebuild) {
        brute->build(previous, 2.0 * radius, 1);
        embree->build(previous, 2.0 * radius, 1);
    }
    const std::vector<Beam> beams = randomBeams(rng, beamCount, radius);
    brute->build(beams, radius, 1);
    embree->build(beams, radius, 1);
    EXPECT_EQ(brute->pieceCount(), embree->pieceCount());
    Counts n;
    std::vector<BeamPiece> cb, ce;
    for (size_t q = 0; q < queries; ++q) {
        const Segment s = randomSegment(rng, beams, radius);
        cb.clear();
        ce.clear();
        brute->candidates(s.o, s.d, s.sMax, s.region, cb);
        embree->candidates(s.o, s.d, s.sMax, s.region, ce);
        expectSortedUniqueOfRegion(cb, beams, s.region, "brute-force");
        expectSortedUniqueOfRegion(ce, beams, s.region, embree->name().c_str());
        // (b) Embree's pieces are the brute-force ones (same ranges), i.e. a subset of them.
        size_t j = 0;
        for (const BeamPiece& p : ce) {
            while (j < cb.size() && key(cb[j]) < key(p)) ++j;
            EXPECT_TRUE(j < cb.size() && key(cb[j]) == key(p))
                << "Embree piece (" << p.beam << ", " << p.piece << ") is not a brute-force piece";
        }
        // (a) + (c): every overlapping piece is an Embree candidate; after the test the sets agree.
        const std::vector<Key> ob = overlapping(cb, beams, s, radius), oe = overlapping(ce, beams, s, radius);
        EXPECT_EQ(ob, oe) << "query " << q << " (seed " << seed << "): o " << s.o.x << " " << s.o.y << " " << s.o.z
                          << ", d " << s.d.x << " " << s.d.y << " " << s.d.z << ", sMax " << s.sMax;
        if (ob != oe) break;  // one failing query is enough to read
        ++n.queries;
        n.overlaps += ob.size();
        n.candidatesEmbree += ce.size();
        n.candidatesBrute += cb.size();
    }
    return n;
}

}  // namespace

// Embree's BVH and ours (accel/piece_bvh.h) against brute force.
TEST(BeamAccel, IndexedCandidatesContainEveryOverlapAndMatchBruteForce) {
    for (AccelBackend indexed : {AccelBackend::Embree, AccelBackend::Bvh}) {
        const double radii[] = {0.01, 0.05, 0.3};
        Counts total;
        for (int i = 0; i < 3; ++i) {
            const Counts n = compareBackends(indexed, 1000 + i, 300, radii[i], 3000);
            EXPECT_EQ(n.queries, 3000u);
            total.overlaps += n.overlaps;
            total.candidatesEmbree += n.candidatesEmbree;
            total.candidatesBrute += n.candidatesBrute;
        }
        // The comparison is not vacuous: many overlaps found, and the hierarchy culls most pieces.
        EXPECT_GT(total.overlaps, 3000u);
        EXPECT_LT(total.candidatesEmbree, total.candidatesBrute / 10);
    }
}

// boxCandidates (the raw list a batched test reads): for both backends, sorted and made unique it
// is candidates() without a test, and its axes are the beams' axes and the pieces' ranges, bit for bit.
TEST(BeamAccel, BoxCandidatesAreTheUntestedCandidatesWithTheirAxes) {
    Rng rng(3000, Stream::Test, 0, 0);
    const double radius = 0.05;
    const std::vector<Beam> beams = randomBeams(rng, 300, radius);
    size_t listed = 0;
    for (AccelBackend backend : {AccelBackend::BruteForce, AccelBackend::Embree, AccelBackend::Bvh}) {
        auto accel = BeamAccel::create(backend);
        accel->build(beams, radius, 1);
        for (int q = 0; q < 500; ++q) {
            const Segment s = randomSegment(rng, beams, radius);
            std::vector<BeamPiece> want, box;
            PieceAxes axes;
            accel->candidates(s.o, s.d, s.sMax, s.region, want);
            accel->boxCandidates(s.o, s.d, s.sMax, s.region, box, axes);
            ASSERT_EQ(axes.size(), box.size());
            for (size_t i = 0; i < box.size(); ++i) {
                const Beam& b = beams[box[i].beam];
                EXPECT_TRUE(axes.ox[i] == b.origin.x && axes.oy[i] == b.origin.y && axes.oz[i] == b.origin.z);
                EXPECT_TRUE(axes.dx[i] == b.dir.x && axes.dy[i] == b.dir.y && axes.dz[i] == b.dir.z);
                EXPECT_TRUE(axes.lo[i] == box[i].sbLo && axes.hi[i] == box[i].sbHi);
            }
            sortBeamPieces(box, 0);
            ASSERT_EQ(box.size(), want.size()) << "query " << q;
            for (size_t i = 0; i < box.size(); ++i) EXPECT_EQ(key(box[i]), key(want[i])) << "query " << q;
            listed += box.size();
        }
    }
    EXPECT_GT(listed, 1000u);
}

TEST(BeamAccel, RebuildReplacesTheBeams) {
    for (AccelBackend indexed : {AccelBackend::Embree, AccelBackend::Bvh}) {
        const Counts n = compareBackends(indexed, 2000, 200, 0.05, 2000, /*rebuild=*/true);
        EXPECT_EQ(n.queries, 2000u);
        EXPECT_GT(n.overlaps, 500u);
    }
}

TEST(BeamAccel, EmptyBeamListAndRegionsWithoutBeams) {
    for (AccelBackend backend : {AccelBackend::Embree, AccelBackend::BruteForce, AccelBackend::Bvh}) {
        auto accel = BeamAccel::create(backend);
        std::vector<BeamPiece> c;
        const std::vector<Beam> none;
        accel->build(none, 0.1, 1);
        EXPECT_EQ(accel->pieceCount(), 0u);
        accel->candidates(Vec3(0.0), Vec3(0.0, 0.0, 1.0), kInf, 0, c);
        EXPECT_TRUE(c.empty());

        Beam b{};
        b.origin = Vec3(0.0, 0.0, 1.0);
        b.dir = Vec3(1.0, 0.0, 0.0);
        b.length = 1.0;
        b.region = 1;
        const std::vector<Beam> one = {b};
        accel->build(one, 0.1, 1);
        accel->candidates(Vec3(0.5, 0.0, 0.0), Vec3(0.0, 0.0, 1.0), kInf, 0, c);
        EXPECT_TRUE(c.empty()) << "region 0 has no beams";
        accel->candidates(Vec3(0.5, 0.0, 0.0), Vec3(0.0, 0.0, 1.0), kInf, 1, c);
        ASSERT_EQ(c.size(), 1u);
        EXPECT_EQ(c[0].beam, 0u);
        EXPECT_EQ(c[0].sbHi, 1.0);
    }
}

TEST(BeamAccel, PieceCountBoundsAndPiecesTileTheBeam) {
    // (d) 1..16 pieces, whatever the length and radius (zero, tiny, huge, infinite ratio).
    const double radii[] = {0.0, 1e-300, 1e-12, 1e-3, 0.05, 1.0, 1e6};
    const double lengths[] = {0.0, 1e-300, 1e-9, 1e-3, 0.3, 0.8, 1.0, 7.0, 1e3, 1e9};
    for (double r : radii) {
        for (double L : lengths) {
            const uint32_t n = beamPieceCount(L, r);
            EXPECT_GE(n, 1u) << "L " << L << " r " << r;
            EXPECT_LE(n, 16u) << "L " << L << " r " << r;
        }
    }
    EXPECT_EQ(beamPieceCount(16.0 * 0.05 * 3.5, 0.05), 4u);  // ceil(L / 16 r)
    EXPECT_EQ(beamPieceCount(1e3, 0.05), 16u);

    // The pieces the accelerator hands out tile [0, length]: first starts at 0, each ends where the
    // next starts, the last ends at the length exactly.
    Rng rng(7, Stream::Test, 0, 0);
    const double radius = 0.02;
    const std::vector<Beam> beams = randomBeams(rng, 400, radius);
    auto brute = BeamAccel::create(AccelBackend::BruteForce);
    brute->build(beams, radius, 1);
    std::vector<BeamPiece> all;
    for (int region = 0; region < kRegions; ++region)
        brute->candidates(Vec3(0.0), Vec3(1.0, 0.0, 0.0), kInf, region, all);
    size_t expectedPieces = 0;
    for (const Beam& b : beams) expectedPieces += beamPieceCount(b.length, radius);
    ASSERT_EQ(all.size(), expectedPieces);
    EXPECT_EQ(brute->pieceCount(), expectedPieces);
    std::vector<std::vector<BeamPiece>> perBeam(beams.size());
    for (const BeamPiece& p : all) perBeam[p.beam].push_back(p);
    bool sawSixteen = false, sawOne = false;
    for (size_t i = 0; i < beams.size(); ++i) {
        const std::vector<BeamPiece>& ps = perBeam[i];
        ASSERT_EQ(ps.size(), beamPieceCount(beams[i].length, radius)) << "beam " << i;
        sawSixteen |= ps.size() == 16;
        sawOne |= ps.size() == 1;
        EXPECT_EQ(ps.front().sbLo, 0.0);
        EXPECT_EQ(ps.back().sbHi, beams[i].length);
        for (size_t k = 0; k < ps.size(); ++k) {
            EXPECT_EQ(ps[k].piece, k);
            EXPECT_LT(ps[k].sbLo, ps[k].sbHi) << "beam " << i << " piece " << k;
            if (k > 0) {
                EXPECT_EQ(ps[k - 1].sbHi, ps[k].sbLo) << "beam " << i << " piece " << k;
            }
        }
    }
    EXPECT_TRUE(sawSixteen && sawOne);
}

// Points: the kernels of point2d / point3d are zero farther than r from the point; a point is a
// true overlap when the ball around it meets the segment (rayPointChord).
TEST(BeamAccel, PointCandidatesContainEveryPointNearTheSegmentAndMatchBruteForce) {
    Rng rng(3000, Stream::Test, 0, 0);
    const double radius = 0.05;
    // Points clustered near the beams' axes of randomBeams (so that segments aimed at a beam meet many).
    const std::vector<Beam> beams = randomBeams(rng, 300, radius);
    std::vector<VolumePhoton> points;
    for (const Beam& b : beams)
        for (int k = 0; k < 4; ++k) {
            VolumePhoton v{};
            v.position =
                b.origin + rng.uniform() * b.length * b.dir + 2.0 * radius * (rng.uniform() - 0.5) * randomDir(rng);
            v.dirIn = b.dir;
            v.power = Color(1.0);
            v.region = b.region;
            points.push_back(v);
        }
    for (AccelBackend indexed : {AccelBackend::Embree, AccelBackend::Bvh})
        for (int round = 0; round < 2; ++round) {
            auto brute = BeamAccel::create(AccelBackend::BruteForce);
            auto embree = BeamAccel::create(indexed);  // round 1: rebuilt over beams in between
            if (round == 1) {
                brute->build(beams, radius, 1);
                embree->build(beams, radius, 1);
            }
            brute->build(points, radius, 1);
            embree->build(points, radius, 1);
            ASSERT_EQ(brute->pieceCount(), points.size());
            ASSERT_EQ(embree->pieceCount(), points.size());
            size_t overlaps = 0, candidatesEmbree = 0, candidatesBrute = 0;
            std::vector<BeamPiece> cb, ce;
            Rng qrng(3100 + round, Stream::Test, 0, 0);  // the same queries for both backends
            for (int q = 0; q < 3000; ++q) {
                const Segment s = randomSegment(qrng, beams, radius);
                cb.clear();
                ce.clear();
                brute->candidates(s.o, s.d, s.sMax, s.region, cb);
                embree->candidates(s.o, s.d, s.sMax, s.region, ce);
                const auto near = [&](const std::vector<BeamPiece>& c) {
                    std::vector<uint32_t> out;
                    for (size_t i = 0; i < c.size(); ++i) {
                        EXPECT_EQ(c[i].piece, 0u);
                        EXPECT_EQ(c[i].sbLo, 0.0);
                        EXPECT_EQ(c[i].sbHi, 0.0);
                        EXPECT_EQ(points[c[i].beam].region, s.region);
                        if (i > 0) {
                            EXPECT_LT(c[i - 1].beam, c[i].beam);
                        }
                        if (rayPointChord(s.o, s.d, s.sMax, points[c[i].beam].position, radius))
                            out.push_back(c[i].beam);
                    }
                    return out;
                };
                const std::vector<uint32_t> nb = near(cb), ne = near(ce);
                ASSERT_EQ(nb, ne) << "query " << q;
                overlaps += nb.size();
                candidatesEmbree += ce.size();
                candidatesBrute += cb.size();
            }
            EXPECT_GT(overlaps, 1500u);
            EXPECT_LT(candidatesEmbree, candidatesBrute / 10);
        }
}

TEST(EmbreeDevice, OneDeviceAndErrorsThrowWithTheirCode) {
    const EmbreeDeviceHandle device = embreeDevice();
    ASSERT_NE(device, nullptr);
    EXPECT_EQ(embreeDevice(), device);
    EXPECT_NO_THROW(checkEmbree("doing nothing"));
    // An invalid call: Embree reports it through the error function, checkEmbree throws it.
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_REFIT);  // invalid for a scene (Embree 3.13: UNKNOWN)
    try {
        checkEmbree("setting an invalid build quality");
        ADD_FAILURE() << "no EmbreeError thrown";
    } catch (const EmbreeError& e) {
        EXPECT_EQ(e.code(), static_cast<int>(RTC_ERROR_UNKNOWN));
        const std::string what = e.what();
        EXPECT_NE(what.find("setting an invalid build quality"), std::string::npos) << what;
        EXPECT_NE(what.find("RTC_ERROR_UNKNOWN"), std::string::npos) << what;      // the code
        EXPECT_NE(what.find("invalid build quality"), std::string::npos) << what;  // Embree's message
        EXPECT_NE(what.find("report it"), std::string::npos) << what;              // the hint
    }
    EXPECT_NO_THROW(checkEmbree("after the error was reported"));
    rtcReleaseScene(scene);
}
