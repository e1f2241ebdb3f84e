// Veach's path-space Metropolis light transport (Veach 1997, Ch. 11; Veach & Guibas 1997): many
// independent chains on paths (path_state.h), each a Metropolis-Hastings chain over the mixture
// of the bidirectional mutation, the lens, the caustic and the multi-chain perturbation, run by
// the generic kernel of estimators/mcmc/ (Mixture, select_component, HastingsRatio): the
// acceptance of a move by component j is
//   min(1, pi(y) c_j(y) T_j(y -> x) / (pi(x) c_j(x) T_j(x -> y)))
// with the T_j the mutations state and the terms of mcmc::mixture_terms, the same functions the
// detailed-balance checks evaluate; c_j(x) depends on the path (path_mutations.h).
//
// Estimator (Veach 1997, Sec. 11.3): pixel j has I_j = P int h_j(r(x)) f(x) dmu(x) (P pixels,
// whole-image camera normalisation, docs/camera.md) = P b E_pi[h_j f / Y(f)], b = int Y(f) dmu.
// Per chain:
//  - start-up (Veach 1997, Sec. 11.3.1): n_boot BDPT samples with uniform raster positions over
//    the image; b_c = mean over samples of sum_{s,t} Y(weighted contribution), an unbiased
//    estimate of b; the start path is resampled among all connections proportionally to Y
//    (start_paths.h: start_chain). Then E[b_c g(X_t)] = int g Y(f) dmu for every t: each chain's
//    image is unbiased, whatever its length;
//  - M mutations with expected-value splatting (Veach 1997, Sec. 11.5: x with 1 - a, y with a),
//    each splat f / Y(f), the pass closed with splat scale P b_c / M.
// The target is pluggable (MltOptions::target, MltTarget): with a density pi other than Y(f) the
// start-up estimates int pi dmu (terms w_{s,t} pi / p_{s,t}) and resamples by pi, the acceptance
// uses pi, and the splats are f / pi (mlt-stratified, stratified_mlt.h). Without one the code
// path above is unchanged.
// RenderSettings: spp = mutations per pixel over all chains, passes = number of chains (each
// chain is one Welch sample of the film, so >= 32 chains give image tests their samples),
// max_depth + 1 = maximum path length in segments, seed. Chains are seeded by (seed, chain) and
// merged in chain order: images are bit-identical for any thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lib/film/film.h"
#include "estimators/mcmc/chain_step.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/scene/world.h"

namespace tb::path_space {

// A chain target other than Veach's pi = Y(f) (Hoberock & Hart 2010: any pi > 0 wherever f > 0
// keeps the estimator unbiased). The start-up estimates b = int pi dmu and resamples the start
// path by pi (start_paths.h, the StartupTerm form), the acceptance uses pi (Hastings ratio of the
// kernel, unchanged T and mixture terms), and each state splats f / pi with the pass scale
// P b / M. Built once per run by MltOptions::target (e.g. after a pilot).
struct MltTarget {
  std::function<double(const MltPath& x, const Rgb& f)> density;  // pi(x) from x and f(x); required
  // The start-up term of a connection; empty: w_{s,t} pi(x) / p_{s,t}(x), evaluated as
  // Y(c.value) pi(x) / Y(f(x)) (BDPT's c.value = w_{s,t} f / p_{s,t}; f with visibility, as the
  // chain's). Broken variants of validate/ replace it.
  StartupTerm startup;
  // The divisor of a state's splat f / d; empty: pi. Broken variants of validate/ replace it.
  std::function<double(const MltPath& x, const Rgb& f, double pi)> splat_divisor;
  double brightness = 0.0;    // reported: a brightness the target was built with (0: none)
  int64_t pilot_samples = 0;  // reported: the samples of its pilot
};

struct MltOptions {
  // The mutations of the chains, built for the driver's path context; empty: every registered one
  // (path_mutations.h) with its default weight. Negative controls (validate/) build broken
  // wrappers of the registered ones here.
  std::function<PathMutationList(const PathContext&, const PathMutationSettings&)> mutations;
  int64_t bootstrap_per_chain = 0;  // 0: max(256, 4 P / chains)
  // The chain target, built once for the run's path context and settings; empty: pi = Y(f).
  std::function<MltTarget(const PathContext&, const RenderSettings&)> target;
};

struct MutationStats {
  std::string name;
  int64_t proposed = 0;     // times selected
  int64_t failed = 0;       // proposals that returned nothing (the chain stays)
  int64_t accepted = 0;
  int64_t errors = 0;           // moves with a stated forward density of 0 or non-finite terms
  double acceptance_sum = 0.0;  // sum of a over proposals
  double acceptance_rate() const { return proposed > 0 ? static_cast<double>(accepted) / proposed : 0.0; }
  // Adds one chain's counts of this mutation.
  void add(const mcmc::ComponentCounts& c) {
    proposed += c.proposed;
    failed += c.failed;
    accepted += c.accepted;
    errors += c.errors;
    acceptance_sum += c.acceptance_sum;
  }
};

struct MltStats {
  std::vector<MutationStats> mutations;  // per mutation of the run, in its order
  int64_t chains = 0, mutations_total = 0, chains_without_start = 0;
  double b_mean = 0.0;      // mean of the chains' b_c (of int pi dmu)
  double brightness = 0.0;  // MltTarget::brightness of the run's target (0: plain target)
  int64_t pilot_samples = 0;
  double seconds = 0.0;          // wall time of the chains (start-ups included; a target's pilot not)
  double startup_seconds = 0.0;  // the chains' start-ups, summed over chains (thread time)
  double mutations_per_second() const { return seconds > 0 ? mutations_total / seconds : 0.0; }
};

MltStats run_mlt(const World& world, const RenderSettings& settings, Film& film, const MltOptions& options = {});

// Copies a run's per-mutation counts and rate into the render report (null: nothing); shared by
// the mlt, ramlt-* and hslt entry points.
void fill_report(const MltStats& stats, RunReport* report);

}  // namespace tb::path_space

namespace tb {
// The renderer entry point for the integrator registry (name "mlt"): run_mlt with the default
// options; returns the number of chains run (= Welch samples of the film).
int64_t render_mlt(const World& world, const RenderSettings& settings, Film& film);
}  // namespace tb
