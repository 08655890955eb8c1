// libFuzzer target for the scene loader (built and run by tools/fuzz, not by CMake).
//
// Any byte string must either load or throw tpb::UserError: a crash, a sanitizer report, a hang or
// any other exception is a bug. A scene that loads must also respect the documented ranges
// (docs/user/scenes.md "Scene format"), so a validation gap is reported as a crash too (__builtin_trap).
#include "base/error.h"
#include "integrators/render_settings.h"
#include "scene/scene_loader.h"

#include <cmath>
#include <cstdint>
#include <string>

namespace {

bool finite(const tpb::Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool nonNegative(const tpb::Color& c) { return finite(c) && c.x >= 0.0 && c.y >= 0.0 && c.z >= 0.0; }
void require(bool ok) {
    if (!ok) __builtin_trap();
}

void checkInvariants(const tpb::SceneDesc& d) {
    require(d.camera.width >= 1 && d.camera.height >= 1);
    require(d.camera.fovYDeg > 0.0 && d.camera.fovYDeg < 180.0);
    require(finite(d.camera.position) && finite(d.camera.lookAt) && finite(d.camera.up));
    require(d.film.bins >= 1);
    require(tpb::filmBytes(d.camera.width, d.camera.height, d.film.bins) <= tpb::maxFilmBytes());
    require(std::isfinite(d.film.startOpl) && d.film.binWidthOpl > 0.0 && std::isfinite(d.film.binWidthOpl));
    require(d.globalMedium >= -1 && d.globalMedium < static_cast<int>(d.media.size()));
    for (const tpb::MediumDesc& m : d.media) {
        require(nonNegative(m.sigma_s) && nonNegative(m.sigma_a));
        require(m.ior >= 1.0 && std::isfinite(m.ior));
        require(m.g > -1.0 && m.g < 1.0);
    }
    for (const tpb::MaterialDesc& m : d.materials) require(m.ior >= 1.0 && std::isfinite(m.ior));
    for (const tpb::ShapeDesc& s : d.shapes) {
        require(s.material >= -1 && s.material < static_cast<int>(d.materials.size()));
        require(s.interiorMedium >= -1 && s.interiorMedium < static_cast<int>(d.media.size()));
        if (s.type == tpb::ShapeType::Sphere) require(s.radius > 0.0);
    }
    for (const tpb::LightDesc& l : d.lights) {
        require(nonNegative(l.power));
        require(std::isfinite(l.emitOpl));
        require(l.laserRadius >= 0.0);
    }
}

// The render block is range-checked once, by RenderSettings::validate (the loader only parses it;
// prepareRender calls validate again with the built scene's diagonal): what passes must be usable.
void checkSettings(const tpb::SceneDesc& d) {
    tpb::RenderSettings s = tpb::RenderSettings::fromDesc(d.render, 1.0);
    s.validate({&d, nullptr, 0.0});
    require(s.photonsPerPass >= 1 && s.maxDepth >= 1 && s.passes >= 0 && s.threads >= 0);
    require(s.alpha > 0.0 && s.alpha <= 1.0);
    require(s.beamRadius0 > 0.0 && s.surfaceRadius0 > 0.0);
    require(s.timeBudgetSec >= 0.0 && std::isfinite(s.timeBudgetSec));
    require(s.bounceMin >= 0 && s.bounceMin <= s.bounceMax);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        // A folder that does not exist: relative mesh paths never name a real file.
        const tpb::SceneDesc desc = tpb::loadSceneFromString(text, "/nonexistent/tpb-fuzz/scene.json");
        checkInvariants(desc);
        checkSettings(desc);
    } catch (const tpb::UserError&) {
        // The expected outcome for bad input.
    }
    return 0;
}
