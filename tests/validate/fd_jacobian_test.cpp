#include "validate/stats/fd_jacobian.h"

#include <cmath>

#include <gtest/gtest.h>

#include "lib/core/rng.h"

namespace tb::stats {
namespace {

Eigen::VectorXd f(const Eigen::VectorXd& x) {
  Eigen::VectorXd y(2);
  y << std::sin(x[0]) * x[1], std::exp(0.5 * x[0]) + x[1] * x[1] * x[1];
  return y;
}
Eigen::MatrixXd jf(const Eigen::VectorXd& x) {
  Eigen::MatrixXd j(2, 2);
  j << std::cos(x[0]) * x[1], std::sin(x[0]), 0.5 * std::exp(0.5 * x[0]), 3.0 * x[1] * x[1];
  return j;
}
Eigen::VectorXd config(int64_t i) {
  Rng rng = Rng::for_sample(1, 2, static_cast<uint64_t>(i));
  Eigen::VectorXd x(2);
  x << 4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0;
  return x;
}

TEST(FdJacobian, AcceptsCorrectJacobian) {
  const FdResult r = check_jacobian(f, jf, config, 200);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(r.checked, 200);
  EXPECT_LT(r.worst_rel_error, 1e-8);
  EXPECT_LT(r.worst_ridders_rel_error, 1e-8);
  EXPECT_LT(r.worst_taylor_slope_deviation, 0.1);
}

TEST(FdJacobian, RejectsWrongJacobian) {
  const auto wrong = [](const Eigen::VectorXd& x) {
    Eigen::MatrixXd j = jf(x);
    j(1, 1) *= 1.0 + 1e-4;  // a small relative error in one entry
    return j;
  };
  const FdResult r = check_jacobian(f, wrong, config, 200);
  EXPECT_FALSE(r.passed);
  EXPECT_GT(r.failed, 150);
  EXPECT_EQ(r.first_failure_index >= 0, true);
}

TEST(FdJacobian, TaylorSlopeIsOneForWrongJacobian) {
  FdOptions o;
  o.ridders = false;
  const auto wrong = [](const Eigen::VectorXd& x) { return Eigen::MatrixXd(-jf(x)); };
  const FdPointResult p = check_jacobian_at(f, wrong, config(3), o, 3);
  EXPECT_NEAR(p.taylor_slope, 1.0, 0.05);
  EXPECT_FALSE(p.passed);
}

TEST(FdJacobian, SkipsDiscontinuity) {
  const auto step = [](const Eigen::VectorXd& x) {
    Eigen::VectorXd y(1);
    y << std::floor(x[0]);
    return y;
  };
  const auto zero = [](const Eigen::VectorXd&) { return Eigen::MatrixXd::Zero(1, 1).eval(); };
  Eigen::VectorXd at_jump(1), away(1);
  at_jump << 1.0 + 1e-6;
  away << 0.5;
  EXPECT_TRUE(check_jacobian_at(step, zero, at_jump).skipped);
  const FdPointResult p = check_jacobian_at(step, zero, away);
  EXPECT_FALSE(p.skipped);
  EXPECT_TRUE(p.passed);  // constant: linear along every direction, slope NaN and not failed
  EXPECT_TRUE(std::isnan(p.taylor_slope));
}

TEST(FdJacobian, LinearFunctionHasNoTaylorSlope) {
  const auto lin = [](const Eigen::VectorXd& x) { return Eigen::VectorXd(2.0 * x); };
  const auto jl = [](const Eigen::VectorXd& x) { return Eigen::MatrixXd(2.0 * Eigen::MatrixXd::Identity(x.size(), x.size())); };
  Eigen::VectorXd x(3);
  x << 1, 2, 3;
  const FdPointResult p = check_jacobian_at(lin, jl, x);
  EXPECT_TRUE(p.passed);
  EXPECT_NEAR(p.condition_number, 1.0, 1e-12);
}

}  // namespace
}  // namespace tb::stats
