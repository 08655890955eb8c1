// Triangle meshes: OBJ loading through tinyobjloader, transforms, and the tessellated analytic
// shapes (quad, box).
// GCC 12 reports a spurious -Wrestrict inside libstdc++'s `"literal" + std::string&&` once
// UserError's "file:line" formatting is inlined here (GCC bug 105329). The warning is attributed
// to the libstdc++ header, so it can only be silenced around the includes.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wrestrict"
#endif
#include "scene/mesh.h"
#include "scene/ply.h"
#include "base/error.h"
#include "base/text.h"
#include "scene/scene_desc.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <array>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12
#pragma GCC diagnostic pop
#endif

namespace tpb {

static_assert(kMaxSceneCoordinateM == 1e9, "the messages below say 1e9 m");

Bounds3 TriangleMesh::bounds() const {
    // Over the referenced vertices only: unused vertices do not make the mesh bigger.
    Bounds3 b;
    const size_t n = positions.size();
    for (const glm::uvec3& t : triangles)
        for (int k = 0; k < 3; ++k)
            if (t[k] < n) b.expand(positions[t[k]]);
    return b;
}

void TriangleMesh::transform(const Mat4& objectToWorld) {
    for (size_t i = 0; i < positions.size(); ++i) {
        Vec3& p = positions[i];
        p = Vec3(objectToWorld * glm::dvec4(p, 1.0));
        if (!(std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) <= kMaxSceneCoordinateM)) {
            char at[96];
            std::snprintf(at, sizeof at, "(%.3g, %.3g, %.3g)", p.x, p.y, p.z);
            throw UserError(std::string("the shape's \"transform\" moves a vertex of the mesh to ") + at +
                            ", beyond +-1e9 m (the limit of scene coordinates); use a smaller scale or translation");
        }
    }

    const glm::dmat3 linear(objectToWorld);
    const double det = glm::determinant(linear);
    if (!normals.empty()) {
        if (det != 0.0 && std::isfinite(det)) {
            const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear));
            for (Vec3& n : normals) {
                const Vec3 m = normalMatrix * n;
                const double len = glm::length(m);
                n = len > 0.0 && std::isfinite(len) ? m / len : n;
            }
        } else {
            normals.clear();  // singular transform: no meaningful normals, shade flat
        }
    }
    // A mirroring transform reverses the orientation of every triangle; swap the winding so that
    // the geometric normal cross(e1, e2) keeps facing the side the normals (and "outside") face.
    if (det < 0.0)
        for (glm::uvec3& t : triangles) std::swap(t.y, t.z);
}

void TriangleMesh::flip() {
    for (glm::uvec3& t : triangles) std::swap(t.y, t.z);
    for (Vec3& n : normals) n = -n;
}

namespace {

std::string trimmed(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ' || s.back() == '.')) s.pop_back();
    // tinyobj separates messages with newlines; keep one line per message.
    std::replace(s.begin(), s.end(), '\n', ' ');
    return s;
}

// tinyobj reports "... line 12.)": recover the line number for the error position.
int lineOf(const std::string& message) {
    for (size_t at = message.find("line "); at != std::string::npos; at = message.find("line ", at + 1)) {
        size_t i = at + 5;
        long value = 0;
        while (i < message.size() && message[i] >= '0' && message[i] <= '9' && value < 100000000)
            value = value * 10 + (message[i++] - '0');
        if (i > at + 5) return int(value);
    }
    return 0;
}

// Zero area up to rounding: |e1 x e2| below a tiny fraction of the squared longest edge also
// catches collinear vertices whose cross product is only rounding noise.
bool isDegenerate(const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 e1 = b - a, e2 = c - a, e3 = c - b;
    const double area2 = glm::length(glm::cross(e1, e2));
    const double longest2 = std::max({glm::dot(e1, e1), glm::dot(e2, e2), glm::dot(e3, e3)});
    return !(area2 > 1e-12 * longest2);
}

// All loader errors name the file (and the line when tinyobj gives one).
[[noreturn]] void objError(const std::string& path, int line, const std::string& message) {
    throw UserError(path, line, std::string(), message);
}

// tinyobj reads a face's indices as int without a range check: 2^40 wrapped to 0 and was reported
// as "zero value". Each index of an "f" line (v, v/t, v//n, v/t/n) must be a non-zero integer
// within int (negative ones count back from the last vertex); the message names the line.
void checkFaceLine(const std::string& path, int line, int verticesSoFar, const char* p, const char* e) {
    while (p < e) {
        while (p < e && (*p == ' ' || *p == '\t' || *p == '\r' || *p == '/')) ++p;
        const char* t = p;
        while (p < e && *p != ' ' && *p != '\t' && *p != '\r' && *p != '/') ++p;
        if (p == t) continue;
        const std::string token(t, p);
        if (token[0] == '#') return;  // a comment ends the line
        long long index = 0;
        const char* digits = token.data() + (token[0] == '+' ? 1 : 0);
        const auto [end, ec] = std::from_chars(digits, token.data() + token.size(), index);
        const std::string where = "corrupt OBJ file: face (\"f\" line " + std::to_string(line) + ")";
        if (ec == std::errc::result_out_of_range || (ec == std::errc() && (index > INT_MAX || index < -INT_MAX)))
            objError(path, line,
                     where + ": index " + clipped(token) + " is beyond the largest OBJ index tpb reads (" +
                         std::to_string(INT_MAX) + "); the file has " + std::to_string(verticesSoFar) +
                         " vertices before this line");
        if (ec != std::errc() || end != token.data() + token.size())
            objError(path, line, where + ": index \"" + clipped(token) + "\" is not an integer");
        if (index == 0)
            objError(path, line,
                     where +
                         ": index 0; OBJ indices start at 1 (negative ones count back from the last "
                         "vertex)");
    }
}

// tinyobj reads a coordinate it cannot parse ("nan", "inf", "1,5", garbage) as 0 and a missing one
// as 0, so a broken vertex silently moves to the origin (and a triangle of such vertices was then
// reported as "degenerate"). Check the first three coordinates of every "v" line first: numbers,
// finite as doubles and within the scene's coordinate limit, with the line they are on.
void checkVertexLines(const std::string& path, const std::string& text) {
    int line = 0, vertex = 0;
    size_t pos = 0;
    while (pos < text.size()) {
        ++line;
        size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        const char* p = text.data() + pos;
        const char* const e = text.data() + end;
        pos = end + 1;
        while (p < e && (*p == ' ' || *p == '\t')) ++p;
        if (e - p >= 2 && p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
            checkFaceLine(path, line, vertex, p + 2, e);
            continue;
        }
        if (e - p < 2 || p[0] != 'v' || (p[1] != ' ' && p[1] != '\t')) continue;
        ++vertex;
        p += 2;
        for (int k = 0; k < 3; ++k) {
            while (p < e && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
            const char* t = p;
            while (p < e && *p != ' ' && *p != '\t' && *p != '\r') ++p;
            const std::string token(t, p);
            const std::string where = "vertex " + std::to_string(vertex) + " (\"v\" line " + std::to_string(line) + ")";
            if (token.empty())
                objError(path, line, where + " has " + std::to_string(k) + " coordinates, expected x y z");
            char* stop = nullptr;
            errno = 0;
            const double v = std::strtod(token.c_str(), &stop);
            if (stop != token.c_str() + token.size())
                objError(path, line, where + " coordinate \"" + token + "\" is not a number");
            // strtod reads "nan" and "inf" literals, and 1e999 overflows to inf.
            if (!std::isfinite(v)) {
                const bool literal = token.find_first_of("nNiI") != std::string::npos;
                objError(path, line,
                         where + " has a non-finite coordinate (" + token +
                             (literal ? "" : ", beyond the range of a double") +
                             "); coordinates must be finite and within +-1e9 m");
            }
            if (!(std::fabs(v) <= kMaxSceneCoordinateM))
                objError(path, line,
                         where + " coordinate " + token +
                             " is beyond +-1e9 m, the limit of scene coordinates; "
                             "check the file's units, or scale the mesh with the shape's \"transform\"");
        }
    }
}

}  // namespace

TriangleMesh loadMeshFile(const std::string& path, size_t* droppedDegenerate) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".ply") return loadPly(path, droppedDegenerate);
    if (ext == ".obj") return loadObj(path, droppedDegenerate);
    // By its extension only: another format read as OBJ used to say "no triangles".
    objError(path, 0,
             "unsupported mesh format " + (ext.empty() ? std::string("(no extension)") : ext) +
                 "; supported: .obj (Wavefront OBJ), .ply (PLY, ASCII or binary); convert the mesh to one "
                 "of them (e.g. with Blender or MeshLab) or rename a file of that format");
}

TriangleMesh loadObj(const std::string& path, size_t* droppedDegenerate) {
    namespace fs = std::filesystem;
    if (droppedDegenerate) *droppedDegenerate = 0;

    std::error_code ec;
    if (!fs::exists(path, ec)) objError(path, 0, "OBJ file not found");
    if (fs::is_directory(path, ec)) objError(path, 0, "is a folder, expected an OBJ file");
    std::ifstream file(path, std::ios::binary);
    if (!file) objError(path, 0, std::string("cannot open OBJ file: ") + std::strerror(errno));
    std::ostringstream text;
    text << file.rdbuf();
    if (file.bad()) objError(path, 0, "read error while loading the OBJ file");
    checkVertexLines(path, text.str());
    std::istringstream in(text.str());

    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    // No material reader: materials come from the scene file, `mtllib` lines are ignored.
    const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr,
                                     /*triangulate=*/true, /*default_vcols_fallback=*/false);
    if (in.bad()) objError(path, 0, "read error while loading the OBJ file");
    if (!ok || !err.empty()) {
        const std::string msg = trimmed(err);
        objError(path, lineOf(msg), "corrupt OBJ file: " + (msg.empty() ? std::string("parse error") : msg));
    }
    // tinyobj only warns about bad indices (and silently skips such quads): make them errors.
    if (warn.find("Vertex indices out of bounds") != std::string::npos ||
        warn.find("invalid vertex index") != std::string::npos)
        objError(path, 0, "corrupt OBJ file: a face uses a vertex index out of range");
    if (warn.find("Vertex normal indices out of bounds") != std::string::npos)
        objError(path, 0, "corrupt OBJ file: a face uses a normal index out of range");

    const size_t nv = attrib.vertices.size() / 3;
    const size_t nn = attrib.normals.size() / 3;
    for (size_t i = 0; i < nv; ++i)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(attrib.vertices[3 * i + k]))
                objError(path, 0, "corrupt OBJ file: vertex " + std::to_string(i + 1) + " has a non-finite coordinate");
    auto vertex = [&](int i) {
        return Vec3(attrib.vertices[3 * i + 0], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]);
    };
    auto normal = [&](int i) {
        return Vec3(attrib.normals[3 * i + 0], attrib.normals[3 * i + 1], attrib.normals[3 * i + 2]);
    };

    // Collect the triangles (tinyobj already triangulated every polygon).
    struct Corner {
        int v, n;
    };
    std::vector<std::array<Corner, 3>> tris;
    size_t faces = 0, dropped = 0;
    for (const tinyobj::shape_t& shape : shapes) {
        const tinyobj::mesh_t& m = shape.mesh;
        size_t offset = 0;
        for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
            const size_t fv = m.num_face_vertices[f];
            if (offset + fv > m.indices.size()) break;  // defensive: malformed tinyobj output
            if (fv == 3) {
                ++faces;
                std::array<Corner, 3> tri;
                for (size_t k = 0; k < 3; ++k) {
                    const tinyobj::index_t& idx = m.indices[offset + k];
                    if (idx.vertex_index < 0 || size_t(idx.vertex_index) >= nv)
                        objError(path, 0,
                                 "corrupt OBJ file: vertex index " + std::to_string(idx.vertex_index + 1) +
                                     " out of range (the file has " + std::to_string(nv) + " vertices)");
                    if (idx.normal_index < -1 || idx.normal_index >= int(nn))
                        objError(path, 0,
                                 "corrupt OBJ file: normal index " + std::to_string(idx.normal_index + 1) +
                                     " out of range (the file has " + std::to_string(nn) + " normals)");
                    tri[k] = Corner{idx.vertex_index, idx.normal_index};
                }
                if (isDegenerate(vertex(tri[0].v), vertex(tri[1].v), vertex(tri[2].v)))
                    ++dropped;
                else
                    tris.push_back(tri);
            }
            offset += fv;
        }
    }
    if (droppedDegenerate) *droppedDegenerate = dropped;
    if (tris.empty()) {
        if (faces == 0) objError(path, 0, "the OBJ file contains no triangles");
        objError(path, 0, "all " + std::to_string(faces) + " triangles of the OBJ file are degenerate (zero area)");
    }

    // Vertex normals are used only when every corner has one, they are finite and non-zero, and
    // each position has a single normal (smooth shading). Per-face normals, partial or broken
    // normals: no normals (flat shading from the geometric normal).
    bool useNormals = true;
    std::vector<int> normalOf(nv, -1);
    auto unitNormal = [&](int i) {
        const Vec3 n = normal(i);
        const double len = glm::length(n);
        return len > 0.0 && std::isfinite(len) ? n / len : Vec3(0.0);
    };
    for (const auto& tri : tris) {
        for (const Corner& c : tri) {
            if (c.n < 0 || unitNormal(c.n) == Vec3(0.0)) {
                useNormals = false;
                break;
            }
            int& assigned = normalOf[c.v];
            if (assigned < 0)
                assigned = c.n;
            else if (assigned != c.n && glm::length(unitNormal(assigned) - unitNormal(c.n)) > 1e-6) {
                useNormals = false;
                break;
            }
        }
        if (!useNormals) break;
    }

    // Compact to the referenced vertices, keeping the file order.
    std::vector<uint32_t> remap(nv, UINT32_MAX);
    for (const auto& tri : tris)
        for (const Corner& c : tri) remap[c.v] = 0;
    TriangleMesh mesh;
    for (size_t i = 0; i < nv; ++i) {
        if (remap[i] == UINT32_MAX) continue;
        remap[i] = uint32_t(mesh.positions.size());
        mesh.positions.push_back(vertex(int(i)));
        if (useNormals) mesh.normals.push_back(unitNormal(normalOf[i]));
    }
    mesh.triangles.reserve(tris.size());
    for (const auto& tri : tris) mesh.triangles.emplace_back(remap[tri[0].v], remap[tri[1].v], remap[tri[2].v]);
    return mesh;
}

TriangleMesh makeQuad(const Vec3& corner, const Vec3& edgeU, const Vec3& edgeV) {
    TriangleMesh m;
    m.positions = {corner, corner + edgeU, corner + edgeU + edgeV, corner + edgeV};
    // Both triangles have normal along cross(edgeU, edgeV); they share the diagonal 0-2.
    m.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(0, 2, 3)};
    return m;
}

OpenEdges openEdges(const TriangleMesh& m) {
    // One id per distinct position (sorted, then equal neighbours share it).
    const size_t n = m.positions.size();
    std::vector<uint32_t> order(n), id(n);
    for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
    const auto key = [&](uint32_t i) {
        return std::array<double, 3>{m.positions[i].x, m.positions[i].y, m.positions[i].z};
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    uint32_t next = 0;
    for (size_t k = 0; k < n; ++k) {
        if (k > 0 && key(order[k]) != key(order[k - 1])) ++next;
        id[order[k]] = next;
    }
    // Every directed edge as (lower id, higher id) and its direction; an edge is matched when its
    // uses in both directions are as many.
    std::vector<std::pair<uint64_t, int>> edges;
    edges.reserve(3 * m.triangles.size());
    for (const glm::uvec3& t : m.triangles) {
        if (t.x >= n || t.y >= n || t.z >= n) continue;
        const uint32_t v[3] = {id[t.x], id[t.y], id[t.z]};
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) continue;
        for (int e = 0; e < 3; ++e) {
            const uint32_t a = v[e], b = v[(e + 1) % 3];
            edges.push_back({(uint64_t(std::min(a, b)) << 32) | std::max(a, b), a < b ? 1 : -1});
        }
    }
    std::sort(edges.begin(), edges.end());
    OpenEdges out;
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        int balance = 0;
        for (; j < edges.size() && edges[j].first == edges[i].first; ++j) balance += edges[j].second;
        if (balance != 0) ++(j - i == 1 ? out.holes : out.misfits);
        i = j;
    }
    return out;
}

TriangleMesh makeBox(const Vec3& lo, const Vec3& hi) {
    const Vec3 a = glm::min(lo, hi), b = glm::max(lo, hi);
    TriangleMesh m;
    // Vertex i has coordinate axis k at b[k] when bit k of i is set, else at a[k].
    for (uint32_t i = 0; i < 8; ++i)
        m.positions.emplace_back((i & 1) ? b.x : a.x, (i & 2) ? b.y : a.y, (i & 4) ? b.z : a.z);
    for (int axis = 0; axis < 3; ++axis) {
        const uint32_t bu = 1u << ((axis + 1) % 3), bv = 1u << ((axis + 2) % 3);
        for (int side = 0; side < 2; ++side) {
            const uint32_t base = side ? (1u << axis) : 0u;
            // Going base -> +u -> +u+v -> +v turns counter-clockwise around +axis, since
            // (axis, axis+1, axis+2) is a cyclic permutation of (x, y, z).
            uint32_t q[4] = {base, base | bu, base | bu | bv, base | bv};
            if (!side) std::swap(q[1], q[3]);  // the low face looks along -axis
            m.triangles.emplace_back(q[0], q[1], q[2]);
            m.triangles.emplace_back(q[0], q[2], q[3]);
        }
    }
    return m;
}

}  // namespace tpb
