// The adaptive forward path sampling small step (APT) of Zirr & Dachsbacher 2020, Sec. 7.1
// (Listing 1), derivative-free form (the footprints of Eq. 21, Sec. 6.5), at a FIXED path length
// k (k vertices x_1..x_k after the pinhole eye, x_k on an emitter; no next-event estimation). k = 1
// (the emitter seen directly) has the film group only.
// docs/zirr2020.md, "Adaptive forward path sampling", has the checks.
//
// State (primary sample space, Lebesgue measure on [0,1)^n, n = 3k - 1): group 0 = u_0, the two film
// uniforms over the WHOLE image (raster = u_0 (W, H)); group j = 1..k-1 = (u_j, l_j), the two
// direction uniforms of the BSDF sample at x_j and its lobe uniform (SurfaceScatter::sample). The
// path is X(U) of lib/differential/path_differential.h (trace_forward with pixel 0 and raster
// u_0 (W, H)). Target f(U) = luminance(L_e(x_k -> x_{k-1}) prod_j weight_j), the path tracer's
// estimate of that path without NEE (0 when x_k is not on an emitter's front); it integrates to the
// mean pixel value of the length-k transport (the pixel measurement is P int f 1[raster in j] dU).
//
// Derivation (on paper; the terms are Listing 1's):
//  * Footprints (Listing 1 lines 1-11). The endpoint-direction footprint of dimension group j under
//    the plain path tracer's sampling is 1 / (p(i_j) |di_j/di_1|) (Eq. 21's terms, solid angle at
//    the camera's i_1 after undoing the refraction compressions, line 5), and the camera's is
//    1 / p(i_1), p(i_1) the solid-angle density of the whole-image film sampling (pdf_we.dir).
//    In units of the camera's footprint: F_0 = 1, F_j = p(i_1) / (p(i_j) |di_j/di_1|), which is the
//    term t_j of variance_ratio_derivative_free (whose p(i_1) is per pixel, P times larger) over P.
//    A pinhole has no aperture group (Listing 1's i = 0 line 9 is absent).
//  * Budget (Eq. 23-24, Listing 1 line 13): r~_g D_g = R with R = 1 / sqrt(P) (Sec. 7.1.1: "one
//    over the square root of the image pixel count"); in footprint units the constraint is
//    sum_j F_j / A_j = R, A_j the factor by which group j's sampling density is raised over the plain
//    sampler's (s_j of Eq. 24 is 1 / A_j).
//  * KKT (Eq. 25-26, Listing 1 lines 14-26): stationarity gives equal shares F_j / A_j = R / n over
//    the n active groups (Eq. 26: A_j = n F_j / R); Dirac vertices start inactive (line 14, their
//    term in Eq. 21 is 0); a group with A_j <= 1 violates s_j <= 1 and is removed with its
//    footprint taken from the budget, and the solve repeats (lines 22-26). Inactive groups keep
//    A_j = 1 (line 31). estimators/mcmc/kkt_footprints.h holds this loop.
//  * Proposal in primary sample space (Listing 1 line 31 N(x_{i+1}, (2 pi pdfs_i)^-1 I), moved from
//    the vertex to its primary samples): the plain sampler's density in PSS is 1, so the adaptive
//    density of group j is A_j at the current primary samples: an isotropic Gaussian of peak
//    1 / (2 pi sigma_j^2) = A_j, i.e. sigma_j(x) = (2 pi A_j(x))^-1/2, wrapped on the unit torus:
//    y_i = x_i + sigma_{g(i)}(x) z_i mod 1, z_i ~ N(0, 1) independent, g(i) the group of coordinate
//    i (the lobe uniform moves with its vertex's sigma).
//  * Density: T(x -> y) = prod_i w_{sigma_{g(i)}(x)}(y_i - x_i), w_sigma the wrapped normal
//    (pss::wrapped_normal_pdf), on Lebesgue measure of [0,1)^n. The scales are those of x's own
//    path, so T(y -> x) = prod_i w_{sigma_{g(i)}(y)}(x_i - y_i) uses y's scales: the proposal is
//    asymmetric (sigma(x) != sigma(y) in general).
//  * Acceptance (Metropolis-Hastings): a(x -> y) = min{1, f(y) T(y -> x) / (f(x) T(x -> y))}.
//    A state whose path cannot be traced (or has no vertex data) gets all A_j = 1: T is defined
//    for every x, and T(x -> y) > 0 for every y, so the move set is irreducible.
#pragma once

#include <optional>
#include <vector>

#include "estimators/mcmc/kkt_footprints.h"
#include "lib/core/spectrum.h"
#include "lib/core/uniforms.h"
#include "lib/differential/path_differential.h"
#include "lib/scene/world.h"

namespace tb::mcmc {

using AptState = std::vector<double>;

// The scales of one state: per group (0 = film, j = bounce at x_j).
struct AptScales {
  std::vector<double> footprint;  // F_j (camera = 1)
  KktAmplifiers kkt;
  std::vector<double> sigma;      // sigma_j = (2 pi A_j)^-1/2
  bool traced = false;            // the path of the state exists (otherwise A_j = 1)
};

// Fixed-length path-tracer target over the state above.
class AptTarget {
 public:
  using State = AptState;
  AptTarget(const World& world, int k);
  int k() const { return k_; }
  size_t dimension() const { return static_cast<size_t>(3 * k_ - 1); }
  // The group of coordinate i.
  static int group(size_t i) { return i < 2 ? 0 : static_cast<int>((i - 2) / 3) + 1; }
  std::optional<differential::ForwardPath> trace(const State& x) const;
  // The longest prefix of the path of x of at most k vertices (differential::trace_forward_prefix).
  std::optional<differential::ForwardPath> trace_prefix(const State& x) const;
  double density(const State& x) const;  // luminance(value(x))
  // f's colour: L_e(x_k -> x_{k-1}) prod_j weight_j (0 unless its luminance is positive and finite).
  Rgb value(const State& x) const;
  // The same for the first k vertices of a traced path (of at least k vertices; 0 otherwise): the
  // candidates of the apt large step (lib/mcmc/apt_integrator.h) are the prefixes of one path.
  static Rgb contribution(const World& world, const differential::ForwardPath& path, int k);
  Vec2 raster(const State& x) const;
  // Listing 1 for the state's path; budget R = 1 / sqrt(P).
  AptScales scales(const State& x) const;
  const World& world() const { return *world_; }

 private:
  std::optional<differential::ForwardPath> trace_impl(const State& x, bool prefix) const;
  const World* world_;
  int k_;
  double width_, height_;
};

// The small step as a Proposal (estimators/mcmc/concepts.h): propose(x, u), density(x, y) =
// T(x -> y), and the factor of one coordinate, of which T is the product (the 1D marginal the
// proposal chi-square tests).
class AptSmallStep {
 public:
  using State = AptState;
  explicit AptSmallStep(const AptTarget& target) : target_(&target) {}
  std::optional<State> propose(const State& x, Uniforms& u) const;
  // The same with x's scales given (target().scales(x)), for a chain that caches them.
  State propose(const State& x, const AptScales& sx, Uniforms& u) const;
  double density(const State& x, const State& y) const;
  // w_{sigma_{g(i)}}(y_i - x_i) with the given scales.
  static double factor(const AptScales& s, size_t i, double d);
  double log_density(const State& x, const State& y, const AptScales& sx) const;
  const AptTarget& target() const { return *target_; }

 private:
  const AptTarget* target_;
};

}  // namespace tb::mcmc
