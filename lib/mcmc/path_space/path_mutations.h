// The registered mutations of Veach's path-space MLT (Veach 1997, Sec. 11.4): each one is a
// Proposal on MltPath (its own file: bidirectional_mutation.h, lens_perturbation.h,
// caustic_perturbation.h, multi_chain_perturbation.h) made a registered component
// (estimators/mcmc/mutation.h) by PathProposalMutation, with its default selection weight and the
// paths it applies to. run_mlt (mlt.h) runs the mixture of every registered mutation; the pairwise,
// flux and chi-square checks of validate/ loop over the same list.
//
// Selection (Otsu et al., Sec. 3.2): c_j(x) = w_j [j applies to x] / sum_i w_i [i applies to x]
// with the defaults w = (0.4, 0.3, 0.3, 0.2) for (bidirectional, lens, caustic, multi-chain); the
// caustic perturbation applies to paths of at least two segments, the multi-chain perturbation to
// paths with its structure (multi_chain_levels non-empty); the others to every path (their
// proposals fail where they cannot act). Since c_j depends on the path, c_j(y) / c_j(x) enters the
// acceptance of moves that change the length or the specular structure.
//
// Otsu et al.'s regional adaptive lens and multi-chain perturbations (ramlt_perturbations.h) are
// registered too ("ramlt-lens", "ramlt-multichain", weight 0.5 as in Otsu Sec. 8.1), outside the
// default mixture; built from the registry they use the 20 x 20 grid with every lambda frozen at -6.
//
// Adding a mutation: a Proposal class in its own file and one line in the table of
// path_mutations.cpp (or register_path_mutation at run time).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "estimators/mcmc/mutation.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

using PathMutation = mcmc::Mutation<MltPath>;
using PathMutationList = mcmc::MutationList<MltPath>;
using PathMixture = mcmc::MutationMixture<MltPath>;

// What the registered mutations are built from.
struct PathMutationSettings {
  int max_segments = 11;  // longest path, in segments (max_depth + 1)
};

// A Proposal on paths as a registered mutation: constant weight where applies(p, x).
template <class P>
class PathProposalMutation final : public PathMutation {
 public:
  using Applies = bool (*)(const P&, const MltPath&);
  PathProposalMutation(std::string name, double weight, P p, Applies applies = nullptr)
      : name_(std::move(name)), weight_(weight), p_(std::move(p)), applies_(applies) {}
  std::string name() const override { return name_; }
  double weight(const MltPath& x) const override { return !applies_ || applies_(p_, x) ? weight_ : 0.0; }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return p_.propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override { return p_.density(x, y); }
  const P& proposal() const { return p_; }
  double base_weight() const { return weight_; }

 private:
  std::string name_;
  double weight_;
  P p_;
  Applies applies_;
};

struct PathMutationInfo {
  std::string name;
  std::string description;
  double weight = 1.0;  // default selection weight
  std::shared_ptr<const PathMutation> (*make)(const PathContext&, const PathMutationSettings&, double weight);
  // false: registered (checked by every registered-mutation check) but not part of Veach's mixture
  // that make_path_mutations builds for run_mlt (the regional adaptive perturbations of
  // ramlt_perturbations.h, run by their own driver, ramlt.h).
  bool in_default_mixture = true;
};

// Every registered mutation, in selection order.
const std::vector<PathMutationInfo>& path_mutations();
const PathMutationInfo* find_path_mutation(const std::string& name);
// Registers a mutation at run time (outside code, tests); not thread-safe: register before running.
void register_path_mutation(PathMutationInfo info);
// Removes a mutation registered at run time (tests that register one clean up after themselves).
void unregister_path_mutation(const std::string& name);
// The registered mutations of the default mixture built for a context (each with its default weight).
PathMutationList make_path_mutations(const PathContext& ctx, const PathMutationSettings& s);
// Every registered mutation, in the order of path_mutations(), default mixture or not.
PathMutationList make_all_path_mutations(const PathContext& ctx, const PathMutationSettings& s);

}  // namespace tb::path_space
