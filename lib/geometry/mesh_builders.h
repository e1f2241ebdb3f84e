// Procedural triangle meshes for tests and benchmarks.
#pragma once

#include "lib/geometry/triangle_mesh.h"

namespace tb {

// Latitude-longitude sphere of radius r about `centre` with n_theta bands and n_phi segments
// (2 n_phi (n_theta - 1) triangles), vertex normals = exact sphere normals.
TriangleMesh make_uv_sphere_mesh(double radius, int n_theta, int n_phi, const Vec3& centre = Vec3(0.0));

// Axis-aligned quad [-a, a] x [-b, b] at z = 0 as two triangles, normal +z.
TriangleMesh make_quad_mesh(double half_x, double half_y);

}  // namespace tb
