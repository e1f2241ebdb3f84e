// Block LU factorisation of the block-tridiagonal constraint Jacobian of Eq. 11 (Kaplanyan,
// Hanika, Dachsbacher 2014, Sec. 7: "a stripped-down version of LU decomposition", no full
// inversion), in O(k) time and memory for k - 1 blocks of 2 x 2.
//
// With diagonal blocks B_r, sub-diagonal A_r (row r, column r - 1) and super-diagonal C_r
// (row r, column r + 1), r = 0 .. n-1 (the block Thomas algorithm; Golub & Van Loan, Matrix
// Computations, Sec. 4.5.1):
//   D_0 = B_0,   L_r = A_r D_{r-1}^{-1},   D_r = B_r - L_r C_{r-1},
//   J = L U,  L = unit lower block bidiagonal (L_r),  U = upper block bidiagonal (D_r, C_r),
//   det J = prod_r det D_r,
//   solve J x = b:  y_0 = b_0, y_r = b_r - L_r y_{r-1};  x_{n-1} = D_{n-1}^{-1} y_{n-1},
//                   x_r = D_r^{-1} (y_r - C_r x_{r+1}).
// There is no pivoting between blocks; a singular pivot block D_r (a singular leading principal
// block minor) is reported by ok() == false even where J itself is regular. Within a block the
// 2 x 2 inverse is explicit.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "lib/differential/hslt_constraints.h"

namespace tb {

class HsltBlockLu {
 public:
  // A[0] and C[n-1] are ignored (the endpoint columns of Eq. 11 are not part of the square J).
  HsltBlockLu(const std::vector<Eigen::Matrix2d>& A, const std::vector<Eigen::Matrix2d>& B,
              const std::vector<Eigen::Matrix2d>& C);
  explicit HsltBlockLu(const HsltBlocks& b) : HsltBlockLu(b.A, b.B, b.C) {}

  bool ok() const { return failed_block_ < 0; }
  int failed_block() const { return failed_block_; }  // first singular pivot block, -1 if none
  int size() const { return static_cast<int>(dinv_.size()); }

  double determinant() const;          // prod det D_r (may over/underflow for long paths)
  double log_abs_determinant() const;  // sum log |det D_r|
  int determinant_sign() const;        // sign of the determinant (0 when singular)

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;  // requires ok()
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;  // 2n x m right-hand sides

 private:
  std::vector<Eigen::Matrix2d> l_, c_, dinv_;
  std::vector<double> det_;
  int failed_block_ = -1;
};

// The blocks D_i of Eq. 9 (Kaplanyan 2014): the last block row of J^{-1} (how x_{k-1}, the
// vertex next to the sensor, moves per change of h_i^perp), D[r] = (J^{-1})_{n-1, r}, without the
// inverse: the transposed system J^T Z = [0 .. 0; I] by the same block LU (blocks of J^T:
// diagonal B_r^T, sub-diagonal C_{r-1}^T, super-diagonal A_{r+1}^T), D[r] = Z_r^T. O(k).
// Returns false on a singular pivot.
bool hslt_inverse_last_block_row(const HsltBlocks& b, std::vector<Eigen::Matrix2d>* D);

}  // namespace tb
