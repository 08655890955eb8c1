// What the point-estimator tests share (tests/estimators/test_point2d.cpp, test_point3d.cpp): a
// photon point, the single-scattering scene of their oracle checks, a closed fog box with glass and
// mirror spheres, and a render of both time axes' delta volumes.
#pragma once
#include "render/driver.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <vector>

namespace tpb::test {

inline VolumePhoton point(const Vec3& x, const Vec3& dirIn, const Color& power, double opl) {
    return VolumePhoton{x, glm::normalize(dirIn), power, opl, 0, 0};
}

// Single scattering from a point-light pulse (emitted at 1 ns) in an infinite chromatic medium with
// eta = 1.2; the camera, 3 m from the light, looks past it (the view starts 11.6 degrees from it:
// the rays come within 0.6 m of the light). The film starts at 0, so nothing arrives before it.
inline const char* kSingleScatter = R"({
  "version": 1,
  "camera": {"position": [0, 0, 3], "look_at": [1.5, 0, 0], "fov": 30, "resolution": [12, 12]},
  "film": {"start_m": 0, "bin_width_m": 0.25, "bins": 48},
  "media": {"m": {"sigma_s": [0.3, 0.4, 0.6], "sigma_a": [0.1, 0.1, 0.2], "g": 0.3, "ior": 1.2}},
  "global_medium": "m",
  "lights": [{"type": "point", "position": [0, 0, 0], "power": 10, "emit_time_ns": 1}],
  "render": {"photons_per_pass": 50000, "radius": 0.05, "alpha": 1, "passes": 1, "max_depth": 1, "seed": 3}
})";

// Inside a closed box of fog with a glass and a mirror sphere (multiple scattering, walls, specular chains).
inline const char* kBox = R"({
  "version": 1,
  "camera": {"position": [0, 1, 0.95], "look_at": [0, 0.8, -1], "fov": 60, "resolution": [20, 16]},
  "film": {"bins": 32},
  "media": {"fog": {"sigma_s": 0.5, "sigma_a": 0.05, "g": 0.2}},
  "global_medium": "fog",
  "materials": {"white": {"type": "diffuse", "albedo": 0.7}, "glass": {"type": "dielectric", "ior": 1.5},
                "chrome": {"type": "mirror", "reflectance": 0.9}},
  "shapes": [
    {"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "material": "white", "flip_normals": true},
    {"type": "sphere", "center": [-0.4, 0.5, 0], "radius": 0.35, "material": "glass"},
    {"type": "sphere", "center": [0.45, 0.4, -0.2], "radius": 0.3, "material": "chrome"}
  ],
  "lights": [{"type": "point", "position": [0, 1.8, 0], "power": 20}],
  "render": {"photons_per_pass": 3000, "radius_relative": 0.02, "surface_radius_relative": 0.03, "seed": 9}
})";

inline std::vector<double> renderVolume(const TestScene& sc, const RenderSettings& s, int passes) {
    Driver drv(*sc, s, sc.time);
    for (int p = 1; p <= passes; ++p) EXPECT_TRUE(drv.runPass(p));
    std::vector<double> v, u;
    drv.film().volume(TimeAxis::Real, EmissionMode::Delta, v);
    drv.film().volume(TimeAxis::Unwarped, EmissionMode::Delta, u);
    v.insert(v.end(), u.begin(), u.end());
    EXPECT_EQ(drv.film().stats.rejectedSamples.load(), 0);
    return v;
}

}  // namespace tpb::test
