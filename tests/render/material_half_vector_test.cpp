// |d omega_h / d omega_o| of the generalised half vector (lib/material/half_vector.h; Kaplanyan et
// al. 2014, Eq. 10) against central finite differences over 1,000 seeded configurations per named
// case, relative error < 1e-6 (docs/validation.md C); a wrong Jacobian must be rejected.
#include "lib/material/half_vector.h"

#include <functional>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "lib/core/frame.h"
#include "lib/core/rng.h"
#include "lib/material/bsdf.h"

namespace tb {
namespace {

struct HvConfig {
  Vec3 i, o;
  double eta_i, eta_o;
};

Vec3 random_dir(Rng& r) {
  const double z = 2 * r.uniform() - 1, phi = 2 * kPi * r.uniform();
  const double s = std::sqrt(std::max(0.0, 1 - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

// Physical configurations: a facet normal m, i on its front side, o = reflect or refract(i, m).
// cos_max bounds |<i, m>| from below for the grazing case.
std::optional<HvConfig> make_config(Rng& r, bool refraction, double eta_lo, double eta_hi, bool grazing) {
  const Vec3 m = random_dir(r);
  Frame f = Frame::from_z(m);
  const double c = grazing ? std::cos(glm::radians(89.9)) * (0.2 + 0.8 * r.uniform()) : 0.02 + 0.98 * r.uniform();
  const double phi = 2 * kPi * r.uniform();
  const Vec3 i = f.to_world(Vec3(std::sqrt(1 - c * c) * std::cos(phi), std::sqrt(1 - c * c) * std::sin(phi), c));
  if (!refraction) return HvConfig{i, reflect(i, m), 1.0, 1.0};
  double eta = eta_lo + (eta_hi - eta_lo) * r.uniform();
  if (r.uniform() < 0.5) eta = 1.0 / eta;  // both directions across the interface
  const auto o = refract(i, m, eta);
  if (!o) return std::nullopt;
  return HvConfig{i, *o, 1.0, eta};
}

// The 2x2 Jacobian of the chart map (a, b) -> h(o(a, b)) at 0 by central differences, where
// o(a, b) = normalize(o0 + s (a e1 + b e2)) and h is read in the tangent basis of h0. Both charts
// are isometric at the origin, so |det| / s^2 = |d omega_h / d omega_o|. s rescales the step to
// the problem's own length scale |H| / eta_o (IOR near 1: H nearly cancels).
// Returns |det| / s^2 and the 2-norm condition number of the 2x2 chart Jacobian in *kappa.
double fd_jacobian(const HvConfig& c, double step, double* kappa) {
  const Vec3 H0 = generalized_half_vector_unnormalized(c.i, c.o, c.eta_i, c.eta_o);
  const Vec3 h0 = glm::normalize(H0);
  const double s = std::min(1.0, glm::length(H0) / c.eta_o);
  Vec3 e1, e2, f1, f2;
  coordinate_system(c.o, &e1, &e2);
  coordinate_system(h0, &f1, &f2);
  auto chart = [&](double a, double b) {
    const Vec3 o = glm::normalize(c.o + s * (a * e1 + b * e2));
    const Vec3 h = glm::normalize(generalized_half_vector_unnormalized(c.i, o, c.eta_i, c.eta_o));
    return Vec2(glm::dot(h, f1), glm::dot(h, f2));
  };
  const Vec2 da = (chart(step, 0) - chart(-step, 0)) / (2 * step);
  const Vec2 db = (chart(0, step) - chart(0, -step)) / (2 * step);
  // Singular values of [da db]: the determinant's relative error from rounding is about
  // (rounding error of the entries) / sigma_min, hence the tolerance 1e-6 * kappa below.
  const double det = std::abs(da.x * db.y - da.y * db.x);
  const double fro2 = glm::dot(da, da) + glm::dot(db, db);
  const double smax = std::sqrt(0.5 * (fro2 + std::sqrt(std::max(0.0, fro2 * fro2 - 4 * det * det))));
  *kappa = smax * smax / det;
  return det / (s * s);
}

struct Outcome {
  int checked = 0, failed = 0;
  double worst = 0;
  int worst_index = -1;
};

Outcome run(const std::string& name, bool refraction, double eta_lo, double eta_hi, bool grazing,
            const std::function<double(const HvConfig&)>& jac) {
  const double step = std::cbrt(kEpsilon * 2);  // eps^(1/3) * max(1, |x|), x = 0 (docs/validation.md C)
  Outcome out;
  for (int k = 0; out.checked < 1000 && k < 100000; ++k) {
    Rng r = Rng::for_sample(1, hash_string(name), static_cast<uint64_t>(k));
    const auto c = make_config(r, refraction, eta_lo, eta_hi, grazing);
    if (!c) continue;
    double kappa = 1;
    const double fd = fd_jacobian(*c, step, &kappa), an = jac(*c);
    // Relative error scaled by the condition number: at grazing angles one singular value of the
    // chart Jacobian is |<h,o>| ~ 1e-3 and rounding in it is amplified by kappa.
    const double err = std::abs(fd - an) / std::abs(an) / std::max(1.0, kappa);
    ++out.checked;
    if (!(err < 1e-6)) ++out.failed;
    if (!(err <= out.worst)) {
      out.worst = err;
      out.worst_index = k;
    }
  }
  return out;
}

double closed_form(const HvConfig& c) { return half_vector_jacobian(c.i, c.o, c.eta_i, c.eta_o); }

TEST(HalfVectorJacobian, MatchesFiniteDifferences) {
  struct Case {
    const char* name;
    bool refraction;
    double lo, hi;
    bool grazing;
  };
  for (const Case& k : {Case{"reflection", false, 1, 1, false}, Case{"refraction", true, 1.0001, 2.5, false},
                        Case{"reflection_grazing", false, 1, 1, true}, Case{"refraction_grazing", true, 1.0001, 2.5, true},
                        Case{"ior_near_one", true, 1.0001, 1.001, false}}) {
    const Outcome o = run(k.name, k.refraction, k.lo, k.hi, k.grazing, closed_form);
    EXPECT_EQ(o.checked, 1000) << k.name;
    EXPECT_EQ(o.failed, 0) << k.name << ": worst rel. error " << o.worst << " at config " << o.worst_index;
    EXPECT_LT(o.worst, 1e-6) << k.name;
  }
}

TEST(HalfVectorJacobian, ReflectionIsOneOverFourCos) {
  Rng r(5);
  for (int k = 0; k < 100; ++k) {
    const auto c = make_config(r, false, 1, 1, false);
    const Vec3 h = generalized_half_vector(c->i, c->o, 1, 1, c->i);
    EXPECT_NEAR(closed_form(*c), 1.0 / (4 * glm::dot(h, c->o)), 1e-12 * closed_form(*c));
  }
}

TEST(HalfVectorJacobian, NegativeControlWrongJacobianIsRejected) {
  // A dropped eta_o^2 factor, and the reflection Jacobian used for refraction.
  const auto no_eta2 = [](const HvConfig& c) { return closed_form(c) / (c.eta_o * c.eta_o); };
  const auto refl_for_refr = [](const HvConfig& c) {
    const Vec3 h = glm::normalize(generalized_half_vector_unnormalized(c.i, c.o, c.eta_i, c.eta_o));
    return 1.0 / (4 * std::abs(glm::dot(h, c.o)));
  };
  EXPECT_GT(run("refraction", true, 1.0001, 2.5, false, no_eta2).failed, 900);
  EXPECT_GT(run("refraction", true, 1.0001, 2.5, false, refl_for_refr).failed, 900);
}

}  // namespace
}  // namespace tb
