// The predictor-corrector walk in half-vector space (Kaplanyan, Hanika, Dachsbacher 2014,
// Sec. 5.1 "Obtaining Path Vertices", Sec. 7; the Newton walk of manifold exploration, Jakob and
// Marschner 2012): given a path X = (x_0 .. x_k) and target constraint values h*, move the
// interior vertices x_1 .. x_{k-1} (the endpoints stay fixed, App. A) until H^perp(X') = h*.
//
// One iteration at the current path X_n with F = H^perp(X_n) - h*:
//   predictor  Delta(u,v) = -J^{-1} F by the block LU solve of Eq. 11 (Sec. 7, no inverse);
//              the predicted vertex x'_i = x_i + lambda (dp/du Delta u_i + dp/dv Delta v_i) lies
//              on the tangent plane of x_i (Sec. 5.2: "sampling the point x' on the tangent plane");
//   corrector  ray casting (Sec. 5.1, Fig. 8): from the fixed endpoint, a ray from the already
//              projected previous vertex towards the predicted x'_i; its hit on the surface of
//              x_i is the new x_i. From x_0: x_1, x_2, .. ; from x_k: x_{k-1}, x_{k-2}, .. .
//   step size  lambda = 1, 1/2, 1/4, .. until |F| decreases (a failed projection also halves).
// Stops when |F|_2 < tolerance (converged), or with a failure status (never NaN).
//
// Projection side (Sec. 5.1, Table 2): |dx_1/dx_{k-1}| = |T_1| |T_{k-1}|^{-1}, the first-order
// movement of x_1 per movement of x_{k-1} at fixed H^perp. T_r = dx_r/dx_k = -(J^{-1})_{r,k-1}
// C_{k-1} (Eq. 6), so the ratio is |det (J^{-1})_{1,k-1}| / |det (J^{-1})_{k-1,k-1}| and C_{k-1}
// cancels: one block LU solve with the two columns of the last block. If it is below one the
// walk projects from x_k (the paper's sensor side: x_{k-1}, x_{k-2}, ..), otherwise from x_0
// (the paper's light side: x_1, x_2, ..). The side is chosen once, at the start path.
//
// With visibility on, the projected x_i is the first hit of the ray; off (the sampled paths of
// the checks are connected through other shapes), the hit of the surface of x_i along the ray
// nearest to the predicted point.
//
// Statuses. kHitDifferentSurface: the ray misses the surface of x_i, or meets it on another
// primitive (another triangle of a mesh: another (u, v) chart and, on the cube, another normal,
// i.e. another subspace of Sec. 5.2). kOccluded (only with visibility on): another shape lies
// between the previous vertex and the projected x_i. These two are reported only when no step
// size lambda >= 2^-max_halvings gives a projection. kDiverged: no such step size decreases |F|
// (or F is not finite). kSingularJacobian: the block LU has a singular pivot, or the 1-norm
// condition estimate exceeds max_condition. kMaxIterations: |F| >= tolerance after
// max_iterations.
//
// Reversibility (Sec. 5.2): the walk from X' back to h^perp(X) must return to X (same vertex
// positions within a tolerance); hslt_walk_reversible tests it.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/geometry/scene.h"

namespace tb {

enum class HsltWalkStatus {
  kConverged,
  kDiverged,
  kHitDifferentSurface,
  kOccluded,
  kMaxIterations,
  kSingularJacobian,
};
inline constexpr int kHsltWalkStatusCount = 6;
const char* hslt_walk_status_name(HsltWalkStatus s);

// Which endpoint the corrector projects from (Sec. 5.1, Table 2).
enum class HsltProjectionSide { kFromStart, kFromEnd, kHeuristic };

struct HsltWalkOptions {
  double tolerance = 1e-11;     // converged when |H^perp(X) - h*|_2 < tolerance
  int max_iterations = 20;      // predictor-corrector iterations
  int max_halvings = 10;        // step sizes lambda = 1 .. 2^-max_halvings
  double max_condition = 1e12;  // 1-norm condition estimate above this: kSingularJacobian
  HsltProjectionSide side = HsltProjectionSide::kHeuristic;
  bool visibility = true;       // report a shape between consecutive vertices as kOccluded
};

struct HsltWalkResult {
  HsltWalkStatus status = HsltWalkStatus::kDiverged;
  HsltPath path;                       // the last accepted path (the start path if none)
  int iterations = 0;                  // accepted predictor-corrector steps
  int halvings = 0;                    // step-size halvings over the whole walk
  double residual = 0;                 // |H^perp(path) - h*|_2, finite
  std::vector<double> residuals;       // |F| before the first and after every accepted step
  std::vector<double> step_sizes;      // lambda of every accepted step
  double condition_estimate = 0;       // 1-norm condition estimate of J at the last path (finite)
  bool from_start = true;              // projection side used
  double side_ratio = 1;               // |det T_1| / |det T_{k-1}| (Table 2 heuristic), finite
};

// The square Jacobian blocks of Eq. 11 at a path (hslt_constraint_blocks in production).
using HsltBlocksFn = std::function<HsltBlocks(const HsltPath&)>;
// The corrector: the path with the interior vertices moved to the surface points found from the
// predicted positions `predicted` (index = vertex index; endpoints unused), projecting from x_0
// (from_start) or from x_k. Returns kConverged on success (the status value means "projected"),
// kHitDifferentSurface or kOccluded otherwise.
using HsltProjectFn =
    std::function<HsltWalkStatus(const HsltPath& current, const std::vector<Vec3>& predicted, bool from_start, HsltPath* out)>;

// The ray-casting corrector of Sec. 5.1 on `scene` (must outlive the returned function).
HsltProjectFn hslt_ray_cast_projection(const Scene& scene, bool visibility);

// The walk with explicit Jacobian and corrector (the checks substitute broken copies).
HsltWalkResult hslt_walk(const HsltPath& start, const Eigen::VectorXd& target, const HsltWalkOptions& options,
                         const HsltBlocksFn& blocks, const HsltProjectFn& project);
// The production walk: Eq. 11 blocks and ray casting on `scene`.
HsltWalkResult hslt_walk(const Scene& scene, const HsltPath& start, const Eigen::VectorXd& target,
                         const HsltWalkOptions& options = {});

// Estimate of the 1-norm condition number |J|_1 |J^{-1}|_1 of the square Eq. 11 Jacobian (Hager's
// estimator, Higham's variant, with block LU solves of J and J^T: O(k)); +inf when the LU fails.
double hslt_condition_estimate(const HsltBlocks& b);
// |det T_1| / |det T_{k-1}| of Sec. 5.1 (ratio of the first and last blocks of J^{-1} E_last);
// 1 for k = 2; +inf / 0 clamped to [1e-300, 1e300]; 1 when the LU fails.
double hslt_projection_side_ratio(const HsltBlocks& b);

// Max distance between the interior vertices of two paths with the same vertex count.
double hslt_max_vertex_distance(const HsltPath& a, const HsltPath& b);

struct HsltReversibility {
  HsltWalkResult back;   // the walk from the forward result back to h^perp(start)
  bool reversible = false;
  double distance = 0;   // max vertex distance to the start path (finite; +inf mapped to 1e300)
};
// Walks back from `forward` (a converged walk from `start`) to h^perp(start) with the same
// options, Jacobian and corrector; reversible when it converges to vertices within `tolerance`
// (scene units) of the start path (Sec. 5.2).
HsltReversibility hslt_walk_reversible(const HsltPath& start, const HsltPath& forward, const HsltWalkOptions& options,
                                       const HsltBlocksFn& blocks, const HsltProjectFn& project, double tolerance);

}  // namespace tb
