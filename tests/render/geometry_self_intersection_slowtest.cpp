// Robust ray spawning with 10^6 rays per shape (label "slow"; the quick version is
// geometry_self_intersection_test.cpp).
#include "geometry_self_intersection_cases.h"

namespace tb {
namespace {

using namespace self_intersection_cases;
constexpr int64_t kRays = 1000000;

TEST(GeometrySelfIntersectionSlow, AnalyticShapes) { check_analytic_shapes(kRays); }
TEST(GeometrySelfIntersectionSlow, TriangleMesh) { check_triangle_mesh(kRays); }

}  // namespace
}  // namespace tb
