#include "lib/mcmc/path_space/start_paths.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "lib/core/parallel.h"
#include "lib/path/dirac.h"

namespace tb::path_space {

MltPath assemble_connection(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s, int t,
                            const Connection& c) {
  MltPath x;
  x.v.reserve(static_cast<size_t>(s + t));
  for (int i = 0; i < s; ++i) x.v.push_back(light[i]);
  for (int i = t - 1; i >= 0; --i) x.v.push_back(camera[i]);
  if (s == 1 && t >= 2) x.v[0] = c.sampled;
  if (t == 1) x.v.back() = c.sampled;
  // Dirac flags as the path-space mutations set them: a property of the surface's material (BDPT
  // flags only the vertices it scattered at).
  for (auto& v : x.v)
    if (v.is_surface()) v.delta = is_dirac_surface(v);
  return x;
}

std::optional<MltPath> sample_bdpt_path(const PathContext& ctx, Uniforms& u, int max_depth, int min_segments,
                                        int attempts) {
  const Camera& cam = ctx.world->camera();
  std::vector<PathVertex> cp, lp;
  std::vector<MltPath> found;
  for (int a = 0; a < attempts; ++a) {
    const Vec2 uf = u.next2(), lens_u = u.next2();
    const int nc = generate_camera_subpath(ctx, Vec2(uf.x * cam.width(), uf.y * cam.height()), lens_u, u,
                                           max_depth + 2, &cp);
    const int nl = generate_light_subpath(ctx, u, max_depth + 1, &lp);
    found.clear();
    for (int t = 1; t <= nc; ++t)
      for (int s = 0; s <= nl; ++s) {
        if (s + t < 2 || s + t - 2 > max_depth || s + t - 1 < min_segments) continue;
        const Connection c = connect_bdpt(ctx, lp, cp, s, t, u);
        if (luminance(c.unweighted) > 0.0) found.push_back(assemble_connection(lp, cp, s, t, c));
      }
    const double pick = u.next();
    if (!found.empty())
      return found[std::min(found.size() - 1, static_cast<size_t>(pick * static_cast<double>(found.size())))];
  }
  return std::nullopt;
}

namespace {

// Replays BDPT sample `index` of stream key `key`: camera and light subpaths and the connections
// in a fixed order; calls visit(s, t, connection, light, camera) until it returns false.
template <class F>
void keyed_bdpt_sample(const PathContext& ctx, uint64_t seed, uint64_t key, uint64_t index, int max_depth, F&& visit) {
  Rng stream = Rng::for_sample(seed, key, index);
  RngUniforms rng(stream);
  const Camera& cam = ctx.world->camera();
  const Vec2 u_film = rng.next2(), lens_u = rng.next2();
  const Vec2 raster(u_film.x * cam.width(), u_film.y * cam.height());
  std::vector<PathVertex> cp, lp;
  const int nc = generate_camera_subpath(ctx, raster, lens_u, rng, max_depth + 2, &cp);
  const int nl = generate_light_subpath(ctx, rng, max_depth + 1, &lp);
  for (int t = 1; t <= nc; ++t)
    for (int s = 0; s <= nl; ++s) {
      if (s + t < 2 || s + t - 2 > max_depth) continue;
      const Connection c = connect_bdpt(ctx, lp, cp, s, t, rng);
      if (!visit(s, t, c, lp, cp)) return;
    }
}

// Bootstrap sample `index` of a chain (key: "mlt" and the chain).
template <class F>
void bootstrap_sample(const PathContext& ctx, uint64_t seed, uint64_t chain, uint64_t index, int max_depth, F&& visit) {
  keyed_bdpt_sample(ctx, seed, 0x6d6c7400ULL + chain, index, max_depth, std::forward<F>(visit));
}

constexpr int64_t kBrightnessChunks = 64;  // fixed chunks: sums independent of the thread count

struct Candidate {
  uint64_t sample = 0;
  int s = 0, t = 0;
  double weight = 0.0;
};

// b = sum / n_boot and the start path: the candidate connection drawn with probability weight /
// sum by the uniform `pick`, re-traced from its bootstrap sample (shared by both start_chain forms).
ChainStart resample_start(const PathContext& ctx, uint64_t seed, uint64_t chain, int64_t n_boot, int max_depth,
                          double pick, const std::vector<Candidate>& cands, double sum) {
  ChainStart start;
  start.b = sum / static_cast<double>(std::max<int64_t>(1, n_boot));
  if (cands.empty()) return start;
  const double target = pick * sum;
  double acc = 0.0;
  const Candidate* chosen = &cands.back();
  for (const auto& c : cands) {
    acc += c.weight;
    if (target < acc) {
      chosen = &c;
      break;
    }
  }
  bootstrap_sample(ctx, seed, chain, chosen->sample, max_depth,
                   [&](int s, int t, const Connection& c, const auto& lp, const auto& cp) {
                     if (s != chosen->s || t != chosen->t) return true;
                     start.x = assemble_connection(lp, cp, s, t, c);
                     return false;
                   });
  return start;
}

}  // namespace

ChainStart start_chain(const PathContext& ctx, uint64_t seed, uint64_t chain, int64_t n_boot, int max_depth,
                       double pick) {
  std::vector<Candidate> cands;
  double sum = 0.0;
  for (int64_t i = 0; i < n_boot; ++i)
    bootstrap_sample(ctx, seed, chain, static_cast<uint64_t>(i), max_depth,
                     [&](int s, int t, const Connection& c, const auto&, const auto&) {
                       const double w = luminance(c.value);
                       if (w > 0.0 && std::isfinite(w)) {
                         sum += w;
                         cands.push_back({static_cast<uint64_t>(i), s, t, w});
                       }
                       return true;
                     });
  return resample_start(ctx, seed, chain, n_boot, max_depth, pick, cands, sum);
}

ChainStart start_chain(const PathContext& ctx, uint64_t seed, uint64_t chain, int64_t n_boot, int max_depth,
                       double pick, const StartupTerm& term) {
  std::vector<Candidate> cands;
  double sum = 0.0;
  for (int64_t i = 0; i < n_boot; ++i)
    bootstrap_sample(ctx, seed, chain, static_cast<uint64_t>(i), max_depth,
                     [&](int s, int t, const Connection& c, const auto& lp, const auto& cp) {
                       if (!(luminance(c.value) > 0.0)) return true;
                       const double w = term(c, assemble_connection(lp, cp, s, t, c));
                       if (w > 0.0 && std::isfinite(w)) {
                         sum += w;
                         cands.push_back({static_cast<uint64_t>(i), s, t, w});
                       }
                       return true;
                     });
  return resample_start(ctx, seed, chain, n_boot, max_depth, pick, cands, sum);
}

double bdpt_brightness(const PathContext& ctx, uint64_t seed, uint64_t key, int64_t n, int max_depth) {
  if (n <= 0) return 0.0;
  std::vector<double> sum(static_cast<size_t>(kBrightnessChunks), 0.0);
  parallel_for(static_cast<size_t>(kBrightnessChunks), [&](size_t chunk) {
    const int64_t lo = n * static_cast<int64_t>(chunk) / kBrightnessChunks;
    const int64_t hi = n * static_cast<int64_t>(chunk + 1) / kBrightnessChunks;
    double acc = 0.0;
    for (int64_t i = lo; i < hi; ++i)
      keyed_bdpt_sample(ctx, seed, key, static_cast<uint64_t>(i), max_depth,
                        [&](int, int, const Connection& c, const auto&, const auto&) {
                          const double w = luminance(c.value);
                          if (w > 0.0 && std::isfinite(w)) acc += w;
                          return true;
                        });
    sum[chunk] = acc;
  });
  double total = 0.0;
  for (double v : sum) total += v;
  return total / static_cast<double>(n);
}

}  // namespace tb::path_space
