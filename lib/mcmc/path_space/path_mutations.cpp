#include "lib/mcmc/path_space/path_mutations.h"

#include <algorithm>
#include <stdexcept>

#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/caustic_perturbation.h"
#include "lib/mcmc/path_space/hslt_mutation.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/manifold_perturbation.h"
#include "lib/mcmc/path_space/multi_chain_perturbation.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"

namespace tb::path_space {

namespace {

std::shared_ptr<const PathMutation> make_bidir(const PathContext& ctx, const PathMutationSettings& s, double w) {
  return std::make_shared<const PathProposalMutation<BidirectionalMutation>>(
      "bidirectional", w, BidirectionalMutation(ctx, s.max_segments));
}
std::shared_ptr<const PathMutation> make_lens(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const PathProposalMutation<LensPerturbation>>("lens", w, LensPerturbation(ctx, 0.1, 0.0));
}
std::shared_ptr<const PathMutation> make_caustic(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const PathProposalMutation<CausticPerturbation>>(
      "caustic", w, CausticPerturbation(ctx), [](const CausticPerturbation&, const MltPath& x) { return x.segments() >= 2; });
}
std::shared_ptr<const PathMutation> make_multi(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const PathProposalMutation<MultiChainPerturbation>>(
      "multi-chain", w, MultiChainPerturbation(ctx),
      [](const MultiChainPerturbation&, const MltPath& x) { return !multi_chain_levels(x).empty(); });
}

// The 20 x 20 screen grid of Otsu et al., Sec. 8.1, frozen at lambda = -6 (sigma = 0.05 rad): the
// registry's instances do not adapt, and at Otsu's lambda0 = 1 (sigma = 1.65 rad) almost every
// multi-chain proposal fails; the driver of ramlt.h builds its own, from lambda0 = 1, with live scales.
constexpr double kRegistryLambda = -6.0;
std::shared_ptr<const PathMutation> make_ramlt_lens(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const RamltLensMutation>(
      "ramlt-lens", w, RamltLensPerturbation(ctx, RegionalScale::uniform(ScreenPartition::make(ctx, "grid", 20), kRegistryLambda)));
}
std::shared_ptr<const PathMutation> make_ramlt_multi(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const RamltMultiChainMutation>(
      "ramlt-multichain", w,
      RamltMultiChainPerturbation(ctx, RegionalScale::uniform(ScreenPartition::make(ctx, "grid", 20), kRegistryLambda)));
}

std::shared_ptr<const PathMutation> make_hslt(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const PathProposalMutation<HsltMutation>>("hslt", w, HsltMutation(ctx), hslt_applies);
}

std::shared_ptr<const PathMutation> make_manifold(const PathContext& ctx, const PathMutationSettings&, double w) {
  return std::make_shared<const PathProposalMutation<ManifoldPerturbation>>("manifold", w, ManifoldPerturbation(ctx),
                                                                             manifold_applies);
}

std::vector<PathMutationInfo>& table() {
  static std::vector<PathMutationInfo> t = {
      {"bidirectional", "delete a subpath, regenerate it from both ends (Veach 1997, Sec. 11.4.2)", 0.4, make_bidir},
      {"lens", "perturb the image position, retrace the specular chain (Veach 1997, Sec. 11.4.3)", 0.3, make_lens},
      {"caustic", "perturb the direction at the light end of a caustic chain (Veach 1997, Sec. 11.4.3)", 0.3,
       make_caustic},
      {"multi-chain", "lens perturbation continued through several specular chains (Veach 1997, Sec. 11.4.3)", 0.2,
       make_multi},
      {"ramlt-lens", "regional adaptive lens perturbation: truncated-normal primary direction, sigma of the screen "
       "region (Otsu et al., Sec. 3, 5)", 0.5, make_ramlt_lens, false},
      {"ramlt-multichain", "regional adaptive multi-chain perturbation: truncated-normal directions, sigma of the "
       "screen region (Otsu et al., Sec. 3, 5)", 0.5, make_ramlt_multi, false},
      {"hslt", "half-vector mutation: perturb every half vector, walk to the new constraints, reverse check "
       "(Kaplanyan et al. 2014, Sec. 5, 6.1)", 0.5, make_hslt, false},
      {"manifold", "manifold perturbation: lens perturbation to the first non-specular vertex, the specular chain "
       "behind it re-solved by the half-vector walk, reverse check (Jakob and Marschner 2012, Sec. 5)", 0.5,
       make_manifold, false},
  };
  return t;
}

}  // namespace

const std::vector<PathMutationInfo>& path_mutations() { return table(); }

const PathMutationInfo* find_path_mutation(const std::string& name) { return mcmc::find_named(table(), name); }

void register_path_mutation(PathMutationInfo info) { mcmc::add_named(table(), std::move(info), "path mutation"); }

void unregister_path_mutation(const std::string& name) { mcmc::remove_named(table(), name); }

PathMutationList make_path_mutations(const PathContext& ctx, const PathMutationSettings& s) {
  PathMutationList out;
  for (const auto& m : table())
    if (m.in_default_mixture) out.push_back(m.make(ctx, s, m.weight));
  return out;
}

PathMutationList make_all_path_mutations(const PathContext& ctx, const PathMutationSettings& s) {
  PathMutationList out;
  for (const auto& m : table()) out.push_back(m.make(ctx, s, m.weight));
  return out;
}

}  // namespace tb::path_space
