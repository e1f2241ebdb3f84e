#include "validate/render/mis_enumeration.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "lib/integrator/bdpt.h"
#include "lib/path/light_sampler.h"

namespace tb {

bool has_only_dirac_lobes(const PathVertex& v) {
  if (!v.is_surface() || !v.bsdf) return false;
  const uint32_t f = v.bsdf->flags();
  return (f & bsdf_flags::kDelta) != 0 && (f & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy)) == 0;
}

namespace {

// Can x_0 be hit by a camera subpath by chance (s = 0)?
bool emitter_has_extent(const PathVertex& x0) {
  if (!x0.light) return false;
  const uint32_t f = x0.light->flags();
  if (f & (light_flags::kDeltaPosition | light_flags::kDeltaDirection)) return false;
  return (f & (light_flags::kArea | light_flags::kInfinite)) != 0;
}

// A Dirac-direction emitter at a finite position: x_1 lies on its one ray, so pL[1] is a delta.
// Not the directional light: that one is an infinite emitter, whose x_0 is the direction itself
// (the delta is its pL[0], common to every s >= 1), and pL[1] is the genuine area density of the
// point x_1 drawn on its emission disk.
bool dirac_direction_emitter(const PathVertex& x0) {
  return x0.light && !x0.infinite && (x0.light->flags() & light_flags::kDeltaDirection) != 0;
}

}  // namespace

TechniqueEnumeration enumerate_techniques(std::span<const PathVertex> x, const PathDensities& d) {
  const size_t n = x.size(), k = n - 1;
  TechniqueEnumeration e;
  e.can_generate.assign(n, 0);
  e.weight.assign(n, 0.0);
  std::vector<uint8_t> dirac(n, 0);
  for (size_t i = 1; i < k; ++i) {
    dirac[i] = has_only_dirac_lobes(x[i]) ? 1 : 0;
    e.dirac_vertices += dirac[i];
  }
  // A density generated at a Dirac vertex (or by a Dirac-direction emitter): a delta common to
  // every technique that can generate the path, counted as 1.
  const auto pl_is_delta = [&](size_t i) { return i == 1 ? dirac_direction_emitter(x[0]) : (i >= 2 && dirac[i - 1]); };
  const auto pe_is_delta = [&](size_t i) { return i + 1 < k && dirac[i + 1]; };
  std::vector<double> log_p(n, -std::numeric_limits<double>::infinity());
  for (size_t s = 0; s <= k; ++s) {
    bool ok;
    if (s == 0) {
      ok = emitter_has_extent(x[0]);
    } else {
      const bool left = s - 1 == 0 || !dirac[s - 1];  // x_0 (the emitter) can always be joined
      const bool right = s == k || !dirac[s];         // x_k (the lens) can always be joined
      ok = left && right && !(s == 1 && k == 1 && x[0].infinite);
    }
    double lp = 0.0;
    for (size_t i = 0; ok && i < k; ++i) {  // pE[k] (lens position) is common to all: left out
      const bool from_light = i < s;
      if (from_light ? pl_is_delta(i) : pe_is_delta(i)) continue;
      const double p = from_light ? d.pL[i] : d.pE[i];
      if (!(p > 0.0) || !std::isfinite(p)) {
        ok = false;
      } else {
        lp += std::log(p);
      }
    }
    if (!ok) continue;
    e.can_generate[s] = 1;
    log_p[s] = lp;
  }
  double m = -std::numeric_limits<double>::infinity();
  for (size_t s = 0; s <= k; ++s)
    if (e.can_generate[s]) m = std::max(m, log_p[s]);
  double sum = 0.0;
  for (size_t s = 0; s <= k; ++s)
    if (e.can_generate[s]) sum += std::exp(2.0 * (log_p[s] - m));
  for (size_t s = 0; s <= k; ++s)
    if (e.can_generate[s]) e.weight[s] = std::exp(2.0 * (log_p[s] - m)) / sum;
  return e;
}

void MisInvariantTally::add(std::span<const PathVertex> x, const TechniqueEnumeration& e, std::span<const double> code,
                            int sampled_s, const std::string& where) {
  ++paths;
  if (e.dirac_vertices > 0) ++paths_with_dirac;
  const auto note = [&](const std::string& what) {
    if (!first_violation.empty()) return;
    // Enough to reproduce the verdict by hand: the emitter, the vertex kinds, both weight vectors.
    std::string kinds, wc, we;
    for (size_t i = 0; i < x.size(); ++i) {
      kinds += i == 0 ? "" : " ";
      kinds += x[i].kind == VertexKind::kCamera ? "C" : x[i].kind == VertexKind::kLight ? "L" : (x[i].delta ? "S*" : "S");
      if (x[i].bsdf) kinds += fmt::format("({})", x[i].bsdf->name());
      wc += fmt::format("{}{:.3g}", i == 0 ? "" : " ", code[i]);
      we += fmt::format("{}{:.3g}", i == 0 ? "" : " ", e.weight[i]);
    }
    first_violation = fmt::format("{} (path of {} segments, emitter {}, vertices [{}]): {}; weights [{}], enumeration [{}]",
                                  where, x.size() - 1, x[0].light ? std::string(x[0].light->name()) : "none", kinds,
                                  what, wc, we);
  };
  if (sampled_s < 0 || sampled_s >= static_cast<int>(e.can_generate.size()) || !e.can_generate[sampled_s]) {
    ++sampled_invalid;
    note(fmt::format("sampled by s = {}, which cannot generate it", sampled_s));
  }
  double sum = 0.0;
  for (size_t s = 0; s < e.can_generate.size(); ++s) {
    ++techniques;
    if (e.can_generate[s]) {
      ++can_generate;
      sum += code[s];
      const double dv = std::abs(code[s] - e.weight[s]);
      if (dv > worst_vs_enumeration) worst_vs_enumeration = dv;
      if (dv > 1e-9) note(fmt::format("w_{} = {} but the enumeration gives {}", s, code[s], e.weight[s]));
    } else if (code[s] != 0.0) {
      ++nonzero_invalid;
      worst_invalid = std::max(worst_invalid, std::abs(code[s]));
      note(fmt::format("s = {} cannot generate the path but has weight {}", s, code[s]));
    }
  }
  const double ds = std::abs(sum - 1.0);
  if (ds > worst_sum) worst_sum = ds;
  if (ds > 1e-12) note(fmt::format("weights sum to 1 {:+.3g}", sum - 1.0));
}

bool MisInvariantTally::holds() const {
  return worst_sum <= 1e-12 && nonzero_invalid == 0 && worst_vs_enumeration <= 1e-9 && sampled_invalid == 0;
}

void sample_mis_invariant(const World& world, const std::string& label, const MisInvariantOptions& o,
                          MisInvariantTally* tally, double* worst_incremental) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const Camera& cam = world.camera();
  const double w = cam.width(), h = cam.height();
  std::vector<PathVertex> camera, light, x;
  std::vector<double> code;
  for (int64_t i = 0; i < o.subpath_pairs; ++i) {
    Rng stream = Rng::for_sample(o.seed, 0x6d6973 /* "mis" */, static_cast<uint64_t>(i));
    RngUniforms u(stream);
    const Vec2 raster(u.next() * w, u.next() * h);
    const Vec2 lens = u.next2();
    const int nc = generate_camera_subpath(ctx, raster, lens, u, o.max_depth + 2, &camera);
    const int nl = generate_light_subpath(ctx, u, o.max_depth + 1, &light);
    for (int t = 1; t <= nc; ++t)
      for (int s = 0; s <= nl; ++s) {
        if (s + t - 2 > o.max_depth || s + t < 2) continue;
        const Connection c = connect_bdpt(ctx, light, camera, s, t, u);
        if (is_black(c.unweighted)) continue;
        x.clear();
        for (int j = 0; j < s; ++j) x.push_back(light[j]);
        for (int j = t - 1; j >= 0; --j) x.push_back(camera[j]);
        if (s == 1 && t >= 2) x[0] = c.sampled;
        if (t == 1) x.back() = c.sampled;
        PathDensities d = path_densities(ctx, x);
        const TechniqueEnumeration e = enumerate_techniques(x, d);
        if (o.drop_dirac_flags) std::fill(d.delta.begin(), d.delta.end(), uint8_t{0});
        code.assign(x.size(), 0.0);
        for (size_t j = 0; j < x.size(); ++j) code[j] = mis_weight(d, static_cast<int>(j), MisKind::kPower);
        // s = 0 on an infinite light sums over the environment emitters: its weight is not one number.
        if (!(s == 0 && x[0].infinite))
          *worst_incremental = std::max(*worst_incremental, std::abs(c.weight - code[static_cast<size_t>(s)]));
        tally->add(x, e, code, s, fmt::format("{}, pair {}, s = {}, t = {}", label, i, s, t));
      }
  }
}

}  // namespace tb
