#include "lib/mcmc/pss/pss_state.h"

#include <algorithm>
#include <array>
#include <cstdint>
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

void PssState::reset(Rng rng, double sigma) {
  rng_ = rng;
  sigma_ = sigma;
  x_.clear();
  touched_.clear();
  iteration_ = 0;
  last_large_ = 0;
  large_ = false;
  stream_ = 0;
  index_.fill(0);
  rescaled_ = false;
  sigma_shared_ = 0.0;
  current_reads_.fill(0);
}

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
  touched_.clear();
  restart();
}

void PssState::accept() {
  if (large_) last_large_ = iteration_;
  commit_reads();
}

void PssState::reject() {
  for (const uint32_t i : touched_) {
    Coordinate& c = x_[i];
    c.value = c.backup_value;
    c.modified = c.backup_modified;
  }
  touched_.clear();
  --iteration_;
}

namespace {

// The ziggurat of N(0, 1) (Marsaglia & Tsang 2000, "The Ziggurat Method for Generating Random
// Variables", Sec. 2 and the tail of Sec. 3): the density f(x) = exp(-x^2 / 2) (unnormalised)
// covered by 128 horizontal strips of equal area V; strip 0 is the base rectangle [0, x_0] x
// [0, f(R)] plus the tail x > R (x_0 = V / f(R), x_1 = R), strip i >= 1 spans the heights
// f(x_i) .. f(x_{i+1}) with x_{i+1} = f^-1(V / x_i + f(x_i)), x_128 = 0. R and V are the paper's
// values for 128 strips. A draw picks a strip and a signed uniform position in it; inside the
// curve's rectangle (|x| < x_{i+1}) it is returned at once (98.8% of draws), otherwise the wedge
// or the tail decides. Exact in distribution, with one 64-bit draw per normal in the common case.
struct Ziggurat {
  static constexpr int kStrips = 128;
  static constexpr double kR = 3.442619855899;
  static constexpr double kV = 9.91256303526217e-3;
  std::array<double, kStrips + 1> x{};      // strip edges, decreasing; x[128] = 0
  std::array<double, kStrips + 1> fx{};     // f(x[i])
  std::array<double, kStrips> inner{};      // x[i + 1] / x[i]: the fast-accept bound on |u|
  Ziggurat() {
    const auto f = [](double v) { return std::exp(-0.5 * v * v); };
    x[0] = kV / f(kR);
    x[1] = kR;
    for (int i = 1; i < kStrips - 1; ++i) x[i + 1] = std::sqrt(-2.0 * std::log(kV / x[i] + f(x[i])));
    x[kStrips] = 0.0;
    for (int i = 0; i <= kStrips; ++i) fx[i] = f(x[i]);
    for (int i = 0; i < kStrips; ++i) inner[i] = x[i + 1] / x[i];
  }
};

const Ziggurat kZiggurat;

// The ziggurat's rare branches for the draw (strip i, position u) that missed the rectangle: the
// tail (strip 0) or the wedge; a rejected draw is followed by fresh ones, all in here.
[[gnu::noinline]] double normal_slow(Rng& rng, size_t i, double u) {
  const Ziggurat& z = kZiggurat;
  for (;;) {
    if (i == 0) {  // the tail |x| > R (Marsaglia 1964): R + a with a ~ exp(R), accepted w.p. exp(-a^2 / 2)
      double a, b;
      do {
        a = -std::log(1.0 - rng.uniform()) / Ziggurat::kR;
        b = -std::log(1.0 - rng.uniform());
      } while (b + b < a * a);
      return u < 0.0 ? -(Ziggurat::kR + a) : Ziggurat::kR + a;
    }
    const double v = u * z.x[i];
    // The wedge between x_{i+1} and x_i: a uniform height in the strip below f(v) accepts v.
    if (z.fx[i] + rng.uniform() * (z.fx[i + 1] - z.fx[i]) < std::exp(-0.5 * v * v)) return v;
    const uint64_t r = rng.next_u64();
    i = static_cast<size_t>(r & (Ziggurat::kStrips - 1));
    u = 2.0 * (static_cast<double>(r >> 11) * 0x1p-53) - 1.0;
    if (std::abs(u) < z.inner[i]) return u * z.x[i];
  }
}

// N(0, 1) by the ziggurat above. The strip index takes the low 7 bits of a 64-bit draw and the
// signed position u in (-1, 1) its top 53 bits, so the two are independent. The rectangle test,
// taken by 98.8% of the draws, is inlined into the lazy update.
inline double standard_normal(Rng& rng) {
  const uint64_t r = rng.next_u64();
  const size_t i = static_cast<size_t>(r & (Ziggurat::kStrips - 1));
  const double u = 2.0 * (static_cast<double>(r >> 11) * 0x1p-53) - 1.0;
  if (std::abs(u) < kZiggurat.inner[i]) return u * kZiggurat.x[i];
  return normal_slow(rng, i, u);
}

}  // namespace

void PssState::ensure_ready(size_t i) {
  if (i >= x_.size()) x_.resize(i + 1);
  Coordinate& c = x_[i];
  if (c.modified == iteration_) return;  // already brought up to date in this iteration
  touched_.push_back(static_cast<uint32_t>(i));
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
    c.value = wrap01(c.value + sigma_shared_ * standard_normal(rng_));
  } else {
    const int64_t n_small = iteration_ - c.modified;  // accepted small steps, this one included
    // sqrt(1) = 1 exactly: the common case (a coordinate read at every iteration) skips the sqrt.
    const double scale = n_small == 1 ? sigma_ : sigma_ * std::sqrt(static_cast<double>(n_small));
    if (n_small > 0) c.value = wrap01(c.value + scale * standard_normal(rng_));
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
