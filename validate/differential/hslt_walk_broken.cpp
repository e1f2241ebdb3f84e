#include "validate/differential/hslt_walk_broken.h"

#include "validate/differential/hslt_broken.h"

namespace tb {

HsltProjectFn hslt_tangent_plane_projection_broken() {
  return [](const HsltPath& current, const std::vector<Vec3>& predicted, bool, HsltPath* out) {
    *out = current;
    for (int i = 1; i < current.segments(); ++i) {
      HsltVertex& v = out->vertices[static_cast<size_t>(i)];
      const Vec3 d = predicted[static_cast<size_t>(i)] - v.p;
      // (u, v) of the predicted point in the tangent chart: dp/du du + dp/dv dv = d (least squares).
      Eigen::Matrix2d G;
      G << glm::dot(v.dpdu, v.dpdu), glm::dot(v.dpdu, v.dpdv), glm::dot(v.dpdu, v.dpdv), glm::dot(v.dpdv, v.dpdv);
      const Eigen::Vector2d duv = G.inverse() * Eigen::Vector2d(glm::dot(v.dpdu, d), glm::dot(v.dpdv, d));
      v.p = predicted[static_cast<size_t>(i)];  // fault: no ray cast back onto the surface
      v.uv += Vec2(duv[0], duv[1]);
    }
    return HsltWalkStatus::kConverged;
  };
}

HsltWalkResult hslt_walk_without_projection(const HsltPath& start, const Eigen::VectorXd& target,
                                            const HsltWalkOptions& options) {
  return hslt_walk(start, target, options, hslt_constraint_blocks, hslt_tangent_plane_projection_broken());
}

HsltWalkResult hslt_walk_sign_error(const Scene& scene, const HsltPath& start, const Eigen::VectorXd& target,
                                    const HsltWalkOptions& options) {
  return hslt_walk(start, target, options, hslt_blocks_sign_error, hslt_ray_cast_projection(scene, options.visibility));
}

HsltWalkResult hslt_walk_single_step_broken(const Scene& scene, const HsltPath& start, const Eigen::VectorXd& target,
                                            const HsltWalkOptions& options) {
  HsltWalkOptions o = options;
  o.max_iterations = 1;
  HsltWalkResult r = hslt_walk(scene, start, target, o);
  if (r.status == HsltWalkStatus::kMaxIterations) r.status = HsltWalkStatus::kConverged;  // fault
  return r;
}

}  // namespace tb
