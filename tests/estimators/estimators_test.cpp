// Deterministic identities of the generic estimators (tolerance 1e-12 relative):
// MMIS with T = 1 equals SMIS; MMIS whose techniques are all classical (extruded, or in the split
// classical sum) equals multi-sample balance-heuristic MIS; the split and extruded forms of mixing
// classical and marginal techniques agree; MIS weights sum to one; pdf-evaluation counts are n·N·T;
// the per-sample MMIS weights give exactly the scalar Eq. 6 estimate; CMIS with the continuous
// balance heuristic equals MC from the exact marginal (and MC itself over an extruded technique).
#include <array>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "analytic/classical_techniques_1d.h"
#include "analytic/integrands.h"
#include "analytic/marginal_techniques_1d.h"
#include "analytic/uniform_centre_normal_1d.h"
#include "estimators/any_marginal_technique.h"
#include "estimators/cmis.h"
#include "estimators/extruded_technique.h"
#include "estimators/mc.h"
#include "estimators/mis.h"
#include "estimators/mis_heuristics.h"
#include "estimators/mmis.h"
#include "estimators/mmis_budget.h"
#include "estimators/smis.h"
#include "estimators/technique_subset.h"
#include "lib/core/rng.h"

namespace tb {
namespace {

static_assert(Technique<Classical1D>);
static_assert(Technique<ExactMarginal1D>);
static_assert(MarginalTechnique<ConditionalNormal1D>);
static_assert(MarginalTechnique<ExtrudedTechnique<Classical1D>>);
static_assert(MarginalTechnique<AnyMarginalTechnique<ExtrudedTechnique<Classical1D>, ConditionalNormal1D>>);
static_assert(ContinuousTechnique<ConditionalNormal1D>);
static_assert(ContinuousTechnique<UniformCentreNormal1D>);
static_assert(ContinuousTechnique<ExtrudedTechnique<Classical1D>>);
static_assert(ContinuousMisWeight<ContinuousBalanceHeuristic, UniformCentreNormal1D>);

constexpr double kTol = 1e-12;

std::vector<Classical1D> classical_set() {
  return {Classical1D(UniformTechnique1D{0.0, 1.0}), Classical1D(TruncatedNormalTechnique1D(0.3, 0.1)),
          Classical1D(PiecewiseConstantTechnique1D({0.0, 0.5, 0.8, 1.0}, {1.0, 3.0, 0.5}))};
}

ConditionalNormal1D centre_technique(double defensive = 0.0) {
  ConditionalNormal1D::Params p;
  p.name = "centre";
  p.t_dist = Classical1D(UniformTechnique1D{0.5, 0.9});
  p.mode = ConditionalNormal1D::Mode::kCentre;
  p.fixed = 0.05;
  p.defensive = defensive;
  return ConditionalNormal1D(p);
}

ConditionalNormal1D width_technique() {
  ConditionalNormal1D::Params p;
  p.name = "width";
  p.t_dist = Classical1D(UniformTechnique1D{0.02, 0.3});
  p.mode = ConditionalNormal1D::Mode::kWidth;
  p.fixed = 0.3;
  p.defensive = 0.1;
  return ConditionalNormal1D(p);
}

void expect_close(double a, double b) { EXPECT_NEAR(a, b, kTol * std::max(1.0, std::abs(b))); }

TEST(Mmis, EqualsSmisForOneTechniqueSpace) {
  const auto& f = integrand_1d("gaussian_mixture");
  const std::array<ConditionalNormal1D, 1> m{centre_technique(0.2)};
  for (int n : {1, 2, 5, 16}) {
    for (uint64_t rep = 0; rep < 20; ++rep) {
      Rng r1 = Rng::for_sample(7, n, rep), r2 = r1;
      RngUniforms u1(r1), u2(r2);
      const std::array<int, 1> counts{n};
      const Estimate a = estimate_mmis(f, std::span<const ConditionalNormal1D>(m), std::span<const int>(counts), u1);
      const Estimate b = estimate_smis(f, m[0], n, u2);
      expect_close(a.value, b.value);
      EXPECT_EQ(a.pdf_evals, b.pdf_evals);
      EXPECT_EQ(a.pdf_evals, int64_t{n} * n);
    }
  }
}

TEST(Mmis, AllClassicalEqualsBalanceMis) {
  const auto& f = integrand_1d("product");
  const auto cs = classical_set();
  std::vector<ExtrudedTechnique<Classical1D>> extruded;
  for (const auto& c : cs) extruded.push_back({c});
  const std::vector<int> counts{3, 1, 4};
  for (uint64_t rep = 0; rep < 50; ++rep) {
    Rng r1 = Rng::for_sample(11, 0, rep), r2 = r1, r3 = r1;
    RngUniforms u1(r1), u2(r2), u3(r3);
    const Estimate mis = estimate_mis(f, std::span<const Classical1D>(cs), std::span<const int>(counts), u1);
    const Estimate ext = estimate_mmis(f, std::span<const ExtrudedTechnique<Classical1D>>(extruded),
                                       std::span<const int>(counts), u2);
    const Estimate split = estimate_mmis(f, std::span<const Classical1D>(cs), std::span<const int>(counts),
                                         std::span<const ConditionalNormal1D>{}, std::span<const int>{}, u3);
    expect_close(ext.value, mis.value);
    expect_close(split.value, mis.value);
    EXPECT_EQ(split.pdf_evals, mis.pdf_evals);  // split form: one evaluation per classical technique
    EXPECT_EQ(ext.pdf_evals, 8 * 8);            // extruded form: one per sampled (identical) technique
  }
}

TEST(Mmis, SplitAndExtrudedMixingAgree) {
  using Any = AnyMarginalTechnique<ExtrudedTechnique<Classical1D>, ConditionalNormal1D>;
  const auto& f = integrand_1d("fig1_two_features");
  const std::vector<Classical1D> cls{Classical1D(TruncatedNormalTechnique1D(0.22, 0.1))};
  const std::vector<ConditionalNormal1D> mar{centre_technique(), width_technique()};
  const std::vector<Any> all{Any(ExtrudedTechnique<Classical1D>{cls[0]}), Any(mar[0]), Any(mar[1])};
  for (int n : {1, 3, 8}) {
    const std::vector<int> nc{n}, nm{n, n}, na{n, n, n};
    for (uint64_t rep = 0; rep < 20; ++rep) {
      Rng r1 = Rng::for_sample(13, n, rep), r2 = r1;
      RngUniforms u1(r1), u2(r2);
      const Estimate split = estimate_mmis(f, std::span<const Classical1D>(cls), std::span<const int>(nc),
                                           std::span<const ConditionalNormal1D>(mar), std::span<const int>(nm), u1);
      const Estimate ext = estimate_mmis(f, std::span<const Any>(all), std::span<const int>(na), u2);
      expect_close(split.value, ext.value);
      EXPECT_EQ(ext.pdf_evals, int64_t{3 * n} * (3 * n));
      EXPECT_EQ(split.pdf_evals, int64_t{3 * n} * (2 * n + 1));
    }
  }
}

TEST(Mmis, CostIsnNT) {
  // MMIS_n with budget N: N / (nT) realisations of n pairs from each of T techniques cost n·N·T.
  const auto& f = integrand_1d("smooth");
  const std::vector<ConditionalNormal1D> mar{centre_technique(0.1), width_technique(), centre_technique(0.5),
                                             width_technique()};
  const int big_n = 64, t = 4;
  for (int n : {1, 2, 4, 8, 16}) {
    Rng r(3);
    RngUniforms u(r);
    int64_t evals = 0;
    const std::vector<int> counts(t, n);
    for (int k = 0; k < big_n / (n * t); ++k)
      evals += estimate_mmis(f, std::span<const ConditionalNormal1D>(mar), std::span<const int>(counts), u).pdf_evals;
    EXPECT_EQ(evals, int64_t{n} * big_n * t);
  }
}

// A marginal technique whose t and x draws fail (probability 0.2 each), to exercise the pairing of
// samples with their auxiliaries when some are missing. Its densities are sub-probability ones.
struct FlakyTechnique {
  using Aux = ConditionalNormal1D::Aux;
  using Sample = double;
  const ConditionalNormal1D* m = nullptr;
  std::optional<Aux> sample_aux(Uniforms& u) const {
    if (u.next() < 0.2) return std::nullopt;
    return m->sample_aux(u);
  }
  std::optional<double> sample(const Aux& a, Uniforms& u) const {
    if (u.next() < 0.2) return std::nullopt;
    return m->sample(a, u);
  }
  double pdf(double x, const Aux& a) const { return 0.8 * m->pdf(x, a); }
};

// Eq. 6 written out directly (West et al. 2022), the reference for the per-sample weights.
template <class C, class M>
double eq6_reference(const Integrand1D& f, const std::vector<C>& cls, const std::vector<int>& nc,
                     const std::vector<M>& mar, const MmisDraw<double, typename M::Aux>& d) {
  double sum = 0.0;
  for (const auto& x : d.xs) {
    if (!x) continue;
    double den = 0.0;
    for (size_t c = 0; c < cls.size(); ++c)
      if (nc[c] > 0) den += nc[c] * cls[c].pdf(*x);
    for (const auto& a : d.aux) den += mar[a.technique].pdf(*x, a.t);
    sum += safe_ratio(f(*x), den);
  }
  return sum;
}

TEST(Mmis, PerSampleWeightsGiveTheScalarEstimate) {
  const auto& f = integrand_1d("fig1_two_features");
  const auto cn = centre_technique(), wd = width_technique();
  const std::vector<Classical1D> cls{Classical1D(TruncatedNormalTechnique1D(0.22, 0.1)), Classical1D(UniformTechnique1D{})};
  const std::vector<FlakyTechnique> mar{{&cn}, {&wd}};
  int64_t failed = 0;
  for (int n : {1, 3, 8}) {
    const std::vector<int> nc{n, n == 3 ? 0 : 1}, nm{n, 2 * n};
    for (uint64_t rep = 0; rep < 30; ++rep) {
      Rng r = Rng::for_sample(17, n, rep);
      RngUniforms u(r);
      const auto cs = std::span<const Classical1D>(cls);
      const auto ms = std::span<const FlakyTechnique>(mar);
      const auto d = draw_mmis(cs, std::span<const int>(nc), ms, std::span<const int>(nm), u);
      failed += d.failed;
      const Estimate e = evaluate_mmis(f, cs, std::span<const int>(nc), ms, d);
      const auto ws = mmis_weights(cs, std::span<const int>(nc), ms, d);
      // The scalar estimate is the sum of the per-sample contributions, bit for bit.
      double sum = 0.0, via_weight = 0.0;
      for (const auto& s : ws) {
        sum += s.w.contribution(f(s.x));
        via_weight += s.w.own_pdf > 0.0 ? s.w.weight * f(s.x) / s.w.own_pdf : 0.0;
      }
      EXPECT_EQ(sum, e.value);
      expect_close(via_weight, e.value);
      // Eq. 6 written out sums every denominator in the same order: the same round-off, bit for bit.
      EXPECT_EQ(e.value, eq6_reference(f, cls, nc, mar, d));
      // Every sample that did not fail appears once, with its own technique's density.
      size_t drawn = 0;
      for (const auto& x : d.xs) drawn += x.has_value();
      ASSERT_EQ(ws.size(), drawn);
      for (const auto& s : ws) {
        ASSERT_TRUE(d.xs[s.w.sample]);
        EXPECT_EQ(*d.xs[s.w.sample], s.x);
        if (s.w.classical) {
          ASSERT_LT(s.w.sample, d.classical_samples());
          EXPECT_EQ(mmis_own_aux(d, s.w), nullptr);
          EXPECT_EQ(s.w.own_pdf, nc[s.w.technique] * cls[s.w.technique].pdf(s.x));
        } else {
          const auto& a = d.aux[s.w.sample - d.classical_samples()];
          EXPECT_EQ(a.technique, s.w.technique);
          EXPECT_EQ(mmis_own_aux(d, s.w), &a.t);
          EXPECT_EQ(s.w.own_pdf, mar[a.technique].pdf(s.x, a.t));
        }
        EXPECT_GE(s.w.weight, 0.0);
        EXPECT_LE(s.w.weight, 1.0 + kTol);
        expect_close(s.w.weight * s.w.denominator, s.w.own_pdf);
      }
      // The one-sample form gives the same weight, technique and densities, bit for bit.
      for (const auto& sw : ws) {
        const auto one = mmis_weight(cs, std::span<const int>(nc), ms, d, sw.w.sample);
        ASSERT_TRUE(one);
        EXPECT_EQ(one->technique, sw.w.technique);
        EXPECT_EQ(one->classical, sw.w.classical);
        EXPECT_EQ(one->own_pdf, sw.w.own_pdf);
        EXPECT_EQ(one->denominator, sw.w.denominator);
        EXPECT_EQ(one->weight, sw.w.weight);
      }
      for (size_t s = 0; s < d.xs.size(); ++s)
        EXPECT_EQ(mmis_weight(cs, std::span<const int>(nc), ms, d, s).has_value(), d.xs[s].has_value());
      EXPECT_FALSE(mmis_weight(cs, std::span<const int>(nc), ms, d, d.xs.size()));
      EXPECT_EQ(e.pdf_evals, static_cast<int64_t>(drawn) * mmis_pdf_evals_per_sample(std::span<const int>(nc), d));
    }
  }
  EXPECT_GT(failed, 0);  // the failing draws were exercised
}

// The two uses of one per-sample weight function (for_each_mmis_weight): the analytic checks' scalar
// estimate (evaluate_mmis) and a renderer that splats an RGB contribution weight · f_rgb / own_pdf per
// sample. On fixed seeds the scalar estimate equals Eq. 6 written out directly (eq6_reference, the form
// evaluate_mmis had before it was built on the weights) bit for bit, and the splat to 1e-12.
TEST(Mmis, OneWeightFunctionServesTheScalarEstimateAndAnRgbSplat) {
  const auto& f = integrand_1d("fig1_two_features");
  const auto cn = centre_technique(0.1), wd = width_technique();
  const std::vector<Classical1D> cls{Classical1D(UniformTechnique1D{})};
  const std::vector<ConditionalNormal1D> mar{cn, wd};
  const auto cs = std::span<const Classical1D>(cls);
  const auto ms = std::span<const ConditionalNormal1D>(mar);
  for (int n : {1, 2, 4}) {
    const std::vector<int> nc{n}, nm{n, n};
    for (uint64_t rep = 0; rep < 20; ++rep) {
      Rng r = Rng::for_sample(29, n, rep);
      RngUniforms u(r);
      const auto d = draw_mmis(cs, std::span<const int>(nc), ms, std::span<const int>(nm), u);
      // Analytic use: the scalar Eq. 6 estimate.
      const Estimate e = evaluate_mmis(f, cs, std::span<const int>(nc), ms, d);
      // Renderer use: an RGB throughput f_rgb(x) / own_pdf splatted with the sample's MMIS weight.
      std::array<double, 3> rgb{0.0, 0.0, 0.0};
      double scalar = 0.0;
      for_each_mmis_weight(cs, std::span<const int>(nc), ms, d, [&](double x, const MmisWeight& w) {
        const std::array<double, 3> f_rgb{f(x), 0.5 * f(x), 2.0 * f(x)};
        for (size_t c = 0; c < 3; ++c) rgb[c] += w.own_pdf > 0.0 ? w.weight * f_rgb[c] / w.own_pdf : 0.0;
        scalar += w.contribution(f(x));
      });
      const double reference = eq6_reference(f, cls, nc, mar, d);
      EXPECT_EQ(scalar, e.value);
      EXPECT_EQ(e.value, reference);  // the same summation order as Eq. 6 written out: bit for bit
      expect_close(rgb[0], reference);
      expect_close(rgb[1], 0.5 * reference);
      expect_close(rgb[2], 2.0 * reference);
    }
  }
}

TEST(Mmis, BudgetEstimateReusesOneDrawAndEqualsRealisationsAveraged) {
  const auto& f = integrand_1d("smooth");
  const std::vector<ConditionalNormal1D> mar{centre_technique(0.1), width_technique()};
  for (int n : {1, 2, 4}) {
    Rng r1(23), r2(23);
    RngUniforms u1(r1), u2(r2);
    const Estimate b = estimate_mmis_budget(f, std::span<const ConditionalNormal1D>(mar), n, 16, u1);
    const std::vector<int> counts(2, n);
    double s = 0.0;
    const int k = 16 / (2 * n);
    for (int i = 0; i < k; ++i)
      s += estimate_mmis(f, std::span<const ConditionalNormal1D>(mar), std::span<const int>(counts), u2).value;
    EXPECT_EQ(b.value, s / k);
    EXPECT_EQ(b.pdf_evals, int64_t{n} * 16 * 2);
  }
}

TEST(Cmis, BalanceHeuristicEqualsMcFromTheExactMarginal) {
  // Draw by draw: ExactMarginal1D samples t then x, as CMIS does, and divides by p(x) (quadrature).
  const auto& f = integrand_1d("gaussian_mixture");
  const auto m = centre_technique(0.2);
  const ExactMarginal1D exact{&m};
  for (uint64_t rep = 0; rep < 5; ++rep) {
    Rng r1 = Rng::for_sample(19, 0, rep), r2 = r1;
    RngUniforms u1(r1), u2(r2);
    const Estimate c = estimate_cmis(f, m, 4, u1);
    const Estimate mc = estimate_mc(f, exact, 4, u2);
    expect_close(c.value, mc.value);
    EXPECT_EQ(c.pdf_evals, 8);  // p(x | t) and p(x) per sample
  }
}

TEST(Cmis, OverAnExtrudedTechniqueIsMc) {
  const auto& f = integrand_1d("product");
  const Classical1D c(PiecewiseConstantTechnique1D({0.0, 0.5, 0.8, 1.0}, {1.0, 3.0, 0.5}));
  const ExtrudedTechnique<Classical1D> e{c};
  for (uint64_t rep = 0; rep < 50; ++rep) {
    Rng r1 = Rng::for_sample(29, 0, rep), r2 = r1;
    RngUniforms u1(r1), u2(r2);
    expect_close(estimate_cmis(f, e, 16, u1).value, estimate_mc(f, c, 16, u2).value);
  }
}

TEST(Cmis, ClosedFormMarginalIsImportanceSamplingFromIt) {
  // With the balance heuristic every term is f(x) / p(x): exact when f is proportional to p(x).
  const UniformCentreNormal1D m(0.2, 0.7, 0.1, 0.2);
  auto f = [&](double x) { return 2.5 * m.marginal_pdf(x); };
  Rng r(31);
  RngUniforms u(r);
  for (int rep = 0; rep < 100; ++rep) EXPECT_NEAR(estimate_cmis(f, m, 8, u).value, 2.5, 1e-12);
}

TEST(MisHeuristics, WeightsSumToOne) {
  const AnyHeuristic hs[] = {BalanceHeuristic{}, PowerHeuristic{}, PowerHeuristic{3.0}, MaximumHeuristic{},
                             CutoffHeuristic{0.3}};
  Rng r(5);
  for (int rep = 0; rep < 1000; ++rep) {
    std::vector<double> q(1 + rep % 6);
    for (double& v : q) v = r.uniform() < 0.2 ? 0.0 : std::exp(20.0 * (r.uniform() - 0.5));
    if (rep % 7 == 0) q[0] = q.back();  // ties for the maximum heuristic
    bool any = false;
    for (double v : q) any |= v > 0.0;
    for (const auto& h : hs) {
      double s = 0.0;
      for (size_t i = 0; i < q.size(); ++i) {
        const double w = mis_weight(h, q, i);
        EXPECT_GE(w, 0.0);
        s += w;
      }
      if (any) {
        EXPECT_NEAR(s, 1.0, kTol);
      }
    }
  }
  EXPECT_THROW(heuristic_by_name("nope"), std::invalid_argument);
}

TEST(MisHeuristics, TwoTechniquePowerHeuristicEqualsGeneric) {
  Rng r(11);
  for (int rep = 0; rep < 100000; ++rep) {
    double a = r.uniform() < 0.05 ? 0.0 : std::exp(200.0 * (r.uniform() - 0.5));
    const double b = r.uniform() < 0.05 ? 0.0 : std::exp(200.0 * (r.uniform() - 0.5));
    if (rep % 13 == 0) a = b;  // ties
    const std::array<double, 2> q{a, b};
    const double w = power_heuristic_2(a, b), ref = PowerHeuristic{}.weight(q, 0);
    // Both compute r^2 / (r^2 + 1)-type expressions with a handful of roundings each: 8 ulps.
    EXPECT_NEAR(w, ref, 8 * 0x1p-53 * std::max(ref, 1e-300)) << a << " " << b;
    if (a > 0 || b > 0) {
      EXPECT_NEAR(w + power_heuristic_2(b, a), 1.0, 4 * 0x1p-53);
    }
  }
  EXPECT_EQ(power_heuristic_2(0.0, 0.0), 0.0);
  EXPECT_EQ(power_heuristic_2(2.0, 2.0), 0.5);
  EXPECT_EQ(power_heuristic_2(1e300, 1e300), 0.5);  // no overflow of the squares
}

TEST(Mis, OneSampleBalanceOnConstantRatioIsExact) {
  // f proportional to the balance mixture Σ c_k p_k: every one-sample estimate equals the integral.
  const auto cs = classical_set();
  const std::vector<double> c{0.2, 0.5, 0.3};
  auto f = [&](double x) { return 2.0 * (c[0] * cs[0].pdf(x) + c[1] * cs[1].pdf(x) + c[2] * cs[2].pdf(x)); };
  Rng r(9);
  RngUniforms u(r);
  for (int rep = 0; rep < 100; ++rep)
    expect_close(estimate_one_sample_mis(f, std::span<const Classical1D>(cs), std::span<const double>(c), u).value, 2.0);
}

TEST(Mc, ExactForIntegrandProportionalToPdf) {
  const Classical1D p(TruncatedNormalTechnique1D(0.3, 0.1));
  auto f = [&](double x) { return 3.0 * p.pdf(x); };
  Rng r(1);
  RngUniforms u(r);
  expect_close(estimate_mc(f, p, 100, u).value, 3.0);
}

TEST(TechniqueSubset, KeepsAlwaysAndChoosesK) {
  Rng r(2);
  RngUniforms u(r);
  const std::vector<int> counts{2, 2, 2, 2};
  const std::array<bool, 4> always{false, false, false, true};
  for (int rep = 0; rep < 100; ++rep) {
    const auto out = random_subset_counts(counts, always, 2, u);
    EXPECT_EQ(out[3], 2);
    EXPECT_EQ((out[0] > 0) + (out[1] > 0) + (out[2] > 0), 2);
  }
}

}  // namespace
}  // namespace tb
