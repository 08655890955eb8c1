// The viewer's render session (app/viewer/session.h) runs without a window: no GLFW, GL or ImGui,
// so a script or another front end can drive it. The first film is prepared while the steady
// preview renders; the film takes over once it has caught up; "Save checkpoint" writes a
// checkpoint that resumes; a restart starts a new generation.
#include "viewer/session.h"

#include "render/checkpoint.h"
#include "scene/scene_loader.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>

using namespace tpb;
using namespace tpb::app;

namespace {

const char* kScene = R"({
  "version": 1,
  "camera": {"position": [0, 1.1, 0.95], "look_at": [0, 0.8, -1], "fov": 70, "resolution": [24, 20]},
  "film": {"bins": 16},
  "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.05}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.7}},
  "shapes": [{"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true}],
  "lights": [{"type": "point", "position": [0, 1.8, 0], "power": 20}],
  "render": {"photons_per_pass": 1000, "radius_relative": 0.02, "surface_radius_relative": 0.04, "seed": 4,
             "passes": 4, "threads": 2}
})";

PreparedRender prepared() {
    PrepareOptions o;
    o.pilot.run = false;
    return prepareRender(loadSceneFromString(kScene, "session.json"), {}, o);
}

// Polls `done` every 5 ms for at most 60 s.
template <class F>
bool waitFor(F done) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!done()) {
        if (std::chrono::steady_clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
}

}  // namespace

TEST(ViewerSession, RendersPreviewsCheckpointsAndRestartsWithoutAWindow) {
    const PreparedRender p = prepared();
    std::atomic<int> wakes{0};
    ViewerSession session(p, p.settings, {}, "", true, [&] { ++wakes; });
    ASSERT_NE(session.preview(), nullptr);
    ASSERT_TRUE(waitFor([&] { return session.filmReady(); }));
    EXPECT_EQ(session.adoptFirst(), 0u);
    EXPECT_EQ(session.generation(), 1u);
    ASSERT_TRUE(waitFor([&] { return !session.driver().running(); }));
    EXPECT_EQ(session.driver().completedPasses(), 4u);
    EXPECT_GE(wakes.load(), 4) << "a wake per finished pass";
    // The film has caught up with the preview (it stopped after at most the render's passes): the
    // steady picture is the film's from now on, and the preview is gone.
    EXPECT_EQ(session.shownPasses(true), 4u);
    EXPECT_EQ(session.shownSnapshot(true)->minPasses(), 4);
    EXPECT_EQ(session.preview(), nullptr);

    // "Save checkpoint" into a folder: written on a helper thread, readable, of the 4 passes.
    test::TempDir dir("viewer_session");
    session.requestCheckpoint(dir.path().string());
    ASSERT_TRUE(waitFor([&] {
        session.pollCheckpoint();
        return session.checkpointStage() == ViewerSession::CheckpointStage::Idle;
    }));
    EXPECT_FALSE(session.checkpointFailed()) << session.status();
    const std::filesystem::path cp = dir.path() / kCheckpointFile;
    ASSERT_TRUE(std::filesystem::exists(cp)) << session.status();
    EXPECT_EQ(readCheckpointInfo(cp.string()).passes, 4u);

    // A restart: a new driver, an empty film, the next generation.
    RenderSettings s = session.driver().settings();
    s.passes = 1;
    session.restart(s);
    EXPECT_EQ(session.generation(), 2u);
    ASSERT_TRUE(waitFor([&] { return !session.driver().running(); }));
    EXPECT_EQ(session.driver().completedPasses(), 1u);
}
