// Light paths for the half-vector constraint checks (lib/differential/hslt_*.h), built two ways:
//  * traced: from the pinhole camera of a scene through a uniform raster position (even index),
//    or from a uniform point on an area light towards a uniform point on a delta surface (odd
//    index), continued through every delta (specular) surface by reflection or refraction,
//    ending at the first non-delta surface. The interior vertices are then specular (h^perp = 0,
//    Kaplanyan 2014 Sec. 4.4); x_0 is the camera point (a fixed point) or the light point (a
//    surface point, free in the Jacobian checks), x_k the diffuse surface point;
//  * sampled: k + 1 points sampled uniformly by area on the non-emitting shapes of a scene
//    and connected vertex by vertex (each redrawn until the previous interior vertex is a
//    physical reflection / refraction away from grazing and from h in the tangent plane), visibility ignored (the constraints
//    are purely geometric). Interior vertices are reflections, refractions or a mix with random
//    indices of refraction; h^perp is then generic (a glossy vertex).
// Plus the finite-difference view of H^perp: a function of the (u, v) of the free vertices.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "lib/differential/hslt_constraints.h"
#include "lib/scene/world.h"

namespace tb {

// A specular chain traced from the camera or a light (by index parity); nullopt when the first
// surface hit is not a delta surface,
// the chain escapes or hits an emitter, or it has more than max_segments segments.
// Refractions are chosen with probability 1/2 at a dielectric (reflection on TIR).
std::optional<HsltPath> trace_hslt_specular_path(const World& world, uint64_t seed, uint64_t key, int64_t index,
                                                 int max_segments = 8);

enum class HsltVertexMix { kReflection, kRefraction, kMixed };

// k = segments; nullopt on a degenerate draw (points closer than 0.05, |H| < 0.05, a degenerate
// tangent frame).
std::optional<HsltPath> sample_hslt_connected_path(const World& world, HsltVertexMix mix, int segments, uint64_t seed,
                                                   uint64_t key, int64_t index);

// For a traced specular path: x_1 moved to (u, v) on its surface, the chain retraced from the fixed
// x_0 through x_1 by the law of reflection / Snell's law at every interior vertex (h^perp kept at
// 0), and the (u, v) of the end point where it meets the surface of x_k. nullopt when the
// retraced chain meets another shape than the original (or total internal reflection). This is
// the forward map whose derivative d(u,v)_k / d(u,v)_1 is T_1^{-1} (Kaplanyan 2014, Eq. 6).
std::optional<Vec2> retrace_hslt_specular_endpoint(const World& world, const HsltPath& path, const Vec2& uv1);

// The vertices whose (u, v) are variables: interior vertices and endpoints on a surface.
std::vector<int> hslt_free_vertices(const HsltPath& path);
// (u, v) of the free vertices, concatenated.
Eigen::VectorXd hslt_free_coordinates(const HsltPath& path, const std::vector<int>& free);
// The path with the free vertices moved to the given (u, v) (Scene::surface_at).
HsltPath hslt_path_at(const Scene& scene, const HsltPath& path, const std::vector<int>& free, const Eigen::VectorXd& uv);
// Columns of a full Jacobian (hslt_full_jacobian, 2 per vertex) of the free vertices.
Eigen::MatrixXd hslt_free_columns(const Eigen::MatrixXd& full, const std::vector<int>& free);

// The coordinates the finite-difference checks differentiate in: a local chart around the path,
// delta = 0 at the path, uv = uv0 + delta * length / (|dp/du|, |dp/dv|) per free vertex, so that
// a unit of every coordinate moves its vertex by about `length` scene units whatever the shape's
// (u, v) scale (a floor of half size 4 has |dp/du| = 8, a sphere of radius 0.35 has 2.2); the
// constraint values are divided by `length` too, so that the Jacobian in the chart,
// J_uv diag(scale) / length, is the derivative of h^perp per scene unit of displacement (entries
// of order 1-10, where the relative error of fd_jacobian.h with its floor of 1 is relative).
// With length = 0.003, Ceres' default first Ridders step (2^5 x 1e-2 at delta = 0) is 1e-3
// scene units (at 3.2e-3 one curved-mirror path of 160 gave a Ridders error of 1e-2 from the
// early exit of the tableau while central differences agreed to 1e-9), the central-difference
// step 2e-8 and the largest Taylor step (taylor_h0 = 0.1) 3e-4.
struct HsltFdChart {
  std::vector<int> free;
  Eigen::VectorXd uv0, scale;
  double length = 0.003;
  Eigen::VectorXd uv(const Eigen::VectorXd& delta) const { return uv0 + scale.cwiseProduct(delta); }
  Eigen::VectorXd value(const Eigen::VectorXd& h_perp) const { return h_perp / length; }
  Eigen::MatrixXd jacobian(const Eigen::MatrixXd& j_uv) const { return j_uv * scale.asDiagonal() / length; }
};
HsltFdChart hslt_fd_chart(const HsltPath& path, const std::vector<int>& free, double length = 0.003);

// A named set of paths the checks run on.
struct HsltPathSet {
  std::string name;             // e.g. "dg-glass traced", "mixed sampled"
  std::vector<HsltPath> paths;
  int64_t attempts = 0;         // draws made to obtain them
};
// Families: "curved_mirrors", "glass", "mirror_chain" (traced on scenes/dg-*.json), "reflection",
// "refraction", "mixed" (sampled on dg-curved-mirrors / dg-glass shapes, k = 2 .. 8 in turn).
const std::vector<std::string>& hslt_families();
HsltPathSet hslt_path_set(const std::string& family, int count, uint64_t seed);
// The world a family is built on (loaded once, cached).
const World& hslt_family_world(const std::string& family);

}  // namespace tb
