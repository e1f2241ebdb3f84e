// The Embree scene: hits agree with closed-form intersections, triangle hits are refined in
// double, occlusion and shadow rays, OBJ loading, transforms and orientation.
#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/geometry/cylinder.h"
#include "lib/geometry/disk.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/obj_loader.h"
#include "lib/geometry/paraboloid.h"
#include "lib/geometry/polynomial_roots.h"
#include "lib/geometry/reference_shapes.h"
#include "lib/geometry/scene.h"
#include "lib/geometry/sphere.h"
#include "lib/geometry/spawn.h"
#include "lib/geometry/torus.h"

namespace tb {
namespace {

Ray make_ray(const Vec3& o, const Vec3& d) {
  Ray r;
  r.o = o;
  r.d = d;
  return r;
}

TEST(GeometryScene, SphereHitIsExact) {
  Scene scene;
  scene.add(ShapeInstance(std::make_shared<Sphere>(2.0), AffineTransform::translate(Vec3(1, 2, 3))));
  scene.commit();
  const auto h = scene.intersect(make_ray(Vec3(1, 2, -10), Vec3(0, 0, 1)));
  ASSERT_TRUE(h);
  EXPECT_DOUBLE_EQ(h->t, 11.0);
  EXPECT_NEAR(h->p.z, 1.0, 1e-15);
  EXPECT_NEAR(h->ng.z, -1.0, 1e-15);
  EXPECT_EQ(h->shape_id, 0u);
  EXPECT_FALSE(scene.intersect(make_ray(Vec3(1, 2, -10), Vec3(0, 0, 1)), 10.5));
  EXPECT_FALSE(scene.intersect(make_ray(Vec3(4, 2, -10), Vec3(0, 0, 1))));
}

TEST(GeometryScene, HitsLieOnTheSurfaceToDoubleRounding) {
  Rng rng(11);
  for (const ReferenceShape& s : reference_analytic_shapes()) {
    Scene scene;
    scene.add(s.instance);
    scene.commit();
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
      // Rays from a sphere around the shape towards random surface points.
      const Hit target = s.instance.surface_at(rng.uniform2());
      const Vec3 dir = glm::normalize(Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5));
      const Ray r = make_ray(target.p + 3.0 * s.scale * dir, -dir);
      const auto h = scene.intersect(r);
      ASSERT_TRUE(h) << s.name << " ray " << i;
      ++hits;
      // The hit is on the ray and on the surface.
      const Vec3 on_ray = r.at(h->t);
      EXPECT_LT(glm::length(on_ray - h->p), 1e-12 * s.scale) << s.name;
      const Vec3 p_obj = s.instance.to_world().inverse_point(h->p);
      const Hit again = s.instance.surface_at(s.instance.shape().project(p_obj));
      EXPECT_LT(glm::length(again.p - h->p), 1e-13 * s.scale) << s.name;
      // Nothing is hit before the returned hit: t is at most that of the known target point,
      // up to the conditioning of the hit, which moves by ~eps |o| / cos^2 at grazing angles.
      const double cos_t = std::abs(glm::dot(dir, target.ng));
      EXPECT_LE(h->t, 3.0 * s.scale * (1 + 1e-13 / (cos_t * cos_t))) << s.name << " uv " << target.uv.x << " " << target.uv.y
                                                   << " cos " << glm::dot(dir, target.ng);
    }
    EXPECT_EQ(hits, 2000);
  }
}

TEST(GeometryScene, TriangleHitsAreRefinedInDouble) {
  Scene scene;
  scene.add(make_quad_mesh(1.0, 1.0));
  scene.commit();
  const Ray r = make_ray(Vec3(0.1, 0.3, 1.0), glm::normalize(Vec3(0.1, 0.2, -1.0)));
  const auto h = scene.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->p.z, 0.0);
  EXPECT_LT(glm::length(r.at(h->t) - h->p), 1e-15);
  EXPECT_EQ(h->ng, Vec3(0, 0, 1));
}

TEST(GeometryScene, OcclusionAndShadowRays) {
  Scene scene;
  const uint32_t floor = scene.add(make_quad_mesh(5.0, 5.0));
  scene.add(ShapeInstance(std::make_shared<Sphere>(0.5), AffineTransform::translate(Vec3(0, 0, 2))));
  scene.commit();
  const auto below_hit = scene.intersect(make_ray(Vec3(0.1, -0.1, 1.0), Vec3(0, 0, -1)));
  ASSERT_TRUE(below_hit);
  ASSERT_EQ(below_hit->shape_id, floor);
  const Hit below = *below_hit;
  // Straight up through the sphere: occluded; sideways: free.
  EXPECT_TRUE(scene.occluded(spawn_ray_to(below, Vec3(below.p.x, below.p.y, 5.0))));
  EXPECT_FALSE(scene.occluded(spawn_ray_to(below, Vec3(below.p.x + 3, below.p.y, 1.0))));
  // A point on the sphere is visible from directly beneath, and its own surface does not
  // occlude the shadow ray (both ends offset).
  const auto top = scene.intersect(make_ray(Vec3(below.p.x, below.p.y, 0.5), Vec3(0, 0, 1)));
  ASSERT_TRUE(top);
  EXPECT_FALSE(scene.occluded(spawn_ray_to(below, *top)));
}

TEST(GeometryScene, ObjLoadingWithNormals) {
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vn 0 0 1\nvn 0.6 0 0.8\nvn 0 0 1\nvn 0 0.6 0.8\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "f 1/1/1 2/2/2 3/3/3 4/4/4\n";
  const TriangleMesh m = load_obj_from_string(obj, AffineTransform::translate(Vec3(0, 0, 1)));
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_TRUE(m.has_normals());
  EXPECT_NEAR(m.area(), 1.0, 1e-15);
  const Hit h = m.surface_at(0, Vec2(0.5, 0.0));  // midway along the edge v0-v1
  EXPECT_NEAR(h.p.z, 1.0, 1e-15);
  EXPECT_NEAR(glm::length(h.n), 1.0, 1e-15);
  EXPECT_GT(h.n.x, 0.2);
  EXPECT_GT(glm::length(h.dndu), 0.1);
  EXPECT_NEAR(m.texcoord(0, Vec2(0.5, 0.0)).x, 0.5, 1e-7);
  EXPECT_THROW(load_obj("/nonexistent/file.obj"), std::runtime_error);
}

TEST(GeometryScene, ReflectionKeepsOutwardNormals) {
  const ShapeInstance s(std::make_shared<Sphere>(1.0), AffineTransform::scale(Vec3(-1, 1, 1)));
  const Hit h = s.surface_at(Vec2(0.3, 0.6));
  EXPECT_GT(glm::dot(h.ng, h.p), 0.99);
  const ShapeInstance f(std::make_shared<Sphere>(1.0), AffineTransform(), true);
  EXPECT_LT(glm::dot(f.surface_at(Vec2(0.3, 0.6)).ng, f.surface_at(Vec2(0.3, 0.6)).p), -0.99);
}

TEST(GeometryScene, TorusQuarticFindsAllFourCrossings) {
  const Torus t(2.0, 0.5);
  // Along the x axis from far away: crossings at x = -2.5, -1.5, 1.5, 2.5.
  auto h = t.intersect(Vec3(-10, 0, 0), Vec3(1, 0, 0), 0, kInfinity);
  ASSERT_TRUE(h);
  EXPECT_NEAR(*h, 7.5, 1e-13);
  h = t.intersect(Vec3(-10, 0, 0), Vec3(1, 0, 0), 7.6, kInfinity);
  ASSERT_TRUE(h);
  EXPECT_NEAR(*h, 8.5, 1e-13);
  h = t.intersect(Vec3(0, 0, 0), Vec3(1, 0, 0), 0, kInfinity);
  ASSERT_TRUE(h);
  EXPECT_NEAR(*h, 1.5, 1e-14);
  EXPECT_FALSE(t.intersect(Vec3(0, 0, 5), Vec3(0, 0, -1), 0, kInfinity));  // through the hole
  const std::vector<double> c = {24, -50, 35, -10, 1};  // (t-1)(t-2)(t-3)(t-4)
  const auto roots = polynomial_roots(c, 0.0, 10.0);
  ASSERT_EQ(roots.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(roots[static_cast<size_t>(i)], i + 1.0, 1e-14);
}

TEST(GeometryScene, ParaboloidAndCylinderAndDisk) {
  const Paraboloid p(1.0, 1.0);  // z = x^2 + y^2
  auto h = p.intersect(Vec3(0.5, 0, 5), Vec3(0, 0, -1), 0, kInfinity);
  ASSERT_TRUE(h);
  EXPECT_NEAR(*h, 5 - 0.25, 1e-14);
  const Cylinder c(1.0, 0.0, 2.0);
  h = c.intersect(Vec3(-5, 0, 1), Vec3(1, 0, 0), 0, kInfinity);
  ASSERT_TRUE(h);
  EXPECT_NEAR(*h, 4.0, 1e-14);
  EXPECT_FALSE(c.intersect(Vec3(-5, 0, 3), Vec3(1, 0, 0), 0, kInfinity));
  const Disk d(1.0, 0.5);
  EXPECT_FALSE(d.intersect(Vec3(0.2, 0, 1), Vec3(0, 0, -1), 0, kInfinity));  // in the hole
  EXPECT_TRUE(d.intersect(Vec3(0.7, 0, 1), Vec3(0, 0, -1), 0, kInfinity));
}


TEST(GeometryScene, NearestHitAcrossGeometryTypes) {
  // Analytic sphere (r = 2) around a mesh sphere (r = 1) around an analytic sphere (r = 0.5):
  // walking a ray inward with spawn_ray visits them in order.
  Scene scene;
  const uint32_t outer = scene.add(ShapeInstance(std::make_shared<Sphere>(2.0)));
  const uint32_t middle = scene.add(make_uv_sphere_mesh(1.0, 64, 128));
  const uint32_t inner = scene.add(ShapeInstance(std::make_shared<Sphere>(0.5)));
  scene.commit();
  const Vec3 d = glm::normalize(Vec3(0.01, 0.02, -1.0));
  auto h = scene.intersect(make_ray(Vec3(0, 0, 10), d));
  const std::vector<uint32_t> expected = {outer, middle, inner, inner, middle, outer};
  for (size_t k = 0; k < expected.size(); ++k) {
    ASSERT_TRUE(h) << "step " << k;
    EXPECT_EQ(h->shape_id, expected[k]) << "step " << k;
    h = scene.intersect(spawn_ray(*h, d));
  }
  EXPECT_FALSE(h);
}

}  // namespace
}  // namespace tb
