#include "lib/registry/integrator_registry.h"

#include <algorithm>
#include <cmath>

#include "lib/integrator/albedo_integrator.h"
#include "lib/integrator/bdpt.h"
#include "lib/integrator/light_tracer.h"
#include "lib/integrator/path_tracer.h"
#include "lib/integrator/path_filter.h"
#include "lib/integrator/path_filter_multi.h"
#include "lib/integrator/photon_map.h"
#include "lib/mcmc/apt_integrator.h"
#include "lib/mcmc/path_space/hslt_mutation.h"
#include "lib/mcmc/path_space/manifold_perturbation.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "lib/mcmc/path_space/stratified_mlt.h"
#include "lib/mcmc/pss/msmlt.h"
#include "lib/mcmc/pss/stratified_pss.h"
#include "lib/mcmc/pss/pss_driver.h"

namespace tb {

namespace {

std::vector<IntegratorParameter> ramlt_parameters() {
  std::vector<IntegratorParameter> out;
  for (const auto& [name, description] : path_space::ramlt_parameter_list()) out.push_back({name, description});
  return out;
}

std::vector<IntegratorParameter> pss_parameters() {
  return {{"bootstrap", "bootstrap samples per pass (default: PssSettings::bootstrap_for)"},
          {"chains", "chains per pass (default 64)"},
          {"large_step", "large-step probability (default 0.3)"},
          {"sigma", "small-step standard deviation (default 0.01)"},
          {"resample_levels", "MMLT: 1 draws each chain's path length with its start from the joint bootstrap "
                              "(pbrt-v3), 0 (default) fixes the mutations per length by a pilot bootstrap"}};
}

std::vector<IntegratorParameter> stratified_parameters() {
  std::vector<IntegratorParameter> p = pss_parameters();
  p.push_back({"mis_reduction", "1 (default): an s = 0 path's last direction, MIS-weighted against next-event "
                                "estimation, is left out of r~ (Zirr & Dachsbacher 2020, Sec. 6.6); 0: counted"});
  return p;
}

std::vector<IntegratorParameter> mlt_stratified_parameters() {
  return {{"mis_reduction", "1 (default): the last direction of a path read from the camera (towards the emitter, "
                            "MIS-weighted against next-event estimation) is left out of r~ (Zirr & Dachsbacher "
                            "2020, Sec. 6.6); 0: counted"},
          {"pilot", "BDPT samples of the pilot that estimates the brightness B (0, default: max(1024, pixels))"}};
}

std::vector<IntegratorParameter> photon_map_parameters(bool progressive) {
  std::vector<IntegratorParameter> out;
  for (const auto& [name, description] : photon_map_parameter_list(progressive)) out.push_back({name, description});
  return out;
}

std::vector<IntegratorParameter> to_parameters(const std::vector<std::pair<std::string, std::string>>& list) {
  std::vector<IntegratorParameter> out;
  for (const auto& [name, description] : list) out.push_back({name, description});
  return out;
}
std::vector<IntegratorParameter> pf1_parameters() { return to_parameters(pf1_parameter_list()); }
std::vector<IntegratorParameter> pfk_parameters() { return to_parameters(pfk_parameter_list()); }

}  // namespace

std::string validate_params(const IntegratorInfo& info, const std::map<std::string, double>& params) {
  for (const auto& [name, value] : params) {
    bool known = false;
    for (const auto& p : info.parameters) known = known || p.name == name;
    if (!known) {
      std::string names;
      for (const auto& p : info.parameters) names += (names.empty() ? "" : ", ") + p.name;
      return "integrator '" + info.name + "' has no parameter '" + name + "' (" +
             (names.empty() ? std::string("it takes none") : "it takes: " + names) + ")";
    }
    if (!std::isfinite(value)) return "parameter '" + name + "' must be a finite number";
  }
  return {};
}

const std::vector<IntegratorInfo>& integrators() {
  // An explicit table, not static registrars: tb_render is a static library and self-registering
  // objects in it would be dropped by the linker when nothing references them.
  static const std::vector<IntegratorInfo> table = [] {
    std::vector<IntegratorInfo> t = {
        {"albedo", "primary-hit albedo (emitted radiance on emitters, directional albedo by one BSDF sample)",
         render_albedo},
        {"apt", "Zirr & Dachsbacher 2020's MCMC over path-tracer paths (pinhole, no NEE): the adaptive forward path "
         "sampling small step (Sec. 7.1) and the path tracer as a multiple-try reversible-jump large step (Sec. 7.2)",
         render_apt,
         {{"large_step", "large-step probability (default 0.3)"},
          {"chains", "chains per pass (default 64)"},
          {"bootstrap", "bootstrap draws per pass (default: N / 8 clamped to [8192, 100000])"}}},
        {"bdpt", "bidirectional path tracing: all (s, t) connections, power-heuristic MIS over the shared path densities",
         [](const World& w, const RenderSettings& s, Film& f) { return render_bdpt(w, s, f); }},
        {"lt", "light tracing: emitter paths connected to the camera and splatted (importance transport)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_lt(w, s, f); }},
        {"hslt", "path-space MLT with the half-vector mutation (Kaplanyan et al. 2014) mixed with the bidirectional mutation (pinhole)", render_hslt, {{"gamma", "half-vector step scale of Sec. 6.1 (default 0.1)"}, {"stratify", "1: Sec. 6.2-6.3 step sizes (default), 0: BSDF steps only"}, {"jump", "1: subspace jump of Sec. 5.2 (default), 0: off"}}},
        {"memlt", "path-space MLT with the manifold perturbation of manifold exploration (Jakob and Marschner 2012: lens perturbation, specular chain re-solved by the half-vector walk) mixed with the bidirectional mutation (pinhole)", render_memlt, {{"r2", "lens kernel outer radius in pixels (default 10% of the larger image side)"}}},
        {"mlt", "Veach's path-space MLT: bidirectional mutation, lens and caustic perturbations through specular chains (pinhole)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_mlt(w, s, f); }},
        {"mlt-stratified", "Veach's path-space MLT with Zirr & Dachsbacher 2020's stratified target "
         "min{r~ p, f / B} (Eq. 8, 21, 22): bright low-variance paths capped, bounded-error splats (pinhole)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_mlt_stratified(w, s, f); },
         mlt_stratified_parameters()},
        {"ramlt-lens", "regional adaptive MLT (Otsu et al.): bidirectional mutation + regional adaptive lens "
         "perturbation, 20 x 20 screen grid, adapted in synchronous batches (pinhole; tb render --partition)",
         [](const World& w, const RenderSettings& s, Film& f) {
           return render_ramlt(w, s, f, path_space::apply_ramlt_params({}, s.params));
         },
         ramlt_parameters()},
        {"ramlt-multichain", "regional adaptive MLT (Otsu et al.): bidirectional mutation + regional adaptive "
         "multi-chain perturbation, 20 x 20 screen grid, adapted in synchronous batches (pinhole; tb render --partition)",
         [](const World& w, const RenderSettings& s, Film& f) {
           path_space::RamltOptions o;
           o.perturbation = path_space::RamltPerturbation::kMultiChain;
           return render_ramlt(w, s, f, path_space::apply_ramlt_params(o, s.params));
         },
         ramlt_parameters()},
        {"mmlt", "multiplexed MLT (Hachisuka et al. 2014): primary-sample-space chains per path length over single BDPT techniques",
         [](const World& w, const RenderSettings& s, Film& f) { return render_mmlt(w, s, f); }, pss_parameters()},
        {"mmlt-stratified", "MMLT with Zirr & Dachsbacher 2020's stratified target min{r~, f / B} (Eq. 8, 21, 22): "
         "bright low-variance paths capped, bounded-error splats",
         [](const World& w, const RenderSettings& s, Film& f) { return render_mmlt_stratified(w, s, f); },
         stratified_parameters()},
        {"pssmlt-stratified", "PSSMLT over BDPT with Zirr & Dachsbacher 2020's stratified target (sum over splats of "
         "min{r~, f / B}, Eq. 8, 21, 22)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pssmlt_stratified(w, s, f); },
         stratified_parameters()},
        {"pssmlt-pt-stratified", "PSSMLT over the path tracer with Zirr & Dachsbacher 2020's stratified target "
         "(sum over the sample's paths of min{r~, f / B})",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pssmlt_pt_stratified(w, s, f); },
         stratified_parameters()},
        {"pssmlt-pt-rescaled-stratified", "the rescaled PSSMLT over the path tracer (Szirmay-Kalos & Szecsi 2017) "
         "with Zirr & Dachsbacher 2020's stratified target",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pssmlt_pt_rescaled_stratified(w, s, f); },
         stratified_parameters()},
        {"pssmlt", "primary sample space MLT (Kelemen et al. 2002) over BDPT: large and small steps, expected-value splats",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pssmlt(w, s, f); }, pss_parameters()},
        {"pssmlt-pt", "primary sample space MLT (Kelemen et al. 2002) over the path tracer (one NEE+MIS radiance sample per state)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pssmlt_pt(w, s, f); }, pss_parameters()},
        {"msmlt", "multi-stage PSSMLT over BDPT (Hoberock & Hart 2010): target f / I~(pixel), I~ a recursively refined coarse image",
         [](const World& w, const RenderSettings& s, Film& f) { return render_msmlt(w, s, f); }},
        {"msmlt-mmlt", "multi-stage MMLT (Hoberock & Hart 2010 target over Hachisuka et al. 2014's per-length chains)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_msmlt_mmlt(w, s, f); }},
        {"pssmlt-pt-rescaled", "PSSMLT over the path tracer, small step sigma rescaled by the path's luminance (Szirmay-Kalos & Szecsi 2017)",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pssmlt_pt_rescaled(w, s, f); }, pss_parameters()},
        {"pm", "photon mapping: density estimation with a fixed-radius constant kernel at the first non-delta camera vertex",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pm(w, s, f); }, photon_map_parameters(false)},
        {"sppm", "stochastic progressive photon mapping (Hachisuka & Jensen 2009): per-pixel radius reduction, one pass = one run",
         [](const World& w, const RenderSettings& s, Film& f) { return render_sppm(w, s, f); }, photon_map_parameters(true)},
        {"pf1", "single-vertex path filtering as unbiased marginal MIS (West et al. 2022, Sec. 5, K = 1): directions of neighbouring prefixes reused at the first camera vertex",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pf1(w, s, f); }, pf1_parameters()},
        {"pfk", "multi-vertex path filtering as unbiased marginal MIS (West et al. 2022, Sec. 5, Eq. 14): directions of neighbouring prefixes reused at the first K camera vertices",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pfk(w, s, f); }, pfk_parameters()},
        {"pt", "path tracing with next-event estimation, MIS (power heuristic) and Russian roulette",
         [](const World& w, const RenderSettings& s, Film& f) { return render_pt(w, s, f); }},
    };
    std::sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    return t;
  }();
  return table;
}

const IntegratorInfo* find_integrator(const std::string& name) {
  for (const auto& i : integrators())
    if (i.name == name) return &i;
  return nullptr;
}

}  // namespace tb
