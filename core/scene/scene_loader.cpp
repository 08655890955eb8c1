// Scene file loader: JSON text -> SceneDesc, with every value's file:line kept in SceneDesc::locs.
//
// ==== Scene format (version 1) ====================================================================
// A scene file is one JSON object (strict RFC 8259: no comments, no trailing commas). Keys starting
// with "_" or named "comment" are comments, allowed in any object and ignored. Any other key that is
// not listed below is an error (with the closest allowed key suggested), as is a value of the wrong
// type or out of range. Every key is optional unless marked (required); defaults are in brackets.
// Colors and spectra ("power", "albedo", "sigma_s", ...) are a number (grey) or an [r, g, b] array.
// Vectors are [x, y, z] arrays; directions are normalized and must not be zero. Positions, edges,
// sizes, radii and translations are meters within +-1e9 (kMaxSceneCoordinateM), and so are mesh
// vertices after the shape's transform.
// Times are optical path length (OPL) in meters: each time key exists as "<name>_m" and
// "<name>_ns" (ns are converted with c = 0.299792458 m/ns); giving both is an error.
//
// {
//   "version": 1,                        // only 1; missing -> warning, 1 assumed
//   "camera": {
//     "position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0],
//     "fov": 40,                         // vertical field of view, degrees, in (0, 180)
//     "resolution": [256, 256]           // [width, height], integers >= 1
//   },                                   // or a relay-wall sensor (NLOS captures):
//   // "camera": {"type": "relay_wall",  // ["pinhole"]
//   //   "position": [-0.5, 0, 0.25],    // the sensor's origin
//   //   "wall": "relay",                // name of the quad shape the grid lies on
//   //   "resolution": [32, 32],         // the grid: pixel (i, j) = corner + [i, i+1)/W edge_u + [j, j+1)/H edge_v
//   //   "time_origin": "sensor",        // "sensor": the wall -> sensor leg counted ["sensor"]; "wall": not
//   //   "scan": {"mode": "confocal",    // "single" | "confocal" | "exhaustive" (no "scan": the lights as they are)
//   //            "laser": "laser",      // name of the laser light that scans (its direction is the aim's)
//   //            "point": [0.5, 0.5],   // single: the laser point as wall fractions [u, v] in [0, 1]
//   //            "grid": [4, 4]}},      // exhaustive: Lx x Ly laser points at the cell centres
//   "film": {
//     "bins": 256,                       // time bins, integer >= 1
//     "phasor": [0.5, 2],                // optional exact phasor film: frequencies in cycles per m of
//                                        // OPL, or a string "F1,F2" | "wl:WL1,WL2" | "band:MEAN:SIGMA"
//                                        // (docs/user/phasor.md; read once the time axis is known)
//     "range": "auto",                   // fit the time range to the scene [default] ...
//     "start_m": 0, "bin_width_m": 0.01  // ... or an explicit range (start_ns / bin_width_ns too);
//   },                                   //     giving either one turns "auto" off (and both: error)
//   "media": {                           // named homogeneous media
//     "fog": {"sigma_s": 0.5, "sigma_a": 0.0,   // 1/m, >= 0, number or [r, g, b] [0]
//             "ior": 1.0,                        // >= 1 [1]
//             "g": 0.0}                          // Henyey-Greenstein, in (-1, 1) [0]
//   },
//   "global_medium": "fog",              // medium filling the outside [none: vacuum]
//   "materials": {                       // named materials; "type" (required) is one of:
//     "white":  {"type": "diffuse", "albedo": 0.8},        // albedo in [0, 1] [0.8]
//     "chrome": {"type": "mirror", "reflectance": 1.0},    // in [0, 1] [1]
//     "glass":  {"type": "dielectric", "ior": 1.5, "tint": 1.0},  // ior >= 1 [1.5], tint in [0, 1] [1]
//     "box":    {"type": "null"}                           // invisible boundary of a medium
//   },
//   "shapes": [                          // may be empty; every shape has "type" (required),
//                                        // "name" [""], "material" (a material name) [none]
//     {"type": "mesh", "file": "armadillo.obj",  // (required) OBJ, relative to the scene file
//      "interior_medium": "juice", "transform": {...}, "flip_normals": false},
//     {"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior_medium": "juice"},  // radius > 0
//     {"type": "quad", "corner": [0, 0, 0], "edge_u": [1, 0, 0], "edge_v": [0, 1, 0],
//      "flip_normals": false},           // normal = cross(edge_u, edge_v)
//     {"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5],  // min < max
//      "transform": {...}, "interior_medium": "juice", "flip_normals": false}
//   ],
//   "lights": [                          // may be empty (warning); every light has "type"
//                                        // (required), "name" [""], "power" (W, 0..1e20) [1],
//                                        // "emit_time_m" / "emit_time_ns" [0]
//     {"type": "point", "position": [0, 0, 0]},
//     {"type": "spot", "position": [..], "direction": [0, -1, 0],
//      "cutoff_deg": 30,                 // cone half-angle, in (0, 180]
//      "falloff_deg": 25},               // in [0, cutoff_deg] [min(25, cutoff_deg)]
//     {"type": "area", "corner": [..], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1]},  // emits along
//                                        // cross(edge_u, edge_v); also a visible emitting quad
//     {"type": "laser", "position": [..], "direction": [..], "radius": 0}  // radius >= 0, m
//   ],
//   "render": {
//     "photons_per_pass": 20000,         // integer >= 1
//     "warmup": 0,                       // 0..20 first passes with fewer photons (1/2^W ... 1/2); the viewer: 3
//     "radius": 0.01 | "auto" | "radius_relative": 0.01,  // volume kernel radius, > 0: absolute (m),
//                                                // "auto" (a pilot pass's photon density: also
//                                                // the default when neither is written), or a
//                                                // fraction of the scene diagonal [relative 0.01];
//                                                // at most 0.25 of the diagonal (a wider kernel makes a
//                                                // pass cost rays x beams), warned about above 0.05
//     "surface_radius": 0.02 | "surface_radius_relative": 0.02,  // surface photons [relative 0.02]
//                                        // the two radii share one convention: mixing absolute and
//                                        // relative is an error; giving one of them sets it for both
//     "alpha": 0.7,                      // progressive radius reduction, in (0, 1]
//     "passes": 16,                      // integer >= 0, 0 = until the time budget
//     "time_budget_s": 0,                // >= 0, 0 = none
//     "max_depth": 16,                   // integer >= 1
//     "bounces": [2, 3],                 // bounce filter: only light with 2..3 scattering events (or n: exactly n) [all]
//     "seed": 1,                         // integer in [0, 2^64)
//     "threads": 0,                      // integer >= 0, 0 = all cores; above 4 x the cores: capped
//     "emission": "delta",               // "delta" | "continuous"
//     "unwarp": false,                   // remove the camera-to-scene travel time
//     "time_profile": "exact",           // "exact" | "uniform"
//     "beam_length": "short",            // "short" | "long"
//     "volume_estimator": "beam2d",      // estimators/estimator_names.h (docs/user/estimators.md)
//     "surface_estimator": "ppm",        // the surface photon map
//     "time_kernel": "none"              // "none" | "box" | {"type": "box", "width": m of OPL > 0}
//   }
// }
//
// Transform object (meshes and boxes): either "matrix": 16 numbers, row-major, affine (last row
// 0 0 0 1), with a positive determinant; or any of
//   "translate": [x, y, z], "scale": s or [x, y, z] (each > 0),
//   "rotate": {"axis": [x, y, z], "angle_deg": a} or a list of such rotations,
// composed as T * R * S (scale first, then rotate, then translate). A list of rotations is applied
// in list order: R = R_n * ... * R_2 * R_1. Mirroring is refused (use "flip_normals").
//
// Names: a material or medium is referred to by its key in "materials" / "media"; references to
// undefined names are errors. "global_medium" and "interior_medium" may also be null (none).
// ==================================================================================================
#include "scene/scene_loader.h"
#include "scene/mitsuba_loader.h"

#include "base/error.h"
#include "base/text.h"
#include "io/json.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <functional>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>
#include <unistd.h>

namespace tpb {

namespace {

// ---- small helpers -------------------------------------------------------------------------------

std::string join(const std::vector<std::string>& words) {
    std::string s;
    for (const std::string& w : words) s += (s.empty() ? "" : ", ") + w;
    return s;
}

bool isPlainInteger(const std::string& lit) { return !lit.empty() && lit.find_first_of(".eE") == std::string::npos; }

// ---- the property bag ----------------------------------------------------------------------------

struct Context {
    std::string file;
    SceneDesc& desc;
};

// Reads the members of one JSON object. Every key asked for is remembered as allowed (and, when
// present, its file:line goes to desc.locs); finish() reports the keys nobody asked for.
class Bag {
public:
    Bag(Context& ctx, const JsonValue& obj, std::string path, std::string what = "")
        : ctx_(ctx), obj_(obj), path_(std::move(path)), what_(std::move(what)) {
        if (!path_.empty()) ctx_.desc.locs.emplace(path_, SourceLoc{ctx_.file, obj_.line});
    }

    void setWhat(std::string what) { what_ = std::move(what); }
    const std::string& path() const { return path_; }
    std::string pathOf(std::string_view key) const {
        return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
    }

    // Marks `key` as allowed; returns its member (recording where it was written) or nullptr.
    const JsonMember* member(std::string_view key) {
        if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end()) allowed_.emplace_back(key);
        const JsonMember* m = obj_.findMember(key);
        if (m) ctx_.desc.locs[pathOf(key)] = SourceLoc{ctx_.file, m->line};
        return m;
    }
    const JsonValue* get(std::string_view key) {
        const JsonMember* m = member(key);
        return m ? &m->value : nullptr;
    }
    bool has(std::string_view key) { return member(key) != nullptr; }

    // Error about `key`: at its value's line when written, else at this object's line.
    [[noreturn]] void fail(std::string_view key, const std::string& message) const {
        const JsonMember* m = obj_.findMember(key);
        throw UserError(ctx_.file, m ? m->value.line : obj_.line, pathOf(key), message);
    }
    // "<key> <rule> (got <value>)" unless ok.
    void check(bool ok, std::string_view key, const std::string& rule) const {
        if (ok) return;
        const JsonValue* v = obj_.find(key);
        fail(key, std::string(key) + " " + rule + (v ? " (got " + v->brief() + ")" : ""));
    }
    // A warning about `key`, "file:line: key: message" (at this object's line when not written).
    void warnAbout(std::string_view key, const std::string& message) const {
        const JsonMember* m = obj_.findMember(key);
        ctx_.desc.warnings.push_back(ctx_.file + ":" + std::to_string(m ? m->value.line : obj_.line) + ": " +
                                     pathOf(key) + ": " + message);
    }
    [[noreturn]] void wrongType(std::string_view key, const std::string& expected) const {
        const JsonValue* v = obj_.find(key);
        fail(key, "expected " + expected + (v ? ", got " + std::string(v->typeName()) + " " + v->brief() : ""));
    }
    // A required key is absent. A misspelling of it is the likelier mistake, so that is reported first.
    [[noreturn]] void missing(std::string_view key, const std::string& hint = "") {
        member(key);
        for (const JsonMember& m : obj_.members)
            if (!isAllowed(m.key) && !suggestion(m.key, {std::string(key)}).empty()) finish();
        fail(key, "required key is missing" + hint);
    }
    const JsonValue& require(std::string_view key, const std::string& hint = "") {
        const JsonValue* v = get(key);
        if (!v) missing(key, hint);
        return *v;
    }

    // ---- typed readers: nullopt when the key is absent ----

    std::optional<double> number(std::string_view key) {
        const JsonValue* v = get(key);
        if (!v) return std::nullopt;
        if (!v->isNumber()) wrongType(key, "a number");
        return v->number;
    }
    double number(std::string_view key, double def) { return number(key).value_or(def); }

    std::optional<bool> boolean(std::string_view key) {
        const JsonValue* v = get(key);
        if (!v) return std::nullopt;
        if (!v->isBool()) wrongType(key, "true or false");
        return v->boolean;
    }

    std::optional<std::string> string(std::string_view key) {
        const JsonValue* v = get(key);
        if (!v) return std::nullopt;
        if (!v->isString()) wrongType(key, "a string");
        return v->text;
    }

    std::optional<Color> color(std::string_view key) {
        const JsonValue* v = get(key);
        if (!v) return std::nullopt;
        if (v->isNumber()) return Color(v->number);
        if (!v->isArray() || v->items.size() != 3 || !v->items[0].isNumber() || !v->items[1].isNumber() ||
            !v->items[2].isNumber())
            wrongType(key, "a number or an [r, g, b] array");
        return Color(v->items[0].number, v->items[1].number, v->items[2].number);
    }

    std::optional<Vec3> vec3(std::string_view key) {
        const JsonValue* v = get(key);
        if (!v) return std::nullopt;
        if (!v->isArray() || v->items.size() != 3 || !v->items[0].isNumber() || !v->items[1].isNumber() ||
            !v->items[2].isNumber())
            wrongType(key, "an [x, y, z] array of 3 numbers");
        return Vec3(v->items[0].number, v->items[1].number, v->items[2].number);
    }
    Vec3 vec3(std::string_view key, const Vec3& def) { return vec3(key).value_or(def); }

    // A position, edge or extent in meters: every coordinate within +-kMaxSceneCoordinateM.
    std::optional<Vec3> point(std::string_view key) {
        std::optional<Vec3> p = vec3(key);
        if (p) checkCoordinates(key, {p->x, p->y, p->z});
        return p;
    }
    Vec3 point(std::string_view key, const Vec3& def) { return point(key).value_or(def); }
    // A length in meters (a radius): at most kMaxSceneCoordinateM.
    double length(std::string_view key, double def) {
        const double v = number(key, def);
        checkCoordinates(key, {v});
        return v;
    }
    void checkCoordinates(std::string_view key, std::initializer_list<double> values) const {
        for (double v : values)
            if (!(std::fabs(v) <= kMaxSceneCoordinateM)) {
                const JsonValue* j = obj_.find(key);
                fail(key, std::string(key) + " is too far out: scene coordinates and sizes must be within +-" +
                              shortNumber(kMaxSceneCoordinateM) + " m" + (j ? " (got " + j->brief() + ")" : "") +
                              "; check the units (meters) and the exponent");
            }
    }

    // A non-zero vector, normalized. Scaled by its largest component first, so that a huge but
    // finite vector ([1e308, 1e308, 0]) is a direction and not an overflow to a "zero vector".
    std::optional<Vec3> direction(std::string_view key) {
        std::optional<Vec3> d = vec3(key);
        if (!d) return d;
        const double largest = std::max({std::fabs(d->x), std::fabs(d->y), std::fabs(d->z)});
        check(largest > 0.0, key, "must not be a zero vector");
        return glm::normalize(*d / largest);
    }

    // An integral number in [lo, hi].
    std::optional<int64_t> integer(std::string_view key, int64_t lo, int64_t hi) {
        const JsonValue* v = get(key);
        if (!v) return std::nullopt;
        return toInteger(*v, key, std::string(key), lo, hi);
    }
    int toInt(const JsonValue& v, std::string_view key, const std::string& name, int lo) const {
        return static_cast<int>(toInteger(v, key, name, lo, INT_MAX));
    }

    int64_t toInteger(const JsonValue& v, std::string_view key, const std::string& name, int64_t lo, int64_t hi) const {
        if (!v.isNumber()) wrongType(key, "an integer");
        bool tooLow = false, tooHigh = false;
        int64_t n = 0;
        if (isPlainInteger(v.text)) {
            const auto [ptr, ec] = std::from_chars(v.text.data(), v.text.data() + v.text.size(), n);
            if (ec != std::errc()) (v.text[0] == '-' ? tooLow : tooHigh) = true;
        } else {
            const double d = v.number;
            if (d != std::floor(d)) fail(key, name + " must be an integer (got " + v.text + ")");
            if (d < -9223372036854775808.0)
                tooLow = true;
            else if (d >= 9223372036854775808.0)
                tooHigh = true;
            else
                n = static_cast<int64_t>(d);
        }
        if (tooLow || (!tooHigh && n < lo))
            fail(key, name + " must be >= " + std::to_string(lo) + " (got " + v.text + ")");
        if (tooHigh || n > hi) fail(key, name + " must be <= " + std::to_string(hi) + " (got " + v.text + ")");
        return n;
    }

    // One of `options` (a string), reported with the allowed values when unknown.
    template <class E>
    std::optional<E> choice(std::string_view key, const std::vector<std::pair<std::string, E>>& options,
                            const std::string& what, const std::string& hint = "") {
        const std::optional<std::string> s = string(key);
        if (!s) return std::nullopt;
        std::vector<std::string> names;
        for (const auto& [name, value] : options) {
            if (name == *s) return value;
            names.push_back("\"" + name + "\"");
        }
        std::vector<std::string> plain;
        for (const auto& o : options) plain.push_back(o.first);
        fail(key, "unknown " + what + " \"" + clipped(*s) + "\"" + suggestion(*s, plain) + "; allowed: " + join(names) +
                      hint);
    }

    // A time given as "<base>_m" or "<base>_ns", returned as OPL in meters.
    std::optional<double> opl(const std::string& base) {
        const std::string km = base + "_m", kns = base + "_ns";
        const std::optional<double> m = number(km);
        const std::optional<double> ns = number(kns);
        if (m && ns) fail(kns, "give either " + km + " or " + kns + ", not both");
        if (ns) return *ns * kC_m_per_ns;
        return m;
    }

    // Unknown keys are errors.
    void finish() const {
        for (const JsonMember& m : obj_.members) {
            if (isAllowed(m.key)) continue;
            std::string msg = "unknown key";
            if (!what_.empty()) msg += " for " + what_;
            msg += suggestion(m.key, allowed_);
            msg += allowed_.empty() ? "; this object takes no keys" : "; allowed: " + join(allowed_);
            throw UserError(ctx_.file, m.line, pathOf(clipped(m.key)), msg);
        }
    }

private:
    bool isAllowed(const std::string& key) const {
        return isJsonCommentKey(key) || std::find(allowed_.begin(), allowed_.end(), key) != allowed_.end();
    }

    Context& ctx_;
    const JsonValue& obj_;
    std::string path_;
    std::string what_;
    std::vector<std::string> allowed_;
};

// The object under `key`, or nullptr when absent; other types are errors.
const JsonValue* objectAt(Bag& bag, std::string_view key) {
    const JsonValue* v = bag.get(key);
    if (v && !v->isObject()) bag.wrongType(key, "an object { ... }");
    return v;
}

bool inUnit(const Color& c) { return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x <= 1 && c.y <= 1 && c.z <= 1; }
bool nonNegative(const Color& c) { return c.x >= 0 && c.y >= 0 && c.z >= 0; }

// ---- sections ------------------------------------------------------------------------------------

// The names a camera block refers to, resolved once the shapes and lights are read.
struct CameraRefs {
    std::string wall;   // the relay wall's quad ("" for a pinhole camera)
    std::string laser;  // the scanning laser ("" without a scan)
};

void readScan(Context& ctx, const JsonValue& obj, CameraDesc& cam, CameraRefs& refs) {
    Bag b(ctx, obj, "camera.scan", "the scan");
    const std::optional<ScanMode> mode = b.choice<ScanMode>(
        "mode", {{"single", ScanMode::Single}, {"confocal", ScanMode::Confocal}, {"exhaustive", ScanMode::Exhaustive}},
        "mode");
    if (!mode) b.missing("mode", "; allowed: \"single\", \"confocal\", \"exhaustive\"");
    cam.scan = *mode;
    if (!b.has("laser")) b.missing("laser", " (the name of the laser light that scans the wall)");
    refs.laser = b.string("laser").value_or("");
    if (cam.scan == ScanMode::Single) {
        if (const JsonValue* p = b.get("point")) {
            if (!p->isArray() || p->items.size() != 2 || !p->items[0].isNumber() || !p->items[1].isNumber())
                b.wrongType("point", "a [u, v] array of wall fractions");
            cam.scanPointU = p->items[0].number;
            cam.scanPointV = p->items[1].number;
            b.check(cam.scanPointU >= 0.0 && cam.scanPointU <= 1.0 && cam.scanPointV >= 0.0 && cam.scanPointV <= 1.0,
                    "point", "must be wall fractions in [0, 1] (u along edge_u, v along edge_v)");
        }
    } else if (b.has("point")) {
        b.fail("point", "point is the single scan's laser point; a " + std::string(scanModeName(cam.scan)) +
                            " scan aims at " + (cam.scan == ScanMode::Confocal ? "every sensor point" : "its grid") +
                            " (remove it, or use \"mode\": \"single\")");
    }
    if (cam.scan == ScanMode::Exhaustive) {
        const JsonValue* g = b.get("grid");
        if (!g) b.missing("grid", " (the exhaustive scan's laser grid, [Lx, Ly])");
        if (!g->isArray() || g->items.size() != 2) b.wrongType("grid", "a [Lx, Ly] array");
        cam.laserGridX = b.toInt(g->items[0], "grid", "grid", 1);
        cam.laserGridY = b.toInt(g->items[1], "grid", "grid", 1);
    } else if (b.has("grid")) {
        b.fail("grid", "grid is the exhaustive scan's laser grid; a " + std::string(scanModeName(cam.scan)) +
                           " scan has none (remove it, or use \"mode\": \"exhaustive\")");
    }
    b.finish();
}

CameraRefs readCamera(Context& ctx, const JsonValue& obj, CameraDesc& cam) {
    Bag b(ctx, obj, "camera", "the camera");
    cam.type =
        b.choice<CameraType>("type", {{"pinhole", CameraType::Pinhole}, {"relay_wall", CameraType::RelayWall}}, "type")
            .value_or(cam.type);
    const bool wall = cam.type == CameraType::RelayWall;
    cam.position = b.point("position", cam.position);
    CameraRefs refs;
    if (wall) {
        b.setWhat("a relay-wall sensor");
        for (const char* pinholeOnly : {"look_at", "up", "fov"})
            if (b.has(pinholeOnly))
                b.fail(pinholeOnly, std::string(pinholeOnly) +
                                        " is a pinhole camera's; a relay wall looks at its wall (remove it, or use "
                                        "\"type\": \"pinhole\")");
        if (!b.has("wall"))
            b.fail("wall", "a relay-wall sensor needs \"wall\": the name of the quad shape its grid lies on");
        refs.wall = b.string("wall").value_or("");
        if (const JsonValue* scan = objectAt(b, "scan")) readScan(ctx, *scan, cam, refs);
        cam.timeOrigin =
            b.choice<WallTimeOrigin>(
                 "time_origin", {{"sensor", WallTimeOrigin::Sensor}, {"wall", WallTimeOrigin::Wall}}, "time_origin")
                .value_or(cam.timeOrigin);
    } else {
        cam.lookAt = b.point("look_at", cam.lookAt);
        if (auto up = b.direction("up")) cam.up = *up;
        if (auto fov = b.number("fov")) {
            cam.fovYDeg = *fov;
            b.check(*fov > 0.0 && *fov < 180.0, "fov", "must be in (0, 180) degrees");
        }
    }
    if (const JsonValue* r = b.get("resolution")) {
        if (!r->isArray() || r->items.size() != 2) b.wrongType("resolution", "a [width, height] array");
        cam.width = b.toInt(r->items[0], "resolution", "resolution", 1);
        cam.height = b.toInt(r->items[1], "resolution", "resolution", 1);
        if (static_cast<int64_t>(cam.width) * cam.height > INT_MAX)
            b.fail("resolution", "resolution " + std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                                     " has more than " + std::to_string(INT_MAX) + " pixels");
    }
    b.finish();
    if (wall) return refs;
    const Vec3 view = cam.lookAt - cam.position;
    if (glm::length(view) == 0.0) b.fail("look_at", "look_at must differ from position");
    if (glm::length(glm::cross(glm::normalize(view), glm::normalize(cam.up))) < 1e-6)
        b.fail("up", "up must not be parallel to the viewing direction (look_at - position)");
    return refs;
}

void readFilm(Context& ctx, const JsonValue& obj, FilmDesc& film) {
    Bag b(ctx, obj, "film", "the film");
    if (auto bins = b.integer("bins", 1, INT_MAX)) film.bins = static_cast<int>(*bins);
    const auto range = b.choice<int>("range", {{"auto", 0}}, "range",
                                     " (or give start_m/start_ns and bin_width_m/bin_width_ns for a fixed range)");
    const std::optional<double> start = b.opl("start");
    const std::optional<double> width = b.opl("bin_width");
    if (range && (start || width)) {
        const std::string key = start ? (b.has("start_m") ? "start_m" : "start_ns")
                                      : (b.has("bin_width_m") ? "bin_width_m" : "bin_width_ns");
        b.fail(key, key + " cannot be combined with \"range\": \"auto\" (remove one of them)");
    }
    if (const JsonValue* v = b.get("phasor")) {
        if (v->isString()) {
            film.phasor = v->text;
        } else if (v->isArray() && !v->items.empty()) {
            for (const JsonValue& x : v->items) {
                if (!x.isNumber())
                    b.wrongType("phasor", "frequencies [f1, f2, ...] in cycles per m of OPL, or a string");
                if (!film.phasor.empty()) film.phasor += ',';
                film.phasor += shortest(x.number);
            }
        } else {
            b.wrongType("phasor",
                        "frequencies [f1, f2, ...] in cycles per m of OPL, or a string such as \"band:0.5:0.5\"");
        }
    }
    if (start || width) film.autoRange = false;
    if (start) film.startOpl = *start;
    if (width) {
        film.binWidthOpl = *width;
        const std::string key = b.has("bin_width_m") ? "bin_width_m" : "bin_width_ns";
        b.check(*width > 0.0, key, "must be > 0");
    }
    b.finish();
}

// Named objects ("media", "materials"): calls read(bag, name) for each, in file order.
template <class F>
void readNamed(Context& ctx, const JsonValue& obj, const std::string& section, const std::string& what, F read) {
    for (const JsonMember& m : obj.members) {
        if (isJsonCommentKey(m.key)) continue;
        const std::string path = section + "." + m.key;
        if (m.key.empty()) throw UserError(ctx.file, m.line, section, "a " + what + " name must not be empty");
        if (!m.value.isObject())
            throw UserError(ctx.file, m.value.line, path,
                            "expected an object { ... } describing the " + what + ", got " + m.value.typeName());
        ctx.desc.locs[path] = SourceLoc{ctx.file, m.line};
        Bag b(ctx, m.value, path, "a " + what);
        read(b, m.key);
        b.finish();
    }
}

void readMedium(Bag& b, MediumDesc& md) {
    if (auto s = b.color("sigma_s")) md.sigma_s = *s;
    b.check(nonNegative(md.sigma_s), "sigma_s", "must be >= 0");
    if (auto a = b.color("sigma_a")) md.sigma_a = *a;
    b.check(nonNegative(md.sigma_a), "sigma_a", "must be >= 0");
    md.ior = b.number("ior", md.ior);
    b.check(md.ior >= 1.0, "ior", "must be >= 1");
    md.g = b.number("g", md.g);
    b.check(md.g > -1.0 && md.g < 1.0, "g", "must be in (-1, 1)");
}

void readMaterial(Bag& b, MaterialDesc& mat) {
    const auto type = b.choice<MaterialType>("type",
                                             {{"diffuse", MaterialType::Diffuse},
                                              {"mirror", MaterialType::Mirror},
                                              {"dielectric", MaterialType::Dielectric},
                                              {"null", MaterialType::Null}},
                                             "material type");
    if (!type) b.missing("type", "; allowed: \"diffuse\", \"mirror\", \"dielectric\", \"null\"");
    mat.type = *type;
    switch (mat.type) {
        case MaterialType::Diffuse:
            b.setWhat("a diffuse material");
            if (auto a = b.color("albedo")) mat.albedo = *a;
            b.check(inUnit(mat.albedo), "albedo", "must be in [0, 1]");
            break;
        case MaterialType::Mirror:
            b.setWhat("a mirror material");
            if (auto r = b.color("reflectance")) mat.specular = *r;
            b.check(inUnit(mat.specular), "reflectance", "must be in [0, 1]");
            break;
        case MaterialType::Dielectric:
            b.setWhat("a dielectric material");
            mat.ior = b.number("ior", mat.ior);
            b.check(mat.ior >= 1.0, "ior", "must be >= 1");
            if (auto t = b.color("tint")) mat.specular = *t;
            b.check(inUnit(mat.specular), "tint", "must be in [0, 1]");
            break;
        case MaterialType::Null: b.setWhat("a null material"); break;
    }
}

// Index of the name under `key` in `names` (-1 when absent or null).
int readReference(Bag& b, std::string_view key, const std::map<std::string, int>& names, const std::string& what,
                  const std::string& plural) {
    const JsonValue* v = b.get(key);
    if (!v || v->isNull()) return -1;
    if (!v->isString()) b.wrongType(key, "the name of a " + what + " (a string)");
    const auto it = names.find(v->text);
    if (it != names.end()) return it->second;
    std::vector<std::string> defined, quoted;
    for (const auto& [name, index] : names) {
        defined.push_back(name);
        if (quoted.size() < 20) quoted.push_back("\"" + name + "\"");
    }
    if (defined.size() > quoted.size()) quoted.push_back("...");
    b.fail(key,
           "undefined " + what + " \"" + clipped(v->text) + "\"" + suggestion(v->text, defined) +
               (defined.empty() ? "; no " + plural + " are defined" : "; defined " + plural + ": " + join(quoted)));
}

// T * R * S, or a row-major matrix.
Mat4 readTransform(Context& ctx, const JsonValue& obj, const std::string& path) {
    Bag b(ctx, obj, path, "a transform");
    const std::optional<Vec3> translate = b.point("translate");
    Vec3 scale(1.0);
    if (const JsonValue* s = b.get("scale")) {
        if (!s->isNumber() && !(s->isArray() && s->items.size() == 3 && s->items[0].isNumber() &&
                                s->items[1].isNumber() && s->items[2].isNumber()))
            b.wrongType("scale", "a number or an [x, y, z] array");
        scale = s->isNumber() ? Vec3(s->number) : Vec3(s->items[0].number, s->items[1].number, s->items[2].number);
        b.check(scale.x > 0 && scale.y > 0 && scale.z > 0, "scale",
                "must be > 0 in every axis (mirroring is not supported; use flip_normals)");
        b.checkCoordinates("scale", {scale.x, scale.y, scale.z});
    }
    Mat4 rotation(1.0);
    if (const JsonValue* r = b.get("rotate")) {
        if (!r->isObject() && !r->isArray())
            b.wrongType("rotate", "{\"axis\": [x, y, z], \"angle_deg\": a} or a list of them");
        const bool list = r->isArray();
        const size_t n = list ? r->items.size() : 1;
        for (size_t i = 0; i < n; ++i) {
            const JsonValue& one = list ? r->items[i] : *r;
            std::string rpath = b.pathOf("rotate");
            if (list) rpath += "[" + std::to_string(i) + "]";
            if (!one.isObject())
                throw UserError(ctx.file, one.line, rpath,
                                "expected {\"axis\": [x, y, z], \"angle_deg\": a}, got " + std::string(one.typeName()));
            Bag rb(ctx, one, rpath, "a rotation");
            const std::optional<Vec3> axis = rb.direction("axis");
            const std::optional<double> angle = rb.number("angle_deg");
            if (!axis) rb.missing("axis");
            if (!angle) rb.missing("angle_deg");
            rb.finish();
            rotation = glm::rotate(Mat4(1.0), glm::radians(*angle), *axis) * rotation;
        }
    }
    const JsonValue* m = b.get("matrix");
    b.finish();
    if (m) {
        if (translate || b.has("scale") || b.has("rotate"))
            b.fail("matrix", "matrix cannot be combined with translate, scale or rotate");
        bool ok = m->isArray() && m->items.size() == 16;
        for (size_t i = 0; ok && i < 16; ++i) ok = m->items[i].isNumber();
        if (!ok) b.wrongType("matrix", "an array of 16 numbers (row-major)");
        for (size_t i = 0; i < 16; ++i) b.checkCoordinates("matrix", {m->items[i].number});
        Mat4 M(1.0);
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) M[c][r] = m->items[r * 4 + c].number;  // glm is column-major
        if (M[0][3] != 0.0 || M[1][3] != 0.0 || M[2][3] != 0.0 || M[3][3] != 1.0)
            b.fail("matrix", "matrix must be affine: its last row must be 0, 0, 0, 1");
        const double det = glm::determinant(glm::dmat3(M));
        if (!(det > 0.0) || !std::isfinite(det))
            b.fail("matrix",
                   "matrix must be invertible and must not mirror (the determinant of its 3x3 part "
                   "must be > 0; got " +
                       std::to_string(det) + ")");
        return M;
    }
    const Mat4 T = glm::translate(Mat4(1.0), translate.value_or(Vec3(0.0)));
    return T * rotation * glm::scale(Mat4(1.0), scale);
}

// The mesh file must be a readable regular file. A folder is the likeliest near miss (the mesh's
// folder instead of the file in it): say so, and name the OBJ files it holds.
void checkMeshPath(const Bag& b, const std::string& written, const std::string& resolved) {
    namespace fs = std::filesystem;
    const std::string resolvedNote =
        fs::path(written).is_relative() ? " (\"" + written + "\" resolved against the scene's folder)" : "";
    std::error_code ec;
    const fs::file_status st = fs::status(resolved, ec);
    if (fs::is_regular_file(st)) return;
    if (fs::is_directory(st)) {
        std::vector<std::string> objs;
        for (const fs::directory_entry& e : fs::directory_iterator(resolved, ec)) {
            std::string ext = e.path().extension().string();
            std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
            if (ext == ".obj") objs.push_back((fs::path(written) / e.path().filename()).generic_string());
        }
        std::sort(objs.begin(), objs.end());
        std::string hint = "; \"file\" must name the OBJ file itself";
        if (!objs.empty()) {
            hint += ", e.g. \"" + objs.front() + "\"";
            if (objs.size() > 1) hint += " (the folder holds " + std::to_string(objs.size()) + " .obj files)";
        } else {
            hint += " (the folder holds no .obj file)";
        }
        b.fail("file", "mesh file " + resolved + " is a folder, not a file" + resolvedNote + hint);
    }
    if (fs::exists(st))
        b.fail("file", "mesh file " + resolved + " is not a regular file (a device, socket or pipe)" + resolvedNote);
    b.fail("file", "mesh file not found: " + resolved + resolvedNote);
}

struct Names {
    std::map<std::string, int> media, materials;
};

void readShape(Context& ctx, const JsonValue& obj, const std::string& path, const Names& names, ShapeDesc& s) {
    Bag b(ctx, obj, path, "a shape");
    const auto type = b.choice<ShapeType>(
        "type",
        {{"mesh", ShapeType::Mesh}, {"sphere", ShapeType::Sphere}, {"quad", ShapeType::Quad}, {"box", ShapeType::Box}},
        "shape type");
    if (!type) b.missing("type", "; allowed: \"mesh\", \"sphere\", \"quad\", \"box\"");
    s.type = *type;
    s.name = b.string("name").value_or("");
    s.material = readReference(b, "material", names.materials, "material", "materials");
    const bool closed = s.type != ShapeType::Quad;
    if (closed) s.interiorMedium = readReference(b, "interior_medium", names.media, "medium", "media");
    switch (s.type) {
        case ShapeType::Mesh: {
            b.setWhat("a mesh");
            const JsonValue& f = b.require("file", " (the OBJ file of the mesh)");
            if (!f.isString()) b.wrongType("file", "a file name (a string)");
            std::filesystem::path p(f.text);
            if (p.is_relative()) p = std::filesystem::path(ctx.desc.dir) / p;
            s.meshPath = p.lexically_normal().string();
            checkMeshPath(b, f.text, s.meshPath);
            break;
        }
        case ShapeType::Sphere:
            b.setWhat("a sphere");
            s.center = b.point("center", s.center);
            s.radius = b.length("radius", s.radius);
            b.check(s.radius > 0.0, "radius", "must be > 0");
            break;
        case ShapeType::Quad:
            b.setWhat("a quad");
            s.corner = b.point("corner", s.corner);
            s.edgeU = b.point("edge_u", s.edgeU);
            s.edgeV = b.point("edge_v", s.edgeV);
            if (glm::length(glm::cross(s.edgeU, s.edgeV)) == 0.0)
                b.fail(b.has("edge_v") ? "edge_v" : "edge_u", "edge_u and edge_v must be non-zero and not parallel");
            break;
        case ShapeType::Box:
            b.setWhat("a box");
            s.boxMin = b.point("min", s.boxMin);
            s.boxMax = b.point("max", s.boxMax);
            if (!(s.boxMin.x < s.boxMax.x && s.boxMin.y < s.boxMax.y && s.boxMin.z < s.boxMax.z))
                b.fail(b.has("max") ? "max" : "min", "min must be < max in every axis");
            break;
    }
    if (s.type == ShapeType::Mesh || s.type == ShapeType::Box)
        if (const JsonValue* t = objectAt(b, "transform")) s.transform = readTransform(ctx, *t, b.pathOf("transform"));
    if (s.type == ShapeType::Box)  // (a mesh's vertices are checked after loading, core/scene/mesh.h)
        for (int i = 0; i < 8; ++i) {
            const Vec3 corner((i & 1) ? s.boxMax.x : s.boxMin.x, (i & 2) ? s.boxMax.y : s.boxMin.y,
                              (i & 4) ? s.boxMax.z : s.boxMin.z);
            const Vec3 world(s.transform * glm::dvec4(corner, 1.0));
            if (!(std::max({std::fabs(world.x), std::fabs(world.y), std::fabs(world.z)}) <= kMaxSceneCoordinateM))
                b.fail(b.has("transform") ? "transform" : "max",
                       "the transformed box reaches beyond +-" + shortNumber(kMaxSceneCoordinateM) +
                           " m, the limit of scene coordinates; use a smaller scale or translation");
        }
    if (s.type != ShapeType::Sphere) s.flipNormals = b.boolean("flip_normals").value_or(false);
    b.finish();
}

void readLight(Context& ctx, const JsonValue& obj, const std::string& path, LightDesc& l) {
    Bag b(ctx, obj, path, "a light");
    const auto type = b.choice<LightType>("type",
                                          {{"point", LightType::Point},
                                           {"spot", LightType::Spot},
                                           {"area", LightType::AreaQuad},
                                           {"laser", LightType::Laser}},
                                          "light type");
    if (!type) b.missing("type", "; allowed: \"point\", \"spot\", \"area\", \"laser\"");
    l.type = *type;
    l.name = b.string("name").value_or("");
    if (auto p = b.color("power")) l.power = *p;
    b.check(nonNegative(l.power), "power", "must be >= 0");
    // The film sums radiance in 32-bit floats (at most 3.4e38) over up to millions of passes, and
    // a small kernel concentrates a photon's power by many decades: 1e20 W leaves room for both.
    b.check(maxComponent(l.power) <= 1e20, "power",
            "must be <= 1e20 W: the film accumulates in 32-bit floats (max 3.4e38), which a larger power can "
            "overflow; transport is linear, so express the powers in a smaller unit (scaling every light by s "
            "scales the whole film by s)");
    l.emitOpl = b.opl("emit_time").value_or(l.emitOpl);
    switch (l.type) {
        case LightType::Point:
            b.setWhat("a point light");
            l.position = b.point("position", l.position);
            break;
        case LightType::Spot: {
            b.setWhat("a spot light");
            l.position = b.point("position", l.position);
            l.direction = b.direction("direction").value_or(l.direction);
            l.spotCutoffDeg = b.number("cutoff_deg", l.spotCutoffDeg);
            b.check(l.spotCutoffDeg > 0.0 && l.spotCutoffDeg <= 180.0, "cutoff_deg", "must be in (0, 180]");
            const std::optional<double> falloff = b.number("falloff_deg");
            l.spotFalloffDeg = falloff.value_or(std::min(l.spotFalloffDeg, l.spotCutoffDeg));
            b.check(l.spotFalloffDeg >= 0.0 && l.spotFalloffDeg <= l.spotCutoffDeg, "falloff_deg",
                    "must be in [0, cutoff_deg]");
            break;
        }
        case LightType::AreaQuad:
            b.setWhat("an area light");
            l.corner = b.point("corner", l.corner);
            l.edgeU = b.point("edge_u", l.edgeU);
            l.edgeV = b.point("edge_v", l.edgeV);
            if (glm::length(glm::cross(l.edgeU, l.edgeV)) == 0.0)
                b.fail(b.has("edge_v") ? "edge_v" : "edge_u", "edge_u and edge_v must be non-zero and not parallel");
            break;
        case LightType::Laser:
            b.setWhat("a laser");
            l.position = b.point("position", l.position);
            l.direction = b.direction("direction").value_or(l.direction);
            l.laserRadius = b.length("radius", l.laserRadius);
            b.check(l.laserRadius >= 0.0, "radius", "must be >= 0");
            break;
    }
    b.finish();
}

// Types only here; the ranges are RenderSettings::validate()'s (integrators/render_settings.h),
// the one check of the render settings, which prepareRender calls with this file's locations.
void readRender(Context& ctx, const JsonValue& obj, RenderDesc& r) {
    Bag b(ctx, obj, "render", "render settings");
    r.photonsPerPass = b.integer("photons_per_pass", INT64_MIN, INT64_MAX).value_or(r.photonsPerPass);
    r.warmup = static_cast<int>(b.integer("warmup", INT_MIN, INT_MAX).value_or(r.warmup));

    // Both radii share RenderDesc::radiusRelative.
    // "radius": "auto": from the photon density of a pilot pass (render/auto_radius.h).
    bool autoWritten = false;
    if (const JsonValue* v = b.get("radius"); v && v->isString()) {
        if (v->text != "auto")
            b.fail("radius", "radius must be a length in m or \"auto\" (from a pilot pass's photon density), got \"" +
                                 v->text + "\"");
        autoWritten = r.radiusAuto = true;
    }
    const std::optional<double> abs = autoWritten ? std::nullopt : b.number("radius"),
                                rel = b.number("radius_relative");
    if (autoWritten && rel)
        b.fail("radius_relative", "give either radius (m or \"auto\") or radius_relative, not both");
    const std::optional<double> sAbs = b.number("surface_radius"), sRel = b.number("surface_radius_relative");
    if (abs && rel) b.fail("radius_relative", "give either radius (m) or radius_relative, not both");
    if (sAbs && sRel)
        b.fail("surface_radius_relative", "give either surface_radius (m) or surface_radius_relative, not both");
    if ((abs && sRel) || (rel && sAbs))
        b.fail(sAbs ? "surface_radius" : "surface_radius_relative",
               "the volume and surface radii must both be absolute (radius, surface_radius) or both relative "
               "(radius_relative, surface_radius_relative)");
    if (abs || rel) r.radiusAuto = false;  // a written radius; none (or "auto"): from the pilot
    if (abs || sAbs) r.radiusRelative = false;
    if (rel || sRel) r.radiusRelative = true;
    if (auto v = abs ? abs : rel) r.radius = *v;
    if (auto v = sAbs ? sAbs : sRel) r.surfaceRadius = *v;
    if (abs && r.radius > 0.0) b.checkCoordinates("radius", {r.radius});
    if (sAbs && r.surfaceRadius > 0.0) b.checkCoordinates("surface_radius", {r.surfaceRadius});

    r.alpha = b.number("alpha", r.alpha);
    r.passes = static_cast<int>(b.integer("passes", INT_MIN, INT_MAX).value_or(r.passes));
    r.timeBudgetSec = b.number("time_budget_s", r.timeBudgetSec);
    r.maxDepth = static_cast<int>(b.integer("max_depth", INT_MIN, INT_MAX).value_or(r.maxDepth));
    if (const JsonValue* v = b.get("bounces")) {
        // n (exactly n events) or [min, max].
        if (v->isNumber()) {
            r.bounceMin = r.bounceMax = b.toInt(*v, "bounces", "bounces", 0);
        } else {
            if (!v->isArray() || v->items.size() != 2) b.wrongType("bounces", "an integer n or a [min, max] array");
            r.bounceMin = b.toInt(v->items[0], "bounces", "bounces", 0);
            r.bounceMax = b.toInt(v->items[1], "bounces", "bounces", 0);
            b.check(r.bounceMin <= r.bounceMax, "bounces", "must be [min, max] with min <= max");
        }
    }
    if (const JsonValue* s = b.get("seed")) {
        if (!s->isNumber()) b.wrongType("seed", "an integer");
        uint64_t seed = 0;
        const auto [ptr, ec] = std::from_chars(s->text.data(), s->text.data() + s->text.size(), seed);
        const bool exact = isPlainInteger(s->text) && ec == std::errc() && ptr == s->text.data() + s->text.size();
        if (!exact) {
            const double d = s->number;
            if (d != std::floor(d)) b.fail("seed", "seed must be an integer (got " + s->text + ")");
            b.check(d >= 0.0, "seed", "must be >= 0");
            b.check(d < 18446744073709551616.0, "seed", "must be < 2^64");
            seed = static_cast<uint64_t>(d);
        }
        r.seed = seed;
    }
    r.threads = static_cast<int>(b.integer("threads", INT_MIN, INT_MAX).value_or(r.threads));
    r.emission =
        b.choice<EmissionMode>("emission", {{"delta", EmissionMode::Delta}, {"continuous", EmissionMode::Continuous}},
                               "emission")
            .value_or(r.emission);
    r.unwarp = b.boolean("unwarp").value_or(r.unwarp);
    r.timeProfile =
        b.choice<TimeProfile>("time_profile", {{"exact", TimeProfile::Exact}, {"uniform", TimeProfile::Uniform}},
                              "time_profile")
            .value_or(r.timeProfile);
    r.beamLength =
        b.choice<BeamLength>("beam_length", {{"short", BeamLength::Short}, {"long", BeamLength::Long}}, "beam_length")
            .value_or(r.beamLength);
    // The estimators: names checked by validate() (the allowed values in its message).
    r.volumeEstimator = b.string("volume_estimator").value_or(r.volumeEstimator);
    r.surfaceEstimator = b.string("surface_estimator").value_or(r.surfaceEstimator);
    // "time_kernel": "none" | "box" | {"type": "box", "width": m of OPL}.
    if (const JsonValue* tk = b.get("time_kernel")) {
        const auto kind = [&](const std::string& name, const std::function<void(const std::string&)>& bad) {
            if (name == "none") return TimeKernelKind::None;
            if (name == "box") return TimeKernelKind::Box;
            bad("unknown time kernel \"" + name + "\"; allowed: none, box (or {\"type\": \"box\", \"width\": m})");
            return TimeKernelKind::None;
        };
        if (tk->isString()) {
            r.timeKernel = {kind(tk->text, [&](const std::string& m) { b.fail("time_kernel", m); }), 0.0};
        } else if (tk->isObject()) {
            Bag k(ctx, *tk, b.pathOf("time_kernel"), "time kernel");
            const std::string type = k.string("type").value_or("box");
            r.timeKernel.kind = kind(type, [&](const std::string& m) { k.fail("type", m); });
            if (const std::optional<double> w = k.number("width")) {
                k.check(*w > 0.0 && std::isfinite(*w), "width",
                        "must be > 0 (m of optical path; leave it out to "
                        "let the renderer choose it from the scene)");
                k.checkCoordinates("width", {*w});
                r.timeKernel.width = *w;
            }
            k.finish();
        } else {
            b.wrongType("time_kernel", "\"none\", \"box\" or an object {\"type\": \"box\", \"width\": m}");
        }
    }
    b.finish();
}

// Each element of the array under `key` must be an object; calls read(element, "key[i]").
template <class F>
void readList(Context& ctx, Bag& root, std::string_view key, F read) {
    const JsonValue* v = root.get(key);
    if (!v) return;
    if (!v->isArray()) root.wrongType(key, "an array [ ... ]");
    for (size_t i = 0; i < v->items.size(); ++i) {
        const JsonValue& e = v->items[i];
        const std::string path = std::string(key) + "[" + std::to_string(i) + "]";
        if (!e.isObject())
            throw UserError(ctx.file, e.line, path, "expected an object { ... }, got " + std::string(e.typeName()));
        read(e, path);
    }
}

void warn(SceneDesc& desc, const std::string& keyPath, const std::string& message) {
    desc.warnings.push_back(desc.where(keyPath) + message);
}

}  // namespace

// ---- public API ----------------------------------------------------------------------------------

SceneDesc loadSceneFromString(const std::string& text, const std::string& virtualPath) {
    SceneDesc desc;
    desc.path = virtualPath;
    desc.dir = std::filesystem::path(virtualPath).parent_path().string();
    if (desc.dir.empty()) desc.dir = ".";
    Context ctx{virtualPath, desc};

    const JsonValue root = parseJson(text, virtualPath);
    if (!root.isObject())
        throw UserError(virtualPath, root.line, "",
                        "a scene must be a JSON object { ... }, got " + std::string(root.typeName()));
    Bag b(ctx, root, "", "the scene");

    // Version.
    if (const JsonValue* v = b.get("version")) {
        if (!v->isNumber()) b.wrongType("version", "the number 1");
        if (v->number != 1.0) b.fail("version", "unsupported version " + v->text + "; this tpb reads version 1");
        desc.version = 1;
    } else {
        warn(desc, "version", "\"version\" is missing; version 1 is assumed (add \"version\": 1)");
    }

    CameraRefs refs;
    if (const JsonValue* c = objectAt(b, "camera")) refs = readCamera(ctx, *c, desc.camera);
    if (const JsonValue* f = objectAt(b, "film")) readFilm(ctx, *f, desc.film);

    // The film must fit in memory.
    if (desc.camera.width * desc.camera.filmHeight() > INT_MAX) {
        const SourceLoc loc =
            desc.locs.count("camera.scan.grid") ? desc.locs["camera.scan.grid"] : SourceLoc{virtualPath, 0};
        throw UserError(loc.file, loc.line, "camera.scan.grid",
                        "the exhaustive scan's film has " +
                            std::to_string(desc.camera.width * desc.camera.filmHeight()) + " pixels (" +
                            std::to_string(desc.camera.laserPoints()) + " laser points of " +
                            std::to_string(desc.camera.width) + " x " + std::to_string(desc.camera.height) +
                            "), more than " + std::to_string(INT_MAX) + "; lower the grid or the resolution");
    }
    const uint64_t need = filmBytes(desc.camera.width, static_cast<int>(desc.camera.filmHeight()), desc.film.bins),
                   limit = maxFilmBytes();
    if (need > limit) {
        const std::string key = desc.locs.count("film.bins")           ? "film.bins"
                                : desc.locs.count("camera.resolution") ? "camera.resolution"
                                                                       : "";
        const SourceLoc loc = key.empty() ? SourceLoc{virtualPath, 0} : desc.locs[key];
        throw UserError(
            loc.file, loc.line, key,
            "the film needs " + std::to_string(need) + " bytes (" + humanBytes(need) + ") for " +
                std::to_string(desc.camera.width) + " x " + std::to_string(desc.camera.filmHeight()) + " pixels x " +
                std::to_string(desc.film.bins) + " bins" +
                (desc.camera.scan == ScanMode::Exhaustive
                     ? " (" + std::to_string(desc.camera.laserPoints()) + " laser points of " +
                           std::to_string(desc.camera.width) + " x " + std::to_string(desc.camera.height) + ")"
                     : "") +
                ", more than the limit of " + std::to_string(limit) + " bytes (" + humanBytes(limit) +
                ", 75% of physical memory unless TPB_MAX_FILM_BYTES is set); lower film.bins or "
                "camera.resolution");
    }

    // Media and materials, then everything that refers to them by name.
    Names names;
    if (const JsonValue* m = objectAt(b, "media")) {
        readNamed(ctx, *m, "media", "medium", [&](Bag& mb, const std::string& name) {
            MediumDesc md;
            md.name = name;
            readMedium(mb, md);
            names.media[name] = static_cast<int>(desc.media.size());
            desc.media.push_back(md);
        });
    }
    if (const JsonValue* m = objectAt(b, "materials")) {
        readNamed(ctx, *m, "materials", "material", [&](Bag& mb, const std::string& name) {
            MaterialDesc mat;
            mat.name = name;
            readMaterial(mb, mat);
            names.materials[name] = static_cast<int>(desc.materials.size());
            desc.materials.push_back(mat);
        });
    }
    desc.globalMedium = readReference(b, "global_medium", names.media, "medium", "media");

    readList(ctx, b, "shapes", [&](const JsonValue& e, const std::string& path) {
        ShapeDesc s;
        readShape(ctx, e, path, names, s);
        desc.shapes.push_back(s);
        if (s.interiorMedium >= 0 && (s.material < 0 || (desc.materials[s.material].type != MaterialType::Dielectric &&
                                                         desc.materials[s.material].type != MaterialType::Null)))
            warn(desc, path + ".interior_medium",
                 "interior_medium has no effect: the shape's material is not \"dielectric\" or \"null\"");
    });
    // A relay wall's grid lies on a quad shape, named.
    if (desc.camera.type == CameraType::RelayWall) {
        for (size_t i = 0; i < desc.shapes.size(); ++i)
            if (desc.shapes[i].name == refs.wall) desc.camera.wallShape = static_cast<int>(i);
        const SourceLoc at = desc.locs.count("camera.wall") ? desc.locs["camera.wall"] : SourceLoc{virtualPath, 0};
        if (desc.camera.wallShape < 0)
            throw UserError(at.file, at.line, "camera.wall",
                            "no shape is named \"" + refs.wall + "\" (give the relay wall's quad a \"name\")");
        if (desc.shapes[static_cast<size_t>(desc.camera.wallShape)].type != ShapeType::Quad)
            throw UserError(at.file, at.line, "camera.wall",
                            "the relay wall \"" + refs.wall +
                                "\" must be a quad (its grid is the quad's corner + "
                                "edge_u, edge_v)");
    }
    readList(ctx, b, "lights", [&](const JsonValue& e, const std::string& path) {
        LightDesc l;
        readLight(ctx, e, path, l);
        desc.lights.push_back(l);
    });
    // A scan's laser is a laser light, named.
    if (desc.camera.scan != ScanMode::None) {
        for (size_t i = 0; i < desc.lights.size(); ++i)
            if (desc.lights[i].name == refs.laser) desc.camera.scanLaser = static_cast<int>(i);
        const SourceLoc at =
            desc.locs.count("camera.scan.laser") ? desc.locs["camera.scan.laser"] : SourceLoc{virtualPath, 0};
        if (desc.camera.scanLaser < 0)
            throw UserError(at.file, at.line, "camera.scan.laser",
                            "no light is named \"" + refs.laser + "\" (give the scanning laser a \"name\")");
        if (desc.lights[static_cast<size_t>(desc.camera.scanLaser)].type != LightType::Laser)
            throw UserError(at.file, at.line, "camera.scan.laser",
                            "the scan's light \"" + refs.laser + "\" is a " +
                                lightTypeName(desc.lights[static_cast<size_t>(desc.camera.scanLaser)].type) +
                                " light; a scan needs a \"laser\" (a collimated beam)");
    }
    if (const JsonValue* r = objectAt(b, "render")) readRender(ctx, *r, desc.render);
    b.finish();

    if (desc.lights.empty()) warn(desc, "lights", "the scene has no lights: the image will be black");
    if (desc.render.passes == 0 && desc.render.timeBudgetSec == 0.0)
        warn(desc, "render.passes",
             "render.passes is 0 and render.time_budget_s is 0: the render only stops when interrupted");
    return desc;
}

std::string readSceneFile(const std::string& path, const std::string& what) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);  // follows symlinks: a link to a file is fine
    if (fs::is_directory(st)) throw UserError(path, 0, "", "cannot open " + what + " (it is a directory)");
    if (fs::exists(st) && !fs::is_regular_file(st))
        throw UserError(path, 0, "",
                        "cannot read " + what + ": it is not a regular file but a " +
                            (fs::is_character_file(st) || fs::is_block_file(st) ? "device"
                             : fs::is_fifo(st)                                  ? "FIFO (pipe)"
                             : fs::is_socket(st)                                ? "socket"
                                                                                : "special file") +
                            ", which could be read forever; save the scene to a file and give its path");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path, 0, "", "cannot open " + what + " (" + std::strerror(errno) + ")");
    const uint64_t bytes = fs::file_size(path, ec);
    if (ec) throw UserError(path, 0, "", "cannot read " + what + " (" + ec.message() + ")");
    if (bytes > kMaxSceneFileBytes)
        throw UserError(path, 0, "",
                        what + " is " + humanBytes(bytes) + " (" + std::to_string(bytes) + " bytes), more than the " +
                            humanBytes(kMaxSceneFileBytes) +
                            " a scene file may take; is it the right file? Large meshes belong in "
                            "OBJ/PLY files the scene names");
    // Exactly the size it had when asked: a file that grows while being read is not followed.
    std::string text(static_cast<size_t>(bytes), '\0');
    in.read(text.data(), static_cast<std::streamsize>(bytes));
    if (in.bad() || static_cast<uint64_t>(in.gcount()) != bytes)
        throw UserError(path, 0, "",
                        "cannot read " + what + " (read " + std::to_string(in.gcount()) + " of " +
                            std::to_string(bytes) + " bytes: did it change while being read?)");
    return text;
}

SceneDesc loadScene(const std::string& path) {
    // Mitsuba 3 XML (scene/mitsuba_loader.h) by its extension or its content; anything else is a
    // JSON scene.
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".xml") return loadMitsubaScene(path);
    // A Mitsuba XML scene under another extension (scene.txt): XML by its content, '<' first.
    const std::string text = readSceneFile(path);
    const size_t first = text.find_first_not_of(" \t\r\n");
    if (first != std::string::npos && text[first] == '<') return loadMitsubaScene(path);
    return loadSceneFromString(text, path);
}

}  // namespace tpb
