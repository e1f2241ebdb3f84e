#include "lib/differential/variance_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

double subpath_variance_ratio(const World& world, std::span<const PathVertex> camera, int t, int s,
                              bool mis_reduction) {
  const size_t n = t < 0 ? camera.size() : std::min(camera.size(), static_cast<size_t>(t));
  if (n < 3) return 1.0;
  // The last bounce whose sampled direction enters the sum (index into camera).
  size_t last = n - 2;
  if (s == 0 && mis_reduction) --last;
  if (last < 1) return 1.0;
  const Camera& cam = world.camera();
  const Vec3 d0 = direction(camera[0], camera[1]);
  const double camera_density = cam.pdf_we(Ray{camera[0].hit.p, d0}).dir * static_cast<double>(cam.pixel_count());
  if (!(camera_density > 0.0)) return 1.0;
  double r = 1.0;            // the i = 1 term
  double compression = 1.0;  // |di_i / di_1| on linearized geometry
  for (size_t j = 1; j <= last; ++j) {
    const PathVertex& v = camera[j];
    const PathVertex& next = camera[j + 1];
    const Vec3 wo = direction(v, camera[j - 1]);
    const Vec3 wi = direction(v, next);
    const Vec3 ng = v.geometric_normal();
    if (v.bsdf && glm::dot(wo, ng) * glm::dot(wi, ng) < 0.0) {  // a refraction
      const double eta_b = v.bsdf->eta();
      const double eta = glm::dot(wo, v.hit.n) > 0 ? eta_b : 1.0 / eta_b;  // eta_wi_side / eta_wo_side
      Vec3 m = generalized_half_vector(wi, wo, eta, 1.0);
      if (glm::dot(m, wo) < 0) m = -m;
      compression *= refraction_solid_angle_ratio(wo, wi, m, eta);
    }
    if (v.delta) continue;  // Dirac lobes contribute nothing
    // Solid-angle pdf of the direction sampled at v: the area density at `next` converted back.
    double pdf_w = next.pdf_fwd;
    if (!next.infinite) {
      const Vec3 dv = next.hit.p - v.hit.p;
      const double cos_next = std::abs(glm::dot(next.geometric_normal(), glm::normalize(dv)));
      pdf_w = cos_next > 0.0 ? next.pdf_fwd * glm::dot(dv, dv) / cos_next : 0.0;
    }
    // A non-Dirac direction of zero density cannot be bounded: r~ = infinity (no downweighting).
    if (!(pdf_w > 0.0 && compression > 0.0)) return std::numeric_limits<double>::infinity();
    r += camera_density / (pdf_w * compression);
  }
  return std::isnan(r) ? std::numeric_limits<double>::infinity() : r;
}

}  // namespace tb::differential
