// Flux symmetry by bins (docs/validation.md E, "flux symmetry"), each MLT variant binned by pixel
// and path length. For a kernel reversible with respect to pi, at
// stationarity the expected number of transitions from bin A to bin B equals that from B to A
// (pi(A) P(A -> B) = pi(B) P(B -> A)), so given N_AB + N_BA crossings between A and B, N_AB is
// Binomial(N_AB + N_BA, 1/2). Bins: (pixel block of block x block pixels) x (path length).
//
// Stationarity: chains start from importance-resampled paths (start_paths.h: start_chain), whose
// law approaches pi as the bootstrap grows, then run burn_in steps before counting. (Only the
// b_c-weighted statistics of net_flux.h are exactly stationary at every step; the counts here are
// unweighted, as the binomial test needs.) A kernel whose stated T is wrong has another invariant
// law pi' and drifts from pi towards it: during the counted steps the drift shows as a net flow
// between bins. The burn-in is therefore short (a few steps per chain, the counts come from many
// chains), which is what lets the test see such a drift; see docs/mlt-path-space.md.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "estimators/mcmc/kernel_step.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "validate/stats/tests.h"

namespace tb::path_space {

struct FluxBinOptions {
  int64_t chains = 512;
  int64_t burn_in = 8;
  int64_t steps = 200;
  int64_t bootstrap = 64;
  int max_depth = 4;
  int block = 4;  // pixels per bin side
  uint64_t seed = 1;
  uint64_t key = 0;
};

struct FluxBinCounts {
  std::map<std::pair<int, int>, int64_t> n;  // (from bin, to bin) -> accepted transitions, from != to
  int64_t chains_started = 0, transitions = 0, crossings = 0;
};

// Bin of a path: pixel block and length; -1 when the path has no raster position.
inline int flux_bin(const PathContext& ctx, const MltPath& x, int block, int max_depth) {
  const auto r = path_raster(ctx, x);
  if (!r) return -1;
  const Camera& cam = ctx.world->camera();
  const int nbx = (cam.width() + block - 1) / block;
  const int bx = std::clamp(static_cast<int>(r->x) / block, 0, nbx - 1);
  const int by = std::clamp(static_cast<int>(r->y) / block, 0, (cam.height() + block - 1) / block - 1);
  return (by * nbx + bx) * (max_depth + 2) + x.segments();
}

// K: a MoveKernel on MltPath (estimators/mcmc/metropolis_hastings.h).
template <class K>
FluxBinCounts flux_bins(const K& kernel, const PathContext& ctx, const FluxBinOptions& o) {
  std::vector<std::map<std::pair<int, int>, int64_t>> local(static_cast<size_t>(o.chains));
  std::vector<int64_t> started(static_cast<size_t>(o.chains), 0);
  parallel_for(static_cast<size_t>(o.chains), [&](size_t c) {
    Rng rng = Rng::for_sample(o.seed, o.key, c);
    RngUniforms u(rng);
    ChainStart s = start_chain(ctx, o.seed ^ o.key, c, o.bootstrap, o.max_depth, u.next());
    if (!s.x) return;
    started[c] = 1;
    MltPath x = std::move(*s.x);
    int bx = flux_bin(ctx, x, o.block, o.max_depth);
    for (int64_t t = 0; t < o.burn_in + o.steps; ++t) {
      auto tr = mcmc::step(kernel, x, u);
      if (!tr.accepted) continue;
      x = std::move(*tr.proposed);
      const int by = flux_bin(ctx, x, o.block, o.max_depth);
      if (t >= o.burn_in && by != bx && bx >= 0 && by >= 0) ++local[c][{bx, by}];
      bx = by;
    }
  });
  FluxBinCounts out;  // merged in chain order: deterministic for any thread count
  for (size_t c = 0; c < local.size(); ++c) {
    out.chains_started += started[c];
    for (const auto& [k, v] : local[c]) {
      out.n[k] += v;
      out.crossings += v;
    }
  }
  out.transitions = o.chains * o.steps;
  return out;
}

// The binomial test of flux symmetry over the bin pairs of c: N_AB ~ Binomial(N_AB + N_BA, 1/2) for
// each unordered pair with at least min_crossings crossings (a pair seen in one direction only
// included), Šidák over the pairs tested.
struct FluxBinTest {
  int64_t tested = 0;     // bin pairs tested
  double p_min = 1.0;     // smallest binomial p
  double p_family = 1.0;  // Šidák-adjusted p_min (1 when nothing is tested)
  std::pair<int, int> worst{-1, -1};
  int64_t worst_ab = 0, worst_ba = 0;
};

inline FluxBinTest flux_bin_test(const FluxBinCounts& c, int64_t min_crossings) {
  FluxBinTest t;
  const auto consider = [&](std::pair<int, int> ab, int64_t nab, int64_t nba) {
    if (nab + nba < min_crossings) return;
    ++t.tested;
    const double p = stats::binomial_test(nab, nab + nba, 0.5).p_value;
    if (p < t.p_min) {
      t.p_min = p;
      t.worst = ab;
      t.worst_ab = nab;
      t.worst_ba = nba;
    }
  };
  for (const auto& [ab, nab] : c.n) {
    const auto it = c.n.find({ab.second, ab.first});
    if (ab.first < ab.second) consider(ab, nab, it == c.n.end() ? 0 : it->second);  // each pair once
    else if (it == c.n.end()) consider({ab.second, ab.first}, 0, nab);  // seen only as B -> A with B > A
  }
  t.p_family = t.tested > 0 ? stats::sidak_adjust(t.p_min, t.tested) : 1.0;
  return t;
}

}  // namespace tb::path_space
