// The `apt` integrator: Zirr & Dachsbacher 2020's MCMC over path-tracer paths (Sec. 7): the adaptive
// forward path sampling small step (Sec. 7.1, Listing 1; lib/mcmc/apt_small_step.h) and the path
// tracer as a multiple-try reversible-jump large step (Sec. 7.2, Listing 2, App. D, Eq. 27-29;
// estimators/mcmc/prefix_multiple_try.h). docs/zirr2020.md, "The apt integrator", has the
// derivation and the deviations from the paper.
//
// State: (k, u), k = 1..K vertices after the pinhole eye (K = max_depth + 1), u in [0,1)^{3k-1} the
// primary samples of apt_small_step.h; target pi(k, u) = f_k(u) (luminance of the BSDF-sampled path
// without next-event estimation, AptTarget(k).density). The models of the prefix family are the path
// lengths; a draw U in [0,1)^{3K-1} is traced once and every prefix of k vertices ending on an
// emitter is a candidate with weight W_k(U) = f_k(U[0, 3k-1)).
//
// One film pass = one independent group of chains (a Welch sample), as the PSS driver
// (lib/mcmc/pss/pss_driver.h):
//   1. bootstrap: M fresh draws U_i, b = mean of S(U_i) = sum_k W_k(U_i) (b = integral of pi over the
//      union of the path spaces: E[S(U)] = sum_k integral f_k);
//   2. each chain starts at a draw resampled in proportion to S(U_i), at its candidate k chosen in
//      proportion to W_k(U_i) (sampling-importance resampling);
//   3. each mutation is mcmc::chain_step (estimators/mcmc/chain_step.h): the large step with
//      probability large_step_probability, else the APT small step at the current k; the proposed
//      and the current state are splatted with weights a and 1 - a, each with value v / f times
//      P b / N (P pixels, N mutations of the pass), v the path's colour;
//   4. end_pass(1).
// Determinism: bootstrap draw i of pass p from Rng::for_sample(seed, key_bootstrap, p M + i); chain
// c of pass p from Rng::for_sample(seed, key_chain / key_state, p C + c); chains run in parallel over
// segments of mutations whose splat buffers are merged in chain order: bit-identical for any thread
// count.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/prefix_multiple_try.h"
#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/apt_small_step.h"
#include "lib/scene/world.h"

namespace tb::apt {

// The path lengths k = 1..K as the models j = k - 1 of a prefix family (prefix_multiple_try.h).
class AptPathFamily {
 public:
  AptPathFamily(const World& world, int max_vertices);
  int models() const { return static_cast<int>(targets_.size()); }
  size_t dimension(int j) const { return targets_[static_cast<size_t>(j)].dimension(); }
  double density(const mcmc::ModelState& x) const { return targets_[static_cast<size_t>(x.model)].density(x.u); }
  // W_j(U) for a draw of 3K - 1 coordinates: one trace (AptTarget::trace_prefix of the longest length).
  void weights(const std::vector<double>& U, std::vector<double>* w) const;
  const mcmc::AptTarget& target(int j) const { return targets_[static_cast<size_t>(j)]; }

 private:
  const World* world_;
  std::vector<mcmc::AptTarget> targets_;
};

// Film weight of a splat of a state of target pi with expected-value weight w: empty (the
// estimator) w / pi. Only negative controls (validate/) set it.
using SplatWeight = std::function<double(mcmc::Which, double w, double pi)>;

struct AptSettings {
  double large_step_probability = 0.3;
  int64_t chains = 64;    // per pass
  int64_t bootstrap = 0;  // draws per pass; 0: N / 8 clamped to [8192, 100000] (the PSS driver's rule)
  int64_t segment = 1024;  // mutations per chain between splat merges
  SplatWeight splat_weight;
  // A bootstrap draw's weight from its candidates' W_k; empty (the estimator): S = sum_k W_k. Only
  // negative controls (validate/) set it.
  std::function<double(const std::vector<double>& w)> bootstrap_sum;
  int64_t bootstrap_for(int64_t N) const;
};

struct AptStats {
  mcmc::ComponentCounts small, large;
  int64_t mutations = 0, bootstrap_samples = 0, zero_passes = 0, step_errors = 0;
  double seconds = 0.0, mutation_seconds = 0.0, last_b = 0.0;
  double mutations_per_second() const { return mutation_seconds > 0 ? double(mutations) / mutation_seconds : 0.0; }
  std::string message() const;
};

// Applies RenderSettings::params (large_step, chains, bootstrap); throws std::invalid_argument on an
// unknown name or a value out of range.
void apply_params(const std::map<std::string, double>& params, AptSettings* a);

int64_t run_apt(const World& world, const RenderSettings& settings, const AptSettings& apt, Film& film,
                AptStats* stats = nullptr);

}  // namespace tb::apt

namespace tb {
// The registered renderer (default settings and RenderSettings::params; statistics into the report).
int64_t render_apt(const World& world, const RenderSettings& settings, Film& film);
}  // namespace tb
