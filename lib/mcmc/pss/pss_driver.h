// Primary-sample-space Metropolis light transport: the chain driver, generic over a sample
// function (pss_sample.h), and the two registered renderers built on it:
//   pssmlt  Kelemen et al. 2002 over BDPT (target: luminance of all weighted connections of one
//           camera + light subpath pair);
//   mmlt    Hachisuka, Kaplanyan & Dachsbacher 2014 (one chain set per path length, one
//           technique per sample, chosen by a uniform of the state).
//
// One film pass = one independent group of chains (a Welch sample, docs/validation.md A):
//   1. bootstrap: M independent samples u_j per level (fresh uniforms), I_j = I(level, u_j);
//      b_l = mean of I over level l (Kelemen 2002, Sec. 5.2: b = E[I(u)]), b = sum_l b_l;
//   2. chains start at bootstrap samples drawn with probability I_j / sum I (sampling-importance
//      resampling; with b from the same samples the estimate is exactly unbiased, docs/mlt-pss.md).
//      PSSMLT: one group of C chains. MMLT: one chain set per level (path length), its share of the
//      mutations N_l fixed by an independent pilot bootstrap before the first pass (0.9 b_l / b +
//      0.1 / levels), each set resampling within its level; or, with resample_levels, pbrt-v3's
//      rule (each chain draws its level with its start from the joint bootstrap);
//   3. each chain makes its share of the mutations with the one step of estimators/mcmc/
//      chain_step.h over the registered mutations (pss_mutation.h; default: the large step with
//      probability p_large, else the small step), accepted by mcmc::decide with the Hastings terms of
//      pss_move_terms (the large and the fixed small step are symmetric; the rescaled small step is
//      not, and carries its T ratio); the proposed and the current state are both splatted with
//      weights a and 1 - a, each splat value v divided by I and multiplied by its group's
//      P b_group / N_group (P pixels; derivation in docs/mlt-pss.md, "Normalisation");
//   4. end_pass(1): the splats carry their scale.
// Options: a custom target pi (PssSettings::target; splats are then v / pi, b = mean of pi, used by
// the multi-stage driver msmlt.h), the rescaled small step (PssSettings::rescale), or any list of
// registered mutations (PssSettings::mutations).
//
// Determinism: bootstrap sample j of pass p uses Rng::for_sample(seed, key_bootstrap, p * L * M
// + j); chain c of pass p uses Rng::for_sample(seed, key_chain, p * C + c) for its decisions and
// key_state for its uniforms; chains run in parallel over fixed segments of mutations whose
// splat buffers are merged in (segment, chain) order: bit-identical for any thread count.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "estimators/mcmc/chain_step.h"
#include "lib/mcmc/pss/pss_mutation.h"
#include "lib/mcmc/pss/pss_sample.h"
#include "lib/scene/world.h"

namespace tb {

namespace pss {

// The chain's scalar target pi(u) from the splats of a state (empty: target_value, the luminance
// of the sum). Any pi > 0 wherever a splat is non-zero keeps the estimator unbiased (msmlt.h).
using TargetFunction = std::function<double(const std::vector<Splat>&)>;

// The factor a state's splat values are multiplied by before the group scale P b / N: given which
// state (current or proposed), its expected-value weight w, its target pi and its splats. Empty
// (the estimator): w / pi. Only negative controls (validate/) set it.
using SplatWeight = std::function<double(mcmc::Which, double w, double pi, const std::vector<Splat>&)>;

// Small-step rescaling by the current target value (the "rescaled small step" of pss_steps.h):
// sigma(x) = clamp(sigma0 (Y_ref / Y(x))^kappa, sigma_min, sigma_max), Y_ref = b of the pass.
struct StepRescaling {
  bool enabled = false;
  double exponent = 1.0;     // kappa: sigma inversely proportional to Y (Zirr 2020, Sec. 8)
  double sigma_min = 1e-4;   // keeps the step above the double resolution of wrapped Gaussians
  double sigma_max = 0.1;    // beyond ~0.3 the wrapped Gaussian is nearly uniform: a large step
};

struct PssSettings {
  double large_step_probability = 0.3;  // Kelemen et al. 2002, Sec. 5.3 (pbrt-v3 default 0.3)
  double sigma = 0.01;                  // small-step standard deviation (pbrt-v3 default)
  // Bootstrap samples per pass, split evenly over levels; 0 (default): bootstrap_for(N, levels).
  int64_t bootstrap = 0;
  int64_t chains = 64;                  // chains per pass (at most one per mutation)
  int64_t segment = 1024;               // mutations per chain between splat merges (memory bound)
  // Levels (MMLT path lengths). false: one chain set per level, its share of the mutations fixed
  // by a pilot bootstrap (stratified over levels; docs/mlt-pss.md). true: as pbrt-v3, every
  // chain draws its level with its start from the joint bootstrap distribution.
  bool resample_levels = false;
  // The mutations (pss_mutation.h). Empty: the registered "large step" with probability
  // large_step_probability and "small step" (or, with rescale.enabled, "rescaled small step").
  PssMutationList mutations;
  SplatWeight splat_weight;             // empty: the estimator's w / pi (negative controls only)
  // Wraps the sample function the driver runs (negative controls only: a broken variant of the
  // real one, validate/render/broken_pss.h).
  std::function<SampleFunction(const SampleFunction&)> wrap_sample;
  bool print_stats = false;             // acceptance rates and mutations/s to stderr
  // Small-step sigma rescaled by the current target value ("rescaled small step", pss_steps.h), Y_ref = b of the pass.
  StepRescaling rescale;
  // The settings of the registered mutations, and the list they make (mutations, when set).
  PssStepSettings step_settings() const;
  PssMutationList mutation_list() const;
  // The bootstrap of a pass of N mutations: `bootstrap` when set, else N / 8 clamped to
  // [8192, 100000], for one level and for MMLT alike. b's error is common to all pixels of a
  // pass, so it only has to stay well below a pixel's, which sees about N / P mutations; measured
  // on the Cornell box at 128 x 128, 64 mutations per pixel in 8 passes (docs/mlt-pss.md,
  // "Bootstrap size"): MMLT's relMSE is 0.0232 with 100000 bootstrap samples per pass and 0.0235
  // with 16384 (N / 8), at 37% less work. The statistical checks set their own, larger bootstrap.
  int64_t bootstrap_for(int64_t N, int /*levels*/) const {
    if (bootstrap > 0) return bootstrap;
    return std::clamp<int64_t>(N / 8, 8192, 100000);
  }
  TargetFunction target;                // empty: luminance of the splat sum
  int64_t mutations_per_pass = 0;       // > 0: replaces spp per pass * pixels (multi-stage guides)
  bool count_visits = false;            // PssStats::visits: per pixel, mutations whose state lies there
};

struct PssStats {
  // Per mutation (in the order of the list the driver ran): its name and counts.
  std::vector<std::pair<std::string, mcmc::ComponentCounts>> components;
  // Sums over the independent (large) and the other mutations, for the report.
  int64_t large_proposed = 0, large_accepted = 0;
  int64_t small_proposed = 0, small_accepted = 0;
  int64_t mutations = 0;
  int64_t bootstrap_samples = 0;
  int64_t zero_passes = 0;  // passes whose bootstrap found no contribution (b = 0)
  int64_t nonfinite = 0;    // states whose target I was NaN or infinite (read as I = 0, never splatted)
  int64_t step_errors = 0;  // moves whose Hastings terms were not finite or whose forward density was 0
  double seconds = 0.0;     // wall time of the whole run, bootstrap included
  double mutation_seconds = 0.0;  // wall time of the chains' mutations only
  double last_b = 0.0;      // b of the last pass
  // With PssSettings::count_visits: per pixel (y * width + x), the mutations after which the
  // chain's state lies in it, summed over passes; a state spreads its one unit over the pixels of
  // its splats in proportion to each splat's own target value (for BDPT: the camera pixel and the
  // pixels its t = 1 connections reach).
  std::vector<double> visits;
  // Coefficient of variation (standard deviation / mean) of visits over the pixels.
  double visits_cv() const;
  // Adds the counts of another run (visits summed, wall times added, b of `o`).
  void add(const PssStats& o);
  double large_acceptance() const { return large_proposed ? double(large_accepted) / double(large_proposed) : 0.0; }
  double small_acceptance() const { return small_proposed ? double(small_accepted) / double(small_proposed) : 0.0; }
  // Mutations per second of the mutation phase (bootstrap and chain starts excluded).
  double mutations_per_second() const { return mutation_seconds > 0 ? double(mutations) / mutation_seconds : 0.0; }
  std::string message() const;
};

// Expected number of mutations per pass that a chain spends in each pixel at stationarity,
// mutations * luminance(pixel) / sum of luminances, from an image of the same scene (a reference).
// PSSMLT distributes mutations in proportion to brightness: a pixel visited a handful of times per
// pass has far-from-normal Welch samples, which the image checks exclude (docs/mlt-pss.md).
std::vector<double> expected_visits(const std::vector<Rgb>& image, int64_t mutations);

// Effective number of independent visits per pass of each pixel (y * width + x) by a chain
// targeting pi, from n fresh states per level (seed and key of their own; deterministic for any
// thread count). A pass estimates pixel j as P b_l / N_l sum_i Y_j(x_i) / pi(x_i) over each level's
// N_l mutations, x_i ~ pi / b_l; with independent x_i its relative variance is 1 / n_j,
//   n_j = I_j^2 / sum_l (b_l E_u[Y_j^2 / pi] / N_l),   I_j = sum_l E_u[Y_j],   b_l = E_u[pi],
// Y_j(u) the luminance of the state's splats in pixel j, E_u over uniform states of level l. For
// the plain target (pi = Y of the one pixel a state splats to) n_j = N Y_j / b, expected_visits.
// A target that caps bright states (stratified_pss.h) makes n_j small where a pixel's value comes
// from states the chain rarely visits; such a pixel's Welch samples are heavy-tailed
// (docs/zirr2020.md). N_l from level_shares (one level, or resample_levels: N).
std::vector<double> effective_visits(const SampleFunction& f, const TargetFunction& target, int width, int height,
                                     int64_t mutations, int64_t n, uint64_t seed, bool resample_levels = false);

// The share of a pass's mutations each level's chain set gets when the levels are not resampled:
// 0.9 b_l / b + 0.1 / L from the pilot's b_l (1 for a single level; 1 / L when the pilot found
// nothing). The chains of a level are its share of PssSettings::chains, at least one.
std::vector<double> level_shares(const std::vector<double>& pilot_b);

// Renders settings.passes passes of settings.spp / settings.passes mutations per pixel each.
// Returns the number of passes done.
// Applies RenderSettings::params (bootstrap, chains, large_step, sigma) to PssSettings; throws
// std::invalid_argument on an unknown name or a value out of range.
void apply_params(const std::map<std::string, double>& params, PssSettings* p);

int64_t run_pss(const SampleFunction& f, const RenderSettings& settings, const PssSettings& pss, Film& film,
                PssStats* stats = nullptr);

// Fills the RunReport of `tb render` (nothing if report is null): acceptance per mutation type.
void fill_report(const PssStats& s, RunReport* report, const char* small_step_name = "small step");

}  // namespace pss

// The registered renderers (default PssSettings; acceptance rates printed to stderr).
int64_t render_pssmlt(const World& world, const RenderSettings& settings, Film& film);
int64_t render_mmlt(const World& world, const RenderSettings& settings, Film& film);
// PSSMLT over the path tracer (lib/integrator/path_tracer.h pt_sample): the target is the
// luminance of one path-traced radiance sample.
int64_t render_pssmlt_pt(const World& world, const RenderSettings& settings, Film& film);
int64_t render_pssmlt_pt(const World& world, const RenderSettings& settings, const pss::PssSettings& pss, Film& film,
                         pss::PssStats* stats);
// The same with explicit MCMC settings and statistics.
int64_t render_pssmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& pss, Film& film,
                      pss::PssStats* stats);
int64_t render_mmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& pss, Film& film,
                    pss::PssStats* stats);
// PSSMLT over the path tracer with the small step rescaled by the path's luminance ("rescaled small step", pss_steps.h).
int64_t render_pssmlt_pt_rescaled(const World& world, const RenderSettings& settings, Film& film);

}  // namespace tb
