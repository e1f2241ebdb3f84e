// The analytic catalogue: closed-form integrals against quadrature, densities that integrate to one,
// samples distributed as their pdf (KS test, fixed seed, alpha = 1e-5 with Šidák over the
// techniques tested), exact marginals against sampled histograms, and the exact MIS variance
// against a closed form.
#include <algorithm>
#include <cmath>
#include <vector>

#include <boost/math/quadrature/gauss.hpp>
#include <gtest/gtest.h>

#include "analytic/classical_techniques_1d.h"
#include "analytic/classical_techniques_2d.h"
#include "analytic/integrands.h"
#include "analytic/marginal_techniques_1d.h"
#include "analytic/mis_variance.h"
#include "analytic/quadrature.h"
#include "analytic/uniform_centre_normal_1d.h"
#include "lib/core/rng.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

TEST(Integrands, ClosedFormsMatchQuadrature) {
  for (const auto& g : integrands_1d()) {
    if (g.singular) continue;
    const double q = integrate_1d(g.f, 0.0, 1.0, g.breakpoints).value;
    EXPECT_NEAR(g.integral, q, 1e-10 * std::abs(q)) << g.name;
    EXPECT_EQ(g.description["name"], g.name);
  }
  // The singular one: substitute x = s², dx = 2 s ds, which removes the singularity.
  const auto& s = integrand_1d("singularity");
  EXPECT_NEAR(integrate_1d([&](double v) { return s(v * v) * 2.0 * v; }, 0.0, 1.0).value, s.integral, 1e-12);
  EXPECT_THROW(integrand_1d("no_such"), std::invalid_argument);
}

TEST(Integrands, TwoDimensionalByNestedQuadrature) {
  for (const auto& g : integrands_2d()) {
    if (g.singular || g.name == "quarter_disk_2d") continue;  // kink-free nested rule; disk below
    const double q = integrate_1d([&](double y) {
      return integrate_1d([&](double x) { return g(Vec2{x, y}); }, 0.0, 1.0, {0.5, y}, 1e-12).value;
    }, 0.0, 1.0, {0.5}, 1e-12).value;
    EXPECT_NEAR(g.integral, q, 1e-9 * std::abs(q)) << g.name;
  }
  const auto& d = integrand_2d("quarter_disk_2d");
  const double q = integrate_1d([](double y) { return std::sqrt(std::max(0.0, 0.64 - y * y)); }, 0.0, 0.8).value;
  EXPECT_NEAR(d.integral, q, 1e-12);
}

std::vector<Classical1D> classical_set() {
  return {Classical1D(UniformTechnique1D{0.2, 0.7}), Classical1D(TruncatedNormalTechnique1D(0.3, 0.1)),
          Classical1D(TruncatedNormalTechnique1D(0.95, 0.02)),  // mass deep in the upper tail: mirrored inversion
          Classical1D(PiecewiseConstantTechnique1D({0.0, 0.5, 0.8, 1.0}, {1.0, 3.0, 0.5})),
          Classical1D(MixtureTechnique1D({UniformTechnique1D{}, TruncatedNormalTechnique1D(0.7, 0.05)}, {0.3, 0.7}))};
}

std::vector<ConditionalNormal1D> marginal_set() {
  std::vector<ConditionalNormal1D> v;
  ConditionalNormal1D::Params a;
  a.name = "centre_partial";
  a.t_dist = Classical1D(UniformTechnique1D{0.1, 0.4});
  a.fixed = 0.05;
  a.x_lo = 0.0;
  a.x_hi = 0.5;
  v.emplace_back(a);
  ConditionalNormal1D::Params b;
  b.name = "width_defensive";
  b.t_dist = Classical1D(TruncatedNormalTechnique1D(0.1, 0.1, 0.02, 0.4));
  b.mode = ConditionalNormal1D::Mode::kWidth;
  b.fixed = 0.6;
  b.defensive = 0.2;
  v.emplace_back(b);
  ConditionalNormal1D::Params c;
  c.name = "extruded";
  c.mode = ConditionalNormal1D::Mode::kClassical;
  c.classical = Classical1D(TruncatedNormalTechnique1D(0.3, 0.1));
  v.emplace_back(c);
  return v;
}

double cdf_by_quadrature(const std::function<double(double)>& pdf, double x, const std::vector<double>& b) {
  return integrate_1d(pdf, 0.0, x, b, 1e-10).value;
}

TEST(ClassicalTechniques, DensityIntegratesToOneAndSamplesFollowIt) {
  const auto cs = classical_set();
  const double alpha = stats::sidak_alpha(1e-5, static_cast<int64_t>(cs.size()));
  for (size_t k = 0; k < cs.size(); ++k) {
    const auto& c = cs[k];
    const auto b = c.breakpoints();
    EXPECT_NEAR(integrate_1d([&](double x) { return c.pdf(x); }, 0.0, 1.0, b).value, 1.0, 1e-10) << k;
    Rng r = Rng::for_sample(1, 0xa11, k);
    RngUniforms u(r);
    std::vector<double> xs;
    for (int i = 0; i < 3000; ++i) {
      const auto x = c.sample(u);
      ASSERT_TRUE(x);
      ASSERT_GT(c.pdf(*x), 0.0) << "sample outside the support, technique " << k;
      xs.push_back(*x);
    }
    const auto t = stats::ks_test(xs, [&](double x) { return cdf_by_quadrature([&](double v) { return c.pdf(v); }, x, b); });
    EXPECT_GT(t.p_value, alpha) << "technique " << k << " D = " << t.statistic << " (seed 1, key 0xa11)";
  }
}

TEST(MarginalTechniques, MarginalAndJointIntegrateToOneAndSamplesFollowMarginal) {
  const auto ms = marginal_set();
  const double alpha = stats::sidak_alpha(1e-5, static_cast<int64_t>(ms.size()));
  for (size_t k = 0; k < ms.size(); ++k) {
    const auto& m = ms[k];
    const auto b = m.x_breakpoints();
    EXPECT_NEAR(integrate_1d([&](double x) { return m.marginal_pdf(x); }, 0.0, 1.0, b, 1e-10).value, 1.0, 1e-9)
        << m.name();
    // p(x | t) integrates to one for a few t.
    for (double t : {m.t_lo(), 0.5 * (m.t_lo() + m.t_hi()), m.t_hi()}) {
      const auto a = m.aux_for(t);
      EXPECT_NEAR(integrate_1d([&](double x) { return m.pdf(x, a); }, 0.0, 1.0, b).value, 1.0, 1e-10) << m.name();
    }
    Rng r = Rng::for_sample(1, 0xa12, k);
    RngUniforms u(r);
    std::vector<double> xs;
    for (int i = 0; i < 1500; ++i) {
      const auto a = m.sample_aux(u);
      ASSERT_TRUE(a);
      const auto x = m.sample(*a, u);
      ASSERT_TRUE(x);
      ASSERT_GT(m.pdf(*x, *a), 0.0);
      xs.push_back(*x);
    }
    // CDF of the marginal tabulated on 1000 cells (edges i/1000, so the breakpoints 0.5 and 1 are
    // edges) with 10-point Gauss-Legendre per cell, interpolated linearly: error far below the KS
    // resolution 1/sqrt(1500).
    std::vector<double> cdf{0.0};
    for (int i = 0; i < 1000; ++i)
      cdf.push_back(cdf.back() + boost::math::quadrature::gauss<double, 10>::integrate(
                                     [&](double v) { return m.marginal_pdf(v); }, i / 1000.0, (i + 1) / 1000.0));
    const auto t = stats::ks_test(xs, [&](double x) {
      const double s = std::clamp(x, 0.0, 1.0) * 1000.0;
      const int i = std::min(999, static_cast<int>(s));
      return cdf[i] + (s - i) * (cdf[i + 1] - cdf[i]);
    });
    EXPECT_GT(t.p_value, alpha) << m.name() << " D = " << t.statistic << " (seed 1, key 0xa12)";
  }
}

TEST(UniformCentreNormal, ClosedFormMarginalMatchesQuadratureAndSamplesFollowIt) {
  const std::vector<UniformCentreNormal1D> ms{UniformCentreNormal1D(0.02, 0.98, 0.1, 0.2),
                                              UniformCentreNormal1D(-0.1, 1.1, 0.15, 0.0),
                                              UniformCentreNormal1D(0.3, 0.35, 0.01, 0.05)};
  const double alpha = stats::sidak_alpha(1e-5, static_cast<int64_t>(ms.size()));
  for (size_t k = 0; k < ms.size(); ++k) {
    const auto& m = ms[k];
    // p(x) = ∫ p(t) p(x | t) dt by quadrature, at x inside, near and far outside [0, 1].
    for (double x : {-0.5, -0.05, 0.0, 0.01, 0.2, 0.33, 0.5, 0.9, 1.0, 1.07, 1.6}) {
      const double q = integrate_1d([&](double t) { return m.aux_pdf({t}) * m.pdf(x, {t}); }, m.t_lo(), m.t_hi()).value;
      EXPECT_NEAR(m.marginal_pdf(x), q, 1e-10 * q + 1e-300) << k << " x = " << x;
    }
    // p(x) integrates to one over the real line (the normal part decays within 12 sigma).
    const double lo = std::min(0.0, m.t_lo() - 12 * m.sigma()), hi = std::max(1.0, m.t_hi() + 12 * m.sigma());
    EXPECT_NEAR(integrate_1d([&](double x) { return m.marginal_pdf(x); }, lo, hi, {0.0, 1.0}).value, 1.0, 1e-10) << k;
    Rng r = Rng::for_sample(1, 0xa13, k);
    RngUniforms u(r);
    std::vector<double> xs;
    for (int i = 0; i < 3000; ++i) {
      const auto a = m.sample_aux(u);
      ASSERT_TRUE(a);
      EXPECT_GT(m.aux_pdf(*a), 0.0);
      const auto x = m.sample(*a, u);
      ASSERT_TRUE(x);
      xs.push_back(*x);
    }
    const auto t = stats::ks_test(xs, [&](double x) {
      return integrate_1d([&](double v) { return m.marginal_pdf(v); }, std::min(lo, x), x, {0.0, 1.0}, 1e-10).value;
    });
    EXPECT_GT(t.p_value, alpha) << k << " D = " << t.statistic << " (seed 1, key 0xa13)";
  }
}

TEST(MisVariance, UniformMcOnSmoothMatchesClosedForm) {
  const auto& f = integrand_1d("smooth");
  MisVarianceInput in{f.f, {[](double) { return 1.0; }}, {1}, {}};
  const double f2 = 7.0 / 3.0 - 1.0 / (2.0 * kPi) + 0.125;  // ∫ (1 + x + sin(2πx)/2)² dx
  EXPECT_NEAR(mis_balance_variance(in), f2 - 2.25, 1e-12);
  // Two identical techniques with n = 1 each equal one technique with n = 2: Var = (∫f² − I²) / 2.
  MisVarianceInput in2{f.f, {[](double) { return 1.0; }, [](double) { return 1.0; }}, {1, 1}, {}};
  EXPECT_NEAR(mis_balance_variance(in2), (f2 - 2.25) / 2.0, 1e-12);
  // A technique that misses part of the support: infinite variance (the estimator is biased).
  MisVarianceInput in3{f.f, {[](double x) { return x < 0.5 ? 2.0 : 0.0; }}, {1}, {0.5}};
  EXPECT_TRUE(std::isinf(mis_balance_variance(in3)));
}

TEST(Product2D, DensityIntegratesToOne) {
  const Product2D p{Classical1D(TruncatedNormalTechnique1D(0.4, 0.2)), Classical1D(UniformTechnique1D{})};
  const double q = integrate_1d([&](double y) {
    return integrate_1d([&](double x) { return p.pdf(Vec2{x, y}); }, 0.0, 1.0).value;
  }, 0.0, 1.0).value;
  EXPECT_NEAR(q, 1.0, 1e-10);
}

}  // namespace
}  // namespace tb
