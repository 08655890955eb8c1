// Tests of the photon pass's volume photons (photons/photon_tracer.h, PhotonPassParams::storePoints):
//  - off by default, and storing them changes nothing else: the same beams and surface photons bit
//    for bit (no random number is drawn for them), in grey and chromatic media;
//  - each point is the end of its photon's short beam of the same depth: position, direction, OPL,
//    region, and its weight is exactly the beam's power at its end divided by sigma_bar;
//  - the weight is unbiased: the track-length "fluence" integral Int_R phi dV over a region R, from
//    the points (sum of Phi_p over the points in R) equals the one from long beams and from short
//    beams (Int over the beam's part in R of its power along s), per channel, paired z-tests per
//    photon in a closed box of grey and of chromatic fog with multiple scattering; and, for the
//    uncollided photons of a point light in an unbounded medium, the closed form
//    P (e^{-sigma_t a} - e^{-sigma_t b}) / sigma_t over a shell a < |x| < b;
//  - the memory guard counts points;
//  - (issue 33) the deep Russian roulette ends photons that never lose weight and keeps the energy,
//    and the abort flag stops a pass inside a long photon.
#include "base/error.h"
#include "photons/photon_tracer.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <thread>

using namespace tpb;

namespace {

// A closed diffuse box (2 m) filled with fog, point light inside; `media` is the medium's JSON.
std::string boxScene(const std::string& medium) {
    return R"({
      "version": 1,
      "camera": {"position": [0, 1, 0.9], "look_at": [0, 1, 0], "fov": 40, "resolution": [8, 8]},
      "film": {"start_m": 0, "bin_width_m": 0.1, "bins": 8},
      "media": {"fog": )" +
           medium + R"(},
      "global_medium": "fog",
      "materials": {"white": {"type": "diffuse", "albedo": 0.7}},
      "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true}],
      "lights": [{"type": "point", "position": [0.2, 1.5, -0.1], "power": 10}],
      "render": {"photons_per_pass": 1000, "radius": 0.05, "seed": 5}
    })";
}

// A point light at the origin in an unbounded medium (no shapes).
std::string openScene(const std::string& medium) {
    return R"({
      "version": 1,
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 20, "resolution": [4, 4]},
      "film": {"start_m": 0, "bin_width_m": 0.1, "bins": 8},
      "media": {"m": )" +
           medium + R"(},
      "global_medium": "m",
      "lights": [{"type": "point", "position": [0, 0, 0], "power": 7}],
      "render": {"photons_per_pass": 1000, "radius": 0.05, "seed": 2}
    })";
}

const char* kGrey = R"({"sigma_s": 0.8, "sigma_a": 0.2, "g": 0.4})";
const char* kChromatic = R"({"sigma_s": [0.3, 0.9, 1.6], "sigma_a": [0.2, 0.1, 0.4], "g": -0.2})";

PhotonPassParams params(int64_t photons, int maxDepth, bool points, BeamLength length = BeamLength::Short) {
    PhotonPassParams p;
    p.seed = 11;
    p.pass = 3;
    p.photons = photons;
    p.maxDepth = maxDepth;
    p.storeBeams = true;
    p.storeSurfacePhotons = true;
    p.storePoints = points;
    p.beamLength = length;
    p.threads = 2;
    return p;
}

bool sameBeam(const Beam& a, const Beam& b) {
    return a.origin == b.origin && a.dir == b.dir && a.length == b.length && a.power == b.power && a.opl0 == b.opl0 &&
           a.region == b.region && a.depth == b.depth;
}
bool samePhoton(const SurfacePhoton& a, const SurfacePhoton& b) {
    return a.position == b.position && a.dirIn == b.dirIn && a.normal == b.normal && a.power == b.power &&
           a.opl == b.opl;
}

// The axis-aligned region R of the fluence integrals.
struct Box {
    Vec3 lo, hi;
    bool holds(const Vec3& p) const {
        return p.x > lo.x && p.x < hi.x && p.y > lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z;
    }
    // The part [t0, t1] of o + t d, t in [0, len], inside the box (slabs).
    std::optional<std::pair<double, double>> clip(const Vec3& o, const Vec3& d, double len) const {
        double t0 = 0.0, t1 = len;
        for (int a = 0; a < 3; ++a) {
            if (std::abs(d[a]) < 1e-300) {
                if (o[a] <= lo[a] || o[a] >= hi[a]) return std::nullopt;
                continue;
            }
            double u = (lo[a] - o[a]) / d[a], v = (hi[a] - o[a]) / d[a];
            if (u > v) std::swap(u, v);
            t0 = std::max(t0, u);
            t1 = std::min(t1, v);
        }
        if (!(t1 > t0)) return std::nullopt;
        return std::make_pair(t0, t1);
    }
};

// Int_{t0}^{t1} exp(-tau s) ds (tau may be negative or zero).
double expIntegral(double tau, double t0, double t1) {
    if (std::abs(tau) * (t1 - t0) < 1e-9) return (t1 - t0) * std::exp(-tau * 0.5 * (t0 + t1));
    return (std::exp(-tau * t0) - std::exp(-tau * t1)) / tau;
}

// Per-channel sums of x and x^2 over photons, for the mean and its standard error.
struct Moments {
    Color sum{0.0}, sum2{0.0};
    int64_t n = 0;
    void add(const Color& x) {
        sum += x;
        sum2 += x * x;
        ++n;
    }
    Color total() const { return sum; }  // the estimate of the integral (powers are divided by n)
    // Standard error of the total: n * sqrt(var / n).
    Color totalError() const {
        const double nn = static_cast<double>(n);
        const Color mean = sum / nn;
        const Color var = (sum2 / nn - mean * mean) * (nn / (nn - 1.0));
        return Color(std::sqrt(var.x * nn), std::sqrt(var.y * nn), std::sqrt(var.z * nn));
    }
};

}  // namespace

TEST(PhotonTracerPoints, OffByDefaultAndStoringThemChangesNothingElse) {
    EXPECT_FALSE(PhotonPassParams{}.storePoints);
    for (const char* medium : {kGrey, kChromatic}) {
        const test::TestScene sc = test::testSceneFrom(boxScene(medium));
        for (BeamLength length : {BeamLength::Short, BeamLength::Long}) {
            const PhotonMap off = tracePhotons(*sc, params(3000, 8, false, length));
            const PhotonMap on = tracePhotons(*sc, params(3000, 8, true, length));
            EXPECT_TRUE(off.points.empty());
            EXPECT_GT(on.points.size(), 3000u);
            ASSERT_EQ(off.beams.size(), on.beams.size());
            ASSERT_EQ(off.photons.size(), on.photons.size());
            for (size_t i = 0; i < off.beams.size(); ++i) ASSERT_TRUE(sameBeam(off.beams[i], on.beams[i])) << i;
            for (size_t i = 0; i < off.photons.size(); ++i) ASSERT_TRUE(samePhoton(off.photons[i], on.photons[i])) << i;
            EXPECT_EQ(off.emittedFlux, on.emittedFlux);
            EXPECT_EQ(off.rejected, on.rejected);
        }
        // Points alone (the point estimators store no beams): the same points.
        PhotonPassParams onlyPoints = params(3000, 8, true);
        onlyPoints.storeBeams = false;
        onlyPoints.storeSurfacePhotons = false;
        const PhotonMap a = tracePhotons(*sc, onlyPoints), b = tracePhotons(*sc, params(3000, 8, true));
        EXPECT_TRUE(a.beams.empty());
        ASSERT_EQ(a.points.size(), b.points.size());
        for (size_t i = 0; i < a.points.size(); ++i) {
            ASSERT_EQ(a.points[i].position, b.points[i].position) << i;
            ASSERT_EQ(a.points[i].power, b.points[i].power) << i;
        }
        // Threads do not change the order (fixed batches).
        PhotonPassParams one = params(3000, 8, true);
        one.threads = 1;
        const PhotonMap c = tracePhotons(*sc, one);
        ASSERT_EQ(c.points.size(), b.points.size());
        for (size_t i = 0; i < c.points.size(); ++i) ASSERT_EQ(c.points[i].opl, b.points[i].opl) << i;
    }
}

// Each point ends the short beam of its photon with the same depth, and weighs that beam's power at
// its end, Phi T(d) / Tbar(d), divided by sigma_bar (photon_tracer.h).
TEST(PhotonTracerPoints, EachPointEndsItsBeamWithTheSameDepthAndWeight) {
    for (const char* medium : {kGrey, kChromatic}) {
        const test::TestScene sc = test::testSceneFrom(boxScene(medium));
        const Medium& m = sc->regions[0].medium;
        const double sigmaBar = m.samplingSigma(), eta = sc->regions[0].ior;
        const PhotonPassParams p = params(400, 8, true);
        int64_t matched = 0, deeper = 0;
        for (int64_t i = 0; i < p.photons; ++i) {
            PhotonMap one;
            tracePhoton(*sc, p, i, one);
            // Beams that end at a scattering event, in order: exactly the points, in order.
            size_t k = 0;
            for (const Beam& b : one.beams) {
                const Vec3 end = b.origin + b.length * b.dir;
                if (k < one.points.size() &&
                    glm::length(one.points[k].position - end) < 1e-9 * (1.0 + glm::length(end))) {
                    const VolumePhoton& v = one.points[k];
                    EXPECT_EQ(v.depth, b.depth);
                    EXPECT_EQ(v.region, b.region);
                    EXPECT_EQ(v.dirIn, b.dir);
                    EXPECT_NEAR(v.opl, b.opl0 + eta * b.length, 1e-12 * (1.0 + v.opl));
                    for (int c = 0; c < 3; ++c) {
                        const double atEnd =
                            b.power[c] * std::exp(-m.sigma_t[c] * b.length) / std::exp(-sigmaBar * b.length);
                        EXPECT_NEAR(v.power[c], atEnd / sigmaBar, 1e-12 * v.power[c]) << "channel " << c;
                    }
                    if (v.depth > 0) ++deeper;
                    ++k;
                    ++matched;
                }
            }
            EXPECT_EQ(k, one.points.size()) << "photon " << i << ": a point that ends no beam";
        }
        EXPECT_GT(matched, 800);
        EXPECT_GT(deeper, 400);  // multiple scattering and bounces off the walls are covered
    }
}

// The points' weight is unbiased: the integral of the fluence over a region R from the points equals
// the one from long and from short beams, per channel, photon by photon on the same photon paths
// (paired z-test: the three estimators see the same random numbers). Multiple scattering, walls.
TEST(PhotonTracerPoints, PointsEstimateTheSameFluenceAsLongAndShortBeams) {
    const Box region{Vec3(-0.6, 0.3, -0.5), Vec3(0.4, 1.2, 0.5)};
    for (const char* medium : {kGrey, kChromatic}) {
        const test::TestScene sc = test::testSceneFrom(boxScene(medium));
        const Medium& m = sc->regions[0].medium;
        const double sigmaBar = m.samplingSigma();
        const PhotonPassParams shortP = params(500000, 12, true), longP = params(500000, 12, false, BeamLength::Long);
        Moments points, longBeams, shortBeams, dLong, dShort;
        for (int64_t i = 0; i < shortP.photons; ++i) {
            PhotonMap s, l;
            tracePhoton(*sc, shortP, i, s);
            tracePhoton(*sc, longP, i, l);
            Color xp(0.0), xl(0.0), xs(0.0);
            for (const VolumePhoton& v : s.points)
                if (region.holds(v.position)) xp += v.power;
            const auto beamPart = [&](const Beam& b, const Color& tau) {
                const auto in = region.clip(b.origin, b.dir, b.length);
                if (!in) return Color(0.0);
                return b.power * Color(expIntegral(tau.x, in->first, in->second),
                                       expIntegral(tau.y, in->first, in->second),
                                       expIntegral(tau.z, in->first, in->second));
            };
            for (const Beam& b : l.beams) xl += beamPart(b, m.sigma_t);
            for (const Beam& b : s.beams) xs += beamPart(b, m.sigma_t - Color(sigmaBar));
            points.add(xp);
            longBeams.add(xl);
            shortBeams.add(xs);
            dLong.add(xp - xl);
            dShort.add(xp - xs);
        }
        for (int c = 0; c < 3; ++c) {
            const double total = longBeams.total()[c];
            const double zLong = dLong.total()[c] / dLong.totalError()[c];
            const double zShort = dShort.total()[c] / dShort.totalError()[c];
            std::printf(
                "%s channel %d: fluence integral points %.5f +- %.5f, long beams %.5f, short beams %.5f (z %.2f, "
                "%.2f)\n",
                medium == kGrey ? "grey" : "chromatic", c, points.total()[c], points.totalError()[c], total,
                shortBeams.total()[c], zLong, zShort);
            EXPECT_LT(std::abs(zLong), 4.0) << "channel " << c;
            EXPECT_LT(std::abs(zShort), 4.0) << "channel " << c;
            // The test resolves a few percent: the difference's error is well below 1% of the value.
            EXPECT_LT(dLong.totalError()[c], 0.005 * total) << "channel " << c;
        }
    }
}

// Uncollided photons of a point light of power P in an unbounded medium: the fluence is
// P e^{-sigma_t d} / (4 pi d^2), whose integral over the shell a < d < b is
// P (e^{-sigma_t a} - e^{-sigma_t b}) / sigma_t per channel; the depth-0 points estimate it.
TEST(PhotonTracerPoints, UncollidedPointsMatchTheClosedFormInAnUnboundedMedium) {
    for (const char* medium : {kGrey, kChromatic}) {
        const test::TestScene sc = test::testSceneFrom(openScene(medium));
        const Medium& m = sc->regions[0].medium;
        const double P = sc->lights[0].power.x, a = 0.3, b = 1.7;
        const PhotonPassParams p = params(200000, 1, true);
        Moments est;
        for (int64_t i = 0; i < p.photons; ++i) {
            PhotonMap one;
            tracePhoton(*sc, p, i, one);
            Color x(0.0);
            for (const VolumePhoton& v : one.points) {
                EXPECT_EQ(v.depth, 0u);
                const double d = glm::length(v.position);
                EXPECT_NEAR(v.opl, d, 1e-9);
                if (d > a && d < b) x += v.power;
            }
            est.add(x);
        }
        for (int c = 0; c < 3; ++c) {
            const double st = m.sigma_t[c];
            const double exact = P * (std::exp(-st * a) - std::exp(-st * b)) / st;
            const double z = (est.total()[c] - exact) / est.totalError()[c];
            std::printf("%s channel %d: shell fluence integral %.5f +- %.5f, closed form %.5f (z %.2f)\n",
                        medium == kGrey ? "grey" : "chromatic", c, est.total()[c], est.totalError()[c], exact, z);
            EXPECT_LT(std::abs(z), 4.0) << "channel " << c;
            EXPECT_LT(est.totalError()[c], 0.005 * exact) << "channel " << c;
        }
    }
}

TEST(PhotonTracerPoints, MemoryGuardCountsPoints) {
    const test::TestScene sc = test::testSceneFrom(boxScene(kGrey));
    PhotonPassParams p = params(2000, 8, true);
    p.storeBeams = false;
    p.storeSurfacePhotons = false;
    p.maxMapBytes = 100 * sizeof(VolumePhoton);
    EXPECT_THROW(tracePhotons(*sc, p), UserError);
    p.storePoints = false;  // nothing stored: nothing to guard
    EXPECT_NO_THROW(tracePhotons(*sc, p));
}

// ---- issue 33 item 5: paths that never lose weight end, and a pass stops at Ctrl-C -------------------

namespace {

// A closed box (2 m) of walls with albedo `wallAlbedo`, filled with a lossless fog (sigma_s 2 /m,
// albedo 1), a point light inside: with white walls nothing is ever absorbed.
std::string furnaceScene(double wallAlbedo, bool fog = true) {
    return std::string(R"({"version": 1,
      "camera": {"position": [0, 0, 0.9], "look_at": [0, 0, 0], "fov": 60, "resolution": [8, 8]},
      "film": {"start_m": 0, "bin_width_m": 0.25, "bins": 8},)") +
           (fog ? R"("media": {"m": {"sigma_s": 2.0}}, "global_medium": "m",)" : "") + R"(
      "materials": {"wall": {"type": "diffuse", "albedo": )" +
           std::to_string(wallAlbedo) + R"(}},
      "shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": "wall", "flip_normals": true}],
      "lights": [{"type": "point", "position": [0.2, 0.1, -0.3], "power": 2}],
      "render": {"photons_per_pass": 2000, "seed": 8}})";
}

}  // namespace

// max_depth 1e6 (a Mitsuba user's "unbounded") in an albedo-1 box full of albedo-1 fog: the weight
// never drops, so the throughput roulette never fires. The deep rule (russianRoulette from
// kDeepRouletteDepth events, survival 0.95) ends every photon: events per photon are
// 64 + Geometric(0.05), mean 64 + 19 = 83, and each event is the end of one fog segment (a beam).
// Before it, photon 0 alone ran to 1e6 events: the 64 MiB guard stopped the pass (UserError).
TEST(PhotonTracerDeepRoulette, AlbedoOneBoxWithAHugeMaxDepthEndsEveryPhoton) {
    const test::TestScene sc = test::testSceneFrom(furnaceScene(1.0));
    PhotonPassParams p = params(2000, 1000000, false);
    p.maxMapBytes = 64u << 20;
    PhotonMap map;
    ASSERT_NO_THROW(map = tracePhotons(*sc, p));
    EXPECT_EQ(map.emitted, p.photons);
    EXPECT_FALSE(map.aborted);
    const double q = kDeepRouletteSurvival;
    const double meanEvents = kDeepRouletteDepth + q / (1.0 - q);
    const double sigmaMean = std::sqrt(q) / (1.0 - q) / std::sqrt(double(p.photons));
    const double beamsPerPhoton = double(map.beams.size()) / double(p.photons);
    uint32_t deepest = 0;
    for (const Beam& b : map.beams) deepest = std::max(deepest, b.depth);
    std::printf(
        "albedo-1 box, max_depth 1e6: %.2f beams/photon (expect %.2f +- %.2f), %.2f surface photons/photon, "
        "deepest event %u, %.1f MB\n",
        beamsPerPhoton, meanEvents, sigmaMean, double(map.photons.size()) / p.photons, deepest,
        storedMapBytes(map) / 1e6);
    EXPECT_NEAR(beamsPerPhoton, meanEvents, 5.0 * sigmaMean);
    EXPECT_LT(deepest, 1000u);  // P(one photon past 1000) = 0.95^936 ~ 1e-21
}

// The deep rule is unbiased: in a lossy box (walls 0.8, lossless fog) where it acts at every fog
// event (rouletteDepth 1: survival 0.95, weight / 0.95), the energy landing on the walls, Phi (1 +
// rho + rho^2 + ...) = Phi / (1 - rho) = 5 Phi, and the fog's track length sum(P_b len_b) agree
// with the same pass without it (rouletteDepth off) and, for the landed energy, with the closed
// form; z-tests on per-photon sums (max_depth 1000 truncates nothing measurable: rho^1000/3).
TEST(PhotonTracerDeepRoulette, EndingFullWeightPathsKeepsTheEnergy) {
    const test::TestScene sc = test::testSceneFrom(furnaceScene(0.8));
    struct Tally {
        double landed = 0.0, landed2 = 0.0, track = 0.0, track2 = 0.0, events = 0.0;
    };
    const auto run = [&](int rouletteDepth) {
        PhotonPassParams p = params(20000, 1000, false);
        p.rouletteDepth = rouletteDepth;
        Tally t;
        PhotonMap one;
        for (int64_t i = 0; i < p.photons; ++i) {
            one.clear();
            tracePhoton(*sc, p, i, one);
            double landed = 0.0, track = 0.0;
            for (const SurfacePhoton& ph : one.photons) landed += ph.power.x;
            for (const Beam& b : one.beams) track += b.power.x * b.length;
            t.landed += landed;
            t.landed2 += landed * landed;
            t.track += track;
            t.track2 += track * track;
            t.events += double(one.beams.size());
        }
        return t;
    };
    const Tally off = run(std::numeric_limits<int>::max()), deep = run(1);
    const double n = 20000.0, phi = 2.0;
    const auto var = [&](double s, double s2) { return (s2 - s * s / n) / (n - 1.0) * n; };  // of the sum
    const double zLanded =
        (deep.landed - off.landed) / std::sqrt(var(deep.landed, deep.landed2) + var(off.landed, off.landed2));
    const double zTrack =
        (deep.track - off.track) / std::sqrt(var(deep.track, deep.track2) + var(off.track, off.track2));
    const double zClosed = (deep.landed - phi / (1.0 - 0.8)) / std::sqrt(var(deep.landed, deep.landed2));
    std::printf(
        "deep roulette: landed %.4f vs %.4f without vs %.4f closed form (z %.2f, %.2f); track %.4f vs %.4f "
        "(z %.2f); %.1f vs %.1f events/photon\n",
        deep.landed / phi, off.landed / phi, 1.0 / (1.0 - 0.8), zLanded, zClosed, deep.track, off.track, zTrack,
        deep.events / n, off.events / n);
    EXPECT_LT(deep.events, 0.8 * off.events);  // the deep rule did act
    EXPECT_LT(std::abs(zLanded), 4.0);
    EXPECT_LT(std::abs(zTrack), 4.0);
    EXPECT_LT(std::abs(zClosed), 4.0);
}

// Ctrl-C inside a pass: the abort flag is read within a photon too, not only between batches of
// 1024. One photon in a white box (no fog, nothing stored) with the deep rule off and max_depth
// 2e7 bounces would run for seconds; a flag set from another thread after 20 ms stops it, the pass
// returns marked aborted with the photon not counted. (Before: the flag was read only between
// batches, so this pass ran all 2e7 bounces and returned a complete photon.)
TEST(PhotonTracerDeepRoulette, AbortStopsALongPhotonInsideThePass) {
    const test::TestScene sc = test::testSceneFrom(furnaceScene(1.0, false));
    PhotonPassParams p = params(1, 20000000, false);
    p.rouletteDepth = std::numeric_limits<int>::max();
    p.storeSurfacePhotons = false;
    p.threads = 1;
    std::atomic<bool> abort{false};
    std::thread ctrlC([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        abort = true;
    });
    const PhotonMap map = tracePhotons(*sc, p, &abort);
    ctrlC.join();
    EXPECT_TRUE(map.aborted);
    EXPECT_EQ(map.emitted, 0);
    // With the flag already set nothing is handed out (aborted); with it clear the pass completes.
    p.maxDepth = 5000;
    const PhotonMap none = tracePhotons(*sc, p, &abort);
    EXPECT_TRUE(none.aborted);
    EXPECT_EQ(none.emitted, 0);
    abort = false;
    const PhotonMap done = tracePhotons(*sc, p, &abort);
    EXPECT_FALSE(done.aborted);
    EXPECT_EQ(done.emitted, 1);
}
