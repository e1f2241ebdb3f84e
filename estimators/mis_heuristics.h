// MIS weighting heuristics (Veach 1997, Sec. 9.2): each is its own type with
//   double weight(std::span<const double> q, size_t i) const
// where q_k = n_k p_k(x) (multi-sample MIS, n_k samples from technique k) or q_k = c_k p_k(x)
// (one-sample MIS, technique k chosen with probability c_k). All of them sum to one over i
// wherever some q_k > 0, which keeps MIS unbiased (Veach Eq. 9.3).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <variant>

namespace tb {

template <class H>
concept MisHeuristic = requires(const H& h, std::span<const double> q, size_t i) {
  { h.weight(q, i) } -> std::convertible_to<double>;
};

// Balance heuristic (Veach Eq. 9.6): w_i = q_i / Σ q_k.
struct BalanceHeuristic {
  double weight(std::span<const double> q, size_t i) const {
    double s = 0.0;
    for (double v : q) s += v;
    return s > 0.0 ? q[i] / s : 0.0;
  }
};

// Power heuristic (Veach Eq. 9.11): w_i = q_i^β / Σ q_k^β, β = 2 by default. Computed relative
// to the largest q so that the powers cannot overflow.
struct PowerHeuristic {
  double beta = 2.0;
  double weight(std::span<const double> q, size_t i) const {
    const double qmax = *std::max_element(q.begin(), q.end());
    if (!(qmax > 0.0)) return 0.0;
    double s = 0.0;
    for (double v : q) s += std::pow(v / qmax, beta);
    return std::pow(q[i] / qmax, beta) / s;
  }
};

// PowerHeuristic{}.weight({q_this, q_other}, 0) (beta = 2, two techniques) with two divisions
// instead of four and no data-dependent branch, for per-vertex MIS in the path tracer's inner
// loop. Scaled by the larger q as above, so that the squares cannot overflow. Equal to the
// generic weight up to a few ulps of rounding; the two weights of a pair sum to one up to rounding.
inline double power_heuristic_2(double q_this, double q_other) {
  const double qmax = std::max(q_this, q_other);
  if (!(qmax > 0.0)) return 0.0;
  const double inv = 1.0 / qmax;
  const double a = q_this * inv, b = q_other * inv;
  return (a * a) / (a * a + b * b);
}

// Maximum heuristic (Veach Eq. 9.9): the whole weight to the technique of largest q; ties are split
// evenly so that the weights still sum to exactly one.
struct MaximumHeuristic {
  double weight(std::span<const double> q, size_t i) const {
    const double qmax = *std::max_element(q.begin(), q.end());
    if (!(qmax > 0.0) || q[i] != qmax) return 0.0;
    const auto ties = std::count(q.begin(), q.end(), qmax);
    return 1.0 / static_cast<double>(ties);
  }
};

// Cutoff heuristic (Veach Eq. 9.10): techniques with q_k < α·q_max get no weight, the others the
// balance heuristic among themselves.
struct CutoffHeuristic {
  double alpha = 0.1;
  double weight(std::span<const double> q, size_t i) const {
    const double qmax = *std::max_element(q.begin(), q.end());
    if (!(qmax > 0.0)) return 0.0;
    const double cut = alpha * qmax;
    if (q[i] < cut) return 0.0;
    double s = 0.0;
    for (double v : q)
      if (v >= cut) s += v;
    return q[i] / s;
  }
};

// The heuristics chosen by name ("balance", "power", "maximum", "cutoff") for settings files.
using AnyHeuristic = std::variant<BalanceHeuristic, PowerHeuristic, MaximumHeuristic, CutoffHeuristic>;

inline AnyHeuristic heuristic_by_name(const std::string& name) {
  if (name == "balance") return BalanceHeuristic{};
  if (name == "power") return PowerHeuristic{};
  if (name == "maximum") return MaximumHeuristic{};
  if (name == "cutoff") return CutoffHeuristic{};
  throw std::invalid_argument("unknown MIS heuristic '" + name + "' (balance, power, maximum, cutoff)");
}

inline double mis_weight(const AnyHeuristic& h, std::span<const double> q, size_t i) {
  return std::visit([&](const auto& hh) { return hh.weight(q, i); }, h);
}

}  // namespace tb
