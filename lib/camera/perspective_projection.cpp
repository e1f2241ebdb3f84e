#include "lib/camera/perspective_projection.h"

#include <stdexcept>

#include <fmt/format.h>

namespace tb {

PerspectiveProjection::PerspectiveProjection(const CameraSetup& s) : eye_(s.eye), width_(s.width), height_(s.height) {
  if (s.width <= 0 || s.height <= 0)
    throw std::invalid_argument(fmt::format("camera: resolution {}x{} is empty", s.width, s.height));
  if (!(s.vfov_degrees > 0.0 && s.vfov_degrees < 180.0))
    throw std::invalid_argument(fmt::format("camera: vertical field of view {} deg outside (0, 180)", s.vfov_degrees));
  const Vec3 view = s.target - s.eye;
  const double len = glm::length(view);
  if (!(len > 0.0) || !is_finite(view)) throw std::invalid_argument("camera: eye and target coincide");
  forward_ = view / len;
  // Right-handed look-at: right = forward x up, up' = right x forward.
  const Vec3 r = glm::cross(forward_, s.up);
  const double rl = glm::length(r);
  // A relative tolerance: |f x up| / |up| below ~1e-12 means up is parallel to the view direction.
  if (!(rl > 1e-12 * glm::length(s.up))) throw std::invalid_argument("camera: up is parallel to the view direction");
  right_ = r / rl;
  up_ = glm::cross(right_, forward_);
  tan_y_ = std::tan(0.5 * s.vfov_degrees * kPi / 180.0);
  tan_x_ = tan_y_ * static_cast<double>(s.width) / static_cast<double>(s.height);
}

}  // namespace tb
