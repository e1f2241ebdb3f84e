// Batch means: a stream of (possibly correlated) observations cut into consecutive batches of
// equal size; the batch means are nearly independent and nearly normal when batches are long,
// so a one-sample t test on them tests the stream's mean (docs/validation.md A: 2^22 samples in 256
// batches, t test against the closed-form value). Also the batch-means estimate of the
// asymptotic variance of an MCMC average (Flegal & Jones 2010).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb::stats {

class BatchMeans {
 public:
  // Observations are grouped in batches of batch_size (>= 1) consecutive values.
  explicit BatchMeans(int64_t batch_size);

  // Adds one observation; when the current batch is full its mean is stored. Non-finite values
  // are counted (nonfinite()) and not added.
  void add(double x);
  // Appends an already computed batch mean (e.g. from a parallel loop over batches).
  void add_batch_mean(double mean);

  int64_t batch_size() const { return batch_size_; }
  int64_t batches() const { return static_cast<int64_t>(means_.size()); }
  // Observations in the unfinished last batch; they are not part of any statistic.
  int64_t pending() const { return current_.count(); }
  int64_t nonfinite() const { return nonfinite_; }
  const std::vector<double>& means() const { return means_; }

  // Moments of the batch means (their std_error() is the standard error of the grand mean).
  Welford summary() const;
  // Two-sided one-sample t test of the batch means against mu0, dof = batches - 1.
  TestResult t_test(double mu0) const;
  // Batch-means estimate of the asymptotic variance sigma^2 in sqrt(n)(mean - mu) -> N(0, sigma^2):
  // batch_size * var(batch means) (Flegal & Jones 2010, Eq. 6).
  double asymptotic_variance() const;

 private:
  int64_t batch_size_;
  int64_t nonfinite_ = 0;
  Welford current_;
  std::vector<double> means_;
};

// Means of `batches` equal consecutive batches of xs; a remainder of xs.size() % batches values
// at the end is dropped. Requires 1 <= batches <= xs.size().
std::vector<double> batch_means(std::span<const double> xs, int64_t batches);

}  // namespace tb::stats
