// Unit tests of lib/differential/path_differential and variance_bound (Zirr & Dachsbacher 2020,
// App. B, Eq. 18-21). The registered checks (differential.path.*) run the full finite-difference
// study; these tests pin the building blocks and one path per kind.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "lib/core/frame.h"
#include "lib/differential/path_differential.h"
#include "lib/differential/variance_bound.h"
#include "lib/material/bsdf.h"
#include "lib/scene/scene_loader.h"

namespace tb::differential {
namespace {

const World& scene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<World>> cache;
  auto& w = cache[name];
  if (!w) w = load_world(std::string(TB_SOURCE_DIR) + "/scenes/" + name + ".json");
  return *w;
}

Eigen::Vector3d ev(const Vec3& v) { return {v.x, v.y, v.z}; }

TEST(PathDifferential, FrameDerivativeMatchesFiniteDifferences) {
  for (const Vec3 n0 : {Vec3(0.3, -0.5, 0.81), Vec3(-0.2, 0.4, -0.89), Vec3(0.9, 0.1, 0.3)}) {
    const Vec3 n = glm::normalize(n0);
    Mat3 ds, dt;
    frame_derivative(n, &ds, &dt);
    for (int c = 0; c < 3; ++c) {
      Vec3 e(0.0);
      e[c] = 1e-6;
      Vec3 sp, tp, sm, tm;
      coordinate_system(n + e, &sp, &tp);
      coordinate_system(n - e, &sm, &tm);
      EXPECT_LT((ev((sp - sm) / 2e-6) - ds.col(c)).norm(), 1e-8);
      EXPECT_LT((ev((tp - tm) / 2e-6) - dt.col(c)).norm(), 1e-8);
    }
  }
}

TEST(PathDifferential, RefractionDerivativeMatchesFiniteDifferencesAndNeedsEta) {
  const Vec3 m = glm::normalize(Vec3(0.1, -0.2, 1.0));
  const Vec3 w = glm::normalize(Vec3(0.4, 0.3, 0.8));
  for (const double eta : {1.5, 1.0 / 1.5}) {
    Mat3 d_w, d_m;
    refract_derivative(w, m, eta, &d_w, &d_m);
    for (int c = 0; c < 3; ++c) {
      Vec3 e(0.0);
      e[c] = 1e-6;
      const Vec3 fw = (*refract(w + e, m, eta) - *refract(w - e, m, eta)) / 2e-6;
      const Vec3 fm = (*refract(w, m + e, eta) - *refract(w, m - e, eta)) / 2e-6;
      EXPECT_LT((ev(fw) - d_w.col(c)).norm(), 1e-8);
      EXPECT_LT((ev(fm) - d_m.col(c)).norm(), 1e-8);
    }
    Mat3 b_w, b_m;
    refract_derivative(w, m, 1.0, &b_w, &b_m);  // the missing-eta negative control's derivative
    EXPECT_GT((b_w - d_w).norm(), 0.1);
  }
}

// dX/dU of one sampled path against central differences of trace_forward.
double jacobian_error(const World& world, const SampledPath& sp, int k) {
  const PathDifferential d = differentiate(world, sp.pixel, sp.path, sp.U);
  const Eigen::MatrixXd J = vertex_jacobian(d);
  Eigen::MatrixXd F(3 * k, 2 * k);
  const double h = 1e-7;
  for (int c = 0; c < 2 * k; ++c) {
    Eigen::VectorXd up = sp.U, um = sp.U;
    up[c] += h;
    um[c] -= h;
    F.col(c) = (vertex_vector(*trace_forward(world, sp.pixel, up, k, sp.lobe)) -
                vertex_vector(*trace_forward(world, sp.pixel, um, k, sp.lobe))) / (2 * h);
  }
  return (J - F).cwiseAbs().maxCoeff() / std::max(1.0, J.cwiseAbs().maxCoeff());
}

TEST(PathDifferential, DiffuseJacobianMatchesFiniteDifferences) {
  const World& world = scene("cornell-box");
  const auto sp = sample_path(world, 5, 7, 11, 0);
  ASSERT_TRUE(sp.has_value());
  EXPECT_LT(jacobian_error(world, *sp, 5), 1e-6);
}

TEST(PathDifferential, GlossyAndRefractiveJacobianMatchesFiniteDifferences) {
  const World& world = scene("glossy");
  int found = 0;
  for (uint64_t i = 0; i < 64 && found < 3; ++i) {
    const auto sp = sample_path(world, 4, 7, 12, i);
    if (!sp) continue;
    bool glossy = false;
    for (uint32_t f : sp->path.flags) glossy = glossy || (f & bsdf_flags::kGlossy);
    if (!glossy) continue;
    ++found;
    EXPECT_LT(jacobian_error(world, *sp, 4), 1e-6) << "path " << i;
  }
  EXPECT_EQ(found, 3);
}

TEST(PathDifferential, IncrementalEqualsFullRecurrence) {
  for (const char* name : {"dg-curved-mirrors", "dg-glass", "cornell-box"}) {
    const World& world = scene(name);
    for (int k = 1; k <= 8; ++k) {
      const auto sp = sample_path(world, k, 3, 5, static_cast<uint64_t>(k), 0.02, 1024);
      ASSERT_TRUE(sp.has_value()) << name << " k " << k;
      const PathDifferential d = differentiate(world, sp->pixel, sp->path, sp->U);
      const EndpointMap e = endpoint_map(sp->path, d);
      const EndpointCovariance a = endpoint_covariance_full(d.blocks, e);
      const EndpointCovariance b = endpoint_covariance_incremental(d.blocks, e);
      EXPECT_LE((a.sigma - b.sigma).cwiseAbs().maxCoeff(), 1e-10 * a.sigma.cwiseAbs().maxCoeff()) << name << " " << k;
      EXPECT_LE((a.sigma_camera - b.sigma_camera).cwiseAbs().maxCoeff(),
                1e-10 * a.sigma_camera.cwiseAbs().maxCoeff())
          << name << " " << k;
    }
  }
}

TEST(PathDifferential, HalfVectorBlocksEqualPrimarySampleBlocksOnSpecularPaths) {
  // Delta lobes have no random variable: both parameterisations give the same blocks.
  const World& world = scene("dg-curved-mirrors");
  int found = 0;
  for (uint64_t i = 0; i < 512 && found < 2; ++i) {
    const auto sp = sample_path(world, 2 + static_cast<int>(i % 2), 9, 13, i);
    if (!sp) continue;
    bool delta = true;
    for (uint32_t f : sp->path.flags) delta = delta && (f & bsdf_flags::kDelta);
    if (!delta) continue;
    ++found;
    const PathDifferential a = differentiate(world, sp->pixel, sp->path, sp->U);
    const PathDifferential b =
        differentiate(world, sp->pixel, sp->path, sp->U, BounceParameterisation::kHalfVector);
    for (size_t j = 0; j < a.blocks.size(); ++j) {
      EXPECT_LT((a.blocks[j].g_cur - b.blocks[j].g_cur).norm(), 1e-9 * (1 + a.blocks[j].g_cur.norm()));
      EXPECT_LT((a.blocks[j].g_prev - b.blocks[j].g_prev).norm(), 1e-9 * (1 + a.blocks[j].g_prev.norm()));
    }
  }
  EXPECT_EQ(found, 2);
}

TEST(VarianceBound, RatioIsOneForTheCameraAloneAndAtLeastOneOtherwise) {
  const World& world = scene("cornell-box");
  for (int k = 1; k <= 4; ++k) {
    const auto sp = sample_path(world, k, 1, 2, static_cast<uint64_t>(k));
    ASSERT_TRUE(sp.has_value());
    const PathDifferential d = differentiate(world, sp->pixel, sp->path, sp->U, BounceParameterisation::kHalfVector);
    const EndpointCovariance c = endpoint_covariance_incremental(d.blocks, endpoint_map(sp->path, d));
    const double r = variance_ratio(c).r;
    if (k == 1) {
      EXPECT_NEAR(r, 1.0, 1e-9);
      EXPECT_DOUBLE_EQ(variance_ratio_derivative_free(world, sp->path).r, 1.0);
    } else {
      EXPECT_GE(r, 1.0);
      EXPECT_GE(variance_ratio_derivative_free(world, sp->path).r, r);  // planar: Eq. 21 is conservative
    }
  }
}

// The camera subpath of a bidirectional technique holding the vertices of a traced path: the lens,
// then x_1..x_k with the area densities a camera random walk stores (pdf_fwd of x_{j+1} = the
// solid-angle pdf at x_j converted to area at x_{j+1}).
std::vector<PathVertex> as_camera_subpath(const World& world, const ForwardPath& p) {
  std::vector<PathVertex> c(p.vertices.size() + 1);
  c[0].kind = VertexKind::kCamera;
  c[0].hit.p = p.eye;
  c[0].pdf_fwd = 1.0;
  for (size_t j = 0; j < p.vertices.size(); ++j) {
    PathVertex& v = c[j + 1];
    v.kind = VertexKind::kSurface;
    v.hit = p.vertices[j];
    v.bsdf = world.surface(p.vertices[j].shape_id).bsdf;
    v.delta = j < p.flags.size() && (p.flags[j] & bsdf_flags::kDelta);
    if (j > 0) {
      const Vec3 d = v.hit.p - c[j].hit.p;
      v.pdf_fwd = p.pdf[j - 1] * std::abs(glm::dot(v.hit.ng, glm::normalize(d))) / glm::dot(d, d);
      if (c[j].delta) v.pdf_fwd = 0.0;  // stored as 0 behind a Dirac lobe (lib/path/path.h)
    }
  }
  return c;
}

TEST(VarianceBound, SubpathFormEqualsThePathTracerForm) {
  // Eq. 21 from a camera subpath's stored area densities equals Eq. 21 from the traced path's
  // solid-angle pdfs, on diffuse, glossy and refractive paths; with the MIS reduction an s = 0
  // path loses exactly its last term.
  int compared = 0, refractive = 0;
  for (const char* name : {"cornell-box", "glossy", "dg-glass"}) {
    const World& world = scene(name);
    for (int k = 1; k <= 6; ++k)
      for (uint64_t i = 0; i < 6; ++i) {
        const auto sp = sample_path(world, k, 5, 17, static_cast<uint64_t>(k) * 100 + i);
        if (!sp) continue;
        const DerivativeFreeRatio ref = variance_ratio_derivative_free(world, sp->path);
        const std::vector<PathVertex> cam = as_camera_subpath(world, sp->path);
        const int t = static_cast<int>(cam.size());
        const double r = subpath_variance_ratio(world, cam, t, 1, true);
        EXPECT_NEAR(r, ref.r, 1e-9 * ref.r) << name << " k=" << k;
        const double last = ref.terms.empty() ? 0.0 : ref.terms.back();
        EXPECT_NEAR(subpath_variance_ratio(world, cam, t, 0, true), ref.r - last, 1e-9 * ref.r) << name << " k=" << k;
        EXPECT_NEAR(subpath_variance_ratio(world, cam, t, 0, false), ref.r, 1e-9 * ref.r) << name << " k=" << k;
        for (uint32_t f : sp->path.flags) refractive += (f & bsdf_flags::kTransmission) ? 1 : 0;
        ++compared;
      }
  }
  EXPECT_GE(compared, 60);
  EXPECT_GT(refractive, 0);
}

TEST(VarianceBound, RefractionSolidAngleRatioOfNormalIncidence) {
  // At normal incidence dw_t / dw_i = 1 / eta^2 (Snell's law, eta_i sin_i = eta_t sin_t).
  const Vec3 n(0, 0, 1);
  EXPECT_NEAR(refraction_solid_angle_ratio(n, -n, n, 1.5), 1.0 / 2.25, 1e-15);
}

}  // namespace
}  // namespace tb::differential
