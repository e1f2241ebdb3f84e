// Unit tests of the exact-image code of the integrator checks (validate/render/): the closed
// forms against independent quadrature, the pixel quadrature, the geometry of the test worlds
// (the camera sees only what the closed form assumes), and the comparison helpers.
#include <cmath>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <gtest/gtest.h>

#include "lib/core/frame.h"
#include "validate/render/analytic_worlds.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

TEST(AnalyticWorlds, FurnaceRadianceIsTheTruncatedNeumannSeries) {
  const Rgb rho(0.8, 0.5, 0.0), le(1.0, 2.0, 3.0);
  EXPECT_EQ(furnace_radiance(rho, le, 0), le);
  const Rgb two = furnace_radiance(rho, le, 2);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(two[c], le[c] * (1 + rho[c] + rho[c] * rho[c]), 1e-15);
  const Rgb inf = furnace_radiance(rho, le, -1), many = furnace_radiance(rho, le, 400);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(inf[c], le[c] / (1 - rho[c]), 1e-15);
    EXPECT_NEAR(many[c], inf[c], 1e-12 * inf[c]);
  }
}

// E = int_cone L cos(theta_n) dw over the cone the sphere subtends, by adaptive Gauss-Kronrod in
// coordinates about the direction to the centre (independent of the closed form's derivation).
double sphere_irradiance_quadrature(double L, double r, const Vec3& c, const Vec3& p, const Vec3& n) {
  const Vec3 d = c - p;
  const double dist = glm::length(d);
  const Frame fr = Frame::from_z(d / dist);
  const double cos_max = std::sqrt(1.0 - (r / dist) * (r / dist));
  using boost::math::quadrature::gauss_kronrod;
  return gauss_kronrod<double, 31>::integrate(
      [&](double phi) {
        return gauss_kronrod<double, 31>::integrate(
            [&](double cos_t) {
              const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
              const Vec3 w = fr.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t));
              return L * std::max(0.0, glm::dot(w, n));
            },
            cos_max, 1.0, 10, 1e-13);
      },
      0.0, 2.0 * kPi, 10, 1e-13);
}

TEST(AnalyticWorlds, SphereIrradianceMatchesQuadrature) {
  const Vec3 n(0, 0, 1);
  for (const Vec3& p : {Vec3(0.0), Vec3(0.3, -0.2, 0.0), Vec3(-0.5, 0.5, 0.0)}) {
    const Vec3 c(1.3, 0.2, 0.5);
    const double closed = sphere_irradiance(2.0, 0.3, c, p, n);
    const double quad = sphere_irradiance_quadrature(2.0, 0.3, c, p, n);
    EXPECT_NEAR(closed, quad, 1e-10 * quad) << p.x << " " << p.y;
  }
  // Partly below the horizon: the closed form does not hold and refuses.
  EXPECT_THROW(sphere_irradiance(1.0, 0.5, Vec3(1.0, 0.0, 0.2), Vec3(0.0), n), std::invalid_argument);
}

TEST(AnalyticWorlds, PointIrradiance) {
  // I cos / d^2 with d = 2, cos = 0.5 (light at 60 degrees from the normal).
  const Vec3 light(2.0 * std::sin(kPi / 3), 0.0, 2.0 * std::cos(kPi / 3));
  EXPECT_NEAR(point_irradiance(3.0, light, Vec3(0.0), Vec3(0, 0, 1)), 3.0 * 0.5 / 4.0, 1e-15);
  EXPECT_EQ(point_irradiance(3.0, Vec3(0, 0, -1), Vec3(0.0), Vec3(0, 0, 1)), 0.0);
}

TEST(AnalyticWorlds, PixelAveragesIntegratePolynomialsExactly) {
  // Average of x^3 y^2 over [i, i+1) x [j, j+1): ((i+1)^4 - i^4)/4 * ((j+1)^3 - j^3)/3.
  for (int order : {5, 10, 20}) {
    const auto avg = pixel_averages(3, 2, [](const Vec2& r) { return Rgb(r.x * r.x * r.x * r.y * r.y, 1.0, r.x); }, order);
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) {
        const Rgb v = avg[size_t(j) * 3 + size_t(i)];
        const double ex = (std::pow(i + 1, 4) - std::pow(i, 4)) / 4.0 * (std::pow(j + 1, 3) - std::pow(j, 3)) / 3.0;
        EXPECT_NEAR(v.r, ex, 1e-12 * ex);
        EXPECT_NEAR(v.g, 1.0, 1e-14);
        EXPECT_NEAR(v.b, i + 0.5, 1e-14);
      }
  }
  EXPECT_THROW(pixel_averages(1, 1, [](const Vec2&) { return Rgb(0.0); }, 7), std::invalid_argument);
}

// Every primary ray through the pixel corners and centres hits the shape `name` (and nothing else
// is in view), the assumption of the closed forms.
void expect_sees_only(const AnalyticScene& s, const std::string& name) {
  const Camera& cam = s.world->camera();
  for (int y = 0; y <= 2 * cam.height(); ++y)
    for (int x = 0; x <= 2 * cam.width(); ++x) {
      const Vec2 raster(std::min(0.5 * x, cam.width() - 1e-9), std::min(0.5 * y, cam.height() - 1e-9));
      const auto hit = s.world->geometry().intersect(cam.generate_ray(raster, Vec2(0.5)).ray);
      ASSERT_TRUE(hit.has_value()) << s.name << " raster " << raster.x << " " << raster.y;
      EXPECT_EQ(s.world->surface(hit->shape_id).name, name) << s.name;
    }
}

TEST(AnalyticWorlds, CamerasSeeOnlyWhatTheClosedFormsAssume) {
  expect_sees_only(make_furnace({}), "furnace");
  expect_sees_only(make_sky_plane({}), "plane");
  OneBounceParams p;
  expect_sees_only(make_one_bounce(p), "plane");
  p.light = OneBounceLight::kPoint;
  expect_sees_only(make_one_bounce(p), "plane");
}

TEST(AnalyticWorlds, ExactImages) {
  FurnaceParams fp;
  fp.resolution = 3;
  const AnalyticScene f = make_furnace(fp);
  ASSERT_EQ(f.exact.size(), 9u);
  EXPECT_EQ(f.exact[4], furnace_radiance(fp.albedo, fp.emission, fp.max_depth));
  const AnalyticScene sky = make_sky_plane({});
  EXPECT_EQ(sky.exact[0], SkyPlaneParams{}.albedo * SkyPlaneParams{}.sky);

  // One bounce: the pixel average is close to the value at the pixel centre (smooth integrand)
  // and the image is symmetric under the mirror y -> -y only if the light is: here it is not,
  // so just check the centre value and that the pixel nearer the light is brighter.
  OneBounceParams p;
  p.resolution = 8;
  const AnalyticScene s = make_one_bounce(p);
  const Camera& cam = s.world->camera();
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      const Ray ray = cam.generate_ray(Vec2(x + 0.5, y + 0.5), Vec2(0.5)).ray;
      const Vec3 pt = ray.o + (-ray.o.z / ray.d.z) * ray.d;
      const double e = sphere_irradiance(p.emission.r, p.light_radius, p.light_position, pt, Vec3(0, 0, 1));
      EXPECT_NEAR(s.exact[size_t(y) * 8 + size_t(x)].r, p.albedo.r / kPi * e, 0.02 * p.albedo.r / kPi * e);
    }
  // The light is at +x: camera right is world +x or -x depending on the look-at frame; compare
  // the two pixels whose plane points are nearest and farthest from the light.
  const Ray r0 = cam.generate_ray(Vec2(0.5, 3.5), Vec2(0.5)).ray, r7 = cam.generate_ray(Vec2(7.5, 3.5), Vec2(0.5)).ray;
  const double x0 = (r0.o + (-r0.o.z / r0.d.z) * r0.d).x, x7 = (r7.o + (-r7.o.z / r7.d.z) * r7.d).x;
  const double v0 = s.exact[3 * 8 + 0].r, v7 = s.exact[3 * 8 + 7].r;
  EXPECT_EQ(x0 > x7, v0 > v7);

  const WelchImage w = exact_welch_image(3, 3, f.exact);
  EXPECT_EQ(w.count[0], 1);
  EXPECT_EQ(w.mean(0), f.exact[0]);
  EXPECT_EQ(w.variance(0), Rgb(0.0));
}

TEST(RenderCompare, DeterministicChannelsAreReconciledAndSkipped) {
  WelchImage img(2, 1), exact = exact_welch_image(2, 1, {Rgb(1.0, 2.0, 3.0), Rgb(1.0)});
  // Pixel 0: red deterministic up to rounding, green noisy, blue deterministic but wrong.
  img.add(0, Rgb(1.0 + 1e-15, 2.1, 3.5));
  img.add(0, Rgb(1.0 + 1e-15, 1.9, 3.5));
  img.add(1, Rgb(0.9));
  img.add(1, Rgb(1.1));
  const int64_t n = reconcile_deterministic(img, exact);
  EXPECT_EQ(n, 1);
  EXPECT_EQ(img.mean(0).r, exact.mean(0).r);
  const ChannelCompare c = compare_channels(img, exact, 0.01);
  EXPECT_TRUE(c.rejects());  // blue: zero variance, 3.5 vs 3
  EXPECT_EQ(c.channel[2].zero_variance_mismatch, 1);
  EXPECT_EQ(c.channel[0].tested, 1);  // pixel 1 only; pixel 0 red skipped as identical
  EXPECT_EQ(c.channel[1].tested, 2);
}

TEST(RenderCompare, ChannelsAreTestedSeparately) {
  // Two pixels with identical statistics in all channels: each channel comparison sees only its
  // own channel (the others are skipped as identical), and a bias in green alone is found in green.
  WelchImage a(2, 1), b(2, 1);
  for (int k = 0; k < 64; ++k) {
    const double noise = (k % 2 ? 1.0 : -1.0) * (1.0 + 0.01 * k);
    for (size_t i = 0; i < 2; ++i) {
      a.add(i, Rgb(10 + noise, 11.5 + noise, 10 + noise));
      b.add(i, Rgb(10 - noise, 10 - noise, 10 - noise));
    }
  }
  const ChannelCompare c = compare_channels(a, b, 0.01);
  EXPECT_EQ(c.channel[0].tested, 2);
  EXPECT_FALSE(c.channel[0].rejects());
  EXPECT_TRUE(c.channel[1].rejects());
  EXPECT_FALSE(c.channel[2].rejects());
  EXPECT_EQ(c.worst_channel(), 1);
}

}  // namespace
}  // namespace tb

namespace tb {
namespace {

TEST(RenderCompare, ImageSumAddsMeansAndVariances) {
  WelchImage img(2, 1);
  for (double v : {1.0, 3.0}) img.add(0, Rgb(v));       // mean 2, variance 2
  for (double v : {10.0, 14.0}) img.add(1, Rgb(v));     // mean 12, variance 8
  const WelchImage s = image_sum(img);
  ASSERT_EQ(s.pixels(), 1u);
  EXPECT_EQ(s.count[0], 2);
  EXPECT_NEAR(s.mean(0).r, 14.0, 1e-12);
  // Variance of the sum of the two means: 2/2 + 8/2 = 5 = Welch variance / n with n = 2.
  EXPECT_NEAR(s.variance(0).r / 2.0, 5.0, 1e-12);
}

}  // namespace
}  // namespace tb
