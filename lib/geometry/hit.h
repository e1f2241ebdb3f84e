// The intersection records: a surface point, and the same point with its exact first-order
// differential geometry.
//
// Hit is designed for derivative-based path methods: the half-vector constraint Jacobians of
// manifold exploration / Kaplanyan et al. 2014 ("The natural-constraint representation of the
// path space", Sec. 4) and the path differentials of Zirr & Dachsbacher 2020 need the
// tangents dp/du, dp/dv and the derivatives of the shading normal dn/du, dn/dv at each vertex,
// in a parameterisation (u, v) that can be re-evaluated at a moved point (Scene::surface_at).
//
// SurfacePoint is the lean part of it (128 bytes instead of 224): everything a path tracer needs
// to shade a vertex and to spawn rays from it (position, normals, error bound, ids).
// Scene::sample_point computes these fields with the very expressions of the full query, so its
// SurfacePoint equals the SurfacePoint part of the corresponding Hit bit for bit;
// Scene::intersect_point differs on triangles by using Embree's float barycentrics (see there).
// Functions that need only these fields take a `const SurfacePoint&`, which a Hit binds to.
// All quantities are in world space and double precision.
#pragma once

#include <cstdint>

#include "lib/core/math.h"

namespace tb {

struct SurfacePoint {
  Vec3 p{0.0};         // position
  Vec3 ng{0, 0, 1};    // geometric normal, unit length (outward for closed analytic shapes)
  Vec3 n{0, 0, 1};     // shading normal, unit length (== ng for analytic shapes)
  Vec2 uv{0.0};        // surface parameters in the shape's parameterisation (docs/geometry.md)
  uint32_t shape_id = 0;      // index of the shape in the Scene (== Embree geometry id)
  uint32_t prim_id = 0;       // triangle index for meshes, 0 for analytic shapes
  double t = 0.0;             // ray parameter of the hit (0 for points not found by a ray)
  Vec3 p_error{0.0};          // conservative componentwise bound on |p - p_exact| (ray spawning)
};

struct Hit : SurfacePoint {
  Vec3 dpdu{0.0}, dpdv{0.0};  // exact tangents dp/du, dp/dv
  Vec3 dndu{0.0}, dndv{0.0};  // derivatives of the (unit) shading normal n(u, v)
};

}  // namespace tb
