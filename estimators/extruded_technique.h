// A classical technique seen as a marginal one (West et al. 2022, Sec. 3.1, "Combining classical and
// marginal techniques"): extrude it over a technique space of identical conditional techniques,
// p(x | t) = p(x) for every t. The auxiliary variable carries no information (std::monostate) and
// consumes no uniforms.
#pragma once

#include <optional>
#include <variant>

#include "estimators/concepts.h"

namespace tb {

template <Technique C>
struct ExtrudedTechnique {
  using Aux = std::monostate;
  using Sample = typename C::Sample;
  C technique;

  std::optional<Aux> sample_aux(Uniforms&) const { return Aux{}; }
  std::optional<Sample> sample(const Aux&, Uniforms& u) const { return technique.sample(u); }
  // Same measure as C::pdf.
  double pdf(const Sample& x, const Aux&) const { return technique.pdf(x); }
  // The technique space is one point of unit mass, so p(t) = 1 and the marginal is p(x) itself: an
  // extruded technique is a tb::ContinuousTechnique, and CMIS over it is plain MC (cmis.h).
  double aux_pdf(const Aux&) const { return 1.0; }
  double marginal_pdf(const Sample& x) const { return technique.pdf(x); }
};

}  // namespace tb
