// The BDPT MIS weights over the techniques that can generate a path sum to one and every other
// technique gets weight zero (Veach 1997, Eq. 9.3: the condition for MIS to be unbiased), on paths
// BDPT samples on every shipped scene, paths through Dirac vertices included; which techniques can
// generate a path is enumerated independently of the MIS code (validate/render/mis_enumeration.h).
// Deterministic: identities to 1e-12 (sum) and 1e-9 (each weight against the enumeration's, BDPT's
// incremental weight against the from-scratch one); the negative control clears the Dirac flags
// of the densities and must be caught. docs/integrator-checks.md, section 6.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "validate/registry.h"
#include "validate/render/mis_enumeration.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

std::vector<std::string> shipped_scenes() {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(scenes_dir()))
    if (e.path().extension() == ".json") files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  return files;
}

CheckResult run_mis_invariant(const CheckContext& ctx, bool control) {
  MisInvariantOptions o;
  o.subpath_pairs = ctx.size(1000, 10000);
  o.max_depth = 6;
  o.seed = hash_values(ctx.seed, hash_string("integrator.bdpt.mis_invariant"));
  o.drop_dirac_flags = control;
  MisInvariantTally tally;
  double worst_incremental = 0.0;
  nlohmann::json per_scene = nlohmann::json::object();
  const auto files = shipped_scenes();
  for (size_t i = 0; i < files.size(); ++i) {
    const auto world = load_scene_at_resolution(files[i], 16, 16);
    const int64_t before = tally.paths, before_dirac = tally.paths_with_dirac;
    sample_mis_invariant(*world, files[i], o, &tally, &worst_incremental);
    per_scene[files[i]] = {{"paths", tally.paths - before}, {"paths_with_dirac", tally.paths_with_dirac - before_dirac}};
    ctx.progress(double(i + 1) / double(files.size()));
  }
  const bool holds = tally.holds() && worst_incremental <= 1e-9;
  CheckResult r;
  r.statistic_name = "max |sum of weights - 1|";
  r.statistic = tally.worst_sum;
  r.samples = tally.paths;
  r.details["scenes"] = per_scene;
  r.details["techniques"] = tally.techniques;
  r.details["techniques_that_can_generate"] = tally.can_generate;
  r.details["nonzero_weight_on_impossible_technique"] = tally.nonzero_invalid;
  r.details["worst_weight_on_impossible_technique"] = tally.worst_invalid;
  r.details["worst_weight_vs_enumeration"] = tally.worst_vs_enumeration;
  r.details["worst_incremental_vs_from_scratch"] = worst_incremental;
  r.details["sampled_by_impossible_technique"] = tally.sampled_invalid;
  r.details["first_violation"] = tally.first_violation;
  const std::string summary = fmt::format(
      "{} paths on {} scenes ({} through Dirac vertices), {} techniques ({} can generate their path): max |sum w - 1| "
      "{:.2g}, {} impossible techniques with weight != 0 (max {:.3g}), max |w - w_enum| {:.2g}, max |w_incr - w| "
      "{:.2g}",
      tally.paths, files.size(), tally.paths_with_dirac, tally.techniques, tally.can_generate, tally.worst_sum,
      tally.nonzero_invalid, tally.worst_invalid, tally.worst_vs_enumeration, worst_incremental);
  if (control) {
    r.passed = !holds && tally.paths_with_dirac > 0;
    r.message = fmt::format("negative control (Dirac flags cleared, must be caught): {}; {}",
                            r.passed ? "caught" : "NOT caught", summary) +
                (tally.first_violation.empty() ? "" : "; first: " + tally.first_violation);
  } else {
    r.passed = holds && tally.paths_with_dirac > 0 && tally.paths >= 100;
    r.message = summary + (tally.first_violation.empty() ? "" : "; first violation: " + tally.first_violation);
    if (tally.paths_with_dirac == 0) r.message += "; no path through a Dirac vertex was sampled";
  }
  return r;
}

TB_REGISTER_CHECK({.name = "integrator.bdpt.mis_invariant",
                   .description = "on paths bdpt samples on every shipped scene (Dirac vertices included), the power-"
                                  "heuristic weights of the techniques that can generate the path, enumerated "
                                  "independently, sum to 1 (1e-12), every other technique has weight 0, each weight "
                                  "equals the enumeration's (1e-9) and bdpt's incremental weight (1e-9)",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_mis_invariant(c, false); }});
TB_REGISTER_CHECK({.name = "integrator.bdpt.mis_invariant.control.dirac_flags_dropped",
                   .description = "negative control: the MIS weights computed with the Dirac flags cleared must "
                                  "violate the invariant of integrator.bdpt.mis_invariant",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_mis_invariant(c, true); }});

}  // namespace
}  // namespace tb
