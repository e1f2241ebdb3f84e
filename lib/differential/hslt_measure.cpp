#include "lib/differential/hslt_measure.h"

#include <cmath>

#include "lib/differential/hslt_block_lu.h"
#include "lib/material/half_vector.h"

namespace tb {

double hslt_geometry_term(const HsltVertex& a, const HsltVertex& b) {
  const Vec3 d = b.p - a.p;
  const double l2 = glm::dot(d, d);
  const Vec3 w = d / std::sqrt(l2);
  const double ca = a.on_surface ? std::abs(glm::dot(w, a.n)) : 1.0;
  const double cb = b.on_surface ? std::abs(glm::dot(w, b.ng)) : 1.0;
  return ca * cb / l2;
}

bool hslt_transfer_matrix(const HsltBlocks& b, Eigen::Matrix2d* t1) {
  const int n = b.size();
  const HsltBlockLu lu(b);
  if (n < 1 || !lu.ok()) return false;
  // dH^perp = J dX + C_{k-1} dx_k = 0 at fixed H^perp: dX = -J^{-1} [0 .. 0; C_{k-1}] dx_k.
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(2 * n, 2);
  rhs.bottomRows<2>() = -b.C.back();
  *t1 = lu.solve(rhs).topRows<2>();
  return t1->allFinite();
}

HsltMeasureTerms hslt_measure_terms(const HsltPath& path) {
  HsltMeasureTerms t;
  const int k = path.segments(), n = path.interior_count();
  if (n < 1 || !path.vertices.back().on_surface) return t;
  t.geometry_product = 1.0;
  for (int i = 0; i < k; ++i)
    t.geometry_product *= hslt_geometry_term(path.vertices[static_cast<size_t>(i)], path.vertices[static_cast<size_t>(i + 1)]);
  t.g01 = hslt_geometry_term(path.vertices[0], path.vertices[1]);
  const HsltBlocks b = hslt_constraint_blocks(path);
  const HsltBlockLu lu(b);
  Eigen::Matrix2d t1;
  if (!lu.ok() || !hslt_transfer_matrix(b, &t1)) return t;
  // Area measure: d(h^perp) / dA_i = d(h^perp)/d(u,v)_i / |dp/du x dp/dv|_i (Eq. 11 in area).
  t.log_abs_det_area = lu.log_abs_determinant();
  for (int i = 1; i <= n; ++i) t.log_abs_det_area -= std::log(path.vertices[static_cast<size_t>(i)].area_element());
  // |T_1| (Eq. 6) from (u, v) to area.
  t.transfer_det = std::abs(t1.determinant()) * path.vertices[1].area_element() / path.vertices.back().area_element();
  for (int i = 1; i <= n; ++i) {
    const HsltVertex& x = path.vertices[static_cast<size_t>(i)];
    const HsltHalfVector hv = hslt_half_vector(path, i);
    // Eq. 10: |dh/do| at fixed i; Eq. 5 needs its inverse.
    t.do_dh.push_back(1.0 / half_vector_jacobian(hv.w_prev, hv.w_next, x.eta_prev, x.eta_next));
    t.cos_o.push_back(std::abs(glm::dot(hv.w_next, x.n)));
    t.cos_h.push_back(std::abs(glm::dot(hv.h, x.n)));
  }
  t.ok = true;
  return t;
}

double hslt_measure_direct(const HsltMeasureTerms& t) {
  return t.geometry_product * std::exp(-t.log_abs_det_area);
}

double hslt_measure_product(const HsltMeasureTerms& t) {
  double m = t.g01 * t.transfer_det;
  for (size_t i = 0; i < t.do_dh.size(); ++i) m *= t.do_dh[i] * t.cos_o[i] / t.cos_h[i];
  return m;
}

}  // namespace tb
