// Broken copies of the half-vector mutation (lib/mcmc/path_space/hslt_mutation.h) for the negative
// controls of validate/checks/mcmc_hslt_checks.cpp, built from its public parts:
//  - HsltNoReverseCheck: proposes the forward walk's result without the reverse walk (Sec. 5.2)
//    and states T = N(delta) |det J_area| without either landing indicator, so moves whose reverse
//    walk does not return (or reaches another path) are accepted with a positive reverse density;
//  - hslt_density_without_measure: T without the change of measure (|det J_area| and the Dirac
//    factors of Eq. 3-7, Eq. 11): the density in h^perp taken for the density in the path measure.
//  - hslt_jump_density_without_g_ratio, HsltJumpWithoutGRatio: the subspace jump (Sec. 5.2) stated
//    without the G-ratio of its projection step.
#pragma once

#include <optional>

#include "lib/mcmc/path_space/hslt_mutation.h"

namespace tb::path_space {

class HsltNoReverseCheck {
 public:
  using State = MltPath;
  explicit HsltNoReverseCheck(HsltMutation m) : m_(std::move(m)) {}
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const {
    if (!m_.applicable(x)) return std::nullopt;
    const std::optional<HsltPath> X = m_.hslt_path(x);
    if (!X) return std::nullopt;
    const HsltWalkResult r = m_.walk(*X, m_.perturbed_target(*X, m_.step_factors(x, *X), u));
    if (r.status != HsltWalkStatus::kConverged) return std::nullopt;
    MltPath y = m_.path_at(x, r.path);
    if (!m_.applicable(y) || !m_.hslt_path(y, &*X)) return std::nullopt;
    return y;
  }
  double density(const MltPath& x, const MltPath& y) const {
    const HsltMutation::DensityParts p = parts_without_walks(x, y);
    return p.structure ? p.perturbation * p.measure : 0.0;
  }
  const HsltMutation& inner() const { return m_; }

 private:
  // density_parts without the two walks (the structure, perturbation and measure only).
  HsltMutation::DensityParts parts_without_walks(const MltPath& x, const MltPath& y) const {
    HsltMutation::DensityParts p;
    if (y.segments() != x.segments() || !m_.applicable(x) || !m_.applicable(y)) return p;
    const std::optional<HsltPath> X = m_.hslt_path(x);
    const std::optional<HsltPath> Y = X ? m_.hslt_path(y, &*X) : std::nullopt;
    if (!Y) return p;
    std::vector<bool> dirac;
    double g = 0.0;
    if (!m_.perturbation_density(m_.step_factors(x, *X), *X, *Y, &g, &dirac)) return p;
    p.structure = true;
    p.perturbation = g;
    p.measure = m_.measure_factor(*Y, dirac);
    return p;
  }
  HsltMutation m_;
};

// T(x -> y) with the measure factor dropped (the walks kept).
inline double hslt_density_without_measure(const HsltMutation& m, const MltPath& x, const MltPath& y) {
  const HsltMutation::DensityParts p = m.density_parts(x, y);
  return p.structure && p.forward_lands && p.reverse_lands ? p.perturbation : 0.0;
}

}  // namespace tb::path_space

namespace tb::path_space {

// The mutation with T stated without the change of measure (proposals unchanged): a registered
// mutation for the image negative control.
class HsltWithoutMeasure {
 public:
  using State = MltPath;
  explicit HsltWithoutMeasure(HsltMutation m) : m_(std::move(m)) {}
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const { return m_.propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const { return hslt_density_without_measure(m_, x, y); }
  bool applicable(const MltPath& x) const { return m_.applicable(x); }

 private:
  HsltMutation m_;
};

}  // namespace tb::path_space

namespace tb::path_space {

// The subspace jump (Sec. 5.2) with its density stated without the ratio of geometric terms
// G(y_prev, y_i) / G(y_prev, x'_i) of the projection (the tangent-plane density of the prediction
// taken for the density on the surface); the regular branch and the proposals unchanged.
inline double hslt_jump_density_without_g_ratio(const HsltMutation& m, const MltPath& x, const MltPath& y) {
  const HsltMutation::JumpParts p = m.jump_parts(x, y);
  if (!p.structure || !p.replay_lands || !p.bidirectionally_invalid) return 0.0;
  return p.perturbation * p.measure;
}

class HsltJumpWithoutGRatio {
 public:
  using State = MltPath;
  explicit HsltJumpWithoutGRatio(HsltMutation m) : m_(std::move(m)) {}
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const { return m_.propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const {
    const HsltMutation::DensityParts p = m_.density_parts(x, y);
    if (p.structure && p.forward_lands && p.reverse_lands) return m_.density(x, y);
    return hslt_jump_density_without_g_ratio(m_, x, y);
  }
  bool applicable(const MltPath& x) const { return m_.applicable(x); }

 private:
  HsltMutation m_;
};

}  // namespace tb::path_space
