// A researcher's own technique checked with an installed testbench (see README.md here).
//
// The technique: a cosine-power lobe around +z, pdf(w) = (n+1)/(2 pi) cos^n(theta) in solid
// angle on the upper hemisphere, sampled by inverting the CDF of cos(theta): P(cos <= c) = c^(n+1),
// so cos(theta) = u0^(1/(n+1)), phi = 2 pi u1.
//
// Three assertions, each with a negative control that must be rejected:
//   1. chi-square goodness of fit of the sampler against its pdf (validate/chi2/sampler_chi2.h),
//      alpha = 0.01; control: the same sampler with its pdf stated 5% too high.
//   2. unbiasedness of the multi-sample MIS estimator (balance heuristic, one sample from the lobe
//      and one from the uniform sphere) of the integral over the sphere of
//      f(w) = max(cos theta, 0)^3 + 1/4, known value 2 pi/4 + pi = 3 pi / 2: a one-sample t test
//      against 3 pi / 2 and a Welch test against plain uniform-sphere MC, Šidák over the two at a
//      family-wise alpha = 0.01; control: the MIS estimator with the 5%-too-high lobe pdf.
//   3. the Ceres fit of RMSE = C N^(-alpha) of the MIS estimator over N = 2^4..2^14 (64
//      replicates): 1/2 inside the 99% interval, half-width below 0.05; control: an estimator that
//      spends only sqrt(N) of its N samples (alpha = 1/4) must have 1/2 outside its interval.
// Every random number comes from fixed seeds, so a run prints the same numbers every time.
// Exit status: 0 when every assertion and every control behaves, 1 otherwise.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "estimators/mc.h"
#include "estimators/mis.h"
#include "lib/core/frame.h"
#include "lib/core/hash.h"
#include "lib/core/math.h"
#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "lib/core/warp_sphere.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/stats/convergence_fit.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace {

using tb::Vec2;
using tb::Vec3;

constexpr double kLobeExponent = 8.0;   // n of the lobe
constexpr double kIntegrandPower = 3.0; // k of f(w) = max(cos theta, 0)^k + 1/4
constexpr double kAlpha = 0.01;

// The technique under test. pdf_scale = 1 is the correct density; 1.05 states it 5% too high
// (the broken variant the tests must reject).
struct CosinePowerLobe {
  double n = kLobeExponent;
  double pdf_scale = 1.0;

  Vec3 warp(const Vec2& u) const {
    const double cos_t = std::pow(u.x, 1.0 / (n + 1.0));
    return tb::spherical_direction(tb::safe_sqrt(1.0 - cos_t * cos_t), cos_t, 2.0 * tb::kPi * u.y);
  }
  double pdf(const Vec3& w) const {
    return w.z > 0.0 ? pdf_scale * (n + 1.0) * tb::kInv2Pi * std::pow(w.z, n) : 0.0;
  }
};

// One technique type for the estimators (estimate_mis takes a span of one type): either the lobe
// or the uniform sphere. Satisfies tb::Technique.
struct SphereTechnique {
  using Sample = Vec3;
  bool is_lobe = true;
  CosinePowerLobe lobe;

  std::optional<Vec3> sample(tb::Uniforms& u) const {
    const Vec2 v = u.next2();
    return is_lobe ? lobe.warp(v) : tb::sample_uniform_sphere(v);
  }
  double pdf(const Vec3& w) const { return is_lobe ? lobe.pdf(w) : tb::pdf_uniform_sphere(); }
};
static_assert(tb::Technique<SphereTechnique>);

double integrand(const Vec3& w) { return std::pow(std::max(w.z, 0.0), kIntegrandPower) + 0.25; }
const double kTruth = 2.0 * tb::kPi / (kIntegrandPower + 1.0) + tb::kPi;  // = 3 pi / 2

int g_failures = 0;
void expect(bool ok, const std::string& what) {
  std::printf("  [%s] %s\n", ok ? "ok" : "FAILED", what.c_str());
  if (!ok) ++g_failures;
}

// --- 1. chi-square test of the sampler --------------------------------------------------------
void chi2_section() {
  std::printf("1. chi-square test of the cosine-power lobe sampler (n = %g), alpha = %g\n", kLobeExponent, kAlpha);
  const tb::SamplerChi2Options options{.samples = 1000000, .seed = 1, .key = tb::hash_string("own-sampler.chi2")};
  const auto run = [&](const CosinePowerLobe& lobe) {
    return tb::chi2_test(
        tb::Chi2Domain::hemisphere(), [&](const Vec2& u) { return lobe.warp(u); },
        [&](const Vec3& w) { return lobe.pdf(w); }, options);
  };
  const tb::SamplerChi2Result good = run(CosinePowerLobe{});
  std::printf("     correct pdf:     %s\n", good.message().c_str());
  expect(good.passed(kAlpha), "the lobe sampler matches its pdf (p >= alpha)");
  const tb::SamplerChi2Result broken = run(CosinePowerLobe{.pdf_scale = 1.05});
  std::printf("     pdf 5%% too high: %s\n", broken.message().c_str());
  expect(!broken.passed(kAlpha), "negative control: the pdf stated 5% too high is rejected (p < alpha)");
}

// --- 2. unbiasedness of the MIS estimator ------------------------------------------------------
// Welford accumulators of R realisations of the two-sample MIS estimator (one lobe sample, one
// uniform sample) and of plain MC with two uniform-sphere samples.
tb::stats::Welford mis_realisations(const CosinePowerLobe& lobe, int64_t replicates, uint64_t key) {
  const std::vector<SphereTechnique> techniques{{.is_lobe = true, .lobe = lobe}, {.is_lobe = false, .lobe = lobe}};
  const std::vector<int> counts{1, 1};
  tb::stats::Welford w;
  for (int64_t r = 0; r < replicates; ++r) {
    tb::Rng rng = tb::Rng::for_sample(7, key, static_cast<uint64_t>(r));
    tb::RngUniforms u(rng);
    w.add(tb::estimate_mis(integrand, std::span<const SphereTechnique>(techniques), std::span<const int>(counts), u).value);
  }
  return w;
}

tb::stats::Welford uniform_mc_realisations(int64_t replicates, uint64_t key) {
  const SphereTechnique uniform{.is_lobe = false, .lobe = {}};
  tb::stats::Welford w;
  for (int64_t r = 0; r < replicates; ++r) {
    tb::Rng rng = tb::Rng::for_sample(7, key, static_cast<uint64_t>(r));
    tb::RngUniforms u(rng);
    w.add(tb::estimate_mc(integrand, uniform, 2, u).value);
  }
  return w;
}

void unbiasedness_section() {
  const int64_t replicates = 200000;
  const double per_test = tb::stats::sidak_alpha(kAlpha, 2);
  std::printf("2. unbiasedness of balance-heuristic MIS (lobe + uniform sphere) of I = 3 pi/2 = %.6f\n", kTruth);
  std::printf("   %lld realisations each; family-wise alpha = %g, Šidák per test = %.6f\n",
              static_cast<long long>(replicates), kAlpha, per_test);
  const auto mc = uniform_mc_realisations(replicates, tb::hash_string("own-sampler.mc"));
  const auto report = [&](const char* name, const tb::stats::Welford& mis) {
    const auto t = tb::stats::one_sample_t_test(mis, kTruth);
    const auto welch = tb::stats::welch_t_test(mis, mc);
    std::printf("     %s: mean %.6f +- %.6f (SE); t = %.3f, p = %.4g; Welch vs uniform MC (mean %.6f +- %.6f): t = %.3f, p = %.4g\n",
                name, mis.mean(), mis.std_error(), t.statistic, t.p_value, mc.mean(), mc.std_error(), welch.statistic,
                welch.p_value);
    return std::pair{t, welch};
  };
  const auto [t_good, welch_good] = report("MIS, correct pdf", mis_realisations(CosinePowerLobe{}, replicates, tb::hash_string("own-sampler.mis")));
  expect(!t_good.rejects(per_test) && !welch_good.rejects(per_test),
         "MIS is consistent with the known integral and with uniform MC");
  const auto [t_bad, welch_bad] = report("MIS, pdf 5% high",
                                         mis_realisations(CosinePowerLobe{.pdf_scale = 1.05}, replicates,
                                                          tb::hash_string("own-sampler.mis")));
  expect(t_bad.rejects(per_test) && welch_bad.rejects(per_test),
         "negative control: MIS with the 5%-too-high lobe pdf is rejected by both tests");
}

// --- 3. convergence rate -----------------------------------------------------------------------
// MIS with N samples split evenly; `spent(n)` is how many of them are actually used.
tb::stats::Estimator mis_estimator(int64_t (*spent)(int64_t)) {
  return [spent](int64_t n, uint64_t seed) {
    const std::vector<SphereTechnique> techniques{{.is_lobe = true, .lobe = {}}, {.is_lobe = false, .lobe = {}}};
    const int half = static_cast<int>(std::max<int64_t>(1, spent(n) / 2));
    const std::vector<int> counts{half, half};
    tb::Rng rng = tb::Rng::for_sample(seed, 0, 0);
    tb::RngUniforms u(rng);
    return tb::estimate_mis(integrand, std::span<const SphereTechnique>(techniques), std::span<const int>(counts), u).value;
  };
}

void convergence_section() {
  std::printf("3. Ceres fit of RMSE = C N^-alpha for the MIS estimator, N = 2^4..2^14, 64 replicates, 99%% interval\n");
  const tb::stats::ConvergenceStudyOptions options{
      .log2_min = 4, .log2_max = 14, .replicates = 64, .seed = 3, .key = tb::hash_string("own-sampler.rate"), .fit = {}};
  const auto good = tb::stats::run_convergence_study(mis_estimator([](int64_t n) { return n; }), kTruth, options);
  std::printf("     all N samples:   alpha = %.4f, 99%% interval [%.4f, %.4f], reduced chi2 %.2f\n", good.fit.alpha,
              good.fit.alpha_lo, good.fit.alpha_hi, good.fit.reduced_chi2);
  expect(good.fit.converged && good.fit.alpha_lo <= 0.5 && 0.5 <= good.fit.alpha_hi && good.fit.half_width() < 0.05,
         "the fitted rate is consistent with 1/2 (interval contains 0.5, half-width < 0.05)");
  const auto slow = tb::stats::run_convergence_study(
      mis_estimator([](int64_t n) { return static_cast<int64_t>(std::llround(std::sqrt(static_cast<double>(n)))); }),
      kTruth, options);
  std::printf("     sqrt(N) samples: alpha = %.4f, 99%% interval [%.4f, %.4f]\n", slow.fit.alpha, slow.fit.alpha_lo,
              slow.fit.alpha_hi);
  expect(slow.fit.converged && !(slow.fit.alpha_lo <= 0.5 && 0.5 <= slow.fit.alpha_hi),
         "negative control: an estimator using sqrt(N) samples (alpha = 1/4) is rejected");
}

}  // namespace

int main() {
  chi2_section();
  unbiasedness_section();
  convergence_section();
  if (g_failures > 0) {
    std::printf("own-sampler: %d assertion(s) FAILED\n", g_failures);
    return 1;
  }
  std::printf("own-sampler: all assertions and negative controls behaved\n");
  return 0;
}
