#include "validate/mcmc/path_space/path_projections.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "estimators/mcmc/mutation.h"
#include "lib/core/frame.h"
#include "lib/core/hash.h"
#include "lib/geometry/spawn.h"
#include "lib/path/path.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "validate/mcmc/path_space/proposal_projections.h"

namespace tb::path_space {

namespace {

constexpr int kMaxDepth = 4;  // test paths of up to 5 segments (the per-mutation chi-squares' depth)

// The concrete proposal of a registered mutation (the chart's helpers); throws when the registry
// built something else under that name.
template <class P>
const P& concrete(const PathMutation& m) {
  if (const auto* p = dynamic_cast<const PathProposalMutation<P>*>(&m)) return p->proposal();
  throw std::logic_error("projection of '" + m.name() + "': the registered mutation is not of the expected type");
}
template <class P>
const P& concrete_ramlt(const PathMutation& m) {
  if (const auto* p = dynamic_cast<const RamltMutation<P>*>(&m)) return p->proposal();
  throw std::logic_error("projection of '" + m.name() + "': the registered mutation is not of the expected type");
}

// A projection with the object its pointers refer to, owned.
template <class P>
struct KeepAlive {
  P p;
  std::shared_ptr<const void> owned;
  std::optional<Vec2> sample(Uniforms& u) const { return p.sample(u); }
  double pdf(const Vec2& q) const { return p.pdf(q); }
  Vec2 chart_lo() const { return p.chart_lo(); }
  Vec2 chart_hi() const { return p.chart_hi(); }
};

template <class P>
PathProjectionList one(P p, std::string label) {
  PathProjectionList out;
  out.push_back(std::make_unique<const PathProjectionOf<P>>(std::move(p), std::move(label)));
  return out;
}

// The bidirectional projection is on the sphere; the chart is (phi, cos theta) of the world frame,
// where d omega = d phi d cos theta, so its density is the solid-angle density.
class BidirChart final : public PathChi2Projection {
 public:
  BidirChart(BidirVertexProjection p, std::string label) : p_(std::move(p)), label_(std::move(label)) {}
  std::optional<Vec2> sample(Uniforms& u) const override {
    const auto w = p_.sample(u);
    if (!w) return std::nullopt;
    double phi = std::atan2(w->y, w->x);
    if (phi < 0) phi += 2 * kPi;
    return Vec2(phi, std::clamp(w->z, -1.0, 1.0));
  }
  double pdf(const Vec2& q) const override {
    const double s = std::sqrt(std::max(0.0, 1.0 - q.y * q.y));
    return p_.pdf(Vec3(s * std::cos(q.x), s * std::sin(q.x), q.y));
  }
  Vec2 chart_lo() const override { return {0.0, -1.0}; }
  Vec2 chart_hi() const override { return {2 * kPi, 1.0}; }
  std::string label() const override { return label_; }

 private:
  BidirVertexProjection p_;
  std::string label_;
};

std::vector<MltPath> paths_of_lengths(const PathContext& ctx, std::initializer_list<int> ks, uint64_t seed) {
  std::vector<MltPath> out;
  for (int k : ks) out.push_back(path_with_segments(ctx, k, kMaxDepth, seed + static_cast<uint64_t>(k)));
  return out;
}

// Is no other surface within r of v, along 8 directions 10 degrees above its tangent plane?
bool clear_of_corners(const PathContext& ctx, const PathVertex& v, double r) {
  if (v.kind != VertexKind::kSurface) return true;
  const Frame f = Frame::from_z(v.hit.ng);
  for (int i = 0; i < 8; ++i) {
    const double phi = 2 * kPi * i / 8, e = 10.0 * kPi / 180.0;
    for (const double side : {1.0, -1.0}) {
      const Vec3 w = f.to_world(Vec3(std::cos(e) * std::cos(phi), std::cos(e) * std::sin(phi), side * std::sin(e)));
      const auto h = ctx.world->geometry().intersect(spawn_ray(v.hit, w));
      if (h && glm::length(h->p - v.hit.p) < r) return false;
    }
  }
  return true;
}

// Bidirectional test paths: k = 3, 4, their kept neighbours x_{k-3} and x_{k-1} of the new vertex
// at least 5 % of the scene's bounding diameter from any other surface. Near a corner the area
// density of a vertex added from x_{k-1} (or x_{k-3}) has a 1 / d^2 peak on the adjacent surface
// so narrow that the Gauss-Kronrod rules of the expected counts do not see it (their error
// estimate agrees on the flanks); measured at seed 10 before this restriction.
std::vector<MltPath> bidir_paths(const PathContext& ctx, uint64_t seed) {
  std::vector<MltPath> out;
  const double r = 0.1 * ctx.world->bounds().radius;
  for (int k : {3, 4})
    for (uint64_t i = 0;; ++i) {
      const MltPath x = path_with_segments(ctx, k, kMaxDepth, hash_values(seed, static_cast<uint64_t>(k), i));
      if (clear_of_corners(ctx, x.v[k - 3], r) && clear_of_corners(ctx, x.v[k - 1], r)) {
        out.push_back(x);
        break;
      }
    }
  return out;
}

std::vector<PathProjectionInfo>& table() {
  static std::vector<PathProjectionInfo> t = {
      {.name = "bidirectional",
       .coordinate = "direction x_{k-3} -> y_{k-2} of the one-vertex way (phi, cos theta)",
       .scenes = {"cornell-box.json"},
       .paths = [](const PathContext& ctx, const PathMutation&, uint64_t seed) { return bidir_paths(ctx, seed); },
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         BidirChart c(BidirVertexProjection{&in.checked, &in.ctx, &concrete<BidirectionalMutation>(in.registered), x},
                      fmt::format("k={}", x.segments()));
         PathProjectionList out;
         out.push_back(std::make_unique<const BidirChart>(std::move(c)));
         return out;
       },
       // Coarse cells: the support (f > 0, seen from x_{k-3}) is cut by shadow and surface edges,
       // and a cell holding only a sliver of it can miss every node of the expected counts'
       // quadrature (zero expected, a hard failure); measured: at 25 x 13 cells seed 6 failed so.
       .cells_x = 13,
       .cells_y = 7,
       // About 5 % of the whole mutation's proposals take the one-vertex way with f(y) > 0.
       .quick_samples = 300000,
       .full_samples = 3000000,
       .monte_carlo_expected = true},
      {.name = "lens",
       .coordinate = "raster offset (phi, ln r)",
       .scenes = {"cornell-box.json"},
       .paths = [](const PathContext& ctx, const PathMutation&,
                   uint64_t seed) { return paths_of_lengths(ctx, {1, 2, 3}, seed + 10); },
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         const auto& lens = concrete<LensPerturbation>(in.registered);
         return one(LensOffsetProjection{&lens, &in.ctx, x, &in.checked},
                    fmt::format("k={} j={}", x.segments(), lens.chain_end(x)));
       }},
      {.name = "caustic",
       .coordinate = "direction change (phi, ln theta)",
       .scenes = {"cornell-box.json"},
       .paths = [](const PathContext& ctx, const PathMutation&,
                   uint64_t seed) { return paths_of_lengths(ctx, {2, 3}, seed + 20); },
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         const auto& c = concrete<CausticPerturbation>(in.registered);
         return one(CausticAngleProjection{&c, x, &in.checked},
                    fmt::format("k={} j={}", x.segments(), c.chain_start(x)));
       }},
      {.name = "multi-chain",
       .coordinate = "direction change at the first continued level given the raster offset (phi, ln theta)",
       .scenes = {"caustic.json", "dg-glass.json", "dg-mirror-chain.json"},
       // Paths with exactly one continued level after a non-empty first chain, the first few of
       // 20000 BDPT paths.
       .paths =
           [](const PathContext& ctx, const PathMutation& reg, uint64_t seed) {
             const auto& mc = concrete<MultiChainPerturbation>(reg);
             std::vector<MltPath> out;
             for (uint64_t i = 0; i < 20000 && out.size() < 4; ++i) {
               Rng r = Rng::for_sample(seed + 30, 0x6d756c7469ULL, i);
               RngUniforms u(r);
               auto p = sample_bdpt_path(ctx, u, kMaxDepth);
               if (!p) continue;
               const std::vector<int> lv = mc.levels(*p);
               // D S+ D S* E: the first chain not empty (j1 < k - 1).
               if (lv.size() == 2 && lv[0] < p->segments() - 1) out.push_back(std::move(*p));
             }
             return out;
           },
       // The first fixed offset whose move succeeds for at least half of 64 pilot proposals
       // (elsewhere the success region is a sliver the expected counts' quadrature cannot resolve).
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         const auto& mc = concrete<MultiChainPerturbation>(in.registered);
         const Vec2 offsets[] = {{0.3, 0.9}, {0.8, 0.95}, {0.55, 0.7}, {0.05, 0.8}, {0.3, 0.5}, {0.8, 0.9}};
         for (const Vec2 uo : offsets) {
           const MultiChainAngleProjection p{&mc, &mc, &in.ctx, x, uo, &in.checked};
           int ok = 0;
           for (uint64_t t = 0; t < 64; ++t) {
             Rng rp = Rng::for_sample(in.seed + 31, 0x70696c6f74ULL, t);
             RngUniforms up(rp);
             ok += p.sample(up).has_value();
           }
           if (ok >= 32) {
             const std::vector<int> lv = mc.levels(x);
             return one(p, fmt::format("k={} levels={},{} u_offset=({},{})", x.segments(), lv[0], lv[1], uo.x, uo.y));
           }
         }
         return {};
       },
       .cells_x = 21,
       .cells_y = 21,
       .quick_samples = 10000,
       .full_samples = 100000,
       .configs_per_scene = 1},
      {.name = "ramlt-lens",
       .coordinate = "primary direction change (phi, theta)",
       .scenes = {"cornell-box.json"},
       .paths = [](const PathContext& ctx, const PathMutation&,
                   uint64_t seed) { return paths_of_lengths(ctx, {1, 2, 3}, seed + 40); },
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         const auto& r = concrete_ramlt<RamltLensPerturbation>(in.registered);
         const LensPerturbation structure(in.ctx);
         if (!r.applicable(x) || structure.chain_end(x) != x.segments() - 1) return {};  // empty lens chain only
         return one(RamltLensAngleProjection{&r, x, &in.checked}, fmt::format("k={}", x.segments()));
       }},
      {.name = "ramlt-multichain",
       .coordinate = "direction change at the first continued level given the primary direction (phi, theta)",
       .scenes = {"caustic.json", "dg-glass.json", "dg-mirror-chain.json"},
       // As multi-chain: paths D S+ D S* E with one continued level, the first 8 of 100000 BDPT paths (the
       // primary and level steps, 0.05 rad, often change a chain: more candidates than multi-chain's).
       .paths =
           [](const PathContext& ctx, const PathMutation& reg, uint64_t seed) {
             const MultiChainPerturbation mc(ctx);
             std::vector<MltPath> out;
             for (uint64_t i = 0; i < 100000 && out.size() < 8; ++i) {
               Rng r = Rng::for_sample(seed + 60, 0x72616d6c74ULL, i);
               RngUniforms u(r);
               auto p = sample_bdpt_path(ctx, u, kMaxDepth);
               if (!p || !(reg.weight(*p) > 0.0)) continue;
               const std::vector<int> lv = mc.levels(*p);
               if (lv.size() == 2 && lv[0] < p->segments() - 1) out.push_back(std::move(*p));
             }
             return out;
           },
       // The first fixed primary whose move succeeds for at least 16 of 64 pilot proposals (Monte Carlo
       // expected counts resolve a narrow success region).
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         const auto& r = concrete_ramlt<RamltMultiChainPerturbation>(in.registered);
         const auto mc = std::make_shared<const MultiChainPerturbation>(in.ctx);
         const Vec2 offsets[] = {{0.3, 0.9}, {0.8, 0.95}, {0.55, 0.7}, {0.05, 0.8}, {0.3, 0.5}, {0.8, 0.9}};
         for (const Vec2 uo : offsets) {
           const RamltMultiChainAngleProjection p{&r, mc.get(), &in.ctx, x, uo, &in.checked};
           int ok = 0;
           for (uint64_t t = 0; t < 64; ++t) {
             Rng rp = Rng::for_sample(in.seed + 61, 0x70696c6f74ULL, t);
             RngUniforms up(rp);
             ok += p.sample(up).has_value();
           }
           if (ok >= 16) {
             const std::vector<int> lv = mc->levels(x);
             return one(KeepAlive<RamltMultiChainAngleProjection>{p, mc},
                        fmt::format("k={} levels={},{} u_primary=({},{})", x.segments(), lv[0], lv[1], uo.x, uo.y));
           }
         }
         return {};
       },
       .cells_x = 21,
       .cells_y = 21,
       .quick_samples = 10000,
       .full_samples = 100000,
       .monte_carlo_expected = true,
       .configs_per_scene = 1},
      {.name = "hslt",
       .coordinate = "y_1 on the tangent plane of x_1 in the chart of the step's first-order spread, k = 2",
       .scenes = {"glossy.json"},
       // Paths light -> x_1 -> camera with x_1 on the rough gold sphere (Beckmann roughness >= 0.15),
       // away from its silhouette (|cos| to the camera >= 0.5) so that the chart is regular over the
       // support: the first of seeded BDPT samples (mcmc.hslt.proposal_chi2.glossy's paths).
       .paths =
           [](const PathContext& ctx, const PathMutation& reg, uint64_t seed) {
             const auto& h = concrete<HsltMutation>(reg);
             std::vector<MltPath> out;
             for (uint64_t i = 0; i < 200000 && out.empty(); ++i) {
               Rng r = Rng::for_sample(seed + 50, 0x68736c74ULL, i);
               RngUniforms u(r);
               auto p = sample_bdpt_path(ctx, u, 1, 2);
               if (!p || p->segments() != 2 || !h.applicable(*p) || !(reg.weight(*p) > 0.0)) continue;
               const PathVertex& v = p->v[1];
               if (v.bsdf->name() != "rough_conductor" || v.bsdf->beckmann_roughness() < 0.15) continue;
               if (std::abs(glm::dot(v.hit.ng, direction(v, p->v[2]))) < 0.5) continue;
               out.push_back(std::move(*p));
             }
             return out;
           },
       .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
         const auto p = HsltTangentProjection::at(&concrete<HsltMutation>(in.registered), &in.ctx, x, &in.checked);
         if (!p) return {};
         return one(*p, fmt::format("k=2 x_1 on {}", x.v[1].bsdf->name()));
       },
       .cells_x = 15,
       .cells_y = 15,
       .quick_samples = 20000,
       .full_samples = 200000,
       .quadrature_max_depth = 2},
      // The manifold perturbation's y is a deterministic function of the lens kernel's raster offset:
      // a chi-square in that chart divides its whole change of measure out again (the lens part is the
      // lens perturbation's, checked by its projection). Its generalised geometry term is checked by
      // mcmc.memlt.pairwise.* against the stated T and by the memlt image checks.
      {.name = "manifold",
       .no_projection_reason = "y is a deterministic function of the lens offset (lens chi-square); the walk's "
                               "geometry term is checked by mcmc.memlt.pairwise and mcmc.memlt.image"},
  };
  return t;
}

}  // namespace

const std::vector<PathProjectionInfo>& path_projections() { return table(); }
const PathProjectionInfo* find_path_projection(const std::string& mutation) { return mcmc::find_named(table(), mutation); }
void register_path_projection(PathProjectionInfo info) { mcmc::add_named(table(), std::move(info), "path projection"); }
void unregister_path_projection(const std::string& mutation) { mcmc::remove_named(table(), mutation); }

}  // namespace tb::path_space
