#include "validate/differential/bound_experiment.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/binomial.hpp>
#include <fmt/format.h>

#include "lib/core/rng.h"
#include "lib/core/spectrum.h"
#include "lib/differential/variance_bound.h"
#include "lib/scene/scene_loader.h"

namespace tb::bound {

using differential::ForwardPath;

std::string scene_json(const BoundScene& s) {
  const std::string floor_material =
      s.roughness < 0 ? fmt::format(R"({{"name": "floor", "type": "lambert", "reflectance": [{0}, {0}, {0}]}})", s.albedo)
                      : fmt::format(R"({{"name": "floor", "type": "rough_conductor", "distribution": "ggx", "alpha": {}}})",
                                    s.roughness);
  return fmt::format(R"({{
 "description": "Bound experiment: floor, back wall, square emitter facing down (half side {light_half}, height {light_height}).",
 "camera": {{"type": "pinhole", "position": [0, 0.8, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": {fov},
             "resolution": [{res}, {res}]}},
 "materials": [{floor_material},
               {{"name": "wall", "type": "lambert", "reflectance": [{albedo}, {albedo}, {albedo}]}}],
 "shapes": [
  {{"name": "floor", "type": "rectangle", "half_size": [4, 4], "material": "floor",
    "transform": {{"rotate": [[1, 0, 0, -90]]}}}},
  {{"name": "wall", "type": "rectangle", "half_size": [4, 1], "material": "wall",
    "transform": {{"translate": [0, 1, -1.5]}}}},
  {{"name": "light", "type": "rectangle", "half_size": [{light_half}, {light_half}], "emission": [1, 1, 1],
    "transform": {{"rotate": [[1, 0, 0, 90]], "translate": [0, {light_height}, 0]}}}}
 ]
}})",
                     fmt::arg("light_half", s.light_half), fmt::arg("light_height", s.light_height), fmt::arg("fov", s.fov),
                     fmt::arg("res", s.resolution), fmt::arg("floor_material", floor_material),
                     fmt::arg("albedo", s.albedo));
}

std::unique_ptr<World> make_world(const BoundScene& s) { return load_world_from_string(scene_json(s), "bound-scene"); }

double ratio_eq21(const World& w, const Vec2&, const Eigen::VectorXd&, const ForwardPath& p) {
  return differential::variance_ratio_derivative_free(w, p).r;
}

double ratio_eq20(const World& w, const Vec2& pixel, const Eigen::VectorXd& U, const ForwardPath& p) {
  const differential::PathDifferential d = differential::differentiate(w, pixel, p, U);
  return differential::variance_ratio(differential::endpoint_covariance_incremental(d.blocks, differential::endpoint_map(p, d))).r;
}

double UnitStats::relative_variance() const {
  if (hits == 0 || n < 2) return std::numeric_limits<double>::infinity();
  const double nd = static_cast<double>(n);
  const double mean = sum / nd;
  const double var = std::max(0.0, (sum2 - nd * mean * mean) / (nd - 1.0));
  return var / (mean * mean);
}

namespace {

void add(UnitStats& u, bool hit, double s, double r, double kappa_over_n) {
  ++u.n;
  if (!hit) return;
  const double w = s / (kappa_over_n * r);  // the splat reweighted by r~^-1 N / kappa (Sec. 8.5)
  if (u.hits == 0) {
    u.r_min = u.r_max = r;
    u.s_min = u.s_max = s;
  }
  ++u.hits;
  u.sum += s;
  u.sum2 += s * s;
  u.sum_w += w;
  u.sum_w2 += w * w;
  u.sum_r += r;
  u.r_min = std::min(u.r_min, r);
  u.r_max = std::max(u.r_max, r);
  u.s_min = std::min(u.s_min, s);
  u.s_max = std::max(u.s_max, s);
}

}  // namespace

std::vector<PixelStats> run(const World& world, const RunConfig& cfg, const RatioFn& ratio) {
  const Camera& cam = world.camera();
  std::vector<PixelStats> out;
  const int k = cfg.k;
  Eigen::VectorXd U(2 * k);
  std::vector<double> lobe(static_cast<size_t>(std::max(0, k - 1)));
  for (int gy = 0; gy < cfg.grid; ++gy)
    for (int gx = 0; gx < cfg.grid; ++gx) {
      PixelStats ps;
      ps.pixel = Vec2(std::floor((gx + 0.5) * static_cast<double>(cam.width()) / cfg.grid),
                      std::floor((gy + 0.5) * static_cast<double>(cam.height()) / cfg.grid));
      Rng rng = Rng::for_sample(cfg.seed, cfg.key, static_cast<uint64_t>(out.size()));
      for (int64_t i = 0; i < cfg.samples_per_pixel; ++i) {
        for (int d = 0; d < 2 * k; ++d) U[d] = rng.uniform();
        for (double& l : lobe) l = rng.uniform();
        const auto path = differential::trace_forward(world, ps.pixel, U, k, lobe);
        bool hit = false;
        double s = 0.0, r = 1.0;
        if (path) {
          const Hit& last = path->vertices.back();
          const AreaLight* em = world.surface(last.shape_id).emitter;
          const Vec3 wo_light = -(path->wi.empty() ? path->camera_dir : path->wi.back());
          if (em && k >= 2) {
            Rgb t = em->le(last.n, wo_light);
            for (const Rgb& w : path->weight) t = t * w;
            s = luminance(t);
            hit = s > 0.0;
            if (hit) r = ratio(world, ps.pixel, U, *path);
          }
        }
        const int cell = (U[0] >= 0.5 ? 1 : 0) + (U[1] >= 0.5 ? 2 : 0);
        add(ps.pixel_unit, hit, s, r, cfg.kappa_over_n);
        add(ps.sub[cell], hit, s, r, cfg.kappa_over_n);
      }
      out.push_back(ps);
    }
  return out;
}

double bound(const UnitStats& u, BoundRule rule) { return rule == BoundRule::kMin ? u.r_min : u.r_mean(); }

double conservative_p_value(const UnitStats& u, BoundRule rule) {
  if (u.hits == 0) return 1.0;
  const double p0 = 1.0 / (1.0 + bound(u, rule));
  const boost::math::binomial_distribution<double> b(static_cast<double>(u.n), p0);
  return boost::math::cdf(b, static_cast<double>(u.hits));
}

SlackSummary slack(const std::vector<const UnitStats*>& units, BoundRule rule) {
  std::vector<double> q;
  for (const UnitStats* u : units)
    if (u->hits > 0) q.push_back(bound(*u, rule) / u->relative_variance());
  SlackSummary s;
  s.units = static_cast<int64_t>(q.size());
  if (q.empty()) return s;
  std::sort(q.begin(), q.end());
  s.min = q.front();
  s.max = q.back();
  const size_t m = q.size() / 2;
  s.median = q.size() % 2 ? q[m] : 0.5 * (q[m - 1] + q[m]);
  return s;
}

nlohmann::json unit_json(const UnitStats& u, BoundRule rule) {
  const double nd = static_cast<double>(u.n);
  return {{"n", u.n},
          {"hits", u.hits},
          {"mean", u.sum / nd},
          {"relative_variance", u.hits ? u.relative_variance() : -1.0},
          {"r_min", u.r_min},
          {"r_mean", u.r_mean()},
          {"r_max", u.r_max},
          {"bound", bound(u, rule)},
          {"slack", u.hits ? bound(u, rule) / u.relative_variance() : -1.0},
          {"slack_r_min", u.hits ? u.r_min / u.relative_variance() : -1.0},
          {"reweighted_mean", u.sum_w / nd},
          {"reweighted_second_moment", u.sum_w2 / nd},
          {"p_value", conservative_p_value(u, rule)}};
}

}  // namespace tb::bound
