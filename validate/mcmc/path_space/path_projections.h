// The chi-square projections of the registered path-space mutations (lib/mcmc/path_space/
// path_mutations.h), keyed by mutation name, for the generic proposal chi-square
// mlt.path_space.registered_mutations.chi2 (validate/mcmc/registered_mutations.h).
//
// A path-space density T(x -> .) is a density on paths of varying length and structure, not on a
// fixed low-dimensional space, so no chi-square follows from propose() and density() alone. Each
// mutation's registration therefore carries, here in validate/ (lib/ never includes validate/), a
// projection: given a scene, the built mutation and a test path x, objects with
// sample(Uniforms&) -> optional<Vec2> (y proposed from x, mapped to a 2D chart coordinate) and
// pdf(Vec2) (the stated density of that coordinate, computed from the mutation's density(x, y)
// times the Jacobian of the chart, never from the sampling code), and the chart's bounds. The
// projections are those of proposal_projections.h:
//   bidirectional     the whole mutation through its one-vertex way at k = 3, 4: direction
//                     x_{k-3} -> y_{k-2} in (phi, cos theta) (d omega = d phi d cos theta: the
//                     solid-angle density), other ways failed samples; Monte Carlo expected
//                     counts (its density lives on slivers of the chart);
//   lens              raster offset (phi, ln r), Cornell box, k = 1, 2, 3;
//   caustic           direction change (phi, ln theta), Cornell box, k = 2, 3;
//   multi-chain       direction change at the first continued level given a fixed raster offset,
//                     on the scenes with specular chains (one configuration per scene found,
//                     paths D S+ D S* E with a non-empty first chain);
//   ramlt-lens        primary direction change (phi, theta), Cornell box, k = 1, 2, 3;
//   ramlt-multichain  direction change at the first continued level given a fixed primary
//                     direction (phi, theta), the scenes of multi-chain, Monte Carlo expected counts;
//   hslt              y_1 on the tangent plane of x_1 in the chart of the step's first-order
//                     spread, glossy.json, k = 2 (x_1 on the rough gold sphere).
// A mutation may instead declare why it has no projection (no_projection_reason); the check prints
// it. A registered mutation with neither fails the check, naming the mutation.
//
// Stated density and wrappers: the projection reads proposals and the stated density from
// `checked`, the mutation under test (the registered one, or a wrapper of it in a negative control),
// and the chart (perturb, Jacobians, way_between) from `registered`, the concrete registered
// instance, so a wrapper's misstatement reaches the chi-square of every projection.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/path_mutations.h"

namespace tb::path_space {

class PathChi2Projection {
 public:
  virtual ~PathChi2Projection() = default;
  virtual std::optional<Vec2> sample(Uniforms& u) const = 0;
  virtual double pdf(const Vec2& q) const = 0;  // w.r.t. dq on the chart
  virtual Vec2 chart_lo() const = 0;
  virtual Vec2 chart_hi() const = 0;
  virtual std::string label() const = 0;  // the configuration, e.g. "k=3 s'=1"
};

struct PathProjectionInput {
  const PathContext& ctx;
  const PathMutation& registered;  // as built by the registry for ctx (the chart's helpers)
  const PathMutation& checked;     // whose propose() and density() are tested (registered or a wrapper)
  uint64_t seed;                   // for searches (pilot proposals) the factory makes
};

using PathProjectionList = std::vector<std::unique_ptr<const PathChi2Projection>>;

struct PathProjectionInfo {
  std::string name;        // the mutation's registered name
  std::string coordinate = {};  // what is projected
  std::vector<std::string> scenes = {};  // scene files tried, each at 16 x 16
  // Test paths on a scene (deterministic in seed; empty: the mutation has none there).
  std::function<std::vector<MltPath>(const PathContext&, const PathMutation& registered, uint64_t seed)> paths = {};
  // The projections at x (several configurations, or none where x is unusable).
  std::function<PathProjectionList(const PathProjectionInput&, const MltPath& x)> make = {};
  int cells_x = 25, cells_y = 25;
  int64_t quick_samples = 40000, full_samples = 400000;
  // Bisections per level of the expected counts' quadrature (sampler_chi2.h): 3 keeps cells cut
  // by the image border cheap; more where the stated density has an integrable peak.
  int quadrature_max_depth = 3;
  // Expected counts by a Monte Carlo integral of the stated density (sampler_chi2.h,
  // monte_carlo_expected) instead: where the density lives on slivers quadrature misses.
  bool monte_carlo_expected = false;
  int configs_per_scene = 0;  // at most this many configurations per scene (0: every one)
  // Non-empty: the mutation is declared to have no projection, for this reason (printed).
  std::string no_projection_reason = {};
};

// Every declared projection (one per registered mutation).
const std::vector<PathProjectionInfo>& path_projections();
const PathProjectionInfo* find_path_projection(const std::string& mutation);
// Run-time registration (tests, outside code), next to register_path_mutation.
void register_path_projection(PathProjectionInfo info);
void unregister_path_projection(const std::string& mutation);

// Wraps a projection struct of proposal_projections.h (sample, pdf, chart_lo, chart_hi).
template <class P>
class PathProjectionOf final : public PathChi2Projection {
 public:
  PathProjectionOf(P p, std::string label) : p_(std::move(p)), label_(std::move(label)) {}
  std::optional<Vec2> sample(Uniforms& u) const override { return p_.sample(u); }
  double pdf(const Vec2& q) const override { return p_.pdf(q); }
  Vec2 chart_lo() const override { return p_.chart_lo(); }
  Vec2 chart_hi() const override { return p_.chart_hi(); }
  std::string label() const override { return label_; }
  const P& projection() const { return p_; }

 private:
  P p_;
  std::string label_;
};

}  // namespace tb::path_space
