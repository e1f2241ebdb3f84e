#include "validate/render/broken_path_mutations.h"

#include "lib/path/measure.h"

namespace tb::path_space {

double BidirWithoutGeometryTerm::split_density(const MltPath& y, int l, int na, int s) const {
  const double p = b_.split_density(y, l, na, s);
  // Each factor of p_{s'} is an area density pdf_next = pdf_solid_angle |cos| / d^2: remove the
  // |cos| / d^2 of every added vertex (the emitter origin y_0 has none).
  const std::vector<PathVertex>& v = y.v;
  double geometry = 1.0;
  for (int i = l + 1; i <= l + s; ++i)
    if (i >= 1 && !v[i - 1].infinite && !v[i].infinite)
      geometry *= solid_angle_to_area(1.0, v[i - 1].hit.p, v[i].hit.p, v[i].geometric_normal());
  for (int i = l + s + 1; i <= l + na; ++i)
    if (!v[i + 1].infinite && !v[i].infinite)
      geometry *= solid_angle_to_area(1.0, v[i + 1].hit.p, v[i].hit.p, v[i].geometric_normal());
  return geometry > 0.0 ? p / geometry : 0.0;
}

// The mutation's density (Veach 1997, Sec. 11.4.2.1) with the broken p_{s'}.
double BidirWithoutGeometryTerm::density(const MltPath& x, const MltPath& y) const {
  if (y.segments() < 1 || y.segments() > b_.max_segments()) return 0.0;
  const auto w = b_.way_between(x, y);
  if (!w) return 0.0;
  const double pd = b_.deletion_probability(x, w->l, w->m);
  const double pa = b_.addition_probability(x.segments(), w->kd(), w->ka);
  if (!(pd > 0.0) || !(pa > 0.0)) return 0.0;
  const std::vector<int> splits = b_.valid_splits(x, *w);
  if (splits.empty()) return 0.0;
  double sum = 0.0;
  for (int s : splits)
    if (b_.split_connectible(y, w->l, s)) sum += split_density(y, w->l, w->na(), s);
  return pd * pa * sum / static_cast<double>(splits.size());
}

namespace {

PathMutationList replace(PathMutationList list, const std::string& name, std::shared_ptr<const PathMutation> by) {
  for (auto& m : list)
    if (m->name() == name) m = by;
  return list;
}

}  // namespace

PathMutationList with_lens_without_density_ratio(const PathContext& ctx, const PathMutationSettings& s) {
  PathMutationList list = make_path_mutations(ctx, s);
  for (auto& m : list)
    if (m->name() == "lens") m = std::make_shared<const LensWithoutDensityRatio>(m);
  return list;
}

PathMutationList with_bidir_without_geometry_term(const PathContext& ctx, const PathMutationSettings& s) {
  const PathMutationInfo* info = find_path_mutation("bidirectional");
  return replace(make_path_mutations(ctx, s), "bidirectional",
                 std::make_shared<const BidirWithoutGeometryTerm>(ctx, s.max_segments, info ? info->weight : 0.4));
}

}  // namespace tb::path_space
