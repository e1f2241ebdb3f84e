// Pearson's chi-square goodness of fit of observed counts against expected counts
// (docs/validation.md A). Cells with expected count below a threshold (5) are pooled into one
// cell, as Mitsuba 3's chi2 test does; any observation in a cell of zero expected mass fails
// hard (p = 0) and names the cell. dof = cells after pooling - 1; the p-value is the upper
// tail of Boost.Math's chi_squared distribution.
//
// Estimated expected counts (a Monte Carlo integral of the stated density, sampler_chi2.h): with
// expected_variance set, cell i's term is (O - E)^2 / (E + V_i), V_i the variance of the estimate
// E_i (O and E independent, so O - E has variance E + V under the null hypothesis; Gagunashvili's
// comparison of weighted and unweighted histograms, with the normalisation known), and a cell whose
// estimate is zero is pooled rather than a hard failure (the estimate may miss a sliver of mass).
#pragma once

#include <cstddef>
#include <functional>
#include <span>
#include <string>

namespace tb {

struct PearsonOptions {
  double min_expected = 5.0;  // cells below this expected count are pooled
  // Empty: exact expected counts. Else one variance per cell (same length as expected).
  std::span<const double> expected_variance = {};
};

struct PearsonResult {
  double statistic = 0;       // sum (O - E)^2 / E over the cells after pooling
  int dof = 0;                // cells after pooling - 1
  double p_value = 1;         // P(chi2_dof >= statistic); 0 on a zero-expected violation
  size_t cells = 0;           // cells after pooling
  size_t pooled_cells = 0;    // input cells merged into the pooled cell
  double pooled_expected = 0, pooled_observed = 0;
  // Observations where the expected count is exactly zero: a hard failure.
  double zero_expected_observed = 0;
  size_t zero_expected_cells = 0;
  std::string first_zero_expected_cell;  // name of the first such cell
  std::string message;                   // one line

  bool rejects(double alpha) const { return p_value < alpha; }
};

// Power of Pearson's test (docs/statistics.md, "What a passing check rules out"). Against an
// alternative whose cell probabilities are p'_i, the statistic is approximately non-central
// chi-square with dof degrees of freedom and non-centrality lambda = n sum_i (p'_i - p_i)^2 / p_i.
// Returns the lambda at which the test at level alpha rejects with probability `power` (Boost's
// non_central_chi_squared::find_non_centrality); infinite for dof < 1.
double pearson_detectable_noncentrality(int dof, double alpha, double power = 0.9);
// The smallest epsilon such that a density off by a factor (1 + epsilon) on one half of its mass
// and (1 - epsilon) on the other (halves made of whole cells) is rejected with probability
// `power` from n samples: lambda = n epsilon^2, so epsilon = sqrt(lambda / n).
double pearson_min_detectable_density_error(int dof, double n, double alpha, double power = 0.9);

// observed and expected have the same length; expected counts are in the same units as the
// observations (normalised to the number of samples). cell_name(i) names cell i in messages
// (default: "cell i").
PearsonResult pearson_chi2_gof(std::span<const double> observed, std::span<const double> expected,
                               const PearsonOptions& options = {},
                               const std::function<std::string(size_t)>& cell_name = {});

}  // namespace tb
