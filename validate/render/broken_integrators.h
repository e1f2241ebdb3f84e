// Negative controls of the path tracer, light tracer and BDPT: the templates lib/ renders with
// (lib/integrator/path_tracer_impl.h, light_tracer_impl.h, bdpt_impl.h) instantiated with one
// estimator term wrong (lib/integrator/estimator_terms.h). The checks that must reject them are in
// validate/checks/integrator_checks.cpp; they reach them by name, "pt~nee_no_cosine", through
// find_render_function, which also resolves every registered integrator.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/film/film.h"
#include "lib/integrator/bdpt.h"
#include "lib/integrator/render_settings.h"
#include "lib/path/path.h"
#include "lib/scene/world.h"

namespace tb {

enum class EstimatorFault {
  kMisMissingDensity,          // an MIS weight with one density left out of its denominator
  kNeeNoCosine,                // next-event estimation without |cos| at the receiving vertex
  kRouletteNoInverse,          // Russian roulette survivors not divided by q
  kShadingCorrectionInverted,  // light subpaths with the reciprocal of the adjoint's shading factor
};

// "mis_missing_density", "nee_no_cosine", "roulette_no_inverse", "shading_correction_inverted".
const char* fault_name(EstimatorFault fault);

using RenderFunction = std::function<int64_t(const World&, const RenderSettings&, Film&)>;

// `integrator` ("pt", "lt", "bdpt") rendering with `fault`; empty when the integrator has no such
// term (lt has no MIS and no next-event estimation; bdpt no Russian roulette).
RenderFunction broken_integrator(const std::string& integrator, EstimatorFault fault);

// The name a broken integrator goes by in records and in find_render_function: "pt~nee_no_cosine".
std::string broken_integrator_name(const std::string& integrator, EstimatorFault fault);

// A registered integrator by name, or a broken one by its broken_integrator_name; empty if neither.
RenderFunction find_render_function(const std::string& name);

// BDPT's pieces with a fault, for the unit tests of single connections.
int generate_light_subpath_broken(EstimatorFault fault, const PathContext& ctx, Uniforms& u, int max_vertices,
                                  std::vector<PathVertex>* path);
Connection connect_bdpt_broken(EstimatorFault fault, const PathContext& ctx, std::span<const PathVertex> light,
                               std::span<const PathVertex> camera, int s, int t, Uniforms& u);

// The reciprocal of importance_shading_correction (0 where that is 0): the broken shading factor.
double inverted_importance_shading_correction(const SurfacePoint& hit, const Vec3& wo, const Vec3& wi);

// Photon mapping ("pm", "sppm") whose density-estimation kernel is not normalised by its area:
// the photons' sum divided by N r instead of N pi r^2 (lib/integrator/photon_map_impl.h's
// PhotonTerms with kernel_area(r) = r). Goes by "pm~kernel_per_radius" / "sppm~kernel_per_radius"
// in find_render_function; empty for another integrator or fault name.
RenderFunction broken_photon_map(const std::string& integrator, const std::string& fault);
inline constexpr const char* kPhotonKernelPerRadius = "kernel_per_radius";

}  // namespace tb
