#include "render/nlos_capture.h"

#include "base/error.h"
#include "base/text.h"
#include "film/film_view.h"

#include <cmath>
#include <cstdio>
#include <optional>

namespace tpb {

namespace {

// A number YAML 1.1 readers (PyYAML) take as a float: the shortest exact decimal (base/text.h),
// with a ".0" before an exponent that has no point ("1e-17" would be read as a string).
std::string yamlNumber(double v) {
    std::string s = shortest(v);
    const size_t e = s.find('e');
    if (e != std::string::npos && s.find('.') == std::string::npos) s.insert(e, ".0");
    return s;
}

// A double-quoted YAML scalar (the JSON escapes, which YAML reads the same).
std::string yamlString(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) < 0x20) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", c);
            out += b;
            continue;
        }
        out += c;
    }
    return out + "\"";
}

// scene_info: the scene, the scan and the ground truth seen from the wall (sensor points in tal's
// order: Sx lists of Sy values; null where the normal ray from the wall meets nothing).
std::string sceneInfo(const Scene& scene, const std::string& scenePath) {
    const Camera& c = scene.camera;
    // The hidden side is the sensor's side of the wall.
    const Vec3 n = glm::dot(c.position - c.wallCorner, c.wallN) > 0.0 ? c.wallN : -c.wallN;
    std::string depth = "[", normals = "[";
    for (int x = 0; x < c.width; ++x) {
        depth += x ? ", [" : "[";
        normals += x ? ", [" : "[";
        for (int y = 0; y < c.sensorRows; ++y) {
            const Vec3 w = c.wallPoint(x + 0.5, y + 0.5);
            const std::optional<SurfaceHit> hit = scene.geometry.intersect(scene.leaveSurface(w, n, n));
            const std::string sep = y ? ", " : "";
            if (!hit) {
                depth += sep + "null";
                normals += sep + "null";
                continue;
            }
            const Vec3 hn = glm::dot(hit->ng, n) > 0.0 ? -hit->ng : hit->ng;  // facing the wall
            depth += sep + yamlNumber(hit->t);
            normals += sep + "[" + yamlNumber(hn.x) + ", " + yamlNumber(hn.y) + ", " + yamlNumber(hn.z) + "]";
        }
        depth += "]";
        normals += "]";
    }
    depth += "]";
    normals += "]";
    return "tpb:\n  scene: " + yamlString(scenePath) + "\n  scan: " + scanModeName(c.scan) +
           "\n  H: \"luminance of the pulse response, real time axis; bin k integrates [t_start + k delta_t, "
           "t_start + (k + 1) delta_t)\"\n" +
           "ground_truth:\n  about: \"per sensor point [sx][sy]: distance (m) along the wall's normal to the first "
           "surface, and that surface's normal facing the wall; null: nothing\"\n" +
           "  depth: " + depth + "\n  normals: " + normals + "\n";
}

}  // namespace

NlosCapture nlosCaptureGeometry(const Scene& scene, const TimeBins& tb) {
    const Camera& c = scene.camera;
    if (!c.relayWall || c.scan == ScanMode::None)
        throw UserError("an NLOS capture needs a relay-wall camera with a \"scan\" (docs/user/scenes.md)");
    NlosCapture cap;
    cap.bins = tb.bins;
    cap.sensorX = c.width;
    cap.sensorY = c.sensorRows;
    cap.confocal = c.scan == ScanMode::Confocal;
    cap.exhaustive = c.scan == ScanMode::Exhaustive;
    if (cap.exhaustive) {
        cap.laserX = c.laserGridX;
        cap.laserY = c.laserGridY;
    }
    const Vec3 n = glm::dot(c.position - c.wallCorner, c.wallN) > 0.0 ? c.wallN : -c.wallN;  // towards the sensor
    for (int x = 0; x < c.width; ++x)
        for (int y = 0; y < c.sensorRows; ++y) {
            cap.sensorGrid.push_back(c.wallPoint(x + 0.5, y + 0.5));
            cap.sensorNormals.push_back(n);
        }
    if (!cap.confocal) {
        // tal's laser grid: index lx Ly + ly; tpb's laser point l = ly Lx + lx (single: 0).
        for (int lx = 0; lx < cap.laserX; ++lx)
            for (int ly = 0; ly < cap.laserY; ++ly) {
                cap.laserGrid.push_back(c.laserTarget(static_cast<int64_t>(ly) * cap.laserX + lx));
                cap.laserNormals.push_back(n);
            }
    }
    cap.sensorOrigin = c.position;
    cap.laserOrigin = scene.lights.at(static_cast<size_t>(c.scanLaser)).position;
    cap.deltaT = tb.binWidth;
    cap.tStart = tb.startOpl;
    cap.tAccountsFirstAndLastBounces = !c.timeFromWall;
    return cap;
}

NlosCapture nlosCapture(const FilmSnapshot& film, const Scene& scene, const std::string& scenePath,
                        const TimeResponse& response) {
    NlosCapture cap = nlosCaptureData(film, scene, response);
    cap.sceneInfoYaml = sceneInfo(scene, scenePath);
    return cap;
}

NlosCapture nlosCaptureData(const FilmSnapshot& film, const Scene& scene, const TimeResponse& response) {
    const Camera& c = scene.camera;
    const TimeBins& tb = film.time();
    NlosCapture cap = nlosCaptureGeometry(scene, tb);

    // H[k][lx][ly][sx][sy] = luminance of film pixel (sx, l Sy + sy), l = ly Lx + lx, bin k.
    const size_t perBin = static_cast<size_t>(cap.laserX) * cap.laserY * cap.sensorX * cap.sensorY;
    cap.H.assign(perBin * static_cast<size_t>(tb.bins), 0.0f);
    for (int k = 0; k < tb.bins; ++k) {
        const std::vector<float> img = frameImage(film, k, TimeAxis::Real, EmissionMode::Delta, response);
        float* h = &cap.H[static_cast<size_t>(k) * perBin];
        for (int lx = 0; lx < cap.laserX; ++lx)
            for (int ly = 0; ly < cap.laserY; ++ly) {
                const int layer = ly * cap.laserX + lx;
                for (int sx = 0; sx < cap.sensorX; ++sx)
                    for (int sy = 0; sy < cap.sensorY; ++sy) {
                        const size_t px = static_cast<size_t>(layer * c.sensorRows + sy) * c.width + sx;
                        const float* rgb = &img[px * 3];
                        *h++ = static_cast<float>(luminance(Color(rgb[0], rgb[1], rgb[2])));
                    }
            }
    }
    return cap;
}

}  // namespace tpb
