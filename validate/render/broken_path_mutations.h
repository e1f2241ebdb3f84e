// Negative controls of path-space MLT as wrappers of the registered mutations (path_mutations.h):
// the production mutation with one factor of its stated density removed, handed to the unchanged
// driver (MltOptions::mutations) or to the checkers.
#pragma once

#include <memory>
#include <string>

#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/path_mutations.h"

namespace tb::path_space {

// The lens perturbation's T stated as a constant where it is positive: the raster-to-path
// Jacobians drop out of the ratio, so a = min(1, f(y) / f(x)).
class LensWithoutDensityRatio final : public PathMutation {
 public:
  explicit LensWithoutDensityRatio(std::shared_ptr<const PathMutation> m) : m_(std::move(m)) {}
  std::string name() const override { return m_->name(); }
  double weight(const MltPath& x) const override { return m_->weight(x); }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return m_->propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override { return m_->density(x, y) > 0.0 ? 1.0 : 0.0; }

 private:
  std::shared_ptr<const PathMutation> m_;
};

// The bidirectional mutation's density with the solid-angle densities of the added vertices (no
// |cos| / d^2 to area), i.e. p_{s'} without its geometry terms (Veach 1997, Sec. 11.4.2.1).
class BidirWithoutGeometryTerm final : public PathMutation {
 public:
  BidirWithoutGeometryTerm(const PathContext& ctx, int max_segments, double weight = 0.4)
      : b_(ctx, max_segments), weight_(weight) {}
  std::string name() const override { return "bidirectional"; }
  double weight(const MltPath&) const override { return weight_; }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return b_.propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override;
  // p_{s'}(y) without the |cos| / d^2 of the added vertices (the defect).
  double split_density(const MltPath& y, int l, int na, int s) const;
  const BidirectionalMutation& mutation() const { return b_; }

 private:
  BidirectionalMutation b_;
  double weight_;
};

// Any registered mutation with its stated density tilted, its sampler unchanged (the path-space
// analogue of broken_pss.h's MisstatedDensity): T'(x -> y) = T(x -> y) (1 + tilt cos a), a the angle
// between a fixed axis and the displacement y_i - x_i of the moved vertex nearest the light (the
// lowest index whose position changed); 1 where none moved or the length changed. For the
// negative control of mlt.path_space.registered_mutations.chi2: the tilt follows the direction of
// the move, which every projection resolves.
class MisstatedPathDensity final : public PathMutation {
 public:
  explicit MisstatedPathDensity(std::shared_ptr<const PathMutation> m, double tilt = 0.3)
      : m_(std::move(m)), tilt_(tilt) {}
  std::string name() const override { return m_->name(); }
  double weight(const MltPath& x) const override { return m_->weight(x); }
  double scale(const MltPath& x) const override { return m_->scale(x); }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return m_->propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override {
    const double t = m_->density(x, y);
    if (!(t > 0.0) || x.v.size() != y.v.size()) return t;
    const Vec3 axis = glm::normalize(Vec3(1.0, 2.0, 3.0));
    for (size_t i = 0; i < x.v.size(); ++i) {
      const Vec3 d = y.v[i].hit.p - x.v[i].hit.p;
      const double len = glm::length(d);
      if (len > 0.0) return t * (1.0 + tilt_ * glm::dot(d, axis) / len);
    }
    return t;
  }

 private:
  std::shared_ptr<const PathMutation> m_;
  double tilt_;
};

// The registered mutations with `name` replaced by its broken variant.
PathMutationList with_lens_without_density_ratio(const PathContext& ctx, const PathMutationSettings& s);
PathMutationList with_bidir_without_geometry_term(const PathContext& ctx, const PathMutationSettings& s);

}  // namespace tb::path_space
