#include "validate/render/broken_path_filter.h"

#include "lib/integrator/path_filter_impl.h"

namespace tb {
namespace {

struct OmitQueryWeights {
  static FilteringWeight weight(std::span<const double> column, int own, int query, double classical) {
    return pf1_weight_omitting_query(column, own, query, classical);
  }
};

}  // namespace

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
  if (integrator != "pf1" || fault != kPf1OmitsQuery) return {};
  return [](const World& w, const RenderSettings& st, Film& film) {
    return detail::render_pf1_with<OmitQueryWeights>(w, st, film);
  };
}

}  // namespace tb
