// Multi-stage MLT (Hoberock & Hart 2010, "Arbitrary importance functions for Metropolis light
// transport") in primary sample space, over BDPT (msmlt) and over MMLT's per-length sample function
// (msmlt-mmlt): the chain's target is the path's contribution divided by a low-resolution estimate
// of the image it lands in, so that every pixel receives about the same number of mutations
// (Zirr & Dachsbacher 2020, Sec. 4.1, Eq. 3-4: W'(X) = f(X) sum_j h_j(X) / I_j; their Fig. 6).
//
// Stages of one pass (Hoberock & Hart 2010, Sec. 5, "recursively refined" guides; base B, K stages):
//   stage K: an independent estimate of the image at resolution film / B^K (M fresh samples of the
//            sample function, each splat v_c at raster r_c: I_K(J) = P / (M |J|) sum_samples
//            sum_c Y(v_c) 1[r_c in J], |J| the fine pixels of coarse pixel J);
//   stage k = K-1 .. 1: PSS chains with the target of guide I_(k+1) render the image at full
//            resolution; its box average over B^k x B^k blocks is the guide I_k;
//   stage 0: PSS chains with the target of guide I_1 render the film pass.
// Guide lookup: I~(r) = max(I_k(J(r)), phi * mean_J I_k(J)), J(r) the coarse pixel holding raster
// r (nearest, no interpolation), phi = floor_fraction: I~ never divides by ~0 where the coarse
// estimate found nothing. A guide that found nothing at all is replaced by I~ = 1 (plain PSSMLT).
//
// Target and estimator of a stage, given its guide (fixed while the stage's chains run):
//   pi(u) = Y( sum_c v_c(u) / I~(r_c(u)) )               (Y = luminance; v_c >= 0 so pi > 0 iff any v_c != 0)
//   b     = (1/M) sum_{m=1..M} pi(u_m),   u_m fresh        (bootstrap, unbiased for int pi du)
//   Phi_j = P b (1/N) sum_{i=1..N} sum_{Z in {x_i, y_i}} w_i(Z) sum_c v_c(Z) 1[r_c(Z) in j] / pi(Z)
// with w_i(y_i) = a_i, w_i(x_i) = 1 - a_i (expected-value splats), N mutations, P pixels, chains
// started from the bootstrap by resampling proportional to pi (pss_driver.h, docs/mlt-pss.md,
// "Normalisation": E[b h(u_J)] = int pi h du exactly). Since pi > 0 wherever f != 0,
// E_pi[sum_c v_c 1[r_c in j] / pi] * int pi du = int sum_c v_c 1[r_c in j] du = Phi_j / P: the pass
// is unbiased for any guide. The guide is built from randomness independent of the final stage's,
// so the film pass is unbiased unconditionally; the earlier stages only shape pi and are not added
// to the film (Hoberock & Hart combine them; we keep the estimate that is provably unbiased).
// The negative control "splat throughput" (validate/render/broken_pss.h, a PssSettings::splat_weight)
// splats v / Y(sum v) instead of v / pi: the image is then the PSSMLT estimator of a wrongly weighted distribution (biased towards dark pixels).
//
// Cost: stage k makes stage_budget * N / B^(2k) mutations (the same mutations per pixel of its own
// resolution, Hoberock & Hart), about N / 3 extra for B = 2; plus a bootstrap of bootstrap / B^(2k)
// samples per guide stage (at least 2 per chain) and max(64 per coarse pixel, N / B^(2K))
// independent samples for stage K.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "lib/scene/world.h"

namespace tb {
namespace pss {

struct MultiStageSettings {
  int base = 2;                  // resolution ratio B between consecutive stages
  int stages = 3;                // K: the coarsest guide is at film / B^K (an independent estimate)
  double floor_fraction = 0.05;  // phi: I~ >= phi * mean of the guide
  double stage_budget = 1.0;     // stage k (k >= 1) makes stage_budget * N / B^(2k) mutations
  int64_t guide_samples = 0;     // independent samples of stage K (0: max(64 per coarse pixel, budget N / B^(2K)))
};

// A guide image: a coarse luminance estimate with its floor, looked up at a film raster position.
class GuideImage {
 public:
  GuideImage() = default;
  // From a full-resolution image (width x height), box-averaged over factor x factor blocks.
  GuideImage(const std::vector<Rgb>& fine, int width, int height, int factor, double floor_fraction);
  // From per-coarse-pixel luminances (cw x ch = ceil(width / factor) x ceil(height / factor)).
  GuideImage(std::vector<double> coarse, int width, int height, int factor, double floor_fraction);
  // I~(r) (see the top of this file); 1 for a raster outside the film.
  double at(const Vec2& raster) const;
  // pi(u) = Y(sum_c v_c / I~(r_c)).
  double target(const std::vector<Splat>& splats) const;
  int coarse_width() const { return cw_; }
  int coarse_height() const { return ch_; }
  double floor_value() const { return floor_; }
  const std::vector<double>& coarse() const { return coarse_; }

 private:
  void finish(double floor_fraction);
  std::vector<double> coarse_;
  int width_ = 0, height_ = 0, factor_ = 1, cw_ = 0, ch_ = 0;
  double floor_ = 1.0;
  bool uniform_ = true;  // no guide information: I~ = 1
};

struct MultiStageStats {
  PssStats final_stage;  // the film's chains (visit counts when PssSettings::count_visits)
  PssStats guides;       // the guide stages' chains
  int64_t guide_samples = 0;
  double seconds = 0.0;
  GuideImage last_guide;  // the guide of the last pass's final stage
};

// Renders settings.passes passes; each pass runs all stages (see the top of this file) and adds
// one Welch sample to the film. Returns the number of passes done.
int64_t run_msmlt(const SampleFunction& f, const RenderSettings& settings, const PssSettings& pss,
                  const MultiStageSettings& ms, Film& film, MultiStageStats* stats = nullptr);

}  // namespace pss

// Registered renderers: multi-stage PSSMLT over BDPT, and over MMLT's per-length sample function.
int64_t render_msmlt(const World& world, const RenderSettings& settings, Film& film);
int64_t render_msmlt_mmlt(const World& world, const RenderSettings& settings, Film& film);
int64_t render_msmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& pss,
                     const pss::MultiStageSettings& ms, Film& film, pss::MultiStageStats* stats);
int64_t render_msmlt_mmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& pss,
                          const pss::MultiStageSettings& ms, Film& film, pss::MultiStageStats* stats);

}  // namespace tb
