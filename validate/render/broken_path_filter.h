// Negative controls of pf1 (lib/integrator/path_filter.h): the renderer template with a broken MMIS
// weighting. "pf1~mmis_omits_query" in find_render_function (validate/render/broken_integrators.h).
#pragma once

#include <span>
#include <string>

#include "estimators/mmis_filtering.h"
#include "validate/render/broken_integrators.h"

namespace tb {

inline constexpr const char* kPf1OmitsQuery = "mmis_omits_query";

// pf1_mmis_weight with the query's own prefix left out of the denominator (its term p_query(w) dropped
// from the sum of Eq. 14 with K = 1): the weights of a kernel's techniques no longer sum to one.
FilteringWeight pf1_weight_omitting_query(std::span<const double> column, int own, int query, double classical);

// "pf1" with `fault` == kPf1OmitsQuery; empty otherwise.
RenderFunction broken_path_filter(const std::string& integrator, const std::string& fault);

}  // namespace tb
