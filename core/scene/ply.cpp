// PLY reader: header, then the elements in their declared order, ascii or binary little-endian.
#include "scene/ply.h"

#include "base/error.h"
#include "scene/scene_desc.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace tpb {

namespace {

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool scalarOf(const std::string& name, Scalar& s) {
    static const std::pair<const char*, Scalar> kNames[] = {
        {"char", Scalar::Int8},      {"int8", Scalar::Int8},       {"uchar", Scalar::UInt8},
        {"uint8", Scalar::UInt8},    {"short", Scalar::Int16},     {"int16", Scalar::Int16},
        {"ushort", Scalar::UInt16},  {"uint16", Scalar::UInt16},   {"int", Scalar::Int32},
        {"int32", Scalar::Int32},    {"uint", Scalar::UInt32},     {"uint32", Scalar::UInt32},
        {"float", Scalar::Float32},  {"float32", Scalar::Float32}, {"double", Scalar::Float64},
        {"float64", Scalar::Float64}};
    for (const auto& [n, v] : kNames)
        if (name == n) {
            s = v;
            return true;
        }
    return false;
}

size_t sizeOf(Scalar s) {
    switch (s) {
        case Scalar::Int8:
        case Scalar::UInt8: return 1;
        case Scalar::Int16:
        case Scalar::UInt16: return 2;
        case Scalar::Int32:
        case Scalar::UInt32:
        case Scalar::Float32: return 4;
        case Scalar::Float64: return 8;
    }
    return 1;
}

struct Property {
    std::string name;
    Scalar type = Scalar::Float32;
    bool list = false;
    Scalar countType = Scalar::UInt8;
};

struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> props;
    int line = 0;
};

// Reads values one at a time from the data section, ascii tokens or little-endian binary.
class Reader {
public:
    Reader(const std::string& bytes, size_t pos, bool ascii, int line, const std::string& path)
        : b_(bytes), pos_(pos), ascii_(ascii), line_(line), path_(path) {}

    double value(Scalar t) {
        if (ascii_) return token();
        const size_t n = sizeOf(t);
        if (pos_ + n > b_.size()) fail("the file ends inside the data (truncated binary PLY)");
        unsigned char raw[8];
        std::memcpy(raw, b_.data() + pos_, n);  // little-endian host (x86-64, aarch64)
        pos_ += n;
        switch (t) {
            case Scalar::Int8: {
                int8_t v;
                std::memcpy(&v, raw, 1);
                return v;
            }
            case Scalar::UInt8: return raw[0];
            case Scalar::Int16: {
                int16_t v;
                std::memcpy(&v, raw, 2);
                return v;
            }
            case Scalar::UInt16: {
                uint16_t v;
                std::memcpy(&v, raw, 2);
                return v;
            }
            case Scalar::Int32: {
                int32_t v;
                std::memcpy(&v, raw, 4);
                return v;
            }
            case Scalar::UInt32: {
                uint32_t v;
                std::memcpy(&v, raw, 4);
                return v;
            }
            case Scalar::Float32: {
                float v;
                std::memcpy(&v, raw, 4);
                return v;
            }
            case Scalar::Float64: {
                double v;
                std::memcpy(&v, raw, 8);
                return v;
            }
        }
        return 0.0;
    }
    [[noreturn]] void fail(const std::string& message) const {
        throw UserError(path_, ascii_ ? line_ : 0, "", message);
    }

private:
    double token() {
        while (pos_ < b_.size() && (b_[pos_] == ' ' || b_[pos_] == '\t' || b_[pos_] == '\r' || b_[pos_] == '\n')) {
            if (b_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= b_.size()) fail("the file ends inside the data (fewer values than the header declares)");
        size_t end = pos_;
        while (end < b_.size() && !std::isspace(static_cast<unsigned char>(b_[end]))) ++end;
        double v = 0.0;
        const auto [ptr, ec] = std::from_chars(b_.data() + pos_, b_.data() + end, v);
        if (ec != std::errc() || ptr != b_.data() + end)
            fail("\"" + b_.substr(pos_, std::min<size_t>(end - pos_, 32)) + "\" is not a number");
        pos_ = end;
        return v;
    }

    const std::string& b_;
    size_t pos_;
    bool ascii_;
    int line_;
    const std::string& path_;
};

}  // namespace

TriangleMesh parsePly(const std::string& bytes, const std::string& path, size_t* droppedDegenerate) {
    const auto fail = [&](int line, const std::string& m) -> void { throw UserError(path, line, "", m); };
    // ---- header ----
    size_t pos = 0;
    int line = 0;
    bool ascii = false, sawFormat = false, ended = false;
    std::vector<Element> elements;
    while (pos < bytes.size() && !ended) {
        size_t end = bytes.find('\n', pos);
        if (end == std::string::npos) end = bytes.size();
        std::string text = bytes.substr(pos, end - pos);
        if (!text.empty() && text.back() == '\r') text.pop_back();
        pos = end + 1;
        ++line;
        std::istringstream ss(text);
        std::string word;
        ss >> word;
        if (line == 1) {
            if (word != "ply") fail(1, "not a PLY file (the first line must be \"ply\")");
            continue;
        }
        if (word.empty() || word == "comment" || word == "obj_info") continue;
        if (word == "format") {
            std::string f, version;
            ss >> f >> version;
            if (f == "ascii")
                ascii = true;
            else if (f == "binary_big_endian")
                fail(line, "binary_big_endian PLY is not supported; convert it to binary_little_endian or ascii");
            else if (f != "binary_little_endian")
                fail(line, "unknown PLY format \"" + f + "\"");
            sawFormat = true;
        } else if (word == "element") {
            Element e;
            e.line = line;
            long long n = -1;
            ss >> e.name >> n;
            if (e.name.empty() || n < 0) fail(line, "malformed element line (expected \"element <name> <count>\")");
            e.count = static_cast<uint64_t>(n);
            elements.push_back(e);
        } else if (word == "property") {
            if (elements.empty()) fail(line, "a property before any element");
            Property p;
            std::string t;
            ss >> t;
            if (t == "list") {
                std::string ct, it;
                ss >> ct >> it >> p.name;
                p.list = true;
                if (!scalarOf(ct, p.countType) || !scalarOf(it, p.type)) fail(line, "unknown list property type");
            } else {
                ss >> p.name;
                if (!scalarOf(t, p.type)) fail(line, "unknown property type \"" + t + "\"");
            }
            if (p.name.empty()) fail(line, "a property without a name");
            elements.back().props.push_back(p);
        } else if (word == "end_header") {
            ended = true;
        } else {
            fail(line, "unknown header line \"" + word + "\"");
        }
    }
    if (!ended) fail(line, "the header has no end_header line");
    if (!sawFormat) fail(line, "the header has no format line");

    // ---- data ----
    TriangleMesh mesh;
    size_t dropped = 0;
    Reader rd(bytes, pos, ascii, line + 1, path);
    std::vector<std::vector<uint32_t>> polygons;
    bool haveVertices = false;
    for (const Element& e : elements) {
        const bool isVertex = e.name == "vertex", isFace = e.name == "face";
        int ix = -1, iy = -1, iz = -1, ii = -1;
        for (size_t k = 0; k < e.props.size(); ++k) {
            const std::string& n = e.props[k].name;
            if (isVertex && !e.props[k].list) {
                if (n == "x") ix = int(k);
                if (n == "y") iy = int(k);
                if (n == "z") iz = int(k);
            }
            if (isFace && e.props[k].list && (n == "vertex_indices" || n == "vertex_index")) ii = int(k);
        }
        if (isVertex) {
            if (ix < 0 || iy < 0 || iz < 0) fail(e.line, "the vertex element has no x, y and z properties");
            if (e.count > (1ull << 31)) fail(e.line, "too many vertices");
            mesh.positions.reserve(e.count);
            haveVertices = true;
        }
        if (isFace && ii < 0) fail(e.line, "the face element has no vertex_indices list");
        if (!ascii && e.count > bytes.size()) fail(e.line, "the element count is larger than the file");
        for (uint64_t r = 0; r < e.count; ++r) {
            double xyz[3] = {0, 0, 0};
            for (size_t k = 0; k < e.props.size(); ++k) {
                const Property& p = e.props[k];
                if (p.list) {
                    const double cnt = rd.value(p.countType);
                    if (!(cnt >= 0 && cnt <= 1e6) || cnt != std::floor(cnt)) rd.fail("bad list length in " + e.name);
                    std::vector<uint32_t> idx;
                    for (int j = 0; j < int(cnt); ++j) {
                        const double v = rd.value(p.type);
                        if (int(k) == ii) {
                            if (!(v >= 0 && v < 4294967296.0) || v != std::floor(v))
                                rd.fail("face " + std::to_string(r) + ": bad vertex index");
                            idx.push_back(static_cast<uint32_t>(v));
                        }
                    }
                    if (int(k) == ii) polygons.push_back(std::move(idx));
                } else {
                    const double v = rd.value(p.type);
                    if (isVertex && (int(k) == ix || int(k) == iy || int(k) == iz))
                        xyz[int(k) == ix ? 0 : int(k) == iy ? 1 : 2] = v;
                }
            }
            if (isVertex) {
                for (double c : xyz)
                    if (!(std::fabs(c) <= kMaxSceneCoordinateM))
                        rd.fail("vertex " + std::to_string(r) + ": coordinate " + std::to_string(c) +
                                " is not finite or beyond +-1e9 m");
                mesh.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
            }
        }
    }
    if (!haveVertices) fail(0, "the file has no vertex element");
    const size_t nv = mesh.positions.size();
    for (size_t f = 0; f < polygons.size(); ++f) {
        const std::vector<uint32_t>& p = polygons[f];
        for (uint32_t i : p)
            if (i >= nv)
                fail(0, "face " + std::to_string(f) + " refers to vertex " + std::to_string(i) + " of " +
                            std::to_string(nv));
        for (size_t j = 1; j + 1 < p.size(); ++j) {
            const Vec3 a = mesh.positions[p[0]], b = mesh.positions[p[j]], c = mesh.positions[p[j + 1]];
            const Vec3 e1 = b - a, e2 = c - a, e3 = c - b;
            const double longest2 = std::max({glm::dot(e1, e1), glm::dot(e2, e2), glm::dot(e3, e3)});
            if (!(glm::length(glm::cross(e1, e2)) > 1e-12 * longest2)) {
                ++dropped;
                continue;
            }
            mesh.triangles.emplace_back(p[0], p[j], p[j + 1]);
        }
    }
    if (droppedDegenerate) *droppedDegenerate = dropped;
    if (mesh.triangles.empty()) fail(0, "the mesh has no (non-degenerate) triangles");
    return mesh;
}

TriangleMesh loadPly(const std::string& path, size_t* droppedDegenerate) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path, 0, "", std::string("cannot open mesh file (") + std::strerror(errno) + ")");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw UserError(path, 0, "", "cannot read mesh file");
    return parsePly(ss.str(), path, droppedDegenerate);
}

}  // namespace tpb
