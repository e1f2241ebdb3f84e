#include "validate/render/broken_path_filter.h"

#include "lib/integrator/path_filter_impl.h"
#include "lib/integrator/path_filter_multi_impl.h"

namespace tb {
namespace {

struct OmitQueryWeights {
  static FilteringWeight weight(std::span<const double> column, int own, int query, double classical) {
    return pf1_weight_omitting_query(column, own, query, classical);
  }
};

struct OmitOwnWeights : PfkExactWeights {
  static FilteringWeight path_weight(std::span<const PfkLevel> levels) { return pfk_weight_omitting_own(levels); }
};

}  // namespace

FilteringWeight pfk_weight_omitting_own(std::span<const PfkLevel> levels) {
  FilteringWeight w = pfk_mmis_weight(levels);
  double den = 1.0;
  for (size_t d = 0; d < levels.size(); ++d) {
    double s = 0.0;
    for (size_t t = 0; t < levels[d].column.size(); ++t)
      if (d == 0 || static_cast<int>(t) != levels[d].self) s += levels[d].column[t];
    den *= s;
  }
  w.denominator = den;
  w.weight = den > 0 ? w.own_pdf / den : 0.0;
  return w;
}

FilteringWeight pf1_weight_omitting_query(std::span<const double> column, int own, int query, double classical) {
  FilteringWeight w = pf1_mmis_weight(column, own, classical);
  double den = classical;  // the Eq. 14 sum (K = 1) over the members other than the query
  for (size_t j = 0; j < column.size(); ++j)
    if (static_cast<int>(j) != query) den += column[j];
  w.denominator = den;
  w.weight = den > 0 ? w.own_pdf / den : 0.0;  // a query alone in its kernel then counts nothing
  return w;
}

RenderFunction broken_path_filter(const std::string& integrator, const std::string& fault) {
  if (integrator == "pfk" && fault == kPfkOmitsOwn)
    return [](const World& w, const RenderSettings& st, Film& film) {
      return detail::render_pfk_with<OmitOwnWeights>(w, st, film);
    };
  if (integrator != "pf1" || fault != kPf1OmitsQuery) return {};
  return [](const World& w, const RenderSettings& st, Film& film) {
    return detail::render_pf1_with<OmitQueryWeights>(w, st, film);
  };
}

}  // namespace tb
