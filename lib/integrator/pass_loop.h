// The pass loop every Monte Carlo integrator shares: settings.passes passes of
// settings.spp / passes samples per pixel each, one Welch sample per pixel per pass
// (Film::end_pass), stopping early when interrupted or when the time budget has run out at the
// end of a pass; progress reported after each pass. And the camera-sample loop over a tile:
// sample `index` of pixel (x, y) uses the random stream Rng::for_sample(seed, pixel, index), so
// the image does not depend on how tiles are spread over threads.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/film/film_tile.h"
#include "lib/integrator/render_settings.h"

namespace tb {

// render_pass(pass, spp_pass) renders one pass into the film and returns the splat scale for
// Film::end_pass (0 when the pass splats nothing). Returns the number of passes done.
template <class RenderPass>
int64_t run_passes(const RenderSettings& st, Film& film, RenderPass&& render_pass) {
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t spp_pass = std::max<int64_t>(1, st.spp / passes);
  const auto t0 = std::chrono::steady_clock::now();
  int64_t done = 0;
  for (int64_t pass = 0; pass < passes; ++pass) {
    if (st.interrupted && st.interrupted->load()) break;
    film.end_pass(render_pass(pass, spp_pass));
    ++done;
    st.progress(static_cast<double>(done) / static_cast<double>(passes));
    if (st.time_budget_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > st.time_budget_s)
      break;
  }
  return done;
}

// Calls sample(x, y, index, rng) for every pixel of the tile and each of the pass's samples.
template <class Sample>
void for_each_camera_sample(const FilmTile& tile, int film_width, const RenderSettings& st, int64_t pass,
                            int64_t spp_pass, Sample&& sample) {
  const PixelBounds& pb = tile.pixels();
  for (int y = pb.y0; y < pb.y1; ++y)
    for (int x = pb.x0; x < pb.x1; ++x) {
      const uint64_t pixel = static_cast<uint64_t>(y) * static_cast<uint64_t>(film_width) + static_cast<uint64_t>(x);
      for (int64_t s = 0; s < spp_pass; ++s) {
        const uint64_t index = static_cast<uint64_t>(pass * spp_pass + s);
        Rng rng = Rng::for_sample(st.seed, pixel, index);
        sample(x, y, index, rng);
      }
    }
}

}  // namespace tb
