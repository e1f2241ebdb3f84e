// The predictor-corrector walk (lib/differential/hslt_walk.h; Kaplanyan 2014, Sec. 5.1, 5.2):
// the O(k) condition estimate and the Table 2 side ratio against dense matrices, walks on traced
// and sampled paths of the dg scenes (convergence, on-surface result, reversibility), and the
// failure statuses (singular Jacobian, failed projection, non-finite target) without NaN.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_walk.h"
#include "validate/differential/hslt_paths.h"
#include "validate/differential/hslt_walk_support.h"

namespace tb {
namespace {

HsltBlocks random_blocks(int n, uint64_t seed) {
  Rng rng = Rng::for_sample(seed, 7, 0);
  HsltBlocks b;
  auto m = [&](double diag) {
    Eigen::Matrix2d x;
    x << 2 * rng.uniform() - 1 + diag, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1 + diag;
    return x;
  };
  for (int r = 0; r < n; ++r) {
    b.A.push_back(m(0));
    b.B.push_back(m(1.5));
    b.C.push_back(m(0));
  }
  return b;
}

TEST(HsltWalk, ConditionEstimateIsTheDenseOneNormCondition) {
  for (int n = 1; n <= 12; ++n) {
    const HsltBlocks b = random_blocks(n, static_cast<uint64_t>(n));
    const Eigen::MatrixXd J = hslt_dense_jacobian(b);
    const double exact = J.cwiseAbs().colwise().sum().maxCoeff() * J.inverse().cwiseAbs().colwise().sum().maxCoeff();
    const double est = hslt_condition_estimate(b);
    // Hager's estimate is a lower bound, usually exact; within a factor 3 on these matrices.
    EXPECT_LE(est, exact * (1 + 1e-10)) << n;
    EXPECT_GE(est, exact / 3) << n;
  }
}

TEST(HsltWalk, SideRatioIsTheRatioOfTheTransferDeterminants) {
  for (int n = 2; n <= 8; ++n) {
    const HsltBlocks b = random_blocks(n, 100 + static_cast<uint64_t>(n));
    const Eigen::MatrixXd inv = hslt_dense_jacobian(b).inverse();
    const Eigen::Index last = 2 * (n - 1);
    const double expect = std::abs(Eigen::Matrix2d(inv.block<2, 2>(0, last)).determinant()) /
                          std::abs(Eigen::Matrix2d(inv.block<2, 2>(last, last)).determinant());
    EXPECT_NEAR(hslt_projection_side_ratio(b), expect, 1e-10 * expect) << n;
  }
  EXPECT_EQ(hslt_projection_side_ratio(random_blocks(1, 3)), 1.0);
}

// Walks to h^perp + 1e-3 on a disk per vertex converge to paths on the surfaces that meet h*,
// and walk back to the start.
void expect_walks_converge(const std::string& family, int count) {
  const HsltPathSet set = hslt_path_set(family, count, 1);
  const Scene& scene = hslt_family_world(family).geometry();
  const HsltWalkOptions opt = hslt_walk_options_for(family);
  int walked = 0, converged = 0;
  for (size_t i = 0; i < set.paths.size(); ++i) {
    const HsltPath& x = set.paths[i];
    if (!hslt_walk_start_ok(scene, x, opt.visibility)) continue;
    ++walked;
    const Eigen::VectorXd target = hslt_walk_target(x, 1e-3, 1, 11, static_cast<int64_t>(i));
    const HsltWalkResult r = hslt_walk(scene, x, target, opt);
    EXPECT_TRUE(std::isfinite(r.residual) && std::isfinite(r.condition_estimate));
    if (r.status != HsltWalkStatus::kConverged) continue;
    ++converged;
    EXPECT_LT(r.residual, opt.tolerance);
    EXPECT_EQ(r.residuals.size(), static_cast<size_t>(r.iterations) + 1);
    const HsltOnSurface s = hslt_walk_on_surface(scene, r.path, target);
    EXPECT_LT(s.surface_distance, 1e-9) << family << " " << i;
    EXPECT_LT(s.constraint_error, 1e-10) << family << " " << i;
    const HsltReversibility rev = hslt_walk_reversible(x, r.path, opt, hslt_constraint_blocks,
                                                       hslt_ray_cast_projection(scene, opt.visibility), 1e-7);
    EXPECT_TRUE(rev.reversible) << family << " " << i << " distance " << rev.distance;
  }
  EXPECT_GT(walked, 0);
  EXPECT_GE(converged, walked * 8 / 10) << family;
}

TEST(HsltWalk, ConvergesOnTracedGlassChains) { expect_walks_converge("glass", 8); }
TEST(HsltWalk, ConvergesOnSampledMixedPaths) { expect_walks_converge("mixed", 8); }

TEST(HsltWalk, ZeroStepIsConvergedWithoutIterations) {
  const HsltPathSet set = hslt_path_set("curved_mirrors", 2, 1);
  ASSERT_FALSE(set.paths.empty());
  const Scene& scene = hslt_family_world("curved_mirrors").geometry();
  const HsltPath& x = set.paths[0];
  const HsltWalkResult r = hslt_walk(scene, x, hslt_constraints(x));
  EXPECT_EQ(r.status, HsltWalkStatus::kConverged);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(hslt_max_vertex_distance(r.path, x), 0.0);
}

TEST(HsltWalk, FailuresAreReportedWithoutNaN) {
  const HsltPathSet set = hslt_path_set("mixed", 3, 1);
  ASSERT_FALSE(set.paths.empty());
  const HsltPath& x = set.paths[0];
  const Scene& scene = hslt_family_world("mixed").geometry();
  const Eigen::VectorXd target = hslt_walk_target(x, 1e-3, 1, 11, 0);
  HsltWalkOptions opt;
  opt.visibility = false;
  // Singular Jacobian: zero blocks.
  const HsltBlocksFn zero = [](const HsltPath& p) {
    HsltBlocks b = hslt_constraint_blocks(p);
    for (auto& m : b.B) m.setZero();
    for (auto& m : b.C) m.setZero();
    for (auto& m : b.A) m.setZero();
    return b;
  };
  const HsltWalkResult s = hslt_walk(x, target, opt, zero, hslt_ray_cast_projection(scene, false));
  EXPECT_EQ(s.status, HsltWalkStatus::kSingularJacobian);
  EXPECT_TRUE(std::isfinite(s.condition_estimate) && std::isfinite(s.residual));
  // A corrector that always reports an occluder.
  const HsltProjectFn blocked = [](const HsltPath&, const std::vector<Vec3>&, bool, HsltPath*) {
    return HsltWalkStatus::kOccluded;
  };
  const HsltWalkResult o = hslt_walk(x, target, opt, hslt_constraint_blocks, blocked);
  EXPECT_EQ(o.status, HsltWalkStatus::kOccluded);
  EXPECT_EQ(o.halvings, opt.max_halvings);
  EXPECT_TRUE(std::isfinite(o.residual));
  // A non-finite target.
  Eigen::VectorXd bad = target;
  bad[0] = std::numeric_limits<double>::quiet_NaN();
  const HsltWalkResult d = hslt_walk(scene, x, bad, opt);
  EXPECT_EQ(d.status, HsltWalkStatus::kDiverged);
  EXPECT_TRUE(std::isfinite(d.residual));
  // A target of the wrong size.
  const HsltWalkResult w = hslt_walk(scene, x, Eigen::VectorXd::Zero(target.size() + 2), opt);
  EXPECT_EQ(w.status, HsltWalkStatus::kDiverged);
  EXPECT_TRUE(std::isfinite(w.residual));
  // An unreachable target (|h*| > 1 cannot be a projected unit vector): no convergence, no NaN.
  const Eigen::VectorXd far = Eigen::VectorXd::Constant(target.size(), 2.0);
  const HsltWalkResult f = hslt_walk(scene, x, far, opt);
  EXPECT_NE(f.status, HsltWalkStatus::kConverged);
  EXPECT_TRUE(std::isfinite(f.residual));
  for (double v : f.residuals) EXPECT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace tb
