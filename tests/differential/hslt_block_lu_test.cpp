// Block LU of the block-tridiagonal constraint Jacobian (lib/differential/hslt_block_lu.h)
// against dense Eigen LU on random matrices of 1 .. 63 blocks (path lengths 2 .. 64).
#include <cmath>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/differential/hslt_block_lu.h"

namespace tb {
namespace {

Eigen::Matrix2d random_block(Rng& rng, double diag) {
  Eigen::Matrix2d m;
  m << 2 * rng.uniform() - 1 + diag, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1 + diag;
  return m;
}

HsltBlocks random_blocks(int n, uint64_t seed) {
  Rng rng = Rng::for_sample(seed, 7, static_cast<uint64_t>(n));
  HsltBlocks b;
  for (int r = 0; r < n; ++r) {
    b.A.push_back(random_block(rng, 0.0));
    b.B.push_back(random_block(rng, 3.0));
    b.C.push_back(random_block(rng, 0.0));
  }
  return b;
}

TEST(HsltBlockLu, DeterminantAndSolveMatchDenseLu) {
  for (int n = 1; n <= 63; ++n) {
    const HsltBlocks b = random_blocks(n, 1);
    const Eigen::MatrixXd J = hslt_dense_jacobian(b);
    const HsltBlockLu lu(b);
    ASSERT_TRUE(lu.ok()) << n;
    const Eigen::PartialPivLU<Eigen::MatrixXd> dense(J);
    const double det = dense.determinant();
    EXPECT_NEAR(lu.determinant() / det, 1.0, 1e-11) << n;
    EXPECT_NEAR(lu.log_abs_determinant(), std::log(std::abs(det)), 1e-10) << n;
    EXPECT_EQ(lu.determinant_sign(), det > 0 ? 1 : -1) << n;
    Rng rng = Rng::for_sample(2, 3, static_cast<uint64_t>(n));
    Eigen::MatrixXd rhs(2 * n, 3);
    for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs.data()[i] = 2 * rng.uniform() - 1;
    const Eigen::MatrixXd x = lu.solve(rhs), xd = dense.solve(rhs);
    EXPECT_LT((x - xd).norm() / xd.norm(), 1e-12) << n;
    const Eigen::VectorXd v = lu.solve(Eigen::VectorXd(rhs.col(1)));
    EXPECT_LT((J * v - rhs.col(1)).norm(), 1e-12 * rhs.col(1).norm() * J.norm()) << n;
  }
}

TEST(HsltBlockLu, Eq9BlocksAreTheLastBlockRowOfTheInverse) {
  for (int n : {1, 2, 3, 7, 20, 63}) {
    const HsltBlocks b = random_blocks(n, 4);
    std::vector<Eigen::Matrix2d> D;
    ASSERT_TRUE(hslt_inverse_last_block_row(b, &D)) << n;
    const Eigen::MatrixXd inv = hslt_dense_jacobian(b).inverse();
    for (int r = 0; r < n; ++r)
      EXPECT_LT((D[static_cast<size_t>(r)] - inv.block<2, 2>(2 * (n - 1), 2 * r)).cwiseAbs().maxCoeff(),
                1e-12 * inv.cwiseAbs().maxCoeff())
          << n << " " << r;
  }
}

TEST(HsltBlockLu, IgnoresEndpointBlocks) {
  // A[0] and C[n-1] are the endpoint columns of Eq. 11, not part of the square J.
  HsltBlocks b = random_blocks(4, 5);
  const double det = HsltBlockLu(b).determinant();
  b.A[0] = Eigen::Matrix2d::Constant(100.0);
  b.C[3] = Eigen::Matrix2d::Constant(-100.0);
  EXPECT_EQ(HsltBlockLu(b).determinant(), det);
}

TEST(HsltBlockLu, ReportsSingularPivot) {
  HsltBlocks b = random_blocks(5, 9);
  b.B[0] << 1, 2, 2, 4;  // singular leading block: no pivoting across blocks
  const HsltBlockLu lu(b);
  EXPECT_FALSE(lu.ok());
  EXPECT_EQ(lu.failed_block(), 0);
  EXPECT_EQ(lu.determinant_sign(), 0);
}

}  // namespace
}  // namespace tb
