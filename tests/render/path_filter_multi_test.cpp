// pfk (multi-vertex path filtering, lib/integrator/path_filter_multi.h; West et al. 2022, Eq. 13-14):
//  - the per-path weight (pfk_mmis_weight, through filtering_mmis_weight) against the exponential
//    enumeration of every combination: weights = own / sum of products, summing to one;
//  - vertices = 1 renders pf1's image bit for bit (the same code and streams);
//  - the output paths the renderer records: one level per filtered vertex (at most K), the producing
//    technique's counted density positive, the denominator the product of the columns' sums, expected
//    counts 1 / M_d at d >= 2 (the own technique last among the M_d).
// The furnace test of the estimator is in path_filter_multi_slowtest.cpp (label slow).
#include <cmath>
#include <span>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "estimators/mmis_filtering.h"
#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/integrator/path_filter.h"
#include "lib/integrator/path_filter_multi.h"
#include "validate/render/broken_path_filter.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

TEST(PfkWeight, ProductOfSumsEqualsEveryCombinationAndSumsToOne) {
  Rng rng = Rng::for_sample(11, 0x70666b, 0);
  for (int trial = 0; trial < 50; ++trial) {
    const int levels = 1 + trial % 4;
    std::vector<std::vector<double>> cols(static_cast<size_t>(levels));
    std::vector<int> sizes;
    for (auto& c : cols) {
      c.resize(1 + static_cast<size_t>(rng.uniform() * 6));
      for (double& v : c) v = rng.uniform() < 0.2 ? 0.0 : rng.uniform() * 3.0;
      c[0] += 0.1;  // one positive density per level
      sizes.push_back(static_cast<int>(c.size()));
    }
    const double all = filtering_sum_of_products(std::span<const int>(sizes), [&](size_t d, int j) {
      return cols[d][static_cast<size_t>(j)];
    });
    std::vector<int> own(static_cast<size_t>(levels), 0);
    double sum = 0.0;
    do {
      std::vector<PfkLevel> view;
      double prod = 1.0;
      for (int d = 0; d < levels; ++d) {
        view.push_back({cols[static_cast<size_t>(d)], own[static_cast<size_t>(d)], 0});
        prod *= cols[static_cast<size_t>(d)][static_cast<size_t>(own[static_cast<size_t>(d)])];
      }
      const FilteringWeight w = pfk_mmis_weight(view);
      EXPECT_NEAR(w.denominator, all, 1e-12 * all);
      EXPECT_NEAR(w.own_pdf, prod, 1e-15 * (1.0 + prod));
      EXPECT_NEAR(w.weight, prod / all, 1e-13);
      // The broken control's denominator leaves out the self entry (0) of every level after the first.
      double broken = 1.0;
      for (int d = 0; d < levels; ++d) {
        double s = 0.0;
        for (size_t j = 0; j < cols[static_cast<size_t>(d)].size(); ++j)
          if (d == 0 || j != 0) s += cols[static_cast<size_t>(d)][j];
        broken *= s;
      }
      EXPECT_NEAR(pfk_weight_omitting_own(view).denominator, broken, 1e-12 * (1.0 + broken));
      sum += w.weight;
    } while (next_filtering_combination(std::span<int>(own), std::span<const int>(sizes)));
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
}

TEST(Pfk, ParametersOutsideTheirDomainThrow) {
  const auto world = load_scene_at_resolution("cornell-box.json", 4, 4);
  RenderSettings st;
  EXPECT_EQ(pfk_params(*world, st).vertices, 2);
  st.params["vertices"] = 0;
  EXPECT_THROW(pfk_params(*world, st), std::invalid_argument);
  st.params["vertices"] = kPfkMaxVertices + 1;
  EXPECT_THROW(pfk_params(*world, st), std::invalid_argument);
  st.params["vertices"] = 3;
  EXPECT_EQ(pfk_params(*world, st).vertices, 3);
}

TEST(Pfk, OneVertexIsPf1BitForBit) {
  const auto world = load_scene_at_resolution("cornell-box.json", 12, 12);
  RenderSettings st;
  st.spp = 8;
  st.passes = 2;
  st.seed = 5;
  st.max_depth = 5;
  Film a(12, 12), b(12, 12);
  render_pf1(*world, st, a);
  st.params["vertices"] = 1;
  render_pfk(*world, st, b);
  const WelchImage wa = a.welch(), wb = b.welch();
  ASSERT_EQ(wa.pixels(), wb.pixels());
  double total = 0.0;
  for (size_t i = 0; i < wa.pixels(); ++i) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(wa.mean(i)[c], wb.mean(i)[c]) << "pixel " << i;
      total += wa.mean(i)[c];
    }
  }
  EXPECT_GT(total, 0.0);
  // K = 2 filters x_2 as well: a different image of the same scene.
  st.params["vertices"] = 2;
  Film c(12, 12);
  render_pfk(*world, st, c);
  const WelchImage wc = c.welch();
  int differ = 0;
  for (size_t i = 0; i < wa.pixels(); ++i) differ += wa.mean(i)[0] != wc.mean(i)[0];
  EXPECT_GT(differ, 0);
}

TEST(Pfk, RecordedPathsCarryTheProductOfSums) {
  const auto world = load_scene_at_resolution("cornell-box.json", 16, 16);
  RenderSettings st;
  st.spp = 8;
  st.passes = 1;
  st.seed = 7;
  st.max_depth = 5;
  st.params["radius"] = 0.03 * world->bounds().radius;
  st.params["vertices"] = 3;
  const PfkSample s = pfk_sample_paths(*world, st, 60);
  ASSERT_EQ(s.depth_vertices.size(), 3u);
  ASSERT_GT(s.paths.size(), 100u);
  int deep = 0, with_members = 0;
  for (const PfkSampledPath& p : s.paths) {
    ASSERT_GE(p.levels.size(), 1u);  // 1: x_2 not filterable (the path tracer goes on there)
    ASSERT_LE(p.levels.size(), 3u);
    deep += p.levels.size() == 3;
    double product = 1.0;
    for (size_t d = 0; d < p.levels.size(); ++d) {
      const PfkPathLevel& lv = p.levels[d];
      ASSERT_GE(lv.own, 0);
      ASSERT_LT(static_cast<size_t>(lv.own), lv.column.size());
      EXPECT_GT(lv.column[static_cast<size_t>(lv.own)], 0.0);
      double sum = 0.0;
      for (double v : lv.column) sum += v;
      product *= sum;
      const bool light_only = d + 1 == p.levels.size() && p.delta_light;
      if (d > 0 && !light_only) {
        // m members and the own technique (entry m), each counted 1 / (m + 1): the own entry is
        // (1 / (m + 1)) times x_d's BSDF density, so (m + 1) * entry is a density of at most a few units.
        ASSERT_GE(lv.self, 0);
        with_members += lv.self > 0;
        const size_t expected = static_cast<size_t>(lv.self) + 1 + (d + 1 == p.levels.size() && p.light_entry);
        EXPECT_EQ(lv.column.size(), expected);
      }
    }
    EXPECT_NEAR(p.weight.denominator, product, 1e-12 * product);
  }
  EXPECT_GT(deep, 50);
  EXPECT_GT(with_members, 50);
}

}  // namespace
}  // namespace tb
