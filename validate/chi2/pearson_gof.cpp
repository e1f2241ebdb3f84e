#include "validate/chi2/pearson_gof.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/non_central_chi_squared.hpp>
#include <fmt/format.h>

#include "lib/core/math.h"

namespace tb {

double pearson_detectable_noncentrality(int dof, double alpha, double power) {
  if (dof < 1 || !(alpha > 0 && alpha < 1) || !(power > alpha && power < 1)) return kInfinity;
  const double critical = boost::math::quantile(boost::math::complement(boost::math::chi_squared(dof), alpha));
  return boost::math::non_central_chi_squared::find_non_centrality(dof, critical, 1.0 - power);
}

double pearson_min_detectable_density_error(int dof, double n, double alpha, double power) {
  if (!(n > 0)) return kInfinity;
  return std::sqrt(pearson_detectable_noncentrality(dof, alpha, power) / n);
}

PearsonResult pearson_chi2_gof(std::span<const double> observed, std::span<const double> expected,
                               const PearsonOptions& options, const std::function<std::string(size_t)>& cell_name) {
  if (observed.size() != expected.size()) throw std::invalid_argument("pearson_chi2_gof: size mismatch");
  const auto name = [&](size_t i) { return cell_name ? cell_name(i) : fmt::format("cell {}", i); };
  PearsonResult r;
  const bool estimated = !options.expected_variance.empty();
  if (estimated && options.expected_variance.size() != expected.size())
    throw std::invalid_argument("pearson_chi2_gof: variance size mismatch");
  const auto var = [&](size_t i) { return estimated ? options.expected_variance[i] : 0.0; };

  // Hard failure: samples where the distribution puts no mass at all.
  for (size_t i = 0; i < observed.size(); ++i) {
    if (!estimated && expected[i] <= 0 && observed[i] > 0) {
      if (r.zero_expected_cells == 0) r.first_zero_expected_cell = name(i);
      ++r.zero_expected_cells;
      r.zero_expected_observed += observed[i];
    }
  }
  if (r.zero_expected_cells > 0) {
    r.p_value = 0;
    r.statistic = kInfinity;
    r.message = fmt::format("{} observation(s) in {} cell(s) of zero expected mass, first: {}",
                            r.zero_expected_observed, r.zero_expected_cells, r.first_zero_expected_cell);
    return r;
  }

  // Pool the small cells (Mitsuba 3, chi2.py): visit cells by increasing expected count; those
  // below the threshold go into one pooled cell. If the pool itself stays below the threshold,
  // it is merged into the smallest regular cell.
  std::vector<size_t> order(observed.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  struct Cell {
    double o, e, v;
  };
  std::vector<Cell> cells;
  CompensatedSum pool_o, pool_e, pool_v;
  for (size_t i : order) {
    if (expected[i] <= 0 && observed[i] <= 0 && var(i) <= 0) continue;  // no mass, no observations
    if (expected[i] < options.min_expected) {
      pool_o += observed[i];
      pool_e += std::max(0.0, expected[i]);
      pool_v += var(i);
      ++r.pooled_cells;
    } else {
      cells.push_back({observed[i], expected[i], var(i)});
    }
  }
  r.pooled_observed = pool_o.value();
  r.pooled_expected = pool_e.value();
  if (r.pooled_cells > 0) {
    if (r.pooled_expected >= options.min_expected || cells.empty()) {
      cells.push_back({r.pooled_observed, r.pooled_expected, pool_v.value()});
    } else {
      // cells are in increasing order of expected count: cells[0] is the smallest regular cell.
      cells[0].o += r.pooled_observed;
      cells[0].e += r.pooled_expected;
      cells[0].v += pool_v.value();
    }
  }
  r.cells = cells.size();
  CompensatedSum stat;
  for (const Cell& c : cells) {
    const double denom = c.e + c.v;
    if (denom > 0) {
      stat += sqr(c.o - c.e) / denom;
    } else if (c.o > 0) {  // an estimated pool of zero mass that holds observations
      stat += kInfinity;
    }
  }
  r.statistic = stat.value();
  r.dof = static_cast<int>(cells.size()) - 1;
  if (r.dof < 1) {
    r.p_value = 1;
    r.message = fmt::format("only {} cell(s) after pooling: no test possible", cells.size());
    return r;
  }
  const boost::math::chi_squared_distribution<double> chi2(r.dof);
  r.p_value = std::isfinite(r.statistic) ? boost::math::cdf(boost::math::complement(chi2, r.statistic)) : 0.0;
  r.message = fmt::format("chi2 = {:.1f}, dof = {}, p = {:.3g} ({} cells pooled, E = {:.1f})", r.statistic, r.dof,
                          r.p_value, r.pooled_cells, r.pooled_expected);
  return r;
}

}  // namespace tb
