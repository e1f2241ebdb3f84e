#include "validate/differential/bound_broken.h"

#include "lib/differential/variance_bound.h"
#include "lib/material/half_vector.h"

namespace tb::bound {

// Copy of variance_ratio_derivative_free (lib/differential/variance_bound.cpp) with p(i_1) = 1.
double ratio_eq21_without_camera_density(const World& world, const Vec2&, const Eigen::VectorXd&,
                                         const differential::ForwardPath& path) {
  double r = 1.0, compression = 1.0;
  for (size_t j = 0; j < path.wi.size(); ++j) {
    const Hit& h = path.vertices[j];
    const Vec3 wo = -(j == 0 ? path.camera_dir : path.wi[j - 1]);
    const Vec3& wi = path.wi[j];
    if (path.flags[j] & bsdf_flags::kTransmission) {
      const double eta_b = world.surface(h.shape_id).bsdf->eta();
      const double eta = glm::dot(wo, h.n) > 0 ? eta_b : 1.0 / eta_b;
      Vec3 m = generalized_half_vector(wi, wo, eta, 1.0);
      if (glm::dot(m, wo) < 0) m = -m;
      compression *= differential::refraction_solid_angle_ratio(wo, wi, m, eta);
    }
    if (!(path.flags[j] & bsdf_flags::kDelta)) r += 1.0 / (path.pdf[j] * compression);  // BROKEN: no p(i_1)
  }
  return r;
}

}  // namespace tb::bound
