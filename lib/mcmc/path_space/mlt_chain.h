// One chain of path-space MLT as the ScoredChain of estimators/mcmc/chain_step.h, shared by the
// drivers of mlt.cpp and ramlt.cpp.
#pragma once

#include <algorithm>
#include <functional>
#include <optional>
#include <vector>

#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

// One chain on paths as the ScoredChain of chain_step.h: x with f(x) and pi(x) cached, the proposal
// y scored once when proposed. pi(x) = Y(f(x)) unless `density` is set (a target of
// mlt.h: MltTarget, given the path and its f).
struct MltChain {
  const PathMixture* mix = nullptr;
  const PathTarget* target = nullptr;
  const std::function<double(const MltPath&, const Rgb&)>* density = nullptr;
  MltPath x;
  Rgb fx{0.0};
  double pix = 0.0;
  std::optional<MltPath> y;
  Rgb fy{0.0};
  double piy = 0.0;
  // Selection weights of x (cached while x is current) and of the proposal (filled by terms()).
  std::vector<double> wx, wy;
  double sum_x = 0.0, sum_y = 0.0;
  bool y_weighed = false;

  void start() { sum_x = mix->weights(x, &wx); }
  int select(double v) const { return PathMixture::select_from(wx, sum_x, v); }
  bool propose(int k, Uniforms& u) {
    y_weighed = false;
    y = mix->propose(k, x, u);
    if (!y) return false;
    fy = target->contribution(*y);
    piy = score(*y, fy);
    return true;
  }
  double score(const MltPath& p, const Rgb& f) const {
    return density ? std::max(0.0, (*density)(p, f)) : std::max(0.0, luminance(f));
  }
  // mcmc::mixture_terms with c_k(x) from the cache and c_k(y) from y's weights (kept for accept).
  mcmc::MoveTerms terms(int k) {
    const size_t j = static_cast<size_t>(k);
    const double cx = sum_x > 0.0 && wx[j] > 0.0 ? wx[j] / sum_x : 0.0;
    double cy = 0.0;
    if (piy > 0.0) {
      sum_y = mix->weights(*y, &wy);
      y_weighed = true;
      cy = sum_y > 0.0 && wy[j] > 0.0 ? wy[j] / sum_y : 0.0;
    }
    return mcmc::mixture_terms(*mix, k, x, *y, pix, piy, cx, cy);
  }
  void accept() {
    x = std::move(*y);
    fx = fy;
    pix = piy;
    if (y_weighed) {
      std::swap(wx, wy);
      sum_x = sum_y;
    } else {
      start();
    }
  }
  void reject() {}
};

}  // namespace tb::path_space
