// A multiple-try reversible-jump independence move whose candidates are the prefixes of ONE draw
// (Zirr & Dachsbacher 2020, Sec. 7.2 and App. D: a path tracer's large step, every prefix length of
// the traced path a candidate; Listing 2 without next-event estimation).
//
// Models and state. Models j = 0..M-1 of dimension d_j (d_0 <= d_1 <= ...); a state is (j, u),
// u in [0,1)^{d_j}; the reference measure is the disjoint union of the Lebesgue measures; the
// target pi(j, u) >= 0. A draw is a full U in [0,1)^{D}, D = d_{M-1}; its candidates are the
// prefixes (j, U[0, d_j)) with weights W_j(U) = pi(j, U[0, d_j)) (Eq. 27 with w_MIS = 1 and the
// primary-sample density p = 1), S(U) = sum_j W_j(U).
//
// The move (from x = (k, u)):
//   1. draw U_Y uniform on [0,1)^D, select J with probability W_J(U_Y) / S(U_Y) (Eq. 28; the
//      reservoir of Listing 2 lines 26-32 selects with the same probabilities); y = (J, U_Y[0, d_J));
//   2. draw the extension U_X^+ uniform on [0,1)^{D - d_k}: the reverse candidates are the prefixes
//      of U_X = (u, U_X^+) (Listing 2 with the proposal given: "sample_or_keep_next_vertex");
//   3. accept with min{1, S(U_Y) / S(U_X)} (Eq. 29: the weight of either side is the sum of its
//      candidates' weights).
// Derivation (docs/zirr2020.md, "The apt integrator"): on the extended space of (j, U) with
// pi~(j, U) = pi(j, U[0, d_j)) (the coordinates past d_j uniform), step 2 is a Gibbs refresh of
// the coordinates past d_k, which keeps pi~; steps 1 and 3 are an independence Metropolis-Hastings
// move with proposal q(J, U) = W_J(U) / S(U), whose ratio pi~(y) q(x) / (pi~(x) q(y)) is
// S(U_Y) / S(U_X). As a MoveKernel (concepts.h) the move holds U_Y, J and U_X^+;
// move_density(x, m) = W_J(U_Y) / S(U_Y) (uniform draws have density 1), reverse() swaps the roles
// (U_X with J' = k, U_Y's coordinates past d_J as the extension of y), and
//   pi(x) move_density(x, m) a(x, m) = pi(x) pi(y) min{1 / S(U_Y), 1 / S(U_X)}
// is symmetric: detailed balance on the extended space, which the pairwise checker tests.
//
// A family F provides: models(), dimension(j), density(state) = pi, and weights(U, out) filling
// out[j] = W_j(U) for a draw of D coordinates (in one pass: a path tracer traces once).
#pragma once

#include <concepts>
#include <optional>
#include <utility>
#include <vector>

#include "estimators/mcmc/chain_step.h"
#include "lib/core/uniforms.h"

namespace tb::mcmc {

struct ModelState {
  int model = 0;
  std::vector<double> u;
  bool operator==(const ModelState&) const = default;
};

template <class F>
concept PrefixFamily = requires(const F& f, const ModelState& x, const std::vector<double>& U, std::vector<double>* w,
                                int j) {
  { f.models() } -> std::convertible_to<int>;
  { f.dimension(j) } -> std::convertible_to<size_t>;
  { f.density(x) } -> std::convertible_to<double>;
  { f.weights(U, w) };
};

// The sum of a weight list.
inline double weight_sum(const std::vector<double>& w) {
  double s = 0.0;
  for (double v : w) s += v;
  return s;
}

// J with probability w_J / sum w from one uniform (inversion; -1 when every weight is 0).
inline int select_weighted(const std::vector<double>& w, double v) {
  const double sum = weight_sum(w);
  if (!(sum > 0.0)) return -1;
  const double target = v * sum;
  double acc = 0.0;
  int last = -1;
  for (size_t j = 0; j < w.size(); ++j) {
    if (!(w[j] > 0.0)) continue;
    last = static_cast<int>(j);
    acc += w[j];
    if (target < acc) return last;
  }
  return last;  // rounding: the running sum fell just below target
}

template <PrefixFamily F>
class PrefixMultipleTry {
 public:
  using State = ModelState;
  struct Move {
    std::vector<double> draw;       // U_Y (D coordinates)
    int selected = -1;              // J
    std::vector<double> extension;  // U_X^+ (D - d_k coordinates)
    std::vector<double> w_forward;  // W_j(U_Y)
    std::vector<double> w_reverse;  // W_j(U_X), U_X = (u, U_X^+)
  };

  explicit PrefixMultipleTry(F family) : f_(std::move(family)) {}
  const F& target() const { return f_; }
  const F& family() const { return f_; }
  size_t full_dimension() const { return f_.dimension(f_.models() - 1); }

  double target_density(const State& x) const { return f_.density(x); }

  // The candidates' weights of the draw (u, extension).
  std::vector<double> weights_of(const std::vector<double>& u, const std::vector<double>& extension) const {
    std::vector<double> U(u);
    U.insert(U.end(), extension.begin(), extension.end());
    std::vector<double> w(static_cast<size_t>(f_.models()), 0.0);
    f_.weights(U, &w);
    return w;
  }

  // Steps 1 and 2 (nothing when no candidate of U_Y has positive weight: the chain stays).
  std::optional<Move> sample_move(const State& x, Uniforms& u) const {
    const size_t D = full_dimension();
    Move m;
    m.draw.resize(D);
    for (double& v : m.draw) v = u.next();
    m.w_forward.assign(static_cast<size_t>(f_.models()), 0.0);
    f_.weights(m.draw, &m.w_forward);
    m.selected = select_weighted(m.w_forward, u.next());
    m.extension.resize(D - x.u.size());
    for (double& v : m.extension) v = u.next();
    if (m.selected < 0) return std::nullopt;
    m.w_reverse = weights_of(x.u, m.extension);
    return m;
  }

  State destination(const Move& m) const {
    const size_t d = f_.dimension(m.selected);
    return State{m.selected, std::vector<double>(m.draw.begin(), m.draw.begin() + static_cast<std::ptrdiff_t>(d))};
  }

  Move reverse(const State& x, const Move& m) const {
    const size_t d = f_.dimension(m.selected);
    Move r;
    r.draw = x.u;
    r.draw.insert(r.draw.end(), m.extension.begin(), m.extension.end());
    r.selected = x.model;
    r.extension.assign(m.draw.begin() + static_cast<std::ptrdiff_t>(d), m.draw.end());
    r.w_forward = m.w_reverse;
    r.w_reverse = m.w_forward;
    return r;
  }

  // W_J(U_Y) / S(U_Y): the draws are uniform (density 1).
  double move_density(const State&, const Move& m) const {
    const double s = weight_sum(m.w_forward);
    return s > 0.0 && m.selected >= 0 ? m.w_forward[static_cast<size_t>(m.selected)] / s : 0.0;
  }

  // Eq. 29 as Hastings terms, pi folded into the candidate sums: {1, S(U_X), 1, S(U_Y)}.
  MoveTerms move_terms(const State&, const Move& m) const {
    return {1.0, weight_sum(m.w_reverse), 1.0, weight_sum(m.w_forward)};
  }
  double acceptance(const State& x, const Move& m) const { return decide(move_terms(x, m)).acceptance; }

 private:
  F f_;
};

}  // namespace tb::mcmc
