// The chi-square test of a sampling routine against its own density (docs/validation.md A;
// after Mitsuba 3's chi2.py and pbrt-v4's sampling tests). Samples are drawn from seeded
// streams (Rng::for_sample(seed, key, i)) in parallel and histogrammed on a grid over the
// domain; expected counts integrate the stated pdf over every cell with adaptive
// Gauss-Kronrod quadrature (Boost.Math), times the number of samples; Pearson's test
// (pearson_gof.h) compares the two. Samples outside the domain, and failed samples where the
// pdf integrates to one, are hard failures.
//
// Domains and the measure of the pdf:
//   interval [x0, x1]           pdf w.r.t. length,
//   rectangle [x0,x1]x[y0,y1]   pdf w.r.t. area,
//   sphere / hemisphere (z>=0)  pdf w.r.t. solid angle; binned in (phi, cos theta), where
//                               d omega = d phi d cos(theta), so no Jacobian enters.
//
// Usage (any sampler: (Vec2 u) -> optional<P> or (Uniforms&) -> optional<P>, P = double,
// Vec2 or Vec3 matching the domain; pdf: (P) -> double):
//   auto r = chi2_test(Chi2Domain::hemisphere(), sample_fn, pdf_fn, {.samples = 1000000});
//   r.passed(alpha), r.gof.p_value, r.worst, r.details(), r.observed_heatmap()
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/core/math.h"
#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "validate/check_result.h"
#include "validate/chi2/pearson_gof.h"
#include "validate/plot_spec.h"

namespace tb {

enum class Chi2DomainKind { kInterval, kRectangle, kSphere, kHemisphere };

// A grid over a parameter rectangle (x, y): for spheres x = phi in [0, 2 pi), y = cos theta.
// Odd resolutions keep cell edges off symmetric discontinuities (docs/validation.md A).
struct Chi2Domain {
  Chi2DomainKind kind = Chi2DomainKind::kRectangle;
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;
  int nx = 101, ny = 51;

  static Chi2Domain interval(double a, double b, int n = 101) { return {Chi2DomainKind::kInterval, a, b, 0, 1, n, 1}; }
  static Chi2Domain rectangle(Vec2 lo, Vec2 hi, int nx = 101, int ny = 101) {
    return {Chi2DomainKind::kRectangle, lo.x, hi.x, lo.y, hi.y, nx, ny};
  }
  static Chi2Domain sphere(int n_phi = 101, int n_cos = 51) {
    return {Chi2DomainKind::kSphere, 0, 2 * kPi, -1, 1, n_phi, n_cos};
  }
  static Chi2Domain hemisphere(int n_phi = 101, int n_cos = 51) {
    return {Chi2DomainKind::kHemisphere, 0, 2 * kPi, 0, 1, n_phi, n_cos};
  }
  // The cap cos(theta) >= cos_min around +z (e.g. a cone): finer rows where the mass is;
  // directions below the cap are outside the domain.
  static Chi2Domain spherical_cap(double cos_min, int n_phi = 101, int n_cos = 51) {
    return {Chi2DomainKind::kSphere, 0, 2 * kPi, cos_min, 1, n_phi, n_cos};
  }
  std::string describe() const;
};

struct SamplerChi2Options {
  int64_t samples = 1000000;
  uint64_t seed = 1;
  uint64_t key = 0;             // stream key, e.g. hash_string(check name + configuration)
  double min_expected = 5.0;    // pooling threshold
  int worst_cells = 8;          // how many cells to report by |standardized residual|
  // Per nested Gauss-Kronrod level. A cell's expected count needs a relative error far below
  // 1/sqrt(E) (~5% at E = 500); 1e-8 is ample and keeps cells cut by a curved discontinuity
  // (a disk rim, a triangle edge) cheap.
  double quadrature_tolerance = 1e-8;
  int quadrature_max_depth = 6;         // bisections per level (nested: cost grows as 4^depth at a 2D edge)
  // Expected counts by a Monte Carlo integral of the pdf instead of quadrature: for a stated
  // density that quadrature cannot resolve (support or peaks in slivers narrower than its nodes'
  // spacing, e.g. a surface seen edge-on). Per cell, mc_replicates independent jittered m x m
  // grids (m = mc_grid_min, doubled while the estimate's variance V (in counts^2) exceeds
  // mc_variance_fraction * (E + 1), up to mc_grid_max); the estimate is their mean, V its
  // sample variance over the replicates / mc_replicates, and Pearson's terms are
  // (O - E)^2 / (E + V) (pearson_gof.h). Streams: seed, hash(key, "expected"), the cell.
  bool monte_carlo_expected = false;
  int mc_replicates = 8;
  int mc_grid_min = 16, mc_grid_max = 128;
  double mc_variance_fraction = 0.1;
  // A failed sample is legitimate only where the pdf integrates to less than one: the
  // failure cell's expected count is N (1 - integral), taken as zero when 1 - integral is
  // below this (a quadrature error, not a real deficit).
  double failure_mass_floor = 1e-5;
  // Tolerance on |w| - 1 for directions (sphere domains).
  double unit_tolerance = 1e-6;
};

struct Chi2Cell {
  int ix = 0, iy = 0;              // iy = -1: the failure cell
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  double observed = 0, expected = 0;
  double residual = 0;             // (O - E) / sqrt(E)
};

struct SamplerChi2Result {
  Chi2Domain domain;
  int64_t samples = 0, failed = 0, outside = 0;
  std::string first_outside;        // the first sample outside the domain, printed
  double pdf_integral = 0;          // integral of the pdf over the domain (should be <= 1)
  std::vector<double> observed, expected;  // nx * ny cells, row-major (row = y)
  std::vector<double> expected_variance;   // Monte Carlo expected counts: per cell (else empty)
  int64_t pdf_evaluations = 0;             // Monte Carlo expected counts: points evaluated
  PearsonResult gof;
  std::vector<Chi2Cell> worst;      // largest |standardized residual| first

  // Passes iff nothing fell outside the domain and Pearson's test does not reject.
  bool passed(double alpha) const { return outside == 0 && !gof.rejects(alpha); }
  double p_value() const { return outside > 0 ? 0.0 : gof.p_value; }
  std::string message() const;      // one line
  nlohmann::json details() const;   // counts, chi2, dof, p, pooled cells, worst cells
  PlotSpec observed_heatmap(const std::string& title) const;
  PlotSpec expected_heatmap(const std::string& title) const;
  PlotSpec residual_heatmap(const std::string& title) const;  // (O - E) / sqrt(E)
  // The smallest relative density error (+-epsilon on two halves of the mass) this run rejects
  // with 90% power at alpha (pearson_min_detectable_density_error over its pooled cells).
  double min_detectable_density_error(double alpha, double power = 0.9) const {
    return pearson_min_detectable_density_error(gof.dof, static_cast<double>(samples), alpha, power);
  }
};

inline constexpr const char* kChi2EffectKind = "relative density error (+-e on two halves of the mass)";

// States a chi-square run's power in a check record: the worst (largest) MDE over the runs a
// check combines, each at the level it is tested at.
inline void state_chi2_power(CheckResult& r, const SamplerChi2Result& s, double alpha) {
  const double e = s.min_detectable_density_error(alpha);
  r.min_detectable_effect = r.effect_kind.empty() ? e : std::max(r.min_detectable_effect, e);
  r.effect_kind = kChi2EffectKind;
}

// --- Type-erased core, on the parameter rectangle of the domain ---------------------------

struct Chi2Draw {
  enum Status { kOk, kFailed, kOutside } status = kFailed;
  Vec2 param{0, 0};        // (x, y) on the domain's parameter rectangle
  std::string describe;    // for kOutside: the offending point, printed
};

// draw(rng) produces one sample; pdf_param(x, y) is the density w.r.t. dx dy.
SamplerChi2Result run_sampler_chi2(const Chi2Domain& domain, const std::function<Chi2Draw(Rng&)>& draw,
                                   const std::function<double(Vec2)>& pdf_param, const SamplerChi2Options& options);

// --- Generic front end ---------------------------------------------------------------------

namespace chi2_detail {
template <class F>
auto call_sampler(const F& f, Rng& rng) {
  if constexpr (std::is_invocable_v<const F&, Uniforms&>) {
    RngUniforms u(rng);
    return f(static_cast<Uniforms&>(u));
  } else {
    return f(rng.uniform2());
  }
}
template <class T>
std::optional<T> as_optional(std::optional<T> v) { return v; }
template <class T>
std::optional<T> as_optional(T v) { return std::optional<T>(std::move(v)); }

Chi2Draw classify(const Chi2Domain& d, double x, const SamplerChi2Options& o);
Chi2Draw classify(const Chi2Domain& d, const Vec2& p, const SamplerChi2Options& o);
Chi2Draw classify(const Chi2Domain& d, const Vec3& w, const SamplerChi2Options& o);
double param_to_point_pdf(const Chi2Domain& d, Vec2 param, const std::function<double(double)>& pdf);
double param_to_point_pdf(const Chi2Domain& d, Vec2 param, const std::function<double(Vec2)>& pdf);
double param_to_point_pdf(const Chi2Domain& d, Vec2 param, const std::function<double(Vec3)>& pdf);
}  // namespace chi2_detail

// sample: (Vec2) or (Uniforms&) -> std::optional<P> (or P); pdf: (P) -> double, with P = double
// for intervals, Vec2 for rectangles, Vec3 for (hemi)spheres.
template <class SampleFn, class PdfFn>
SamplerChi2Result chi2_test(const Chi2Domain& domain, const SampleFn& sample, const PdfFn& pdf,
                            const SamplerChi2Options& options = {}) {
  using Raw = decltype(chi2_detail::call_sampler(sample, std::declval<Rng&>()));
  using Point = typename decltype(chi2_detail::as_optional(std::declval<Raw>()))::value_type;
  const std::function<Chi2Draw(Rng&)> draw = [&](Rng& rng) {
    const auto p = chi2_detail::as_optional(chi2_detail::call_sampler(sample, rng));
    if (!p) return Chi2Draw{Chi2Draw::kFailed, {}, {}};
    return chi2_detail::classify(domain, *p, options);
  };
  const std::function<double(Point)> pdf_point = [&](Point p) { return static_cast<double>(pdf(p)); };
  const std::function<double(Vec2)> pdf_param = [&](Vec2 q) {
    return chi2_detail::param_to_point_pdf(domain, q, pdf_point);
  };
  return run_sampler_chi2(domain, draw, pdf_param, options);
}

}  // namespace tb
