// Object-to-world affine transforms x -> M x + t, with rounding-error bounds (pbrt-v3 Sec. 3.9.3).
#pragma once

#include <glm/gtc/matrix_transform.hpp>

#include "lib/core/math.h"
#include "lib/geometry/spawn.h"

namespace tb {

class AffineTransform {
 public:
  AffineTransform() = default;
  AffineTransform(const Mat3& m, const Vec3& t) : m_(m), m_inv_(glm::inverse(m)), t_(t) {}

  static AffineTransform translate(const Vec3& t) { return {Mat3(1.0), t}; }
  static AffineTransform scale(const Vec3& s) { return {Mat3(glm::dvec3(s.x, 0, 0), Vec3(0, s.y, 0), Vec3(0, 0, s.z)), Vec3(0.0)}; }
  static AffineTransform scale(double s) { return scale(Vec3(s)); }
  // Rotation by `radians` about `axis` (right-handed).
  static AffineTransform rotate(double radians, const Vec3& axis) {
    return {Mat3(glm::rotate(glm::dmat4(1.0), radians, glm::normalize(axis))), Vec3(0.0)};
  }
  // (*this)(other(x)).
  AffineTransform operator*(const AffineTransform& o) const { return {m_ * o.m_, m_ * o.t_ + t_}; }

  Vec3 point(const Vec3& p) const { return m_ * p + t_; }
  Vec3 vector(const Vec3& v) const { return m_ * v; }
  Vec3 inverse_point(const Vec3& p) const { return m_inv_ * (p - t_); }
  Vec3 inverse_vector(const Vec3& v) const { return m_inv_ * v; }

  const Mat3& linear() const { return m_; }
  const Mat3& inverse_linear() const { return m_inv_; }
  const Vec3& translation() const { return t_; }
  double determinant() const { return glm::determinant(m_); }

  // Bound on the world-space error of point(p) for an object-space point p carrying the error
  // box p_err: propagated error plus the rounding of the transform itself (pbrt-v3 Eq. 3.11).
  Vec3 point_error(const Vec3& p, const Vec3& p_err) const {
    const Mat3 am = abs_matrix(m_);
    return am * p_err + gamma_d(3) * (am * glm::abs(p) + glm::abs(t_));
  }
  // World-space size of the error made when a world point pw is mapped back to object space
  // (inverse_point) and the result pushed forward again: covers the origin of a spawned ray
  // as seen by the object-space intersector.
  Vec3 round_trip_error(const Vec3& pw) const {
    const Vec3 e_obj = gamma_d(3) * (abs_matrix(m_inv_) * (glm::abs(pw) + glm::abs(t_)));
    return abs_matrix(m_) * e_obj;
  }

 private:
  static Mat3 abs_matrix(const Mat3& a) { return Mat3(glm::abs(a[0]), glm::abs(a[1]), glm::abs(a[2])); }
  Mat3 m_{1.0};
  Mat3 m_inv_{1.0};
  Vec3 t_{0.0};
};

}  // namespace tb
