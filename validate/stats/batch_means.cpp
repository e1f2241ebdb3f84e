#include "validate/stats/batch_means.h"

#include <cmath>
#include <stdexcept>

namespace tb::stats {

BatchMeans::BatchMeans(int64_t batch_size) : batch_size_(batch_size) {
  if (batch_size < 1) throw std::invalid_argument("BatchMeans: batch_size < 1");
}

void BatchMeans::add(double x) {
  if (!std::isfinite(x)) {
    ++nonfinite_;
    return;
  }
  current_.add(x);
  if (current_.count() == batch_size_) {
    means_.push_back(current_.mean());
    current_ = Welford();
  }
}

void BatchMeans::add_batch_mean(double mean) {
  if (!std::isfinite(mean)) {
    ++nonfinite_;
    return;
  }
  means_.push_back(mean);
}

Welford BatchMeans::summary() const {
  Welford w;
  for (double m : means_) w.add(m);
  return w;
}

TestResult BatchMeans::t_test(double mu0) const { return one_sample_t_test(summary(), mu0); }

double BatchMeans::asymptotic_variance() const { return static_cast<double>(batch_size_) * summary().variance(); }

std::vector<double> batch_means(std::span<const double> xs, int64_t batches) {
  if (batches < 1 || static_cast<size_t>(batches) > xs.size()) throw std::invalid_argument("batch_means: bad batch count");
  const size_t size = xs.size() / static_cast<size_t>(batches);
  std::vector<double> out(static_cast<size_t>(batches));
  for (size_t b = 0; b < out.size(); ++b) {
    Welford w;
    for (size_t i = b * size; i < (b + 1) * size; ++i) w.add(xs[i]);
    out[b] = w.mean();
  }
  return out;
}

}  // namespace tb::stats
