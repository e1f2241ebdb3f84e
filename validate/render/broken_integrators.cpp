#include "validate/render/broken_integrators.h"
#include "validate/render/broken_path_filter.h"

#include "lib/integrator/bdpt_impl.h"
#include "lib/integrator/light_tracer_impl.h"
#include "lib/integrator/path_tracer_impl.h"
#include "lib/integrator/photon_map_impl.h"
#include "lib/registry/integrator_registry.h"

namespace tb {

double inverted_importance_shading_correction(const SurfacePoint& hit, const Vec3& wo, const Vec3& wi) {
  const double c = importance_shading_correction(hit, wo, wi);
  return c > 0 ? 1.0 / c : 0.0;
}

namespace {

struct MisMissingDensityTerms : ExactTerms {
  static constexpr bool kMisFullDenominator = false;
};
struct NeeNoCosineTerms : ExactTerms {
  static constexpr bool kNeeReceiverCosine = false;
};
struct RouletteNoInverseTerms : ExactTerms {
  static constexpr bool kRouletteDividesByQ = false;
};
struct ShadingCorrectionInvertedTerms : ExactTerms {
  static constexpr ImportanceCorrection kImportanceCorrection = &inverted_importance_shading_correction;
};

// Calls f.template operator()<Terms>() with the Terms of `fault`.
template <class F>
auto with_terms(EstimatorFault fault, F&& f) {
  switch (fault) {
    case EstimatorFault::kMisMissingDensity: return f.template operator()<MisMissingDensityTerms>();
    case EstimatorFault::kNeeNoCosine: return f.template operator()<NeeNoCosineTerms>();
    case EstimatorFault::kRouletteNoInverse: return f.template operator()<RouletteNoInverseTerms>();
    case EstimatorFault::kShadingCorrectionInverted: break;
  }
  return f.template operator()<ShadingCorrectionInvertedTerms>();
}

constexpr EstimatorFault kAllFaults[] = {EstimatorFault::kMisMissingDensity, EstimatorFault::kNeeNoCosine,
                                         EstimatorFault::kRouletteNoInverse,
                                         EstimatorFault::kShadingCorrectionInverted};

}  // namespace

const char* fault_name(EstimatorFault fault) {
  switch (fault) {
    case EstimatorFault::kMisMissingDensity: return "mis_missing_density";
    case EstimatorFault::kNeeNoCosine: return "nee_no_cosine";
    case EstimatorFault::kRouletteNoInverse: return "roulette_no_inverse";
    case EstimatorFault::kShadingCorrectionInverted: break;
  }
  return "shading_correction_inverted";
}

RenderFunction broken_integrator(const std::string& integrator, EstimatorFault fault) {
  if (integrator == "pt") {
    // The path tracer has no light subpaths: no adjoint shading factor to invert.
    if (fault == EstimatorFault::kShadingCorrectionInverted) return {};
    return with_terms(fault, []<class Terms>() -> RenderFunction {
      return [](const World& w, const RenderSettings& st, Film& film) {
        return detail::render_pt_with<Terms>(w, st, film, nullptr);
      };
    });
  }
  if (integrator == "lt") {
    if (fault == EstimatorFault::kMisMissingDensity || fault == EstimatorFault::kNeeNoCosine) return {};
    return with_terms(fault, []<class Terms>() -> RenderFunction {
      return [](const World& w, const RenderSettings& st, Film& film) {
        return detail::render_lt_with<Terms>(w, st, film, nullptr);
      };
    });
  }
  if (integrator == "bdpt") {
    if (fault == EstimatorFault::kRouletteNoInverse) return {};  // bdpt paths end at max_depth
    return with_terms(fault, []<class Terms>() -> RenderFunction {
      return [](const World& w, const RenderSettings& st, Film& film) {
        return detail::render_bdpt_with<Terms>(w, st, film);
      };
    });
  }
  return {};
}

std::string broken_integrator_name(const std::string& integrator, EstimatorFault fault) {
  return integrator + "~" + fault_name(fault);
}

RenderFunction find_render_function(const std::string& name) {
  if (const IntegratorInfo* info = find_integrator(name)) return info->render;
  const size_t tilde = name.find('~');
  if (tilde == std::string::npos) return {};
  if (auto pm = broken_photon_map(name.substr(0, tilde), name.substr(tilde + 1))) return pm;
  if (auto pf = broken_path_filter(name.substr(0, tilde), name.substr(tilde + 1))) return pf;
  for (const EstimatorFault f : kAllFaults)
    if (name.substr(tilde + 1) == fault_name(f)) return broken_integrator(name.substr(0, tilde), f);
  return {};
}

int generate_light_subpath_broken(EstimatorFault fault, const PathContext& ctx, Uniforms& u, int max_vertices,
                                  std::vector<PathVertex>* path) {
  return with_terms(fault, [&]<class Terms>() {
    return detail::generate_light_subpath_with<Terms>(ctx, u, max_vertices, path);
  });
}

Connection connect_bdpt_broken(EstimatorFault fault, const PathContext& ctx, std::span<const PathVertex> light,
                               std::span<const PathVertex> camera, int s, int t, Uniforms& u) {
  return with_terms(fault, [&]<class Terms>() {
    return detail::connect_bdpt_with<Terms>(ctx, light, camera, s, t, u);
  });
}

}  // namespace tb

namespace tb {
namespace {

struct KernelPerRadiusTerms : PhotonTerms {
  static double kernel_area(double r) { return r; }
};

}  // namespace

RenderFunction broken_photon_map(const std::string& integrator, const std::string& fault) {
  if (fault != kPhotonKernelPerRadius) return {};
  if (integrator == "pm")
    return [](const World& w, const RenderSettings& st, Film& film) {
      return detail::render_pm_with<KernelPerRadiusTerms>(w, st, film);
    };
  if (integrator == "sppm")
    return [](const World& w, const RenderSettings& st, Film& film) {
      return detail::render_sppm_with<KernelPerRadiusTerms>(w, st, film);
    };
  return {};
}

}  // namespace tb
