// Deliberately broken copies of the half-vector constraint code (lib/differential/hslt_*.h),
// for the negative controls of the registered checks differential.hslt.*. Each wraps or copies
// the real routine with one fault; nothing here is used by lib/.
#pragma once

#include <Eigen/Dense>

#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/differential/hslt_measure.h"

namespace tb {

// The real blocks with the sign of one block flipped: C of the middle block row.
HsltBlocks hslt_blocks_sign_error(const HsltPath& path);
// A copy of hslt_constraint_blocks without the derivative of the shading frame (the dn/du,
// dn/dv term of B_i).
HsltBlocks hslt_blocks_without_frame_derivative(const HsltPath& path);
// Eq. 5 without the projection factor 1 / |<h_i, n_i>| (solid angle of h instead of dh^perp).
double hslt_measure_product_without_projection(const HsltMeasureTerms& t);
// Block LU determinant without the Schur complement (D_r = B_r): prod det B_r.
double hslt_determinant_without_schur(const HsltBlocks& b);
// H^perp with the refractive indices of the two sides swapped at every vertex (App. A's eta
// inverted).
Eigen::VectorXd hslt_constraints_swapped_eta(const HsltPath& path);

}  // namespace tb
