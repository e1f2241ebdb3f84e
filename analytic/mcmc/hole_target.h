// A density with a hole: the standard normal on R^2 with the disk |x| < r0 removed,
//   pi(x) = N(x; 0, I) 1[|x| >= r0].
// In polar coordinates the radius has P(R > r | R > r0) = exp(-(r^2 - r0^2) / 2) and the angle is
// uniform, which gives exact draws by inversion and exact masses of polar bins (annulus sectors).
// One extra bin of zero mass collects states inside the hole: a chain that enters it fails the
// chi-square test outright. Measure: Lebesgue on R^2.
#pragma once

#include <algorithm>
#include <cmath>

#include "analytic/mcmc/normal.h"

namespace tb::mcmc {

class HoleTarget {
 public:
  using State = Point<2>;
  explicit HoleTarget(double r0 = 1.2) : r0_(r0) {}

  double radius() const { return r0_; }
  double density(const State& x) const {
    const double r2 = x[0] * x[0] + x[1] * x[1];
    return r2 < r0_ * r0_ ? 0.0 : std::exp(-0.5 * r2) / (2.0 * kPi);
  }

  State sample_exact(Uniforms& u) const {
    const double v = 1.0 - u.next();  // in (0, 1]
    const double r = std::sqrt(r0_ * r0_ - 2.0 * std::log(v));
    const double phi = 2.0 * kPi * u.next();
    return {r * std::cos(phi), r * std::sin(phi)};
  }

  // kRadial radial cells of width kDr from r0 (the last one unbounded) times kAngular sectors,
  // plus the hole.
  static constexpr int kRadial = 9, kAngular = 7;
  static constexpr double kDr = 0.3;
  int bin_count() const { return kRadial * kAngular + 1; }
  int bin_of(const State& x) const {
    const double r = std::hypot(x[0], x[1]);
    if (r < r0_) return kRadial * kAngular;
    const int ir = std::min(kRadial - 1, static_cast<int>((r - r0_) / kDr));
    double phi = std::atan2(x[1], x[0]);
    if (phi < 0) phi += 2.0 * kPi;
    const int ia = std::min(kAngular - 1, static_cast<int>(phi / (2.0 * kPi) * kAngular));
    return ir * kAngular + ia;
  }
  double bin_mass(int i) const {
    if (i == kRadial * kAngular) return 0.0;
    const int ir = i / kAngular;
    const double ra = r0_ + ir * kDr, rb = r0_ + (ir + 1) * kDr;
    const double tail_a = std::exp(-0.5 * (ra * ra - r0_ * r0_));
    const double tail_b = ir == kRadial - 1 ? 0.0 : std::exp(-0.5 * (rb * rb - r0_ * r0_));
    return (tail_a - tail_b) / kAngular;
  }
  double summary(const State& x) const { return x[0]; }

 private:
  double r0_;
};

}  // namespace tb::mcmc
