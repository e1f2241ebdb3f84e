// Path tracer and light tracer (lib/integrator/path_tracer.h, light_tracer.h) on a small box
// built in code: a Lambertian floor and walls, a rough-conductor back wall (glossy: MIS and the
// adjoint BSDF matter), an area light under the ceiling facing down, 16 x 16 pixels.
//  - pt and lt estimate the same image: Welch comparison (per pixel-channel Welch t-test with
//    Šidák, Stouffer and sum z^2; alpha = 0.001 for the whole comparison), fixed seeds;
//  - images are bit-identical with 1 and 2 threads;
//  - negative controls: each broken estimator term makes pt disagree with the exact pt
//    (same comparison, alpha = 0.001), in this scene where each of them matters.
#include <gtest/gtest.h>

#include "lib/camera/pinhole_camera.h"
#include "lib/core/parallel.h"
#include "lib/integrator/light_tracer.h"
#include "lib/integrator/path_tracer.h"
#include "lib/material/bsdf_registry.h"
#include "lib/material/lambert.h"
#include "lib/registry/integrator_registry.h"
#include "validate/image_compare.h"
#include "validate/render/broken_integrators.h"

namespace tb {
namespace {

// Quad with corners c, c + a, c + a + b, c + b; geometric normal along a x b.
TriangleMesh quad(const Vec3& c, const Vec3& a, const Vec3& b) {
  return TriangleMesh({c, c + a, c + a + b, c + b}, {glm::uvec3(0, 1, 2), glm::uvec3(0, 2, 3)});
}

std::unique_ptr<World> small_box() {
  CameraSetup cs;
  cs.eye = {0.0, 1.0, 3.2};
  cs.target = {0.0, 0.9, 0.0};
  cs.vfov_degrees = 40;
  cs.width = 16;
  cs.height = 16;
  WorldBuilder b;
  b.camera(std::make_unique<PinholeCamera>(cs));
  b.material("white", std::make_unique<LambertBsdf>(Rgb(0.7)));
  b.material("red", std::make_unique<LambertBsdf>(Rgb(0.7, 0.15, 0.1)));
  b.material("glossy", make_bsdf("rough_conductor", {{"alpha", 0.3}}));
  // Box [-1, 1] x [0, 2] x [-1, 1], open towards +z (the camera); normals point inside.
  b.add_shape(quad({-1, 0, -1}, {0, 0, 2}, {2, 0, 0}), "white");                    // floor, +y
  b.add_shape(quad({-1, 2, -1}, {2, 0, 0}, {0, 0, 2}), "white");                    // ceiling, -y
  b.add_shape(quad({-1, 0, -1}, {2, 0, 0}, {0, 2, 0}), "glossy");                   // back, +z
  b.add_shape(quad({-1, 0, -1}, {0, 2, 0}, {0, 0, 2}), "red");                      // left, +x
  b.add_shape(quad({1, 0, -1}, {0, 0, 2}, {0, 2, 0}), "white");                     // right, -x
  b.add_shape(quad({-0.3, 1.98, -0.3}, {0.6, 0, 0}, {0, 0, 0.6}), "", Rgb(10.0));   // light, -y
  return b.build();
}

RenderSettings settings(uint64_t seed, int64_t spp, int64_t passes) {
  RenderSettings st;
  st.seed = seed;
  st.spp = spp;
  st.passes = passes;
  st.max_depth = 6;
  st.rr_min_depth = 1;  // roulette from the first bounce on, so that its 1/q matters
  return st;
}

WelchImage render(const char* name, const World& w, const RenderSettings& st) {
  Film film(w.camera().width(), w.camera().height());
  const IntegratorInfo* integ = find_integrator(name);
  EXPECT_NE(integ, nullptr) << name;
  EXPECT_EQ(integ->render(w, st, film), st.passes);
  EXPECT_EQ(film.nonfinite().count(), 0) << name;
  return film.welch();
}

TEST(IntegratorPtLt, PathTracingAndLightTracingAgree) {
  const auto w = small_box();
  const WelchImage pt = render("pt", *w, settings(101, 32 * 64, 32));
  const WelchImage lt = render("lt", *w, settings(202, 32 * 64, 32));
  const ImageCompareResult r = compare_welch_images(pt, lt, 0.001);
  RecordProperty("comparison", r.message());  // p-values in the test log (docs/validation.md)
  EXPECT_FALSE(r.rejects()) << r.message() << " (seeds 101 / 202)";
  EXPECT_NEAR(r.mean_relative_difference, 0.0, 0.02) << r.message();
  // Not an empty image: the light and the walls are lit.
  double sum = 0;
  for (size_t i = 0; i < pt.pixels(); ++i) sum += pt.mean(i).g;
  EXPECT_GT(sum / double(pt.pixels()), 0.1);
}

TEST(IntegratorPtLt, BitIdenticalForOneAndTwoThreads) {
  const auto w = small_box();
  for (const char* name : {"pt", "lt"}) {
    WelchImage one, two;
    {
      ThreadLimit limit(1);
      one = render(name, *w, settings(7, 8, 2));
    }
    {
      ThreadLimit limit(2);
      two = render(name, *w, settings(7, 8, 2));
    }
    for (size_t i = 0; i < one.pixels(); ++i) {
      ASSERT_EQ(one.sum[i], two.sum[i]) << name << " pixel " << i;
      ASSERT_EQ(one.sum_sq[i], two.sum_sq[i]) << name << " pixel " << i;
    }
  }
}

TEST(IntegratorPtLt, RayCountsAreReported) {
  const auto w = small_box();
  Film film(16, 16);
  RayCounts rc;
  render_pt(*w, settings(3, 1, 1), film, &rc);
  EXPECT_GE(rc.extension, 256);  // at least the camera rays
  EXPECT_GT(rc.shadow, 0);
}

class IntegratorFaultTest : public ::testing::TestWithParam<EstimatorFault> {};

TEST_P(IntegratorFaultTest, FaultyPathTracerIsRejected) {
  const auto w = small_box();
  const WelchImage good = render("pt", *w, settings(301, 16 * 32, 16));
  const RenderSettings st = settings(302, 16 * 32, 16);
  const RenderFunction broken = broken_integrator("pt", GetParam());
  ASSERT_TRUE(broken);
  Film film(w->camera().width(), w->camera().height());
  EXPECT_EQ(broken(*w, st, film), st.passes);
  const WelchImage bad = film.welch();
  const ImageCompareResult r = compare_welch_images(bad, good, 0.001);
  RecordProperty("comparison", r.message());
  EXPECT_TRUE(r.rejects()) << "fault " << static_cast<int>(GetParam()) << " not caught: " << r.message();
}

INSTANTIATE_TEST_SUITE_P(Faults, IntegratorFaultTest,
                         ::testing::Values(EstimatorFault::kMisMissingDensity, EstimatorFault::kNeeNoCosine,
                                           EstimatorFault::kRouletteNoInverse));

TEST(IntegratorPtLt, FaultFreeRendersWithOtherSeedsAgree) {
  // The fault tests' control: the same comparison between two fault-free renders accepts.
  const auto w = small_box();
  const WelchImage a = render("pt", *w, settings(301, 16 * 32, 16));
  const WelchImage b = render("pt", *w, settings(303, 16 * 32, 16));
  const ImageCompareResult r = compare_welch_images(a, b, 0.001);
  RecordProperty("comparison", r.message());
  EXPECT_FALSE(r.rejects()) << r.message();
}

}  // namespace
}  // namespace tb
