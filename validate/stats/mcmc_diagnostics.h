// Diagnostics of Markov-chain output (docs/validation.md E, "Diagnostics, not proofs"): the
// autocorrelation function, the integrated autocorrelation time by Geyer's initial sequence
// estimators, the effective sample size, and split R-hat over several chains.
//
// Definitions (for a stationary scalar chain x_t with variance sigma^2 and autocorrelation rho_k):
//   integrated autocorrelation time  tau = 1 + 2 sum_{k>=1} rho_k,  Var(mean) ~= tau sigma^2 / n,
//   effective sample size            ESS = n / tau.
// Geyer 1992, "Practical Markov chain Monte Carlo", Stat. Sci. 7(4), Sec. 3.3: sums of adjacent
// pairs Gamma_m = rho_{2m} + rho_{2m+1} are positive and decreasing for reversible chains; the
// initial positive sequence truncates at the first non-positive Gamma_m, the initial monotone
// sequence additionally replaces each Gamma_m by the minimum of the preceding ones.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace tb::stats {

// Sample autocorrelation rho_k for k = 0..max_lag (rho_0 = 1) with the biased (1/n) autocovariance
// estimator, which keeps the sequence positive semi-definite (Geyer 1992, Sec. 3.1). Computed by
// FFT (Eigen's unsupported FFT module) in O(n log n). max_lag < 0 means n - 1.
std::vector<double> autocorrelation(std::span<const double> x, int64_t max_lag = -1);

enum class GeyerSequence {
  kInitialPositive,  // truncate at the first Gamma_m <= 0
  kInitialMonotone,  // and force Gamma_m non-increasing (the default; smaller variance)
};

struct AutocorrelationTime {
  double tau = 1.0;          // integrated autocorrelation time (>= 1/n, may be < 1 for antithetic chains)
  double ess = 0.0;          // n / tau
  int64_t n = 0;             // chain length
  int64_t truncation_lag = 0;  // last lag included in the sum
  bool constant = false;     // zero sample variance: tau undefined, reported as 1, ess as n
};

// Integrated autocorrelation time of one chain (Geyer 1992, Sec. 3.3). Requires n >= 4.
AutocorrelationTime integrated_autocorrelation_time(std::span<const double> x,
                                                    GeyerSequence seq = GeyerSequence::kInitialMonotone);
// n / tau for one chain.
double effective_sample_size(std::span<const double> x);

// Split R-hat over m >= 1 chains of equal length n >= 4 (Gelman et al. 2013, BDA3 Sec. 11.4,
// Eq. 11.3-11.4): each chain is split in halves (a trailing odd sample is dropped), W = mean of
// within-half variances, B/n' = variance of the half means, var+ = (n'-1)/n' W + B/n',
// R-hat = sqrt(var+ / W). Values above 1.01 indicate non-mixing (Vehtari et al. 2021).
double split_rhat(const std::vector<std::vector<double>>& chains);
// Rank-normalized split R-hat (Vehtari, Gelman, Simpson, Carpenter & Bürkner 2021, "Rank-
// normalization, folding, and localization: an improved R-hat", Bayesian Anal. 16(2), Sec. 4.2):
// the maximum of split R-hat on the rank-normalized draws ("bulk") and on the rank-normalized
// |x - median| ("tail" / folded). Robust to heavy tails.
double rank_normalized_split_rhat(const std::vector<std::vector<double>>& chains);
// Multi-chain effective sample size (Vehtari et al. 2021, Sec. 3.2, Eq. 10-11): autocorrelations
// combined over chains through var+ and W, truncated by Geyer's initial monotone sequence.
double multichain_ess(const std::vector<std::vector<double>>& chains);

}  // namespace tb::stats
