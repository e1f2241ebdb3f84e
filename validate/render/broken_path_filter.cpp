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
  w.denominator -= column[static_cast<size_t>(query)];
  w.weight = safe_ratio(w.own_pdf, w.denominator);
  return w;
}

RenderFunction broken_path_filter(const std::string& integrator, const std::string& fault) {
  if (integrator != "pf1" || fault != kPf1OmitsQuery) return {};
  return [](const World& w, const RenderSettings& st, Film& film) {
    return detail::render_pf1_with<OmitQueryWeights>(w, st, film);
  };
}

}  // namespace tb
