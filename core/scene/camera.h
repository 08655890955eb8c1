// Pinhole camera, or a relay-wall sensor (scene_desc.h CameraType). Pinhole: pixel (0, 0) is the
// top-left corner, raster y grows downwards. Relay wall: raster (x, y) is the wall point
// corner + x / width edge_u + y / height edge_v, every ray leaves `position` (the sensor) for it.
#pragma once
#include "base/math.h"
#include "scene/scene_desc.h"

namespace tpb {

struct Camera {
    Vec3 position{0.0}, forward{0.0, 0.0, -1.0}, right{1.0, 0.0, 0.0}, up{0.0, 1.0, 0.0};
    double tanHalfFovY = 0.4;
    int width = 1, height = 1;
    // Relay wall: the quad (wallN its unit normal), where time starts, and the index of refraction
    // between the sensor and the wall (Scene::build: the sensor's region).
    bool relayWall = false, timeFromWall = false;
    Vec3 wallCorner{0.0}, wallU{1.0, 0.0, 0.0}, wallV{0.0, 1.0, 0.0}, wallN{0.0, 0.0, 1.0};
    double legIor = 1.0;

    // A pinhole camera from its description (a relay wall's quad is set by Scene::build).
    static Camera fromDesc(const CameraDesc& d);
    // Ray through raster position (px, py) in pixels (pixel centres at +0.5).
    Ray generate(double px, double py) const {
        if (relayWall)
            return {position, glm::normalize(wallCorner + (px / width) * wallU + (py / height) * wallV - position)};
        const double aspect = static_cast<double>(width) / height;
        const double sx = (2.0 * px / width - 1.0) * tanHalfFovY * aspect;
        const double sy = (1.0 - 2.0 * py / height) * tanHalfFovY;
        return {position, glm::normalize(forward + sx * right + sy * up)};
    }
    // The camera path's optical length where `ray` (from generate) starts: 0, except for a relay
    // wall whose time starts at the wall: minus the leg to the wall, eta |x_wall - position|.
    double startOpl(const Ray& ray) const {
        if (!timeFromWall) return 0.0;
        return -legIor * glm::dot(wallCorner - position, wallN) / glm::dot(ray.d, wallN);
    }
    // Raster position of a world point (relay wall: where the line from the sensor through it
    // meets the wall's plane); false if behind the camera.
    bool project(const Vec3& p, double& px, double& py) const;
};

}  // namespace tpb
