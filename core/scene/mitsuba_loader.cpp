// Mitsuba 3 XML -> SceneDesc. Parse (pugixml, with byte offsets turned into line numbers), expand
// <include> and <default>/$param, then walk the scene: every plugin is read through a property
// bag (Props) that remembers what was asked for; a parameter nobody asked for is a warning.
//
// Mappings (docs/user/scenes.md "Mitsuba 3 XML" has the full table):
//   sensor perspective -> camera (fov converted to tpb's vertical fov; lookat or matrix to_world);
//   film hdrfilm -> resolution (automatic time range), transient_hdr_film -> resolution + bins,
//   start_opl, bin_width_opl; the sensor's medium -> global_medium;
//   shapes obj/ply -> mesh, sphere -> sphere, rectangle -> quad ([-1,1]^2, z = 0, normal +z),
//   cube -> box ([-1,1]^3), disk -> a 128-segment triangle fan (radius 1, z = 0, normal +z);
//   bsdfs diffuse, conductor/roughconductor -> mirror (warned), dielectric/roughdielectric ->
//   dielectric (rough: warned), thindielectric -> null (warned), twosided -> its inner bsdf, null;
//   homogeneous media (sigma_t + albedo or sigma_a + sigma_s, scale; isotropic / hg phase);
//   emitters point (flux = 4 pi I), spot (flux = I * int of tpb's profile), area on a rectangle
//   (flux = pi L A); integrator max_depth -> render.max_depth = max_depth - 1 (Mitsuba counts the
//   segments, tpb the scattering vertices), tpb_* parameters of the integrator -> render.*;
//   mitransient's NLOS setup: a rectangle holding an nlos_capture_meter -> a relay-wall camera on
//   it (sensor_origin, transient_nlos_path's account_first_and_last_bounces and capture_type), a
//   projector -> a laser (flux = pi E scale A, A its image at z = 1), the scan's laser.
#include "scene/mitsuba_loader.h"

#include "base/error.h"
#include "base/text.h"
#include "base/memory.h"
#include "film/film_bytes.h"
#include "scene/light.h"
#include "scene/scene_loader.h"

#include <pugixml.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <sstream>

namespace tpb {

namespace fs = std::filesystem;

bool mitsubaNamedIor(const std::string& name, double& ior) {
    // Mitsuba's table of named indices of refraction (src/core/... "ior.h" in Mitsuba 3).
    static const std::pair<const char*, double> kIors[] = {
        {"vacuum", 1.0},      {"helium", 1.00004},         {"hydrogen", 1.00013},
        {"air", 1.00028},     {"carbon dioxide", 1.00045}, {"water", 1.3330},
        {"acetone", 1.36},    {"ethanol", 1.361},          {"carbon tetrachloride", 1.461},
        {"glycerol", 1.4729}, {"benzene", 1.501},          {"silicone oil", 1.52045},
        {"bromine", 1.661},   {"water ice", 1.31},         {"fused quartz", 1.458},
        {"pyrex", 1.470},     {"acrylic glass", 1.49},     {"polypropylene", 1.49},
        {"bk7", 1.5046},      {"sodium chloride", 1.544},  {"amber", 1.55},
        {"pet", 1.5750},      {"diamond", 2.419}};
    for (const auto& [n, v] : kIors)
        if (name == n) {
            ior = v;
            return true;
        }
    return false;
}

namespace {

constexpr int kDiskSegments = 128;
constexpr double kAirTolerance = 1e-3;  // ext_ior within this of 1 (air: 1.00028) is taken as 1
constexpr int kXmlMaxDepth = 256;       // element nesting (Importer::checkNesting)
// Widest projector imported as a laser (full angle, degrees): tal writes 0.2 (2 without laser sampling).
constexpr double kMaxProjectorFovDeg = 5.0;

struct XmlFile {
    std::string path, dir, text;
    std::vector<size_t> lineStarts;
    pugi::xml_document doc;
    int lineOf(ptrdiff_t offset) const {
        if (offset < 0) return 0;
        return static_cast<int>(std::upper_bound(lineStarts.begin(), lineStarts.end(), size_t(offset)) -
                                lineStarts.begin());
    }
};

struct Elem {
    pugi::xml_node node;
    const XmlFile* file = nullptr;
    std::string tag() const { return node.name(); }
    int line() const { return file->lineOf(node.offset_debug()); }
};

// "<shape type="sphere" id="ball">": the element as written (attributes before substitution).
std::string label(const Elem& e) {
    std::string s = "<";
    s.append(e.node.name());
    for (const char* a : {"type", "name", "id"})
        if (const pugi::xml_attribute at = e.node.attribute(a))
            s.append(" ").append(a).append("=\"").append(at.value()).append("\"");
    return s.append(">");
}

std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

const std::set<std::string> kPropertyTags = {"float",    "integer", "boolean", "string",    "rgb",
                                             "spectrum", "point",   "vector",  "transform", "texture"};
const std::set<std::string> kObjectTags = {"bsdf",    "medium", "phase",  "emitter",    "film", "sampler",
                                           "rfilter", "shape",  "sensor", "integrator", "ref"};

class Importer;

// The parameters of one plugin element, by name; the nested plugins (and anonymous refs) in order.
class Props {
public:
    Props(Importer& im, const Elem& owner);
    const Elem& owner() const { return owner_; }
    std::string type() const;

    const Elem* find(const std::string& name) {
        asked_.insert(name);
        const auto it = byName_.find(name);
        return it == byName_.end() ? nullptr : &it->second;
    }
    std::optional<double> number(const std::string& name);
    std::optional<int64_t> integer(const std::string& name);
    std::optional<bool> boolean(const std::string& name);
    std::optional<std::string> string(const std::string& name);
    std::optional<Color> color(const std::string& name);
    std::optional<Vec3> point(const std::string& name);
    std::optional<Mat4> transform(const std::string& name);
    // A parameter tpb reads but that has no effect: a warning when it is written.
    void noEffect(const std::string& name, const std::string& why);
    // Nested plugins (bsdf, medium, ...) and anonymous <ref id=...> elements.
    std::vector<Elem>& objects() { return objects_; }
    // Unused parameters and nested plugins nobody took: warnings.
    void finish();
    void took(const Elem& child) { taken_.insert(child.node.internal_object()); }

private:
    Importer& im_;
    Elem owner_;
    std::map<std::string, Elem> byName_;
    std::vector<Elem> objects_;
    std::set<std::string> asked_;
    std::set<const void*> taken_;
};

class Importer {
public:
    Importer(SceneDesc& d, const MitsubaOptions& o) : d_(d), params_(o.params) {}
    void run(const std::string& text, const std::string& path);

    [[noreturn]] void fail(const Elem& e, const std::string& message) const {
        throw UserError(e.file->path, e.line(), label(e), message);
    }
    void warn(const Elem& e, const std::string& message) {
        d_.warnings.push_back(e.file->path + ":" + std::to_string(e.line()) + ": " + label(e) + ": " + message);
    }
    void loc(const std::string& key, const Elem& e) { d_.locs[key] = SourceLoc{e.file->path, e.line()}; }
    // An attribute after $param substitution; empty optional when absent.
    std::optional<std::string> attr(const Elem& e, const char* name) const;
    std::string required(const Elem& e, const char* name) const {
        const std::optional<std::string> v = attr(e, name);
        if (!v) fail(e, std::string("the attribute \"") + name + "\" is missing");
        return *v;
    }
    std::vector<double> numbers(const Elem& e, const std::string& text, const char* what) const;
    double number(const Elem& e, const std::string& text, const char* what) const {
        const std::vector<double> v = numbers(e, text, what);
        if (v.size() != 1) fail(e, std::string(what) + " must be one number, got \"" + text + "\"");
        return v[0];
    }
    // The element an id names (any tag), or an error listing the ids defined.
    const Elem& lookup(const Elem& ref, const std::string& id) const;

private:
    friend class Props;
    const XmlFile& parse(const std::string& text, const std::string& path);
    void checkNesting(const XmlFile& f) const;
    void collect(const Elem& scene, std::vector<Elem>& out, std::vector<std::string>& stack);
    void registerIds(const Elem& e);

    void readSensor(const Elem& e);
    void readSampler(Props& p, const Elem& o);
    void readFilm(const Elem& e, bool nlos = false);
    void readCaptureMeter(const Elem& sensor, const Elem& shape, const std::string& shapeType);
    void finishNlos();
    void readIntegrator(const Elem& e);
    void readShape(const Elem& e);
    void readEmitter(const Elem& e, const Elem* shape, const Mat4* shapeToWorld, bool flip);
    int material(const Elem& e);
    MaterialDesc readBsdf(const Elem& e, bool wrapped);
    int medium(const Elem& e);
    int mediumParam(Props& p, const std::string& name);
    void checkPoint(const Elem& e, const Vec3& p, const char* what) const {
        if (!(std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) <= kMaxSceneCoordinateM))
            fail(e, std::string(what) +
                        " lies beyond +-1e9 m (the limit of scene coordinates); check the units and the exponent");
    }

    SceneDesc& d_;
    std::map<std::string, std::string> params_;
    std::deque<XmlFile> files_;
    std::map<std::string, Elem> ids_;
    std::map<const void*, int> materials_, media_;
    int defaultDiffuse_ = -1, defaultNull_ = -1;
    bool haveSensor_ = false, haveIntegrator_ = false;
    bool captureMeterAhead_ = false;  // a shape holds an nlos_capture_meter: it is the sensor
    std::vector<Elem> lightElems_;    // the element of each light, by index
    // mitransient's NLOS setup: the relay wall's nlos_capture_meter, read when its shape is, and
    // the transient_nlos_path integrator's settings; resolved into the camera by finishNlos().
    struct Nlos {
        bool present = false;
        Elem sensor, shape, film;
        int wall = -1;
        std::optional<Elem> origin, lookatPixel, lookat3d, laserOrigin, original, laserScan;
        Vec3 lookatPixelV{0.0}, lookat3dV{0.0}, laserOriginV{0.0};
        int originalW = 0, originalH = 0;  // original_film_width/height: one confocal point per render
        bool exhaustiveFilm = false;
        int laserScanW = 0, laserScanH = 0;
    } nlos_;
    struct NlosIntegrator {
        std::string type;
        std::optional<ScanMode> capture;
        std::optional<bool> account;
        bool forceEqual = true;
        std::optional<Elem> captureElem, accountElem, forceEqualElem;
    } nlosInt_;
    struct Projector {
        int light = -1;
        Elem e;
        std::optional<Elem> toWorld;
        bool translationOnly = true;  // no to_world, or a translation: tal's laser, aimed from Python
    };
    std::vector<Projector> projectors_;
    std::vector<std::pair<Elem, int>> exteriorChecks_;  // (element, medium) to compare with the global medium
};

// ---- Props ---------------------------------------------------------------------------------------

Props::Props(Importer& im, const Elem& owner) : im_(im), owner_(owner) {
    for (pugi::xml_node c = owner.node.first_child(); c; c = c.next_sibling()) {
        if (c.type() != pugi::node_element) continue;
        const Elem ce{c, owner.file};
        const std::string tag = ce.tag();
        const std::optional<std::string> name = im.attr(ce, "name");
        if (kPropertyTags.count(tag) || (tag == "ref" && name)) {
            if (!name) im.fail(ce, "a parameter needs a name=\"...\" attribute");
            if (!byName_.emplace(*name, ce).second) im.fail(ce, "the parameter \"" + *name + "\" is given twice");
        } else if (kObjectTags.count(tag)) {
            if (name && tag != "medium" && tag != "bsdf" && tag != "emitter")
                im.fail(ce, "unexpected name=\"" + *name + "\"");
            if (name && tag == "medium")
                byName_.emplace(*name, ce);
            else
                objects_.push_back(ce);
        } else {
            im.fail(ce,
                    "unknown element <" + tag +
                        ">; parameters are <float>, <integer>, <boolean>, <string>, <rgb>, "
                        "<spectrum>, <point>, <vector>, <transform>, <ref>, nested plugins <bsdf>, <medium>, <phase>, "
                        "<emitter>, <film>, <sampler>, <rfilter>");
        }
    }
}

std::string Props::type() const { return im_.attr(owner_, "type").value_or(""); }

std::optional<double> Props::number(const std::string& name) {
    const Elem* e = find(name);
    if (!e) return std::nullopt;
    if (e->tag() != "float" && e->tag() != "integer") im_.fail(*e, "\"" + name + "\" must be a <float>");
    const double v = im_.number(*e, im_.required(*e, "value"), "value");
    if (!std::isfinite(v)) im_.fail(*e, "\"" + name + "\" must be a finite number");
    return v;
}

std::optional<int64_t> Props::integer(const std::string& name) {
    const Elem* e = find(name);
    if (!e) return std::nullopt;
    if (e->tag() != "integer") im_.fail(*e, "\"" + name + "\" must be an <integer>");
    const std::string v = trim(im_.required(*e, "value"));
    int64_t n = 0;
    const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (ec != std::errc() || ptr != v.data() + v.size() || v.empty()) im_.fail(*e, "\"" + v + "\" is not an integer");
    return n;
}

std::optional<bool> Props::boolean(const std::string& name) {
    const Elem* e = find(name);
    if (!e) return std::nullopt;
    if (e->tag() != "boolean") im_.fail(*e, "\"" + name + "\" must be a <boolean>");
    const std::string v = lower(trim(im_.required(*e, "value")));
    if (v != "true" && v != "false") im_.fail(*e, "a boolean is \"true\" or \"false\", got \"" + v + "\"");
    return v == "true";
}

std::optional<std::string> Props::string(const std::string& name) {
    const Elem* e = find(name);
    if (!e) return std::nullopt;
    if (e->tag() != "string") im_.fail(*e, "\"" + name + "\" must be a <string>");
    return im_.required(*e, "value");
}

std::optional<Color> Props::color(const std::string& name) {
    const Elem* e = find(name);
    if (!e) return std::nullopt;
    const std::string tag = e->tag();
    if (tag == "texture" || tag == "ref")
        im_.fail(*e, "textures are not supported (tpb's materials and lights are uniform); give <rgb name=\"" + name +
                         "\" value=\"r, g, b\"/> or <float>");
    if (tag == "float") return Color(*number(name));
    if (tag == "rgb") {
        const std::vector<double> v = im_.numbers(*e, im_.required(*e, "value"), "value");
        if (v.size() == 1) return Color(v[0]);
        if (v.size() != 3) im_.fail(*e, "an <rgb> value is 1 or 3 numbers");
        return Color(v[0], v[1], v[2]);
    }
    if (tag == "spectrum") {
        if (im_.attr(*e, "filename") || im_.attr(*e, "type") || e->node.first_child())
            im_.fail(*e, "a spectrum from a file or a spectrum plugin is not supported (tpb renders RGB); give <rgb>");
        const std::string text = im_.required(*e, "value");
        if (text.find(':') == std::string::npos) return Color(im_.number(*e, text, "value"));
        // "wavelength:value, ...": representable only when constant.
        std::string flat = text;
        std::replace(flat.begin(), flat.end(), ':', ' ');
        const std::vector<double> v = im_.numbers(*e, flat, "value");
        if (v.size() < 2 || v.size() % 2) im_.fail(*e, "a spectrum is \"wavelength:value, ...\" pairs");
        for (size_t i = 3; i < v.size(); i += 2)
            if (v[i] != v[1])
                im_.fail(*e,
                         "a wavelength-dependent spectrum cannot be represented (tpb renders RGB); give "
                         "<rgb name=\"" +
                             name + "\" value=\"r, g, b\"/>");
        return Color(v[1]);
    }
    im_.fail(*e, "\"" + name + "\" must be a colour: <rgb>, <spectrum value=...> or <float>");
}

std::optional<Vec3> Props::point(const std::string& name) {
    const Elem* e = find(name);
    if (!e) return std::nullopt;
    if (e->tag() != "point" && e->tag() != "vector") im_.fail(*e, "\"" + name + "\" must be a <point>");
    if (const std::optional<std::string> v = im_.attr(*e, "value")) {
        const std::vector<double> xs = im_.numbers(*e, *v, "value");
        if (xs.size() != 3) im_.fail(*e, "a point's value is 3 numbers \"x, y, z\"");
        return Vec3(xs[0], xs[1], xs[2]);
    }
    Vec3 p(0.0);
    for (int k = 0; k < 3; ++k)
        if (const std::optional<std::string> c = im_.attr(*e, k == 0 ? "x" : k == 1 ? "y" : "z"))
            p[k] = im_.number(*e, *c, k == 0 ? "x" : k == 1 ? "y" : "z");
    return p;
}

std::optional<Mat4> Props::transform(const std::string& name) {
    const Elem* t = find(name);
    if (!t) return std::nullopt;
    if (t->tag() != "transform") im_.fail(*t, "\"" + name + "\" must be a <transform>");
    Mat4 M(1.0);
    const auto vec = [&](const Elem& e, const char* key, std::optional<Vec3> def) -> Vec3 {
        const std::optional<std::string> v = im_.attr(e, key);
        if (!v) {
            if (!def) im_.fail(e, std::string("the attribute \"") + key + "\" is missing");
            return *def;
        }
        const std::vector<double> xs = im_.numbers(e, *v, key);
        if (xs.size() != 3) im_.fail(e, std::string(key) + " must be 3 numbers \"x, y, z\"");
        return Vec3(xs[0], xs[1], xs[2]);
    };
    const auto xyz = [&](const Elem& e, double def) {
        if (im_.attr(e, "value")) return vec(e, "value", std::nullopt);
        Vec3 v(def);
        for (int k = 0; k < 3; ++k)
            if (const std::optional<std::string> c = im_.attr(e, k == 0 ? "x" : k == 1 ? "y" : "z"))
                v[k] = im_.number(e, *c, "coordinate");
        return v;
    };
    for (pugi::xml_node c = t->node.first_child(); c; c = c.next_sibling()) {
        if (c.type() != pugi::node_element) continue;
        const Elem e{c, t->file};
        const std::string tag = e.tag();
        Mat4 step(1.0);
        if (tag == "translate") {
            step = glm::translate(Mat4(1.0), xyz(e, 0.0));
        } else if (tag == "rotate") {
            const Vec3 axis = xyz(e, 0.0);
            const double angle = im_.number(e, im_.required(e, "angle"), "angle");
            if (!(glm::length(axis) > 0.0)) im_.fail(e, "the rotation axis must not be zero");
            step = glm::rotate(Mat4(1.0), glm::radians(angle), glm::normalize(axis));
        } else if (tag == "scale") {
            Vec3 s(1.0);
            if (const std::optional<std::string> v = im_.attr(e, "value")) {
                const std::vector<double> xs = im_.numbers(e, *v, "value");
                if (xs.size() == 1)
                    s = Vec3(xs[0]);
                else if (xs.size() == 3)
                    s = Vec3(xs[0], xs[1], xs[2]);
                else
                    im_.fail(e, "a scale's value is 1 or 3 numbers");
            } else {
                s = xyz(e, 1.0);
            }
            step = glm::scale(Mat4(1.0), s);
        } else if (tag == "matrix") {
            const std::vector<double> m = im_.numbers(e, im_.required(e, "value"), "value");
            if (m.size() != 16 && m.size() != 9) im_.fail(e, "a matrix is 16 (4x4) or 9 (3x3) numbers, row-major");
            const int n = m.size() == 16 ? 4 : 3;
            for (int r = 0; r < n; ++r)
                for (int k = 0; k < n; ++k) step[k][r] = m[r * n + k];  // glm is column-major
            if (step[0][3] != 0.0 || step[1][3] != 0.0 || step[2][3] != 0.0 || step[3][3] != 1.0)
                im_.fail(e, "the matrix must be affine (last row 0, 0, 0, 1): tpb has no projective transforms");
        } else if (tag == "lookat") {
            const Vec3 origin = vec(e, "origin", std::nullopt), target = vec(e, "target", std::nullopt);
            const Vec3 up = vec(e, "up", Vec3(0.0, 1.0, 0.0));
            const Vec3 dir = target - origin;
            if (!(glm::length(dir) > 0.0)) im_.fail(e, "target must differ from origin");
            const Vec3 dn = glm::normalize(dir);
            const Vec3 l = glm::cross(glm::normalize(up), dn);
            if (!(glm::length(l) > 1e-9)) im_.fail(e, "up must not be parallel to target - origin");
            const Vec3 left = glm::normalize(l), newUp = glm::cross(dn, left);
            step = Mat4(glm::dvec4(left, 0.0), glm::dvec4(newUp, 0.0), glm::dvec4(dn, 0.0), glm::dvec4(origin, 1.0));
        } else {
            im_.fail(e, "unknown transform element <" + tag + ">; allowed: translate, rotate, scale, matrix, lookat");
        }
        M = step * M;  // each later element is applied after the earlier ones
    }
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(M[c][r])) im_.fail(*t, "the transform is not finite");
    return M;
}

void Props::noEffect(const std::string& name, const std::string& why) {
    if (const Elem* e = find(name)) im_.warn(*e, "\"" + name + "\" has no effect in tpb: " + why);
}

void Props::finish() {
    for (const auto& [name, e] : byName_) {
        if (asked_.count(name)) continue;
        std::string known;
        for (const std::string& a : asked_) known += (known.empty() ? "" : ", ") + a;
        im_.warn(e, "unknown or unsupported parameter \"" + clipped(name) + "\" of " + label(owner_) + ", ignored" +
                        (known.empty() ? "" : " (tpb reads: " + known + ")"));
    }
    for (const Elem& o : objects_)
        if (!taken_.count(o.node.internal_object())) im_.warn(o, "not used by " + label(owner_) + ", ignored");
}

// ---- parsing, includes, parameters ----------------------------------------------------------------

const XmlFile& Importer::parse(const std::string& text, const std::string& path) {
    XmlFile& f = files_.emplace_back();
    f.path = path;
    f.dir = fs::path(path).parent_path().string();
    if (f.dir.empty()) f.dir = ".";
    f.text = text;
    f.lineStarts.push_back(0);
    for (size_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') f.lineStarts.push_back(i + 1);
    const pugi::xml_parse_result r =
        f.doc.load_buffer(f.text.data(), f.text.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!r)
        throw UserError(path, f.lineOf(r.offset), "",
                        std::string("XML parse error: ") + r.description() +
                            "; check the markup on this line and the one before it");
    checkNesting(f);
    return f;
}

// The importer walks elements recursively (ids, nested bsdfs): refuse documents nested deeper
// than kXmlMaxDepth elements before it does, walking the tree without recursion (a 50,000-deep
// file overflowed the stack). Real scenes nest under ten levels.
void Importer::checkNesting(const XmlFile& f) const {
    int depth = 0;  // of n below the root element
    pugi::xml_node n = f.doc.document_element();
    while (n) {
        if (depth >= kXmlMaxDepth)
            throw UserError(f.path, f.lineOf(n.offset_debug()), "",
                            "elements nested deeper than " + std::to_string(kXmlMaxDepth) + " levels (<" +
                                std::string(n.name()) +
                                "> here); a Mitsuba scene nests a few levels: check for "
                                "unclosed or runaway elements");
        if (pugi::xml_node c = n.first_child(); c) {  // down
            n = c;
            ++depth;
            continue;
        }
        while (depth > 0 && !n.next_sibling()) {  // up to the first ancestor with a next sibling
            n = n.parent();
            --depth;
        }
        if (depth == 0) break;  // back at the root element
        n = n.next_sibling();
    }
}

std::optional<std::string> Importer::attr(const Elem& e, const char* name) const {
    const pugi::xml_attribute a = e.node.attribute(name);
    if (!a) return std::nullopt;
    const std::string raw = a.value();
    std::string out;
    for (size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] != '$') {
            out += raw[i];
            continue;
        }
        size_t j = i + 1;
        while (j < raw.size() && (std::isalnum(static_cast<unsigned char>(raw[j])) || raw[j] == '_')) ++j;
        const std::string key = raw.substr(i + 1, j - i - 1);
        if (key.empty()) fail(e, "a lone \"$\" in " + std::string(name) + "=\"" + raw + "\"");
        const auto it = params_.find(key);
        if (it == params_.end())
            fail(e, "undefined parameter $" + key + "; define it with <default name=\"" + key +
                        "\" value=\"...\"/> (or -D " + key + "=... on the command line)");
        out += it->second;
        i = j - 1;
    }
    return out;
}

std::vector<double> Importer::numbers(const Elem& e, const std::string& text, const char* what) const {
    std::vector<double> out;
    std::string s = text;
    std::replace(s.begin(), s.end(), ',', ' ');
    std::istringstream ss(s);
    std::string tok;
    while (ss >> tok) {
        double v = 0.0;
        const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
        if (ec != std::errc() || ptr != tok.data() + tok.size() || !std::isfinite(v))
            fail(e, std::string(what) + ": \"" + tok + "\" is not a finite number");
        out.push_back(v);
    }
    if (out.empty()) fail(e, std::string(what) + " is empty; expected a number");
    return out;
}

void Importer::collect(const Elem& scene, std::vector<Elem>& out, std::vector<std::string>& stack) {
    for (pugi::xml_node c = scene.node.first_child(); c; c = c.next_sibling()) {
        if (c.type() != pugi::node_element) continue;
        const Elem e{c, scene.file};
        const std::string tag = e.tag();
        if (tag == "default") {
            const std::string name = required(e, "name");
            const pugi::xml_attribute v = c.attribute("value");
            if (!v) fail(e, "the attribute \"value\" is missing");
            params_.emplace(name, v.value());  // a -D value (or an earlier default) wins
        } else if (tag == "include") {
            fs::path p(required(e, "filename"));
            if (p.is_relative()) p = fs::path(scene.file->dir) / p;
            const std::string path = p.lexically_normal().string();
            if (std::find(stack.begin(), stack.end(), path) != stack.end() || stack.size() > 16)
                fail(e, "include cycle (or more than 16 levels): " + path + " is already being read");
            std::string text;
            try {
                text = readSceneFile(path, "the included file");
            } catch (const UserError& err) {
                fail(e, err.what());
            }
            const XmlFile& f = parse(text, path);
            const pugi::xml_node root = f.doc.document_element();
            if (std::string(root.name()) != "scene")
                fail(Elem{root, &f},
                     "an included file must hold a <scene> element, got <" + std::string(root.name()) + ">");
            stack.push_back(path);
            collect(Elem{root, &f}, out, stack);
            stack.pop_back();
        } else {
            out.push_back(e);
        }
    }
}

void Importer::registerIds(const Elem& e) {
    if (const std::optional<std::string> id = attr(e, "id"); id && e.tag() != "ref") {
        const auto [it, fresh] = ids_.emplace(*id, e);
        if (!fresh)
            fail(e, "the id \"" + *id + "\" is already used at " + it->second.file->path + ":" +
                        std::to_string(it->second.line()));
    }
    for (pugi::xml_node c = e.node.first_child(); c; c = c.next_sibling())
        if (c.type() == pugi::node_element) registerIds(Elem{c, e.file});
}

const Elem& Importer::lookup(const Elem& ref, const std::string& id) const {
    const auto it = ids_.find(id);
    if (it != ids_.end()) return it->second;
    std::string defined;
    int n = 0;
    for (const auto& [name, e] : ids_)
        if (n++ < 20) defined += (defined.empty() ? "\"" : ", \"") + name + "\"";
    fail(ref, "no object has the id \"" + id + "\"" +
                  (defined.empty() ? "; no ids are defined" : "; defined ids: " + defined));
}

// ---- sensor, film, integrator --------------------------------------------------------------------

void Importer::readSensor(const Elem& e) {
    if (captureMeterAhead_) {
        warn(e,
             "ignored (with its film, sampler and medium): the scene's nlos_capture_meter, on its relay wall, is "
             "tpb's sensor");
        return;
    }
    if (haveSensor_) {
        warn(e, "a second sensor: tpb renders the first one only; ignored");
        return;
    }
    haveSensor_ = true;
    Props p(*this, e);
    const std::string type = p.type();
    if (type != "perspective")
        fail(e, "unsupported sensor type \"" + type + "\"; tpb imports \"perspective\" (a pinhole camera" +
                    (type == "thinlens" ? ": no depth of field" : "") + ")");
    loc("camera", e);
    CameraDesc& cam = d_.camera;
    for (Elem& o : p.objects()) {
        if (o.tag() == "film") {
            p.took(o);
            readFilm(o);
        }
    }
    if (!d_.locs.count("camera.resolution")) {  // no film: Mitsuba's default hdrfilm
        cam.width = 768;
        cam.height = 576;
    }
    const Mat4 M = p.transform("to_world").value_or(Mat4(1.0));
    const Vec3 pos(M * glm::dvec4(0, 0, 0, 1)), dir(M * glm::dvec4(0, 0, 1, 0)), up(M * glm::dvec4(0, 1, 0, 0)),
        left(M * glm::dvec4(1, 0, 0, 0));
    if (!(glm::length(dir) > 0.0) || !(glm::length(glm::cross(dir, up)) > 0.0))
        fail(*p.find("to_world"), "the sensor's to_world is singular");
    if (glm::dot(left, glm::cross(up, dir)) < 0.0)
        fail(*p.find("to_world"),
             "the sensor's to_world mirrors the image (a negative scale); tpb's camera cannot "
             "mirror: remove the mirroring scale");
    checkPoint(e, pos, "the sensor");
    cam.position = pos;
    cam.lookAt = pos + glm::normalize(dir);
    cam.up = glm::normalize(up);
    if (const Elem* t = p.find("to_world")) loc("camera.position", *t);

    // Field of view: tpb's is vertical.
    const double w = cam.width, h = cam.height, aspect = w / h;
    std::optional<double> fov = p.number("fov");
    std::string axis = lower(p.string("fov_axis").value_or("x"));
    const std::optional<std::string> focal = p.string("focal_length");
    const Elem* at = p.find(fov ? "fov" : "focal_length");
    if (fov && focal) fail(*p.find("focal_length"), "give either fov or focal_length, not both");
    if (!fov) {  // 35 mm film equivalent, on the diagonal (Mitsuba's default: 50mm)
        std::string f = trim(focal.value_or("50mm"));
        if (f.size() > 2 && f.substr(f.size() - 2) == "mm") f.resize(f.size() - 2);
        const double mm = number(at ? *at : e, f, "focal_length");
        if (!(mm > 0.0)) fail(at ? *at : e, "focal_length must be > 0 mm");
        fov = 2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm)) * 180.0 / kPi;
        axis = "diagonal";
    }
    if (!(*fov > 0.0 && *fov < 180.0)) fail(at ? *at : e, "fov must be in (0, 180) degrees");
    const double t = std::tan(0.5 * *fov * kPi / 180.0);
    double ty = 0.0;
    if (axis == "smaller") axis = w < h ? "x" : "y";
    if (axis == "larger") axis = w > h ? "x" : "y";
    if (axis == "x")
        ty = t / aspect;
    else if (axis == "y")
        ty = t;
    else if (axis == "diagonal")
        ty = t / std::sqrt(aspect * aspect + 1.0);
    else
        fail(*p.find("fov_axis"), "unknown fov_axis \"" + axis + "\"; allowed: x, y, diagonal, smaller, larger");
    cam.fovYDeg = 2.0 * std::atan(ty) * 180.0 / kPi;
    if (at) loc("camera.fov", *at);

    p.noEffect("near_clip", "tpb's camera rays start at the sensor");
    p.noEffect("far_clip", "tpb's camera rays are not clipped");
    p.noEffect("principal_point_offset_x", "tpb's camera is centred");
    p.noEffect("principal_point_offset_y", "tpb's camera is centred");
    p.noEffect("shutter_open", "tpb's time is the transient film's");
    p.noEffect("shutter_close", "tpb's time is the transient film's");
    for (Elem& o : p.objects()) {
        const std::string tag = o.tag();
        if (tag == "sampler") {
            readSampler(p, o);
        } else if (tag == "medium" || tag == "ref") {
            const Elem& target = tag == "ref" ? lookup(o, required(o, "id")) : o;
            if (target.tag() != "medium") fail(o, "a sensor takes a medium here, not a <" + target.tag() + ">");
            p.took(o);
            d_.globalMedium = medium(target);
            loc("global_medium", o);
        }
    }
    if (const Elem* m = p.find("medium")) {  // <medium name="medium"> (named inline)
        d_.globalMedium = medium(*m);
        loc("global_medium", *m);
    }
    p.finish();
}

void Importer::readSampler(Props& p, const Elem& o) {
    p.took(o);
    Props s(*this, o);
    if (const Elem* c = s.find("sample_count"))
        warn(*c,
             "sample_count has no tpb equivalent (tpb renders progressive passes: set tpb_passes on the "
             "<integrator>, or --passes); ignored");
    if (const std::optional<int64_t> seed = s.integer("seed")) {
        if (*seed < 0) fail(*s.find("seed"), "seed must be >= 0");
        d_.render.seed = static_cast<uint64_t>(*seed);
        loc("render.seed", *s.find("seed"));
    }
    s.finish();
}

void Importer::readFilm(const Elem& e, bool nlos) {
    Props p(*this, e);
    const std::string type = p.type();
    if (type != "hdrfilm" && type != "transient_hdr_film")
        fail(e, "unsupported film type \"" + type +
                    "\"; tpb imports \"transient_hdr_film\" (mitransient) and \"hdrfilm\"");
    const auto size = [&](const char* key, int def) {
        const std::optional<int64_t> v = p.integer(key);
        if (v && (*v < 1 || *v > INT_MAX)) fail(*p.find(key), std::string(key) + " must be an integer >= 1");
        if (v) loc("camera.resolution", *p.find(key));
        return v ? static_cast<int>(*v) : def;
    };
    d_.camera.width = size("width", 768);
    d_.camera.height = size("height", 576);
    if (!d_.locs.count("camera.resolution")) loc("camera.resolution", e);
    if (static_cast<int64_t>(d_.camera.width) * d_.camera.height > INT_MAX) fail(e, "the film has too many pixels");
    FilmDesc& film = d_.film;
    if (type == "transient_hdr_film") {
        if (const std::optional<int64_t> b = p.integer("temporal_bins")) {
            if (*b < 1 || *b > INT_MAX) fail(*p.find("temporal_bins"), "temporal_bins must be an integer >= 1");
            film.bins = static_cast<int>(*b);
            loc("film.bins", *p.find("temporal_bins"));
        }
        const std::optional<double> width = p.number("bin_width_opl"), start = p.number("start_opl");
        if (width) {
            if (!(*width > 0.0)) fail(*p.find("bin_width_opl"), "bin_width_opl must be > 0 (m of optical path)");
            film.binWidthOpl = *width;
            film.autoRange = false;
            loc("film.bin_width_m", *p.find("bin_width_opl"));
        }
        if (start) {
            if (!width) fail(*p.find("start_opl"), "start_opl needs bin_width_opl (or give neither: automatic range)");
            film.startOpl = *start;
            loc("film.start_m", *p.find("start_opl"));
        }
        p.noEffect("auto_detect_bins", "tpb's automatic range is used when bin_width_opl is not given");
        if (nlos) {  // mitransient's exhaustive NLOS capture: the laser's grid
            nlos_.film = e;
            nlos_.exhaustiveFilm = p.boolean("exhaustive_scan").value_or(false);
            for (const char* k : {"laser_scan_width", "laser_scan_height"})
                if (const std::optional<int64_t> v = p.integer(k)) {
                    if (*v < 0 || *v > INT_MAX) fail(*p.find(k), std::string(k) + " must be an integer >= 0");
                    (k[11] == 'w' ? nlos_.laserScanW : nlos_.laserScanH) = static_cast<int>(*v);
                    nlos_.laserScan = *p.find(k);
                }
        }
    }
    for (const char* k : {"crop_offset_x", "crop_offset_y", "crop_width", "crop_height"})
        if (const Elem* c = p.find(k)) fail(*c, "crop windows are not supported; render the full film (width, height)");
    for (const char* k : {"file_format", "pixel_format", "component_format", "sample_border", "compensate", "banner"})
        p.noEffect(k, "tpb writes RGB float EXR frames (tpb render) or shows the film (tpb view)");
    for (Elem& o : p.objects())
        if (o.tag() == "rfilter") {
            p.took(o);
            const std::string f = attr(o, "type").value_or("");
            if (f != "box")
                warn(o, "tpb's film has no reconstruction filter (each pixel is a box); \"" + f + "\" ignored");
        }
    p.finish();
    const uint64_t need = filmBytes(d_.camera.width, d_.camera.height, film.bins), limit = maxFilmBytes();
    if (need > limit)
        fail(e, "the film needs " + humanBytes(need) + " for " + std::to_string(d_.camera.width) + " x " +
                    std::to_string(d_.camera.height) + " pixels x " + std::to_string(film.bins) +
                    " bins, more than the limit of " + humanBytes(limit) + "; lower temporal_bins or width/height");
}

void Importer::readIntegrator(const Elem& e) {
    if (haveIntegrator_) {
        warn(e, "a second integrator: ignored");
        return;
    }
    haveIntegrator_ = true;
    Props p(*this, e);
    const std::string type = p.type();
    static const std::set<std::string> kKnown = {"path",
                                                 "volpath",
                                                 "volpathmis",
                                                 "prbvolpath",
                                                 "prb",
                                                 "direct",
                                                 "transient_path",
                                                 "transient_volpath",
                                                 "transient_prbvolpath",
                                                 "transientpath",
                                                 "transient_nlos_path"};
    if (!kKnown.count(type))
        warn(e, "unknown integrator \"" + type +
                    "\": tpb renders with transient photon beams whatever the integrator; "
                    "its max_depth is read");
    RenderDesc& r = d_.render;
    if (const std::optional<int64_t> depth = p.integer("max_depth")) {
        const Elem& de = *p.find("max_depth");
        if (*depth == -1) {
            warn(de, "max_depth -1 (unbounded) has no tpb equivalent; render.max_depth " + std::to_string(r.maxDepth) +
                         " (tpb's default) is used: give a bound");
        } else {
            if (*depth < 2 || *depth > INT_MAX)
                fail(de,
                     "max_depth must be >= 2 or -1 (tpb renders scattered light: max_depth 2 is single scattering; "
                     "tpb's render.max_depth = max_depth - 1)");
            r.maxDepth = static_cast<int>(*depth - 1);
            loc("render.max_depth", de);
        }
    }
    // mitransient's transient_nlos_path: the NLOS capture (resolved with the nlos_capture_meter).
    nlosInt_.type = type;
    if (const Elem* c = p.find("capture_type")) {  // "single"/"confocal"/"exhaustive" or 1/2/3
        nlosInt_.captureElem = *c;
        const std::string v = lower(trim(required(*c, "value")));
        if (v == "single" || v == "1")
            nlosInt_.capture = ScanMode::Single;
        else if (v == "confocal" || v == "2")
            nlosInt_.capture = ScanMode::Confocal;
        else if (v == "exhaustive" || v == "3")
            nlosInt_.capture = ScanMode::Exhaustive;
        else
            fail(*c, "unknown capture_type \"" + v + "\"; allowed: single (1), confocal (2), exhaustive (3)");
    }
    if (const std::optional<bool> a = p.boolean("account_first_and_last_bounces")) {
        nlosInt_.account = *a;
        nlosInt_.accountElem = *p.find("account_first_and_last_bounces");
    }
    if (const std::optional<bool> f = p.boolean("force_equal_illumination_scanning")) {
        nlosInt_.forceEqual = *f;
        nlosInt_.forceEqualElem = *p.find("force_equal_illumination_scanning");
    }
    p.noEffect("illumination_scan_fov",
               "tpb's exhaustive laser grid lies on the relay wall (force_equal_illumination_scanning)");
    for (const char* k :
         {"nlos_laser_sampling", "nlos_hidden_geometry_sampling", "nlos_hidden_geometry_sampling_do_rroulette",
          "nlos_hidden_geometry_sampling_includes_relay_wall"})
        p.noEffect(k, "a path-tracing technique of mitransient; tpb's photon beams need none");
    p.noEffect("block_size", "tpb schedules its own work");
    for (const char* k : {"filter_depth", "filter_bounces"})
        if (const std::optional<int64_t> v = p.integer(k); v && *v != -1)
            warn(*p.find(k), std::string(k) +
                                 " has no tpb equivalent: tpb's film holds paths of every length (up to max_depth); "
                                 "ignored");
    p.noEffect("rr_depth", "tpb's Russian roulette has its own rule");
    p.noEffect("hide_emitters", "visible area lights are always drawn");
    p.noEffect("temporal_filter", "tpb's time kernel is tpb_time_kernel");
    p.noEffect("gaussian_stddev", "tpb's time kernel is tpb_time_kernel");
    p.noEffect("discard_direct_paths", "tpb keeps every path");
    if (const std::optional<bool> u = p.boolean("camera_unwarp")) {
        r.unwarp = *u;
        loc("render.unwarp", *p.find("camera_unwarp"));
    }
    // tpb's own render settings, as tpb_<key> parameters (Mitsuba ignores them with a warning).
    const auto key = [&](const char* k) -> const Elem* {
        const Elem* x = p.find(std::string("tpb_") + k);
        if (x) loc(std::string("render.") + k, *x);
        return x;
    };
    const auto intIn = [&](const char* k, int64_t lo, int64_t hi) -> std::optional<int64_t> {
        if (!key(k)) return std::nullopt;
        const int64_t v = *p.integer(std::string("tpb_") + k);
        if (v < lo || v > hi) fail(*p.find(std::string("tpb_") + k), std::string("tpb_") + k + " is out of range");
        return v;
    };
    const auto num = [&](const char* k) { return key(k) ? p.number(std::string("tpb_") + k) : std::nullopt; };
    const auto str = [&](const char* k) { return key(k) ? p.string(std::string("tpb_") + k) : std::nullopt; };
    if (auto v = intIn("photons_per_pass", 1, INT64_MAX)) r.photonsPerPass = *v;
    if (auto v = intIn("warmup", INT_MIN, INT_MAX)) r.warmup = static_cast<int>(*v);
    if (auto v = intIn("passes", INT_MIN, INT_MAX)) r.passes = static_cast<int>(*v);
    if (auto v = intIn("threads", INT_MIN, INT_MAX)) r.threads = static_cast<int>(*v);
    if (auto v = intIn("seed", 0, INT64_MAX)) r.seed = static_cast<uint64_t>(*v);
    if (auto v = num("alpha")) r.alpha = *v;
    if (auto v = num("time_budget_s")) r.timeBudgetSec = *v;
    const std::optional<double> abs = num("radius"), rel = num("radius_relative"), sAbs = num("surface_radius"),
                                sRel = num("surface_radius_relative");
    if ((abs && rel) || (sAbs && sRel) || ((abs || sAbs) && (rel || sRel)))
        fail(e,
             "the radii must all be absolute (tpb_radius, tpb_surface_radius) or all relative (tpb_radius_relative, "
             "tpb_surface_radius_relative)");
    if (abs || rel) {
        r.radiusAuto = false;
        r.radius = abs ? *abs : *rel;
    }
    if (sAbs || sRel) r.surfaceRadius = sAbs ? *sAbs : *sRel;
    if (abs || sAbs) r.radiusRelative = false;
    if (rel || sRel) r.radiusRelative = true;
    const auto choose = [&](const char* k, const std::vector<std::string>& allowed) -> std::optional<size_t> {
        const std::optional<std::string> v = str(k);
        if (!v) return std::nullopt;
        for (size_t i = 0; i < allowed.size(); ++i)
            if (*v == allowed[i]) return i;
        std::string list;
        for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(*p.find(std::string("tpb_") + k), "unknown value \"" + *v + "\"; allowed: " + list);
    };
    if (auto i = choose("emission", {"delta", "continuous"}))
        r.emission = *i ? EmissionMode::Continuous : EmissionMode::Delta;
    if (auto i = choose("time_profile", {"exact", "uniform"}))
        r.timeProfile = *i ? TimeProfile::Uniform : TimeProfile::Exact;
    if (auto i = choose("beam_length", {"short", "long"})) r.beamLength = *i ? BeamLength::Long : BeamLength::Short;
    if (key("unwarp")) r.unwarp = *p.boolean("tpb_unwarp");
    if (auto v = str("volume_estimator")) r.volumeEstimator = *v;
    if (auto v = str("surface_estimator")) r.surfaceEstimator = *v;
    if (auto v = str("time_kernel")) {
        const std::optional<TimeKernelSettings> k = parseTimeKernel(*v);
        if (!k)
            fail(*p.find("tpb_time_kernel"), "unknown time kernel \"" + *v + "\"; allowed: none, box, box:WIDTH (m)");
        r.timeKernel = *k;
    }
    p.finish();
}

// ---- materials and media -------------------------------------------------------------------------

int Importer::material(const Elem& e) {
    const auto it = materials_.find(e.node.internal_object());
    if (it != materials_.end()) return it->second;
    MaterialDesc m = readBsdf(e, false);
    m.name = attr(e, "id").value_or("bsdf at line " + std::to_string(e.line()));
    const int index = static_cast<int>(d_.materials.size());
    loc("materials." + m.name, e);
    d_.materials.push_back(m);
    materials_[e.node.internal_object()] = index;
    return index;
}

MaterialDesc Importer::readBsdf(const Elem& e, bool wrapped) {
    Props p(*this, e);
    const std::string type = p.type();
    MaterialDesc m;
    const auto unit = [&](const char* key, const Color& c) {
        if (!(c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x <= 1 && c.y <= 1 && c.z <= 1))
            fail(*p.find(key), std::string(key) + " must be in [0, 1]");
        return c;
    };
    const auto ior = [&](const char* key, double def) {
        const Elem* x = p.find(key);
        if (!x) return def;
        if (x->tag() == "string") {
            const std::string name = lower(trim(*p.string(key)));
            double v = 0.0;
            if (!mitsubaNamedIor(name, v))
                fail(*x, "unknown named IOR \"" + name +
                             "\"; give a number or one of vacuum, air, water, "
                             "ethanol, glycerol, fused quartz, pyrex, acrylic glass, bk7, sodium chloride, pet, "
                             "diamond, ...");
            return v;
        }
        return *p.number(key);
    };
    if (type == "twosided") {
        std::vector<Elem> inner;
        for (Elem& o : p.objects()) {
            if (o.tag() == "bsdf")
                inner.push_back(o);
            else if (o.tag() == "ref")
                inner.push_back(lookup(o, required(o, "id")));
            else
                continue;
            p.took(o);
        }
        if (inner.size() != 1)
            fail(e, "twosided must hold exactly one bsdf (tpb cannot give the two sides different materials)");
        if (inner[0].tag() != "bsdf") fail(inner[0], "twosided holds a bsdf, not a <" + inner[0].tag() + ">");
        m = readBsdf(inner[0], true);
    } else if (type == "diffuse") {
        m.type = MaterialType::Diffuse;
        m.albedo = unit("reflectance", p.color("reflectance").value_or(Color(0.5)));
    } else if (type == "conductor" || type == "roughconductor") {
        m.type = MaterialType::Mirror;
        m.specular = unit("specular_reflectance", p.color("specular_reflectance").value_or(Color(1.0)));
        for (const char* k : {"material", "eta", "k", "alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"})
            p.find(k);
        warn(e, std::string("imported as a perfect mirror of reflectance specular_reflectance (") +
                    std::to_string(maxComponent(m.specular)) +
                    "): tpb has no conductor Fresnel (material/eta/k are "
                    "ignored)" +
                    (type == "roughconductor" ? " and no roughness (alpha is ignored)" : ""));
    } else if (type == "dielectric" || type == "roughdielectric" || type == "thindielectric") {
        const double intIor = ior("int_ior", 1.5046), extIor = ior("ext_ior", 1.000277);
        if (!(intIor >= 1.0)) fail(p.find("int_ior") ? *p.find("int_ior") : e, "int_ior must be >= 1 in tpb");
        if (std::fabs(extIor - 1.0) > kAirTolerance)
            warn(p.find("ext_ior") ? *p.find("ext_ior") : e,
                 "ext_ior " + std::to_string(extIor) +
                     " is ignored: tpb takes the index outside a dielectric from "
                     "the region around it (the global medium's, 1 in vacuum)");
        const std::optional<Color> refl = p.color("specular_reflectance"), trans = p.color("specular_transmittance");
        m.specular =
            unit(trans ? "specular_transmittance" : "specular_reflectance", trans ? *trans : refl.value_or(Color(1.0)));
        if (refl && trans && *refl != *trans)
            warn(*p.find("specular_reflectance"),
                 "tpb's dielectric has one tint for reflection and transmission: "
                 "specular_transmittance is used");
        if (type == "thindielectric") {
            m.type = MaterialType::Null;
            const double f = (intIor - 1.0) / (intIor + 1.0);
            warn(e,
                 "tpb has no thin dielectric: imported as a null surface (light passes straight through, as "
                 "through a thin sheet, undelayed); its Fresnel reflection (" +
                     std::to_string(2 * f * f / (1 + f * f)) + " at normal incidence) is lost");
        } else {
            m.type = MaterialType::Dielectric;
            m.ior = intIor;
            if (type == "roughdielectric") {
                for (const char* k : {"alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"}) p.find(k);
                warn(e, "imported as a smooth dielectric: tpb has no rough dielectric (alpha is ignored)");
            }
        }
    } else if (type == "null") {
        m.type = MaterialType::Null;
    } else {
        fail(e, "unsupported bsdf type \"" + type +
                    "\"; tpb imports diffuse, conductor, roughconductor (as mirrors), "
                    "dielectric, roughdielectric, thindielectric, twosided, null");
    }
    (void)wrapped;
    p.finish();
    return m;
}

int Importer::medium(const Elem& e) {
    const auto it = media_.find(e.node.internal_object());
    if (it != media_.end()) return it->second;
    Props p(*this, e);
    const std::string type = p.type();
    if (type != "homogeneous") fail(e, "unsupported medium type \"" + type + "\"; tpb imports \"homogeneous\" media");
    MediumDesc md;
    md.name = attr(e, "id").value_or("medium at line " + std::to_string(e.line()));
    const std::optional<Color> st = p.color("sigma_t"), al = p.color("albedo"), sa = p.color("sigma_a"),
                               ss = p.color("sigma_s");
    const double scale = p.number("scale").value_or(1.0);
    if (!(scale >= 0.0)) fail(*p.find("scale"), "scale must be >= 0");
    const auto nonNeg = [&](const char* key, const Color& c) {
        if (!(c.x >= 0 && c.y >= 0 && c.z >= 0)) fail(*p.find(key), std::string(key) + " must be >= 0");
    };
    if ((sa || ss) && (st || al))
        fail(*p.find(sa ? "sigma_a" : "sigma_s"), "give sigma_t and albedo, or sigma_a and sigma_s, not a mix");
    if (sa || ss) {
        md.sigma_a = sa.value_or(Color(0.0)) * scale;
        md.sigma_s = ss.value_or(Color(0.0)) * scale;
        if (sa) nonNeg("sigma_a", *sa);
        if (ss) nonNeg("sigma_s", *ss);
    } else {
        const Color sigmaT = st.value_or(Color(1.0)), albedo = al.value_or(Color(0.75));
        if (st) nonNeg("sigma_t", sigmaT);
        if (al && !(albedo.x >= 0 && albedo.y >= 0 && albedo.z >= 0 && albedo.x <= 1 && albedo.y <= 1 && albedo.z <= 1))
            fail(*p.find("albedo"), "albedo must be in [0, 1]");
        md.sigma_s = albedo * sigmaT * scale;
        md.sigma_a = (Color(1.0) - albedo) * sigmaT * scale;
    }
    p.find("sample_emitters");  // a sampling strategy of Mitsuba's: no effect on the result
    md.g = 0.0;
    for (Elem& o : p.objects()) {
        if (o.tag() != "phase") continue;
        p.took(o);
        Props ph(*this, o);
        const std::string pt = ph.type();
        if (pt == "hg") {
            md.g = ph.number("g").value_or(0.8);
            if (!(md.g > -1.0 && md.g < 1.0)) fail(*ph.find("g"), "g must be in (-1, 1)");
        } else if (pt != "isotropic") {
            fail(o, "unsupported phase function \"" + pt + "\"; tpb imports isotropic and hg");
        }
        ph.finish();
    }
    p.finish();
    const int index = static_cast<int>(d_.media.size());
    loc("media." + md.name, e);
    d_.media.push_back(md);
    media_[e.node.internal_object()] = index;
    return index;
}

// <ref name="interior" id="..."/> or <medium name="interior" ...>: its index, -1 when absent.
int Importer::mediumParam(Props& p, const std::string& name) {
    const Elem* x = p.find(name);
    if (!x) return -1;
    const Elem& target = x->tag() == "ref" ? lookup(*x, required(*x, "id")) : *x;
    if (target.tag() != "medium") fail(*x, name + " must be a medium, not a <" + target.tag() + ">");
    return medium(target);
}

// ---- shapes and emitters -------------------------------------------------------------------------

void Importer::readShape(const Elem& e) {
    Props p(*this, e);
    const std::string type = p.type();
    const std::string key = "shapes[" + std::to_string(d_.shapes.size()) + "]";
    ShapeDesc s;
    s.name = attr(e, "id").value_or(attr(e, "name").value_or(type + " at line " + std::to_string(e.line())));
    const std::optional<Mat4> toWorld = p.transform("to_world");
    const Mat4 M = toWorld.value_or(Mat4(1.0));
    const bool flip = p.boolean("flip_normals").value_or(false);
    const int interior = mediumParam(p, "interior"), exterior = mediumParam(p, "exterior");
    if (exterior >= 0) exteriorChecks_.push_back({*p.find("exterior"), exterior});

    // The bsdf (nested or a ref) and an area emitter.
    const Elem* bsdf = nullptr;
    const Elem* emitter = nullptr;
    const Elem* sensor = nullptr;
    for (Elem& o : p.objects()) {
        if (o.tag() == "sensor") {  // mitransient's relay wall: an nlos_capture_meter on the shape
            if (sensor) fail(o, "a shape holds one sensor");
            sensor = &o;
            p.took(o);
            continue;
        }
        const Elem* t = o.tag() == "ref" ? &lookup(o, required(o, "id")) : &o;  // ids_ entries are stable
        if (t->tag() == "bsdf") {
            if (bsdf) fail(o, "a shape has one bsdf");
            bsdf = t;
        } else if (t->tag() == "emitter") {
            emitter = t;
        } else if (t->tag() == "medium") {
            fail(o, "a shape's medium needs name=\"interior\" or name=\"exterior\"");
        } else {
            fail(o, "a shape takes a bsdf, an emitter and media, not a <" + t->tag() + ">");
        }
        p.took(o);
    }
    const Mat4 linear = glm::dmat4(glm::dmat3(M));
    const double det = glm::determinant(glm::dmat3(M));
    if (toWorld && !(std::fabs(det) > 0.0)) fail(*p.find("to_world"), "to_world is singular");

    if (sensor && emitter)
        fail(*sensor, "a relay wall cannot also be an area light; put the emitter on another rectangle");
    if (emitter) {
        if (type != "rectangle") fail(*emitter, "an area emitter must sit on a rectangle: tpb's area lights are quads");
        if (bsdf)
            warn(*bsdf, "the bsdf of an area emitter's shape is ignored: tpb's area lights absorb what reaches them");
        if (interior >= 0) fail(*p.find("interior"), "an area emitter's rectangle cannot have an interior medium");
        readEmitter(*emitter, &e, &M, flip);
        p.finish();
        return;
    }

    if (bsdf)
        s.material = material(*bsdf);
    else if (interior >= 0 || exterior >= 0) {  // Mitsuba: a medium boundary without a bsdf is null
        if (defaultNull_ < 0) {
            defaultNull_ = static_cast<int>(d_.materials.size());
            MaterialDesc m;
            m.type = MaterialType::Null;
            m.name = "null (default of media boundaries)";
            d_.materials.push_back(m);
        }
        s.material = defaultNull_;
    } else {  // Mitsuba's default: diffuse, reflectance 0.5
        if (defaultDiffuse_ < 0) {
            defaultDiffuse_ = static_cast<int>(d_.materials.size());
            MaterialDesc m;
            m.type = MaterialType::Diffuse;
            m.albedo = Color(0.5);
            m.name = "diffuse (default)";
            d_.materials.push_back(m);
        }
        s.material = defaultDiffuse_;
    }
    const bool open = type == "rectangle" || type == "disk";
    if (interior >= 0 && open)
        fail(*p.find("interior"), "a " + type + " is open: it has no interior (use a cube, sphere or closed mesh)");
    s.interiorMedium = interior;
    loc(key, e);
    if (toWorld) loc(key + ".transform", *p.find("to_world"));

    if (type == "obj" || type == "ply") {
        s.type = ShapeType::Mesh;
        const Elem* fe = p.find("filename");
        if (!fe) fail(e, "a " + type + " shape needs <string name=\"filename\" value=\"...\"/>");
        fs::path path(*p.string("filename"));
        if (path.is_relative()) path = fs::path(e.file->dir) / path;
        s.meshPath = path.lexically_normal().string();
        const bool isPly = lower(path.extension().string()) == ".ply";
        if (isPly != (type == "ply"))
            fail(*fe, "a " + type + " shape needs a ." + type + " file, got " + path.filename().string());
        std::error_code ec;
        if (!fs::is_regular_file(s.meshPath, ec))
            fail(*fe, "mesh file not found (or not a file): " + s.meshPath + " (relative to the XML file's folder)");
        loc(key + ".file", *fe);
        s.transform = M;
        s.flipNormals = flip;
        p.noEffect("face_normals", "tpb shades with the file's normals when it has them (OBJ), else flat");
        p.noEffect("flip_tex_coords", "tpb has no textures");
    } else if (type == "sphere") {
        s.type = ShapeType::Sphere;
        if (flip) fail(*p.find("flip_normals"), "flip_normals on a sphere is not supported (tpb's spheres face out)");
        const Vec3 c = p.point("center").value_or(Vec3(0.0));
        double r = p.number("radius").value_or(1.0);
        if (!(r > 0.0)) fail(*p.find("radius"), "radius must be > 0");
        // to_world: a similarity (rotation, uniform scale, translation) keeps the sphere round.
        const Vec3 a(linear[0]), b(linear[1]), d(linear[2]);
        const double la = glm::length(a), lb = glm::length(b), ld = glm::length(d);
        const double tol = 1e-6 * std::max({la, lb, ld});
        if (std::fabs(la - lb) > tol || std::fabs(la - ld) > tol || std::fabs(glm::dot(a, b)) > tol * la ||
            std::fabs(glm::dot(a, d)) > tol * la || std::fabs(glm::dot(b, d)) > tol * lb)
            fail(*p.find("to_world"),
                 "a sphere's to_world must be a rotation, a uniform scale and a translation "
                 "(tpb's spheres are round; use a mesh for an ellipsoid)");
        s.center = Vec3(M * glm::dvec4(c, 1.0));
        s.radius = r * la;
        checkPoint(e, s.center, "the sphere's center");
        if (!(s.radius <= kMaxSceneCoordinateM)) fail(e, "the sphere's radius is beyond 1e9 m");
    } else if (type == "rectangle") {
        s.type = ShapeType::Quad;
        s.corner = Vec3(M * glm::dvec4(-1, -1, 0, 1));
        s.edgeU = Vec3(linear * glm::dvec4(2, 0, 0, 0));
        s.edgeV = Vec3(linear * glm::dvec4(0, 2, 0, 0));
        // Mitsuba's normal is the transformed +z (inverse transpose): with a mirroring to_world the
        // edges' cross product points the other way.
        s.flipNormals = flip != (det < 0.0);
        for (const Vec3& v : {s.corner, s.corner + s.edgeU + s.edgeV}) checkPoint(e, v, "the rectangle");
    } else if (type == "cube") {
        s.type = ShapeType::Box;
        s.boxMin = Vec3(-1.0);
        s.boxMax = Vec3(1.0);
        s.transform = M;
        s.flipNormals = flip;
        for (int i = 0; i < 8; ++i)
            checkPoint(e, Vec3(M * glm::dvec4(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1, 1)), "the cube");
    } else if (type == "disk") {
        s.type = ShapeType::Mesh;  // a triangle fan of kDiskSegments, vertices on the unit circle
        s.inlinePositions.push_back(Vec3(0.0));
        for (int i = 0; i < kDiskSegments; ++i) {
            const double phi = 2.0 * kPi * i / kDiskSegments;
            s.inlinePositions.push_back(Vec3(std::cos(phi), std::sin(phi), 0.0));
        }
        for (int i = 0; i < kDiskSegments; ++i)
            s.inlineTriangles.emplace_back(0u, 1u + i, 1u + (i + 1) % kDiskSegments);
        s.transform = M;
        s.flipNormals = flip;
        checkPoint(e, Vec3(M * glm::dvec4(0, 0, 0, 1)), "the disk");
    } else {
        fail(e, "unsupported shape type \"" + type + "\"; tpb imports obj, ply, sphere, rectangle, cube, disk");
    }
    if (interior >= 0 && d_.materials[s.material].type != MaterialType::Dielectric &&
        d_.materials[s.material].type != MaterialType::Null)
        warn(*p.find("interior"), "the interior medium has no effect: the shape's bsdf is not a dielectric or null");
    p.finish();
    d_.shapes.push_back(s);
    if (sensor) readCaptureMeter(*sensor, e, type);
}

void Importer::readEmitter(const Elem& e, const Elem* shape, const Mat4* shapeToWorld, bool flip) {
    Props p(*this, e);
    const std::string type = p.type();
    const std::string key = "lights[" + std::to_string(d_.lights.size()) + "]";
    LightDesc l;
    l.name = attr(e, "id").value_or(type + " light at line " + std::to_string(e.line()));
    const auto colorOf = [&](const char* k, double def) {
        const Color c = p.color(k).value_or(Color(def));
        if (!(c.x >= 0 && c.y >= 0 && c.z >= 0)) fail(*p.find(k), std::string(k) + " must be >= 0");
        if (const Elem* x = p.find(k)) loc(key + ".power", *x);
        return c;
    };
    if (shape) {
        if (type != "area") fail(e, "a shape's emitter must be \"area\", got \"" + type + "\"");
        const Mat4& M = *shapeToWorld;
        const glm::dmat3 lin(M);
        l.type = LightType::AreaQuad;
        l.corner = Vec3(M * glm::dvec4(-1, -1, 0, 1));
        l.edgeU = lin * Vec3(2, 0, 0);
        l.edgeV = lin * Vec3(0, 2, 0);
        if (flip != (glm::determinant(lin) < 0.0)) std::swap(l.edgeU, l.edgeV);  // emit along Mitsuba's normal
        const double area = glm::length(glm::cross(l.edgeU, l.edgeV));
        if (!(area > 0.0)) fail(*shape, "the emitting rectangle has no area");
        l.power = colorOf("radiance", 1.0) * (kPi * area);  // Lambertian, one-sided: flux = pi L A
        checkPoint(*shape, l.corner, "the area light");
        loc(key, *shape);
    } else if (type == "point") {
        l.type = LightType::Point;
        const std::optional<Vec3> pos = p.point("position");
        const std::optional<Mat4> M = p.transform("to_world");
        if (pos && M) fail(*p.find("position"), "give either position or to_world, not both");
        l.position = pos ? *pos : Vec3((M ? *M : Mat4(1.0)) * glm::dvec4(0, 0, 0, 1));
        l.power = colorOf("intensity", 1.0) * (4.0 * kPi);  // isotropic: flux = 4 pi I
        loc(key, e);
    } else if (type == "spot") {
        l.type = LightType::Spot;
        const Mat4 M = p.transform("to_world").value_or(Mat4(1.0));
        l.position = Vec3(M * glm::dvec4(0, 0, 0, 1));
        const Vec3 dir(M * glm::dvec4(0, 0, 1, 0));
        if (!(glm::length(dir) > 0.0)) fail(e, "the spot's to_world is singular");
        l.direction = glm::normalize(dir);
        l.spotCutoffDeg = p.number("cutoff_angle").value_or(20.0);
        if (!(l.spotCutoffDeg > 0.0 && l.spotCutoffDeg <= 180.0))
            fail(*p.find("cutoff_angle"), "cutoff_angle must be in (0, 180]");
        l.spotFalloffDeg = p.number("beam_width").value_or(0.75 * l.spotCutoffDeg);
        if (!(l.spotFalloffDeg >= 0.0 && l.spotFalloffDeg <= l.spotCutoffDeg))
            fail(*p.find("beam_width"), "beam_width must be in [0, cutoff_angle]");
        if (const Elem* t = p.find("texture")) fail(*t, "projected textures are not supported");
        // The on-axis intensity is Mitsuba's; the flux is I times the solid-angle integral of
        // tpb's profile (computed by Light exactly as it emits).
        LightDesc unit = l;
        unit.power = Color(1.0);
        l.power = colorOf("intensity", 1.0) * Light::fromDesc(unit).spotIntegral;
        if (l.spotFalloffDeg < l.spotCutoffDeg)
            warn(e,
                 "between beam_width and cutoff_angle tpb's spot falls off as a smoothstep in cos(angle), Mitsuba's "
                 "linearly in the angle; the on-axis intensity and the cone are the same");
        loc(key, e);
    } else if (type == "projector") {
        // A laser: mitransient's NLOS scenes light the relay wall with a projector of a small fov.
        // tpb's laser is a thin collimated beam from the projector's origin along its +z.
        l.type = LightType::Laser;
        const std::optional<Mat4> T = p.transform("to_world");
        const Mat4 M = T.value_or(Mat4(1.0));
        l.position = Vec3(M * glm::dvec4(0, 0, 0, 1));
        const Vec3 dir(M * glm::dvec4(0, 0, 1, 0));
        if (!(glm::length(dir) > 0.0)) fail(T ? *p.find("to_world") : e, "the projector's to_world is singular");
        l.direction = glm::normalize(dir);
        // The image on the plane z = 1: a square of half side t (a constant irradiance is a 1 x 1
        // texture), t from the fov as Mitsuba's perspective mapping (fov_axis), or a focal length.
        const std::optional<double> fov = p.number("fov");
        const std::optional<std::string> focal = p.string("focal_length");
        const std::string axis = lower(p.string("fov_axis").value_or("x"));
        if (fov && focal) fail(*p.find("focal_length"), "give either fov or focal_length, not both");
        double t = 0.0;
        if (fov) {
            if (!(*fov > 0.0 && *fov < 180.0)) fail(*p.find("fov"), "fov must be in (0, 180) degrees");
            t = std::tan(0.5 * *fov * kPi / 180.0);
            if (axis == "diagonal")
                t /= std::sqrt(2.0);
            else if (axis != "x" && axis != "y" && axis != "smaller" && axis != "larger")
                fail(*p.find("fov_axis"),
                     "unknown fov_axis \"" + axis + "\"; allowed: x, y, diagonal, smaller, larger");
        } else {  // 35 mm film equivalent, on the diagonal (Mitsuba's default: 50mm)
            const Elem* fe = p.find("focal_length");
            std::string f = trim(focal.value_or("50mm"));
            if (f.size() > 2 && f.substr(f.size() - 2) == "mm") f.resize(f.size() - 2);
            const double mm = number(fe ? *fe : e, f, "focal_length");
            if (!(mm > 0.0)) fail(fe ? *fe : e, "focal_length must be > 0 mm");
            t = std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm) / std::sqrt(2.0);
        }
        const double fullDeg = 2.0 * std::atan(t) * 180.0 / kPi;
        if (fullDeg > kMaxProjectorFovDeg) {
            char deg[32];
            std::snprintf(deg, sizeof deg, "%.3g", fullDeg);
            fail(fov ? *p.find("fov") : e,
                 "a projector is imported as a laser (a thin collimated beam), but this one "
                 "spreads over " +
                     std::string(deg) + " degrees (more than " + std::to_string(static_cast<int>(kMaxProjectorFovDeg)) +
                     "); give it a small fov (mitransient's lasers use 0.2), or use a spot");
        }
        const double scale = p.number("scale").value_or(1.0);
        if (!(scale >= 0.0)) fail(*p.find("scale"), "scale must be >= 0");
        // Mitsuba's projector emits pi * irradiance * scale * (area of its image at z = 1) watts
        // (the weight of its sample_ray): that is the laser's flux.
        l.power = colorOf("irradiance", 1.0) * (kPi * scale * 4.0 * t * t);
        l.laserRadius = 0.0;
        Projector pr;
        pr.light = static_cast<int>(d_.lights.size());
        pr.e = e;
        if (T) {
            pr.toWorld = *p.find("to_world");
            pr.translationOnly = glm::dmat3(*T) == glm::dmat3(1.0);
        }
        projectors_.push_back(pr);
        loc(key, e);
    } else if (type == "directional") {
        fail(e,
             "directional emitters are not supported: tpb has no light at infinity (in a medium it would carry "
             "infinite flux); use a spot, a large area light, or a tpb laser (JSON scenes)");
    } else if (type == "area") {
        fail(e, "an area emitter must be nested in the <shape type=\"rectangle\"> it lights");
    } else {
        fail(e, "unsupported emitter type \"" + type +
                    "\"; tpb imports point, spot, area (on a rectangle) and projector (as a laser)");
    }
    checkPoint(e, l.position, "the light");
    if (maxComponent(l.power) > 1e20)
        fail(e, "the light's flux is above 1e20 W (the film's float images could overflow)");
    // A medium on the emitter: tpb finds the region of a light itself.
    for (Elem& o : p.objects())
        if (o.tag() == "ref" || o.tag() == "medium") {
            p.took(o);
            const Elem& t = o.tag() == "ref" ? lookup(o, required(o, "id")) : o;
            if (t.tag() != "medium") fail(o, "an emitter takes a medium here, not a <" + t.tag() + ">");
            exteriorChecks_.push_back({o, medium(t)});
        }
    p.finish();
    d_.lights.push_back(l);
    lightElems_.push_back(e);
}

// ---- mitransient's NLOS setup ----------------------------------------------------------------------

// <sensor type="nlos_capture_meter"> on the relay wall's rectangle (mitransient's
// sensors/nloscapturemeter.py): its film's pixels are the wall's grid, sensor_origin the sensor.
void Importer::readCaptureMeter(const Elem& sensor, const Elem& shape, const std::string& shapeType) {
    Props p(*this, sensor);
    const std::string type = p.type();
    if (type != "nlos_capture_meter")
        fail(sensor, "unsupported sensor type \"" + type + "\" on a shape; tpb imports mitransient's " +
                         "\"nlos_capture_meter\" (a relay wall)" +
                         (type == "nloscapturemeter"
                              ? ": \"nloscapturemeter\" is mitsuba2-transient-nlos's; write the scene for mitransient "
                                "(tal's mitsuba3 backend)"
                              : ""));
    if (nlos_.present)
        fail(sensor, "a second nlos_capture_meter (the first is at line " + std::to_string(nlos_.sensor.line()) +
                         "): tpb renders one relay wall; keep one capture meter and render the other wall as its "
                         "own scene");
    if (shapeType != "rectangle")
        fail(shape,
             "the nlos_capture_meter's relay wall must be a rectangle (tpb's relay wall is a quad; mitransient "
             "recommends a rectangle too): use <shape type=\"rectangle\"> placed by its to_world");
    nlos_.present = true;
    nlos_.sensor = sensor;
    nlos_.shape = shape;
    nlos_.wall = static_cast<int>(d_.shapes.size()) - 1;
    loc("camera", sensor);
    loc("camera.wall", shape);
    bool film = false;
    for (Elem& o : p.objects()) {
        if (o.tag() == "film") {
            if (film) fail(o, "a sensor has one film");
            film = true;
            p.took(o);
            readFilm(o, true);
        } else if (o.tag() == "sampler") {
            readSampler(p, o);
        }
    }
    if (!film) {  // Mitsuba's default hdrfilm
        d_.camera.width = 768;
        d_.camera.height = 576;
        loc("camera.resolution", sensor);
    }
    if (const std::optional<Vec3> o = p.point("sensor_origin")) {
        checkPoint(*p.find("sensor_origin"), *o, "sensor_origin");
        d_.camera.position = *o;
        nlos_.origin = *p.find("sensor_origin");
        loc("camera.position", *nlos_.origin);
    } else {
        d_.camera.position = Vec3(0.0);  // mitransient's default
        loc("camera.position", sensor);
    }
    // One point of a sequential confocal scan (tal's simultaneous_scan false): a 1 x 1 film, the
    // scan's size in original_film_width/height.
    const std::optional<int64_t> ow = p.integer("original_film_width"), oh = p.integer("original_film_height");
    if (ow || oh) {
        const Elem& at = *p.find(ow ? "original_film_width" : "original_film_height");
        if (!ow || !oh) fail(at, "give both original_film_width and original_film_height (a confocal scan's size)");
        if (*ow < 1 || *oh < 1 || *ow > INT_MAX || *oh > INT_MAX || *ow * *oh > INT_MAX)
            fail(at, "original_film_width and original_film_height must be integers >= 1");
        if (d_.camera.width != 1 || d_.camera.height != 1)
            fail(at,
                 "original_film_width/height mean a confocal capture of one point per render, with a 1 x 1 "
                 "film (mitransient refuses others); make the film 1 x 1, or remove them");
        nlos_.original = at;
        nlos_.originalW = static_cast<int>(*ow);
        nlos_.originalH = static_cast<int>(*oh);
    }
    // Aims of the laser: mitransient aims it from Python (mitransient.nlos.focus_emitter_at_relay_wall_*);
    // mitsuba2-transient-nlos wrote them on the sensor, as tpb reads them.
    if (const std::optional<Vec3> v = p.point("laser_lookat_pixel")) {
        nlos_.lookatPixel = *p.find("laser_lookat_pixel");
        nlos_.lookatPixelV = *v;
    }
    if (const std::optional<Vec3> v = p.point("laser_lookat_3d")) {
        nlos_.lookat3d = *p.find("laser_lookat_3d");
        nlos_.lookat3dV = *v;
    }
    if (nlos_.lookatPixel && nlos_.lookat3d)
        fail(*nlos_.lookat3d, "give laser_lookat_pixel or laser_lookat_3d, not both");
    if (const std::optional<Vec3> v = p.point("laser_origin")) {
        checkPoint(*p.find("laser_origin"), *v, "laser_origin");
        nlos_.laserOrigin = *p.find("laser_origin");
        nlos_.laserOriginV = *v;
    }
    if (const Elem* a = p.find("account_first_and_last_bounces"))
        warn(*a,
             "deprecated on the nlos_capture_meter, and ignored by mitransient as by tpb: the time origin is the "
             "transient_nlos_path integrator's account_first_and_last_bounces (default false)");
    if (const Elem* c = p.find("confocal"))
        warn(*c,
             "mitsuba2-transient-nlos's parameter, ignored by mitransient as by tpb: set capture_type on the "
             "transient_nlos_path integrator (single, confocal, exhaustive)");
    p.finish();
}

// The relay-wall camera and its scan, once the integrator and the emitters are read.
void Importer::finishNlos() {
    if (!nlos_.present) {
        if (nlosInt_.captureElem)
            warn(*nlosInt_.captureElem, "capture_type has no effect: the scene has no nlos_capture_meter (relay wall)");
        return;
    }
    CameraDesc& cam = d_.camera;
    cam.type = CameraType::RelayWall;
    cam.wallShape = nlos_.wall;
    const bool nlosPath = nlosInt_.type == "transient_nlos_path";
    // mitransient's account_first_and_last_bounces (transient_nlos_path, default false): true counts
    // the laser -> wall and wall -> sensor legs (tpb's "sensor" origin), false leaves both out
    // (tpb's "wall"). Other integrators (transient_path) count every segment.
    const bool account = nlosPath ? nlosInt_.account.value_or(false) : true;
    cam.timeOrigin = account ? WallTimeOrigin::Sensor : WallTimeOrigin::Wall;
    loc("camera.time_origin", nlosInt_.accountElem ? *nlosInt_.accountElem : nlos_.sensor);
    ScanMode mode = nlosPath ? nlosInt_.capture.value_or(ScanMode::Single) : ScanMode::Single;
    if (nlos_.original) {
        if (mode != ScanMode::Confocal)
            fail(*nlos_.original, std::string("original_film_width/height are for confocal captures, but the "
                                              "capture is ") +
                                      scanModeName(mode) +
                                      ": set <string name=\"capture_type\" value=\"confocal\"/> on the "
                                      "transient_nlos_path integrator, or remove them");
        cam.width = nlos_.originalW;
        cam.height = nlos_.originalH;
        warn(*nlos_.original, "one confocal point per render (tal's simultaneous_scan false): tpb renders the whole " +
                                  std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                                  " confocal scan into one film");
    }
    const auto badLight = [&](int i) -> const Elem& { return lightElems_.at(static_cast<size_t>(i)); };
    // The laser: the emitter with id "laser" (mitransient's and tal's convention), else the only projector.
    int laser = -1;
    for (size_t i = 0; i < d_.lights.size(); ++i)
        if (d_.lights[i].name == "laser") laser = static_cast<int>(i);
    if (laser >= 0 && d_.lights[static_cast<size_t>(laser)].type != LightType::Laser)
        fail(badLight(laser), std::string("the NLOS laser (id \"laser\") is a ") +
                                  lightTypeName(d_.lights[static_cast<size_t>(laser)].type) +
                                  " light; tpb maps a projector to its laser: make it <emitter type=\"projector\" "
                                  "id=\"laser\"> with a small fov");
    if (laser < 0 && projectors_.size() > 1)
        fail(projectors_[1].e, "several projectors and none has id=\"laser\": give the NLOS laser id=\"laser\"");
    if (laser < 0 && projectors_.size() == 1) laser = projectors_[0].light;
    if (laser < 0) {
        if (mode != ScanMode::Single)
            fail(nlosInt_.captureElem ? *nlosInt_.captureElem : nlos_.sensor,
                 std::string("a ") + scanModeName(mode) +
                     " capture needs its laser: add <emitter type=\"projector\" id=\"laser\"> (a small fov) with "
                     "its to_world at the laser's position");
        for (const std::optional<Elem>& x : {nlos_.lookatPixel, nlos_.lookat3d, nlos_.laserOrigin})
            if (x) warn(*x, "no effect: the scene has no laser (a projector)");
        cam.scan = ScanMode::None;  // the scene's lights as they are
        return;
    }
    const Projector* proj = nullptr;
    for (const Projector& pr : projectors_)
        if (pr.light == laser) proj = &pr;
    LightDesc& L = d_.lights[static_cast<size_t>(laser)];
    const Elem& laserElem = badLight(laser);
    L.name = "laser";
    cam.scan = mode;
    cam.scanLaser = laser;
    loc("camera.scan.laser", laserElem);
    if (nlos_.laserOrigin) {  // mitsuba2-transient-nlos: the laser's position on the sensor
        const ShapeDesc& w = d_.shapes[static_cast<size_t>(nlos_.wall)];
        const double size = std::max(glm::length(w.edgeU), glm::length(w.edgeV));
        if (proj->toWorld && glm::length(L.position - nlos_.laserOriginV) > 1e-9 * size)
            fail(*nlos_.laserOrigin, "laser_origin differs from the laser's to_world (line " +
                                         std::to_string(proj->toWorld->line()) + "): remove one of them");
        L.position = nlos_.laserOriginV;
    }
    const ShapeDesc& w = d_.shapes[static_cast<size_t>(nlos_.wall)];
    if (mode != ScanMode::Single) {
        for (const std::optional<Elem>& x : {nlos_.lookatPixel, nlos_.lookat3d})
            if (x)
                warn(*x, std::string("no effect: a ") + scanModeName(mode) + " capture aims the laser at " +
                             (mode == ScanMode::Confocal ? "every sensor point" : "its grid"));
    }
    if (mode == ScanMode::Exhaustive) {
        if (!nlosInt_.forceEqual)
            fail(*nlosInt_.forceEqualElem,
                 "force_equal_illumination_scanning false makes mitransient's laser points a grid of directions "
                 "within illumination_scan_fov of the projector, which tpb's exhaustive scan (a grid of cells of the "
                 "relay wall) cannot reproduce; set it to true (the laser grid is then laser_scan_width x "
                 "laser_scan_height cells of the wall)");
        cam.laserGridX = nlos_.laserScanW > 0 ? nlos_.laserScanW : cam.width;
        cam.laserGridY = nlos_.laserScanH > 0 ? nlos_.laserScanH : cam.height;
        if (nlos_.exhaustiveFilm && (cam.laserGridX != cam.width || cam.laserGridY != cam.height))
            fail(*nlos_.laserScan, "laser_scan_width x laser_scan_height (" + std::to_string(cam.laserGridX) + " x " +
                                       std::to_string(cam.laserGridY) + ") must equal the film's width x height (" +
                                       std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                                       ") with force_equal_illumination_scanning (mitransient refuses others); make "
                                       "them equal");
        if (!nlos_.exhaustiveFilm)
            warn(nlos_.film.node ? nlos_.film : nlos_.sensor,
                 "exhaustive_scan is false: one laser point per render (tal's simultaneous_scan false); tpb renders "
                 "all " +
                     std::to_string(cam.laserGridX) + " x " + std::to_string(cam.laserGridY) +
                     " laser points into one film (one sensor image per laser point)");
        return;
    }
    if (mode != ScanMode::Single) return;
    // A single laser point: (u, v) on the wall, from laser_lookat_pixel, laser_lookat_3d or the aim of
    // the projector's to_world.
    const Vec3 U = w.edgeU, V = w.edgeV, N = glm::cross(U, V);
    const double size = std::max(glm::length(U), glm::length(V));
    const auto uvOf = [&](const Vec3& q, double& u, double& v) {
        u = glm::dot(q - w.corner, U) / glm::dot(U, U);
        v = glm::dot(q - w.corner, V) / glm::dot(V, V);
    };
    double u = 0.5, v = 0.5;
    const Elem* aim = nullptr;
    if (nlos_.lookatPixel) {  // mitransient.nlos.focus_emitter_at_relay_wall_pixel: uv = pixel / film size
        aim = &*nlos_.lookatPixel;
        u = nlos_.lookatPixelV.x / cam.width;
        v = nlos_.lookatPixelV.y / cam.height;
    } else if (nlos_.lookat3d) {  // focus_emitter_at_relay_wall_3dpoint
        aim = &*nlos_.lookat3d;
        if (std::fabs(glm::dot(nlos_.lookat3dV - w.corner, glm::normalize(N))) > 1e-6 * size)
            fail(*aim, "laser_lookat_3d is not on the relay wall's plane; give a point of the wall");
        uvOf(nlos_.lookat3dV, u, v);
    } else {
        const double den = glm::dot(L.direction, N);
        const double t = den != 0.0 ? glm::dot(w.corner - L.position, N) / den : -1.0;
        bool hit = false;
        if (t > 0.0) {
            uvOf(L.position + t * L.direction, u, v);
            hit = u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0;
        }
        if (!hit) {
            if (!proj->translationOnly)
                fail(*proj->toWorld,
                     "the laser's to_world aims at no point of the relay wall \"" + w.name +
                         "\"; aim it with <lookat origin=... target=\"a point of the wall\"/>, or give the "
                         "nlos_capture_meter <point name=\"laser_lookat_pixel\" x=... y=... z=\"0\"/>");
            u = v = 0.5;
            warn(proj->toWorld ? *proj->toWorld : laserElem,
                 "the laser is not aimed in the file (mitransient and tal aim it from Python, tal by default at "
                 "the wall's centre): aimed at the centre of the relay wall \"" +
                     w.name +
                     "\"; for another point give the nlos_capture_meter <point name=\"laser_lookat_pixel\" x=... "
                     "y=... z=\"0\"/> (film pixels) or laser_lookat_3d, or a <lookat> in the projector's to_world");
        }
    }
    if (!(u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0)) {
        char at[96];
        std::snprintf(at, sizeof at, "(u, v) = (%.4g, %.4g)", u, v);
        fail(*aim, std::string("the laser's aim lies outside the relay wall: ") + at +
                       " (laser_lookat_pixel is in film pixels, 0..width and 0..height); aim inside the wall");
    }
    cam.scanPointU = u;
    cam.scanPointV = v;
    const Vec3 target = w.corner + u * U + v * V;
    if (glm::length(target - L.position) > 0.0) L.direction = glm::normalize(target - L.position);
}

void Importer::run(const std::string& text, const std::string& path) {
    d_.path = path;
    d_.dir = fs::path(path).parent_path().string();
    if (d_.dir.empty()) d_.dir = ".";
    const XmlFile& f = parse(text, path);
    const pugi::xml_node root = f.doc.document_element();
    const Elem rootE{root, &f};
    if (!root || std::string(root.name()) != "scene")
        throw UserError(path, root ? rootE.line() : 1, "",
                        "a Mitsuba scene is a <scene version=\"3.0.0\"> element" +
                            (root ? ", got <" + std::string(root.name()) + ">" : std::string()));
    if (const pugi::xml_attribute v = root.attribute("version"); !v)
        warn(rootE, "no version attribute; read as Mitsuba 3 (write <scene version=\"3.0.0\">)");
    else if (std::string(v.value()).rfind("3.", 0) != 0)
        warn(rootE,
             "written for Mitsuba " + std::string(v.value()) + "; read as Mitsuba 3 (parameter names may differ)");
    loc("version", rootE);

    std::vector<Elem> top;
    std::vector<std::string> stack{path};
    collect(rootE, top, stack);
    for (const Elem& e : top) registerIds(e);
    for (const Elem& e : top)
        if (e.tag() == "shape")
            for (pugi::xml_node c = e.node.child("sensor"); c; c = c.next_sibling("sensor")) captureMeterAhead_ = true;
    for (const Elem& e : top) {
        const std::string tag = e.tag();
        if (tag == "sensor")
            readSensor(e);
        else if (tag == "integrator")
            readIntegrator(e);
        else if (tag == "shape")
            readShape(e);
        else if (tag == "emitter")
            readEmitter(e, nullptr, nullptr, false);
        else if (tag == "bsdf")
            material(e);
        else if (tag == "medium")
            medium(e);
        else if (tag == "texture")
            fail(e, "textures are not supported (tpb's materials are uniform colours)");
        else
            fail(e, "unknown or unsupported element <" + tag +
                        "> in a scene; tpb imports sensor, integrator, shape, "
                        "emitter, bsdf, medium, default, include");
    }
    finishNlos();
    if (!haveSensor_ && !nlos_.present)
        d_.warnings.push_back(path + ": the scene has no sensor: tpb's default camera is used");
    if (d_.lights.empty()) d_.warnings.push_back(path + ": the scene has no emitters: the image will be black");
    for (const auto& [e, m] : exteriorChecks_)
        if (m != d_.globalMedium)
            warn(e, "medium \"" + d_.media[m].name + "\" is not the sensor's medium" +
                        (d_.globalMedium >= 0 ? " (\"" + d_.media[d_.globalMedium].name + "\")" : " (none)") +
                        ": tpb takes the medium outside shapes (and around lights) from the regions they are in "
                        "(the sensor's medium fills the outside), so this medium is not used here");
}

}  // namespace

SceneDesc loadMitsubaSceneFromString(const std::string& text, const std::string& virtualPath,
                                     const MitsubaOptions& options) {
    SceneDesc desc;
    Importer im(desc, options);
    im.run(text, virtualPath);
    return desc;
}

SceneDesc loadMitsubaScene(const std::string& path, const MitsubaOptions& options) {
    return loadMitsubaSceneFromString(readSceneFile(path), path, options);
}

}  // namespace tpb
