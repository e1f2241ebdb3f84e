// The regional adaptive random walk on R^N (Otsu et al., Sec. 5.2, Eq. 2-3, with the proposal of
// their Algorithm 1, line 10, replaced by a Gaussian step): y = x + sigma(x) z, z ~ N(0, I), where
// sigma(x) = sigma_k of the region k = region_of(x) of a partition (estimators/mcmc/partition.h),
// read from a regional adapter (estimators/mcmc/adaptation.h). Hence
//   T(x -> y) = N(y; x, sigma(region(x))^2 I),   T(y -> x) = N(x; y, sigma(region(y))^2 I),
// which differ when x and y lie in different regions: the Hastings ratio carries both (Otsu et al.,
// Sec. 3; Eq. 2). It is a Mutation (mutation.h) whose scale(x) is sigma(x), so MutationMixture,
// MetropolisHastings and chain_step run it unchanged.
//
// And the analytic target of the regional adaptation checks: a narrow and a wide Gaussian mode in
// different cells of a two-cell grid, so that no single scale suits both.
#pragma once

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "analytic/mcmc/gaussian_mixture_target.h"
#include "analytic/mcmc/normal.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/mutation.h"
#include "estimators/mcmc/partition.h"

namespace tb::mcmc {

template <size_t N, Partition P, class Adapter>
class RegionalAdaptiveWalk final : public Mutation<Point<N>> {
 public:
  using State = Point<N>;
  // The adapter must outlive the mutation; its lambda is read at every call (frozen while chains
  // run, adaptive_chains.h).
  RegionalAdaptiveWalk(std::shared_ptr<const P> partition, const Adapter* adapter)
      : part_(std::move(partition)), ad_(adapter) {}
  std::string name() const override { return "regional_gaussian_walk"; }
  double weight(const State&) const override { return 1.0; }
  // sigma(x) = sigma_{region(x)} (Eq. 2; Algorithm 1, lines 8-9).
  double scale(const State& x) const override { return ad_->sigma(part_->region_of(x)); }
  std::optional<State> propose(const State& x, Uniforms& u) const override {
    const double s = scale(x);
    State y = x;
    for (size_t d = 0; d < N; ++d) y[d] += s * standard_normal(u);
    return y;
  }
  // T(x -> y) with the scale of x's region: density(y, x), the reverse, uses y's region.
  double density(const State& x, const State& y) const override { return density_with_scale(x, y, scale(x)); }
  static double density_with_scale(const State& x, const State& y, double s) {
    double p = 1.0;
    for (size_t d = 0; d < N; ++d) p *= normal_pdf(y[d], x[d], s);
    return p;
  }
  const P& partition() const { return *part_; }

 private:
  std::shared_ptr<const P> part_;
  const Adapter* ad_;
};

// The Metropolis-Hastings kernel of one regional adaptive walk.
template <size_t N, Partition P, class Adapter, class Tg>
auto regional_adaptive_kernel(Tg target, std::shared_ptr<const P> partition, const Adapter* adapter) {
  MutationList<Point<N>> parts{std::make_shared<const RegionalAdaptiveWalk<N, P, Adapter>>(std::move(partition), adapter)};
  return MetropolisHastings(std::move(target), MutationMixture<Point<N>>(std::move(parts)));
}

// 0.5 N(-2, 0.25^2) + 0.5 N(5, 2^2) on R, binned in 60 cells of 0.25 over [-4, 11] plus tails.
// Scales that reach a* = 0.5 differ by a factor of about 8 between the modes; the two-cell grid
// over [-8, 8) (cut at 0) puts the narrow mode in region 0 and the wide one (all but 0.6% of its
// mass) in region 1.
inline GaussianMixtureTarget<1> two_scale_1d() {
  return GaussianMixtureTarget<1>({{0.5, {-2.0}, {0.25}}, {0.5, {5.0}, {2.0}}}, GridBins<1>({-4.0}, {11.0}, 60));
}
inline PartitionBox<1> two_scale_box() { return {{-8.0}, {8.0}, {2}}; }

// A unimodal two-scale target on R: pi(x) proportional to exp(-x^2 / (2 s(x)^2)), s = 0.25 for x < 0
// and 2 for x >= 0 (a "split normal": continuous at 0, masses 1/9 and 8/9). The two cells of
// two_scale_box() hold one scale each and a chain crosses between them at every scale, so the ESS
// of x measures the local moves, not mode crossings as on two_scale_1d().
struct SplitNormalTarget {
  using State = Point<1>;
  static constexpr double kLeft = 0.25, kRight = 2.0;
  double density(const State& x) const {
    const double s = x[0] < 0.0 ? kLeft : kRight;
    return std::exp(-0.5 * x[0] * x[0] / (s * s));
  }
  State sample_exact(Uniforms& u) const {
    const bool left = u.next() < kLeft / (kLeft + kRight);
    const double z = std::abs(standard_normal(u));
    return {left ? -kLeft * z : kRight * z};
  }
  double summary(const State& x) const { return x[0]; }
};

}  // namespace tb::mcmc
