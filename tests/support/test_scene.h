// A scene prepared for a test as the CLI prepares it (prepareRender, render/prepare.h) but without
// the pilot: "range": "auto" keeps the heuristic window. `sc->camera` and `*sc` reach the Scene.
#pragma once
#include "render/prepare.h"
#include "scene/scene_loader.h"

#include <string>

namespace tpb::test {

struct TestScene {
    std::unique_ptr<const Scene> scene;
    RenderSettings settings;
    TimeBins time;
    SceneSource source;

    const Scene* operator->() const { return scene.get(); }
    const Scene& operator*() const { return *scene; }
    explicit operator bool() const { return scene != nullptr; }
};

inline TestScene prepareTestScene(SceneDesc desc, const SettingsOverrides& overrides = {}) {
    PrepareOptions o;
    o.pilot.run = false;
    PreparedRender p = prepareRender(std::move(desc), overrides, o);
    return {std::move(p.scene), p.settings, p.time, std::move(p.source)};
}

inline TestScene testSceneFrom(const std::string& json, const std::string& path = "test.json") {
    return prepareTestScene(loadSceneFromString(json, path));
}

}  // namespace tpb::test
