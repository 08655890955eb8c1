// Scene loader and JSON parser: round trips, defaults, and one test per kind of user mistake, each
// checking that the message names the file, the line and the key.
#include "base/parallel.h"
#include "render/prepare.h"
#include "transport/stages.h"
#include "base/error.h"
#include "io/json.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "support/temp_dir.h"

#include <glm/gtc/matrix_transform.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sys/stat.h>
#include <unistd.h>

using namespace tpb;
using ::testing::HasSubstr;

namespace {

namespace fs = std::filesystem;

// Loads `text` as `file` and prepares its render as `tpb render` does (pilots off): the loader
// reads types, prepareRender checks the render block's ranges with the file's locations
// (RenderSettings::validate). The warnings of both, in order, go to `warnings`.
PreparedRender prepareText(const std::string& text, const std::string& file,
                           std::vector<std::string>* warnings = nullptr) {
    PrepareOptions opt;
    opt.pilot.run = false;
    if (warnings) opt.warn = [warnings](const std::string& w) { warnings->push_back(w); };
    return prepareRender(loadSceneFromString(text, file), {}, opt);
}

// Loads and prepares `text` as "scene.json" and expects a UserError at `line` about `key`
// containing `fragment`.
void expectError(const std::string& text, int line, const std::string& key, const std::string& fragment,
                 const std::string& file = "scene.json") {
    SCOPED_TRACE(text);
    try {
        prepareText(text, file);
        ADD_FAILURE() << "no error; expected: " << fragment;
    } catch (const UserError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.file(), file) << what;
        EXPECT_EQ(e.line(), line) << what;
        EXPECT_EQ(e.key(), key) << what;
        const std::string prefix = file + ":" + std::to_string(line) + ": " + (key.empty() ? "" : key + ": ");
        EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
        EXPECT_THAT(what, HasSubstr(fragment));
    }
}

// The error message of parseJson(text), or "" when it parses.
std::string jsonError(const std::string& text, int* line = nullptr) {
    try {
        parseJson(text, "t.json");
    } catch (const UserError& e) {
        if (line) *line = e.line();
        return e.what();
    }
    return "";
}

// A temporary folder with a tiny OBJ file, removed at the end.
struct ObjFolder {
    test::TempDir tmp{"test_scene_loader"};
    const fs::path dir = tmp.path();
    ObjFolder() { tmp.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"); }
    std::string scene() const { return (dir / "scene.json").string(); }
};

Vec3 apply(const Mat4& m, const Vec3& p) { return Vec3(m * glm::dvec4(p, 1.0)); }

void expectNear(const Vec3& a, const Vec3& b) {
    EXPECT_NEAR(a.x, b.x, 1e-12);
    EXPECT_NEAR(a.y, b.y, 1e-12);
    EXPECT_NEAR(a.z, b.z, 1e-12);
}

const char* kFullScene = R"({
  "version": 1,
  "_comment": "every section, every shape and light type",
  "camera": {"position": [0, 1, 5], "look_at": [0, 1, 0], "up": [0, 2, 0], "fov": 35, "resolution": [320, 240]},
  "film": {"bins": 100, "start_ns": 2, "bin_width_ns": 0.05},
  "media": {"fog": {"sigma_s": [0.1, 0.2, 0.3], "sigma_a": 0.05, "ior": 1.33, "g": 0.4}, "juice": {"sigma_s": 1}},
  "global_medium": "fog",
  "materials": {
    "white": {"type": "diffuse", "albedo": 0.5, "comment": "walls"},
    "chrome": {"type": "mirror", "reflectance": [0.9, 0.8, 0.7]},
    "glass": {"type": "dielectric", "ior": 1.6, "tint": 0.95},
    "container": {"type": "null"}
  },
  "shapes": [
    {"type": "mesh", "file": "tri.obj", "material": "glass", "interior_medium": "juice", "name": "tri", "flip_normals": true,
     "transform": {"translate": [1, 2, 3], "scale": 2, "rotate": {"axis": [0, 1, 0], "angle_deg": 90}}},
    {"type": "sphere", "center": [0, 1, 0], "radius": 0.3, "material": "chrome"},
    {"type": "quad", "corner": [-1, 0, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "white"},
    {"type": "box", "min": [0, 0, 0], "max": [1, 2, 3], "material": "container", "interior_medium": "fog",
     "transform": {"matrix": [1, 0, 0, 5,  0, 1, 0, 6,  0, 0, 1, 7,  0, 0, 0, 1]}}
  ],
  "lights": [
    {"type": "point", "position": [0, 2, 0], "power": 10, "emit_time_ns": 1},
    {"type": "spot", "position": [0, 2, 0], "direction": [0, -2, 0], "cutoff_deg": 20, "falloff_deg": 15, "power": [1, 2, 3], "emit_time_m": 0.5},
    {"type": "area", "corner": [0, 1.9, 0], "edge_u": [0.5, 0, 0], "edge_v": [0, 0, 0.5], "power": 4, "name": "ceiling"},
    {"type": "laser", "position": [0, 0, 0], "direction": [3, 0, 4], "radius": 0.001, "power": 2}
  ],
  "render": {"photons_per_pass": 50000, "radius": 0.02, "surface_radius": 0.03, "alpha": 0.5, "passes": 8,
             "time_budget_s": 60, "max_depth": 10, "seed": 18446744073709551615, "threads": 4,
             "emission": "continuous", "unwarp": true, "time_profile": "uniform", "beam_length": "long"}
})";

}  // namespace

// ---- round trips -----------------------------------------------------------------------------------

TEST(SceneLoader, FullSceneRoundTrip) {
    ObjFolder tmp;
    std::ofstream(tmp.scene()) << kFullScene;
    const SceneDesc d = loadScene(tmp.scene());
    EXPECT_EQ(d.path, tmp.scene());
    EXPECT_EQ(fs::path(d.dir), tmp.dir);
    EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();

    EXPECT_EQ(d.camera.position, Vec3(0, 1, 5));
    EXPECT_EQ(d.camera.lookAt, Vec3(0, 1, 0));
    EXPECT_EQ(d.camera.up, Vec3(0, 1, 0));  // normalized
    EXPECT_EQ(d.camera.fovYDeg, 35.0);
    EXPECT_EQ(d.camera.width, 320);
    EXPECT_EQ(d.camera.height, 240);

    EXPECT_FALSE(d.film.autoRange);
    EXPECT_EQ(d.film.bins, 100);
    EXPECT_DOUBLE_EQ(d.film.startOpl, 2 * kC_m_per_ns);
    EXPECT_DOUBLE_EQ(d.film.binWidthOpl, 0.05 * kC_m_per_ns);

    ASSERT_EQ(d.media.size(), 2u);
    EXPECT_EQ(d.media[0].name, "fog");
    EXPECT_EQ(d.media[0].sigma_s, Color(0.1, 0.2, 0.3));
    EXPECT_EQ(d.media[0].sigma_a, Color(0.05));
    EXPECT_EQ(d.media[0].ior, 1.33);
    EXPECT_EQ(d.media[0].g, 0.4);
    EXPECT_EQ(d.media[1].name, "juice");
    EXPECT_EQ(d.media[1].sigma_s, Color(1.0));
    EXPECT_EQ(d.media[1].sigma_a, Color(0.0));
    EXPECT_EQ(d.globalMedium, 0);

    ASSERT_EQ(d.materials.size(), 4u);
    EXPECT_EQ(d.materials[0].type, MaterialType::Diffuse);
    EXPECT_EQ(d.materials[0].albedo, Color(0.5));
    EXPECT_EQ(d.materials[1].type, MaterialType::Mirror);
    EXPECT_EQ(d.materials[1].specular, Color(0.9, 0.8, 0.7));
    EXPECT_EQ(d.materials[2].type, MaterialType::Dielectric);
    EXPECT_EQ(d.materials[2].ior, 1.6);
    EXPECT_EQ(d.materials[2].specular, Color(0.95));
    EXPECT_EQ(d.materials[3].type, MaterialType::Null);
    EXPECT_EQ(d.materials[3].name, "container");

    ASSERT_EQ(d.shapes.size(), 4u);
    const ShapeDesc& mesh = d.shapes[0];
    EXPECT_EQ(mesh.type, ShapeType::Mesh);
    EXPECT_EQ(mesh.name, "tri");
    EXPECT_EQ(fs::path(mesh.meshPath), tmp.dir / "tri.obj");
    EXPECT_EQ(mesh.material, 2);
    EXPECT_EQ(mesh.interiorMedium, 1);
    EXPECT_TRUE(mesh.flipNormals);
    // T * R * S: (1,0,0) -> scale 2 -> (2,0,0) -> 90 deg about +y -> (0,0,-2) -> + (1,2,3).
    expectNear(apply(mesh.transform, Vec3(1, 0, 0)), Vec3(1, 2, 1));
    expectNear(apply(mesh.transform, Vec3(0, 0, 0)), Vec3(1, 2, 3));
    EXPECT_EQ(d.shapes[1].type, ShapeType::Sphere);
    EXPECT_EQ(d.shapes[1].center, Vec3(0, 1, 0));
    EXPECT_EQ(d.shapes[1].radius, 0.3);
    EXPECT_EQ(d.shapes[1].material, 1);
    EXPECT_EQ(d.shapes[1].interiorMedium, -1);
    EXPECT_EQ(d.shapes[2].type, ShapeType::Quad);
    EXPECT_EQ(d.shapes[2].corner, Vec3(-1, 0, -1));
    EXPECT_EQ(d.shapes[2].edgeU, Vec3(2, 0, 0));
    EXPECT_EQ(d.shapes[2].edgeV, Vec3(0, 0, 2));
    EXPECT_EQ(d.shapes[2].material, 0);
    EXPECT_EQ(d.shapes[3].type, ShapeType::Box);
    EXPECT_EQ(d.shapes[3].boxMin, Vec3(0, 0, 0));
    EXPECT_EQ(d.shapes[3].boxMax, Vec3(1, 2, 3));
    EXPECT_EQ(d.shapes[3].interiorMedium, 0);
    expectNear(apply(d.shapes[3].transform, Vec3(1, 1, 1)), Vec3(6, 7, 8));  // row-major translation

    ASSERT_EQ(d.lights.size(), 4u);
    EXPECT_EQ(d.lights[0].type, LightType::Point);
    EXPECT_EQ(d.lights[0].power, Color(10.0));
    EXPECT_DOUBLE_EQ(d.lights[0].emitOpl, 0.299792458);
    EXPECT_EQ(d.lights[1].type, LightType::Spot);
    EXPECT_EQ(d.lights[1].direction, Vec3(0, -1, 0));
    EXPECT_EQ(d.lights[1].spotCutoffDeg, 20.0);
    EXPECT_EQ(d.lights[1].spotFalloffDeg, 15.0);
    EXPECT_EQ(d.lights[1].power, Color(1, 2, 3));
    EXPECT_EQ(d.lights[1].emitOpl, 0.5);
    EXPECT_EQ(d.lights[2].type, LightType::AreaQuad);
    EXPECT_EQ(d.lights[2].name, "ceiling");
    EXPECT_EQ(d.lights[2].corner, Vec3(0, 1.9, 0));
    EXPECT_EQ(d.lights[2].edgeV, Vec3(0, 0, 0.5));
    EXPECT_EQ(d.lights[3].type, LightType::Laser);
    expectNear(d.lights[3].direction, Vec3(0.6, 0, 0.8));
    EXPECT_EQ(d.lights[3].laserRadius, 0.001);

    const RenderDesc& r = d.render;
    EXPECT_EQ(r.photonsPerPass, 50000);
    EXPECT_FALSE(r.radiusRelative);
    EXPECT_EQ(r.radius, 0.02);
    EXPECT_EQ(r.surfaceRadius, 0.03);
    EXPECT_EQ(r.alpha, 0.5);
    EXPECT_EQ(r.passes, 8);
    EXPECT_EQ(r.timeBudgetSec, 60.0);
    EXPECT_EQ(r.maxDepth, 10);
    EXPECT_EQ(r.seed, 18446744073709551615ull);  // exact, not through a double
    EXPECT_EQ(r.threads, 4);
    EXPECT_EQ(r.emission, EmissionMode::Continuous);
    EXPECT_TRUE(r.unwarp);
    EXPECT_EQ(r.timeProfile, TimeProfile::Uniform);
    EXPECT_EQ(r.beamLength, BeamLength::Long);

    // Where each value was written.
    EXPECT_EQ(d.locs.at("camera.fov").line, 4);
    EXPECT_EQ(d.locs.at("camera.fov").file, tmp.scene());
    EXPECT_EQ(d.locs.at("film.start_ns").line, 5);
    EXPECT_EQ(d.locs.at("media.fog.sigma_s").line, 6);
    EXPECT_EQ(d.locs.at("media.juice").line, 6);
    EXPECT_EQ(d.locs.at("materials.chrome.reflectance").line, 10);
    EXPECT_EQ(d.locs.at("shapes[0].transform.rotate.angle_deg").line, 16);
    EXPECT_EQ(d.locs.at("shapes[1].radius").line, 17);
    EXPECT_EQ(d.locs.at("shapes[3].transform.matrix").line, 20);
    EXPECT_EQ(d.locs.at("lights[0].power").line, 23);
    EXPECT_EQ(d.locs.at("lights[2]").line, 25);
    EXPECT_EQ(d.locs.at("render.seed").line, 29);
    EXPECT_EQ(d.where("lights[0].power"), tmp.scene() + ":23: ");
}

TEST(SceneLoader, Defaults) {
    const SceneDesc d = loadSceneFromString(R"({"version": 1})", "min.json");
    const SceneDesc def;
    EXPECT_EQ(d.version, 1);
    EXPECT_EQ(d.path, "min.json");
    EXPECT_EQ(d.dir, ".");
    EXPECT_EQ(d.camera.position, def.camera.position);
    EXPECT_EQ(d.camera.lookAt, def.camera.lookAt);
    EXPECT_EQ(d.camera.up, def.camera.up);
    EXPECT_EQ(d.camera.fovYDeg, def.camera.fovYDeg);
    EXPECT_EQ(d.camera.width, def.camera.width);
    EXPECT_EQ(d.camera.height, def.camera.height);
    EXPECT_EQ(d.film.autoRange, def.film.autoRange);
    EXPECT_EQ(d.film.bins, def.film.bins);
    EXPECT_EQ(d.film.startOpl, def.film.startOpl);
    EXPECT_EQ(d.film.binWidthOpl, def.film.binWidthOpl);
    EXPECT_EQ(d.globalMedium, -1);
    EXPECT_TRUE(d.media.empty());
    EXPECT_TRUE(d.materials.empty());
    EXPECT_TRUE(d.shapes.empty());
    EXPECT_TRUE(d.lights.empty());
    EXPECT_EQ(d.render.photonsPerPass, def.render.photonsPerPass);
    EXPECT_EQ(d.render.radius, def.render.radius);
    EXPECT_EQ(d.render.radiusRelative, def.render.radiusRelative);
    EXPECT_EQ(d.render.surfaceRadius, def.render.surfaceRadius);
    EXPECT_EQ(d.render.alpha, def.render.alpha);
    EXPECT_EQ(d.render.passes, def.render.passes);
    EXPECT_EQ(d.render.timeBudgetSec, def.render.timeBudgetSec);
    EXPECT_EQ(d.render.maxDepth, def.render.maxDepth);
    EXPECT_EQ(d.render.seed, def.render.seed);
    EXPECT_EQ(d.render.threads, def.render.threads);
    EXPECT_EQ(d.render.emission, def.render.emission);
    EXPECT_EQ(d.render.unwarp, def.render.unwarp);
    EXPECT_EQ(d.render.timeProfile, def.render.timeProfile);
    EXPECT_EQ(d.render.beamLength, def.render.beamLength);
    ASSERT_EQ(d.warnings.size(), 1u);
    EXPECT_THAT(d.warnings[0], HasSubstr("no lights"));
}

TEST(SceneLoader, MissingVersionWarns) {
    const SceneDesc d = loadSceneFromString(R"({"lights": [{"type": "point"}]})", "s.json");
    ASSERT_EQ(d.warnings.size(), 1u);
    EXPECT_EQ(d.warnings[0], "s.json: \"version\" is missing; version 1 is assumed (add \"version\": 1)");
}

TEST(SceneLoader, RotationListAppliedInOrderAndRelativeRadii) {
    const SceneDesc d = loadSceneFromString(R"({"version": 1,
      "shapes": [{"type": "box", "transform": {"rotate": [{"axis": [0, 0, 1], "angle_deg": 90},
                                                          {"axis": [1, 0, 0], "angle_deg": 90}]}}],
      "lights": [{"type": "spot", "cutoff_deg": 10, "emit_time_m": 1.5}],
      "render": {"radius_relative": 0.003, "surface_radius_relative": 0.004},
      "film": {"range": "auto", "bins": 7}})",
                                            "s.json");
    // (1,0,0) -> about z -> (0,1,0) -> about x -> (0,0,1).
    expectNear(apply(d.shapes[0].transform, Vec3(1, 0, 0)), Vec3(0, 0, 1));
    EXPECT_EQ(d.lights[0].spotFalloffDeg, 10.0);  // default clamped to the cutoff
    EXPECT_EQ(d.lights[0].emitOpl, 1.5);
    EXPECT_TRUE(d.render.radiusRelative);
    EXPECT_EQ(d.render.radius, 0.003);
    EXPECT_EQ(d.render.surfaceRadius, 0.004);
    EXPECT_TRUE(d.film.autoRange);
    EXPECT_EQ(d.film.bins, 7);
}

TEST(SceneLoader, CommentKeysAreIgnoredEverywhere) {
    const SceneDesc d = loadSceneFromString(R"({"version": 1, "comment": "top", "_a": 1, "_a": 2,
      "camera": {"_note": [1, 2], "fov": 50},
      "media": {"_unused": {"sigma_s": -5}},
      "lights": [{"type": "point", "comment": "key light"}]})",
                                            "s.json");
    EXPECT_EQ(d.camera.fovYDeg, 50.0);
    EXPECT_TRUE(d.media.empty());
    EXPECT_EQ(d.lights.size(), 1u);
}

TEST(SceneLoader, FilmBytesAndLimit) {
    CameraDesc cam;
    cam.width = 10;
    cam.height = 20;
    EXPECT_EQ(
        filmBytes(cam.width, cam.height, 5),
        200u * (5 * 2 * 3 * 8 + (3 + 2 * 2 * 3) * 8));  // tests/film/test_transient_film.cpp: = what the film allocates
    cam.width = cam.height = INT_MAX;
    EXPECT_EQ(filmBytes(cam.width, cam.height, INT_MAX), UINT64_MAX);  // saturates instead of wrapping
    EXPECT_GT(maxFilmBytes(), 0u);

    ::setenv("TPB_MAX_FILM_BYTES", "1000", 1);
    EXPECT_EQ(maxFilmBytes(), 1000u);
    expectError("{\"version\": 1,\n\"film\": {\"bins\": 10}}", 2, "film.bins", "more than the limit of 1000 bytes");
    ::setenv("TPB_MAX_FILM_BYTES", "lots", 1);
    EXPECT_THROW(maxFilmBytes(), UserError);
    ::unsetenv("TPB_MAX_FILM_BYTES");
}

TEST(SceneLoader, CannotOpenFile) {
    try {
        loadScene("/nonexistent/dir/scene.json");
        FAIL();
    } catch (const UserError& e) {
        EXPECT_THAT(std::string(e.what()), HasSubstr("cannot open scene file"));
        EXPECT_THAT(std::string(e.what()), HasSubstr("/nonexistent/dir/scene.json"));
    }
}

// Issue 33 item 8: `tpb render /dev/zero` read forever. A scene file must be a regular file of at
// most kMaxSceneFileBytes: a device, a FIFO and a folder are refused before any read, a larger file
// by its size (a sparse file here: no disk used), JSON and XML alike.
TEST(SceneLoader, RefusesSpecialAndHugeFilesBeforeReading) {
    const auto error = [](const std::string& path) {
        try {
            loadScene(path);
        } catch (const UserError& e) {
            EXPECT_EQ(e.file(), path);
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_THAT(error("/dev/zero"),
                HasSubstr("/dev/zero: cannot read scene file: it is not a regular file but a device"));
    test::TempDir tmp{"test_scene_file_kinds"};
    const std::string fifo = (tmp.path() / "pipe.json").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    EXPECT_THAT(error(fifo), HasSubstr("not a regular file but a FIFO (pipe)"));  // (opening it would block)
    std::filesystem::create_directories(tmp.path() / "dir.xml");
    EXPECT_THAT(error((tmp.path() / "dir.xml").string()), HasSubstr("cannot open scene file (it is a directory)"));
    for (const char* name : {"huge.json", "huge.xml"}) {
        const std::string huge = (tmp.path() / name).string();
        std::ofstream(huge) << "{";
        std::filesystem::resize_file(huge, kMaxSceneFileBytes + 1);
        EXPECT_THAT(error(huge), HasSubstr("scene file is 256.0 MiB (268435457 bytes), more than the 256.0 MiB"));
    }
    // At the limit's side of it, an ordinary file reads whole.
    tmp.write("ok.json", "{\"version\": 1}");
    EXPECT_EQ(readSceneFile((tmp.path() / "ok.json").string()), "{\"version\": 1}");
}

// Issue 33 item 8: a mesh that holds a medium (a null or dielectric shape with interior_medium)
// must be closed and consistently oriented, else the fog leaks out through its holes (a ray that
// entered never pops the region). Refused at Scene::build with the shape's file:line, the count of
// open edges and the fix; the closed mesh, and the open one as a plain dielectric, load.
TEST(SceneLoader, OpenMeshHoldingAMediumIsRefused) {
    test::TempDir tmp{"test_scene_open_mesh"};
    const std::string cube =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 1 5 8 4\n";
    tmp.write("closed.obj", cube + "f 4 8 7 3\n");
    tmp.write("open.obj", cube);                     // no y = 1 face: its 4 edges are holes
    tmp.write("flipped.obj", cube + "f 4 3 7 8\n");  // that face inside out: its 4 edges misfit
    const auto sceneWith = [&](const std::string& obj, const std::string& material, bool medium) {
        return tmp
            .write("s.json", R"({"version": 1,
  "media": {"fog": {"sigma_s": 1}},
  "materials": {"m": {"type": ")" +
                                 material + R"("}},
  "shapes": [
    {"type": "mesh", "file": ")" +
                                 obj + R"(", "material": "m")" +
                                 (medium ? ",\n     \"interior_medium\": \"fog\"" : "") + R"(}],
  "lights": [{"type": "point", "position": [0.5, 3, 0.5], "power": 1}]})")
            .string();
    };
    const auto buildError = [&](const std::string& path) {
        try {
            Scene::build(loadScene(path), analyzeStages);
        } catch (const UserError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string s = sceneWith("open.obj", "null", true);
    EXPECT_THAT(buildError(s), HasSubstr(s + ":6: shapes[0].interior_medium: the mesh \"shapes[0]\" ("));
    EXPECT_THAT(buildError(s), HasSubstr("open.obj) holds a medium but is not closed: 4 edges of one triangle only "
                                         "(holes); the medium would leak out through them. Close the mesh"));
    EXPECT_THAT(buildError(sceneWith("flipped.obj", "dielectric", true)),
                HasSubstr("not closed: 4 edges shared by triangles facing opposite ways"));
    EXPECT_EQ(buildError(sceneWith("closed.obj", "null", true)), "no error");
    EXPECT_EQ(buildError(sceneWith("open.obj", "dielectric", false)), "no error");  // no medium to hold
    EXPECT_EQ(buildError(sceneWith("open.obj", "null", false)), "no error");

    // openEdges itself: vertices split (same position, other index) still meet.
    TriangleMesh quad = makeQuad(Vec3(0.0), Vec3(1.0, 0.0, 0.0), Vec3(0.0, 1.0, 0.0));
    EXPECT_EQ(openEdges(quad).holes, 4);
    TriangleMesh box = makeBox(Vec3(0.0), Vec3(1.0));
    EXPECT_TRUE(openEdges(box).closed());
    TriangleMesh split = box;
    for (glm::uvec3& t : split.triangles) {  // every triangle its own three vertices
        const uint32_t base = static_cast<uint32_t>(split.positions.size());
        split.positions.insert(split.positions.end(), {box.positions[t.x], box.positions[t.y], box.positions[t.z]});
        t = glm::uvec3(base, base + 1, base + 2);
    }
    EXPECT_TRUE(openEdges(split).closed());
    box.flip();
    EXPECT_TRUE(openEdges(box).closed());  // inside out but consistent
}

// ---- one test per kind of mistake --------------------------------------------------------------

TEST(SceneErrors, UnknownKeySuggestsClosest) {
    expectError("{\"version\": 1,\n\"lights\": [\n {\"type\": \"point\",\n  \"powr\": 3}]}", 4, "lights[0].powr",
                "unknown key for a point light (did you mean \"power\"?); allowed: type, name, power");
    expectError("{\"version\": 1,\n\"shape\": []}", 2, "shape", "(did you mean \"shapes\"?)");
    expectError("{\"version\": 1,\n\"camera\": {\"zoom\": 2}}", 2, "camera.zoom", "allowed: type, position, look_at, up");
    // A misspelt required key is reported as such, not as missing.
    expectError("{\"version\": 1, \"lights\": [{\n\"tpye\": \"point\"}]}", 2, "lights[0].tpye",
                "(did you mean \"type\"?)");
    // A key that belongs to another type of the same object.
    expectError("{\"shapes\": [{\"type\": \"quad\",\n \"interior_medium\": \"x\"}]}", 2, "shapes[0].interior_medium",
                "unknown key for a quad");
}

TEST(SceneErrors, WrongType) {
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": \"wide\"}}", 2, "camera.fov",
                "expected a number, got a string");
    expectError("{\"lights\": [{\"type\": \"point\",\n\"power\": [1, 2]}]}", 2, "lights[0].power",
                "expected a number or an [r, g, b] array");
    expectError("{\"version\": 1,\n\"camera\": {\"position\": 3}}", 2, "camera.position",
                "expected an [x, y, z] array");
    expectError("{\"version\": 1,\n\"render\": {\"unwarp\": 1}}", 2, "render.unwarp", "expected true or false");
    expectError("{\"version\": 1,\n\"shapes\": {}}", 2, "shapes", "expected an array");
    expectError("{\"version\": 1,\n\"render\": []}", 2, "render", "expected an object");
    expectError("[1, 2]", 1, "", "a scene must be a JSON object");
}

TEST(SceneErrors, NonIntegralInteger) {
    expectError("{\"version\": 1,\n\"film\": {\"bins\": 2.5}}", 2, "film.bins", "bins must be an integer");
}

TEST(SceneErrors, NegativeSigma) {
    expectError("{\"version\": 1, \"media\": {\n\"fog\": {\n\"sigma_s\": [0.1, -1, 0]}}}", 3, "media.fog.sigma_s",
                "sigma_s must be >= 0 (got [0.1, -1, 0])");
    expectError("{\"version\": 1, \"media\": {\"fog\": {\n\"sigma_a\": -0.5}}}", 2, "media.fog.sigma_a",
                "sigma_a must be >= 0");
}

TEST(SceneErrors, IorBelowOne) {
    expectError("{\"version\": 1, \"media\": {\"fog\": {\n\"ior\": 0.9}}}", 2, "media.fog.ior", "ior must be >= 1");
    expectError("{\"version\": 1, \"materials\": {\"glass\": {\"type\": \"dielectric\",\n\"ior\": 0.5}}}", 2,
                "materials.glass.ior", "ior must be >= 1");
}

TEST(SceneErrors, PhaseGOutOfRange) {
    expectError("{\"version\": 1, \"media\": {\"fog\": {\n\"g\": 1}}}", 2, "media.fog.g", "g must be in (-1, 1)");
}

TEST(SceneErrors, OtherRanges) {
    expectError("{\"version\": 1,\n\"render\": {\"alpha\": 0}}", 2, "render.alpha", "alpha must be in (0, 1]");
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": 180}}", 2, "camera.fov", "fov must be in (0, 180)");
    expectError("{\"version\": 1,\n\"shapes\": [{\"type\": \"sphere\", \"radius\": 0}]}", 2, "shapes[0].radius",
                "radius must be > 0");
    expectError("{\"version\": 1,\n\"materials\": {\"w\": {\"type\": \"diffuse\", \"albedo\": 1.2}}}", 2,
                "materials.w.albedo", "albedo must be in [0, 1]");
    expectError("{\"version\": 1,\n\"render\": {\"photons_per_pass\": 0}}", 2, "render.photons_per_pass",
                "photons_per_pass must be >= 1");
    expectError("{\"version\": 1,\n\"render\": {\"radius\": 0.1, \"radius_relative\": 0.1}}", 2,
                "render.radius_relative", "not both");
    expectError("{\"version\": 1,\n\"render\": {\"radius\": 0.1, \"surface_radius_relative\": 0.1}}", 2,
                "render.surface_radius_relative", "must both be absolute");
    expectError("{\"version\": 1,\n\"lights\": [{\"type\": \"laser\", \"direction\": [0, 0, 0]}]}", 2,
                "lights[0].direction", "must not be a zero vector");
    expectError("{\"version\": 1,\n\"camera\": {\"position\": [0, 0, 0], \"look_at\": [0, 0, 0]}}", 2, "camera.look_at",
                "look_at must differ from position");
    expectError("{\"version\": 1,\n\"lights\": [{\"type\": \"spot\", \"cutoff_deg\": 20, \"falloff_deg\": 30}]}", 2,
                "lights[0].falloff_deg", "falloff_deg must be in [0, cutoff_deg]");
}

TEST(SceneErrors, ZeroResolution) {
    expectError("{\"version\": 1, \"camera\": {\n\"resolution\": [0, 100]}}", 2, "camera.resolution",
                "resolution must be >= 1 (got 0)");
    expectError("{\"version\": 1, \"camera\": {\n\"resolution\": [1e12, 100]}}", 2, "camera.resolution",
                "resolution must be <= 2147483647");
    expectError("{\"version\": 1, \"camera\": {\n\"resolution\": [100000, 100000]}}", 2, "camera.resolution", "pixels");
}

TEST(SceneErrors, ZeroBins) {
    expectError("{\"version\": 1, \"film\": {\n\"bins\": 0}}", 2, "film.bins", "bins must be >= 1");
}

TEST(SceneErrors, HugeBins) {
    expectError("{\"version\": 1, \"film\": {\n\"bins\": 1e12}}", 2, "film.bins", "bins must be <= 2147483647");
    expectError("{\"version\": 1, \"film\": {\n\"bins\": 99999999999999999999999}}", 2, "film.bins",
                "bins must be <= 2147483647");
    // Fits an int, but not in memory: 4096^2 pixels x 2e9 bins.
    expectError("{\"version\": 1, \"camera\": {\"resolution\": [4096, 4096]},\n\"film\": {\"bins\": 2000000000}}", 2,
                "film.bins", "bytes");
}

TEST(SceneErrors, MissingMeshFile) {
    ObjFolder tmp;
    const std::string text = "{\"version\": 1, \"shapes\": [\n{\"type\": \"mesh\",\n\"file\": \"nope.obj\"}]}";
    const std::string resolved = (tmp.dir / "nope.obj").string();
    expectError(text, 3, "shapes[0].file", "mesh file not found: " + resolved, tmp.scene());
    expectError("{\"version\": 1, \"shapes\": [\n{\"type\": \"mesh\"}]}", 2, "shapes[0].file",
                "required key is missing");
}

TEST(SceneErrors, UndefinedMaterial) {
    expectError(
        "{\"version\": 1, \"materials\": {\"glass\": {\"type\": \"dielectric\"}},\n\"shapes\": [{\"type\": "
        "\"sphere\",\n"
        "\"material\": \"glas\"}]}",
        3, "shapes[0].material", "undefined material \"glas\" (did you mean \"glass\"?); defined materials: \"glass\"");
}

TEST(SceneErrors, UndefinedMedium) {
    expectError("{\"version\": 1,\n\"global_medium\": \"smoke\"}", 2, "global_medium",
                "undefined medium \"smoke\"; no media are defined");
    expectError(
        "{\"version\": 1, \"media\": {\"fog\": {}},\n\"shapes\": [{\"type\": \"box\", \"interior_medium\": \"fgo\"}]}",
        2, "shapes[0].interior_medium", "defined media: \"fog\"");
}

TEST(SceneErrors, BadEnum) {
    expectError("{\"version\": 1, \"render\": {\n\"emission\": \"pulsed\"}}", 2, "render.emission",
                "unknown emission \"pulsed\"; allowed: \"delta\", \"continuous\"");
    expectError("{\"version\": 1, \"lights\": [{\n\"type\": \"sun\"}]}", 2, "lights[0].type",
                "unknown light type \"sun\"; allowed: \"point\", \"spot\", \"area\", \"laser\"");
    expectError("{\"version\": 1, \"shapes\": [{\n\"type\": \"spere\"}]}", 2, "shapes[0].type",
                "did you mean \"sphere\"");
    expectError("{\"version\": 1, \"film\": {\n\"range\": \"manual\"}}", 2, "film.range", "allowed: \"auto\"");
    expectError("{\"version\": 1, \"lights\": [\n{\"power\": 1}]}", 2, "lights[0].type", "required key is missing");
}

TEST(SceneErrors, TimeInBothUnits) {
    expectError("{\"version\": 1, \"film\": {\"start_m\": 0,\n\"start_ns\": 1}}", 2, "film.start_ns",
                "give either start_m or start_ns, not both");
    expectError("{\"version\": 1, \"lights\": [{\"type\": \"point\", \"emit_time_m\": 0,\n\"emit_time_ns\": 1}]}", 2,
                "lights[0].emit_time_ns", "not both");
    expectError("{\"version\": 1, \"film\": {\"range\": \"auto\",\n\"start_m\": 1}}", 2, "film.start_m",
                "cannot be combined");
}

TEST(SceneErrors, TruncatedJson) {
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": 40\n", 3, "", "the object opened at line 2 is not closed");
    expectError("{\"version\": 1,\n\"name\": \"abc", 2, "", "the string opened at line 2 is not closed");
    expectError("", 1, "", "the file is empty");
}

TEST(SceneErrors, TrailingComma) {
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": 40,\n}}", 3, "", "trailing comma before '}'");
    expectError("{\"version\": 1,\n\"lights\": [{\"type\": \"point\"},\n]}", 3, "", "trailing comma before ']'");
}

TEST(SceneErrors, NanLiteral) {
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": NaN}}", 2, "", "NaN and Infinity are not valid JSON numbers");
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": -Infinity}}", 2, "", "NaN and Infinity");
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": 1e999}}", 2, "", "out of the range of a double");
}

TEST(SceneErrors, DuplicateKey) {
    expectError("{\"version\": 1,\n\"camera\": {\"fov\": 40,\n\"fov\": 50}}", 3, "",
                "duplicate key \"fov\" (first written at line 2)");
}

TEST(SceneErrors, InvalidVersion) {
    expectError("{\n\"version\": 2}", 2, "version", "unsupported version 2; this tpb reads version 1");
    expectError("{\n\"version\": \"1\"}", 2, "version", "expected the number 1");
}

TEST(SceneErrors, BadTransform) {
    const auto box = [](const std::string& transform) {
        return "{\"version\": 1, \"shapes\": [{\"type\": \"box\",\n\"transform\": " + transform + "}]}";
    };
    expectError(box("{\"scale\": 0}"), 2, "shapes[0].transform.scale", "scale must be > 0");
    expectError(box("{\"scale\": [1, -1, 1]}"), 2, "shapes[0].transform.scale", "mirroring");
    expectError(box("{\"translate\": [1, 0, 0], \"matrix\": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}"), 2,
                "shapes[0].transform.matrix", "cannot be combined");
    expectError(box("{\"matrix\": [1, 2, 3]}"), 2, "shapes[0].transform.matrix", "16 numbers");
    expectError(box("{\"matrix\": [1,0,0,0, 0,1,0,0, 0,0,1,0, 1,0,0,1]}"), 2, "shapes[0].transform.matrix",
                "last row must be 0, 0, 0, 1");
    expectError(box("{\"matrix\": [1,0,0,0, 0,1,0,0, 0,0,0,0, 0,0,0,1]}"), 2, "shapes[0].transform.matrix",
                "determinant");
    expectError(
        box("{\"rotate\": [{\"axis\": [0, 1, 0], \"angle_deg\": 10}, {\"axis\": [0, 0, 0], \"angle_deg\": 5}]}"), 2,
        "shapes[0].transform.rotate[1].axis", "must not be a zero vector");
    expectError(box("{\"rotate\": {\"axis\": [0, 1, 0]}}"), 2, "shapes[0].transform.rotate.angle_deg",
                "required key is missing");
    expectError(box("{\"rotate\": {\"axis\": [0, 1, 0], \"angel_deg\": 3}}"), 2, "shapes[0].transform.rotate.angel_deg",
                "did you mean \"angle_deg\"");
    expectError(box("{\"translte\": [0, 1, 0]}"), 2, "shapes[0].transform.translte", "did you mean \"translate\"");
}

// ---- issue 12, item 12: messages that misled ------------------------------------------------------

// camera.position 1e308 was reported as "camera.up: up must not be parallel to the viewing direction"
// (the view vector overflowed). Now: the key that is out of range, the limit and the fix.
TEST(SceneErrors, HugeCameraPositionNamesThePositionNotUp) {
    expectError("{\"version\": 1,\n\"camera\": {\"position\": [1e308, 0.5, 3]}}", 2, "camera.position",
                "position is too far out: scene coordinates and sizes must be within +-1e9 m (got [1e308, 0.5, 3]); "
                "check the units (meters)");
    expectError("{\"version\": 1,\n\"camera\": {\"look_at\": [0, -2e9, 0]}}", 2, "camera.look_at", "within +-1e9 m");
    // Other positions and sizes follow the same rule, with their keys.
    expectError("{\"version\": 1,\n\"shapes\": [{\"type\": \"sphere\", \"radius\": 1e300}]}", 2, "shapes[0].radius",
                "within +-1e9 m");
    expectError("{\"version\": 1,\n\"lights\": [{\"type\": \"point\", \"position\": [0, 0, -1e10]}]}", 2,
                "lights[0].position", "within +-1e9 m");
    expectError("{\"version\": 1, \"shapes\": [{\"type\": \"box\",\n\"transform\": {\"translate\": [1e20, 0, 0]}}]}", 2,
                "shapes[0].transform.translate", "within +-1e9 m");
    expectError(
        "{\"version\": 1, \"shapes\": [{\"type\": \"box\", \"max\": [1, 1, 1],\n\"transform\": {\"scale\": 1e9, "
        "\"translate\": [1e9, 0, 0]}}]}",
        2, "shapes[0].transform", "the transformed box reaches beyond +-1e9 m");
    // A huge but finite direction is a direction, not an overflow to a "zero vector".
    const SceneDesc d = loadSceneFromString("{\"version\": 1, \"camera\": {\"up\": [1e308, 1e308, 0]}}", "scene.json");
    expectNear(d.camera.up, glm::normalize(Vec3(1, 1, 0)));
}

// A mesh "file" that is a folder was reported as "not found". Now: it is a folder, and the OBJ
// files in it.
TEST(SceneErrors, MeshPathThatIsAFolder) {
    ObjFolder tmp;
    fs::create_directories(tmp.dir / "bunny");
    std::ofstream(tmp.dir / "bunny" / "bunny.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    const std::string text = "{\"version\": 1, \"shapes\": [\n{\"type\": \"mesh\",\n\"file\": \"bunny\"}]}";
    expectError(text, 3, "shapes[0].file",
                "mesh file " + (tmp.dir / "bunny").string() +
                    " is a folder, not a file (\"bunny\" resolved against the "
                    "scene's folder); \"file\" must name the OBJ file itself, e.g. \"bunny/bunny.obj\"",
                tmp.scene());
    fs::create_directories(tmp.dir / "empty");
    expectError("{\"version\": 1, \"shapes\": [{\"type\": \"mesh\",\n\"file\": \"empty\"}]}", 2, "shapes[0].file",
                "(the folder holds no .obj file)", tmp.scene());
}

// NaN vertices were read as 0 by tinyobj (a triangle of them was then "degenerate"); huge ones
// were "non-finite" or, after the float conversion, had no file:line. Now the OBJ line and the fix.
TEST(SceneErrors, NanAndHugeMeshVerticesNameTheObjLine) {
    ObjFolder tmp;
    const auto objError = [&](const std::string& text) -> std::string {
        std::ofstream(tmp.dir / "m.obj") << text;
        try {
            loadObj((tmp.dir / "m.obj").string());
        } catch (const UserError& e) {
            return e.what();
        }
        return "";
    };
    const std::string obj = (tmp.dir / "m.obj").string();
    EXPECT_EQ(objError("v 0 0 0\nv nan nan nan\nv 0 1 0\nf 1 2 3\n"),
              obj +
                  ":2: vertex 2 (\"v\" line 2) has a non-finite coordinate (nan); coordinates must be finite and "
                  "within +-1e9 m");
    EXPECT_EQ(objError("# a comment\nv 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n"),
              obj +
                  ":3: vertex 2 (\"v\" line 3) has a non-finite coordinate (inf); coordinates must be finite and "
                  "within +-1e9 m");
    EXPECT_THAT(
        objError("v 1e30 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        HasSubstr(obj + ":1: vertex 1 (\"v\" line 1) coordinate 1e30 is beyond +-1e9 m, the limit of scene "
                        "coordinates; check the file's units, or scale the mesh with the shape's \"transform\""));
    EXPECT_THAT(objError("v 1e999 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
                HasSubstr("non-finite coordinate (1e999, beyond the range of a double)"));
    EXPECT_EQ(objError("v 0 0 0\nv 1,5 0 0\nv 0 1 0\nf 1 2 3\n"),
              obj + ":2: vertex 2 (\"v\" line 2) coordinate \"1,5\" is not a number");
    EXPECT_EQ(objError("v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
              obj + ":1: vertex 1 (\"v\" line 1) has 2 coordinates, expected x y z");
    // Vertex colours after x y z, normals ("vn") and texture coordinates ("vt") are not vertices.
    EXPECT_EQ(objError("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvn nan 0 1\nvt 0.5 0.5\nf 1 2 3\n"), "");
    // A transform that moves a vertex beyond the limit.
    TriangleMesh m = loadObj(obj);
    try {
        m.transform(glm::scale(Mat4(1.0), Vec3(1e10)));
        ADD_FAILURE() << "no error";
    } catch (const UserError& e) {
        EXPECT_THAT(std::string(e.what()), HasSubstr("moves a vertex of the mesh to (1e+10, 0, 0), beyond +-1e9 m"));
    }
}

// A UTF-16 scene (Notepad's "Unicode") was "unexpected byte 0xFF: expected a value".
TEST(SceneErrors, Utf16SceneFileSaysToConvertIt) {
    const std::string ascii = "{\"version\": 1}";
    std::string le = "\xFF\xFE", be = "\xFE\xFF", leNoBom;
    for (char c : ascii) {
        le += std::string{c, '\0'};
        leNoBom += std::string{c, '\0'};
        be += std::string{'\0', c};
    }
    const std::string fix = "scene files must be UTF-8; convert it (e.g. iconv -f UTF-16 -t UTF-8 in.json > out.json)";
    expectError(le, 1, "", "the file is UTF-16 (little-endian) text, but " + fix);
    expectError(leNoBom, 1, "", "the file is UTF-16 (little-endian) text");
    expectError(be, 1, "", "the file is UTF-16 (big-endian) text");
    expectError(std::string("\xFF\xFE\0\0{\0\0\0", 8), 1, "", "the file is UTF-32 (little-endian) text");
    // UTF-8 with a byte order mark is fine.
    EXPECT_NO_THROW(loadSceneFromString("\xEF\xBB\xBF" + ascii, "scene.json"));
}

// radius_relative >= 1 hung the automatic-range pilot (every beam in every camera ray's kernel).
// Now refused with the key, the allowed range and why; large but allowed radii are warned about.
TEST(SceneErrors, KernelRadiusThatMakesPassesQuadratic) {
    expectError("{\"version\": 1,\n\"render\": {\"radius_relative\": 1}}", 2, "render.radius_relative",
                "radius_relative 1 is too large: allowed (0, 0.25] (a fraction of the scene's diagonal). A kernel that "
                "wide makes every camera ray gather every beam or photon, so a pass costs rays x beams");
    expectError("{\"version\": 1,\n\"render\": {\"surface_radius_relative\": 0.5}}", 2,
                "render.surface_radius_relative", "allowed (0, 0.25]");
    std::vector<std::string> w;
    prepareText("{\"version\": 1,\n\"render\": {\"radius_relative\": 0.1}}", "scene.json", &w);
    ASSERT_EQ(w.size(), 2u);  // "the scene has no lights", then the radius
    EXPECT_THAT(w[1], HasSubstr("scene.json:2: render.radius_relative: radius_relative 0.1 is large (above "
                                "0.05 of the scene's diagonal): passes get much slower"));
    w.clear();
    prepareText("{\"version\": 1, \"render\": {\"radius_relative\": 0.05}}", "s.json", &w);
    EXPECT_EQ(w.size(), 1u);
}

// render.threads far above the cores ran a thread per tile: capped with a warning naming the key.
TEST(SceneErrors, ThreadsAboveTheCoresAreCapped) {
    std::vector<std::string> w;
    const PreparedRender p = prepareText("{\"version\": 1,\n\"render\": {\"threads\": 100000}}", "scene.json", &w);
    EXPECT_EQ(p.settings.threads, maxUsefulThreads());
    ASSERT_EQ(w.size(), 2u);  // "the scene has no lights", then the threads
    EXPECT_THAT(w[1], HasSubstr("scene.json:2: render.threads: threads 100000 is more than 4 x the "));
    EXPECT_THAT(w[1], HasSubstr("using " + std::to_string(maxUsefulThreads()) + " (0 = all cores)"));
}

// ---- JSON parser -----------------------------------------------------------------------------------

TEST(Json, LineNumbersOfNestedValuesAndKeys) {
    const JsonValue v = parseJson("\n{\n  \"a\": [1,\n    {\"b\":\n      true}],\n  \"c\": \"x\"\n}\n", "t.json");
    ASSERT_TRUE(v.isObject());
    EXPECT_EQ(v.line, 2);
    ASSERT_EQ(v.members.size(), 2u);
    EXPECT_EQ(v.members[0].key, "a");
    EXPECT_EQ(v.members[0].line, 3);
    const JsonValue& a = v.members[0].value;
    ASSERT_TRUE(a.isArray());
    EXPECT_EQ(a.line, 3);
    EXPECT_EQ(a.items[0].line, 3);
    EXPECT_EQ(a.items[1].line, 4);
    EXPECT_EQ(a.items[1].members[0].line, 4);
    EXPECT_EQ(a.items[1].members[0].value.line, 5);
    EXPECT_TRUE(a.items[1].members[0].value.boolean);
    EXPECT_EQ(v.members[1].line, 6);
    EXPECT_EQ(v.find("c")->text, "x");
    EXPECT_EQ(v.find("zz"), nullptr);
}

TEST(Json, Escapes) {
    const JsonValue v = parseJson(R"(["a\"b\\c\/d\b\f\n\r\t", "\u00e9\u20AC", "\ud83d\ude00", "\u0000x"])", "t.json");
    EXPECT_EQ(v.items[0].text, "a\"b\\c/d\b\f\n\r\t");
    EXPECT_EQ(v.items[1].text, "\xC3\xA9\xE2\x82\xAC");  // é €
    EXPECT_EQ(v.items[2].text, "\xF0\x9F\x98\x80");      // U+1F600 from a surrogate pair
    EXPECT_EQ(v.items[3].text, std::string("\0x", 2));
    EXPECT_THAT(jsonError(R"(["\x"])"), HasSubstr("invalid escape"));
    EXPECT_THAT(jsonError(R"(["\u12"])"), HasSubstr("4 hexadecimal digits"));
    EXPECT_THAT(jsonError(R"(["\ud83d"])"), HasSubstr("low surrogate"));
    EXPECT_THAT(jsonError(R"(["\ud83dx"])"), HasSubstr("low surrogate"));
    EXPECT_THAT(jsonError(R"(["\ud83d\u0041"])"), HasSubstr("low surrogate"));
    EXPECT_THAT(jsonError(R"(["\ude00"])"), HasSubstr("unpaired low surrogate"));
}

TEST(Json, Utf8) {
    EXPECT_EQ(parseJson("\xEF\xBB\xBF[\"\xC3\xA9\xF0\x9F\x98\x80\"]", "t.json").items[0].text,
              "\xC3\xA9\xF0\x9F\x98\x80");                                         // BOM skipped, raw UTF-8 kept
    EXPECT_THAT(jsonError("[\"\xC3\"]"), HasSubstr("invalid UTF-8"));              // truncated sequence
    EXPECT_THAT(jsonError("[\"\xC0\xAF\"]"), HasSubstr("invalid UTF-8"));          // overlong
    EXPECT_THAT(jsonError("[\"\xED\xA0\x80\"]"), HasSubstr("invalid UTF-8"));      // encoded surrogate
    EXPECT_THAT(jsonError("[\"\xF4\x90\x80\x80\"]"), HasSubstr("invalid UTF-8"));  // > U+10FFFF
    EXPECT_THAT(jsonError("[\"\xFF\"]"), HasSubstr("invalid UTF-8"));
    EXPECT_THAT(jsonError("[\"a\tb\"]"), HasSubstr("control character U+0009"));
    EXPECT_THAT(jsonError("[\"a\nb\"]"), HasSubstr("not closed"));
}

TEST(Json, Numbers) {
    const JsonValue v =
        parseJson("[0, -0, 12, -3.5, 1e3, 2.5E-2, 1E+2, 123456789012345678901234567890, 1e-400]", "t.json");
    const double expected[] = {0, 0, 12, -3.5, 1000, 0.025, 100, 1.2345678901234568e29, 0};
    ASSERT_EQ(v.items.size(), 9u);
    for (size_t i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(v.items[i].number, expected[i]) << i;
    EXPECT_TRUE(std::signbit(v.items[1].number));
    EXPECT_EQ(v.items[4].text, "1e3");
    EXPECT_DOUBLE_EQ(parseJson("1.7976931348623157e308", "t.json").number, 1.7976931348623157e308);
    EXPECT_DOUBLE_EQ(parseJson("0.000000000000000000000000000001e-300", "t.json").number, 0.0);

    EXPECT_THAT(jsonError("[1e309]"), HasSubstr("out of the range of a double"));
    EXPECT_THAT(jsonError("[-1e309]"), HasSubstr("out of the range of a double"));
    EXPECT_THAT(jsonError("[1000000000000000000000000000000e300]"), HasSubstr("out of the range"));
    EXPECT_THAT(jsonError("[01]"), HasSubstr("leading zeros"));
    EXPECT_THAT(jsonError("[1.]"), HasSubstr("digit after '.'"));
    EXPECT_THAT(jsonError("[.5]"), HasSubstr("digit before '.'"));
    EXPECT_THAT(jsonError("[+1]"), HasSubstr("'+'"));
    EXPECT_THAT(jsonError("[1e]"), HasSubstr("exponent"));
    EXPECT_THAT(jsonError("[-]"), HasSubstr("digit after '-'"));
    EXPECT_THAT(jsonError("[1x]"), HasSubstr("invalid number"));
    EXPECT_THAT(jsonError("[0x10]"), HasSubstr("invalid number"));
    EXPECT_THAT(jsonError("[nan]"), HasSubstr("NaN and Infinity"));
    EXPECT_THAT(jsonError("[Infinity]"), HasSubstr("NaN and Infinity"));
    EXPECT_THAT(jsonError("[inf]"), HasSubstr("NaN and Infinity"));
}

TEST(Json, LiteralsAndStructure) {
    const JsonValue v = parseJson(" {\"t\": true, \"f\": false, \"n\": null, \"e\": {}, \"a\": []} ", "t.json");
    EXPECT_TRUE(v.find("t")->boolean);
    EXPECT_FALSE(v.find("f")->boolean);
    EXPECT_TRUE(v.find("n")->isNull());
    EXPECT_TRUE(v.find("e")->isObject());
    EXPECT_TRUE(v.find("a")->isArray());

    int line = 0;
    EXPECT_THAT(jsonError("{\"a\": 1}\n{", &line), HasSubstr("after the end of the JSON value"));
    EXPECT_EQ(line, 2);
    EXPECT_THAT(jsonError("[truex]"), HasSubstr("unexpected 'truex'"));
    EXPECT_THAT(jsonError("[nul]"), HasSubstr("unexpected 'nul'"));
    EXPECT_THAT(jsonError("{'a': 1}"), HasSubstr("double quotes"));
    EXPECT_THAT(jsonError("{a: 1}"), HasSubstr("expected a key in double quotes"));
    EXPECT_THAT(jsonError("{\"a\" 1}"), HasSubstr("expected ':'"));
    EXPECT_THAT(jsonError("{\"a\": 1 \"b\": 2}"), HasSubstr("expected ',' or '}'"));
    EXPECT_THAT(jsonError("[1 2]"), HasSubstr("expected ',' or ']'"));
    EXPECT_THAT(jsonError("[1,,2]"), HasSubstr("expected a value"));
    EXPECT_THAT(jsonError("// hi\n{}"), HasSubstr("comments are not allowed"));
    EXPECT_THAT(jsonError("[\x01]"), HasSubstr("byte 0x01"));
    EXPECT_THAT(jsonError("  \n "), HasSubstr("empty"));
    EXPECT_THAT(jsonError("{\"_c\": 1, \"_c\": 2, \"comment\": 1, \"comment\": 2}"), ::testing::IsEmpty());
    EXPECT_TRUE(isJsonCommentKey("_x"));
    EXPECT_TRUE(isJsonCommentKey("comment"));
    EXPECT_FALSE(isJsonCommentKey("comments"));
}

TEST(Json, NestingLimit) {
    const auto nested = [](int depth) { return std::string(depth, '[') + std::string(depth, ']'); };
    EXPECT_EQ(jsonError(nested(kJsonMaxDepth)), "");
    EXPECT_THAT(jsonError(nested(kJsonMaxDepth + 1)), HasSubstr("nesting deeper than 256"));
    EXPECT_THAT(jsonError(std::string(1000000, '[')), HasSubstr("nesting deeper"));  // no stack overflow
    std::string objects;
    for (int i = 0; i < 300; ++i) objects += "{\"a\":";
    EXPECT_THAT(jsonError(objects), HasSubstr("nesting deeper"));
}

// Cheap robustness check (the fuzzer goes further): mutated and truncated documents either parse
// or throw UserError, never anything else.
TEST(Json, MutatedInputNeverCrashes) {
    const std::string base = kFullScene;
    std::mt19937 rng(12345);
    const char alphabet[] = "{}[]\",:\\ue0-+.1aENtfn\n \x80\xC3\xFF";
    for (int iter = 0; iter < 3000; ++iter) {
        std::string s = base.substr(0, rng() % (base.size() + 1));
        const int edits = 1 + static_cast<int>(rng() % 4);
        for (int e = 0; e < edits && !s.empty(); ++e) s[rng() % s.size()] = alphabet[rng() % (sizeof(alphabet) - 1)];
        try {
            parseJson(s, "fuzz.json");
            loadSceneFromString(s, "fuzz.json");
        } catch (const UserError&) {}
    }
}
