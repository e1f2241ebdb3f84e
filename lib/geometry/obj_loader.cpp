#include "lib/geometry/obj_loader.h"

#include <map>
#include <stdexcept>
#include <tuple>

#include <tiny_obj_loader.h>

namespace tb {
namespace {

TriangleMesh to_mesh(const tinyobj::ObjReader& reader, const std::string& what, const AffineTransform& xf,
                     bool flip) {
  if (!reader.Valid()) throw std::runtime_error("OBJ " + what + ": " + reader.Error());
  const tinyobj::attrib_t& a = reader.GetAttrib();
  bool all_normals = true, all_uvs = true;
  for (const auto& shape : reader.GetShapes())
    for (const auto& idx : shape.mesh.indices) {
      all_normals = all_normals && idx.normal_index >= 0;
      all_uvs = all_uvs && idx.texcoord_index >= 0;
    }
  std::map<std::tuple<int, int, int>, uint32_t> vertex_of;
  std::vector<Vec3> pos, nrm;
  std::vector<Vec2> uv;
  std::vector<glm::uvec3> tris;
  const Mat3 normal_matrix = glm::transpose(xf.inverse_linear());
  for (const auto& shape : reader.GetShapes()) {
    const auto& m = shape.mesh;
    size_t offset = 0;
    for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
      const size_t nv = m.num_face_vertices[f];
      if (nv != 3) throw std::runtime_error("OBJ " + what + ": face not triangulated");
      glm::uvec3 tri;
      for (size_t k = 0; k < 3; ++k) {
        const tinyobj::index_t idx = m.indices[offset + k];
        const auto key = std::make_tuple(idx.vertex_index, all_normals ? idx.normal_index : -1,
                                         all_uvs ? idx.texcoord_index : -1);
        auto [it, inserted] = vertex_of.try_emplace(key, static_cast<uint32_t>(pos.size()));
        if (inserted) {
          const size_t vi = 3 * static_cast<size_t>(idx.vertex_index);
          pos.push_back(xf.point(Vec3(a.vertices[vi], a.vertices[vi + 1], a.vertices[vi + 2])));
          if (all_normals) {
            const size_t ni = 3 * static_cast<size_t>(idx.normal_index);
            nrm.push_back(glm::normalize(normal_matrix * Vec3(a.normals[ni], a.normals[ni + 1], a.normals[ni + 2])));
          }
          if (all_uvs) {
            const size_t ti = 2 * static_cast<size_t>(idx.texcoord_index);
            uv.emplace_back(a.texcoords[ti], a.texcoords[ti + 1]);
          }
        }
        tri[static_cast<int>(k)] = it->second;
      }
      tris.push_back(tri);
      offset += nv;
    }
  }
  if (tris.empty()) throw std::runtime_error("OBJ " + what + ": no triangles");
  return TriangleMesh(std::move(pos), std::move(tris), std::move(nrm), std::move(uv), flip);
}

}  // namespace

TriangleMesh load_obj(const std::string& path, const AffineTransform& to_world, bool flip_normal) {
  tinyobj::ObjReaderConfig cfg;
  cfg.triangulate = true;
  tinyobj::ObjReader reader;
  reader.ParseFromFile(path, cfg);
  return to_mesh(reader, path, to_world, flip_normal);
}

TriangleMesh load_obj_from_string(const std::string& obj_text, const AffineTransform& to_world, bool flip_normal) {
  tinyobj::ObjReaderConfig cfg;
  cfg.triangulate = true;
  tinyobj::ObjReader reader;
  reader.ParseFromString(obj_text, "", cfg);
  return to_mesh(reader, "<string>", to_world, flip_normal);
}

}  // namespace tb
