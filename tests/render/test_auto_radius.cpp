// "radius": "auto" (render/auto_radius.h): the radius a pilot pass's photon density gives, checked
// against an independent count. The rule assumes that a camera chord through the medium is an
// isotropic uniform random line through the box the beams fill; for such lines the mean number of
// beams whose kernel cylinder a line crosses is exactly sum_b (mean projected area of the cylinder)
// / (mean projected area of the box) = (2 pi r L + 2 pi r^2 n) / A (Cauchy), whatever the beams'
// directions. The test draws such lines and counts with beam2d's own overlap test.
#include "render/auto_radius.h"
#include "render/prepare.h"
#include "estimators/beam2d.h"
#include "photons/photon_tracer.h"
#include "scene/scene_loader.h"
#include "base/error.h"
#include "base/rng.h"
#include "base/sampling.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace tpb;
using ::testing::HasSubstr;

namespace {

// A closed box (walls facing in) full of fog, the camera and a point light inside: no photon leaves
// the scene's bounds, so the pilot's clipping changes nothing.
std::string boxScene(const std::string& render, const std::string& estimator = "beam2d") {
    return R"({
  "version": 1,
  "camera": {"position": [0, 1, 0.9], "look_at": [0, 1, 0], "fov": 60, "resolution": [8, 8]},
  "film": {"start_m": 0, "bin_width_m": 0.1, "bins": 16},
  "media": {"fog": {"sigma_s": 0.6, "sigma_a": 0.1, "g": 0.2}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.5}},
  "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true}],
  "lights": [{"type": "point", "position": [0.2, 1.5, -0.3], "power": 10}],
  "render": {"volume_estimator": ")" +
           estimator + R"(", "photons_per_pass": 3000, "max_depth": 8, "seed": 5)" + render + "}\n}";
}

PreparedRender prepare(const std::string& json, const SettingsOverrides& o = {},
                       std::vector<std::string>* warnings = nullptr) {
    PrepareOptions opt;
    opt.pilot.run = false;
    opt.warn = [warnings](const std::string& w) {
        if (warnings) warnings->push_back(w);
    };
    return prepareRender(loadSceneFromString(json, "auto.json"), o, opt);
}

std::string errorOf(const std::string& json) {
    try {
        prepare(json);
    } catch (const UserError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(AutoRadius, BeamsPerRandomChordMatchTheTarget) {
    const PreparedRender p = prepare(boxScene(R"(, "radius": "auto")"));
    const RadiusPilot& rp = p.radiusPilot;
    ASSERT_TRUE(rp.measured) << rp.why;
    EXPECT_FALSE(rp.pointKernel);
    EXPECT_EQ(p.settings.beamRadius0, rp.radius);
    const double r = rp.radius;
    EXPECT_GT(r, 1e-3);
    EXPECT_LT(r, 0.5);

    // The pilot's photons again (pass 0, same seed): the same beams.
    PhotonPassParams pt;
    pt.seed = p.settings.seed;
    pt.pass = 0;
    pt.photons = p.settings.photonsPerPass;
    pt.maxDepth = p.settings.maxDepth;
    pt.storeSurfacePhotons = false;
    pt.threads = 1;
    const PhotonMap map = tracePhotons(*p.scene, pt);
    Bounds3 box;
    for (const Beam& b : map.beams) {
        box.expand(b.origin);
        box.expand(b.origin + b.length * b.dir);
    }
    // Isotropic uniform random lines through the box: a uniform direction, then a uniform point on
    // the plane across it within the box's shadow (a disc of the box's circumradius), kept if the
    // line meets the box; the chord is the part inside.
    Rng rng(11, Stream::Test, 0, 0);
    const Vec3 c = box.center();
    const double R = 0.5 * box.diagonal();
    double total = 0.0, totalSq = 0.0;
    int lines = 0;
    while (lines < 3000) {
        const Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        const Vec3 t1 =
            glm::normalize(std::abs(d.x) < 0.9 ? glm::cross(d, Vec3(1, 0, 0)) : glm::cross(d, Vec3(0, 1, 0)));
        const Vec3 t2 = glm::cross(d, t1);
        const double u = 2.0 * rng.uniform() - 1.0, v = 2.0 * rng.uniform() - 1.0;
        if (u * u + v * v > 1.0) continue;
        const Vec3 o = c + R * (u * t1 + v * t2) - 2.0 * R * d;
        double s0 = 0.0, s1 = 4.0 * R;  // clip to the box
        for (int k = 0; k < 3; ++k) {
            if (std::abs(d[k]) < 1e-12) {
                if (o[k] < box.lo[k] || o[k] > box.hi[k]) s1 = -1.0;
                continue;
            }
            double a = (box.lo[k] - o[k]) / d[k], e = (box.hi[k] - o[k]) / d[k];
            if (a > e) std::swap(a, e);
            s0 = std::max(s0, a);
            s1 = std::min(s1, e);
        }
        if (!(s1 > s0)) continue;
        ++lines;
        const Vec3 start = o + s0 * d;
        int count = 0;
        for (const Beam& b : map.beams) {
            RayBeamOverlap ov;
            if (rayBeamOverlap(start, d, s1 - s0, b.origin, b.dir, b.length, r, ov)) ++count;
        }
        total += count;
        totalSq += static_cast<double>(count) * count;
    }
    const double mean = total / lines;
    const double stderrMean = std::sqrt((totalSq / lines - mean * mean) / (lines - 1));
    // Expected: the target, plus the cylinders' end caps (2 pi r^2 per beam over A).
    const Vec3 e = box.hi - box.lo;
    const double area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    const double expected = kAutoBeamsPerRay + 2.0 * kPi * r * r * static_cast<double>(map.beams.size()) / area;
    // Within 4 standard errors (the standard error is about 1.5 % of the mean here): a rule off
    // by 10 % fails.
    EXPECT_NEAR(mean, expected, 4.0 * stderrMean) << "lines " << lines << ", radius " << r;
    EXPECT_LT(stderrMean, 0.03 * expected);
    // Surface radius: the default ratio to the volume radius (2x) when not given.
    EXPECT_NEAR(p.settings.surfaceRadius0, 2.0 * r, 1e-12 * r);
}

TEST(AutoRadius, PointsAndPhotonCountScaleAsDerived) {
    // Beams: r = K A / (2 pi L), so twice the photons (twice the length) halve it.
    const PreparedRender a = prepare(boxScene(R"(, "radius": "auto")"));
    std::string twice = boxScene(R"(, "radius": "auto")");
    twice.replace(twice.find("3000"), 4, "6000");
    const PreparedRender b = prepare(twice);
    ASSERT_TRUE(a.radiusPilot.measured && b.radiusPilot.measured);
    EXPECT_NEAR(b.settings.beamRadius0 / a.settings.beamRadius0, 0.5, 0.05);
    // Points: r = sqrt(K A / (4 pi n)); the point count gathers the target at that radius.
    const PreparedRender pt = prepare(boxScene(R"(, "radius": "auto")", "point3d"));
    ASSERT_TRUE(pt.radiusPilot.measured);
    EXPECT_TRUE(pt.radiusPilot.pointKernel);
    EXPECT_NEAR(pt.radiusPilot.gathered(pt.settings.beamRadius0), kAutoPointsPerRay, 1e-9);
    EXPECT_NEAR(a.radiusPilot.gathered(a.settings.beamRadius0), kAutoBeamsPerRay, 1e-9);
}

TEST(AutoRadius, FlagsOverridesAndBadValues) {
    // --radius wins over the file's "auto"; --auto-radius over the file's number.
    SettingsOverrides o;
    o.radius = 0.05;
    EXPECT_EQ(prepare(boxScene(R"(, "radius": "auto")"), o).settings.beamRadius0, 0.05);
    SettingsOverrides a;
    a.autoRadius = true;
    const PreparedRender p = prepare(boxScene(R"(, "radius": 0.05, "surface_radius": 0.07)"), a);
    EXPECT_TRUE(p.radiusPilot.measured);
    EXPECT_NE(p.settings.beamRadius0, 0.05);
    EXPECT_EQ(p.settings.surfaceRadius0, 0.07);  // given: kept
    // Without a scattering medium nothing is measured: the default stays, with a warning.
    std::string vacuum = boxScene(R"(, "radius": "auto")");
    vacuum.replace(vacuum.find(R"("global_medium": "fog",)"), 23, "");
    std::vector<std::string> warnings;
    const PreparedRender v = prepare(vacuum, {}, &warnings);
    EXPECT_FALSE(v.radiusPilot.measured);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_THAT(warnings[0], HasSubstr("render.radius: auto: no scattering medium"));
    // Bad values name the file, the line and the key.
    EXPECT_THAT(errorOf(boxScene(R"(, "radius": "big")")),
                HasSubstr("auto.json:10: render.radius: radius must be a length"));
    EXPECT_THAT(errorOf(boxScene(R"(, "radius": "auto", "radius_relative": 0.01)")),
                HasSubstr("render.radius_relative: give either radius"));
}
