// Net flux of a path-space kernel (docs/validation.md E, "flux symmetry", in a form that needs no exact
// draws from pi). For a kernel reversible with respect to pi and any antisymmetric function
// g(x, y) = -g(y, x), the pair (X, X') of a stationary transition is exchangeable, so
// E_pi[g(X, X')] = 0: the net flux across any partition (bins of pixel, path length, ...) is
// zero. Exact draws from pi are not available on paths, but chains started by importance
// resampling (start_paths.h: start_chain) satisfy E[b_c h(X_0)] = b E_pi[h], and then, for a
// pi-invariant kernel, E[b_c g(X_t, X_{t+1})] = b E_pi[g(X, X')] = 0 at every step t. Per chain c
// the statistic Z_c = b_c sum_t g(X_t, X_{t+1}) therefore has mean zero, and the chains are
// independent: a one-sample t-test across chains (in the checks) tests it.
// Antisymmetric functions used (differences of a function of the state, h(y) - h(x)):
//   segments: path length; raster_x, raster_y: the image position (pixel flux);
//   log_pi: ln pi (the kernel must not drift towards brighter or darker paths).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "estimators/mcmc/kernel_step.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/mcmc/path_space/start_paths.h"

namespace tb::path_space {

struct NetFluxOptions {
  int64_t chains = 128;
  int64_t steps = 200;
  int64_t bootstrap = 64;
  int max_depth = 4;
  uint64_t seed = 1;
  uint64_t key = 0;
};

struct NetFluxSamples {
  std::vector<std::string> names = {"segments", "raster_x", "raster_y", "log_pi"};
  std::vector<std::vector<double>> z;  // [statistic][chain]: b_c sum_t g(X_t, X_{t+1})
  int64_t chains_started = 0, transitions = 0, accepted = 0;
};

// K: a MoveKernel on MltPath (estimators/mcmc/metropolis_hastings.h over the path-space mutations).
template <class K>
NetFluxSamples net_flux(const K& kernel, const PathContext& ctx, const NetFluxOptions& o) {
  NetFluxSamples out;
  const size_t nstat = out.names.size();
  out.z.assign(nstat, std::vector<double>(static_cast<size_t>(o.chains), 0.0));
  std::vector<int64_t> started(static_cast<size_t>(o.chains), 0), acc(static_cast<size_t>(o.chains), 0);
  auto features = [&](const MltPath& x, double pi, double* h) {
    const auto r = path_raster(ctx, x);
    h[0] = x.segments();
    h[1] = r ? r->x : 0.0;
    h[2] = r ? r->y : 0.0;
    h[3] = pi > 0.0 ? std::log(pi) : 0.0;
  };
  parallel_for(static_cast<size_t>(o.chains), [&](size_t c) {
    Rng rng = Rng::for_sample(o.seed, o.key, c);
    RngUniforms u(rng);
    ChainStart s = start_chain(ctx, o.seed ^ o.key, c, o.bootstrap, o.max_depth, u.next());
    if (!s.x) return;  // b_c = 0: contributes Z_c = 0, as it should
    started[c] = 1;
    MltPath x = std::move(*s.x);
    double hx[4], hy[4], sum[4] = {0, 0, 0, 0};
    features(x, kernel.target_density(x), hx);
    for (int64_t t = 0; t < o.steps; ++t) {
      auto tr = mcmc::step(kernel, x, u);
      if (!tr.accepted) continue;
      ++acc[c];
      x = std::move(*tr.proposed);
      features(x, kernel.target_density(x), hy);
      for (size_t i = 0; i < nstat; ++i) {
        sum[i] += hy[i] - hx[i];
        hx[i] = hy[i];
      }
    }
    for (size_t i = 0; i < nstat; ++i) out.z[i][c] = s.b * sum[i];
  });
  for (size_t c = 0; c < static_cast<size_t>(o.chains); ++c) {
    out.chains_started += started[c];
    out.accepted += acc[c];
  }
  out.transitions = o.chains * o.steps;
  return out;
}

}  // namespace tb::path_space
