// An image of Welch samples (Jung, Hanika & Dachsbacher 2020; docs/validation.md A): per pixel and
// channel the sum and the sum of squares of n Welch samples, a Welch sample being the average
// of several raw samples (one film pass). From these, the per-pixel mean and the unbiased
// sample variance of the Welch samples, which Welch's t-test compares between two images.
#pragma once

#include <cstdint>
#include <vector>

#include "lib/core/spectrum.h"

namespace tb {

struct WelchImage {
  int width = 0, height = 0;
  std::vector<Rgb> sum, sum_sq;   // per pixel, per channel
  // Sum of cubes, for the skewness of the Welch samples (the skew-corrected comparison,
  // validate/image_compare.h). Empty when not known (an image rebuilt from moments without it).
  std::vector<Rgb> sum_cu;
  std::vector<int64_t> count;     // Welch samples per pixel

  WelchImage() = default;
  WelchImage(int w, int h)
      : width(w), height(h), sum(size_t(w) * size_t(h), Rgb(0.0)), sum_sq(size_t(w) * size_t(h), Rgb(0.0)),
        sum_cu(size_t(w) * size_t(h), Rgb(0.0)), count(size_t(w) * size_t(h), 0) {}
  size_t pixels() const { return sum.size(); }

  void add(size_t pixel, const Rgb& welch_sample) {
    sum[pixel] += welch_sample;
    sum_sq[pixel] += welch_sample * welch_sample;
    if (!sum_cu.empty()) sum_cu[pixel] += welch_sample * welch_sample * welch_sample;
    ++count[pixel];
  }
  Rgb mean(size_t pixel) const { return count[pixel] > 0 ? sum[pixel] / double(count[pixel]) : Rgb(0.0); }
  // Unbiased sample variance of the Welch samples, (sum_sq - sum^2 / n) / (n - 1), clamped at
  // 0 against round-off; 0 when n < 2.
  Rgb variance(size_t pixel) const {
    const double n = double(count[pixel]);
    if (n < 2) return Rgb(0.0);
    return glm::max(Rgb(0.0), (sum_sq[pixel] - sum[pixel] * sum[pixel] / n) / (n - 1.0));
  }
  bool has_third_moment() const { return sum_cu.size() == sum.size(); }
  // Third central moment of the Welch samples, (1/n) sum (x - mean)^3 (0 when n < 3).
  Rgb third_central_moment(size_t pixel) const {
    const double n = double(count[pixel]);
    if (n < 3 || !has_third_moment()) return Rgb(0.0);
    const Rgb m = sum[pixel] / n;
    return sum_cu[pixel] / n - 3.0 * m * (sum_sq[pixel] / n) + 2.0 * m * m * m;
  }
  // Rebuilds the sums from a mean, a sample variance, a count and, when given, the third central
  // moment (references stored as EXR; without it the third moment reads as 0).
  void set_from_moments(size_t pixel, const Rgb& mean, const Rgb& var, int64_t n, const Rgb& m3 = Rgb(0.0)) {
    const double dn = double(n);
    count[pixel] = n;
    sum[pixel] = dn * mean;
    const Rgb m2 = n >= 2 ? (dn - 1.0) / dn * var : Rgb(0.0);  // biased second central moment
    sum_sq[pixel] = dn * m2 + dn * mean * mean;
    if (has_third_moment()) sum_cu[pixel] = dn * (m3 + 3.0 * mean * m2 + mean * mean * mean);
  }
};

}  // namespace tb
