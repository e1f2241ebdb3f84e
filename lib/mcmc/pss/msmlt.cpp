#include "lib/mcmc/pss/msmlt.h"

#include "lib/integrator/pass_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/path/light_sampler.h"

namespace tb {
namespace pss {

namespace {

constexpr uint64_t kGuideKey = hash_string("msmlt.guide");
constexpr uint64_t kStageKey = hash_string("msmlt.stage");
constexpr int64_t kGuideChunks = 64;  // fixed chunks of the guide estimate: thread-count independent sums

int ceil_div(int a, int b) { return (a + b - 1) / b; }

}  // namespace

GuideImage::GuideImage(const std::vector<Rgb>& fine, int width, int height, int factor, double floor_fraction)
    : width_(width), height_(height), factor_(std::max(1, factor)) {
  cw_ = ceil_div(width, factor_);
  ch_ = ceil_div(height, factor_);
  coarse_.assign(static_cast<size_t>(cw_) * static_cast<size_t>(ch_), 0.0);
  std::vector<int> count(coarse_.size(), 0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t J = static_cast<size_t>(y / factor_) * static_cast<size_t>(cw_) + static_cast<size_t>(x / factor_);
      coarse_[J] += luminance(fine[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]);
      ++count[J];
    }
  for (size_t J = 0; J < coarse_.size(); ++J) coarse_[J] /= std::max(1, count[J]);
  finish(floor_fraction);
}

GuideImage::GuideImage(std::vector<double> coarse, int width, int height, int factor, double floor_fraction)
    : coarse_(std::move(coarse)), width_(width), height_(height), factor_(std::max(1, factor)) {
  cw_ = ceil_div(width, factor_);
  ch_ = ceil_div(height, factor_);
  finish(floor_fraction);
}

void GuideImage::finish(double floor_fraction) {
  double sum = 0.0;
  bool finite = true;
  for (double v : coarse_) {
    finite = finite && std::isfinite(v) && v >= 0.0;
    sum += v;
  }
  const double mean = coarse_.empty() ? 0.0 : sum / static_cast<double>(coarse_.size());
  uniform_ = !(finite && mean > 0.0);
  floor_ = uniform_ ? 1.0 : std::max(floor_fraction * mean, mean * 1e-12);  // floor > 0 even for phi = 0
}

double GuideImage::at(const Vec2& r) const {
  if (uniform_) return 1.0;
  const int x = static_cast<int>(std::floor(r.x)), y = static_cast<int>(std::floor(r.y));
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return 1.0;
  return std::max(coarse_[static_cast<size_t>(y / factor_) * static_cast<size_t>(cw_) + static_cast<size_t>(x / factor_)],
                  floor_);
}

double GuideImage::target(const std::vector<Splat>& splats) const {
  Rgb sum(0.0);
  for (const Splat& s : splats) sum += s.value / at(s.raster);
  return luminance(sum);
}

namespace {

// Stage K: an independent estimate of the coarse image from `n` fresh samples (levels drawn
// uniformly, weight = number of levels). Fine pixel j: P / n sum_samples sum_c Y(v_c) 1[r_c in j].
GuideImage independent_guide(const SampleFunction& f, int width, int height, int factor, int64_t n, uint64_t seed,
                             double sigma, double floor_fraction) {
  const int levels = std::max(1, f.levels);
  const size_t P = static_cast<size_t>(width) * static_cast<size_t>(height);
  std::vector<std::vector<double>> acc(static_cast<size_t>(kGuideChunks));
  parallel_for(static_cast<size_t>(kGuideChunks), [&](size_t chunk) {
    std::vector<double>& a = acc[chunk];
    a.assign(P, 0.0);
    std::vector<Splat> sp;
    const int64_t lo = n * static_cast<int64_t>(chunk) / kGuideChunks, hi = n * static_cast<int64_t>(chunk + 1) / kGuideChunks;
    for (int64_t i = lo; i < hi; ++i) {
      PssState s(Rng::for_sample(seed, kGuideKey, static_cast<uint64_t>(i)), sigma);
      sp.clear();
      s.restart();
      f.sample(static_cast<int>(i % levels), s, &sp);
      for (const Splat& c : sp) {
        const double y = luminance(c.value);
        const int x = static_cast<int>(std::floor(c.raster.x)), yy = static_cast<int>(std::floor(c.raster.y));
        if (!std::isfinite(y) || x < 0 || yy < 0 || x >= width || yy >= height) continue;
        a[static_cast<size_t>(yy) * static_cast<size_t>(width) + static_cast<size_t>(x)] += y;
      }
    }
  });
  std::vector<Rgb> fine(P, Rgb(0.0));
  const double scale = static_cast<double>(P) * levels / static_cast<double>(std::max<int64_t>(1, n));
  for (size_t j = 0; j < P; ++j) {
    double sum = 0.0;
    for (const auto& a : acc) sum += a[j];
    fine[j] = Rgb(sum * scale);  // grey: luminance(Rgb(v)) = v for weights summing to 1
  }
  return GuideImage(fine, width, height, factor, floor_fraction);
}

int64_t ipow(int64_t b, int e) {
  int64_t r = 1;
  while (e-- > 0) r *= b;
  return r;
}

}  // namespace

int64_t run_msmlt(const SampleFunction& f, const RenderSettings& st, const PssSettings& pss,
                  const MultiStageSettings& ms, Film& film, MultiStageStats* stats_out) {
  const auto t0 = std::chrono::steady_clock::now();
  const int W = film.width(), H = film.height();
  const int64_t P = film.pixel_count();
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t spp_pass = std::max<int64_t>(1, st.spp / passes);
  const int64_t N = spp_pass * P;
  const int B = std::max(2, ms.base), K = std::max(0, ms.stages);
  // Stage K: the same samples per pixel of its resolution as the other stages, at least 64 per
  // coarse pixel (a guide of a handful of samples is mostly floor).
  const int64_t FK = ipow(B, K);
  const int64_t coarse_pixels = ((W + FK - 1) / FK) * ((H + FK - 1) / FK);
  const int64_t guide_n =
      ms.guide_samples > 0
          ? ms.guide_samples
          : std::max<int64_t>(64 * coarse_pixels, std::llround(ms.stage_budget * static_cast<double>(N) /
                                                               static_cast<double>(FK * FK)));
  MultiStageStats total;
  const int64_t done = for_each_pass_batch(st, passes, 1, [&](int64_t pass, int64_t) {
    const uint64_t pass_seed = hash_values(st.seed, kStageKey, static_cast<uint64_t>(pass));
    // Stage K: independent estimate on the coarsest grid.
    auto guide = std::make_shared<GuideImage>(
        independent_guide(f, W, H, static_cast<int>(ipow(B, K)), guide_n, pass_seed, pss.sigma, ms.floor_fraction));
    total.guide_samples += guide_n;
    // Stages K-1 .. 1: PSS chains guided by the previous stage, box-averaged to the next guide.
    for (int k = K - 1; k >= 1; --k) {
      Film tmp(W, H);
      RenderSettings sk = st;
      sk.passes = 1;
      sk.spp = 1;
      sk.seed = hash_values(pass_seed, static_cast<uint64_t>(k));
      sk.progress = [](double) {};
      sk.time_budget_s = 0;
      sk.first_pass = 0;
      sk.pass_count = -1;
      sk.report = nullptr;
      PssSettings pk = pss;
      const int64_t area = ipow(B, 2 * k);
      pk.mutations_per_pass =
          std::max<int64_t>(pss.chains, std::llround(ms.stage_budget * static_cast<double>(N) / static_cast<double>(area)));
      // The guide's scale cancels in pi (the floor is relative to its mean), so this stage's b
      // matters not at all; its bootstrap only has to supply the chains' starts.
      pk.bootstrap = std::max<int64_t>(2 * pss.chains, pss.bootstrap_for(N, f.levels) / area);
      pk.count_visits = false;
      pk.print_stats = false;
      pk.splat_weight = {};  // a negative control's splat weight breaks the film's stage only
      pk.target = [g = guide](const std::vector<Splat>& s) { return g->target(s); };
      PssStats sst;
      run_pss(f, sk, pk, tmp, &sst);
      total.guides.add(sst);
      guide = std::make_shared<GuideImage>(tmp.mean_image(), W, H, static_cast<int>(ipow(B, k)), ms.floor_fraction);
    }
    // Stage 0: the film pass.
    RenderSettings s0 = st;
    s0.passes = 1;
    s0.spp = spp_pass;
    s0.seed = hash_values(pass_seed, uint64_t{0});
    s0.progress = [](double) {};
    s0.time_budget_s = 0;
    s0.first_pass = 0;
    s0.pass_count = -1;
    s0.report = nullptr;
    PssSettings p0 = pss;
    p0.print_stats = false;
    p0.target = [g = guide](const std::vector<Splat>& s) { return g->target(s); };
    PssStats fst;
    run_pss(f, s0, p0, film, &fst);
    total.final_stage.add(fst);
    total.last_guide = *guide;
  });
  total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (pss.print_stats) {
    fmt::print(stderr, "msmlt film stage: {}\n", total.final_stage.message());
    fmt::print(stderr, "msmlt guide stages: {}\n", total.guides.message());
  }
  if (stats_out) *stats_out = std::move(total);
  return done;
}

}  // namespace pss

namespace {

void fill_msmlt_report(const pss::MultiStageStats& s, RunReport* report) {
  if (!report) return;
  const pss::PssStats& f = s.final_stage;
  const pss::PssStats& g = s.guides;
  // Every registered mutation the stages ran, film stage first.
  report->mutations.clear();
  for (const auto& [name, c] : f.components) report->mutations.push_back({name, c.proposed, c.accepted, c.errors});
  for (const auto& [name, c] : g.components)
    report->mutations.push_back({"guide stages: " + name, c.proposed, c.accepted, c.errors});
  report->mutations_total = f.mutations + g.mutations;
  const double sec = f.mutation_seconds + g.mutation_seconds;
  report->mutations_per_second = sec > 0.0 ? static_cast<double>(f.mutations + g.mutations) / sec : 0.0;
}

}  // namespace

int64_t render_msmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                     const pss::MultiStageSettings& ms, Film& film, pss::MultiStageStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::bdpt_sample_function(ctx, film.width(), film.height(), settings.max_depth);
  return pss::run_msmlt(f, settings, p, ms, film, stats);
}

int64_t render_msmlt_mmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                          const pss::MultiStageSettings& ms, Film& film, pss::MultiStageStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::mmlt_sample_function(ctx, film.width(), film.height(), settings.max_depth);
  return pss::run_msmlt(f, settings, p, ms, film, stats);
}

int64_t render_msmlt(const World& world, const RenderSettings& settings, Film& film) {
  pss::MultiStageStats stats;
  const int64_t passes = render_msmlt(world, settings, pss::PssSettings{}, pss::MultiStageSettings{}, film, &stats);
  fill_msmlt_report(stats, settings.report);
  return passes;
}

int64_t render_msmlt_mmlt(const World& world, const RenderSettings& settings, Film& film) {
  pss::MultiStageStats stats;
  const int64_t passes =
      render_msmlt_mmlt(world, settings, pss::PssSettings{}, pss::MultiStageSettings{}, film, &stats);
  fill_msmlt_report(stats, settings.report);
  return passes;
}

}  // namespace tb
