// Pinhole camera, or a relay-wall sensor (scene_desc.h CameraType). Pinhole: pixel (0, 0) is the
// top-left corner, raster y grows downwards. Relay wall: raster (x, y) is the wall point
// corner + x / width edge_u + y / sensorRows edge_v, every ray leaves `position` (the sensor) for it;
// an exhaustive scan stacks one sensor image per laser point, so raster row y is sensor row
// y mod sensorRows of laser point y / sensorRows.
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
    // The scan (scene_desc.h ScanMode): the laser light that scans, the rows of one sensor image
    // (height, but for an exhaustive scan), the laser grid and the single scan's point (wall
    // fractions).
    ScanMode scan = ScanMode::None;
    int scanLaser = -1;
    int sensorRows = 1;
    int laserGridX = 1, laserGridY = 1;
    double scanPointU = 0.5, scanPointV = 0.5;

    // A pinhole camera from its description (a relay wall's quad is set by Scene::build).
    static Camera fromDesc(const CameraDesc& d);
    // Ray through raster position (px, py) in pixels (pixel centres at +0.5).
    Ray generate(double px, double py) const {
        if (relayWall) return {position, glm::normalize(wallPoint(px, py) - position)};
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
    // Relay wall: the wall point at raster (px, py) (pixel centres at +0.5), any laser layer.
    Vec3 wallPoint(double px, double py) const {
        const int layer = static_cast<int>(py) / sensorRows;
        return wallCorner + (px / width) * wallU +
               ((py - static_cast<double>(layer) * sensorRows) / sensorRows) * wallV;
    }
    // Laser points of the scan, rendered one after the other in each pass (1 without a scan).
    int64_t laserPoints() const {
        return scan == ScanMode::Confocal     ? static_cast<int64_t>(width) * height
               : scan == ScanMode::Exhaustive ? static_cast<int64_t>(laserGridX) * laserGridY
                                              : 1;
    }
    // The wall point laser point `l` aims at: confocal l = y width + x, the centre of pixel (x, y);
    // exhaustive l = ly Lx + lx, the centre of grid cell (lx, ly); single: the scan's point.
    Vec3 laserTarget(int64_t l) const {
        if (scan == ScanMode::Confocal)
            return wallPoint(static_cast<double>(l % width) + 0.5, static_cast<double>(l / width) + 0.5);
        if (scan == ScanMode::Exhaustive)
            return wallCorner + ((static_cast<double>(l % laserGridX) + 0.5) / laserGridX) * wallU +
                   ((static_cast<double>(l / laserGridX) + 0.5) / laserGridY) * wallV;
        return wallCorner + scanPointU * wallU + scanPointV * wallV;
    }
    // The laser point that lights pixel (x, y) of the film.
    int64_t laserPointOf(int x, int y) const {
        if (scan == ScanMode::Confocal) return static_cast<int64_t>(y) * width + x;
        if (scan == ScanMode::Exhaustive) return y / sensorRows;
        return 0;
    }
    // Raster position of a world point (relay wall: where the line from the sensor through it
    // meets the wall's plane, in the first laser point's image); false if behind the camera.
    bool project(const Vec3& p, double& px, double& py) const;
};

}  // namespace tpb
