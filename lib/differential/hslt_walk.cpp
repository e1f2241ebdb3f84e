#include "lib/differential/hslt_walk.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tb {
namespace {

constexpr double kHuge = 1e300;

double finite_or(double x, double fallback) { return std::isfinite(x) ? x : fallback; }

// The blocks of J^T (diagonal B_r^T, sub-diagonal C_{r-1}^T, super-diagonal A_{r+1}^T), as in
// hslt_inverse_last_block_row.
HsltBlockLu transposed_lu(const HsltBlocks& b) {
  const int n = b.size();
  std::vector<Eigen::Matrix2d> At(static_cast<size_t>(n), Eigen::Matrix2d::Zero()), Bt(static_cast<size_t>(n)),
      Ct(static_cast<size_t>(n), Eigen::Matrix2d::Zero());
  for (int r = 0; r < n; ++r) {
    const auto ur = static_cast<size_t>(r);
    Bt[ur] = b.B[ur].transpose();
    if (r > 0) At[ur] = b.C[ur - 1].transpose();
    if (r + 1 < n) Ct[ur] = b.A[ur + 1].transpose();
  }
  return HsltBlockLu(At, Bt, Ct);
}

// |J|_1: the largest absolute column sum of the square Eq. 11 matrix (column block c meets B_c,
// A_{c+1} and C_{c-1}).
double one_norm(const HsltBlocks& b) {
  const int n = b.size();
  double best = 0;
  for (int c = 0; c < n; ++c) {
    const auto uc = static_cast<size_t>(c);
    Eigen::Vector2d s = b.B[uc].cwiseAbs().colwise().sum().transpose();
    if (c + 1 < n) s += b.A[uc + 1].cwiseAbs().colwise().sum().transpose();
    if (c > 0) s += b.C[uc - 1].cwiseAbs().colwise().sum().transpose();
    best = std::max(best, s.maxCoeff());
  }
  return best;
}

double path_residual(const HsltPath& path, const Eigen::VectorXd& target, Eigen::VectorXd* F) {
  *F = hslt_constraints(path) - target;
  return F->norm();
}

// The hit of the surface of `orig` on the ray from `origin` towards `toward`.
// With visibility: the first hit of the ray must be on that surface (another shape in front:
// kOccluded). Without (paths connected through other shapes, the constraints being geometric):
// of the hits of that surface along the ray, the one nearest to `toward` (a segment may cross
// its own shape, e.g. a chord inside a concave mirror, so the first hit is not always meant).
HsltWalkStatus cast_to_surface(const Scene& scene, const Vec3& origin, const Vec3& toward, const HsltVertex& orig,
                               bool visibility, Hit* out) {
  const Vec3 d = toward - origin;
  const double len = glm::length(d);
  if (!(len > 0) || !std::isfinite(len)) return HsltWalkStatus::kHitDifferentSurface;
  // From the exact previous vertex with a small t_min, as the traced paths (hslt_paths.cpp): an
  // offset origin would tilt the segment and bias h^perp.
  Ray ray{origin, d / len, 1e-5 * std::max(1.0, glm::length(origin)), kInfinity};
  bool blocked = false, found = false;
  double best = kInfinity;
  for (int s = 0; s < 64; ++s) {
    const std::optional<Hit> hit = scene.intersect(ray);
    if (!hit) break;
    if (hit->shape_id == orig.shape_id) {
      if (visibility) {
        if (blocked) return HsltWalkStatus::kOccluded;
        if (hit->prim_id != orig.prim_id) return HsltWalkStatus::kHitDifferentSurface;
        *out = *hit;
        return HsltWalkStatus::kConverged;
      }
      const double gap = std::abs(hit->t - len);
      if (gap < best) {
        best = gap;
        *out = *hit;
        found = true;
      }
      if (hit->t > len) break;  // later hits are farther from `toward`
    }
    blocked = true;
    ray.t_min = hit->t + 1e-9 * std::max(1.0, hit->t);
  }
  if (!found || out->prim_id != orig.prim_id) return HsltWalkStatus::kHitDifferentSurface;
  return HsltWalkStatus::kConverged;
}

}  // namespace

const char* hslt_walk_status_name(HsltWalkStatus s) {
  switch (s) {
    case HsltWalkStatus::kConverged: return "converged";
    case HsltWalkStatus::kDiverged: return "diverged";
    case HsltWalkStatus::kHitDifferentSurface: return "hit_different_surface";
    case HsltWalkStatus::kOccluded: return "occluded";
    case HsltWalkStatus::kMaxIterations: return "max_iterations";
    case HsltWalkStatus::kSingularJacobian: return "singular_jacobian";
  }
  return "unknown";
}

HsltProjectFn hslt_ray_cast_projection(const Scene& scene, bool visibility) {
  return [&scene, visibility](const HsltPath& current, const std::vector<Vec3>& predicted, bool from_start,
                              HsltPath* out) {
    *out = current;
    const int k = current.segments();
    // Sec. 5.1: from x_0 project x_1, x_2, ..; from x_k project x_{k-1}, x_{k-2}, .. ; each ray
    // leaves the vertex projected just before (Fig. 8: "from the point of the previous vertex").
    for (int step = 1; step < k; ++step) {
      const int i = from_start ? step : k - step;
      const int prev = from_start ? i - 1 : i + 1;
      const HsltVertex& orig = current.vertices[static_cast<size_t>(i)];
      Hit hit;
      const HsltWalkStatus st = cast_to_surface(scene, out->vertices[static_cast<size_t>(prev)].p,
                                                predicted[static_cast<size_t>(i)], orig, visibility, &hit);
      if (st != HsltWalkStatus::kConverged) return st;
      out->vertices[static_cast<size_t>(i)] = moved_hslt_vertex(orig, hit);
    }
    // The segment to the fixed endpoint on the other side.
    if (visibility && k >= 2) {
      const int a = from_start ? k - 1 : 1, e = from_start ? k : 0;
      const Vec3 pa = out->vertices[static_cast<size_t>(a)].p, pe = out->vertices[static_cast<size_t>(e)].p;
      const double len = glm::length(pe - pa);
      const Ray ray{pa, (pe - pa) / len, 1e-5 * std::max(1.0, glm::length(pa)), len * (1 - 1e-6)};
      if (scene.occluded(ray)) return HsltWalkStatus::kOccluded;
    }
    return HsltWalkStatus::kConverged;
  };
}

double hslt_condition_estimate(const HsltBlocks& b) {
  const int n = b.size();
  if (n < 1) return kHuge;
  const HsltBlockLu lu(b), lut = transposed_lu(b);
  if (!lu.ok() || !lut.ok()) return std::numeric_limits<double>::infinity();
  // Hager (1984) / Higham (1988): maximise |J^{-1} x|_1 over |x|_1 = 1 by a few sign iterations.
  const Eigen::Index m = 2 * n;
  Eigen::VectorXd x = Eigen::VectorXd::Constant(m, 1.0 / static_cast<double>(m));
  double est = 0;
  Eigen::Index last = -1;
  for (int it = 0; it < 5; ++it) {
    const Eigen::VectorXd y = lu.solve(x);
    est = std::max(est, y.lpNorm<1>());
    Eigen::VectorXd xi(m);
    for (Eigen::Index i = 0; i < m; ++i) xi[i] = y[i] >= 0 ? 1.0 : -1.0;
    const Eigen::VectorXd z = lut.solve(xi);
    Eigen::Index j = 0;
    const double zmax = z.cwiseAbs().maxCoeff(&j);
    if (zmax <= z.dot(x) || j == last) break;
    last = j;
    x.setZero();
    x[j] = 1.0;
  }
  const double c = one_norm(b) * est;
  return std::isfinite(c) ? c : std::numeric_limits<double>::infinity();
}

double hslt_projection_side_ratio(const HsltBlocks& b) {
  const int n = b.size();
  if (n < 2) return 1.0;
  const HsltBlockLu lu(b);
  if (!lu.ok()) return 1.0;
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(2 * n, 2);
  e.bottomRows<2>().setIdentity();
  const Eigen::MatrixXd z = lu.solve(e);  // column block k-1 of J^{-1}
  const double first = std::abs(Eigen::Matrix2d(z.topRows<2>()).determinant());
  const double last = std::abs(Eigen::Matrix2d(z.bottomRows<2>()).determinant());
  const double r = first / last;
  if (std::isnan(r)) return 1.0;
  return std::clamp(r, 1e-300, kHuge);
}

HsltWalkResult hslt_walk(const HsltPath& start, const Eigen::VectorXd& target, const HsltWalkOptions& options,
                         const HsltBlocksFn& blocks_fn, const HsltProjectFn& project) {
  HsltWalkResult res;
  res.path = start;
  const int k = start.segments();
  Eigen::VectorXd F;
  const bool sized = target.size() == 2 * static_cast<Eigen::Index>(std::max(0, start.interior_count()));
  double r = sized ? path_residual(start, target, &F) : kHuge;
  if (!std::isfinite(r) || !sized) {
    res.status = HsltWalkStatus::kDiverged;
    res.residual = kHuge;
    res.residuals.push_back(kHuge);
    return res;
  }
  res.residual = r;
  res.residuals.push_back(r);
  if (k < 2) {  // no interior vertex: nothing to move
    res.status = HsltWalkStatus::kConverged;
    return res;
  }
  std::vector<Vec3> predicted(start.vertices.size());
  for (int it = 0;; ++it) {
    if (r < options.tolerance) {
      res.status = HsltWalkStatus::kConverged;
      return res;
    }
    if (it >= options.max_iterations) {
      res.status = HsltWalkStatus::kMaxIterations;
      return res;
    }
    // Predictor (Sec. 5.1, Sec. 7): Delta X = -J^{-1} F by the block LU of Eq. 11.
    const HsltBlocks b = blocks_fn(res.path);
    const double cond = hslt_condition_estimate(b);
    res.condition_estimate = finite_or(cond, kHuge);
    if (it == 0) {
      res.side_ratio = hslt_projection_side_ratio(b);
      res.from_start = options.side == HsltProjectionSide::kFromStart ||
                       (options.side == HsltProjectionSide::kHeuristic && !(res.side_ratio < 1.0));
    }
    const HsltBlockLu lu(b);
    if (!lu.ok() || !(cond <= options.max_condition)) {
      res.status = HsltWalkStatus::kSingularJacobian;
      return res;
    }
    const Eigen::VectorXd delta = -lu.solve(F);
    if (!delta.allFinite()) {
      res.status = HsltWalkStatus::kSingularJacobian;
      return res;
    }
    // Corrector with step-size halving.
    double lambda = 1.0;
    bool accepted = false, projected_once = false;
    HsltWalkStatus first_failure = HsltWalkStatus::kDiverged;
    HsltPath cand;
    Eigen::VectorXd Fc;
    double rc = 0;
    for (int h = 0; h <= options.max_halvings; ++h, lambda *= 0.5) {
      if (h > 0) ++res.halvings;
      for (int i = 1; i < k; ++i) {
        const HsltVertex& v = res.path.vertices[static_cast<size_t>(i)];
        const Eigen::Index c = 2 * (i - 1);
        predicted[static_cast<size_t>(i)] = v.p + lambda * (v.dpdu * delta[c] + v.dpdv * delta[c + 1]);
      }
      const HsltWalkStatus st = project(res.path, predicted, res.from_start, &cand);
      if (st != HsltWalkStatus::kConverged) {
        if (!projected_once && first_failure == HsltWalkStatus::kDiverged) first_failure = st;
        continue;
      }
      projected_once = true;
      rc = path_residual(cand, target, &Fc);
      if (std::isfinite(rc) && rc < r) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      res.status = projected_once ? HsltWalkStatus::kDiverged : first_failure;
      return res;
    }
    res.path = std::move(cand);
    F = Fc;
    r = rc;
    res.residual = r;
    res.residuals.push_back(r);
    res.step_sizes.push_back(lambda);
    ++res.iterations;
  }
}

HsltWalkResult hslt_walk(const Scene& scene, const HsltPath& start, const Eigen::VectorXd& target,
                         const HsltWalkOptions& options) {
  return hslt_walk(start, target, options, hslt_constraint_blocks, hslt_ray_cast_projection(scene, options.visibility));
}

double hslt_max_vertex_distance(const HsltPath& a, const HsltPath& b) {
  double d = 0;
  const size_t n = std::min(a.vertices.size(), b.vertices.size());
  for (size_t i = 0; i < n; ++i) d = std::max(d, glm::length(a.vertices[i].p - b.vertices[i].p));
  if (a.vertices.size() != b.vertices.size()) return kHuge;
  return finite_or(d, kHuge);
}

HsltReversibility hslt_walk_reversible(const HsltPath& start, const HsltPath& forward, const HsltWalkOptions& options,
                                       const HsltBlocksFn& blocks, const HsltProjectFn& project, double tolerance) {
  HsltReversibility rev;
  rev.back = hslt_walk(forward, hslt_constraints(start), options, blocks, project);
  rev.distance = hslt_max_vertex_distance(rev.back.path, start);
  rev.reversible = rev.back.status == HsltWalkStatus::kConverged && rev.distance < tolerance;
  return rev;
}

}  // namespace tb
