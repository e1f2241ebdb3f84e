// The geometry shared by the perspective cameras: a look-at frame, the vertical field of view,
// the image resolution, and the affine map between raster coordinates and the image plane at
// unit distance in front of the lens.
//
// Conventions (docs/camera.md):
//   camera space  x right, y up, z forward (z is the lens normal); world = eye + x r + y u + z f.
//   raster space  x in [0, width) to the right, y in [0, height) downwards; pixel (i, j) covers
//                 [i, i+1) x [j, j+1), so the raster area of a pixel is 1.
//   image plane   the plane z = 1 in camera space; raster (x, y) maps to
//                 (px, py) = ((2x/W - 1) tan_x, (1 - 2y/H) tan_y), tan_y = tan(vfov / 2),
//                 tan_x = tan_y W / H (square pixels). Its area is A = 4 tan_x tan_y.
#pragma once

#include <cstdint>

#include "lib/core/math.h"

namespace tb {

struct CameraSetup {
  Vec3 eye{0.0, 0.0, 0.0};
  Vec3 target{0.0, 0.0, 1.0};
  Vec3 up{0.0, 1.0, 0.0};
  double vfov_degrees = 45.0;  // full vertical field of view
  int width = 64;
  int height = 64;
  double lens_radius = 0.0;     // thin lens only: aperture radius (world units)
  double focus_distance = 1.0;  // thin lens only: distance of the plane in focus along the axis
};

class PerspectiveProjection {
 public:
  // Throws std::invalid_argument on a degenerate frame (eye == target, up parallel to the
  // view direction), a field of view outside (0, 180) degrees or an empty resolution.
  explicit PerspectiveProjection(const CameraSetup& setup);

  int width() const { return width_; }
  int height() const { return height_; }
  int64_t pixel_count() const { return static_cast<int64_t>(width_) * height_; }
  double tan_half_x() const { return tan_x_; }
  double tan_half_y() const { return tan_y_; }
  // Area of the image rectangle on the plane z = 1 (camera space): A = 4 tan_x tan_y.
  double plane_area() const { return 4.0 * tan_x_ * tan_y_; }

  const Vec3& eye() const { return eye_; }
  const Vec3& right() const { return right_; }
  const Vec3& up() const { return up_; }
  const Vec3& forward() const { return forward_; }

  Vec3 to_world_dir(const Vec3& c) const { return c.x * right_ + c.y * up_ + c.z * forward_; }
  Vec3 to_camera_dir(const Vec3& w) const { return {glm::dot(w, right_), glm::dot(w, up_), glm::dot(w, forward_)}; }
  Vec3 to_world_point(const Vec3& c) const { return eye_ + to_world_dir(c); }
  Vec3 to_camera_point(const Vec3& w) const { return to_camera_dir(w - eye_); }

  // Raster position -> point (px, py) on the plane z = 1, and back (affine, exact inverses up
  // to rounding).
  Vec2 plane_from_raster(const Vec2& raster) const {
    return {(2.0 * raster.x / width_ - 1.0) * tan_x_, (1.0 - 2.0 * raster.y / height_) * tan_y_};
  }
  Vec2 raster_from_plane(const Vec2& plane) const {
    return {0.5 * width_ * (plane.x / tan_x_ + 1.0), 0.5 * height_ * (1.0 - plane.y / tan_y_)};
  }
  // Half-open raster rectangle [0, W) x [0, H).
  bool inside(const Vec2& raster) const {
    return raster.x >= 0.0 && raster.x < width_ && raster.y >= 0.0 && raster.y < height_;
  }

 private:
  Vec3 eye_, right_, up_, forward_;
  double tan_x_ = 1, tan_y_ = 1;
  int width_ = 1, height_ = 1;
};

}  // namespace tb
