// Deterministic tests of lib/core/microfacet.h: normalisation of D, the projected-area identity
// that ties Lambda to D, sampling-by-inversion against the CDF of D cos, G2 properties, and the
// Beckmann-equivalent roughness mapping.
#include "lib/core/microfacet.h"

#include <vector>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <gtest/gtest.h>

#include "lib/core/rng.h"

namespace tb {
namespace {

using boost::math::quadrature::gauss_kronrod;

struct Case {
  MicrofacetType type;
  double alpha;  // native alpha
};

std::vector<Case> cases() {
  std::vector<Case> v;
  for (MicrofacetType t : {MicrofacetType::kBeckmann, MicrofacetType::kGgx})
    for (double a : {0.01, 0.05, 0.2, 0.5, 1.0, 1.5}) v.push_back({t, a});
  return v;
}

Vec3 dir(double theta, double phi) { return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)}; }

// Integral over theta_m in [0, pi/2] of g(theta) with breakpoints near the lobe width.
template <class F>
double integrate_theta(F g, double alpha, double hi = kPiOver2) {
  std::vector<double> b = {0.0};
  for (double k : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0})
    if (std::atan(k * alpha) < hi) b.push_back(std::atan(k * alpha));
  b.push_back(hi);
  double s = 0;
  for (size_t i = 0; i + 1 < b.size(); ++i) s += gauss_kronrod<double, 61>::integrate(g, b[i], b[i + 1], 12, 1e-13);
  return s;
}

TEST(Microfacet, DIsNormalisedOverProjectedArea) {
  // Walter 2007, Eq. 4: integral of D(m) cos theta_m d omega_m = 1.
  for (const Case& c : cases()) {
    const MicrofacetDistribution d(c.type, c.alpha);
    const double v = integrate_theta(
        [&](double t) { return 2 * kPi * d.D(dir(t, 0.3)) * std::cos(t) * std::sin(t); }, c.alpha);
    EXPECT_NEAR(v, 1.0, 1e-8) << to_string(c.type) << " alpha " << c.alpha;
  }
}

TEST(Microfacet, VisibleProjectedAreaEqualsCosine) {
  // Heitz 2014, Eq. 2 (with Smith G1): integral of G1(w, m) max(0, <w, m>) D(m) d omega_m = cos theta_w.
  // This ties Lambda to D: a wrong Lambda breaks it.
  for (const Case& c : cases()) {
    const MicrofacetDistribution d(c.type, c.alpha);
    for (double theta_w : {0.0, 0.5, 1.2, 1.5, 1.56}) {
      const Vec3 w = dir(theta_w, 0.0);
      auto inner = [&](double tm) {
        // Integral over phi of max(0, A cos(phi) + B) in closed form.
        const double A = std::sin(theta_w) * std::sin(tm), B = std::cos(theta_w) * std::cos(tm);
        double ip = 0;
        if (B >= A) ip = 2 * kPi * B;
        else if (B > -A) {
          const double ps = std::acos(-B / A);
          ip = 2 * (B * ps + A * std::sin(ps));
        }
        return ip * d.D(dir(tm, 0.0)) * std::sin(tm);
      };
      const double G1 = 1.0 / (1.0 + d.lambda(w));
      const double v = G1 * integrate_theta(inner, c.alpha);
      EXPECT_NEAR(v, w.z, 2e-7 * std::max(1.0, 1.0 / std::max(w.z, 1e-3)) * w.z + 1e-12)
          << to_string(c.type) << " alpha " << c.alpha << " theta_w " << theta_w;
    }
  }
}

TEST(Microfacet, SampleMInvertsTheCdfOfDcos) {
  // The theta_m of sample_m(u) must satisfy CDF(theta_m) = u.x, with CDF from quadrature of D cos.
  for (const Case& c : cases()) {
    const MicrofacetDistribution d(c.type, c.alpha);
    for (double ux : {0.01, 0.3, 0.5, 0.9, 0.999}) {
      const Vec3 m = d.sample_m({ux, 0.25});
      EXPECT_NEAR(glm::length(m), 1.0, 1e-14);
      EXPECT_NEAR(spherical_phi(m), 0.5 * kPi, 1e-12);
      const double tm = std::acos(m.z);
      const double cdf = integrate_theta(
          [&](double t) { return 2 * kPi * d.D(dir(t, 0.0)) * std::cos(t) * std::sin(t); }, c.alpha, tm);
      EXPECT_NEAR(cdf, ux, 1e-8) << to_string(c.type) << " alpha " << c.alpha;
    }
  }
}

TEST(Microfacet, VisibleSamplesAreFrontFacing) {
  // Sampled visible normals face wo; their distribution against pdf_visible is checked by the
  // chi-square test in tests/render/material_chi2_test.cpp.
  const MicrofacetDistribution d(MicrofacetType::kGgx, 0.3);
  for (double theta_o : {0.0, 0.7, 1.4, 1.55}) {
    const Vec3 wo = dir(theta_o, 0.4);
    Rng rng(7);
    for (int k = 0; k < 1000; ++k) {
      const Vec3 m = d.sample_visible(wo, rng.uniform2());
      EXPECT_GT(glm::dot(wo, m), -1e-12);
      EXPECT_GT(m.z, 0);
      EXPECT_NEAR(glm::length(m), 1.0, 1e-13);
    }
  }
}

TEST(Microfacet, G2Properties) {
  Rng rng(3);
  for (const Case& c : cases()) {
    const MicrofacetDistribution d(c.type, c.alpha);
    for (int k = 0; k < 200; ++k) {
      const Vec3 wo = dir(std::acos(rng.uniform()), 2 * kPi * rng.uniform());
      const Vec3 wi = dir(std::acos(rng.uniform()), 2 * kPi * rng.uniform());
      const Vec3 m = glm::normalize(wo + wi);
      // Height-correlated >= separable (Heitz 2014, Sec. 6), symmetric, in [0, 1].
      const double g2 = d.G2(wo, wi, m);
      EXPECT_DOUBLE_EQ(g2, d.G2(wi, wo, m));
      EXPECT_GE(g2 + 1e-15, d.G1(wo, m) * d.G1(wi, m));
      EXPECT_LE(g2, std::min(d.G1(wo, m), d.G1(wi, m)) + 1e-15);
      // Transmission: wi below. B(1+a, 1+b) <= 1/(1+max(a, b)) and symmetric.
      const Vec3 wt(wi.x, wi.y, -wi.z);
      const Vec3 mt = glm::normalize(wo + 1.5 * wt) * -1.0;
      const double g2t = d.G2(wo, wt, mt);
      EXPECT_DOUBLE_EQ(g2t, d.G2(wt, wo, mt));
      EXPECT_LE(g2t, std::min(d.G1(wo, mt), d.G1(wt, mt)) + 1e-15);
    }
  }
}

TEST(Microfacet, LambdaLimits) {
  for (const Case& c : cases()) {
    const MicrofacetDistribution d(c.type, c.alpha);
    EXPECT_EQ(d.lambda({0, 0, 1}), 0.0);
    EXPECT_EQ(d.lambda({1, 0, 0}), kInfinity);
    EXPECT_EQ(d.lambda({0, 0, -1}), 0.0);
    double prev = 0;
    for (double t = 0.05; t < 1.57; t += 0.05) {
      const double l = d.lambda(dir(t, 0.0));
      EXPECT_GE(l, prev);  // masking grows towards grazing
      prev = l;
    }
  }
}

TEST(Microfacet, BeckmannEquivalentMappingMatchesSlopeCurvature) {
  // ln P22(x) = ln(D(m) cos^4 theta_m) near x = 0 has curvature -2/alpha_b^2 (Beckmann) and
  // -4/alpha_g^2 (GGX); with alpha_g = sqrt(2) alpha_b they agree.
  for (double ab : {0.01, 0.1, 0.7}) {
    const auto b = MicrofacetDistribution::from_beckmann_equivalent(MicrofacetType::kBeckmann, ab);
    const auto g = MicrofacetDistribution::from_beckmann_equivalent(MicrofacetType::kGgx, ab);
    EXPECT_DOUBLE_EQ(g.beckmann_equivalent_alpha(), ab);
    auto log_p22 = [](const MicrofacetDistribution& d, double slope) {
      const Vec3 m = glm::normalize(Vec3(-slope, 0, 1));
      return std::log(d.D(m) * std::pow(m.z, 4));
    };
    const double h = 1e-3 * ab;
    auto curv = [&](const MicrofacetDistribution& d) {
      return (log_p22(d, h) - 2 * log_p22(d, 0) + log_p22(d, -h)) / (h * h);
    };
    EXPECT_NEAR(curv(g) / curv(b), 1.0, 1e-5);
  }
}

}  // namespace
}  // namespace tb
