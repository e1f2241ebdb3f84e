// Veach's path-space Metropolis light transport (Veach 1997, Ch. 11; Veach & Guibas 1997): many
// independent chains on paths (path_state.h), each a Metropolis-Hastings chain over the mixture
// of the bidirectional mutation, the lens, the caustic and the multi-chain perturbation, run by
// the generic kernel of estimators/mcmc/ (Mixture, select_component, HastingsRatio): the
// acceptance of a move by component j is
//   min(1, pi(y) c_j(y) T_j(y -> x) / (pi(x) c_j(x) T_j(x -> y)))
// with the T_j the mutations state, the same functions the detailed-balance checks evaluate.
// Components: 0 bidirectional mutation, 1 lens, 2 caustic, 3 multi-chain perturbation, selected
// with probabilities c_j(x) that depend on the path (MutationSelection), so the ratio
// c_j(y) / c_j(x) enters the acceptance of moves that change the length or the specular structure.
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
// RenderSettings: spp = mutations per pixel over all chains, passes = number of chains (each
// chain is one Welch sample of the film, so >= 32 chains give image tests their samples),
// max_depth + 1 = maximum path length in segments, seed. Chains are seeded by (seed, chain) and
// merged in chain order: images are bit-identical for any thread count.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/caustic_perturbation.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/multi_chain_perturbation.h"
#include "lib/scene/world.h"

namespace tb::path_space {

// c_j(x): (p_bidir, p_lens, p_caustic, p_multi) normalised, with p_caustic = 0 for paths of fewer
// than two segments (where the caustic perturbation cannot act) and p_multi = 0 for paths without
// the multi-chain structure (multi_chain_levels empty).
struct MutationSelection {
  double p_bidir = 0.4, p_lens = 0.3, p_caustic = 0.3, p_multi = 0.2;
  double operator()(int j, const MltPath& x) const {
    const double pc = x.segments() >= 2 ? p_caustic : 0.0;
    const double pm = p_multi > 0.0 && !multi_chain_levels(x).empty() ? p_multi : 0.0;
    const double sum = p_bidir + p_lens + pc + pm;
    return (j == 0 ? p_bidir : j == 1 ? p_lens : j == 2 ? pc : pm) / sum;
  }
};

struct MltOptions {
  MutationSelection selection;
  int64_t bootstrap_per_chain = 0;  // 0: max(256, 4 P / chains)
  // Deliberate errors for the negative controls of the image checks (never set by `tb render`).
  BidirFault bidir_fault = BidirFault::kNone;
  LensFault lens_fault = LensFault::kNone;
};

struct MutationStats {
  std::string name;
  int64_t proposed = 0;     // times selected
  int64_t failed = 0;       // proposals that returned nothing (the chain stays)
  int64_t accepted = 0;
  double acceptance_sum = 0.0;  // sum of a over proposals
  double acceptance_rate() const { return proposed > 0 ? static_cast<double>(accepted) / proposed : 0.0; }
};

struct MltStats {
  std::vector<MutationStats> mutations;  // bidirectional, lens, caustic, multi-chain
  int64_t chains = 0, mutations_total = 0, chains_without_start = 0;
  double b_mean = 0.0;      // mean of the chains' b_c
  double seconds = 0.0;
  double mutations_per_second() const { return seconds > 0 ? mutations_total / seconds : 0.0; }
};

MltStats run_mlt(const World& world, const RenderSettings& settings, Film& film, const MltOptions& options = {});

}  // namespace tb::path_space

namespace tb {
// The renderer entry point for the integrator registry (name "mlt"): run_mlt with the default
// options; returns the number of chains run (= Welch samples of the film).
int64_t render_mlt(const World& world, const RenderSettings& settings, Film& film);
}  // namespace tb
