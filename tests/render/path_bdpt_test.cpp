// The shared path representation against the bidirectional path tracer that samples with it:
// for every connection (s, t) BDPT makes, the densities and the MIS weight it computes
// incrementally equal those evaluated from scratch on the finished path (lib/path/path.h), and
// its unweighted contribution equals f(X) / p_{s,t}(X). The weights of all techniques that can
// sample a path sum to one.
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lib/core/rng.h"
#include "lib/integrator/bdpt.h"
#include "lib/material/lambert.h"
#include "lib/path/light_sampler.h"
#include "lib/path/path.h"
#include "lib/path/scattering.h"
#include "lib/scene/scene_loader.h"
#include "validate/render/broken_integrators.h"

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

// The smallest |cos| between a scattering vertex's geometric normal and its path neighbours.
double min_geometric_cosine(const std::vector<PathVertex>& x) {
  double m = 1.0;
  for (size_t v = 1; v + 1 < x.size(); ++v)
    m = std::min({m, std::abs(glm::dot(x[v].hit.ng, direction(x[v], x[v - 1]))),
                  std::abs(glm::dot(x[v].hit.ng, direction(x[v], x[v + 1])))});
  return m;
}

// The check of unweighted = f / p: relative difference below 1e-9, or with cos_scaled below
// 1e-5 after multiplying it by min_geometric_cosine(x). Where n == ng the sampling weights cancel
// the cosines they share with f / p exactly. Where n != ng the light subpath's weight has the
// factor |c.ng| / |l.ng| of the directions it sampled (docs/path.md, Shading normals), and those
// differ from the directions between the stored vertices by the ray-spawn offsets (measured:
// ~3e-6 relative to the distance), a relative difference of ~3e-6 / |cos_g| in that factor.
void check_scene(const std::string& name, int max_depth, bool expect_deltas, bool cos_scaled = false) {
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
          const double scale = cos_scaled ? min_geometric_cosine(x) : 1.0;
          const Rgb f = measurement_contribution(ctx, x, true);
          const double p = technique_density(d, s);
          ASSERT_GT(p, 0.0) << name << " s=" << s << " t=" << t;
          for (int ch = 0; ch < 3; ++ch) {
            if (c.unweighted[ch] > 0 && rel(f[ch] / p, c.unweighted[ch]) * scale > worst_f) {
              worst_f = rel(f[ch] / p, c.unweighted[ch]) * scale;
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
  EXPECT_LT(worst_f, cos_scaled ? 1e-5 : 1e-9) << name << ": unweighted contribution != f/p at " << where_f;
}

TEST(PathBdpt, CornellBoxWeightsAndContributions) { check_scene("cornell-box.json", 5, false); }
TEST(PathBdpt, GlossyWeightsAndContributions) { check_scene("glossy.json", 5, false); }
TEST(PathBdpt, CausticWeightsWithDeltaVertices) { check_scene("caustic.json", 6, true); }
// Per-vertex shading normals (OBJ vn and inline "normals"): f(X) with geometric cosines in G and
// the projected BSDF f_s |l.n_s| (the path tracer's measurement), the light subpaths with the
// adjoint's shading-normal factor (Veach 1997, Eq. 5.19; docs/path.md, Shading normals).
TEST(PathBdpt, SmoothMeshWeightsAndContributions) { check_scene("smooth-mesh.json", 5, false, true); }

// The adjoint identity with shading normals (Veach 1997, Eq. 5.19): for a light-side direction l
// and a camera-side direction c at a point with n != ng,
//   f_imp(l -> c) |c.n| |l.ng| = f_rad(c -> l) |l.n| |c.ng|,
// both sides the measurement's factor at the vertex (docs/path.md). The inverted factor (the
// negative control) breaks it.
TEST(PathBdpt, AdjointShadingCorrectionIdentity) {
  const auto bsdf = std::make_unique<LambertBsdf>(Rgb(0.6));
  SurfacePoint hit;
  hit.p = Vec3(0.0);
  hit.ng = Vec3(0, 0, 1);
  hit.n = glm::normalize(Vec3(0.3, -0.2, 1.0));
  double worst = 0, worst_inverted = 0;
  for (uint64_t i = 0; i < 200; ++i) {
    Rng rng = Rng::for_sample(5, 17, i);
    const auto dir = [&] {  // upper hemisphere of ng, away from grazing
      const double z = 0.1 + 0.9 * rng.uniform(), phi = 2 * kPi * rng.uniform();
      const double r = std::sqrt(1 - z * z);
      return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    const Vec3 l = dir(), c = dir();
    if (glm::dot(l, hit.n) <= 0.05 || glm::dot(c, hit.n) <= 0.05) continue;
    const double rad = SurfaceScatter(hit, *bsdf).f(c, l, TransportMode::kRadiance).r * std::abs(glm::dot(l, hit.n)) *
                       std::abs(glm::dot(c, hit.ng));
    const double imp = SurfaceScatter(hit, *bsdf).f(l, c, TransportMode::kImportance).r *
                       std::abs(glm::dot(c, hit.n)) * std::abs(glm::dot(l, hit.ng));
    const double inv = SurfaceScatter(hit, *bsdf, &inverted_importance_shading_correction).f(l, c, TransportMode::kImportance).r *
                       std::abs(glm::dot(c, hit.n)) * std::abs(glm::dot(l, hit.ng));
    ASSERT_GT(rad, 0.0);
    worst = std::max(worst, rel(imp, rad));
    worst_inverted = std::max(worst_inverted, rel(inv, rad));
  }
  EXPECT_LT(worst, 1e-14);
  EXPECT_GT(worst_inverted, 0.05);  // negative control
}

// Negative control of SmoothMeshWeightsAndContributions: with the inverted shading-normal factor
// on the light subpath (EstimatorFault::kShadingCorrectionInverted) the unweighted contribution
// of connections with s >= 2 departs from f(X) / p_{s,t}(X) (by the same cosine-scaled measure).
TEST(PathBdpt, InvertedShadingCorrectionBreaksContributions) {
  const auto world = load_small("smooth-mesh.json", 32);
  const LightSampler sampler(*world);
  const PathContext ctx{world.get(), &sampler};
  std::vector<PathVertex> cam, light;
  double worst = 0;
  for (uint64_t i = 0; i < 300; ++i) {
    Rng stream = Rng::for_sample(9, 99, i);
    RngUniforms rng(stream);
    const Vec2 raster(rng.next() * 32, rng.next() * 32);
    const int nc = generate_camera_subpath(ctx, raster, rng.next2(), rng, 5, &cam);
    const int nl = generate_light_subpath_broken(EstimatorFault::kShadingCorrectionInverted, ctx, rng, 4, &light);
    for (int t = 1; t <= nc; ++t)
      for (int s = 2; s <= nl; ++s) {
        const Connection c = connect_bdpt_broken(EstimatorFault::kShadingCorrectionInverted, ctx, light, cam, s, t, rng);
        if (is_black(c.unweighted)) continue;
        const auto x = full_path(light, cam, s, t, c);
        const double p = technique_density(path_densities(ctx, x), s);
        const Rgb f = measurement_contribution(ctx, x, true);
        if (p > 0 && f.r > 0) worst = std::max(worst, rel(f.r / p, c.unweighted.r) * min_geometric_cosine(x));
      }
  }
  EXPECT_GT(worst, 1e-3);  // the criterion of SmoothMeshWeightsAndContributions is 1e-5
}

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
        const Connection c = connect_bdpt_broken(EstimatorFault::kMisMissingDensity, ctx, light, cam, s, t, rng);
        if (is_black(c.unweighted)) continue;
        const auto x = full_path(light, cam, s, t, c);
        worst = std::max(worst, std::abs(mis_weight(path_densities(ctx, x), s, MisKind::kPower) - c.weight));
      }
  }
  EXPECT_GT(worst, 1e-3);
}

}  // namespace
}  // namespace tb
