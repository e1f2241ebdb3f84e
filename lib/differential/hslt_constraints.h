// Half-vector constraints of a light path and their Jacobian (Kaplanyan, Hanika, Dachsbacher
// 2014, Sec. 4.2, App. A; the block structure is Jakob 2013, Sec. 4.3).
//
// A path X = (x_0, ..., x_k) has k - 1 interior vertices. At interior vertex i, with unit
// directions w_prev = (x_{i-1} - x_i)/|.| (the paper's i) and w_next = (x_{i+1} - x_i)/|.| (o),
// the generalised half vector is (App. A)
//   H_i = eta_prev w_prev + eta_next w_next,   h_i = +-H_i / |H_i|  (oriented to the side of n_i),
// proportional to App. A's (i + eta o) with eta = eta_next / eta_prev. The constraint is its
// projection onto the local tangent frame (s_i, t_i) of hslt_vertex.h (Sec. 4.2, Table 1):
//   h_i^perp = (<h_i, s_i>, <h_i, t_i>),   H^perp(X) = (h_1^perp, ..., h_{k-1}^perp),
// two components per interior vertex. A specular vertex (Snell's law, law of reflection)
// has h_i^perp = 0 (Sec. 4.4).
//
// The vertex coordinates are the surface parameters (u, v) of every vertex. The Jacobian
// dH^perp/dX is block tridiagonal (Eq. 11): h_i^perp depends on x_{i-1}, x_i, x_{i+1} only,
//   A_i = dh_i^perp / d(u,v)_{i-1},  B_i = dh_i^perp / d(u,v)_i,  C_i = dh_i^perp / d(u,v)_{i+1}.
// App. A fixes the endpoints x_0, x_k: J = dH^perp / d(x_1 .. x_{k-1}) is square, A_1 and C_{k-1}
// are then the derivatives with respect to the endpoints (kept: the transfer matrix of Eq. 6
// needs C_{k-1}); a point endpoint (no surface) has zero blocks.
//
// Derivatives (d denotes a displacement of the vertex positions):
//   d w = (I - w w^T) d(x_neighbour - x_i) / |x_neighbour - x_i|
//   d h = (I - h h^T) d H / |H|    (the sign of h is locally constant)
//   d h^perp = (<dh, s>, <dh, t>) + (<h, ds>, <h, dt>)
// where the second term, present in B_i only, is the derivative of the shading frame through
// dn/du, dn/dv (hslt_vertex.h), and dx = dp/du du + dp/dv dv.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "lib/differential/hslt_vertex.h"

namespace tb {

struct HsltPath {
  std::vector<HsltVertex> vertices;  // x_0 .. x_k
  int segments() const { return static_cast<int>(vertices.size()) - 1; }  // k
  int interior_count() const { return static_cast<int>(vertices.size()) - 2; }  // k - 1
};

// Everything about the half vector at one interior vertex.
struct HsltHalfVector {
  Vec3 w_prev{0.0}, w_next{0.0};  // unit directions to x_{i-1}, x_{i+1}
  double l_prev = 0, l_next = 0;  // distances
  Vec3 H{0.0};                    // eta_prev w_prev + eta_next w_next
  double H_len = 0;
  Vec3 h{0.0};                    // unit, <h, n> >= 0
  Vec2 h_perp{0.0};               // (<h, s>, <h, t>)
  HsltFrame frame;
};

// The half vector at interior vertex i (1 <= i <= k - 1).
HsltHalfVector hslt_half_vector(const HsltPath& path, int i);

// H^perp(X): 2 (k - 1) components, h_1^perp first.
Eigen::VectorXd hslt_constraints(const HsltPath& path);

// The 3x3 derivatives of the unit half vector h_i with respect to the positions of x_{i-1},
// x_i, x_{i+1}: dh = dprev dx_{i-1} + dself dx_i + dnext dx_{i+1}.
struct HsltHalfVectorDifferential {
  Eigen::Matrix3d dprev, dself, dnext;
};
HsltHalfVectorDifferential hslt_half_vector_differential(const HsltHalfVector& hv, double eta_prev, double eta_next);

// (<dh, s>, <dh, t>) for dh = M (dp/du du + dp/dv dv) of vertex `moved`: the part of a block
// that comes from the motion of the half vector.
Eigen::Matrix2d hslt_projected_block(const HsltHalfVector& hv, const Eigen::Matrix3d& M, const HsltVertex& moved);
// (<h, ds/du>, <h, ds/dv>; <h, dt/du>, <h, dt/dv>): the part of B_i that comes from the rotation
// of the tangent frame with the shading normal (dn/du, dn/dv).
Eigen::Matrix2d hslt_frame_block(const HsltHalfVector& hv);

// Blocks of Eq. 11 for block row r = 0 .. k-2 (interior vertex i = r + 1):
// A[r] = dh_i^perp/d(u,v)_{i-1}, B[r] = dh_i^perp/d(u,v)_i, C[r] = dh_i^perp/d(u,v)_{i+1}.
// A[0] and C[k-2] are the endpoint derivatives.
struct HsltBlocks {
  std::vector<Eigen::Matrix2d> A, B, C;
  int size() const { return static_cast<int>(B.size()); }
};
HsltBlocks hslt_constraint_blocks(const HsltPath& path);

// The square Jacobian dH^perp / d(x_1 .. x_{k-1}) of Eq. 11 as a dense matrix (2(k-1) x 2(k-1)),
// in (u, v) coordinates.
Eigen::MatrixXd hslt_dense_jacobian(const HsltBlocks& b);
// dH^perp / d(x_0 .. x_k): 2(k-1) x 2(k+1), endpoint columns included.
Eigen::MatrixXd hslt_full_jacobian(const HsltBlocks& b);

// The path with its (u, v) coordinates replaced: vertex j moves to scene point `surface(j, uv)`.
// Used to evaluate H^perp at perturbed coordinates (finite differences, Newton steps).
template <class SurfaceAt>
HsltPath hslt_path_at(const HsltPath& path, const std::vector<int>& free_vertices, const Eigen::VectorXd& uv,
                      SurfaceAt&& surface) {
  HsltPath moved = path;
  for (size_t j = 0; j < free_vertices.size(); ++j) {
    const int v = free_vertices[j];
    const Vec2 c(uv[static_cast<Eigen::Index>(2 * j)], uv[static_cast<Eigen::Index>(2 * j + 1)]);
    moved.vertices[static_cast<size_t>(v)] = moved_hslt_vertex(path.vertices[static_cast<size_t>(v)], surface(path.vertices[static_cast<size_t>(v)], c));
  }
  return moved;
}

}  // namespace tb
