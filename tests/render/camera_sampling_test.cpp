// Chi-square tests (validate/chi2) of the camera's sampling against its stated densities:
//   lens points, binned in (phi, s = r^2 / R^2), where the area density p_A maps to
//     p(phi, s) = p_A R^2 / 2   (dA = r dr dphi = R^2/2 ds dphi);
//   directions of generated rays for a fixed lens point, binned in the angles
//     (a, b) = (atan(x / z), atan(y / z)) of the camera-space direction, where
//     dw = sec^2 a sec^2 b / (1 + tan^2 a + tan^2 b)^(3/2) da db,
//   so that the image is a rectangle in (a, b) and no cell straddles its edge.
// Negative control: a lens pdf missing the 1 / (pi R^2) factor is rejected.
#include <gtest/gtest.h>

#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"
#include "lib/core/hash.h"
#include "validate/chi2/sampler_chi2.h"

namespace tb {
namespace {

CameraSetup setup() {
  CameraSetup s;
  s.eye = {0.0, 1.0, 5.0};
  s.target = {0.0, 0.0, 0.0};
  s.vfov_degrees = 80;
  s.width = 48;
  s.height = 36;
  s.lens_radius = 0.5;
  s.focus_distance = 3.0;
  return s;
}

SamplerChi2Result lens_chi2(const ThinLensCamera& cam, bool broken, uint64_t key) {
  const double R = cam.lens_radius();
  SamplerChi2Options o;
  o.samples = 200000;
  o.key = key;
  o.quadrature_tolerance = 1e-9;
  return chi2_test(
      Chi2Domain::rectangle({0, 0}, {2 * kPi, 1}, 31, 31),
      [&](Vec2 u) {
        const Vec3 p = cam.lens_point_camera(u);
        double phi = std::atan2(p.y, p.x);
        if (phi < 0) phi += 2 * kPi;
        return Vec2(phi, (p.x * p.x + p.y * p.y) / (R * R));
      },
      [&](Vec2 q) {
        const double r = R * std::sqrt(q.y);
        const double pdf_area = cam.pdf_lens_area({r * std::cos(q.x), r * std::sin(q.x)});
        return (broken ? pdf_area * cam.lens_area() : pdf_area) * R * R / 2;
      },
      o);
}

TEST(CameraSampling, LensPointsChiSquare) {
  const ThinLensCamera cam(setup());
  const auto r = lens_chi2(cam, false, hash_string("camera_sampling_test.lens"));
  EXPECT_TRUE(r.passed(0.01)) << r.message();
}

TEST(CameraSampling, NegativeControlLensPdfWithoutAreaFactorIsRejected) {
  const ThinLensCamera cam(setup());
  const auto r = lens_chi2(cam, true, hash_string("camera_sampling_test.lens"));
  EXPECT_FALSE(r.passed(0.01)) << r.message();
}

SamplerChi2Result direction_chi2(const Camera& cam, Vec2 lens_u, double plane_distance, uint64_t key) {
  SamplerChi2Options o;
  o.samples = 200000;
  o.key = key;
  o.quadrature_tolerance = 1e-9;
  const Vec3 lens_world = cam.generate_ray({0.5, 0.5}, lens_u).ray.o;
  const PerspectiveProjection& proj = cam.projection();
  const Vec3 lens = proj.to_camera_point(lens_world);
  const double h = plane_distance, tx = proj.tan_half_x(), ty = proj.tan_half_y();
  // The image seen from the lens point: a rectangle in (atan(x/z), atan(y/z)).
  const Vec2 lo(std::atan((-h * tx - lens.x) / h), std::atan((-h * ty - lens.y) / h));
  const Vec2 hi(std::atan((h * tx - lens.x) / h), std::atan((h * ty - lens.y) / h));
  return chi2_test(
      Chi2Domain::rectangle(lo, hi, 41, 31),
      [&](Vec2 u) {
        const Vec3 d = proj.to_camera_dir(cam.generate_ray({u.x * cam.width(), u.y * cam.height()}, lens_u).ray.d);
        return Vec2(std::atan(d.x / d.z), std::atan(d.y / d.z));
      },
      [&](Vec2 ab) {
        const double ta = std::tan(ab.x), tb = std::tan(ab.y);
        const double n2 = 1 + ta * ta + tb * tb;
        const double jacobian = (1 + ta * ta) * (1 + tb * tb) / (n2 * std::sqrt(n2));  // dw / (da db)
        const Vec3 w(ta, tb, 1.0);
        return cam.pdf_we(Ray{lens_world, proj.to_world_dir(w / std::sqrt(n2))}).dir * jacobian;
      },
      o);
}

TEST(CameraSampling, DirectionsChiSquare) {
  // Three configurations at alpha = 0.01 overall (Sidak).
  const double alpha = 1.0 - std::pow(1.0 - 0.01, 1.0 / 3.0);
  const PinholeCamera pin(setup());
  const ThinLensCamera lens(setup());
  const auto a = direction_chi2(pin, {0.5, 0.5}, 1.0, hash_string("camera_sampling_test.dir.pinhole"));
  EXPECT_TRUE(a.passed(alpha)) << a.message();
  const auto b = direction_chi2(lens, {0.5, 0.5}, 3.0, hash_string("camera_sampling_test.dir.lens_centre"));
  EXPECT_TRUE(b.passed(alpha)) << b.message();
  const auto c = direction_chi2(lens, {0.9, 0.2}, 3.0, hash_string("camera_sampling_test.dir.lens_edge"));
  EXPECT_TRUE(c.passed(alpha)) << c.message();
}

}  // namespace
}  // namespace tb
