// Mitsuba 3 XML import (core/scene/mitsuba_loader.h): the shipped XML twins render the films of
// their JSON scenes, transforms against hand-computed matrices, fov_axis conversions, unit
// conversions, <default>/$param/<include>/<ref>, the PLY reader, and every error path naming
// file:line.
#include "render/prepare.h"
#include "base/error.h"
#include "render/driver.h"
#include "scene/light.h"
#include "scene/mitsuba_loader.h"
#include "scene/ply.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "support/temp_dir.h"
#include "support/test_scene.h"

#include <glm/gtc/matrix_transform.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>

using namespace tpb;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

const std::string kScenes = std::string(TPB_SOURCE_DIR) + "/scenes/";

// A scene around `body`: a sensor, then body.
std::string scene(const std::string& body, const std::string& sensor = "") {
    return "<scene version=\"3.0.0\">\n" + sensor + body + "\n</scene>\n";
}

SceneDesc load(const std::string& xml, const MitsubaOptions& o = {}) {
    return loadMitsubaSceneFromString(xml, "t.xml", o);
}

// Expects a UserError at t.xml:`line` whose message contains `fragment`.
void expectError(const std::string& xml, int line, const std::string& fragment) {
    SCOPED_TRACE(xml);
    try {
        load(xml);
        ADD_FAILURE() << "no error; expected: " << fragment;
    } catch (const UserError& e) {
        EXPECT_EQ(e.file(), "t.xml") << e.what();
        EXPECT_EQ(e.line(), line) << e.what();
        EXPECT_EQ(std::string(e.what()).rfind("t.xml:" + std::to_string(line) + ": ", 0), 0u) << e.what();
        EXPECT_THAT(e.what(), HasSubstr(fragment));
    }
}

void expectNear(const Vec3& a, const Vec3& b, double tol = 1e-12) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

// The film of `d` rendered small: 32x32, 16 bins, 1500 photons, 2 passes, seed 7, 2 threads, the
// time range from the scene's bounds (no pilot).
std::vector<float> renderSmall(SceneDesc d) {
    if (d.camera.type != CameraType::RelayWall) d.camera.width = d.camera.height = 32;
    d.film.bins = 16;
    d.render.photonsPerPass = 1500;
    d.render.seed = 7;
    test::TestScene ts = test::prepareTestScene(std::move(d));
    RenderSettings s = ts.settings;
    s.threads = 2;
    Driver drv(*ts, s, ts.time);
    for (int p = 1; p <= 2; ++p) EXPECT_TRUE(drv.runPass(p));
    std::vector<float> all, img;
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped})
        for (int k = 0; k < drv.film().bins(); ++k) {
            drv.film().frame(k, axis, EmissionMode::Delta, img);
            all.insert(all.end(), img.begin(), img.end());
        }
    drv.film().steadyImage(img);
    all.insert(all.end(), img.begin(), img.end());
    return all;
}

// The world corners of a box shape.
std::vector<Vec3> boxCorners(const ShapeDesc& s) {
    std::vector<Vec3> c;
    for (int i = 0; i < 8; ++i) {
        const Vec3 p(i & 1 ? s.boxMax.x : s.boxMin.x, i & 2 ? s.boxMax.y : s.boxMin.y, i & 4 ? s.boxMax.z : s.boxMin.z);
        c.push_back(Vec3(s.transform * glm::dvec4(p, 1.0)));
    }
    return c;
}

// Field by field: the XML twin describes the JSON scene.
void expectSameScene(const SceneDesc& j, const SceneDesc& x) {
    const Camera cj = Camera::fromDesc(j.camera), cx = Camera::fromDesc(x.camera);
    expectNear(cj.position, cx.position);
    expectNear(cj.forward, cx.forward);
    expectNear(cj.up, cx.up);
    EXPECT_NEAR(j.camera.fovYDeg, x.camera.fovYDeg, 1e-12);
    EXPECT_EQ(j.camera.width, x.camera.width);
    EXPECT_EQ(j.camera.height, x.camera.height);
    EXPECT_EQ(j.film.bins, x.film.bins);
    EXPECT_EQ(j.film.autoRange, x.film.autoRange);
    ASSERT_EQ(j.media.size(), x.media.size());
    for (size_t i = 0; i < j.media.size(); ++i) {
        expectNear(j.media[i].sigma_s, x.media[i].sigma_s, 1e-15);
        expectNear(j.media[i].sigma_a, x.media[i].sigma_a, 1e-15);
        EXPECT_EQ(j.media[i].g, x.media[i].g);
    }
    EXPECT_EQ(j.globalMedium, x.globalMedium);
    ASSERT_EQ(j.shapes.size(), x.shapes.size());
    for (size_t i = 0; i < j.shapes.size(); ++i) {
        SCOPED_TRACE(j.shapes[i].name);
        const ShapeDesc &a = j.shapes[i], &b = x.shapes[i];
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.type, b.type);
        EXPECT_EQ(a.flipNormals, b.flipNormals);
        const MaterialDesc &ma = j.materials[a.material], &mb = x.materials[b.material];
        EXPECT_EQ(ma.type, mb.type);
        expectNear(ma.albedo, mb.albedo, 0.0);
        expectNear(ma.specular, mb.specular, 0.0);
        if (ma.type == MaterialType::Dielectric) {
            EXPECT_EQ(ma.ior, mb.ior);
        }
        if (a.type == ShapeType::Quad) {  // exact: the matrices map [-1,1]^2 onto the quads
            expectNear(a.corner, b.corner, 0.0);
            expectNear(a.edgeU, b.edgeU, 0.0);
            expectNear(a.edgeV, b.edgeV, 0.0);
        } else if (a.type == ShapeType::Box) {
            const std::vector<Vec3> ca = boxCorners(a), cb = boxCorners(b);
            for (int k = 0; k < 8; ++k) expectNear(ca[k], cb[k], 1e-15);
        } else if (a.type == ShapeType::Sphere) {
            expectNear(a.center, b.center, 1e-15);
            EXPECT_NEAR(a.radius, b.radius, 1e-15);
        }
    }
    ASSERT_EQ(j.lights.size(), x.lights.size());
    for (size_t i = 0; i < j.lights.size(); ++i) {
        EXPECT_EQ(j.lights[i].type, x.lights[i].type);
        expectNear(j.lights[i].position, x.lights[i].position, 0.0);
        expectNear(j.lights[i].power, x.lights[i].power, 1e-13);
    }
    const RenderDesc &rj = j.render, &rx = x.render;
    EXPECT_EQ(rj.photonsPerPass, rx.photonsPerPass);
    EXPECT_EQ(rj.radius, rx.radius);
    EXPECT_EQ(rj.radiusRelative, rx.radiusRelative);
    EXPECT_EQ(rj.radiusAuto, rx.radiusAuto);
    EXPECT_EQ(rj.surfaceRadius, rx.surfaceRadius);
    EXPECT_EQ(rj.alpha, rx.alpha);
    EXPECT_EQ(rj.passes, rx.passes);
    EXPECT_EQ(rj.maxDepth, rx.maxDepth);
    EXPECT_EQ(rj.volumeEstimator, rx.volumeEstimator);
}

// The films are bit for bit the same (the same seed, the same description up to the last bit of
// the blocks' corners, which do not turn any path here).
void expectSameFilm(const std::vector<float>& a, const std::vector<float>& b) {
    ASSERT_EQ(a.size(), b.size());
    size_t differ = 0;
    double total = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        differ += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
        total += a[i];
    }
    EXPECT_GT(total, 0.0);
    EXPECT_EQ(differ, 0u) << "of " << a.size() << " film values";
}

}  // namespace

// ---- the shipped twins ---------------------------------------------------------------------------

TEST(MitsubaLoader, CornellMediumTwinRendersTheJsonFilm) {
    const SceneDesc j = loadScene(kScenes + "cornell_medium.json"),
                    x = loadScene(kScenes + "mitsuba/cornell_medium.xml");
    expectSameScene(j, x);
    expectSameFilm(renderSmall(j), renderSmall(x));
}

TEST(MitsubaLoader, CornellSpheresTwinRendersTheJsonFilm) {
    const SceneDesc j = loadScene(kScenes + "cornell_spheres.json"),
                    x = loadScene(kScenes + "mitsuba/cornell_spheres.xml");
    expectSameScene(j, x);
    // The conductor is announced as a mirror, with the file and line of its <bsdf>.
    bool warned = false;
    for (const std::string& w : x.warnings)
        warned |=
            w.find("cornell_spheres.xml:43: <bsdf type=\"conductor\" id=\"chrome\">: imported as a perfect mirror") !=
            std::string::npos;
    EXPECT_TRUE(warned);
    expectSameFilm(renderSmall(j), renderSmall(x));
}

// mitransient's NLOS setup: the confocal capture written as mitransient / tal write it imports to
// the JSON scene's relay wall and scan, and renders its film (the projector's irradiance is the 1 W
// laser up to rounding: values within 1e-6 relative).
TEST(MitsubaLoader, NlosConfocalTwinRendersTheJsonFilm) {
    const SceneDesc j = loadScene(kScenes + "nlos_confocal.json"), x = loadScene(kScenes + "mitsuba/nlos_confocal.xml");
    EXPECT_EQ(x.camera.type, CameraType::RelayWall);
    expectNear(j.camera.position, x.camera.position, 0.0);
    EXPECT_EQ(j.camera.width, x.camera.width);
    EXPECT_EQ(j.camera.height, x.camera.height);
    EXPECT_EQ(j.camera.timeOrigin, x.camera.timeOrigin);
    EXPECT_EQ(j.camera.scan, x.camera.scan);
    EXPECT_EQ(j.film.bins, x.film.bins);
    EXPECT_NEAR(j.film.startOpl, x.film.startOpl, 1e-12);
    EXPECT_NEAR(j.film.binWidthOpl, x.film.binWidthOpl, 1e-12);
    const ShapeDesc &wj = j.shapes.at(static_cast<size_t>(j.camera.wallShape)),
                    &wx = x.shapes.at(static_cast<size_t>(x.camera.wallShape));
    expectNear(wj.corner, wx.corner, 0.0);
    expectNear(wj.edgeU, wx.edgeU, 0.0);
    expectNear(wj.edgeV, wx.edgeV, 0.0);
    const LightDesc &lj = j.lights.at(static_cast<size_t>(j.camera.scanLaser)),
                    &lx = x.lights.at(static_cast<size_t>(x.camera.scanLaser));
    EXPECT_EQ(lx.type, LightType::Laser);
    expectNear(lj.position, lx.position, 0.0);
    expectNear(lj.power, lx.power, 1e-12);
    EXPECT_EQ(j.render.maxDepth, x.render.maxDepth);
    SceneDesc a = j, b = x;
    for (SceneDesc* d : {&a, &b}) d->camera.width = d->camera.height = 8;  // 64 laser points
    const std::vector<float> fa = renderSmall(a), fb = renderSmall(b);
    ASSERT_EQ(fa.size(), fb.size());
    double total = 0.0;
    for (size_t i = 0; i < fa.size(); ++i) {
        total += fa[i];
        EXPECT_NEAR(fa[i], fb[i], 1e-6 * std::abs(fa[i]) + 1e-30) << "film value " << i;
    }
    EXPECT_GT(total, 0.0);
}

TEST(MitsubaLoader, AFilmComparisonCanFail) {
    // The twin with its light 1% brighter is told apart.
    SceneDesc x = loadScene(kScenes + "mitsuba/cornell_medium.xml"), y = x;
    y.lights[0].power *= 1.01;
    const std::vector<float> a = renderSmall(x), b = renderSmall(y);
    double diff = 0.0, total = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        diff += std::fabs(double(a[i]) - b[i]);
        total += a[i];
    }
    EXPECT_GT(diff / total, 1e-3);
}

// ---- transforms, sensor ----------------------------------------------------------------------------

TEST(MitsubaLoader, TransformsComposeInMitsubasOrder) {
    // scale, then rotate 90 deg about z, then translate: each later element pre-multiplies.
    const SceneDesc d = load(scene(R"(<shape type="cube"><transform name="to_world">
        <scale x="2" y="3" z="4"/><rotate z="1" angle="90"/><translate value="1, 2, 3"/></transform></shape>)"));
    const Mat4 want = glm::translate(Mat4(1.0), Vec3(1, 2, 3)) * glm::rotate(Mat4(1.0), kPi / 2, Vec3(0, 0, 1)) *
                      glm::scale(Mat4(1.0), Vec3(2, 3, 4));
    ASSERT_EQ(d.shapes.size(), 1u);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(d.shapes[0].transform[c][r], want[c][r], 1e-12);
    // By hand: the corner (1, 1, 1) -> scale (2, 3, 4) -> rotate (-3, 2, 4) -> translate (-2, 4, 7).
    expectNear(Vec3(d.shapes[0].transform * glm::dvec4(1, 1, 1, 1)), Vec3(-2, 4, 7));
}

TEST(MitsubaLoader, RectangleMatrixLookatAndFlip) {
    // A rectangle is [-1,1]^2 at z = 0 with normal +z; a row-major matrix.
    SceneDesc d = load(scene(R"(<shape type="rectangle"><transform name="to_world">
        <matrix value="2 0 0 1, 0 3 0 0, 0 0 1 5, 0 0 0 1"/></transform></shape>
        <shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>
        <shape type="rectangle"><transform name="to_world"><lookat origin="0, 0, 0" target="0, -1, 0" up="0, 0, 1"/></transform></shape>)"));
    ASSERT_EQ(d.shapes.size(), 3u);
    expectNear(d.shapes[0].corner, Vec3(-1, -3, 5));
    expectNear(d.shapes[0].edgeU, Vec3(4, 0, 0));
    expectNear(d.shapes[0].edgeV, Vec3(0, 6, 0));
    EXPECT_FALSE(d.shapes[0].flipNormals);
    EXPECT_TRUE(d.shapes[1].flipNormals);
    // lookat: +z goes to the direction (0, -1, 0); the quad's normal cross(edgeU, edgeV) too.
    const Vec3 n = glm::normalize(glm::cross(d.shapes[2].edgeU, d.shapes[2].edgeV));
    expectNear(n, Vec3(0, -1, 0));
}

TEST(MitsubaLoader, SphereToWorldAndDisk) {
    const SceneDesc d = load(scene(R"(<shape type="sphere"><float name="radius" value="2"/><transform name="to_world">
        <rotate x="1" angle="30"/><scale value="0.5"/><translate x="1"/></transform></shape>
        <shape type="disk"><transform name="to_world"><scale value="2"/></transform></shape>)"));
    expectNear(d.shapes[0].center, Vec3(1, 0, 0));
    EXPECT_NEAR(d.shapes[0].radius, 1.0, 1e-12);
    // The disk: a fan of 128 triangles whose area is 128/2 sin(2 pi / 128) of pi r^2 (0.9996).
    const ShapeDesc& disk = d.shapes[1];
    ASSERT_EQ(disk.inlineTriangles.size(), 128u);
    double area = 0.0;
    for (const glm::uvec3& t : disk.inlineTriangles) {
        const Vec3 a(disk.transform * glm::dvec4(disk.inlinePositions[t.x], 1)),
            b(disk.transform * glm::dvec4(disk.inlinePositions[t.y], 1)),
            c(disk.transform * glm::dvec4(disk.inlinePositions[t.z], 1));
        const Vec3 n = glm::cross(b - a, c - a);
        EXPECT_GT(n.z, 0.0);  // normal +z
        area += 0.5 * glm::length(n);
    }
    EXPECT_NEAR(area, 4.0 * kPi * 64.0 / kPi * std::sin(2.0 * kPi / 128.0), 1e-9);
    EXPECT_NEAR(area / (4.0 * kPi), 1.0, 5e-4);
    expectError(
        scene(R"(<shape type="sphere"><transform name="to_world"><scale x="1" y="2" z="1"/></transform></shape>)"), 2,
        "rotation, a uniform scale and a translation");
}

TEST(MitsubaLoader, FovAxisConversions) {
    const auto fovY = [](const std::string& axis, int w, int h) {
        const std::string s =
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/><string name=\"fov_axis\" value=\"" + axis +
            "\"/><film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(w) +
            "\"/><integer name=\"height\" value=\"" + std::to_string(h) + "\"/></film></sensor>";
        return load(scene("", s)).camera.fovYDeg;
    };
    const double t = std::tan(kPi / 6), deg = 180.0 / kPi;
    EXPECT_NEAR(fovY("y", 200, 100), 60.0, 1e-12);
    EXPECT_NEAR(fovY("x", 200, 100), 2 * std::atan(t / 2) * deg, 1e-12);
    EXPECT_NEAR(fovY("diagonal", 200, 100), 2 * std::atan(t / std::sqrt(5.0)) * deg, 1e-12);
    EXPECT_NEAR(fovY("smaller", 200, 100), 60.0, 1e-12);                        // the height
    EXPECT_NEAR(fovY("larger", 200, 100), 2 * std::atan(t / 2) * deg, 1e-12);   // the width
    EXPECT_NEAR(fovY("smaller", 100, 200), 2 * std::atan(t * 2) * deg, 1e-12);  // the width
    // No fov: Mitsuba's 50 mm focal length on the 35 mm diagonal.
    const SceneDesc d =
        load(scene("",
                   "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"36\"/>"
                   "<integer name=\"height\" value=\"24\"/></film></sensor>"));
    EXPECT_NEAR(std::tan(d.camera.fovYDeg / 2 / deg), 12.0 / 50.0, 1e-12);
    expectError(scene("",
                      "<sensor type=\"perspective\">\n<string name=\"fov_axis\" value=\"z\"/><float name=\"fov\" "
                      "value=\"30\"/></sensor>"),
                3, "unknown fov_axis");
}

TEST(MitsubaLoader, SensorLookatFilmAndMedium) {
    const SceneDesc d = load(scene(
        R"(<medium type="homogeneous" id="m"><float name="sigma_t" value="2"/>
        <rgb name="albedo" value="0.5, 0.25, 1"/><float name="scale" value="3"/></medium>)",
        R"(<sensor type="perspective"><transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform>
        <ref id="m"/><film type="transient_hdr_film"><integer name="width" value="40"/><integer name="height" value="30"/>
        <integer name="temporal_bins" value="50"/><float name="bin_width_opl" value="0.02"/><float name="start_opl" value="1.5"/></film></sensor>)"));
    expectNear(d.camera.position, Vec3(1, 2, 3));
    expectNear(glm::normalize(d.camera.lookAt - d.camera.position), Vec3(0, 0, -1));
    EXPECT_EQ(d.camera.width, 40);
    EXPECT_EQ(d.camera.height, 30);
    EXPECT_EQ(d.film.bins, 50);
    EXPECT_FALSE(d.film.autoRange);
    EXPECT_EQ(d.film.binWidthOpl, 0.02);
    EXPECT_EQ(d.film.startOpl, 1.5);
    ASSERT_EQ(d.globalMedium, 0);
    expectNear(d.media[0].sigma_s, Vec3(3, 1.5, 6));  // albedo sigma_t scale
    expectNear(d.media[0].sigma_a, Vec3(3, 4.5, 0));
    EXPECT_EQ(d.media[0].g, 0.0);  // no phase: isotropic
    // hdrfilm: the time axis is automatic.
    const SceneDesc h = load(scene("", R"(<sensor type="perspective"><film type="hdrfilm"/></sensor>)"));
    EXPECT_TRUE(h.film.autoRange);
    EXPECT_EQ(h.camera.width, 768);
    EXPECT_EQ(h.camera.height, 576);
}

// ---- unit conversions, materials -------------------------------------------------------------------

TEST(MitsubaLoader, EmitterUnitConversions) {
    const SceneDesc d = load(scene(R"(<emitter type="point"><rgb name="intensity" value="1, 2, 3"/></emitter>
        <shape type="rectangle"><transform name="to_world"><scale x="2" y="3"/></transform>
          <emitter type="area"><float name="radiance" value="5"/></emitter></shape>
        <emitter type="spot"><float name="intensity" value="2"/><float name="cutoff_angle" value="30"/>
          <float name="beam_width" value="30"/></emitter>
        <emitter type="spot"/>)"));
    ASSERT_EQ(d.lights.size(), 4u);
    expectNear(d.lights[0].power, 4 * kPi * Vec3(1, 2, 3));  // flux = 4 pi I
    EXPECT_EQ(d.lights[1].type, LightType::AreaQuad);
    EXPECT_TRUE(d.shapes.empty());                      // tpb draws the light's quad itself
    expectNear(d.lights[1].power, Vec3(kPi * 5 * 24));  // flux = pi L A, A = 4 x 6 m^2
    expectNear(glm::normalize(glm::cross(d.lights[1].edgeU, d.lights[1].edgeV)), Vec3(0, 0, 1));  // emits along +z
    // A hard-edged spot: flux = I * 2 pi (1 - cos 30 deg), to the midpoint rule's accuracy.
    EXPECT_NEAR(d.lights[2].power.x, 2 * 2 * kPi * (1 - std::cos(kPi / 6)), 1e-6);
    expectNear(d.lights[2].direction, Vec3(0, 0, 1));
    // Mitsuba's defaults: cutoff 20 deg, beam_width 3/4 of it.
    EXPECT_EQ(d.lights[3].spotCutoffDeg, 20.0);
    EXPECT_EQ(d.lights[3].spotFalloffDeg, 15.0);
    EXPECT_NEAR(d.lights[3].power.x, Light::fromDesc(d.lights[3]).spotIntegral, 1e-12);  // I = 1
}

TEST(MitsubaLoader, BsdfsAndDefaults) {
    const SceneDesc d = load(scene(
        R"(<bsdf type="twosided" id="w"><bsdf type="diffuse"><spectrum name="reflectance" value="0.3"/></bsdf></bsdf>
        <shape type="cube"><ref id="w"/></shape>
        <shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="water"/></bsdf></shape>
        <shape type="cube"/>
        <shape type="cube"><medium type="homogeneous" name="interior"><phase type="hg"/></medium></shape>
        <shape type="cube"><bsdf type="roughconductor"/></shape>
        <shape type="cube"><bsdf type="thindielectric"/></shape>)"));
    ASSERT_EQ(d.shapes.size(), 6u);
    const auto mat = [&](int i) { return d.materials[d.shapes[i].material]; };
    EXPECT_EQ(mat(0).type, MaterialType::Diffuse);
    expectNear(mat(0).albedo, Vec3(0.3));
    EXPECT_EQ(mat(1).type, MaterialType::Dielectric);
    EXPECT_EQ(mat(1).ior, 1.3330);
    EXPECT_EQ(mat(2).type, MaterialType::Diffuse);  // Mitsuba's default bsdf
    expectNear(mat(2).albedo, Vec3(0.5));
    EXPECT_EQ(mat(3).type, MaterialType::Null);             // a medium boundary without a bsdf
    EXPECT_EQ(d.media[d.shapes[3].interiorMedium].g, 0.8);  // hg's default
    EXPECT_EQ(mat(4).type, MaterialType::Mirror);
    EXPECT_EQ(mat(5).type, MaterialType::Null);
    int mirrorWarnings = 0, thinWarnings = 0;
    for (const std::string& w : d.warnings) {
        mirrorWarnings += w.rfind("t.xml:7: <bsdf type=\"roughconductor\">: imported as a perfect mirror", 0) == 0;
        thinWarnings += w.rfind("t.xml:8: <bsdf type=\"thindielectric\">: tpb has no thin dielectric", 0) == 0;
    }
    EXPECT_EQ(mirrorWarnings, 1);
    EXPECT_EQ(thinWarnings, 1);
    double ior = 0;
    for (const char* n : {"vacuum", "air", "water", "bk7", "diamond", "acrylic glass"})
        EXPECT_TRUE(mitsubaNamedIor(n, ior)) << n;
    EXPECT_FALSE(mitsubaNamedIor("unobtainium", ior));
}

// ---- defaults, $param, include, ref, integrator ----------------------------------------------------

TEST(MitsubaLoader, DefaultsParametersIncludesAndRefs) {
    test::TempDir tmp("test_mitsuba_loader");
    std::filesystem::create_directories(tmp.path() / "sub");
    tmp.write("sub/walls.xml",
              R"(<scene version="3.0.0"><bsdf type="diffuse" id="grey"><float name="reflectance" value="$refl"/></bsdf>
        <shape type="cube" id="inc"><ref id="grey"/></shape></scene>)");
    tmp.write("main.xml", R"(<scene version="3.0.0">
    <default name="refl" value="0.25"/>
    <default name="r" value="2"/>
    <include filename="sub/walls.xml"/>
    <shape type="sphere"><float name="radius" value="$r"/><ref id="grey"/></shape>
    <integrator type="transient_path"><integer name="max_depth" value="5"/><integer name="tpb_passes" value="3"/>
        <string name="tpb_volume_estimator" value="beam1d"/><float name="tpb_radius" value="0.05"/></integrator>
</scene>)");
    const SceneDesc d = loadScene((tmp.path() / "main.xml").string());
    ASSERT_EQ(d.shapes.size(), 2u);
    EXPECT_EQ(d.shapes[0].material, d.shapes[1].material);  // one material for the two refs
    expectNear(d.materials[d.shapes[0].material].albedo, Vec3(0.25));
    EXPECT_EQ(d.shapes[1].radius, 2.0);
    EXPECT_EQ(d.render.maxDepth, 4);  // Mitsuba counts segments
    EXPECT_EQ(d.render.passes, 3);
    EXPECT_EQ(d.render.volumeEstimator, "beam1d");
    EXPECT_FALSE(d.render.radiusRelative);
    EXPECT_EQ(d.render.radius, 0.05);
    // The included file's elements carry their own file and line.
    EXPECT_EQ(d.locs.at("shapes[0]").file, (tmp.path() / "sub/walls.xml").lexically_normal().string());
    EXPECT_EQ(d.locs.at("shapes[1]").line, 5);
    EXPECT_EQ(d.locs.at("render.passes").line, 6);
    // -D name=value wins over <default>.
    MitsubaOptions o;
    o.params["r"] = "3";
    EXPECT_EQ(loadMitsubaScene((tmp.path() / "main.xml").string(), o).shapes[1].radius, 3.0);
    // A bad render setting is reported at its XML line by the render settings' own check
    // (RenderSettings::validate, when prepareRender checks the loaded file).
    tmp.write("bad.xml",
              "<scene version=\"3.0.0\">\n<integrator type=\"path\">\n<float name=\"tpb_alpha\" "
              "value=\"7\"/></integrator></scene>");
    try {
        PrepareOptions opt;
        opt.pilot.run = false;
        prepareRender(loadScene((tmp.path() / "bad.xml").string()), {}, opt);
        ADD_FAILURE() << "no error";
    } catch (const UserError& e) {
        EXPECT_THAT(e.what(), HasSubstr("bad.xml:3: render.alpha"));
    }
}

// ---- PLY ---------------------------------------------------------------------------------------------

TEST(MitsubaLoader, PlyAsciiAndBinary) {
    const std::string header =
        "ply\nformat ascii 1.0\ncomment a quad and a triangle\nelement vertex 5\nproperty float x\n"
        "property float y\nproperty float z\nproperty uchar red\nelement face 2\n"
        "property list uchar int vertex_indices\nend_header\n";
    const TriangleMesh a =
        parsePly(header + "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n0 0 1 5\n4 0 1 2 3\n3 0 1 4\n", "a.ply");
    EXPECT_EQ(a.positions.size(), 5u);
    ASSERT_EQ(a.triangles.size(), 3u);
    EXPECT_EQ(a.triangles[1], glm::uvec3(0, 2, 3));
    // The same as binary_little_endian, with double coordinates and uint indices.
    std::string b =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
        "property double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    for (double v : {0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0, 0.0}) b.append(reinterpret_cast<const char*>(&v), 8);
    b.push_back(3);
    for (uint32_t i : {0u, 1u, 2u}) b.append(reinterpret_cast<const char*>(&i), 4);
    const TriangleMesh m = parsePly(b, "b.ply");
    ASSERT_EQ(m.triangles.size(), 1u);
    expectNear(m.positions[2], Vec3(0, 3, 0));
    EXPECT_THROW(parsePly(b.substr(0, b.size() - 2), "b.ply"), UserError);  // truncated
    try {
        parsePly(header + "0 0 0 1\n1 0 0 2\n1 x 0 3\n", "a.ply");
        ADD_FAILURE();
    } catch (const UserError& e) {
        EXPECT_THAT(e.what(), HasSubstr("a.ply:14: \"x\" is not a number"));
    }
    // Through an XML scene, with its transform, to a built scene.
    test::TempDir tmp("test_mitsuba_ply");
    tmp.write("m.ply", b);
    tmp.write("s.xml", R"(<scene version="3.0.0"><shape type="ply"><string name="filename" value="m.ply"/>
        <transform name="to_world"><translate x="1"/></transform></shape><emitter type="point"><point name="position" value="0,0,1"/></emitter></scene>)");
    const test::TestScene ts = test::prepareTestScene(loadScene((tmp.path() / "s.xml").string()));
    EXPECT_NEAR(ts->geometry.bounds().hi.x, 3.0, 1e-12);
}

// ---- errors: file:line: element: problem ----------------------------------------------------------

TEST(MitsubaLoader, ErrorsNameFileAndLine) {
    expectError("<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n</scene>", 3, "XML parse error");
    expectError(scene("<shape type=\"cylinder\"/>"), 2, "unsupported shape type \"cylinder\"");
    expectError(scene("<shape type=\"cube\">\n<ref id=\"nope\"/></shape>"), 3, "no object has the id \"nope\"");
    expectError(scene("<shape type=\"sphere\">\n<float name=\"radius\" value=\"1.5x\"/></shape>"), 3,
                "\"1.5x\" is not a finite number");
    expectError(scene("<bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"bitmap\"/></bsdf>"), 3,
                "textures are not supported");
    expectError(scene("<bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"400:0.1, 700:0.9\"/></bsdf>"), 3,
                "wavelength-dependent spectrum");
    expectError(scene("<shape type=\"sphere\"><float name=\"radius\" value=\"$nope\"/></shape>"), 2,
                "undefined parameter $nope");
    expectError(scene("\n<emitter type=\"directional\"/>"), 3, "directional emitters are not supported");
    expectError(scene("<bsdf type=\"plastic\"/>"), 2, "unsupported bsdf type \"plastic\"");
    expectError(scene("<medium type=\"heterogeneous\"/>"), 2, "unsupported medium type");
    expectError(scene("<shape type=\"obj\"><string name=\"filename\" value=\"missing.obj\"/></shape>"), 2,
                "mesh file not found");
    expectError(scene("<integrator type=\"path\"><integer name=\"max_depth\" value=\"1\"/></integrator>"), 2,
                "max_depth must be >= 2");
    expectError(scene("<shape type=\"rectangle\"><medium type=\"homogeneous\" name=\"interior\"/></shape>"), 2, "open");
    expectError(scene("<shape type=\"cube\" id=\"a\"/>\n<shape type=\"cube\" id=\"a\"/>"), 3, "already used");
    expectError("<scene version=\"3.0.0\">\n<include filename=\"nowhere.xml\"/></scene>", 2,
                "cannot open the included file");
}

// Issue 33 item 8: XML nested 50,000 deep overflowed the stack (the importer walks elements
// recursively). Nesting beyond 256 levels is refused at the first element too deep, by file:line,
// without recursion; 255 levels below <scene> pass.
TEST(MitsubaLoader, DeepNestingIsRefusedWithoutRecursion) {
    const auto nested = [](int depth) {
        std::string x = "<scene version=\"3.0.0\">\n";
        for (int i = 0; i < depth; ++i) x += "<bsdf type=\"twosided\">\n";
        for (int i = 0; i < depth; ++i) x += "</bsdf>";
        return x + "</scene>\n";
    };
    expectError(nested(50000), 257, "nested deeper than 256 levels (<bsdf> here)");  // the 256th <bsdf>
    expectError(nested(256), 257, "nested deeper than 256");
    // 255 levels pass the check (and are then refused for what they are, not for the depth).
    try {
        load(nested(255));
    } catch (const UserError& e) {
        EXPECT_THAT(e.what(), Not(HasSubstr("nested deeper")));
    }
    // Deep in an included file: that file's line.
    test::TempDir tmp("test_mitsuba_nesting");
    tmp.write("deep.xml", nested(300));
    tmp.write("main.xml", "<scene version=\"3.0.0\">\n<include filename=\"deep.xml\"/>\n</scene>\n");
    try {
        loadScene((tmp.path() / "main.xml").string());
        ADD_FAILURE() << "no error";
    } catch (const UserError& e) {
        EXPECT_EQ(e.file(), (tmp.path() / "deep.xml").lexically_normal().string()) << e.what();
        EXPECT_EQ(e.line(), 257) << e.what();
    }
}

// Issue 33 item 8: a mesh that holds a medium must be closed, or the medium leaks out through its
// holes; an open OBJ with an interior medium is refused by the shape's line, with the count of
// open edges. The same open mesh as a plain dielectric (no interior medium) still loads.
TEST(MitsubaLoader, OpenMeshHoldingAMediumIsRefused) {
    test::TempDir tmp("test_mitsuba_open_mesh");
    // A unit cube without its y = 1 face: 10 triangles, that square's 4 edges open.
    tmp.write("open.obj",
              "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
              "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 1 5 8 4\n");
    const std::string body = R"(<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="1"/></medium>
<shape type="obj">
<string name="filename" value="open.obj"/><ref name="interior" id="fog"/></shape>)";
    tmp.write("s.xml", scene(body));
    try {
        test::prepareTestScene(loadScene((tmp.path() / "s.xml").string()));
        ADD_FAILURE() << "no error";
    } catch (const UserError& e) {
        const std::string msg = e.what();
        EXPECT_THAT(msg, HasSubstr("s.xml:3: shapes[0]: "));
        EXPECT_THAT(msg, HasSubstr("open.obj"));
        EXPECT_THAT(msg, HasSubstr("holds a medium but is not closed: 4 edges of one triangle only"));
        EXPECT_THAT(msg, HasSubstr("Close the mesh"));
    }
    tmp.write(
        "glass.xml",
        scene(R"(<shape type="obj"><string name="filename" value="open.obj"/><bsdf type="dielectric"/></shape>)"));
    EXPECT_NO_THROW(test::prepareTestScene(loadScene((tmp.path() / "glass.xml").string())));
}

TEST(MitsubaLoader, UnknownParametersAreWarnedAbout) {
    const SceneDesc d = load(scene("<shape type=\"sphere\">\n<float name=\"radious\" value=\"2\"/></shape>"));
    ASSERT_FALSE(d.warnings.empty());
    EXPECT_THAT(d.warnings[0],
                HasSubstr("t.xml:3: <float name=\"radious\">: unknown or unsupported parameter \"radious\""));
}

// ---- mitransient's NLOS setup (nlos_capture_meter on the relay wall, a projector laser) -----------

namespace {

// A mitransient-style NLOS scene, as tal writes it: a 2 m relay wall at z = 0 (the rectangle's
// default) holding the capture meter, the sensor and the laser at (-0.5, 0, 0.25), a 0.5 m target
// at z = 1. Every element on its own line (the refusals name them): {K} fields are replaced.
std::string nlosScene(const std::map<std::string, std::string>& k = {}) {
    std::string t = R"(<scene version="3.0.0">
<integrator type="transient_nlos_path">
<string name="capture_type" value="{CAPTURE}"/>
<boolean name="account_first_and_last_bounces" value="{ACCOUNT}"/>
<integer name="tpb_photons_per_pass" value="3000"/><float name="tpb_surface_radius" value="0.08"/><float name="tpb_radius" value="0.01"/><integer name="max_depth" value="4"/>{INTEGRATOR}
</integrator>
{EMITTER}
<shape type="rectangle" id="target"><transform name="to_world"><scale value="0.25"/><translate z="1"/></transform></shape>
<shape type="{WALL}" id="relay_wall"><bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>
<sensor type="{SENSOR}">
<point name="sensor_origin" x="-0.5" y="0" z="0.25"/>{SENSOR_EXTRA}
<film type="transient_hdr_film"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>{FILM}
<integer name="temporal_bins" value="150"/><float name="bin_width_opl" value="0.04"/><float name="start_opl" value="0"/><rfilter type="box"/></film>
</sensor></shape>
{TAIL}
</scene>
)";
    std::map<std::string, std::string> v = {
        {"CAPTURE", "confocal"},
        {"ACCOUNT", "false"},
        {"INTEGRATOR", ""},
        {"EMITTER",
         R"(<emitter type="projector" id="laser"><transform name="to_world"><translate x="-0.5" y="0" z="0.25"/></transform><rgb name="irradiance" value="1, 2, 3"/><float name="fov" value="0.2"/></emitter>)"},
        {"WALL", "rectangle"},
        {"SENSOR", "nlos_capture_meter"},
        {"SENSOR_EXTRA", ""},
        {"W", "8"},
        {"H", "6"},
        {"FILM", ""},
        {"TAIL", ""}};
    for (const auto& [key, val] : k) v[key] = val;
    for (const auto& [key, val] : v) {
        const std::string f = "{" + key + "}";
        for (size_t at; (at = t.find(f)) != std::string::npos;) t.replace(at, f.size(), val);
    }
    return t;
}

bool hasWarning(const SceneDesc& d, const std::string& fragment) {
    for (const std::string& w : d.warnings)
        if (w.find(fragment) != std::string::npos) return true;
    return false;
}

// One pass of the Driver over the imported scene: no error, light on the film.
void renderOnePass(const SceneDesc& d) {
    test::TestScene ts = test::prepareTestScene(d);
    RenderSettings s = ts.settings;
    s.threads = 2;
    Driver drv(*ts, s, ts.time);
    EXPECT_TRUE(drv.runPass(1));
    std::vector<float> img;
    drv.film().steadyImage(img);
    double total = 0.0;
    for (float x : img) total += x;
    EXPECT_GT(total, 0.0);
}

}  // namespace

TEST(MitsubaLoader, NlosConfocalCaptureImportsAsARelayWallScan) {
    const SceneDesc d = load(nlosScene());
    const CameraDesc& c = d.camera;
    EXPECT_EQ(c.type, CameraType::RelayWall);
    ASSERT_EQ(c.wallShape, 1);
    const ShapeDesc& w = d.shapes[1];
    EXPECT_EQ(w.name, "relay_wall");
    EXPECT_EQ(w.type, ShapeType::Quad);
    expectNear(w.corner, Vec3(-1, -1, 0));
    expectNear(w.edgeU, Vec3(2, 0, 0));
    expectNear(w.edgeV, Vec3(0, 2, 0));
    EXPECT_EQ(c.width, 8);
    EXPECT_EQ(c.height, 6);
    expectNear(c.position, Vec3(-0.5, 0, 0.25));
    EXPECT_EQ(c.timeOrigin, WallTimeOrigin::Wall);  // account_first_and_last_bounces false
    EXPECT_EQ(c.scan, ScanMode::Confocal);
    ASSERT_EQ(c.scanLaser, 0);
    const LightDesc& l = d.lights[0];
    EXPECT_EQ(l.type, LightType::Laser);
    EXPECT_EQ(l.name, "laser");
    expectNear(l.position, Vec3(-0.5, 0, 0.25));
    EXPECT_EQ(l.laserRadius, 0.0);
    // flux = pi * irradiance * (2 tan(fov / 2))^2: the projector's image at z = 1.
    const double a = std::pow(2.0 * std::tan(0.1 * kPi / 180.0), 2.0);
    expectNear(l.power, Color(1, 2, 3) * (kPi * a), 1e-18);
    EXPECT_FALSE(d.film.autoRange);
    EXPECT_EQ(d.film.bins, 150);
    EXPECT_EQ(d.film.binWidthOpl, 0.04);
    EXPECT_EQ(d.film.startOpl, 0.0);
    EXPECT_EQ(d.render.maxDepth, 3);
    EXPECT_FALSE(hasWarning(d, "the scene has no sensor"));
    EXPECT_EQ(d.where("camera.scan.laser"), "t.xml:7: ");
    renderOnePass(d);
    // account_first_and_last_bounces true counts both legs: tpb's "sensor" origin.
    EXPECT_EQ(load(nlosScene({{"ACCOUNT", "true"}})).camera.timeOrigin, WallTimeOrigin::Sensor);
}

TEST(MitsubaLoader, NlosSingleCaptureAims) {
    // laser_lookat_pixel in film pixels (mitransient's focus_emitter_at_relay_wall_pixel: uv = pixel / size).
    SceneDesc d = load(nlosScene(
        {{"CAPTURE", "single"}, {"SENSOR_EXTRA", R"(<point name="laser_lookat_pixel" x="2" y="3" z="0"/>)"}}));
    EXPECT_EQ(d.camera.scan, ScanMode::Single);
    EXPECT_DOUBLE_EQ(d.camera.scanPointU, 0.25);
    EXPECT_DOUBLE_EQ(d.camera.scanPointV, 0.5);
    expectNear(d.lights[0].direction, Vec3(0, 0, -1), 1e-15);
    renderOnePass(d);
    // laser_lookat_3d: a wall point.
    d = load(
        nlosScene({{"CAPTURE", "1"}, {"SENSOR_EXTRA", R"(<point name="laser_lookat_3d" x="0.5" y="-0.5" z="0"/>)"}}));
    EXPECT_DOUBLE_EQ(d.camera.scanPointU, 0.75);
    EXPECT_DOUBLE_EQ(d.camera.scanPointV, 0.25);
    // A lookat in the projector's to_world.
    d = load(nlosScene(
        {{"CAPTURE", "single"},
         {"EMITTER",
          R"(<emitter type="projector" id="laser"><transform name="to_world"><lookat origin="-0.5, 0, 0.25" target="0.5, 0.5, 0"/></transform><float name="fov" value="0.2"/></emitter>)"}}));
    EXPECT_NEAR(d.camera.scanPointU, 0.75, 1e-12);
    EXPECT_NEAR(d.camera.scanPointV, 0.75, 1e-12);
    // tal's projector (a translation, aimed from Python): the wall's centre, with a warning.
    d = load(nlosScene({{"CAPTURE", "single"}}));
    EXPECT_EQ(d.camera.scanPointU, 0.5);
    EXPECT_EQ(d.camera.scanPointV, 0.5);
    EXPECT_TRUE(hasWarning(d, "t.xml:7: <transform name=\"to_world\">: the laser is not aimed in the file"));
    // mitsuba2-transient-nlos's laser_origin places an untransformed projector.
    d = load(nlosScene({{"CAPTURE", "single"},
                        {"EMITTER", R"(<emitter type="projector"><float name="fov" value="0.2"/></emitter>)"},
                        {"SENSOR_EXTRA", R"(<point name="laser_origin" x="-0.4" y="0.1" z="0.3"/>)"}}));
    expectNear(d.lights[0].position, Vec3(-0.4, 0.1, 0.3));
    EXPECT_EQ(d.lights[0].name, "laser");  // the only projector
}

TEST(MitsubaLoader, NlosExhaustiveAndSequentialConfocalCaptures) {
    SceneDesc d = load(nlosScene(
        {{"CAPTURE", "exhaustive"},
         {"FILM",
          R"(<boolean name="exhaustive_scan" value="true"/><integer name="laser_scan_width" value="8"/><integer name="laser_scan_height" value="6"/>)"}}));
    EXPECT_EQ(d.camera.scan, ScanMode::Exhaustive);
    EXPECT_EQ(d.camera.laserGridX, 8);
    EXPECT_EQ(d.camera.laserGridY, 6);
    // tal without simultaneous_scan: one laser point per render, its grid in laser_scan_*.
    d = load(nlosScene(
        {{"CAPTURE", "3"},
         {"FILM", R"(<integer name="laser_scan_width" value="2"/><integer name="laser_scan_height" value="3"/>)"}}));
    EXPECT_EQ(d.camera.laserGridX, 2);
    EXPECT_EQ(d.camera.laserGridY, 3);
    EXPECT_TRUE(hasWarning(d, "exhaustive_scan is false"));
    renderOnePass(d);
    // tal's sequential confocal scan: a 1 x 1 film, the scan in original_film_width/height.
    d = load(nlosScene(
        {{"W", "1"},
         {"H", "1"},
         {"SENSOR_EXTRA",
          R"(<integer name="original_film_width" value="4"/><integer name="original_film_height" value="5"/>)"}}));
    EXPECT_EQ(d.camera.scan, ScanMode::Confocal);
    EXPECT_EQ(d.camera.width, 4);
    EXPECT_EQ(d.camera.height, 5);
    EXPECT_TRUE(hasWarning(d, "t.xml:11: <integer name=\"original_film_width\">: one confocal point per render"));
}

TEST(MitsubaLoader, NlosRefusals) {
    expectError(nlosScene({{"WALL", "sphere"}}), 9, "relay wall must be a rectangle");
    expectError(nlosScene({{"TAIL", R"(<shape type="rectangle"><sensor type="nlos_capture_meter"/></shape>)"}}), 15,
                "a second nlos_capture_meter (the first is at line 10)");
    expectError(nlosScene({{"EMITTER", R"(<emitter type="spot" id="laser"/>)"}}), 7,
                "the NLOS laser (id \"laser\") is a spot light");
    expectError(
        nlosScene({{"EMITTER", R"(<emitter type="projector" id="laser"><float name="fov" value="30"/></emitter>)"}}), 7,
        "spreads over 30 degrees");
    expectError(nlosScene({{"CAPTURE", "exhaustive"},
                           {"INTEGRATOR", R"(<boolean name="force_equal_illumination_scanning" value="false"/>)"}}),
                5, "force_equal_illumination_scanning false");
    expectError(
        nlosScene({{"CAPTURE", "exhaustive"},
                   {"FILM",
                    R"(<boolean name="exhaustive_scan" value="true"/><integer name="laser_scan_width" value="4"/>)"}}),
        12, "must equal the film's width x height");
    expectError(nlosScene({{"CAPTURE", "single"},
                           {"SENSOR_EXTRA", R"(<point name="laser_lookat_pixel" x="20" y="1" z="0"/>)"}}),
                11, "outside the relay wall");
    expectError(
        nlosScene(
            {{"CAPTURE", "single"},
             {"EMITTER",
              R"(<emitter type="projector"><transform name="to_world"><rotate y="1" angle="90"/><translate x="-0.5" z="0.25"/></transform><float name="fov" value="0.2"/></emitter>)"}}),
        7, "aims at no point of the relay wall");
    expectError(nlosScene({{"CAPTURE", "zigzag"}}), 3, "unknown capture_type \"zigzag\"");
    expectError(nlosScene({{"SENSOR", "irradiancemeter"}}), 10, "tpb imports mitransient's \"nlos_capture_meter\"");
    expectError(nlosScene({{"SENSOR", "nloscapturemeter"}}), 10, "mitsuba2-transient-nlos");
    expectError(nlosScene({{"CAPTURE", "confocal"}, {"EMITTER", ""}}), 3, "a confocal capture needs its laser");
}
