#include "lib/mcmc/pss/pss_state.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tb::pss {

double wrapped_normal_pdf(double d, double sigma) {
  // r = d - round(d) in [-1/2, 1/2] and the images summed in pairs +-m: the result is bitwise
  // symmetric, g(d) = g(-d) (round is odd, and each pair is added in the same order).
  const double r = d - std::round(d);
  const double norm = 1.0 / (sigma * std::sqrt(2.0 * std::numbers::pi));
  auto phi = [sigma](double x) { return std::exp(-0.5 * (x / sigma) * (x / sigma)); };
  const int images = static_cast<int>(std::ceil(12.0 * sigma)) + 1;  // beyond: below 1e-31 of the peak
  double sum = phi(r);
  for (int m = 1; m <= images; ++m) sum += phi(r + m) + phi(r - m);
  return norm * sum;
}

PssState::PssState(Rng rng, double sigma) : rng_(rng), sigma_(sigma) {}

PssState PssState::at(const std::vector<double>& u, Rng rng, double sigma) {
  PssState s(rng, sigma);
  s.x_.resize(u.size());
  for (size_t i = 0; i < u.size(); ++i) {
    s.x_[i].value = u[i];
    s.x_[i].modified = 0;  // current at iteration 0 (= last_large_): never redrawn as stale
  }
  return s;
}

void PssState::start_iteration(bool large_step, double sigma_shared) {
  ++iteration_;
  large_ = large_step;
  sigma_shared_ = sigma_shared;
  restart();
}

void PssState::accept() {
  if (large_) last_large_ = iteration_;
  commit_reads();
}

void PssState::reject() {
  for (Coordinate& c : x_)
    if (c.modified == iteration_) {
      c.value = c.backup_value;
      c.modified = c.backup_modified;
    }
  --iteration_;
}

// A standard normal from two uniforms (Box & Muller 1958); 1 - u keeps the log argument in (0, 1].
// N(0, 1) by the polar method (Marsaglia & Bray 1964): (u, v) uniform in the unit disk by
// rejection from the square, then u f and v f with f = sqrt(-2 ln s / s), s = u^2 + v^2, are two
// independent standard normals; the second is kept for the next call. One log and no cosine per
// two normals.
double PssState::gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u, v, s;
  do {
    u = 2.0 * rng_.uniform() - 1.0;
    v = 2.0 * rng_.uniform() - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double f = std::sqrt(-2.0 * std::log(s) / s);
  spare_ = v * f;
  has_spare_ = true;
  return u * f;
}

void PssState::ensure_ready(size_t i) {
  if (i >= x_.size()) x_.resize(i + 1);
  Coordinate& c = x_[i];
  if (c.modified == iteration_) return;  // already brought up to date in this iteration
  c.backup_value = c.value;
  c.backup_modified = c.modified;
  if (c.modified < last_large_) {  // an accepted large step (or the initial draw) in the gap
    c.value = rng_.uniform();
    c.modified = last_large_;
  }
  if (large_) {
    c.value = rng_.uniform();
  } else if (rescaled_ && i / kStreams < current_reads_[i % kStreams]) {
    // In D(x) (and now read by y): x read it at iteration n = iteration_ - 1, so exactly this
    // iteration's step is pending, with the rescaled sigma(x).
    c.value = wrap01(c.value + sigma_shared_ * gaussian());
  } else {
    const int64_t n_small = iteration_ - c.modified;  // accepted small steps, this one included
    if (n_small > 0) c.value = wrap01(c.value + sigma_ * std::sqrt(static_cast<double>(n_small)) * gaussian());
  }
  c.modified = iteration_;
}

double PssState::next() {
  const size_t i = index_[stream_]++ * kStreams + static_cast<size_t>(stream_);
  ensure_ready(i);
  return x_[i].value;
}

double DenseStreams::next() {
  const size_t i = index_[stream_]++ * kStreams + static_cast<size_t>(stream_);
  if (i >= u_->size()) throw std::out_of_range("DenseStreams: coordinate beyond the state's dimension");
  max_read_ = std::max(max_read_, i + 1);
  return (*u_)[i];
}

}  // namespace tb::pss
