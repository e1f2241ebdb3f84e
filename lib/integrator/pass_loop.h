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
#include <vector>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/film/film_tile.h"
#include "lib/integrator/render_settings.h"

namespace tb {

// The one pass loop of every integrator. A run is `total` passes (Welch samples: pt, lt, bdpt and
// the PSS drivers make one film pass per pass; path-space MLT one per chain); this loop runs the
// range [settings.first_pass, first_pass + pass_count) of them in batches of `batch` consecutive
// passes, owning interrupt (checked before each batch), progress (after each batch, as the fraction
// of the range done) and the time budget (stop after the batch during which it ran out).
// body(first, n) renders and closes (Film::end_pass) passes first .. first + n - 1 in order.
// Every pass is a pure function of (seed, pass index), so a film that receives a range [0, a) and
// then [a, b) is bit-identical to one that receives [0, b): this is the unit of work handed to
// another thread, process or machine. Returns the number of passes done.
template <class Body>
int64_t for_each_pass_batch(const RenderSettings& st, int64_t total, int64_t batch, Body&& body) {
  const int64_t first = std::clamp<int64_t>(st.first_pass, 0, total);
  const int64_t end = st.pass_count < 0 ? total : std::min(total, first + st.pass_count);
  const int64_t range = std::max<int64_t>(0, end - first);
  batch = std::max<int64_t>(1, batch);
  const auto t0 = std::chrono::steady_clock::now();
  int64_t done = 0;
  for (int64_t p = first; p < end; p += batch) {
    if (st.interrupted && st.interrupted->load()) break;
    const int64_t n = std::min(batch, end - p);
    body(p, n);
    done += n;
    st.progress(static_cast<double>(done) / static_cast<double>(range));
    if (st.time_budget_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > st.time_budget_s)
      break;
  }
  return done;
}

// settings.passes passes of settings.spp / passes samples per pixel each: render_pass(pass,
// spp_pass) renders one pass into the film and returns the splat scale for Film::end_pass (0 when
// the pass splats nothing).
template <class RenderPass>
int64_t run_passes(const RenderSettings& st, Film& film, RenderPass&& render_pass) {
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t spp_pass = std::max<int64_t>(1, st.spp / passes);
  return for_each_pass_batch(st, passes, 1, [&](int64_t pass, int64_t) { film.end_pass(render_pass(pass, spp_pass)); });
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

// The mutation phase of a pass of chain-based MCMC (the PSS driver, apt): every chain runs its
// `remaining` mutations in segments of `segment`, chains in parallel, each splatting into its own
// buffer (mutate(chain, buffer) makes one mutation); after each segment the buffers are merged
// into the film in chain order, so the film is bit-identical for any thread count.
template <class Chain, class Mutate>
void run_chain_segments(std::vector<Chain>& chains, std::vector<SplatBuffer>& buffers, int64_t segment, Film& film,
                        Mutate&& mutate) {
  for (bool more = true; more;) {
    parallel_for(chains.size(), [&](size_t ci) {
      Chain& c = chains[ci];
      SplatBuffer& buf = buffers[ci];
      buf.clear();
      for (int64_t m = 0; m < segment && c.remaining > 0; ++m, --c.remaining) mutate(c, buf);
    });
    more = false;
    for (size_t ci = 0; ci < chains.size(); ++ci) {
      film.merge_splats(buffers[ci]);
      more = more || chains[ci].remaining > 0;
    }
  }
}

}  // namespace tb
