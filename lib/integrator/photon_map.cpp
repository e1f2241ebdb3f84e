#include "lib/integrator/photon_map.h"

#include <bit>
#include <stdexcept>

#include "lib/core/hash.h"
#include "lib/integrator/photon_map_impl.h"

namespace tb {

size_t PointGrid::bucket_of_cell(int64_t i, int64_t j, int64_t k) const {
  return static_cast<size_t>(hash_values(static_cast<uint64_t>(i), static_cast<uint64_t>(j), static_cast<uint64_t>(k)) &
                             (buckets_ - 1));
}

void PointGrid::build(std::span<const Vec3> points, double cell_size) {
  build_with_buckets(points, cell_size, std::bit_ceil(std::max<size_t>(2 * points.size(), 16)));
}

void PointGrid::build_with_buckets(std::span<const Vec3> points, double cell_size, size_t buckets) {
  if (!(cell_size > 0) || !std::isfinite(cell_size)) throw std::invalid_argument("PointGrid: cell size must be > 0");
  if (buckets == 0 || !std::has_single_bit(buckets)) throw std::invalid_argument("PointGrid: bucket count must be 2^m");
  if (points.size() >= (size_t{1} << 32)) throw std::invalid_argument("PointGrid: too many points");
  cell_ = cell_size;
  inv_cell_ = 1.0 / cell_size;
  buckets_ = buckets;
  std::vector<uint32_t> bucket(points.size());
  start_.assign(buckets_ + 1, 0);
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    bucket[i] = static_cast<uint32_t>(bucket_of_cell(cell_coord(p.x), cell_coord(p.y), cell_coord(p.z)));
    ++start_[bucket[i] + 1];
  }
  for (size_t b = 0; b < buckets_; ++b) start_[b + 1] += start_[b];
  std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
  points_.resize(points.size());
  index_.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {  // stable: input order within a bucket
    const uint32_t at = fill[bucket[i]]++;
    points_[at] = points[i];
    index_[at] = static_cast<uint32_t>(i);
  }
}

std::vector<std::pair<std::string, std::string>> photon_map_parameter_list(bool progressive) {
  std::vector<std::pair<std::string, std::string>> out = {
      {"radius", progressive ? "initial gather radius (default 0.01 x the scene's bounding-sphere radius)"
                             : "gather radius (default 0.01 x the scene's bounding-sphere radius)"},
      {"photons", progressive ? "photons per iteration (default: the pixel count)"
                              : "photons per pass (default: pixels x samples per pass)"}};
  if (progressive) out.push_back({"alpha", "radius reduction alpha in (0, 1) (default 2/3)"});
  return out;
}

PhotonMapParams photon_map_params(const World& world, const RenderSettings& st, int64_t photons_default,
                                  bool progressive) {
  PhotonMapParams p;
  p.radius = 0.01 * world.bounds().radius;
  p.photons = std::max<int64_t>(1, photons_default);
  if (auto it = st.params.find("radius"); it != st.params.end()) p.radius = it->second;
  if (auto it = st.params.find("photons"); it != st.params.end()) p.photons = static_cast<int64_t>(std::llround(it->second));
  if (auto it = st.params.find("alpha"); it != st.params.end()) {
    if (!progressive) throw std::invalid_argument("pm: 'alpha' is a parameter of sppm only");
    p.alpha = it->second;
  }
  if (!(p.radius > 0) || !std::isfinite(p.radius)) throw std::invalid_argument("photon mapping: radius must be > 0");
  if (p.photons < 1 || p.photons > (int64_t{1} << 31)) throw std::invalid_argument("photon mapping: photons must be in [1, 2^31]");
  if (!(p.alpha > 0 && p.alpha < 1)) throw std::invalid_argument("sppm: alpha must lie in (0, 1)");
  return p;
}

int64_t render_pm(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_pm_with<PhotonTerms>(world, st, film);
}

int64_t render_sppm(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_sppm_with<PhotonTerms>(world, st, film);
}

}  // namespace tb
