// The sampler chi-square tester on warps whose answers are known: a correct warp passes, a
// warp with a wrong pdf, a sampler leaving its domain, and a sampler failing where its pdf
// says it should not, are rejected. Fixed seeds: deterministic.
#include "validate/chi2/sampler_chi2.h"

#include <gtest/gtest.h>

#include "lib/core/parallel.h"
#include "lib/core/warp_sphere.h"

namespace tb {
namespace {

constexpr double kAlpha = 0.01;

SamplerChi2Options opts(int64_t n, uint64_t key) {
  SamplerChi2Options o;
  o.samples = n;
  o.seed = 12345;
  o.key = key;
  return o;
}

TEST(Chi2Sampler, CorrectWarpPasses) {
  const SamplerChi2Result r =
      chi2_test(Chi2Domain::hemisphere(), sample_cosine_hemisphere, pdf_cosine_hemisphere, opts(200000, 1));
  EXPECT_TRUE(r.passed(kAlpha)) << r.message();
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-9);
  EXPECT_EQ(r.outside, 0);
  EXPECT_EQ(r.failed, 0);
  EXPECT_EQ(r.worst.size(), 8u);
}

TEST(Chi2Sampler, WrongPdfIsRejected) {
  // Claims a uniform hemisphere while sampling the cosine distribution.
  const SamplerChi2Result r =
      chi2_test(Chi2Domain::hemisphere(), sample_cosine_hemisphere, pdf_uniform_hemisphere, opts(200000, 2));
  EXPECT_FALSE(r.passed(kAlpha)) << r.message();
  EXPECT_LT(r.p_value(), 1e-12);
  // The worst cells sit near the horizon (too few samples) or the pole (too many).
  ASSERT_FALSE(r.worst.empty());
  EXPECT_TRUE(r.worst[0].y0 > 0.8 || r.worst[0].y1 < 0.2) << r.worst[0].y0;
}

TEST(Chi2Sampler, SamplesOutsideTheDomainFail) {
  const SamplerChi2Result r = chi2_test(Chi2Domain::hemisphere(), sample_uniform_sphere,
                                        [](const Vec3& w) { return w.z >= 0 ? kInv2Pi : 0.0; }, opts(20000, 3));
  EXPECT_GT(r.outside, 0);
  EXPECT_FALSE(r.passed(0.5));
  EXPECT_NE(r.message().find("outside"), std::string::npos);
}

TEST(Chi2Sampler, SamplesWherePdfIsZeroFail) {
  // A cone sampler tested against a narrower cone's pdf: samples land in zero-mass cells.
  const SamplerChi2Result r = chi2_test(
      Chi2Domain::sphere(), [](Vec2 u) { return sample_uniform_cone(u, 0.5); },
      [](const Vec3& w) { return pdf_uniform_cone(w, 0.8); }, opts(100000, 4));
  EXPECT_EQ(r.p_value(), 0.0);
  EXPECT_GT(r.gof.zero_expected_cells, 0u);
  EXPECT_NE(r.gof.first_zero_expected_cell.find("cos theta"), std::string::npos);
}

TEST(Chi2Sampler, FailuresAreAccountedAgainstPdfDeficit) {
  // A sampler that fails when u0 < 0.2 and otherwise draws u uniformly on [0.2, 1): its pdf on
  // [0, 1] is 1 on [0.2, 1), integrating to 0.8; the failure cell expects 20%.
  const auto sample = [](Vec2 u) -> std::optional<double> {
    if (u.x < 0.2) return std::nullopt;
    return u.x;
  };
  const auto pdf = [](double x) { return x >= 0.2 ? 1.0 : 0.0; };
  const SamplerChi2Result ok = chi2_test(Chi2Domain::interval(0, 1, 51), sample, pdf, opts(100000, 5));
  EXPECT_TRUE(ok.passed(kAlpha)) << ok.message();
  EXPECT_NEAR(ok.pdf_integral, 0.8, 1e-4);  // a discontinuity inside a bin: quadrature error
  EXPECT_GT(ok.failed, 19000);
  // The same sampler against a pdf claiming full mass: failures land in a zero-mass cell.
  const SamplerChi2Result bad = chi2_test(
      Chi2Domain::interval(0, 1, 51), sample, [](double x) { return x >= 0.2 ? 1.25 : 0.0; }, opts(100000, 5));
  EXPECT_EQ(bad.p_value(), 0.0) << bad.message();
}

TEST(Chi2Sampler, DeterministicAcrossThreadCounts) {
  const auto run = [](size_t threads) {
    ThreadLimit limit(threads);
    return chi2_test(Chi2Domain::sphere(), sample_uniform_sphere, [](const Vec3&) { return kInv4Pi; },
                     opts(50000, 6));
  };
  const SamplerChi2Result a = run(1), b = run(2);
  EXPECT_EQ(a.observed, b.observed);
  EXPECT_EQ(a.gof.statistic, b.gof.statistic);
}

TEST(Chi2Sampler, AcceptsUniformsSamplers) {
  // A sampler taking Uniforms& (three numbers): a mixture choosing a lobe with the first.
  const auto sample = [](Uniforms& u) -> std::optional<Vec3> {
    const double pick = u.next();
    const Vec2 v = u.next2();
    return pick < 0.5 ? sample_uniform_hemisphere(v) : sample_cosine_hemisphere(v);
  };
  const auto pdf = [](const Vec3& w) { return 0.5 * pdf_uniform_hemisphere(w) + 0.5 * pdf_cosine_hemisphere(w); };
  const SamplerChi2Result r = chi2_test(Chi2Domain::hemisphere(), sample, pdf, opts(100000, 7));
  EXPECT_TRUE(r.passed(kAlpha)) << r.message();
}

TEST(Chi2Sampler, HeatmapsAndDetails) {
  const SamplerChi2Result r =
      chi2_test(Chi2Domain::hemisphere(11, 5), sample_cosine_hemisphere, pdf_cosine_hemisphere, opts(10000, 8));
  const PlotSpec p = r.observed_heatmap("obs");
  ASSERT_EQ(p.heatmap.size(), 5u);
  ASSERT_EQ(p.heatmap[0].size(), 11u);
  double total = 0;
  for (const auto& row : p.heatmap)
    for (double v : row) total += v;
  EXPECT_EQ(total, 10000.0);
  const nlohmann::json d = r.details();
  EXPECT_TRUE(d.contains("worst_cells"));
  EXPECT_TRUE(d.contains("p_value"));
}


// A density on slivers (7 strips 0.003 wide across 5 x 5 cells, weights 1..7): the Monte Carlo
// expected counts (jittered replicates, their variance in the denominators) pass the correct
// statement and reject one with the strip weights misstated by 15 %.
struct Strips {
  static constexpr int kN = 7;
  static constexpr double kWidth = 0.003;
  static double left(int i) { return 0.05 + 0.137 * i; }
  static double weight(int i) { return (i + 1) / 28.0; }  // sums to 1
  static std::optional<Vec2> sample(Uniforms& u) {
    const double a = u.next();
    int i = 0;
    for (double c = weight(0); a >= c && i + 1 < kN; c += weight(++i)) {
    }
    return Vec2(left(i) + kWidth * u.next(), u.next());
  }
  static double pdf(const Vec2& q, double tilt) {
    for (int i = 0; i < kN; ++i)
      if (q.x >= left(i) && q.x < left(i) + kWidth) return weight(i) * (1.0 + tilt * (i - 3)) / kWidth;
    return 0.0;
  }
};

TEST(Chi2Sampler, MonteCarloExpectedCountsOnSlivers) {
  SamplerChi2Options o = opts(100000, 11);
  o.monte_carlo_expected = true;
  const Chi2Domain d = Chi2Domain::rectangle({0.0, 0.0}, {1.0, 1.0}, 5, 5);
  const SamplerChi2Result r =
      chi2_test(d, [](Uniforms& u) { return Strips::sample(u); }, [](const Vec2& q) { return Strips::pdf(q, 0.0); }, o);
  EXPECT_TRUE(r.passed(kAlpha)) << r.message();
  EXPECT_EQ(r.expected_variance.size(), 25u);
  EXPECT_GT(r.pdf_evaluations, 0);
  EXPECT_NEAR(r.pdf_integral, 1.0, 0.02);
  o.key = 12;
  const SamplerChi2Result b =
      chi2_test(d, [](Uniforms& u) { return Strips::sample(u); }, [](const Vec2& q) { return Strips::pdf(q, 0.05); }, o);
  EXPECT_FALSE(b.passed(kAlpha)) << b.message();
}

}  // namespace
}  // namespace tb
