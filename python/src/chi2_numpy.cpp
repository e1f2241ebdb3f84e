#include "python/src/chi2_numpy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <boost/math/quadrature/gauss.hpp>
#include <fmt/format.h>

#include "lib/core/frame.h"
#include "lib/core/math.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"

namespace tb::py_bindings {

namespace {

// The grid of a domain, as in the C++ tester: cell edges x_min + i dx, the last edge exactly x_max.
struct Grid {
  const Chi2Domain& d;
  double dx() const { return (d.x_max - d.x_min) / d.nx; }
  double dy() const { return (d.y_max - d.y_min) / d.ny; }
  double x0(int ix) const { return d.x_min + ix * dx(); }
  double x1(int ix) const { return ix + 1 == d.nx ? d.x_max : d.x_min + (ix + 1) * dx(); }
  double y0(int iy) const { return d.y_min + iy * dy(); }
  double y1(int iy) const { return iy + 1 == d.ny ? d.y_max : d.y_min + (iy + 1) * dy(); }
  size_t index(const Vec2& p) const {
    const int ix = std::clamp(static_cast<int>(std::floor((p.x - d.x_min) / dx())), 0, d.nx - 1);
    const int iy = std::clamp(static_cast<int>(std::floor((p.y - d.y_min) / dy())), 0, d.ny - 1);
    return static_cast<size_t>(iy) * static_cast<size_t>(d.nx) + static_cast<size_t>(ix);
  }
  size_t cells() const { return static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny); }
};

bool is_sphere(const Chi2Domain& d) {
  return d.kind == Chi2DomainKind::kSphere || d.kind == Chi2DomainKind::kHemisphere;
}

// The 7-point Gauss-Legendre rule on [-1, 1] (Boost.Math stores the non-negative half).
struct Rule {
  std::vector<double> x, w;
  Rule() {
    using G = boost::math::quadrature::gauss<double, 7>;
    const auto& a = G::abscissa();
    const auto& b = G::weights();
    for (size_t i = 0; i < a.size(); ++i) {
      x.push_back(a[i]);
      w.push_back(b[i]);
      if (a[i] != 0.0) {
        x.push_back(-a[i]);
        w.push_back(b[i]);
      }
    }
  }
};

// Writes the point of parameter (x, y) into out[0..dim).
void param_to_point(const Chi2Domain& d, double x, double y, double* out) {
  if (d.kind == Chi2DomainKind::kInterval) {
    out[0] = x;
  } else if (d.kind == Chi2DomainKind::kRectangle) {
    out[0] = x;
    out[1] = y;
  } else {
    // d omega = d phi d cos(theta): the solid-angle density is the density in (phi, cos theta).
    const Vec3 w = spherical_direction(safe_sqrt(1.0 - y * y), y, x);
    out[0] = w.x;
    out[1] = w.y;
    out[2] = w.z;
  }
}

Chi2Draw classify_row(const Chi2Domain& d, const double* p, const SamplerChi2Options& o) {
  switch (point_dimension(d)) {
    case 1: return chi2_detail::classify(d, p[0], o);
    case 2: return chi2_detail::classify(d, Vec2{p[0], p[1]}, o);
    default: return chi2_detail::classify(d, Vec3{p[0], p[1], p[2]}, o);
  }
}

std::string cell_name(const Chi2Domain& d, size_t c) {
  const Grid g{d};
  if (c == g.cells()) return "failed samples (sampler returned nothing)";
  const int ix = static_cast<int>(c % static_cast<size_t>(d.nx)), iy = static_cast<int>(c / static_cast<size_t>(d.nx));
  if (d.kind == Chi2DomainKind::kInterval) return fmt::format("bin {} x in [{:.6g}, {:.6g}]", ix, g.x0(ix), g.x1(ix));
  const char* xn = is_sphere(d) ? "phi" : "x";
  const char* yn = is_sphere(d) ? "cos theta" : "y";
  return fmt::format("cell ({}, {}) {} in [{:.6g}, {:.6g}], {} in [{:.6g}, {:.6g}]", ix, iy, xn, g.x0(ix), g.x1(ix), yn,
                     g.y0(iy), g.y1(iy));
}

// Integral of the pdf over every cell: s x s sub-cells, 7 x 7 Gauss-Legendre nodes each (7 nodes
// per sub-interval on an interval), all nodes of a chunk of cells evaluated in one pdf call.
std::vector<double> cell_masses(const Chi2Domain& d, const VectorPdf& pdf, const VectorChi2Options& o) {
  const Grid g{d};
  const Rule rule;
  const int s = std::max(1, o.subdivisions);
  const bool one_d = d.kind == Chi2DomainKind::kInterval;
  const int dim = point_dimension(d);
  const size_t k = rule.x.size();
  const size_t nodes_per_cell = one_d ? static_cast<size_t>(s) * k : static_cast<size_t>(s * s) * k * k;
  const size_t cells_per_call = std::max<size_t>(1, static_cast<size_t>(o.chunk) / nodes_per_cell);
  std::vector<double> mass(g.cells(), 0.0);
  std::vector<double> points, weights;
  for (size_t first = 0; first < g.cells(); first += cells_per_call) {
    const size_t last = std::min(g.cells(), first + cells_per_call);
    points.clear();
    weights.clear();
    for (size_t c = first; c < last; ++c) {
      const int ix = static_cast<int>(c % static_cast<size_t>(d.nx)), iy = static_cast<int>(c / static_cast<size_t>(d.nx));
      const double hx = (g.x1(ix) - g.x0(ix)) / s, hy = (g.y1(iy) - g.y0(iy)) / s;
      const double ymid = 0.5 * (d.y_min + d.y_max);
      for (int sy = 0; sy < (one_d ? 1 : s); ++sy) {
        for (int sx = 0; sx < s; ++sx) {
          const double cx = g.x0(ix) + (sx + 0.5) * hx, cy = g.y0(iy) + (sy + 0.5) * hy;
          for (size_t jy = 0; jy < (one_d ? 1 : k); ++jy) {
            for (size_t jx = 0; jx < k; ++jx) {
              const double x = cx + 0.5 * hx * rule.x[jx];
              const double y = one_d ? ymid : cy + 0.5 * hy * rule.x[jy];
              const double w = one_d ? 0.5 * hx * rule.w[jx] : 0.25 * hx * hy * rule.w[jx] * rule.w[jy];
              const size_t at = points.size();
              points.resize(at + static_cast<size_t>(dim));
              param_to_point(d, x, y, points.data() + at);
              weights.push_back(w);
            }
          }
        }
      }
    }
    const int64_t m = static_cast<int64_t>(weights.size());
    const std::vector<double> values = pdf(points, m);
    if (static_cast<int64_t>(values.size()) != m)
      throw std::invalid_argument(fmt::format("chi2_test: pdf returned {} values for {} points", values.size(), m));
    for (size_t i = 0; i < values.size(); ++i) {
      if (!std::isfinite(values[i]) || values[i] < 0.0) {
        std::string where;
        for (int j = 0; j < dim; ++j) where += fmt::format("{}{:.17g}", j ? ", " : "", points[i * static_cast<size_t>(dim) + static_cast<size_t>(j)]);
        throw std::invalid_argument(fmt::format("chi2_test: pdf({}) = {} (must be finite and >= 0)", where, values[i]));
      }
    }
    for (size_t c = first, i = 0; c < last; ++c) {
      CompensatedSum sum;
      for (size_t j = 0; j < nodes_per_cell; ++j, ++i) sum += weights[i] * values[i];
      mass[c] = sum.value();
    }
  }
  return mass;
}

}  // namespace

int point_dimension(const Chi2Domain& d) {
  if (d.kind == Chi2DomainKind::kInterval) return 1;
  if (d.kind == Chi2DomainKind::kRectangle) return 2;
  return 3;
}

SamplerChi2Result chi2_test_vectorized(const Chi2Domain& d, const VectorSampler& sample, const VectorPdf& pdf,
                                       const VectorChi2Options& o) {
  if (o.samples <= 0) throw std::invalid_argument("chi2_test: samples must be positive");
  if (d.nx <= 0 || d.ny <= 0) throw std::invalid_argument("chi2_test: the grid needs at least one cell");
  SamplerChi2Options co;
  co.samples = o.samples;
  co.seed = o.seed;
  co.key = o.key;
  co.min_expected = o.min_expected;
  co.failure_mass_floor = o.failure_mass_floor;
  co.unit_tolerance = o.unit_tolerance;

  const Grid g{d};
  const int dim = point_dimension(d);
  SamplerChi2Result r;
  r.domain = d;
  r.samples = o.samples;

  const std::vector<double> mass = cell_masses(d, pdf, o);
  CompensatedSum total;
  for (double m : mass) total += m;
  r.pdf_integral = total.value();
  const double n = static_cast<double>(o.samples);
  r.expected.resize(g.cells());
  for (size_t c = 0; c < g.cells(); ++c) r.expected[c] = n * mass[c];

  // Observed counts, chunk by chunk: uniforms from the same streams as the C++ tester.
  std::vector<int64_t> counts(g.cells(), 0);
  const int64_t chunk = std::max<int64_t>(1, o.chunk);
  std::vector<double> u;
  for (int64_t first = 0; first < o.samples; first += chunk) {
    const int64_t m = std::min(chunk, o.samples - first);
    u.assign(static_cast<size_t>(2 * m), 0.0);
    parallel_for(0, static_cast<size_t>(m), [&](size_t i) {
      Rng rng = Rng::for_sample(o.seed, o.key, static_cast<uint64_t>(first) + i);
      const Vec2 v = rng.uniform2();
      u[2 * i] = v.x;
      u[2 * i + 1] = v.y;
    }, 4096);
    const PointChunk points = sample(u, m);
    if (static_cast<int64_t>(points.values.size()) != m * dim)
      throw std::invalid_argument(fmt::format("chi2_test: sample returned {} numbers for {} points of dimension {}",
                                              points.values.size(), m, dim));
    if (!points.valid.empty() && static_cast<int64_t>(points.valid.size()) != m)
      throw std::invalid_argument("chi2_test: the validity mask needs one entry per sample");
    for (int64_t i = 0; i < m; ++i) {
      if (!points.valid.empty() && !points.valid[static_cast<size_t>(i)]) {
        ++r.failed;
        continue;
      }
      const Chi2Draw s = classify_row(d, points.values.data() + i * dim, co);
      if (s.status == Chi2Draw::kOk) {
        ++counts[g.index(s.param)];
      } else if (r.outside++ == 0) {
        r.first_outside = fmt::format("sample {} (seed {}, key {}): {}", first + i, o.seed, o.key, s.describe);
      }
    }
  }
  r.observed.assign(counts.begin(), counts.end());

  std::vector<double> obs = r.observed, exp = r.expected;
  const double deficit = 1.0 - r.pdf_integral;
  obs.push_back(static_cast<double>(r.failed));
  exp.push_back(deficit > o.failure_mass_floor ? n * deficit : 0.0);
  r.gof = pearson_chi2_gof(obs, exp, {.min_expected = o.min_expected}, [&](size_t c) { return cell_name(d, c); });
  return r;
}

}  // namespace tb::py_bindings
