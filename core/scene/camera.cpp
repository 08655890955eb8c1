#include "scene/camera.h"

namespace tpb {

Camera Camera::fromDesc(const CameraDesc& d) {
    Camera c;
    c.position = d.position;
    c.forward = glm::normalize(d.lookAt - d.position);
    c.right = glm::normalize(glm::cross(c.forward, d.up));
    c.up = glm::cross(c.right, c.forward);
    c.tanHalfFovY = std::tan(0.5 * d.fovYDeg * kPi / 180.0);
    c.width = d.width;
    c.height = d.height;
    return c;
}

bool Camera::project(const Vec3& p, double& px, double& py) const {
    const Vec3 v = p - position;
    const double z = glm::dot(v, forward);
    if (z <= 0.0) return false;
    const double aspect = static_cast<double>(width) / height;
    const double sx = glm::dot(v, right) / z / (tanHalfFovY * aspect);
    const double sy = glm::dot(v, up) / z / tanHalfFovY;
    px = 0.5 * (sx + 1.0) * width;
    py = 0.5 * (1.0 - sy) * height;
    return true;
}

}  // namespace tpb
