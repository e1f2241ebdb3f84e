// pf1's per-sample MMIS weight (pf1_mmis_weight, lib/integrator/path_filter.h: Eq. 14 of West et al.
// 2022 with K = 1 through estimators/mmis_filtering.h) serves both uses:
//  - the analytic use: a 1-D marginal-MIS problem (estimators/mmis.h, Eq. 6) with one classical technique
//    and window techniques conditioned on random centres; every drawn sample's weight from mmis_weight
//    equals pf1_mmis_weight on the same densities;
//  - the path use: the kernels pf1 forms on the Cornell box, whose weights are the balance heuristic
//    p_k / sum_j p_j over the kernel and sum to one over the kernel's techniques.
#include <cmath>
#include <numbers>
#include <optional>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "estimators/mmis.h"
#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "lib/integrator/path_filter.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

// x on the circle [0, 1): classical technique uniform (pdf 1); marginal technique: centre t ~ U(0, 1),
// x ~ uniform on the arc |x - t| <= 0.25 (circular distance), pdf 2 there.
struct UniformCircle {
  using Sample = double;
  std::optional<double> sample(Uniforms& u) const { return u.next(); }
  double pdf(const double&) const { return 1.0; }
};
double circular_distance(double a, double b) {
  const double d = std::abs(a - b);
  return std::min(d, 1.0 - d);
}
struct WindowTechnique {
  using Sample = double;
  using Aux = double;
  std::optional<double> sample_aux(Uniforms& u) const { return u.next(); }
  std::optional<double> sample(const double& t, Uniforms& u) const {
    const double x = t + 0.5 * u.next() - 0.25;
    return x - std::floor(x);
  }
  double pdf(const double& x, const double& t) const { return circular_distance(x, t) <= 0.25 ? 2.0 : 0.0; }
};

TEST(PathFilterWeight, AnalyticUseEqualsEq6Weights) {
  const UniformCircle classical[1] = {{}};
  const int classical_counts[1] = {1};
  const WindowTechnique marginal[1] = {{}};
  const int marginal_counts[1] = {5};
  Rng rng = Rng::for_sample(7, 0x7066, 0);
  RngUniforms u(rng);
  int compared = 0;
  for (int draw = 0; draw < 200; ++draw) {
    const auto d = draw_mmis(std::span<const UniformCircle>(classical), std::span<const int>(classical_counts),
                             std::span<const WindowTechnique>(marginal), std::span<const int>(marginal_counts), u);
    const size_t nc = d.classical_samples();
    for (size_t s = nc; s < d.xs.size(); ++s) {
      const auto w6 = mmis_weight(std::span<const UniformCircle>(classical), std::span<const int>(classical_counts),
                                  std::span<const WindowTechnique>(marginal), d, s);
      ASSERT_TRUE(w6.has_value());
      std::vector<double> column;
      for (const auto& pair : d.aux) column.push_back(marginal[0].pdf(*d.xs[s], pair.t));
      const FilteringWeight wf = pf1_mmis_weight(column, static_cast<int>(s - nc), 1.0 * classical[0].pdf(*d.xs[s]));
      EXPECT_NEAR(wf.weight, w6->weight, 1e-14);
      EXPECT_NEAR(wf.denominator, w6->denominator, 1e-14 * w6->denominator);
      EXPECT_EQ(wf.own_pdf, w6->own_pdf);
      ++compared;
    }
  }
  EXPECT_EQ(compared, 200 * 5);
}

TEST(PathFilterWeight, PathUseIsTheBalanceHeuristicOverTheKernel) {
  const auto world = load_scene_at_resolution("cornell-box.json", 16, 16);
  RenderSettings st;
  st.spp = 8;
  st.passes = 1;
  st.seed = 3;
  st.params["radius"] = 0.05 * world->bounds().radius;
  const std::vector<Pf1Kernel> kernels = pf1_sample_kernels(*world, st, 100);
  ASSERT_GE(kernels.size(), 50u);
  int multi = 0, paths = 0;
  for (const Pf1Kernel& k : kernels) {
    const int m = k.members;
    multi += m > 1;
    ASSERT_GE(k.query, 0);
    ASSERT_LT(k.query, m);
    for (int s = 0; s < m; ++s) {
      if (!k.sampled[static_cast<size_t>(s)] || !(k.pdf[static_cast<size_t>(s * m + s)] > 0)) continue;
      std::vector<double> column(static_cast<size_t>(m));
      double total = 0.0;
      for (int j = 0; j < m; ++j) total += column[static_cast<size_t>(j)] = k.pdf[static_cast<size_t>(j * m + s)];
      double sum = 0.0;
      for (int own = 0; own < m; ++own) {
        const FilteringWeight w = pf1_mmis_weight(column, own);
        EXPECT_NEAR(w.weight, column[static_cast<size_t>(own)] / total, 1e-15);
        sum += w.weight;
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      ++paths;
    }
  }
  EXPECT_GT(multi, 10);
  EXPECT_GT(paths, 50);
}

}  // namespace
}  // namespace tb
