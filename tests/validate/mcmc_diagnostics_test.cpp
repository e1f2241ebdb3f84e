#include "validate/stats/mcmc_diagnostics.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "validate/stats/ar1_process.h"

namespace tb::stats {
namespace {

TEST(Autocorrelation, MatchesDirectSum) {
  Rng rng(3);
  std::vector<double> x(300);
  for (double& v : x) v = rng.uniform();
  const auto rho = autocorrelation(x, 10);
  double mean = 0;
  for (double v : x) mean += v / 300.0;
  double c0 = 0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  for (int k = 0; k <= 10; ++k) {
    double ck = 0;
    for (size_t t = 0; t + static_cast<size_t>(k) < x.size(); ++t) ck += (x[t] - mean) * (x[t + static_cast<size_t>(k)] - mean);
    EXPECT_NEAR(rho[static_cast<size_t>(k)], ck / c0, 1e-12);
  }
}

TEST(AutocorrelationTime, IidAndAr1) {
  Rng rng(5);
  const auto iid = ar1_chain(rng, 0.0, 1 << 16, 0.0, true);
  EXPECT_NEAR(integrated_autocorrelation_time(iid).tau, 1.0, 0.1);
  for (double rho : {0.5, 0.9, -0.5}) {
    Rng r2 = Rng::for_sample(7, 1, static_cast<uint64_t>(rho * 100 + 100));
    const auto x = ar1_chain(r2, rho, 1 << 17, 0.0, true);
    const double truth = ar1_autocorrelation_time(rho);
    for (auto seq : {GeyerSequence::kInitialPositive, GeyerSequence::kInitialMonotone}) {
      const auto t = integrated_autocorrelation_time(x, seq);
      EXPECT_NEAR(t.tau, truth, 0.1 * truth) << "rho " << rho;
      EXPECT_NEAR(t.ess, static_cast<double>(x.size()) / t.tau, 1e-9);
    }
  }
  const std::vector<double> constant(100, 2.0);
  EXPECT_TRUE(integrated_autocorrelation_time(constant).constant);
}

TEST(SplitRhat, MixedAndUnmixed) {
  std::vector<std::vector<double>> good, bad;
  for (uint64_t c = 0; c < 4; ++c) {
    Rng rng = Rng::for_sample(9, 2, c);
    good.push_back(ar1_chain(rng, 0.5, 4000, 0.0, true));
    Rng rng2 = Rng::for_sample(9, 3, c);
    bad.push_back(ar1_chain(rng2, 0.999, 4000, c % 2 == 0 ? 10.0 : -10.0, false));
  }
  EXPECT_LT(split_rhat(good), 1.01);
  EXPECT_LT(rank_normalized_split_rhat(good), 1.01);
  EXPECT_GT(split_rhat(bad), 1.1);
  EXPECT_GT(rank_normalized_split_rhat(bad), 1.1);
  // Multi-chain ESS of AR(0.5): about 4 * 4000 / 3.
  EXPECT_NEAR(multichain_ess(good), 16000.0 / 3.0, 0.15 * 16000.0 / 3.0);
  EXPECT_LT(multichain_ess(bad), 100.0);
}

TEST(SplitRhat, DetectsTrendWithinOneChain) {
  // A single chain drifting linearly: the halves differ, split R-hat sees it.
  std::vector<double> drift(1000);
  Rng rng(1);
  for (size_t i = 0; i < drift.size(); ++i) drift[i] = static_cast<double>(i) / 100.0 + rng.uniform();
  EXPECT_GT(split_rhat({drift}), 1.5);
}

}  // namespace
}  // namespace tb::stats
