// The zoomed spherical domain (validate/chi2/direction_chart.h): a uniform cone of half-angle
// 1e-4 rad around an oblique axis passes (fully inside the chart and cut by it, the cut mass
// going to the failure cell), a pdf with the orthographic Jacobian 1/z dropped is rejected on a
// wide cap, a wrong cone angle is rejected on a narrow one, non-unit directions are hard
// failures, and fit() centres the chart on the lobe. Fixed seeds: deterministic.
#include "validate/chi2/direction_chart.h"

#include <gtest/gtest.h>

namespace tb {
namespace {

constexpr double kAlpha = 0.01;

SamplerChi2Options opts(int64_t n, uint64_t key) {
  SamplerChi2Options o;
  o.samples = n;
  o.seed = 777;
  o.key = key;
  o.quadrature_tolerance = 1e-7;
  o.quadrature_max_depth = 4;
  return o;
}

// Uniform directions in the cone of half-angle theta_max around `axis` (pdf w.r.t. solid angle
// 1 / (2 pi (1 - cos theta_max))), written with 1 - cos theta = 2 sin^2(theta / 2) so that a
// 1e-4 rad cone keeps full relative precision.
struct Cone {
  Frame frame;
  double theta_max;
  double one_minus_cos_max() const { return 2.0 * std::pow(std::sin(0.5 * theta_max), 2); }
  Vec3 sample(Vec2 u) const {
    const double omc = u.x * one_minus_cos_max();  // 1 - cos theta, uniform
    const double sin_t = std::sqrt(omc * (2.0 - omc)), phi = 2 * kPi * u.y;
    return frame.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), 1.0 - omc));
  }
  double pdf(const Vec3& w) const {
    const Vec3 l = frame.to_local(w);
    // sin theta from the tangential components (precise near the axis).
    const double sin_t = std::sqrt(l.x * l.x + l.y * l.y);
    return (l.z > 0 && sin_t <= std::sin(theta_max)) ? 1.0 / (2 * kPi * one_minus_cos_max()) : 0.0;
  }
};

const Vec3 kAxis = glm::normalize(Vec3(0.3, -0.8, -0.5));

TEST(Chi2Chart, NarrowConeInsideChartPasses) {
  const Cone cone{Frame::from_z(kAxis), 1e-4};
  const auto chart = Chi2DirectionChart::around(kAxis, 1.2 * std::sin(1e-4), 31);
  const auto r = chi2_test_zoomed(chart, [&](Vec2 u) { return cone.sample(u); },
                                  [&](const Vec3& w) { return cone.pdf(w); }, opts(200000, 1));
  EXPECT_TRUE(r.passed(kAlpha)) << r.message();
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);  // a disk on a square grid: rim cells by bisection
  EXPECT_EQ(r.failed, 0);
  EXPECT_EQ(r.outside, 0);
}

TEST(Chi2Chart, ChartCuttingTheLobeCountsTheRestAsFailures) {
  const Cone cone{Frame::from_z(kAxis), 1e-4};
  const auto chart = Chi2DirectionChart::around(kAxis, 0.5 * std::sin(1e-4), 31);
  const auto r = chi2_test_zoomed(chart, [&](Vec2 u) { return cone.sample(u); },
                                  [&](const Vec3& w) { return cone.pdf(w); }, opts(200000, 2));
  EXPECT_TRUE(r.passed(kAlpha)) << r.message();
  // The square [-h, h]^2 with h = r / 2 holds 1 / pi of the disk's mass.
  EXPECT_NEAR(r.pdf_integral, 1.0 / kPi, 1e-6);
  EXPECT_NEAR(static_cast<double>(r.failed) / 200000.0, 1.0 - 1.0 / kPi, 0.005);
}

TEST(Chi2Chart, WrongConeAngleIsRejected) {
  const Cone cone{Frame::from_z(kAxis), 1e-4}, stated{Frame::from_z(kAxis), 1.03e-4};
  const auto chart = Chi2DirectionChart::around(kAxis, 1.2 * std::sin(1e-4), 31);
  const auto r = chi2_test_zoomed(chart, [&](Vec2 u) { return cone.sample(u); },
                                  [&](const Vec3& w) { return stated.pdf(w); }, opts(200000, 3));
  EXPECT_FALSE(r.passed(kAlpha)) << r.message();
}

TEST(Chi2Chart, WideCapPassesAndDroppedJacobianIsRejected) {
  const Cone cone{Frame::from_z(kAxis), 0.6};
  const auto chart = Chi2DirectionChart::around(kAxis, std::sin(0.6), 31);
  const auto good = chi2_test_zoomed(chart, [&](Vec2 u) { return cone.sample(u); },
                                     [&](const Vec3& w) { return cone.pdf(w); }, opts(200000, 4));
  EXPECT_TRUE(good.passed(kAlpha)) << good.message();
  EXPECT_NEAR(good.pdf_integral, 1.0, 1e-3);
  // pdf * z: the chart density without d omega / (dx dy) = 1 / z.
  const auto bad = chi2_test_zoomed(chart, [&](Vec2 u) { return cone.sample(u); },
                                    [&](const Vec3& w) { return cone.pdf(w) * glm::dot(w, kAxis); }, opts(200000, 5));
  EXPECT_FALSE(bad.passed(kAlpha)) << bad.message();
}

TEST(Chi2Chart, NonUnitDirectionIsAHardFailure) {
  const auto chart = Chi2DirectionChart::around(kAxis, 0.1, 11);
  const auto r = chi2_test_zoomed(chart, [&](Vec2) { return 1.01 * kAxis; }, [](const Vec3&) { return 1.0; },
                                  opts(1000, 6));
  EXPECT_GT(r.outside, 0);
  EXPECT_FALSE(r.passed(kAlpha));
}

TEST(Chi2Chart, JacobianIntegratesTheCapArea) {
  // int_{x^2 + y^2 <= sin^2 t} dx dy / z = 2 pi (1 - cos t): the chart's Jacobian.
  const Cone cone{Frame::from_z(kAxis), 0.6};
  const auto chart = Chi2DirectionChart::around(kAxis, std::sin(0.6), 31);
  const auto r = chi2_test_zoomed(chart, [&](Vec2 u) { return cone.sample(u); }, [&](const Vec3& w) {
    return cone.pdf(w) > 0 ? 1.0 : 0.0;
  }, opts(10, 7));
  EXPECT_NEAR(r.pdf_integral, 2 * kPi * (1 - std::cos(0.6)), 1e-3);
}

TEST(Chi2Chart, FitCentresOnTheLobe) {
  const Vec3 centre = glm::normalize(Vec3(0.1, 0.2, -0.97));
  const Cone cone{Frame::from_z(centre), 2e-5};
  std::vector<Vec3> pilot;
  Rng rng = Rng::for_sample(1, 2, 3);
  for (int i = 0; i < 4000; ++i) pilot.push_back(cone.sample(rng.uniform2()));
  const auto chart = Chi2DirectionChart::fit(pilot, Vec3(0, 0, -1), 0.97, 21);
  ASSERT_TRUE(chart.has_value());
  EXPECT_LT(glm::length(chart->frame.n - centre), 3e-6);
  EXPECT_GT(chart->half_width, 0.5 * 2e-5);
  EXPECT_LT(chart->half_width, 2e-5);
  EXPECT_FALSE(Chi2DirectionChart::fit(pilot, Vec3(0, 0, 1), 0.97).has_value());
}

}  // namespace
}  // namespace tb
