// The one pass loop (lib/integrator/pass_loop.h): every integrator renders a range
// [first_pass, first_pass + pass_count) of its passes (MLT: chains); a film that receives [0, a)
// and then [a, n) is bit-identical to one that receives [0, n), for every registered integrator.
#include <string>

#include <gtest/gtest.h>

#include "lib/core/parallel.h"
#include "lib/film/film.h"
#include "lib/registry/integrator_registry.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

WelchImage render_ranges(const IntegratorInfo& integ, const World& w, const std::vector<std::pair<int64_t, int64_t>>& ranges) {
  Film film(w.camera().width(), w.camera().height());
  for (const auto& [first, count] : ranges) {
    RenderSettings st;
    st.spp = 24;
    st.passes = 6;
    st.max_depth = 3;
    st.seed = 5;
    st.first_pass = first;
    st.pass_count = count;
    integ.render(w, st, film);
  }
  return film.welch();
}

TEST(PassRange, RangesCutAnywhereGiveTheSameFilm) {
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  for (const IntegratorInfo& integ : integrators()) {
    const WelchImage whole = render_ranges(integ, *world, {{0, -1}});
    const WelchImage cut = render_ranges(integ, *world, {{0, 2}, {2, 3}, {5, -1}});
    ASSERT_EQ(whole.pixels(), cut.pixels()) << integ.name;
    int64_t passes = 0;
    for (size_t i = 0; i < whole.pixels(); ++i) {
      passes = std::max(passes, whole.count[i]);
      ASSERT_EQ(whole.count[i], cut.count[i]) << integ.name << " pixel " << i;
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(whole.sum[i][c], cut.sum[i][c]) << integ.name << " pixel " << i;
        ASSERT_EQ(whole.sum_sq[i][c], cut.sum_sq[i][c]) << integ.name << " pixel " << i;
      }
    }
    EXPECT_EQ(passes, 6) << integ.name;
  }
}

// Every registered integrator gives bit-identical Welch sums on one thread and on all of them.
TEST(PassRange, EveryIntegratorBitIdenticalAcrossThreadCounts) {
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  for (const IntegratorInfo& integ : integrators()) {
    const WelchImage all = render_ranges(integ, *world, {{0, -1}});
    WelchImage one;
    {
      const ThreadLimit limit(1);
      one = render_ranges(integ, *world, {{0, -1}});
    }
    for (size_t i = 0; i < all.pixels(); ++i)
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(all.sum[i][c], one.sum[i][c]) << integ.name << " pixel " << i;
        ASSERT_EQ(all.sum_sq[i][c], one.sum_sq[i][c]) << integ.name << " pixel " << i;
      }
  }
}

TEST(PassRange, EmptyAndOutOfRangeRangesRenderNothing) {
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  const IntegratorInfo* pt = find_integrator("pt");
  ASSERT_NE(pt, nullptr);
  Film film(8, 8);
  RenderSettings st;
  st.passes = 4;
  st.spp = 4;
  st.first_pass = 4;
  EXPECT_EQ(pt->render(*world, st, film), 0);
  st.first_pass = 1;
  st.pass_count = 0;
  EXPECT_EQ(pt->render(*world, st, film), 0);
  EXPECT_EQ(film.passes(), 0);
}

}  // namespace
}  // namespace tb
