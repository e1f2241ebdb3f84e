#include "validate/differential/hslt_walk_support.h"

#include <cmath>

#include "lib/core/rng.h"
#include "validate/differential/hslt_paths.h"

namespace tb {

Eigen::VectorXd hslt_walk_direction(const HsltPath& path, uint64_t seed, uint64_t key, int64_t index) {
  Rng rng = Rng::for_sample(seed, key, static_cast<uint64_t>(index));
  const int n = path.interior_count();
  Eigen::VectorXd d(2 * n);
  for (int r = 0; r < n; ++r) {
    const double phi = 2 * M_PI * rng.uniform();
    d[2 * r] = std::cos(phi);
    d[2 * r + 1] = std::sin(phi);
  }
  return d;
}

Eigen::VectorXd hslt_walk_target(const HsltPath& path, double delta, uint64_t seed, uint64_t key, int64_t index) {
  return hslt_constraints(path) + delta * hslt_walk_direction(path, seed, key, index);
}

HsltWalkOptions hslt_walk_options_for(const std::string& family) {
  HsltWalkOptions o;
  o.visibility = family == "curved_mirrors" || family == "glass" || family == "mirror_chain";
  return o;
}

bool hslt_walk_start_ok(const Scene& scene, const HsltPath& path, bool visibility) {
  const HsltProjectFn project = hslt_ray_cast_projection(scene, visibility);
  std::vector<Vec3> predicted;
  for (const HsltVertex& v : path.vertices) predicted.push_back(v.p);
  for (const bool from_start : {true, false}) {
    HsltPath out;
    if (project(path, predicted, from_start, &out) != HsltWalkStatus::kConverged) return false;
    if (!(hslt_max_vertex_distance(out, path) < 1e-7)) return false;
  }
  return true;
}

HsltOnSurface hslt_walk_on_surface(const Scene& scene, const HsltPath& path, const Eigen::VectorXd& target) {
  std::vector<int> interior;
  for (int i = 1; i <= path.interior_count(); ++i) interior.push_back(i);
  const HsltPath rebuilt = hslt_path_at(scene, path, interior, hslt_free_coordinates(path, interior));
  HsltOnSurface r;
  r.surface_distance = hslt_max_vertex_distance(rebuilt, path);
  const double e = (hslt_constraints(rebuilt) - target).norm();
  r.constraint_error = std::isfinite(e) ? e : 1e300;
  return r;
}

}  // namespace tb
