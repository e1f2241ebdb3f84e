#include "lib/differential/hslt_constraints.h"

#include <cmath>

#include "lib/material/half_vector.h"

namespace tb {
namespace {

Eigen::Vector3d ev(const Vec3& v) { return {v.x, v.y, v.z}; }

// (I - w w^T) / l: derivative of the unit vector w = d / |d| with l = |d|.
Eigen::Matrix3d unit_derivative(const Vec3& w, double l) {
  const Eigen::Vector3d e = ev(w);
  return (Eigen::Matrix3d::Identity() - e * e.transpose()) / l;
}

}  // namespace

HsltHalfVector hslt_half_vector(const HsltPath& path, int i) {
  const HsltVertex& prev = path.vertices[static_cast<size_t>(i - 1)];
  const HsltVertex& x = path.vertices[static_cast<size_t>(i)];
  const HsltVertex& next = path.vertices[static_cast<size_t>(i + 1)];
  HsltHalfVector hv;
  const Vec3 dp = prev.p - x.p, dn = next.p - x.p;
  hv.l_prev = glm::length(dp);
  hv.l_next = glm::length(dn);
  hv.w_prev = dp / hv.l_prev;
  hv.w_next = dn / hv.l_next;
  // Kaplanyan 2014, App. A: h = (i + eta o)/|i + eta o|, eta = eta_o / eta_i (times eta_i).
  hv.H = generalized_half_vector_unnormalized(hv.w_prev, hv.w_next, x.eta_prev, x.eta_next);
  hv.H_len = glm::length(hv.H);
  hv.h = hv.H / hv.H_len;
  if (glm::dot(hv.h, x.n) < 0) hv.h = -hv.h;
  hv.frame = hslt_frame(x);
  hv.h_perp = Vec2(glm::dot(hv.h, hv.frame.s), glm::dot(hv.h, hv.frame.t));
  return hv;
}

Eigen::VectorXd hslt_constraints(const HsltPath& path) {
  const int n = path.interior_count();
  Eigen::VectorXd c(2 * n);
  for (int r = 0; r < n; ++r) {
    const Vec2 hp = hslt_half_vector(path, r + 1).h_perp;
    c[2 * r] = hp.x;
    c[2 * r + 1] = hp.y;
  }
  return c;
}

HsltHalfVectorDifferential hslt_half_vector_differential(const HsltHalfVector& hv, double eta_prev,
                                                         double eta_next) {
  // dH = eta_prev dw_prev + eta_next dw_next; dw_prev = U_prev (dx_{i-1} - dx_i), likewise next.
  const Eigen::Matrix3d Up = eta_prev * unit_derivative(hv.w_prev, hv.l_prev);
  const Eigen::Matrix3d Un = eta_next * unit_derivative(hv.w_next, hv.l_next);
  // h = sigma H / |H| with sigma = sign <h, H> = +-1 (the orientation to the side of n, locally
  // constant): dh = sigma (I - h h^T) dH / |H|.
  const Eigen::Vector3d h = ev(hv.h);
  const double sign = glm::dot(hv.h, hv.H) < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d N = sign * (Eigen::Matrix3d::Identity() - h * h.transpose()) / hv.H_len;
  HsltHalfVectorDifferential d;
  d.dprev = N * Up;
  d.dnext = N * Un;
  d.dself = -(d.dprev + d.dnext);
  return d;
}

Eigen::Matrix2d hslt_projected_block(const HsltHalfVector& hv, const Eigen::Matrix3d& M, const HsltVertex& moved) {
  Eigen::Matrix<double, 2, 3> P;
  P.row(0) = ev(hv.frame.s).transpose();
  P.row(1) = ev(hv.frame.t).transpose();
  Eigen::Matrix<double, 3, 2> T;
  T.col(0) = ev(moved.dpdu);
  T.col(1) = ev(moved.dpdv);
  return P * M * T;
}

Eigen::Matrix2d hslt_frame_block(const HsltHalfVector& hv) {
  Eigen::Matrix2d F;
  for (int k = 0; k < 2; ++k) {
    F(0, k) = glm::dot(hv.h, hv.frame.ds[static_cast<size_t>(k)]);
    F(1, k) = glm::dot(hv.h, hv.frame.dt[static_cast<size_t>(k)]);
  }
  return F;
}

HsltBlocks hslt_constraint_blocks(const HsltPath& path) {
  const int n = path.interior_count();
  HsltBlocks b;
  b.A.resize(static_cast<size_t>(n));
  b.B.resize(static_cast<size_t>(n));
  b.C.resize(static_cast<size_t>(n));
  for (int r = 0; r < n; ++r) {
    const int i = r + 1;
    const HsltVertex& x = path.vertices[static_cast<size_t>(i)];
    const HsltHalfVector hv = hslt_half_vector(path, i);
    const HsltHalfVectorDifferential d = hslt_half_vector_differential(hv, x.eta_prev, x.eta_next);
    const auto ur = static_cast<size_t>(r);
    b.A[ur] = hslt_projected_block(hv, d.dprev, path.vertices[static_cast<size_t>(i - 1)]);
    b.B[ur] = hslt_projected_block(hv, d.dself, x) + hslt_frame_block(hv);
    b.C[ur] = hslt_projected_block(hv, d.dnext, path.vertices[static_cast<size_t>(i + 1)]);
  }
  return b;
}

Eigen::MatrixXd hslt_dense_jacobian(const HsltBlocks& b) {
  const int n = b.size();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  for (int r = 0; r < n; ++r) {
    const auto ur = static_cast<size_t>(r);
    if (r > 0) J.block<2, 2>(2 * r, 2 * (r - 1)) = b.A[ur];
    J.block<2, 2>(2 * r, 2 * r) = b.B[ur];
    if (r + 1 < n) J.block<2, 2>(2 * r, 2 * (r + 1)) = b.C[ur];
  }
  return J;
}

Eigen::MatrixXd hslt_full_jacobian(const HsltBlocks& b) {
  const int n = b.size();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 2 * (n + 2));
  for (int r = 0; r < n; ++r) {
    const auto ur = static_cast<size_t>(r);
    // Column block c = vertex index; block row r is vertex r + 1.
    J.block<2, 2>(2 * r, 2 * r) = b.A[ur];
    J.block<2, 2>(2 * r, 2 * (r + 1)) = b.B[ur];
    J.block<2, 2>(2 * r, 2 * (r + 2)) = b.C[ur];
  }
  return J;
}

}  // namespace tb
