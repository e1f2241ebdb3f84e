// Algorithm 1 of Otsu et al. ("Regional Adaptive Metropolis Light Transport", lines 8-18, Eq. 4-6)
// over a growing set of regions: the per-region state of estimators/mcmc/adaptation.h's
// RegionalAdaptation (lambda_k, visits i_k, accumulated acceptance A_k, update count n_k) with the
// same update rule types (OtsuSignUpdate by default), plus the inheritance of a quadtree split
// (Otsu Sec. 6.2): every child of a split region starts from the parent's lambda and n_k / 4
// updates (so gamma_j continues from j = n_k / 4, Eq. 6), with empty visit and acceptance counts.
// Without splits it makes exactly RegionalAdaptation's updates (tests/render/ramlt_driver_test.cpp).
// With keep_record every batch of L reports is recorded (region, j, a_hat, gamma, lambda after);
// a frozen adapter (the FIXED partition) records its batches with gamma 0 and never updates.
#pragma once

#include <algorithm>
#include <vector>

#include "estimators/mcmc/adaptation.h"

namespace tb::path_space {

template <mcmc::AdaptationUpdate Update = mcmc::OtsuSignUpdate>
class SplittableAdaptation {
 public:
  SplittableAdaptation(int regions, mcmc::AdaptationOptions o, bool keep_record = false, bool frozen = false)
      : o_(o), keep_record_(keep_record), frozen_(frozen), lambda_(static_cast<size_t>(regions), o.lambda0), sum_(static_cast<size_t>(regions), 0.0),
        visits_(static_cast<size_t>(regions), 0), updates_(static_cast<size_t>(regions), 0) {}
  int regions() const { return static_cast<int>(lambda_.size()); }
  double lambda(int r) const { return lambda_[static_cast<size_t>(r)]; }
  double parameter(int r) const { return std::exp(0.5 * lambda(r)); }  // sigma_k (line 9)
  int updates(int r) const { return updates_[static_cast<size_t>(r)]; }
  const mcmc::AdaptationOptions& options() const { return o_; }
  const std::vector<mcmc::AdaptationUpdateRecord>& record() const { return record_; }

  // Algorithm 1, lines 11-18 (the update on the L-th visit, as RegionalAdaptation::observe).
  void observe(int r, double acceptance) {
    const size_t k = static_cast<size_t>(r);
    sum_[k] += acceptance;
    if (++visits_[k] < o_.batch) return;
    const double a_hat = sum_[k] / o_.batch;                  // Eq. 4
    sum_[k] = 0.0;
    visits_[k] = 0;
    if (frozen_) {
      if (keep_record_) record_.push_back({r, 0, a_hat, 0.0, lambda_[k]});
      return;
    }
    const int j = ++updates_[k];
    const double g = Update::gamma(o_, j);                    // Eq. 6
    lambda_[k] = std::max(o_.lambda_min, lambda_[k] + g * Update::direction(a_hat, o_.target_acceptance));  // Eq. 5
    if (keep_record_) record_.push_back({r, j, a_hat, g, lambda_[k]});
  }
  // Region `parent` was split into itself and `count` new regions appended at regions()
  // (QuadtreePartition::split): lambda copied, n_k / 4 updates, counters emptied (Otsu Sec. 6.2).
  void split(int parent, int count) {
    const size_t p = static_cast<size_t>(parent);
    const double l = lambda_[p];
    const int n = updates_[p] / 4;
    sum_[p] = 0.0;
    visits_[p] = 0;
    updates_[p] = n;
    for (int c = 0; c < count; ++c) {
      lambda_.push_back(l);
      sum_.push_back(0.0);
      visits_.push_back(0);
      updates_.push_back(n);
    }
  }

 private:
  mcmc::AdaptationOptions o_;
  bool keep_record_ = false, frozen_ = false;
  std::vector<double> lambda_, sum_;
  std::vector<int> visits_, updates_;
  std::vector<mcmc::AdaptationUpdateRecord> record_;
};

static_assert(mcmc::RegionAdapter<SplittableAdaptation<>>);

}  // namespace tb::path_space
