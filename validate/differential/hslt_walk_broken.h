// Deliberately broken copies of the predictor-corrector walk (lib/differential/hslt_walk.h),
// for the negative controls of the checks differential.hslt.walk.*. Nothing here is used by lib/.
#pragma once

#include <Eigen/Dense>

#include "lib/differential/hslt_walk.h"
#include "lib/geometry/scene.h"

namespace tb {

// A corrector that does not project (Sec. 5.1's ray casting left out): every interior vertex is
// left at its predicted point on the tangent plane, with the (u, v) of that point in the tangent
// chart and the old tangents and normals. The vertices leave the curved surfaces.
HsltProjectFn hslt_tangent_plane_projection_broken();
HsltWalkResult hslt_walk_without_projection(const HsltPath& start, const Eigen::VectorXd& target,
                                            const HsltWalkOptions& options);

// The walk with the Eq. 11 blocks of hslt_blocks_sign_error (C of the middle block row negated):
// a wrong Newton matrix (identical to the real one for k = 2, which has no C block inside J).
HsltWalkResult hslt_walk_sign_error(const Scene& scene, const HsltPath& start, const Eigen::VectorXd& target,
                                    const HsltWalkOptions& options);

// A walk that stops after the first predictor-corrector step and declares convergence (the first
// order prediction of Sec. 5.2 taken as the solution): not reversible beyond first order.
HsltWalkResult hslt_walk_single_step_broken(const Scene& scene, const HsltPath& start, const Eigen::VectorXd& target,
                                            const HsltWalkOptions& options);

}  // namespace tb
