// A small PLY reader (Stanford polygon files) for the meshes of Mitsuba scenes: formats "ascii 1.0"
// and "binary_little_endian 1.0"; the "vertex" element's x, y, z (any scalar type) and the "face"
// element's vertex_indices (or vertex_index) list, polygons triangulated as fans. Every other
// element and property is skipped (read past, by its declared type); normals and colours are not
// used (flat shading). Degenerate triangles are dropped like the OBJ loader's.
#pragma once
#include "scene/mesh.h"
#include <string>

namespace tpb {

// Throws UserError naming the file (and, for the header and ascii data, the line) on a missing,
// unreadable, truncated or malformed file, big-endian data, an index out of range, a coordinate
// that is not finite or beyond +-kMaxSceneCoordinateM, or a mesh without triangles.
TriangleMesh loadPly(const std::string& path, size_t* droppedDegenerate = nullptr);
// Same, from the bytes of a file (`path` names it in messages).
TriangleMesh parsePly(const std::string& bytes, const std::string& path, size_t* droppedDegenerate = nullptr);

}  // namespace tpb
