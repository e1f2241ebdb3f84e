// The catalogue of canonical integrands on [0, 1] and [0, 1]² with known integrals: smooth, Gaussian
// peaks and mixtures, steps, a kink, a narrow spike, an integrable singularity, and products of
// features. Each is named (a registry by name) and carries a JSON description; integrals are in
// closed form (Boost.Math erf for Gaussians) or by adaptive Gauss-Kronrod quadrature split at the
// discontinuities (relative tolerance 1e-12), as the description says. f is zero outside the domain.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/core/math.h"

namespace tb {

struct Integrand1D {
  std::string name;
  std::function<double(double)> f;
  double integral = 0.0;            // ∫_0^1 f(x) dx
  std::vector<double> breakpoints;  // discontinuities of f or of its derivative in (0, 1)
  bool singular = false;            // f unbounded (infinite variance for some techniques)
  nlohmann::json description;       // formula, parameters, how the integral was obtained
  double operator()(double x) const { return (x >= 0.0 && x <= 1.0) ? f(x) : 0.0; }
};

struct Integrand2D {
  std::string name;
  std::function<double(Vec2)> f;
  double integral = 0.0;  // ∫_[0,1]² f(x) dx
  bool singular = false;
  nlohmann::json description;
  double operator()(const Vec2& x) const {
    return (x.x >= 0.0 && x.x <= 1.0 && x.y >= 0.0 && x.y <= 1.0) ? f(x) : 0.0;
  }
};

const std::vector<Integrand1D>& integrands_1d();
const std::vector<Integrand2D>& integrands_2d();
// Throws std::invalid_argument naming the known integrands when the name is unknown.
const Integrand1D& integrand_1d(const std::string& name);
const Integrand2D& integrand_2d(const std::string& name);

// ∫_lo^hi of a Gaussian bump exp(-(x - mu)² / (2 sigma²)) in closed form (Boost.Math erf).
double gaussian_bump_integral(double mu, double sigma, double lo, double hi);

}  // namespace tb
