// Photon mapping with a fixed radius (`pm`) and stochastic progressive photon mapping with the
// radius reduction of Hachisuka & Jensen 2009 (`sppm`); docs/photon-mapping.md.
//
// Photons: light paths traced as the light tracer traces them (LightSampler, Light::sample_le,
// SurfaceScatter in TransportMode::kImportance with the adjoint's shading-normal factor, Russian
// roulette after rr_min_depth scattering events) but without camera connections. A photon is
// stored at every surface vertex whose BSDF has a non-delta lobe, with its throughput
//     beta = Le |cos_light| / (pmf pdf_pos pdf_dir) * prod f_imp |cos wi| / pdf_bsdf,
// so that (1 / N) sum beta over N emitted paths estimates the flux arriving there.
//
// Camera paths follow delta lobes (mirror, smooth glass) from the camera and collect the emission
// they see on the way (camera ray or after delta bounces only, weight 1). At every vertex with a
// non-delta lobe they estimate the reflected radiance from the photons within radius r
// (density estimation with the constant kernel, normalised by its area pi r^2):
//     L(x, wo) ~= 1 / (N pi r^2) sum_{|x_p - x| <= r} f(wo, wi_p) |n_s . wi_p| / |n_g . wi_p| beta_p
// (the last factor turns the photons' density per unit of geometric area into the shading
// normal's cosine of the rendering equation; it is 1 on flat shading). All light that has left a
// non-delta surface towards the camera is counted by the photons, direct light included: no
// next-event estimation, so the estimate's only bias is the kernel's. A photon that took d
// scattering events before it arrived counts at a camera vertex after k delta bounces when
// d + 1 + k <= max_depth: the same paths as the path tracer's.
//
// pm: one pass = one photon map of `photons` photons and spp_per_pass camera samples per pixel,
// each density estimate at the fixed radius `radius`; passes are independent Welch samples.
// sppm: one pass = one independent progressive run of spp_per_pass iterations; an iteration
// traces `photons` photons and one camera sample per pixel, and each pixel keeps its own radius
// r_i, photon count N_i and unnormalised flux tau_i (Hachisuka & Jensen 2009, with the radius and
// flux update of progressive photon mapping, Hachisuka, Ogaki & Jensen 2008):
//     M = photons found within r_i, Phi = their sum of f beta (times the camera throughput),
//     N_{i+1} = N_i + alpha M,   r_{i+1}^2 = r_i^2 (N_i + alpha M) / (N_i + M),
//     tau_{i+1} = (tau_i + Phi) r_{i+1}^2 / r_i^2,
// and its estimate is emission / I + tau / (I N_photons pi r^2) after I iterations. With M
// proportional to r_i^2 in expectation this is r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1) (Knaus &
// Zwicker 2011), so r_i^2 ~ i^(alpha - 1). The pass's estimate is added at the pixel's centre.
//
// Parameters (RenderSettings::params): radius (default: 0.01 x the scene's bounding-sphere
// radius; sppm: the initial radius), photons (per pass / per iteration; default: the pixel count
// times the samples per pass for pm, the pixel count for sppm), alpha (sppm only, default 2/3).
//
// Random streams: photons Rng::for_sample(seed, kPhotonKey, global photon index), camera samples
// Rng::for_sample(seed, pixel, sample index) as in the path tracer. Photons are traced in fixed
// chunks and concatenated in chunk order, so maps and images are identical for any thread count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

struct Photon {
  Vec3 p{0.0};     // where it arrived
  Vec3 wi{0.0};    // towards where it came from (unit)
  Rgb beta{0.0};   // throughput (flux x number of emitted paths)
  int depth = 0;   // scattering events before it arrived
};

// A hashed uniform grid over points for fixed-radius range queries (the spatial index of the
// photon map). Cells are cubes of side `cell_size`; cell (i, j, k) = floor(p / cell_size) is
// hashed into a table of 2^m >= 2 n buckets, and the points are sorted by bucket (counting sort,
// stable, so the order within a bucket is the input order). A query of radius r visits the
// buckets of the cells overlapping the cube [x - r, x + r]^3 (27 cells for r <= cell_size),
// each bucket once (two cells may share one), and reports exactly the points with
// |p - x|^2 <= r^2. Hash collisions cost time only, never correctness.
class PointGrid {
 public:
  PointGrid() = default;
  // cell_size > 0 and finite.
  void build(std::span<const Vec3> points, double cell_size);

  size_t size() const { return points_.size(); }
  double cell_size() const { return cell_; }
  size_t bucket_count() const { return buckets_; }

  // Calls f(index) for every point with |p - x|^2 <= r^2, index into the span given to build;
  // in increasing bucket order, input order within a bucket (deterministic).
  template <class F>
  void for_each_within(const Vec3& x, double r, F&& f) const;

  // Bucket of a cell (exposed for the unit tests, which force collisions).
  size_t bucket_of_cell(int64_t i, int64_t j, int64_t k) const;
  // For tests: a table of exactly `buckets` buckets (a power of two), collisions likely.
  void build_with_buckets(std::span<const Vec3> points, double cell_size, size_t buckets);

 private:
  int64_t cell_coord(double v) const { return static_cast<int64_t>(std::floor(v * inv_cell_)); }

  double cell_ = 1.0, inv_cell_ = 1.0;
  size_t buckets_ = 0;             // power of two
  std::vector<uint32_t> start_;    // buckets_ + 1 offsets into points_ / index_
  std::vector<Vec3> points_;       // sorted by bucket
  std::vector<uint32_t> index_;    // input index of points_[k]
};

template <class F>
void PointGrid::for_each_within(const Vec3& x, double r, F&& f) const {
  if (points_.empty() || !(r >= 0)) return;
  const int64_t x0 = cell_coord(x.x - r), x1 = cell_coord(x.x + r);
  const int64_t y0 = cell_coord(x.y - r), y1 = cell_coord(x.y + r);
  const int64_t z0 = cell_coord(x.z - r), z1 = cell_coord(x.z + r);
  // Distinct buckets of the cells; 27 fit inline (r <= cell_size), larger radii use the heap.
  size_t inline_buckets[27];
  std::vector<size_t> heap_buckets;
  const uint64_t n_cells = static_cast<uint64_t>(x1 - x0 + 1) * static_cast<uint64_t>(y1 - y0 + 1) *
                           static_cast<uint64_t>(z1 - z0 + 1);
  size_t* b = inline_buckets;
  if (n_cells > 27) {
    heap_buckets.resize(std::min<uint64_t>(n_cells, 1u << 26));
    b = heap_buckets.data();
  }
  size_t n = 0;
  if (n_cells > (1u << 26) || n_cells >= buckets_) {
    // The cube covers more cells than there are buckets: visit every bucket.
    heap_buckets.resize(buckets_);
    b = heap_buckets.data();
    for (size_t k = 0; k < buckets_; ++k) b[n++] = k;
  } else {
    for (int64_t i = x0; i <= x1; ++i)
      for (int64_t j = y0; j <= y1; ++j)
        for (int64_t k = z0; k <= z1; ++k) b[n++] = bucket_of_cell(i, j, k);
    std::sort(b, b + n);
    n = static_cast<size_t>(std::unique(b, b + n) - b);
  }
  const double r2 = r * r;
  for (size_t q = 0; q < n; ++q)
    for (uint32_t s = start_[b[q]], e = start_[b[q] + 1]; s < e; ++s) {
      const Vec3 d = points_[s] - x;
      if (d.x * d.x + d.y * d.y + d.z * d.z <= r2) f(index_[s]);
    }
}

// The photon-mapping parameters of a run, from RenderSettings::params and the defaults above.
struct PhotonMapParams {
  double radius = 0.0;
  int64_t photons = 0;
  double alpha = 2.0 / 3.0;
};
PhotonMapParams photon_map_params(const World& world, const RenderSettings& st, int64_t pixels, bool progressive);
// The parameter list of `pm` (progressive = false) and `sppm` (name, description with default).
std::vector<std::pair<std::string, std::string>> photon_map_parameter_list(bool progressive);

int64_t render_pm(const World& world, const RenderSettings& settings, Film& film);
int64_t render_sppm(const World& world, const RenderSettings& settings, Film& film);

}  // namespace tb
