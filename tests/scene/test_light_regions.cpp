// Where light starts, and where it cannot go (issue 12, items 2, 3 and 16):
//  - an area light's photons start in the region of the point they leave from: fog in an invisible
//    (null) box around the light gives the image of the same fog everywhere, a light across a fog
//    box's face emits into it from its inside part only, a light on the inside of the box's ceiling
//    emits into it;
//  - a light inside a closed opaque box lights nothing outside it: no photon and no beam is stored
//    outside, and the beam renderer's and the path tracer's images of the outside (the box, a
//    ceiling 5 cm above it, a floor below) are exactly zero, for a point light in fog and for an
//    area light filling the ceiling of a rotated box;
//  - the pieces behind that: bounce origins at the edges of a box, which surface points see each
//    other (convex, concave, flat, across a wall), the region stack's capacity (refused nesting,
//    counted overflows).
// Inside/outside is decided here with the test's own rotation (Rodrigues), not with the renderer's
// geometry.
#include "support/path_tracer_passes.h"
#include "render/driver.h"
#include "base/error.h"
#include "integrators/path_tracer.h"
#include "photons/photon_tracer.h"
#include "scene/scene_loader.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

using namespace tpb;

namespace {

constexpr double kPiT = 3.14159265358979323846;

test::TestScene sceneFrom(const std::string& json) { return test::testSceneFrom(json, "test.json"); }

std::string vec(const Vec3& v) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", v.x, v.y, v.z);
    return buf;
}

// Rodrigues' rotation of v about the unit axis k by `deg` degrees (right-handed, as glm::rotate).
Vec3 rotate(const Vec3& v, const Vec3& axis, double deg) {
    const Vec3 k = glm::normalize(axis);
    const double a = deg * kPiT / 180.0;
    return v * std::cos(a) + glm::cross(k, v) * std::sin(a) + k * glm::dot(k, v) * (1.0 - std::cos(a));
}

// The closed box of the tests: [-0.5, 0.5] x [0, 1] x [-0.5, 0.5], rotated about `axis` by `deg`.
struct Cage {
    Vec3 axis{0.0, 1.0, 0.0};
    double deg = 0.0;
    Vec3 toWorld(const Vec3& local) const { return rotate(local, axis, deg); }
    Vec3 toLocal(const Vec3& world) const { return rotate(world, axis, -deg); }
    // Inside or on the surface, up to `tol` (float-rounded vertices).
    bool holds(const Vec3& world, double tol) const {
        const Vec3 p = toLocal(world);
        return std::abs(p.x) <= 0.5 + tol && p.y >= -tol && p.y <= 1.0 + tol && std::abs(p.z) <= 0.5 + tol;
    }
    double highestY() const {
        double y = -1e9;
        for (int i = 0; i < 8; ++i)
            y = std::max(y, toWorld(Vec3(i & 1 ? 0.5 : -0.5, i & 2 ? 1.0 : 0.0, i & 4 ? 0.5 : -0.5)).y);
        return y;
    }
    double lowestY() const {
        double y = 1e9;
        for (int i = 0; i < 8; ++i)
            y = std::min(y, toWorld(Vec3(i & 1 ? 0.5 : -0.5, i & 2 ? 1.0 : 0.0, i & 4 ? 0.5 : -0.5)).y);
        return y;
    }
};

// A diffuse closed box (the cage) with a ceiling 5 cm above it and a floor 5 cm below it, seen
// from outside; `light` inside it, optionally a fog filling everything (inside and outside).
std::string closedBoxScene(const Cage& cage, const std::string& light, bool fog, int photons) {
    const double top = cage.highestY() + 0.05, bottom = cage.lowestY() - 0.05;
    return R"({
  "version": 1,
  "camera": {"position": [0.3, 0.6, 3.0], "look_at": [0, 0.6, 0], "fov": 70, "resolution": [32, 32]},
  "film": {"start_m": 0, "bin_width_m": 0.25, "bins": 48},
  "media": {"fog": {"sigma_s": 0.3, "sigma_a": 0.05, "g": 0.2}},
  )" + std::string(fog ? R"("global_medium": "fog",)" : "") +
           R"(
  "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
  "shapes": [
    {"name": "cage", "type": "box", "min": [-0.5, 0, -0.5], "max": [0.5, 1, 0.5], "material": "white",
     "transform": {"rotate": {"axis": )" +
           vec(cage.axis) + R"(, "angle_deg": )" + std::to_string(cage.deg) + R"(}}},
    {"name": "ceiling", "type": "quad", "corner": [-2, )" +
           std::to_string(top) + R"(, -2], "edge_u": [4, 0, 0], "edge_v": [0, 0, 4], "material": "white"},
    {"name": "floor", "type": "quad", "corner": [-2, )" +
           std::to_string(bottom) + R"(, -2], "edge_u": [0, 0, 4], "edge_v": [4, 0, 0], "material": "white"}
  ],
  "lights": [)" +
           light + R"(],
  "render": {"photons_per_pass": )" +
           std::to_string(photons) + R"(, "radius_relative": 0.01, "surface_radius_relative": 0.02,
             "passes": 2, "max_depth": 16, "seed": 5}
})";
}

struct Outside {
    int64_t photons = 0, beams = 0;
};

// Photons and beams of passes 1..passes stored outside the cage. A surface photon is outside when
// the point 0.1 mm off it on the side it arrived from is not in the cage.
Outside storedOutside(const test::TestScene& t, const Cage& cage, int passes, size_t& photons, size_t& beams) {
    const Scene& sc = *t;
    Outside out;
    photons = beams = 0;
    for (int pass = 1; pass <= passes; ++pass) {
        PhotonPassParams ts;
        ts.photons = t.settings.photonsPerPass;
        ts.seed = t.settings.seed;
        ts.pass = static_cast<uint64_t>(pass);
        ts.storeBeams = sc.stages.beams;
        ts.threads = 2;
        const PhotonMap map = tracePhotons(sc, ts);
        photons += map.photons.size();
        beams += map.beams.size();
        for (const SurfacePhoton& p : map.photons)
            if (!cage.holds(p.position + 1e-4 * p.normal, 1e-6)) ++out.photons;
        for (const Beam& b : map.beams)
            if (!cage.holds(b.origin, 1e-6) || !cage.holds(b.origin + b.length * b.dir, 1e-6)) ++out.beams;
    }
    return out;
}

struct ImageSum {
    double sum = 0.0;
    int64_t nonzero = 0;
};
ImageSum sumOf(const std::vector<float>& img) {
    ImageSum s;
    for (float v : img) {
        s.sum += v;
        s.nonzero += v != 0.0f;
    }
    return s;
}

// The beam renderer (passes 1..2) and the path tracer (16 paths per pixel) on the scene; both
// images must be exactly zero since the camera sees only the outside of the cage.
void expectDarkOutside(const test::TestScene& t) {
    const Scene& sc = *t;
    RenderSettings ds = t.settings;
    ds.threads = 2;
    Driver drv(sc, ds, t.time);
    for (int p = 1; p <= 2; ++p) ASSERT_TRUE(drv.runPass(p));
    std::vector<float> img;
    drv.film().steadyImage(img);
    const ImageSum beams = sumOf(img);
    EXPECT_EQ(beams.nonzero, 0) << "photon-beam image of the outside: sum " << beams.sum;
    std::vector<double> vol;
    drv.film().volume(TimeAxis::Real, EmissionMode::Delta, vol);
    int64_t lit = 0;
    for (double v : vol) lit += v != 0.0;
    EXPECT_EQ(lit, 0) << "texels of the transient volume";

    RenderSettings ps;
    ps.maxDepth = 64;  // the path tracer's depth unless set below
    ps.samplesPerPixel = 16;
    ps.threads = 2;
    ps.seed = 3;
    TransientFilm film(sc.camera.width, sc.camera.height, t.time);
    PathTracerStats st;
    test::renderPathTracer(sc, ps, 1, 1, film, &st);
    film.steadyImage(img);
    const ImageSum pt = sumOf(img);
    EXPECT_EQ(pt.nonzero, 0) << "path-traced image of the outside: sum " << pt.sum;
    EXPECT_GT(st.shadowRays, 0);  // the path tracer did try to reach the light
}

// The same renderer sees the light when the camera is inside the cage (the test is not vacuous).
void expectLitInside(std::string json) {
    const std::string cam = R"("position": [0.3, 0.6, 3.0], "look_at": [0, 0.6, 0])";
    json.replace(json.find(cam), cam.size(), R"("position": [0.1, 0.4, 0.1], "look_at": [-0.3, 0.6, -0.3])");
    const std::string res = R"("resolution": [32, 32])", photons = R"("photons_per_pass": 20000)";
    json.replace(json.find(res), res.size(), R"("resolution": [8, 8])");
    json.replace(json.find(photons), photons.size(), R"("photons_per_pass": 2000)");
    const auto sc = sceneFrom(json);
    RenderSettings ds = sc.settings;
    ds.threads = 2;
    Driver drv(*sc, ds, sc.time);
    ASSERT_TRUE(drv.runPass(1));
    std::vector<float> img;
    drv.film().steadyImage(img);
    EXPECT_GT(sumOf(img).nonzero, static_cast<int64_t>(img.size() / 2));
}

}  // namespace

// ---- item 3: a closed box holds its light -------------------------------------------------------

// The box holds its light to the last photon: many photons and beams stored, none outside the
// box, both renderers' images of the outside exactly dark, and the inside lit.
static void expectBoxHoldsItsLight(const test::TestScene& sc, const Cage& cage, const std::string& json) {
    size_t photons, beams;
    const Outside out = storedOutside(sc, cage, 2, photons, beams);
    EXPECT_GT(photons, 20000u);
    EXPECT_GT(beams, 20000u);
    EXPECT_EQ(out.photons, 0);
    EXPECT_EQ(out.beams, 0);
    expectDarkOutside(sc);
    expectLitInside(json);
}

TEST(ClosedBox, PointLightInFogLightsNothingOutsideTheBox) {
    // Fog everywhere (one region inside and outside): the beam kernel (r = 6.5 cm) and the surface
    // kernel (13 cm) both reach across the walls and across the 5 cm gaps.
    const Cage cage;
    const std::string json =
        closedBoxScene(cage, R"({"type": "point", "position": [0.1, 0.5, 0.05], "power": 10})", true, 20000);
    const auto sc = sceneFrom(json);
    ASSERT_GT(sc.settings.beamRadius0, 0.05);
    ASSERT_GT(sc.settings.surfaceRadius0, 0.05);
    expectBoxHoldsItsLight(sc, cage, json);
}

TEST(ClosedBox, AreaLightFillingTheCeilingOfATiltedBoxLightsNothingOutside) {
    // The light covers the inside of the box's top face exactly (its edges on the side walls), and
    // the box is tilted so that its faces are perpendicular only up to float rounding.
    Cage cage;
    cage.axis = Vec3(0.3, 1.0, 0.2);
    cage.deg = 23.0;
    const std::string light = R"({"type": "area", "corner": )" + vec(cage.toWorld(Vec3(-0.5, 1.0, -0.5))) +
                              R"(, "edge_u": )" + vec(cage.toWorld(Vec3(1.0, 0.0, 0.0))) + R"(, "edge_v": )" +
                              vec(cage.toWorld(Vec3(0.0, 0.0, 1.0))) + R"(, "power": 10})";
    const std::string json = closedBoxScene(cage, light, true, 20000);
    const auto sc = sceneFrom(json);
    ASSERT_LT(glm::dot(sc->lights[0].normal, cage.toWorld(Vec3(0.0, 1.0, 0.0))), -0.999);  // emits into the box
    expectBoxHoldsItsLight(sc, cage, json);
}

TEST(ClosedBox, BouncesAtTheEdgesOfATiltedBoxLeaveFromInside) {
    // Rays from the centre aimed exactly at points on the 12 edges: the hit lies within rounding
    // of both faces, and the bounce origin must be inside both. A step along the hit face's normal
    // alone lies on the other face's plane (up to rounding), and rays from it escape.
    Cage cage;
    cage.axis = Vec3(0.3, 1.0, 0.2);
    cage.deg = 23.0;
    const auto sc = sceneFrom(closedBoxScene(cage, R"({"type": "point", "position": [0, 0.5, 0]})", false, 10));
    const Vec3 centre = cage.toWorld(Vec3(0.0, 0.5, 0.0));
    Rng rng(11, Stream::Photon, 0, 0);
    int64_t originsOutside = 0, escapes = 0, rays = 0;
    for (int i = 0; i < 6000; ++i) {
        const int edge = i % 12, axis = edge / 4;
        const double s = rng.uniform() - 0.5;
        const double a = edge & 1 ? 0.5 : -0.5, b = edge & 2 ? 0.5 : -0.5;
        const Vec3 local = axis == 0 ? Vec3(s, a + 0.5, b) : axis == 1 ? Vec3(a, s + 0.5, b) : Vec3(a, b + 0.5, s);
        const Vec3 target = cage.toWorld(local);
        const Ray ray{centre, glm::normalize(target - centre)};
        const auto hit = sc->geometry.intersect(ray);
        ASSERT_TRUE(hit);
        ASSERT_EQ(hit->shape, 0);
        const Vec3 ng = glm::dot(ray.d, hit->ng) < 0.0 ? hit->ng : -hit->ng;
        const Vec3 o = sc->bounceOrigin(ray, *hit, ng);
        const Vec3 ol = cage.toLocal(o);
        if (!(std::abs(ol.x) < 0.5 && ol.y > 0.0 && ol.y < 1.0 && std::abs(ol.z) < 0.5)) ++originsOutside;
        for (int k = 0; k < 8; ++k) {
            // Directions in the hemisphere of ng, most of them through the neighbouring face.
            Vec3 w = glm::normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
            if (glm::dot(w, ng) < 0.0) w -= 2.0 * glm::dot(w, ng) * ng;
            const auto next = sc->geometry.intersect(Ray{o, w});
            ++rays;
            if (!next || next->shape != 0 || glm::dot(w, next->ng) <= 0.0) ++escapes;
        }
    }
    EXPECT_EQ(originsOutside, 0);
    EXPECT_EQ(escapes, 0) << "of " << rays << " rays";
}

// ---- which surface points see each other (the surface photon gather) ----------------------------

TEST(SurfaceVisibility, PointsOnASphereSeeEachOtherFromOutsideAndInside) {
    // The straight chord between two points of a convex surface dips under it (a sphere would hide
    // its own photons); over the tangent planes' apex it does not. From inside the chord is free.
    const auto sc =
        sceneFrom(R"({"version": 1, "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [4, 4]},
      "materials": {"white": {"type": "diffuse"}},
      "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "white"}],
      "lights": [{"type": "point", "position": [0, 2, 0]}]})");
    Rng rng(3, Stream::Photon, 0, 0);
    int blockedOut = 0, blockedIn = 0;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 n1 = glm::normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
        // A second point up to 0.3 m away (the kernel radius reaches 0.6 R).
        const Vec3 t = glm::normalize(glm::cross(n1, Vec3(0.3, 0.5, 0.7)));
        const double angle = 0.6 * rng.uniform();
        const Vec3 n2 = glm::normalize(n1 * std::cos(angle) + t * std::sin(angle));
        const Vec3 p1 = 0.5 * n1, p2 = 0.5 * n2;
        const double e = sc->rayEps;
        if (!sc->surfacePointsSeeEachOther(p1 + e * n1, n1, p2 + e * n2, n2)) ++blockedOut;
        if (!sc->surfacePointsSeeEachOther(p1 - e * n1, -n1, p2 - e * n2, -n2)) ++blockedIn;
    }
    EXPECT_EQ(blockedOut, 0);
    EXPECT_EQ(blockedIn, 0);
}

TEST(SurfaceVisibility, AWallStandingOnAFloorAndTheFacesOfABoxSeparatePoints) {
    const auto sc =
        sceneFrom(R"({"version": 1, "camera": {"position": [0, 0.5, 5], "look_at": [0, 0, 0], "resolution": [4, 4]},
      "materials": {"white": {"type": "diffuse"}},
      "shapes": [{"name": "floor", "type": "quad", "corner": [-2, 0, -2], "edge_u": [0, 0, 4], "edge_v": [4, 0, 0], "material": "white"},
                 {"name": "divider", "type": "quad", "corner": [0, 0, -2], "edge_u": [0, 1, 0], "edge_v": [0, 0, 4], "material": "white"},
                 {"name": "block", "type": "box", "min": [1, 0, -0.5], "max": [1.5, 0.5, 0.5], "material": "white"}],
      "lights": [{"type": "point", "position": [-1, 2, 0]}]})");
    const double e = sc->rayEps;
    const Vec3 up(0.0, 1.0, 0.0);
    Rng rng(5, Stream::Photon, 0, 0);
    int sameSide = 0, across = 0, boxEdge = 0;
    for (int i = 0; i < 2000; ++i) {
        // Floor points within 5 cm of the divider (x = 0), on either side.
        const double z1 = 0.8 * (rng.uniform() - 0.5), z2 = z1 + 0.05 * (rng.uniform() - 0.5);
        const double xa = -0.05 * rng.uniform() - 1e-3, xb = -0.05 * rng.uniform() - 1e-3;
        const Vec3 a(xa, e, z1), b(xb, e, z2), c(-xb, e, z2);
        sameSide += sc->surfacePointsSeeEachOther(a, up, b, up);
        across += sc->surfacePointsSeeEachOther(a, up, c, up);
        // Outside of the block's top face near its edge x = 1.5, and the inside of the side face
        // x = 1.5 near the same edge (whose inward normal -x is perpendicular to +y).
        const Vec3 top(1.5 - 0.02 * rng.uniform(), 0.5 + e, z1), side(1.5 - e, 0.5 - 0.02 * rng.uniform(), z2);
        boxEdge += sc->surfacePointsSeeEachOther(top, up, side, glm::normalize(Vec3(-1.0, 1e-9, 0.0)));
    }
    EXPECT_EQ(sameSide, 2000);
    EXPECT_EQ(across, 0);
    EXPECT_EQ(boxEdge, 0);
}

// ---- item 2: area lights start in the region they emit from -------------------------------------

namespace {

// An area light under the ceiling of an absorbing room (a box without material) 2 m wide, with a
// camera inside looking down at the lit fog (the light itself out of view); the fog either fills
// everything or an invisible (null) box 1 mm inside the room.
std::string roomScene(bool fogInNullBox, uint64_t seed) {
    return R"({
  "version": 1,
  "camera": {"position": [0, -0.1, 0.9], "look_at": [0, -0.5, 0], "fov": 75, "resolution": [24, 24]},
  "film": {"start_m": 0, "bin_width_m": 0.2, "bins": 40},
  "media": {"fog": {"sigma_s": 0.6, "sigma_a": 0.1, "g": 0.3}},
  )" + std::string(fogInNullBox ? "" : R"("global_medium": "fog",)") +
           R"(
  "materials": {"container": {"type": "null"}},
  "shapes": [{"name": "room", "type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]})" +
           std::string(fogInNullBox ? R"(,
             {"name": "fog box", "type": "box", "min": [-0.999, -0.999, -0.999], "max": [0.999, 0.999, 0.999],
              "material": "container", "interior_medium": "fog"})"
                                    : "") +
           R"(],
  "lights": [{"type": "area", "corner": [-0.2, 0.5, -0.2], "edge_u": [0.4, 0, 0], "edge_v": [0, 0, 0.4], "power": 20}],
  "render": {"photons_per_pass": 6000, "radius": 0.04, "surface_radius": 0.05, "passes": 2, "max_depth": 12,
             "seed": )" +
           std::to_string(seed) + R"(}
})";
}

// Luminance sums over 4x4-pixel blocks of the steady image.
std::vector<double> blockSums(const std::vector<float>& img, int w, int h) {
    std::vector<double> blocks(static_cast<size_t>((w / 4) * (h / 4)), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = 3 * (static_cast<size_t>(y) * w + x);
            blocks[static_cast<size_t>((y / 4) * (w / 4) + x / 4)] += luminance(Color(img[i], img[i + 1], img[i + 2]));
        }
    return blocks;
}

std::vector<float> beamImage(const test::TestScene& sc, int64_t* beams = nullptr) {
    RenderSettings ds = sc.settings;
    ds.threads = 2;
    Driver drv(*sc, ds, sc.time);
    for (int p = 1; p <= 2; ++p) EXPECT_TRUE(drv.runPass(p));
    if (beams) *beams = drv.lastPass().beams;
    std::vector<float> img;
    drv.film().steadyImage(img);
    return img;
}

std::vector<float> pathTracedImage(const test::TestScene& t) {
    const Scene& sc = *t;
    RenderSettings ps;
    ps.maxDepth = 64;  // the path tracer's depth unless set below
    ps.samplesPerPixel = 128;
    ps.threads = 2;
    ps.seed = t.settings.seed;
    TransientFilm film(sc.camera.width, sc.camera.height, t.time);
    test::renderPathTracer(sc, ps, 1, 1, film);
    std::vector<float> img;
    film.steadyImage(img);
    return img;
}

// Block by block, the fog-in-a-box image B must match the global-fog image A of the same seed
// within 4 standard deviations of the difference of two independent renders of A (seeds s1, s2):
// the tolerance a correct B would meet even if it were independent of A. With the same seed the
// random streams agree until a photon or path reaches the 1 mm gap outside the fog box, so the
// actual difference is far smaller; today's B (no fog lit at all) differs by most of A.
void expectSameImage(const std::vector<float>& a1, const std::vector<float>& a2, const std::vector<float>& b1, int w,
                     int h, const char* what) {
    const std::vector<double> A1 = blockSums(a1, w, h), A2 = blockSums(a2, w, h), B1 = blockSums(b1, w, h);
    double var = 0.0, total = 0.0;
    for (size_t k = 0; k < A1.size(); ++k) {
        var += (A1[k] - A2[k]) * (A1[k] - A2[k]);
        total += A1[k];
    }
    const double sigmaDiff = std::sqrt(var / A1.size());
    ASSERT_GT(sigmaDiff, 0.0);
    // Fine enough to tell: an image without the fog's light (today's B) fails in most blocks.
    ASSERT_LT(4.0 * sigmaDiff, total / A1.size()) << what << ": too noisy to compare";
    double worst = 0.0;
    for (size_t k = 0; k < A1.size(); ++k) worst = std::max(worst, std::abs(B1[k] - A1[k]) / sigmaDiff);
    EXPECT_LT(worst, 4.0) << what << ": worst block differs by " << worst << " sigma";
}

}  // namespace

TEST(AreaLightRegions, FogInANullBoxAroundTheLightLooksLikeTheSameFogEverywhere) {
    const auto a1 = sceneFrom(roomScene(false, 7)), a2 = sceneFrom(roomScene(false, 8)),
               b1 = sceneFrom(roomScene(true, 7));
    ASSERT_EQ(b1->lightPlacement[0].regions.top(), b1->shapes[1].interiorRegion);  // the light sits in the fog box
    int64_t beamsA = 0, beamsB = 0;
    const std::vector<float> ia1 = beamImage(a1, &beamsA), ia2 = beamImage(a2), ib1 = beamImage(b1, &beamsB);
    EXPECT_GT(beamsB, beamsA * 9 / 10);
    expectSameImage(ia1, ia2, ib1, 24, 24, "photon beams");
    // The path tracer connects to the light through the null box on its own (shadow rays cross
    // null boundaries); it must agree too.
    expectSameImage(pathTracedImage(a1), pathTracedImage(a2), pathTracedImage(b1), 24, 24, "path tracer");
}

TEST(AreaLightRegions, ALightAcrossAFogBoxFaceEmitsIntoItFromItsInsidePartOnly) {
    // The fog box's face x = 0 halves the light: photons leaving from x < 0 start in the fog (their
    // first beam starts at the light), those from x > 0 in vacuum (no beam until they enter).
    const auto sc =
        sceneFrom(R"({"version": 1, "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "resolution": [4, 4]},
      "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.1}},
      "materials": {"container": {"type": "null"}},
      "shapes": [{"name": "fog box", "type": "box", "min": [-1, -1, -1], "max": [0, 1, 1], "material": "container", "interior_medium": "fog"}],
      "lights": [{"type": "area", "corner": [-0.5, 0.5, -0.25], "edge_u": [1, 0, 0], "edge_v": [0, 0, 0.5], "power": 1}]})");
    ASSERT_FALSE(sc->lightPlacement[0].uniform);
    PhotonPassParams ts;
    ts.photons = 20000;
    ts.seed = 2;
    ts.pass = 1;
    ts.threads = 2;
    const PhotonMap map = tracePhotons(*sc, ts);
    int64_t atLightInside = 0, atLightOutside = 0;
    for (const Beam& b : map.beams) {
        if (b.depth != 0 || b.origin.y < 0.5 - 1e-3) continue;  // first segments leaving the light
        EXPECT_EQ(b.region, sc->shapes[0].interiorRegion);
        if (b.origin.x < -1e-6)
            ++atLightInside;
        else if (b.origin.x > 1e-6)
            ++atLightOutside;
    }
    EXPECT_EQ(atLightOutside, 0);
    // Every photon from the inside half stores its first beam there: Binomial(20000, 1/2).
    EXPECT_NEAR(static_cast<double>(atLightInside), 10000.0, 5.0 * std::sqrt(20000.0 * 0.25));
}

TEST(AreaLightRegions, ALightOnTheInsideOfAFogBoxCeilingEmitsIntoTheBox) {
    // The light lies on the fog box's top face, facing down: every photon starts in the fog and
    // no beam lies outside the box.
    const auto sc =
        sceneFrom(R"({"version": 1, "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "resolution": [4, 4]},
      "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.1}},
      "materials": {"container": {"type": "null"}},
      "shapes": [{"name": "fog box", "type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "material": "container", "interior_medium": "fog"}],
      "lights": [{"type": "area", "corner": [-1, 1, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "power": 1}]})");
    PhotonPassParams ts;
    ts.photons = 20000;
    ts.seed = 4;
    ts.pass = 1;
    ts.threads = 2;
    const PhotonMap map = tracePhotons(*sc, ts);
    int64_t first = 0, outside = 0;
    for (const Beam& b : map.beams) {
        if (b.depth == 0 && b.origin.y > 1.0 - 1e-3) ++first;
        const Vec3 e = b.origin + b.length * b.dir;
        for (const Vec3& p : {b.origin, e})
            if (std::abs(p.x) > 1.0 + 1e-6 || std::abs(p.y) > 1.0 + 1e-6 || std::abs(p.z) > 1.0 + 1e-6) ++outside;
    }
    EXPECT_EQ(first, ts.photons);
    EXPECT_EQ(outside, 0);
}

// ---- item 16: the region stack's capacity -------------------------------------------------------

TEST(RegionStack, APushIntoAFullStackFailsAndLeavesTheStackAsItWas) {
    RegionStack st;
    for (int r = 1; r < RegionStack::kCapacity; ++r) EXPECT_TRUE(st.push(r));
    EXPECT_EQ(st.size, RegionStack::kCapacity);
    EXPECT_FALSE(st.push(99));
    EXPECT_EQ(st.size, RegionStack::kCapacity);
    EXPECT_EQ(st.top(), RegionStack::kCapacity - 1);
}

namespace {

std::string nestedSpheres(int count) {
    std::string shapes;
    for (int i = count; i >= 1; --i)
        shapes += std::string(shapes.empty() ? "" : ",\n") + R"({"name": "shell )" + std::to_string(i) +
                  R"(", "type": "sphere", "center": [0, 0, 0], "radius": )" + std::to_string(i) +
                  R"(, "material": "container", "interior_medium": "fog"})";
    return R"({"version": 1, "camera": {"position": [0, 0, 0.5], "look_at": [0, 0, 0], "resolution": [4, 4]},
      "media": {"fog": {"sigma_s": 0.1}}, "materials": {"container": {"type": "null"}},
      "shapes": [)" +
           shapes + R"(], "lights": [{"type": "point", "position": [0, 0.2, 0]}]})";
}

}  // namespace

TEST(RegionStack, ShapesNestedDeeperThanTheStackAreRefusedNamingThem) {
    const auto ok = sceneFrom(nestedSpheres(RegionStack::kCapacity - 1));
    EXPECT_EQ(ok->cameraRegions.size, RegionStack::kCapacity);
    EXPECT_EQ(ok->lightPlacement[0].regions.size, RegionStack::kCapacity);
    try {
        sceneFrom(nestedSpheres(RegionStack::kCapacity));
        FAIL() << "8 nested shapes were accepted";
    } catch (const UserError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("test.json:"), std::string::npos) << msg;
        EXPECT_NE(msg.find("shapes[7]"), std::string::npos) << msg;
        EXPECT_NE(msg.find("\"shell 8\" > \"shell 7\""), std::string::npos) << msg;
        EXPECT_NE(msg.find("\"shell 1\""), std::string::npos) << msg;
        EXPECT_NE(msg.find("at most 7"), std::string::npos) << msg;
    }
}

TEST(RegionStack, AnOverflowAtRunTimeEndsThePathAndIsCounted) {
    // Eight small null quads in a row, each facing a laser (and the camera) that crosses them
    // front to back: each crossing enters one more region and none is left, the 8th finds the
    // stack full. (Open shapes: the scene's nesting check sees each alone.) A wall behind them
    // would get the photons if the overflow were ignored.
    std::string quads;
    for (int k = 1; k <= 8; ++k)
        quads += R"({"type": "quad", "corner": [-0.1, -0.1, )" + std::to_string(-k) +
                 R"(], "edge_u": [0.2, 0, 0], "edge_v": [0, 0.2, 0], "material": "container"},)";
    const auto sc = sceneFrom(
        R"({"version": 1, "camera": {"position": [0, 0, 0.5], "look_at": [0, 0, -1], "fov": 0.5, "resolution": [4, 4]},
      "film": {"start_m": 0, "bin_width_m": 1, "bins": 30},
      "materials": {"container": {"type": "null"}, "white": {"type": "diffuse"}},
      "shapes": [)" +
        quads +
        R"({"name": "wall", "type": "quad", "corner": [-1, -1, -9], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "white"}],
      "lights": [{"type": "laser", "position": [0, 0, 0], "direction": [0, 0, -1], "power": 1}]})");
    PhotonPassParams ts;
    ts.photons = 500;
    ts.pass = 1;
    const PhotonMap map = tracePhotons(*sc, ts);
    EXPECT_EQ(map.regionOverflows, 500);
    EXPECT_TRUE(map.photons.empty());

    CameraPassParams cs;
    CameraPassScratch scratch{PixelAccumulator(sc.time.bins), {}};
    CameraPassStats cst;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            renderPixel(*sc, CameraPassEstimators{}, cs, sc.time, x, y, scratch, cst);
            scratch.acc.clearTouched();
        }
    EXPECT_EQ(cst.regionOverflows, 16);

    RenderSettings ps;
    ps.maxDepth = 64;  // the path tracer's depth unless set below
    ps.threads = 1;
    TransientFilm film(4, 4, sc.time);
    PathTracerStats pst;
    test::renderPathTracer(*sc, ps, 1, 1, film, &pst);
    EXPECT_EQ(pst.regionOverflows, 16);
    EXPECT_EQ(pst.shadowRays, 0);  // the paths never reached the wall

    // The driver's pass statistics carry both counts (for summary.json).
    RenderSettings ds = sc.settings;
    ds.photonsPerPass = 300;
    ds.threads = 1;
    Driver drv(*sc, ds, sc.time);
    ASSERT_TRUE(drv.runPass(1));
    EXPECT_EQ(drv.lastPass().regionOverflows, 300);
    EXPECT_EQ(drv.lastPass().camera.regionOverflows, 16);
}
