// The terms of the path tracer, light tracer and BDPT estimators that a negative control may get
// wrong on purpose. Each integrator is a template over a Terms type (path_tracer_impl.h,
// light_tracer_impl.h, bdpt_impl.h); lib/ instantiates only ExactTerms, so production code holds
// no switch for a deliberate error. The controls (validate/render/broken_integrators.h) derive
// from ExactTerms, change one term and instantiate the same templates.
#pragma once

#include "lib/path/scattering.h"

namespace tb {

struct ExactTerms {
  // Russian roulette divides survivors by their survival probability q (pbrt-v3 Sec. 13.7).
  static constexpr bool kRouletteDividesByQ = true;
  // Next-event estimation carries |cos| at the receiving vertex (Veach 1997, Eq. 8.8's G).
  static constexpr bool kNeeReceiverCosine = true;
  // MIS weights sum every technique's density in their denominator (Veach 1997, Eq. 9.13 / 10.9).
  static constexpr bool kMisFullDenominator = true;
  // The shading-normal factor of the adjoint BSDF on light subpaths (Veach 1997, Eq. 5.19).
  static constexpr ImportanceCorrection kImportanceCorrection = &importance_shading_correction;
};

}  // namespace tb
