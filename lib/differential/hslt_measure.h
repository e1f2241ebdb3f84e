// Measurement in half-vector space (Kaplanyan, Hanika, Dachsbacher 2014, Sec. 4.3, Eq. 3-7):
// the change of measure between the on-surface path measure dX = prod dA(x_i) and the projected
// half-vector measure dH^perp = prod dh_i^perp, dh^perp = |<h, n>| dh (App. A), at fixed
// endpoints x_0 and x_k.
//
// Direct form (Eq. 4 without rho):
//   prod_{i=0}^{k-1} G(x_i, x_{i+1}) |d(x_1..x_{k-1}) / d(h_1^perp..h_{k-1}^perp)|
//   = prod G / |det J_area|,   J_area = J_uv diag(1 / |dp/du x dp/dv|_i)  (Eq. 11).
// Product-of-Jacobians form (Eq. 5 with Eq. 6):
//   |do_0^perp / dx_k| prod_{i=1}^{k-1} |do_i / dh_i| |<o_i, n_i>| / |<h_i, n_i>|,
//   |do_0^perp / dx_k| = G(x_0, x_1) |T_1|,  T_1 = dx_1 / dx_k at fixed H^perp and x_0,
// with |do_i/dh_i| the inverse of Eq. 10 (lib/material/half_vector.h) and T_1 the first block
// row of -J^{-1} C_{k-1} (block LU solve, Sec. 7). Derivation: (o_0^perp, h^perp) -> (o_0^perp,
// o_1^perp .. o_{k-1}^perp) is block triangular with diagonal |do_i^perp / dh_i^perp| (each o_i
// depends on h_i and on the already fixed incoming direction), and d(o^perp)/d(x_1..x_k) is
// block triangular with diagonal G; the chain rule through (x_k, h^perp) gives Eq. 5.
//
// G(a, b) = |<w, n_a>| |<w, ng_b>| / |a - b|^2 (Sec. 4.1) with w the unit a -> b: the projected
// solid angle at a is taken about the shading normal (the normal of h^perp), the foreshortening
// of the area at b about the geometric normal; a point endpoint has no cosine at a.
#pragma once

#include <vector>

#include "lib/differential/hslt_constraints.h"

namespace tb {

double hslt_geometry_term(const HsltVertex& a, const HsltVertex& b);

// The transfer matrix of Eq. 6 in (u, v) coordinates: T_1 = d(u,v)_1 / d(u,v)_k at fixed H^perp
// and x_0, the first block row of -J^{-1} [0 .. 0; C_{k-1}] (block LU solve, Sec. 7). Returns
// false when the block LU meets a singular pivot.
bool hslt_transfer_matrix(const HsltBlocks& b, Eigen::Matrix2d* t1);

// The factors of both forms, for reporting and for the checks.
struct HsltMeasureTerms {
  bool ok = false;                     // block LU succeeded and x_k lies on a surface
  double geometry_product = 0;         // prod_{i=0}^{k-1} G(x_i, x_{i+1})
  double log_abs_det_area = 0;         // log |det J_area|
  double g01 = 0;                      // G(x_0, x_1)
  double transfer_det = 0;             // |T_1| in area measure (Eq. 6)
  std::vector<double> do_dh;           // |do_i / dh_i| = 1 / Eq. 10, i = 1 .. k-1
  std::vector<double> cos_o, cos_h;    // |<o_i, n_i>|, |<h_i, n_i>|
};
HsltMeasureTerms hslt_measure_terms(const HsltPath& path);

// The two forms from the terms.
double hslt_measure_direct(const HsltMeasureTerms& t);   // Eq. 4 / rho
double hslt_measure_product(const HsltMeasureTerms& t);  // Eq. 5, 6

}  // namespace tb
