// The direction kernel of Otsu et al.'s regional adaptive perturbations (Otsu, Herveau, Hanika,
// Nowrouzezahrai, Dachsbacher, "Regional Adaptive Metropolis Light Transport", Sec. 3,
// "Perturbing Ray Directions"): the new direction w' is written in spherical coordinates
// (theta, phi) in a frame around the current direction w; phi ~ U[0, 2 pi) and theta from a
// normal of scale sigma truncated to [-pi, pi]. A signed theta with a uniform phi describes the
// same direction as (|theta|, phi + pi), so the angle between w and w' has the density
//   p_theta(t | sigma) = 2 N(t; 0, sigma^2) / Z(sigma),  t in [0, pi],  Z = erf(pi / (sigma sqrt 2)),
// and the direction density per unit solid angle around w is
//   p_w(w' | w, sigma) = p_theta(t | sigma) / (2 pi sin t),  t = angle(w, w'),
// symmetric in (w, w') for a fixed sigma: only sigma (the region's, Otsu Eq. 2-3) differs between
// T(x -> y) and T(y -> x). sigma = exp(lambda / 2), lambda = log sigma^2 (Otsu Sec. 5.3, Eq. 5).
// Sampling is by inversion: t = sigma sqrt(2) erf^-1(u Z), two uniforms per direction.
#pragma once

#include <algorithm>
#include <cmath>

#include "lib/core/frame.h"
#include "lib/core/math.h"

namespace tb::path_space {

// erf^-1 on (-1, 1): Giles (2010) single-precision approximation refined by two Newton steps on
// std::erf (double precision away from |v| -> 1).
inline double erf_inverse(double v) {
  v = std::clamp(v, -1.0 + 1e-16, 1.0 - 1e-16);
  double w = -std::log((1.0 - v) * (1.0 + v)), p;
  if (w < 5.0) {
    w -= 2.5;
    p = 2.81022636e-08;
    p = 3.43273939e-07 + p * w;
    p = -3.5233877e-06 + p * w;
    p = -4.39150654e-06 + p * w;
    p = 0.00021858087 + p * w;
    p = -0.00125372503 + p * w;
    p = -0.00417768164 + p * w;
    p = 0.246640727 + p * w;
    p = 1.50140941 + p * w;
  } else {
    w = std::sqrt(w) - 3.0;
    p = -0.000200214257;
    p = 0.000100950558 + p * w;
    p = 0.00134934322 + p * w;
    p = -0.00367342844 + p * w;
    p = 0.00573950773 + p * w;
    p = -0.0076224613 + p * w;
    p = 0.00943887047 + p * w;
    p = 1.00167406 + p * w;
    p = 2.83297682 + p * w;
  }
  double t = p * v;
  for (int i = 0; i < 2; ++i) {
    const double d = 2.0 / std::sqrt(kPi) * std::exp(-t * t);
    if (!(d > 0.0)) break;
    t -= (std::erf(t) - v) / d;
  }
  return t;
}

struct TruncatedNormalDirection {
  // Z(sigma): the mass of N(0, sigma^2) in [-pi, pi].
  static double mass(double sigma) { return std::erf(kPi / (sigma * std::sqrt(2.0))); }
  // p_theta(t | sigma) on [0, pi] (0 outside).
  static double angle_density(double t, double sigma) {
    if (!(t >= 0.0) || !(t <= kPi) || !(sigma > 0.0)) return 0.0;
    const double z = t / sigma;
    return 2.0 * std::exp(-0.5 * z * z) / (sigma * std::sqrt(2.0 * kPi) * mass(sigma));
  }
  // p_w(w' | w, sigma) per unit solid angle, t = angle(w, w').
  static double density(double t, double sigma) {
    const double s = std::sin(t);
    if (!(s > 0.0)) return 0.0;
    return angle_density(t, sigma) / (2.0 * kPi * s);
  }
  // The angle t from one uniform (inversion of p_theta).
  static double sample_angle(double u, double sigma) {
    const double t = sigma * std::sqrt(2.0) * erf_inverse(u * mass(sigma));
    return std::clamp(t, 0.0, kPi);
  }
  // w' around the unit direction w from two uniforms (u.x: theta, u.y: phi).
  static Vec3 sample(const Vec3& w, const Vec2& u, double sigma) {
    const double t = sample_angle(u.x, sigma), phi = 2.0 * kPi * u.y, st = std::sin(t);
    return glm::normalize(Frame::from_z(w).to_world(Vec3(st * std::cos(phi), st * std::sin(phi), std::cos(t))));
  }
  // The angle between two unit directions, accurate near 0.
  static double angle(const Vec3& a, const Vec3& b) { return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)); }
};

}  // namespace tb::path_space
