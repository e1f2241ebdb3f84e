// End-to-end check of the importance conventions (docs/camera.md): light tracing from a
// Lambertian emitter of radiance L = 1 filling the view, with sample_wi, splats and
// splat_scale = P / N, must give every pixel the value 1, as the camera-side measurement does
// (weight 1 per primary ray). Compared per pixel with the exact image by the Welch comparison
// (one-sample t-tests, Šidák + Stouffer + sum z^2, alpha = 0.01).
#include <gtest/gtest.h>

#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"
#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "validate/image_compare.h"

namespace tb {
namespace {

CameraSetup setup(double lens_radius) {
  CameraSetup s;
  s.eye = {0.1, -0.2, 3.0};
  s.target = {0.0, 0.0, 0.0};
  s.vfov_degrees = 40;
  s.width = 16;
  s.height = 12;
  s.lens_radius = lens_radius;
  s.focus_distance = 2.5;
  return s;
}

// Emitter: the square [-S, S]^2 in the plane z = 0, normal +z, sampled uniformly by area.
WelchImage light_trace(const Camera& cam, uint64_t seed, int passes, uint64_t paths_per_pass) {
  constexpr double S = 2.5, L = 1.0;
  const double area = 4 * S * S;
  Film film(cam.width(), cam.height());
  for (int pass = 0; pass < passes; ++pass) {
    for (uint64_t i = 0; i < paths_per_pass; ++i) {
      Rng rng = Rng::for_sample(seed, uint64_t(pass), i);
      const Vec3 x(S * (2 * rng.uniform() - 1), S * (2 * rng.uniform() - 1), 0.0);
      const auto s = cam.sample_wi(x, rng.uniform2());
      if (!s || s->importance == 0.0) continue;
      const double cos_x = s->wi.z;  // emitter normal +z
      if (cos_x <= 0) continue;
      // L We cos_x / (pdf_wi(solid angle at x) pdf_x(area)), pdf_x = 1 / area.
      film.splat(s->raster, Rgb(L * s->importance * cos_x / s->pdf * area), i);
    }
    film.end_pass(double(film.pixel_count()) / double(paths_per_pass));
  }
  EXPECT_EQ(film.nonfinite().count(), 0);
  return film.welch();
}

void expect_unit_image(const Camera& cam, uint64_t seed) {
  const WelchImage img = light_trace(cam, seed, 24, 100000);
  WelchImage exact(cam.width(), cam.height());
  for (size_t i = 0; i < exact.pixels(); ++i) exact.add(i, Rgb(1.0));
  const auto r = compare_welch_images(img, exact, 0.01);
  EXPECT_FALSE(r.rejects()) << cam.name() << ": " << r.message();
  EXPECT_NEAR(r.mean_relative_difference, 0.0, 0.01) << cam.name();
}

TEST(CameraLightTracing, PinholeMeasuresUnitRadiance) { expect_unit_image(PinholeCamera(setup(0.0)), 11); }
TEST(CameraLightTracing, ThinLensMeasuresUnitRadiance) { expect_unit_image(ThinLensCamera(setup(0.2)), 12); }

TEST(CameraLightTracing, NegativeControlWrongSplatScaleIsRejected) {
  // Dividing by the lens area twice (a common slip) biases the image by 1/(pi r^2).
  const ThinLensCamera cam(setup(0.2));
  WelchImage img = light_trace(cam, 13, 24, 100000);
  for (size_t i = 0; i < img.pixels(); ++i) {
    img.sum[i] /= cam.lens_area();
    img.sum_sq[i] /= cam.lens_area() * cam.lens_area();
  }
  WelchImage exact(cam.width(), cam.height());
  for (size_t i = 0; i < exact.pixels(); ++i) exact.add(i, Rgb(1.0));
  EXPECT_TRUE(compare_welch_images(img, exact, 0.01).rejects());
}

}  // namespace
}  // namespace tb
