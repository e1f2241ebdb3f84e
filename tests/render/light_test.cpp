#include <memory>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/geometry/rectangle.h"
#include "lib/geometry/scene.h"
#include "lib/geometry/sphere.h"
#include "lib/light/area_light.h"
#include "lib/light/infinite_lights.h"
#include "lib/light/point_light.h"

namespace tb {
namespace {

TEST(PointLight, InverseSquareAndDelta) {
  const PointLight l(Vec3(0, 0, 2), Rgb(3.0));
  const auto s = l.sample_li(Vec3(0.0), Vec2(0.5));
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ(s->li.r, 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(s->distance, 2.0);
  EXPECT_EQ(s->wi, Vec3(0, 0, 1));
  EXPECT_TRUE(l.is_delta());
  EXPECT_EQ(l.pdf_li(Vec3(0.0), s->wi, nullptr), 0.0);
  EXPECT_DOUBLE_EQ(l.power().g, 12.0 * kPi);
}

TEST(SpotLight, ProfileAndPower) {
  const SpotLight l(Vec3(0.0), Vec3(0, 0, 1), Rgb(1.0), 30.0, 20.0);
  EXPECT_EQ(l.intensity(Vec3(0, 0, 1)).r, 1.0);
  EXPECT_EQ(l.intensity(glm::normalize(Vec3(1, 0, 1))).r, 0.0);  // 45 degrees: outside
  const double c = std::cos(25.0 * kPi / 180.0);
  const double mid = l.intensity(Vec3(std::sqrt(1 - c * c), 0, c)).r;
  EXPECT_GT(mid, 0.0);
  EXPECT_LT(mid, 1.0);
  // Power = integral of I over the sphere, by a fine midpoint rule in cos theta.
  double p = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (i + 0.5) / n;  // cos theta in (0, 1)
    p += l.intensity(Vec3(std::sqrt(1 - z * z), 0, z)).r * 2 * kPi / n;
  }
  EXPECT_NEAR(l.power().r, p, 1e-6 * p);
}

TEST(AreaLight, PowerAndDensitiesAgreeWithSampling) {
  Scene scene;
  const uint32_t id = scene.add(ShapeInstance(std::make_shared<Sphere>(0.5), AffineTransform::translate(Vec3(0, 0, 3))));
  scene.commit();
  const AreaLight l(scene, id, Rgb(2.0), false);
  EXPECT_NEAR(l.area(), 4 * kPi * 0.25, 1e-9);
  EXPECT_NEAR(l.power().r, kPi * 2.0 * 4 * kPi * 0.25, 1e-9);
  Rng rng(3);
  int tested = 0;
  for (int i = 0; i < 1000; ++i) {
    const auto s = l.sample_li(Vec3(0.1, 0.0, 0.0), rng.uniform2());
    ASSERT_TRUE(s);
    // The sampled point seen from the reference point: pdf_li from the hit must equal s->pdf.
    const auto hit = scene.intersect(Ray{Vec3(0.1, 0.0, 0.0), s->wi});
    ASSERT_TRUE(hit);
    if (glm::length(hit->p - s->p_light) > 1e-9) continue;  // the sample is on the far side
    EXPECT_NEAR(l.pdf_li(Vec3(0.1, 0, 0), s->wi, &*hit), s->pdf, 1e-9 * s->pdf);
    ++tested;
    const auto e = l.sample_le(rng.uniform2(), rng.uniform2());
    ASSERT_TRUE(e);
    Hit at = scene.surface_at(id, 0, scene.sample_area(id, Vec2(0.3, 0.7)).hit.uv);
    at.p = e->ray.o;
    at.n = e->n;
    double pp, pd;
    l.pdf_le(at, e->ray.d, &pp, &pd);
    EXPECT_NEAR(pd, e->pdf_dir, 1e-12);
    EXPECT_NEAR(pp, e->pdf_pos, 1e-9);
    EXPECT_GT(glm::dot(e->ray.d, e->n), 0.0);  // one-sided emits to the front only
  }
  EXPECT_GT(tested, 300);
  // One-sided: no radiance from the back.
  EXPECT_EQ(l.le(Vec3(0, 0, 1), Vec3(0, 0, -1)).r, 0.0);
  EXPECT_EQ(l.le(Vec3(0, 0, 1), Vec3(0, 0, 1)).r, 2.0);
}

TEST(InfiniteLights, EmissionDiskCoversTheSceneSphere) {
  ConstantEnvironmentLight env(Rgb(1.0));
  DirectionalLight dir(Vec3(0, 0, -1), Rgb(2.0));
  const SceneSphere s{Vec3(1, 2, 3), 2.0};
  env.set_scene_sphere(s);
  dir.set_scene_sphere(s);
  Rng rng(1);
  for (int i = 0; i < 1000; ++i) {
    for (const Light* l : {static_cast<const Light*>(&env), static_cast<const Light*>(&dir)}) {
      const auto e = l->sample_le(rng.uniform2(), rng.uniform2());
      ASSERT_TRUE(e);
      // The origin lies on the plane tangent to the sphere, behind it, within radius R of the axis.
      const Vec3 to_c = s.center - e->ray.o;
      EXPECT_NEAR(glm::dot(to_c, e->ray.d), s.radius, 1e-9);
      const Vec3 perp = to_c - glm::dot(to_c, e->ray.d) * e->ray.d;
      EXPECT_LE(glm::length(perp), s.radius * (1 + 1e-12));
      EXPECT_DOUBLE_EQ(e->pdf_pos, 1.0 / (kPi * 4.0));
    }
  }
  const auto li = dir.sample_li(Vec3(0.0), Vec2(0.5));
  EXPECT_EQ(li->wi, Vec3(0, 0, 1));
  EXPECT_EQ(li->li.r, 2.0);
}

}  // namespace
}  // namespace tb
