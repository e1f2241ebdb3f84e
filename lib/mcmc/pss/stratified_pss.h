// Differential-informed stratified MCMC (Zirr & Dachsbacher 2020, Sec. 4.3, 6.1, 6.8) on the
// primary-sample-space driver (pss_driver.h), over MMLT's per-length techniques (mmlt-stratified),
// over BDPT (pssmlt-stratified) and over the path tracer with its sample split into paths
// (pssmlt-pt-stratified, and pssmlt-pt-rescaled-stratified with the rescaled small step; r~ of
// each path from the path tracer itself, lib/integrator/path_tracer.h pt_sample_paths).
//
// The changes to MLT of Sec. 6.1, in the driver's terms. A state's splat c carries the MC estimate
// v_c of its pixel (its value; Y = luminance) and the path it came from. With the variance-bounding
// ratio r~_c of that path (Eq. 21 on its camera subpath, lib/differential/variance_bound.h
// subpath_variance_ratio) and the image brightness B (below), the chain targets
//   pi(u) = sum_c W~_c,   W~_c = min{ r~_c, Y(v_c) / B }        (Eq. 8's footnote form, p = 1 in PSS)
// instead of Y(sum_c v_c). The driver splats v_c / pi times its group's P b / N with b = the mean
// of pi over the bootstrap (the estimate of the integral of W~, stratified_target.h): for one
// splat per state (MMLT) that is the bounded-error splat S~ = Y(v) / W~ = max{ Y(v) / r~, B }
// (Eq. 8) carried in the colour of v, with the acceptance of Eq. 22 and the expected-value weights
// A and 1 - A of Sec. 6.8 (the driver's, pss_driver.h). Any pi > 0 wherever a splat is non-zero
// keeps each pass unbiased (Hoberock & Hart 2010; docs/mlt-pss.md), so neither r~ nor B can bias
// the image; they only decide where the mutations go. Where Y(v) / B < r~ (dim or high-variance
// paths) the target is the usual f / B; where a path is brighter than B times its ratio (a
// directly seen emitter: r~ = 1; a specular chain) it is capped, and the mutations it would have
// taken go to the rest of the image (the paper's Fig. 6).
//
// BDPT's camera-raster splat sums the connections of every t >= 2; its r~ is that of the whole
// camera subpath (every sampled direction counted: the largest of the summed techniques' r~, the
// most conservative). Its t = 1 splats have r~ = 1.
//
// B: the brightness of Sec. 4.3, the mean pixel value. In PSS, with the raster uniform over the
// image, that is E_u[Y(sum_c v_c)] = the b of plain PSSMLT / MMLT (summed over levels). It is
// estimated once before the first pass from `pilot` fresh states (levels drawn in turn, as the
// bootstrap does) from randomness of its own, and held fixed: the passes stay independent
// given B, and each is unbiased for any B > 0. A pilot that finds nothing leaves the plain target.
#pragma once

#include <cstdint>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "lib/mcmc/pss/pss_sample.h"
#include "lib/scene/world.h"

namespace tb::pss {

struct StratifiedSettings {
  bool mis_reduction = true;  // Sec. 6.6: an s = 0 path's last direction is left out of r~
  int64_t pilot = 0;          // pilot states for B; 0: PssSettings::bootstrap_for of one pass
  double brightness = 0.0;    // > 0: this B instead of a pilot (checks, tests)
};

// pi(u) for a list of splats (see the top of this file). Thread-safe; reads the splats' paths,
// which are valid while the target is evaluated (pss_sample.h).
class StratifiedTarget {
 public:
  StratifiedTarget(const World& world, double brightness, bool mis_reduction)
      : world_(&world), B_(brightness), mis_reduction_(mis_reduction) {}
  double operator()(const std::vector<Splat>& splats) const;
  // r~ of one splat's path (1 for a splat without a path or with t = 1).
  double ratio(const Splat& s) const;
  double brightness() const { return B_; }

 private:
  const World* world_;
  double B_;
  bool mis_reduction_;
};

// B from n fresh states of f (levels in turn; seed and key of its own): sum over levels of the
// mean of Y(sum of the splat values). Deterministic for any thread count.
double pilot_brightness(const SampleFunction& f, int64_t n, uint64_t seed, double sigma);

struct StratifiedStats {
  PssStats pss;
  double brightness = 0.0;     // B used
  int64_t pilot_samples = 0;
};

// Runs the PSS driver on f with the stratified target (pss.target is replaced).
int64_t run_stratified(const SampleFunction& f, const World& world, const RenderSettings& settings,
                       const PssSettings& pss, const StratifiedSettings& ss, Film& film, StratifiedStats* stats);

}  // namespace tb::pss

namespace tb {

// The registered renderers (PssSettings from RenderSettings::params, as mmlt and pssmlt).
int64_t render_mmlt_stratified(const World& world, const RenderSettings& settings, Film& film);
int64_t render_pssmlt_stratified(const World& world, const RenderSettings& settings, Film& film);
// Over the path tracer, its sample split into paths (pss_sample.h pt_paths_sample_function), with
// the plain and with the throughput-rescaled small step (the paper's "rescaled PSSMLT").
int64_t render_pssmlt_pt_stratified(const World& world, const RenderSettings& settings, Film& film);
int64_t render_pssmlt_pt_rescaled_stratified(const World& world, const RenderSettings& settings, Film& film);
// With explicit settings and statistics.
int64_t render_mmlt_stratified(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                               const pss::StratifiedSettings& ss, Film& film, pss::StratifiedStats* stats);
int64_t render_pssmlt_stratified(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                                 const pss::StratifiedSettings& ss, Film& film, pss::StratifiedStats* stats);
int64_t render_pssmlt_pt_stratified(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                                    const pss::StratifiedSettings& ss, Film& film, pss::StratifiedStats* stats);

}  // namespace tb
