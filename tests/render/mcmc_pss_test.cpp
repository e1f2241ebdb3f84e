// Primary-sample-space MLT (lib/mcmc/pss/): the lazily updated state against its eager definition,
// the rescaled small step (lazy ratio = dense density ratio; pairwise balance with its control),
// the multi-stage guide lookup, msmlt / msmlt over MMLT / rescaled PSSMLT over PT images,
// the small step's density, pairwise detailed balance of the PSS kernel on the Cornell box target
// (validate/mcmc/pairwise_balance.h), determinism over thread counts, and image unbiasedness of
// PSSMLT (over BDPT and over a next-event path tracer) and MMLT against BDPT with Welch's t-test over
// 32 independent passes (each pass its own bootstrap and chains), with the negative controls the
// image test must reject. Pixels with fewer than 32 expected chain visits per pass are excluded
// (docs/mlt-pss.md, "Checks and tests"). Statistical tests: alpha = 0.01 (image tests,
// per-channel Šidák inside compare_channels), 1e-5 for the KS tests of the state; fixed seeds.
#include <chrono>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lib/core/parallel.h"
#include "lib/integrator/bdpt.h"
#include "lib/integrator/path_tracer.h"
#include "lib/mcmc/pss/msmlt.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "lib/mcmc/pss/pss_kernel.h"
#include "lib/mcmc/pss/pss_steps.h"
#include "lib/mcmc/pss/stratified_pss.h"
#include "validate/render/broken_pss.h"
#include "lib/path/light_sampler.h"
#include "lib/scene/scene_loader.h"
#include "validate/mcmc/broken_variants.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/render/render_compare.h"
#include "validate/stats/tests.h"

namespace tb::pss {
namespace {

constexpr double kSigma = 0.01;

// Signed circular difference b - a in [-0.5, 0.5).
double circ(double a, double b) {
  double d = b - a;
  d -= std::floor(d + 0.5);
  return d;
}

TEST(PssState, StreamsInterleave) {
  const std::vector<double> u = [] {
    std::vector<double> v(30);
    std::iota(v.begin(), v.end(), 0.0);
    return v;
  }();
  DenseStreams s(u);
  s.use_stream(kLightStream);
  EXPECT_EQ(s.next(), 1.0);
  EXPECT_EQ(s.next(), 4.0);
  s.use_stream(kCameraStream);
  EXPECT_EQ(s.next(), 0.0);
  s.use_stream(kLightStream);
  EXPECT_EQ(s.next(), 7.0);  // streams keep their positions
  s.use_stream(kConnectionStream);
  EXPECT_EQ(s.next(), 2.0);
  s.restart();
  s.use_stream(kLightStream);
  EXPECT_EQ(s.next(), 1.0);
}

// Reads `n` uniforms of each stream.
std::vector<double> read_all(PssState& s, int n) {
  std::vector<double> v;
  for (int st = 0; st < kStreams; ++st) {
    s.use_stream(st);
    for (int i = 0; i < n; ++i) v.push_back(s.next());
  }
  return v;
}

TEST(PssState, RejectRestoresAcceptKeeps) {
  PssState s(Rng::for_sample(1, 2, 3), kSigma);
  const std::vector<double> x0 = read_all(s, 8);
  for (bool large : {false, true}) {
    s.start_iteration(large);
    const std::vector<double> y = read_all(s, 12);  // reads 4 new coordinates per stream too
    s.reject();
    s.restart();
    // Read back at the same iteration number without a new proposal: nothing is mutated.
    EXPECT_EQ(s.iteration(), 0);
    const std::vector<double> back = read_all(s, 8);
    EXPECT_EQ(back, x0) << (large ? "large" : "small");
    size_t changed = 0;
    for (size_t i = 0; i < 8; ++i) changed += y[i] != x0[i];
    EXPECT_EQ(changed, 8u);
  }
  s.start_iteration(false);
  const std::vector<double> y = read_all(s, 8);
  s.accept();
  s.restart();
  EXPECT_EQ(read_all(s, 8), y);  // same iteration: the accepted values, unchanged
  for (size_t i = 0; i < y.size(); ++i) EXPECT_LT(std::abs(circ(x0[i], y[i])), 12 * kSigma);
}

// The small step's normals (the ziggurat of pss_state.cpp, Marsaglia & Tsang 2000): one
// coordinate at 0.5 perturbed by sigma z and rejected, 10^6 times (the wrap is unreachable:
// |z| would have to exceed 10). KS of z against N(0, 1), alpha 0.01, and the share of |z| beyond
// the ziggurat's tail start R = 3.4426 (the tail branch, 5.8e-4 of the draws) against its exact
// probability, 99% Clopper-Pearson. Negative control: the same KS against N(0, 1.01^2) (a 1%
// scale error) must reject.
TEST(PssState, SmallStepNormalsAreStandardNormal) {
  constexpr double sigma = 0.05, R = 3.442619855899;
  constexpr int64_t n = 1000000;
  PssState s = PssState::at({0.5}, Rng::for_sample(0x5eed, 0x2167, 7), sigma);
  std::vector<double> z;
  z.reserve(n);
  int64_t tail = 0;
  for (int64_t k = 0; k < n; ++k) {
    s.start_iteration(false);
    z.push_back((s.next() - 0.5) / sigma);
    tail += std::abs(z.back()) > R;
    s.reject();
  }
  const auto ks = stats::ks_test(z, [](double v) { return stats::normal_cdf(v); });
  EXPECT_FALSE(ks.rejects(0.01)) << "D = " << ks.statistic << ", p = " << ks.p_value;
  const double p_tail = 2.0 * (1.0 - stats::normal_cdf(R));
  EXPECT_TRUE(stats::binomial_interval(tail, n, 0.99).contains(p_tail)) << tail << " of " << n << " beyond R";
  const auto wide = stats::ks_test(z, [](double v) { return stats::normal_cdf(v / 1.01); });
  EXPECT_TRUE(wide.rejects(0.01)) << "negative control: p = " << wide.p_value;
}

// Lazy = eager in distribution: a coordinate left unread for n accepted small steps (with
// rejected iterations in between, which do not count) moves by a wrapped N(0, n sigma^2), exactly
// as a coordinate read, hence perturbed, at every accepted iteration. KS against the normal CDF
// (the wrap is negligible at sigma sqrt(n) = 0.045: mass beyond 0.5 is below 1e-28), alpha 1e-5.
TEST(PssState, LazyUpdateEqualsEager) {
  constexpr int kAccepted = 20, kReps = 4000;
  std::vector<double> lazy, eager;
  for (int r = 0; r < kReps; ++r) {
    PssState s(Rng::for_sample(5, 6, static_cast<uint64_t>(r)), kSigma);
    Rng decide = Rng::for_sample(5, 7, static_cast<uint64_t>(r));
    s.use_stream(kCameraStream);
    const double e0 = s.next();
    s.use_stream(kLightStream);
    const double l0 = s.next();
    int accepted = 0;
    while (accepted < kAccepted - 1) {
      s.start_iteration(false);
      s.use_stream(kCameraStream);
      s.next();  // the eager coordinate: read every iteration
      if (decide.uniform() < 0.5) {
        s.accept();
        ++accepted;
      } else {
        s.reject();
      }
    }
    s.start_iteration(false);
    s.use_stream(kCameraStream);
    const double e1 = s.next();
    s.use_stream(kLightStream);
    const double l1 = s.next();  // the lazy coordinate: first read after kAccepted small steps
    s.accept();
    eager.push_back(circ(e0, e1));
    lazy.push_back(circ(l0, l1));
  }
  const double sd = kSigma * std::sqrt(double(kAccepted));
  auto cdf = [sd](double d) { return stats::normal_cdf(d / sd); };
  const auto kl = stats::ks_test(lazy, cdf), ke = stats::ks_test(eager, cdf);
  EXPECT_GT(kl.p_value, 1e-5) << "lazy D = " << kl.statistic;
  EXPECT_GT(ke.p_value, 1e-5) << "eager D = " << ke.statistic;
}

// An accepted large step in the gap makes the lazily read coordinate a fresh uniform; a rejected
// one leaves it to the small steps.
TEST(PssState, LazyLargeStep) {
  constexpr int kReps = 4000;
  std::vector<double> after_accepted, moved_rejected;
  for (int r = 0; r < kReps; ++r) {
    for (bool acc : {true, false}) {
      PssState s(Rng::for_sample(8, acc, static_cast<uint64_t>(r)), kSigma);
      s.use_stream(kCameraStream);
      s.next();
      s.use_stream(kLightStream);
      const double l0 = s.next();
      s.start_iteration(true);  // reads only the camera coordinate
      s.use_stream(kCameraStream);
      s.next();
      if (acc)
        s.accept();
      else
        s.reject();
      s.start_iteration(false);
      s.use_stream(kLightStream);
      const double l1 = s.next();
      s.accept();
      if (acc)
        after_accepted.push_back(circ(l0, l1) + 0.5);  // uniform on [0, 1) when l1 is fresh
      else
        moved_rejected.push_back(circ(l0, l1));
    }
  }
  EXPECT_GT(stats::ks_test(after_accepted, [](double x) { return std::clamp(x, 0.0, 1.0); }).p_value, 1e-5);
  // One accepted small step only (the rejected large step does not count).
  EXPECT_GT(stats::ks_test(moved_rejected, [](double d) { return stats::normal_cdf(d / kSigma); }).p_value, 1e-5);
}

TEST(PssKernel, SmallStepDensitySymmetricAndNormalised) {
  Rng rng(42);
  for (int i = 0; i < 1000; ++i) {
    const double d = rng.uniform() * 0.2 - 0.1;
    EXPECT_DOUBLE_EQ(wrapped_normal_pdf(d, kSigma), wrapped_normal_pdf(-d, kSigma));
    EXPECT_NEAR(wrapped_normal_pdf(d, 0.3), wrapped_normal_pdf(d + 1.0, 0.3), 1e-12);
  }
  for (double sigma : {0.01, 0.3}) {  // midpoint rule over one period: spectrally accurate
    const int n = 20000;
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += wrapped_normal_pdf((i + 0.5) / n, sigma) / n;
    EXPECT_NEAR(sum, 1.0, 1e-9) << sigma;
  }
  // The registered small step as the renderer's kernel proposes it (lazy state), on a target
  // that reads every coordinate of a 12-dimensional state.
  SampleFunction all;
  all.sample = [](int, StreamUniforms& u, std::vector<Splat>* out) {
    double v = 1.0;
    for (int st = 0; st < kStreams; ++st) {
      u.use_stream(st);
      for (int i = 0; i < 4; ++i) v += u.next();
    }
    out->push_back({Vec2(0.5, 0.5), Rgb(v)});
  };
  PssStepSettings ps;
  ps.sigma = kSigma;
  const PssKernel k(all, 0, make_pss_mutations({"small step"}, ps), kSigma);
  RngUniforms u(rng);
  for (int i = 0; i < 200; ++i) {
    DenseState x(12);
    for (double& v : x) v = u.next();
    const auto y = k.propose(0, x, u);
    ASSERT_TRUE(y);
    const double f = k.density(0, x, *y), b = k.density(0, *y, x);
    EXPECT_GT(f, 0.0);
    EXPECT_NEAR(f, b, 1e-12 * f);
  }
}

// ---- the Cornell box ---------------------------------------------------------------------------

constexpr int kRes = 16, kDepth = 3;

// scenes/cornell-box.json with camera.resolution rewritten in the JSON text.
std::unique_ptr<World> load_cornell(int res) {
  const std::string dir = std::string(TB_SOURCE_DIR) + "/scenes";
  std::ifstream in(dir + "/cornell-box.json");
  std::stringstream ss;
  ss << in.rdbuf();
  nlohmann::json j = nlohmann::json::parse(ss.str());
  j["camera"]["resolution"] = {res, res};
  return load_world_from_string(j.dump(1), "cornell-box.json", dir);
}

struct Cornell {
  std::unique_ptr<World> world = load_cornell(kRes);
  LightSampler sampler{*world};
  PathContext ctx{world.get(), &sampler};
};

Cornell& cornell() {
  static Cornell c;
  return c;
}

TEST(PssKernel, PairwiseDetailedBalanceCornellBox) {
  const Cornell& c = cornell();
  const SampleFunction f = bdpt_sample_function(c.ctx, kRes, kRes, kDepth);
  const SampleFunction m = mmlt_sample_function(c.ctx, kRes, kRes, kDepth);
  const size_t dims = kStreams * 40;  // more than the sample functions read at max_depth 3
  PssStepSettings ps;
  ps.sigma = kSigma;
  const PssKernel kernel(f, 0, make_pss_mutations({"large step", "small step"}, ps), kSigma);
  const PssKernel mkernel(m, 2, make_pss_mutations({"large step", "small step"}, ps), kSigma);  // 3 segments
  auto start = [&](const PssTarget& target) {
    return [&target, dims](Uniforms& u) {
      DenseState x(dims);
      for (int tries = 0; tries < 64; ++tries) {  // any start sampler will do; prefer pi > 0
        for (double& v : x) v = u.next();
        if (target.density(x) > 0) break;
      }
      return x;
    };
  };
  const auto r = mcmc::check_pairwise_balance<decltype(kernel)>(kernel, start(kernel.target()), 3000, 11, 1);
  EXPECT_TRUE(r.passed) << r.message;
  const auto rm = mcmc::check_pairwise_balance<decltype(mkernel)>(mkernel, start(mkernel.target()), 3000, 11, 2);
  EXPECT_TRUE(rm.passed) << rm.message;
  // The negative control of the generic checker applies: the rule without T (Metropolis ratio)
  // is exact here, because both PSS mutations are symmetric; that is why the image checks carry
  // the negative controls of this module (dropped rejected splat, dropped technique count).
}

// ---- rescaled small step (pss_steps.h) -----------------------------------------------------------

// A synthetic sample function whose read set depends on the values read: the camera stream reads
// 2 + floor(4 u_0) uniforms after its first, the light stream 1 + floor(3 u'_0); the value is
// smooth and positive, so sigma(x) varies from state to state.
SampleFunction variable_reads_function() {
  SampleFunction f;
  f.sample = [](int, StreamUniforms& u, std::vector<Splat>* out) {
    u.use_stream(kCameraStream);
    const double c0 = u.next();
    double v = 0.1 + c0;
    for (int i = 0, n = 2 + static_cast<int>(4 * c0); i < n; ++i) v += std::sin(6.0 * u.next());
    u.use_stream(kLightStream);
    const double l0 = u.next();
    for (int i = 0, n = 1 + static_cast<int>(3 * l0); i < n; ++i) v *= 1.0 + u.next();
    out->push_back({Vec2(0.5, 0.5), Rgb(std::exp(0.5 * v))});
  };
  return f;
}

// The lazy state's ratio (the rescaled step's log_reverse_over_forward over the lazy move, as the
// renderer's chain forms it) against its dense densities log T(y -> x) - log T(x -> y) on the same
// x and y, along a chain with accepted and rejected small and large steps.
TEST(PssState, RescaledLazyRatioMatchesDenseDensity) {
  const SampleFunction f = variable_reads_function();
  PssStepSettings ps;
  ps.sigma = kSigma;
  ps.sigma_max = 0.2;
  const double y_ref = 3.0;
  const RescaledSmallStep step(ps);
  const size_t dims = kStreams * 12;
  PssState s(Rng(7), kSigma);
  std::vector<Splat> sp;
  auto eval = [&]() {
    sp.clear();
    s.restart();
    f.sample(0, s, &sp);
    return target_value(sp);
  };
  double ix = eval();
  s.commit_reads();
  Rng control(8);
  int compared = 0;
  for (int it = 0; it < 400; ++it) {
    const bool large = control.uniform() < 0.2;
    const double sx = step.scale(ix, y_ref);
    const auto dx = s.current_reads();
    if (large)
      s.start_iteration(true);
    else
      step.begin(s, sx);
    const double iy = eval();
    if (!large) {
      const double sy = step.scale(iy, y_ref);
      LazyPssMove lm(s);
      lm.reads_x = dx;
      lm.reads_y = s.reads();
      lm.sigma_x = sx;
      lm.sigma_y = sy;
      const double lazy = step.log_reverse_over_forward(lm);
      // Dense x and y: coordinates in D(x) hold x's values, in D(y) y's; the rest agree.
      DenseState x(dims, 0.5), y(dims, 0.5);
      const auto dy = s.reads();
      for (size_t i = 0; i < dims; ++i) {
        const size_t j = i / kStreams, st = i % kStreams;
        const bool in_x = j < dx[st], in_y = j < dy[st];
        if (in_y) y[i] = s.stored(i);
        if (in_x) x[i] = in_y ? s.backup(i) : s.stored(i);
        // Outside D(x) ∩ D(y) the coordinate is read by at most one of them; the other's value
        // is set equal (its g_sigma0 factor is then the same both ways, and the lazy state may not
        // hold a materialised value for it: e.g. a never-read coordinate is drawn when first read).
        if (in_x && !in_y) y[i] = x[i];
        if (in_y && !in_x) x[i] = y[i];
      }
      ASSERT_NEAR(evaluate_dense(f, 0, x).value, ix, 1e-12 * ix);
      ASSERT_NEAR(evaluate_dense(f, 0, y).value, iy, 1e-12 * iy);
      DenseMove fwd(x, y), back(y, x);
      fwd.reads_x = back.reads_y = dx;
      fwd.reads_y = back.reads_x = dy;
      fwd.sigma_x = back.sigma_y = sx;
      fwd.sigma_y = back.sigma_x = sy;
      const double want = step.log_density(y, x, back) - step.log_density(x, y, fwd);
      if (std::isinf(want))  // g_sigma(y) underflows: a jump of many sigma(y) (both sides say so)
        ASSERT_EQ(lazy, want) << "iteration " << it;
      else
        ASSERT_NEAR(lazy, want, 1e-9 * std::max(1.0, std::abs(want))) << "iteration " << it;
      ++compared;
    }
    if (control.uniform() < 0.5) {
      s.accept();
      ix = iy;
    } else {
      s.reject();
    }
  }
  EXPECT_GT(compared, 200);
}

TEST(PssKernel, RescaledSmallStepPairwiseBalanceAndControl) {
  const SampleFunction f = variable_reads_function();
  PssStepSettings ps;
  ps.sigma = kSigma;
  ps.sigma_max = 0.2;
  auto start = [](Uniforms& u) {
    DenseState x(kStreams * 12);
    for (double& v : x) v = u.next();
    return x;
  };
  const PssMutationList list = make_pss_mutations({"rescaled small step"}, ps);
  const PssKernel good(f, 0, list, kSigma, 3.0);
  const auto rg = mcmc::check_pairwise_balance<PssKernel>(good, start, 3000, 12, 1);
  EXPECT_TRUE(rg.passed) << rg.message;
  // The renderer's own step with the ratio dropped (a wrapper of the registered mutation).
  const PssKernel bad(f, 0, {std::make_shared<const WithoutProposalRatio>(list[0])}, kSigma, 3.0);
  const auto rb = mcmc::check_pairwise_balance<PssKernel>(bad, start, 3000, 12, 1);
  EXPECT_FALSE(rb.passed) << rb.message;
  EXPECT_GT(rb.violations, 100);
}

TEST(MultiStage, GuideLookupAndFloor) {
  // 4x2 film, factor 2: coarse 2x1 = {mean of left block, mean of right block}.
  std::vector<Rgb> fine(8, Rgb(0.0));
  for (int y = 0; y < 2; ++y) {
    fine[static_cast<size_t>(y * 4 + 0)] = Rgb(2.0);
    fine[static_cast<size_t>(y * 4 + 1)] = Rgb(6.0);
  }
  const GuideImage g(fine, 4, 2, 2, 0.1);
  ASSERT_EQ(g.coarse_width(), 2);
  ASSERT_EQ(g.coarse_height(), 1);
  EXPECT_NEAR(g.coarse()[0], 4.0, 1e-12);
  EXPECT_NEAR(g.coarse()[1], 0.0, 1e-12);
  EXPECT_NEAR(g.at(Vec2(1.5, 0.5)), 4.0, 1e-12);
  EXPECT_NEAR(g.at(Vec2(3.5, 1.5)), 0.1 * 2.0, 1e-12);  // floor: 0.1 * mean (4 + 0) / 2
  const std::vector<Splat> sp = {{Vec2(0.5, 0.5), Rgb(8.0)}, {Vec2(2.5, 0.5), Rgb(0.4)}};
  EXPECT_NEAR(g.target(sp), 8.0 / 4.0 + 0.4 / 0.2, 1e-9);
  const GuideImage empty(std::vector<Rgb>(8, Rgb(0.0)), 4, 2, 2, 0.1);
  EXPECT_EQ(empty.at(Vec2(0.5, 0.5)), 1.0);  // nothing found: plain PSSMLT target
}

// Bit-identical results for 1 and 2 threads.
TEST(PssRender, DeterministicAcrossThreadCounts) {
  const Cornell& c = cornell();
  RenderSettings st;
  st.spp = 8;
  st.passes = 2;
  st.max_depth = kDepth;
  PssSettings p;
  p.bootstrap = 512;
  p.chains = 7;
  p.segment = 100;
  auto run = [&](size_t threads, bool mmlt) {
    ThreadLimit limit(threads);
    Film film(kRes, kRes);
    if (mmlt)
      render_mmlt(*c.world, st, p, film, nullptr);
    else
      render_pssmlt(*c.world, st, p, film, nullptr);
    return film.welch().sum;
  };
  for (bool mmlt : {false, true}) {
    const auto a = run(1, mmlt), b = run(2, mmlt);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "pixel " << i << (mmlt ? " mmlt" : " pssmlt");
  }
  // Multi-stage and rescaled variants.
  auto run2 = [&](size_t threads, bool ms) {
    ThreadLimit limit(threads);
    Film film(kRes, kRes);
    if (ms) {
      render_msmlt(*c.world, st, p, MultiStageSettings{}, film, nullptr);
    } else {
      PssSettings q = p;
      q.rescale.enabled = true;
      render_pssmlt_pt(*c.world, st, q, film, nullptr);
    }
    return film.welch().sum;
  };
  for (bool ms : {false, true}) {
    const auto a = run2(1, ms), b = run2(2, ms);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "pixel " << i << (ms ? " msmlt" : " rescaled");
  }
}

// ---- image unbiasedness against BDPT ----------------------------------------------------------

constexpr int64_t kPasses = 32;

const Film& bdpt_reference() {
  static const Film film = [] {
    RenderSettings st;
    st.passes = kPasses;
    st.spp = kPasses * 96;
    st.max_depth = kDepth;
    st.seed = 101;
    Film f(kRes, kRes);
    render_bdpt(*cornell().world, st, f);
    return f;
  }();
  return film;
}

// The negative controls, each a wrapper of the real component (validate/render/broken_pss.h).
enum class PssFault { kNone, kNoRejectedSplat, kNoTechniqueCount, kSplatThroughput };

void apply(PssFault fault, PssSettings* p) {
  if (fault == PssFault::kNoRejectedSplat) p->splat_weight = splat_without_rejected;
  if (fault == PssFault::kSplatThroughput) p->splat_weight = splat_throughput;
  if (fault == PssFault::kNoTechniqueCount) p->wrap_sample = without_technique_count;
}

Film render_mcmc(bool mmlt, PssFault fault, int64_t spp_pass, PssStats* stats) {
  RenderSettings st;
  st.passes = kPasses;
  st.spp = kPasses * spp_pass;
  st.max_depth = kDepth;
  st.seed = mmlt ? 202 : 303;
  PssSettings p;
  // b's error is common to all pixels of a pass: keep it below theirs (docs/mlt-pss.md, "Checks").
  p.bootstrap = mmlt ? 2 * spp_pass * kRes * kRes : spp_pass * kRes * kRes / 2;
  p.chains = 256;
  apply(fault, &p);
  Film film(kRes, kRes);
  if (mmlt)
    render_mmlt(*cornell().world, st, p, film, stats);
  else
    render_pssmlt(*cornell().world, st, p, film, stats);
  return film;
}

// Welch comparison of an MCMC image with the reference over the pixels the chains visit at
// least kMinVisits times per pass in expectation (expected_visits); the others are excluded.
constexpr double kMinVisits = 32;
ChannelCompare compare_mcmc(const Film& film, const Film& ref, int64_t mutations_per_pass, int64_t* excluded) {
  const std::vector<double> visits = expected_visits(ref.mean_image(), mutations_per_pass);
  std::vector<bool> mask(visits.size());
  *excluded = 0;
  for (size_t i = 0; i < visits.size(); ++i) *excluded += (mask[i] = visits[i] < kMinVisits);
  WelchImage a = film.welch(), b = ref.welch();
  exclude_pixels(a, b, mask);
  return compare_channels(a, b, 0.01);
}

void expect_compare(bool mmlt, PssFault fault, int64_t spp_pass, bool expect_reject) {
  PssStats stats;
  const Film film = render_mcmc(mmlt, fault, spp_pass, &stats);
  int64_t excluded = 0;
  const ChannelCompare cmp = compare_mcmc(film, bdpt_reference(), spp_pass * kRes * kRes, &excluded);
  EXPECT_EQ(film.nonfinite().count(), 0);
  EXPECT_EQ(stats.nonfinite, 0);
  EXPECT_EQ(cmp.rejects(), expect_reject) << (mmlt ? "mmlt: " : "pssmlt: ") << cmp.message();
  std::printf("%s fault %d, %lld pixels excluded: %s\n  %s\n", mmlt ? "mmlt" : "pssmlt", static_cast<int>(fault),
              static_cast<long long>(excluded), cmp.message().c_str(), stats.message().c_str());
}

// PSSMLT over a radiance estimator L(raster, u) through radiance_sample_function, the hook for the
// path tracer: here a path tracer with next-event estimation and no MIS built from BDPT's
// unweighted techniques: s = 0 for the emitter seen directly (t = 2), s = 1 (next-event) for every
// longer path; each path length is estimated once, so it estimates the same image.
TEST(PssRender, PssmltOverRadianceEstimatorUnbiasedAgainstBdpt) {
  const Cornell& c = cornell();
  const SampleFunction f = radiance_sample_function(kRes, kRes, [&c](const Vec2& raster, Uniforms& u) {
    thread_local std::vector<PathVertex> cam;
    const Vec2 lens = u.next2();
    const int nc = generate_camera_subpath(c.ctx, raster, lens, u, kDepth + 2, &cam);
    Rgb L(0.0);
    const PathVertex unused;  // s = 1 samples its own emitter vertex (next-event); the span needs one
    if (nc >= 2) L += connect_bdpt(c.ctx, {}, cam, 0, 2, u).unweighted;
    for (int t = 2; t <= nc && t - 1 <= kDepth; ++t)
      L += connect_bdpt(c.ctx, std::span<const PathVertex>(&unused, 1), cam, 1, t, u).unweighted;
    return L;
  });
  constexpr int64_t kSppPass = 32;
  RenderSettings st;
  st.passes = kPasses;
  st.spp = kPasses * kSppPass;
  st.max_depth = kDepth;
  st.seed = 404;
  PssSettings p;
  p.bootstrap = kSppPass * kRes * kRes / 2;
  p.chains = 256;
  Film film(kRes, kRes);
  PssStats stats;
  run_pss(f, st, p, film, &stats);
  int64_t excluded = 0;
  const ChannelCompare cmp = compare_mcmc(film, bdpt_reference(), kSppPass * kRes * kRes, &excluded);
  EXPECT_EQ(stats.nonfinite, 0);
  EXPECT_FALSE(cmp.rejects()) << cmp.message();
  std::printf("pssmlt over next-event path tracing, %lld pixels excluded: %s\n  %s\n", static_cast<long long>(excluded),
              cmp.message().c_str(), stats.message().c_str());
}

// Multi-stage PSSMLT (msmlt.h) and the rescaled PSSMLT over the path tracer against BDPT; the
// multi-stage negative control splats f / Y(f) instead of f / pi.
void expect_compare_variant(bool msmlt, PssFault fault, int64_t spp_pass, bool expect_reject, bool over_mmlt = false) {
  RenderSettings st;
  st.passes = kPasses;
  st.spp = kPasses * spp_pass;
  st.max_depth = kDepth;
  st.seed = msmlt ? 505 : 606;
  PssSettings p;
  p.bootstrap = spp_pass * kRes * kRes / 2;
  p.chains = 256;
  apply(fault, &p);
  Film film(kRes, kRes);
  PssStats stats;
  if (msmlt) {
    MultiStageStats ms;
    if (over_mmlt) {
      p.bootstrap = 2 * spp_pass * kRes * kRes;  // as for MMLT (render_mcmc)
      render_msmlt_mmlt(*cornell().world, st, p, MultiStageSettings{}, film, &ms);
    } else {
      render_msmlt(*cornell().world, st, p, MultiStageSettings{}, film, &ms);
    }
    stats = ms.final_stage;
  } else {
    p.rescale.enabled = true;
    render_pssmlt_pt(*cornell().world, st, p, film, &stats);
  }
  int64_t excluded = 0;
  const ChannelCompare cmp = compare_mcmc(film, bdpt_reference(), spp_pass * kRes * kRes, &excluded);
  EXPECT_EQ(film.nonfinite().count(), 0);
  EXPECT_EQ(stats.nonfinite, 0);
  EXPECT_EQ(cmp.rejects(), expect_reject) << (msmlt ? "msmlt: " : "pssmlt-pt-rescaled: ") << cmp.message();
  std::printf("%s fault %d, %lld pixels excluded: %s\n  %s\n", msmlt ? "msmlt" : "pssmlt-pt-rescaled",
              static_cast<int>(fault), static_cast<long long>(excluded), cmp.message().c_str(), stats.message().c_str());
}

TEST(PssRender, MsmltUnbiasedAgainstBdpt) { expect_compare_variant(true, PssFault::kNone, 64, false); }
TEST(PssRender, MsmltNegativeControlSplatThroughputIsCaught) {
  expect_compare_variant(true, PssFault::kSplatThroughput, 16, true);
}
TEST(PssRender, MsmltOverMmltUnbiasedAgainstBdpt) { expect_compare_variant(true, PssFault::kNone, 64, false, true); }
TEST(PssRender, PssmltPtRescaledUnbiasedAgainstBdpt) { expect_compare_variant(false, PssFault::kNone, 64, false); }

TEST(PssRender, PssmltUnbiasedAgainstBdpt) { expect_compare(false, PssFault::kNone, 64, false); }
TEST(PssRender, MmltUnbiasedAgainstBdpt) { expect_compare(true, PssFault::kNone, 64, false); }
TEST(PssRender, NegativeControlNoRejectedSplatIsCaught) { expect_compare(false, PssFault::kNoRejectedSplat, 32, true); }
TEST(PssRender, NegativeControlNoTechniqueCountIsCaught) { expect_compare(true, PssFault::kNoTechniqueCount, 16, true); }

}  // namespace
}  // namespace tb::pss

namespace tb::pss {
namespace {

// Splats carry their path (pss_sample.h SplatPath) to the chain's target: MMLT's one technique
// (s, t) with s + t = k + 1 vertices, read from the subpaths the sample function built.
TEST(PssRender, SplatsCarryTheirPathToTheTarget) {
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  const LightSampler sampler(*world);
  const PathContext ctx{world.get(), &sampler};
  const SampleFunction f = mmlt_sample_function(ctx, 8, 8, 3);
  std::atomic<int64_t> seen{0}, wrong{0};
  PssSettings p;
  p.chains = 8;
  p.target = [&](const std::vector<Splat>& splats) {
    for (const Splat& s : splats) {
      ++seen;
      const SplatPath& q = s.path;
      if (q.empty() || q.s < 0 || q.t < 1 || static_cast<int>(q.light->size()) < q.s ||
          static_cast<int>(q.camera->size()) < q.t || q.s + q.t < 2 || q.s + q.t > 3 + 2)
        ++wrong;
    }
    return target_value(splats);
  };
  RenderSettings st;
  st.spp = 8;
  st.passes = 1;
  Film film(8, 8);
  run_pss(f, st, p, film);
  EXPECT_GT(seen.load(), 1000);
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
}  // namespace tb::pss

namespace tb::pss {
namespace {

// effective_visits on synthetic sample functions (one splat per state, raster uniform over the
// image). Plain target: n_j = N Y_j / b, so the n_j of a single-pixel-per-state target sum to N
// exactly (the pilot's own estimates cancel) and agree with expected_visits of the exact image.
TEST(PssEffectiveVisits, PlainTargetIsExpectedVisits) {
  constexpr int kW = 4, kH = 2;
  SampleFunction f;
  f.sample = [](int, StreamUniforms& u, std::vector<Splat>* out) {
    u.use_stream(kCameraStream);
    const Vec2 r{u.next() * kW, u.next() * kH};
    const double y = 1.0 + std::floor(r.x) + 2.0 * std::floor(r.y);  // constant per pixel
    out->push_back({r, Rgb(y)});
  };
  const int64_t N = 8192;
  const std::vector<double> n = effective_visits(f, {}, kW, kH, N, 1 << 16, 3);
  std::vector<Rgb> image(kW * kH);
  for (int j = 0; j < kW * kH; ++j) image[static_cast<size_t>(j)] = Rgb(1.0 + (j % kW) + 2.0 * (j / kW));
  const std::vector<double> ev = expected_visits(image, N);
  double sum = 0.0;
  for (size_t j = 0; j < n.size(); ++j) {
    sum += n[j];
    EXPECT_NEAR(n[j], ev[j], 0.05 * ev[j]) << j;  // 2^13 pilot states per pixel: ~1-2 % noise
  }
  EXPECT_NEAR(sum, double(N), 1e-9 * double(N));
}

// A capped target (pi = min{Y, 1}, as the stratified target caps at r~ = 1) on one pixel whose
// value is 100 with probability q = 0.01 and 1 otherwise: b = 1, E[Y] = 1.99, E[Y^2 / pi] = 100.99,
// so n = N 1.99^2 / 100.99 = 0.0392 N, against N for the plain target. With two levels (the same
// function on each), N_l = N / 2 (level_shares of equal b_l), and the variances of the levels add:
// n = N (2 * 1.99)^2 / (2 * 100.99 * 2) = 0.0392 N as well.
TEST(PssEffectiveVisits, CappedTargetCountsTheRareBrightStates) {
  for (int levels : {1, 2}) {
    SampleFunction f;
    f.levels = levels;
    f.sample = [](int, StreamUniforms& u, std::vector<Splat>* out) {
      u.use_stream(kCameraStream);
      const double a = u.next(), b = u.next();
      out->push_back({Vec2{a, b}, Rgb(u.next() < 0.01 ? 100.0 : 1.0)});
    };
    const TargetFunction capped = [](const std::vector<Splat>& sp) { return std::min(1.0, target_value(sp)); };
    const int64_t N = 10000;
    const double plain = effective_visits(f, {}, 1, 1, N, 1 << 16, 5)[0];
    const double n = effective_visits(f, capped, 1, 1, N, 1 << 16, 5)[0];
    // One level: exactly N. Two: N when the shares are b_l / b; level_shares mixes in 1 / L, which
    // moves n only to second order in the pilots' difference of b_l.
    EXPECT_NEAR(plain, double(N), (levels == 1 ? 1e-9 : 1e-3) * double(N)) << levels;
    const double expect = double(N) * 1.99 * 1.99 / 100.99;
    EXPECT_NEAR(n, expect, 0.1 * expect) << levels;  // 655 bright pilot states per level: ~4 %
    EXPECT_LT(n, 0.05 * double(N)) << levels;
  }
}

// The path tracer split into paths (pt_paths_sample_function) sums to its single radiance splat
// on the same state, every ratio is >= 1, direct illumination (and the emitter seen directly)
// has ratio 1, and paths with a diffuse bounce before their last vertex have ratio > 1.
TEST(PssStratified, PathTracerSplitSumsToTheRadianceSample) {
  const auto world = load_scene_at_resolution("cornell-box.json", 16, 16);
  const LightSampler sampler(*world);
  const PathContext ctx{world.get(), &sampler};
  RenderSettings rs;
  rs.max_depth = 4;
  const SampleFunction split = pt_paths_sample_function(ctx, rs, 16, 16);
  const SampleFunction whole = radiance_sample_function(
      16, 16, [&](const Vec2& r, Uniforms& u) { return pt_sample(ctx, rs, r, u); });
  int nonzero = 0, above_one = 0, equal_one = 0;
  std::vector<Splat> a, b;
  for (uint64_t i = 0; i < 2000; ++i) {
    PssState s(Rng::for_sample(11, 13, i), kSigma), t(Rng::for_sample(11, 13, i), kSigma);
    s.restart();
    t.restart();
    a.clear();
    b.clear();
    split.sample(0, s, &a);
    whole.sample(0, t, &b);
    Rgb sum(0.0);
    for (const Splat& c : a) {
      sum += c.value;
      EXPECT_GE(c.ratio, 1.0);
      above_one += c.ratio > 1.0;
      equal_one += c.ratio == 1.0;
      if (!b.empty()) {
        EXPECT_EQ(c.raster, b[0].raster);
      }
    }
    const double ref = b.empty() ? 0.0 : luminance(b[0].value);
    EXPECT_NEAR(luminance(sum), ref, 1e-9 * std::max(1.0, ref)) << i;
    nonzero += ref > 0.0;
  }
  EXPECT_GT(nonzero, 500);
  EXPECT_GT(above_one, 100);
  EXPECT_GT(equal_one, 100);
}

}  // namespace
}  // namespace tb::pss
