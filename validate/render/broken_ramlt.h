// Negative controls of regional adaptive MLT (lib/mcmc/path_space/ramlt_perturbations.h) as
// wrappers of the production perturbations: the broken variant is built here, never a flag of
// lib/.
#pragma once

#include <cmath>
#include <memory>
#include <string>

#include "lib/core/math.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"

namespace tb::path_space {

// A regional adaptive perturbation whose density T(a -> b) is evaluated with the scale of b's
// region instead of a's: the reverse density T(y -> x) of a move then uses the region of x
// instead of y's (and the forward one y's), the bug of reading one cached sigma for both
// directions of a move across a region boundary. Otsu Eq. 2 requires sigma(a).
template <class P>
class RamltDestinationScale final : public PathMutation {
 public:
  explicit RamltDestinationScale(std::shared_ptr<const RamltMutation<P>> m) : m_(std::move(m)) {}
  std::string name() const override { return m_->name(); }
  double weight(const MltPath& x) const override { return m_->weight(x); }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return m_->propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override {
    return m_->proposal().density_at(x, y, y);
  }
  double scale(const MltPath& x) const override { return m_->scale(x); }

 private:
  std::shared_ptr<const RamltMutation<P>> m_;
};

// The regional adaptive multi-chain perturbation with its density stated with sigma_1 for every
// direction (the continued levels at sigma_1 instead of sigma_2, Otsu Sec. 5.2), while the
// proposal draws them at sigma_2: the bug of reading one scale for the whole kernel.
class RamltMultiChainWithoutSigma2 final : public PathMutation {
 public:
  explicit RamltMultiChainWithoutSigma2(std::shared_ptr<const RamltMultiChainMutation> m) : m_(std::move(m)) {}
  std::string name() const override { return m_->name(); }
  double weight(const MltPath& x) const override { return m_->weight(x); }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return m_->propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override {
    const auto& p = m_->proposal();
    const double s1 = p.scale().sigma(x);
    return p.density_with(x, y, s1, s1);
  }
  double scale(const MltPath& x) const override { return m_->scale(x); }

 private:
  std::shared_ptr<const RamltMultiChainMutation> m_;
};

// The truncated-normal angle density stated without the truncation mass Z(sigma) = erf(pi /
// (sigma sqrt 2)) (ramlt_direction.h): 2 N(t; 0, sigma^2) on [0, pi], which does not integrate to
// one once sigma is comparable with pi.
inline double angle_density_without_truncation(double t, double sigma) {
  if (!(t >= 0.0) || !(t <= kPi) || !(sigma > 0.0)) return 0.0;
  const double z = t / sigma;
  return 2.0 * std::exp(-0.5 * z * z) / (sigma * std::sqrt(2.0 * kPi));
}

}  // namespace tb::path_space
