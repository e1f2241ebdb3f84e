// Robust ray spawning: rays fired from surface points never re-hit the surface they leave
// (10^5 rays per shape here; 10^6 in geometry_self_intersection_slowtest.cpp and in the
// full `tb check geometry`), and inward rays of closed shapes never escape.
#include "geometry_self_intersection_cases.h"

namespace tb {
namespace {

using namespace self_intersection_cases;
constexpr int64_t kRays = 100000;

TEST(GeometrySelfIntersection, AnalyticShapes) { check_analytic_shapes(kRays); }
TEST(GeometrySelfIntersection, TriangleMesh) { check_triangle_mesh(kRays); }
TEST(GeometrySelfIntersection, WithoutOffsetSelfIntersectionsAreFound) { check_without_offset_self_intersections_are_found(); }

}  // namespace
}  // namespace tb
