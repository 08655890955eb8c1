#include "render/fingerprint.h"

#include "base/text.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

namespace tpb {

namespace {

std::string num(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v);
    return b;
}
std::string num(int v) { return std::to_string(v); }
std::string num(bool v) { return v ? "true" : "false"; }
std::string num(const Vec3& v) {
    char b[96];
    std::snprintf(b, sizeof b, "(%.17g, %.17g, %.17g)", v.x, v.y, v.z);
    return b;
}
std::string num(const Mat4& m) {
    std::string s = "[";
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            if (c || r) s.append(", ");
            s.append(num(m[c][r]));
        }
    s.push_back(']');
    return s;
}

struct Writer {
    Fingerprint fp;
    template <class T>
    void operator()(const std::string& key, const T& v) {
        fp.emplace_back(key, num(v));
    }
    void text(const std::string& key, const std::string& v) { fp.emplace_back(key, v); }
};

}  // namespace

std::string fileFingerprint(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return "unreadable";
    uint64_t h = 0xcbf29ce484222325ull;
    char buf[1 << 16];
    while (in) {
        in.read(buf, sizeof buf);
        const std::streamsize n = in.gcount();
        for (std::streamsize i = 0; i < n; ++i) {
            h ^= static_cast<unsigned char>(buf[i]);
            h *= 0x100000001b3ull;
        }
    }
    char out[20];
    std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
    return out;
}

Fingerprint sceneFingerprint(const SceneDesc& d) {
    Writer w;
    w("camera.position", d.camera.position);
    w("camera.look_at", d.camera.lookAt);
    w("camera.up", d.camera.up);
    w("camera.fov_y_deg", d.camera.fovYDeg);
    w("camera.width", d.camera.width);
    w("camera.height", d.camera.height);
    if (d.camera.type == CameraType::RelayWall) {  // (absent for a pinhole: older checkpoints still resume)
        w.text("camera.type", "relay_wall");
        w("camera.wall", d.camera.wallShape);
        w.text("camera.time_origin", d.camera.timeOrigin == WallTimeOrigin::Wall ? "wall" : "sensor");
        if (d.camera.scan != ScanMode::None) {  // (absent without a scan: relay-wall checkpoints still resume)
            w.text("camera.scan.mode", scanModeName(d.camera.scan));
            w("camera.scan.laser", d.camera.scanLaser);
            w("camera.scan.point_u", d.camera.scanPointU);
            w("camera.scan.point_v", d.camera.scanPointV);
            w("camera.scan.grid_x", d.camera.laserGridX);
            w("camera.scan.grid_y", d.camera.laserGridY);
        }
    }
    w("film.auto_range", d.film.autoRange);
    w("film.bins", d.film.bins);
    if (!d.film.autoRange) {
        w("film.start_opl", d.film.startOpl);
        w("film.bin_width_opl", d.film.binWidthOpl);
    }
    w("global_medium", d.globalMedium);
    for (size_t i = 0; i < d.media.size(); ++i) {
        const MediumDesc& m = d.media[i];
        const std::string k = "media[" + std::to_string(i) + "].";
        w.text(k + "name", m.name);
        w(k + "sigma_s", m.sigma_s);
        w(k + "sigma_a", m.sigma_a);
        w(k + "ior", m.ior);
        w(k + "g", m.g);
    }
    for (size_t i = 0; i < d.materials.size(); ++i) {
        const MaterialDesc& m = d.materials[i];
        const std::string k = "materials[" + std::to_string(i) + "].";
        w.text(k + "name", m.name);
        w.text(k + "type", materialTypeName(m.type));
        w(k + "albedo", m.albedo);
        w(k + "specular", m.specular);
        w(k + "ior", m.ior);
    }
    for (size_t i = 0; i < d.shapes.size(); ++i) {
        const ShapeDesc& s = d.shapes[i];
        const std::string k = "shapes[" + std::to_string(i) + "].";
        w.text(k + "name", s.name);
        w.text(k + "type", shapeTypeName(s.type));
        w(k + "material", s.material);
        w(k + "interior_medium", s.interiorMedium);
        w(k + "flip_normals", s.flipNormals);
        w(k + "area_light", s.areaLight);
        switch (s.type) {
            case ShapeType::Mesh:
                w.text(
                    k + "mesh",
                    std::filesystem::path(s.meshPath).filename().string());  // not the folder: resumable from elsewhere
                w.text(k + "mesh_bytes_fnv1a64", fileFingerprint(s.meshPath));
                w(k + "transform", s.transform);
                break;
            case ShapeType::Sphere:
                w(k + "center", s.center);
                w(k + "radius", s.radius);
                break;
            case ShapeType::Quad:
                w(k + "corner", s.corner);
                w(k + "edge_u", s.edgeU);
                w(k + "edge_v", s.edgeV);
                break;
            case ShapeType::Box:
                w(k + "min", s.boxMin);
                w(k + "max", s.boxMax);
                w(k + "transform", s.transform);
                break;
        }
    }
    for (size_t i = 0; i < d.lights.size(); ++i) {
        const LightDesc& l = d.lights[i];
        const std::string k = "lights[" + std::to_string(i) + "].";
        w.text(k + "name", l.name);
        w.text(k + "type", lightTypeName(l.type));
        w(k + "power", l.power);
        w(k + "emit_opl", l.emitOpl);
        switch (l.type) {
            case LightType::Point: w(k + "position", l.position); break;
            case LightType::Spot:
                w(k + "position", l.position);
                w(k + "direction", l.direction);
                w(k + "cutoff_deg", l.spotCutoffDeg);
                w(k + "falloff_deg", l.spotFalloffDeg);
                break;
            case LightType::AreaQuad:
                w(k + "corner", l.corner);
                w(k + "edge_u", l.edgeU);
                w(k + "edge_v", l.edgeV);
                break;
            case LightType::Laser:
                w(k + "position", l.position);
                w(k + "direction", l.direction);
                w(k + "radius", l.laserRadius);
                break;
        }
    }
    return w.fp;
}

Fingerprint settingsFingerprint(const RenderSettings& s) {
    // The keys of settingsRecord that enter a pass (fingerprint.h: not the pass count, budget,
    // threads, accelerator or how the film is shown).
    static const char* const kPassKeys[] = {"method",           "seed",
                                            "max_depth",        "photons_per_pass",
                                            "warmup",           "radius",
                                            "surface_radius",   "alpha",
                                            "time_profile",     "beam_length",
                                            "volume_estimator", "surface_estimator",
                                            "time_kernel",      "samples_per_pixel",
                                            "equiangular",      "bounces"};
    const Record record = settingsRecord(s);
    Fingerprint fp;
    for (const char* key : kPassKeys)
        if (const RecordValue* v = recordFind(record, key))
            fp.emplace_back(std::string("render.") + key, recordText(*v));
    return fp;
}

Fingerprint timeFingerprint(const TimeBins& t) {
    Writer w;
    w("film.time.bins", t.bins);
    w("film.time.start_opl_m", t.startOpl);
    w("film.time.bin_width_opl_m", t.binWidth);
    return w.fp;
}

std::string phasorListText(const PhasorSpec& p) {
    std::string list;
    for (double x : p.frequencies) {
        if (!list.empty()) list += ',';
        list += shortest(x);
    }
    return list;
}

Fingerprint phasorFingerprint(const PhasorSpec& p) {
    Fingerprint f;
    if (p.active()) f.emplace_back("film.phasor.frequencies", phasorListText(p));
    return f;
}

std::string currentFingerprintKey(const std::string& key) {
    static const std::map<std::string, std::string> kRenamed = {{"render.photons", "render.photons_per_pass"},
                                                                {"render.radius_m", "render.radius"},
                                                                {"render.surface_radius_m", "render.surface_radius"},
                                                                {"render.estimator", "render.volume_estimator"},
                                                                {"render.spp", "render.samples_per_pixel"}};
    const auto it = kRenamed.find(key);
    return it == kRenamed.end() ? key : it->second;
}

std::vector<std::string> fingerprintChanges(const Fingerprint& stored, const Fingerprint& now) {
    Fingerprint checkpoint;
    for (const auto& [k, v] : stored) checkpoint.emplace_back(currentFingerprintKey(k), v);
    std::map<std::string, std::string> a(checkpoint.begin(), checkpoint.end()), b(now.begin(), now.end());
    std::vector<std::string> out;
    for (const auto& [k, v] : checkpoint) {
        // Checkpoints written before the accelerator left the fingerprint (every backend gives the
        // same films, bit for bit) still name it: not a difference.
        if (k == "render.accel") continue;
        const auto it = b.find(k);
        // Compared as stored (%.17g: bit-exact), shown in the shortest form that reads back the same.
        if (it == b.end())
            out.push_back(k + ": only in the checkpoint (" + withShortestNumbers(v) + ")");
        else if (it->second != v)
            out.push_back(k + ": the checkpoint has " + withShortestNumbers(v) + ", this run has " +
                          withShortestNumbers(it->second));
    }
    for (const auto& [k, v] : now)
        if (!a.count(k)) out.push_back(k + ": only in this run (" + withShortestNumbers(v) + ")");
    return out;
}

}  // namespace tpb
