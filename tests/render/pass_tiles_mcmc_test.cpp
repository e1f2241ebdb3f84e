// tb compare's pass-tile test (validate/pass_tile_compare.h) on real MCMC renders: two PSSMLT and
// two MMLT renders of the Cornell box with different seeds are consistent at alpha 0.01 (fixed
// seeds), and the same renders with B's passes scaled by 1.05 (a 5% bias) are rejected.
#include <gtest/gtest.h>

#include "lib/film/film.h"
#include "lib/film/pass_tiles.h"
#include "lib/registry/integrator_registry.h"
#include "validate/pass_tile_compare.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

PassTiles render_tiles(const World& w, const std::string& integrator, uint64_t seed, double scale) {
  const IntegratorInfo* integ = find_integrator(integrator);
  EXPECT_NE(integ, nullptr);
  Film film(w.camera().width(), w.camera().height());
  PassTiles tiles(film.width(), film.height());
  film.set_pass_observer([&](const std::vector<Rgb>& pass) {
    std::vector<Rgb> scaled = pass;
    for (Rgb& v : scaled) v *= scale;
    tiles.add_pass(scaled);
  });
  RenderSettings st;
  st.spp = 16 * 16;
  st.passes = 16;
  st.seed = seed;
  integ->render(w, st, film);
  return tiles;
}

TEST(PassTilesMcmc, SameRendererConsistentAndFivePercentBiasRejected) {
  const auto world = load_scene_at_resolution("cornell-box.json", 16, 16);
  for (const char* integ : {"pssmlt", "mmlt"}) {
    const PassTiles a = render_tiles(*world, integ, 11, 1.0);
    const PassTiles b = render_tiles(*world, integ, 12, 1.0);
    const PassTiles biased = render_tiles(*world, integ, 12, 1.05);
    const PassTileCompareResult same = compare_pass_tiles(a, b, 0.01);
    const PassTileCompareResult off = compare_pass_tiles(a, biased, 0.01);
    EXPECT_FALSE(same.rejects()) << integ << ": p = " << same.p_family << ", worst tile " << same.worst_tile;
    EXPECT_TRUE(off.rejects()) << integ << ": 5% bias not caught, p = " << off.p_family;
    std::printf("%s 16x16, 16 passes: same p = %.3g; 5%% bias p = %.3g (totals %+.4f)\n", integ, same.p_family,
                off.p_family, off.total_rel_diff[0]);
  }
}

}  // namespace
}  // namespace tb
