// The shared path representation against the bidirectional path tracer that samples with it:
// for every connection (s, t) BDPT makes, the densities and the MIS weight it computes
// incrementally equal those evaluated from scratch on the finished path (lib/path/path.h), and
// its unweighted contribution equals f(X) / p_{s,t}(X). The weights of all techniques that can
// sample a path sum to one.
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lib/integrator/bdpt.h"
#include "lib/path/light_sampler.h"
#include "lib/path/path.h"
#include "lib/scene/scene_loader.h"

namespace tb {
namespace {

std::unique_ptr<World> load_small(const std::string& name, int res) {
  const std::string dir = std::string(TB_SOURCE_DIR) + "/scenes";
  std::ifstream in(dir + "/" + name);
  std::stringstream ss;
  ss << in.rdbuf();
  nlohmann::json j = nlohmann::json::parse(ss.str());
  j["camera"]["resolution"] = {res, res};
  return load_world_from_string(j.dump(1), name, dir);
}

// The full path x_0..x_k of connection (s, t).
std::vector<PathVertex> full_path(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s,
                                  int t, const Connection& c) {
  std::vector<PathVertex> x;
  for (int i = 0; i < s; ++i) x.push_back(light[i]);
  for (int i = t - 1; i >= 0; --i) x.push_back(camera[i]);
  if (s == 1 && t >= 2) x[0] = c.sampled;
  if (t == 1) x.back() = c.sampled;
  return x;
}

double rel(double a, double b) { return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-300}); }

void check_scene(const std::string& name, int max_depth, bool expect_deltas) {
  const auto world = load_small(name, 32);
  const LightSampler sampler(*world);
  const PathContext ctx{world.get(), &sampler};
  std::vector<PathVertex> cam, light;
  int checked = 0, with_delta = 0;
  double worst_w = 0, worst_f = 0, worst_sum = 0;
  std::string where_w, where_f;
  for (uint64_t i = 0; i < 1500; ++i) {
    Rng stream = Rng::for_sample(7, 99, i);
    RngUniforms rng(stream);
    const Vec2 raster(rng.next() * 32, rng.next() * 32);
    const Vec2 lens_u = rng.next2();
    const int nc = generate_camera_subpath(ctx, raster, lens_u, rng, max_depth + 2, &cam);
    const int nl = generate_light_subpath(ctx, rng, max_depth + 1, &light);
    for (int t = 1; t <= nc; ++t)
      for (int s = 0; s <= nl; ++s) {
        if (s + t - 2 > max_depth || s + t < 2) continue;
        const Connection c = connect_bdpt(ctx, light, cam, s, t, rng);
        if (is_black(c.unweighted)) continue;
        const auto x = full_path(light, cam, s, t, c);
        const PathDensities d = path_densities(ctx, x);
        bool delta = false;
        for (auto f : d.delta) delta |= f != 0;
        if (delta) ++with_delta;
        // MIS weight from scratch, except for the environment sum of s = 0 (several emitters).
        const double w = mis_weight(d, s, MisKind::kPower);
        if (!(s == 0 && x[0].infinite) && std::abs(w - c.weight) > worst_w) {
          worst_w = std::abs(w - c.weight);
          where_w = "s=" + std::to_string(s) + " t=" + std::to_string(t);
        }
        // Weights over techniques sum to one.
        double sum = 0;
        for (int j = 0; j < static_cast<int>(x.size()); ++j) sum += mis_weight(d, j, MisKind::kPower);
        worst_sum = std::max(worst_sum, std::abs(sum - 1.0));
        if (!delta) {
          const Rgb f = measurement_contribution(ctx, x, true);
          const double p = technique_density(d, s);
          ASSERT_GT(p, 0.0) << name << " s=" << s << " t=" << t;
          for (int ch = 0; ch < 3; ++ch) {
            if (c.unweighted[ch] > 0 && rel(f[ch] / p, c.unweighted[ch]) > worst_f) {
              worst_f = rel(f[ch] / p, c.unweighted[ch]);
              where_f = "s=" + std::to_string(s) + " t=" + std::to_string(t) + " f/p=" + std::to_string(f[ch] / p) +
                        " c=" + std::to_string(c.unweighted[ch]);
            }
          }
        }
        ++checked;
      }
  }
  EXPECT_GT(checked, 400) << name;
  if (expect_deltas) {
    EXPECT_GT(with_delta, 0) << name;
  }
  EXPECT_LT(worst_w, 1e-9) << name << ": incremental vs from-scratch MIS weight at " << where_w;
  EXPECT_LT(worst_sum, 1e-12) << name << ": MIS weights do not sum to one";
  EXPECT_LT(worst_f, 1e-9) << name << ": unweighted contribution != f/p at " << where_f;
}

TEST(PathBdpt, CornellBoxWeightsAndContributions) { check_scene("cornell-box.json", 5, false); }
TEST(PathBdpt, GlossyWeightsAndContributions) { check_scene("glossy.json", 5, false); }
TEST(PathBdpt, CausticWeightsWithDeltaVertices) { check_scene("caustic.json", 6, true); }

TEST(PathBdpt, MissingDensityBreaksTheWeightSum) {
  // The negative control of the weights: with one density dropped the incremental weight
  // differs from the one evaluated from scratch for some connection.
  const auto world = load_small("cornell-box.json", 32);
  const LightSampler sampler(*world);
  const PathContext ctx{world.get(), &sampler};
  std::vector<PathVertex> cam, light;
  double worst = 0;
  for (uint64_t i = 0; i < 100; ++i) {
    Rng stream = Rng::for_sample(8, 99, i);
    RngUniforms rng(stream);
    const int nc = generate_camera_subpath(ctx, Vec2(16.5, 16.5), Vec2(0.5), rng, 6, &cam);
    const int nl = generate_light_subpath(ctx, rng, 5, &light);
    for (int t = 2; t <= nc; ++t)
      for (int s = 2; s <= nl; ++s) {
        const Connection c = connect_bdpt(ctx, light, cam, s, t, rng, IntegratorFault::kMisMissingDensity);
        if (is_black(c.unweighted)) continue;
        const auto x = full_path(light, cam, s, t, c);
        worst = std::max(worst, std::abs(mis_weight(path_densities(ctx, x), s, MisKind::kPower) - c.weight));
      }
  }
  EXPECT_GT(worst, 1e-3);
}

}  // namespace
}  // namespace tb
