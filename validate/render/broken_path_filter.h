// Negative controls of pf1 (lib/integrator/path_filter.h) and pfk (path_filter_multi.h): the renderer
// templates with a broken MMIS weighting. "pf1~mmis_omits_query" and "pfk~mmis_omits_own" in
// find_render_function (validate/render/broken_integrators.h).
#pragma once

#include <span>
#include <string>

#include "estimators/mmis_filtering.h"
#include "lib/integrator/path_filter_multi.h"
#include "validate/render/broken_integrators.h"

namespace tb {

inline constexpr const char* kPf1OmitsQuery = "mmis_omits_query";
inline constexpr const char* kPfkOmitsOwn = "mmis_omits_own";

// pf1_mmis_weight with the query's own prefix left out of the denominator (its term p_query(w) dropped
// from the sum of Eq. 14 with K = 1): the weights of a kernel's techniques no longer sum to one.
FilteringWeight pf1_weight_omitting_query(std::span<const double> column, int own, int query, double classical);

// pfk_mmis_weight whose product of sums leaves out, at every filtered vertex x_d with d >= 2, the vertex's
// own technique (its term in S_d of Eq. 14): the weights over the techniques no longer sum to one.
FilteringWeight pfk_weight_omitting_own(std::span<const PfkLevel> levels);

// "pf1" with `fault` == kPf1OmitsQuery, "pfk" with kPfkOmitsOwn; empty otherwise.
RenderFunction broken_path_filter(const std::string& integrator, const std::string& fault);

}  // namespace tb
