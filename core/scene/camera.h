// Pinhole camera. Pixel (0, 0) is the top-left corner; raster y grows downwards.
#pragma once
#include "base/math.h"
#include "scene/scene_desc.h"

namespace tpb {

struct Camera {
    Vec3 position{0.0}, forward{0.0, 0.0, -1.0}, right{1.0, 0.0, 0.0}, up{0.0, 1.0, 0.0};
    double tanHalfFovY = 0.4;
    int width = 1, height = 1;

    static Camera fromDesc(const CameraDesc& d);
    // Ray through raster position (px, py) in pixels (pixel centres at +0.5).
    Ray generate(double px, double py) const {
        const double aspect = static_cast<double>(width) / height;
        const double sx = (2.0 * px / width - 1.0) * tanHalfFovY * aspect;
        const double sy = (1.0 - 2.0 * py / height) * tanHalfFovY;
        return {position, glm::normalize(forward + sx * right + sy * up)};
    }
    // Raster position of a world point; false if behind the camera.
    bool project(const Vec3& p, double& px, double& py) const;
};

}  // namespace tpb
