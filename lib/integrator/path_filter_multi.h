// Multi-vertex path filtering as an unbiased marginal-MIS estimator (`pfk`; West, Georgiev & Hachisuka
// 2022, Sec. 4.3 Eq. 13 and Sec. 5 Eq. 14; docs/mmis-paths.md, "Multi-vertex filtering").
//
// A pass traces every camera prefix (pf1's, path_filter.h) on to depth K: prefix a has vertices
// y_{a,1..K}, each filterable one (a non-delta BSDF) with the direction w_{a,d} it sampled from its BSDF
// for its own outgoing direction wo_{a,d} (towards y_{a,d-1}); y_{a,d+1} is where w_{a,d} leads. The
// depth-d vertices are indexed in a hashed grid per depth (PointGrid, as pf1).
//
// The output path of query i: x_1 = y_{i,1}; at filtered vertex x_d (d = 1..K) a technique of the kernel
// of x_d gives the direction w_d, x_{d+1} is found by tracing the actual ray from x_d along w_d, and f is
// evaluated along it (visibility and BSDF at x_d for the output path's own wo_d: the unbiased variant of
// Sec. 5.1). Techniques at x_d:
//   d = 1: the members of pf1's kernel (the query's own prefix among them), each used once (n = 1);
//   d >= 2: the m_d depth-d prefix vertices within r of x_d (at most max_members, the nearest) and x_d's
//          own technique (its BSDF sampled for wo_d: coverage, Sec. 5.1), M_d = m_d + 1 of them; one of
//          them is chosen uniformly per output path, so each has the expected count n = 1 / M_d;
//   and at every d, the light sample at x_d (next-event estimation, a classical technique, n = 1) for
//   paths ending on an emitter at x_{d+1}.
// Conditional density of w_d under member j of depth d: p_{j,d}(w_d) = pdf of y_{j,d}'s BSDF for wo_{j,d}
// (solid angle); the densities of the rest of the path (the path-tracer suffix after x_{K+1}) are common to
// all techniques and cancel. Every technique that can produce the output path is one choice per filtered
// vertex, so the Eq. 13 denominator is the product of sums of Eq. 14,
//     D(x) = prod_{d} S_d,   S_d = sum_{t at x_d} n_{t,d} p_{t,d}(w_d)   (+ p_L(w_d) at the emitter's level),
// and every sampled output path contributes f(x) / D(x). Unbiased by induction over d: given everything
// up to the depth-d prefix vertices (which fix x_d and its kernel), the depth-d directions are
// independent with densities p_{j,d}, so the choice at x_d is one sample of the mixture
// sum_t n_t p_t and E[f / S_d] integrates the rest over w_d, provided S_d > 0 where f > 0 (the query's
// prefix at d = 1, the own technique at d >= 2).
//
// K = 1 is pf1 (the same code, the same streams: bit-identical images). Parameters: pf1's radius and
// max_members (per filtered vertex), vertices = K (default 2, at most 8, capped at max_depth).
// Streams: the prefix beyond x_1 from Rng::for_sample(hash(seed, "pfk.prefix", pass), slot, 0); the
// choices, own directions and light samples at x_2.. x_K and then the suffix from pf1's pair stream
// (query, level-1 member).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "estimators/mmis_filtering.h"
#include "lib/film/film.h"
#include "lib/geometry/hit.h"
#include "lib/integrator/path_filter.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

inline constexpr int kPfkMaxVertices = 8;

// One filtered vertex x_d of an output path in the Eq. 14 product: column[t] = n_t p_t(w_d) for every
// technique t at x_d (kernel members, the vertex's own technique, and the light sample where it can
// produce the path), own = the technique that produced w_d, self = the vertex's own technique (d = 1:
// the query's prefix; d >= 2: the BSDF sample at x_d).
struct PfkLevel {
  std::span<const double> column;
  int own = -1;
  int self = -1;
};

// The MMIS weight of an output path filtered at levels.size() vertices: filtering_mmis_weight (the
// function of the analytic filtering checks) with one kernel per filtered vertex: own_pdf = prod_d
// column_d[own_d], denominator = prod_d sum_t column_d[t].
FilteringWeight pfk_mmis_weight(std::span<const PfkLevel> levels);

// The weighting of pfk as a policy of the renderer template (path_filter_multi_impl.h): level 1 as pf1
// (weight), the whole path through pfk_mmis_weight (path_weight); validate/ provides broken ones.
struct PfkExactWeights : Pf1ExactWeights {
  static FilteringWeight path_weight(std::span<const PfkLevel> levels) { return pfk_mmis_weight(levels); }
};

struct PfkParams {
  Pf1Params kernel;
  int vertices = 2;
};
PfkParams pfk_params(const World& world, const RenderSettings& st);
std::vector<std::pair<std::string, std::string>> pfk_parameter_list();

// For the checks: output paths of the first pass as the renderer forms them, with the pass's prefix
// vertices, so that the techniques of every filtered vertex can be enumerated independently.
struct PfkPassVertex {
  SurfacePoint hit;
  Vec3 wo{0.0}, wi{0.0};
  bool has_dir = false;
  uint32_t slot = 0;
};
struct PfkPathLevel {
  SurfacePoint x;       // the filtered vertex x_d of the output path
  Vec3 wo{0.0};         // its outgoing direction (towards x_{d-1} or the camera)
  Vec3 w{0.0};          // the direction at x_d whose densities the column holds
  std::vector<double> column;  // as the renderer formed it
  int own = -1, self = -1;
};
struct PfkSampledPath {
  uint32_t query_slot = 0;
  std::vector<PfkPathLevel> levels;
  // The path ends on an emitter found from the last level (emission at x_{d+1} or the light sample at
  // x_d): the light sample's density there is the column's last entry; delta_light: the only entry.
  bool light_entry = false, delta_light = false;
  FilteringWeight weight;  // the renderer's weight of this path (Weights::path_weight)
};
struct PfkSample {
  PfkParams params;
  std::vector<std::vector<PfkPassVertex>> depth_vertices;  // [d - 1]: the filterable depth-d prefix vertices
  std::vector<PfkSampledPath> paths;
};
// Runs the first pass of a pfk render (settings as for render_pfk) for at most max_queries queries
// (every stride-th filterable prefix) and records every output path that reaches x_2 and its weight.
PfkSample pfk_sample_paths(const World& world, const RenderSettings& settings, size_t max_queries);

int64_t render_pfk(const World& world, const RenderSettings& settings, Film& film);

}  // namespace tb
