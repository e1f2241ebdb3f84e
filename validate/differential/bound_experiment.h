// The experiment of Zirr & Dachsbacher 2020, Fig. 3 / Sec. 8.5, as a measurement: path-tracer
// samples of a small scene, reweighted by r~^-1 N / kappa, per pixel and per subfilter, with the
// measured relative variance set against the bound of Prop. 3 (docs/zirr2020.md, "Variance bound
// against measured variance").
//
// The bound. For a pixel filter h_j (or a subfilter g <= h_j, Sec. 5.1) and sample values f(U) of
// the path tracer, Prop. 3 (Eq. 9) with alpha = 2 and Eq. 14-16 give
//   V[f_j] / I_j^2  <=  J_j^(2) / I_j^2  <=  rho_g (J^(2)_{j|d} / I_{j|d}^2)  <=  r~,
// when the locally deterministic transport has relative second moment 1 (its camera-only beam
// sees constant emission: an emitter larger than the deterministic footprint, a constant
// albedo). r~ is Eq. 21 (derivative-free, the variant of Fig. 3) or Eq. 20 (full differentials).
// Reweighting a splat by r~^-1 N / kappa (Sec. 8.5) thus bounds its second moment by
// (N / kappa)^2 I_j^2 / r~: the "bounded-variance images" of Fig. 3.
//
// The test. On a Lambertian scene each path of k vertices has the sample value f in {0, c} with
// c = rho^(k-1) L_e, so V/I^2 = (1 - P)/P with P the probability that x_k lies on the emitter;
// V/I^2 <= B  <=>  P >= 1 / (1 + B). The sample variance is then a function of the hit count
// alone, and the one-sided test of "measured relative variance <= bound" is exactly the lower-tail
// binomial test of the hit count at p0 = 1/(1 + B): no normal approximation of s^2, whose
// distribution here is as skewed as a Bernoulli(P) with P ~ 1e-2 (kurtosis ~ 1/P), and which
// neither the chi-square test of s^2 (normal data) nor a bootstrap (which cannot see rarer hits
// than those drawn) would treat correctly.
//
// B per unit. r~ is a property of one path: Eq. 14-16 bound the relative second moment of the
// subfilter around each contributing path by that path's r~, and a unit's contributing paths carry
// a spread of r~ (a factor <= 1.8 within a pixel for one diffuse bounce here, 3-50 for two).
// BoundRule::kMin takes the smallest r~ of the unit's contributing paths (the strictest bound they
// give); BoundRule::kMean their mean E[r~ | contributing] (the per-path bound averaged over the
// paths that carry the pixel's value).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/differential/path_differential.h"

namespace tb::bound {

// A floor (Lambert or GGX rough conductor), a back wall (Lambert) and a square emitter facing
// down; a pinhole camera below the emitter's height, so that no camera ray sees its back.
struct BoundScene {
  double light_half = 0.1;     // half side of the square emitter
  double light_height = 1.0;   // above the floor
  double roughness = -1.0;     // < 0: Lambert floor; otherwise GGX alpha of a rough conductor
  double albedo = 0.5;         // Lambert reflectance (floor and wall)
  int resolution = 32;
  double fov = 30.0;
};
std::string scene_json(const BoundScene& s);
std::unique_ptr<World> make_world(const BoundScene& s);

// r~ of one contributing path (pixel, U and the traced path).
using RatioFn = std::function<double(const World&, const Vec2& pixel, const Eigen::VectorXd& U,
                                     const differential::ForwardPath&)>;
double ratio_eq21(const World& w, const Vec2& pixel, const Eigen::VectorXd& U, const differential::ForwardPath& p);
double ratio_eq20(const World& w, const Vec2& pixel, const Eigen::VectorXd& U, const differential::ForwardPath& p);

// Sums over the samples of one unit: a pixel, or one of its 2x2 sub-pixel subfilters (cells of
// the film uniforms u_0, g <= h_j summing to h_j).
struct UnitStats {
  int64_t n = 0, hits = 0;
  double sum = 0, sum2 = 0;          // raw sample values S = f / p
  double sum_w = 0, sum_w2 = 0;      // reweighted splats S N / (kappa r~)
  double r_min = 0, r_max = 0;       // r~ over contributing paths
  double sum_r = 0;                  // sum of r~ over contributing paths
  double s_min = 0, s_max = 0;       // S over contributing paths
  double relative_variance() const;  // s^2 / mean^2 (unbiased s^2); infinite without hits
  double r_mean() const { return hits ? sum_r / static_cast<double>(hits) : 0.0; }
};

enum class BoundRule { kMin, kMean };
double bound(const UnitStats& u, BoundRule rule);

struct PixelStats {
  Vec2 pixel{0.0};
  UnitStats pixel_unit;
  UnitStats sub[4];  // u_0 cells: (u_0x >= 1/2) + 2 (u_0y >= 1/2)
};

struct RunConfig {
  int k = 2;                   // path vertices (k - 1 bounces)
  int64_t samples_per_pixel = 32768;
  int grid = 4;                // grid x grid pixels, evenly spread over the image
  double kappa_over_n = 1.0;   // kappa / N of the reweighting (a global scale)
  uint64_t seed = 1, key = 0;
};

std::vector<PixelStats> run(const World& world, const RunConfig& cfg, const RatioFn& ratio);

// One-sided lower-tail binomial p-value of "V/I^2 <= bound" for a unit (see above): P(X <= hits)
// under Binomial(n, 1 / (1 + bound)). 1 when the unit has no hits (no bound to test).
double conservative_p_value(const UnitStats& u, BoundRule rule);

// Bound / measured (r~_min / (s^2 / mean^2)) over the units with hits.
struct SlackSummary {
  int64_t units = 0;
  double min = 0, median = 0, max = 0;
};
SlackSummary slack(const std::vector<const UnitStats*>& units, BoundRule rule);

nlohmann::json unit_json(const UnitStats& u, BoundRule rule);

}  // namespace tb::bound
