#include "scene/camera.h"

namespace tpb {

Camera Camera::fromDesc(const CameraDesc& d) {
    Camera c;
    c.position = d.position;
    c.width = d.width;
    c.height = d.height;
    c.sensorRows = d.height;
    if (d.type == CameraType::RelayWall) {  // (no view direction: Scene::build sets the wall)
        c.height = static_cast<int>(d.filmHeight());
        c.scan = d.scan;
        c.scanLaser = d.scanLaser;
        c.laserGridX = d.laserGridX;
        c.laserGridY = d.laserGridY;
        c.scanPointU = d.scanPointU;
        c.scanPointV = d.scanPointV;
        return c;
    }  // (no view direction: Scene::build sets the wall)
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
    if (relayWall) {
        const double den = glm::dot(v, wallN);
        if (den == 0.0) return false;
        const double t = glm::dot(wallCorner - position, wallN) / den;
        if (!(t > 0.0)) return false;
        // q = s edge_u + t edge_v (a parallelogram: the 2x2 normal equations).
        const Vec3 q = position + t * v - wallCorner;
        const double uu = glm::dot(wallU, wallU), uv = glm::dot(wallU, wallV), vv = glm::dot(wallV, wallV);
        const double qu = glm::dot(q, wallU), qv = glm::dot(q, wallV), det = uu * vv - uv * uv;
        px = (qu * vv - qv * uv) / det * width;
        py = (qv * uu - qu * uv) / det * sensorRows;
        return true;
    }
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
