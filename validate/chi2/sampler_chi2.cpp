#include "validate/chi2/sampler_chi2.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <fmt/format.h>

#include "lib/core/frame.h"
#include "lib/core/hash.h"
#include "lib/core/parallel.h"

namespace tb {

std::string Chi2Domain::describe() const {
  switch (kind) {
    case Chi2DomainKind::kInterval: return fmt::format("interval [{}, {}], {} bins", x_min, x_max, nx);
    case Chi2DomainKind::kRectangle:
      return fmt::format("rectangle [{}, {}] x [{}, {}], {} x {} bins", x_min, x_max, y_min, y_max, nx, ny);
    case Chi2DomainKind::kSphere: return fmt::format("sphere, {} (phi) x {} (cos theta) bins", nx, ny);
    case Chi2DomainKind::kHemisphere: return fmt::format("hemisphere, {} (phi) x {} (cos theta) bins", nx, ny);
  }
  return "?";
}

namespace chi2_detail {

Chi2Draw classify(const Chi2Domain& d, double x, const SamplerChi2Options&) {
  if (!(std::isfinite(x) && x >= d.x_min && x <= d.x_max))
    return {Chi2Draw::kOutside, {}, fmt::format("x = {:.17g}", x)};
  return {Chi2Draw::kOk, {x, 0.5 * (d.y_min + d.y_max)}, {}};
}

Chi2Draw classify(const Chi2Domain& d, const Vec2& p, const SamplerChi2Options&) {
  if (!(is_finite(p) && p.x >= d.x_min && p.x <= d.x_max && p.y >= d.y_min && p.y <= d.y_max))
    return {Chi2Draw::kOutside, {}, fmt::format("p = ({:.17g}, {:.17g})", p.x, p.y)};
  return {Chi2Draw::kOk, p, {}};
}

Chi2Draw classify(const Chi2Domain& d, const Vec3& w, const SamplerChi2Options& o) {
  const bool unit = is_finite(w) && std::abs(glm::length(w) - 1.0) <= o.unit_tolerance;
  // Hemisphere: z >= 0 exactly. A cap: z >= cos_min up to the unit-length tolerance.
  const bool upper = d.kind == Chi2DomainKind::kHemisphere ? w.z >= 0.0 : w.z >= d.y_min - o.unit_tolerance;
  if (!unit || !upper) return {Chi2Draw::kOutside, {}, fmt::format("w = ({:.17g}, {:.17g}, {:.17g})", w.x, w.y, w.z)};
  return {Chi2Draw::kOk, {spherical_phi(w), std::clamp(w.z, d.y_min, d.y_max)}, {}};
}

double param_to_point_pdf(const Chi2Domain&, Vec2 q, const std::function<double(double)>& pdf) { return pdf(q.x); }
double param_to_point_pdf(const Chi2Domain&, Vec2 q, const std::function<double(Vec2)>& pdf) { return pdf(q); }
double param_to_point_pdf(const Chi2Domain&, Vec2 q, const std::function<double(Vec3)>& pdf) {
  // d omega = d phi d cos(theta): the solid-angle density is the density in (phi, cos theta).
  return pdf(spherical_direction(safe_sqrt(1.0 - q.y * q.y), q.y, q.x));
}

}  // namespace chi2_detail

namespace {

using GaussKronrod = boost::math::quadrature::gauss_kronrod<double, 15>;

struct CellGeometry {
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
};

// Integral of the pdf over every cell: nested adaptive Gauss-Kronrod (15 points), so a
// discontinuity inside a cell (a cone's rim, a triangle's edge) is resolved by bisection.
std::vector<double> cell_masses(const Chi2Domain& d, const std::function<double(Vec2)>& pdf,
                                const SamplerChi2Options& o) {
  const CellGeometry g{d};
  std::vector<double> mass(static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny));
  const bool one_d = d.kind == Chi2DomainKind::kInterval;
  const unsigned depth = static_cast<unsigned>(o.quadrature_max_depth);
  parallel_for(mass.size(), [&](size_t c) {
    const int ix = static_cast<int>(c % static_cast<size_t>(d.nx)), iy = static_cast<int>(c / static_cast<size_t>(d.nx));
    const double ymid = 0.5 * (d.y_min + d.y_max);
    auto inner = [&](double y) {
      return GaussKronrod::integrate([&](double x) { return pdf({x, y}); }, g.x0(ix), g.x1(ix), depth,
                                     o.quadrature_tolerance);
    };
    // An interval's pdf does not depend on y and its density is per unit length.
    mass[c] = one_d ? inner(ymid) : GaussKronrod::integrate(inner, g.y0(iy), g.y1(iy), depth, o.quadrature_tolerance);
  });
  return mass;
}

// Monte Carlo integral of the pdf over every cell (SamplerChi2Options::monte_carlo_expected):
// mass and the variance of its estimate per cell, in units of probability.
struct CellEstimates {
  std::vector<double> mass, variance;
  int64_t evaluations = 0;
};
CellEstimates cell_masses_mc(const Chi2Domain& d, const std::function<double(Vec2)>& pdf, const SamplerChi2Options& o) {
  const CellGeometry g{d};
  const size_t n_cells = static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny);
  CellEstimates e;
  e.mass.resize(n_cells);
  e.variance.resize(n_cells);
  std::vector<int64_t> evals(n_cells, 0);
  const int reps = std::max(2, o.mc_replicates);
  const double n = static_cast<double>(o.samples);
  const uint64_t key = hash_values(o.key, hash_string("expected"));
  parallel_for(n_cells, [&](size_t c) {
    const int ix = static_cast<int>(c % static_cast<size_t>(d.nx)), iy = static_cast<int>(c / static_cast<size_t>(d.nx));
    const double x0 = g.x0(ix), y0 = g.y0(iy), wx = g.x1(ix) - x0, wy = g.y1(iy) - y0;
    Rng rng = Rng::for_sample(o.seed, key, c);
    for (int m = std::max(1, o.mc_grid_min);; m *= 2) {
      std::vector<double> rep(static_cast<size_t>(reps));
      for (int r = 0; r < reps; ++r) {
        CompensatedSum s;
        for (int j = 0; j < m; ++j)
          for (int i = 0; i < m; ++i) {
            const Vec2 u = rng.uniform2();
            s += pdf({x0 + (i + u.x) / m * wx, y0 + (j + u.y) / m * wy});
          }
        rep[static_cast<size_t>(r)] = s.value() / (static_cast<double>(m) * m) * wx * wy;
        evals[c] += static_cast<int64_t>(m) * m;
      }
      const double mean = std::accumulate(rep.begin(), rep.end(), 0.0) / reps;
      double ss = 0;
      for (double v : rep) ss += sqr(v - mean);
      const double var = ss / (reps - 1) / reps;
      e.mass[c] = mean;
      e.variance[c] = var;
      if (n * n * var <= o.mc_variance_fraction * (n * mean + 1.0) || 2 * m > o.mc_grid_max) break;
    }
  });
  for (int64_t v : evals) e.evaluations += v;
  return e;
}

std::string cell_name(const Chi2Domain& d, size_t c) {
  const CellGeometry g{d};
  if (c == static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny)) return "failed samples (sampler returned nothing)";
  const int ix = static_cast<int>(c % static_cast<size_t>(d.nx)), iy = static_cast<int>(c / static_cast<size_t>(d.nx));
  const char* xn = (d.kind == Chi2DomainKind::kSphere || d.kind == Chi2DomainKind::kHemisphere) ? "phi" : "x";
  const char* yn = (d.kind == Chi2DomainKind::kSphere || d.kind == Chi2DomainKind::kHemisphere) ? "cos theta" : "y";
  if (d.kind == Chi2DomainKind::kInterval) return fmt::format("bin {} x in [{:.6g}, {:.6g}]", ix, g.x0(ix), g.x1(ix));
  return fmt::format("cell ({}, {}) {} in [{:.6g}, {:.6g}], {} in [{:.6g}, {:.6g}]", ix, iy, xn, g.x0(ix), g.x1(ix), yn,
                     g.y0(iy), g.y1(iy));
}

}  // namespace

SamplerChi2Result run_sampler_chi2(const Chi2Domain& d, const std::function<Chi2Draw(Rng&)>& draw,
                                   const std::function<double(Vec2)>& pdf_param, const SamplerChi2Options& o) {
  SamplerChi2Result r;
  r.domain = d;
  r.samples = o.samples;
  const CellGeometry g{d};
  const size_t n_cells = static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny);

  // Expected counts.
  const double n = static_cast<double>(o.samples);
  std::vector<double> mass;
  CompensatedSum total_variance;
  if (o.monte_carlo_expected) {
    CellEstimates e = cell_masses_mc(d, pdf_param, o);
    mass = std::move(e.mass);
    r.pdf_evaluations = e.evaluations;
    r.expected_variance.resize(n_cells);
    for (size_t c = 0; c < n_cells; ++c) {
      r.expected_variance[c] = n * n * e.variance[c];
      total_variance += e.variance[c];
    }
  } else {
    mass = cell_masses(d, pdf_param, o);
  }
  CompensatedSum total;
  for (double m : mass) total += m;
  r.pdf_integral = total.value();
  r.expected.resize(n_cells);
  for (size_t c = 0; c < n_cells; ++c) r.expected[c] = n * mass[c];

  // Observed counts: blocks of samples with local histograms; integer counts merge in any order.
  constexpr int64_t kBlock = 8192;
  const int64_t blocks = (o.samples + kBlock - 1) / kBlock;
  std::vector<int64_t> counts(n_cells, 0);
  int64_t failed = 0, outside = 0, first_outside_index = std::numeric_limits<int64_t>::max();
  std::mutex merge;
  parallel_for(static_cast<size_t>(blocks), [&](size_t b) {
    std::vector<int64_t> local(n_cells, 0);
    int64_t l_failed = 0, l_outside = 0, l_first = std::numeric_limits<int64_t>::max();
    std::string l_desc;
    const int64_t begin = static_cast<int64_t>(b) * kBlock, end = std::min(o.samples, begin + kBlock);
    for (int64_t i = begin; i < end; ++i) {
      Rng rng = Rng::for_sample(o.seed, o.key, static_cast<uint64_t>(i));
      const Chi2Draw s = draw(rng);
      if (s.status == Chi2Draw::kOk) {
        ++local[g.index(s.param)];
      } else if (s.status == Chi2Draw::kFailed) {
        ++l_failed;
      } else {
        if (l_outside++ == 0) {
          l_first = i;
          l_desc = s.describe;
        }
      }
    }
    std::lock_guard<std::mutex> lock(merge);
    for (size_t c = 0; c < n_cells; ++c) counts[c] += local[c];
    failed += l_failed;
    outside += l_outside;
    if (l_outside > 0 && l_first < first_outside_index) {
      first_outside_index = l_first;
      r.first_outside = fmt::format("sample {} (seed {}, key {}): {}", l_first, o.seed, o.key, l_desc);
    }
  });
  r.failed = failed;
  r.outside = outside;
  r.observed.assign(counts.begin(), counts.end());

  // The failure cell: samples the sampler declined to produce.
  std::vector<double> obs = r.observed, exp = r.expected;
  const double deficit = 1.0 - r.pdf_integral;
  obs.push_back(static_cast<double>(r.failed));
  exp.push_back(deficit > o.failure_mass_floor ? n * deficit : 0.0);
  std::vector<double> var = r.expected_variance;
  // The failure cell's estimate is 1 minus the sum of the cells' (independent) estimates.
  if (o.monte_carlo_expected) var.push_back(n * n * total_variance.value());
  r.gof = pearson_chi2_gof(obs, exp, {.min_expected = o.min_expected, .expected_variance = var},
                           [&](size_t c) { return cell_name(d, c); });

  // Worst cells by standardized residual.
  std::vector<Chi2Cell> cells;
  for (size_t c = 0; c < obs.size(); ++c) {
    if (exp[c] <= 0 && obs[c] <= 0) continue;
    Chi2Cell cell;
    if (c < n_cells) {
      cell.ix = static_cast<int>(c % static_cast<size_t>(d.nx));
      cell.iy = static_cast<int>(c / static_cast<size_t>(d.nx));
      cell.x0 = g.x0(cell.ix), cell.x1 = g.x1(cell.ix), cell.y0 = g.y0(cell.iy), cell.y1 = g.y1(cell.iy);
    } else {
      cell.ix = -1, cell.iy = -1;
    }
    cell.observed = obs[c];
    cell.expected = exp[c];
    const double v = exp[c] + (var.empty() ? 0.0 : var[c]);
    cell.residual = v > 0 ? (obs[c] - exp[c]) / std::sqrt(v) : kInfinity;
    cells.push_back(cell);
  }
  const size_t k = std::min(cells.size(), static_cast<size_t>(std::max(0, o.worst_cells)));
  std::partial_sort(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(k), cells.end(),
                    [](const Chi2Cell& a, const Chi2Cell& b) { return std::abs(a.residual) > std::abs(b.residual); });
  r.worst.assign(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(k));
  return r;
}

std::string SamplerChi2Result::message() const {
  if (outside > 0) return fmt::format("{} of {} samples outside the domain; first: {}", outside, samples, first_outside);
  return fmt::format("{}; {} failed samples; pdf integrates to {:.6f}", gof.message, failed, pdf_integral);
}

nlohmann::json SamplerChi2Result::details() const {
  nlohmann::json worst_json = nlohmann::json::array();
  for (const Chi2Cell& c : worst) {
    nlohmann::json w = {{"observed", c.observed}, {"expected", c.expected},
                        {"residual", std::isfinite(c.residual) ? nlohmann::json(c.residual) : nlohmann::json("Inf")}};
    if (c.ix >= 0)
      w.update({{"ix", c.ix}, {"iy", c.iy}, {"x", {c.x0, c.x1}}, {"y", {c.y0, c.y1}}});
    else
      w["cell"] = "failed samples";
    worst_json.push_back(w);
  }
  nlohmann::json j = {{"domain", domain.describe()},
                      {"samples", samples},
                      {"failed", failed},
                      {"outside", outside},
                      {"pdf_integral", pdf_integral},
                      {"chi2", std::isfinite(gof.statistic) ? nlohmann::json(gof.statistic) : nlohmann::json("Inf")},
                      {"dof", gof.dof},
                      {"p_value", p_value()},
                      {"cells_after_pooling", gof.cells},
                      {"pooled_cells", gof.pooled_cells},
                      {"pooled_expected", gof.pooled_expected},
                      {"worst_cells", worst_json}};
  if (!expected_variance.empty()) {
    double max_ratio = 0;  // largest V / E over cells with E >= 5
    for (size_t c = 0; c < expected.size(); ++c)
      if (expected[c] >= 5) max_ratio = std::max(max_ratio, expected_variance[c] / expected[c]);
    j["expected_by"] = "monte carlo";
    j["pdf_evaluations"] = pdf_evaluations;
    j["max_expected_variance_ratio"] = max_ratio;
  }
  if (outside > 0) j["first_outside"] = first_outside;
  if (gof.zero_expected_cells > 0) j["first_zero_expected_cell"] = gof.first_zero_expected_cell;
  return j;
}

namespace {
PlotSpec heatmap(const SamplerChi2Result& r, const std::string& title, const std::function<double(size_t)>& value) {
  const Chi2Domain& d = r.domain;
  PlotSpec p;
  p.title = title;
  const bool sph = d.kind == Chi2DomainKind::kSphere || d.kind == Chi2DomainKind::kHemisphere;
  p.x_label = sph ? "phi" : "x";
  p.y_label = sph ? "cos theta" : (d.kind == Chi2DomainKind::kInterval ? "" : "y");
  p.x_min = d.x_min, p.x_max = d.x_max, p.y_min = d.y_min, p.y_max = d.y_max;
  p.heatmap.assign(static_cast<size_t>(d.ny), std::vector<double>(static_cast<size_t>(d.nx)));
  for (size_t iy = 0; iy < static_cast<size_t>(d.ny); ++iy)
    for (size_t ix = 0; ix < static_cast<size_t>(d.nx); ++ix)
      p.heatmap[iy][ix] = value(iy * static_cast<size_t>(d.nx) + ix);
  return p;
}
}  // namespace

PlotSpec SamplerChi2Result::observed_heatmap(const std::string& title) const {
  return heatmap(*this, title, [&](size_t c) { return observed[c]; });
}
PlotSpec SamplerChi2Result::expected_heatmap(const std::string& title) const {
  return heatmap(*this, title, [&](size_t c) { return expected[c]; });
}
PlotSpec SamplerChi2Result::residual_heatmap(const std::string& title) const {
  return heatmap(*this, title, [&](size_t c) {
    return expected[c] > 0 ? (observed[c] - expected[c]) / std::sqrt(expected[c]) : (observed[c] > 0 ? kInfinity : 0.0);
  });
}

}  // namespace tb
