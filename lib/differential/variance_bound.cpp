#include "lib/differential/variance_bound.h"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "lib/material/half_vector.h"

namespace tb::differential {

VarianceRatio variance_ratio(const EndpointCovariance& c) {
  // Sec. 6.3: project onto the plane of widest spread of Sigma (its two leading eigenvectors).
  const Eigen::SelfAdjointEigenSolver<Mat4> es(c.sigma);
  VarianceRatio out;
  out.V.row(0) = es.eigenvectors().col(3).transpose();
  out.V.row(1) = es.eigenvectors().col(2).transpose();
  return variance_ratio(c, out.V);  // Eq. 20
}

VarianceRatio variance_ratio(const EndpointCovariance& c, const Eigen::Matrix<double, 2, 4>& V) {
  VarianceRatio out;
  out.V = V;
  out.det_full = (V * c.sigma * V.transpose()).determinant();
  out.det_camera = (V * c.sigma_camera * V.transpose()).determinant();
  out.r = std::sqrt(out.det_full / out.det_camera);
  return out;
}

Eigen::Matrix<double, 2, 4> position_plane() {
  Eigen::Matrix<double, 2, 4> V = Eigen::Matrix<double, 2, 4>::Zero();
  V(0, 0) = V(1, 1) = 1.0;
  return V;
}

Eigen::Matrix<double, 2, 4> direction_plane() {
  Eigen::Matrix<double, 2, 4> V = Eigen::Matrix<double, 2, 4>::Zero();
  V(0, 2) = V(1, 3) = 1.0;
  return V;
}

double refraction_solid_angle_ratio(const Vec3& wo, const Vec3& wi, const Vec3& m, double eta) {
  return std::abs(glm::dot(wo, m)) / (eta * eta * std::abs(glm::dot(wi, m)));
}

DerivativeFreeRatio variance_ratio_derivative_free(const World& world, const ForwardPath& path) {
  const Camera& cam = world.camera();
  DerivativeFreeRatio out;
  // Raster positions are sampled uniformly per pixel: density P * pdf_dir per unit raster area.
  out.camera_density = cam.pdf_we(Ray{path.eye, path.camera_dir}).dir * static_cast<double>(cam.pixel_count());
  double compression = 1.0;  // |di_i / di_1| on linearized geometry
  out.r = 1.0;               // the i = 1 term, p(i_1) / p(i_1)
  for (size_t j = 0; j < path.wi.size(); ++j) {
    const Hit& h = path.vertices[j];
    const Vec3 wo = -(j == 0 ? path.camera_dir : path.wi[j - 1]);
    const Vec3& wi = path.wi[j];
    if (path.flags[j] & bsdf_flags::kTransmission) {
      const double eta_b = world.surface(h.shape_id).bsdf->eta();
      const double eta = glm::dot(wo, h.n) > 0 ? eta_b : 1.0 / eta_b;  // eta_wi_side / eta_wo_side
      Vec3 m = generalized_half_vector(wi, wo, eta, 1.0);
      if (glm::dot(m, wo) < 0) m = -m;
      compression *= refraction_solid_angle_ratio(wo, wi, m, eta);
    }
    double term = 0.0;
    if (!(path.flags[j] & bsdf_flags::kDelta)) term = out.camera_density / (path.pdf[j] * compression);
    out.terms.push_back(term);
    out.r += term;
  }
  return out;
}

}  // namespace tb::differential
