// Triangle meshes: OBJ loading (tinyobjloader) and tessellation of the analytic shapes that are
// rendered as triangles (quad, box).
#pragma once
#include "base/math.h"
#include <cstdint>
#include <string>
#include <vector>

namespace tpb {

struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;          // per vertex, may be empty (then flat shading)
    std::vector<glm::uvec3> triangles;  // vertex indices
    Bounds3 bounds() const;
    // Positions and normals (inverse transpose). Throws UserError (no file:line: the caller adds
    // the shape's) when a vertex lands beyond +-kMaxSceneCoordinateM (scene_desc.h).
    void transform(const Mat4& objectToWorld);
    void flip();  // reverse winding and normals
};

// Loads a Wavefront OBJ file (triangulating polygons). Throws UserError naming the file on a
// missing, unreadable or corrupt file (also a vertex coordinate that is not a finite number or lies
// beyond +-kMaxSceneCoordinateM, with its line), or a mesh without triangles. Degenerate (zero-area)
// triangles are dropped and counted in `droppedDegenerate` if non-null.
TriangleMesh loadObj(const std::string& path, size_t* droppedDegenerate = nullptr);
// A mesh file by its extension (any case): ".ply" through loadPly (scene/ply.h), ".obj" through
// loadObj; any other extension is refused (UserError naming the supported ones).
TriangleMesh loadMeshFile(const std::string& path, size_t* droppedDegenerate = nullptr);

// The edges of a mesh that no other triangle walks the opposite way (vertices compared by position,
// so vertices split for normals still meet; triangles with a repeated vertex skipped). A mesh is
// closed and consistently oriented - the boundary of a solid, which a ray that enters must leave -
// iff there are none. `holes`: edges of one triangle only; `misfits`: edges shared by triangles
// that face opposite ways, or by more than two.
struct OpenEdges {
    int64_t holes = 0;
    int64_t misfits = 0;
    bool closed() const { return holes == 0 && misfits == 0; }
};
OpenEdges openEdges(const TriangleMesh& m);

// corner + s*edgeU + t*edgeV; two triangles, normal along cross(edgeU, edgeV).
TriangleMesh makeQuad(const Vec3& corner, const Vec3& edgeU, const Vec3& edgeV);
// Axis-aligned box [lo, hi], 12 triangles, normals facing out.
TriangleMesh makeBox(const Vec3& lo, const Vec3& hi);

}  // namespace tpb
