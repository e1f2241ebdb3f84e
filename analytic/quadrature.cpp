#include "analytic/quadrature.h"

#include <algorithm>

#include <boost/math/quadrature/gauss_kronrod.hpp>

namespace tb {

QuadratureResult integrate_1d(const std::function<double(double)>& g, double a, double b,
                              const std::vector<double>& breakpoints, double rel_tol) {
  std::vector<double> edges{a};
  for (double p : breakpoints)
    if (p > a && p < b) edges.push_back(p);
  edges.push_back(b);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  QuadratureResult r;
  for (size_t i = 0; i + 1 < edges.size(); ++i) {
    double err = 0.0;
    // max_depth 15: up to 2^15 panels per interval, enough for the narrow spikes of the catalogue.
    r.value += boost::math::quadrature::gauss_kronrod<double, 61>::integrate(g, edges[i], edges[i + 1], 15, rel_tol, &err);
    r.error_estimate += err;
  }
  return r;
}

}  // namespace tb
