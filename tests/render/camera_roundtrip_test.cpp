// Cameras: raster -> ray -> raster round trips to 1e-9, ray differentials, the consistency of
// We, pdf_we and generate_ray's weight, and sample_wi against the raster mapping.
#include <gtest/gtest.h>

#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"
#include "lib/core/rng.h"

namespace tb {
namespace {

std::vector<std::unique_ptr<Camera>> test_cameras() {
  std::vector<std::unique_ptr<Camera>> cams;
  CameraSetup a;
  a.eye = {1.0, 2.0, -3.0};
  a.target = {0.2, 0.5, 1.0};
  a.up = {0.1, 1.0, 0.0};
  a.vfov_degrees = 50;
  a.width = 64;
  a.height = 48;
  cams.push_back(std::make_unique<PinholeCamera>(a));
  CameraSetup b = a;
  b.vfov_degrees = 100;
  b.width = 17;
  b.height = 31;
  cams.push_back(std::make_unique<PinholeCamera>(b));
  CameraSetup c = a;
  c.lens_radius = 0.25;
  c.focus_distance = 4.0;
  cams.push_back(std::make_unique<ThinLensCamera>(c));
  CameraSetup d = b;
  d.lens_radius = 1.5;
  d.focus_distance = 0.7;
  cams.push_back(std::make_unique<ThinLensCamera>(d));
  return cams;
}

TEST(CameraRoundTrip, RasterRayRaster) {
  Rng rng(7);
  for (const auto& cam : test_cameras()) {
    for (int i = 0; i < 2000; ++i) {
      const Vec2 raster(rng.uniform() * cam->width(), rng.uniform() * cam->height());
      const Vec2 lens_u = rng.uniform2();
      const CameraRay cr = cam->generate_ray(raster, lens_u);
      EXPECT_NEAR(glm::length(cr.ray.d), 1.0, 1e-14);
      const auto hit = cam->raster_from_ray(cr.ray);
      ASSERT_TRUE(hit) << cam->name() << " raster " << raster.x << "," << raster.y;
      EXPECT_NEAR(hit->raster.x, raster.x, 1e-9) << cam->name();
      EXPECT_NEAR(hit->raster.y, raster.y, 1e-9) << cam->name();
      EXPECT_LT(glm::length(hit->lens_point - cr.ray.o), 1e-9);
      if (!cam->lens_is_delta()) {
        EXPECT_NEAR(hit->lens_uniforms.x, lens_u.x, 1e-9) << cam->name();
        EXPECT_NEAR(hit->lens_uniforms.y, lens_u.y, 1e-9) << cam->name();
      }
      // A point further along the ray maps to the same raster position.
      const auto via_point = cam->raster_from_point(cr.ray.at(3.7), cr.ray.o);
      ASSERT_TRUE(via_point);
      EXPECT_NEAR(via_point->raster.x, raster.x, 1e-9);
      EXPECT_NEAR(via_point->raster.y, raster.y, 1e-9);
    }
  }
}

TEST(CameraRoundTrip, DifferentialsAreOnePixelOver) {
  Rng rng(8);
  for (const auto& cam : test_cameras()) {
    for (int i = 0; i < 200; ++i) {
      const Vec2 raster(rng.uniform() * (cam->width() - 1), rng.uniform() * (cam->height() - 1));
      const CameraRay cr = cam->generate_ray(raster, rng.uniform2());
      ASSERT_TRUE(cr.ray.has_differentials);
      const auto hx = cam->raster_from_ray(Ray{cr.ray.rx_o, cr.ray.rx_d});
      const auto hy = cam->raster_from_ray(Ray{cr.ray.ry_o, cr.ray.ry_d});
      ASSERT_TRUE(hx && hy);
      EXPECT_NEAR(hx->raster.x, raster.x + 1, 1e-9);
      EXPECT_NEAR(hx->raster.y, raster.y, 1e-9);
      EXPECT_NEAR(hy->raster.x, raster.x, 1e-9);
      EXPECT_NEAR(hy->raster.y, raster.y + 1, 1e-9);
    }
  }
}

TEST(CameraRoundTrip, RasterFromDirectionOfPinhole) {
  const auto cams = test_cameras();
  const Camera& cam = *cams[0];
  const Vec2 raster(10.25, 33.5);
  const CameraRay cr = cam.generate_ray(raster, Vec2(0.5));
  const auto hit = cam.raster_from_direction(5.0 * cr.ray.d);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->raster.x, raster.x, 1e-9);
  EXPECT_NEAR(hit->raster.y, raster.y, 1e-9);
  EXPECT_FALSE(cam.raster_from_direction(-cr.ray.d));  // behind the camera
}

TEST(CameraRoundTrip, ImportanceOverPdfsIsTheRayWeight) {
  // We cos / (pdf_pos pdf_dir) = 1: sampling the raster uniformly is importance sampling We.
  Rng rng(9);
  for (const auto& cam : test_cameras()) {
    for (int i = 0; i < 500; ++i) {
      const CameraRay cr =
          cam->generate_ray(Vec2(rng.uniform() * cam->width(), rng.uniform() * cam->height()), rng.uniform2());
      const double cos_t = glm::dot(cr.ray.d, cam->projection().forward());
      const CameraPdf pdf = cam->pdf_we(cr.ray);
      EXPECT_EQ(pdf.pos_is_delta, cam->lens_is_delta());
      EXPECT_NEAR(cam->importance(cr.ray) * cos_t / (pdf.pos * pdf.dir), cr.weight, 1e-12) << cam->name();
    }
  }
}

TEST(CameraRoundTrip, OutsideTheImageHasNoImportance) {
  for (const auto& cam : test_cameras()) {
    const Vec3 side = cam->projection().right();
    const Ray r{cam->projection().eye(), side + 0.01 * cam->projection().forward()};
    EXPECT_EQ(cam->importance(r), 0.0);
    EXPECT_EQ(cam->pdf_we(r).dir, 0.0);
    EXPECT_FALSE(cam->raster_from_ray(r));
  }
}

TEST(CameraRoundTrip, SampleWiConnectsToTheRasterPosition) {
  Rng rng(10);
  for (const auto& cam : test_cameras()) {
    int found = 0;
    for (int i = 0; i < 500; ++i) {
      // A scene point in front of the camera: along a random primary ray.
      const CameraRay cr =
          cam->generate_ray(Vec2(rng.uniform() * cam->width(), rng.uniform() * cam->height()), rng.uniform2());
      const Vec3 ref = cr.ray.at(2.0 + 5.0 * rng.uniform());
      const Vec2 lens_u = rng.uniform2();
      const auto s = cam->sample_wi(ref, lens_u);
      if (!s) continue;
      ++found;
      EXPECT_NEAR(glm::length(s->lens_point + -s->wi * 0.0 - ref), s->distance, 1e-12);
      const Ray out{s->lens_point, -s->wi};
      EXPECT_DOUBLE_EQ(s->importance, cam->importance(out));
      const auto hit = cam->raster_from_ray(out);
      ASSERT_TRUE(hit);
      EXPECT_NEAR(hit->raster.x, s->raster.x, 1e-12);
      // Solid-angle pdf at ref = pdf_pos dist^2 / cos at the lens.
      const double cos_lens = glm::dot(cam->projection().forward(), -s->wi);
      EXPECT_NEAR(s->pdf, cam->pdf_we(out).pos * s->distance * s->distance / cos_lens, 1e-12 * s->pdf);
      EXPECT_EQ(s->delta, cam->lens_is_delta());
    }
    EXPECT_GT(found, 100) << cam->name();
  }
}

TEST(CameraRoundTrip, InvalidSetupsThrow) {
  CameraSetup s;
  s.target = s.eye;
  EXPECT_THROW(PinholeCamera{s}, std::invalid_argument);
  s = {};
  s.up = {0, 0, 1};
  EXPECT_THROW(PinholeCamera{s}, std::invalid_argument);
  s = {};
  s.vfov_degrees = 180;
  EXPECT_THROW(PinholeCamera{s}, std::invalid_argument);
  s = {};
  EXPECT_THROW(ThinLensCamera{s}, std::invalid_argument);  // radius 0
  EXPECT_THROW(make_camera("fisheye", s), std::invalid_argument);
}

}  // namespace
}  // namespace tb
