// Shared bodies of the self-intersection tests (geometry_self_intersection_test.cpp runs them
// with 10^5 rays per shape, geometry_self_intersection_slowtest.cpp with 10^6).
#pragma once

#include <gtest/gtest.h>

#include "lib/core/hash.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/reference_shapes.h"
#include "lib/geometry/self_intersection.h"

namespace tb::self_intersection_cases {

inline void check_analytic_shapes(int64_t kRays) {
  for (const ReferenceShape& s : reference_analytic_shapes()) {
    Scene scene;
    const uint32_t id = scene.add(s.instance);
    scene.commit();
    SelfIntersectionOptions o;
    o.rays = kRays;
    o.key = hash_string("geometry_self_intersection_test." + s.name);
    o.closed = s.instance.shape().closed();
    o.convex = s.name.rfind("sphere", 0) == 0;
    o.size = s.scale;
    const SelfIntersectionStats st = count_self_intersections(scene, id, o);
    EXPECT_EQ(st.self_hits, 0) << s.name << " first bad ray " << st.first_bad;
    EXPECT_EQ(st.leaks, 0) << s.name << " first bad ray " << st.first_bad;
  }
}

inline void check_triangle_mesh(int64_t kRays) {
  Scene scene;
  const uint32_t id = scene.add(make_uv_sphere_mesh(1.7, 64, 128, Vec3(3.1, -2.3, 0.7)));
  scene.commit();
  SelfIntersectionOptions o;
  o.rays = kRays;
  o.key = hash_string("geometry_self_intersection_test.mesh");
  o.closed = true;
  o.size = 2 * std::sqrt(3.0) * 1.7;
  o.convex = true;
  // Float triangles: spurious hits lie within the offset (~1e-6 of the size); genuine grazing
  // exits through a neighbouring triangle can be much closer than a triangle's size.
  o.self_distance = 1e-6;
  const SelfIntersectionStats st = count_self_intersections(scene, id, o);
  EXPECT_EQ(st.self_hits, 0) << "first bad ray " << st.first_bad;
  EXPECT_EQ(st.leaks, 0) << "first bad ray " << st.first_bad;
}

inline void check_without_offset_self_intersections_are_found() {
  // Negative control: spawning from the unoffset point must produce self-intersections.
  const auto shapes = reference_analytic_shapes();
  int64_t total = 0;
  for (const ReferenceShape& s : shapes) {
    if (s.name != "sphere" && s.name != "torus") continue;
    Scene scene;
    const uint32_t id = scene.add(s.instance);
    scene.commit();
    SelfIntersectionOptions o;
    o.rays = 20000;
    o.closed = true;
    o.size = s.scale;
    o.disable_offset = true;
    const SelfIntersectionStats st = count_self_intersections(scene, id, o);
    total += st.self_hits + st.leaks;
    EXPECT_GT(st.self_hits + st.leaks, 0) << s.name;
  }
  Scene scene;
  const uint32_t id = scene.add(make_uv_sphere_mesh(1.7, 64, 128, Vec3(3.1, -2.3, 0.7)));
  scene.commit();
  SelfIntersectionOptions o;
  o.rays = 20000;
  o.closed = true;
  o.size = 5.9;
  o.convex = true;
  o.self_distance = 1e-6;
  o.disable_offset = true;
  const SelfIntersectionStats st = count_self_intersections(scene, id, o);
  EXPECT_GT(st.self_hits + st.leaks, 0) << "mesh";
}

}  // namespace tb::self_intersection_cases
