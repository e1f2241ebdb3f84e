// Regional adaptive Metropolis light transport (Otsu, Herveau, Hanika, Nowrouzezahrai,
// Dachsbacher, "Regional Adaptive Metropolis Light Transport"): path-space MLT (mlt.h: the same
// start-up, estimator and expected-value splats) whose chains mix the bidirectional mutation
// (Veach 1997, Sec. 11.4.2) with one regional adaptive perturbation (ramlt_perturbations.h), 0.5 /
// 0.5, the bidirectional mutation alone where the perturbation cannot act (Otsu Sec. 8.1).
//
// Adaptation (Otsu Algorithm 1, Eq. 4-6, estimators/mcmc/adaptation.h, OtsuSignUpdate): each
// proposal of the perturbation made from a path in region k reports a(x -> y) to region k (a
// failed proposal reports 0); every L reports lambda_k moves by gamma_j sgn(a_hat_k - a*). The
// defaults are Otsu Sec. 8.1: lambda0 = 1, L = 10, gamma_max = 1, gamma_scale = 5, lambda >= -30,
// a* = 0.5 (estimators/mcmc/adaptation.h), grid N_top = 20.
//
// All chains share one lambda per region and adapt in synchronous batches (the scheme of
// estimators/mcmc/adaptive_chains.h, with splats): every chain runs `batch_steps` steps with lambda
// frozen, recording (region of x, a); then the reports are applied in chain order, each chain's in
// step order. The image and the maps are a function of (seed, settings, options) only: bit-identical
// for any thread count. Within a batch each chain runs a fixed Metropolis-Hastings kernel that
// leaves pi invariant; across batches lambda depends on the chains' past, so the per-chain
// unbiasedness argument of mlt.h holds only as the adaptation diminishes (gamma_j -> 0, Otsu Sec.
// 4.3); docs/ramlt.md. The chains are coupled through lambda and always all run: a pass range
// (first_pass / pass_count) receives its chains of the whole run (the same film as cutting the
// whole run, at the cost of the whole run); time budgets are not supported.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "estimators/mcmc/adaptation.h"
#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/scene/world.h"

namespace tb::path_space {

enum class RamltPerturbation { kLens, kMultiChain };

struct RamltOptions {
  RamltPerturbation perturbation = RamltPerturbation::kLens;
  // fixed | global | grid | quadtree (estimators/mcmc/partition.h), and for the multi-chain
  // perturbation grid4d | quadtree4d (Otsu Sec. 5.4, 6.3: N_top^2 screen cells for sigma_1, each
  // split into N_bottom^2 direction cells or a quadtree over the direction for sigma_2).
  std::string partition = "grid";
  int grid = 20;                     // N_top: grid x grid screen cells (Otsu Sec. 8.1)
  int grid_bottom = 50;              // N_bottom: direction cells per side of grid4d (Otsu Sec. 8.1)
  // Quadtree (Otsu Sec. 6.2, defaults of Sec. 8.1): after every refine_every mutations (all chains
  // together, at the next batch boundary) each leaf with more than split_threshold reports since
  // the last refinement is split once; children inherit lambda and n_k / 4 updates.
  int64_t split_threshold = 5000;    // M_split
  int64_t refine_every = 10000000;   // M_refine
  int quadtree_max_depth = 12;
  mcmc::AdaptationOptions adaptation;  // Otsu Sec. 8.1 defaults
  double perturbation_weight = 0.5, bidirectional_weight = 0.5;
  // Steps per chain per synchronous batch; 0: ceil(L * regions / chains), so that a batch makes
  // about one update per region (adaptive_chains.h), at most the chain length.
  int64_t batch_steps = 0;
  int64_t bootstrap_per_chain = 0;  // 0: max(256, 4 P / chains), as mlt.h
  // Keep every batch of L reports of the screen-level adapter in RamltStats::record (validate/).
  bool keep_record = false;
  // Negative controls (validate/): receives the mixture {bidirectional, perturbation} and returns it
  // with broken wrappers in place (same order).
  std::function<PathMutationList(PathMutationList)> wrap;
};

// Per region (quadtree: per leaf of the final tree, reports counted since the leaf was made): final lambda, reports (visits of proposals of the perturbation), mean acceptance,
// number of updates; and the region of every film pixel (for the maps).
struct RamltRegionMaps {
  std::string partition;
  int regions = 0;
  std::vector<double> lambda, acceptance_sum;
  std::vector<int64_t> visits;
  std::vector<int> updates;
  int width = 0, height = 0;
  std::vector<int> pixel_region;
  std::vector<std::array<double, 4>> leaf_boxes;  // quadtree: (x0, y0, x1, y1) of each region in [0, 1]^2
  int refinements = 0;                            // quadtree refinement passes that split a leaf
  // 4d partitions (grid4d, quadtree4d): the screen level above holds sigma_1; these the 4d regions
  // of sigma_2 (lambda, reports, acceptance sum, updates, screen cell of each region).
  int regions2 = 0;
  std::vector<double> lambda2, acceptance_sum2;
  std::vector<int64_t> visits2;
  std::vector<int> updates2, cell2;
  double acceptance(int r) const {
    return visits[static_cast<size_t>(r)] > 0 ? acceptance_sum[static_cast<size_t>(r)] / static_cast<double>(visits[static_cast<size_t>(r)]) : 0.0;
  }
};

struct RamltStats {
  MltStats mlt;
  RamltRegionMaps maps;
  int64_t batches = 0, batch_steps = 0;
  double adaptation_seconds = 0.0;  // applying the reports to the adapter and publishing lambda
  std::vector<mcmc::AdaptationUpdateRecord> record;   // RamltOptions::keep_record (screen level)
};

RamltStats run_ramlt(const World& world, const RenderSettings& settings, Film& film, const RamltOptions& options = {});

// The numeric options by name (`tb render --param NAME=VALUE`, RenderSettings::params): "grid"
// (N_top), "grid_bottom" (N_bottom), "refine_every" (M_refine), "split_threshold" (M_split), "lambda0", "target_acceptance"
// (a*), "batch_steps"; names not listed are left to the caller's check (validate_params).
RamltOptions apply_ramlt_params(RamltOptions o, const std::map<std::string, double>& params);
// (name, description with its default) of each of them.
std::vector<std::pair<std::string, std::string>> ramlt_parameter_list();

// The maps next to an output: <base>.ramlt.json (every number) and <base>.ramlt_{lambda,
// acceptance,visits}.png (film resolution, each pixel the value of its region, normalised to
// [0, 1]: lambda by its min / max, acceptance as is, visits by the maximum).
void write_ramlt_maps(const RamltRegionMaps& maps, const std::string& base);

}  // namespace tb::path_space

namespace tb {
// Registry entries "ramlt-lens", "ramlt-multichain": run_ramlt with the grid partition.
int64_t render_ramlt(const World& world, const RenderSettings& settings, Film& film,
                     const path_space::RamltOptions& options);
}  // namespace tb
