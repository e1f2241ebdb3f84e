// The normalisation of We (docs/camera.md): int_image We cos dw = 1 / A_lens from every lens
// point, by nested Gauss-Kronrod quadrature in spherical coordinates; and the negative control:
// a thin-lens We missing its 1 / (pi r^2) factor integrates to pi r^2, not 1.
#include <gtest/gtest.h>

#include "lib/camera/importance_integral.h"
#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"

namespace tb {
namespace {

CameraSetup setup() {
  CameraSetup s;
  s.eye = {0.3, -1.0, 2.0};
  s.target = {0.0, 0.0, 0.0};
  s.up = {0.0, 0.0, 1.0};
  s.vfov_degrees = 60;
  s.width = 40;
  s.height = 30;
  s.lens_radius = 0.4;
  s.focus_distance = 2.5;
  return s;
}

TEST(CameraImportance, PinholeIntegratesToOne) {
  const PinholeCamera cam(setup());
  const double I = integrate_importance_cos(cam, [&](const Ray& r) { return cam.importance(r); }, {0, 0}, 1.0);
  EXPECT_NEAR(I, 1.0, 1e-9);
}

TEST(CameraImportance, ThinLensIntegratesToOneOverLensArea) {
  const ThinLensCamera cam(setup());
  for (Vec2 p : {Vec2(0, 0), Vec2(0.3, -0.1), Vec2(-0.2, 0.33)}) {
    const double I =
        integrate_importance_cos(cam, [&](const Ray& r) { return cam.importance(r); }, p, cam.focus_distance());
    EXPECT_NEAR(I * cam.lens_area(), 1.0, 1e-9) << p.x << "," << p.y;
  }
}

TEST(CameraImportance, NegativeControlMissingLensAreaFactor) {
  const ThinLensCamera cam(setup());
  const auto broken = [&](const Ray& r) { return cam.importance(r) * cam.lens_area(); };
  const double I = integrate_importance_cos(cam, broken, {0.1, 0.1}, cam.focus_distance());
  EXPECT_GT(std::abs(I * cam.lens_area() - 1.0), 0.1);
  EXPECT_NEAR(I * cam.lens_area(), cam.lens_area(), 1e-9);
}

}  // namespace
}  // namespace tb
