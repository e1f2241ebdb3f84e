// An MLT mixture through run_mlt on a small image against BDPT, each chain one Welch sample
// (docs/mlt-path-space.md: the estimator is unbiased for every chain length), compared per
// pixel-channel by compare_channels (Šidák over pixels and channels, Stouffer, sum z^2): the image
// checks of the half-vector mutation (mcmc.hslt.image.*) and of the manifold perturbation
// (mcmc.memlt.image.*). BDPT: 2048 (quick) / 8192 (full) spp in 32 passes; MLT: 48 / 128 chains of
// 160 samples per pixel each.
#pragma once

#include <memory>
#include <string>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/mlt.h"
#include "validate/registry.h"
#include "validate/render/render_compare.h"

namespace tb {

// `mutation`: the name whose acceptance the message reports; `what`: the message's prefix (after
// which the mutation's own statistics may follow). broken: passes when the comparison rejects.
inline CheckResult mlt_image_against_bdpt(const CheckContext& cx, const std::string& name, const std::string& file,
                                          int max_depth, const path_space::MltOptions& o, bool broken, double alpha,
                                          const std::string& mutation, const std::function<std::string()>& what) {
  constexpr int kImage = 8;
  const std::unique_ptr<World> world = load_scene_at_resolution(file, kImage, kImage);
  Film ref(kImage, kImage);
  RenderSettings rs;
  rs.spp = cx.size(2048, 8192);
  rs.passes = 32;
  rs.max_depth = max_depth;
  rs.seed = hash_values(cx.seed, hash_string(name + ".bdpt"));
  render_bdpt(*world, rs, ref);
  Film film(kImage, kImage);
  RenderSettings st;
  st.passes = cx.size(48, 128);
  st.spp = st.passes * 160;
  st.max_depth = max_depth;
  st.seed = hash_values(cx.seed, hash_string(name));
  const path_space::MltStats s = path_space::run_mlt(*world, st, film, o);
  const ChannelCompare c = compare_channels(film.welch(), ref.welch(), alpha);
  CheckResult res;
  res.passed = broken ? c.rejects() : !c.rejects();
  res.statistic_name = "p (Šidák over pixel channels)";
  res.statistic = c.p_value();
  res.p_value = c.p_value();
  res.alpha = alpha;
  res.samples = s.mutations_total;
  double acc = 0.0;
  for (const auto& m : s.mutations)
    if (m.name == mutation) acc = m.acceptance_rate();
  res.message = fmt::format("{} chains x {} mutations, {} (acceptance {:.3f}) against BDPT: {}", s.chains,
                            s.mutations_total / std::max<int64_t>(1, s.chains), what(), acc, c.message());
  if (broken) res.message = (res.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + res.message;
  res.details = c.details();
  for (const auto& m : s.mutations) res.details["acceptance_" + m.name] = m.acceptance_rate();
  return res;
}

}  // namespace tb
