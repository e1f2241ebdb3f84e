#include "validate/differential/hslt_broken.h"

#include <utility>

namespace tb {

HsltBlocks hslt_blocks_sign_error(const HsltPath& path) {
  HsltBlocks b = hslt_constraint_blocks(path);
  const auto r = static_cast<size_t>((b.size() - 1) / 2);
  b.C[r] = -b.C[r];
  return b;
}

HsltBlocks hslt_blocks_without_frame_derivative(const HsltPath& path) {
  const int n = path.interior_count();
  HsltBlocks b;
  for (int r = 0; r < n; ++r) {
    const int i = r + 1;
    const HsltVertex& x = path.vertices[static_cast<size_t>(i)];
    const HsltHalfVector hv = hslt_half_vector(path, i);
    const HsltHalfVectorDifferential d = hslt_half_vector_differential(hv, x.eta_prev, x.eta_next);
    b.A.push_back(hslt_projected_block(hv, d.dprev, path.vertices[static_cast<size_t>(i - 1)]));
    b.B.push_back(hslt_projected_block(hv, d.dself, x));  // fault: + hslt_frame_block(hv) missing
    b.C.push_back(hslt_projected_block(hv, d.dnext, path.vertices[static_cast<size_t>(i + 1)]));
  }
  return b;
}

double hslt_measure_product_without_projection(const HsltMeasureTerms& t) {
  double m = t.g01 * t.transfer_det;
  for (size_t i = 0; i < t.do_dh.size(); ++i) m *= t.do_dh[i] * t.cos_o[i];  // fault: / cos_h[i] missing
  return m;
}

double hslt_determinant_without_schur(const HsltBlocks& b) {
  double d = 1.0;
  for (const Eigen::Matrix2d& B : b.B) d *= B.determinant();  // fault: D_r = B_r
  return d;
}

Eigen::VectorXd hslt_constraints_swapped_eta(const HsltPath& path) {
  HsltPath p = path;
  for (HsltVertex& v : p.vertices) std::swap(v.eta_prev, v.eta_next);  // fault
  return hslt_constraints(p);
}

}  // namespace tb
