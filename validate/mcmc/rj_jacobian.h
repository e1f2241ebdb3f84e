// Checks a reversible-jump dimension-matching map g(x, u) = y against finite differences
// (docs/validation.md C applied to E): over seeded configurations (x, u), with x and u drawn from
// caller-supplied samplers, the stated |det dg/d(x, u)| must match the determinant of the
// central-difference Jacobian (step h = eps^(1/3) max(1, |z_i|), Press et al., Numerical Recipes
// 3rd ed., Sec. 5.7) to a relative 1e-6, and g^{-1}(g(x, u)) must return (x, u) to 1e-10.
// For maps with Low = std::array<double, n>, Aux = double, High = std::array<double, n + 1>.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "lib/core/rng.h"
#include "validate/mcmc/checker_concepts.h"

namespace tb::mcmc {

struct RjJacobianResult {
  int64_t configurations = 0, failed = 0;
  double worst_rel_error = 0.0;     // |J_fd - J| / max(1, |J_fd|)
  int64_t worst_index = -1;
  double worst_roundtrip = 0.0;     // max |g^{-1}(g(x, u)) - (x, u)|
  double tolerance = 1e-6;
  bool passed = false;
  std::string message;
};

template <DimensionMatchingMap G>
RjJacobianResult check_rj_jacobian(const G& g, const std::function<typename G::Low(Uniforms&)>& sample_low,
                                   int64_t configurations, uint64_t seed, uint64_t key, double tolerance = 1e-6) {
  using Low = typename G::Low;
  using High = typename G::High;
  constexpr int n = static_cast<int>(std::tuple_size_v<Low>);
  static_assert(std::tuple_size_v<High> == n + 1, "maps with one auxiliary dimension");
  auto f = [&](const Eigen::Matrix<double, n + 1, 1>& z) {
    Low x{};
    for (int i = 0; i < n; ++i) x[i] = z[i];
    const High y = g.up(x, z[n]);
    Eigen::Matrix<double, n + 1, 1> out;
    for (int i = 0; i <= n; ++i) out[i] = y[i];
    return out;
  };
  RjJacobianResult r;
  r.tolerance = tolerance;
  r.configurations = configurations;
  const double h0 = std::cbrt(std::numeric_limits<double>::epsilon());
  for (int64_t c = 0; c < configurations; ++c) {
    Rng rng = Rng::for_sample(seed, key, c);
    RngUniforms u(rng);
    const Low x = sample_low(u);
    const auto a = g.sample_aux(u);
    Eigen::Matrix<double, n + 1, 1> z;
    for (int i = 0; i < n; ++i) z[i] = x[i];
    z[n] = a;
    Eigen::Matrix<double, n + 1, n + 1> J;
    for (int i = 0; i <= n; ++i) {
      const double h = h0 * std::max(1.0, std::abs(z[i]));
      auto zp = z, zm = z;
      zp[i] += h;
      zm[i] -= h;
      J.col(i) = (f(zp) - f(zm)) / (zp[i] - zm[i]);
    }
    const double jfd = std::abs(J.determinant());
    const double err = std::abs(jfd - g.jacobian(x, a)) / std::max(1.0, jfd);
    const auto [xb, ab] = g.down(g.up(x, a));
    double rt = std::abs(ab - a);
    for (int i = 0; i < n; ++i) rt = std::max(rt, std::abs(xb[i] - x[i]));
    r.worst_roundtrip = std::max(r.worst_roundtrip, rt);
    if (err > r.worst_rel_error || !(err == err)) {
      r.worst_rel_error = err;
      r.worst_index = c;
    }
    r.failed += !(err <= tolerance) || !(rt <= 1e-10 * std::max(1.0, std::abs(a)));
  }
  r.passed = r.failed == 0;
  r.message = fmt::format("{} configurations: worst relative |det J_fd - J| = {:.3g} (config {}), worst round trip "
                          "{:.3g}, {} failed (tolerance {:.0e})",
                          configurations, r.worst_rel_error, r.worst_index, r.worst_roundtrip, r.failed, tolerance);
  return r;
}

}  // namespace tb::mcmc
