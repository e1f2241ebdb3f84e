#include "analytic/integrands.h"

#include <cmath>
#include <stdexcept>

#include <boost/math/special_functions/erf.hpp>

#include "analytic/quadrature.h"

namespace tb {

double gaussian_bump_integral(double mu, double sigma, double lo, double hi) {
  const double s = sigma * std::sqrt(2.0);
  return sigma * std::sqrt(kPi / 2.0) * (boost::math::erf((hi - mu) / s) - boost::math::erf((lo - mu) / s));
}

namespace {

double bump(double x, double mu, double sigma) { return std::exp(-0.5 * sqr((x - mu) / sigma)); }

Integrand1D by_quadrature(Integrand1D g) {
  g.integral = integrate_1d(g.f, 0.0, 1.0, g.breakpoints).value;
  g.description["integral_by"] = "adaptive Gauss-Kronrod (61 points, rel. tol 1e-12) split at breakpoints";
  return g;
}

std::vector<Integrand1D> make_1d() {
  std::vector<Integrand1D> v;
  v.push_back({"smooth", [](double x) { return 1.0 + x + 0.5 * std::sin(2.0 * kPi * x); }, 1.5, {}, false,
               {{"formula", "1 + x + 0.5 sin(2 pi x)"}, {"integral_by", "closed form: 3/2"}}});
  v.push_back({"gaussian_peak", [](double x) { return bump(x, 0.3, 0.05); }, gaussian_bump_integral(0.3, 0.05, 0, 1),
               {}, false, {{"formula", "exp(-(x - 0.3)^2 / (2 0.05^2))"}, {"integral_by", "closed form (erf)"}}});
  v.push_back({"gaussian_mixture",
               [](double x) { return 0.6 * bump(x, 0.25, 0.04) + 0.4 * bump(x, 0.75, 0.08); },
               0.6 * gaussian_bump_integral(0.25, 0.04, 0, 1) + 0.4 * gaussian_bump_integral(0.75, 0.08, 0, 1), {}, false,
               {{"formula", "0.6 exp(-(x-0.25)^2/(2 0.04^2)) + 0.4 exp(-(x-0.75)^2/(2 0.08^2))"},
                {"integral_by", "closed form (erf)"}}});
  v.push_back({"step", [](double x) { return x >= 0.6 ? 1.25 : 0.25; }, 0.25 + 0.4, {0.6}, false,
               {{"formula", "0.25 + [x >= 0.6]"}, {"integral_by", "closed form: 0.65"}}});
  v.push_back({"kink", [](double x) { return std::abs(x - 0.4) + 0.1; }, 0.36, {0.4}, false,
               {{"formula", "|x - 0.4| + 0.1"}, {"integral_by", "closed form: (0.4^2 + 0.6^2)/2 + 0.1"}}});
  v.push_back({"narrow_spike", [](double x) { return 0.5 + bump(x, 0.7, 0.002); },
               0.5 + gaussian_bump_integral(0.7, 0.002, 0, 1), {0.7}, false,
               {{"formula", "0.5 + exp(-(x - 0.7)^2 / (2 0.002^2))"}, {"integral_by", "closed form (erf)"}}});
  v.push_back({"singularity", [](double x) { return x > 0.0 ? 0.5 / std::sqrt(x) : 0.0; }, 1.0, {}, true,
               {{"formula", "1 / (2 sqrt(x))"}, {"integral_by", "closed form: 1"},
                {"note", "integrable singularity at 0; infinite variance under uniform sampling"}}});
  v.push_back(by_quadrature({"product",
                             [](double x) { return (1.0 + x) * (x < 0.55 ? 1.0 : 0.3) * (0.2 + bump(x, 0.5, 0.1)); },
                             0.0, {0.55}, false,
                             {{"formula", "(1 + x) (x < 0.55 ? 1 : 0.3) (0.2 + exp(-(x - 0.5)^2 / (2 0.1^2)))"}}}));
  // The integrand of the mmis-fig1 experiment (docs/mmis-fig1.md): a step-shaped plateau on the left
  // and a Gaussian peak on the right.
  v.push_back({"fig1_two_features",
               [](double x) { return 0.05 + (x >= 0.1 && x < 0.35 ? 1.0 : 0.0) + 2.0 * bump(x, 0.72, 0.03); },
               0.05 + 0.25 + 2.0 * gaussian_bump_integral(0.72, 0.03, 0, 1), {0.1, 0.35}, false,
               {{"formula", "0.05 + [0.1 <= x < 0.35] + 2 exp(-(x - 0.72)^2 / (2 0.03^2))"},
                {"integral_by", "closed form (erf)"}}});
  // The integrand of the mmis-fig1 bottom experiment: three features for three non-covering techniques.
  v.push_back({"fig1_three_peaks",
               [](double x) { return 0.1 + bump(x, 0.15, 0.03) + 1.5 * bump(x, 0.5, 0.05) + bump(x, 0.85, 0.03); },
               0.1 + gaussian_bump_integral(0.15, 0.03, 0, 1) + 1.5 * gaussian_bump_integral(0.5, 0.05, 0, 1) +
                   gaussian_bump_integral(0.85, 0.03, 0, 1),
               {}, false,
               {{"formula", "0.1 + exp(-(x-0.15)^2/(2 0.03^2)) + 1.5 exp(-(x-0.5)^2/(2 0.05^2)) + exp(-(x-0.85)^2/(2 0.03^2))"},
                {"integral_by", "closed form (erf)"}}});
  for (auto& g : v) g.description["name"] = g.name;
  return v;
}

std::vector<Integrand2D> make_2d() {
  std::vector<Integrand2D> v;
  v.push_back({"smooth_2d", [](Vec2 p) { return (1.0 + p.x) * (1.0 + p.y * p.y); }, 2.0, false,
               {{"formula", "(1 + x)(1 + y^2)"}, {"integral_by", "closed form: 3/2 * 4/3"}}});
  v.push_back({"gaussian_2d", [](Vec2 p) { return bump(p.x, 0.4, 0.1) * bump(p.y, 0.6, 0.1); },
               gaussian_bump_integral(0.4, 0.1, 0, 1) * gaussian_bump_integral(0.6, 0.1, 0, 1), false,
               {{"formula", "exp(-((x-0.4)^2 + (y-0.6)^2) / (2 0.1^2))"}, {"integral_by", "closed form (erf)"}}});
  v.push_back({"quarter_disk_2d", [](Vec2 p) { return p.x * p.x + p.y * p.y < 0.64 ? 1.0 : 0.0; }, kPi * 0.64 / 4.0,
               false, {{"formula", "[x^2 + y^2 < 0.8^2]"}, {"integral_by", "closed form: pi 0.64 / 4"}}});
  v.push_back({"step_times_peak_2d", [](Vec2 p) { return ((p.x >= 0.5) + 0.2) * (0.1 + bump(p.y, 0.3, 0.05)); },
               0.7 * (0.1 + gaussian_bump_integral(0.3, 0.05, 0, 1)), false,
               {{"formula", "([x >= 0.5] + 0.2) (0.1 + exp(-(y-0.3)^2/(2 0.05^2)))"}, {"integral_by", "closed form (erf)"}}});
  v.push_back({"kink_2d", [](Vec2 p) { return std::abs(p.x - p.y); }, 1.0 / 3.0, false,
               {{"formula", "|x - y|"}, {"integral_by", "closed form: 1/3"}}});
  v.push_back({"singular_2d", [](Vec2 p) { return p.x > 0 && p.y > 0 ? 0.25 / std::sqrt(p.x * p.y) : 0.0; }, 1.0, true,
               {{"formula", "1 / (4 sqrt(x y))"}, {"integral_by", "closed form: 1"}}});
  for (auto& g : v) g.description["name"] = g.name;
  return v;
}

template <class V>
const auto& find_by_name(const V& v, const std::string& name) {
  std::string known;
  for (const auto& g : v) {
    if (g.name == name) return g;
    known += (known.empty() ? "" : ", ") + g.name;
  }
  throw std::invalid_argument("unknown integrand '" + name + "' (known: " + known + ")");
}

}  // namespace

const std::vector<Integrand1D>& integrands_1d() {
  static const std::vector<Integrand1D> v = make_1d();
  return v;
}
const std::vector<Integrand2D>& integrands_2d() {
  static const std::vector<Integrand2D> v = make_2d();
  return v;
}
const Integrand1D& integrand_1d(const std::string& name) { return find_by_name(integrands_1d(), name); }
const Integrand2D& integrand_2d(const std::string& name) { return find_by_name(integrands_2d(), name); }

}  // namespace tb
