// A scene prepared for a test as the CLI prepares it (prepareRender, render/prepare.h) but without
// the pilot: "range": "auto" keeps the heuristic window. `sc->camera` and `*sc` reach the Scene.
#pragma once
#include "base/error.h"
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

inline TestScene testSceneFrom(const std::string& json, const std::string& path = "test.json",
                               const SettingsOverrides& overrides = {}) {
    return prepareTestScene(loadSceneFromString(json, path), overrides);
}

// The UserError message of loading and preparing `json` so, "" when it prepares.
inline std::string prepareError(const std::string& json, const std::string& path = "test.json",
                                const SettingsOverrides& overrides = {}) {
    try {
        testSceneFrom(json, path, overrides);
    } catch (const UserError& e) {
        return e.what();
    }
    return "";
}

}  // namespace tpb::test
