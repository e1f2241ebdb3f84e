#include "lib/mcmc/apt_integrator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/film/film_tile.h"
#include "lib/integrator/pass_loop.h"

namespace tb::apt {

AptPathFamily::AptPathFamily(const World& world, int max_vertices) : world_(&world) {
  if (max_vertices < 1) throw std::invalid_argument("apt: at least one vertex after the eye");
  targets_.reserve(static_cast<size_t>(max_vertices));
  for (int k = 1; k <= max_vertices; ++k) targets_.emplace_back(world, k);
}

void AptPathFamily::weights(const std::vector<double>& U, std::vector<double>* w) const {
  std::fill(w->begin(), w->end(), 0.0);
  const auto path = targets_.back().trace_prefix(U);
  if (!path) return;
  const int n = std::min(models(), static_cast<int>(path->vertices.size()));
  for (int k = 1; k <= n; ++k) (*w)[static_cast<size_t>(k - 1)] = luminance(mcmc::AptTarget::contribution(*world_, *path, k));
}

int64_t AptSettings::bootstrap_for(int64_t N) const {
  if (bootstrap > 0) return bootstrap;
  return std::clamp<int64_t>(N / 8, 8192, 100000);
}

std::string AptStats::message() const {
  const auto rate = [](const mcmc::ComponentCounts& c) { return c.proposed ? double(c.accepted) / double(c.proposed) : 0.0; };
  return fmt::format("{} mutations in {:.2f} s ({:.3g} /s in the mutation phase); acceptance: large step {:.3f} ({} of "
                     "{}), APT small step {:.3f} ({} of {}); {} bootstrap samples, b = {:.6g} (last pass); {} step errors",
                     mutations, seconds, mutations_per_second(), rate(large), large.accepted, large.proposed,
                     rate(small), small.accepted, small.proposed, bootstrap_samples, last_b, step_errors);
}

void apply_params(const std::map<std::string, double>& params, AptSettings* a) {
  for (const auto& [name, v] : params) {
    if (name == "large_step" && v > 0 && v <= 1) a->large_step_probability = v;
    else if (name == "chains" && v >= 1) a->chains = static_cast<int64_t>(v);
    else if (name == "bootstrap" && v >= 1) a->bootstrap = static_cast<int64_t>(v);
    else
      throw std::invalid_argument(fmt::format(
          "apt parameter {} = {} is unknown or out of range (0 < large_step <= 1, chains >= 1, bootstrap >= 1)", name, v));
  }
}

namespace {

constexpr uint64_t kBootstrapKey = hash_string("apt.bootstrap");
constexpr uint64_t kChainKey = hash_string("apt.chain.decisions");
constexpr uint64_t kStateKey = hash_string("apt.chain.uniforms");
constexpr int kSmall = 0, kLarge = 1;

using LargeStep = mcmc::PrefixMultipleTry<AptPathFamily>;

std::vector<double> draw(Rng rng, size_t n) {
  std::vector<double> U(n);
  for (double& v : U) v = rng.uniform();
  return U;
}

// A chain: the current state (f, colour and the small step's scales cached) and the proposal
// slot, as the ScoredChain of estimators/mcmc/chain_step.h.
struct Chain {
  const LargeStep* large = nullptr;
  double c_large = 0.3;
  mcmc::ModelState x, y;
  Rgb vx{0.0}, vy{0.0};
  double fx = 0.0, fy = 0.0;
  std::optional<mcmc::AptScales> sx, sy;
  std::optional<LargeStep::Move> move;
  Rng control, state;
  double scale = 0.0;  // P b / N
  int64_t remaining = 0;
  uint64_t next_index = 0;
  AptStats stats;

  const AptPathFamily& family() const { return large->family(); }
  void set_current(mcmc::ModelState s) {
    x = std::move(s);
    vx = family().target(x.model).value(x.u);
    fx = luminance(vx);
    sx.reset();
  }
  // ---- ScoredChain -------------------------------------------------------------------------------
  int select(double v) const { return v < c_large ? kLarge : kSmall; }
  bool propose(int k, Uniforms& u) {
    sy.reset();
    if (k == kLarge) {
      move = large->sample_move(x, u);
      if (!move) return false;
      y = large->destination(*move);
    } else {
      const mcmc::AptTarget& t = family().target(x.model);
      if (!sx) sx = t.scales(x.u);
      y.model = x.model;
      y.u = mcmc::AptSmallStep(t).propose(x.u, *sx, u);
    }
    vy = family().target(y.model).value(y.u);
    fy = luminance(vy);
    return true;
  }
  mcmc::MoveTerms terms(int k) {
    if (k == kLarge) {
      mcmc::MoveTerms t = large->move_terms(x, *move);  // Eq. 29: {1, S(U_X), 1, S(U_Y)}
      t.forward *= c_large;
      t.reverse *= c_large;
      return t;
    }
    const double c = 1.0 - c_large;
    if (!(fy > 0.0)) return {fx, c, 0.0, 0.0};
    const mcmc::AptTarget& t = family().target(x.model);
    const mcmc::AptSmallStep step(t);
    sy = t.scales(y.u);
    const double log_ratio = step.log_density(y.u, x.u, *sy) - step.log_density(x.u, y.u, *sx);
    return {fx, c, fy, c * std::exp(log_ratio)};
  }
  void accept() {
    std::swap(x, y);
    vx = vy;
    fx = fy;
    sx = std::move(sy);
  }
  void reject() {}
};

void mutate(Chain& c, SplatBuffer& buffer, const SplatWeight& weight, int width, int height) {
  const uint64_t index = c.next_index++;
  RngUniforms decisions(c.control), proposal(c.state);
  const mcmc::StepOutcome o = mcmc::chain_step(c, decisions, proposal, [&](mcmc::Which which, double w) {
    const bool cur = which == mcmc::Which::kCurrent;
    const double f = cur ? c.fx : c.fy;
    if (!(f > 0.0)) return;
    const mcmc::ModelState& s = cur ? c.x : c.y;
    const double factor = weight ? weight(which, w, f) : w / f;
    buffer.splat(Vec2(s.u[0] * width, s.u[1] * height), (cur ? c.vx : c.vy) * (c.scale * factor), index);
  });
  if (o.component == kLarge) c.stats.large.add(o);
  if (o.component == kSmall) c.stats.small.add(o);
  c.stats.step_errors += o.status == mcmc::MoveStatus::kZeroForward || o.status == mcmc::MoveStatus::kNonFinite;
  ++c.stats.mutations;
}

}  // namespace

int64_t run_apt(const World& world, const RenderSettings& st, const AptSettings& apt, Film& film, AptStats* stats_out) {
  const auto t0 = std::chrono::steady_clock::now();
  const LargeStep large(AptPathFamily(world, std::max(1, st.max_depth + 1)));
  const AptPathFamily& fam = large.family();
  const size_t D = large.full_dimension();
  const int64_t P = film.pixel_count();
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t N = std::max<int64_t>(1, st.spp / passes) * P;  // mutations per pass
  const int64_t M = apt.bootstrap_for(N);
  const int64_t C = std::clamp<int64_t>(apt.chains, 1, N);
  const int64_t segment = std::max<int64_t>(1, apt.segment);
  AptStats total;
  std::vector<double> boot(static_cast<size_t>(M)), cdf(static_cast<size_t>(M));
  std::vector<Chain> chains(static_cast<size_t>(C));
  std::vector<SplatBuffer> buffers(static_cast<size_t>(C), SplatBuffer(film.width(), film.height()));
  const int64_t done = for_each_pass_batch(st, passes, 1, [&](int64_t pass, int64_t) {
    // 1. Bootstrap: b = mean of S(U) over fresh draws.
    const uint64_t base = static_cast<uint64_t>(pass * M);
    parallel_for(static_cast<size_t>(M), [&](size_t i) {
      std::vector<double> w(static_cast<size_t>(fam.models()));
      fam.weights(draw(Rng::for_sample(st.seed, kBootstrapKey, base + i), D), &w);
      boot[i] = apt.bootstrap_sum ? apt.bootstrap_sum(w) : mcmc::weight_sum(w);
    });
    double acc = 0.0;
    for (int64_t i = 0; i < M; ++i) cdf[static_cast<size_t>(i)] = acc += boot[static_cast<size_t>(i)];
    const double b = acc / static_cast<double>(M);
    total.bootstrap_samples += M;
    total.last_b = b;
    if (!(acc > 0.0)) {
      ++total.zero_passes;
      film.end_pass(1.0);
      return;
    }
    // 2. Chains start at draws resampled by S, at a candidate chosen by W_k.
    const double scale = static_cast<double>(P) * b / static_cast<double>(N);
    parallel_for(static_cast<size_t>(C), [&](size_t k) {
      Chain& c = chains[k];
      const uint64_t gc = static_cast<uint64_t>(pass * C) + k;
      c.control = Rng::for_sample(st.seed, kChainKey, gc);
      c.state = Rng::for_sample(st.seed, kStateKey, gc);
      c.large = &large;
      c.c_large = apt.large_step_probability;
      c.stats = {};
      c.scale = scale;
      c.remaining = N / C + (static_cast<int64_t>(k) < N % C ? 1 : 0);
      c.next_index = gc << 32;  // film reproducer: (pass * chains + chain) * 2^32 + mutation
      const double v = c.control.uniform() * acc;
      const size_t i = std::min<size_t>(static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), v) - cdf.begin()),
                                        static_cast<size_t>(M - 1));
      std::vector<double> U = draw(Rng::for_sample(st.seed, kBootstrapKey, base + i), D);
      std::vector<double> w(static_cast<size_t>(fam.models()));
      fam.weights(U, &w);
      const int j = std::max(0, mcmc::select_weighted(w, c.control.uniform()));
      U.resize(fam.dimension(j));
      c.set_current({j, std::move(U)});
    });
    // 3. Mutations, in segments whose splat buffers are merged in chain order.
    const auto tm = std::chrono::steady_clock::now();
    run_chain_segments(chains, buffers, segment, film, [&](Chain& c, SplatBuffer& buf) {
      mutate(c, buf, apt.splat_weight, film.width(), film.height());
    });
    total.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - tm).count();
    for (const Chain& c : chains) {
      total.small.merge(c.stats.small);
      total.large.merge(c.stats.large);
      total.mutations += c.stats.mutations;
      total.step_errors += c.stats.step_errors;
    }
    // 4. The splats carry P b / N already.
    film.end_pass(1.0);
  });
  total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (stats_out) *stats_out = total;
  return done;
}

}  // namespace tb::apt

namespace tb {

int64_t render_apt(const World& world, const RenderSettings& settings, Film& film) {
  apt::AptSettings a;
  apt::apply_params(settings.params, &a);
  apt::AptStats stats;
  const int64_t passes = apt::run_apt(world, settings, a, film, &stats);
  if (settings.report) {
    RunReport& r = *settings.report;
    r.mutations = {{"large step (path tracer, multiple-try)", stats.large.proposed, stats.large.accepted, stats.large.errors},
                   {"APT small step", stats.small.proposed, stats.small.accepted, stats.small.errors}};
    r.mutations_total = stats.mutations;
    r.mutations_per_second = stats.mutations_per_second();
  }
  return passes;
}

}  // namespace tb
