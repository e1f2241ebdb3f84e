#include "analytic/mis_variance.h"

#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "analytic/quadrature.h"

namespace tb {

double mis_balance_variance(const MisVarianceInput& in) {
  const size_t nt = in.pdfs.size();
  if (in.counts.size() != nt) throw std::invalid_argument("mis_balance_variance: one count per pdf");
  // p_i(x) for all i at once, cached: the 2T integrals below visit mostly the same nodes.
  std::unordered_map<uint64_t, std::vector<double>> cache;
  auto pdfs_at = [&](double x) -> const std::vector<double>& {
    const uint64_t key = std::bit_cast<uint64_t>(x);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    std::vector<double> p(nt);
    for (size_t i = 0; i < nt; ++i) p[i] = in.counts[i] > 0 ? in.pdfs[i](x) : 0.0;
    return cache.emplace(key, std::move(p)).first->second;
  };
  bool uncovered = false;
  double var = 0.0;
  for (size_t i = 0; i < nt; ++i) {
    if (in.counts[i] <= 0) continue;
    auto term = [&](double x, int power) {
      const double fx = in.f(x);
      if (fx == 0.0) return 0.0;
      const auto& p = pdfs_at(x);
      double big_p = 0.0;
      for (size_t k = 0; k < nt; ++k) big_p += in.counts[k] * p[k];
      if (big_p <= 0.0) {
        uncovered = true;
        return 0.0;
      }
      return (power == 2 ? fx * fx : fx) * p[i] / (power == 2 ? big_p * big_p : big_p);
    };
    const double m2 = integrate_1d([&](double x) { return term(x, 2); }, 0.0, 1.0, in.breakpoints).value;
    const double m1 = integrate_1d([&](double x) { return term(x, 1); }, 0.0, 1.0, in.breakpoints).value;
    var += in.counts[i] * (m2 - m1 * m1);
  }
  return uncovered ? std::numeric_limits<double>::infinity() : var;
}

}  // namespace tb
