// pfk (lib/integrator/path_filter_multi.h) in the white furnace (closed-form image,
// validate/render/analytic_worlds.h): K = 2 and 3 with large kernels (r = 0.2 on the unit sphere, more
// than 8 members on average), 24 independent renders per K (fixed seeds), a t-test of their image means
// per channel against the exact value, |t| < 6 (23 dof: alpha about 1e-5 per test, 6 tests). Slow
// (about two minutes on two cores): label slow.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "lib/film/film.h"
#include "lib/integrator/path_filter.h"
#include "lib/integrator/path_filter_multi.h"
#include "validate/render/analytic_worlds.h"

namespace tb {
namespace {

TEST(Pfk, FurnaceImageMeanIsExact) {
  FurnaceParams fp;
  fp.resolution = 8;
  fp.max_depth = 5;
  const AnalyticScene sc = make_furnace(fp);
  const Rgb exact = sc.exact[0];
  constexpr int kRenders = 24;
  for (const int k : {2, 3}) {
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    double members = 0.0;
    for (int r = 0; r < kRenders; ++r) {
      RenderSettings st;
      st.spp = 32;
      st.passes = 1;
      st.max_depth = fp.max_depth;
      st.seed = 1000 + static_cast<uint64_t>(100 * k + r);
      st.params["radius"] = 0.2;  // many members per kernel on the unit sphere
      st.params["vertices"] = k;
      Film film(8, 8);
      render_pfk(*sc.world, st, film);
      members += pf1_last_timing().mean_members;
      const WelchImage w = film.welch();
      for (int c = 0; c < 3; ++c) {
        double m = 0.0;
        for (size_t i = 0; i < w.pixels(); ++i) m += w.mean(i)[c];
        m /= static_cast<double>(w.pixels());
        sum[c] += m;
        sum2[c] += m * m;
      }
    }
    EXPECT_GT(members / kRenders, 8.0);
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / kRenders;
      const double var = (sum2[c] - kRenders * mean * mean) / (kRenders - 1);
      const double t = (mean - exact[c]) / std::sqrt(var / kRenders);
      // |t| > 6.0 has probability ~4e-6 at 23 dof.
      std::printf("pfk K=%d channel %d: mean %.6f exact %.6f t %.2f\n", k, c, mean, exact[c], t);
      EXPECT_LT(std::abs(t), 6.0) << "K " << k << " channel " << c << " mean " << mean << " exact " << exact[c];
      EXPECT_GT(var, 0.0);
    }
  }
}

}  // namespace
}  // namespace tb
