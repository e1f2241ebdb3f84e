#include "lib/differential/hslt_block_lu.h"

#include <cmath>

namespace tb {

HsltBlockLu::HsltBlockLu(const std::vector<Eigen::Matrix2d>& A, const std::vector<Eigen::Matrix2d>& B,
                         const std::vector<Eigen::Matrix2d>& C) {
  const size_t n = B.size();
  l_.assign(n, Eigen::Matrix2d::Zero());
  c_.assign(n, Eigen::Matrix2d::Zero());
  dinv_.assign(n, Eigen::Matrix2d::Zero());
  det_.assign(n, 0.0);
  for (size_t r = 0; r < n; ++r) {
    Eigen::Matrix2d D = B[r];
    if (r > 0) {
      l_[r] = A[r] * dinv_[r - 1];
      D -= l_[r] * C[r - 1];
    }
    if (r + 1 < n) c_[r] = C[r];
    const double det = D(0, 0) * D(1, 1) - D(0, 1) * D(1, 0);
    det_[r] = det;
    if (!(std::abs(det) > 0) || !std::isfinite(det)) {
      if (failed_block_ < 0) failed_block_ = static_cast<int>(r);
      continue;
    }
    Eigen::Matrix2d inv;
    inv << D(1, 1), -D(0, 1), -D(1, 0), D(0, 0);
    dinv_[r] = inv / det;
  }
}

double HsltBlockLu::determinant() const {
  double d = 1.0;
  for (double x : det_) d *= x;
  return d;
}

double HsltBlockLu::log_abs_determinant() const {
  double s = 0.0;
  for (double x : det_) s += std::log(std::abs(x));
  return s;
}

int HsltBlockLu::determinant_sign() const {
  int s = 1;
  for (double x : det_) {
    if (x == 0 || !std::isfinite(x)) return 0;
    if (x < 0) s = -s;
  }
  return s;
}

Eigen::MatrixXd HsltBlockLu::solve(const Eigen::MatrixXd& b) const {
  const auto n = static_cast<Eigen::Index>(dinv_.size());
  Eigen::MatrixXd y = b;
  for (Eigen::Index r = 1; r < n; ++r)
    y.middleRows<2>(2 * r) -= l_[static_cast<size_t>(r)] * y.middleRows<2>(2 * (r - 1));
  Eigen::MatrixXd x(b.rows(), b.cols());
  for (Eigen::Index r = n - 1; r >= 0; --r) {
    Eigen::MatrixXd rhs = y.middleRows<2>(2 * r);
    if (r + 1 < n) rhs -= c_[static_cast<size_t>(r)] * x.middleRows<2>(2 * (r + 1));
    x.middleRows<2>(2 * r) = dinv_[static_cast<size_t>(r)] * rhs;
  }
  return x;
}

Eigen::VectorXd HsltBlockLu::solve(const Eigen::VectorXd& b) const {
  const Eigen::MatrixXd x = solve(Eigen::MatrixXd(b));
  return x.col(0);
}

bool hslt_inverse_last_block_row(const HsltBlocks& b, std::vector<Eigen::Matrix2d>* D) {
  const int n = b.size();
  if (n < 1) return false;
  std::vector<Eigen::Matrix2d> At(static_cast<size_t>(n), Eigen::Matrix2d::Zero()),
      Bt(static_cast<size_t>(n)), Ct(static_cast<size_t>(n), Eigen::Matrix2d::Zero());
  for (int r = 0; r < n; ++r) {
    const auto ur = static_cast<size_t>(r);
    Bt[ur] = b.B[ur].transpose();
    if (r > 0) At[ur] = b.C[ur - 1].transpose();
    if (r + 1 < n) Ct[ur] = b.A[ur + 1].transpose();
  }
  const HsltBlockLu lu(At, Bt, Ct);
  if (!lu.ok()) return false;
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(2 * n, 2);
  e.bottomRows<2>().setIdentity();
  const Eigen::MatrixXd z = lu.solve(e);
  D->resize(static_cast<size_t>(n));
  for (int r = 0; r < n; ++r) (*D)[static_cast<size_t>(r)] = z.middleRows<2>(2 * r).transpose();
  return z.allFinite();
}

}  // namespace tb
