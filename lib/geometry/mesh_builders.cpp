#include "lib/geometry/mesh_builders.h"

#include <stdexcept>

namespace tb {

TriangleMesh make_uv_sphere_mesh(double radius, int n_theta, int n_phi, const Vec3& centre) {
  if (n_theta < 2 || n_phi < 3) throw std::invalid_argument("make_uv_sphere_mesh: too coarse");
  std::vector<Vec3> pos, nrm;
  std::vector<glm::uvec3> tris;
  // Rings 1 .. n_theta-1 plus two poles.
  pos.push_back(centre + Vec3(0, 0, -radius));
  nrm.emplace_back(0, 0, -1);
  for (int i = 1; i < n_theta; ++i) {
    const double theta = kPi * i / n_theta;
    for (int j = 0; j < n_phi; ++j) {
      const double phi = 2 * kPi * j / n_phi;
      const Vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -std::cos(theta));
      pos.push_back(centre + radius * n);
      nrm.push_back(n);
    }
  }
  const auto top = static_cast<uint32_t>(pos.size());
  pos.push_back(centre + Vec3(0, 0, radius));
  nrm.emplace_back(0, 0, 1);
  auto ring = [&](int i, int j) { return static_cast<uint32_t>(1 + (i - 1) * n_phi + (j % n_phi)); };
  for (int j = 0; j < n_phi; ++j) tris.emplace_back(0u, ring(1, j + 1), ring(1, j));
  for (int i = 1; i < n_theta - 1; ++i)
    for (int j = 0; j < n_phi; ++j) {
      tris.emplace_back(ring(i, j), ring(i, j + 1), ring(i + 1, j + 1));
      tris.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i + 1, j));
    }
  for (int j = 0; j < n_phi; ++j) tris.emplace_back(ring(n_theta - 1, j), ring(n_theta - 1, j + 1), top);
  return TriangleMesh(std::move(pos), std::move(tris), std::move(nrm));
}

TriangleMesh make_quad_mesh(double half_x, double half_y) {
  std::vector<Vec3> pos = {{-half_x, -half_y, 0}, {half_x, -half_y, 0}, {half_x, half_y, 0}, {-half_x, half_y, 0}};
  std::vector<glm::uvec3> tris = {{0u, 1u, 2u}, {0u, 2u, 3u}};
  return TriangleMesh(std::move(pos), std::move(tris));
}

}  // namespace tb
