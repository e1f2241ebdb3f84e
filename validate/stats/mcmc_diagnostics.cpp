#include "validate/stats/mcmc_diagnostics.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <unsupported/Eigen/FFT>

#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb::stats {
namespace {

// Biased autocovariance c_k = (1/n) sum_t (x_t - mean)(x_{t+k} - mean), k = 0..max_lag, by FFT of
// the zero-padded centred series (padding to >= 2n avoids circular wrap-around).
std::vector<double> autocovariance(std::span<const double> x, int64_t max_lag) {
  const size_t n = x.size();
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(n);
  size_t size = 1;
  while (size < 2 * n) size <<= 1;
  std::vector<double> padded(size, 0.0);
  for (size_t i = 0; i < n; ++i) padded[i] = x[i] - mean;
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, padded);
  for (auto& c : spectrum) c = std::complex<double>(std::norm(c), 0.0);
  std::vector<double> acov;
  fft.inv(acov, spectrum);
  const size_t lags = static_cast<size_t>(max_lag) + 1;
  std::vector<double> out(lags);
  for (size_t k = 0; k < lags; ++k) out[k] = acov[k] / static_cast<double>(n);
  return out;
}

// Geyer 1992, Sec. 3.3: tau = -1 + 2 sum_{m=0}^{M} Gamma_m with Gamma_m = rho_{2m} + rho_{2m+1},
// M the last index of the initial positive (and optionally monotone) sequence.
std::pair<double, int64_t> geyer_tau(const std::vector<double>& rho, GeyerSequence seq) {
  double sum = 0.0;
  double previous = std::numeric_limits<double>::infinity();
  int64_t last_lag = 0;
  for (size_t m = 0; 2 * m + 1 < rho.size(); ++m) {
    double gamma = rho[2 * m] + rho[2 * m + 1];
    if (!(gamma > 0.0)) break;
    if (seq == GeyerSequence::kInitialMonotone) gamma = std::min(gamma, previous);
    previous = gamma;
    sum += gamma;
    last_lag = static_cast<int64_t>(2 * m + 1);
  }
  return {-1.0 + 2.0 * sum, last_lag};
}

void require_chains(const std::vector<std::vector<double>>& chains) {
  if (chains.empty()) throw std::invalid_argument("mcmc diagnostics: no chains");
  for (const auto& c : chains)
    if (c.size() != chains[0].size() || c.size() < 4)
      throw std::invalid_argument("mcmc diagnostics: chains must have equal length >= 4");
}

// Splits each chain into its two halves (a trailing odd sample is dropped).
std::vector<std::vector<double>> split_halves(const std::vector<std::vector<double>>& chains) {
  std::vector<std::vector<double>> out;
  const size_t half = chains[0].size() / 2;
  for (const auto& c : chains) {
    out.emplace_back(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(half));
    out.emplace_back(c.begin() + static_cast<std::ptrdiff_t>(half), c.begin() + static_cast<std::ptrdiff_t>(2 * half));
  }
  return out;
}

struct VarianceParts {
  double w = 0.0;         // mean within-chain variance
  double var_plus = 0.0;  // (n-1)/n W + B/n
};

// Gelman et al. 2013 (BDA3), Eq. 11.2-11.3, on already split chains.
VarianceParts variance_parts(const std::vector<std::vector<double>>& chains) {
  const double n = static_cast<double>(chains[0].size());
  Welford means;
  double w = 0.0;
  for (const auto& c : chains) {
    Welford wc;
    for (double v : c) wc.add(v);
    means.add(wc.mean());
    w += wc.variance();
  }
  w /= static_cast<double>(chains.size());
  const double b_over_n = chains.size() > 1 ? means.variance() : 0.0;  // B/n = var of chain means
  return {w, (n - 1.0) / n * w + b_over_n};
}

double rhat_of_split(const std::vector<std::vector<double>>& split) {
  const VarianceParts p = variance_parts(split);
  if (p.w <= 0.0) return p.var_plus > 0.0 ? std::numeric_limits<double>::infinity() : 1.0;
  return std::sqrt(p.var_plus / p.w);
}

// Vehtari et al. 2021, Eq. 14: z = Phi^{-1}((r - 3/8) / (S + 1/4)) with average ranks r of the
// pooled draws, returned in the shape of the input.
std::vector<std::vector<double>> rank_normalize(const std::vector<std::vector<double>>& chains) {
  std::vector<std::pair<double, size_t>> pooled;
  for (size_t c = 0; c < chains.size(); ++c)
    for (size_t i = 0; i < chains[c].size(); ++i) pooled.push_back({chains[c][i], c * chains[0].size() + i});
  std::sort(pooled.begin(), pooled.end());
  const double s = static_cast<double>(pooled.size());
  std::vector<std::vector<double>> out(chains.size(), std::vector<double>(chains[0].size()));
  for (size_t i = 0; i < pooled.size();) {
    size_t j = i;
    while (j < pooled.size() && pooled[j].first == pooled[i].first) ++j;
    const double rank = 0.5 * static_cast<double>(i + 1 + j);  // average of ranks i+1..j
    const double z = normal_quantile((rank - 0.375) / (s + 0.25));
    for (size_t t = i; t < j; ++t) {
      const size_t idx = pooled[t].second;
      out[idx / chains[0].size()][idx % chains[0].size()] = z;
    }
    i = j;
  }
  return out;
}

}  // namespace

std::vector<double> autocorrelation(std::span<const double> x, int64_t max_lag) {
  const int64_t n = static_cast<int64_t>(x.size());
  if (n < 2) throw std::invalid_argument("autocorrelation: n < 2");
  if (max_lag < 0 || max_lag > n - 1) max_lag = n - 1;
  std::vector<double> c = autocovariance(x, max_lag);
  const double c0 = c[0];
  for (double& v : c) v = c0 > 0.0 ? v / c0 : 0.0;
  if (c0 > 0.0) c[0] = 1.0;
  return c;
}

AutocorrelationTime integrated_autocorrelation_time(std::span<const double> x, GeyerSequence seq) {
  if (x.size() < 4) throw std::invalid_argument("integrated_autocorrelation_time: n < 4");
  AutocorrelationTime r;
  r.n = static_cast<int64_t>(x.size());
  const std::vector<double> rho = autocorrelation(x);
  if (rho[1] == 0.0 && std::all_of(x.begin(), x.end(), [&](double v) { return v == x[0]; })) {
    r.constant = true;
    r.tau = 1.0;
    r.ess = static_cast<double>(r.n);
    return r;
  }
  const auto [tau, lag] = geyer_tau(rho, seq);
  // A tiny or negative tau comes from estimation noise: cap ESS at n log10(n), as Stan does.
  r.tau = std::max(tau, 1.0 / std::log10(static_cast<double>(r.n)));
  r.truncation_lag = lag;
  r.ess = static_cast<double>(r.n) / r.tau;
  return r;
}

double effective_sample_size(std::span<const double> x) { return integrated_autocorrelation_time(x).ess; }

double split_rhat(const std::vector<std::vector<double>>& chains) {
  require_chains(chains);
  return rhat_of_split(split_halves(chains));
}

double rank_normalized_split_rhat(const std::vector<std::vector<double>>& chains) {
  require_chains(chains);
  const auto split = split_halves(chains);
  const double bulk = rhat_of_split(rank_normalize(split));
  // Folded draws |x - median| (Vehtari et al. 2021, Sec. 4.2).
  std::vector<double> all;
  for (const auto& c : split) all.insert(all.end(), c.begin(), c.end());
  const size_t mid = all.size() / 2;
  std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(mid), all.end());
  double median = all[mid];
  if (all.size() % 2 == 0) {
    const double below = *std::max_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(mid));
    median = 0.5 * (median + below);
  }
  auto folded = split;
  for (auto& c : folded)
    for (double& v : c) v = std::fabs(v - median);
  const double tail = rhat_of_split(rank_normalize(folded));
  return std::max(bulk, tail);
}

double multichain_ess(const std::vector<std::vector<double>>& chains) {
  require_chains(chains);
  const auto split = split_halves(chains);
  const VarianceParts p = variance_parts(split);
  const size_t n = split[0].size();
  const double total = static_cast<double>(n * split.size());
  if (p.var_plus <= 0.0) return total;
  std::vector<double> mean_acov(n, 0.0);
  for (const auto& c : split) {
    const std::vector<double> ac = autocovariance(c, static_cast<int64_t>(n) - 1);
    for (size_t k = 0; k < n; ++k) mean_acov[k] += ac[k] / static_cast<double>(split.size());
  }
  // Vehtari et al. 2021, Eq. 10: rho_t = 1 - (W - mean_m(s_m^2 rho_{t,m})) / var+, with the biased
  // per-chain autocovariances in place of s_m^2 rho_{t,m}.
  std::vector<double> rho(n);
  for (size_t k = 0; k < n; ++k) rho[k] = 1.0 - (p.w - mean_acov[k]) / p.var_plus;
  rho[0] = 1.0;
  const double tau = geyer_tau(rho, GeyerSequence::kInitialMonotone).first;
  return total / std::max(tau, 1.0 / std::log10(total));
}

}  // namespace tb::stats
