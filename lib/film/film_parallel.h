// Deterministic parallel accumulation into a film. Work is cut into pieces that depend only on
// the image size / sample count (never on the thread count), each piece accumulates into its
// own tile or splat buffer, and the pieces are merged into the film in their index order, so
// floating-point sums are formed in the same order whatever the number of threads.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "lib/core/parallel.h"
#include "lib/film/film.h"

namespace tb {

// Calls f(tile) for every tile_size x tile_size block of pixels in parallel; f adds the samples
// of tile.pixels() to the tile. Tiles are merged in row-major tile order.
template <class F>
void for_each_film_tile(Film& film, int tile_size, F&& f) {
  const int tx = (film.width() + tile_size - 1) / tile_size, ty = (film.height() + tile_size - 1) / tile_size;
  std::vector<FilmTile> tiles;
  tiles.reserve(size_t(tx) * size_t(ty));
  for (int j = 0; j < ty; ++j)
    for (int i = 0; i < tx; ++i)
      tiles.push_back(film.make_tile({i * tile_size, j * tile_size, std::min(film.width(), (i + 1) * tile_size),
                                      std::min(film.height(), (j + 1) * tile_size)}));
  parallel_for(tiles.size(), [&](size_t k) { f(tiles[k]); });
  film.merge_tiles(tiles);
}

// Calls f(sample_index, buffer) for sample indices [0, n) in parallel; chunks of chunk_size
// consecutive indices share a splat buffer, and buffers are merged in chunk order, in batches
// of `batch` chunks to bound memory.
template <class F>
void splat_parallel(Film& film, uint64_t n, uint64_t chunk_size, F&& f, size_t batch = 64) {
  const uint64_t chunks = (n + chunk_size - 1) / chunk_size;
  std::vector<SplatBuffer> buffers(batch, SplatBuffer(film.width(), film.height()));
  for (uint64_t first = 0; first < chunks; first += batch) {
    const size_t count = static_cast<size_t>(std::min<uint64_t>(batch, chunks - first));
    parallel_for(count, [&](size_t k) {
      SplatBuffer& b = buffers[k];
      b.clear();
      const uint64_t begin = (first + k) * chunk_size, end = std::min(n, begin + chunk_size);
      for (uint64_t s = begin; s < end; ++s) f(s, b);
    });
    for (size_t k = 0; k < count; ++k) film.merge_splats(buffers[k]);
  }
}

}  // namespace tb
