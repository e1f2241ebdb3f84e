// Finite-difference check of a Hit's differential geometry: dp/du, dp/dv,
// dn/du, dn/dv against central differences of p(u, v) and n(u, v) with step
// h = eps^(1/3) max(1, |x|) (truncation O(h^2) balances rounding O(eps / h)), cross-checked
// at h / 2 to detect discontinuities (skipped and counted).
//
// Error measure per point: max over the four derivatives of |analytic - fd| / max(1, |fd|)
// (relative with a floor of one, as validate/stats/fd_jacobian.h does).
#pragma once

#include <cstdint>
#include <functional>

#include "lib/geometry/hit.h"

namespace tb {

struct DifferentialError {
  double rel_error = 0;        // worst of dp/du, dp/dv, dn/du, dn/dv
  double step_disagreement = 0;
  bool skipped = false;        // h and h/2 disagree: a discontinuity
};

DifferentialError check_differentials_at(const std::function<Hit(const Vec2&)>& surface, const Vec2& uv);

}  // namespace tb
