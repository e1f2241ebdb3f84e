// Wavefront OBJ to TriangleMesh via tinyobjloader (Debian package; a maintained, header-only
// parser that triangulates polygons). Vertices are shared by (position, normal, texcoord)
// index triple; per-vertex shading normals are used when every face provides them.
#pragma once

#include <string>

#include "lib/geometry/transform.h"
#include "lib/geometry/triangle_mesh.h"

namespace tb {

// Throws std::runtime_error naming the file on a parse error or an empty mesh.
TriangleMesh load_obj(const std::string& path, const AffineTransform& to_world = {}, bool flip_normal = false);
// The same from OBJ text (tests, embedded scenes).
TriangleMesh load_obj_from_string(const std::string& obj_text, const AffineTransform& to_world = {},
                                  bool flip_normal = false);

}  // namespace tb
